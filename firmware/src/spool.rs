//! Spool calibration: multi-turn encoder counts to cable length, and back.
//!
//! `length = length_at_zero_m + sign * (position - zero_offset_counts) * 2 pi radius / counts_per_spool_turn`,
//! with `sign` from [`Direction`] and `position` the angle sensor's multi-turn count. A sensor on the
//! motor shaft behind a gearhead of ratio `n` sees `n` sensor turns per spool turn:
//! `counts_per_spool_turn = n * sensor counts per turn`. Generic over the scalar so that the host generates fixtures in f64
//! with the same code the MCU runs in f32.

use model_core::Scalar;

/// Which way the cable moves when the counts increase.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Direction {
    /// Increasing counts pay cable out: the measured length grows.
    PayOutWithCounts,
    /// Increasing counts reel cable in: the measured length shrinks.
    ReelInWithCounts,
}

/// A calibration the spool refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum CalibrationError {
    /// The spool radius is not a positive finite number.
    Radius,
    /// Counts per spool turn is not a positive finite number.
    CountsPerTurn,
    /// The length at the zero offset is not a positive finite number.
    LengthAtZero,
    /// The turn tracker refused its settings (see [`crate::encoder::multiturn::ConfigError`]).
    Tracker,
    /// A length whose position does not fit the counter (non-finite or beyond +-2^53 counts).
    Unrepresentable,
}

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Radius => "spool radius must be positive and finite",
            Self::CountsPerTurn => "counts per spool turn must be positive and finite",
            Self::LengthAtZero => "cable length at the zero offset must be positive and finite",
            Self::Tracker => {
                "the turn tracker refused the sensor's counts per turn or the step limit"
            }
            Self::Unrepresentable => "the length has no representable encoder position",
        })
    }
}

impl core::error::Error for CalibrationError {}

/// How one spool turns encoder counts into cable length.
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct SpoolCalibration<T> {
    /// Radius at the cable's centreline on the spool, m.
    pub radius_m: T,
    /// Sensor counts in one spool turn (sensor counts per turn times the gear ratio).
    pub counts_per_spool_turn: T,
    /// Multi-turn position at which the cable is `length_at_zero_m` long, counts. It is also the home
    /// position, where the steppers start: the sampler checks the first readings after power-up
    /// against it and names a cable that is not there (`CableFault::PowerUpOffHome`).
    pub zero_offset_counts: i64,
    /// Cable length at `zero_offset_counts`, m.
    pub length_at_zero_m: T,
    /// Which way the cable moves with increasing counts.
    pub direction: Direction,
}

