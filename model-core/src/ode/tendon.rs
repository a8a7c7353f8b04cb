//! The rod pulled by tendons: the equations with the internal force and moment as states
//! (`force_state.rs`), and at each guide the tendons' chord forces (`crate::tendon`), which read the
//! previous guide's pose, this one's and, where a tendon passes, the next one's.
//!
//! The next guide's pose depends on the internal force just distal of this guide, which the jump
//! sets: the jump is implicit. At such a guide the equations look ahead: from the pose here and a
//! trial `x = (n(s+), m(s+))` they integrate the segment to the next guide with the same RK4 steps as
//! the sweep, and Newton solves `g(x) = x - x(s-) + W(P_prev, P, P_next(x)) = 0` (six unknowns, the
//! segment's six sensitivities as its Jacobian `I + W_next Psi`). Each tangent the sweep carries is
//! made consistent in the same pass: with `dx0 = dx(s-) - dW_known` integrated ahead to `dP0`, the
//! change is `dx = dx0 + delta`, `(I + W_next Psi) delta = -W_next dP0` (the implicit function
//! theorem). So a sweep stays a function of the six base unknowns `n(0)`, `m(0)` with an exact
//! Jacobian, and the one Newton/LM and load continuation (`crate::solve`) solve it: single shooting,
//! with a local solve per guide instead of multiple shooting's `6 (guides + 1)` unknowns.
//!
//! The look-aheads are most of a sweep's work, so the sweep's tangents ride along only on the one
//! expected to end the local solve, a correction whose successor Newton's quadratic convergence
//! puts at rounding ends it without another look-ahead, and a sweep without tangents takes chord
//! steps after its first Newton step (the same factored Jacobian; a look-ahead of the state alone)
//! while they contract, and the riding tangents, integrated to the next guide by the last
//! look-ahead, are not integrated again by the sweep (MODEL.md §6.5).
//!
//! The state carries the previous guide's pose (the base plate's at the start) for the chords.

use core::cell::Cell;

use nalgebra::{SMatrix, SVector, Vector3};

use super::force_state::{self, ForceStateRod};
use super::{Family, Linear, Pose, RodOde};
use crate::kinematics::Attitude;
use crate::loads::{NoShapeLoad, TipLoad};
use crate::model::{Grid, Model};
use crate::plan::{Interval, NO_GUIDE, Node};
use crate::shape::ShapePoint;
use crate::sweep::{MAX_TANGENTS, rk4};
use crate::tendon::Routed;
use crate::tendon::guide_force::{
    GuideLoad, GuidePose, PoseDelta, Role, d_hole, d_wrench_d_next, guide_load, hole, reads_next,
    role,
};
use crate::tendon::{MAX_TENDONS, Tendons};
use crate::{MAX_GUIDES, Scalar};

/// Newton iterations of one guide's implicit jump.
const MAX_JUMP_ITERATIONS: usize = 12;

static NO_SHAPE_LOAD: NoShapeLoad = NoShapeLoad;

/// What the last sweep saw at the guides: its unknowns, its load scale and each guide's pose. The
/// converged sweep of a solve has passed every guide, so a solve's tendon paths are read from it
/// rather than from one more sweep (when the record is that sweep's: same unknowns, full scale).
#[derive(Debug)]
pub(crate) struct GuideRecord<T: Scalar> {
    x: Cell<SVector<T, 6>>,
    alpha: Cell<T>,
    /// Guides passed by the last sweep, in order.
    passed: Cell<usize>,
    poses: [Cell<GuidePose<T>>; MAX_GUIDES],
}

/// How each tendon's path changed along the tangents of the last sweep that carried some (a
/// joint displacement step's, `tendon/joint_step.rs`): kept beside a [`GuideRecord`], which says
/// where that sweep was.
#[derive(Debug)]
pub(crate) struct PathChanges<T: Scalar> {
    /// Tangents the last sweep carried past its guides (0: none).
    tangents: Cell<usize>,
    /// Each tendon's path change along each tangent: over its chords, `unit(chord) . (dP_k -
    /// dP_k-1)`, the holes' moves `dP = dp + R (dtheta x d)`.
    d_path: [Cell<[T; MAX_TANGENTS]>; MAX_TENDONS],
}

impl<T: Scalar> PathChanges<T> {
    pub(crate) fn new() -> Self {
        Self {
            tangents: Cell::new(0),
            d_path: core::array::from_fn(|_| Cell::new([T::zero(); MAX_TANGENTS])),
        }
    }

    /// Each tendon's path change along the `tangents` tangents (in their slots) of the sweep
    /// `record` holds, if it ran at unknowns `x` at full load, passed `guides` guides and carried
    /// them.
    pub(crate) fn along(
        &self,
        record: &GuideRecord<T>,
        x: &SVector<T, 6>,
        guides: usize,
        tangents: usize,
    ) -> Option<[[T; MAX_TANGENTS]; MAX_TENDONS]> {
        let whole = record.holds(x, guides) && self.tangents.get() == tangents;
        whole.then(|| self.d_path.each_ref().map(Cell::get))
    }

    fn start(&self) {
        self.tangents.set(0);
        for cell in &self.d_path {
            cell.set([T::zero(); MAX_TANGENTS]);
        }
    }

    /// The sweep's `tangents` at guide `guide` (pose `cur`, the previous hole's guide or the base
    /// plate at `prev`): each tendon routed here adds its chord's change along each.
    fn pass(
        &self,
        guide: usize,
        prev: &GuidePose<T>,
        cur: &GuidePose<T>,
        tangents: &[Tangent<T>],
        routed: &[Routed<T>],
    ) {
        if tangents.is_empty() {
            return;
        }
        self.tangents.set(tangents.len());
        for (cell, r) in self.d_path.iter().zip(routed) {
            if guide > r.end_guide {
                continue;
            }
            let chord = hole(cur, &r.offset_m) - hole(prev, &r.offset_m);
            let unit = chord / chord.norm();
            let mut d = cell.get();
            for (d, t) in d.iter_mut().zip(tangents) {
                let here = d_hole(cur, &r.offset_m, &pose_delta(&t.rod));
                let back = d_hole(prev, &r.offset_m, &t.prev);
                *d += unit.dot(&(here - back));
            }
            cell.set(d);
        }
    }
}

impl<T: Scalar> GuideRecord<T> {
    /// An empty record.
    pub(crate) fn new() -> Self {
        let blank = GuidePose {
            position_m: Vector3::zeros(),
            rotation: nalgebra::Matrix3::identity(),
        };
        Self {
            x: Cell::new(SVector::zeros()),
            alpha: Cell::new(T::zero()),
            passed: Cell::new(0),
            poses: core::array::from_fn(|_| Cell::new(blank)),
        }
    }

    /// The guides' poses of the last sweep, if it ran at unknowns `x` at full load and passed
    /// `guides` guides.
    pub(crate) fn poses_at(
        &self,
        x: &SVector<T, 6>,
        guides: usize,
    ) -> Option<[GuidePose<T>; MAX_GUIDES]> {
        self.holds(x, guides)
            .then(|| self.poses.each_ref().map(Cell::get))
    }

    /// Whether the last sweep ran at unknowns `x` at full load and passed `guides` guides.
    fn holds(&self, x: &SVector<T, 6>, guides: usize) -> bool {
        self.x.get() == *x && self.alpha.get() == T::one() && self.passed.get() == guides
    }

    fn start(&self, x: &SVector<T, 6>, alpha: T) {
        self.x.set(*x);
        self.alpha.set(alpha);
        self.passed.set(0);
    }

    fn pass(&self, guide: usize, pose: &GuidePose<T>) {
        if let Some(cell) = self.poses.get(guide) {
            cell.set(*pose);
            // In order: a guide passed out of turn leaves the record incomplete.
            if self.passed.get() == guide {
                self.passed.set(guide + 1);
            }
        }
    }
}

