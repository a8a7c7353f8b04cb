//! The planar reduction's equations: when every load lies in one plane through the base tangent and
//! the section bends freely about the plane's normal, the rod stays in that plane, and the 3D statics
//! reduce to position `(x, y)`, the direction's half-turn pair `q` and one curvature `k`:
//!
//! `r' = v_t t + v_n t_perp`, `q' = (k / 2) q_perp`, `E I k' = -(r' x n)_z`,
//! `v_t = 1 + n.t / E A`, `v_n = n.t_perp / G A` (or `1, 0` for a Kirchhoff rod),
//!
//! with `t = (q_x^2 - q_y^2, 2 q_x q_y) / |q|^2 = (cos phi, sin phi)`, `t_perp = (-t_y, t_x)`: five
//! states instead of the 3D rod's ten (quaternion) to fifteen (rotation matrix), one shooting unknown
//! `k(0)`. `q` is the 3D quaternion's part in the plane, stepped and renormalised as the quaternion
//! is (`kinematics.rs`), so every RK4 stage here is the 3D quaternion sweep's stage restricted to the
//! plane: the same discretisation, and the same answer to rounding on any grid (MODEL.md §3.8).
//! Cable holes rotate with the frame about the plane's normal, so cable lengths and the 3D shape
//! follow exactly.
//!
//! Linearised (a tangent `(dr, dtheta, dk)`, `dtheta` the turn, `dt = t_perp dtheta`):
//! `dr' = t_perp (v_t dtheta + dv_n) + t (dv_t - v_n dtheta)`, `dtheta' = dk`,
//! `E I dk' = -(dr' x n)_z`, with `dv_t = (n.t_perp) dtheta / E A`, `dv_n = -(n.t) dtheta / G A`.
//! The in-plane Jacobi field is the turn `dtheta` per unit `dk(0)`.

use nalgebra::{Matrix3, SVector, Vector2, Vector3};

use super::dead_load::compensated_add;
use super::guess::base_strain;
use super::{Family, Linear, Pose, RodOde};
use crate::Scalar;
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::{Grid, Model};
use crate::plan::{Interval, Node};
use crate::rod::StrainModel;
use crate::shape::ShapePoint;

/// The plane a scene stays in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane<T> {
    /// The base tangent (first in-plane axis), global.
    pub e1: Vector3<T>,
    /// The second in-plane axis, `normal x e1`, global.
    pub e2: Vector3<T>,
    /// The plane's unit normal, global.
    pub normal: Vector3<T>,
}

/// One section in the plane: bending stiffness about the normal (N m^2), `1 / G A`, `1 / E A` (1/N).
pub(crate) type PlanarSection<T> = (T, T, T);

/// The planar equations of a model under an in-plane load.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlanarRod<'a, T: Scalar, A: Attitude<T>, const NODES: usize> {
    model: &'a Model<T, A, NODES>,
    plane: Plane<T>,
    sections: &'a [PlanarSection<T>],
    load: TipLoad<T>,
    alpha: T,
    kirchhoff: bool,
    /// The normal in the base's local frame (the body axis the plane turns about).
    local_normal: Vector3<T>,
    /// `[e1 e2 n]^T R0`: the frame is `[e1 c + e2 s, e2 c - e1 s, n]` times this.
    basis: Matrix3<T>,
    /// The smallest bending stiffness about the normal, N m^2.
    ei_ref: T,
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> PlanarRod<'a, T, A, NODES> {
    /// The planar equations of `model` in `plane` (sections as in [`PlanarSection`]) under `load`.
    pub(crate) fn new(
        model: &'a Model<T, A, NODES>,
        plane: Plane<T>,
        sections: &'a [PlanarSection<T>],
        load: &TipLoad<T>,
        alpha: T,
    ) -> Self {
        let base = model.rod().base_orientation;
        Self {
            model,
            plane,
            sections,
            load: *load,
            alpha,
            kirchhoff: model.rod().strain_model == StrainModel::Kirchhoff,
            local_normal: base.tr_mul(&plane.normal),
            basis: Matrix3::from_rows(&[
                plane.e1.transpose(),
                plane.e2.transpose(),
                plane.normal.transpose(),
            ]) * base,
            ei_ref: sections
                .iter()
                .fold(T::max_value().unwrap_or_else(T::one), |m, s| m.min(s.0)),
        }
    }

    /// The normal in the base's local frame: the base strain of an in-plane equilibrium is this
    /// times `k(0)`.
    pub(crate) fn local_normal(&self) -> Vector3<T> {
        self.local_normal
    }

    /// The model.
    pub(super) fn model(&self) -> &'a Model<T, A, NODES> {
        self.model
    }

    /// The in-plane internal force at `s` on an interval with coefficients `f`, and the direction
    /// of state `y`.
    #[inline]
    pub(super) fn force_and_direction(
        &self,
        f: &Field<T>,
        s: T,
        y: &State<T>,
    ) -> (Vector2<T>, Vector2<T>) {
        (f.n_end + f.g_lambda * (f.s1 - s), direction(&y.q))
    }

    fn project(&self, v: &Vector3<T>) -> Vector2<T> {
        Vector2::new(v.dot(&self.plane.e1), v.dot(&self.plane.e2))
    }

    fn in_space(&self, r: &Vector2<T>) -> Vector3<T> {
        self.plane.e1 * r.x + self.plane.e2 * r.y
    }

    /// The 3D frame for a planar direction `t`: the base frame turned about the normal.
    fn frame(&self, t: &Vector2<T>) -> Matrix3<T> {
        let (e1, e2, n) = (self.plane.e1, self.plane.e2, self.plane.normal);
        Matrix3::from_columns(&[e1 * t.x + e2 * t.y, e2 * t.x - e1 * t.y, n]) * self.basis
    }
}