impl<T: Scalar> SpoolCalibration<T> {
    /// Checks the fields.
    ///
    /// # Errors
    /// [`CalibrationError::Radius`], [`CalibrationError::CountsPerTurn`] or
    /// [`CalibrationError::LengthAtZero`] for the field that is out of range.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        if !(self.radius_m.is_finite() && self.radius_m > T::zero()) {
            return Err(CalibrationError::Radius);
        }
        if !(self.counts_per_spool_turn.is_finite() && self.counts_per_spool_turn > T::zero()) {
            return Err(CalibrationError::CountsPerTurn);
        }
        if !(self.length_at_zero_m.is_finite() && self.length_at_zero_m > T::zero()) {
            return Err(CalibrationError::LengthAtZero);
        }
        Ok(())
    }

    /// Cable travel per count, m.
    pub fn metres_per_count(&self) -> T {
        T::two_pi() * self.radius_m / self.counts_per_spool_turn
    }

    fn sign(&self) -> T {
        match self.direction {
            Direction::PayOutWithCounts => T::one(),
            Direction::ReelInWithCounts => -T::one(),
        }
    }

    /// The cable length at a multi-turn position, m. In f32 the count difference from the zero
    /// offset is exact below 2^24 counts (1024 turns of a 14-bit sensor).
    /// Differences beyond the i32 range (2^31 counts: 500 m of cable at 0.24 um a count) saturate.
    pub fn length_m(&self, position_counts: i64) -> T {
        let difference = position_counts.saturating_sub(self.zero_offset_counts);
        let clamped =
            i32::try_from(difference).unwrap_or(if difference < 0 { i32::MIN } else { i32::MAX });
        // i32 -> f32 is one instruction on the MCU (i64 or f64 would link software routines); every
        // i32 is a finite f32 and f64, so the conversion cannot fail.
        let counts = T::from_i32(clamped).unwrap_or_else(T::zero);
        self.length_at_zero_m + self.sign() * counts * self.metres_per_count()
    }

    /// The multi-turn position that reads closest to `length_m`, counts (for generating fixtures and
    /// for homing at a known length).
    ///
    /// # Errors
    /// [`CalibrationError::Unrepresentable`] for a non-finite length or one beyond 2^53 counts.
    pub fn position_counts(&self, length_m: T) -> Result<i64, CalibrationError> {
        let counts = ((length_m - self.length_at_zero_m) * self.sign() / self.metres_per_count())
            .round()
            .to_f64();
        if !counts.is_finite() || counts.abs() > 9.0e15 {
            return Err(CalibrationError::Unrepresentable);
        }
        // In range by the check above; `as` rounds nothing here (the value is already integral).
        Ok(self.zero_offset_counts.saturating_add(counts as i64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spool(direction: Direction) -> SpoolCalibration<f64> {
        SpoolCalibration {
            radius_m: 0.005,
            counts_per_spool_turn: 16384.0,
            zero_offset_counts: -20_000,
            length_at_zero_m: 0.38,
            direction,
        }
    }

    #[test]
    fn one_turn_is_one_circumference() {
        let s = spool(Direction::PayOutWithCounts);
        let turn = s.length_m(-20_000 + 16384) - s.length_m(-20_000);
        assert!((turn - 2.0 * core::f64::consts::PI * 0.005).abs() < 1e-15);
        assert!((s.metres_per_count() - 1.917_475_984_857e-6).abs() < 1e-15);
        let r = spool(Direction::ReelInWithCounts);
        assert!((r.length_m(-20_000 + 16384) - (0.38 - 0.031_415_926_535)).abs() < 1e-12);
    }

    #[test]
    fn lengths_and_positions_round_trip() -> Result<(), CalibrationError> {
        for direction in [Direction::PayOutWithCounts, Direction::ReelInWithCounts] {
            let s = spool(direction);
            for position in [-1_000_000i64, -20_001, 0, 12_345, 3_000_000] {
                assert_eq!(s.position_counts(s.length_m(position))?, position);
            }
            // Half a count off rounds to the nearest count.
            let near = s.length_m(500) + 0.4 * s.metres_per_count();
            assert_eq!(s.position_counts(near)?, 500);
        }
        Ok(())
    }

    #[test]
    fn f32_lengths_match_f64_within_a_tenth_of_a_count() {
        let s64 = spool(Direction::ReelInWithCounts);
        let s32 = SpoolCalibration::<f32> {
            radius_m: 0.005,
            counts_per_spool_turn: 16384.0,
            zero_offset_counts: -20_000,
            length_at_zero_m: 0.38,
            direction: Direction::ReelInWithCounts,
        };
        for position in [-30_000i64, -20_000, -5_000, 0, 4_000] {
            let err = (f64::from(s32.length_m(position)) - s64.length_m(position)).abs();
            assert!(err < 0.1 * s64.metres_per_count(), "{position}: {err}");
        }
    }

    #[test]
    fn invalid_calibrations_name_the_field() {
        let good = spool(Direction::PayOutWithCounts);
        assert_eq!(good.validate(), Ok(()));
        let mut bad = good;
        bad.radius_m = -0.005;
        assert_eq!(bad.validate(), Err(CalibrationError::Radius));
        let mut bad = good;
        bad.counts_per_spool_turn = 0.0;
        assert_eq!(bad.validate(), Err(CalibrationError::CountsPerTurn));
        let mut bad = good;
        bad.length_at_zero_m = f64::NAN;
        assert_eq!(bad.validate(), Err(CalibrationError::LengthAtZero));
        assert_eq!(
            good.position_counts(f64::INFINITY),
            Err(CalibrationError::Unrepresentable)
        );
    }
}