/// Where each guide's implicit jump converged in the sweeps so far, and the Newton matrix
/// `I + W_next Psi` of its last Newton pass, factored: a sweep without tangents near them (a
/// displacement solve's confirming and chord sweeps) starts each jump there and takes chord steps
/// on that matrix, a look-ahead of the state alone each, instead of a Newton pass that carries
/// the six directions of `(n, m)` through the segment (MODEL.md §6.5). Lent to the equations of
/// one displacement solve's forward solves and joint step ([`TendonRod::remembering`]); sized by
/// the plan's nodes, as every guide is one.
#[derive(Debug)]
pub(crate) struct JumpMemory<T: Scalar, const NODES: usize> {
    jumps: [Cell<Option<Remembered<T>>>; NODES],
    /// Jumps that converged on remembered factors, without a Newton pass (for the tests).
    #[cfg(test)]
    recalled: Cell<u32>,
}

/// One guide's remembered jump.
#[derive(Clone, Copy, Debug)]
struct Remembered<T: Scalar> {
    /// The load scale it was solved at.
    alpha: T,
    /// The jump's wrench `W`, stacked `(f L, m)`: `(n, m)(s+) = (n, m)(s-) - W`.
    wrench: SVector<T, 6>,
    /// `I + W_next Psi` of the last Newton pass there, factored.
    lu: Lu6<T>,
}

impl<T: Scalar, const NODES: usize> JumpMemory<T, NODES> {
    /// A memory of no jumps.
    pub(crate) fn new() -> Self {
        Self {
            jumps: core::array::from_fn(|_| Cell::new(None)),
            #[cfg(test)]
            recalled: Cell::new(0),
        }
    }

    /// How many jumps converged on remembered factors alone, without a Newton pass.
    #[cfg(test)]
    pub(crate) fn recalled(&self) -> u32 {
        self.recalled.get()
    }

    /// The wrench of `guide`'s remembered jump at load scale `alpha`, its factors into `lu`.
    // Out of line, as `keep`: the factors' copies inlined into the sweep took 1.3 KB of the
    // controller's flash (and a `memmove`, 1.5 KB).
    #[inline(never)]
    fn recall(&self, guide: usize, alpha: T, lu: &mut Lu6<T>) -> Option<SVector<T, 6>> {
        let r = self
            .jumps
            .get(guide)
            .and_then(Cell::get)
            .filter(|r| r.alpha == alpha)?;
        *lu = r.lu;
        Some(r.wrench)
    }

    /// Keeps `guide`'s jump: its wrench and factors at load scale `alpha`.
    /// `recalled`: whether the jump converged on the remembered factors alone.
    #[inline(never)]
    fn keep(&self, guide: usize, alpha: T, wrench: &SVector<T, 6>, lu: &Lu6<T>, recalled: bool) {
        #[cfg(test)]
        if recalled {
            self.recalled.set(self.recalled.get().saturating_add(1));
        }
        #[cfg(not(test))]
        let _ = recalled;
        if let Some(cell) = self.jumps.get(guide) {
            cell.set(Some(Remembered {
                alpha,
                wrench: *wrench,
                lu: *lu,
            }));
        }
    }
}

