//! The encoder sampler: every cable's angle read, placed in its turn, cross-checked against the
//! stepper's commanded position, and turned into a cable length, once per sample (1 kHz on the MCU,
//! in a timer task that preempts the estimator: turn tracking never waits for a solve).
//!
//! Two witnesses of each motor shaft are compared every sample: the sensor's multi-turn position
//! (its angle placed in the turn nearest the last accepted position, never the stepper's) and the
//! stepper's commanded position (microsteps since home, in sensor counts). A reading is accepted
//! only when they agree within [`SamplerSettings::tolerance_counts`]. A refused reading gives no
//! length for that sample and says why ([`SampleError`]); a refusal that persists is named and
//! latched as a [`CableFault`], after which the cable gives no length until [`Sampler::rehome`]:
//!
//! | fault | evidence |
//! | --- | --- |
//! | [`CableFault::PowerUpOffHome`] | the first readings after power-up sit the same distance (beyond the tolerance) from home, where the stepper starts |
//! | [`CableFault::HomeUnknown`] | the MCU started from a reset other than a power-up ([`crate::reset`]): the cables may be anywhere, whole sensor turns from home included ([`Sampler::distrust_home`]) |
//! | [`CableFault::StuckSensor`] | refused, and the angle has not moved while the stepper moved by more than the tolerance (a dead sensor, a frozen bus, or a stalled motor: the two look alike) |
//! | [`CableFault::TurnAliasing`] | refused with a steady offset of whole sensor turns: the turn count and the stepper disagree |
//! | [`CableFault::SlippedMagnet`] | refused with a steady offset that is not whole turns (a magnet slipped on its shaft, or the motor lost steps once) |
//! | [`CableFault::RefusalStreak`] | refused [`SamplerSettings::max_refused_samples`] times in a row for any other reason (a bus outage, a wandering offset): the shaft may have moved far enough since the last accepted read that the nearest turn is no longer certain |
//!
//! Each cause is named only after [`SamplerSettings::persist_samples`] refusals in a row, so a
//! single glitch costs one sample and no re-homing.
//!
//! Nothing here panics, allocates or uses floating point except the final length.

use crate::encoder::AngleSensor;
use crate::encoder::multiturn::{self, UnwrapError};
use crate::spool::{CalibrationError, SpoolCalibration};
use crate::stepper::{ScaleError, StepperScale};
use crate::validate::CABLES;

/// How the sampler cross-checks the sensors against the steppers (`config::sampler_settings`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct SamplerSettings {
    /// Largest accepted difference between sensor and stepper, counts.
    pub tolerance_counts: u32,
    /// An angle that moves by no more than this has not moved, counts (the sensor's noise).
    pub still_counts: u32,
    /// Refusals in a row before their cause is named.
    pub persist_samples: u16,
    /// Refusals in a row after which the turn is given up ([`CableFault::RefusalStreak`]).
    pub max_refused_samples: u16,
    /// The most the shaft can turn in one sample (the drives' speed limit), counts.
    pub max_step_counts_per_sample: u32,
}

/// A fault latched on one cable: the cable gives no length until [`Sampler::rehome`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum CableFault {
    /// After power-up the sensor's angle was not home's, where the stepper starts: the cable was
    /// moved while the power was off (or the magnet slipped then). The offset is known only modulo
    /// a sensor turn (3.93 mm of cable), which is why the turn cannot be picked.
    PowerUpOffHome {
        /// Sensor minus stepper, counts, in `[-turn/2, turn/2)`.
        offset_counts: i32,
    },
    /// The MCU started from a reset other than a power-up (the firmware's own after a fault, a
    /// watchdog, the reset pin, a brownout): the motors may have left home, and a cable a whole
    /// number of sensor turns from home reads like home. Set by [`Sampler::distrust_home`].
    HomeUnknown,
    /// The angle stayed put while the stepper moved: a dead sensor or bus, or a stalled motor.
    StuckSensor {
        /// The angle it is stuck at, counts.
        angle_counts: u16,
        /// How far the stepper moved meanwhile, counts.
        commanded_move_counts: i32,
    },
    /// The sensor follows the stepper at a steady offset that is not whole turns: the magnet
    /// slipped on its shaft (or the motor lost steps once).
    SlippedMagnet {
        /// Sensor minus stepper, counts.
        offset_counts: i32,
    },
    /// The sensor's turn count is whole turns away from the stepper's: a turn was lost (the shaft
    /// moved more than half a turn between two reads).
    TurnAliasing {
        /// Sensor minus stepper, in sensor turns.
        turns: i32,
    },
    /// Too many refused reads in a row: the shaft may have moved far enough since the last accepted
    /// one that its turn is no longer certain.
    RefusalStreak {
        /// The refused samples.
        samples: u16,
    },
}

