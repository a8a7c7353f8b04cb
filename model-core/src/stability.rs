//! Elastic stability of an equilibrium of the clamped-free rod under dead loads.
//!
//! A converged shooting solve can land on an unstable equilibrium (a rod standing upside-down under
//! its load). The second variation of the energy decides: with the internal force fixed by the loads,
//! the Jacobi fields are the sweep's tangents seeded by the base strain, `H(s) = d theta(s) / d u(0)`
//! and `M(s) = d m(s) / d u(0)` (body frame, `M(L)` is the shooting Jacobian). The equilibrium is stable
//! when (Jacobi's condition for a fixed-free interval):
//!
//! 1. no conjugate point on `(0, L]` (`H(s)` never singular), and
//! 2. the free-end Riccati matrix `W = M(L) H(L)^-1` has a positive definite symmetric part.
//!
//! Conjugate points are found on the grid (`ConjugateTrack`) two ways. A sign change of `det H`
//! finds an odd number in a step. An even number (two at once: a rod pushed back along itself past
//! its buckling load bends in and across the plane alike, and near such symmetry two crossings fall
//! in one step) leaves `det H` positive, so the Riccati matrix `W(s) = M(s) H(s)^-1`, `M = C dU`, is
//! watched too. It is symmetric (the fields are Lagrangian), and it obeys `W' = -W C^-1 W + ...`:
//! an eigenvalue heads to minus infinity at a conjugate point and returns from plus infinity, and
//! once below `-c` with `c` large it can only keep falling. With `c = (min C) / (2 h)`, `h` the step,
//! every eigenvalue that blows up within a step is below `-c` at the step's start and above it at the
//! end, and nothing else crosses `-c` upward while the step resolves the rod's bending wavelength
//! (the condition RK4 needs anyway). So a conjugate point is a drop in the count of eigenvalues below
//! `-c` between grid points (both counted with the same `c`), by Descartes' rule on `W + c I`'s
//! characteristic polynomial, exact for a symmetric matrix.
//!
//! Both come from the three tangents the Newton iteration already carries: the test costs a 3x3
//! solve per step and one more at the tip.
//!
//! The energy test needs conservative loads. Dead forces (gravity, hung masses, a tip force fixed
//! in direction) are; a moment of fixed direction is not, in 3D (finite rotations do not commute:
//! Ziegler's "axial" moment), so when any moment acts the verdict is [`Stability::NonConservative`]
//! and the solve relies on load continuation alone to stay on the branch connected to the
//! unloaded rod.

use nalgebra::{Const, DimMin, Matrix3, SMatrix};

use crate::Scalar;

/// Watches the Jacobi fields along a sweep for conjugate points (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConjugateTrack<T> {
    /// The previous grid point's symmetric Riccati matrix `W` (N m / rad), the level `c` it was
    /// last counted against, and its count of eigenvalues below `-c`.
    previous: Option<(Matrix3<T>, T, usize)>,
}

impl<T: Scalar> ConjugateTrack<T> {
    pub(crate) fn new() -> Self {
        Self { previous: None }
    }

    /// Whether a conjugate point lies in the step (of `step_m`, on a section whose softest bending or
    /// torsion stiffness is `stiffness_min_nm2`) that ended at the grid point with fields `h`, `m`.
    pub(crate) fn crosses(
        &mut self,
        h: &Matrix3<T>,
        m: &Matrix3<T>,
        stiffness_min_nm2: T,
        step_m: T,
    ) -> bool {
        if h.determinant() <= T::zero() {
            return true;
        }
        let Some(h_inv) = h.try_inverse() else {
            return true;
        };
        let w = m * h_inv;
        let w = (w + w.transpose()) * T::lit(0.5);
        let c = stiffness_min_nm2 * T::lit(0.5) / step_m;
        let count = count_below(&w, c);
        // Both counts against the same level: steps change length between intervals.
        let crossed = self
            .previous
            .is_some_and(|(previous, level, previous_count)| {
                let before = if level == c {
                    previous_count
                } else {
                    count_below(&previous, c)
                };
                count < before
            });
        self.previous = Some((w, c, count));
        crossed
    }
}