/// The rod under dead loads and the tendons' tensions.
#[derive(Debug)]
pub(crate) struct TendonRod<'a, T: Scalar, A: Attitude<T>, const NODES: usize> {
    rod: ForceStateRod<'a, T, A, NoShapeLoad, NODES>,
    model: &'a Model<T, A, NODES>,
    tendons: &'a Tendons<T>,
    record: Option<&'a GuideRecord<T>>,
    memory: Option<&'a JumpMemory<T, NODES>>,
    paths: Option<&'a PathChanges<T>>,
    /// Whether the sweep takes its tangents from a jump's look-ahead one predicted correction
    /// from the answer too, not only at rounding ([`TendonRod::jumping_ahead`]).
    jump_ahead: bool,
    /// Full tensions, N.
    tensions_n: [T; MAX_TENDONS],
    /// Tensions at the load scale, N.
    scaled_n: [T; MAX_TENDONS],
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Clone for TendonRod<'_, T, A, NODES> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Copy for TendonRod<'_, T, A, NODES> {}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> TendonRod<'a, T, A, NODES> {
    /// The equations of `model` under `load`, the scene's dead loads and the tendons at
    /// `tensions_n`, all scaled by `alpha`.
    pub(crate) fn new(
        model: &'a Model<T, A, NODES>,
        tendons: &'a Tendons<T>,
        tensions_n: &[T; MAX_TENDONS],
        load: &TipLoad<T>,
        alpha: T,
    ) -> Self {
        Self {
            rod: ForceStateRod::new(model, &NO_SHAPE_LOAD, load, alpha),
            model,
            tendons,
            record: None,
            memory: None,
            paths: None,
            jump_ahead: false,
            tensions_n: *tensions_n,
            scaled_n: tensions_n.map(|t| t * alpha),
        }
    }

    /// These equations, keeping in `record` what each sweep sees at the guides.
    pub(crate) fn recording(self, record: &'a GuideRecord<T>) -> Self {
        Self {
            record: Some(record),
            ..self
        }
    }

    /// These equations, their jumps starting from and kept in `memory` (sweeps without tangents
    /// start there; every sweep keeps its own).
    pub(crate) fn remembering(self, memory: &'a JumpMemory<T, NODES>) -> Self {
        Self {
            memory: Some(memory),
            ..self
        }
    }

    /// These equations, keeping in `paths` how the tendons' paths change along each sweep's
    /// tangents.
    pub(crate) fn tracing_paths(self, paths: &'a PathChanges<T>) -> Self {
        Self {
            paths: Some(paths),
            ..self
        }
    }

    /// These equations, their sweeps taking the tangents beyond a guide from its jump's last
    /// look-ahead also where that ran one predicted correction from the answer: a Jacobian off by
    /// about that correction, relative (f32: up to about `sqrt(eps)`), for a sweep less. For a
    /// step whose answer a plain sweep checks (the joint step's); not for solves whose answers are
    /// differenced (the tendon inverse's sensitivities see the difference).
    pub(crate) fn jumping_ahead(self) -> Self {
        Self {
            jump_ahead: true,
            ..self
        }
    }

    /// The scaled unknowns of a base force (N) and moment (N m).
    pub(crate) fn unknowns(&self, force_n: &Vector3<T>, moment_nm: &Vector3<T>) -> SVector<T, 6> {
        self.rod.unknowns(force_n, moment_nm)
    }

    /// The base strain, force and moment of unknowns `x`.
    pub(crate) fn base(&self, x: &SVector<T, 6>) -> (Vector3<T>, Vector3<T>, Vector3<T>) {
        self.rod.base(x)
    }

    fn tensions(&self) -> &[T] {
        self.scaled_n.get(..self.tendons.len()).unwrap_or(&[])
    }

    /// `(f L, m)`: a wrench in the units of the scaled residual, N m.
    fn stack(&self, f: &Vector3<T>, m: &Vector3<T>) -> SVector<T, 6> {
        crate::scalar::stacked(&(f * self.model.length_m()), m)
    }

    fn guide_pose(y: &force_state::State<T, A>) -> GuidePose<T> {
        GuidePose {
            position_m: y.p + y.p_lo,
            rotation: y.att.matrix(),
        }
    }

    /// The tendons' load at `guide` with the chord tensions `back_n` arriving there.
    fn load(
        &self,
        guide: usize,
        back_n: &[T],
        poses: [&GuidePose<T>; 3],
        d: Option<([&PoseDelta<T>; 3], &[T])>,
    ) -> GuideLoad<T> {
        guide_load(&self.tendons.routed, back_n, guide, poses, d)
    }

    /// Integrates from node `start` (state `y`, its jump applied) to the next node with a guide,
    /// carrying `tangents`, with the sweep's steps; the state there before its jump.
    fn ahead(
        &self,
        start: usize,
        y: &force_state::State<T, A>,
        tangents: &mut [force_state::Tangent<T>],
    ) -> Option<force_state::State<T, A>> {
        let grid = self.rod.grid();
        let seeds = [Vector3::zeros(); 2 * MAX_TANGENTS];
        let seeds = seeds.get(..tangents.len())?;
        let mut stages = [self.rod.blank_stage(); 4];
        let mut y = *y;
        let mut index = start;
        loop {
            let interval: &Interval<T> = grid.intervals.get(index)?;
            let field = self.rod.field(interval)?;
            let (s0, len) = (interval.s0_m, interval.s1_m - interval.s0_m);
            let steps = T::lit(f64::from(interval.steps));
            let mut s = s0;
            for i in 1..=interval.steps {
                let s_next = if i == interval.steps {
                    interval.s1_m
                } else {
                    s0 + len * (T::lit(f64::from(i)) / steps)
                };
                let h = s_next - s;
                y = rk4::step(&self.rod, &field, s, h, &y, Some(&mut stages));
                rk4::tangent_steps(&self.rod, &field, &stages, seeds, h, tangents);
                s = s_next;
            }
            let next: &Node<T> = grid.nodes.get(index + 1)?;
            if next.guide != NO_GUIDE {
                return Some(y);
            }
            let alpha = self.scale();
            y.n -= next.force_n * alpha;
            y.m -= next.moment_nm * alpha;
            index += 1;
        }
    }

    /// The jump's linearisation at `guide` with `poses` (the next one a look-ahead's, whose
    /// first six directions `dirs` are `(n, m)`'s), into `lin` (in place: the matrices stay in the
    /// jump's frame).
    fn linearise(
        &self,
        guide: usize,
        back_n: &[T],
        poses: [&GuidePose<T>; 3],
        dirs: &[force_state::Tangent<T>],
        lin: &mut Linearised<T>,
    ) {
        let zero = PoseDelta::zero();
        let no_change = [T::zero(); MAX_TENDONS];
        let [_, cur, next] = poses;
        let direct = d_wrench_d_next(&self.tendons.routed, back_n, guide, cur, next);
        for (j, mut col) in lin.w_next.column_iter_mut().enumerate() {
            let dw = match direct.as_ref().and_then(|d| d.get(j)) {
                Some(dw) => *dw,
                None => {
                    let d = unstacked(&super::unit::<T, 6>(j));
                    self.load(guide, back_n, poses, Some(([&zero, &zero, &d], &no_change)))
                        .d_wrench
                }
            };
            col.copy_from(&self.stack(&dw.force_n, &dw.moment_nm));
        }
        for (mut col, t) in lin.psi.column_iter_mut().zip(dirs) {
            col.copy_from(&stacked(&pose_delta(t)));
        }
        lin.lu = (SMatrix::<T, 6, 6>::identity() + lin.w_next * lin.psi).lu();
    }

    /// The look-ahead's end of tangent `t0` from its first nine directions' (`(n, m)`'s six, then
    /// the start's three turns): `t0`'s translation, turn and change of `(n, m)` combined.
    fn assembled(
        &self,
        t0: &force_state::Tangent<T>,
        dirs: &[force_state::Tangent<T>],
    ) -> force_state::Tangent<T> {
        let translated = force_state::Tangent {
            p: t0.p,
            ..force_state::Tangent::zero()
        };
        // The `(n, m)` directions are `(e_i / L, e_i)`: `t0`'s weights are its stacked wrench.
        let wrench = self.stack(&t0.n, &t0.m);
        along(translated, dirs, wrench.iter().chain(t0.th.iter()))
    }

    fn scale(&self) -> T {
        // The load scale is the ratio of scaled to full tensions of any tendon, but tensions may be
        // zero: the wrapped equations keep it.
        self.rod.alpha()
    }

    /// The implicit jump at `guide` (node index `index`), where a tendon passes: solves for
    /// `(n(s+), m(s+))`, sets the chord tensions beyond and makes the tangents consistent. `false`
    /// when it does not converge.
    ///
    /// Newton's look-aheads carry the six directions of `(n, m)` only; the sweep's tangents ride
    /// along on the look-ahead expected to end the solve (Newton's quadratic convergence predicts
    /// the next correction), or on one more at the answer when that prediction missed. They start
    /// from the tangents before the jump and are corrected at the end by linearity (the segment's
    /// six directions), so the known poses' share is taken at the answer's next pose: the
    /// tangents are the converged jump's, for a fraction of the look-ahead work.
    fn implicit_jump(
        &self,
        index: usize,
        guide: usize,
        y: &mut State<T, A>,
        tangents: &mut [Tangent<T>],
        remember: bool,
    ) -> bool {
        let length = self.model.length_m();
        let zero = PoseDelta::zero();
        let prev = y.prev;
        let cur = Self::guide_pose(&y.rod);
        let back = y.chord_n;
        let (n_minus, m_minus) = (y.rod.n, y.rod.m);
        // Start from the next guide straight ahead.
        let ds = self
            .tendons
            .guide_s_m
            .get(guide + 1)
            .map_or(T::zero(), |s| {
                *s - self.tendons.guide_s_m.get(guide).copied().unwrap_or(*s)
            });
        let predicted = GuidePose {
            position_m: cur.position_m + cur.rotation.column(2) * ds,
            rotation: cur.rotation,
        };
        let w0 = self
            .load(guide, &back, [&prev, &cur, &predicted], None)
            .wrench;
        let straight = (n_minus - w0.force_n, m_minus - w0.moment_nm);
        let (mut n, mut m) = straight;

        let count = tangents.len().min(MAX_TANGENTS);
        let scale = self.stack(&n_minus, &m_minus).norm()
            + self.stack(&w0.force_n, &w0.moment_nm).norm()
            + self.model.moment_scale_nm();
        let eps = T::default_epsilon();
        let done_at = T::lit(16.0) * eps * scale;
        // With friction here the tensions beyond read the next pose: the answer must be at
        // rounding itself, not one correction from it.
        let friction = self
            .tendons
            .routed
            .iter()
            .any(|r| r.capstan_per_rad != T::zero() && role(r, guide) == Role::Passes);
        let mut last_step: Option<T> = None;
        // The last step's size if it was a Newton step (not a chord step).
        let mut last_newton: Option<T> = None;
        let mut contraction: Option<T> = None;
        let mut all = [force_state::Tangent::zero(); 2 * MAX_TANGENTS];
        // The last Newton pass's `W_next`, `Psi` and `I + W_next Psi` factored (or the remembered
        // factors), and whether the next pass may reuse them (a chord step).
        let mut lin = Linearised::blank();
        let mut chord_next = false;
        let mut chord_spent = false;
        // A sweep without tangents starts where this guide's jump converged before and takes chord
        // steps on that jump's Newton matrix (`JumpMemory`). The first has no contraction to show
        // and is taken unless it is larger than the jump's own scale; the next must halve it, and
        // so on. Until a Newton pass, a step that is not finite, too large or refused leaves the
        // memory: the jump starts again straight ahead with all its passes, exactly as without
        // one (`retreat`).
        let remembered = self
            .memory
            .filter(|_| count == 0 && remember)
            .and_then(|memory| memory.recall(guide, self.scale(), &mut lin.lu));
        let mut first_remembered = false;
        let mut retreat = false;
        // Whether a Newton pass replaced the remembered factors.
        let mut linearised = false;
        if let Some(wrench) = &remembered {
            let (f, moment) = split(wrench);
            (n, m) = (n_minus - f / length, m_minus - moment);
            (chord_next, first_remembered, retreat) = (true, true, true);
        }
        // One pass beyond the limit, for the tangents of a solve that converged on its last.
        let mut passes = MAX_JUMP_ITERATIONS;
        let mut pass = 0;
        while pass < passes {
            pass += 1;
            // The tangents ride along when this look-ahead's correction is expected to end the
            // solve, `C |last|^2` with `C` from the last two corrections and a margin of 4. Before
            // two corrections show `C`, a prior: `0.1 / scale`, 25 times the largest measured on
            // the bench (a wrong prior costs a look-ahead, never the answer).
            let c = contraction.unwrap_or(T::lit(0.1) / scale);
            let ride = count > 0
                && last_step.is_some_and(|s| {
                    let e = c * s * s;
                    e * T::lit(4.0) <= done_at || (!friction && T::lit(4.0) * c * e * e <= done_at)
                });
            let carried = if ride { count } else { 0 };
            // A sweep without tangents reuses the last Newton pass's Jacobian while its steps
            // contract (a chord step): its look-ahead integrates the state alone, a seventh of
            // one with the six directions.
            // (Not in the second half of the passes: a slow chord must leave Newton the rest.)
            let chord = count == 0 && chord_next && 2 * pass <= passes;
            // More than three riding tangents are assembled from three turns of the start
            // instead (a tangent is a translation, a turn and a change of `(n, m)`, and the
            // look-ahead is linear; a translation moves its end rigidly, as no rate reads the
            // position).
            let assemble = carried > 3;
            let riding = if assemble { 3 } else { carried };
            let directions = if chord { 0 } else { 6 + riding };
            for (j, t) in all.iter_mut().enumerate().take(directions) {
                *t = force_state::Tangent::zero();
                if j < 3 {
                    t.n = super::unit::<T, 3>(j) / length;
                } else if j < 6 {
                    t.m = super::unit::<T, 3>(j - 3);
                } else if assemble {
                    t.th = super::unit::<T, 3>(j - 6);
                } else if let Some(t0) = tangents.get(j - 6) {
                    *t = t0.rod;
                }
            }
            let Some(dirs) = all.get_mut(..directions) else {
                return false;
            };
            let start = force_state::State { n, m, ..y.rod };
            let Some(end) = self.ahead(index, &start, dirs) else {
                return false;
            };
            let next = Self::guide_pose(&end);
            let poses = [&prev, &cur, &next];
            let here = self.load(guide, &back, poses, None);
            let w = here.wrench;
            let g = self.stack(&(n - n_minus + w.force_n), &(m - m_minus + w.moment_nm));
            if !chord {
                self.linearise(guide, &back, poses, &all, &mut lin);
                (retreat, linearised) = (false, true);
            }
            let step = lin.lu.solve(&(-g)).filter(crate::scalar::all_finite);
            // (Only chord steps on the remembered factors while `retreat` holds.)
            let left = retreat
                && step.as_ref().map(SVector::norm).is_none_or(|size| {
                    if first_remembered {
                        size > scale
                    } else {
                        !last_step.is_some_and(|p| p > T::zero() && size <= p * T::lit(0.5))
                    }
                });
            if left {
                (n, m) = straight;
                (chord_next, chord_spent, first_remembered, retreat) = (false, false, false, false);
                (last_step, last_newton, contraction) = (None, None, None);
                (pass, passes) = (0, MAX_JUMP_ITERATIONS);
                continue;
            }
            let Some(step) = step else {
                return false;
            };
            let (dn, dm) = split(&step);
            let size = step.norm();
            if chord {
                // A chord step leaves about `rho |step|`, `rho` its contraction against the last
                // step taken. One that does not halve is not taken (far from the last Newton
                // point its Jacobian may be nothing like the jump's): Newton goes on from here.
                let rho = last_step.filter(|p| *p > T::zero()).map(|p| size / p);
                let first = core::mem::take(&mut first_remembered);
                if !(first || rho.is_some_and(|r| r <= T::lit(0.5))) {
                    chord_next = false;
                    chord_spent = true;
                    continue;
                }
                n += dn / length;
                m += dm;
                last_step = Some(size);
                // A chord step says nothing of Newton's `C`; one that contracts by less than
                // sixteen ends the chord steps of this jump.
                last_newton = None;
                contraction = None;
                chord_next = first || rho.is_some_and(|r| r <= T::lit(0.0625));
                chord_spent = chord_spent || !chord_next;
                let done = size <= done_at
                    || (!friction
                        && rho.is_some_and(|r| {
                            r <= T::lit(0.25) && T::lit(4.0) * r * size <= done_at
                        }));
                if !done {
                    continue;
                }
            } else {
                n += dn / length;
                m += dm;
                last_step = Some(size);
                chord_next = !chord_spent;
                // Newton's `C` and its stall from consecutive Newton steps only.
                let prior = last_newton;
                last_newton = Some(size);
                let stalled =
                    prior.is_some_and(|last| size >= last * T::lit(0.5)) && contraction.is_some();
                contraction = prior
                    .filter(|last| *last > T::zero())
                    .map(|last| size / (last * last));
                // Done when the correction is at rounding, or (without friction, and converging
                // clearly: a quarter of the last correction at most) when the one it leaves,
                // `C |step|^2`, is.
                let converging = prior.is_some_and(|last| size <= last * T::lit(0.25));
                let done = size <= done_at
                    || (!friction
                        && converging
                        && contraction.is_some_and(|c| T::lit(4.0) * c * size * size <= done_at));
                if !(done || stalled) {
                    continue;
                }
                if !done && size > T::lit(1024.0) * eps * scale {
                    return false;
                }
            }
            if count > carried {
                // Converged on a look-ahead without the tangents: one more, at the answer, with them.
                contraction = Some(T::zero());
                passes = passes.max(pass + 1);
                continue;
            }
            // The tangents at the next guide come from the look-ahead where no cable reads them
            // at the nodes between (`observe` in the sweep), and where it ran at the answer: at
            // rounding, or (`jumping_ahead`) one correction `|step|` from it, which it predicted at
            // rounding (the tangents then lie on a path `|step|` off the sweep's; the riding
            // tangents' jump was taken there already).
            let ahead_of_sweep =
                self.model.grid().cable_offsets.is_empty() && (size <= done_at || self.jump_ahead);
            // The tangents: `dx = dx0 + delta`, `(I + W_next Psi) delta = -W_next dP0`; the next
            // pose then moves by `dP0 + Psi delta`, which sets the tensions beyond. `dx0` is the
            // tangent before the jump less the known poses' and tensions' share, here; the look-ahead
            // integrated the tangent before the jump, so its end is corrected along the six
            // directions (the look-ahead is linear in its tangents).
            for (j, t) in tangents.iter_mut().enumerate().take(count) {
                let ahead = if assemble {
                    self.assembled(&t.rod, &all)
                } else {
                    let Some(ahead) = all.get(6 + j) else {
                        return false;
                    };
                    *ahead
                };
                let ahead = &ahead;
                let d = pose_delta(&t.rod);
                let known = self
                    .load(
                        guide,
                        &back,
                        poses,
                        Some(([&t.prev, &d, &zero], &t.d_chord_n)),
                    )
                    .d_wrench;
                let fix = self.stack(&(-known.force_n), &(-known.moment_nm));
                let d0 = stacked(&pose_delta(ahead)) + lin.psi * fix;
                let Some(delta) = lin.lu.solve(&(-(lin.w_next * d0))) else {
                    return false;
                };
                let (dn, dm) = split(&(fix + delta));
                t.rod.n += dn / length;
                t.rod.m += dm;
                if friction {
                    let d_next = unstacked(&(d0 + lin.psi * delta));
                    let d_cur = pose_delta(&t.rod);
                    let full = self.load(
                        guide,
                        &back,
                        poses,
                        Some(([&t.prev, &d_cur, &d_next], &t.d_chord_n)),
                    );
                    carry(
                        &self.tendons.routed,
                        guide,
                        &full.d_ahead_n,
                        &mut t.d_chord_n,
                    );
                }
                if ahead_of_sweep {
                    // The look-ahead integrated this tangent to the next guide; with the jump's
                    // change of `(n, m)` along the six directions (the look-ahead is linear in its
                    // tangents) it is the tangent there, and the sweep need not step it again.
                    t.prev = pose_delta(&t.rod);
                    t.rod = along(*ahead, &all, (fix + delta).iter());
                }
            }
            if let Some(memory) = self.memory {
                // (`lin` holds the remembered factors where no Newton pass replaced them.)
                let wrench = self.stack(&(n_minus - n), &(m_minus - m));
                let recalled = remembered.is_some() && !linearised;
                memory.keep(guide, self.scale(), &wrench, &lin.lu, recalled);
            }
            y.tangents_ahead = ahead_of_sweep && count > 0;
            carry(&self.tendons.routed, guide, &here.ahead_n, &mut y.chord_n);
            y.rod.n = n;
            y.rod.m = m;
            return true;
        }
        false
    }
}

