//! Measuring one variant on one scene: its error against the f64 reference (tip, the worst of
//! [`SHAPE_POINTS`] backbone points, cable lengths), its deterministic work (sweeps times RK4 steps
//! per sweep) and its host wall time per cold forward solve.

use std::hint::black_box;
use std::time::{Duration, Instant};

use model_core::planar::PlanarModel;
use model_core::{
    Attitude, Equilibrium, LieGroup, Model, ModelError, Quaternion, RotationMatrix, Scalar,
    ShapePoint, ShootingSettings, Start, TipLoad,
};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::cases::Scene;
use super::variants::{Arithmetic, Family, Frame};
use host_sim::scene::SceneError;

/// Backbone points compared, evenly spaced in arc length from the base to the tip.
pub const SHAPE_POINTS: usize = 40;
/// Steps per section of the reference.
pub const REFERENCE_STEPS: u16 = 4000;
/// Steps per section of the grid the reference is checked against.
pub const CHECK_STEPS: u16 = 2000;
/// The two reference grids must agree to this, m, or the study fails.
pub const REFERENCE_AGREEMENT_M: f64 = 1e-9;

/// How long to time each variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// At least this many timed runs.
    pub min_runs: usize,
    /// Then more until this much time has gone by.
    pub budget: Duration,
    /// At most this many.
    pub max_runs: usize,
}

impl Timing {
    /// The full study's timing.
    pub const FULL: Self = Self {
        min_runs: 7,
        budget: Duration::from_millis(60),
        max_runs: 400,
    };
    /// The quick study's.
    pub const QUICK: Self = Self {
        min_runs: 3,
        budget: Duration::from_millis(4),
        max_runs: 40,
    };
}

/// What the reference says about one case.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseReference {
    /// Tip position, m.
    pub tip_m: Vector3<f64>,
    /// Backbone points at [`arc_lengths_m`], m.
    pub shape_m: Vec<Vector3<f64>>,
    /// Cable lengths, m.
    pub cables_m: Vec<f64>,
}

/// The converged f64 answer of a scene, with how far its two grids differ.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// One per case.
    pub cases: Vec<CaseReference>,
    /// Largest difference between the [`REFERENCE_STEPS`] and [`CHECK_STEPS`] grids over tips,
    /// backbone points and cable lengths, m.
    pub grid_difference_m: f64,
    /// Sweeps of the reference solves, summed over the cases.
    pub sweeps: u32,
}

impl Reference {
    /// The reference of case `case` only (see [`Scene::only`]).
    pub fn only(&self, case: usize) -> Result<Self, SceneError> {
        Ok(Self {
            cases: vec![
                self.cases
                    .get(case)
                    .ok_or_else(|| SceneError::new("reference", format!("no case {case}")))?
                    .clone(),
            ],
            ..self.clone()
        })
    }
}

/// One variant on one scene: the unit of the table, the CSV and the plot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Scene key.
    pub scene: String,
    /// The variant's family.
    pub family: Family,
    /// Steps per section.
    pub steps_per_section: u16,
    /// RK4 steps of one sweep (the plan adds steps at guides and mass edges).
    pub rk4_steps_per_sweep: u32,
    /// Cases (tip loads) solved.
    pub cases: usize,
    /// Sweeps per cold solve, mean over the cases.
    pub sweeps_per_solve: f64,
    /// Sweeps times RK4 steps per sweep, mean over the cases.
    pub work_rk4_steps: f64,
    /// Host wall time per cold solve, median over the timed runs, us.
    pub host_time_us: f64,
    /// Timed runs.
    pub timed_runs: usize,
    /// "Converged", or the first other termination and its case.
    pub termination: String,
    /// Worst tip position error over the cases, m (converged rows only).
    pub tip_error_m: Option<f64>,
    /// Worst backbone point error, m.
    pub backbone_error_m: Option<f64>,
    /// Worst cable length error, m.
    pub cable_error_m: Option<f64>,
    /// Tendon scenes only: sweeps times RK4 steps per sweep times the relative cost of one step of
    /// the tendon model (`model_core::tendon_step_cost`, a dead-load 3D step = 100); for PCC, which
    /// has no grid, `model_core::PCC_COST`. The work the tendon rows' Pareto front is drawn on.
    #[serde(default)]
    pub tendon_work: Option<f64>,
    /// On the Pareto front of work against error (set after all rows are in).
    #[serde(default)]
    pub front_work: bool,
    /// On the Pareto front of host time against error.
    #[serde(default)]
    pub front_time: bool,
}

