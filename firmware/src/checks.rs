//! The checks the QEMU images run, target-agnostic so that the host tests run the same code.
//!
//! * [`run_trajectory`]: the recorded encoder trajectory ([`crate::fixture::ANGLE_COUNTS`]) through
//!   the sampler (ten samples a tick, each cross-checked against the recorded steppers) and the
//!   estimator loop, each tick against the f64 reference, with a sensor fault and a glitch injected
//!   on the way (both must be refused, the last estimate kept, and no fault latched).
//! * [`run_golden`]: the golden 3D rows, from their cable lengths alone.
//!
//! Its host tests also hold the composition root's robot ([`crate::config::rod`]) equal to the
//! golden reference's bench (`model_checks::reference::golden_bench`).

use model_checks::reference::golden_rows;
use model_core::{ModelError, Termination};

use crate::config::{BenchModel, MODEL_NODES, SAMPLES_PER_TICK, loop_config};
use crate::control::{EstimatorLoop, Status, TickRecord, TickReport};
use crate::encoder::replay::ReplayError;
use crate::fixture::{
    JUMP_COUNTS, JUMP_TICK, REFERENCE, RecordedSensor, RecordedSteppers, Reference,
    SENSOR_FAULT_TICK, TICK_COUNT,
};
use crate::sampler::{SampleError, SamplerError};
use crate::validate::Rejection;
use model_core::inverse::{Estimator, LoadBasis};
use nalgebra::Vector3;

/// An estimate's tip error against the converged f64 reference may be at most this many times the
/// tip standard deviation it reports (the length of its per-axis vector): the uncertainty includes
/// the model's own error.
pub const COVERAGE: f64 = 5.0;

/// Largest tip error against the f64 reference, m (0.1 mm).
pub const TIP_TOLERANCE_M: f64 = 1.0e-4;

/// Largest tip force error against the applied force, N. The cables determine the force to about
/// 1-2 mN (the estimate's own standard deviation at 1.9 um per count); the warm loop adds its lag.
pub const FORCE_TOLERANCE_N: f64 = 5.0e-3;

/// Why a check could not start.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum SetupError {
    /// The model or the loop refused its configuration.
    Model(ModelError),
    /// The sampler refused its sensors, calibrations or settings.
    Sampler(SamplerError),
}

impl From<ModelError> for SetupError {
    fn from(e: ModelError) -> Self {
        Self::Model(e)
    }
}

impl From<SamplerError> for SetupError {
    fn from(e: SamplerError) -> Self {
        Self::Sampler(e)
    }
}

/// The estimator loop over the firmware's robot ([`BenchModel`]).
pub type BenchLoop<'m> = EstimatorLoop<'m, model_core::Quaternion<f32>, MODEL_NODES>;

/// The loop's report of one tick of the recording.
pub type ReplayReport = TickReport<SampleError<ReplayError>>;

/// What a tick of the trajectory was expected to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Expected {
    /// A fresh estimate within tolerance.
    Fresh,
    /// The injected sensor fault refused, the last estimate kept.
    SensorFault,
    /// The injected glitch refused by the stepper cross-check, the last estimate kept.
    Jump,
}

/// One tick's verdict.
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct TickCheck {
    /// The tick.
    pub tick: u32,
    /// What it had to do.
    pub expected: Expected,
    /// What the loop said.
    pub status: Status<SampleError<ReplayError>>,
    /// The tick of the estimate the loop reported (`None` if it had none).
    pub estimate_tick: Option<u32>,
    /// Tip error of that estimate against the reference at its own tick, m.
    pub tip_error_m: f64,
    /// Force error of that estimate against the applied force at its own tick, N.
    pub force_error_n: f64,
    /// Sweeps the estimate took.
    pub sweeps: u16,
    /// The loop tick's cost in the caller's clock units (the sampling is counted apart).
    pub cost: u64,
    /// Whether the tick did what was expected, within tolerance.
    pub passed: bool,
}

/// The tally of a check.
#[derive(Clone, Copy, Debug, Default, PartialEq, defmt::Format)]
pub struct Summary {
    /// Cases (ticks or rows) that passed.
    pub passed: usize,
    /// Cases that failed.
    pub failed: usize,
    /// Worst tip error, m.
    pub worst_tip_error_m: f64,
    /// Worst force error, N.
    pub worst_force_error_n: f64,
    /// Most sweeps one estimate took.
    pub max_sweeps: u16,
    /// The costliest warm tick (every tick but the first), in the caller's clock units.
    pub max_warm_cost: u64,
    /// The costliest sample (three sensors read, tracked and cross-checked), in the caller's clock
    /// units.
    pub max_sample_cost: u64,
}