/// A jump's Newton linearisation at a look-ahead: `W_next`, the wrench per move of the next pose
/// (stacked both), `Psi`, the next pose's moves along the look-ahead's six directions, and
/// `I + W_next Psi` factored.
struct Linearised<T: Scalar> {
    w_next: SMatrix<T, 6, 6>,
    psi: SMatrix<T, 6, 6>,
    lu: Lu6<T>,
}

/// A 6 x 6 matrix's LU factors.
type Lu6<T> = nalgebra::linalg::LU<T, nalgebra::Const<6>, nalgebra::Const<6>>;

impl<T: Scalar> Linearised<T> {
    /// Before the first Newton pass (never used: a chord step needs one).
    fn blank() -> Self {
        Self {
            w_next: SMatrix::zeros(),
            psi: SMatrix::zeros(),
            lu: SMatrix::<T, 6, 6>::identity().lu(),
        }
    }
}

/// `start` moved along `dirs` by `weights` (as many as both give), in order.
fn along<'w, T: Scalar>(
    start: force_state::Tangent<T>,
    dirs: &[force_state::Tangent<T>],
    weights: impl Iterator<Item = &'w T>,
) -> force_state::Tangent<T> {
    dirs.iter()
        .zip(weights)
        .fold(start, |end, (d, w)| end.axpy(d, *w))
}

