//! One fixed-step sweep from base to tip (thesis eq. 2.13 and the kinematics), with forward
//! sensitivities.
//!
//! The state is `(r, R, u)`; `n(s)` is known in closed form from the plan. Alongside it the sweep can
//! carry up to [`MAX_TANGENTS`] tangent directions `(dr, dtheta, du)`, `dR = R hat(dtheta)`, seeded by
//! a change of the base strain `u(0)` and of the tip force. Each RK4 step first advances the state and
//! records its four stages; every tangent then takes the same RK4 step over those stages. That is the
//! derivative of the discrete sweep (to the order of the scheme), with no finite-difference
//! cancellation: the Jacobians of the shooting and inverse solves, and the Jacobi fields of the
//! stability test, all come from here. The tangent count is a run-time number, so there is one
//! compiled sweep (the firmware's flash is small), and a plain sweep pays nothing for tangents.
//!
//! Linearised right-hand side, with `n_l = R^T n`:
//! `dn_l = n_l x dtheta + R^T dn`, `dv = D^-1 dn_l`, `dr' = R (dtheta x v + dv)`,
//! `dtheta' = du - u x dtheta`, `du' = -C^-1 (du x C u + u x C du + dv x n_l + v x dn_l)`.

use nalgebra::{Matrix3, Vector3};

use crate::constitutive::Compliance;
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::plan::{NO_GUIDE, Node};
use crate::rod::StrainModel;
use crate::shape::{ShapePoint, ShapeSink};
use crate::stability::ConjugateTrack;
use crate::transitions::{strain_after, strain_tangent_after};
use crate::{MAX_CABLES, Scalar};

/// Most tangent directions a sweep carries: three base-strain and three tip-force directions.
pub(crate) const MAX_TANGENTS: usize = 6;

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

/// Which tangents a sweep carries: the first `count` of the three base-strain directions followed by
/// the three tip-force directions (0: none; 3: the base strain, for shooting and the stability test;
/// 6: both, for the inverse).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Tangents {
    pub count: usize,
    pub track_stability: bool,
}

impl Tangents {
    pub const NONE: Self = Self {
        count: 0,
        track_stability: false,
    };

    /// The three base-strain directions.
    pub fn base_strain(track_stability: bool) -> Self {
        Self {
            count: 3,
            track_stability,
        }
    }

    /// All six directions.
    pub fn all(track_stability: bool) -> Self {
        Self {
            count: MAX_TANGENTS,
            track_stability,
        }
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

    #[inline]
    fn axpy(&self, k: &Self, h: T) -> Self {
        Self {
            r: self.r + k.r * h,
            th: self.th + k.th * h,
            u: self.u + k.u * h,
        }
    }

    fn is_finite(&self) -> bool {
        crate::scalar::all_finite(&self.r)
            && crate::scalar::all_finite(&self.th)
            && crate::scalar::all_finite(&self.u)
    }
}

#[derive(Clone, Copy, Debug)]
struct Point<T: Scalar, A> {
    r: Vector3<T>,
    /// The low-order part of the position (compensated summation): the position is `r + r_lo`.
    /// `r` never feeds back into the right-hand side, so this costs a few additions per step and
    /// keeps f32 positions, and the chords between them, free of accumulated rounding.
    r_lo: Vector3<T>,
    att: A,
    u: Vector3<T>,
}

struct Rates<T: Scalar, A: Attitude<T>> {
    r: Vector3<T>,
    att: A::Rate,
    u: Vector3<T>,
}

/// What a tangent's right-hand side needs from the state at one RK4 stage.
#[derive(Clone, Copy, Debug)]
struct Stage<T> {
    m: Matrix3<T>,
    n_local: Vector3<T>,
    v: Vector3<T>,
    u: Vector3<T>,
    cu: Vector3<T>,
}

impl<T: Scalar> Stage<T> {
    fn zero() -> Self {
        Self {
            m: Matrix3::zeros(),
            n_local: Vector3::zeros(),
            v: Vector3::zeros(),
            u: Vector3::zeros(),
            cu: Vector3::zeros(),
        }
    }
}

/// The internal-force field on one interval: `n(s) = n_end + g_lambda (s1 - s)`.
struct Field<'a, T> {
    comp: &'a Compliance<T>,
    n_end: Vector3<T>,
    g_lambda: Vector3<T>,
    s1: T,
    kirchhoff: bool,
}