impl Row {
    /// Whether every case converged.
    pub fn converged(&self) -> bool {
        self.termination == "Converged"
    }

    /// The largest of the tip, backbone and cable errors, m.
    pub fn error_m(&self) -> Option<f64> {
        let errors = [self.tip_error_m, self.backbone_error_m, self.cable_error_m];
        errors.into_iter().flatten().reduce(f64::max)
    }

    /// The work a Pareto front is drawn on: [`Row::tendon_work`] for a tendon row, else
    /// [`Row::work_rk4_steps`].
    pub fn work(&self) -> f64 {
        self.tendon_work.unwrap_or(self.work_rk4_steps)
    }
}

fn model_error(what: &'static str) -> impl Fn(ModelError) -> SceneError {
    move |e| SceneError::new(what, e.to_string())
}

/// The arc lengths of the compared backbone points, m, within `[0, length]`.
pub fn arc_lengths_m<T: Scalar>(length_m: T) -> Vec<T> {
    let last = (SHAPE_POINTS - 1) as f64;
    (0..SHAPE_POINTS)
        .map(|i| (T::lit(length_m.to_f64() * i as f64 / last)).min(length_m))
        .collect()
}

/// A vector in f64.
pub fn to_f64<T: Scalar>(v: &Vector3<T>) -> Vector3<f64> {
    v.map(Scalar::to_f64)
}

/// A model ready to solve one scene's cases, in 3D or through the planar reduction.
struct Solver<'a, T: Scalar, A: Attitude<T>> {
    model: &'a Model<T, A>,
    loads: Vec<TipLoad<T>>,
    planar: Option<Vec<PlanarModel<'a, T, A>>>,
    settings: ShootingSettings<T>,
}

