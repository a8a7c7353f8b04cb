//! The force of the tendons on one guide, and its linearisation (MODEL.md §6.1).
//!
//! Tendon `j` with tension `tau_j` has its hole at `P = p + R d_j` in the guide's pose `(p, R)`. At a
//! guide it passes, it pulls toward both neighbouring holes:
//! `F = tau (unit(P_next - P) - unit(P - P_prev))`; at its termination only toward the previous one:
//! `F = -tau unit(P - P_prev)`. The moment about the backbone point is `(R d) x F`. Exact for
//! zero-thickness guides and full chords: the chord between two holes pulls them together with
//! equal and opposite forces along one line.
//!
//! Linearised, with `dP = dp + R (dtheta x d)` (`dtheta` in the body frame) and
//! `d unit(a) = (da - unit(a) (unit(a) . da)) / |a|`.

use nalgebra::{Matrix3, Vector3};

use super::Routed;
use crate::Scalar;
use crate::loads::Wrench;

/// A guide's pose: backbone point and frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GuidePose<T> {
    pub position_m: Vector3<T>,
    pub rotation: Matrix3<T>,
}

/// A change of a guide's pose: position (global) and rotation (body frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PoseDelta<T> {
    pub position_m: Vector3<T>,
    pub rotation_rad: Vector3<T>,
}

impl<T: Scalar> PoseDelta<T> {
    pub(crate) fn zero() -> Self {
        Self {
            position_m: Vector3::zeros(),
            rotation_rad: Vector3::zeros(),
        }
    }
}

/// Which tendons act at guide `guide`, and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    /// Not routed here (terminated proximally).
    None,
    /// Passes through: pulls toward both neighbours.
    Passes,
    /// Terminates here.
    Ends,
}

pub(crate) fn role<T>(routed: &Routed<T>, guide: usize) -> Role {
    if guide < routed.end_guide {
        Role::Passes
    } else if guide == routed.end_guide {
        Role::Ends
    } else {
        Role::None
    }
}

/// Whether any tendon with a tension passes guide `guide` (then its force reads the next guide).
pub(crate) fn reads_next<T: Scalar>(routed: &[Routed<T>], tensions_n: &[T], guide: usize) -> bool {
    routed
        .iter()
        .zip(tensions_n)
        .any(|(r, t)| *t != T::zero() && role(r, guide) == Role::Passes)
}

fn hole<T: Scalar>(pose: &GuidePose<T>, offset: &Vector3<T>) -> Vector3<T> {
    pose.position_m + pose.rotation * offset
}

fn d_hole<T: Scalar>(pose: &GuidePose<T>, offset: &Vector3<T>, d: &PoseDelta<T>) -> Vector3<T> {
    d.position_m + pose.rotation * d.rotation_rad.cross(offset)
}

/// `unit(a)` and its change for a change `da`.
fn unit_and_change<T: Scalar>(a: &Vector3<T>, da: &Vector3<T>) -> (Vector3<T>, Vector3<T>) {
    let len = a.norm();
    let u = a / len;
    (u, (da - u * u.dot(da)) / len)
}

/// The tendons' wrench on guide `guide` at pose `cur`, with the previous hole's guide (or the base
/// plate) at `prev` and the next guide at `next` (read only where a tendon passes), and its change
/// for pose changes `d` = `(d_prev, d_cur, d_next)`; `tensions_n` already scaled.
pub(crate) fn guide_wrench<T: Scalar>(
    routed: &[Routed<T>],
    tensions_n: &[T],
    guide: usize,
    poses: [&GuidePose<T>; 3],
    d: Option<[&PoseDelta<T>; 3]>,
) -> (Wrench<T>, Wrench<T>) {
    let [prev, cur, next] = poses;
    let zero = PoseDelta::zero();
    let [dp, dc, dn] = d.unwrap_or([&zero, &zero, &zero]);
    let mut w = Wrench::zero();
    let mut dw = Wrench::zero();
    for (r, tau) in routed.iter().zip(tensions_n) {
        let role = role(r, guide);
        if *tau == T::zero() || role == Role::None {
            continue;
        }
        let tau = *tau;
        let here = hole(cur, &r.offset_m);
        let d_here = d_hole(cur, &r.offset_m, dc);
        let back = here - hole(prev, &r.offset_m);
        let d_back = d_here - d_hole(prev, &r.offset_m, dp);
        let (u_back, du_back) = unit_and_change(&back, &d_back);
        let mut f = -u_back * tau;
        let mut df = -du_back * tau;
        if role == Role::Passes {
            let ahead = hole(next, &r.offset_m) - here;
            let d_ahead = d_hole(next, &r.offset_m, dn) - d_here;
            let (u_ahead, du_ahead) = unit_and_change(&ahead, &d_ahead);
            f += u_ahead * tau;
            df += du_ahead * tau;
        }
        let arm = cur.rotation * r.offset_m;
        let d_arm = cur.rotation * dc.rotation_rad.cross(&r.offset_m);
        w.force_n += f;
        w.moment_nm += arm.cross(&f);
        dw.force_n += df;
        dw.moment_nm += d_arm.cross(&f) + arm.cross(&df);
    }
    (w, dw)
}
