//! Multi-turn positions from single-turn angles.
//!
//! A single-turn sensor cannot tell one turn from the next: a multi-turn position is the position
//! with the sensor's angle nearest a reference (the last accepted position, the stepper's commanded
//! position, or home). That is only right while the shaft is within half a turn of the reference;
//! [`crate::sampler`] keeps it so (it reads at 1 kHz and gives up the turn after a bounded streak
//! of refused reads) and cross-checks every position against the stepper.
//!
//! Positions are `i32` counts: +-2^31 counts are 131 072 turns of a 14-bit sensor, 515 m of cable on
//! the bench's spools. Every operation is a 32-bit one (the Cortex-M4 divides those in hardware).

/// Why an angle could not be placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum UnwrapError {
    /// The raw angle is not within one turn, counts.
    NotInTurn {
        /// The raw reading, counts.
        raw_counts: u16,
    },
}

/// Counts per turn the functions here accept: at least 4, and a `u16` angle (at most 65536).
pub const fn valid_counts_per_turn(counts_per_turn: u32) -> bool {
    counts_per_turn >= 4 && counts_per_turn <= 65_536
}

/// `step` reduced to the shortest signed step of the same angle, in `[-turn/2, turn - turn/2)`.
/// Reduced first, then shifted: no intermediate overflows (shifting first wrapped steps near
/// `i32::MAX` by `2^32`, which changes the angle when the turn does not divide it).
pub fn shortest(step: i32, counts_per_turn: u32) -> i32 {
    let turn = i32::try_from(counts_per_turn).unwrap_or(i32::MAX);
    let within = step.rem_euclid(turn);
    if within < turn - turn / 2 {
        within
    } else {
        within - turn
    }
}

/// The position whose angle is `raw_counts` nearest to `reference`, counts: `reference` plus the
/// shortest step from the reference's angle to `raw_counts`. `counts_per_turn` must satisfy
/// [`valid_counts_per_turn`].
///
/// # Errors
/// [`UnwrapError::NotInTurn`] for an angle beyond one turn.
pub fn nearest(reference: i32, raw_counts: u16, counts_per_turn: u32) -> Result<i32, UnwrapError> {
    if u32::from(raw_counts) >= counts_per_turn {
        return Err(UnwrapError::NotInTurn { raw_counts });
    }
    let step = shortest(
        i32::from(raw_counts).wrapping_sub(reference),
        counts_per_turn,
    );
    Ok(reference.saturating_add(step))
}

/// The angle of a position, counts in `[0, counts_per_turn)`.
pub fn angle(position: i32, counts_per_turn: u32) -> u16 {
    let turn = i32::try_from(counts_per_turn).unwrap_or(i32::MAX);
    u16::try_from(position.rem_euclid(turn)).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed};

    /// A fixed seed, so a run reproduces (a random one found the overflow in `shortest`:
    /// `step = 2147464585`, `turn = 38126`, kept below as a case).
    fn config() -> Config {
        Config {
            cases: 2048,
            rng_seed: RngSeed::Fixed(0x7075_726e),
            failure_persistence: None,
            ..Config::default()
        }
    }

    const TURN: u32 = 16_384;

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn the_nearest_position_has_the_angle_and_is_within_half_a_turn(
            reference in -1_000_000_000i32..1_000_000_000,
            raw in 0u16..16_384,
        ) {
            let p = nearest(reference, raw, TURN).unwrap();
            prop_assert_eq!(angle(p, TURN), raw);
            let d = p - reference;
            prop_assert!((-8192..8192).contains(&d), "{}", d);
        }

        #[test]
        fn shortest_is_the_same_angle_within_half_a_turn(step in any::<i32>(), turn in 4u32..=65_536) {
            let s = shortest(step, turn);
            let t = i64::from(turn);
            prop_assert_eq!((i64::from(step) - i64::from(s)).rem_euclid(t), 0);
            prop_assert!(-t / 2 <= i64::from(s) && i64::from(s) < t - t / 2);
        }
    }

    #[test]
    fn a_step_near_the_largest_is_reduced_without_overflow() {
        let (step, turn) = (2_147_464_585, 38_126u32);
        let s = shortest(step, turn);
        assert_eq!((i64::from(step) - i64::from(s)).rem_euclid(38_126), 0);
        assert!((-19_063..19_063).contains(&s), "{s}");
        assert_eq!(shortest(i32::MIN, 16_384), 0);
        assert_eq!(shortest(i32::MAX, 16_384), -1);
    }

    #[test]
    fn positions_follow_the_reference_across_turn_boundaries() {
        // Home at 3 turns + 16000: raw 100 is 484 counts past it, in the next turn.
        assert_eq!(
            nearest(3 * 16_384 + 16_000, 100, TURN),
            Ok(4 * 16_384 + 100)
        );
        assert_eq!(nearest(-5, 16_383, TURN), Ok(-1));
        assert_eq!(nearest(0, 8192, TURN), Ok(-8192));
        assert_eq!(nearest(0, 8191, TURN), Ok(8191));
        assert_eq!(angle(-1, TURN), 16_383);
        assert_eq!(
            nearest(0, 16_384, TURN),
            Err(UnwrapError::NotInTurn { raw_counts: 16_384 })
        );
        assert!(valid_counts_per_turn(4) && valid_counts_per_turn(65_536));
        assert!(!valid_counts_per_turn(3) && !valid_counts_per_turn(65_537));
    }
}
