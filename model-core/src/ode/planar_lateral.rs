//! Stability out of the plane of a planar equilibrium: the two Jacobi fields that leave the plane,
//! integrated along the planar state (`planar.rs`) instead of the 3D sweep's three.
//!
//! In the section's frame `(n, p, e3)`, `n` the plane's normal, `p = e3 x n` the in-plane
//! transverse axis, a planar equilibrium has `u = (k, 0, 0)`, `n_l = (0, N_p, N_t)` and
//! `v = (0, V_p, V_t)`. The 3D Jacobi equations (`dead_load.rs`: `dtheta' = du - u x dtheta`,
//! `dn_l = n_l x dtheta`, `dv = D^-1 dn_l`, `C du' = -(du x C u + u x C du + dv x n_l + v x dn_l)`)
//! split there: a turn about `n` with a bend about `n` stays in the plane (the planar reduction's own
//! tangent), and a turn `(a_p, a_t)` about `p` and `e3` with a strain `(b_p, b_t)` stays out of it,
//! its force change `dn_l = (N_p a_t - N_t a_p) n` along the normal:
//!
//! `a_p' = b_p + k a_t`, `a_t' = b_t - k a_p`,
//! `C_p b_p' = -(C_n - C_t) k b_t + dv_n N_t - V_t dn_n`,
//! `C_t b_t' = -(C_p - C_n) k b_p - dv_n N_p + V_p dn_n`, with `dv_n = dn_n / G A_n`
//! (zero for a Kirchhoff rod).
//!
//! So `H = d theta / d u(0)` and `M = C du / d u(0)` are block diagonal, in-plane `1 x 1` and
//! out-of-plane `2 x 2`, and Jacobi's conditions (`stability.rs`) hold for the 3D fields exactly
//! when they hold for both blocks: `det H` is the blocks' product, the Riccati matrix is their
//! direct sum, its eigenvalues theirs. The in-plane block is the planar solve's own test; this file
//! gives the out-of-plane one, the 3D test's conjugate-point level `c` (the section's softest
//! stiffness) included. Unknowns: `du(0)` along `p` and along `e3` (`K = 2`); the state is the
//! planar one at the answer's `k(0)`, stepped as the planar sweep steps it.

use nalgebra::{Matrix2, Matrix3, SVector, Vector2, Vector3};

use super::planar::{Field as PlanarField, PlanarRod, Rates, Stage as PlanarStage, State};
use super::{Family, Linear, Pose, RodOde};
use crate::Scalar;
use crate::kinematics::Attitude;
use crate::model::Grid;
use crate::plan::{Interval, Node};
use crate::shape::ShapePoint;
use crate::stability::ConjugateTrack;

/// The out-of-plane Jacobi equations along the planar equilibrium with base curvature `k0`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LateralRod<'a, T: Scalar, A: Attitude<T>, const NODES: usize> {
    planar: PlanarRod<'a, T, A, NODES>,
    k0: T,
    /// The in-plane transverse axis `p = e3 x n` in the section's frame.
    local_p: Vector3<T>,
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> LateralRod<'a, T, A, NODES> {
    /// The out-of-plane fields of `planar`'s equilibrium whose base curvature is `k0`.
    pub(crate) fn new(planar: PlanarRod<'a, T, A, NODES>, k0: T) -> Self {
        let n = planar.local_normal();
        Self {
            planar,
            k0,
            local_p: Vector3::new(-n.y, n.x, T::zero()),
        }
    }
}

/// An out-of-plane tangent: the turn `a = (a_p, a_t)` about `p` and `e3`, and the strain change
/// `b = (b_p, b_t)` along them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tangent<T: Scalar> {
    a: Vector2<T>,
    b: Vector2<T>,
}

impl<T: Scalar> Linear<T> for Tangent<T> {
    #[inline]
    fn zero() -> Self {
        Self {
            a: Vector2::zeros(),
            b: Vector2::zeros(),
        }
    }

    #[inline]
    fn axpy(&self, k: &Self, h: T) -> Self {
        Self {
            a: self.a + k.a * h,
            b: self.b + k.b * h,
        }
    }

    #[inline]
    fn rk4(&self, k: &[Self; 4], h: T) -> Self {
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let [k1, k2, k3, k4] = k;
        Self {
            a: self.a + (k1.a + k4.a) * w1 + (k2.a + k3.a) * w2,
            b: self.b + (k1.b + k4.b) * w1 + (k2.b + k3.b) * w2,
        }
    }

    fn is_finite(&self) -> bool {
        self.a.iter().chain(self.b.iter()).all(|x| x.is_finite())
    }
}

/// What a tangent's rate needs from one stage: the planar stage and its curvature.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stage<T: Scalar> {
    planar: PlanarStage<T>,
    k: T,
}

