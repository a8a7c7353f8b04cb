//! The 3D rod with the internal force and moment as states, for loads that read the shape: once a
//! load depends on the pose, `n(s)` is no longer known before the sweep.
//!
//! State `(p, R, n, m)`, `n` and `m` in the global frame:
//! `p' = R v`, `R' = R hat(u)`, `n' = -f`, `m' = -p' x n`, with `v = D^-1 R^T n + e3` (or `e3`,
//! Kirchhoff), `u = C^-1 R^T m` and `f = rho g` the weight per length. At a node the point loads
//! (dead ones from the plan, and those of [`ShapeLoad`]s at the pose there) make `n` and `m` jump:
//! `n(s+) = n(s-) - F`, `m(s+) = m(s-) - M`. The unknowns are `n(0)` and `m(0)` just distal of the
//! clamp; the tip conditions are `n(L) = F_tip` and `m(L) = M_tip` after the tip node's loads.
//!
//! Unknowns and residuals are scaled so that the solver's sizes are those of the dead-load equations:
//! `x = (n(0) L / E I, m(0) / E I)` (1/m, like a base strain) and `r = ((n(L) - F) L, m(L) - M)`
//! (N m, like a tip-moment error), `E I` the smallest bending stiffness.
//!
//! Linearised, with a tangent `(dp, dtheta, dn, dm)`, `dR = R hat(dtheta)`, `n_l = R^T n`,
//! `m_l = R^T m`: `dn_l = n_l x dtheta + R^T dn`, `dm_l = m_l x dtheta + R^T dm`, `dv = D^-1 dn_l`,
//! `du = C^-1 dm_l`, `dp' = R (dtheta x v + dv)`, `dtheta' = du - u x dtheta`, `dn' = 0`,
//! `dm' = -(dp' x n + p' x dn)`.

use nalgebra::{Matrix3, SVector, Vector3};

use super::dead_load::compensated_add;
use super::guess::StraightRod;
use super::{Family, Linear, Pose, RodOde};
use crate::Scalar;
use crate::constitutive::Compliance;
use crate::kinematics::Attitude;
use crate::loads::{NodePose, PoseChange, ShapeLoad, TipLoad, Wrench};
use crate::model::{Grid, Model};
use crate::plan::{Interval, NO_GUIDE, Node};
use crate::rod::StrainModel;
use crate::shape::ShapePoint;

/// The 3D rod under dead loads and loads that read the shape.
#[derive(Debug)]
pub(crate) struct ForceStateRod<'a, T: Scalar, A: Attitude<T>, L, const NODES: usize> {
    model: &'a Model<T, A, NODES>,
    loads: &'a L,
    load: TipLoad<T>,
    alpha: T,
    kirchhoff: bool,
    /// The smallest bending stiffness, N m^2: the scale of the unknowns and the residual.
    ei_nm2: T,
}

impl<T: Scalar, A: Attitude<T>, L, const NODES: usize> Clone for ForceStateRod<'_, T, A, L, NODES> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T: Scalar, A: Attitude<T>, L, const NODES: usize> Copy for ForceStateRod<'_, T, A, L, NODES> {}

