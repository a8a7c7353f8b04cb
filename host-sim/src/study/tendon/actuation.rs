//! The forward solve from tensions against the solve from spool displacements (displacement
//! control, MODEL.md §6.3), cold and warm, with the discrete guides at the firmware's step count:
//! sweeps, host time, and the tip and tensions against the reference.
//!
//! The displacements are what encoders would read: each tendon's home length (feed and rest path)
//! minus the unstretched length the reference equilibrium needs. A warm solve starts from the
//! previous tick, every tension at [`PREVIOUS_TICK_SCALE`] of the case's (the same tip force):
//! `Model::solve_tendons` from its equilibrium, `Model::update_displacements` from its
//! displacement solve (with its sensitivity).

use std::hint::black_box;

use model_core::reduction::TendonModel;
use model_core::{
    DisplacementSettings, DisplacementSolve, Scalar, ShootingSettings, TendonEquilibrium, Tendons,
};

use super::super::measure::{Timing, time_cases, to_f64};
use super::super::variants::Arithmetic;
use super::cases::TendonScene;
use super::measure::{CaseReference, PREVIOUS_TICK_SCALE, Solver, TendonReference};
use host_sim::scene::SceneError;

/// Steps per section of the comparison: the firmware's (`firmware/expected/bench.run`).
pub const ACTUATION_STEPS: u16 = 20;

/// How the tendons are driven and how the solve starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Mode {
    /// `Model::solve_tendons`, cold (load continuation from the unloaded rod).
    TensionsCold,
    /// `Model::solve_tendons` from the previous tick's equilibrium.
    TensionsWarm,
    /// `Model::solve_displacements`, cold.
    DisplacementsCold,
    /// `Model::update_displacements` from the previous tick's displacement solve.
    DisplacementsWarm,
}

impl Mode {
    /// Every mode, in the table's order.
    pub const ALL: [Self; 4] = [
        Self::TensionsCold,
        Self::TensionsWarm,
        Self::DisplacementsCold,
        Self::DisplacementsWarm,
    ];

    /// A short label.
    pub fn label(self) -> &'static str {
        match self {
            Self::TensionsCold => "tensions, cold",
            Self::TensionsWarm => "tensions, warm",
            Self::DisplacementsCold => "displacements, cold",
            Self::DisplacementsWarm => "displacements, warm update",
        }
    }

    /// Whether the tensions are unknowns.
    pub fn displacements(self) -> bool {
        matches!(self, Self::DisplacementsCold | Self::DisplacementsWarm)
    }
}

/// One mode on one scene in one arithmetic.
#[derive(Clone, Debug, PartialEq)]
pub struct ActuationRow {
    /// Scene key.
    pub scene: String,
    /// f64 or f32.
    pub arithmetic: Arithmetic,
    /// Steps per section.
    pub steps_per_section: u16,
    /// The mode.
    pub mode: Mode,
    /// Cases solved.
    pub cases: usize,
    /// Sweeps per solve, mean over the cases (displacement control: forward solves and
    /// sensitivities together).
    pub sweeps_per_solve: f64,
    /// Semi-smooth Newton iterations per displacement solve, mean over the cases.
    pub iterations: Option<f64>,
    /// Host wall time per solve, median over the timed runs, us.
    pub host_time_us: f64,
    /// "Converged", or the first other termination and its case.
    pub termination: String,
    /// Worst tip distance from the converged reference, m (converged rows only).
    pub tip_error_m: Option<f64>,
    /// Displacement control: worst tension difference from the case's tensions, N.
    pub tension_error_n: Option<f64>,
}

impl ActuationRow {
    /// Whether every case converged.
    pub fn converged(&self) -> bool {
        self.termination == "Converged"
    }
}

/// Displacement control on a tendon model: cold and warm solves with the default settings.
pub struct Actuator<'a, T: Scalar> {
    solver: &'a Solver<T>,
    shooting: ShootingSettings<T>,
    control: DisplacementSettings<T>,
}

impl<T: Scalar> std::fmt::Debug for Actuator<'_, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Actuator").finish_non_exhaustive()
    }
}

fn model_error(what: &'static str) -> impl Fn(model_core::ModelError) -> SceneError {
    move |e| SceneError::new(what, e.to_string())
}

