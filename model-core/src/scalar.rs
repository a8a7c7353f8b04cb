//! The scalar type the model is generic over: `f32` on the MCU, `f64` on the host.

use nalgebra::{RealField, SMatrix};

/// A real scalar for the rod model.
///
/// Everything in the model is written against nalgebra's [`RealField`]; this trait adds the few
/// transcendental functions that sit on the integrator's hot path (frame normalisation, the
/// exponential map, chord lengths), so that the `fast-math` feature can swap them for micromath's
/// approximations on `f32`. That swap trades accuracy for speed and is measured, never assumed.
pub trait Scalar: RealField + Copy {
    /// Square root on the hot path (exact unless `fast-math` is on and `Self` is `f32`).
    fn sqrt_hot(self) -> Self;
    /// `(sin, cos)` on the hot path (exact unless `fast-math` is on and `Self` is `f32`).
    fn sin_cos_hot(self) -> (Self, Self);
    /// A literal in this scalar type.
    #[inline]
    fn lit(x: f64) -> Self {
        nalgebra::convert(x)
    }
    /// The value as `f64`, for reports and comparisons.
    fn to_f64(self) -> f64;
}

impl Scalar for f64 {
    #[inline]
    fn sqrt_hot(self) -> Self {
        <f64 as nalgebra::ComplexField>::sqrt(self)
    }
    #[inline]
    fn sin_cos_hot(self) -> (Self, Self) {
        <f64 as nalgebra::ComplexField>::sin_cos(self)
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

impl Scalar for f32 {
    #[inline]
    fn sqrt_hot(self) -> Self {
        #[cfg(feature = "fast-math")]
        {
            micromath::F32Ext::sqrt(self)
        }
        #[cfg(not(feature = "fast-math"))]
        {
            <f32 as nalgebra::ComplexField>::sqrt(self)
        }
    }
    #[inline]
    fn sin_cos_hot(self) -> (Self, Self) {
        #[cfg(feature = "fast-math")]
        {
            (micromath::F32Ext::sin(self), micromath::F32Ext::cos(self))
        }
        #[cfg(not(feature = "fast-math"))]
        {
            <f32 as nalgebra::ComplexField>::sin_cos(self)
        }
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

/// Two 3-vectors stacked: `top` in rows 0-2, `bottom` in rows 3-5.
#[inline]
pub(crate) fn stacked<T: Scalar>(
    top: &nalgebra::Vector3<T>,
    bottom: &nalgebra::Vector3<T>,
) -> nalgebra::SVector<T, 6> {
    nalgebra::SVector::<T, 6>::new(top.x, top.y, top.z, bottom.x, bottom.y, bottom.z)
}

/// `true` when every component is finite.
#[inline]
pub(crate) fn all_finite<T: Scalar, const R: usize, const C: usize>(
    m: &nalgebra::SMatrix<T, R, C>,
) -> bool {
    m.iter().all(|x| x.is_finite())
}

/// Sorts a short slice in place so that no element is `before` its predecessor (stable).
///
/// An insertion sort: the model sorts at most a few dozen breakpoints once, and a handful of singular
/// values, where core's pattern-defeating quicksort would cost 4 KB of the controller's flash.
pub(crate) fn insertion_sort<T: Copy>(xs: &mut [T], before: impl Fn(&T, &T) -> bool) {
    for i in 1..xs.len() {
        let mut j = i;
        while j > 0 {
            match (xs.get(j - 1), xs.get(j)) {
                (Some(a), Some(b)) if before(b, a) => xs.swap(j - 1, j),
                _ => break,
            }
            j -= 1;
        }
    }
}

/// The matrix whose column `j` is `column(j)`.
#[inline]
pub(crate) fn from_columns<T: Scalar, const R: usize, const C: usize>(
    column: impl Fn(usize) -> nalgebra::SVector<T, R>,
) -> nalgebra::SMatrix<T, R, C> {
    let mut m = nalgebra::SMatrix::<T, R, C>::zeros();
    for (j, mut c) in m.column_iter_mut().enumerate() {
        c.copy_from(&column(j));
    }
    m
}

/// `a b`, nalgebra's product, out of line: one copy per shape of product rather than one per use
/// (the controller's flash; the call costs a few instructions against the product's tens).
#[inline(never)]
pub(crate) fn product<T: Scalar, const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<T, R, K>,
    b: &SMatrix<T, K, C>,
) -> SMatrix<T, R, C> {
    a * b
}
