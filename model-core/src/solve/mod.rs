//! Solving any rod equations for their `K` shooting unknowns: one damped Newton/LM (`newton.rs`), one
//! load continuation (`continuation.rs`), the stopping rules (`stopping.rs`) and the strategy of a
//! solve (here): a cold start first tries Newton from the bent rod's guess and keeps the answer
//! only if the stability test passes; otherwise it ramps all loads from zero, which follows the branch
//! connected to the unloaded rod. A converged but unstable equilibrium is reported as
//! [`Termination::Unstable`], never as success. Equations without a stability test go straight to
//! the continuation from a cold start.

pub(crate) mod continuation;
pub(crate) mod newton;
pub(crate) mod secant;
pub(crate) mod stopping;

use nalgebra::{Const, DimMin, SMatrix, SVector};

use crate::Scalar;
use crate::error::{ModelError, positive};
use crate::ode::guess::cap;
use crate::ode::{Family, RodOde};
use crate::report::{MAX_FRAME_DRIFT, MAX_PHASE_PER_STEP_RAD, Termination};
use crate::scalar::from_columns;
use crate::solve::stopping::default_tolerance;
use crate::stability::{Stability, classify};
use crate::sweep::{Sweep, TangentSet};
pub(crate) use newton::Chord;
use newton::{Newton, NewtonOptions, Work, newton};

/// Settings of the shooting solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShootingSettings<T> {
    /// Newton iterations per solve (per load step during continuation).
    pub max_iterations: u16,
    /// Tolerance on the dimensionless residual `|tip moment error| L / (E I)`, relative to the base
    /// rotation `|u0| L` when that exceeds one radian.
    pub tolerance: T,
    /// Trust region: largest change of base strain per iteration, as an angle `|du0| L`, rad.
    pub max_rotation_step_rad: T,
    /// Most load steps during continuation.
    pub max_load_steps: u16,
    /// Run the Jacobi-field stability test on the answer (one extra sweep with six tangents).
    pub check_stability: bool,
    /// When a warm start fails, start again cold.
    pub cold_fallback: bool,
}

impl<T: Scalar> Default for ShootingSettings<T> {
    fn default() -> Self {
        Self {
            max_iterations: 40,
            tolerance: default_tolerance(),
            max_rotation_step_rad: T::lit(1.0),
            max_load_steps: 64,
            check_stability: true,
            cold_fallback: true,
        }
    }
}

impl<T: Scalar> ShootingSettings<T> {
    pub(crate) fn validate(&self) -> Result<(), ModelError> {
        positive(self.tolerance, "solver tolerance")?;
        positive(self.max_rotation_step_rad, "trust region").map(|_| ())
    }
}

/// Newton iterations a cold start gives the full load before it falls back to continuation.
const DIRECT_ITERATIONS: u16 = 12;

/// The stability verdict on the sweep `sw` of `ode`, which carried the unknowns' tangents with the
/// conjugate-point watch.
pub(crate) fn verdict<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    sw: &Sweep<T, K>,
) -> Stability<T>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    if !ode.has_stability_test() {
        return Stability::Unchecked;
    }
    let rotation: SMatrix<T, K, K> =
        from_columns(|j| ode.jacobi_rotation(&sw.d_rotation(Family::Unknown, j)));
    classify(
        ode.conservative(),
        sw.conjugate_point_m,
        &sw.jacobian(),
        &rotation,
        ode.length_m(),
    )
}

/// A finished solve: its last Newton solve, the stability verdict, the work and load steps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solved<T, const K: usize> {
    pub newton: Newton<T, K>,
    pub stability: Stability<T>,
    pub work: Work,
    pub load_steps: u16,
}

/// A solve that ended without any Newton solve to show (no direct attempt, and the continuation
/// failed): its work.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Failed {
    pub work: Work,
    pub load_steps: u16,
}

/// Solves `ode` (at its full load) from `start` (`None`: cold).
// Out of line: the load continuation's locals stay out of the callers' frames (the controller's
// cold inverse starts with a forward solve and then needs its stack for the inverse).
#[inline(never)]
pub(crate) fn solve<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    start: Option<SVector<T, K>>,
    settings: &ShootingSettings<T>,
) -> Result<Solved<T, K>, Failed>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    solve_from(ode, start, settings, None, 0)
}

/// A start expected to be the answer: its first sweep goes without tangents and ends the solve
/// when it meets the tolerance (see [`NewtonOptions::plain_first`]); where it does not, chord steps
/// with `chord`'s Jacobian, if given ([`Chord`]), before the tangents.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Confirm<'a, T, const K: usize> {
    pub chord: Option<Chord<'a, T, K>>,
}