/// Each tendon passing `guide` takes its tension beyond (`ahead`) into the next chord.
fn carry<T: Scalar>(
    routed: &[Routed<T>],
    guide: usize,
    ahead: &[T; MAX_TENDONS],
    chord: &mut [T; MAX_TENDONS],
) {
    for ((c, a), r) in chord.iter_mut().zip(ahead).zip(routed) {
        if role(r, guide) == Role::Passes {
            *c = *a;
        }
    }
}

/// A tangent's pose change: position (global) and rotation (body frame).
fn pose_delta<T: Scalar>(t: &force_state::Tangent<T>) -> PoseDelta<T> {
    PoseDelta {
        position_m: t.p,
        rotation_rad: t.th,
    }
}

/// A pose change stacked: position (m, rows 0-2), rotation (rad, rows 3-5).
fn stacked<T: Scalar>(d: &PoseDelta<T>) -> SVector<T, 6> {
    crate::scalar::stacked(&d.position_m, &d.rotation_rad)
}

/// A stacked pose change as a [`PoseDelta`].
fn unstacked<T: Scalar>(v: &SVector<T, 6>) -> PoseDelta<T> {
    let (position_m, rotation_rad) = split(v);
    PoseDelta {
        position_m,
        rotation_rad,
    }
}

/// The force and moment parts of a stacked wrench.
fn split<T: Scalar>(v: &SVector<T, 6>) -> (Vector3<T>, Vector3<T>) {
    (
        v.fixed_rows::<3>(0).into_owned(),
        v.fixed_rows::<3>(3).into_owned(),
    )
}

/// The rod's state and the previous guide's pose.
#[derive(Clone, Copy, Debug)]
pub(crate) struct State<T: Scalar, A> {
    rod: force_state::State<T, A>,
    prev: GuidePose<T>,
    /// Each tendon's tension in the chord arriving at the next guide, N (at the load scale).
    chord_n: [T; MAX_TENDONS],
    /// Whether the tangents are already the next guide's (the last jump's look-ahead integrated
    /// them there, `RodOde::tangents_ahead`).
    tangents_ahead: bool,
}

/// A tangent of the rod's state and of the previous guide's pose.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tangent<T> {
    rod: force_state::Tangent<T>,
    prev: PoseDelta<T>,
    d_chord_n: [T; MAX_TENDONS],
}

impl<T: Scalar> Linear<T> for Tangent<T> {
    #[inline]
    fn zero() -> Self {
        Self {
            rod: force_state::Tangent::zero(),
            prev: PoseDelta::zero(),
            d_chord_n: [T::zero(); MAX_TENDONS],
        }
    }

    /// The previous pose does not change along an interval.
    #[inline]
    fn axpy(&self, k: &Self, h: T) -> Self {
        Self {
            rod: self.rod.axpy(&k.rod, h),
            ..*self
        }
    }

    #[inline]
    fn rk4(&self, k: &[Self; 4], h: T) -> Self {
        let [k1, k2, k3, k4] = k;
        Self {
            rod: self.rod.rk4(&[k1.rod, k2.rod, k3.rod, k4.rod], h),
            ..*self
        }
    }

    fn is_finite(&self) -> bool {
        self.rod.is_finite()
            && crate::scalar::all_finite(&self.prev.position_m)
            && crate::scalar::all_finite(&self.prev.rotation_rad)
            && self.d_chord_n.iter().all(|x| x.is_finite())
    }
}

