//! Continuous routing (Rucker & Webster 2011; MODEL.md §6.8): the cross-section's constitutive law
//! when tendons run along the backbone, straight and parallel to it at constant body offsets `r_i`.
//!
//! The rod and its tendons are cut together: the composite force and moment `N`, `M` (global) are the
//! rod's own `n`, `m` plus each tendon's tension along its tangent and that tension's moment about
//! the backbone point,
//!
//! ```text
//! N = n + sum_i tau_i R g_i,      M = m + sum_i tau_i R (r_i x g_i),
//! g_i = w_i / |w_i|,              w_i = v + u x r_i      (the tendon's tangent p_i' = R w_i, body frame)
//! ```
//!
//! and obey the rod's dead-load equations (the tendons' pull on the backbone is internal to the
//! composite; `crate::ode` `tendon_continuous.rs`). Given `N`, `M` the rod's strains solve, in the
//! body frame (`n_l = R^T N`, `m_l = R^T M`),
//!
//! ```text
//! F(v, u) = ( D (v - e3) + sum tau_i g_i - n_l,   C u + sum tau_i r_i x g_i - m_l ) = 0
//! ```
//!
//! (Kirchhoff: `v = e3`, the first block drops), by Newton from the straight tendons' `g_i = e3`,
//! with the Jacobian (`P_i = (I - g_i g_i^T) / |w_i|`, `dw_i = dv - hat(r_i) du`)
//!
//! ```text
//! J = [ D + sum tau P_i             -sum tau P_i hat(r_i)          ]
//!     [ sum tau hat(r_i) P_i         C - sum tau hat(r_i) P_i hat(r_i) ]
//! ```
//!
//! symmetric positive definite (`diag(D, C)` plus `sum tau B_i^T P_i B_i`, `B_i = [I, -hat(r_i)]`).
//! Its inverse maps a change of `(n_l, m_l)` to the change of `(v, u)`: the tangents' constitutive law.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::{MAX_TENDONS, Tendons};
use crate::Scalar;
use crate::constitutive::Compliance;

/// Iterations of one strain solve (chord and Newton steps, and the passes that switch).
const MAX_STRAIN_ITERATIONS: usize = 24;

/// The shortest tendon tangent `|w_i|` accepted (per unit reference length): below it the backbone
/// curves about a centre inside the tendon's offset, which no rod of this model reaches.
const MIN_TENDON_SPEED: f64 = 1e-2;

/// The tendons routed along one stretch of the backbone: their body offsets and tensions (at the
/// load scale); those that terminated proximally are left out. A slack tendon (zero tension) loads
/// nothing but keeps its path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Routing<T> {
    offsets_m: [Vector3<T>; MAX_TENDONS],
    tensions_n: [T; MAX_TENDONS],
    /// Which tendon (index in the set) each entry is.
    index: [usize; MAX_TENDONS],
    count: usize,
}

impl<T: Scalar> Routing<T> {
    /// The tendons of `tendons` at tensions `tensions_n` that run past arc length `s_m` (their
    /// termination lies distal of it).
    pub(crate) fn along(tendons: &Tendons<T>, tensions_n: &[T], s_m: T) -> Self {
        let mut out = Self {
            offsets_m: [Vector3::zeros(); MAX_TENDONS],
            tensions_n: [T::zero(); MAX_TENDONS],
            index: [0; MAX_TENDONS],
            count: 0,
        };
        for (j, (r, tau)) in tendons.routed.iter().zip(tensions_n).enumerate() {
            let end = tendons.guide_s_m.get(r.end_guide).copied();
            if end.is_none_or(|e| e <= s_m) {
                continue;
            }
            if let (Some(o), Some(t), Some(i)) = (
                out.offsets_m.get_mut(out.count),
                out.tensions_n.get_mut(out.count),
                out.index.get_mut(out.count),
            ) {
                *o = r.offset_m;
                *t = *tau;
                *i = j;
                out.count += 1;
            }
        }
        out
    }

