//! Multi-turn tracking of a single-turn absolute angle.
//!
//! A single-turn sensor cannot tell one turn from the next, so the spool's position is tracked by
//! accumulating the shortest angular step between consecutive reads. That is only unambiguous while
//! the shaft turns less than half a turn between reads; a larger implied step (a glitch, a skipped
//! read at full speed) is refused and leaves the position unchanged. At power-up the spool must be
//! within half a turn of its home position (the calibration's zero), which picks the first turn.

/// Why a read could not be unwrapped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum UnwrapError {
    /// The raw angle is not within one turn, counts.
    NotInTurn {
        /// The raw reading, counts.
        raw_counts: u16,
    },
    /// The shortest step from the last accepted read exceeds the limit.
    StepTooLarge {
        /// The implied step, counts (signed: positive is increasing counts).
        step_counts: i32,
        /// The limit it broke, counts.
        limit_counts: u32,
    },
}

/// A configuration the tracker refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ConfigError {
    /// Counts per turn must be at least 4 and fit a `u16` angle (at most 65536).
    CountsPerTurn,
    /// The step limit must be below half a turn, or steps become ambiguous.
    MaxStep,
}

/// Tracks a spool's multi-turn position from single-turn angle reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MultiTurn {
    counts_per_turn: u32,
    max_step_counts: u32,
    home_counts: i64,
    position_counts: Option<i64>,
}

impl MultiTurn {
    /// A tracker for a sensor with `counts_per_turn` counts, refusing steps larger than
    /// `max_step_counts` between reads, whose first read is taken as the position nearest
    /// `home_counts` (multi-turn counts) with that angle.
    ///
    /// # Errors
    /// [`ConfigError`] when `counts_per_turn` is out of range or `max_step_counts` is not below
    /// half a turn.
    pub fn new(
        counts_per_turn: u32,
        max_step_counts: u32,
        home_counts: i64,
    ) -> Result<Self, ConfigError> {
        if !(4..=65536).contains(&counts_per_turn) {
            return Err(ConfigError::CountsPerTurn);
        }
        if max_step_counts >= counts_per_turn / 2 {
            return Err(ConfigError::MaxStep);
        }
        Ok(Self {
            counts_per_turn,
            max_step_counts,
            home_counts,
            position_counts: None,
        })
    }

    /// The position of the last accepted read, counts (`None` before the first).
    pub fn position_counts(&self) -> Option<i64> {
        self.position_counts
    }

    /// Forgets the position: the next read is placed nearest the home position again.
    pub fn rehome(&mut self) {
        self.position_counts = None;
    }

    /// Accepts a raw angle (counts in `[0, counts_per_turn)`) and returns the multi-turn position.
    ///
    /// # Errors
    /// [`UnwrapError::NotInTurn`] for an angle beyond one turn; [`UnwrapError::StepTooLarge`] when the
    /// shortest step from the last accepted read exceeds the limit. Either leaves the position as it was.
    pub fn update(&mut self, raw_counts: u16) -> Result<i64, UnwrapError> {
        // `counts_per_turn` is in 4..=65536 (checked by `new`): every angle and step fits an i32.
        let turn = i32::try_from(self.counts_per_turn).unwrap_or(i32::MAX);
        let raw = i32::from(raw_counts);
        if raw >= turn {
            return Err(UnwrapError::NotInTurn { raw_counts });
        }
        let reference = self.position_counts.unwrap_or(self.home_counts);
        let angle = i32::try_from(angle_of(reference, self.counts_per_turn)).unwrap_or(0);
        // The shortest signed step from the reference's angle to `raw`, in [-turn/2, turn/2).
        let step = (raw - angle + turn / 2).rem_euclid(turn) - turn / 2;
        if self.position_counts.is_some() && step.unsigned_abs() > self.max_step_counts {
            return Err(UnwrapError::StepTooLarge {
                step_counts: step,
                limit_counts: self.max_step_counts,
            });
        }
        let position = reference.saturating_add(i64::from(step));
        self.position_counts = Some(position);
        Ok(position)
    }
}

