//! What the firmware runs: the golden three-cable bench (39 cm Nitinol rod, five guides, cables at
//! 0/120/240 degrees) at [`STEPS_PER_SECTION`], three AS5047P spools, a 100 Hz loop.

use model_checks::reference::{FREE_LENGTH_M, golden_bench};
use model_core::inverse::{EstimatorSettings, InverseSettings};
use model_core::{Model, ModelError, Quaternion, Scalar};

use crate::control::{LoopConfig, SHAPE_POINTS};
use crate::encoder::as5047p::COUNTS_PER_TURN;
use crate::spool::{Direction, SpoolCalibration};

/// RK4 steps over the rod (one section; the plan adds one per guide interval: 22 in all). At 20 the
/// f32 inverse reproduces the golden tips within 0.02 mm; the cost of a sweep is linear in it.
pub const STEPS_PER_SECTION: u16 = 20;

/// Control period, s (100 Hz).
pub const TICK_PERIOD_S: f32 = 0.01;

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

/// Largest angle step the turn tracker accepts between reads, counts: three eighths of a sensor
/// turn, 1.47 mm of cable (three times the speed limit, short of the half turn that would alias).
pub const MAX_UNWRAP_STEP_COUNTS: u32 = COUNTS_PER_TURN * 3 / 8;

/// Cable lengths at the calibration pose, m: the bench under a 0.14 N downward and 0.12 N sideways
/// tip force (the recorded trajectory's first tick). A single-turn sensor behind a gearhead knows
/// its turn only from a known pose: at power-up each cable must be within half a sensor turn
/// (0.98 mm) of it.
pub const HOME_LENGTHS_M: [f64; 3] = [0.389_941, 0.377_469, 0.384_198];

/// The three spools, calibrated at the home pose. The home counts sit near a sensor turn boundary
/// for cable 0, and cable 1 reels in with increasing counts.
pub fn spools<T: Scalar>() -> [SpoolCalibration<T>; 3] {
    let [l0, l1, l2] = HOME_LENGTHS_M;
    let spool = |zero_offset_counts, length_at_zero_m, direction| SpoolCalibration {
        radius_m: T::lit(SPOOL_RADIUS_M),
        counts_per_spool_turn: T::lit(f64::from(GEAR_RATIO * COUNTS_PER_TURN)),
        zero_offset_counts,
        length_at_zero_m: T::lit(length_at_zero_m),
        direction,
    };
    [
        spool(16_380, l0, Direction::PayOutWithCounts),
        spool(5 * 16_384 + 8_000, l1, Direction::ReelInWithCounts),
        spool(-3 * 16_384 + 100, l2, Direction::PayOutWithCounts),
    ]
}

/// Nodes the estimator's model can hold. The bench's plan needs 7 (17 with the accurate guide
/// mass); the plan is most of a model's RAM, 48 bytes a node in f32, so the model-core default (72,
/// for any scene within model-core's limits) would cost 2.5 KB more of the 16 KiB budget.
pub const MODEL_NODES: usize = 20;

/// The estimator's model: f32, quaternion attitude, [`MODEL_NODES`] nodes.
pub type BenchModel = Model<f32, Quaternion<f32>, MODEL_NODES>;

/// The estimator's model of the bench, in f32.
///
/// # Errors
/// Never for these constants; [`ModelError`] if the bench were invalid.
// Out of line: building the plan takes temporaries that need not stay on the caller's stack.
#[inline(never)]
pub fn model() -> Result<BenchModel, ModelError> {
    Model::new(golden_bench(STEPS_PER_SECTION)?)
}

/// Cable length per encoder count, m.
pub fn metres_per_count() -> f32 {
    spools::<f32>()[0].metres_per_count()
}

/// The loop's settings: measurement noise from the encoder resolution, three sweeps per tick,
/// backbone points at the quarters of the rod.
pub fn loop_config() -> LoopConfig {
    let quarter = FREE_LENGTH_M as f32 / SHAPE_POINTS as f32;
    LoopConfig {
        tick_period_s: TICK_PERIOD_S,
        max_cable_speed_m_per_s: MAX_CABLE_SPEED_M_PER_S,
        step_margin_m: STEP_MARGIN_M,
        estimator: EstimatorSettings {
            max_sweeps: 4,
            ..EstimatorSettings::with_inverse(InverseSettings::with_resolution(metres_per_count()))
        },
        shape_s_m: core::array::from_fn(|i| quarter * (i + 1) as f32),
        restart_after: 3,
    }
}
