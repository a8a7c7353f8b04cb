//! One damped Newton / Levenberg-Marquardt iteration for the `K` shooting unknowns of any rod
//! equations: the Newton step when it reduces the residual (`mu = 0`), a damped step
//! `(J^T J + mu diag(J^T J)) dx = -J^T e` when it does not, with a trust region on the base rotation
//! `|dx| L`. The Jacobian comes from the sweep's tangents of the unknowns; a start expected to be
//! the answer is first confirmed by a plain sweep, then, with a Jacobian taken near it by the
//! caller, by chord steps on plain sweeps ([`Chord`]). Where the answer needs no tangents
//! (equations without a stability test), an undamped Newton step from within [`PLAIN_REACH`] of
//! the tolerance is swept without them too, and the same point again with them where that sweep
//! is better but not the answer.

use nalgebra::linalg::LU;
use nalgebra::{Const, DimMin, SMatrix, SVector};

use super::stopping;
use crate::Scalar;
use crate::ode::RodOde;
use crate::report::Termination;
use crate::sweep::{Sweep, TangentSet, sweep};

/// Work counters shared by the stages of one solve.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Work {
    pub iterations: u16,
    pub sweeps: u16,
}

impl Work {
    pub(crate) fn sweep(&mut self) {
        self.sweeps = self.sweeps.saturating_add(1);
    }

    /// Adds the work of an earlier stage.
    pub(crate) fn add(&mut self, earlier: Work) {
        self.iterations = self.iterations.saturating_add(earlier.iterations);
        self.sweeps = self.sweeps.saturating_add(earlier.sweeps);
    }
}

/// How one Newton solve runs and when it stops.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NewtonOptions<T> {
    /// Tolerance on the residual's size (see [`RodOde::residual_size`]).
    pub tolerance: T,
    /// Whether the tolerance is relative to the base rotation beyond one radian and a negligible
    /// correction at the rounding floor ends the solve (a forward solve to the scalar type's
    /// precision), or the tolerance is absolute and only the residual ends it (a projection back onto
    /// the equilibrium, to a tolerance far above rounding).
    pub to_rounding: bool,
    /// Trust region: largest change of the unknowns per iteration, as a base rotation, rad
    /// ([`RodOde::change_rad`]; chord steps bound the unknowns themselves).
    pub max_step_rad: T,
    /// Iterations (each one trial sweep).
    pub max_iterations: u16,
    /// The tangents each sweep carries (at least the unknowns').
    pub tangents: TangentSet,
    /// Whether the start is expected to be the answer: its sweep goes without tangents and ends
    /// the solve when it meets the tolerance (otherwise chord steps follow where the caller gave a
    /// Jacobian, [`Chord`], and then a sweep with the tangents). Ignored when the caller passes the
    /// start's sweep.
    pub plain_first: bool,
}

/// Rejected steps tolerated in a row before the solve is declared stalled.
const MAX_REJECTIONS: u8 = 8;

/// How far above the tolerance a residual may be for the undamped Newton step from it to be swept
/// first without tangents, where the answer needs none (equations without a stability test): from
/// there a step usually lands on the answer (a tendon-driven rod's forward solve from a joint
/// step's start, 100-600 times the tolerance off, converged in one step); where it does not, the
/// same point is swept again with the tangents.
const PLAIN_REACH: f64 = 1000.0;

/// Chord steps at most after a plain first sweep that did not confirm (each one plain sweep and
/// one of the solve's iterations).
const CHORD_STEPS: u8 = 3;

/// The contraction a chord step must reach (its residual over the last) for the next to be tried;
/// a chord step that lowers the residual less is kept, and the tangents follow.
const CHORD_CONTRACTION: f64 = 0.25;

/// How a start expected to be the answer is confirmed (see [`NewtonOptions::plain_first`]): a plain
/// sweep, and where it does not confirm, chord steps with `jacobian` (a sweep's near the start,
/// taken there for another purpose), each on a plain sweep, while each lowers the residual by
/// [`CHORD_CONTRACTION`] (at most [`CHORD_STEPS`], each counted among the solve's iterations, and
/// one fewer than those); then the tangents. A chord step costs a plain
/// sweep where Newton's costs one with tangents, and near the answer contracts almost as well.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Chord<'a, T, const K: usize> {
    pub jacobian: &'a SMatrix<T, K, K>,
}