impl Summary {
    pub(crate) fn add(&mut self, passed: bool, tip_error_m: f64, force_error_n: f64, sweeps: u16) {
        if passed {
            self.passed += 1;
        } else {
            self.failed += 1;
        }
        self.worst_tip_error_m = self.worst_tip_error_m.max(tip_error_m);
        self.worst_force_error_n = self.worst_force_error_n.max(force_error_n);
        self.max_sweeps = self.max_sweeps.max(sweeps);
    }
}

fn distance(a: [f32; 3], b: [f64; 3]) -> f64 {
    let d = a.iter().zip(b).map(|(x, y)| {
        let e = f64::from(*x) - y;
        e * e
    });
    libm_sqrt(d.sum())
}

/// The length of a vector of standard deviations, m.
fn norm(v: [f32; 3]) -> f64 {
    libm_sqrt(v.iter().map(|x| f64::from(*x) * f64::from(*x)).sum())
}

/// `sqrt` without std: nalgebra's, which is libm's.
fn libm_sqrt(x: f64) -> f64 {
    <f64 as nalgebra::ComplexField>::sqrt(x)
}

fn errors(record: &TickRecord, reference: &Reference) -> (f64, f64) {
    (
        distance(record.tip_position_m, reference.tip_m),
        distance(record.tip_force_n, reference.force_n),
    )
}

