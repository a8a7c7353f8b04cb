//! What the firmware runs, and the one place that says so (the composition root): the three-cable
//! bench (a 39 cm Nitinol rod, five guides, cables at 0/120/240 degrees) built here from its
//! constants in SI units at [`STEPS_PER_SECTION`], three stepper-driven spools with AS5047P
//! sensors sampled and cross-checked at 1 kHz, a 100 Hz estimator loop.
//! The library's other modules take the model and settings they are given.
//!
//! The robot is the golden reference's bench (thesis experiment 2, average-mass model); a host test
//! in [`crate::checks`] holds [`rod`] equal, field by field and bit for bit, to
//! `model_checks::reference::golden_bench`, so the two cannot drift apart silently.

use model_core::inverse::{EstimatorSettings, InverseSettings};
use model_core::{
    Cable, CrossSection, Guide, GuideMass, Material, Model, ModelError, Quaternion, Rod, Scalar,
    Section, Stiffness,
};
use nalgebra::{Vector2, Vector3};

use crate::control::{LoopConfig, SHAPE_POINTS};
use crate::encoder::AngleSensor;
use crate::encoder::as5047p::COUNTS_PER_TURN;
use crate::sampler::{Sampler, SamplerError, SamplerSettings};
use crate::spool::{Direction, SpoolCalibration};
use crate::stepper::{ScaleError, StepperScale};

/// Free length of the rod (one section): 40 cm of Nitinol, 1 cm of it in the base clamp, m.
pub const ROD_LENGTH_M: f64 = 0.39;

/// Rod diameter (solid circle), m.
pub const ROD_DIAMETER_M: f64 = 1.56e-3;

/// Young's modulus of the Nitinol, Pa (fitted; measured 61.6-62.7 GPa).
pub const YOUNGS_MODULUS_PA: f64 = 62.7e9;

/// Poisson's ratio of the Nitinol.
pub const POISSON_RATIO: f64 = 0.3;

/// Line density of rod and guides weighed together (14.9 g over the 40 cm rod) and spread evenly
/// (the average-mass model: the guides themselves are weightless, [`GuideMass::Ignore`]), kg/m.
pub const LINE_DENSITY_KG_PER_M: f64 = 0.0149 / 0.40;

/// Cable guides on the rod.
pub const GUIDE_COUNT: usize = 5;

/// Guide thickness along the rod, m.
pub const GUIDE_THICKNESS_M: f64 = 3.01e-3;

/// Arc length of the first guide's centre, m: it starts 3.9 mm from the clamp.
pub const GUIDE_FIRST_CENTRE_M: f64 = 0.0039 + GUIDE_THICKNESS_M / 2.0;

/// Distance between guide centres, m.
pub const GUIDE_PITCH_M: f64 = 0.095;

/// Distance of the cable holes from the backbone, m.
pub const CABLE_RADIUS_M: f64 = 0.01;

/// The three cable holes' directions `(cos a, sin a)` in the guide's frame, at a = 0, 120 and 240
/// degrees, as literals: building the bench takes no trigonometry (the firmware links no sine).
/// Cable 0 is on the upper side (+y at the base).
pub const CABLE_DIRECTIONS: [(f64, f64); 3] = [
    (1.0, 0.0),
    (-0.5, 0.866_025_403_784_438_6),
    (-0.5, -0.866_025_403_784_438_6),
];

/// Standard gravity, m/s^2, along global -y.
pub const GRAVITY_M_S2: f64 = 9.81;

/// RK4 steps over the rod (one section; the plan adds one per guide interval: 22 in all). At 20 the
/// f32 inverse reproduces the golden tips within 0.02 mm; the cost of a sweep is linear in it.
pub const STEPS_PER_SECTION: u16 = 20;

/// Estimator (control) period, s (100 Hz).
pub const TICK_PERIOD_S: f32 = 0.01;

/// Sampler rate, Hz: every encoder is read, tracked and cross-checked against its stepper once a
/// millisecond, in a timer task that preempts the estimator.
pub const SAMPLE_RATE_HZ: u32 = 1000;

/// Sampler period, s.
pub const SAMPLE_PERIOD_S: f32 = 1.0 / SAMPLE_RATE_HZ as f32;

/// Samples per estimator tick.
pub const SAMPLES_PER_TICK: u32 = 10;

/// The live link's UART rate, baud (8N1): a record of this robot (128 bytes at most) takes 1.4 ms
/// of the 10 ms tick; at 115 200 baud it would take 11 ms, longer than the tick.
pub const LINK_BAUD: u32 = 921_600;

