//! Input errors. Solver outcomes (converged or not) are not errors: see [`crate::Termination`].

use core::fmt;

/// Why an input was refused. Each variant names the offending field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// A value is NaN or infinite.
    NonFinite(&'static str),
    /// A length, stiffness, step count or similar is zero or negative.
    NotPositive(&'static str),
    /// A value lies outside the range the model accepts (for example a guide beyond the tip,
    /// or a cable length the rod cannot produce).
    OutOfRange(&'static str),
    /// A list that must be in increasing order is not.
    Unordered(&'static str),
    /// More items than the fixed-capacity buffers hold.
    Capacity(&'static str),
    /// A required list is empty.
    Empty(&'static str),
    /// Two inputs that must agree in size do not.
    Mismatch(&'static str),
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite(what) => write!(f, "{what} is not finite"),
            Self::NotPositive(what) => write!(f, "{what} must be positive"),
            Self::OutOfRange(what) => write!(f, "{what} is out of range"),
            Self::Unordered(what) => write!(f, "{what} must be in increasing order"),
            Self::Capacity(what) => write!(f, "too many {what} for the fixed-capacity buffers"),
            Self::Empty(what) => write!(f, "{what} must not be empty"),
            Self::Mismatch(what) => write!(f, "{what} do not match in size"),
        }
    }
}

impl core::error::Error for ModelError {}

pub(crate) fn finite<T: crate::Scalar>(x: T, what: &'static str) -> Result<T, ModelError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ModelError::NonFinite(what))
    }
}

pub(crate) fn positive<T: crate::Scalar>(x: T, what: &'static str) -> Result<T, ModelError> {
    finite(x, what)?;
    if x > T::zero() {
        Ok(x)
    } else {
        Err(ModelError::NotPositive(what))
    }
}

pub(crate) fn non_negative<T: crate::Scalar>(x: T, what: &'static str) -> Result<T, ModelError> {
    finite(x, what)?;
    if x >= T::zero() {
        Ok(x)
    } else {
        Err(ModelError::OutOfRange(what))
    }
}

pub(crate) fn finite_vec<T: crate::Scalar>(
    v: &nalgebra::Vector3<T>,
    what: &'static str,
) -> Result<(), ModelError> {
    if crate::scalar::all_finite(v) {
        Ok(())
    } else {
        Err(ModelError::NonFinite(what))
    }
}
