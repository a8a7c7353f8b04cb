//! Jump conditions at a breakpoint of zero length (thesis ch. 3.4-3.5; MODEL.md "Several sections").
//!
//! Position and frame are continuous. A point force makes `n` jump; that is already inside the
//! distal force of each interval. A change of stiffness and a point moment `tau` make the strain jump:
//! the moment `m = R C u` satisfies `m(s+) = m(s-) - tau`, so `u(s+) = C+^-1 (C- u(s-) - R^T tau)`.

use nalgebra::Vector3;

use crate::Scalar;
use crate::constitutive::Compliance;

/// Strain just distal of a node; `tau_local` is `R^T tau` (body frame).
#[inline]
pub(crate) fn strain_after<T: Scalar>(
    proximal: &Compliance<T>,
    distal: &Compliance<T>,
    tau_local: &Vector3<T>,
    u: &Vector3<T>,
) -> Vector3<T> {
    distal
        .c_inv
        .component_mul(&(proximal.c.component_mul(u) - tau_local))
}

/// The same jump for a perturbation `(d_theta, d_u)`: `d(R^T tau) = (R^T tau) x d_theta`.
#[inline]
pub(crate) fn strain_tangent_after<T: Scalar>(
    proximal: &Compliance<T>,
    distal: &Compliance<T>,
    tau_local: &Vector3<T>,
    d_theta: &Vector3<T>,
    d_u: &Vector3<T>,
) -> Vector3<T> {
    distal
        .c_inv
        .component_mul(&(proximal.c.component_mul(d_u) - tau_local.cross(d_theta)))
}
