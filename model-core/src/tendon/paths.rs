//! Tendon path lengths (MODEL.md §6.2): straight chords from the fixed hole in the base plate,
//! `P_0 = p(0) + R(0) d`, through the hole `P_k = p(s_k) + R(s_k) d` of every guide up to the
//! termination. A slack tendon's path is the same geometric length.

use nalgebra::{Matrix3, Vector3};

use super::{MAX_TENDONS, Tendons};
use crate::Scalar;
use crate::shape::ShapePoint;

/// Each tendon's path length, m, from the base pose and the guides' poses (`guides[k]` at guide
/// `k`, in order); zero beyond the tendons. `None` if a guide is missing.
pub(crate) fn path_lengths<T: Scalar>(
    tendons: &Tendons<T>,
    base_position_m: &Vector3<T>,
    base_rotation: &Matrix3<T>,
    guides: &[ShapePoint<T>],
) -> Option<[T; MAX_TENDONS]> {
    let mut out = [T::zero(); MAX_TENDONS];
    for (length, r) in out.iter_mut().zip(&tendons.routed) {
        let mut prev = base_position_m + base_rotation * r.offset_m;
        let mut sum = T::zero();
        for guide in guides.get(..=r.end_guide)? {
            let hole = guide.position_m + guide.rotation * r.offset_m;
            sum += (hole - prev).norm();
            prev = hole;
        }
        *length = sum;
    }
    Some(out)
}