/// The eigenvalues of the symmetric `w` below `-c`: the negative roots of `det(x I - (w + c I))
/// = x^3 - a2 x^2 + a1 x - a0`, which by Descartes' rule (exact when every root is real) are the sign
/// changes of `(1, a2, a1, a0)`.
fn count_below<T: Scalar>(w: &Matrix3<T>, c: T) -> usize {
    let a = w + Matrix3::identity() * c;
    let a2 = a.trace();
    let a1 = a.m11 * a.m22 - a.m12 * a.m21 + a.m11 * a.m33 - a.m13 * a.m31 + a.m22 * a.m33
        - a.m23 * a.m32;
    let a0 = a.determinant();
    let mut changes = 0;
    let mut last = T::one();
    for x in [a2, a1, a0] {
        if x != T::zero() {
            if (x > T::zero()) != (last > T::zero()) {
                changes += 1;
            }
            last = x;
        }
    }
    changes
}

/// The stability verdict on an equilibrium.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stability<T> {
    /// The test was not run.
    Unchecked,
    /// Stable: a local minimum of the energy.
    Stable,
    /// A conjugate point in the step ending at this arc length, m.
    ConjugatePoint(T),
    /// No conjugate point, but the free end has a negative stiffness direction (`W` indefinite).
    FreeEndUnstable,
    /// A moment of fixed direction acts: the loads are not conservative and the energy test does not apply.
    NonConservative,
}

impl<T> Stability<T> {
    /// `true` unless the test ran and found the equilibrium unstable.
    pub fn is_acceptable(&self) -> bool {
        matches!(self, Self::Unchecked | Self::Stable | Self::NonConservative)
    }
}

/// The verdict on Jacobi fields that split into two blocks (a planar equilibrium's in-plane and
/// out-of-plane fields, `ode/planar_lateral.rs`) from each block's: the first conjugate point of
/// either, else an unstable free end in either, else stable when both are. Loads that are not
/// conservative void the test (`NonConservative` in either); a block that found its equilibrium
/// unstable says so whatever the other's; otherwise the test is only as complete as its parts
/// (`Unchecked` in either).
pub(crate) fn of_blocks<T: Scalar>(a: Stability<T>, b: Stability<T>) -> Stability<T> {
    use Stability::*;
    match (a, b) {
        (NonConservative, _) | (_, NonConservative) => NonConservative,
        (ConjugatePoint(s), ConjugatePoint(t)) => ConjugatePoint(if t < s { t } else { s }),
        (ConjugatePoint(s), _) | (_, ConjugatePoint(s)) => ConjugatePoint(s),
        (FreeEndUnstable, _) | (_, FreeEndUnstable) => FreeEndUnstable,
        (Unchecked, _) | (_, Unchecked) => Unchecked,
        (Stable, Stable) => Stable,
    }
}

/// The verdict from the sweep's conjugate-point track, the shooting Jacobian `M(L) = de/dx0` and
/// `H(L) = d theta(L)/dx0` (both body frame). `conservative` is false when any moment acts.
///
/// Generic in the number of unknowns `K`: the 3D rod's three (`u(0)`), the planar reduction's one
/// (`k(0)`, with `H` the turn about the plane's normal).
pub(crate) fn classify<T: Scalar, const K: usize>(
    conservative: bool,
    conjugate_point_m: Option<T>,
    jacobian: &SMatrix<T, K, K>,
    tip_rotation_tangent: &SMatrix<T, K, K>,
    length_m: T,
) -> Stability<T>
where
    Const<K>: DimMin<Const<K>, Output = Const<K>>,
{
    if !conservative {
        return Stability::NonConservative;
    }
    if let Some(s) = conjugate_point_m {
        return Stability::ConjugatePoint(s);
    }
    // W = M H^-1, i.e. W^T = H^-T M^T: solve H^T W^T = M^T.
    let Some(w_t) = tip_rotation_tangent
        .transpose()
        .lu()
        .solve(&jacobian.transpose())
    else {
        return Stability::ConjugatePoint(length_m);
    };
    let symmetric = (w_t + w_t.transpose()) * T::lit(0.5);
    if symmetric.cholesky().is_some() {
        Stability::Stable
    } else {
        Stability::FreeEndUnstable
    }
}