/// Fastest cable speed the drives can produce, m/s: 0.5 mm per tick.
pub const MAX_CABLE_SPEED_M_PER_S: f32 = 0.05;

/// Margin on the per-tick cable step for quantisation, m (five counts of 1.9 um).
pub const STEP_MARGIN_M: f32 = 1.0e-5;

/// Spool radius at the cable's centreline, m.
pub const SPOOL_RADIUS_M: f64 = 0.005;

/// Gearhead ratio between the motor shaft (where the AS5047P sits) and the spool. With 8 sensor
/// turns per spool turn a count is 0.24 um of cable (std 0.07 um): quantisation then moves the tip
/// by about 10 um. A sensor on the spool itself (ratio 1, 1.9 um a count) moves it by up to 0.1 mm.
pub const GEAR_RATIO: u32 = 8;

/// Cable per sensor turn, m: `2 pi r / GEAR_RATIO`, 3.93 mm (half a turn: 1.96 mm).
pub const METRES_PER_SENSOR_TURN: f64 =
    2.0 * core::f64::consts::PI * SPOOL_RADIUS_M / GEAR_RATIO as f64;

/// Full steps per motor turn (a 1.8 degree hybrid stepper; the sensor sits on its shaft).
pub const MOTOR_FULL_STEPS_PER_TURN: u32 = 200;

/// The drivers' microstepping.
pub const MICROSTEPS_PER_FULL_STEP: u32 = 16;

/// Microsteps per motor (and sensor) turn: 3200, 5.12 sensor counts each.
pub const MICROSTEPS_PER_TURN: u32 = MOTOR_FULL_STEPS_PER_TURN * MICROSTEPS_PER_FULL_STEP;

/// How far the sensor may be from the stepper's commanded position, counts: one full step (81
/// counts, 19.5 um of cable). A loaded stepper lags its command by under a full step before it slips
/// (and a slip loses four full steps at a time); microstep error and the few microseconds between
/// reading the step counter and the sensor add a few counts. A sensor error smaller than this is
/// not seen by the cross-check (README.md, "Faults").
pub const CROSS_CHECK_TOLERANCE_COUNTS: u32 = COUNTS_PER_TURN / MOTOR_FULL_STEPS_PER_TURN;

/// An angle that moves by no more than this has not moved (the AS5047P's noise is a few counts).
pub const STILL_COUNTS: u32 = 4;

/// Refused samples in a row before their cause is named (a stuck sensor, a slipped magnet, turn
/// aliasing, power-up away from home): 10 ms.
pub const PERSIST_SAMPLES: u16 = 10;

/// Refused samples in a row after which a cable's turn is no longer known (the fault
/// `RefusalStreak`, until re-homed): 25 ms. At the speed limit the shaft turns
/// [`MAX_STEP_COUNTS_PER_SAMPLE`] counts a sample, so by then it may have moved 26 * 209 = 5434
/// counts since the last accepted read: one more tolerance and it stays below half a turn (8192),
/// where the nearest-turn rule would alias.
pub const MAX_REFUSED_SAMPLES: u16 = 25;

/// The most the shaft turns in one sample at [`MAX_CABLE_SPEED_M_PER_S`], counts, rounded up:
/// 0.05 mm of cable a millisecond over 0.24 um a count, 209.
pub const MAX_STEP_COUNTS_PER_SAMPLE: u32 = (MAX_CABLE_SPEED_M_PER_S as f64
    / SAMPLE_RATE_HZ as f64
    / (METRES_PER_SENSOR_TURN / COUNTS_PER_TURN as f64))
    as u32
    + 1;

// The streak limit keeps the nearest-turn rule unambiguous (checked again by `Sampler::new`).
const _: () = assert!(
    (MAX_REFUSED_SAMPLES as u32 + 1) * MAX_STEP_COUNTS_PER_SAMPLE + CROSS_CHECK_TOLERANCE_COUNTS
        < COUNTS_PER_TURN / 2
);

/// Cable lengths at the calibration (home) pose, m: the bench under a 0.14 N downward and 0.12 N
/// sideways tip force (the recorded trajectory's first tick). A single-turn sensor behind a gearhead
/// knows its turn only from a known pose: the spools' zero offsets are the sensors' angles here. At
/// power-up the sampler checks each angle against home and the stepper (which starts at home): a
/// cable more than one full step away, up to half a sensor turn (1.96 mm) either way, is the fault
/// `PowerUpOffHome` until re-homed (README.md, "Faults").
pub const HOME_LENGTHS_M: [f64; 3] = [0.389_941, 0.377_469, 0.384_198];

