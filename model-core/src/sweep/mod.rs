//! One fixed-step sweep from base to tip over the plan, for any rod equations ([`RodOde`]), with
//! forward sensitivities and observers.
//!
//! The sweep walks the plan's intervals with the RK4 stepper (`rk4.rs`); at each node the equations
//! apply their jump (section change, point loads and moments, loads that read the shape), and the
//! observers look at the pose: the cable traces (`cables.rs`), the shape points asked for
//! (`crate::shape`), the frame's drift from a rotation, and after every step the conjugate-point
//! watch (`crate::stability`). At the tip the equations give the residual of the tip condition.
//!
//! Alongside the state the sweep can carry up to [`MAX_TANGENTS`] tangents, by family (the shooting
//! unknowns, then the tip force; or, at fixed unknowns, the tip force and the tendons' tensions).
//! The tangent count is a run-time number, so each set of equations
//! has one compiled sweep (the firmware's flash is small), and a plain sweep pays nothing for
//! tangents.

pub(crate) mod cables;
pub(crate) mod rk4;

use nalgebra::{SMatrix, SVector, Vector3};

use crate::kinematics::orthonormality_error;
use crate::ode::{Family, Linear, Pose, RodOde};
use crate::plan::Node;
use crate::shape::ShapeSink;
use crate::{MAX_CABLES, Scalar};
use cables::CableTraces;

/// Most tangent directions a sweep carries.
pub(crate) const MAX_TANGENTS: usize = 6;

/// Which tangents a sweep carries, in this order: the shooting unknowns' (a Newton iteration, the
/// stability test), the tip force's (the inverse), the tendons' tensions' (the tendon
/// sensitivity); and whether to watch for conjugate points (which needs the unknowns').
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TangentSet {
    unknowns: bool,
    tip_force: bool,
    tensions: u8,
    track_stability: bool,
}

impl TangentSet {
    /// A plain sweep.
    pub const NONE: Self = Self {
        unknowns: false,
        tip_force: false,
        tensions: 0,
        track_stability: false,
    };

    /// The unknowns' tangents.
    pub fn unknowns(track_stability: bool) -> Self {
        Self {
            unknowns: true,
            track_stability,
            ..Self::NONE
        }
    }

    /// The unknowns' and the tip force's tangents.
    pub fn with_tip_force(track_stability: bool) -> Self {
        Self {
            unknowns: true,
            tip_force: true,
            track_stability,
            ..Self::NONE
        }
    }

    /// The parameters' tangents alone, at fixed unknowns: the tip force's (when `tip_force`) and
    /// the first `tensions` tendons' tensions'.
    pub fn parameters(tip_force: bool, tensions: usize) -> Self {
        Self {
            tip_force,
            tensions: u8::try_from(tensions.min(MAX_TANGENTS)).unwrap_or(0),
            ..Self::NONE
        }
    }

    /// How many slots, for `K` unknowns (at most [`MAX_TANGENTS`]).
    pub fn count<const K: usize>(&self) -> usize {
        let force = if self.tip_force { 3 } else { 0 };
        if self.unknowns {
            (K + force).min(MAX_TANGENTS)
        } else {
            (force + usize::from(self.tensions)).min(MAX_TANGENTS)
        }
    }

    /// The family and index of slot `j`. Out of line, and with the unknowns' layout first (the
    /// sweeps of the solves and the estimator): the sweep stays small (the controller's flash).
    #[inline(never)]
    fn family<const K: usize>(&self, j: usize) -> (Family, usize) {
        if self.unknowns {
            if j < K {
                (Family::Unknown, j)
            } else {
                (Family::TipForce, j - K)
            }
        } else if self.tip_force && j < 3 {
            (Family::TipForce, j)
        } else {
            (Family::Tension, j - if self.tip_force { 3 } else { 0 })
        }
    }

