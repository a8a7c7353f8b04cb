//! Cable length sources.
//!
//! Each cable is wound on a spool driven by a stepper through a gearhead; the motor shaft carries a
//! single-turn absolute angle sensor ([`AngleSensor`], e.g. the [`as5047p`] driver). The shaft
//! turns many times over the cable's travel: [`multiturn`] places an angle in its turn,
//! [`crate::sampler`] tracks the turns at 1 kHz and cross-checks them against the stepper, and
//! [`crate::spool::SpoolCalibration`] turns the multi-turn position into a cable length.

pub mod as5047p;
pub mod multiturn;
pub mod replay;

/// A single-turn absolute angle sensor on a spool shaft.
pub trait AngleSensor {
    /// Why a read failed: a small `Copy` enum naming the culprit.
    type Error: Copy + core::fmt::Debug;

    /// Counts in one mechanical turn (16384 for a 14-bit sensor).
    fn counts_per_turn(&self) -> u32;

    /// The shaft angle, counts in `[0, counts_per_turn)`.
    ///
    /// # Errors
    /// Whatever the sensor or its bus reports; the angle is then unknown.
    fn read_angle_counts(&mut self) -> Result<u16, Self::Error>;
}