    /// `(tendon index, body offset, tension)` of each tendon routed here.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (usize, &Vector3<T>, T)> {
        self.index
            .iter()
            .zip(&self.offsets_m)
            .zip(&self.tensions_n)
            .take(self.count)
            .map(|((i, r), t)| (*i, r, *t))
    }

    /// Whether both route the same tendons at the same tensions.
    pub(crate) fn same_tendons(&self, other: &Self) -> bool {
        self.count == other.count
            && self.index == other.index
            && self.tensions_n == other.tensions_n
    }

    /// The tendons' moment about the backbone while they run along its tangent,
    /// `sum tau_i r_i x e3` (body frame), N m.
    pub(crate) fn straight_moment_nm(&self) -> Vector3<T> {
        self.iter().fold(Vector3::zeros(), |m, (_, r, tau)| {
            m + r.cross(&Vector3::z()) * tau
        })
    }

    /// The sum of the tensions, N.
    pub(crate) fn total_tension_n(&self) -> T {
        self.iter().fold(T::zero(), |s, (_, _, tau)| s + tau)
    }
}

/// One section's stiffnesses for the strain solve.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Section<T> {
    /// `C = diag(E I1, E I2, G J)`, N m^2.
    pub c: Vector3<T>,
    pub c_inv: Vector3<T>,
    /// `D = diag(G A, G A, E A)`, N.
    pub d: Vector3<T>,
    pub d_inv: Vector3<T>,
    /// Inextensible and unshearable: `v = e3`.
    pub kirchhoff: bool,
}

impl<T: Scalar> Section<T> {
    pub(crate) fn new(comp: &Compliance<T>, kirchhoff: bool) -> Self {
        Self {
            c: comp.c,
            c_inv: comp.c_inv,
            d: comp.d_inv.map(|x| T::one() / x),
            d_inv: comp.d_inv,
            kirchhoff,
        }
    }
}

/// The rod's strains under composite force and moment, and what the tendons take of them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Strains<T> {
    /// Shear and stretch `v`, body frame.
    pub v: Vector3<T>,
    /// Bending and torsion `u`, body frame, 1/m.
    pub u: Vector3<T>,
    /// The rod's own internal force, body frame, N (the composite's less the tendons').
    pub n_rod: Vector3<T>,
    /// Each routed tendon's length per unit reference length, `|v + u x r_i|`, by tendon index
    /// (zero for tendons not routed here).
    pub speed: [T; MAX_TENDONS],
}

impl<T: Scalar> Strains<T> {
    /// Strains that make every later result non-finite: a solve that failed.
    pub(crate) fn failed() -> Self {
        let nan = Vector3::repeat(T::lit(f64::NAN));
        Self {
            v: nan,
            u: nan,
            n_rod: nan,
            speed: [T::lit(f64::NAN); MAX_TENDONS],
        }
    }
}

/// The residual `F(v, u)` at `v = e3 + e` under `composite = (n_l, m_l)`, and the tendons' total
/// force (body); with `jacobian`, writes `J` there.
fn evaluate<T: Scalar>(
    sec: &Section<T>,
    routing: &Routing<T>,
    composite: &SVector<T, 6>,
    e: &Vector3<T>,
    u: &Vector3<T>,
    speed: &mut [T; MAX_TENDONS],
    jacobian: Option<&mut SMatrix<T, 6, 6>>,
) -> Option<(SVector<T, 6>, Vector3<T>)> {
    let n_l = composite.fixed_rows::<3>(0);
    let m_l = composite.fixed_rows::<3>(3);
    let v = e + Vector3::z();
    let mut tendon_force = Vector3::zeros();
    let mut tendon_moment = Vector3::zeros();
    let mut j11 = Matrix3::zeros();
    let mut j12 = Matrix3::zeros();
    let mut j22 = Matrix3::zeros();
    let with_jacobian = jacobian.is_some();
    for (i, r, tau) in routing.iter() {
        let w = v + u.cross(r);
        let len = w.norm();
        if len < T::lit(MIN_TENDON_SPEED) || !len.is_finite() {
            return None;
        }
        if let Some(s) = speed.get_mut(i) {
            *s = len;
        }
        if tau == T::zero() {
            continue;
        }
        let g = w / len;
        tendon_force += g * tau;
        tendon_moment += r.cross(&g) * tau;
        if with_jacobian {
            let p = (Matrix3::identity() - g * g.transpose()) * (tau / len);
            let hat = r.cross_matrix();
            let hp = hat * p;
            j11 += p;
            // -tau P hat(r) = tau (hat(r) P)^T: P is symmetric and hat(r) skew.
            j12 += hp.transpose();
            j22 -= hp * hat;
        }
    }
    let mut f = SVector::<T, 6>::zeros();
    if !sec.kirchhoff {
        let f1 = sec.d.component_mul(e) + tendon_force - n_l;
        f.fixed_rows_mut::<3>(0).copy_from(&f1);
    }
    let f2 = sec.c.component_mul(u) + tendon_moment - m_l;
    f.fixed_rows_mut::<3>(3).copy_from(&f2);
    if let Some(j) = jacobian {
        j.fill(T::zero());
        if sec.kirchhoff {
            // `v = e3`: the first block is `v - e3 = 0`.
            j.fixed_view_mut::<3, 3>(0, 0).fill_with_identity();
        } else {
            j11 += Matrix3::from_diagonal(&sec.d);
            j.fixed_view_mut::<3, 3>(0, 0).copy_from(&j11);
            j.fixed_view_mut::<3, 3>(0, 3).copy_from(&j12);
        }
        // sum tau hat(r) P = (sum tau (hat(r) P)^T)^T.
        j.fixed_view_mut::<3, 3>(3, 0).copy_from(&j12.transpose());
        j22 += Matrix3::from_diagonal(&sec.c);
        j.fixed_view_mut::<3, 3>(3, 3).copy_from(&j22);
    }
    Some((f, tendon_force))
}

