//! The planar reduction: when every load lies in one plane through the base tangent (forces in the
//! plane, moments normal to it) and the cross-section bends freely about the plane's normal, the rod
//! stays in that plane, and the 3D statics reduce to position `(x, y)`, tangent direction `(c, s)`
//! and one curvature `k`:
//!
//! `r' = v_t t + v_n t_perp`, `t' = k t_perp`, `E I k' = -(r' x n)_z`,
//! `v_t = 1 + n.t / E A`, `v_n = n.t_perp / G A` (or `1, 0` for a Kirchhoff rod),
//!
//! with `t = (c, s)`, `t_perp = (-s, c)`: five states instead of sixteen, no frame to orthonormalise
//! (the direction is renormalised once per step), one shooting unknown `k(0)` with its derivative from
//! a forward sensitivity. Cable holes rotate with the frame about the plane's normal, so cable lengths
//! and the 3D shape follow exactly.
//!
//! The stability test during the solve is the in-plane one (`d theta / d k(0) > 0` along the rod and
//! a positive free-end stiffness); the answer then gets the 3D test (one 3D sweep with its Jacobi
//! fields), since an instability out of the plane is invisible to the reduction.

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::error::{ModelError, finite_vec};
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::plan::MAX_NODES;
use crate::plan::{NO_GUIDE, Node};
use crate::report::{SolveReport, Termination};
use crate::rod::StrainModel;
use crate::shape::{ShapePoint, ShapeSink};
use crate::shooting::{ShootingSettings, TipLoad};
use crate::stability::Stability;
use crate::{MAX_CABLES, Scalar};

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

/// How far from planar (relative to `1 +` the magnitude tested) a scene may be for the reduction.
const PLANE_TOLERANCE: f64 = 1e-9;

/// The plane a rod and a tip load stay in, if they do: every force (gravity, point loads, tip)
/// perpendicular to one normal that is perpendicular to the base tangent, every moment along it, and
/// the section's bending stiffness about that normal a principal one. `None` otherwise.
pub fn plane_of<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    load: &TipLoad<T>,
) -> Option<Plane<T>> {
    let rod = model.rod();
    let tol = T::lit(PLANE_TOLERANCE);
    let tangent = rod.base_orientation.column(2).into_owned();
    let forces = core::iter::once(rod.gravity_m_s2)
        .chain(core::iter::once(load.force_n))
        .chain(rod.loads.iter().map(|l| l.force_n));
    let moments = core::iter::once(load.moment_nm).chain(rod.loads.iter().map(|l| l.moment_nm));
    // The normal: from the first force with a component across the tangent, else the first moment,
    // else the base's local x axis (any plane through the tangent will do).
    let candidate = forces
        .clone()
        .map(|f| tangent.cross(&f))
        .chain(moments.clone())
        .find(|v| v.norm() > tol)
        .unwrap_or_else(|| rod.base_orientation.column(0).into_owned());
    let normal = candidate.try_normalize(T::default_epsilon())?;
    if normal.dot(&tangent).abs() > tol {
        return None;
    }
    let in_plane = forces
        .clone()
        .all(|f| f.dot(&normal).abs() <= tol * (T::one() + f.norm()));
    let along = moments
        .clone()
        .all(|m| (m - normal * m.dot(&normal)).norm() <= tol * (T::one() + m.norm()));
    // The normal in the base's local frame must be a principal axis unless the section is isotropic.
    let local = rod.base_orientation.tr_mul(&normal);
    let principal = rod.sections.iter().all(|s| {
        let c = s.stiffness.bending_torsion_nm2;
        (c.x - c.y).abs() <= tol * c.x || local.x.abs() <= tol || local.y.abs() <= tol
    });
    (in_plane && along && principal && local.z.abs() <= tol).then(|| Plane {
        e1: tangent,
        e2: normal.cross(&tangent),
        normal,
    })
}

/// The planar state and its tangent with respect to `k(0)`.
#[derive(Clone, Copy, Debug)]
struct State<T: Scalar> {
    r: Vector2<T>,
    t: Vector2<T>,
    k: T,
    dr: Vector2<T>,
    dt: Vector2<T>,
    dk: T,
}