/// Why a cable has no length in a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum SampleError<E> {
    /// The sensor's read failed (bus, parity, magnet or CORDIC flags: `E` says which).
    Sensor(E),
    /// The sensor returned an angle beyond one turn.
    NotInTurn {
        /// The raw reading, counts.
        raw_counts: u16,
    },
    /// Sensor and stepper disagree beyond the tolerance: this sample's reading is refused (a fault
    /// is named if it persists).
    Disagrees {
        /// Sensor minus stepper, counts.
        deviation_counts: i32,
    },
    /// A latched fault: no length until re-homed.
    Fault(CableFault),
}

impl<E> From<UnwrapError> for SampleError<E> {
    fn from(e: UnwrapError) -> Self {
        match e {
            UnwrapError::NotInTurn { raw_counts } => Self::NotInTurn { raw_counts },
        }
    }
}

/// One sample of the three cables: what the sampler hands the estimator (the latest one). `E` is
/// why a cable has no length: [`SampleError`] from [`Sampler::sample`].
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct Sample<E> {
    /// The sample's number, counting from 0 at the sampler's rate.
    pub seq: u32,
    /// Each cable's length, m, or why it has none.
    pub readings: [Result<f32, E>; CABLES],
}

/// A configuration the sampler refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum SamplerError {
    /// A spool calibration is invalid, or its zero offset does not fit the `i32` position.
    Calibration(CalibrationError),
    /// A sensor's counts per turn is out of range (4..=65536).
    CountsPerTurn,
    /// The stepper scale is invalid.
    Stepper(ScaleError),
    /// The settings let the nearest-turn rule alias: `(max_refused_samples + 1) *
    /// max_step_counts_per_sample + tolerance_counts` must stay below half a turn, and the
    /// persistence must not exceed the streak limit.
    Settings,
}

/// Where a cable's tracking stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// After power-up: the first good reading must agree with home.
    PowerUp,
    /// After [`Sampler::rehome`]: the first good reading defines home.
    Adopt,
    /// Tracking from the last accepted position, counts.
    Tracking(i32),
    /// Latched until re-homed.
    Faulted(CableFault),
}

/// The evidence of the current run of refused samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Streak {
    /// Refused samples in a row.
    samples: u16,
    /// Of those, the ones with a reading (a sensor-stepper deviation).
    readings: u16,
    /// The first reading's deviation, counts.
    first_deviation: i32,
    /// Whether every reading's deviation stayed within the tolerance of the first.
    steady: bool,
}

/// The angle when it last moved, and the stepper's position then.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Still {
    angle: u16,
    commanded: i32,
}

#[derive(Debug)]
struct Channel<S> {
    sensor: S,
    calibration: SpoolCalibration<f32>,
    /// Multi-turn position at the home pose, counts (the calibration's zero offset).
    home_counts: i32,
    /// The stepper's count at the home pose, microsteps.
    home_steps: i32,
    mode: Mode,
    streak: Streak,
    still: Still,
}

/// Samples three angle sensors, tracks their turns and cross-checks them against the steppers.
#[derive(Debug)]
pub struct Sampler<S> {
    channels: [Channel<S>; CABLES],
    scale: StepperScale,
    settings: SamplerSettings,
    seq: u32,
}

impl<S: AngleSensor> Sampler<S> {
    /// A sampler over `sensors` (cables 0, 1, 2) with their spool calibrations, whose steppers
    /// count in `scale` and start at home (step count 0).
    ///
    /// # Errors
    /// [`SamplerError`] for an invalid calibration, sensor, scale or settings.
    pub fn new(
        sensors: [S; CABLES],
        calibrations: [SpoolCalibration<f32>; CABLES],
        scale: StepperScale,
        settings: SamplerSettings,
    ) -> Result<Self, SamplerError> {
        let [s0, s1, s2] = sensors;
        let [c0, c1, c2] = calibrations;
        let channels = [
            Channel::new(s0, c0, &settings)?,
            Channel::new(s1, c1, &settings)?,
            Channel::new(s2, c2, &settings)?,
        ];
        if settings.persist_samples == 0 || settings.persist_samples > settings.max_refused_samples
        {
            return Err(SamplerError::Settings);
        }
        Ok(Self {
            channels,
            scale,
            settings,
            seq: 0,
        })
    }

