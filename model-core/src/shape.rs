//! Shape output: the backbone at caller-chosen arc lengths, written into the caller's buffer.

use nalgebra::{Matrix3, Vector3};

use crate::Scalar;
use crate::error::ModelError;

/// The backbone at one arc length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapePoint<T> {
    /// Reference arc length, m.
    pub s_m: T,
    /// Position, m, global frame.
    pub position_m: Vector3<T>,
    /// Frame: columns are the local x, y, z (tangent) axes in global coordinates.
    pub rotation: Matrix3<T>,
    /// Bending and torsion strain `u` (body frame), 1/m; just distal of a node where it jumps.
    pub strain_per_m: Vector3<T>,
}

/// The rod's base at rest (arc length zero, at the origin, identity frame, no strain): what an
/// output buffer is filled with before a shape is written into it.
impl<T: nalgebra::RealField + Copy> Default for ShapePoint<T> {
    fn default() -> Self {
        Self {
            s_m: T::zero(),
            position_m: Vector3::zeros(),
            rotation: Matrix3::identity(),
            strain_per_m: Vector3::zeros(),
        }
    }
}

impl<T: nalgebra::RealField + Copy> ShapePoint<T> {
    /// The unit tangent (local z) in global coordinates.
    pub fn tangent(&self) -> Vector3<T> {
        self.rotation.column(2).into_owned()
    }
}

/// Where a sweep writes shape points: sorted query arc lengths and an output slice of at least the same length.
#[derive(Debug)]
pub(crate) struct ShapeSink<'a, T> {
    pub s_m: &'a [T],
    pub out: &'a mut [ShapePoint<T>],
    pub written: usize,
}

impl<T: Copy> ShapeSink<'_, T> {
    /// The next query arc length not yet written.
    pub fn next_query(&self) -> Option<T> {
        self.s_m.get(self.written).copied()
    }

    pub fn write(&mut self, point: ShapePoint<T>) {
        if let Some(slot) = self.out.get_mut(self.written) {
            *slot = point;
            self.written += 1;
        }
    }
}

/// Checks shape queries: finite, increasing, within `[0, length_m]`, and an output buffer of at
/// least `out_len` points.
pub(crate) fn check_queries<T: Scalar>(
    s_m: &[T],
    out_len: usize,
    length_m: T,
) -> Result<(), ModelError> {
    if out_len < s_m.len() {
        return Err(ModelError::Mismatch("shape queries and output buffer"));
    }
    let mut previous = T::zero();
    for &s in s_m {
        crate::error::finite(s, "shape arc length")?;
        if s < previous {
            return Err(ModelError::Unordered("shape arc lengths"));
        }
        if s > length_m {
            return Err(ModelError::OutOfRange("shape arc length"));
        }
        previous = s;
    }
    Ok(())
}
