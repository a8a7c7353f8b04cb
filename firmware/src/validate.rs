//! Reading validation: a tick's three cable lengths are used only when every one is plausible.
//!
//! A reading is refused, with the culprit named, when its source failed (the sampler's refusal or
//! latched fault, [`crate::sampler::SampleError`]), it is not finite, it lies outside what the model
//! can produce (`(0, cable_length_bound_m]`), or it moved further since the last accepted reading
//! than the cable can travel in that time (a physical speed limit times the elapsed samples, plus a
//! margin for quantisation). Time is counted in the sampler's samples, so a tick that comes late
//! (after a cold estimate) is allowed the travel of the time that really passed.

use model_core::inverse::cable_length_bound_m;
use model_core::{Attitude, Model, ModelError};

/// Cables on the bench, one per length source.
pub const CABLES: usize = 3;

/// Why a tick's readings were refused. `cable` is the index of the first culprit (0, 1, 2).
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub enum Rejection<E> {
    /// The length source failed.
    Source {
        /// The cable.
        cable: u8,
        /// The source's error.
        error: E,
    },
    /// The length is NaN or infinite.
    NonFinite {
        /// The cable.
        cable: u8,
    },
    /// The length is outside what the model can produce, m.
    OutOfRange {
        /// The cable.
        cable: u8,
        /// The reading, m.
        length_m: f32,
    },
    /// The length moved further than the cable can travel since the last accepted reading, m.
    Jump {
        /// The cable.
        cable: u8,
        /// The move since the last accepted reading, m (signed).
        step_m: f32,
        /// The largest plausible move, m.
        limit_m: f32,
    },
}

/// Checks readings against the model's bounds and the last accepted reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadingValidator {
    max_length_m: [f32; CABLES],
    max_step_per_sample_m: f32,
    margin_m: f32,
    last: Option<Accepted>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Accepted {
    lengths_m: [f32; CABLES],
    seq: u32,
}

impl ReadingValidator {
    /// A validator for the three cables of `model` (any f32 model: attitude `A`, `NODES` plan nodes),
    /// allowing each cable to move `max_step_per_sample_m` per sample plus `margin_m` (quantisation,
    /// noise), both in m.
    ///
    /// # Errors
    /// [`ModelError::Mismatch`] when the model does not have three cables;
    /// [`ModelError::NotPositive`] or [`ModelError::NonFinite`] for a bad step or margin.
    pub fn new<A: Attitude<f32>, const NODES: usize>(
        model: &Model<f32, A, NODES>,
        max_step_per_sample_m: f32,
        margin_m: f32,
    ) -> Result<Self, ModelError> {
        let rod = model.rod();
        if rod.cables.len() != CABLES {
            return Err(ModelError::Mismatch("length sources and model cables"));
        }
        for (value, what) in [
            (max_step_per_sample_m, "cable step per sample"),
            (margin_m, "cable step margin"),
        ] {
            if !value.is_finite() {
                return Err(ModelError::NonFinite(what));
            }
            if value <= 0.0 {
                return Err(ModelError::NotPositive(what));
            }
        }
        let mut max_length_m = [0.0f32; CABLES];
        for (bound, cable) in max_length_m.iter_mut().zip(rod.cables.iter()) {
            *bound = cable_length_bound_m(rod, cable);
        }
        Ok(Self {
            max_length_m,
            max_step_per_sample_m,
            margin_m,
            last: None,
        })
    }

    /// The largest length the model can produce for each cable, m.
    pub fn max_length_m(&self) -> [f32; CABLES] {
        self.max_length_m
    }

    /// Checks the readings of sample `seq`; returns the lengths when all are plausible. Nothing is
    /// remembered: see [`ReadingValidator::accept`].
    ///
    /// # Errors
    /// The [`Rejection`] of the first implausible reading.
    pub fn check<E: Copy>(
        &self,
        seq: u32,
        readings: &[Result<f32, E>; CABLES],
    ) -> Result<[f32; CABLES], Rejection<E>> {
        let mut lengths_m = [0.0f32; CABLES];
        for (index, ((reading, slot), max_m)) in readings
            .iter()
            .zip(lengths_m.iter_mut())
            .zip(self.max_length_m)
            .enumerate()
        {
            // At most three cables: the index fits a u8.
            let cable = index as u8;
            let length_m = match reading {
                Ok(length_m) => *length_m,
                Err(error) => {
                    return Err(Rejection::Source {
                        cable,
                        error: *error,
                    });
                }
            };
            if !length_m.is_finite() {
                return Err(Rejection::NonFinite { cable });
            }
            if length_m <= 0.0 || length_m > max_m {
                return Err(Rejection::OutOfRange { cable, length_m });
            }
            *slot = length_m;
        }
        if let Some(last) = &self.last {
            // Samples since the last accepted reading: the cable could move that much. A sample
            // that is not newer (the same one again, or an older one: a wrapped difference in the
            // upper half of the range) had no time to move in, and gets the margin alone (an older
            // one once wrapped to about 4e9 samples, and any length passed).
            let elapsed = seq.wrapping_sub(last.seq);
            let samples = if elapsed > u32::MAX / 2 { 0 } else { elapsed } as f32;
            let limit_m = self.max_step_per_sample_m * samples + self.margin_m;
            for (index, (now, before)) in lengths_m.iter().zip(last.lengths_m).enumerate() {
                let step_m = now - before;
                if step_m.abs() > limit_m {
                    return Err(Rejection::Jump {
                        cable: index as u8,
                        step_m,
                        limit_m,
                    });
                }
            }
        }
        Ok(lengths_m)
    }