/// The outcome of one Newton solve at a fixed load scale.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Newton<T, const K: usize> {
    pub x: SVector<T, K>,
    pub sweep: Sweep<T, K>,
    /// The residual's size at `x`.
    pub residual: T,
    pub termination: Termination,
}

/// Damped Newton on the unknowns of `ode` from `start`; `first` is the sweep at `start` when the
/// caller has it already; `chord`, a Jacobian for a plain first sweep's chord steps ([`Chord`]).
pub(crate) fn newton<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    start: SVector<T, K>,
    first: Option<&Sweep<T, K>>,
    chord: Option<Chord<'_, T, K>>,
    options: &NewtonOptions<T>,
    work: &mut Work,
) -> Newton<T, K>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let mut x = start;
    let plain_first = first.is_none() && options.plain_first;
    // Iterations the chord steps used: Newton gets what they left.
    let mut used = 0u16;
    let mut sw = match first {
        Some(sw) => *sw,
        None => {
            work.sweep();
            let which = if plain_first {
                TangentSet::NONE
            } else {
                options.tangents
            };
            sweep(ode, &x, which, None)
        }
    };
    if plain_first {
        let before = work.iterations;
        let confirmed = sw.finite
            && (converged(ode, &sw, &x, options)
                || chord
                    .is_some_and(|c| chord_steps(ode, &mut x, &mut sw, c.jacobian, options, work)));
        used = work.iterations.saturating_sub(before);
        if confirmed {
            return Newton {
                x,
                residual: ode.residual_size(&sw.residual),
                sweep: sw,
                termination: Termination::Converged,
            };
        }
        work.sweep();
        sw = sweep(ode, &x, options.tangents, None);
    }
    let rest = NewtonOptions {
        max_iterations: options.max_iterations.saturating_sub(used),
        ..*options
    };
    let (residual, termination) = newton_in_place(ode, &mut x, &mut sw, &rest, work);
    Newton {
        x,
        sweep: sw,
        residual,
        termination,
    }
}

/// Chord steps from `x`, whose plain sweep is `sw`, with `jacobian` ([`Chord`]), each within the
/// trust region: `x` and `sw` move to each step that lowers the residual. Whether the solve is
/// converged there. Out of line: its trial sweep stays out of the caller's frame.
#[inline(never)]
fn chord_steps<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    x: &mut SVector<T, K>,
    sw: &mut Sweep<T, K>,
    jacobian: &SMatrix<T, K, K>,
    options: &NewtonOptions<T>,
    work: &mut Work,
) -> bool
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let lu = jacobian.lu();
    let max_step = options.max_step_rad / ode.length_m();
    let mut residual = ode.residual_size(&sw.residual);
    // (At least one Newton iteration is left after them.)
    let steps = u16::from(CHORD_STEPS).min(options.max_iterations.saturating_sub(1));
    for _ in 0..steps {
        let Some(step) = bounded_step(&lu, &sw.residual, max_step) else {
            return false;
        };
        work.sweep();
        work.iterations = work.iterations.saturating_add(1);
        let trial_x = *x + step;
        let trial = sweep(ode, &trial_x, TangentSet::NONE, None);
        let size = ode.residual_size(&trial.residual);
        if !(trial.finite && size < residual) {
            return false;
        }
        (*x, *sw) = (trial_x, trial);
        if converged(ode, sw, x, options) {
            return true;
        }
        if size > residual * T::lit(CHORD_CONTRACTION) {
            return false;
        }
        residual = size;
    }
    false
}

/// The step `lu` (a factored Jacobian) gives against the residual `residual`, if finite and within
/// the trust region `max_step` (a change of the unknowns, 1/m).
#[inline]
pub(crate) fn bounded_step<T: Scalar, const K: usize>(
    lu: &LU<T, Const<K>, Const<K>>,
    residual: &SVector<T, K>,
    max_step: T,
) -> Option<SVector<T, K>>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    lu.solve::<Const<K>, Const<1>, _>(&-residual)
        .filter(|d| d.iter().all(|x| x.is_finite()) && d.norm() <= max_step)
}

/// Whether the sweep `sw` at unknowns `x` meets the options' tolerance.
pub(crate) fn converged<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    sw: &Sweep<T, K>,
    x: &SVector<T, K>,
    options: &NewtonOptions<T>,
) -> bool {
    let size = ode.residual_size(&sw.residual);
    if options.to_rounding {
        stopping::residual_converged(size, ode.rotation_rad(x), options.tolerance)
    } else {
        size <= options.tolerance
    }
}

