//! A displacement step on the tensions and the base together (MODEL.md §6.3): one sweep at the
//! forward solve's predicted start gives the tip condition's residual `r` and Jacobian `J` there,
//! and how the tendons' paths change along its tangents; with the carried sensitivities that is
//! a Newton step on both, so that the forward solve at the corrected tensions starts converged to
//! first order and, on a tracking step, confirms in one more sweep (without tangents) instead of
//! two; where it does not confirm, chord steps with this sweep's `J` follow, each a sweep without
//! tangents (`crate::solve::Chord`).
//!
//! At the plain step's trial tensions `tau` and the predicted base `x_p`, `dx = -J^-1 r` is the
//! forward solve's own Newton step; the unstretched lengths it leads to are
//! `N + (dN/dpath)(dpath/dx) dx` (the paths' changes traced by the sweep, `PathChanges`). The
//! tensions' correction `dtau` solves the complementarity linearised there with the carried
//! `dN/dtau` exactly (Josephy-Newton, `complementarity.rs`: a tendon that goes taut or slack in
//! the tick does so in this step), and the base moves on by the carried `d_base dtau` (at a fixed
//! base the tip condition changes by `-J d_base dtau`, so both hold to first order). The forward
//! solve from there decides: its equilibrium is the step's, checked as every step's is.
//! Frictionless only: with capstan friction the chords' tensions read the wrap angles, whose
//! changes the sweep does not trace.

use nalgebra::{SMatrix, SVector};

use super::actuation::{BaseWrench, Tracking, base_move, difference};
use super::complementarity::Complementarity;
use super::paths::lengths;
use super::{MAX_TENDONS, Tendons};
use crate::Scalar;
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::tendon::{GuideRecord, JumpMemory, PathChanges, TendonRod};
use crate::sweep::{TangentSet, sweep};

/// Where a joint step leads: the tensions, N, and the forward solve's start there, base force (N)
/// and moment (N m).
pub(super) struct JointStep<T> {
    pub tensions_n: [T; MAX_TENDONS],
    pub base: BaseWrench<T>,
    /// The residual expected at the start (dimensionless, as the forward solve's tolerance): the
    /// squares of the base's Newton step, `|dx| L`, and of the tensions' move of the base in
    /// tracking scales (Newton's quadratic convergence; a carried sensitivity's error grows with
    /// the move). Where it is within the chord steps' reach of the tolerance the forward solve's
    /// first sweep goes without tangents (at a tendon's change of state, the Newton step's square
    /// alone promised a converged start that was not).
    pub expected_residual: T,
    /// The tip condition's Jacobian in the forward solve's unknowns at the step's sweep: near the
    /// start, for the forward solve's chord steps where its confirming sweep does not confirm.
    pub jacobian: SMatrix<T, 6, 6>,
}

/// The joint step's sweep: its unknowns `x`, the tip condition's Jacobian there and its Newton
/// step `dx`.
struct JointSweep<'a, T> {
    x: &'a SVector<T, 6>,
    dx: &'a SVector<T, 6>,
    jacobian: &'a SMatrix<T, 6, 6>,
}