/// The spool displacements, m (positive taken in), that leave each tendon the unstretched length
/// `unstretched_m` from its home length (feed and rest path on the straight, unloaded rod).
pub fn displacements_m<T: Scalar>(
    tendons: &Tendons<T>,
    unstretched_m: &[f64],
) -> Result<Vec<T>, SceneError> {
    tendons
        .tendons()
        .iter()
        .enumerate()
        .map(|(j, t)| {
            let rest = tendons
                .rest_length_m(j)
                .ok_or_else(|| SceneError::new("tendons", format!("no tendon {j}")))?;
            let needed = unstretched_m
                .get(j)
                .ok_or_else(|| SceneError::new("reference", format!("no length {j}")))?;
            Ok(T::lit(t.feed_length_m.to_f64() + rest.to_f64() - needed))
        })
        .collect()
}

impl<'a, T: Scalar> Actuator<'a, T> {
    /// Displacement control on `solver`'s model (discrete guides).
    pub fn new(solver: &'a Solver<T>) -> Self {
        Self {
            solver,
            shooting: ShootingSettings::default(),
            control: DisplacementSettings::default(),
        }
    }

    /// A cold displacement-controlled solve of case `case`'s load at `displacements_m`.
    pub fn cold(
        &self,
        case: usize,
        displacements_m: &[T],
    ) -> Result<DisplacementSolve<T>, SceneError> {
        let s = self.solver;
        s.model
            .solve_displacements(
                &s.tendons,
                displacements_m,
                s.load(case)?,
                None,
                &self.shooting,
                &self.control,
            )
            .map_err(model_error("displacement solve"))
    }

    /// A displacement-controlled solve started from `start`'s tensions and shape (no sensitivity
    /// carried over: how the firmware's f64 reference steps along its trajectory).
    pub fn cold_from(
        &self,
        case: usize,
        displacements_m: &[T],
        start: &TendonEquilibrium<T>,
    ) -> Result<DisplacementSolve<T>, SceneError> {
        let s = self.solver;
        s.model
            .solve_displacements(
                &s.tendons,
                displacements_m,
                s.load(case)?,
                Some(start),
                &self.shooting,
                &self.control,
            )
            .map_err(model_error("displacement solve"))
    }

    /// The warm update from `previous` to `displacements_m`.
    pub fn warm(
        &self,
        case: usize,
        displacements_m: &[T],
        previous: &DisplacementSolve<T>,
    ) -> Result<DisplacementSolve<T>, SceneError> {
        let s = self.solver;
        s.model
            .update_displacements(
                &s.tendons,
                displacements_m,
                s.load(case)?,
                previous,
                &self.shooting,
                &self.control,
            )
            .map_err(model_error("displacement update"))
    }
}

/// Tip distance of a tendon equilibrium from a reference case, m.
pub fn tip_error<T: Scalar>(eq: &TendonEquilibrium<T>, expected: &CaseReference) -> f64 {
    (to_f64(&eq.equilibrium.tip_position_m) - expected.tip_m).norm()
}

/// Largest tension difference, N.
pub fn tension_error<T: Scalar>(eq: &TendonEquilibrium<T>, tensions_n: &[f64]) -> f64 {
    eq.tensions_n
        .iter()
        .zip(tensions_n)
        .map(|(a, b)| (a.to_f64() - b).abs())
        .fold(0.0, f64::max)
}

/// Item `case` of `v`.
fn at<X>(v: &[X], case: usize) -> Result<&X, SceneError> {
    v.get(case)
        .ok_or_else(|| SceneError::new("case", format!("no case {case}")))
}

/// One outcome of a case.
struct Outcome {
    success: bool,
    termination: String,
    sweeps: u32,
    iterations: Option<u16>,
    tip_error_m: f64,
    tension_error_n: Option<f64>,
}

/// Every mode on `scene` at [`ACTUATION_STEPS`] in `arithmetic`.
pub fn study(
    scene: &TendonScene,
    reference: &TendonReference,
    arithmetic: Arithmetic,
    timing: Timing,
) -> Result<Vec<ActuationRow>, SceneError> {
    match arithmetic {
        Arithmetic::F64 => with_scalar::<f64>(scene, reference, arithmetic, timing),
        Arithmetic::F32 | Arithmetic::F32Micromath => {
            with_scalar::<f32>(scene, reference, arithmetic, timing)
        }
    }
}