/// One interval's coefficients: the planar ones, and the stiffness about the normal, about `p` and
/// in torsion, the shear compliance along the normal, the softest stiffness (the watch's level),
/// and `(1 / E I)^2` about the softer bending axis (the grid's resolution, as the 3D sweep has it).
#[derive(Debug)]
pub(crate) struct Field<T: Scalar> {
    planar: PlanarField<T>,
    c_n: T,
    c_p: T,
    c_t: T,
    shear_n_inv: T,
    c_min: T,
    soft_compliance_squared: T,
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> RodOde<T, 2>
    for LateralRod<'a, T, A, NODES>
{
    type State = State<T>;
    type Rate = Rates<T>;
    type Stage = Stage<T>;
    type Tangent = Tangent<T>;
    type Seed = ();
    type Field = Field<T>;
    type Track = ConjugateTrack<T>;

    /// The plan without cables: nothing here reads them.
    fn grid(&self) -> Grid<'_, T> {
        Grid {
            cable_offsets: &[],
            ..self.planar.grid()
        }
    }

    fn length_m(&self) -> T {
        self.planar.length_m()
    }

    fn at_scale(&self, load_scale: T) -> Self {
        Self {
            planar: self.planar.at_scale(load_scale),
            ..*self
        }
    }

    /// The fields start from the equilibrium itself: no unknown moves the state.
    fn guess(&self) -> SVector<T, 2> {
        SVector::zeros()
    }

    fn start(&self, _x: &SVector<T, 2>) -> State<T> {
        self.planar.start(&SVector::<T, 1>::new(self.k0))
    }

    /// `du(0)` along `p` (`j = 0`) or along `e3` (`j = 1`).
    fn seed(&self, family: Family, j: usize) -> (Tangent<T>, ()) {
        let b = match (family, j) {
            (Family::Unknown, 0) => Vector2::new(T::one(), T::zero()),
            (Family::Unknown, _) => Vector2::new(T::zero(), T::one()),
            (Family::TipForce | Family::Tension, _) => Vector2::zeros(),
        };
        (
            Tangent {
                a: Vector2::zeros(),
                b,
            },
            (),
        )
    }

    fn no_seed(&self) {}

    fn blank_stage(&self) -> Stage<T> {
        Stage {
            planar: self.planar.blank_stage(),
            k: T::zero(),
        }
    }

    fn field(&self, interval: &Interval<T>) -> Option<Field<T>> {
        let planar = self.planar.field(interval)?;
        // The section's stiffness and compliances as the 3D sweep reads them.
        let comp = self.planar.model().compliance(interval.section)?;
        let (n, p) = (self.planar.local_normal(), self.local_p);
        let (c, d_inv) = (comp.c, comp.d_inv);
        let soft = comp.max_bending_compliance();
        Some(Field {
            c_n: planar.ei(),
            c_p: c.x * p.x * p.x + c.y * p.y * p.y,
            c_t: c.z,
            shear_n_inv: d_inv.x * n.x * n.x + d_inv.y * n.y * n.y,
            c_min: c.min(),
            soft_compliance_squared: soft * soft,
            planar,
        })
    }

    /// The planar force against the softer bending axis: a bend out of the plane may be softer
    /// than the one in it, and the grid must resolve it as the 3D sweep's does.
    #[inline]
    fn bending_load(&self, f: &Field<T>, s: T, y: &State<T>) -> T {
        let (n, t) = self.planar.force_and_direction(&f.planar, s, y);
        super::bending_load(&n, &t, f.soft_compliance_squared)
    }

    #[inline]
    fn stage_bending_load(&self, f: &Field<T>, stage: &Stage<T>) -> T {
        super::bending_load(&stage.planar.n, &stage.planar.t, f.soft_compliance_squared)
    }

    #[inline]
    fn rate(&self, f: &Field<T>, s: T, y: &State<T>, record: Option<&mut Stage<T>>) -> Rates<T> {
        match record {
            Some(stage) => {
                stage.k = y.k;
                self.planar.rate(&f.planar, s, y, Some(&mut stage.planar))
            }
            None => self.planar.rate(&f.planar, s, y, None),
        }
    }

    #[inline]
    fn advance(y: &State<T>, k: &Rates<T>, h: T) -> State<T> {
        <PlanarRod<'a, T, A, NODES> as RodOde<T, 1>>::advance(y, k, h)
    }

    #[inline]
    fn combine(y: &State<T>, k: [&Rates<T>; 4], h: T) -> State<T> {
        <PlanarRod<'a, T, A, NODES> as RodOde<T, 1>>::combine(y, k, h)
    }

