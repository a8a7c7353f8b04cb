//! Load continuation from the unloaded rod (where every set of unknowns is zero, exactly) to the full
//! load, for any rod equations: a secant predictor along the branch, the damped Newton as corrector,
//! and an adaptive load step. Every load step is checked for stability (where the equations have the
//! test) and for staying near its prediction, so that a large step cannot hop onto another branch.

use nalgebra::{Const, DimMin, SVector};

use super::ShootingSettings;
use super::newton::{Newton, NewtonOptions, Work, newton};
use super::verdict;
use crate::Scalar;
use crate::ode::RodOde;
use crate::sweep::TangentSet;

/// During continuation a corrected solution may differ from its prediction by at most this much,
/// rad ([`RodOde::change_rad`]); a larger jump is treated as a hop to another branch and the load
/// step is halved.
const PREDICTOR_TRUST_RAD: f64 = 0.5;

/// The smallest load step, as a fraction of the full load, before continuation gives up.
const MIN_LOAD_STEP: f64 = 1.0 / 4096.0;

/// Newton iterations per load step.
const CORRECTOR_ITERATIONS: u16 = 12;

/// Ramps every load of `ode` from zero to its full value; `first_step` is the first load increment (a
/// fraction of the full load). Counts load steps in `load_steps`; `None` when the full load is not
/// reached within the settings' load steps.
pub(crate) fn continuation<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    settings: &ShootingSettings<T>,
    first_step: T,
    work: &mut Work,
    load_steps: &mut u16,
) -> Option<Newton<T, K>>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let (mut alpha, mut x) = (T::zero(), SVector::<T, K>::zeros());
    let (mut prev_alpha, mut prev_x) = (T::zero(), SVector::<T, K>::zeros());
    let mut step = first_step;
    let min_step = T::lit(MIN_LOAD_STEP);
    let options = NewtonOptions {
        tolerance: settings.tolerance,
        to_rounding: true,
        max_step_rad: settings.max_rotation_step_rad,
        max_iterations: settings.max_iterations.min(CORRECTOR_ITERATIONS),
        tangents: TangentSet::unknowns(true),
        plain_first: false,
    };
    while *load_steps < settings.max_load_steps {
        let target = (alpha + step).min(T::one());
        let scaled = ode.at_scale(target);
        // Secant predictor along the branch.
        let guess = if alpha > prev_alpha {
            x + (x - prev_x) * ((target - alpha) / (alpha - prev_alpha))
        } else {
            scaled.guess()
        };
        *load_steps = load_steps.saturating_add(1);
        let iterations_before = work.iterations;
        let out = newton(&scaled, guess, None, None, &options, work);
        let accepted = out.termination.is_success()
            && scaled.change_rad(&(out.x - guess)) <= T::lit(PREDICTOR_TRUST_RAD)
            && verdict(&scaled, &out.sweep).is_acceptable();
        if accepted {
            (prev_alpha, prev_x) = (alpha, x);
            (alpha, x) = (target, out.x);
            if alpha >= T::one() {
                return Some(out);
            }
            let easy = work.iterations.saturating_sub(iterations_before) <= 3;
            step *= if easy { T::lit(2.0) } else { T::lit(1.25) };
        } else {
            step *= T::lit(0.5);
            if step < min_step {
                return None;
            }
        }
    }
    None
}
