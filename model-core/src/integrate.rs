//! One fixed-step sweep from base to tip (thesis eq. 2.13 and the kinematics), with forward
//! sensitivities.
//!
//! The state is `(r, R, u)`; `n(s)` is known in closed form from the plan. Alongside it the sweep can
//! carry `K` tangent directions `(dr, dtheta, du)`, `dR = R hat(dtheta)`, seeded by a change of the
//! base strain `u(0)` and of the tip force. They are integrated with the same RK4 stages, so they are
//! the derivative of the discrete sweep (to the order of the scheme), with no finite-difference
//! cancellation: the Jacobians of the shooting and inverse solves, and the Jacobi fields of the
//! stability test, all come from here.
//!
//! Linearised right-hand side, with `n_l = R^T n`:
//! `dn_l = n_l x dtheta + R^T dn`, `dv = D^-1 dn_l`, `dr' = R (dtheta x v + dv)`,
//! `dtheta' = du - u x dtheta`, `du' = -C^-1 (du x C u + u x C du + dv x n_l + v x dn_l)`.

// Every index below runs over const-sized arrays of the same length (`0..K`, `MAX_CABLES`).
#![allow(clippy::indexing_slicing)]

use core::array;

use nalgebra::{Matrix3, Vector3};

use crate::constitutive::Compliance;
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::plan::{NO_GUIDE, Node};
use crate::rod::StrainModel;
use crate::shape::{ShapePoint, ShapeSink};
use crate::transitions::{strain_after, strain_tangent_after};
use crate::{MAX_CABLES, Scalar};

/// What a sweep needs besides the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Inputs<T> {
    /// Bending/torsion strain at the base, 1/m (body frame): the shooting unknown.
    pub u0: Vector3<T>,
    /// Tip force, N, global.
    pub tip_force_n: Vector3<T>,
    /// Tip moment, N m, global.
    pub tip_moment_nm: Vector3<T>,
    /// Every load (gravity, point loads, tip load) is multiplied by this (load continuation).
    pub load_scale: T,
}

/// A tangent direction: a change of the base strain and of the tip force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Seed<T> {
    pub du0: Vector3<T>,
    pub dforce_n: Vector3<T>,
}

impl<T: Scalar> Seed<T> {
    /// The six unit directions: `u0` components, then tip-force components.
    pub fn all() -> [Self; 6] {
        array::from_fn(|j| {
            let unit = |i: usize| if i == j % 3 { T::one() } else { T::zero() };
            let e = Vector3::new(unit(0), unit(1), unit(2));
            if j < 3 {
                Self {
                    du0: e,
                    dforce_n: Vector3::zeros(),
                }
            } else {
                Self {
                    du0: Vector3::zeros(),
                    dforce_n: e,
                }
            }
        })
    }

    /// The three base-strain directions.
    pub fn base_strain() -> [Self; 3] {
        let all = Self::all();
        [all[0], all[1], all[2]]
    }
}

#[derive(Clone, Copy, Debug)]
struct Tangent<T> {
    r: Vector3<T>,
    th: Vector3<T>,
    u: Vector3<T>,
}