impl<'a, T: Scalar, A: Attitude<T>, L: ShapeLoad<T>, const NODES: usize>
    ForceStateRod<'a, T, A, L, NODES>
{
    /// The equations of `model` under `load`, the scene's dead loads and `loads`, scaled by `alpha`.
    pub(crate) fn new(
        model: &'a Model<T, A, NODES>,
        loads: &'a L,
        load: &TipLoad<T>,
        alpha: T,
    ) -> Self {
        Self {
            model,
            loads,
            load: *load,
            alpha,
            kirchhoff: model.rod().strain_model == StrainModel::Kirchhoff,
            ei_nm2: model.moment_scale_nm() * model.length_m(),
        }
    }

    /// The scaled unknowns of a base force (N) and moment (N m), global frame.
    pub(crate) fn unknowns(&self, force_n: &Vector3<T>, moment_nm: &Vector3<T>) -> SVector<T, 6> {
        let n = force_n * (self.model.length_m() / self.ei_nm2);
        let m = moment_nm / self.ei_nm2;
        crate::scalar::stacked(&n, &m)
    }

    /// The base force (N) and moment (N m) of scaled unknowns `x`.
    pub(crate) fn force_moment(&self, x: &SVector<T, 6>) -> (Vector3<T>, Vector3<T>) {
        let n = Vector3::new(x[0], x[1], x[2]) * (self.ei_nm2 / self.model.length_m());
        let m = Vector3::new(x[3], x[4], x[5]) * self.ei_nm2;
        (n, m)
    }

    /// The load scale.
    pub(crate) fn alpha(&self) -> T {
        self.alpha
    }

    /// The base strain, force and moment of unknowns `x`.
    pub(crate) fn base(&self, x: &SVector<T, 6>) -> (Vector3<T>, Vector3<T>, Vector3<T>) {
        let (n, m) = self.force_moment(x);
        let c_inv = self
            .model
            .base_compliance()
            .map_or(Vector3::zeros(), |c| c.c_inv);
        let u0 = c_inv.component_mul(&self.model.rod().base_orientation.tr_mul(&m));
        (u0, n, m)
    }

    fn node_pose(&self, node: &Node<T>, y: &State<T, A>, tip: bool) -> NodePose<T> {
        NodePose {
            s_m: node.s_m,
            guide: (node.guide != NO_GUIDE).then_some(usize::from(node.guide)),
            tip,
            position_m: y.p + y.p_lo,
            rotation: y.att.matrix(),
        }
    }

    fn change(t: &Tangent<T>) -> PoseChange<T> {
        PoseChange {
            position_m: t.p,
            rotation_rad: t.th,
        }
    }
}

/// The state: position (high and low parts, as in the dead-load equations), frame, internal force
/// and moment (global).
#[derive(Clone, Copy, Debug)]
pub(crate) struct State<T: Scalar, A> {
    pub(super) p: Vector3<T>,
    pub(super) p_lo: Vector3<T>,
    pub(super) att: A,
    pub(super) n: Vector3<T>,
    pub(super) m: Vector3<T>,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Rates<T: Scalar, A: Attitude<T>> {
    pub(super) p: Vector3<T>,
    pub(super) att: A::Rate,
    pub(super) n: Vector3<T>,
    pub(super) m: Vector3<T>,
}

/// A tangent `(dp, dtheta, dn, dm)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tangent<T> {
    pub(super) p: Vector3<T>,
    pub(super) th: Vector3<T>,
    pub(super) n: Vector3<T>,
    pub(super) m: Vector3<T>,
}

impl<T: Scalar> Linear<T> for Tangent<T> {
    #[inline]
    fn zero() -> Self {
        Self {
            p: Vector3::zeros(),
            th: Vector3::zeros(),
            n: Vector3::zeros(),
            m: Vector3::zeros(),
        }
    }

    #[inline]
    fn axpy(&self, k: &Self, h: T) -> Self {
        Self {
            p: self.p + k.p * h,
            th: self.th + k.th * h,
            n: self.n + k.n * h,
            m: self.m + k.m * h,
        }
    }

    #[inline]
    fn rk4(&self, k: &[Self; 4], h: T) -> Self {
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let [k1, k2, k3, k4] = k;
        Self {
            p: self.p + (k1.p + k4.p) * w1 + (k2.p + k3.p) * w2,
            th: self.th + (k1.th + k4.th) * w1 + (k2.th + k3.th) * w2,
            n: self.n + (k1.n + k4.n) * w1 + (k2.n + k3.n) * w2,
            m: self.m + (k1.m + k4.m) * w1 + (k2.m + k3.m) * w2,
        }
    }

    fn is_finite(&self) -> bool {
        [self.p, self.th, self.n, self.m]
            .iter()
            .all(crate::scalar::all_finite)
    }
}

