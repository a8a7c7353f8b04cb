//! The forward solve from tensions (force control): the equilibrium of the rod under the tendons'
//! tensions, the scene's gravity and point loads and a tip load, and each tendon's path length.

use heapless::Vec;
use nalgebra::{SVector, Vector3};

use super::paths::{Lengths, lengths};
use super::{MAX_TENDONS, Tendons};

use crate::error::{ModelError, finite_vec};
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::tendon::{GuideRecord, JumpMemory, TendonRod};
use crate::report::Termination;
use crate::shape::ShapePoint;
use crate::shooting::{Equilibrium, ShootingSettings, equilibrium, shape_of};
use crate::solve::Confirm;
use crate::tendon::guide_force::GuidePose;
use crate::{MAX_GUIDES, Scalar};

/// An equilibrium under tendon tensions.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonEquilibrium<T> {
    /// The rod's equilibrium (base force and moment, tip pose, the solve's report).
    pub equilibrium: Equilibrium<T>,
    /// The tensions it was solved for, N, one per tendon.
    pub tensions_n: Vec<T, MAX_TENDONS>,
    /// Each tendon's path length, m (empty unless the solve succeeded).
    pub path_m: Vec<T, MAX_TENDONS>,
    /// Each tendon's unstretched length from spool to termination that the equilibrium needs, m:
    /// its feed and chords, each shortened by its own tension's stretch (the path plus the feed for
    /// an inextensible tendon). Empty unless the solve succeeded.
    pub unstretched_m: Vec<T, MAX_TENDONS>,
}

impl<T: Scalar> TendonEquilibrium<T> {
    /// Whether the solve converged to an accepted equilibrium.
    pub fn is_success(&self) -> bool {
        self.equilibrium.report.termination.is_success()
    }

    /// The base's internal force (N, rows 0-2) and moment (N m, rows 3-5), stacked.
    pub(crate) fn base(&self) -> SVector<T, 6> {
        let eq = &self.equilibrium;
        crate::scalar::stacked(&eq.base_force_n, &eq.base_moment_nm)
    }
}

impl<T: Scalar> Tendons<T> {
    /// What a shape sweep of `solved` on `model` needs checked: these tendons against the model,
    /// the tensions, a finite base and a valid tip load. Returns the tensions.
    pub(super) fn check_solved<A: Attitude<T>, const NODES: usize>(
        &self,
        model: &Model<T, A, NODES>,
        solved: &TendonEquilibrium<T>,
    ) -> Result<[T; MAX_TENDONS], ModelError> {
        self.check_model(model)?;
        let tau = self.check_tensions(&solved.tensions_n)?;
        let eq = &solved.equilibrium;
        finite_vec(&eq.base_force_n, "base force")?;
        finite_vec(&eq.base_moment_nm, "base moment")?;
        eq.load.validate()?;
        Ok(tau)
    }