/// The state's right-hand side; writes what the tangents need into `record` when asked.
#[inline]
fn rates<T: Scalar, A: Attitude<T>>(
    f: &Field<'_, T>,
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

/// A tangent's right-hand side at one stage; `dn` is its constant change of internal force.
#[inline]
fn tangent_rates<T: Scalar>(
    f: &Field<'_, T>,
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

#[inline]
fn stage<T: Scalar, A: Attitude<T>>(p: &Point<T, A>, k: &Rates<T, A>, h: T) -> Point<T, A> {
    Point {
        r: p.r + k.r * h,
        r_lo: p.r_lo,
        att: A::stage(&p.att, &k.att, h),
        u: p.u + k.u * h,
    }
}

/// One classical RK4 step of length `h` from `s`; writes its four stages into `stages` when given
/// (in place: a plain sweep neither stores nor copies them).
#[inline]
fn rk4_step<T: Scalar, A: Attitude<T>>(
    f: &Field<'_, T>,
    s: T,
    h: T,
    p: &Point<T, A>,
    stages: Option<&mut [Stage<T>; 4]>,
) -> Point<T, A> {
    let [r1, r2, r3, r4] = match stages {
        Some(stages) => stages.each_mut().map(Some),
        None => [None, None, None, None],
    };
    let half = h * T::lit(0.5);
    let k1 = rates(f, s, p, r1);
    let k2 = rates(f, s + half, &stage(p, &k1, half), r2);
    let k3 = rates(f, s + half, &stage(p, &k2, half), r3);
    let k4 = rates(f, s + h, &stage(p, &k3, h), r4);
    let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
    let (r, lo) = compensated_add(&p.r, &((k1.r + k4.r) * w1 + (k2.r + k3.r) * w2));
    Point {
        r,
        r_lo: p.r_lo + lo,
        att: A::combine(&p.att, &[k1.att, k2.att, k3.att, k4.att], h),
        u: p.u + (k1.u + k4.u) * w1 + (k2.u + k3.u) * w2,
    }
}

/// The same RK4 step for one tangent, over the stages of the state's step.
#[inline]
fn tangent_step<T: Scalar>(
    f: &Field<'_, T>,
    stages: &[Stage<T>; 4],
    dn: &Vector3<T>,
    h: T,
    t: &Tangent<T>,
) -> Tangent<T> {
    let half = h * T::lit(0.5);
    let [s1, s2, s3, s4] = stages;
    let k1 = tangent_rates(f, s1, dn, t);
    let k2 = tangent_rates(f, s2, dn, &t.axpy(&k1, half));
    let k3 = tangent_rates(f, s3, dn, &t.axpy(&k2, half));
    let k4 = tangent_rates(f, s4, dn, &t.axpy(&k3, h));
    let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
    Tangent {
        r: t.r + (k1.r + k4.r) * w1 + (k2.r + k3.r) * w2,
        th: t.th + (k1.th + k4.th) * w1 + (k2.th + k3.th) * w2,
        u: t.u + (k1.u + k4.u) * w1 + (k2.u + k3.u) * w2,
    }
}

/// `a + b` rounded, and the rounding error (Neumaier's two-sum, per component).
#[inline]
fn compensated_add<T: Scalar>(a: &Vector3<T>, b: &Vector3<T>) -> (Vector3<T>, Vector3<T>) {
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

/// A cable's running length and its tangents.
#[derive(Clone, Copy, Debug)]
struct CableTrace<T> {
    length_m: T,
    length_lo: T,
    d_length: [T; MAX_TANGENTS],
    /// The previous hole: the backbone point (high and low parts) and the offset `R d`.
    prev: (Vector3<T>, Vector3<T>, Vector3<T>),
    d_prev: [Vector3<T>; MAX_TANGENTS],
    started: bool,
    done: bool,
}

impl<T: Scalar> CableTrace<T> {
    fn new() -> Self {
        Self {
            length_m: T::zero(),
            length_lo: T::zero(),
            d_length: [T::zero(); MAX_TANGENTS],
            prev: (Vector3::zeros(), Vector3::zeros(), Vector3::zeros()),
            d_prev: [Vector3::zeros(); MAX_TANGENTS],
            started: false,
            done: false,
        }
    }

    /// Adds the chord to the hole at `r + R d` (thesis ch. 3.8.1: cable length is the sum of chords).
    /// The chord is formed from differences of like parts (high, low, offset), so no part of the
    /// 40 cm position is lost to cancellation, and the lengths are summed with compensation.
    fn add_hole(
        &mut self,
        p: &Point<T, impl Copy>,
        m: &Matrix3<T>,
        tan: &[Tangent<T>],
        offset: &Vector3<T>,
    ) {
        let arm = m * offset;
        let hole = (p.r, p.r_lo, arm);
        let mut d_hole = [Vector3::zeros(); MAX_TANGENTS];
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
                for ((d_length, d_hole), d_prev) in self
                    .d_length
                    .iter_mut()
                    .zip(&d_hole)
                    .zip(&self.d_prev)
                    .take(tan.len())
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

/// Everything one sweep produces. Tangent arrays hold [`Sweep::tangents`] valid entries.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sweep<T> {
    pub tip_position_m: Vector3<T>,
    pub tip_rotation: Matrix3<T>,
    /// `C u(L) - R(L)^T tau_tip` (body frame), N m: zero when the tip moment condition holds.
    pub moment_residual_nm: Vector3<T>,
    pub d_moment_residual: [Vector3<T>; MAX_TANGENTS],
    pub cable_m: [T; MAX_CABLES],
    pub d_cable: [[T; MAX_TANGENTS]; MAX_CABLES],
    pub d_tip_position: [Vector3<T>; MAX_TANGENTS],
    /// Tip rotation perturbation, body frame.
    pub d_tip_rotation: [Vector3<T>; MAX_TANGENTS],
    /// How many tangents the arrays hold.
    pub tangents: usize,
    /// First arc length where `det H` stopped being positive (only when tracked).
    pub conjugate_point_m: Option<T>,
    /// Largest `|R^T R - I|` met at the nodes.
    pub frame_drift: T,
    pub finite: bool,
}

impl<T: Scalar> Sweep<T> {
    fn non_finite() -> Self {
        Self {
            tip_position_m: Vector3::zeros(),
            tip_rotation: Matrix3::identity(),
            moment_residual_nm: Vector3::zeros(),
            d_moment_residual: [Vector3::zeros(); MAX_TANGENTS],
            cable_m: [T::zero(); MAX_CABLES],
            d_cable: [[T::zero(); MAX_TANGENTS]; MAX_CABLES],
            d_tip_position: [Vector3::zeros(); MAX_TANGENTS],
            d_tip_rotation: [Vector3::zeros(); MAX_TANGENTS],
            tangents: 0,
            conjugate_point_m: None,
            frame_drift: T::zero(),
            finite: false,
        }
    }

    fn carried(&self, j: usize) -> Option<usize> {
        (j < self.tangents).then_some(j)
    }

    /// Tangent `j`'s change of the tip-moment residual (zero when not carried).
    pub fn d_moment(&self, j: usize) -> Vector3<T> {
        self.carried(j)
            .and_then(|j| self.d_moment_residual.get(j))
            .copied()
            .unwrap_or_else(Vector3::zeros)
    }

    /// Tangent `j`'s change of the tip rotation (zero when not carried).
    pub fn d_rotation(&self, j: usize) -> Vector3<T> {
        self.carried(j)
            .and_then(|j| self.d_tip_rotation.get(j))
            .copied()
            .unwrap_or_else(Vector3::zeros)
    }

    /// Tangent `j`'s change of the tip position (zero when not carried).
    pub fn d_position(&self, j: usize) -> Vector3<T> {
        self.carried(j)
            .and_then(|j| self.d_tip_position.get(j))
            .copied()
            .unwrap_or_else(Vector3::zeros)
    }

    /// Tangent `j`'s change of cable `c`'s length (zero when not carried).
    pub fn d_cable_length(&self, c: usize, j: usize) -> T {
        self.carried(j)
            .and_then(|j| self.d_cable.get(c).and_then(|row| row.get(j)))
            .copied()
            .unwrap_or_else(T::zero)
    }
}

/// The Jacobi fields at a grid point, for [`ConjugateTrack`]: `H = d theta / d u(0)` (the first three
/// tangents' rotations) and `M = C du / d u(0)` (their moments), body frame.
fn jacobi_fields<T: Scalar>(
    tan: &[Tangent<T>],
    c: &Vector3<T>,
) -> Option<(Matrix3<T>, Matrix3<T>)> {
    let [a, b, d, ..] = tan else {
        return None;
    };
    let h = Matrix3::from_columns(&[a.th, b.th, d.th]);
    let m = Matrix3::from_columns(&[a.u, b.u, d.u]);
    Some((h, Matrix3::from_diagonal(c) * m))
}

fn is_finite_point<T: Scalar, A: Attitude<T>>(p: &Point<T, A>, tan: &[Tangent<T>]) -> bool {
    crate::scalar::all_finite(&p.r)
        && crate::scalar::all_finite(&p.u)
        && crate::scalar::all_finite(&p.att.matrix())
        && tan.iter().all(Tangent::is_finite)
}

fn shape_point<T: Scalar, A: Attitude<T>>(s: T, p: &Point<T, A>) -> ShapePoint<T> {
    ShapePoint {
        s_m: s,
        position_m: p.r + p.r_lo,
        rotation: p.att.matrix(),
        strain_per_m: p.u,
    }
}

/// Integrates from base to tip with the tangents `which`. Tracking stability needs at least the three
/// base-strain tangents.
pub(crate) fn sweep<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    inputs: &Inputs<T>,
    which: Tangents,
    mut shape: Option<&mut ShapeSink<'_, T>>,
) -> Sweep<T> {
    let rod = model.rod();
    let plan = model.plan();
    let alpha = inputs.load_scale;
    let kirchhoff = rod.strain_model == StrainModel::Kirchhoff;
    let count = which.count.min(MAX_TANGENTS);
    // Seeds: tangent j < 3 changes u(0) along axis j; j >= 3 changes the tip force along axis j - 3.
    let unit = |j: usize| Vector3::from_fn(|i, _| if i == j % 3 { T::one() } else { T::zero() });
    let mut dn = [Vector3::zeros(); MAX_TANGENTS];
    let mut tan = [Tangent::zero(); MAX_TANGENTS];
    for (j, (d, t)) in dn.iter_mut().zip(tan.iter_mut()).enumerate() {
        if j < 3 {
            t.u = unit(j);
        } else {
            *d = unit(j) * alpha;
        }
    }
    let (dn, tan) = (
        dn.get(..count).unwrap_or(&[]),
        tan.get_mut(..count).unwrap_or(&mut []),
    );
    let mut p: Point<T, A> = Point {
        r: rod.base_position_m,
        r_lo: Vector3::zeros(),
        att: *model.base_attitude(),
        u: inputs.u0,
    };
    let offsets = model.cable_offsets();
    let mut cables = [CableTrace::new(); MAX_CABLES];
    let mut conjugate_point_m = None;
    let mut frame_drift = T::zero();
    let mut proximal: Option<&Compliance<T>> = None;
    let mut stages = [Stage::zero(); 4];
    let mut track = ConjugateTrack::new();

    let visit = |node: &Node<T>,
                 p: &Point<T, A>,
                 tan: &[Tangent<T>],
                 cables: &mut [CableTrace<T>; MAX_CABLES]| {
        let m = p.att.matrix();
        for (c, (trace, offset)) in cables
            .iter_mut()
            .zip(offsets)
            .enumerate()
            .take(rod.cables.len())
        {
            let ends = node.cable_ends & (1u8 << c) != 0;
            if !trace.done && node.guide != NO_GUIDE {
                trace.add_hole(p, &m, tan, offset);
            }
            if !trace.done && ends {
                trace.add_hole(p, &m, tan, offset);
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
                    for t in tan.iter_mut() {
                        t.u = strain_tangent_after(prox, comp, &tau_local, &t.th, &t.u);
                    }
                    p.u = strain_after(prox, comp, &tau_local, &p.u);
                }
            }
            let m = visit(node, &p, tan, &mut cables);
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
                    let at_q = if q > s {
                        rk4_step(&field, s, q - s, &p, None)
                    } else {
                        p
                    };
                    sink.write(shape_point(q, &at_q));
                }
            }
            let h = s_next - s;
            if tan.is_empty() {
                p = rk4_step(&field, s, h, &p, None);
            } else {
                p = rk4_step(&field, s, h, &p, Some(&mut stages));
                for (t, d) in tan.iter_mut().zip(dn) {
                    *t = tangent_step(&field, &stages, d, h, t);
                }
            }
            if which.track_stability && conjugate_point_m.is_none() {
                let crossed = jacobi_fields(tan, &comp.c)
                    .is_some_and(|(jh, jm)| track.crosses(&jh, &jm, comp.c.min(), len / steps));
                if crossed {
                    conjugate_point_m = Some(s_next);
                }
            }
            s = s_next;
        }
        if !is_finite_point(&p, tan) {
            return Sweep::non_finite();
        }
        proximal = Some(comp);
    }

    // The tip node: last guide holes and terminations, remaining shape queries, the boundary condition.
    let length = model.length_m();
    let tip_moment_nm = plan.nodes.last().map_or(Vector3::zeros(), |n| {
        visit(n, &p, tan, &mut cables);
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
        d_moment_residual: [Vector3::zeros(); MAX_TANGENTS],
        cable_m: [T::zero(); MAX_CABLES],
        d_cable: [[T::zero(); MAX_TANGENTS]; MAX_CABLES],
        d_tip_position: [Vector3::zeros(); MAX_TANGENTS],
        d_tip_rotation: [Vector3::zeros(); MAX_TANGENTS],
        tangents: count,
        conjugate_point_m,
        frame_drift,
        finite: true,
    };
    for (j, t) in tan.iter().enumerate() {
        if let (Some(e), Some(r), Some(th)) = (
            out.d_moment_residual.get_mut(j),
            out.d_tip_position.get_mut(j),
            out.d_tip_rotation.get_mut(j),
        ) {
            *e = comp.c.component_mul(&t.u) - tau_local.cross(&t.th);
            *r = t.r;
            *th = t.th;
        }
    }
    for ((length, d_length), trace) in out
        .cable_m
        .iter_mut()
        .zip(out.d_cable.iter_mut())
        .zip(&cables)
    {
        *length = trace.length_m + trace.length_lo;
        *d_length = trace.d_length;
    }
    out.finite = crate::scalar::all_finite(&out.moment_residual_nm)
        && out.cable_m.iter().all(|x| x.is_finite())
        && out.d_cable.iter().flatten().all(|x| x.is_finite())
        && out.d_moment_residual.iter().all(crate::scalar::all_finite);
    out
}