#[inline]
fn perp<T: Scalar>(v: &Vector2<T>) -> Vector2<T> {
    Vector2::new(-v.y, v.x)
}

#[inline]
fn cross2<T: Scalar>(a: &Vector2<T>, b: &Vector2<T>) -> T {
    a.x * b.y - a.y * b.x
}

/// The direction `t = (cos phi, sin phi)` of the half-turn pair `q = |q| (cos phi/2, sin phi/2)`,
/// exactly the 3D frame of the quaternion `q0 (q.x, q.y n)` (its `matrix` normalises as this does).
#[inline]
fn direction<T: Scalar>(q: &Vector2<T>) -> Vector2<T> {
    let s = T::lit(2.0) / q.norm_squared();
    Vector2::new(T::one() - q.y * q.y * s, q.x * q.y * s)
}

/// The planar state: position relative to the base (high and low parts), the direction's half-turn
/// pair `q` (the quaternion's part in the plane, so that a step turns the frame exactly as the 3D
/// quaternion sweep's step does), curvature.
#[derive(Clone, Copy, Debug)]
pub(crate) struct State<T: Scalar> {
    r: Vector2<T>,
    r_lo: Vector2<T>,
    q: Vector2<T>,
    pub(super) k: T,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Rates<T: Scalar> {
    r: Vector2<T>,
    q: Vector2<T>,
    k: T,
}

/// A tangent `(dr, dtheta, dk)`: `dtheta` the turn of the direction, `dt = t_perp dtheta`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tangent<T: Scalar> {
    r: Vector2<T>,
    th: T,
    k: T,
}

impl<T: Scalar> Linear<T> for Tangent<T> {
    #[inline]
    fn zero() -> Self {
        Self {
            r: Vector2::zeros(),
            th: T::zero(),
            k: T::zero(),
        }
    }

    #[inline]
    fn axpy(&self, k: &Self, h: T) -> Self {
        Self {
            r: self.r + k.r * h,
            th: self.th + k.th * h,
            k: self.k + k.k * h,
        }
    }

    #[inline]
    fn rk4(&self, k: &[Self; 4], h: T) -> Self {
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let [k1, k2, k3, k4] = k;
        Self {
            r: self.r + (k1.r + k4.r) * w1 + (k2.r + k3.r) * w2,
            th: self.th + (k1.th + k4.th) * w1 + (k2.th + k3.th) * w2,
            k: self.k + (k1.k + k4.k) * w1 + (k2.k + k3.k) * w2,
        }
    }

    fn is_finite(&self) -> bool {
        self.r.iter().all(|x| x.is_finite()) && self.th.is_finite() && self.k.is_finite()
    }
}

/// What a tangent's rate needs from one stage.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stage<T: Scalar> {
    pub(super) t: Vector2<T>,
    pub(super) n: Vector2<T>,
    pub(super) vt: T,
    pub(super) vn: T,
}

impl<T: Scalar> Stage<T> {
    /// The in-plane normal of the direction, `t_perp`.
    #[inline]
    pub(super) fn t_perp(&self) -> Vector2<T> {
        perp(&self.t)
    }
}

/// One interval's coefficients: bending, shear and axial compliance, and the force field
/// `n(s) = n_end + g_lambda (s1 - s)`.
#[derive(Debug)]
pub(crate) struct Field<T: Scalar> {
    ei: T,
    ga_inv: T,
    ea_inv: T,
    n_end: Vector2<T>,
    g_lambda: Vector2<T>,
    s1: T,
    kirchhoff: bool,
}