    /// Reads every sensor once, with the steppers' commanded positions now (microsteps since power-up,
    /// cables 0, 1, 2), and returns the sample. Every sensor is read every sample, faulted or not.
    pub fn sample(&mut self, commanded_steps: [i32; CABLES]) -> Sample<SampleError<S::Error>> {
        let [a, b, c] = &mut self.channels;
        let [sa, sb, sc] = commanded_steps;
        let (scale, settings) = (&self.scale, &self.settings);
        let readings = [
            a.sample(sa, scale, settings),
            b.sample(sb, scale, settings),
            c.sample(sc, scale, settings),
        ];
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        Sample { seq, readings }
    }

    /// The mechanism is at its home pose now (driven there and held): each cable's next good
    /// reading is taken as home (its spool's zero offset moves to that angle, and the stepper's
    /// count then is home's), and every latched fault is cleared.
    pub fn rehome(&mut self) {
        for channel in &mut self.channels {
            channel.mode = Mode::Adopt;
            channel.streak = Streak::default();
        }
    }

    /// The cables may not be at home (the MCU started from a reset other than a power-up,
    /// [`crate::reset::ResetCause::home_is_known`]): every cable latches
    /// [`CableFault::HomeUnknown`] and gives no length until [`Sampler::rehome`].
    pub fn distrust_home(&mut self) {
        for channel in &mut self.channels {
            channel.mode = Mode::Faulted(CableFault::HomeUnknown);
            channel.streak = Streak::default();
        }
    }

    /// Each cable's latched fault.
    pub fn faults(&self) -> [Option<CableFault>; CABLES] {
        self.channels.each_ref().map(|c| match c.mode {
            Mode::Faulted(fault) => Some(fault),
            _ => None,
        })
    }

    /// Each cable's last accepted multi-turn position, counts (`None` before the first, or while
    /// faulted).
    pub fn positions_counts(&self) -> [Option<i32>; CABLES] {
        self.channels.each_ref().map(|c| match c.mode {
            Mode::Tracking(position) => Some(position),
            _ => None,
        })
    }

    /// The number the next sample will have.
    pub fn next_seq(&self) -> u32 {
        self.seq
    }
}

impl<S: AngleSensor> Channel<S> {
    fn new(
        sensor: S,
        calibration: SpoolCalibration<f32>,
        settings: &SamplerSettings,
    ) -> Result<Self, SamplerError> {
        calibration.validate().map_err(SamplerError::Calibration)?;
        let turn = sensor.counts_per_turn();
        if !multiturn::valid_counts_per_turn(turn) {
            return Err(SamplerError::CountsPerTurn);
        }
        // The position may be this far from the last accepted one when the streak ends.
        let reach = u64::from(settings.max_refused_samples) + 1;
        let reach = reach * u64::from(settings.max_step_counts_per_sample)
            + u64::from(settings.tolerance_counts);
        if reach >= u64::from(turn / 2) {
            return Err(SamplerError::Settings);
        }
        let home_counts = i32::try_from(calibration.zero_offset_counts)
            .map_err(|_| SamplerError::Calibration(CalibrationError::Unrepresentable))?;
        Ok(Self {
            sensor,
            calibration,
            home_counts,
            home_steps: 0,
            mode: Mode::PowerUp,
            streak: Streak::default(),
            still: Still {
                angle: multiturn::angle(home_counts, turn),
                commanded: home_counts,
            },
        })
    }

    fn turn(&self) -> u32 {
        self.sensor.counts_per_turn()
    }

