//! What the firmware runs, and the one place that says so (the composition root): the robot of the
//! robot file it was built from (`ROBOT=path/to/robot.toml`, `robots/bench.toml` by default: the
//! three-cable bench, a 39 cm Nitinol rod with five guides), read by `build.rs` with the host tools'
//! own parser and written as the constants included below; three stepper-driven spools with AS5047P
//! sensors sampled and cross-checked at the file's sampling rate, and the estimator loop at its loop
//! rate. The library's other modules take the model and settings they are given.
//!
//! Every number of the robot is the robot file's, as the host computes it in f64 (the stiffness
//! from the material and cross-section, the guides' arc lengths), converted to the estimator's
//! scalar once ([`rod`]). A robot that does not fit the image is a build error naming the capacity
//! and the value (`build.rs`, the parser it calls, and the assertions below and in `target/`).
//!
//! The default robot is the golden reference's bench (thesis experiment 2, average-mass model); a
//! host test in [`crate::checks`] holds [`rod`] equal to `model_checks::reference::golden_bench`,
//! field by field, so the file and the reference cannot drift apart silently.

use model_core::inverse::{EstimatorSettings, InverseSettings};
use model_core::{Model, ModelError, Quaternion, Rod, Scalar};

use crate::control::{LoopConfig, SHAPE_POINTS};
use crate::encoder::AngleSensor;
use crate::encoder::as5047p::COUNTS_PER_TURN;
use crate::sampler::{Sampler, SamplerError, SamplerSettings};
use crate::stepper::{ScaleError, StepperScale};

include!(concat!(env!("OUT_DIR"), "/robot.rs"));

/// Estimator (control) period, s.
pub const TICK_PERIOD_S: f32 = 1.0 / LOOP_RATE_HZ as f32;

/// Sampler period, s.
pub const SAMPLE_PERIOD_S: f32 = 1.0 / SAMPLE_RATE_HZ as f32;

/// Samples per estimator tick (the robot file's rates divide: `robot-scene` checks it).
pub const SAMPLES_PER_TICK: u32 = SAMPLE_RATE_HZ / LOOP_RATE_HZ;

/// The live link's UART rate, baud (8N1): a record of a three-cable robot (128 bytes at most) takes
/// 1.4 ms of a 10 ms tick; at 115 200 baud it would take 11 ms, longer than the tick.
pub const LINK_BAUD: u32 = 921_600;

/// Margin on the per-tick cable step for quantisation, m (five counts of 1.9 um).
pub const STEP_MARGIN_M: f32 = 1.0e-5;

/// Cable per sensor turn, m: `2 pi r / GEAR_RATIO` (the bench's: 3.93 mm; half a turn 1.96 mm).
pub const METRES_PER_SENSOR_TURN: f64 =
    2.0 * core::f64::consts::PI * SPOOL_RADIUS_M / GEAR_RATIO as f64;

/// Microsteps per motor (and sensor) turn (the bench's: 3200, 5.12 sensor counts each).
pub const MICROSTEPS_PER_TURN: u32 = MOTOR_FULL_STEPS_PER_TURN * MICROSTEPS_PER_FULL_STEP;

/// How far the sensor may be from the stepper's commanded position, counts: one full step (81
/// counts, 19.5 um of cable on the bench). A loaded stepper lags its command by under a full step
/// before it slips (and a slip loses four full steps at a time); microstep error and the few
/// microseconds between reading the step counter and the sensor add a few counts. A sensor error
/// smaller than this is not seen by the cross-check (README.md, "Faults").
pub const CROSS_CHECK_TOLERANCE_COUNTS: u32 = COUNTS_PER_TURN / MOTOR_FULL_STEPS_PER_TURN;

/// An angle that moves by no more than this has not moved (the AS5047P's noise is a few counts).
pub const STILL_COUNTS: u32 = 4;

/// Refused samples in a row before their cause is named (a stuck sensor, a slipped magnet, turn
/// aliasing, power-up away from home): 10 samples.
pub const PERSIST_SAMPLES: u16 = 10;

/// Refused samples in a row after which a cable's turn is no longer known (the fault
/// `RefusalStreak`, until re-homed): 25 ms at 1 kHz. At the bench's speed limit the shaft turns
/// [`MAX_STEP_COUNTS_PER_SAMPLE`] counts a sample, so by then it may have moved 26 * 209 = 5434
/// counts since the last accepted read: one more tolerance and it stays below half a turn (8192),
/// where the nearest-turn rule would alias.
pub const MAX_REFUSED_SAMPLES: u16 = 25;

/// The most the shaft turns in one sample at [`MAX_CABLE_SPEED_M_PER_S`], counts, rounded up (the
/// bench: 0.05 mm of cable a millisecond over 0.24 um a count, 209).
pub const MAX_STEP_COUNTS_PER_SAMPLE: u32 = (MAX_CABLE_SPEED_M_PER_S as f64
    / SAMPLE_RATE_HZ as f64
    / (METRES_PER_SENSOR_TURN / COUNTS_PER_TURN as f64))
    as u32
    + 1;

// The streak limit keeps the nearest-turn rule unambiguous (checked again by `Sampler::new`).
const _: () = assert!(
    (MAX_REFUSED_SAMPLES as u32 + 1) * MAX_STEP_COUNTS_PER_SAMPLE + CROSS_CHECK_TOLERANCE_COUNTS
        < COUNTS_PER_TURN / 2,
    "the robot file's drive turns the sensor too far in a sampling period: lower \
     max_cable_speed_m_per_s or gear_ratio, or raise sample_rate_hz or spool_radius_m"
);