impl<T: Scalar> Field<T> {
    /// Whether the rod is Kirchhoff's (inextensible and unshearable).
    #[inline]
    pub(super) fn kirchhoff(&self) -> bool {
        self.kirchhoff
    }

    /// The bending stiffness about the plane's normal, N m^2.
    #[inline]
    pub(super) fn ei(&self) -> T {
        self.ei
    }
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> RodOde<T, 1>
    for PlanarRod<'a, T, A, NODES>
{
    type State = State<T>;
    type Rate = Rates<T>;
    type Stage = Stage<T>;
    type Tangent = Tangent<T>;
    type Seed = ();
    type Field = Field<T>;
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

    /// The 3D small-deflection base strain about the normal.
    fn guess(&self) -> SVector<T, 1> {
        let u0 = base_strain(self.model, &self.load, self.alpha, false);
        SVector::<T, 1>::new(u0.dot(&self.local_normal))
    }

    /// The bent rod's base strain about the normal (`guess.rs`).
    fn cold_guess(&self) -> SVector<T, 1> {
        let u0 = base_strain(self.model, &self.load, self.alpha, true);
        SVector::<T, 1>::new(u0.dot(&self.local_normal))
    }

    fn start(&self, x: &SVector<T, 1>) -> State<T> {
        State {
            r: Vector2::zeros(),
            r_lo: Vector2::zeros(),
            q: Vector2::new(T::one(), T::zero()),
            k: x[0],
        }
    }

    /// `k(0)`'s tangent starts as `dk = 1`. The reduction carries no tip-force tangents.
    fn seed(&self, family: Family, _j: usize) -> (Tangent<T>, ()) {
        match family {
            Family::Unknown => (
                Tangent {
                    k: T::one(),
                    ..Tangent::zero()
                },
                (),
            ),
            Family::TipForce | Family::Tension => (Tangent::zero(), ()),
        }
    }

    fn no_seed(&self) {}

    fn blank_stage(&self) -> Stage<T> {
        Stage {
            t: Vector2::zeros(),
            n: Vector2::zeros(),
            vt: T::zero(),
            vn: T::zero(),
        }
    }

    #[inline]
    fn stage_bending_load(&self, f: &Field<T>, stage: &Stage<T>) -> T {
        super::bending_load(&stage.n, &stage.t, T::one() / (f.ei * f.ei))
    }

    #[inline]
    fn bending_load(&self, f: &Field<T>, s: T, y: &State<T>) -> T {
        let (n, t) = self.force_and_direction(f, s, y);
        super::bending_load(&n, &t, T::one() / (f.ei * f.ei))
    }

    fn field(&self, interval: &Interval<T>) -> Option<Field<T>> {
        let &(ei, ga_inv, ea_inv) = self.sections.get(usize::from(interval.section))?;
        let tip_force = self.project(&self.load.force_n);
        let g = self.project(&self.model.rod().gravity_m_s2);
        Some(Field {
            ei,
            ga_inv,
            ea_inv,
            n_end: (tip_force + self.project(&interval.distal_force_n)) * self.alpha,
            g_lambda: g * (interval.line_density_kg_per_m * self.alpha),
            s1: interval.s1_m,
            kirchhoff: self.kirchhoff,
        })
    }

    #[inline]
    fn rate(&self, f: &Field<T>, s: T, y: &State<T>, record: Option<&mut Stage<T>>) -> Rates<T> {
        let n = f.n_end + f.g_lambda * (f.s1 - s);
        let t = direction(&y.q);
        let np = perp(&t);
        let (vt, vn) = if f.kirchhoff {
            (T::one(), T::zero())
        } else {
            (T::one() + n.dot(&t) * f.ea_inv, n.dot(&np) * f.ga_inv)
        };
        let r = t * vt + np * vn;
        if let Some(stage) = record {
            *stage = Stage { t, n, vt, vn };
        }
        Rates {
            r,
            q: perp(&y.q) * (y.k * T::lit(0.5)),
            k: -cross2(&r, &n) / f.ei,
        }
    }

    #[inline]
    fn advance(y: &State<T>, k: &Rates<T>, h: T) -> State<T> {
        State {
            r: y.r + k.r * h,
            r_lo: y.r_lo,
            q: y.q + k.q * h,
            k: y.k + k.k * h,
        }
    }

    #[inline]
    fn combine(y: &State<T>, k: [&Rates<T>; 4], h: T) -> State<T> {
        let [k1, k2, k3, k4] = k;
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let (r, lo) = compensated_add(&y.r, &((k1.r + k4.r) * w1 + (k2.r + k3.r) * w2));
        State {
            r,
            r_lo: y.r_lo + lo,
            q: y.q + (k1.q + k4.q) * w1 + (k2.q + k3.q) * w2,
            k: y.k + (k1.k + k4.k) * w1 + (k2.k + k3.k) * w2,
        }
    }

    #[inline]
    fn tangent_rate(&self, f: &Field<T>, st: &Stage<T>, _: &(), t: &Tangent<T>) -> Tangent<T> {
        // dt = t_perp dtheta, dt_perp = -t dtheta.
        let np = perp(&st.t);
        let (dvt, dvn) = if f.kirchhoff {
            (T::zero(), T::zero())
        } else {
            (
                st.n.dot(&np) * t.th * f.ea_inv,
                -st.n.dot(&st.t) * t.th * f.ga_inv,
            )
        };
        let dr = np * (st.vt * t.th + dvn) + st.t * (dvt - st.vn * t.th);
        Tangent {
            r: dr,
            th: t.k,
            k: -cross2(&dr, &st.n) / f.ei,
        }
    }

    /// Keeps the half-turn pair a unit vector, as the 3D sweep its quaternion.
    #[inline]
    fn after_step(&self, y: &mut State<T>, _tangents: &mut [Tangent<T>]) {
        let norm = y.q.norm_squared().sqrt_hot();
        y.q /= norm;
    }

    /// A change of stiffness or a point moment about the normal: `k+ = (E I- k- - tau) / E I+`.
    fn node(
        &self,
        node: &Node<T>,
        proximal: &Field<T>,
        distal: &Field<T>,
        y: &mut State<T>,
        tangents: &mut [Tangent<T>],
    ) {
        let tau = node.moment_nm.dot(&self.plane.normal) * self.alpha;
        if proximal.ei != distal.ei || tau != T::zero() {
            y.k = (proximal.ei * y.k - tau) / distal.ei;
            for t in tangents.iter_mut() {
                t.k = proximal.ei * t.k / distal.ei;
            }
        }
    }

    /// `E I k(L) - tau`, `tau` the tip moment and the tip node's point moments about the normal.
    fn tip(
        &self,
        node: Option<&Node<T>>,
        last: &Field<T>,
        y: &State<T>,
        tangents: &[Tangent<T>],
        _: &[()],
        d: &mut [SVector<T, 1>],
    ) -> SVector<T, 1> {
        let normal = &self.plane.normal;
        let tip_moment =
            node.map_or(T::zero(), |n| n.moment_nm.dot(normal)) + self.load.moment_nm.dot(normal);
        for (e, t) in d.iter_mut().zip(tangents) {
            *e = SVector::<T, 1>::new(last.ei * t.k);
        }
        SVector::<T, 1>::new(last.ei * y.k - tip_moment * self.alpha)
    }

    fn pose(&self, y: &State<T>) -> Pose<T> {
        Pose {
            position_m: self.model.rod().base_position_m + self.in_space(&y.r),
            position_lo_m: self.in_space(&y.r_lo),
            rotation: self.frame(&direction(&y.q)),
        }
    }

    fn tangent_pose(&self, _: &State<T>, t: &Tangent<T>) -> (Vector3<T>, Vector3<T>) {
        (self.in_space(&t.r), self.local_normal * t.th)
    }

    fn shape_point(&self, s: T, y: &State<T>, _: &Field<T>) -> ShapePoint<T> {
        let frame = self.frame(&direction(&y.q));
        let pose = self.pose(y);
        ShapePoint {
            s_m: s,
            position_m: pose.position_m + pose.position_lo_m,
            rotation: frame,
            strain_per_m: frame.tr_mul(&self.plane.normal) * y.k,
        }
    }

    fn finite(&self, y: &State<T>, tangents: &[Tangent<T>]) -> bool {
        y.r.iter().chain(y.q.iter()).all(|x| x.is_finite())
            && y.k.is_finite()
            && tangents.iter().all(Linear::is_finite)
    }

    fn has_stability_test(&self) -> bool {
        true
    }

    fn conservative(&self) -> bool {
        self.model.conservative(&self.load.moment_nm)
    }

    fn track(&self) {}

    /// The in-plane Jacobi field: the turn of the direction per unit `dk(0)` must stay positive.
    fn crosses(
        &self,
        _: &mut (),
        _: &State<T>,
        tangents: &[Tangent<T>],
        _: &Field<T>,
        _: T,
    ) -> bool {
        tangents.first().is_some_and(|t| t.th <= T::zero())
    }

    fn jacobi_rotation(&self, d_rotation: &Vector3<T>) -> SVector<T, 1> {
        SVector::<T, 1>::new(d_rotation.dot(&self.local_normal))
    }

    fn residual_size(&self, r: &SVector<T, 1>) -> T {
        r[0].abs() / (self.ei_ref / self.model.length_m())
    }
}