    /// Where each family's tangents lie, `[first slot, how many]` by [`Family`] (within
    /// [`MAX_TANGENTS`]: see [`TangentSet::count`]), in [`TangentSet::family`]'s layout.
    fn layout<const K: usize>(&self) -> [[u8; 2]; 3] {
        let room = |first: usize, len: usize| {
            let first = first.min(MAX_TANGENTS);
            // (At most MAX_TANGENTS: fits a byte.)
            [first as u8, len.min(MAX_TANGENTS - first) as u8]
        };
        let unknowns = if self.unknowns { K } else { 0 };
        let force = if self.tip_force { 3 } else { 0 };
        let tensions = if self.unknowns {
            0
        } else {
            usize::from(self.tensions)
        };
        [
            room(0, unknowns),
            room(unknowns, force),
            room(unknowns + force, tensions),
        ]
    }

    /// The slot of tangent `j` of `family`, if the set has it.
    pub fn slot<const K: usize>(&self, family: Family, j: usize) -> Option<usize> {
        slot_in(&self.layout::<K>(), family, j)
    }
}

/// The slot of tangent `j` of `family` in `layout` ([`TangentSet::layout`]).
fn slot_in(layout: &[[u8; 2]; 3], family: Family, j: usize) -> Option<usize> {
    let [first, len] = *layout.get(family as usize)?;
    (j < usize::from(len)).then_some(usize::from(first) + j)
}

/// Everything one sweep produces. The tangent arrays hold the sweep's tangents in the slots its
/// [`TangentSet`] laid out: the `K` unknowns first, then the tip force's three, or the
/// parameters' alone (the tip force's, then the tensions').
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sweep<T, const K: usize> {
    pub tip_position_m: Vector3<T>,
    pub tip_rotation: nalgebra::Matrix3<T>,
    /// The tip condition's residual: zero when it holds.
    pub residual: SVector<T, K>,
    d_residual: [SVector<T, K>; MAX_TANGENTS],
    pub cable_m: [T; MAX_CABLES],
    d_cable: [[T; MAX_TANGENTS]; MAX_CABLES],
    d_tip_position: [Vector3<T>; MAX_TANGENTS],
    /// Tip rotation perturbation, body frame.
    d_tip_rotation: [Vector3<T>; MAX_TANGENTS],
    /// Where each family's tangents lie in the arrays ([`TangentSet::layout`]).
    layout: [[u8; 2]; 3],
    /// First arc length where a conjugate point was found (only when tracked).
    pub conjugate_point_m: Option<T>,
    /// Largest `|R^T R - I|` met at the nodes.
    pub frame_drift: T,
    /// Largest bending phase per step on the grid, rad (see
    /// [`crate::report::MAX_PHASE_PER_STEP_RAD`]).
    pub phase_per_step_rad: T,
    pub finite: bool,
}

impl<T: Scalar, const K: usize> Sweep<T, K> {
    fn non_finite() -> Self {
        Self {
            tip_position_m: Vector3::zeros(),
            tip_rotation: nalgebra::Matrix3::identity(),
            residual: SVector::zeros(),
            d_residual: [SVector::zeros(); MAX_TANGENTS],
            cable_m: [T::zero(); MAX_CABLES],
            d_cable: [[T::zero(); MAX_TANGENTS]; MAX_CABLES],
            d_tip_position: [Vector3::zeros(); MAX_TANGENTS],
            d_tip_rotation: [Vector3::zeros(); MAX_TANGENTS],
            layout: [[0; 2]; 3],
            conjugate_point_m: None,
            frame_drift: T::zero(),
            phase_per_step_rad: T::zero(),
            finite: false,
        }
    }

    /// The slot of tangent `j` of `family`, if the sweep carried it.
    fn slot(&self, family: Family, j: usize) -> Option<usize> {
        slot_in(&self.layout, family, j)
    }

    /// Tangent `j` of `family`'s change of the tip rotation, body frame (zero when not carried).
    pub fn d_rotation(&self, family: Family, j: usize) -> Vector3<T> {
        self.slot(family, j)
            .and_then(|j| self.d_tip_rotation.get(j))
            .copied()
            .unwrap_or_else(Vector3::zeros)
    }

    /// Tangent `j` of `family`'s change of the tip position (zero when not carried).
    pub fn d_position(&self, family: Family, j: usize) -> Vector3<T> {
        self.slot(family, j)
            .and_then(|j| self.d_tip_position.get(j))
            .copied()
            .unwrap_or_else(Vector3::zeros)
    }

