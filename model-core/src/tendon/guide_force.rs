//! The force of the tendons on one guide, and its linearisation (MODEL.md §6.1).
//!
//! Tendon `j` has its hole at `P = p + R d_j` in the guide's pose `(p, R)`. The chord arriving from
//! the previous hole carries the tension `tau_b`; at a guide the tendon passes, it pulls toward both
//! neighbouring holes: `F = tau_a unit(P_next - P) - tau_b unit(P - P_prev)`; at its termination
//! only toward the previous one: `F = -tau_b unit(P - P_prev)`. The moment about the backbone point
//! is `(R d) x F`. Exact for zero-thickness guides and full chords.
//!
//! Frictionless, `tau_a = tau_b` all along. With capstan friction (coefficient `mu`) the tension
//! changes across each hole by `exp(c theta)`, `theta` the wrap angle between the chords and
//! `c = -mu` while the spool pulls the tendon in (`+mu` while it pays out); at the first guide the
//! base plate's hole adds its own wrap, from the tendon's entry along the base tangent.
//!
//! Linearised, with `dP = dp + R (dtheta x d)` (`dtheta` in the body frame),
//! `d unit(a) = (da - unit(a) (unit(a) . da)) / |a|` and, for `theta = atan2(|a x b|, a . b)`,
//! `d theta = (c ds - s dc) / (s^2 + c^2)`.

use nalgebra::{Matrix3, Vector3};

use super::{MAX_TENDONS, Routed};
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

/// The hole at `offset` (body frame, m) in a guide at `pose`: `p + R d`.
pub(crate) fn hole<T: Scalar>(pose: &GuidePose<T>, offset: &Vector3<T>) -> Vector3<T> {
    pose.position_m + pose.rotation * offset
}

/// The hole's move for a change `d` of the guide's pose: `dp + R (dtheta x d)`.
pub(crate) fn d_hole<T: Scalar>(
    pose: &GuidePose<T>,
    offset: &Vector3<T>,
    d: &PoseDelta<T>,
) -> Vector3<T> {
    d.position_m + pose.rotation * d.rotation_rad.cross(offset)
}

/// `unit(a)` and its change for a change `da`.
fn unit_and_change<T: Scalar>(a: &Vector3<T>, da: &Vector3<T>) -> (Vector3<T>, Vector3<T>) {
    let len = a.norm();
    let u = a / len;
    (u, (da - u * u.dot(da)) / len)
}

/// The angle between unit vectors `a` and `b`, rad, and its change.
pub(crate) fn wrap_and_change<T: Scalar>(
    a: &Vector3<T>,
    da: &Vector3<T>,
    b: &Vector3<T>,
    db: &Vector3<T>,
) -> (T, T) {
    let w = a.cross(b);
    let s = w.norm();
    let c = a.dot(b);
    let dc = da.dot(b) + a.dot(db);
    let ds = if s > T::zero() {
        w.dot(&(da.cross(b) + a.cross(db))) / s
    } else {
        T::zero()
    };
    (s.atan2(c), (c * ds - s * dc) / (s * s + c * c))
}

/// The capstan factor `exp(c theta)` across a wrap `theta` (with change `d_theta`) applied to a
/// tension `tau` (change `d_tau`): the tension beyond, and its change.
fn capstan<T: Scalar>(per_rad: T, theta: T, d_theta: T, tau: T, d_tau: T) -> (T, T) {
    if per_rad == T::zero() {
        return (tau, d_tau);
    }
    let f = (per_rad * theta).exp();
    (tau * f, d_tau * f + tau * f * per_rad * d_theta)
}

/// What the tendons do at one guide: the wrench on the rod and each tendon's tension in the chord
/// beyond (for the next guide), with their changes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GuideLoad<T> {
    pub wrench: Wrench<T>,
    pub d_wrench: Wrench<T>,
    pub ahead_n: [T; MAX_TENDONS],
    pub d_ahead_n: [T; MAX_TENDONS],
}

