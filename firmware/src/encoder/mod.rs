//! Cable length sources.
//!
//! Each cable is wound on a spool whose shaft carries a single-turn absolute angle sensor
//! ([`AngleSensor`], e.g. the [`as5047p`] driver). The spool turns many times over the cable's
//! travel, so [`multiturn::MultiTurn`] tracks the wrap-arounds between reads, and
//! [`crate::spool::SpoolCalibration`] turns the multi-turn position into a cable length.
//! [`SpoolEncoder`] puts the three together behind [`CableLengthSource`], the one trait the
//! estimator loop reads.

pub mod as5047p;
pub mod multiturn;
pub mod replay;

use crate::spool::SpoolCalibration;
use multiturn::{MultiTurn, UnwrapError};

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

/// One cable's length source.
pub trait CableLengthSource {
    /// Why a read failed: a small `Copy` enum naming the culprit.
    type Error: Copy + core::fmt::Debug;

    /// The cable length, m (from the first guide to the termination, as the model defines it).
    ///
    /// # Errors
    /// Whatever the source reports; the length is then unknown.
    fn read_cable_length_m(&mut self) -> Result<f32, Self::Error>;
}

/// Why a spool encoder could not give a cable length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum SpoolError<E> {
    /// The angle sensor failed.
    Sensor(E),
    /// The sensor's angle could not be unwrapped (out of range, or a step beyond the limit).
    Unwrap(UnwrapError),
}

/// A spool: angle sensor, turn tracking and calibration, read as a cable length.
#[derive(Debug)]
pub struct SpoolEncoder<S> {
    sensor: S,
    turns: MultiTurn,
    calibration: SpoolCalibration<f32>,
}

impl<S: AngleSensor> SpoolEncoder<S> {
    /// A spool read through `sensor`, starting at the calibration's home position.
    ///
    /// # Errors
    /// [`crate::spool::CalibrationError`] when the calibration is invalid, or the sensor's counts per
    /// turn or `max_step_counts` (it must be below half a sensor turn) do not suit the turn tracker.
    pub fn new(
        sensor: S,
        calibration: SpoolCalibration<f32>,
        max_step_counts: u32,
    ) -> Result<Self, crate::spool::CalibrationError> {
        calibration.validate()?;
        let turns = MultiTurn::new(
            sensor.counts_per_turn(),
            max_step_counts,
            calibration.zero_offset_counts,
        )
        .map_err(|_| crate::spool::CalibrationError::Tracker)?;
        Ok(Self {
            sensor,
            turns,
            calibration,
        })
    }

    /// The multi-turn position of the last accepted read, counts (`None` before the first).
    pub fn position_counts(&self) -> Option<i64> {
        self.turns.position_counts()
    }

    /// Gives the sensor back.
    pub fn release(self) -> S {
        self.sensor
    }
}

impl<S: AngleSensor> CableLengthSource for SpoolEncoder<S> {
    type Error = SpoolError<S::Error>;

    fn read_cable_length_m(&mut self) -> Result<f32, Self::Error> {
        let raw = self
            .sensor
            .read_angle_counts()
            .map_err(SpoolError::Sensor)?;
        let position = self.turns.update(raw).map_err(SpoolError::Unwrap)?;
        Ok(self.calibration.length_m(position))
    }
}

#[cfg(test)]
mod tests {
    use super::replay::{ReplayError, ReplaySensor};
    use super::*;
    use crate::spool::{CalibrationError, Direction};

    fn calibration() -> SpoolCalibration<f32> {
        SpoolCalibration {
            radius_m: 0.005,
            counts_per_spool_turn: 16384.0,
            zero_offset_counts: 16_380,
            length_at_zero_m: 0.386,
            direction: Direction::PayOutWithCounts,
        }
    }

    #[test]
    fn lengths_follow_the_spool_across_a_wrap() -> Result<(), CalibrationError> {
        // Home at 16380: raw 16380 is the calibrated length; +10 counts wraps to raw 6.
        let sensor = ReplaySensor::new(16384, &[Ok(16380), Ok(6), Ok(16370)]);
        let mut spool = SpoolEncoder::new(sensor, calibration(), 4096)?;
        let metres_per_count = 2.0 * core::f64::consts::PI * 0.005 / 16384.0;
        let expected = [
            0.386,
            0.386 + 10.0 * metres_per_count,
            0.386 - 10.0 * metres_per_count,
        ];
        for want in expected {
            let got = spool
                .read_cable_length_m()
                .map_err(|_| CalibrationError::Tracker)?;
            assert!((f64::from(got) - want).abs() < 1e-7, "{got} vs {want}");
        }
        assert_eq!(spool.position_counts(), Some(16_370));
        Ok(())
    }

    #[test]
    fn sensor_and_unwrap_errors_name_the_culprit() -> Result<(), CalibrationError> {
        let sensor = ReplaySensor::new(16384, &[Ok(100), Err(ReplayError::Injected), Ok(5000)]);
        let mut spool = SpoolEncoder::new(sensor, calibration(), 4096)?;
        assert!(spool.read_cable_length_m().is_ok());
        assert_eq!(
            spool.read_cable_length_m(),
            Err(SpoolError::Sensor(ReplayError::Injected))
        );
        assert_eq!(
            spool.read_cable_length_m(),
            Err(SpoolError::Unwrap(UnwrapError::StepTooLarge {
                step_counts: 4900,
                limit_counts: 4096
            }))
        );
        // The refused step left the position where it was.
        assert_eq!(spool.position_counts(), Some(16_384 + 100));
        Ok(())
    }

    #[test]
    fn a_geared_spool_counts_sensor_turns() -> Result<(), CalibrationError> {
        // 8 sensor turns per spool turn: two sensor turns forward is a quarter of the circumference.
        let mut geared = calibration();
        geared.counts_per_spool_turn = 8.0 * 16384.0;
        let script: Vec<_> = (0..=16)
            .map(|k| Ok(((16380 + k * 2048) % 16384) as u16))
            .collect();
        let mut spool = SpoolEncoder::new(ReplaySensor::new(16384, &script), geared, 4096)?;
        let mut last = 0.0;
        for _ in 0..=16 {
            last = spool
                .read_cable_length_m()
                .map_err(|_| CalibrationError::Tracker)?;
        }
        let quarter = 0.25 * 2.0 * core::f64::consts::PI * 0.005;
        assert!((f64::from(last) - (0.386 + quarter)).abs() < 1e-7, "{last}");
        Ok(())
    }

    #[test]
    fn a_step_limit_of_half_a_turn_is_refused() {
        let sensor = ReplaySensor::new(4096, &[]);
        assert_eq!(
            SpoolEncoder::new(sensor, calibration(), 2048).err(),
            Some(CalibrationError::Tracker)
        );
    }
}