    /// Tangent `j` of `family`'s change of the tip condition's residual (zero when not carried).
    pub fn d_residual(&self, family: Family, j: usize) -> SVector<T, K> {
        self.slot(family, j)
            .and_then(|j| self.d_residual.get(j))
            .copied()
            .unwrap_or_else(SVector::zeros)
    }

    /// The first `N` tangents of `family` as the columns of a matrix: `column(slot)` for each slot
    /// the sweep carried, zero for the others.
    // Out of line: one copy per shape rather than one per block read (the controller's flash).
    #[inline(never)]
    fn block<const R: usize, const N: usize>(
        &self,
        family: Family,
        column: impl Fn(usize) -> Option<SVector<T, R>>,
    ) -> SMatrix<T, R, N> {
        let mut out = SMatrix::<T, R, N>::zeros();
        for (j, mut col) in out.column_iter_mut().enumerate() {
            if let Some(c) = self.slot(family, j).and_then(&column) {
                col.copy_from(&c);
            }
        }
        out
    }

    /// The changes of the cable lengths along the first `N` tangents of `family`, one column each
    /// (zero where not carried, and beyond the rod's cables).
    pub fn cable_block<const N: usize>(&self, family: Family) -> SMatrix<T, MAX_CABLES, N> {
        self.block(family, |slot| {
            let mut col = SVector::<T, MAX_CABLES>::zeros();
            for (out, row) in col.iter_mut().zip(&self.d_cable) {
                *out = row.get(slot).copied().unwrap_or_else(T::zero);
            }
            Some(col)
        })
    }

    /// `d tip position` along the first `N` tangents of `family`.
    pub fn position_block<const N: usize>(&self, family: Family) -> SMatrix<T, 3, N> {
        self.block(family, |slot| self.d_tip_position.get(slot).copied())
    }

    /// `d tip rotation` (body frame) along the first `N` tangents of `family`.
    pub fn rotation_block<const N: usize>(&self, family: Family) -> SMatrix<T, 3, N> {
        self.block(family, |slot| self.d_tip_rotation.get(slot).copied())
    }

    /// `d residual` along the first `N` tangents of `family`.
    pub fn residual_block<const N: usize>(&self, family: Family) -> SMatrix<T, K, N> {
        self.block(family, |slot| self.d_residual.get(slot).copied())
    }

    /// Whether the sweep carried the unknowns' tangents (has a [`Sweep::jacobian`]).
    pub fn has_jacobian(&self) -> bool {
        self.slot(Family::Unknown, K - 1).is_some()
    }

    /// The shooting Jacobian `d residual / d unknowns`.
    pub fn jacobian(&self) -> SMatrix<T, K, K> {
        self.residual_block(Family::Unknown)
    }

    /// The tip move a change `dx` of the unknowns predicts, m.
    pub fn tip_move_m(&self, dx: &SVector<T, K>) -> T {
        let mut moved = Vector3::zeros();
        for (j, d) in dx.iter().enumerate() {
            moved += self.d_position(Family::Unknown, j) * *d;
        }
        moved.norm()
    }
}

/// The observers at a node, after the equations' jump there: each tangent's change of the pose
/// (into `d_pose`), the cable holes, and the frame's drift from a rotation. Returns the pose.
/// Out of line: the tip and every interior node share it.
#[inline(never)]
fn observe<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    node: Option<&Node<T>>,
    y: &O::State,
    tangents: &[O::Tangent],
    cables: &mut CableTraces<T>,
    d_pose: &mut [(Vector3<T>, Vector3<T>); MAX_TANGENTS],
    frame_drift: &mut T,
) -> Pose<T> {
    let pose = ode.pose(y);
    for (d, t) in d_pose.iter_mut().zip(tangents) {
        *d = ode.tangent_pose(y, t);
    }
    if let Some(node) = node {
        let d_pose = d_pose.get(..tangents.len()).unwrap_or(&[]);
        cables.visit(node, ode.grid().cable_offsets, &pose, d_pose);
    }
    *frame_drift = frame_drift.max(orthonormality_error(&pose.rotation));
    pose
}

