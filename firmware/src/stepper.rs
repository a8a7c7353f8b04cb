//! The steppers' commanded positions in the angle sensors' counts.
//!
//! Each cable's stepper motor carries its AS5047P on the motor shaft (the gearhead sits between
//! motor and spool), so the controller's microstep count since home and the sensor's multi-turn
//! count measure the same shaft: the step count is a second witness of where the shaft is, apart
//! from the sensor. [`StepperScale`] converts between the two units with integers only
//! (`counts = steps * counts_per_turn / microsteps_per_turn`, the fraction reduced), and the
//! [`crate::sampler`] compares them every sample.

use core::num::NonZeroU32;

/// A stepper setting the scale refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ScaleError {
    /// Counts and microsteps per turn must be positive, and their reduced product plus the larger
    /// of them must fit a `u32` (the rounding's arithmetic).
    Range,
}

/// Sensor counts per microstep, as a reduced fraction `counts / steps`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepperScale {
    counts: NonZeroU32,
    steps: NonZeroU32,
}

const fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        let r = a % b;
        a = b;
        b = r;
    }
    a
}

/// `value * numerator / denominator` for a non-negative value, rounded half up, saturating: unsigned
/// 32-bit divisions by a non-zero divisor (no panic path; hardware `udiv` on the Cortex-M4).
fn scale(value: u32, numerator: NonZeroU32, denominator: NonZeroU32) -> u32 {
    let whole = value / denominator;
    let part = value % denominator;
    // `part < denominator`, and `numerator * denominator` fits (checked by `StepperScale::new`).
    let rounded = (part * numerator.get() + denominator.get() / 2) / denominator;
    whole
        .saturating_mul(numerator.get())
        .saturating_add(rounded)
}

/// `value` scaled by `numerator / denominator`, rounded to nearest (halves away from zero),
/// saturating at the `i32` range.
fn scale_signed(value: i32, numerator: NonZeroU32, denominator: NonZeroU32) -> i32 {
    let magnitude =
        i32::try_from(scale(value.unsigned_abs(), numerator, denominator)).unwrap_or(i32::MAX);
    if value < 0 { -magnitude } else { magnitude }
}

impl StepperScale {
    /// The scale of a sensor with `counts_per_turn` counts on a motor of `microsteps_per_turn`
    /// microsteps (full steps times the driver's microstepping).
    ///
    /// # Errors
    /// [`ScaleError::Range`] for a zero, or for a reduced fraction whose rounding would pass `u32`
    /// (its terms' product plus the larger term).
    pub const fn new(counts_per_turn: u32, microsteps_per_turn: u32) -> Result<Self, ScaleError> {
        if counts_per_turn == 0 || microsteps_per_turn == 0 {
            return Err(ScaleError::Range);
        }
        let g = gcd(counts_per_turn, microsteps_per_turn);
        let (counts, steps) = (counts_per_turn / g, microsteps_per_turn / g);
        // Rounding a remainder multiplies it (below one term) by the other and adds half the
        // first: `(d - 1) n + d / 2 <= n d + max(n, d)` must fit a u32 (`n d` alone fitting is not
        // enough: 4 / 1 073 741 823 overflowed).
        let larger = if counts > steps { counts } else { steps };
        let bound = match counts.checked_mul(steps) {
            Some(product) => product.checked_add(larger),
            None => None,
        };
        match (bound, NonZeroU32::new(counts), NonZeroU32::new(steps)) {
            (Some(_), Some(counts), Some(steps)) => Ok(Self { counts, steps }),
            _ => Err(ScaleError::Range),
        }
    }

    /// Sensor counts of `steps` microsteps, rounded to nearest (halves away from zero); saturates
    /// far beyond any cable's travel.
    #[inline]
    pub fn counts(&self, steps: i32) -> i32 {
        scale_signed(steps, self.counts, self.steps)
    }

    /// The microstep count nearest `counts` sensor counts (fixtures, homing).
    #[inline]
    pub fn steps(&self, counts: i32) -> i32 {
        scale_signed(counts, self.steps, self.counts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sixteenth_stepped_motor_under_a_14_bit_sensor() -> Result<(), ScaleError> {
        // 200 full steps x 16 = 3200 microsteps per turn: 5.12 counts each (128/25).
        let s = StepperScale::new(16_384, 3200)?;
        assert_eq!(s, StepperScale::new(128, 25)?);
        assert_eq!(s.counts(3200), 16_384);
        assert_eq!(s.counts(-3200), -16_384);
        assert_eq!(s.counts(1), 5);
        assert_eq!(s.counts(2), 10);
        assert_eq!(s.counts(-1), -5);
        assert_eq!(s.counts(-2), -10);
        assert_eq!(s.counts(25), 128);
        // Every microstep maps back to itself.
        for steps in -10_000..10_000 {
            assert_eq!(s.steps(s.counts(steps)), steps, "{steps}");
            // Within half a count of the exact value.
            let exact = f64::from(steps) * 5.12;
            assert!((f64::from(s.counts(steps)) - exact).abs() <= 0.5, "{steps}");
        }
        Ok(())
    }

    #[test]
    fn far_positions_saturate_and_bad_settings_are_refused() -> Result<(), ScaleError> {
        let s = StepperScale::new(16_384, 3200)?;
        assert_eq!(s.counts(i32::MAX), i32::MAX);
        assert_eq!(s.counts(i32::MIN), -i32::MAX);
        assert_eq!(StepperScale::new(0, 3200), Err(ScaleError::Range));
        assert_eq!(StepperScale::new(16_384, 0), Err(ScaleError::Range));
        assert_eq!(StepperScale::new(65_537, 65_539), Err(ScaleError::Range));
        // The product fits, the rounding's sum would not (it overflowed in `counts`).
        assert_eq!(StepperScale::new(4, 1_073_741_823), Err(ScaleError::Range));
        // The largest scale of that kind the rounding holds converts without overflow.
        let edge = StepperScale::new(3, 1_073_741_823)?;
        assert_eq!(edge.counts(1_073_741_822), 3);
        assert_eq!(edge.steps(2), 715_827_882);
        // Halves round away from zero, the same both ways.
        let half = StepperScale::new(1, 2)?;
        assert_eq!(
            (half.counts(1), half.counts(-1), half.counts(3)),
            (1, -1, 2)
        );
        Ok(())
    }
}