/// Replays the recorded trajectory through the sampler (ten samples a tick, against the recorded
/// steppers) and the estimator loop on `model`, calling `report` with each tick's verdict, the
/// loop's own report and the loop as the tick left it (the live link reads its tip frame), after
/// the tick's cost was measured. Each tick takes the sample of its recorded instant. `clock`
/// measures each tick's and each sample's cost (an instruction counter on the MCU; anything
/// monotonic, or a constant, on the host).
///
/// # Errors
/// [`SetupError`] when the loop or the sampler refuses its configuration.
pub fn run_trajectory(
    model: &BenchModel,
    clock: &dyn Fn() -> u64,
    mut report: impl FnMut(&TickCheck, &ReplayReport, &BenchLoop<'_>),
) -> Result<Summary, SetupError> {
    let mut estimator = EstimatorLoop::new(model, loop_config())?;
    let mut sampler = crate::config::sampler([0, 1, 2].map(|c| RecordedSensor::new(c, 0)))?;
    let mut steppers = RecordedSteppers::new(0);
    let mut summary = Summary::default();
    for tick in 0..TICK_COUNT {
        // The samples up to this tick's instant: the loop takes the last.
        let due = tick as u32 * SAMPLES_PER_TICK;
        let sample = loop {
            let steps = steppers.commanded_steps(sampler.next_seq());
            let start = clock();
            let sample = sampler.sample(steps);
            summary.max_sample_cost = summary.max_sample_cost.max(clock().saturating_sub(start));
            if sample.seq >= due {
                break sample;
            }
        };
        let start = clock();
        let out = estimator.tick(&sample);
        let cost = clock().saturating_sub(start);
        if tick > 0 {
            summary.max_warm_cost = summary.max_warm_cost.max(cost);
        }
        let expected = match tick {
            SENSOR_FAULT_TICK => Expected::SensorFault,
            JUMP_TICK => Expected::Jump,
            _ => Expected::Fresh,
        };
        let status_ok = matches!(
            (expected, out.status),
            (Expected::Fresh, Status::Fresh)
                | (
                    Expected::SensorFault,
                    Status::Rejected(Rejection::Source {
                        cable: 1,
                        error: SampleError::Sensor(ReplayError::Injected),
                    })
                )
                | (
                    Expected::Jump,
                    Status::Rejected(Rejection::Source {
                        cable: 2,
                        error: SampleError::Disagrees { .. },
                    })
                )
        );
        // The glitch is refused as what it is: the stepper's position plus the glitch.
        let glitch_named = match out.status {
            Status::Rejected(Rejection::Source {
                error: SampleError::Disagrees { deviation_counts },
                ..
            }) => deviation_counts.abs_diff(i32::from(JUMP_COUNTS)) <= 8,
            _ => true,
        };
        // No fault may be latched on good data.
        let status_ok = status_ok && glitch_named && sampler.faults() == [None; 3];
        // A fresh estimate is this tick's; a refused tick must keep the previous tick's.
        let wanted_tick = match expected {
            Expected::Fresh => tick,
            _ => tick.saturating_sub(1),
        };
        let record = out.estimate.filter(|r| r.tick as usize == wanted_tick);
        let (tip_error_m, force_error_n, sweeps) = match (&record, REFERENCE.get(wanted_tick)) {
            (Some(r), Some(reference)) => {
                let (tip, force) = errors(r, reference);
                (tip, force, r.sweeps)
            }
            _ => (f64::INFINITY, f64::INFINITY, 0),
        };
        // The reported uncertainty covers the error against the converged f64 reference: the
        // model's own error (discretisation, f32) is part of it.
        let covered = record.is_some_and(|r| tip_error_m <= COVERAGE * norm(r.tip_std_m));
        let passed = status_ok
            && covered
            && tip_error_m <= TIP_TOLERANCE_M
            && force_error_n <= FORCE_TOLERANCE_N;
        summary.add(passed, tip_error_m, force_error_n, sweeps);
        let check = TickCheck {
            tick: out.tick,
            expected,
            status: out.status,
            estimate_tick: out.estimate.map(|r| r.tick),
            tip_error_m,
            force_error_n,
            sweeps,
            cost,
            passed,
        };
        report(&check, &out, &estimator);
    }
    Ok(summary)
}

/// One golden row's verdict.
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct RowCheck {
    /// The row, counting from 0.
    pub row: usize,
    /// How the cold estimate ended.
    pub termination: Termination,
    /// Tip error against the golden tip, m.
    pub tip_error_m: f64,
    /// Force error against the golden force, N.
    pub force_error_n: f64,
    /// Standard deviation of the force the estimate reports (largest component), N.
    pub force_std_n: f64,
    /// Sweeps the estimate took.
    pub sweeps: u16,
    /// Converged, and the tip within [`TIP_TOLERANCE_M`].
    pub passed: bool,
}

/// The f32 estimator's cold estimate (the loop's first tick) for each golden row's cable lengths,
/// calling `report` with each row's verdict.
///
/// # Errors
/// [`SetupError`] when the estimator refuses a row or its settings, or a row does not parse.
pub fn run_golden(
    model: &BenchModel,
    mut report: impl FnMut(&RowCheck),
) -> Result<Summary, SetupError> {
    let settings = loop_config().estimator;
    let mut summary = Summary::default();
    for (row, golden) in golden_rows().enumerate() {
        let golden = golden?;
        let lengths = golden.cables_m.map(|x| x as f32);
        let (_, estimate) = Estimator::new(
            model,
            LoadBasis::tip_force(),
            &lengths,
            Vector3::zeros(),
            settings,
        )?;
        let array = |v: &Vector3<f32>| [v.x, v.y, v.z];
        let tip_error_m = distance(array(&estimate.tip_position_m), golden.tip_m);
        let force_error_n = distance(array(&estimate.params), golden.force_n);
        let termination = estimate.report.termination;
        let covered = tip_error_m <= COVERAGE * norm(array(&estimate.quality.tip_std_m));
        let passed = termination.is_success() && covered && tip_error_m <= TIP_TOLERANCE_M;
        summary.add(passed, tip_error_m, force_error_n, estimate.report.sweeps);
        report(&RowCheck {
            row,
            termination,
            tip_error_m,
            force_error_n,
            force_std_n: f64::from(estimate.quality.force_std_n.max()),
            sweeps: estimate.report.sweeps,
            passed,
        });
    }
    Ok(summary)
}

/// Every number of a rod, in order, and its counts and models (what is not a number).
#[cfg(test)]
fn numbers<T: model_core::Scalar>(rod: &model_core::Rod<T>) -> (Vec<T>, String) {
    let mut x = Vec::new();
    for s in &rod.sections {
        x.push(s.length_m);
        x.extend(s.stiffness.bending_torsion_nm2.iter());
        x.extend(s.stiffness.shear_axial_n.iter());
        x.push(s.line_density_kg_per_m);
    }
    for g in &rod.guides {
        x.extend([g.s_m, g.thickness_m, g.mass_kg]);
    }
    for c in &rod.cables {
        x.extend(c.hole_m.iter());
        x.push(c.end_m);
    }
    x.extend(rod.gravity_m_s2.iter());
    x.extend(rod.base_position_m.iter());
    x.extend(rod.base_orientation.iter());
    let kinds = format!(
        "{:?} {:?} steps {:?} guides {} cables {} loads {}",
        rod.guide_mass,
        rod.strain_model,
        rod.sections.iter().map(|s| s.steps).collect::<Vec<_>>(),
        rod.guides.len(),
        rod.cables.len(),
        rod.loads.len()
    );
    (x, kinds)
}

/// The two rods have the same structure, and every number is within `ulps` times `epsilon` of
/// the reference's, relative to its magnitude (at least 0.01, so that a zero compares with
/// its neighbours' rounding).
#[cfg(test)]
pub(crate) fn assert_same_rod<T: model_core::Scalar + Into<f64>>(
    robot: &model_core::Rod<T>,
    reference: &model_core::Rod<T>,
    epsilon: f64,
    ulps: f64,
) {
    let ((a, ka), (b, kb)) = (numbers(robot), numbers(reference));
    assert_eq!(ka, kb);
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        let (x, y): (f64, f64) = ((*x).into(), (*y).into());
        assert!(
            (x - y).abs() <= ulps * epsilon * y.abs().max(1e-2),
            "number {i}: robot file {x:e}, reference {y:e}"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{STEPS_PER_SECTION, rod};
    use model_checks::reference::golden_bench;

    #[test]
    fn the_default_robot_file_is_the_golden_reference_bench() -> Result<(), ModelError> {
        // The robot file's numbers are the host's f64 (the stiffness computed from E, nu and the
        // diameter in f64, the cable holes from their angles) rounded once to the scalar; the
        // reference computes some of them in the scalar itself (the stiffness in f32, the holes
        // from literal directions): the same within a few units in the last place.
        for steps in crate::bench::STEP_COUNTS
            .into_iter()
            .chain([STEPS_PER_SECTION])
        {
            assert_same_rod(
                &rod::<f32>(steps)?,
                &golden_bench::<f32>(steps)?,
                f64::from(f32::EPSILON),
                4.0,
            );
            assert_same_rod(
                &rod::<f64>(steps)?,
                &golden_bench::<f64>(steps)?,
                f64::EPSILON,
                4.0,
            );
        }
        Ok(())
    }

    #[test]
    fn the_trajectory_passes_on_the_host_in_f32() -> Result<(), SetupError> {
        let model = crate::config::model()?;
        let mut lines = Vec::new();
        let summary = run_trajectory(&model, &|| 0, |c, _, _| lines.push(*c))?;
        for c in &lines {
            println!("{c:?}");
        }
        println!("{summary:?}");
        assert_eq!(summary.failed, 0);
        assert_eq!(summary.passed, TICK_COUNT);
        // Warm ticks stay within the loop's sweep budget; only the cold first tick may take more.
        let budget = u16::from(loop_config().estimator.max_sweeps);
        assert!(lines.iter().skip(1).all(|c| c.sweeps <= budget));
        assert!(summary.worst_tip_error_m < TIP_TOLERANCE_M);
        Ok(())
    }

    /// The model's own error at the loop's steps (its discretisation, f64 against ten times the
    /// steps) over the loads the robot meets stays within half the standard deviations the loop
    /// declares for it (`config::MODEL_LENGTH_STD_M`, `MODEL_TIP_STD_M`).
    #[test]
    fn the_model_error_is_covered() -> Result<(), ModelError> {
        use crate::config::{MODEL_LENGTH_STD_M, MODEL_TIP_STD_M, STEPS_PER_SECTION, rod};
        use model_core::{Model, ShootingSettings, Start, TipLoad};
        let coarse = Model::<f64>::new(rod(STEPS_PER_SECTION)?)?;
        let fine = Model::<f64>::new(rod(10 * STEPS_PER_SECTION)?)?;
        let settings = ShootingSettings::default();
        let (mut cable, mut tip) = (0.0f64, 0.0f64);
        for fx in [-0.1, 0.0, 0.1] {
            for fy in [-0.3, -0.15, 0.0, 0.15] {
                for fz in [-0.3, -0.1, 0.1, 0.3] {
                    let load = TipLoad::force(Vector3::new(fx, fy, fz));
                    let a = coarse.solve(&load, Start::Cold, &settings)?;
                    let b = fine.solve(&load, Start::Cold, &settings)?;
                    assert!(a.report.termination.is_success() && b.report.termination.is_success());
                    for (x, y) in a.cable_lengths_m.iter().zip(b.cable_lengths_m.iter()) {
                        cable = cable.max((x - y).abs());
                    }
                    tip = tip.max((a.tip_position_m - b.tip_position_m).norm());
                }
            }
        }
        println!("discretisation at {STEPS_PER_SECTION} steps: cable {cable:e} m, tip {tip:e} m");
        assert!(
            2.0 * cable <= f64::from(MODEL_LENGTH_STD_M),
            "cable {cable:e} m"
        );
        assert!(2.0 * tip <= f64::from(MODEL_TIP_STD_M), "tip {tip:e} m");
        Ok(())
    }

    #[test]
    fn the_golden_rows_pass_on_the_host_in_f32() -> Result<(), SetupError> {
        let model = crate::config::model()?;
        let summary = run_golden(&model, |r| println!("{r:?}"))?;
        assert_eq!((summary.passed, summary.failed), (4, 0));
        assert!(summary.worst_tip_error_m < 5e-5);
        Ok(())
    }
}