/// Nodes the estimator's model holds: the robot's plan needs this many (the bench's 7; 17 with the
/// accurate guide mass). The plan is most of a model's RAM, 48 bytes a node in f32: model-core's
/// default capacity (any scene within its limits) would cost the bench 3.1 KB of its 16 KiB.
pub const MODEL_NODES: usize = PLAN_NODES;

/// The estimator's model: f32, quaternion attitude, [`MODEL_NODES`] nodes.
pub type BenchModel = Model<f32, Quaternion<f32>, MODEL_NODES>;

/// The robot as a rod in `T`, with `steps_per_section` RK4 steps over each section (the estimator
/// uses [`STEPS_PER_SECTION`]): the robot file's numbers, each converted from the host's f64 once.
///
/// # Errors
/// [`ModelError`] if `steps_per_section` is zero (when the model is built) or a capacity of the
/// rod is too small (which the build rules out).
pub fn rod<T: Scalar>(steps_per_section: u16) -> Result<Rod<T>, ModelError> {
    let mut rod = Rod::new();
    push_robot(&mut rod, steps_per_section)?;
    Ok(rod)
}

/// The estimator's model of the robot, in f32 at [`STEPS_PER_SECTION`].
///
/// # Errors
/// Never for a robot the build accepted; [`ModelError`] if the robot were invalid.
// Out of line: building the plan takes temporaries that need not stay on the caller's stack.
#[inline(never)]
pub fn model() -> Result<BenchModel, ModelError> {
    Model::new(rod(STEPS_PER_SECTION)?)
}

/// Cable length per encoder count, m.
pub fn metres_per_count() -> f32 {
    spools::<f32>()[0].metres_per_count()
}

/// The model's own error at [`STEPS_PER_SECTION`], m (one standard deviation), in a cable length
/// and in the tip position: its discretisation against the converged model over the loads the robot
/// meets, with a margin of two (measured by `checks::tests::the_model_error_is_covered`: 0.15 um
/// and 0.15 um at 20 steps). The f32 floor (0.24 um, 9.4 um) is added by model-core.
pub const MODEL_LENGTH_STD_M: f32 = 4.0e-7;
/// See [`MODEL_LENGTH_STD_M`].
pub const MODEL_TIP_STD_M: f32 = 4.0e-7;

/// The largest tip load the estimator looks for other answers at, in buckling scales (`E I / L^2`,
/// 0.12 N on the bench): 16, about 1.9 N, four times the largest load of the recording.
pub const SCAN_REACH: f32 = 16.0;

/// Sweeps one cold estimate may take, its forward solve included: its cost bound. At the loop's 20
/// steps a sweep with its tangents costs about 176 k instructions, so 100 (and the last step's, up to
/// 9 more) stay within 19.2 M instructions, inside the 20 M a restart may take
/// (`expected/bench.run`, `inverse_cold_budget`: readings whose search for other answers runs out
/// of it). A good cold estimate takes about 60.
pub const COLD_SWEEPS: u16 = 100;

/// The steppers' microsteps in sensor counts.
pub const STEPPER_SCALE: Result<StepperScale, ScaleError> =
    StepperScale::new(COUNTS_PER_TURN, MICROSTEPS_PER_TURN);

/// The sampler's cross-check settings.
pub fn sampler_settings() -> SamplerSettings {
    SamplerSettings {
        tolerance_counts: CROSS_CHECK_TOLERANCE_COUNTS,
        still_counts: STILL_COUNTS,
        persist_samples: PERSIST_SAMPLES,
        max_refused_samples: MAX_REFUSED_SAMPLES,
        max_step_counts_per_sample: MAX_STEP_COUNTS_PER_SAMPLE,
    }
}

/// The sampler over three angle sensors (cables 0, 1, 2), calibrated by [`spools`], cross-checked
/// with [`sampler_settings`] against steppers of [`STEPPER_SCALE`].
///
/// # Errors
/// [`SamplerError`] if the sensors or the settings do not suit the sampler.
pub fn sampler<S: AngleSensor>(sensors: [S; CABLE_COUNT]) -> Result<Sampler<S>, SamplerError> {
    let scale = STEPPER_SCALE.map_err(SamplerError::Stepper)?;
    Sampler::new(sensors, spools::<f32>(), scale, sampler_settings())
}

/// The loop's settings: measurement noise from the encoder resolution and the model's own error,
/// five sweeps per tick, backbone points at the quarters of the rod.
pub fn loop_config() -> LoopConfig {
    let quarter = ROD_LENGTH_M as f32 / SHAPE_POINTS as f32;
    LoopConfig {
        sample_period_s: SAMPLE_PERIOD_S,
        max_cable_speed_m_per_s: MAX_CABLE_SPEED_M_PER_S,
        step_margin_m: STEP_MARGIN_M,
        estimator: EstimatorSettings {
            max_sweeps: 6,
            ..EstimatorSettings::with_inverse(InverseSettings {
                model_length_std_m: MODEL_LENGTH_STD_M,
                model_tip_std_m: MODEL_TIP_STD_M,
                scan_reach: SCAN_REACH,
                max_sweeps: COLD_SWEEPS,
                ..InverseSettings::with_resolution(metres_per_count())
            })
        },
        shape_s_m: core::array::from_fn(|i| quarter * (i + 1) as f32),
        restart_after: 3,
    }
}