/// [`newton`] in place: from `x`, whose sweep `sw` is, to where the solve stops, `sw` following.
/// Returns the residual's size there and why it stopped. Out of line: the caller's sweep is not
/// copied into its frame. For equations without a stability test `sw` may end without tangents
/// (a plain sweep that met the tolerance, [`PLAIN_REACH`]): a caller that reads tangents from it
/// afterwards must solve equations with a test (the reduced inverse's projection reads the tip
/// force's, on the dead-load rod).
#[inline(never)]
pub(crate) fn newton_in_place<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    x: &mut SVector<T, K>,
    sw: &mut Sweep<T, K>,
    options: &NewtonOptions<T>,
    work: &mut Work,
) -> (T, Termination)
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    let run = |x: &SVector<T, K>, work: &mut Work| {
        work.sweep();
        sweep(ode, x, options.tangents, None)
    };
    if !sw.finite {
        return (T::zero(), Termination::NonFinite);
    }
    let length = ode.length_m();
    let tolerance = options.tolerance;
    let converged = |sw: &Sweep<T, K>, x: &SVector<T, K>| converged(ode, sw, x, options);
    let mut residual = ode.residual_size(&sw.residual);
    let mut mu = T::zero();
    let mut rejections = 0u8;
    for _ in 0..options.max_iterations {
        if converged(sw, x) {
            return (residual, Termination::Converged);
        }
        let jacobian = sw.jacobian();
        let step: Option<SVector<T, K>> = if mu == T::zero() {
            jacobian.lu().solve::<Const<K>, Const<1>, _>(&-sw.residual)
        } else {
            let jtj = jacobian.tr_mul(&jacobian);
            let damped = jtj + SMatrix::<T, K, K>::from_diagonal(&jtj.diagonal()) * mu;
            damped.cholesky().map(|c| {
                let gradient = jacobian.tr_mul::<Const<K>, Const<1>, _>(&sw.residual);
                c.solve::<Const<K>, Const<1>, _>(&-gradient)
            })
        };
        let Some(mut step) = step.filter(|d| d.iter().all(|x| x.is_finite())) else {
            if mu == T::zero() {
                mu = T::lit(1e-3);
                continue;
            }
            return (residual, Termination::Singular);
        };
        // At the rounding floor the residual stops decreasing. A Newton correction that turns the base
        // by less than the tolerance or a long sweep's floor (`stopping::correction_at_floor`) and
        // moves the tip by less than the tolerance may mean the answer is as good as the scalar type
        // allows: it is when the tip move is negligible outright, or when the
        // correction, tried, no longer lowers the residual. On a badly conditioned rod a correction
        // that small can still lower the residual a hundredfold and move the tip by a tenth of a
        // millimetre.
        let tip_move = sw.tip_move_m(&step);
        let at_floor = options.to_rounding
            && mu == T::zero()
            && stopping::correction_at_floor(
                step.norm() * length,
                ode.rotation_rad(x),
                tip_move,
                length,
                tolerance,
            );
        if at_floor && stopping::tip_move_negligible(tip_move, length, tolerance) {
            return (residual, Termination::Converged);
        }
        // The trust region, measured by how far the step moves the shape (`RodOde::change_rad`:
        // the base rotation for most equations; a tendon-driven rod's base force counted by the
        // turn its chords make, MODEL.md §6.5).
        let change = ode.change_rad(&step);
        if change > options.max_step_rad {
            step *= options.max_step_rad / change;
        }
        work.iterations = work.iterations.saturating_add(1);
        let trial_x = *x + step;
        // Equations without a stability test read no tangents at their answer: a full Newton step
        // from near it is swept without them first, and again with them where that sweep is better
        // but not the answer (the next step needs its Jacobian). A worse one is rejected as it is.
        let plain = !ode.has_stability_test()
            && mu == T::zero()
            && residual <= tolerance * T::lit(PLAIN_REACH);
        work.sweep();
        let mut trial = sweep(
            ode,
            &trial_x,
            if plain {
                TangentSet::NONE
            } else {
                options.tangents
            },
            None,
        );
        if plain
            && trial.finite
            && ode.residual_size(&trial.residual) < residual
            && !converged(&trial, &trial_x)
        {
            trial = run(&trial_x, work);
        }
        let trial_residual = if trial.finite {
            ode.residual_size(&trial.residual)
        } else {
            residual
        };
        if trial.finite && trial_residual < residual {
            (*x, *sw, residual) = (trial_x, trial, trial_residual);
            mu *= T::lit(0.25);
            if mu < T::lit(1e-6) {
                mu = T::zero();
            }
            rejections = 0;
        } else if at_floor {
            return (residual, Termination::Converged);
        } else {
            mu = if mu == T::zero() {
                T::lit(1e-3)
            } else {
                mu * T::lit(8.0)
            };
            rejections += 1;
            if rejections >= MAX_REJECTIONS {
                let termination = if converged(sw, x) {
                    Termination::Converged
                } else {
                    Termination::Stalled
                };
                return (residual, termination);
            }
        }
    }
    let termination = if converged(sw, x) {
        Termination::Converged
    } else {
        Termination::IterationLimit
    };
    (residual, termination)
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::loads::TipLoad;
    use crate::ode::tendon::TendonRod;
    use crate::shooting::ShootingSettings;
    use crate::tendon::{MAX_TENDONS, Tendons};

    /// The tendon scene solved at tensions of 2 and 1.2 N under a tip force.
    struct Scene {
        model: crate::model::Model<f64>,
        set: Tendons<f64>,
        tensions_n: [f64; MAX_TENDONS],
        load: TipLoad<f64>,
        solved: crate::tendon::TendonEquilibrium<f64>,
    }

    impl Scene {
        fn solved() -> Self {
            let (model, tendons) = crate::ode::tendon::tests::scene();
            let set = Tendons::new(&model, &tendons).unwrap();
            let load = TipLoad::force(Vector3::new(0.05, -0.1, 0.02));
            let tau = [2.0, 1.2];
            let solved = model
                .solve_tendons(&set, &tau, &load, None, &ShootingSettings::default())
                .unwrap();
            assert!(solved.is_success());
            let mut tensions_n = [0.0; MAX_TENDONS];
            tensions_n[..2].copy_from_slice(&tau);
            Self {
                model,
                set,
                tensions_n,
                load,
                solved,
            }
        }

        /// The scene's rod equations and the unknowns of its answer.
        fn rod(
            &self,
        ) -> (
            TendonRod<'_, f64, crate::kinematics::Quaternion<f64>, { crate::plan::MAX_NODES }>,
            SVector<f64, 6>,
        ) {
            let ode = TendonRod::new(&self.model, &self.set, &self.tensions_n, &self.load, 1.0);
            let eq = &self.solved.equilibrium;
            let answer = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
            (ode, answer)
        }
    }

    /// A forward solve's options to rounding, 20 iterations, the unknowns' tangents.
    fn to_rounding(plain_first: bool) -> NewtonOptions<f64> {
        let settings = ShootingSettings::<f64>::default();
        NewtonOptions {
            tolerance: settings.tolerance,
            to_rounding: true,
            max_step_rad: settings.max_rotation_step_rad,
            max_iterations: 20,
            tangents: TangentSet::unknowns(false),
            plain_first,
        }
    }

    /// Each exit of the chord steps, on the tendon scene from 0.1 % or 1 % off its answer with a
    /// Jacobian `J` taken at the answer: with `J` they converge (each step one plain sweep and one
    /// iteration); a step beyond the trust region (`J / 1e9`) is refused before its sweep and
    /// leaves the start; a trial that does not lower the residual (`-J`) is swept and left; a step
    /// that lowers it less than fourfold (`2 J`: by half) is kept and ends them; steps that lower it
    /// enough but slowly (`1.2 J`: sixfold) stop after `CHORD_STEPS`; and they leave the solve at
    /// least one iteration.
    #[test]
    fn chord_steps_take_only_steps_that_contract() {
        let scene = Scene::solved();
        let (ode, answer) = scene.rod();
        let eq = &scene.solved.equilibrium;
        let j = sweep(&ode, &answer, TangentSet::unknowns(false), None).jacobian();
        let options = to_rounding(true);
        // (jacobian, start off by, iterations allowed, converged, chord sweeps, moved)
        let cases = [
            (j, 1e-3, 20, true, None, true),
            (j / 1e9, 1e-3, 20, false, Some(0), false),
            (-j, 1e-3, 20, false, Some(1), false),
            (j * 2.0, 1e-3, 20, false, Some(1), true),
            (
                j * 1.2,
                1e-2,
                20,
                false,
                Some(usize::from(CHORD_STEPS)),
                true,
            ),
            (j * 1.2, 1e-2, 2, false, Some(1), true),
        ];
        for (k, (jacobian, off, iterations, converges, chords, moves)) in
            cases.into_iter().enumerate()
        {
            let start = ode.unknowns(&(eq.base_force_n * (1.0 + off)), &eq.base_moment_nm);
            let mut x = start;
            let mut sw = sweep(&ode, &x, TangentSet::NONE, None);
            let before = ode.residual_size(&sw.residual);
            let options = NewtonOptions {
                max_iterations: iterations,
                ..options
            };
            assert!(
                !converged(&ode, &sw, &x, &options),
                "case {k}: the start is off"
            );
            let mut work = Work::default();
            let done = chord_steps(&ode, &mut x, &mut sw, &jacobian, &options, &mut work);
            assert_eq!(done, converges, "case {k}");
            assert_eq!(
                work.sweeps, work.iterations,
                "case {k}: one plain sweep a step"
            );
            if let Some(chords) = chords {
                assert_eq!(usize::from(work.sweeps), chords, "case {k}");
            } else {
                assert!(work.sweeps <= u16::from(CHORD_STEPS), "case {k}: {work:?}");
            }
            assert_eq!(x != start, moves, "case {k}");
            // Where they stopped, `sw` is `x`'s plain sweep and no worse than the start.
            let again = sweep(&ode, &x, TangentSet::NONE, None);
            assert_eq!(again.residual, sw.residual, "case {k}");
            let after = ode.residual_size(&sw.residual);
            assert!(after <= before, "case {k}");
            if converges {
                let apart = (x - answer).norm() / answer.norm();
                assert!(apart < 1e-12, "case {k}: {apart:e} from the answer");
            }
        }
    }

    /// A full Newton step from within `PLAIN_REACH` of the tolerance is swept without tangents
    /// where the answer reads none (the tendon rod: no stability test), and the solve ends on that
    /// sweep at the answer; the dead-load rod, whose verdict reads them, keeps them on its last
    /// sweep.
    #[test]
    fn a_step_near_the_answer_is_swept_without_tangents_where_none_are_read() {
        let scene = Scene::solved();
        let (ode, answer) = scene.rod();
        let eq = &scene.solved.equilibrium;
        let options = to_rounding(false);
        let x = ode.unknowns(&(eq.base_force_n * (1.0 + 1e-10)), &eq.base_moment_nm);
        let (x, sw, work) = converged_from_near(&ode, x, &options);
        assert!(!sw.has_jacobian(), "the answer's sweep carried tangents");
        assert_eq!(work.sweeps, 1, "{work:?}");
        let apart = (x - answer).norm() / answer.norm();
        assert!(apart < 1e-12, "{apart:e} from the answer");

        let dead = crate::ode::dead_load::DeadLoadRod::new(&scene.model, &scene.load, 1.0);
        let cold = scene
            .model
            .solve(
                &scene.load,
                crate::Start::Cold,
                &ShootingSettings::default(),
            )
            .unwrap();
        assert!(cold.report.termination.is_success());
        let u = cold.base_strain_per_m * (1.0 + 1e-9);
        let (_, sw, _) = converged_from_near(&dead, u, &options);
        assert!(
            sw.has_jacobian(),
            "the dead-load answer's sweep lost its tangents"
        );
    }

    /// Newton in place from `x`, which must be off by more than the tolerance and within
    /// `PLAIN_REACH` of it, to a converged answer: its unknowns, its sweep and the work after the
    /// start's sweep (which carries `options`' tangents).
    fn converged_from_near<O: RodOde<f64, K>, const K: usize>(
        ode: &O,
        mut x: SVector<f64, K>,
        options: &NewtonOptions<f64>,
    ) -> (SVector<f64, K>, Sweep<f64, K>, Work)
    where
        Const<K>: DimMin<Const<K>, Output = Const<K>>,
    {
        let mut sw = sweep(ode, &x, options.tangents, None);
        let off = ode.residual_size(&sw.residual);
        assert!(
            off > options.tolerance && off <= options.tolerance * PLAIN_REACH,
            "the start is off by {off:e}, within reach"
        );
        let mut work = Work::default();
        let (_, termination) = newton_in_place(ode, &mut x, &mut sw, options, &mut work);
        assert_eq!(termination, Termination::Converged);
        (x, sw, work)
    }
}