/// `d(v, u) / d(n_l, m_l)` from the strain solve's Jacobian `J` at its answer.
///
/// For a Cosserat rod `J^-1`, by blocks: `J = diag(D, C) + sum tau_i G_i P_i G_i^T` with
/// `P_i = (I - g_i g_i^T) / |w_i|` and `G_i = (I; hat(r_i))` is symmetric, and positive definite
/// for positive stiffnesses and tensions of at least zero; so are its force block `A` and the
/// Schur complement `S = M - K^T A^-1 K` of its moment block `M` (`K` the upper right block), and
/// `J^-1 = (A^-1 + X S^-1 X^T, -X S^-1; -S^-1 X^T, S^-1)` with `X = A^-1 K`: two 3x3 inverses.
/// For a Kirchhoff rod `v = e3` whatever the force, and `u` follows the moment through the
/// moment block alone: `(0, 0; 0, M^-1)`. `None` if a block is singular.
fn strain_map<T: Scalar>(sec: &Section<T>, j: &SMatrix<T, 6, 6>) -> Option<SMatrix<T, 6, 6>> {
    let moment_block = j.fixed_view::<3, 3>(3, 3).into_owned();
    let mut out = SMatrix::<T, 6, 6>::zeros();
    if sec.kirchhoff {
        out.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&moment_block.try_inverse()?);
        return Some(out);
    }
    let a_inv = j.fixed_view::<3, 3>(0, 0).into_owned().try_inverse()?;
    let b = j.fixed_view::<3, 3>(0, 3).into_owned();
    let x = a_inv * b;
    let s_inv = (moment_block - b.tr_mul(&x)).try_inverse()?;
    let upper_right = -(x * s_inv);
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(a_inv - upper_right * x.transpose()));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&upper_right);
    out.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&upper_right.transpose());
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&s_inv);
    Some(out)
}

/// `J^-1` at the straight tendons (`v = e3`, `u = 0`, every `g_i = e3`): the chord iteration's
/// matrix, the same along a section wherever the same tendons run (a sweep inverts it once there,
/// `RodOde::next_field`). `None` if singular (never: `J` is positive definite).
pub(crate) fn chord_matrix<T: Scalar>(
    sec: &Section<T>,
    routing: &Routing<T>,
) -> Option<SMatrix<T, 6, 6>> {
    let mut j = SMatrix::<T, 6, 6>::zeros();
    let zero = Vector3::zeros();
    let mut speed = [T::zero(); MAX_TENDONS];
    evaluate(
        sec,
        routing,
        &SVector::zeros(),
        &zero,
        &zero,
        &mut speed,
        Some(&mut j),
    )?;
    j.try_inverse()
}

