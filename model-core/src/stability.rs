//! Elastic stability of an equilibrium of the clamped-free rod under dead loads.
//!
//! A converged shooting solve can land on an unstable equilibrium (a rod standing upside-down under
//! its load). The second variation of the energy decides: with the internal force fixed by the loads,
//! the Jacobi fields are the sweep's tangents seeded by the base strain, `H(s) = d theta(s) / d u(0)`
//! and `M(s) = d m(s) / d u(0)` (body frame, `M(L)` is the shooting Jacobian). The equilibrium is stable
//! when (Jacobi's condition for a fixed-free interval):
//!
//! 1. `det H(s) > 0` on `(0, L]`: no conjugate point, and
//! 2. the free-end Riccati matrix `W = M(L) H(L)^-1` has a positive definite symmetric part.
//!
//! Both come from the three tangents the Newton iteration already carries: the test costs a 3x3
//! determinant per step and one 3x3 solve at the tip.
//!
//! The energy test needs conservative loads. Dead forces (gravity, hung masses, a tip force fixed
//! in direction) are; a moment of fixed direction is not, in 3D (finite rotations do not commute:
//! Ziegler's "axial" moment), so when any moment acts the verdict is [`Stability::NonConservative`]
//! and the solve relies on load continuation alone to stay on the branch connected to the
//! unloaded rod.

use nalgebra::Matrix3;

use crate::Scalar;

/// The stability verdict on an equilibrium.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stability<T> {
    /// The test was not run.
    Unchecked,
    /// Stable: a local minimum of the energy.
    Stable,
    /// `det H` stops being positive at this arc length, m.
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

/// The verdict from the sweep's conjugate-point track, the shooting Jacobian `M(L) = de/du0` and
/// `H(L) = d theta(L)/du0` (both body frame). `conservative` is false when any moment acts.
pub(crate) fn classify<T: Scalar>(
    conservative: bool,
    conjugate_point_m: Option<T>,
    jacobian: &Matrix3<T>,
    tip_rotation_tangent: &Matrix3<T>,
    length_m: T,
) -> Stability<T> {
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