/// The spools' zero offsets: each sensor's multi-turn count at the home pose. They sit near a
/// sensor turn boundary for cable 0, and away from zero for the others.
pub const ZERO_OFFSET_COUNTS: [i64; 3] = [16_380, 5 * 16_384 + 8_000, -3 * 16_384 + 100];

/// The three spools, calibrated at the home pose ([`ZERO_OFFSET_COUNTS`]); cable 1 reels in with
/// increasing counts.
pub fn spools<T: Scalar>() -> [SpoolCalibration<T>; 3] {
    let [l0, l1, l2] = HOME_LENGTHS_M;
    let [z0, z1, z2] = ZERO_OFFSET_COUNTS;
    let spool = |zero_offset_counts, length_at_zero_m, direction| SpoolCalibration {
        radius_m: T::lit(SPOOL_RADIUS_M),
        counts_per_spool_turn: T::lit(f64::from(GEAR_RATIO * COUNTS_PER_TURN)),
        zero_offset_counts,
        length_at_zero_m: T::lit(length_at_zero_m),
        direction,
    };
    [
        spool(z0, l0, Direction::PayOutWithCounts),
        spool(z1, l1, Direction::ReelInWithCounts),
        spool(z2, l2, Direction::PayOutWithCounts),
    ]
}

/// Nodes the estimator's model can hold. The bench's plan needs 7 (17 with the accurate guide
/// mass); the plan is most of a model's RAM, 48 bytes a node in f32, so the model-core default (72,
/// for any scene within model-core's limits) would cost 2.5 KB more of the 16 KiB budget.
pub const MODEL_NODES: usize = 20;

/// The estimator's model: f32, quaternion attitude, [`MODEL_NODES`] nodes.
pub type BenchModel = Model<f32, Quaternion<f32>, MODEL_NODES>;

/// The bench as a rod in `T`, with `steps_per_section` RK4 steps over its one section (the
/// estimator uses [`STEPS_PER_SECTION`]): the constants above, each terminated cable running from
/// the first guide to the tip, the rod's default base (clamped at the origin, tangent along +x).
/// Every length is converted from its f64 constant once, as computed in f64.
///
/// # Errors
/// Never for these constants with `steps_per_section > 0`; [`ModelError`] if a value were invalid
/// (as zero steps is, when the model is built) or the rod's capacities too small.
pub fn rod<T: Scalar>(steps_per_section: u16) -> Result<Rod<T>, ModelError> {
    let mut rod = Rod::new();
    rod.gravity_m_s2 = Vector3::new(T::zero(), T::lit(-GRAVITY_M_S2), T::zero());
    rod.guide_mass = GuideMass::Ignore;
    let material = Material::isotropic(T::lit(YOUNGS_MODULUS_PA), T::lit(POISSON_RATIO))?;
    let cross_section = CrossSection::solid_circle(T::lit(ROD_DIAMETER_M))?;
    rod.push_section(Section {
        length_m: T::lit(ROD_LENGTH_M),
        stiffness: Stiffness::from_material(&material, &cross_section)?,
        line_density_kg_per_m: T::lit(LINE_DENSITY_KG_PER_M),
        steps: steps_per_section,
    })?;
    for k in 0..GUIDE_COUNT {
        rod.push_guide(Guide {
            s_m: T::lit(GUIDE_FIRST_CENTRE_M + k as f64 * GUIDE_PITCH_M),
            thickness_m: T::lit(GUIDE_THICKNESS_M),
            mass_kg: T::zero(),
        })?;
    }
    for (x, y) in CABLE_DIRECTIONS {
        rod.push_cable(Cable {
            hole_m: Vector2::new(T::lit(x * CABLE_RADIUS_M), T::lit(y * CABLE_RADIUS_M)),
            end_m: T::lit(ROD_LENGTH_M),
        })?;
    }
    Ok(rod)
}

/// The estimator's model of the bench, in f32 at [`STEPS_PER_SECTION`].
///
/// # Errors
/// Never for these constants; [`ModelError`] if the bench were invalid.
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
pub fn sampler<S: AngleSensor>(sensors: [S; 3]) -> Result<Sampler<S>, SamplerError> {
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