/// The angle of a multi-turn position, `position.rem_euclid(counts_per_turn)` for `counts_per_turn`
/// in `1..=65536`, with 32-bit divisions only: the Cortex-M4 divides 32-bit integers in hardware,
/// while a 64-bit remainder links a 1 KB software routine into the estimator's 64 KiB.
///
/// With `v` the position's two's-complement bits, `v = hi 2^32 + lo`; every partial product is
/// below `2^16 2^16`, so nothing overflows.
fn angle_of(position: i64, counts_per_turn: u32) -> u32 {
    let m = counts_per_turn.max(1);
    let bits = position.cast_unsigned();
    let (hi, lo) = ((bits >> 32) as u32, bits as u32);
    let b = (u32::MAX % m + 1) % m; // 2^32 mod m
    let v = ((hi % m) * b % m + lo % m) % m;
    if position < 0 {
        // The bits are position + 2^64: take 2^64 mod m back off.
        let c = b * b % m;
        (v + m - c) % m
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn angle_is_the_euclidean_remainder(position in any::<i64>(), turn in 1u32..=65536) {
            prop_assert_eq!(i64::from(angle_of(position, turn)), position.rem_euclid(i64::from(turn)));
        }
    }

    const TURN: u32 = 16384;

    #[test]
    fn first_read_picks_the_turn_nearest_home() -> Result<(), ConfigError> {
        let mut t = MultiTurn::new(TURN, 4000, 3 * 16384 + 16000)?;
        // raw 100 is 484 counts past home across the wrap: the next turn.
        assert_eq!(t.update(100), Ok(4 * 16384 + 100));
        let mut t = MultiTurn::new(TURN, 4000, -5)?;
        assert_eq!(t.update(16383), Ok(-1));
        Ok(())
    }

    #[test]
    fn wraps_forward_and_backward_over_many_turns() -> Result<(), ConfigError> {
        let mut t = MultiTurn::new(TURN, 4000, 0)?;
        let mut expected = 0i64;
        assert_eq!(t.update(0), Ok(0));
        // 3000 counts a read, forward for ten turns, then back past the start.
        for _ in 0..55 {
            expected += 3000;
            let raw = u16::try_from(expected.rem_euclid(16384)).unwrap_or(0);
            assert_eq!(t.update(raw), Ok(expected));
        }
        assert!(expected > 10 * 16384);
        for _ in 0..70 {
            expected -= 3000;
            let raw = u16::try_from(expected.rem_euclid(16384)).unwrap_or(0);
            assert_eq!(t.update(raw), Ok(expected));
        }
        assert!(expected < 0);
        Ok(())
    }

    #[test]
    fn a_step_beyond_the_limit_is_refused_and_forgotten() -> Result<(), ConfigError> {
        let mut t = MultiTurn::new(TURN, 4000, 0)?;
        assert_eq!(t.update(16000), Ok(-384));
        // 16000 -> 12000 is a step of -4000: allowed; -> 7999 is -4001: refused.
        assert_eq!(t.update(12000), Ok(-4384));
        assert_eq!(
            t.update(7999),
            Err(UnwrapError::StepTooLarge {
                step_counts: -4001,
                limit_counts: 4000
            })
        );
        assert_eq!(t.position_counts(), Some(-4384));
        // The next good read is taken from the last accepted one.
        assert_eq!(t.update(12010), Ok(-4374));
        // Half a turn is ambiguous whatever the limit.
        assert_eq!(
            t.update(12010 - 8192),
            Err(UnwrapError::StepTooLarge {
                step_counts: -8192,
                limit_counts: 4000
            })
        );
        Ok(())
    }

    #[test]
    fn out_of_turn_angles_and_bad_configs_are_refused() -> Result<(), ConfigError> {
        let mut t = MultiTurn::new(4096, 100, 0)?;
        assert_eq!(
            t.update(4096),
            Err(UnwrapError::NotInTurn { raw_counts: 4096 })
        );
        assert_eq!(t.position_counts(), None);
        assert_eq!(MultiTurn::new(4096, 2048, 0), Err(ConfigError::MaxStep));
        assert_eq!(MultiTurn::new(2, 0, 0), Err(ConfigError::CountsPerTurn));
        assert_eq!(
            MultiTurn::new(65537, 10, 0),
            Err(ConfigError::CountsPerTurn)
        );
        t.rehome();
        assert_eq!(t.update(4000), Ok(-96));
        Ok(())
    }
}