/// Writes the shape points asked for in `[s, s_next)` (the step from `s` in progress, on an interval
/// with coefficients `field`); returns the next query (beyond the tip when there is none). Out of
/// line: the step loop stays small.
#[inline(never)]
fn write_shape<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    field: &O::Field,
    s: T,
    s_next: T,
    y: &O::State,
    sink: &mut ShapeSink<'_, T>,
) -> T {
    while let Some(q) = sink.next_query().filter(|q| *q < s_next) {
        let mut at_q = if q > s {
            rk4::step(ode, field, s, q - s, y, None)
        } else {
            *y
        };
        ode.after_step(&mut at_q, &mut []);
        sink.write(ode.shape_point(q, &at_q, field));
    }
    sink.next_query()
        .unwrap_or_else(|| ode.length_m() + ode.length_m())
}

/// Integrates `ode` from base to tip at unknowns `x` with the tangents `which`, writing shape points
/// into `shape` when given.
pub(crate) fn sweep<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    x: &SVector<T, K>,
    which: TangentSet,
    mut shape: Option<&mut ShapeSink<'_, T>>,
) -> Sweep<T, K> {
    let mut out = Sweep::non_finite();
    let grid = ode.grid();
    let count = which.count::<K>();
    let mut seeds = [ode.no_seed(); MAX_TANGENTS];
    let mut tan = [O::Tangent::zero(); MAX_TANGENTS];
    for (j, (t, seed)) in tan.iter_mut().zip(seeds.iter_mut()).enumerate().take(count) {
        let (family, index) = which.family::<K>(j);
        (*t, *seed) = ode.seed(family, index);
    }
    let (seeds, tan) = (
        seeds.get(..count).unwrap_or(&[]),
        tan.get_mut(..count).unwrap_or(&mut []),
    );
    let mut y = ode.start(x);
    let mut cables = CableTraces::new();
    let mut d_pose = [(Vector3::zeros(), Vector3::zeros()); MAX_TANGENTS];
    let mut conjugate_point_m = None;
    let mut frame_drift = T::zero();
    // The largest bending phase per step, to the fourth power (no root per step).
    let mut phase4 = T::zero();
    let mut stages = [ode.blank_stage(); 4];
    let mut track = ode.track();
    let mut proximal: Option<O::Field> = None;
    // The next shape query (beyond the tip when there is none): one comparison per step.
    let beyond = ode.length_m() + ode.length_m();
    let mut next_shape_m = shape
        .as_deref()
        .and_then(ShapeSink::next_query)
        .unwrap_or(beyond);

    for (k, interval) in grid.intervals.iter().enumerate() {
        let Some(field) = ode.next_field(proximal.as_ref(), interval) else {
            return out;
        };
        let node = grid.nodes.get(k);
        if let (Some(node), Some(prox)) = (node, &proximal) {
            ode.node(node, prox, &field, &mut y, tan);
        }
        // Tangents already at the next node (`RodOde::tangents_ahead`) are not stepped.
        let stepped = !tan.is_empty() && !ode.tangents_ahead(&y);
        observe(
            ode,
            node,
            &y,
            tan,
            &mut cables,
            &mut d_pose,
            &mut frame_drift,
        );
        let (s0, len) = (interval.s0_m, interval.s1_m - interval.s0_m);
        let steps = T::lit(f64::from(interval.steps));
        let step_m = len / steps;
        let h4 = (step_m * step_m) * (step_m * step_m);
        let mut s = s0;
        for i in 1..=interval.steps {
            let s_next = if i == interval.steps {
                interval.s1_m
            } else {
                s0 + len * (T::lit(f64::from(i)) / steps)
            };
            if next_shape_m < s_next
                && let Some(sink) = shape.as_deref_mut()
            {
                next_shape_m = write_shape(ode, &field, s, s_next, &y, sink);
            }
            let h = s_next - s;
            // The bending load at the step's start: from the first stage's record when the step
            // keeps one (it has the force in the section's frame at hand).
            let load = if !stepped {
                let load = ode.bending_load(&field, s, &y);
                y = rk4::step(ode, &field, s, h, &y, None);
                load
            } else {
                y = rk4::step(ode, &field, s, h, &y, Some(&mut stages));
                rk4::tangent_steps(ode, &field, &stages, seeds, h, tan);
                ode.stage_bending_load(&field, &stages[0])
            } * h4;
            if load > phase4 {
                phase4 = load;
            }
            ode.after_step(&mut y, tan);
            if which.track_stability
                && conjugate_point_m.is_none()
                && ode.crosses(&mut track, &y, tan, &field, step_m)
            {
                conjugate_point_m = Some(s_next);
            }
            s = s_next;
        }
        let load = ode.bending_load(&field, s, &y) * h4;
        if load > phase4 {
            phase4 = load;
        }
        if !ode.finite(&y, tan) {
            return out;
        }
        proximal = Some(field);
    }

    // The tip node: last guide holes and terminations, remaining shape queries, the tip condition.
    let Some(last) = proximal else {
        return out;
    };
    let tip_node = grid.nodes.last();
    let pose = observe(
        ode,
        tip_node,
        &y,
        tan,
        &mut cables,
        &mut d_pose,
        &mut frame_drift,
    );
    if let Some(sink) = shape {
        let length = ode.length_m();
        while sink.next_query().is_some_and(|q| q <= length) {
            sink.write(ode.shape_point(length, &y, &last));
        }
    }
    out.residual = ode.tip(
        tip_node,
        &last,
        &y,
        tan,
        seeds,
        out.d_residual.get_mut(..count).unwrap_or(&mut []),
    );
    cables.write(&mut out.cable_m, &mut out.d_cable);
    for ((r, th), (dr, dth)) in out
        .d_tip_position
        .iter_mut()
        .zip(out.d_tip_rotation.iter_mut())
        .zip(d_pose.iter().take(count))
    {
        *r = *dr;
        *th = *dth;
    }
    out.tip_position_m = pose.position_m + pose.position_lo_m;
    out.tip_rotation = pose.rotation;
    out.layout = which.layout::<K>();
    out.conjugate_point_m = conjugate_point_m;
    out.frame_drift = frame_drift;
    out.phase_per_step_rad = phase4.sqrt().sqrt();
    out.finite = crate::scalar::all_finite(&out.residual)
        && out.cable_m.iter().all(|x| x.is_finite())
        && out.d_cable.iter().flatten().all(|x| x.is_finite())
        && out.d_residual.iter().all(crate::scalar::all_finite);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two views of a set's layout agree: every slot's family and index lead back to it, and
    /// no family and index beyond the set has a slot (three and six unknowns, the tip force, the
    /// parameters with none to more tensions than fit).
    #[test]
    fn tangent_sets_slots_and_families_agree() {
        fn check<const K: usize>(set: TangentSet, expected: usize) {
            assert_eq!(set.count::<K>(), expected, "{set:?}");
            for slot in 0..expected {
                let (family, j) = set.family::<K>(slot);
                assert_eq!(set.slot::<K>(family, j), Some(slot), "{set:?} slot {slot}");
            }
            let mut found = 0;
            for family in [Family::Unknown, Family::TipForce, Family::Tension] {
                for j in 0..2 * MAX_TANGENTS {
                    if let Some(slot) = set.slot::<K>(family, j) {
                        assert!(slot < expected, "{set:?}: {family:?} {j} at {slot}");
                        found += 1;
                    }
                }
            }
            assert_eq!(found, expected, "{set:?}");
        }
        check::<3>(TangentSet::NONE, 0);
        check::<3>(TangentSet::unknowns(true), 3);
        check::<3>(TangentSet::with_tip_force(false), 6);
        check::<6>(TangentSet::unknowns(false), 6);
        // Six unknowns leave the tip force no room.
        check::<6>(TangentSet::with_tip_force(false), 6);
        for tensions in 0..=8 {
            check::<6>(TangentSet::parameters(false, tensions), tensions.min(6));
            check::<6>(
                TangentSet::parameters(true, tensions),
                (3 + tensions).min(6),
            );
        }
    }
}