/// Solves `F(v, u) = 0` for the rod's strains under the composite force `n_l` and moment `m_l`
/// (body frame), from the straight tendons' guess: chord steps with `chord` (from
/// [`chord_matrix`]; they contract by about `tau r^2 / E I` times the tendons' tilt `|u| r`), and
/// Newton steps once a chord step gains less than a factor four. With `jacobian_inverse`, writes
/// there the map from a change of `(n_l, m_l)` to the change of `(v, u)` (`J^-1` at the answer, its
/// force columns zero for a Kirchhoff rod). `None` when it does not converge, or a tendon folds
/// back on itself.
pub(crate) fn strains<T: Scalar>(
    sec: &Section<T>,
    routing: &Routing<T>,
    chord: &SMatrix<T, 6, 6>,
    n_l: &Vector3<T>,
    m_l: &Vector3<T>,
    jacobian_inverse: Option<&mut SMatrix<T, 6, 6>>,
) -> Option<Strains<T>> {
    // The straight tendons' guess: every `g_i = e3`. The unknowns are `e = v - e3` (no rounding
    // of `v`'s unit stretch, times `E A`, in the residual) and `u`.
    let total = routing.total_tension_n();
    let mut e = if sec.kirchhoff {
        Vector3::zeros()
    } else {
        sec.d_inv.component_mul(&(n_l - Vector3::z() * total))
    };
    let mut u = sec
        .c_inv
        .component_mul(&(m_l - routing.straight_moment_nm()));
    let arm = routing
        .iter()
        .fold(T::zero(), |a, (_, r, tau)| a + r.norm() * tau);
    let eps = T::default_epsilon() * T::lit(32.0);
    let force_scale = n_l.norm() + total;
    let moment_scale = m_l.norm() + arm;
    let mut composite = SVector::<T, 6>::zeros();
    composite.fixed_rows_mut::<3>(0).copy_from(n_l);
    composite.fixed_rows_mut::<3>(3).copy_from(m_l);
    let mut speed = [T::zero(); MAX_TENDONS];
    let mut newton = false;
    let mut last = T::max_value().unwrap_or_else(T::one);
    let mut j = SMatrix::<T, 6, 6>::zeros();
    for _ in 0..MAX_STRAIN_ITERATIONS {
        let (f, tendon_force) = evaluate(
            sec,
            routing,
            &composite,
            &e,
            &u,
            &mut speed,
            newton.then_some(&mut j),
        )?;
        // Each block against its rounding floor.
        let force_tol = eps * (force_scale + sec.d.component_mul(&e).norm());
        let moment_tol = eps * (moment_scale + sec.c.component_mul(&u).norm());
        let (f1, f2) = (f.fixed_rows::<3>(0).norm(), f.fixed_rows::<3>(3).norm());
        if f1 <= force_tol && f2 <= moment_tol {
            if let Some(out) = jacobian_inverse {
                evaluate(sec, routing, &composite, &e, &u, &mut speed, Some(&mut j))?;
                *out = strain_map(sec, &j)?;
            }
            return Some(Strains {
                v: e + Vector3::z(),
                u,
                n_rod: n_l - tendon_force,
                speed,
            });
        }
        let tiny = T::lit(f64::from(f32::MIN_POSITIVE));
        let size = (f1 / force_tol.max(tiny)).max(f2 / moment_tol.max(tiny));
        if !newton && size > last * T::lit(0.25) {
            // The chord contracts too slowly: Newton from here (its Jacobian on the next pass).
            newton = true;
            last = size;
            continue;
        }
        let step = if newton {
            j.lu().solve(&(-f))?
        } else {
            -(chord * f)
        };
        if !crate::scalar::all_finite(&step) {
            return None;
        }
        e += step.fixed_rows::<3>(0);
        u += step.fixed_rows::<3>(3);
        last = size;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn routing() -> Routing<f64> {
        let mut r = Routing {
            offsets_m: [Vector3::zeros(); MAX_TENDONS],
            tensions_n: [0.0; MAX_TENDONS],
            index: [0; MAX_TENDONS],
            count: 3,
        };
        for (k, (angle, tau)) in [(0.3, 2.0), (2.0, 1.5), (4.1, 0.7)].iter().enumerate() {
            r.offsets_m[k] = Vector3::new(f64::cos(*angle), f64::sin(*angle), 0.0) * 0.008;
            r.tensions_n[k] = *tau;
            r.index[k] = k;
        }
        r
    }

    fn section(kirchhoff: bool) -> Section<f64> {
        let c = Vector3::new(0.01, 0.012, 0.008);
        let d = Vector3::new(3e4, 3e4, 8e4);
        Section {
            c,
            c_inv: c.map(|x| 1.0 / x),
            d,
            d_inv: d.map(|x| 1.0 / x),
            kirchhoff,
        }
    }

    /// The solve satisfies the composite balance, and its `J^-1` is the strains' derivative.
    #[test]
    fn tendon_strain_solve_and_its_derivative() {
        for kirchhoff in [false, true] {
            let sec = section(kirchhoff);
            let routing = routing();
            let n_l = Vector3::new(0.3, -0.2, -1.0);
            let m_l = Vector3::new(0.004, -0.006, 0.001);
            let chord = chord_matrix(&sec, &routing).unwrap();
            let mut jinv = SMatrix::<f64, 6, 6>::zeros();
            let s = strains(&sec, &routing, &chord, &n_l, &m_l, Some(&mut jinv)).unwrap();
            let mut force = Vector3::zeros();
            let mut moment = sec.c.component_mul(&s.u);
            for (_, r, tau) in routing.iter() {
                let g = (s.v + s.u.cross(r)).normalize();
                force += g * tau;
                moment += r.cross(&g) * tau;
            }
            assert!((moment - m_l).norm() < 1e-15, "{kirchhoff}");
            if !kirchhoff {
                // `v` holds its unit stretch: `E A` times its rounding.
                assert!((sec.d.component_mul(&(s.v - Vector3::z())) + force - n_l).norm() < 1e-10);
            }
            assert!((s.n_rod - (n_l - force)).norm() < 1e-15);
            for k in 0..6 {
                let mut dn = Vector3::zeros();
                let mut dm = Vector3::zeros();
                if k < 3 {
                    dn[k] = 1e-3;
                } else {
                    dm[k - 3] = 1e-5;
                }
                let plus = strains(&sec, &routing, &chord, &(n_l + dn), &(m_l + dm), None).unwrap();
                let minus =
                    strains(&sec, &routing, &chord, &(n_l - dn), &(m_l - dm), None).unwrap();
                let mut fd = SVector::<f64, 6>::zeros();
                fd.fixed_rows_mut::<3>(0)
                    .copy_from(&((plus.v - minus.v) / 2.0));
                fd.fixed_rows_mut::<3>(3)
                    .copy_from(&((plus.u - minus.u) / 2.0));
                let mut d = SVector::<f64, 6>::zeros();
                d.fixed_rows_mut::<3>(0).copy_from(&dn);
                d.fixed_rows_mut::<3>(3).copy_from(&dm);
                let lin = jinv * d;
                assert!(
                    (fd - lin).norm() <= 1e-6 * lin.norm() + 1e-15,
                    "{kirchhoff} {k}: {fd:?} {lin:?}"
                );
            }
        }
    }

    /// The block inverse is LU's inverse of the whole Jacobian (with the force columns zero for a
    /// Kirchhoff rod), at tendons tilted well off the backbone.
    #[test]
    fn tendon_strain_map_is_the_jacobians_inverse() {
        for kirchhoff in [false, true] {
            let sec = section(kirchhoff);
            let routing = routing();
            let mut j = SMatrix::<f64, 6, 6>::zeros();
            let mut speed = [0.0; MAX_TENDONS];
            let e = Vector3::new(1e-5, -2e-5, 3e-5);
            let u = Vector3::new(8.0, -5.0, 2.0);
            let composite = SVector::<f64, 6>::zeros();
            evaluate(&sec, &routing, &composite, &e, &u, &mut speed, Some(&mut j)).unwrap();
            let mut reference = j.lu().try_inverse().unwrap();
            if kirchhoff {
                reference.fixed_columns_mut::<3>(0).fill(0.0);
            }
            let map = strain_map(&sec, &j).unwrap();
            // Per block: the blocks' scales differ by orders of magnitude (E A against E I).
            for (r, c) in [(0, 0), (0, 3), (3, 0), (3, 3)] {
                let want = reference.fixed_view::<3, 3>(r, c).into_owned();
                let got = map.fixed_view::<3, 3>(r, c).into_owned();
                assert!(
                    (got - want).norm() <= 1e-12 * want.norm(),
                    "{kirchhoff} block ({r}, {c}): {got:?} {want:?}"
                );
            }
        }
    }
}