/// The tendons' load on guide `guide` at pose `cur`, with the previous hole's guide (or, at the
/// first guide, the base plate) at `prev` and the next guide at `next` (read only where a tendon
/// passes); `back_n` each tendon's tension in the chord arriving here (at the load scale), and
/// their changes `d_back_n` with the pose changes `d = (d_prev, d_cur, d_next)`.
pub(crate) fn guide_load<T: Scalar>(
    routed: &[Routed<T>],
    back_n: &[T],
    guide: usize,
    poses: [&GuidePose<T>; 3],
    d: Option<([&PoseDelta<T>; 3], &[T])>,
) -> GuideLoad<T> {
    let [prev, cur, next] = poses;
    let zero = PoseDelta::zero();
    let zeros = [T::zero(); MAX_TENDONS];
    let ([dp, dc, dn], d_back) = d.unwrap_or(([&zero, &zero, &zero], &zeros));
    let mut out = GuideLoad {
        wrench: Wrench::zero(),
        d_wrench: Wrench::zero(),
        ahead_n: [T::zero(); MAX_TENDONS],
        d_ahead_n: [T::zero(); MAX_TENDONS],
    };
    for (j, (r, tau)) in routed.iter().zip(back_n).enumerate() {
        let role = role(r, guide);
        if *tau == T::zero() || role == Role::None {
            continue;
        }
        let d_tau = d_back.get(j).copied().unwrap_or_else(T::zero);
        let here = hole(cur, &r.offset_m);
        let d_here = d_hole(cur, &r.offset_m, dc);
        let back = here - hole(prev, &r.offset_m);
        let d_back_chord = d_here - d_hole(prev, &r.offset_m, dp);
        let (u_back, du_back) = unit_and_change(&back, &d_back_chord);
        // The base plate's hole: the tendon enters along the base tangent.
        let (tau_b, d_tau_b) = if guide == 0 && r.capstan_per_rad != T::zero() {
            let entry = prev.rotation.column(2).into_owned();
            let (theta, d_theta) = wrap_and_change(&entry, &Vector3::zeros(), &u_back, &du_back);
            capstan(r.capstan_per_rad, theta, d_theta, *tau, d_tau)
        } else {
            (*tau, d_tau)
        };
        let mut f = -u_back * tau_b;
        let mut df = -du_back * tau_b - u_back * d_tau_b;
        if role == Role::Passes {
            let ahead = hole(next, &r.offset_m) - here;
            let d_ahead = d_hole(next, &r.offset_m, dn) - d_here;
            let (u_ahead, du_ahead) = unit_and_change(&ahead, &d_ahead);
            let (tau_a, d_tau_a) = if r.capstan_per_rad == T::zero() {
                (tau_b, d_tau_b)
            } else {
                let (theta, d_theta) = wrap_and_change(&u_back, &du_back, &u_ahead, &du_ahead);
                capstan(r.capstan_per_rad, theta, d_theta, tau_b, d_tau_b)
            };
            f += u_ahead * tau_a;
            df += du_ahead * tau_a + u_ahead * d_tau_a;
            if let (Some(a), Some(da)) = (out.ahead_n.get_mut(j), out.d_ahead_n.get_mut(j)) {
                *a = tau_a;
                *da = d_tau_a;
            }
        }
        let arm = cur.rotation * r.offset_m;
        let d_arm = cur.rotation * dc.rotation_rad.cross(&r.offset_m);
        out.wrench.force_n += f;
        out.wrench.moment_nm += arm.cross(&f);
        out.d_wrench.force_n += df;
        out.d_wrench.moment_nm += d_arm.cross(&f) + arm.cross(&df);
    }
    out
}

