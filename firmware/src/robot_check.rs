//! Any robot end to end: the robot the image was built for (its robot file, [`crate::config`]) along
//! a load path scaled to it, tick by tick through the estimator loop. Each tick's cable lengths are
//! the f32 model's at the applied tip force, read through the spools as whole sensor counts (the
//! drive's resolution) and validated as the sampler's would be; the loop estimates the force and
//! the shape from them.
//!
//! The check here holds the estimate to the applied force. The shape is held to the host: the
//! `robot` image prints each applied force and sends each tick's record on the live link, and
//! `test.sh` has host-sim solve the same robot file in f64 at those forces (`host-sim reference`)
//! and check the records against it (`host-sim monitor --check-against`). It runs for the default
//! robot and for `robots/two_section.toml`.

use core::convert::Infallible;

use model_core::{ShootingSettings, Start, TipLoad};
use nalgebra::Vector3;

use crate::checks::{BenchLoop, FORCE_TOLERANCE_N, Summary};
use crate::config::{BenchModel, CABLE_COUNT, SAMPLES_PER_TICK, loop_config, spools};
use crate::control::{EstimatorLoop, Status, TickReport};
use crate::sampler::{Sample, SampleError};

/// Ticks of the load path.
pub const PATH_TICKS: usize = 24;

/// The loop's report of a tick of the path (its readings cannot fail).
pub type PathReport = TickReport<SampleError<Infallible>>;

/// The tip force at `tick`, N, for a robot whose bending scale `E I / L^2` is `scale_n`: a slow
/// loop around a steady downward and sideways push, at most about half the bending scale, so that
/// the cables move by well under the drive's speed limit a tick.
pub fn tip_force_n(tick: usize, scale_n: f64) -> Vector3<f64> {
    // A quarter turn of the loop every six ticks; cos and sin of k pi / 12 from a rotation, since
    // the firmware links no sine.
    let (mut c, mut s) = (1.0f64, 0.0f64);
    let (step_c, step_s) = (0.965_925_826_289_068_3, 0.258_819_045_102_520_8);
    for _ in 0..tick {
        (c, s) = (c * step_c - s * step_s, s * step_c + c * step_s);
    }
    Vector3::new(0.1 * s, -0.3 + 0.1 * c, 0.2 + 0.15 * s) * scale_n
}

/// The robot's bending scale `E I / L^2`, N (its smallest bending stiffness over its length
/// squared): what the load path and the force tolerance are scaled to.
pub fn bending_scale_n(model: &BenchModel) -> f64 {
    f64::from(model.moment_scale_nm() / model.length_m())
}

/// The largest force error a tick may have for a robot of bending scale `scale_n`, N: the
/// firmware's [`FORCE_TOLERANCE_N`], and at most a tenth of the bending scale, so that on a soft
/// robot an estimate of no force at all cannot pass (the path's loads are 0.2 to 0.5 scales).
pub fn force_tolerance_n(scale_n: f64) -> f64 {
    FORCE_TOLERANCE_N.min(0.1 * scale_n)
}

/// Why the path could not run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathError {
    /// The model or the loop refused its configuration.
    Model(model_core::ModelError),
    /// A forward solve that makes a tick's readings did not succeed.
    ForwardSolve(model_core::Termination),
    /// A spool cannot count a tick's cable length.
    Spool(crate::spool::CalibrationError),
}

impl From<model_core::ModelError> for PathError {
    fn from(e: model_core::ModelError) -> Self {
        Self::Model(e)
    }
}

/// One tick's verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTick {
    /// The tick.
    pub tick: u32,
    /// The tip force applied, N.
    pub applied_n: Vector3<f64>,
    /// What the loop said.
    pub status: Status<SampleError<Infallible>>,
    /// The estimate's force error, N (infinite without a fresh estimate).
    pub force_error_n: f64,
    /// Sweeps the estimate took.
    pub sweeps: u16,
    /// The tick's cost in the caller's clock units.
    pub cost: u64,
    /// A fresh estimate, its force within [`force_tolerance_n`] of the applied.
    pub passed: bool,
}

