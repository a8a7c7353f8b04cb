//! A solve from a solved neighbour ([`crate::shooting::Start::Neighbour`]), the cheap path when the
//! loads changed a little (MODEL.md §3.13).
//!
//! A Newton iteration costs a sweep with the unknowns' tangents; a plain sweep costs a quarter of
//! it (3.4-4.6 times less on the host, 12 steps, f64: `report/warm_path_options.md`). From a
//! neighbour, the steps need no fresh tangents: the neighbour's Jacobian, updated along each step
//! by Broyden's rule (the residual's change over the step, which is what the load change made of
//! it), gives steps that contract faster with each one (superlinearly). So the solve takes secant
//! steps on plain sweeps while each lowers the residual at least fourfold, and the answer gets its
//! sweep with the tangents only once, for the stability test: taken at the step predicted to
//! converge (by the secant method's rate, the product of the last two contractions, while they
//! improve), it is also that step's sweep, and where the prediction misses, Newton goes on from
//! it. Where the steps stop contracting, or the answer is refused, the solve goes on as a warm
//! start from where they stopped ([`super::solve_from`], with what they left of the iterations):
//! Newton with the tangents, then the load continuation.

use nalgebra::{Const, DimMin, SMatrix, SVector};

use super::newton::{Newton, NewtonOptions, Work, bounded_step, converged, newton_in_place};
use super::stopping::residual_converged;
use super::{Failed, ShootingSettings, Solved, finish, judge, solve_from};
use crate::Scalar;
use crate::ode::RodOde;
use crate::report::Termination;
use crate::sweep::{Sweep, TangentSet, sweep};

/// Secant steps at most.
const SECANT_STEPS: u16 = 6;

/// The contraction each step must reach (its residual over the last) for the next to be tried.
const SECANT_CONTRACTION: f64 = 0.25;

/// Solves `ode` from `start`, a neighbour's unknowns, with the neighbour's shooting Jacobian; with
/// the solve, the Jacobian the secant steps ended with (Broyden's, at the last point they kept).
pub(crate) fn solve_near<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    start: SVector<T, K>,
    jacobian: &SMatrix<T, K, K>,
    settings: &ShootingSettings<T>,
) -> (Result<Solved<T, K>, Failed>, SMatrix<T, K, K>)
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
    let mut secant = *jacobian;
    let mut x = start;
    work.sweep();
    let mut sw = sweep(ode, &x, TangentSet::NONE, None);
    let mut converged = sw.finite
        && (converged(ode, &sw, &x, &options)
            || secant_steps(
                ode,
                &mut x,
                &mut sw,
                &mut secant,
                &options,
                tested,
                &mut work,
            ));
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
            return (Ok(finish(newton, stability, work, 0)), secant);
        }
    }
    // The warm start's direct attempt gets what the steps left of the iterations.
    let mut outcome = solve_from(ode, Some(x), settings, None, work.iterations);
    match &mut outcome {
        Ok(solved) => solved.work.add(work),
        Err(failed) => failed.work.add(work),
    }
    (outcome, secant)
}