/// Frictionless, the wrench's change per move of the next guide's pose, column `k` for the move
/// along `dp_k` (`k < 3`) or the turn `dtheta_(k-3)` (body frame): [`guide_load`]'s `d_wrench`
/// for those six moves, in one pass. Only the passing tendons' chords ahead move,
/// `dF = tau (dP - u (u . dP)) / |P_next - P|` with `dP` the next hole's move; the moment is the
/// arm's, `(R d) x dF`. `None` where a tendon passing here has capstan friction (its tension
/// beyond reads the wrap): then [`guide_load`] per move.
pub(crate) fn d_wrench_d_next<T: Scalar>(
    routed: &[Routed<T>],
    back_n: &[T],
    guide: usize,
    cur: &GuidePose<T>,
    next: &GuidePose<T>,
) -> Option<[Wrench<T>; 6]> {
    let mut out = [Wrench::zero(); 6];
    for (r, tau) in routed.iter().zip(back_n) {
        if *tau == T::zero() || role(r, guide) != Role::Passes {
            continue;
        }
        if r.capstan_per_rad != T::zero() {
            return None;
        }
        let ahead = hole(next, &r.offset_m) - hole(cur, &r.offset_m);
        let len = ahead.norm();
        let u = ahead / len;
        let k = *tau / len;
        let arm = cur.rotation * r.offset_m;
        for (j, w) in out.iter_mut().enumerate() {
            let mut axis = Vector3::zeros();
            if let Some(a) = axis.get_mut(j % 3) {
                *a = T::one();
            }
            let moved = if j < 3 {
                axis
            } else {
                next.rotation * axis.cross(&r.offset_m)
            };
            let df = (moved - u * u.dot(&moved)) * k;
            w.force_n += df;
            w.moment_nm += arm.cross(&df);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn pose(p: [f64; 3], axis_angle: [f64; 3]) -> GuidePose<f64> {
        GuidePose {
            position_m: Vector3::from(p),
            rotation: Rotation3::new(Vector3::from(axis_angle)).into_inner(),
        }
    }

    /// The direct change of the wrench per move of the next pose is `guide_load`'s along each of
    /// the six moves, for two tendons passing and one ending here; with friction there is none.
    #[test]
    fn tendon_next_pose_change_is_the_loads_along_six_moves() {
        let mut routed = [
            Routed {
                offset_m: Vector3::new(0.01, 0.0, 0.0),
                end_guide: 3,
                capstan_per_rad: 0.0,
            },
            Routed {
                offset_m: Vector3::new(-0.004, 0.008, 0.0),
                end_guide: 2,
                capstan_per_rad: 0.0,
            },
            Routed {
                offset_m: Vector3::new(0.0, -0.009, 0.0),
                end_guide: 1,
                capstan_per_rad: 0.0,
            },
        ];
        let back = [2.0, 1.3, 0.7];
        let prev = pose([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
        let cur = pose([0.002, -0.001, 0.05], [0.05, -0.03, 0.1]);
        let next = pose([0.006, -0.003, 0.099], [0.11, -0.05, 0.17]);
        let direct = d_wrench_d_next(&routed, &back, 1, &cur, &next).unwrap();
        let zero = PoseDelta::zero();
        let none = [0.0; MAX_TENDONS];
        for (k, w) in direct.iter().enumerate() {
            let mut d = PoseDelta::zero();
            if k < 3 {
                d.position_m[k] = 1.0;
            } else {
                d.rotation_rad[k - 3] = 1.0;
            }
            let want = guide_load(
                &routed,
                &back,
                1,
                [&prev, &cur, &next],
                Some(([&zero, &zero, &d], &none)),
            )
            .d_wrench;
            let off = (w.force_n - want.force_n).norm() + (w.moment_nm - want.moment_nm).norm();
            let size = want.force_n.norm() + want.moment_nm.norm();
            assert!(size > 1e-3, "move {k}: a change to compare");
            assert!(off < 1e-12 * size, "move {k}: {off:e}");
        }
        routed[0].capstan_per_rad = -0.2;
        assert!(d_wrench_d_next(&routed, &back, 1, &cur, &next).is_none());
    }
}
