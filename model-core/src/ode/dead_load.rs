//! The 3D rod under dead loads, the fast path: the internal force is known in closed form before the
//! sweep (`n(s) = F_tip + N_k + g lambda_k (s_{k+1} - s)` on interval `k`, summed once in `plan.rs`),
//! so the state is `(r, R, u)` and the unknowns are the base strain `u(0)`, 3 of them.
//!
//! `r' = R v`, `R' = R hat(u)` (`kinematics.rs`), `v = D^-1 R^T n + e3` and
//! `u' = -C^-1 (u x C u + v x R^T n)` (`constitutive.rs`, thesis eqs. 2.9-2.13); the strain jumps at a
//! section change or a point moment (`transitions.rs`); the tip condition is `C u(L) = R(L)^T tau`.
//!
//! Linearised, with `n_l = R^T n` and a tangent `(dr, dtheta, du)`, `dR = R hat(dtheta)`, whose seed
//! is a constant change `dn` of the internal force (a tip-force tangent; zero for the base strain's):
//! `dn_l = n_l x dtheta + R^T dn`, `dv = D^-1 dn_l`, `dr' = R (dtheta x v + dv)`,
//! `dtheta' = du - u x dtheta`, `du' = -C^-1 (du x C u + u x C du + dv x n_l + v x dn_l)`.

use nalgebra::{Matrix3, SVector, Vector3};

use super::guess::base_strain;
use super::{Family, Linear, Pose, RodOde, unit};
use crate::Scalar;
use crate::constitutive::Compliance;
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::{Grid, Model};
use crate::plan::{Interval, Node};
use crate::rod::StrainModel;
use crate::shape::ShapePoint;
use crate::stability::ConjugateTrack;
use crate::transitions::{strain_after, strain_tangent_after};

/// The 3D rod under the scene's dead loads and a tip load.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DeadLoadRod<'a, T: Scalar, A: Attitude<T>, const NODES: usize> {
    model: &'a Model<T, A, NODES>,
    load: TipLoad<T>,
    alpha: T,
    kirchhoff: bool,
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> DeadLoadRod<'a, T, A, NODES> {
    /// The equations of `model` under `load` (plus gravity and point loads), all scaled by `alpha`.
    pub(crate) fn new(model: &'a Model<T, A, NODES>, load: &TipLoad<T>, alpha: T) -> Self {
        Self {
            model,
            load: *load,
            alpha,
            kirchhoff: model.rod().strain_model == StrainModel::Kirchhoff,
        }
    }
}

/// The state: position (high and low parts), frame, bending and torsion strain.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Point<T: Scalar, A> {
    r: Vector3<T>,
    /// The low-order part of the position (compensated summation): the position is `r + r_lo`.
    /// `r` never feeds back into the right-hand side, so this costs a few additions per step and
    /// keeps f32 positions, and the chords between them, free of accumulated rounding.
    r_lo: Vector3<T>,
    att: A,
    u: Vector3<T>,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Rates<T: Scalar, A: Attitude<T>> {
    r: Vector3<T>,
    att: A::Rate,
    u: Vector3<T>,
}

/// A tangent: `(dr, dtheta, du)`, `dR = R hat(dtheta)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tangent<T> {
    r: Vector3<T>,
    th: Vector3<T>,
    u: Vector3<T>,
}

impl<T: Scalar> Linear<T> for Tangent<T> {
    #[inline]
    fn zero() -> Self {
        Self {
            r: Vector3::zeros(),
            th: Vector3::zeros(),
            u: Vector3::zeros(),
        }
    }

    #[inline]
    fn axpy(&self, k: &Self, h: T) -> Self {
        Self {
            r: self.r + k.r * h,
            th: self.th + k.th * h,
            u: self.u + k.u * h,
        }
    }

    #[inline]
    fn rk4(&self, k: &[Self; 4], h: T) -> Self {
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let [k1, k2, k3, k4] = k;
        Self {
            r: self.r + (k1.r + k4.r) * w1 + (k2.r + k3.r) * w2,
            th: self.th + (k1.th + k4.th) * w1 + (k2.th + k3.th) * w2,
            u: self.u + (k1.u + k4.u) * w1 + (k2.u + k3.u) * w2,
        }
    }