fn with_scalar<T: Scalar>(
    scene: &TendonScene,
    reference: &TendonReference,
    arithmetic: Arithmetic,
    timing: Timing,
) -> Result<Vec<ActuationRow>, SceneError> {
    let solver = Solver::<T>::new(scene, ACTUATION_STEPS, TendonModel::DiscreteGuides)?;
    let actuator = Actuator::new(&solver);
    let cases = scene.cases.len();
    // The inputs and the previous ticks, prepared outside the timing.
    let mut previous_eq = Vec::new();
    let mut previous_solve = Vec::new();
    let mut here_d = Vec::new();
    for (case, (expected, before)) in reference.cases.iter().zip(&reference.previous).enumerate() {
        let scaled: Vec<T> = solver
            .tensions(case)?
            .iter()
            .map(|t| *t * T::lit(PREVIOUS_TICK_SCALE))
            .collect();
        previous_eq.push(solver.solve_at(case, Some(&scaled), None)?);
        let d_before = displacements_m::<T>(&solver.tendons, &before.unstretched_m)?;
        previous_solve.push(actuator.cold(case, &d_before)?);
        here_d.push(displacements_m::<T>(
            &solver.tendons,
            &expected.unstretched_m,
        )?);
    }
    let mut rows = Vec::new();
    for mode in Mode::ALL {
        let run = |case: usize| -> Result<Outcome, SceneError> {
            let expected = reference
                .cases
                .get(case)
                .ok_or_else(|| SceneError::new("reference", format!("no case {case}")))?;
            let tensions = &scene.actuation(case)?.tensions_n;
            let d = at(&here_d, case)?;
            match mode {
                Mode::TensionsCold | Mode::TensionsWarm => {
                    let start = match mode {
                        Mode::TensionsWarm => Some(at(&previous_eq, case)?),
                        _ => None,
                    };
                    let eq = solver.solve_at(case, None, start)?;
                    Ok(Outcome {
                        success: eq.is_success(),
                        termination: format!("{:?}", eq.equilibrium.report.termination),
                        sweeps: u32::from(eq.equilibrium.report.sweeps),
                        iterations: None,
                        tip_error_m: tip_error(&eq, expected),
                        tension_error_n: None,
                    })
                }
                Mode::DisplacementsCold | Mode::DisplacementsWarm => {
                    let out = match mode {
                        Mode::DisplacementsWarm => {
                            actuator.warm(case, d, at(&previous_solve, case)?)?
                        }
                        _ => actuator.cold(case, d)?,
                    };
                    Ok(Outcome {
                        success: out.is_success(),
                        termination: format!("{:?}", out.termination),
                        sweeps: out.sweeps,
                        iterations: Some(out.iterations),
                        tip_error_m: tip_error(&out.solved, expected),
                        tension_error_n: Some(tension_error(&out.solved, tensions)),
                    })
                }
            }
        };
        let mut termination = None;
        let (mut sweeps, mut iterations) = (0u32, 0u32);
        let (mut tip, mut tension) = (0.0f64, 0.0f64);
        for case in 0..cases {
            let o = run(case)?;
            sweeps += o.sweeps;
            iterations += o.iterations.map_or(0, u32::from);
            if !o.success {
                termination.get_or_insert_with(|| {
                    let label = scene.cases.get(case).map_or("", |c| c.label.as_str());
                    format!("{} ({label})", o.termination)
                });
                continue;
            }
            tip = tip.max(o.tip_error_m);
            tension = tension.max(o.tension_error_n.unwrap_or(0.0));
        }
        let (host_time_us, _) = time_cases(cases, timing, |case| {
            black_box(run(case)?);
            Ok(())
        })?;
        let n = cases.max(1) as f64;
        let converged = termination.is_none();
        rows.push(ActuationRow {
            scene: scene.key.clone(),
            arithmetic,
            steps_per_section: ACTUATION_STEPS,
            mode,
            cases,
            sweeps_per_solve: f64::from(sweeps) / n,
            iterations: mode.displacements().then_some(f64::from(iterations) / n),
            host_time_us,
            termination: termination.unwrap_or_else(|| "Converged".into()),
            tip_error_m: converged.then_some(tip),
            tension_error_n: (converged && mode.displacements()).then_some(tension),
        });
    }
    Ok(rows)
}
