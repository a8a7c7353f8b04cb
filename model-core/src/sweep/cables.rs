//! Cable lengths (thesis ch. 3.8.1): a cable runs in straight chords between the holes of
//! consecutive guides, from the first guide to its termination, where it is fixed to the backbone at
//! the same offset. An observer of the sweep: at each node it is handed the pose and each tangent's
//! change of the pose, and sums the chords and their derivatives.
//!
//! Chords are formed from differences of like parts (the position's high and low parts and the
//! offset `R d`), so no part of a 40 cm position is lost to cancellation, and the lengths are summed
//! with compensation: in f32 a cable length keeps its micrometres.

use nalgebra::{Matrix3, Vector3};

use crate::ode::Pose;
use crate::plan::{NO_GUIDE, Node};
use crate::sweep::MAX_TANGENTS;
use crate::{MAX_CABLES, Scalar};

/// Every cable's running length and its tangents' changes, field by field, so that a fresh set is
/// all zeros (the firmware's sweep clears it in one go instead of copying a template per cable).
#[derive(Clone, Copy, Debug)]
pub(crate) struct CableTraces<T> {
    /// Running length, high and low parts (compensated summation), m.
    length_m: [T; MAX_CABLES],
    length_lo_m: [T; MAX_CABLES],
    /// Each tangent's change of the running length.
    d_length: [[T; MAX_TANGENTS]; MAX_CABLES],
    /// The previous hole: the backbone point (high and low parts) and the offset `R d`.
    prev: [[Vector3<T>; 3]; MAX_CABLES],
    /// Each tangent's change of the previous hole.
    d_prev: [[Vector3<T>; MAX_TANGENTS]; MAX_CABLES],
    /// Bit `c`: cable `c` has its first hole.
    started: u8,
    /// Bit `c`: cable `c` has reached its termination.
    done: u8,
}

impl<T: Scalar> CableTraces<T> {
    pub(crate) fn new() -> Self {
        Self {
            length_m: [T::zero(); MAX_CABLES],
            length_lo_m: [T::zero(); MAX_CABLES],
            d_length: [[T::zero(); MAX_TANGENTS]; MAX_CABLES],
            prev: [[Vector3::zeros(); 3]; MAX_CABLES],
            d_prev: [[Vector3::zeros(); MAX_TANGENTS]; MAX_CABLES],
            started: 0,
            done: 0,
        }
    }

    /// A node of the sweep: a guide adds each unfinished cable's hole; a termination adds the last.
    /// `offsets` holds one hole offset per cable (local frame, m); `d_pose` each tangent's
    /// `(dr, dtheta)`.
    pub(crate) fn visit(
        &mut self,
        node: &Node<T>,
        offsets: &[Vector3<T>],
        pose: &Pose<T>,
        d_pose: &[(Vector3<T>, Vector3<T>)],
    ) {
        for (c, offset) in offsets.iter().enumerate().take(MAX_CABLES) {
            let bit = 1u8 << c;
            let ends = node.cable_ends & bit != 0;
            if self.done & bit == 0 && node.guide != NO_GUIDE {
                self.add_hole(c, pose, d_pose, offset);
            }
            if self.done & bit == 0 && ends {
                self.add_hole(c, pose, d_pose, offset);
                self.done |= bit;
            }
        }
    }

    /// Adds cable `c`'s chord to the hole at `r + R d`.
    fn add_hole(
        &mut self,
        c: usize,
        pose: &Pose<T>,
        d_pose: &[(Vector3<T>, Vector3<T>)],
        offset: &Vector3<T>,
    ) {
        let (Some(length), Some(length_lo), Some(d_length), Some(prev), Some(d_prev)) = (
            self.length_m.get_mut(c),
            self.length_lo_m.get_mut(c),
            self.d_length.get_mut(c),
            self.prev.get_mut(c),
            self.d_prev.get_mut(c),
        ) else {
            return;
        };
        let m: &Matrix3<T> = &pose.rotation;
        let arm = m * offset;
        let hole = [pose.position_m, pose.position_lo_m, arm];
        let mut d_hole = [Vector3::zeros(); MAX_TANGENTS];
        for (d, (dr, dth)) in d_hole.iter_mut().zip(d_pose) {
            *d = dr + m * dth.cross(offset);
        }
        let bit = 1u8 << c;
        if self.started & bit != 0 {
            let [h0, h1, h2] = &hole;
            let [p0, p1, p2] = &*prev;
            let chord = (h0 - p0) + (h1 - p1) + (h2 - p2);
            let len = chord.norm_squared().sqrt_hot();
            let sum = *length + len;
            *length_lo += if length.abs() >= len.abs() {
                (*length - sum) + len
            } else {
                (len - sum) + *length
            };
            *length = sum;
            if len > T::zero() {
                for ((dl, dh), dp) in d_length
                    .iter_mut()
                    .zip(&d_hole)
                    .zip(d_prev.iter())
                    .take(d_pose.len())
                {
                    *dl += chord.dot(&(dh - dp)) / len;
                }
            }
        }
        *prev = hole;
        *d_prev = d_hole;
        self.started |= bit;
    }

    /// Writes each cable's length, m, and its tangents' changes (zero beyond the rod's cables).
    pub(crate) fn write(
        &self,
        lengths_m: &mut [T; MAX_CABLES],
        d: &mut [[T; MAX_TANGENTS]; MAX_CABLES],
    ) {
        for ((length, hi), lo) in lengths_m
            .iter_mut()
            .zip(&self.length_m)
            .zip(&self.length_lo_m)
        {
            *length = *hi + *lo;
        }
        *d = self.d_length;
    }
}