/// Secant steps from `x`, whose plain sweep is `sw`, starting from `jacobian`, each within the
/// trust region: `x` and `sw` move to each step that lowers the residual, and `jacobian` takes
/// Broyden's update along it. Whether the solve is converged there; with `tested`, the step
/// predicted to converge is swept with the tangents. Out of line: its trial sweep stays out of the
/// caller's frame.
#[inline(never)]
fn secant_steps<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    x: &mut SVector<T, K>,
    sw: &mut Sweep<T, K>,
    jacobian: &mut SMatrix<T, K, K>,
    options: &NewtonOptions<T>,
    tested: bool,
    work: &mut Work,
) -> bool
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let max_step = options.max_step_rad / ode.length_m();
    let mut residual = ode.residual_size(&sw.residual);
    let mut with_tangents = false;
    // The prediction of the next step's residual. Broyden's steps contract faster with each one
    // (superlinearly): along the one direction a load change moves the answer, they are the secant
    // method's, whose residuals go as `r_{k+1} ~ r_k r_{k-1}`, so each contraction is about the
    // product of the two before it. That product predicts the next while the contractions improve
    // (an equal one counts: with linear convergence the product predicts too well, and the miss
    // costs one sweep with the tangents early); otherwise (and after the first step), the slowest
    // contraction so far does. A prediction
    // that misses costs a sweep with the tangents. In the chain of `tests/stress.rs` the product
    // took 620 of its 1 368 solves from five sweeps to four, for 25 more sweeps with the tangents
    // in the whole test (823 fewer plain ones); the last contraction alone, or a margin of ten on
    // the slowest, had cost 2-3 % more than the slowest alone.
    let mut slowest = T::zero();
    let mut before: Option<T> = None;
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
        *jacobian += (change - *jacobian * step) * (step / step.norm_squared()).transpose();
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
        let predicted = match before.replace(contraction) {
            Some(before) if contraction <= before => size * contraction * before,
            _ => size * slowest,
        };
        with_tangents =
            tested && residual_converged(predicted, ode.rotation_rad(x), options.tolerance);
    }
    false
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Vector3};

    use super::*;
    use crate::loads::TipLoad;
    use crate::model::Model;
    use crate::ode::dead_load::DeadLoadRod;
    use crate::ode::guess::tests::rod;
    use crate::shooting::Start;
    use crate::solve::stopping::default_tolerance;
    use crate::stability::Stability;

    /// The thesis's bare rod (12 steps, gravity) under `grams` at the tip.
    fn hang(grams: f64) -> TipLoad<f64> {
        TipLoad::force(Vector3::new(0.0, -grams * 1e-3 * 9.81, 0.0))
    }

    /// The answer at 40.2 g, and the neighbour at 1 % lighter (base strain, Jacobian).
    fn scene() -> (Model<f64>, Vector3<f64>, Vector3<f64>, Matrix3<f64>) {
        let model = rod(9.81, &[]);
        let settings = ShootingSettings::default();
        let answer = model.solve(&hang(40.2), Start::Cold, &settings).unwrap();
        let lighter = model
            .solve(&hang(40.2 * 0.99), Start::Cold, &settings)
            .unwrap();
        assert!(answer.report.termination.is_success());
        assert!(lighter.report.termination.is_success());
        (
            model,
            answer.base_strain_per_m,
            lighter.base_strain_per_m,
            lighter.jacobian_nm2.unwrap(),
        )
    }

    fn options(tolerance: f64, max_iterations: u16) -> NewtonOptions<f64> {
        NewtonOptions {
            tolerance,
            to_rounding: true,
            max_step_rad: 1.0,
            max_iterations,
            tangents: TangentSet::unknowns(true),
            plain_first: true,
        }
    }

    /// Each exit of the secant steps from the 1 % lighter neighbour at 40.2 g: with its Jacobian they
    /// converge (each step one sweep and one iteration) and update the Jacobian; the third step,
    /// predicted to converge by the product of the first two contractions, carries the tangents
    /// and is the last (as at a looser tolerance); without the stability test none does;
    /// a step beyond the trust region (`J / 1e9`) is refused before its sweep; a trial that does not lower the residual (`-J`) is swept and left; a step that
    /// lowers it less than fourfold (`2 J`: by about half) is kept and ends them; they leave the
    /// solve at least one iteration.
    #[test]
    fn secant_steps_take_only_steps_that_contract() {
        let (model, answer, start, j) = scene();
        let ode = DeadLoadRod::new(&model, &hang(40.2), 1.0);
        let tight = default_tolerance();
        // (jacobian, tolerance, iterations, tested, converges, sweeps, moved, tangents at the end)
        let cases = [
            (j, tight, 40, true, true, Some(3), true, true),
            (j, 1e-8, 40, true, true, None, true, true),
            (j, tight, 40, false, true, None, true, false),
            (j / 1e9, tight, 40, true, false, Some(0), false, false),
            (-j, tight, 40, true, false, Some(1), false, false),
            (j * 2.0, tight, 40, true, false, Some(1), true, false),
            (j, tight, 2, true, false, Some(1), true, false),
        ];
        for (k, (jacobian, tolerance, iterations, tested, converges, sweeps, moves, tangents)) in
            cases.into_iter().enumerate()
        {
            let options = options(tolerance, iterations);
            let mut x = start;
            let mut sw = sweep(&ode, &x, TangentSet::NONE, None);
            let before = ode.residual_size(&sw.residual);
            let mut secant = jacobian;
            let mut work = Work::default();
            let done = secant_steps(
                &ode,
                &mut x,
                &mut sw,
                &mut secant,
                &options,
                tested,
                &mut work,
            );
            assert_eq!(done, converges, "case {k}: {work:?}");
            assert_eq!(work.sweeps, work.iterations, "case {k}: one sweep a step");
            if let Some(sweeps) = sweeps {
                assert_eq!(work.sweeps, sweeps, "case {k}");
            }
            assert!(work.iterations < iterations, "case {k}: one iteration left");
            assert_eq!(x != start, moves, "case {k}");
            assert_eq!(sw.has_jacobian(), tangents, "case {k}");
            assert!(ode.residual_size(&sw.residual) <= before, "case {k}");
            if converges {
                let apart = (x - answer).norm() / answer.norm();
                assert!(apart < 1e-9, "case {k}: {apart:e} from the answer");
                assert!(secant != jacobian, "case {k}: the Jacobian took the steps");
                assert!(work.sweeps <= 4, "case {k}: {work:?}");
            }
        }
    }

    /// The whole solve from the neighbour: with the stability test, the answer's sweep carries the
    /// tangents and its verdict (Stable), at most one sweep more than its steps; without it, no sweep
    /// carries tangents at all; the answer is the cold one's; and a budget of two iterations, with
    /// no cold fallback, is kept whatever the neighbour's Jacobian.
    #[test]
    fn a_neighbour_is_confirmed_on_plain_sweeps_and_tested_once() {
        let (model, answer, start, j) = scene();
        let ode = DeadLoadRod::new(&model, &hang(40.2), 1.0);
        let settings = ShootingSettings::default();
        let (solved, secant) = solve_near(&ode, start, &j, &settings);
        let solved = solved.unwrap();
        assert!(solved.newton.termination.is_success());
        assert_eq!(solved.stability, Stability::Stable);
        assert!(solved.newton.sweep.has_jacobian());
        assert!(
            solved.work.sweeps <= solved.work.iterations + 2,
            "{:?}",
            solved.work
        );
        assert!((solved.newton.x - answer).norm() / answer.norm() < 1e-9);
        assert!(secant != j);

        let untested = ShootingSettings {
            check_stability: false,
            ..settings
        };
        let (solved, _) = solve_near(&ode, start, &j, &untested);
        let solved = solved.unwrap();
        assert!(solved.newton.termination.is_success());
        assert!(
            !solved.newton.sweep.has_jacobian(),
            "no sweep with tangents"
        );
        assert_eq!(solved.stability, Stability::Unchecked);
        assert!((solved.newton.x - answer).norm() / answer.norm() < 1e-9);

        let budget = ShootingSettings {
            max_iterations: 2,
            cold_fallback: false,
            ..settings
        };
        for jacobian in [j, -j, j * 2.0, j / 1e9] {
            let (solved, _) = solve_near(&ode, start, &jacobian, &budget);
            let work = match solved {
                Ok(s) => s.work,
                Err(f) => f.work,
            };
            assert!(work.iterations <= 2, "{work:?}");
        }
    }
}