    #[inline]
    fn tangent_rate(&self, f: &Field<T>, st: &Stage<T>, _: &(), t: &Tangent<T>) -> Tangent<T> {
        let ps = &st.planar;
        // The force and the strain in the section's frame: `N_p = -n.t_perp`, `N_t = n.t`.
        let (n_p, n_t) = (-ps.n.dot(&ps.t_perp()), ps.n.dot(&ps.t));
        let (v_p, v_t) = (-ps.vn, ps.vt);
        let k = st.k;
        let (a_p, a_t) = (t.a.x, t.a.y);
        let (b_p, b_t) = (t.b.x, t.b.y);
        let dn = n_p * a_t - n_t * a_p;
        let dv = if f.planar.kirchhoff() {
            T::zero()
        } else {
            dn * f.shear_n_inv
        };
        Tangent {
            a: Vector2::new(b_p + k * a_t, b_t - k * a_p),
            b: Vector2::new(
                (-(f.c_n - f.c_t) * k * b_t + dv * n_t - v_t * dn) / f.c_p,
                (-(f.c_p - f.c_n) * k * b_p - dv * n_p + v_p * dn) / f.c_t,
            ),
        }
    }

    #[inline]
    fn after_step(&self, y: &mut State<T>, _tangents: &mut [Tangent<T>]) {
        self.planar.after_step(y, &mut []);
    }

    /// The state's jump is the planar one; the moment `C du` is continuous across a change of
    /// section. (A point moment would make it jump with the turn; it also makes the loads
    /// non-conservative, and the verdict is then that, whatever the fields.)
    fn node(
        &self,
        node: &Node<T>,
        proximal: &Field<T>,
        distal: &Field<T>,
        y: &mut State<T>,
        tangents: &mut [Tangent<T>],
    ) {
        self.planar
            .node(node, &proximal.planar, &distal.planar, y, &mut []);
        if proximal.c_p != distal.c_p || proximal.c_t != distal.c_t {
            for t in tangents.iter_mut() {
                t.b.x = proximal.c_p * t.b.x / distal.c_p;
                t.b.y = proximal.c_t * t.b.y / distal.c_t;
            }
        }
    }

    /// No residual (the tip moment has no part out of the plane); `M(L) = C du(L)` per field.
    fn tip(
        &self,
        _node: Option<&Node<T>>,
        last: &Field<T>,
        _y: &State<T>,
        tangents: &[Tangent<T>],
        _: &[()],
        d: &mut [SVector<T, 2>],
    ) -> SVector<T, 2> {
        for (e, t) in d.iter_mut().zip(tangents) {
            *e = SVector::<T, 2>::new(last.c_p * t.b.x, last.c_t * t.b.y);
        }
        SVector::zeros()
    }

    fn pose(&self, y: &State<T>) -> Pose<T> {
        self.planar.pose(y)
    }

    /// No move of the backbone (out of the plane it is the field's, not asked for); the turn in the
    /// section's frame.
    fn tangent_pose(&self, _: &State<T>, t: &Tangent<T>) -> (Vector3<T>, Vector3<T>) {
        (
            Vector3::zeros(),
            self.local_p * t.a.x + Vector3::z() * t.a.y,
        )
    }

    fn shape_point(&self, s: T, y: &State<T>, f: &Field<T>) -> ShapePoint<T> {
        self.planar.shape_point(s, y, &f.planar)
    }

    fn finite(&self, y: &State<T>, tangents: &[Tangent<T>]) -> bool {
        self.planar.finite(y, &[]) && tangents.iter().all(Linear::is_finite)
    }

    fn has_stability_test(&self) -> bool {
        true
    }

    fn conservative(&self) -> bool {
        self.planar.conservative()
    }

    fn track(&self) -> ConjugateTrack<T> {
        ConjugateTrack::new()
    }

    /// The out-of-plane fields against the 3D watch, as the `2 x 2` block of the 3D fields (the
    /// in-plane block a unit turn with no moment: its Riccati entry, zero, is never below `-c`).
    fn crosses(
        &self,
        track: &mut ConjugateTrack<T>,
        _: &State<T>,
        tangents: &[Tangent<T>],
        f: &Field<T>,
        step_m: T,
    ) -> bool {
        let [first, second, ..] = tangents else {
            return false;
        };
        let h = Matrix2::from_columns(&[first.a, second.a]);
        let m = Matrix2::from_columns(&[
            Vector2::new(f.c_p * first.b.x, f.c_t * first.b.y),
            Vector2::new(f.c_p * second.b.x, f.c_t * second.b.y),
        ]);
        let mut h3 = Matrix3::identity();
        let mut m3 = Matrix3::zeros();
        h3.fixed_view_mut::<2, 2>(1, 1).copy_from(&h);
        m3.fixed_view_mut::<2, 2>(1, 1).copy_from(&m);
        track.crosses(&h3, &m3, f.c_min, step_m)
    }

    fn jacobi_rotation(&self, d_rotation: &Vector3<T>) -> SVector<T, 2> {
        SVector::<T, 2>::new(d_rotation.dot(&self.local_p), d_rotation.z)
    }

    fn residual_size(&self, r: &SVector<T, 2>) -> T {
        self.planar.residual_size(&SVector::<T, 1>::new(r.norm()))
    }
}
