//! A solve from a solved neighbour ([`crate::shooting::Start::Neighbour`]), the cheap path when the
//! loads changed a little (MODEL.md §3.13).
//!
//! A Newton iteration costs a sweep with the unknowns' tangents; a plain sweep costs a quarter of
//! it (3.4-4.6 times less on the host, 12 steps, f64: `report/warm_path_options.md`). From a
//! neighbour, the steps need no fresh tangents: the neighbour's Jacobian, updated along each step
//! by Broyden's rule (the residual's change over the step, which is what the load change made of
//! it), gives steps that contract faster with each one (superlinearly). So the solve takes secant
//! steps on plain sweeps while each lowers the residual at least fourfold, and the answer gets its
//! sweep with the tangents only once, for the stability test: taken at the step the slowest
//! contraction so far predicts to converge, it is also that step's sweep, and where the prediction
//! misses, Newton goes on from it. Where the steps stop contracting, or the answer is refused, the
//! solve goes on as a warm start from where they stopped ([`super::solve`]): Newton with the
//! tangents, then the load continuation.

use nalgebra::{Const, DimMin, SMatrix, SVector};

use super::newton::{Newton, NewtonOptions, Work, bounded_step, converged, newton_in_place};
use super::stopping::residual_converged;
use super::{Failed, ShootingSettings, Solved, finish, judge, solve};
use crate::Scalar;
use crate::ode::RodOde;
use crate::report::Termination;
use crate::sweep::{Sweep, TangentSet, sweep};

/// Secant steps at most.
const SECANT_STEPS: u16 = 6;

/// The contraction each step must reach (its residual over the last) for the next to be tried.
const SECANT_CONTRACTION: f64 = 0.25;

/// Solves `ode` from `start`, a neighbour's unknowns, with the neighbour's shooting Jacobian.
pub(crate) fn solve_near<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    start: SVector<T, K>,
    jacobian: &SMatrix<T, K, K>,
    settings: &ShootingSettings<T>,
) -> Result<Solved<T, K>, Failed>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let options = NewtonOptions {
        tolerance: settings.tolerance,
        to_rounding: true,
        max_step_rad: settings.max_rotation_step_rad,
        max_iterations: settings.max_iterations,
        tangents: TangentSet::unknowns(settings.check_stability),
        plain_first: true,
    };
    let tested = settings.check_stability && ode.has_stability_test();
    let mut work = Work::default();
    let mut x = start;
    work.sweep();
    let mut sw = sweep(ode, &x, TangentSet::NONE, None);
    let mut converged = sw.finite
        && (converged(ode, &sw, &x, &options)
            || secant_steps(ode, &mut x, &mut sw, jacobian, &options, tested, &mut work));
    if !converged && sw.finite && sw.has_jacobian() {
        // The step predicted to converge did not: Newton goes on from its sweep.
        let rest = NewtonOptions {
            max_iterations: options.max_iterations.saturating_sub(work.iterations),
            ..options
        };
        let (_, termination) = newton_in_place(ode, &mut x, &mut sw, &rest, &mut work);
        converged = termination.is_success();
    }
    if converged && tested && !sw.has_jacobian() {
        work.sweep();
        sw = sweep(ode, &x, options.tangents, None);
    }
    if converged && sw.finite {
        let mut newton = Newton {
            x,
            residual: ode.residual_size(&sw.residual),
            sweep: sw,
            termination: Termination::Converged,
        };
        let stability = judge(ode, settings, &mut newton);
        if newton.termination.is_success() {
            return Ok(finish(newton, stability, work, 0));
        }
    }
    let mut outcome = solve(ode, Some(x), settings);
    match &mut outcome {
        Ok(solved) => solved.work.add(work),
        Err(failed) => failed.work.add(work),
    }
    outcome
}

/// Secant steps from `x`, whose plain sweep is `sw`, starting from `jacobian`, each within the
/// trust region: `x` and `sw` move to each step that lowers the residual. Whether the solve is
/// converged there; with `tested`, the step predicted to converge is swept with the tangents.
/// Out of line: its trial sweep stays out of the caller's frame.
#[inline(never)]
fn secant_steps<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    x: &mut SVector<T, K>,
    sw: &mut Sweep<T, K>,
    jacobian: &SMatrix<T, K, K>,
    options: &NewtonOptions<T>,
    tested: bool,
    work: &mut Work,
) -> bool
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let mut jacobian = *jacobian;
    let max_step = options.max_step_rad / ode.length_m();
    let mut residual = ode.residual_size(&sw.residual);
    let mut with_tangents = false;
    // The slowest contraction so far, for the prediction (the steps usually contract faster each
    // time, but not always: a prediction that misses costs a sweep with the tangents; the last
    // contraction, or a margin of ten on either, cost 2-3 % more in the chain of
    // `tests/stress.rs`).
    let mut slowest = T::zero();
    // (At least one Newton iteration is left after them.)
    for _ in 0..SECANT_STEPS.min(options.max_iterations.saturating_sub(1)) {
        let Some(step) = bounded_step(&jacobian.lu(), &sw.residual, max_step) else {
            return false;
        };
        work.sweep();
        work.iterations = work.iterations.saturating_add(1);
        let trial_x = *x + step;
        let which = if with_tangents {
            options.tangents
        } else {
            TangentSet::NONE
        };
        let trial = sweep(ode, &trial_x, which, None);
        let size = ode.residual_size(&trial.residual);
        if !(trial.finite && size < residual) {
            return false;
        }
        // Broyden: the Jacobian takes the residual's change along the step.
        let change = trial.residual - sw.residual;
        jacobian += (change - jacobian * step) * (step / step.norm_squared()).transpose();
        (*x, *sw) = (trial_x, trial);
        if converged(ode, sw, x, options) {
            return true;
        }
        let contraction = size / residual;
        if with_tangents || contraction > T::lit(SECANT_CONTRACTION) {
            return false;
        }
        residual = size;
        slowest = slowest.max(contraction);
        let predicted = size * slowest;
        with_tangents =
            tested && residual_converged(predicted, ode.rotation_rad(x), options.tolerance);
    }
    false
}