    /// Whether these tendons were checked against a model with `model`'s guides.
    pub(super) fn check_model<A: Attitude<T>, const NODES: usize>(
        &self,
        model: &Model<T, A, NODES>,
    ) -> Result<(), ModelError> {
        let guides = &model.rod().guides;
        if guides.len() != self.guide_s_m.len()
            || guides.iter().zip(&self.guide_s_m).any(|(g, s)| g.s_m != *s)
        {
            return Err(ModelError::Mismatch("tendons and the model's guides"));
        }
        Ok(())
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Solves the equilibrium under tendon tensions `tensions_n` (N, one per tendon, none negative),
    /// the scene's dead loads and `load` at the tip, and each tendon's path length.
    ///
    /// From a cold start the tensions and loads are ramped from zero (load continuation): there is
    /// no energy test of stability with tendons yet, and `report.stability` says
    /// [`crate::Stability::Unchecked`]. A warm start takes a previous equilibrium.
    ///
    /// Fails only on invalid input; a solve that does not converge returns `Ok` with the reason in
    /// the report.
    pub fn solve_tendons(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        load: &TipLoad<T>,
        start: Option<&TendonEquilibrium<T>>,
        settings: &ShootingSettings<T>,
    ) -> Result<TendonEquilibrium<T>, ModelError> {
        // A failed equilibrium is no start: its zeros would send a direct Newton off at full load.
        let start = start
            .filter(|s| s.is_success())
            .map(|s| (s.equilibrium.base_force_n, s.equilibrium.base_moment_nm));
        self.solve_tendons_from(tendons, tensions_n, load, start, settings, None, None)
    }

    /// [`Model::solve_tendons`] from a base force (N) and moment (N m), or cold; `confirm`: the
    /// start is expected to be the answer, its first sweep goes without tangents, then chord steps
    /// if it brings a Jacobian (`crate::solve::solve_from`); `memory`: where the guides' jumps
    /// converged in earlier sweeps, for its sweeps without tangents to start from and its sweeps
    /// to keep (`JumpMemory`).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve_tendons_from(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        load: &TipLoad<T>,
        start: Option<(Vector3<T>, Vector3<T>)>,
        settings: &ShootingSettings<T>,
        confirm: Option<Confirm<'_, T, 6>>,
        memory: Option<&JumpMemory<T, NODES>>,
    ) -> Result<TendonEquilibrium<T>, ModelError> {
        tendons.check_model(self)?;
        let tau = tendons.check_tensions(tensions_n)?;
        load.validate()?;
        settings.validate()?;
        let record = GuideRecord::new();
        let mut ode = TendonRod::new(self, tendons, &tau, load, T::one()).recording(&record);
        if let Some(memory) = memory {
            ode = ode.remembering(memory);
        }
        let start = match start {
            Some((force_n, moment_nm)) => {
                finite_vec(&force_n, "warm-start base force")?;
                finite_vec(&moment_nm, "warm-start base moment")?;
                Some(ode.unknowns(&force_n, &moment_nm))
            }
            None => None,
        };
        let outcome = crate::solve::solve_from(&ode, start, settings, confirm, 0);
        let x = outcome.as_ref().ok().map(|s| s.newton.x);
        let mut eq = equilibrium(load, 0, outcome, |x| ode.base(x));
        let mut tensions = Vec::new();
        for t in tensions_n {
            // Cannot overflow: checked against MAX_TENDONS.
            let _ = tensions.push(*t);
        }
        let mut path_m = Vec::new();
        let mut unstretched_m = Vec::new();
        if let (true, Some(x)) = (eq.report.termination.is_success(), x) {
            match self
                .tendon_lengths(tendons, tensions_n, &ode, &record, &x)
                .filter(|l| {
                    l.path_m
                        .iter()
                        .chain(&l.unstretched_m)
                        .all(|v| v.is_finite())
                }) {
                Some(lengths) => {
                    for (p, u) in lengths
                        .path_m
                        .iter()
                        .zip(&lengths.unstretched_m)
                        .take(tendons.len())
                    {
                        // Cannot overflow: at most MAX_TENDONS.
                        let _ = path_m.push(*p);
                        let _ = unstretched_m.push(*u);
                    }
                }
                None => eq.report.termination = Termination::NonFinite,
            }
        }
        Ok(TendonEquilibrium {
            equilibrium: eq,
            tensions_n: tensions,
            path_m,
            unstretched_m,
        })
    }

    /// The tendons' lengths at the answer `x`: from the guides the solve's last sweep passed when
    /// it was at `x` (the converged sweep), else from a shape sweep. Out of line: its buffers stay
    /// out of the solve's frame.
    #[inline(never)]
    fn tendon_lengths(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        ode: &TendonRod<'_, T, A, NODES>,
        record: &GuideRecord<T>,
        x: &SVector<T, 6>,
    ) -> Option<Lengths<T>> {
        let count = tendons.guide_s_m.len();
        let poses = match record.poses_at(x, count) {
            Some(poses) => poses,
            None => guide_poses(ode, x, &tendons.guide_s_m)?,
        };
        let rod = self.rod();
        lengths(
            tendons,
            tensions_n,
            &rod.base_position_m,
            &rod.base_orientation,
            poses.get(..count)?,
        )
    }

    /// The backbone of a tendon equilibrium at the arc lengths `s_m` (see [`Model::shape`]).
    pub fn shape_tendons(
        &self,
        tendons: &Tendons<T>,
        solved: &TendonEquilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        let tau = tendons.check_solved(self, solved)?;
        let eq = &solved.equilibrium;
        let ode = TendonRod::new(self, tendons, &tau, &eq.load, T::one());
        let x = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        shape_of(&ode, &x, s_m, out)
    }
}

