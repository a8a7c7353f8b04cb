//! Tendon path lengths and the unstretched lengths they need (MODEL.md §6.2).
//!
//! The path runs in straight chords from the fixed hole in the base plate, `P_0 = p(0) + R(0) d`,
//! through the hole `P_k = p(s_k) + R(s_k) d` of every guide up to the termination; a slack
//! tendon's path is the same geometric length. Chord `k` carries the spool's tension changed by
//! the capstan factor of every hole before it (`guide_force.rs`), and stretches by
//! `l tau / (E_t A_t)`: the unstretched length the equilibrium needs, spool to termination, is
//! `feed / (1 + tau_spool / E_t A_t) + sum l_k / (1 + tau_k / E_t A_t)`.

use nalgebra::{Matrix3, Vector3};

use super::guide_force::{GuidePose, hole, wrap_and_change};
use super::{MAX_TENDONS, Tendons};
use crate::Scalar;

/// Each tendon's path, m, and the unstretched length it needs, m.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lengths<T> {
    pub path_m: [T; MAX_TENDONS],
    pub unstretched_m: [T; MAX_TENDONS],
}

/// The lengths of every tendon at spool tensions `tensions_n`, from the base pose and the guides'
/// poses (`guides[k]` at guide `k`, in order). `None` if a guide is missing.
pub(crate) fn lengths<T: Scalar>(
    tendons: &Tendons<T>,
    tensions_n: &[T],
    base_position_m: &Vector3<T>,
    base_rotation: &Matrix3<T>,
    guides: &[GuidePose<T>],
) -> Option<Lengths<T>> {
    let mut out = Lengths {
        path_m: [T::zero(); MAX_TENDONS],
        unstretched_m: [T::zero(); MAX_TENDONS],
    };
    let zero = Vector3::zeros();
    for (j, (r, t)) in tendons.routed.iter().zip(tendons.tendons()).enumerate() {
        let spool = tensions_n.get(j).copied().unwrap_or_else(T::zero);
        let mut prev = base_position_m + base_rotation * r.offset_m;
        let mut direction = base_rotation.column(2).into_owned();
        let mut tau = spool;
        let (mut path, mut unstretched) = (T::zero(), t.unstretched_m(t.feed_length_m, spool));
        for guide in guides.get(..=r.end_guide)? {
            let hole = hole(guide, &r.offset_m);
            let chord = hole - prev;
            let l = chord.norm();
            let u = chord / l;
            if r.capstan_per_rad != T::zero() {
                let (theta, _) = wrap_and_change(&direction, &zero, &u, &zero);
                tau *= (r.capstan_per_rad * theta).exp();
            }
            path += l;
            unstretched += t.unstretched_m(l, tau);
            prev = hole;
            direction = u;
        }
        if let (Some(p), Some(u)) = (out.path_m.get_mut(j), out.unstretched_m.get_mut(j)) {
            *p = path;
            *u = unstretched;
        }
    }
    Some(out)
}

/// The unstretched lengths of tendons with one tension all along (no friction) and paths `path_m`:
/// `(feed + path) / (1 + tau / E_t A_t)`, for the variants that do not resolve the chords.
pub(crate) fn uniform_unstretched<T: Scalar>(
    tendons: &Tendons<T>,
    tensions_n: &[T],
    path_m: &[T],
) -> heapless::Vec<T, MAX_TENDONS> {
    let mut out = heapless::Vec::new();
    for ((t, tau), path) in tendons.tendons().iter().zip(tensions_n).zip(path_m) {
        // Cannot overflow: at most MAX_TENDONS.
        let _ = out.push(t.unstretched_m(t.feed_length_m + *path, *tau));
    }
    out
}