    fn sample(
        &mut self,
        steps: i32,
        scale: &StepperScale,
        settings: &SamplerSettings,
    ) -> Result<f32, SampleError<S::Error>> {
        // Read first, whatever the state: the bus sees the same traffic every sample.
        let read = self.sensor.read_angle_counts();
        if let Mode::Faulted(fault) = self.mode {
            return Err(SampleError::Fault(fault));
        }
        let turn = self.turn();
        let raw = match read {
            Ok(raw) => raw,
            Err(e) => return Err(self.refuse(SampleError::Sensor(e), None, 0, settings)),
        };
        if self.mode == Mode::Adopt {
            return match multiturn::nearest(self.home_counts, raw, turn) {
                Ok(home) => {
                    self.home_counts = home;
                    self.calibration.zero_offset_counts = i64::from(home);
                    self.home_steps = steps;
                    self.still = Still {
                        angle: raw,
                        commanded: home,
                    };
                    Ok(self.accept(home))
                }
                Err(e) => Err(self.refuse(e.into(), None, 0, settings)),
            };
        }
        let commanded = self
            .home_counts
            .saturating_add(scale.counts(steps.wrapping_sub(self.home_steps)));
        // Placed nearest the last accepted position (never the stepper's: the two stay independent
        // witnesses); before the first, nearest the stepper's, which starts at home.
        let reference = match self.mode {
            Mode::Tracking(position) => position,
            _ => commanded,
        };
        let position = match multiturn::nearest(reference, raw, turn) {
            Ok(position) => position,
            Err(e) => return Err(self.refuse(e.into(), None, commanded, settings)),
        };
        if multiturn::shortest(
            i32::from(raw).wrapping_sub(i32::from(self.still.angle)),
            turn,
        )
        .unsigned_abs()
            > settings.still_counts
            || self.mode == Mode::PowerUp
        {
            self.still = Still {
                angle: raw,
                commanded,
            };
        }
        let deviation = position.saturating_sub(commanded);
        if deviation.unsigned_abs() <= settings.tolerance_counts {
            return Ok(self.accept(position));
        }
        let refusal = SampleError::Disagrees {
            deviation_counts: deviation,
        };
        Err(self.refuse(refusal, Some(deviation), commanded, settings))
    }

    /// Accepts a position: the streak ends; returns the cable's length.
    fn accept(&mut self, position: i32) -> f32 {
        self.mode = Mode::Tracking(position);
        self.streak = Streak::default();
        self.calibration.length_m(i64::from(position))
    }

    /// Counts a refused sample (with its deviation if it had a reading), names and latches a fault
    /// when the evidence is in, and returns what the sample reports.
    fn refuse(
        &mut self,
        refusal: SampleError<S::Error>,
        deviation: Option<i32>,
        commanded: i32,
        settings: &SamplerSettings,
    ) -> SampleError<S::Error> {
        let tolerance = settings.tolerance_counts;
        let streak = &mut self.streak;
        streak.samples = streak.samples.saturating_add(1);
        if let Some(d) = deviation {
            if streak.readings == 0 {
                streak.first_deviation = d;
                streak.steady = true;
            } else if d.abs_diff(streak.first_deviation) > tolerance {
                streak.steady = false;
            }
            streak.readings = streak.readings.saturating_add(1);
        }
        let streak = *streak;
        let persisted = streak.readings >= settings.persist_samples && streak.steady;
        let fault = match self.mode {
            // Nothing tracked yet: only a steady disagreement with home is evidence (a sensor still
            // starting up just keeps failing).
            Mode::PowerUp => persisted.then_some(CableFault::PowerUpOffHome {
                offset_counts: streak.first_deviation,
            }),
            Mode::Tracking(_) => {
                let moved = commanded.saturating_sub(self.still.commanded);
                if deviation.is_some()
                    && streak.samples >= settings.persist_samples
                    && moved.unsigned_abs() > tolerance
                {
                    Some(CableFault::StuckSensor {
                        angle_counts: self.still.angle,
                        commanded_move_counts: moved,
                    })
                } else if persisted {
                    Some(whole_turns_or_offset(
                        streak.first_deviation,
                        self.turn(),
                        tolerance,
                    ))
                } else if streak.samples >= settings.max_refused_samples {
                    Some(CableFault::RefusalStreak {
                        samples: streak.samples,
                    })
                } else {
                    None
                }
            }
            Mode::Adopt | Mode::Faulted(_) => None,
        };
        match fault {
            Some(fault) => {
                self.mode = Mode::Faulted(fault);
                SampleError::Fault(fault)
            }
            None => refusal,
        }
    }
}

/// A steady offset: whole turns (within the tolerance) are turn aliasing, anything else a slip.
fn whole_turns_or_offset(offset: i32, counts_per_turn: u32, tolerance: u32) -> CableFault {
    let rest = multiturn::shortest(offset, counts_per_turn);
    let turn = i32::try_from(counts_per_turn).unwrap_or(i32::MAX);
    let turns = offset.saturating_sub(rest) / turn;
    if turns != 0 && rest.unsigned_abs() <= tolerance {
        CableFault::TurnAliasing { turns }
    } else {
        CableFault::SlippedMagnet {
            offset_counts: offset,
        }
    }
}

// `pub(crate)`: the scenario tests drive the same scripted shafts.
#[cfg(test)]
pub(crate) mod tests;