/// The carried sensitivities a joint step reads: the needed unstretched lengths' and the base's
/// to the tensions (see [`super::DisplacementSolve`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Sensitivities<'a, T> {
    pub d_length_d_tension: &'a SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    pub d_base_d_tension: &'a SMatrix<T, 6, MAX_TENDONS>,
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// The joint step from tensions `tau` (each at least zero) and the base `start` (force N,
    /// moment N m) predicted from the last equilibrium's, `anchor`, in one sweep (whatever the
    /// outcome). The step is `None` where the sweep or a linear solve fails, or where the forward
    /// solve would start more than a `tracking` step from `anchor` (the bound on the plain step's
    /// prediction too: a longer move could start it on another branch). The caller then takes
    /// its plain step.
    // Out of line: its record and sweep stay out of the displacement solve's frame, under every
    // later forward solve.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn joint_step(
        &self,
        tendons: &Tendons<T>,
        load: &TipLoad<T>,
        fb: &Complementarity<'_, T>,
        tau: &[T; MAX_TENDONS],
        start: BaseWrench<T>,
        anchor: BaseWrench<T>,
        carried: &Sensitivities<'_, T>,
        tracking: &Tracking<T>,
        memory: &JumpMemory<T, NODES>,
    ) -> Option<JointStep<T>> {
        let record = GuideRecord::new();
        let paths = PathChanges::new();
        let ode = TendonRod::new(self, tendons, tau, load, T::one())
            .recording(&record)
            .tracing_paths(&paths)
            .remembering(memory)
            .jumping_ahead();
        let x = ode.unknowns(&start.0, &start.1);
        let sw = sweep(&ode, &x, TangentSet::unknowns(false), None);
        let jacobian = sw.jacobian();
        // The forward solve's Newton step at these tensions.
        let dx = sw
            .finite
            .then(|| jacobian.lu().solve(&(-sw.residual)))
            .flatten()
            .filter(crate::scalar::all_finite);
        dx.and_then(|dx| {
            let at = JointSweep {
                x: &x,
                dx: &dx,
                jacobian: &jacobian,
            };
            self.joint_from(
                tendons, fb, tau, carried, tracking, anchor, &ode, &record, &paths, &at,
            )
        })
    }

    /// The joint step after its sweep at `x` (kept in `record`), from the base's Newton step `dx`
    /// (`JointSweep`).
    /// Out of line: its buffers (the guides' poses, the complementarity's Jacobian) stay out of
    /// the sweep's frame.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn joint_from(
        &self,
        tendons: &Tendons<T>,
        fb: &Complementarity<'_, T>,
        tau: &[T; MAX_TENDONS],
        carried: &Sensitivities<'_, T>,
        tracking: &Tracking<T>,
        (anchor_force_n, anchor_moment_nm): BaseWrench<T>,
        ode: &TendonRod<'_, T, A, NODES>,
        record: &GuideRecord<T>,
        paths: &PathChanges<T>,
        &JointSweep { x, dx, jacobian }: &JointSweep<'_, T>,
    ) -> Option<JointStep<T>> {
        let count = tendons.len();
        let guides = tendons.guide_s_m.len();
        let d_path = paths.along(record, x, guides, 6)?;
        let poses = record.poses_at(x, guides)?;
        let rod = self.rod();
        let now = lengths(
            tendons,
            tau.get(..count)?,
            &rod.base_position_m,
            &rod.base_orientation,
            poses.get(..guides)?,
        )?;
        // The unstretched lengths after the base's step, and the complementarity's Newton step
        // there.
        let mut needed = now.unstretched_m;
        for (((n, d), t), tension) in needed
            .iter_mut()
            .zip(&d_path)
            .zip(tendons.tendons())
            .zip(tau)
        {
            let path_change_m = d
                .iter()
                .zip(dx.iter())
                .fold(T::zero(), |a, (d, x)| a + *d * *x);
            *n += t.unstretched_m(path_change_m, *tension);
        }
        let (r, parts, phi) = fb.residual(needed.get(..count)?, tau);
        let dtau = fb.josephy_step(tau, &phi, (&r, &parts), carried.d_length_d_tension)?;
        // (Checked before the clamp, which would take a NaN to zero.)
        let mut tensions_n = *tau;
        for (t, d) in tensions_n.iter_mut().zip(dtau.iter()).take(count) {
            *t = (*t + *d).max(T::zero());
        }
        // Where the forward solve starts: the base after its Newton step, moved on by the
        // tensions' step, within a tracking step of the last equilibrium's.
        let moved = base_move(carried.d_base_d_tension, &difference(&tensions_n, tau));
        let (_, force_n, moment_nm) = ode.base(&(x + dx));
        let force_n = force_n + moved.0;
        let moment_nm = moment_nm + moved.1;
        if !tracking.allows(&(force_n - anchor_force_n), &(moment_nm - anchor_moment_nm)) {
            return None;
        }
        let newton_rad = dx.norm() * self.length_m();
        Some(JointStep {
            tensions_n,
            base: (force_n, moment_nm),
            expected_residual: newton_rad * newton_rad + tracking.squared(&moved),
            jacobian: *jacobian,
        })
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::ode::RodOde;

    /// The paths' changes a recording sweep keeps along its six tangents are the paths'
    /// derivatives: central differences of the paths of plain sweeps, for a tendon ending mid-way
    /// and one at the tip. A plain sweep keeps none.
    #[test]
    fn tendon_path_changes_match_finite_differences() {
        let (model, tendons) = crate::ode::tendon::tests::scene();
        let tendons = Tendons::new(&model, &tendons).unwrap();
        let mut tau = [0.0; MAX_TENDONS];
        tau[0] = 2.0;
        tau[1] = 1.5;
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        let guides = tendons.guide_s_m.len();
        let rod = model.rod();
        let record = GuideRecord::new();
        let traced = PathChanges::new();
        let ode = TendonRod::new(&model, &tendons, &tau, &load, 1.0)
            .recording(&record)
            .tracing_paths(&traced);
        let x = ode.guess() * 0.7;
        assert!(sweep(&ode, &x, TangentSet::unknowns(false), None).finite);
        let d = traced.along(&record, &x, guides, 6).unwrap();
        let paths = |x: &SVector<f64, 6>| {
            let plain = GuideRecord::new();
            let untraced = PathChanges::new();
            let ode = TendonRod::new(&model, &tendons, &tau, &load, 1.0)
                .recording(&plain)
                .tracing_paths(&untraced);
            assert!(sweep(&ode, x, TangentSet::NONE, None).finite);
            assert!(untraced.along(&plain, x, guides, 6).is_none());
            let poses = plain.poses_at(x, guides).unwrap();
            lengths(
                &tendons,
                &tau[..2],
                &rod.base_position_m,
                &rod.base_orientation,
                &poses[..guides],
            )
            .unwrap()
            .path_m
        };
        let scale = d.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        let h = 1e-6;
        let mut worst = 0.0f64;
        for k in 0..6 {
            let mut dx = SVector::<f64, 6>::zeros();
            dx[k] = h;
            let (plus, minus) = (paths(&(x + dx)), paths(&(x - dx)));
            for j in 0..2 {
                let fd = (plus[j] - minus[j]) / (2.0 * h);
                worst = worst.max((fd - d[j][k]).abs() / scale);
            }
        }
        // The same discretisation floor as the sweep's Jacobian (`ode/tendon.rs`): 2.7e-7 here,
        // the same with steps of 1e-4 to 1e-6; leaving out the previous hole's turn fails by 0.6.
        assert!(worst < 5e-7, "path changes off by {worst:e} (relative)");
    }
}