impl<'a, T: Scalar, A: Attitude<T>> Solver<'a, T, A> {
    fn new(model: &'a Model<T, A>, scene: &Scene, planar: bool) -> Result<Self, SceneError> {
        let loads = scene.loads::<T>()?;
        let planar = if planar {
            let reduced = loads
                .iter()
                .map(|load| {
                    PlanarModel::new(model, load).ok_or_else(|| {
                        SceneError::new(&scene.key, "the planar reduction does not apply")
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            Some(reduced)
        } else {
            None
        };
        Ok(Self {
            model,
            loads,
            planar,
            settings: ShootingSettings::default(),
        })
    }

    fn solve(&self, case: usize) -> Result<Equilibrium<T>, SceneError> {
        let load = self
            .loads
            .get(case)
            .ok_or_else(|| SceneError::new("case", format!("no case {case}")))?;
        match self.planar.as_ref().and_then(|p| p.get(case)) {
            Some(planar) => planar.solve(load, &self.settings),
            None => self.model.solve(load, Start::Cold, &self.settings),
        }
        .map_err(model_error("solve"))
    }

    fn shape(&self, case: usize, eq: &Equilibrium<T>) -> Result<Vec<Vector3<f64>>, SceneError> {
        let s = arc_lengths_m(self.model.length_m());
        let mut out = vec![ShapePoint::default(); s.len()];
        let written = match self.planar.as_ref().and_then(|p| p.get(case)) {
            Some(planar) => planar.shape(eq, &s, &mut out),
            None => self.model.shape(eq, &s, &mut out),
        }
        .map_err(model_error("shape"))?;
        if written != s.len() {
            return Err(SceneError::new(
                "shape",
                format!("{written} of {} points written", s.len()),
            ));
        }
        Ok(out.iter().map(|p| to_f64(&p.position_m)).collect())
    }
}

/// The f64 quaternion 3D answer of every case at `steps`.
fn solve_reference(scene: &Scene, steps: u16) -> Result<(Vec<CaseReference>, u32), SceneError> {
    let model = Model::<f64, Quaternion<f64>>::new(scene.rod(steps, false)?)
        .map_err(model_error("reference model"))?;
    let solver = Solver::new(&model, scene, false)?;
    let mut cases = Vec::new();
    let mut sweeps = 0u32;
    for (case, label) in scene.case_labels.iter().enumerate() {
        let eq = solver.solve(case)?;
        if !eq.report.termination.is_success() {
            return Err(SceneError::new(
                format!("reference of {} ({label}) at {steps} steps", scene.key),
                format!("did not converge: {:?}", eq.report.termination),
            ));
        }
        sweeps += u32::from(eq.report.sweeps);
        cases.push(CaseReference {
            tip_m: eq.tip_position_m,
            shape_m: solver.shape(case, &eq)?,
            cables_m: eq.cable_lengths_m.to_vec(),
        });
    }
    Ok((cases, sweeps))
}

/// The largest distance between corresponding points, m.
pub fn max_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

/// The largest difference between corresponding values.
pub fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The scene's reference: f64, quaternion, full 3D model at [`REFERENCE_STEPS`], and how far the
/// [`CHECK_STEPS`] grid is from it. Fails if either does not converge.
pub fn reference(scene: &Scene) -> Result<Reference, SceneError> {
    let (cases, sweeps) = solve_reference(scene, REFERENCE_STEPS)?;
    let (check, _) = solve_reference(scene, CHECK_STEPS)?;
    let grid_difference_m = cases
        .iter()
        .zip(&check)
        .map(|(a, b)| {
            (a.tip_m - b.tip_m)
                .norm()
                .max(max_distance(&a.shape_m, &b.shape_m))
                .max(max_difference(&a.cables_m, &b.cables_m))
        })
        .fold(0.0, f64::max);
    Ok(Reference {
        cases,
        grid_difference_m,
        sweeps,
    })
}

/// Measures `family` at `steps` per section on `scene`.
pub fn measure(
    scene: &Scene,
    reference: &Reference,
    family: Family,
    steps: u16,
    timing: Timing,
) -> Result<Row, SceneError> {
    match family.arithmetic {
        Arithmetic::F64 => with_scalar::<f64>(scene, reference, family, steps, timing),
        Arithmetic::F32 | Arithmetic::F32Micromath => {
            with_scalar::<f32>(scene, reference, family, steps, timing)
        }
    }
}

fn with_scalar<T: Scalar>(
    scene: &Scene,
    reference: &Reference,
    family: Family,
    steps: u16,
    timing: Timing,
) -> Result<Row, SceneError> {
    match family.frame {
        Frame::Quaternion => {
            with_frame::<T, Quaternion<T>>(scene, reference, family, steps, timing)
        }
        Frame::RotationMatrix => {
            with_frame::<T, RotationMatrix<T>>(scene, reference, family, steps, timing)
        }
        Frame::LieGroup => with_frame::<T, LieGroup<T>>(scene, reference, family, steps, timing),
    }
}

/// Errors against the reference, worst over the cases.
#[derive(Default)]
struct Errors {
    tip_m: f64,
    backbone_m: f64,
    cable_m: f64,
}

fn with_frame<T: Scalar, A: Attitude<T>>(
    scene: &Scene,
    reference: &Reference,
    family: Family,
    steps: u16,
    timing: Timing,
) -> Result<Row, SceneError> {
    let model = Model::<T, A>::new(scene.rod(steps, family.reduction.kirchhoff())?)
        .map_err(model_error("model"))?;
    let solver = Solver::new(&model, scene, family.reduction.planar())?;
    let cases = scene.forces_n.len();
    let mut termination = None;
    let mut sweeps = 0u32;
    let mut errors = Errors::default();
    for (case, expected) in reference.cases.iter().enumerate().take(cases) {
        let eq = solver.solve(case)?;
        sweeps += u32::from(eq.report.sweeps);
        if !eq.report.termination.is_success() {
            termination.get_or_insert_with(|| {
                let label = scene.case_labels.get(case).map_or("", String::as_str);
                format!("{:?} ({label})", eq.report.termination)
            });
            continue;
        }
        let cables: Vec<f64> = eq.cable_lengths_m.iter().map(|c| c.to_f64()).collect();
        if cables.len() != expected.cables_m.len() {
            return Err(SceneError::new(
                "cables",
                "count differs from the reference",
            ));
        }
        errors.tip_m = errors
            .tip_m
            .max((to_f64(&eq.tip_position_m) - expected.tip_m).norm());
        errors.backbone_m = errors
            .backbone_m
            .max(max_distance(&solver.shape(case, &eq)?, &expected.shape_m));
        errors.cable_m = errors
            .cable_m
            .max(max_difference(&cables, &expected.cables_m));
    }
    let (host_time_us, timed_runs) = time_solves(&solver, cases, timing)?;
    let rk4_steps_per_sweep = model.plan().total_steps();
    let sweeps_per_solve = f64::from(sweeps) / cases.max(1) as f64;
    let converged = termination.is_none();
    let error = |e: f64| converged.then_some(e);
    Ok(Row {
        scene: scene.key.clone(),
        family,
        steps_per_section: steps,
        rk4_steps_per_sweep,
        cases,
        sweeps_per_solve,
        work_rk4_steps: sweeps_per_solve * f64::from(rk4_steps_per_sweep),
        host_time_us,
        timed_runs,
        termination: termination.unwrap_or_else(|| "Converged".into()),
        tip_error_m: error(errors.tip_m),
        backbone_error_m: error(errors.backbone_m),
        cable_error_m: error(errors.cable_m),
        tendon_work: None,
        front_work: false,
        front_time: false,
    })
}

/// Median wall time of one cold solve, us: every case solved per run, the run's time divided by the
/// case count.
fn time_solves<T: Scalar, A: Attitude<T>>(
    solver: &Solver<'_, T, A>,
    cases: usize,
    timing: Timing,
) -> Result<(f64, usize), SceneError> {
    time_cases(cases, timing, |case| {
        black_box(solver.solve(black_box(case))?);
        Ok(())
    })
}

/// Median wall time of `run(case)` over the cases, us: every case run once per timed run, the run's
/// time divided by the case count; at least `timing.min_runs` runs, more while the budget lasts.
/// Also the number of timed runs.
pub fn time_cases(
    cases: usize,
    timing: Timing,
    mut run: impl FnMut(usize) -> Result<(), SceneError>,
) -> Result<(f64, usize), SceneError> {
    let start = Instant::now();
    let mut runs_us = Vec::new();
    while runs_us.len() < timing.min_runs
        || (start.elapsed() < timing.budget && runs_us.len() < timing.max_runs)
    {
        let t0 = Instant::now();
        for case in 0..cases {
            run(black_box(case))?;
        }
        runs_us.push(t0.elapsed().as_secs_f64() * 1e6 / cases.max(1) as f64);
    }
    Ok((median(&mut runs_us), runs_us.len()))
}

/// The median (of a non-empty slice; NaN for an empty one).
pub fn median(xs: &mut [f64]) -> f64 {
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => xs[n / 2],
        _ => 0.5 * (xs[n / 2 - 1] + xs[n / 2]),
    }
}

/// f32 against f64 on the same grid, to tell the f32 solve's stopping rule from f32 arithmetic.
#[derive(Clone, Debug, PartialEq)]
pub struct F32Floor {
    /// Scene key.
    pub scene: String,
    /// Steps per section.
    pub steps_per_section: u16,
    /// Worst tip distance of the f32 solve from the f64 solve, m.
    pub solve_m: f64,
    /// Worst tip distance of one f32 sweep at the f64 answer's base strain from the f64 tip, m: how
    /// well f32 represents the right answer.
    pub sweep_m: f64,
}

/// [`F32Floor`] of `scene` at `steps` (quaternion frame, 3D model).
pub fn f32_floor(scene: &Scene, steps: u16) -> Result<F32Floor, SceneError> {
    let wide = Model::<f64>::new(scene.rod(steps, false)?).map_err(model_error("f64 model"))?;
    let narrow = Model::<f32>::new(scene.rod(steps, false)?).map_err(model_error("f32 model"))?;
    let settings = ShootingSettings::<f64>::default();
    let (mut solve_m, mut sweep_m) = (0.0f64, 0.0f64);
    for case in 0..scene.forces_n.len() {
        let exact = wide
            .solve(&scene.load(case)?, Start::Cold, &settings)
            .map_err(model_error("f64 solve"))?;
        let load = scene.load::<f32>(case)?;
        let rounded = narrow
            .solve(&load, Start::Cold, &ShootingSettings::default())
            .map_err(model_error("f32 solve"))?;
        if !(exact.report.termination.is_success() && rounded.report.termination.is_success()) {
            return Err(SceneError::new(
                &scene.key,
                format!("f32 floor at {steps} steps: a solve did not converge"),
            ));
        }
        let u0 = exact.base_strain_per_m.map(|x| x as f32);
        let swept = narrow
            .evaluate(&u0, &load)
            .map_err(model_error("f32 sweep"))?;
        solve_m = solve_m.max((to_f64(&rounded.tip_position_m) - exact.tip_position_m).norm());
        sweep_m = sweep_m.max((to_f64(&swept.tip_position_m) - exact.tip_position_m).norm());
    }
    Ok(F32Floor {
        scene: scene.key.clone(),
        steps_per_section: steps,
        solve_m,
        sweep_m,
    })
}