    /// Remembers accepted lengths (from [`ReadingValidator::check`]) as the reference for the next jump check.
    pub fn accept(&mut self, seq: u32, lengths_m: [f32; CABLES]) {
        self.last = Some(Accepted { lengths_m, seq });
    }

    /// Forgets the last accepted lengths: the next readings are not jump-checked (after a re-home).
    pub fn forget(&mut self) {
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{BenchModel, rod};

    fn validator() -> Result<ReadingValidator, ModelError> {
        let model = BenchModel::new(rod(10)?)?;
        ReadingValidator::new(&model, 5e-4, 1e-5)
    }

    const GOOD: [f32; 3] = [0.3864, 0.3836, 0.3836];

    fn ok(lengths: [f32; 3]) -> [Result<f32, ()>; 3] {
        lengths.map(Ok)
    }

    #[test]
    fn bounds_are_the_models() -> Result<(), ModelError> {
        let v = validator()?;
        // Four 9.5 cm spans and the last 3.6 cm (guide 0 at 5.41 mm to the tip at 39 cm), each
        // stretched 10 % plus twice the 1 cm offset: 1.1 * 0.38459 + 5 * 0.02 = 0.523 m.
        for max in v.max_length_m() {
            assert!((max - 0.523_049).abs() < 1e-5, "{max}");
        }
        Ok(())
    }

    #[test]
    fn each_bad_reading_names_its_cable_and_reason() -> Result<(), ModelError> {
        let mut v = validator()?;
        assert_eq!(v.check(0, &ok(GOOD)), Ok(GOOD));
        v.accept(0, GOOD);
        let r = [Ok(0.3864), Err(()), Ok(f32::NAN)];
        assert_eq!(
            v.check(1, &r),
            Err(Rejection::Source {
                cable: 1,
                error: ()
            })
        );
        let r = ok([0.3864, 0.3836, f32::NAN]);
        assert_eq!(v.check(1, &r), Err(Rejection::NonFinite { cable: 2 }));
        let r = ok([0.3864, f32::INFINITY, 0.3836]);
        assert_eq!(v.check(1, &r), Err(Rejection::NonFinite { cable: 1 }));
        let r = ok([0.6, 0.3836, 0.3836]);
        assert_eq!(
            v.check(1, &r),
            Err(Rejection::OutOfRange {
                cable: 0,
                length_m: 0.6
            })
        );
        let r = ok([0.3864, -0.001, 0.3836]);
        assert_eq!(
            v.check(1, &r),
            Err(Rejection::OutOfRange {
                cable: 1,
                length_m: -0.001
            })
        );
        Ok(())
    }

    #[test]
    fn jumps_are_limited_by_speed_times_elapsed_samples() -> Result<(), ModelError> {
        let mut v = validator()?;
        v.accept(10, GOOD);
        // 0.6 mm in one sample: limit 0.5 mm + 10 um.
        let moved = [GOOD[0], GOOD[1] + 6e-4, GOOD[2]];
        match v.check(11, &ok(moved)) {
            Err(Rejection::Jump {
                cable: 1,
                step_m,
                limit_m,
            }) => {
                assert!((step_m - 6e-4).abs() < 1e-7);
                assert!((limit_m - 5.1e-4).abs() < 1e-9);
            }
            other => panic!("expected a jump on cable 1, got {other:?}"),
        }
        // The same move over two samples is plausible.
        assert_eq!(v.check(12, &ok(moved)), Ok(moved));
        // A sample no newer than the last accepted one had no time to move: the margin alone.
        v.accept(20, GOOD);
        let nudged = [GOOD[0], GOOD[1] + 2e-5, GOOD[2]];
        for stale in [20, 19, 0] {
            match v.check(stale, &ok(nudged)) {
                Err(Rejection::Jump {
                    cable: 1, limit_m, ..
                }) => {
                    assert!((limit_m - 1e-5).abs() < 1e-12, "{limit_m}");
                }
                other => panic!("expected a jump on cable 1 at sample {stale}, got {other:?}"),
            }
        }
        assert_eq!(v.check(20, &ok(GOOD)), Ok(GOOD));
        // Across the counter's wrap, a newer sample is newer.
        v.accept(u32::MAX, GOOD);
        assert_eq!(v.check(1, &ok(moved)), Ok(moved));
        // Forgotten: anything in range goes.
        v.forget();
        let far = [GOOD[0] + 0.01, GOOD[1], GOOD[2]];
        assert_eq!(v.check(13, &ok(far)), Ok(far));
        Ok(())
    }

    #[test]
    fn any_f32_model_of_the_rod_gives_the_same_validator() -> Result<(), ModelError> {
        // model-core's default model type (72 nodes) next to the bench's (20).
        let other = Model::<f32>::new(rod(10)?)?;
        assert_eq!(ReadingValidator::new(&other, 5e-4, 1e-5)?, validator()?);
        Ok(())
    }

    #[test]
    fn bad_settings_and_models_are_refused() -> Result<(), ModelError> {
        let model = BenchModel::new(rod(10)?)?;
        assert_eq!(
            ReadingValidator::new(&model, 0.0, 1e-5),
            Err(ModelError::NotPositive("cable step per sample"))
        );
        assert_eq!(
            ReadingValidator::new(&model, 1e-3, f32::NAN),
            Err(ModelError::NonFinite("cable step margin"))
        );
        let mut two = rod(10)?;
        two.cables.pop();
        let two_cables = BenchModel::new(two)?;
        assert_eq!(two_cables.rod().cables.len(), 2);
        assert_eq!(
            ReadingValidator::new(&two_cables, 1e-3, 1e-5),
            Err(ModelError::Mismatch("length sources and model cables"))
        );
        Ok(())
    }
}