#[inline]
fn perp<T: Scalar>(v: &Vector2<T>) -> Vector2<T> {
    Vector2::new(-v.y, v.x)
}

#[inline]
fn cross2<T: Scalar>(a: &Vector2<T>, b: &Vector2<T>) -> T {
    a.x * b.y - a.y * b.x
}

/// One interval's coefficients: bending, shear and axial compliance, and the force field.
struct Field<T> {
    ei: T,
    ga_inv: T,
    ea_inv: T,
    n_end: Vector2<T>,
    g_lambda: Vector2<T>,
    s1: T,
    kirchhoff: bool,
}

#[inline]
fn rates<T: Scalar>(f: &Field<T>, s: T, y: &State<T>) -> State<T> {
    let n = f.n_end + f.g_lambda * (f.s1 - s);
    let np = perp(&y.t);
    let (vt, vn) = if f.kirchhoff {
        (T::one(), T::zero())
    } else {
        (T::one() + n.dot(&y.t) * f.ea_inv, n.dot(&np) * f.ga_inv)
    };
    let r = y.t * vt + np * vn;
    let dnp = perp(&y.dt);
    let (dvt, dvn) = if f.kirchhoff {
        (T::zero(), T::zero())
    } else {
        (n.dot(&y.dt) * f.ea_inv, n.dot(&dnp) * f.ga_inv)
    };
    let dr = y.dt * vt + y.t * dvt + dnp * vn + np * dvn;
    State {
        r,
        t: np * y.k,
        k: -cross2(&r, &n) / f.ei,
        dr,
        dt: np * y.dk + dnp * y.k,
        dk: -cross2(&dr, &n) / f.ei,
    }
}

#[inline]
fn axpy<T: Scalar>(y: &State<T>, k: &State<T>, h: T) -> State<T> {
    State {
        r: y.r + k.r * h,
        t: y.t + k.t * h,
        k: y.k + k.k * h,
        dr: y.dr + k.dr * h,
        dt: y.dt + k.dt * h,
        dk: y.dk + k.dk * h,
    }
}

fn rk4<T: Scalar>(f: &Field<T>, s: T, h: T, y: &State<T>) -> State<T> {
    let half = h * T::lit(0.5);
    let k1 = rates(f, s, y);
    let k2 = rates(f, s + half, &axpy(y, &k1, half));
    let k3 = rates(f, s + half, &axpy(y, &k2, half));
    let k4 = rates(f, s + h, &axpy(y, &k3, h));
    let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
    let combine = |a: T, b: T, c: T, d: T| (a + d) * w1 + (b + c) * w2;
    let mut out = State {
        r: y.r + (k1.r + k4.r) * w1 + (k2.r + k3.r) * w2,
        t: y.t + (k1.t + k4.t) * w1 + (k2.t + k3.t) * w2,
        k: y.k + combine(k1.k, k2.k, k3.k, k4.k),
        dr: y.dr + (k1.dr + k4.dr) * w1 + (k2.dr + k3.dr) * w2,
        dt: y.dt + (k1.dt + k4.dt) * w1 + (k2.dt + k3.dt) * w2,
        dk: y.dk + combine(k1.dk, k2.dk, k3.dk, k4.dk),
    };
    // Keep the direction a unit vector (its tangent stays perpendicular to it).
    let norm = out.t.norm_squared().sqrt_hot();
    out.t /= norm;
    out.dt -= out.t * out.t.dot(&out.dt);
    out
}

/// What one planar sweep gives.
struct Sweep<T> {
    tip: Vector2<T>,
    /// `d r(L) / d k(0)`, m^2.
    d_tip: Vector2<T>,
    tangent: Vector2<T>,
    /// `E I k(L) - tau . normal`, N m, and its derivative with respect to `k(0)`.
    residual: T,
    d_residual: T,
    /// `d theta(L) / d k(0)`, and the first arc length where `d theta / d k(0)` stopped being positive.
    d_theta: T,
    conjugate_point_m: Option<T>,
    cables_m: [T; MAX_CABLES],
    finite: bool,
}

