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

/// Most shape points a warm estimator hands out per update (its scratch buffer's size: a control
/// loop reports a few backbone points per tick; [`crate::Model::shape_at`] gives any number).
pub const MAX_SHAPE_POINTS: usize = 4;

/// Checked shape queries and the caller's output buffer.
#[derive(Debug)]
pub(crate) struct Shape<'a, T> {
    pub s_m: &'a [T],
    pub out: &'a mut [ShapePoint<T>],
}

impl<'a, T: Scalar> Shape<'a, T> {
    /// Checks the queries (see [`check_queries`]) and that at most [`MAX_SHAPE_POINTS`] are asked.
    pub(crate) fn new(
        length_m: T,
        s_m: &'a [T],
        out: &'a mut [ShapePoint<T>],
    ) -> Result<Self, ModelError> {
        check_queries(s_m, out.len(), length_m)?;
        if s_m.len() > MAX_SHAPE_POINTS {
            return Err(ModelError::Capacity("shape points"));
        }
        Ok(Self { s_m, out })
    }

    /// A sink writing into the buffer from its start.
    pub(crate) fn sink(&mut self) -> ShapeSink<'_, T> {
        ShapeSink {
            s_m: self.s_m,
            out: self.out,
            written: 0,
        }
    }

    /// Takes the points of another buffer for the same queries.
    pub(crate) fn take(&mut self, other: Shape<'_, T>) {
        let n = self.out.len().min(other.out.len());
        if let (Some(to), Some(from)) = (self.out.get_mut(..n), other.out.get(..n)) {
            to.copy_from_slice(from);
        }
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
///
/// # Errors
/// [`ModelError::Mismatch`] for a short buffer, [`ModelError::NonFinite`],
/// [`ModelError::Unordered`] or [`ModelError::OutOfRange`] for a bad arc length.
pub fn check_queries<T: Scalar>(s_m: &[T], out_len: usize, length_m: T) -> Result<(), ModelError> {
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