/// Runs the load path on `model`, calling `report` with each tick's verdict, the loop's report and
/// the loop (after the tick's cost was measured). `clock` measures each tick's cost.
///
/// # Errors
/// [`PathError`] when the loop refuses its configuration, or the f32 model cannot make a tick's
/// readings (a forward solve that fails, a length the spools cannot count).
pub fn run_path(
    model: &BenchModel,
    clock: &dyn Fn() -> u64,
    mut report: impl FnMut(&PathTick, &PathReport, &BenchLoop<'_>),
) -> Result<Summary, PathError> {
    let mut estimator = EstimatorLoop::new(model, loop_config())?;
    let spools = spools::<f32>();
    let scale_n = bending_scale_n(model);
    let force_tolerance_n = force_tolerance_n(scale_n);
    let settings = ShootingSettings::default();
    let mut start = Start::Cold;
    let mut summary = Summary::default();
    for tick in 0..PATH_TICKS {
        let applied_n = tip_force_n(tick, scale_n);
        let eq = model.solve(&TipLoad::force(applied_n.cast::<f32>()), start, &settings)?;
        if !eq.report.termination.is_success() {
            return Err(PathError::ForwardSolve(eq.report.termination));
        }
        start = Start::Warm(eq.base_strain_per_m);
        // Each length as the drive reads it: the nearest whole count of its sensor.
        let mut readings: [Result<f32, SampleError<Infallible>>; CABLE_COUNT] =
            [Ok(0.0); CABLE_COUNT];
        for ((reading, spool), length) in readings.iter_mut().zip(&spools).zip(&eq.cable_lengths_m)
        {
            let counts = spool.position_counts(*length).map_err(PathError::Spool)?;
            *reading = Ok(spool.length_m(counts));
        }
        let sample = Sample {
            seq: tick as u32 * SAMPLES_PER_TICK,
            readings,
        };
        let begin = clock();
        let out = estimator.tick(&sample);
        let cost = clock().saturating_sub(begin);
        if tick > 0 {
            summary.max_warm_cost = summary.max_warm_cost.max(cost);
        }
        let fresh = out
            .estimate
            .filter(|r| matches!(out.status, Status::Fresh) && r.tick as usize == tick);
        let (force_error_n, sweeps) = fresh.map_or((f64::INFINITY, 0), |r| {
            let error = Vector3::from(r.tip_force_n).cast::<f64>() - applied_n;
            (error.norm(), r.sweeps)
        });
        let passed = force_error_n <= force_tolerance_n;
        summary.add(passed, 0.0, force_error_n, sweeps);
        let check = PathTick {
            tick: out.tick,
            applied_n,
            status: out.status,
            force_error_n,
            sweeps,
            cost,
            passed,
        };
        report(&check, &out, &estimator);
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_robot_follows_its_load_path_on_the_host_in_f32() -> Result<(), PathError> {
        let model = crate::config::model()?;
        let mut ticks = Vec::new();
        let summary = run_path(&model, &|| 0, |t, _, _| ticks.push(*t))?;
        for t in &ticks {
            println!("{t:?}");
        }
        assert_eq!((summary.passed, summary.failed), (PATH_TICKS, 0));
        // The path loads the robot: at least a quarter of its bending scale.
        let scale_n = bending_scale_n(&model);
        assert!(ticks.iter().all(|t| t.applied_n.norm() > 0.25 * scale_n));
        Ok(())
    }

    #[test]
    fn the_path_closes_its_loop() {
        // 24 steps of 15 degrees: back where it started, to rounding.
        let (first, last) = (tip_force_n(0, 1.0), tip_force_n(PATH_TICKS, 1.0));
        assert!((first - last).norm() < 1e-12, "{first} {last}");
        let quarter = tip_force_n(6, 1.0);
        assert!(
            (quarter - Vector3::new(0.1, -0.3, 0.35)).norm() < 1e-12,
            "{quarter}"
        );
    }
}