impl<T: Scalar> Tangent<T> {
    fn zero() -> Self {
        Self {
            r: Vector3::zeros(),
            th: Vector3::zeros(),
            u: Vector3::zeros(),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Point<T: Scalar, A, const K: usize> {
    r: Vector3<T>,
    /// The low-order part of the position (compensated summation): the position is `r + r_lo`.
    /// `r` never feeds back into the right-hand side, so this costs a few additions per step and
    /// keeps f32 positions, and the chords between them, free of accumulated rounding.
    r_lo: Vector3<T>,
    att: A,
    u: Vector3<T>,
    tan: [Tangent<T>; K],
}

struct Rates<T: Scalar, A: Attitude<T>, const K: usize> {
    r: Vector3<T>,
    att: A::Rate,
    u: Vector3<T>,
    tan: [Tangent<T>; K],
}

/// The internal-force field on one interval: `n(s) = n_end + g_lambda (s1 - s)`.
struct Field<'a, T> {
    comp: &'a Compliance<T>,
    n_end: Vector3<T>,
    g_lambda: Vector3<T>,
    s1: T,
    kirchhoff: bool,
}

#[inline]
fn rates<T: Scalar, A: Attitude<T>, const K: usize>(
    f: &Field<'_, T>,
    dn: &[Vector3<T>; K],
    s: T,
    p: &Point<T, A, K>,
) -> Rates<T, A, K> {
    let m = p.att.matrix();
    let n = f.n_end + f.g_lambda * (f.s1 - s);
    let nl = m.tr_mul(&n);
    let v = f.comp.shear_strain(&nl, f.kirchhoff);
    let cu = f.comp.c.component_mul(&p.u);
    // Plain loops, not `array::from_fn`: its closure does not inline here and cost a third of a sweep.
    let mut tan = [Tangent::zero(); K];
    for ((out, t), dnj) in tan.iter_mut().zip(&p.tan).zip(dn) {
        let dnl = nl.cross(&t.th) + m.tr_mul(dnj);
        let dv = if f.kirchhoff {
            Vector3::zeros()
        } else {
            f.comp.d_inv.component_mul(&dnl)
        };
        let cdu = f.comp.c.component_mul(&t.u);
        *out = Tangent {
            r: m * (t.th.cross(&v) + dv),
            th: t.u - p.u.cross(&t.th),
            u: -f
                .comp
                .c_inv
                .component_mul(&(t.u.cross(&cu) + p.u.cross(&cdu) + dv.cross(&nl) + v.cross(&dnl))),
        };
    }
    Rates {
        r: m * v,
        att: p.att.rate(&m, &p.u),
        u: f.comp.strain_rate(&p.u, &cu, &v, &nl),
        tan,
    }
}

#[inline]
fn add_tangents<T: Scalar, const K: usize>(
    a: &[Tangent<T>; K],
    k: &[Tangent<T>; K],
    h: T,
) -> [Tangent<T>; K] {
    let mut out = *a;
    for (o, k) in out.iter_mut().zip(k) {
        o.r += k.r * h;
        o.th += k.th * h;
        o.u += k.u * h;
    }
    out
}

#[inline]
fn stage<T: Scalar, A: Attitude<T>, const K: usize>(
    p: &Point<T, A, K>,
    k: &Rates<T, A, K>,
    h: T,
) -> Point<T, A, K> {
    Point {
        r: p.r + k.r * h,
        r_lo: p.r_lo,
        att: A::stage(&p.att, &k.att, h),
        u: p.u + k.u * h,
        tan: add_tangents(&p.tan, &k.tan, h),
    }
}

/// One classical RK4 step of length `h` from `s`.
#[inline]
fn rk4_step<T: Scalar, A: Attitude<T>, const K: usize>(
    f: &Field<'_, T>,
    dn: &[Vector3<T>; K],
    s: T,
    h: T,
    p: &Point<T, A, K>,
) -> Point<T, A, K> {
    let half = h * T::lit(0.5);
    let k1 = rates(f, dn, s, p);
    let k2 = rates(f, dn, s + half, &stage(p, &k1, half));
    let k3 = rates(f, dn, s + half, &stage(p, &k2, half));
    let k4 = rates(f, dn, s + h, &stage(p, &k3, h));
    let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
    let mut tan = p.tan;
    for (j, t) in tan.iter_mut().enumerate() {
        let (a, b, c, d) = (&k1.tan[j], &k2.tan[j], &k3.tan[j], &k4.tan[j]);
        t.r += (a.r + d.r) * w1 + (b.r + c.r) * w2;
        t.th += (a.th + d.th) * w1 + (b.th + c.th) * w2;
        t.u += (a.u + d.u) * w1 + (b.u + c.u) * w2;
    }
    let (r, lo) = compensated_add(&p.r, &((k1.r + k4.r) * w1 + (k2.r + k3.r) * w2));
    Point {
        r,
        r_lo: p.r_lo + lo,
        att: A::combine(&p.att, &[k1.att, k2.att, k3.att, k4.att], h),
        u: p.u + (k1.u + k4.u) * w1 + (k2.u + k3.u) * w2,
        tan,
    }
}

/// `a + b` rounded, and the rounding error (Neumaier's two-sum, per component).
#[inline]
fn compensated_add<T: Scalar>(a: &Vector3<T>, b: &Vector3<T>) -> (Vector3<T>, Vector3<T>) {
    let sum = a + b;
    let lo = Vector3::from_fn(|i, _| {
        let (x, y, t) = (a[i], b[i], sum[i]);
        if x.abs() >= y.abs() {
            (x - t) + y
        } else {
            (y - t) + x
        }
    });
    (sum, lo)
}

/// A cable's running length and its tangents.
#[derive(Clone, Copy, Debug)]
struct CableTrace<T, const K: usize> {
    length_m: T,
    length_lo: T,
    d_length: [T; K],
    /// The previous hole: the backbone point (high and low parts) and the offset `R d`.
    prev: (Vector3<T>, Vector3<T>, Vector3<T>),
    d_prev: [Vector3<T>; K],
    started: bool,
    done: bool,
}

impl<T: Scalar, const K: usize> CableTrace<T, K> {
    fn new() -> Self {
        Self {
            length_m: T::zero(),
            length_lo: T::zero(),
            d_length: [T::zero(); K],
            prev: (Vector3::zeros(), Vector3::zeros(), Vector3::zeros()),
            d_prev: [Vector3::zeros(); K],
            started: false,
            done: false,
        }
    }

    /// Adds the chord to the hole at `r + R d` (thesis ch. 3.8.1: cable length is the sum of chords).
    /// The chord is formed from differences of like parts (high, low, offset), so no part of the
    /// 40 cm position is lost to cancellation, and the lengths are summed with compensation.
    fn add_hole(
        &mut self,
        r: (&Vector3<T>, &Vector3<T>),
        m: &Matrix3<T>,
        tan: &[Tangent<T>; K],
        offset: &Vector3<T>,
    ) {
        let arm = m * offset;
        let hole = (*r.0, *r.1, arm);
        let mut d_hole = [Vector3::zeros(); K];
        for (d, t) in d_hole.iter_mut().zip(tan) {
            *d = t.r + m * t.th.cross(offset);
        }
        if self.started {
            let chord = (hole.0 - self.prev.0) + (hole.1 - self.prev.1) + (hole.2 - self.prev.2);
            let len = chord.norm_squared().sqrt_hot();
            let sum = self.length_m + len;
            self.length_lo += if self.length_m.abs() >= len.abs() {
                (self.length_m - sum) + len
            } else {
                (len - sum) + self.length_m
            };
            self.length_m = sum;
            if len > T::zero() {
                for ((d_length, d_hole), d_prev) in
                    self.d_length.iter_mut().zip(&d_hole).zip(&self.d_prev)
                {
                    *d_length += chord.dot(&(d_hole - d_prev)) / len;
                }
            }
        }
        self.prev = hole;
        self.d_prev = d_hole;
        self.started = true;
    }
}

/// Everything one sweep produces.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sweep<T, const K: usize> {
    pub tip_position_m: Vector3<T>,
    pub tip_rotation: Matrix3<T>,
    /// `C u(L) - R(L)^T tau_tip` (body frame), N m: zero when the tip moment condition holds.
    pub moment_residual_nm: Vector3<T>,
    pub d_moment_residual: [Vector3<T>; K],
    pub cable_m: [T; MAX_CABLES],
    pub d_cable: [[T; K]; MAX_CABLES],
    pub d_tip_position: [Vector3<T>; K],
    /// Tip rotation perturbation, body frame.
    pub d_tip_rotation: [Vector3<T>; K],
    /// First arc length where `det H` stopped being positive (only when tracked).
    pub conjugate_point_m: Option<T>,
    /// Largest `|R^T R - I|` met at the nodes.
    pub frame_drift: T,
    pub finite: bool,
}

impl<T: Scalar, const K: usize> Sweep<T, K> {
    fn non_finite() -> Self {
        Self {
            tip_position_m: Vector3::zeros(),
            tip_rotation: Matrix3::identity(),
            moment_residual_nm: Vector3::zeros(),
            d_moment_residual: [Vector3::zeros(); K],
            cable_m: [T::zero(); MAX_CABLES],
            d_cable: [[T::zero(); K]; MAX_CABLES],
            d_tip_position: [Vector3::zeros(); K],
            d_tip_rotation: [Vector3::zeros(); K],
            conjugate_point_m: None,
            frame_drift: T::zero(),
            finite: false,
        }
    }
}

/// The Jacobi fields of the clamped-free rod under dead loads: `H(s) = d theta(s) / d u(0)`, the first
/// three tangents (seeded by the base strain, with the internal force fixed). `H ~ s I` near the base,
/// so `det H > 0` there; a sign change on `(0, L]` is a conjugate point (the equilibrium is unstable).
struct StabilityTrack<T> {
    conjugate_point_m: Option<T>,
}

impl<T: Scalar> StabilityTrack<T> {
    fn observe<const K: usize>(&mut self, s: T, tan: &[Tangent<T>; K]) {
        if K < 3 || self.conjugate_point_m.is_some() {
            return;
        }
        let h = Matrix3::from_columns(&[tan[0].th, tan[1].th, tan[2].th]);
        if h.determinant() <= T::zero() {
            self.conjugate_point_m = Some(s);
        }
    }
}

fn is_finite_point<T: Scalar, A: Attitude<T>, const K: usize>(p: &Point<T, A, K>) -> bool {
    crate::scalar::all_finite(&p.r)
        && crate::scalar::all_finite(&p.u)
        && crate::scalar::all_finite(&p.att.matrix())
        && p.tan.iter().all(|t| {
            crate::scalar::all_finite(&t.r)
                && crate::scalar::all_finite(&t.th)
                && crate::scalar::all_finite(&t.u)
        })
}

fn shape_point<T: Scalar, A: Attitude<T>, const K: usize>(
    s: T,
    p: &Point<T, A, K>,
) -> ShapePoint<T> {
    ShapePoint {
        s_m: s,
        position_m: p.r + p.r_lo,
        rotation: p.att.matrix(),
        strain_per_m: p.u,
    }
}

/// Integrates from base to tip. `track_stability` needs the first three seeds to be [`Seed::base_strain`].
pub(crate) fn sweep<T: Scalar, A: Attitude<T>, const K: usize>(
    model: &Model<T, A>,
    inputs: &Inputs<T>,
    seeds: &[Seed<T>; K],
    track_stability: bool,
    mut shape: Option<&mut ShapeSink<'_, T>>,
) -> Sweep<T, K> {
    let rod = model.rod();
    let plan = model.plan();
    let alpha = inputs.load_scale;
    let kirchhoff = rod.strain_model == StrainModel::Kirchhoff;
    let dn: [Vector3<T>; K] = array::from_fn(|j| seeds[j].dforce_n * alpha);
    let mut p: Point<T, A, K> = Point {
        r: rod.base_position_m,
        r_lo: Vector3::zeros(),
        att: *model.base_attitude(),
        u: inputs.u0,
        tan: array::from_fn(|j| Tangent {
            r: Vector3::zeros(),
            th: Vector3::zeros(),
            u: seeds[j].du0,
        }),
    };
    let offsets: [Vector3<T>; MAX_CABLES] = array::from_fn(|c| {
        rod.cables
            .get(c)
            .map_or(Vector3::zeros(), |cable| cable.offset_local_m())
    });
    let mut cables: [CableTrace<T, K>; MAX_CABLES] = array::from_fn(|_| CableTrace::new());
    let mut stability = StabilityTrack {
        conjugate_point_m: None,
    };
    let mut frame_drift = T::zero();
    let mut proximal: Option<&Compliance<T>> = None;

    let visit =
        |node: &Node<T>, p: &mut Point<T, A, K>, cables: &mut [CableTrace<T, K>; MAX_CABLES]| {
            let m = p.att.matrix();
            if node.guide != NO_GUIDE {
                for (c, trace) in cables.iter_mut().enumerate().take(rod.cables.len()) {
                    if !trace.done {
                        trace.add_hole((&p.r, &p.r_lo), &m, &p.tan, &offsets[c]);
                    }
                }
            }
            for (c, trace) in cables.iter_mut().enumerate().take(rod.cables.len()) {
                if node.cable_ends & (1u8 << c) != 0 && !trace.done {
                    trace.add_hole((&p.r, &p.r_lo), &m, &p.tan, &offsets[c]);
                    trace.done = true;
                }
            }
            m
        };

    for (k, interval) in plan.intervals.iter().enumerate() {
        let Some(comp) = model.compliance(interval.section) else {
            return Sweep::non_finite();
        };
        if let Some(node) = plan.nodes.get(k) {
            if let Some(prox) = proximal {
                let jump = prox != comp || node.moment_nm != Vector3::zeros();
                if jump {
                    let m = p.att.matrix();
                    let tau_local = m.tr_mul(&(node.moment_nm * alpha));
                    for t in p.tan.iter_mut() {
                        t.u = strain_tangent_after(prox, comp, &tau_local, &t.th, &t.u);
                    }
                    p.u = strain_after(prox, comp, &tau_local, &p.u);
                }
            }
            let m = visit(node, &mut p, &mut cables);
            frame_drift = frame_drift.max(crate::kinematics::orthonormality_error(&m));
        }
        let field = Field {
            comp,
            n_end: (inputs.tip_force_n + interval.distal_force_n) * alpha,
            g_lambda: rod.gravity_m_s2 * (interval.line_density_kg_per_m * alpha),
            s1: interval.s1_m,
            kirchhoff,
        };
        let (s0, len) = (interval.s0_m, interval.s1_m - interval.s0_m);
        let steps = T::lit(f64::from(interval.steps));
        let mut s = s0;
        for i in 1..=interval.steps {
            let s_next = if i == interval.steps {
                interval.s1_m
            } else {
                s0 + len * (T::lit(f64::from(i)) / steps)
            };
            if let Some(sink) = shape.as_deref_mut() {
                while let Some(q) = sink.next_query().filter(|q| *q < s_next) {
                    let here = Point::<T, A, 0> {
                        r: p.r,
                        r_lo: p.r_lo,
                        att: p.att,
                        u: p.u,
                        tan: [],
                    };
                    let at_q = if q > s {
                        rk4_step(&field, &[], s, q - s, &here)
                    } else {
                        here
                    };
                    sink.write(shape_point(q, &at_q));
                }
            }
            p = rk4_step(&field, &dn, s, s_next - s, &p);
            if track_stability {
                stability.observe(s_next, &p.tan);
            }
            s = s_next;
        }
        if !is_finite_point(&p) {
            return Sweep::non_finite();
        }
        proximal = Some(comp);
    }

    // The tip node: last guide holes and terminations, remaining shape queries, the boundary condition.
    let length = model.length_m();
    let tip_moment_nm = plan.nodes.last().map_or(Vector3::zeros(), |n| {
        visit(n, &mut p, &mut cables);
        n.moment_nm
    }) + inputs.tip_moment_nm;
    if let Some(sink) = shape {
        while sink.next_query().is_some_and(|q| q <= length) {
            sink.write(shape_point(length, &p));
        }
    }
    let m = p.att.matrix();
    frame_drift = frame_drift.max(crate::kinematics::orthonormality_error(&m));
    let Some(comp) = proximal else {
        return Sweep::non_finite();
    };
    let tau_local = m.tr_mul(&(tip_moment_nm * alpha));
    let mut out = Sweep {
        tip_position_m: p.r + p.r_lo,
        tip_rotation: m,
        moment_residual_nm: comp.c.component_mul(&p.u) - tau_local,
        d_moment_residual: array::from_fn(|j| {
            comp.c.component_mul(&p.tan[j].u) - tau_local.cross(&p.tan[j].th)
        }),
        cable_m: [T::zero(); MAX_CABLES],
        d_cable: [[T::zero(); K]; MAX_CABLES],
        d_tip_position: array::from_fn(|j| p.tan[j].r),
        d_tip_rotation: array::from_fn(|j| p.tan[j].th),
        conjugate_point_m: stability.conjugate_point_m,
        frame_drift,
        finite: true,
    };
    for (c, trace) in cables.iter().enumerate() {
        out.cable_m[c] = trace.length_m + trace.length_lo;
        out.d_cable[c] = trace.d_length;
    }
    let finite = crate::scalar::all_finite(&out.moment_residual_nm)
        && out.cable_m.iter().all(|x| x.is_finite())
        && out.d_cable.iter().flatten().all(|x| x.is_finite())
        && out.d_moment_residual.iter().all(crate::scalar::all_finite);
    out.finite = finite;
    out
}