type Inner<'a, T, A, const NODES: usize> = ForceStateRod<'a, T, A, NoShapeLoad, NODES>;

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> RodOde<T, 6>
    for TendonRod<'a, T, A, NODES>
{
    type State = State<T, A>;
    type Rate = force_state::Rates<T, A>;
    type Stage = force_state::Stage<T>;
    type Tangent = Tangent<T>;
    type Seed = Vector3<T>;
    type Field = force_state::Field<'a, T>;
    type Track = ();

    fn grid(&self) -> Grid<'_, T> {
        self.rod.grid()
    }

    fn length_m(&self) -> T {
        self.rod.length_m()
    }

    fn at_scale(&self, load_scale: T) -> Self {
        Self {
            rod: self.rod.at_scale(load_scale),
            scaled_n: self.tensions_n.map(|t| t * load_scale),
            ..*self
        }
    }

    /// The dead loads' guess, plus each tendon on the straight rod: its chords all lie along the
    /// tangent, so only its termination pulls, `-tau t` at the hole.
    fn guess(&self) -> SVector<T, 6> {
        let rod = self.model.rod();
        let tangent = rod.base_orientation.column(2).into_owned();
        let mut n0 = Vector3::zeros();
        let mut m0 = Vector3::zeros();
        for (r, tau) in self.tendons.routed.iter().zip(self.tensions()) {
            let f = tangent * (-*tau);
            n0 += f;
            m0 += (rod.base_orientation * r.offset_m).cross(&f);
        }
        self.rod.guess() + self.rod.unknowns(&n0, &m0)
    }

    fn start(&self, x: &SVector<T, 6>) -> State<T, A> {
        if let Some(record) = self.record {
            record.start(x, self.rod.alpha());
        }
        if let Some(paths) = self.paths {
            paths.start();
        }
        let rod = self.model.rod();
        State {
            rod: self.rod.start(x),
            prev: GuidePose {
                position_m: rod.base_position_m,
                rotation: rod.base_orientation,
            },
            chord_n: self.scaled_n,
            tangents_ahead: false,
        }
    }

    /// A tension's tangent starts as a change of that tendon's tension in every chord (at the load
    /// scale; frictionless it stays one, with capstan friction it reads the wraps at each hole);
    /// the rod's state does not move at the base.
    fn seed(&self, family: Family, j: usize) -> (Tangent<T>, Vector3<T>) {
        let (rod, seed) = self.rod.seed(family, j);
        let mut d_chord_n = [T::zero(); MAX_TENDONS];
        if family == Family::Tension
            && let Some(d) = d_chord_n.get_mut(j)
        {
            *d = self.rod.alpha();
        }
        (
            Tangent {
                rod,
                d_chord_n,
                ..Tangent::zero()
            },
            seed,
        )
    }

    fn no_seed(&self) -> Vector3<T> {
        Vector3::zeros()
    }

    fn blank_stage(&self) -> force_state::Stage<T> {
        self.rod.blank_stage()
    }

    fn field(&self, interval: &Interval<T>) -> Option<force_state::Field<'a, T>> {
        self.rod.field(interval)
    }

    #[inline]
    fn bending_load(&self, f: &force_state::Field<'a, T>, s: T, y: &State<T, A>) -> T {
        self.rod.bending_load(f, s, &y.rod)
    }

    #[inline]
    fn stage_bending_load(
        &self,
        f: &force_state::Field<'a, T>,
        stage: &force_state::Stage<T>,
    ) -> T {
        self.rod.stage_bending_load(f, stage)
    }

    #[inline]
    fn rate(
        &self,
        f: &force_state::Field<'a, T>,
        s: T,
        y: &State<T, A>,
        record: Option<&mut force_state::Stage<T>>,
    ) -> force_state::Rates<T, A> {
        self.rod.rate(f, s, &y.rod, record)
    }

    #[inline]
    fn advance(y: &State<T, A>, k: &force_state::Rates<T, A>, h: T) -> State<T, A> {
        State {
            rod: Inner::<T, A, NODES>::advance(&y.rod, k, h),
            ..*y
        }
    }

    #[inline]
    fn combine(y: &State<T, A>, k: [&force_state::Rates<T, A>; 4], h: T) -> State<T, A> {
        State {
            rod: Inner::<T, A, NODES>::combine(&y.rod, k, h),
            ..*y
        }
    }

    #[inline]
    fn tangent_rate(
        &self,
        f: &force_state::Field<'a, T>,
        stage: &force_state::Stage<T>,
        seed: &Vector3<T>,
        t: &Tangent<T>,
    ) -> Tangent<T> {
        Tangent {
            rod: self.rod.tangent_rate(f, stage, seed, &t.rod),
            ..Tangent::zero()
        }
    }

    /// The dead point loads, then at a guide the tendons' jump (implicit where one passes).
    fn node(
        &self,
        node: &Node<T>,
        _proximal: &force_state::Field<'a, T>,
        _distal: &force_state::Field<'a, T>,
        y: &mut State<T, A>,
        tangents: &mut [Tangent<T>],
    ) {
        let alpha = self.rod.alpha();
        y.rod.n -= node.force_n * alpha;
        y.rod.m -= node.moment_nm * alpha;
        if node.guide == NO_GUIDE {
            return;
        }
        // Tangents integrated here by the last jump's look-ahead are this guide's now.
        y.tangents_ahead = false;
        let guide = usize::from(node.guide);
        let cur = Self::guide_pose(&y.rod);
        if let Some(record) = self.record {
            record.pass(guide, &cur);
        }
        if let Some(paths) = self.paths {
            paths.pass(guide, &y.prev, &cur, tangents, &self.tendons.routed);
        }
        let zero = PoseDelta::zero();
        if reads_next(&self.tendons.routed, &y.chord_n, guide) {
            let grid = self.rod.grid();
            let index = grid.nodes.iter().position(|n| n.guide == node.guide);
            // A jump that started from the memory and failed is solved again without it (a failed
            // jump leaves the state as it was).
            let solved = index.is_some_and(|index| {
                self.implicit_jump(index, guide, y, tangents, true)
                    || (tangents.is_empty()
                        && self.memory.is_some()
                        && self.implicit_jump(index, guide, y, tangents, false))
            });
            if !solved {
                // No consistent jump: the sweep reports a non-finite result, never a wrong one.
                y.rod.n = Vector3::repeat(T::lit(f64::NAN));
            }
        } else {
            let prev = y.prev;
            let poses = [&prev, &cur, &cur];
            let w = self.load(guide, &y.chord_n, poses, None).wrench;
            for t in tangents.iter_mut() {
                let d = pose_delta(&t.rod);
                let dw = self
                    .load(
                        guide,
                        &y.chord_n,
                        poses,
                        Some(([&t.prev, &d, &zero], &t.d_chord_n)),
                    )
                    .d_wrench;
                t.rod.n -= dw.force_n;
                t.rod.m -= dw.moment_nm;
            }
            y.rod.n -= w.force_n;
            y.rod.m -= w.moment_nm;
        }
        y.prev = cur;
        if !y.tangents_ahead {
            for t in tangents.iter_mut() {
                t.prev = pose_delta(&t.rod);
            }
        }
    }

    fn tangents_ahead(&self, y: &State<T, A>) -> bool {
        y.tangents_ahead
    }

    /// The wrapped tip condition, less the tendons terminating at a tip guide.
    fn tip(
        &self,
        node: Option<&Node<T>>,
        last: &force_state::Field<'a, T>,
        y: &State<T, A>,
        tangents: &[Tangent<T>],
        seeds: &[Vector3<T>],
        d: &mut [SVector<T, 6>],
    ) -> SVector<T, 6> {
        let mut rod_tangents = [force_state::Tangent::zero(); MAX_TANGENTS];
        for (r, t) in rod_tangents.iter_mut().zip(tangents) {
            *r = t.rod;
        }
        let rod_tangents = rod_tangents.get(..tangents.len()).unwrap_or(&[]);
        let mut r = self.rod.tip(node, last, &y.rod, rod_tangents, seeds, d);
        if let Some(node) = node.filter(|n| n.guide != NO_GUIDE) {
            let guide = usize::from(node.guide);
            let cur = Self::guide_pose(&y.rod);
            if let Some(record) = self.record {
                record.pass(guide, &cur);
            }
            if let Some(paths) = self.paths {
                paths.pass(guide, &y.prev, &cur, tangents, &self.tendons.routed);
            }
            let zero = PoseDelta::zero();
            let poses = [&y.prev, &cur, &cur];
            let w = self.load(guide, &y.chord_n, poses, None).wrench;
            r -= self.stack(&w.force_n, &w.moment_nm);
            for (e, t) in d.iter_mut().zip(tangents) {
                let dc = pose_delta(&t.rod);
                let dw = self
                    .load(
                        guide,
                        &y.chord_n,
                        poses,
                        Some(([&t.prev, &dc, &zero], &t.d_chord_n)),
                    )
                    .d_wrench;
                *e -= self.stack(&dw.force_n, &dw.moment_nm);
            }
        }
        r
    }

    fn pose(&self, y: &State<T, A>) -> Pose<T> {
        self.rod.pose(&y.rod)
    }

    fn tangent_pose(&self, y: &State<T, A>, t: &Tangent<T>) -> (Vector3<T>, Vector3<T>) {
        self.rod.tangent_pose(&y.rod, &t.rod)
    }

    fn shape_point(&self, s: T, y: &State<T, A>, f: &force_state::Field<'a, T>) -> ShapePoint<T> {
        self.rod.shape_point(s, &y.rod, f)
    }

    fn finite(&self, y: &State<T, A>, tangents: &[Tangent<T>]) -> bool {
        let mut rod_tangents = [force_state::Tangent::zero(); MAX_TANGENTS];
        for (r, t) in rod_tangents.iter_mut().zip(tangents) {
            *r = t.rod;
        }
        let rod_tangents = rod_tangents.get(..tangents.len()).unwrap_or(&[]);
        self.rod.finite(&y.rod, rod_tangents) && tangents.iter().all(Linear::is_finite)
    }

    /// No energy test with tendons yet: a cold solve follows the branch from the slack rod by load
    /// continuation and the answer's stability is reported unchecked.
    fn has_stability_test(&self) -> bool {
        false
    }

    /// Constant tensions are conservative (potential `tau` times the path length).
    fn conservative(&self) -> bool {
        true
    }

    fn track(&self) {}

    fn crosses(
        &self,
        _track: &mut (),
        _y: &State<T, A>,
        _tangents: &[Tangent<T>],
        _f: &force_state::Field<'a, T>,
        _step_m: T,
    ) -> bool {
        false
    }

    fn jacobi_rotation(&self, _d_rotation: &Vector3<T>) -> SVector<T, 6> {
        SVector::zeros()
    }

    fn residual_size(&self, r: &SVector<T, 6>) -> T {
        self.rod.residual_size(r)
    }

    fn rotation_rad(&self, x: &SVector<T, 6>) -> T {
        self.rod.rotation_rad(x)
    }

    /// The base force's rows count against the tendons' tensions as well as the rod's stiffness
    /// (MODEL.md 6.5): the base force is the tendons' pull along their first chords, so a turn
    /// `phi` of those chords moves it by `sum tau phi`, which the force rows (`|n| L / E I`, times
    /// `L`: what a tip force would bend the rod by) would count `sum tau L^2 / E I` times (94 on a
    /// 0.4 m, 1.4 mm Nitinol rod at 6 N). Divided by `1 + sum tau L^2 / E I`, that turn counts as a
    /// turn; without tensions the rows are the force-state rod's.
    fn change_rad(&self, dx: &SVector<T, 6>) -> T {
        let length = self.model.length_m();
        let total_n = self.tensions().iter().fold(T::zero(), |a, t| a + t.abs());
        // `sum tau L / E I`: the force rows of the tensions' sum.
        let pull = self.rod.unknowns(
            &Vector3::new(total_n, T::zero(), T::zero()),
            &Vector3::zeros(),
        );
        let k = pull.fixed_rows::<3>(0).norm() * length;
        let force = dx.fixed_rows::<3>(0).norm() / (T::one() + k);
        let moment = dx.fixed_rows::<3>(3).norm();
        (force * force + moment * moment).sqrt() * length
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::plan::MAX_NODES;
    use crate::sweep::{TangentSet, sweep};
    use crate::tendon::Tendon;
    use crate::{CrossSection, Guide, GuideMass, Material, Rod, Section, Stiffness};

    /// A plain sweep at a converged equilibrium is finite and gives its tip and its residual,
    /// whatever its jumps' chord steps do: at a high tension, where a chord step from the
    /// straight-ahead start may not contract (it is not taken then), the shape sweep of a
    /// converged solve agrees with the solve, and so does a sweep with tangents.
    #[test]
    fn tendon_plain_sweeps_at_a_converged_equilibrium_agree_with_it() {
        let (model, tendons) = scene();
        let tendons = Tendons::new(&model, &tendons).unwrap();
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        for tau in [[20.0, 0.0], [8.0, 4.0], [2.0, 1.5]] {
            let eq = model
                .solve_tendons(&tendons, &tau, &load, None, &Default::default())
                .unwrap();
            assert!(eq.is_success(), "{tau:?}: {:?}", eq.equilibrium.report);
            let mut out = [ShapePoint::default(); 4];
            let written = model
                .shape_tendons(&tendons, &eq, &[0.0, 0.1, 0.2, 0.3], &mut out)
                .unwrap();
            assert_eq!(written, 4);
            let tip = eq.equilibrium.tip_position_m;
            assert!((out[3].position_m - tip).norm() < 1e-12, "{tau:?}");
            let mut full = [0.0; MAX_TENDONS];
            full[..2].copy_from_slice(&tau);
            let ode = TendonRod::new(&model, &tendons, &full, &load, 1.0);
            let eqb = &eq.equilibrium;
            let x = ode.unknowns(&eqb.base_force_n, &eqb.base_moment_nm);
            let plain = sweep(&ode, &x, TangentSet::NONE, None);
            let with = sweep(&ode, &x, TangentSet::unknowns(false), None);
            assert!(plain.finite && with.finite, "{tau:?}");
            assert!(
                plain.residual.norm() < 1e-9,
                "{tau:?}: {:e}",
                plain.residual.norm()
            );
            assert!((plain.residual - with.residual).norm() < 1e-12, "{tau:?}");
        }
    }

    /// A plain sweep on remembered jumps (`JumpMemory`) gives the sweep without them: near the
    /// sweep they were kept at (the jumps then converge on the remembered factors alone, one
    /// per jump and sweep), far from it (new tensions and a base moved by a tenth, where chord
    /// steps may be refused), and from a memory kept at another load scale (not read).
    #[test]
    fn tendon_remembered_jumps_give_the_same_sweeps() {
        let (model, tendons) = scene();
        let tendons = Tendons::new(&model, &tendons).unwrap();
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        let tension = |t: [f64; 2]| {
            let mut full = [0.0; MAX_TENDONS];
            full[..2].copy_from_slice(&t);
            full
        };
        let tau = tension([2.0, 1.5]);
        let eq = model
            .solve_tendons(&tendons, &tau[..2], &load, None, &Default::default())
            .unwrap();
        assert!(eq.is_success());
        let eqb = &eq.equilibrium;
        let ode = TendonRod::new(&model, &tendons, &tau, &load, 1.0);
        let x = ode.unknowns(&eqb.base_force_n, &eqb.base_moment_nm);
        // Jumps where a tendon passes: guides 0-2 (the last is the tip's termination).
        let jumps = 3usize;
        let memory = JumpMemory::new();
        let kept = ode.remembering(&memory);
        assert!(sweep(&kept, &x, TangentSet::unknowns(false), None).finite);
        assert_eq!(
            memory.recalled(),
            0,
            "a sweep with tangents does not read the memory"
        );
        let same =
            |tau: &[f64; MAX_TENDONS], x: &SVector<f64, 6>, memory: &JumpMemory<f64, MAX_NODES>| {
                let plain = TendonRod::new(&model, &tendons, tau, &load, 1.0);
                let remembering = plain.remembering(memory);
                let (a, b) = (
                    sweep(&plain, x, TangentSet::NONE, None),
                    sweep(&remembering, x, TangentSet::NONE, None),
                );
                assert!(
                    a.finite && b.finite,
                    "{tau:?} {x:?}: finite {} {}",
                    a.finite,
                    b.finite
                );
                let scale = a.residual.norm().max(model.moment_scale_nm());
                // Each jump ends within its rounding (`done_at`, 16 eps of its wrench) either way.
                let off = (a.residual - b.residual).norm() / scale;
                assert!(off < 1e-12, "residuals {off:e} apart (relative)");
                assert!((a.tip_position_m - b.tip_position_m).norm() < 1e-13);
            };
        let mut recalled = 0;
        for (k, (t, dx)) in [
            ([2.0, 1.5], 0.0),
            ([2.0, 1.5], 1e-6),
            ([2.01, 1.49], 1e-4),
            ([2.02, 1.5], 1e-3),
        ]
        .into_iter()
        .enumerate()
        {
            let moved = x.map(|v| v * (1.0 + dx) + dx * 1e-3);
            same(&tension(t), &moved, &memory);
            recalled += jumps as u32;
            assert_eq!(memory.recalled(), recalled, "case {k}: every jump recalled");
        }
        // Far: chord steps on the remembered factors may be refused; Newton then goes on.
        for (t, dx) in [([3.0, 0.5], 0.1), ([0.5, 3.0], -0.1), ([8.0, 4.0], 0.05)] {
            same(&tension(t), &x.map(|v| v * (1.0 + dx)), &memory);
        }
        // A memory kept at another load scale is not read, however close.
        let other = JumpMemory::new();
        let near = TendonRod::new(&model, &tendons, &tau, &load, 1.0 - 1e-9).remembering(&other);
        assert!(sweep(&near, &x, TangentSet::unknowns(false), None).finite);
        same(&tau, &x, &other);
        assert_eq!(other.recalled(), 0);
        // An absurd memory is left for the straight-ahead start: a wrench no look-ahead survives,
        // singular factors.
        for (wrench, matrix) in [
            (
                SVector::<f64, 6>::repeat(1e200),
                SMatrix::<f64, 6, 6>::identity(),
            ),
            (SVector::zeros(), SMatrix::zeros()),
        ] {
            let absurd = JumpMemory::<f64, MAX_NODES>::new();
            for guide in 0..jumps {
                absurd.keep(guide, 1.0, &wrench, &matrix.lu(), false);
            }
            same(&tau, &x, &absurd);
            assert_eq!(absurd.recalled(), 0);
        }
    }

    /// A memory kept far from where it is read (a sweep at other tensions, 0 to 40 N, and at other
    /// unknowns, the straight rod's guess scaled by -0.5 to 2, with and without capstan friction)
    /// does not change a plain sweep: it is finite where the sweep without the memory is, and
    /// agrees with it to rounding. (A chord step on another state's factors that is too large or
    /// does not contract leaves the memory, and the jump starts again as without one; a jump that
    /// fails from the memory is solved again without it.) Before those two rules, a jump started
    /// from a far memory reported converged with its condition 1e18 times its tolerance off: a
    /// sweep here was 257 times its residual's size off.
    #[test]
    fn tendon_far_memories_do_not_change_the_sweep() {
        use crate::tendon::Sliding;
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        let (mut checked, mut finite) = (0, 0);
        for mu in [0.0, 0.3] {
            let (model, mut tendons) = scene();
            for t in tendons.iter_mut() {
                t.friction_coefficient = mu;
            }
            let mut tendons = Tendons::new(&model, &tendons).unwrap();
            tendons.set_sliding(0, Sliding::In);
            tendons.set_sliding(1, Sliding::Out);
            let mut states = Vec::new();
            for tau in [0.0, 2.0, 10.0, 40.0] {
                let mut full = [0.0; MAX_TENDONS];
                full[..2].copy_from_slice(&[tau, 0.3 * tau]);
                let guess = TendonRod::new(&model, &tendons, &full, &load, 1.0).guess();
                for scale in [-0.5, 0.0, 0.5, 1.0, 2.0] {
                    states.push((full, guess * scale));
                }
            }
            for (kept_tau, kept_x) in &states {
                let memory = JumpMemory::new();
                let keeping =
                    TendonRod::new(&model, &tendons, kept_tau, &load, 1.0).remembering(&memory);
                if !sweep(&keeping, kept_x, TangentSet::NONE, None).finite {
                    continue;
                }
                for (tau, x) in &states {
                    let plain = TendonRod::new(&model, &tendons, tau, &load, 1.0);
                    let without = sweep(&plain, x, TangentSet::NONE, None);
                    // (The memory is kept afresh by each read: the next read starts from it.)
                    let with = sweep(&plain.remembering(&memory), x, TangentSet::NONE, None);
                    let case = format!(
                        "mu {mu}: kept at {:?} {kept_x:?}, read at {:?} {x:?}",
                        &kept_tau[..2],
                        &tau[..2]
                    );
                    checked += 1;
                    assert_eq!(with.finite, without.finite, "{case}");
                    if !without.finite {
                        continue;
                    }
                    finite += 1;
                    let size = without.residual.norm().max(model.moment_scale_nm());
                    let off = (with.residual - without.residual).norm() / size;
                    assert!(off < 1e-9, "{case}: {off:e}");
                }
            }
        }
        assert!(finite > checked / 2, "{finite} of {checked} finite");
    }

    /// A rod under gravity with four guides and two tendons, one ending mid-way.
    pub(crate) fn scene() -> (Model<f64>, [Tendon<f64>; 2]) {
        let mut rod = Rod::new();
        rod.gravity_m_s2 = Vector3::new(0.0, -9.81, 0.0);
        rod.guide_mass = GuideMass::Ignore;
        let material = Material::isotropic(60e9, 0.3).unwrap();
        rod.push_section(Section {
            length_m: 0.3,
            stiffness: Stiffness::from_material(
                &material,
                &CrossSection::solid_circle(1.5e-3).unwrap(),
            )
            .unwrap(),
            line_density_kg_per_m: 0.03,
            steps: 60,
        })
        .unwrap();
        for k in 1..=4 {
            rod.push_guide(Guide {
                s_m: 0.075 * f64::from(k),
                thickness_m: 0.0,
                mass_kg: 0.0,
            })
            .unwrap();
        }
        let model = Model::new(rod).unwrap();
        (
            model,
            [
                Tendon::at_angle(0.3, 0.01, 0.3),
                Tendon::at_angle(2.0, 0.008, 0.15),
            ],
        )
    }

    /// The sweep's Jacobian (tangents through the implicit jumps, the chords' tensions with capstan
    /// friction both ways) against central differences.
    #[test]
    fn tendon_jacobian_matches_finite_differences() {
        use crate::tendon::Sliding;
        for (mu, sliding) in [(0.0, Sliding::In), (0.3, Sliding::In), (0.3, Sliding::Out)] {
            jacobian_matches(mu, sliding);
        }
    }

    fn jacobian_matches(mu: f64, sliding: crate::tendon::Sliding) {
        let (model, mut tendons) = scene();
        for t in tendons.iter_mut() {
            t.friction_coefficient = mu;
        }
        let mut tendons = Tendons::new(&model, &tendons).unwrap();
        tendons.set_sliding(0, sliding);
        tendons.set_sliding(1, sliding);
        let mut tau = [0.0; MAX_TENDONS];
        tau[0] = 2.0;
        tau[1] = 1.5;
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        let plain = TendonRod::new(&model, &tendons, &tau, &load, 1.0);
        // Also with the tangents taken from the look-aheads one predicted correction from the
        // jumps' answers (`jumping_ahead`), not only at rounding.
        for ode in [plain, plain.jumping_ahead()] {
            jacobian_of_matches(&ode, mu);
        }
    }

    fn jacobian_of_matches(
        ode: &TendonRod<'_, f64, crate::kinematics::Quaternion<f64>, MAX_NODES>,
        mu: f64,
    ) {
        let x = ode.guess() * 0.7;
        let sw = sweep(ode, &x, TangentSet::unknowns(false), None);
        assert!(sw.finite);
        let j = sw.jacobian();
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        for c in 0..6 {
            let mut dx = SVector::<f64, 6>::zeros();
            dx[c] = h;
            let plus = sweep(ode, &(x + dx), TangentSet::NONE, None);
            let minus = sweep(ode, &(x - dx), TangentSet::NONE, None);
            let fd = (plus.residual - minus.residual) / (2.0 * h);
            let err = (fd - j.column(c)).norm() / j.norm();
            worst = worst.max(err);
        }
        // The tangents are RK4 of the linearised equations over the state's stages: the sweep's
        // derivative to the scheme's order, not to rounding (the quaternion is normalised after each
        // step, its tangent is not). On this scene that leaves 1.7-1.9e-7 (relative), the same with
        // steps of 1e-4 to 1e-7 and before the look-aheads were made cheaper: a discretisation
        // floor, not the differences' error. Twice that fails a missing or wrong term.
        assert!(
            worst < 4e-7,
            "mu {mu}: Jacobian off by {worst:e} (relative)"
        );
    }
}