    fn is_finite(&self) -> bool {
        crate::scalar::all_finite(&self.r)
            && crate::scalar::all_finite(&self.th)
            && crate::scalar::all_finite(&self.u)
    }
}

/// What a tangent's right-hand side needs from the state at one RK4 stage.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stage<T> {
    m: Matrix3<T>,
    n_local: Vector3<T>,
    v: Vector3<T>,
    u: Vector3<T>,
    cu: Vector3<T>,
}

/// The internal-force field on one interval: `n(s) = n_end + g_lambda (s1 - s)`.
#[derive(Debug)]
pub(crate) struct Field<'a, T> {
    comp: &'a Compliance<T>,
    n_end: Vector3<T>,
    g_lambda: Vector3<T>,
    s1: T,
    kirchhoff: bool,
    /// `(1 / EI)^2` about the softer bending axis, for [`super::bending_load`].
    compliance_squared: T,
}

/// `a + b` rounded, and the rounding error (Neumaier's two-sum, per component).
#[inline]
pub(crate) fn compensated_add<T: Scalar, const N: usize>(
    a: &SVector<T, N>,
    b: &SVector<T, N>,
) -> (SVector<T, N>, SVector<T, N>) {
    let sum = a + b;
    let lo = a.zip_zip_map(b, &sum, |x, y, t| {
        if x.abs() >= y.abs() {
            (x - t) + y
        } else {
            (y - t) + x
        }
    });
    (sum, lo)
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> RodOde<T, 3>
    for DeadLoadRod<'a, T, A, NODES>
{
    type State = Point<T, A>;
    type Rate = Rates<T, A>;
    type Stage = Stage<T>;
    type Tangent = Tangent<T>;
    type Seed = Vector3<T>;
    type Field = Field<'a, T>;
    type Track = ConjugateTrack<T>;

    #[inline]
    fn grid(&self) -> Grid<'_, T> {
        self.model.grid()
    }

    #[inline]
    fn length_m(&self) -> T {
        self.model.length_m()
    }

    fn at_scale(&self, load_scale: T) -> Self {
        Self {
            alpha: load_scale,
            ..*self
        }
    }

    /// The base moment of all loads on the straight rod, `u0 = C^-1 R0^T m(0)`.
    fn guess(&self) -> SVector<T, 3> {
        base_strain(self.model, &self.load, self.alpha, false)
    }

    /// The same with the forces' lever arms of the bent rod (`guess.rs`).
    fn cold_guess(&self) -> SVector<T, 3> {
        base_strain(self.model, &self.load, self.alpha, true)
    }

    #[inline]
    fn start(&self, x: &SVector<T, 3>) -> Point<T, A> {
        Point {
            r: self.model.rod().base_position_m,
            r_lo: Vector3::zeros(),
            att: *self.model.base_attitude(),
            u: *x,
        }
    }

    /// A base-strain tangent starts as `du = e_j`; a tip-force tangent carries `dn = alpha e_j`.
    fn seed(&self, family: Family, j: usize) -> (Tangent<T>, Vector3<T>) {
        match family {
            Family::Unknown => (
                Tangent {
                    u: unit(j),
                    ..Tangent::zero()
                },
                Vector3::zeros(),
            ),
            Family::TipForce => (Tangent::zero(), unit::<T, 3>(j) * self.alpha),
            Family::Tension => (Tangent::zero(), Vector3::zeros()),
        }
    }

    fn no_seed(&self) -> Vector3<T> {
        Vector3::zeros()
    }

    fn blank_stage(&self) -> Stage<T> {
        Stage {
            m: Matrix3::zeros(),
            n_local: Vector3::zeros(),
            v: Vector3::zeros(),
            u: Vector3::zeros(),
            cu: Vector3::zeros(),
        }
    }

    #[inline]
    fn stage_bending_load(&self, f: &Field<'a, T>, stage: &Stage<T>) -> T {
        super::local_bending_load(&stage.n_local, f.compliance_squared)
    }

    #[inline]
    fn bending_load(&self, f: &Field<'a, T>, s: T, p: &Point<T, A>) -> T {
        let n = f.n_end + f.g_lambda * (f.s1 - s);
        let tangent = p.att.matrix().column(2).into_owned();
        super::bending_load(&n, &tangent, f.compliance_squared)
    }

    #[inline]
    fn field(&self, interval: &Interval<T>) -> Option<Field<'a, T>> {
        let model: &'a Model<T, A, NODES> = self.model;
        let comp = model.compliance(interval.section)?;
        let compliance = comp.max_bending_compliance();
        Some(Field {
            comp,
            n_end: (self.load.force_n + interval.distal_force_n) * self.alpha,
            g_lambda: model.rod().gravity_m_s2 * (interval.line_density_kg_per_m * self.alpha),
            s1: interval.s1_m,
            kirchhoff: self.kirchhoff,
            compliance_squared: compliance * compliance,
        })
    }

    #[inline]
    fn rate(
        &self,
        f: &Field<'a, T>,
        s: T,
        p: &Point<T, A>,
        record: Option<&mut Stage<T>>,
    ) -> Rates<T, A> {
        let m = p.att.matrix();
        let n = f.n_end + f.g_lambda * (f.s1 - s);
        let n_local = m.tr_mul(&n);
        let v = f.comp.shear_strain(&n_local, f.kirchhoff);
        let cu = f.comp.c.component_mul(&p.u);
        let rates = Rates {
            r: m * v,
            att: p.att.rate(&m, &p.u),
            u: f.comp.strain_rate(&p.u, &cu, &v, &n_local),
        };
        if let Some(stage) = record {
            *stage = Stage {
                m,
                n_local,
                v,
                u: p.u,
                cu,
            };
        }
        rates
    }

    #[inline]
    fn advance(p: &Point<T, A>, k: &Rates<T, A>, h: T) -> Point<T, A> {
        Point {
            r: p.r + k.r * h,
            r_lo: p.r_lo,
            att: A::stage(&p.att, &k.att, h),
            u: p.u + k.u * h,
        }
    }

    #[inline]
    fn combine(p: &Point<T, A>, k: [&Rates<T, A>; 4], h: T) -> Point<T, A> {
        let [k1, k2, k3, k4] = k;
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let (r, lo) = compensated_add(&p.r, &((k1.r + k4.r) * w1 + (k2.r + k3.r) * w2));
        Point {
            r,
            r_lo: p.r_lo + lo,
            att: A::combine(&p.att, &[k1.att, k2.att, k3.att, k4.att], h),
            u: p.u + (k1.u + k4.u) * w1 + (k2.u + k3.u) * w2,
        }
    }

    #[inline]
    fn tangent_rate(
        &self,
        f: &Field<'a, T>,
        st: &Stage<T>,
        dn: &Vector3<T>,
        t: &Tangent<T>,
    ) -> Tangent<T> {
        let dnl = st.n_local.cross(&t.th) + st.m.tr_mul(dn);
        let dv = if f.kirchhoff {
            Vector3::zeros()
        } else {
            f.comp.d_inv.component_mul(&dnl)
        };
        let cdu = f.comp.c.component_mul(&t.u);
        Tangent {
            r: st.m * (t.th.cross(&st.v) + dv),
            th: t.u - st.u.cross(&t.th),
            u: -f.comp.c_inv.component_mul(
                &(t.u.cross(&st.cu) + st.u.cross(&cdu) + dv.cross(&st.n_local) + st.v.cross(&dnl)),
            ),
        }
    }

    /// A change of stiffness or a point moment makes the strain jump (`transitions.rs`); point forces
    /// are in the distal force already.
    #[inline]
    fn node(
        &self,
        node: &Node<T>,
        proximal: &Field<'a, T>,
        distal: &Field<'a, T>,
        p: &mut Point<T, A>,
        tangents: &mut [Tangent<T>],
    ) {
        let jump = proximal.comp != distal.comp || node.moment_nm != Vector3::zeros();
        if jump {
            let m = p.att.matrix();
            let tau_local = m.tr_mul(&(node.moment_nm * self.alpha));
            for t in tangents.iter_mut() {
                t.u = strain_tangent_after(proximal.comp, distal.comp, &tau_local, &t.th, &t.u);
            }
            p.u = strain_after(proximal.comp, distal.comp, &tau_local, &p.u);
        }
    }

    /// `e = C u(L) - R(L)^T tau` (body frame), `tau` the tip moment plus point moments at the tip;
    /// `de = C du - (R^T tau) x dtheta`.
    fn tip(
        &self,
        node: Option<&Node<T>>,
        last: &Field<'a, T>,
        p: &Point<T, A>,
        tangents: &[Tangent<T>],
        _seeds: &[Vector3<T>],
        d: &mut [SVector<T, 3>],
    ) -> SVector<T, 3> {
        let tip_moment_nm = node.map_or(Vector3::zeros(), |n| n.moment_nm) + self.load.moment_nm;
        let tau_local = p.att.matrix().tr_mul(&(tip_moment_nm * self.alpha));
        for (e, t) in d.iter_mut().zip(tangents) {
            *e = last.comp.c.component_mul(&t.u) - tau_local.cross(&t.th);
        }
        last.comp.c.component_mul(&p.u) - tau_local
    }

    #[inline]
    fn pose(&self, p: &Point<T, A>) -> Pose<T> {
        Pose {
            position_m: p.r,
            position_lo_m: p.r_lo,
            rotation: p.att.matrix(),
        }
    }

    #[inline]
    fn tangent_pose(&self, _p: &Point<T, A>, t: &Tangent<T>) -> (Vector3<T>, Vector3<T>) {
        (t.r, t.th)
    }

    fn shape_point(&self, s: T, p: &Point<T, A>, _f: &Field<'a, T>) -> ShapePoint<T> {
        ShapePoint {
            s_m: s,
            position_m: p.r + p.r_lo,
            rotation: p.att.matrix(),
            strain_per_m: p.u,
        }
    }

    fn finite(&self, p: &Point<T, A>, tangents: &[Tangent<T>]) -> bool {
        crate::scalar::all_finite(&p.r)
            && crate::scalar::all_finite(&p.u)
            && crate::scalar::all_finite(&p.att.matrix())
            && tangents.iter().all(Linear::is_finite)
    }

    fn has_stability_test(&self) -> bool {
        true
    }

    fn conservative(&self) -> bool {
        self.model.conservative(&self.load.moment_nm)
    }

    fn bends_alike_about_both_axes(&self) -> bool {
        self.model.bends_alike_about_both_axes()
    }

    fn track(&self) -> ConjugateTrack<T> {
        ConjugateTrack::new()
    }

    /// The Jacobi fields `H = d theta / d u(0)` and `M = C du / d u(0)` (body frame) against the
    /// watch (`stability.rs`).
    #[inline]
    fn crosses(
        &self,
        track: &mut ConjugateTrack<T>,
        _p: &Point<T, A>,
        tangents: &[Tangent<T>],
        f: &Field<'a, T>,
        step_m: T,
    ) -> bool {
        let [a, b, d, ..] = tangents else {
            return false;
        };
        let h = Matrix3::from_columns(&[a.th, b.th, d.th]);
        let m = Matrix3::from_diagonal(&f.comp.c) * Matrix3::from_columns(&[a.u, b.u, d.u]);
        track.crosses(&h, &m, f.comp.c.min(), step_m)
    }

    #[inline]
    fn jacobi_rotation(&self, d_rotation: &Vector3<T>) -> SVector<T, 3> {
        *d_rotation
    }

    #[inline]
    fn residual_size(&self, e: &SVector<T, 3>) -> T {
        e.norm() / self.model.moment_scale_nm()
    }
}