/// [`solve`] from `start`, or from a start expected to be the answer (`confirm`). Confirming only
/// for equations without a stability test, whose verdict needs no tangents. `spent`: iterations an
/// earlier stage of the same solve used, which a warm start's direct attempt gives up (the
/// continuation keeps its budget per load step).
#[inline(never)]
pub(crate) fn solve_from<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    start: Option<SVector<T, K>>,
    settings: &ShootingSettings<T>,
    confirm: Option<Confirm<'_, T, K>>,
    spent: u16,
) -> Result<Solved<T, K>, Failed>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let mut work = Work::default();
    let mut load_steps = 0u16;

    // A cold start tries the full load from the bent rod's guess ([`RodOde::cold_guess`]); if that
    // fails, load continuation starts with a step that bends the linear rod by GUESS_ANGLE_RAD
    // (at most half the load).
    let (direct_iterations, first_step) = match start {
        None => (
            settings.max_iterations.min(DIRECT_ITERATIONS),
            cap(ode.change_rad(&ode.guess())).min(T::lit(0.5)),
        ),
        Some(_) => (settings.max_iterations.saturating_sub(spent), T::lit(0.25)),
    };
    let check = |out: &mut Newton<T, K>| judge(ode, settings, out);
    // Without a stability test that can reject it, a direct solve cannot tell a wrong branch from the
    // right one: a cold start then follows the branch from the unloaded rod. So with no test, with
    // the test switched off, and with a moment of fixed direction (not conservative: the energy test
    // does not apply, and a direct answer 1.57 rod lengths from the loaded-from-zero one passed).
    // Nor on sections stiffer about one axis than the other ([`RodOde::bends_alike_about_both_axes`]).
    let testable = ode.has_stability_test()
        && ode.conservative()
        && settings.check_stability
        && ode.bends_alike_about_both_axes();
    let direct = start.is_some() || testable;
    let mut result = direct.then(|| {
        let options = NewtonOptions {
            tolerance: settings.tolerance,
            to_rounding: true,
            max_step_rad: settings.max_rotation_step_rad,
            max_iterations: direct_iterations,
            tangents: TangentSet::unknowns(settings.check_stability),
            plain_first: confirm.is_some() && start.is_some() && !ode.has_stability_test(),
        };
        let chord = confirm.and_then(|c| c.chord);
        let direct_start = start.unwrap_or_else(|| ode.cold_guess());
        let mut out = newton(ode, direct_start, None, chord, &options, &mut work);
        let stability = check(&mut out);
        (out, stability)
    });
    let cold_allowed = start.is_none() || settings.cold_fallback;
    let succeeded = result
        .as_ref()
        .is_some_and(|(out, _)| out.termination.is_success());
    if !succeeded && cold_allowed {
        result =
            match continuation::continuation(ode, settings, first_step, &mut work, &mut load_steps)
            {
                Some(mut out) => {
                    let stability = check(&mut out);
                    Some((out, stability))
                }
                None => result.map(|(mut out, stability)| {
                    out.termination = Termination::ContinuationFailed;
                    (out, stability)
                }),
            };
    }
    let Some((newton, stability)) = result else {
        return Err(Failed { work, load_steps });
    };
    Ok(finish(newton, stability, work, load_steps))
}

/// The stability verdict on the answer of `out` where the settings ask for one (its sweep carried
/// the unknowns' tangents with the conjugate-point watch); an unacceptable one makes it
/// [`Termination::Unstable`].
pub(crate) fn judge<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    settings: &ShootingSettings<T>,
    out: &mut Newton<T, K>,
) -> Stability<T>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    if out.termination.is_success() && settings.check_stability {
        let verdict = verdict(ode, &out.sweep);
        if !verdict.is_acceptable() {
            out.termination = Termination::Unstable;
        }
        verdict
    } else {
        Stability::Unchecked
    }
}

/// A solve's last Newton solve and verdict, with the checks every answer gets: the frame's drift
/// and the grid's resolution.
pub(crate) fn finish<T: Scalar, const K: usize>(
    mut newton: Newton<T, K>,
    mut stability: Stability<T>,
    work: Work,
    load_steps: u16,
) -> Solved<T, K> {
    if newton.termination.is_success()
        && !(newton.sweep.frame_drift.is_finite()
            && newton.sweep.frame_drift <= T::lit(MAX_FRAME_DRIFT))
    {
        newton.termination = Termination::FrameDrift;
    }
    if newton.termination.is_success() && !resolved(newton.sweep.phase_per_step_rad) {
        newton.termination = Termination::UnderResolved;
        // The grid cannot resolve the test either: no verdict rather than a wrong one.
        stability = Stability::Unchecked;
    }
    Solved {
        newton,
        stability,
        work,
        load_steps,
    }
}

/// Whether a sweep's grid resolves its bending: at most [`MAX_PHASE_PER_STEP_RAD`] per step.
pub(crate) fn resolved<T: Scalar>(phase_per_step_rad: T) -> bool {
    phase_per_step_rad.is_finite() && phase_per_step_rad <= T::lit(MAX_PHASE_PER_STEP_RAD)
}