/// A planar view of a model.
#[derive(Clone, Debug)]
pub struct PlanarModel<'a, T: Scalar, A: Attitude<T>, const NODES: usize = MAX_NODES> {
    model: &'a Model<T, A, NODES>,
    plane: Plane<T>,
    /// Per section: bending stiffness about the normal, `1 / G A`, `1 / E A`.
    sections: heapless::Vec<(T, T, T), { crate::MAX_SECTIONS }>,
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> PlanarModel<'a, T, A, NODES> {
    /// The planar reduction of `model` under `load`, if the scene stays in a plane ([`plane_of`]).
    pub fn new(model: &'a Model<T, A, NODES>, load: &TipLoad<T>) -> Option<Self> {
        let plane = plane_of(model, load)?;
        let axis = model.rod().base_orientation.tr_mul(&plane.normal);
        let mut sections = heapless::Vec::new();
        for s in &model.rod().sections {
            let c = s.stiffness.bending_torsion_nm2;
            let d = s.stiffness.shear_axial_n;
            // Bending about the normal: the local normal is (a, b, 0), a principal axis or isotropic.
            let ei = c.x * axis.x * axis.x + c.y * axis.y * axis.y;
            let ga = d.x * axis.y * axis.y + d.y * axis.x * axis.x;
            sections.push((ei, T::one() / ga, T::one() / d.z)).ok()?;
        }
        Some(Self {
            model,
            plane,
            sections,
        })
    }

    /// The plane.
    pub fn plane(&self) -> &Plane<T> {
        &self.plane
    }

    fn project(&self, v: &Vector3<T>) -> Vector2<T> {
        Vector2::new(v.dot(&self.plane.e1), v.dot(&self.plane.e2))
    }

    /// The 3D frame for a planar direction `t`: the base frame turned about the normal.
    fn frame(&self, t: &Vector2<T>) -> Matrix3<T> {
        let (e1, e2, n) = (self.plane.e1, self.plane.e2, self.plane.normal);
        let turn = Matrix3::from_columns(&[e1 * t.x + e2 * t.y, e2 * t.x - e1 * t.y, n])
            * Matrix3::from_rows(&[e1.transpose(), e2.transpose(), n.transpose()]);
        turn * self.model.rod().base_orientation
    }

    fn position(&self, r: &Vector2<T>) -> Vector3<T> {
        self.model.rod().base_position_m + self.plane.e1 * r.x + self.plane.e2 * r.y
    }

    fn sweep(
        &self,
        k0: T,
        load: &TipLoad<T>,
        alpha: T,
        mut shape: Option<&mut ShapeSink<'_, T>>,
    ) -> Sweep<T> {
        let model = self.model;
        let rod = model.rod();
        let plan = model.plan();
        let kirchhoff = rod.strain_model == StrainModel::Kirchhoff;
        let tip_force = self.project(&load.force_n);
        let g = self.project(&rod.gravity_m_s2);
        let mut y = State {
            r: Vector2::zeros(),
            t: Vector2::new(T::one(), T::zero()),
            k: k0,
            dr: Vector2::zeros(),
            dt: Vector2::zeros(),
            dk: T::one(),
        };
        let offsets: [Vector3<T>; MAX_CABLES] = core::array::from_fn(|c| {
            rod.cables
                .get(c)
                .map_or(Vector3::zeros(), |cable| cable.offset_local_m())
        });
        let mut holes: [Option<Vector3<T>>; MAX_CABLES] = [None; MAX_CABLES];
        let mut done = [false; MAX_CABLES];
        let mut cables = [T::zero(); MAX_CABLES];
        let mut conjugate_point_m = None;
        let mut out = Sweep {
            tip: Vector2::zeros(),
            d_tip: Vector2::zeros(),
            tangent: Vector2::new(T::one(), T::zero()),
            residual: T::zero(),
            d_residual: T::zero(),
            d_theta: T::zero(),
            conjugate_point_m: None,
            cables_m: [T::zero(); MAX_CABLES],
            finite: false,
        };
        let mut visit = |node: &Node<T>, y: &State<T>| {
            let frame = self.frame(&y.t);
            let here = self.position(&y.r);
            for (c, (hole, finished)) in holes
                .iter_mut()
                .zip(done.iter_mut())
                .enumerate()
                .take(rod.cables.len())
            {
                let ends = node.cable_ends & (1u8 << c) != 0;
                if (node.guide != NO_GUIDE || ends) && !*finished {
                    let p = here + frame * offsets.get(c).copied().unwrap_or_else(Vector3::zeros);
                    if let (Some(prev), Some(total)) = (*hole, cables.get_mut(c)) {
                        *total += (p - prev).norm();
                    }
                    *hole = Some(p);
                    *finished |= ends;
                }
            }
        };
        let mut proximal: Option<&(T, T, T)> = None;
        let mut ei_last = T::one();
        for (k, interval) in plan.intervals.iter().enumerate() {
            let Some(sec) = self.sections.get(usize::from(interval.section)) else {
                return out;
            };
            if let Some(node) = plan.nodes.get(k) {
                if let Some(prev) = proximal {
                    let tau = node.moment_nm.dot(&self.plane.normal) * alpha;
                    if prev.0 != sec.0 || tau != T::zero() {
                        y.k = (prev.0 * y.k - tau) / sec.0;
                        y.dk = prev.0 * y.dk / sec.0;
                    }
                }
                visit(node, &y);
            }
            let field = Field {
                ei: sec.0,
                ga_inv: sec.1,
                ea_inv: sec.2,
                n_end: (tip_force + self.project(&interval.distal_force_n)) * alpha,
                g_lambda: g * (interval.line_density_kg_per_m * alpha),
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
                        let at = if q > s { rk4(&field, s, q - s, &y) } else { y };
                        sink.write(self.shape_point(q, &at));
                    }
                }
                y = rk4(&field, s, s_next - s, &y);
                // The in-plane Jacobi field: theta turned by a change of k(0) is atan2 of dt across t.
                if conjugate_point_m.is_none() && cross2(&y.t, &y.dt) <= T::zero() {
                    conjugate_point_m = Some(s_next);
                }
                s = s_next;
            }
            if !(y.r.iter().chain(y.t.iter()).all(|x| x.is_finite())
                && y.k.is_finite()
                && y.dk.is_finite())
            {
                return out;
            }
            proximal = Some(sec);
            ei_last = sec.0;
        }
        let tip_moment = plan.nodes.last().map_or(T::zero(), |n| {
            visit(n, &y);
            n.moment_nm.dot(&self.plane.normal)
        }) + load.moment_nm.dot(&self.plane.normal);
        if let Some(sink) = shape {
            while sink.next_query().is_some_and(|q| q <= model.length_m()) {
                sink.write(self.shape_point(model.length_m(), &y));
            }
        }
        out.tip = y.r;
        out.d_tip = y.dr;
        out.tangent = y.t;
        out.residual = ei_last * y.k - tip_moment * alpha;
        out.d_residual = ei_last * y.dk;
        out.d_theta = cross2(&y.t, &y.dt);
        out.conjugate_point_m = conjugate_point_m;
        out.cables_m = cables;
        out.finite = out.residual.is_finite() && out.cables_m.iter().all(|c| c.is_finite());
        out
    }

    fn shape_point(&self, s: T, y: &State<T>) -> ShapePoint<T> {
        let frame = self.frame(&y.t);
        ShapePoint {
            s_m: s,
            position_m: self.position(&y.r),
            rotation: frame,
            strain_per_m: frame.tr_mul(&self.plane.normal) * y.k,
        }
    }

    /// Newton on `k(0)` at load scale `alpha` from `k0`, with backtracking and a trust region.
    fn newton(
        &self,
        load: &TipLoad<T>,
        alpha: T,
        mut k0: T,
        settings: &ShootingSettings<T>,
        work: &mut (u16, u16),
    ) -> (T, Sweep<T>, Termination) {
        let length = self.model.length_m();
        let ei_ref = self
            .sections
            .iter()
            .fold(T::max_value().unwrap_or_else(T::one), |m, s| m.min(s.0));
        let scale = ei_ref / length;
        let max_step = settings.max_rotation_step_rad / length;
        let mut sw = self.sweep(k0, load, alpha, None);
        work.1 = work.1.saturating_add(1);
        for _ in 0..settings.max_iterations {
            if !sw.finite {
                return (k0, sw, Termination::NonFinite);
            }
            let relative = (k0.abs() * length).max(T::one());
            if sw.residual.abs() / scale <= settings.tolerance * relative {
                return (k0, sw, Termination::Converged);
            }
            if sw.d_residual == T::zero() {
                return (k0, sw, Termination::Singular);
            }
            let mut step = -sw.residual / sw.d_residual;
            if step.abs() > max_step {
                step = max_step * step.signum();
            }
            // At the rounding floor: the correction turns the base, and moves the tip, by less than
            // the tolerance (the tip test matters on a badly conditioned rod, where a small turn of
            // the base still swings the tip).
            let tip_move = (sw.d_tip * step).norm();
            let at_floor = step.abs() * length <= settings.tolerance * relative
                && tip_move <= settings.tolerance * length * relative;
            if at_floor && tip_move <= settings.tolerance * length {
                return (k0, sw, Termination::Converged);
            }
            work.0 = work.0.saturating_add(1);
            let mut accepted = false;
            let mut t = T::one();
            for _ in 0..8 {
                let trial = self.sweep(k0 + step * t, load, alpha, None);
                work.1 = work.1.saturating_add(1);
                if trial.finite && trial.residual.abs() < sw.residual.abs() {
                    (k0, sw) = (k0 + step * t, trial);
                    accepted = true;
                    break;
                }
                t *= T::lit(0.5);
            }
            if !accepted {
                // At the rounding floor a correction that no longer helps means done.
                let termination = if at_floor {
                    Termination::Converged
                } else {
                    Termination::Stalled
                };
                return (k0, sw, termination);
            }
        }
        (k0, sw, Termination::IterationLimit)
    }

    fn verdict(&self, load: &TipLoad<T>, sw: &Sweep<T>) -> Stability<T> {
        if !self.model.conservative(&load.moment_nm) {
            Stability::NonConservative
        } else if let Some(s) = sw.conjugate_point_m {
            Stability::ConjugatePoint(s)
        } else if sw.d_residual / sw.d_theta <= T::zero() {
            Stability::FreeEndUnstable
        } else {
            Stability::Stable
        }
    }

    /// The equilibrium under `load`, by the 3D solve's strategy: Newton on `k(0)` from the capped
    /// small-deflection guess, and if that fails or lands on an unstable equilibrium, load
    /// continuation from the unloaded rod. The answer is an [`crate::Equilibrium`] like the 3D
    /// solve's; a failure is reported, not hidden.
    ///
    /// # Errors
    /// [`ModelError::OutOfRange`] when `load` leaves the plane (a force across it or a moment not
    /// along its normal): the reduction would drop that part. Use [`plane_of`] for the load, or the
    /// 3D solve.
    pub fn solve(
        &self,
        load: &TipLoad<T>,
        settings: &ShootingSettings<T>,
    ) -> Result<crate::Equilibrium<T>, ModelError> {
        finite_vec(&load.force_n, "tip force")?;
        finite_vec(&load.moment_nm, "tip moment")?;
        let n = self.plane.normal;
        let tol = T::lit(PLANE_TOLERANCE);
        let across = load.force_n.dot(&n).abs() > tol * (T::one() + load.force_n.norm());
        let askew = (load.moment_nm - n * load.moment_nm.dot(&n)).norm()
            > tol * (T::one() + load.moment_nm.norm());
        if across || askew {
            return Err(ModelError::OutOfRange("tip load (it leaves the plane)"));
        }
        crate::error::positive(settings.tolerance, "solver tolerance")?;
        let model = self.model;
        let length = model.length_m();
        let local_normal = model.rod().base_orientation.tr_mul(&self.plane.normal);
        let guess = model.linear_guess(load, T::one()).dot(&local_normal);
        let limit = T::lit(2.5);
        let angle = guess.abs() * length;
        let capped = if angle > limit {
            guess * limit / angle
        } else {
            guess
        };
        let mut work = (0u16, 0u16);
        let accept = |sw: &Sweep<T>, termination: Termination| {
            termination.is_success()
                && (!settings.check_stability || self.verdict(load, sw).is_acceptable())
        };
        let (mut k0, mut sw, mut termination) =
            self.newton(load, T::one(), capped, settings, &mut work);
        let mut load_steps = 0u16;
        if !accept(&sw, termination) {
            // Load continuation with a secant predictor, as in the 3D solve.
            let (mut alpha, mut k) = (T::zero(), T::zero());
            let (mut prev_alpha, mut prev_k) = (T::zero(), T::zero());
            let mut step = if angle > limit {
                (limit / angle).min(T::lit(0.5))
            } else {
                T::lit(0.25)
            };
            termination = Termination::ContinuationFailed;
            while load_steps < settings.max_load_steps && step >= T::lit(1.0 / 4096.0) {
                let target = (alpha + step).min(T::one());
                let predicted = if alpha > prev_alpha {
                    k + (k - prev_k) * ((target - alpha) / (alpha - prev_alpha))
                } else {
                    capped * target
                };
                load_steps += 1;
                let (k_new, sw_new, t) = self.newton(load, target, predicted, settings, &mut work);
                let near = (k_new - predicted).abs() * length <= T::lit(0.5);
                if t.is_success() && near && self.verdict(load, &sw_new).is_acceptable() {
                    (prev_alpha, prev_k, alpha, k) = (alpha, k, target, k_new);
                    if alpha >= T::one() {
                        (k0, sw, termination) = (k_new, sw_new, t);
                        break;
                    }
                    step *= T::lit(1.5);
                } else {
                    step *= T::lit(0.5);
                }
            }
        }
        let mut stability = Stability::Unchecked;
        if termination.is_success() && settings.check_stability {
            stability = self.verdict(load, &sw);
            if stability.is_acceptable() {
                // Out of the plane (bending across it with twist: lateral buckling) the reduction sees
                // nothing, so the answer gets the 3D test: one sweep with the Jacobi fields.
                work.1 = work.1.saturating_add(1);
                let u0 = local_normal * k0;
                let full = crate::integrate::sweep(
                    model,
                    &model.inputs(&u0, load, T::one()),
                    crate::integrate::Tangents::base_strain(true),
                    None,
                );
                stability =
                    crate::stability::of_sweep(model.conservative(&load.moment_nm), &full, length);
            }
            if !stability.is_acceptable() {
                termination = Termination::Unstable;
            }
        }
        let ei_ref = self
            .sections
            .iter()
            .fold(T::max_value().unwrap_or_else(T::one), |m, s| m.min(s.0));
        let mut cable_lengths_m = heapless::Vec::new();
        for c in sw.cables_m.iter().take(model.rod().cables.len()) {
            // Cannot overflow: at most MAX_CABLES cables.
            let _ = cable_lengths_m.push(*c);
        }
        Ok(crate::Equilibrium {
            base_strain_per_m: local_normal * k0,
            load: *load,
            tip_position_m: self.position(&sw.tip),
            tip_rotation: self.frame(&sw.tangent),
            cable_lengths_m,
            report: SolveReport {
                termination,
                iterations: work.0,
                sweeps: work.1,
                residual: sw.residual.abs() * length / ei_ref,
                load_steps,
                stability,
            },
        })
    }

    /// The shape of a planar equilibrium at the arc lengths `s_m` (increasing, within `[0, L]`).
    pub fn shape(
        &self,
        equilibrium: &crate::Equilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        if out.len() < s_m.len() {
            return Err(ModelError::Mismatch("shape queries and output buffer"));
        }
        let mut previous = T::zero();
        for &s in s_m {
            crate::error::finite(s, "shape arc length")?;
            if s < previous || s > self.model.length_m() {
                return Err(ModelError::OutOfRange("shape arc length"));
            }
            previous = s;
        }
        let local_normal = self.model.rod().base_orientation.tr_mul(&self.plane.normal);
        let k0 = equilibrium.base_strain_per_m.dot(&local_normal);
        let mut sink = ShapeSink {
            s_m,
            out,
            written: 0,
        };
        let sw = self.sweep(k0, &equilibrium.load, T::one(), Some(&mut sink));
        if !sw.finite {
            return Err(ModelError::NonFinite("sweep result"));
        }
        Ok(sink.written)
    }
}