/// The guides' poses at the arc lengths `guide_s_m` of `ode` at unknowns `x`, by a shape sweep.
#[inline(never)]
fn guide_poses<T: Scalar, A: Attitude<T>, const NODES: usize>(
    ode: &TendonRod<'_, T, A, NODES>,
    x: &SVector<T, 6>,
    guide_s_m: &[T],
) -> Option<[GuidePose<T>; MAX_GUIDES]> {
    let mut points = [ShapePoint::default(); MAX_GUIDES];
    let written = shape_of(ode, x, guide_s_m, points.get_mut(..guide_s_m.len())?).ok()?;
    (written == guide_s_m.len()).then(|| {
        points.map(|p| GuidePose {
            position_m: p.position_m,
            rotation: p.rotation,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tendon::{Sliding, Tendon};

    /// `ode::tendon`'s test scene, its tendons with friction `mu`, compliant, behind a feed.
    fn scene(mu: f64) -> (Model<f64>, [Tendon<f64>; 2]) {
        let (model, mut tendons) = crate::ode::tendon::tests::scene();
        for t in tendons.iter_mut() {
            t.friction_coefficient = mu;
            t.axial_stiffness_n = Some(2000.0);
            t.feed_length_m = 0.4;
        }
        (model, tendons)
    }

    /// The confirming solves' tensions, N.
    const CONFIRMING_TENSIONS_N: [f64; 2] = [2.0, 1.2];

    /// The confirming solves' scene (frictionless), its tendons, tip load, and the usual solve's
    /// answer at [`CONFIRMING_TENSIONS_N`].
    fn confirming() -> (
        Model<f64>,
        Tendons<f64>,
        TipLoad<f64>,
        TendonEquilibrium<f64>,
    ) {
        let (model, tendons) = scene(0.0);
        let set = Tendons::new(&model, &tendons).unwrap();
        let load = TipLoad::force(Vector3::new(0.05, -0.1, 0.02));
        let settings = ShootingSettings::default();
        let solved = model
            .solve_tendons(&set, &CONFIRMING_TENSIONS_N, &load, None, &settings)
            .unwrap();
        (model, set, load, solved)
    }

    /// `again` is `solved`'s answer: its tip and its first path within 1e-12 m.
    fn assert_same_answer(again: &TendonEquilibrium<f64>, solved: &TendonEquilibrium<f64>) {
        let tip = solved.equilibrium.tip_position_m;
        let apart = (again.equilibrium.tip_position_m - tip).norm();
        assert!(apart < 1e-12, "tips {apart:e} m apart");
        assert!((again.path_m[0] - solved.path_m[0]).abs() < 1e-12);
    }

    /// A solve started at its answer and expected converged takes one sweep (without tangents:
    /// `expected/bench.run`'s median warm update counts it); one expected converged that is not
    /// takes one sweep more than the usual solve from there and reaches the same answer.
    #[test]
    fn tendon_confirming_solve_takes_one_sweep_at_the_answer() {
        let (model, set, load, solved) = confirming();
        let (tau, settings) = (CONFIRMING_TENSIONS_N, ShootingSettings::default());
        let eq = &solved.equilibrium;
        let at = (eq.base_force_n, eq.base_moment_nm);
        let off = (eq.base_force_n * 1.01, eq.base_moment_nm);
        // At the answer the plain sweep confirms (the usual solve's one sweep carries tangents);
        // off it, the plain sweep is one more than the usual solve's four.
        let plain = Some(Confirm { chord: None });
        for (start, usual_sweeps, more) in [(at, 1, 0), (off, 4, 1)] {
            let again = model
                .solve_tendons_from(&set, &tau, &load, Some(start), &settings, plain, None)
                .unwrap();
            let usual = model
                .solve_tendons_from(&set, &tau, &load, Some(start), &settings, None, None)
                .unwrap();
            assert!(again.is_success(), "{:?}", again.equilibrium.report);
            assert_eq!(usual.equilibrium.report.sweeps, usual_sweeps);
            assert_eq!(
                again.equilibrium.report.sweeps,
                usual.equilibrium.report.sweeps + more
            );
            assert_same_answer(&again, &solved);
        }
    }

    /// A confirming solve that brings a Jacobian near its start takes chord steps on plain sweeps
    /// where the plain sweep does not confirm, and reaches the usual solve's answer: with the
    /// Jacobian at the answer from 1 % and 0.1 % off, chord steps alone, in at most the usual
    /// solve's four sweeps, none with tangents; with a Jacobian of the wrong sign, its chord step
    /// is refused and the tangents take over, to the same answer.
    #[test]
    fn tendon_confirming_solve_takes_chord_steps_to_the_same_answer() {
        use crate::solve::{Chord, Confirm};
        use crate::sweep::{TangentSet, sweep};
        let (model, set, load, solved) = confirming();
        let (tau, settings) = (CONFIRMING_TENSIONS_N, ShootingSettings::default());
        let eq = &solved.equilibrium;
        let mut all = [0.0; MAX_TENDONS];
        all[..2].copy_from_slice(&tau);
        let ode = TendonRod::new(&model, &set, &all, &load, 1.0);
        let x = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        let near = sweep(&ode, &x, TangentSet::unknowns(false), None).jacobian();
        // (Each chord step and each Newton step is an iteration with one sweep; the tangents
        // after chord steps take one more sweep, at the point the chord steps reached.)
        for (scale, jacobian, chord_only) in [
            (1.01, near, true),
            (1.001, near, true),
            (1.01, -near, false),
        ] {
            let off = (eq.base_force_n * scale, eq.base_moment_nm);
            let confirm = Some(Confirm {
                chord: Some(Chord {
                    jacobian: &jacobian,
                }),
            });
            let again = model
                .solve_tendons_from(&set, &tau, &load, Some(off), &settings, confirm, None)
                .unwrap();
            assert!(again.is_success(), "{:?}", again.equilibrium.report);
            let report = &again.equilibrium.report;
            let extra = if chord_only { 1 } else { 2 };
            assert_eq!(report.sweeps, report.iterations + extra, "{report:?}");
            if chord_only {
                assert!(report.sweeps <= 4, "{report:?}");
            }
            assert_same_answer(&again, &solved);
        }
    }

    /// The paths a solve reads from its converged sweep's guides are those of a shape sweep at
    /// its answer, to rounding, with and without friction; a record of another sweep is not used.
    #[test]
    fn tendon_paths_from_the_converged_sweep_are_the_shape_sweeps() {
        for (mu, sliding) in [(0.0, Sliding::In), (0.2, Sliding::In), (0.2, Sliding::Out)] {
            let (model, tendons) = scene(mu);
            let mut set = Tendons::new(&model, &tendons).unwrap();
            set.set_sliding(0, sliding);
            set.set_sliding(1, sliding);
            let tau = [2.0, 1.2];
            let load = TipLoad::force(Vector3::new(0.05, -0.1, 0.02));
            let solved = model
                .solve_tendons(&set, &tau, &load, None, &ShootingSettings::default())
                .unwrap();
            assert!(solved.is_success(), "{:?}", solved.equilibrium.report);
            let mut full = [0.0; MAX_TENDONS];
            full[..2].copy_from_slice(&tau);
            let ode = TendonRod::new(&model, &set, &full, &load, 1.0);
            let eq = &solved.equilibrium;
            let x = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
            let poses = guide_poses(&ode, &x, &set.guide_s_m).unwrap();
            let rod = model.rod();
            let swept = lengths(
                &set,
                &tau,
                &rod.base_position_m,
                &rod.base_orientation,
                &poses[..set.guide_s_m.len()],
            )
            .unwrap();
            for j in 0..2 {
                let path = (solved.path_m[j] - swept.path_m[j]).abs();
                let unstretched = (solved.unstretched_m[j] - swept.unstretched_m[j]).abs();
                assert!(path < 1e-14, "mu {mu} tendon {j}: paths {path:e} m apart");
                assert!(
                    unstretched < 1e-14,
                    "mu {mu} tendon {j}: {unstretched:e} m apart"
                );
            }
            // The solve's own last sweep is the one at its answer, so the record answers there
            // and no shape sweep is taken (the comparison above holds either way).
            let count = set.guide_s_m.len();
            let record = GuideRecord::new();
            let recording = TendonRod::new(&model, &set, &full, &load, 1.0).recording(&record);
            let again = crate::solve::solve(&recording, None, &ShootingSettings::default())
                .map(|s| s.newton.x)
                .unwrap();
            // (`x` went through the base force and moment: within an ulp of the solve's.)
            assert!(
                (again - x).norm() <= 1e-14 * x.norm(),
                "mu {mu}: the same solve"
            );
            let recorded = record
                .poses_at(&again, count)
                .expect("the converged sweep's record");
            for (a, b) in recorded.iter().zip(&poses).take(count) {
                let apart = (a.position_m - b.position_m).norm();
                assert!(apart < 1e-14, "mu {mu}: guide {apart:e} m apart");
            }
            // The record answers only for the sweep it saw.
            let _ = crate::sweep::sweep(&recording, &x, crate::sweep::TangentSet::NONE, None);
            assert!(record.poses_at(&x, count).is_some());
            assert!(record.poses_at(&(x * 1.001), count).is_none());
            assert!(record.poses_at(&x, count + 1).is_none());
        }
    }
}