/// What a tangent's rate needs from one stage.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stage<T> {
    rot: Matrix3<T>,
    n: Vector3<T>,
    n_local: Vector3<T>,
    m_local: Vector3<T>,
    v: Vector3<T>,
    u: Vector3<T>,
    p_rate: Vector3<T>,
}

/// One interval's compliance and weight per length.
#[derive(Debug)]
pub(crate) struct Field<'a, T> {
    pub(super) comp: &'a Compliance<T>,
    /// Distributed force, N/m, global.
    pub(super) f: Vector3<T>,
    pub(super) kirchhoff: bool,
    /// `(1 / EI)^2` about the softer bending axis, for [`super::bending_load`].
    pub(super) compliance_squared: T,
}

impl<'a, T: Scalar, A: Attitude<T>, L: ShapeLoad<T>, const NODES: usize> RodOde<T, 6>
    for ForceStateRod<'a, T, A, L, NODES>
{
    type State = State<T, A>;
    type Rate = Rates<T, A>;
    type Stage = Stage<T>;
    type Tangent = Tangent<T>;
    type Seed = Vector3<T>;
    type Field = Field<'a, T>;
    type Track = ();

    fn grid(&self) -> Grid<'_, T> {
        self.model.grid()
    }

    fn length_m(&self) -> T {
        self.model.length_m()
    }

    fn at_scale(&self, load_scale: T) -> Self {
        Self {
            alpha: load_scale,
            ..*self
        }
    }

    /// The dead loads' base force and moment on the straight rod, plus the loads that read the shape
    /// evaluated on it.
    fn guess(&self) -> SVector<T, 6> {
        let model = self.model;
        let rod = model.rod();
        let mut n0 = (self.load.force_n + model.plan().base_force_n()) * self.alpha;
        let mut m0 = StraightRod::new(model, &self.load, self.alpha).base_moment_nm();
        let tangent = rod.base_orientation.column(2).into_owned();
        let nodes = &model.plan().nodes;
        for (k, node) in nodes.iter().enumerate().skip(1) {
            let pose = NodePose {
                s_m: node.s_m,
                guide: (node.guide != NO_GUIDE).then_some(usize::from(node.guide)),
                tip: k + 1 == nodes.len(),
                position_m: rod.base_position_m + tangent * node.s_m,
                rotation: rod.base_orientation,
            };
            let w = self.loads.wrench(&pose, self.alpha);
            n0 += w.force_n;
            m0 += w.moment_nm + (tangent * node.s_m).cross(&w.force_n);
        }
        self.unknowns(&n0, &m0)
    }

    fn start(&self, x: &SVector<T, 6>) -> State<T, A> {
        let (n, m) = self.force_moment(x);
        State {
            p: self.model.rod().base_position_m,
            p_lo: Vector3::zeros(),
            att: *self.model.base_attitude(),
            n,
            m,
        }
    }

    /// An unknown's tangent starts as its scaled unit change of `n(0)` or `m(0)`; a tip-force tangent
    /// changes only the tip condition (its seed).
    fn seed(&self, family: Family, j: usize) -> (Tangent<T>, Vector3<T>) {
        match family {
            Family::Unknown => {
                let (n, m) = self.force_moment(&super::unit::<T, 6>(j));
                (
                    Tangent {
                        n,
                        m,
                        ..Tangent::zero()
                    },
                    Vector3::zeros(),
                )
            }
            Family::TipForce => (Tangent::zero(), super::unit::<T, 3>(j) * self.alpha),
            // The tendons' rod seeds its own tensions (`tendon.rs`).
            Family::Tension => (Tangent::zero(), Vector3::zeros()),
        }
    }

    fn no_seed(&self) -> Vector3<T> {
        Vector3::zeros()
    }

    fn blank_stage(&self) -> Stage<T> {
        Stage {
            rot: Matrix3::zeros(),
            n: Vector3::zeros(),
            n_local: Vector3::zeros(),
            m_local: Vector3::zeros(),
            v: Vector3::zeros(),
            u: Vector3::zeros(),
            p_rate: Vector3::zeros(),
        }
    }

    #[inline]
    fn stage_bending_load(&self, f: &Field<'a, T>, stage: &Stage<T>) -> T {
        super::local_bending_load(&stage.n_local, f.compliance_squared)
    }

    #[inline]
    fn bending_load(&self, f: &Field<'a, T>, _: T, y: &State<T, A>) -> T {
        let tangent = y.att.matrix().column(2).into_owned();
        super::bending_load(&y.n, &tangent, f.compliance_squared)
    }

    fn field(&self, interval: &Interval<T>) -> Option<Field<'a, T>> {
        let model: &'a Model<T, A, NODES> = self.model;
        let comp = model.compliance(interval.section)?;
        let compliance = comp.max_bending_compliance();
        Some(Field {
            comp,
            f: model.rod().gravity_m_s2 * (interval.line_density_kg_per_m * self.alpha),
            kirchhoff: self.kirchhoff,
            compliance_squared: compliance * compliance,
        })
    }

    #[inline]
    fn rate(
        &self,
        f: &Field<'a, T>,
        _s: T,
        y: &State<T, A>,
        record: Option<&mut Stage<T>>,
    ) -> Rates<T, A> {
        let rot = y.att.matrix();
        let n_local = rot.tr_mul(&y.n);
        let m_local = rot.tr_mul(&y.m);
        let v = f.comp.shear_strain(&n_local, f.kirchhoff);
        let u = f.comp.c_inv.component_mul(&m_local);
        let p_rate = rot * v;
        if let Some(stage) = record {
            *stage = Stage {
                rot,
                n: y.n,
                n_local,
                m_local,
                v,
                u,
                p_rate,
            };
        }
        Rates {
            p: p_rate,
            att: y.att.rate(&rot, &u),
            n: -f.f,
            m: -p_rate.cross(&y.n),
        }
    }

    #[inline]
    fn advance(y: &State<T, A>, k: &Rates<T, A>, h: T) -> State<T, A> {
        State {
            p: y.p + k.p * h,
            p_lo: y.p_lo,
            att: A::stage(&y.att, &k.att, h),
            n: y.n + k.n * h,
            m: y.m + k.m * h,
        }
    }

    #[inline]
    fn combine(y: &State<T, A>, k: [&Rates<T, A>; 4], h: T) -> State<T, A> {
        let [k1, k2, k3, k4] = k;
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let (p, lo) = compensated_add(&y.p, &((k1.p + k4.p) * w1 + (k2.p + k3.p) * w2));
        State {
            p,
            p_lo: y.p_lo + lo,
            att: A::combine(&y.att, &[k1.att, k2.att, k3.att, k4.att], h),
            n: y.n + (k1.n + k4.n) * w1 + (k2.n + k3.n) * w2,
            m: y.m + (k1.m + k4.m) * w1 + (k2.m + k3.m) * w2,
        }
    }

    #[inline]
    fn tangent_rate(
        &self,
        f: &Field<'a, T>,
        st: &Stage<T>,
        _seed: &Vector3<T>,
        t: &Tangent<T>,
    ) -> Tangent<T> {
        let dnl = st.n_local.cross(&t.th) + st.rot.tr_mul(&t.n);
        let dml = st.m_local.cross(&t.th) + st.rot.tr_mul(&t.m);
        let dv = if f.kirchhoff {
            Vector3::zeros()
        } else {
            f.comp.d_inv.component_mul(&dnl)
        };
        let du = f.comp.c_inv.component_mul(&dml);
        let dp = st.rot * (t.th.cross(&st.v) + dv);
        Tangent {
            p: dp,
            th: du - st.u.cross(&t.th),
            n: Vector3::zeros(),
            m: -(dp.cross(&st.n) + st.p_rate.cross(&t.n)),
        }
    }

    /// Point loads at the node: the plan's dead ones and the loads that read the shape.
    fn node(
        &self,
        node: &Node<T>,
        _proximal: &Field<'a, T>,
        _distal: &Field<'a, T>,
        y: &mut State<T, A>,
        tangents: &mut [Tangent<T>],
    ) {
        let pose = self.node_pose(node, y, false);
        let w = self.loads.wrench(&pose, self.alpha);
        y.n -= node.force_n * self.alpha + w.force_n;
        y.m -= node.moment_nm * self.alpha + w.moment_nm;
        for t in tangents.iter_mut() {
            let dw = self
                .loads
                .wrench_change(&pose, self.alpha, &Self::change(t));
            t.n -= dw.force_n;
            t.m -= dw.moment_nm;
        }
    }

    /// `r = ((n(L) - F) L, m(L) - M)`, `F`, `M` the tip load plus the tip node's loads.
    fn tip(
        &self,
        node: Option<&Node<T>>,
        _last: &Field<'a, T>,
        y: &State<T, A>,
        tangents: &[Tangent<T>],
        seeds: &[Vector3<T>],
        d: &mut [SVector<T, 6>],
    ) -> SVector<T, 6> {
        let length = self.model.length_m();
        let (dead_f, dead_m, pose) = match node {
            Some(node) => (
                node.force_n,
                node.moment_nm,
                Some(self.node_pose(node, y, true)),
            ),
            None => (Vector3::zeros(), Vector3::zeros(), None),
        };
        let w = pose.map_or(Wrench::zero(), |p| self.loads.wrench(&p, self.alpha));
        let force = (self.load.force_n + dead_f) * self.alpha + w.force_n;
        let moment = (self.load.moment_nm + dead_m) * self.alpha + w.moment_nm;
        let stack = |f: Vector3<T>, m: Vector3<T>| crate::scalar::stacked(&(f * length), &m);
        for ((e, t), seed) in d.iter_mut().zip(tangents).zip(seeds) {
            let dw = pose.map_or(Wrench::zero(), |p| {
                self.loads.wrench_change(&p, self.alpha, &Self::change(t))
            });
            *e = stack(t.n - dw.force_n - seed, t.m - dw.moment_nm);
        }
        stack(y.n - force, y.m - moment)
    }

    fn pose(&self, y: &State<T, A>) -> Pose<T> {
        Pose {
            position_m: y.p,
            position_lo_m: y.p_lo,
            rotation: y.att.matrix(),
        }
    }

    fn tangent_pose(&self, _y: &State<T, A>, t: &Tangent<T>) -> (Vector3<T>, Vector3<T>) {
        (t.p, t.th)
    }

    fn shape_point(&self, s: T, y: &State<T, A>, f: &Field<'a, T>) -> ShapePoint<T> {
        let rotation = y.att.matrix();
        ShapePoint {
            s_m: s,
            position_m: y.p + y.p_lo,
            rotation,
            strain_per_m: f.comp.c_inv.component_mul(&rotation.tr_mul(&y.m)),
        }
    }

    fn finite(&self, y: &State<T, A>, tangents: &[Tangent<T>]) -> bool {
        [y.p, y.n, y.m].iter().all(crate::scalar::all_finite)
            && crate::scalar::all_finite(&y.att.matrix())
            && tangents.iter().all(Linear::is_finite)
    }

    fn has_stability_test(&self) -> bool {
        false
    }

    fn conservative(&self) -> bool {
        true
    }

    fn track(&self) {}

    fn crosses(
        &self,
        _track: &mut (),
        _y: &State<T, A>,
        _tangents: &[Tangent<T>],
        _f: &Field<'a, T>,
        _step_m: T,
    ) -> bool {
        false
    }

    fn jacobi_rotation(&self, _d_rotation: &Vector3<T>) -> SVector<T, 6> {
        SVector::zeros()
    }

    fn residual_size(&self, r: &SVector<T, 6>) -> T {
        r.norm() / self.model.moment_scale_nm()
    }

    /// The base moment's rotation `|m(0)| L / E I` only: an axial force (a tendon's compression)
    /// turns nothing, and must not loosen the tolerance.
    fn rotation_rad(&self, x: &SVector<T, 6>) -> T {
        x.fixed_rows::<3>(3).norm() * self.model.length_m()
    }
}
