//! Measuring one tendon variant on one tendon scene: its error against the discrete-guide f64
//! reference (tip, the worst of [`SHAPE_POINTS`] backbone points, path lengths), its sweeps and
//! work per cold forward solve from tensions, and its host wall time.

use std::hint::black_box;

use model_core::reduction::{PCC_COST, TendonModel, tendon_step_cost};
use model_core::{
    Model, Scalar, ShapePoint, ShootingSettings, TendonEquilibrium, Tendons, TipLoad,
};
use nalgebra::Vector3;

use super::super::measure::{
    REFERENCE_AGREEMENT_M, Row, SHAPE_POINTS, Timing, arc_lengths_m, max_difference, max_distance,
    time_cases, to_f64,
};
use super::super::variants::{Arithmetic, Family, Frame, Reduction};
use super::cases::TendonScene;
use host_sim::scene::SceneError;

/// Steps per section of the tendon reference (discrete guides, f64).
pub const REFERENCE_STEPS: u16 = 800;
/// Steps per section of the grid the reference is checked against.
pub const CHECK_STEPS: u16 = 400;
/// The reference must lie this close to the golden rows' tip and path lengths, m: the independent
/// solver's own accuracy is about 3e-11 m, but the two-section robot's guide masses are spread
/// over 0.1 mm here (`reference::POINT_GUIDE_THICKNESS_M`) where the golden solver has points.
pub const GOLDEN_AGREEMENT_M: f64 = 1e-8;
/// The previous tick of the warm comparisons: every tension times this.
pub const PREVIOUS_TICK_SCALE: f64 = 0.95;

fn model_error(what: &'static str) -> impl Fn(model_core::ModelError) -> SceneError {
    move |e| SceneError::new(what, e.to_string())
}

/// The tendon model of a family's reduction.
pub fn tendon_model(reduction: Reduction) -> Result<TendonModel, SceneError> {
    match reduction {
        Reduction::TendonDiscrete => Ok(TendonModel::DiscreteGuides),
        Reduction::TendonContinuous => Ok(TendonModel::Continuous),
        Reduction::TendonPcc => Ok(TendonModel::ConstantCurvature),
        other => Err(SceneError::new(
            "tendon study",
            format!("{} is not a tendon model", other.label()),
        )),
    }
}

/// The family of a tendon model in `arithmetic` (quaternion frame).
pub fn tendon_family(arithmetic: Arithmetic, model: TendonModel) -> Family {
    Family {
        arithmetic,
        frame: Frame::Quaternion,
        reduction: match model {
            TendonModel::DiscreteGuides => Reduction::TendonDiscrete,
            TendonModel::Continuous => Reduction::TendonContinuous,
            TendonModel::ConstantCurvature => Reduction::TendonPcc,
        },
    }
}

/// What the reference says about one actuation.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseReference {
    /// Tip position, m.
    pub tip_m: Vector3<f64>,
    /// Backbone points at [`arc_lengths_m`], m.
    pub shape_m: Vec<Vector3<f64>>,
    /// Path lengths, m.
    pub paths_m: Vec<f64>,
    /// The unstretched length each tendon needs, spool to termination, m.
    pub unstretched_m: Vec<f64>,
}

/// The converged discrete-guide f64 answer of a tendon scene.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonReference {
    /// One per case.
    pub cases: Vec<CaseReference>,
    /// Each case at [`PREVIOUS_TICK_SCALE`] times its tensions (the warm comparisons' start).
    pub previous: Vec<CaseReference>,
    /// Largest difference between the [`REFERENCE_STEPS`] and [`CHECK_STEPS`] grids over tips,
    /// backbone points and path lengths, m.
    pub grid_difference_m: f64,
    /// Largest difference from the golden rows' tips and path lengths, m.
    pub golden_difference_m: Option<f64>,
}

impl TendonReference {
    /// The reference of case `case` only.
    pub fn only(&self, case: usize) -> Result<Self, SceneError> {
        let missing = || SceneError::new("tendon reference", format!("no case {case}"));
        Ok(Self {
            cases: vec![self.cases.get(case).ok_or_else(missing)?.clone()],
            previous: vec![self.previous.get(case).ok_or_else(missing)?.clone()],
            ..self.clone()
        })
    }
}

/// A tendon model ready to solve a scene's actuations.
pub struct Solver<T: Scalar> {
    /// The model at the scene's steps.
    pub model: Model<T>,
    /// Its tendons.
    pub tendons: Tendons<T>,
    loads: Vec<TipLoad<T>>,
    tensions: Vec<Vec<T>>,
    kind: TendonModel,
    settings: ShootingSettings<T>,
}

impl<T: Scalar> std::fmt::Debug for Solver<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Solver").field("kind", &self.kind).finish()
    }
}

impl<T: Scalar> Solver<T> {
    /// `kind` on `scene` at `steps` per section.
    pub fn new(scene: &TendonScene, steps: u16, kind: TendonModel) -> Result<Self, SceneError> {
        let (rod, tendons) = scene.rod::<T>(steps.max(1))?;
        let model = Model::<T>::new(rod).map_err(model_error("tendon model"))?;
        let tendons = Tendons::new(&model, &tendons).map_err(model_error("tendons"))?;
        let loads = (0..scene.cases.len())
            .map(|c| scene.load(c))
            .collect::<Result<_, _>>()?;
        let tensions = (0..scene.cases.len())
            .map(|c| scene.tensions(c))
            .collect::<Result<_, _>>()?;
        Ok(Self {
            model,
            tendons,
            loads,
            tensions,
            kind,
            settings: ShootingSettings::default(),
        })
    }

    /// The tip load of case `case`.
    pub fn load(&self, case: usize) -> Result<&TipLoad<T>, SceneError> {
        self.loads
            .get(case)
            .ok_or_else(|| SceneError::new("case", format!("no case {case}")))
    }

    /// The tensions of case `case`.
    pub fn tensions(&self, case: usize) -> Result<&[T], SceneError> {
        self.tensions
            .get(case)
            .map(Vec::as_slice)
            .ok_or_else(|| SceneError::new("case", format!("no case {case}")))
    }

    /// Case `case` at `tensions` (its own if `None`), cold or from `start`.
    pub fn solve_at(
        &self,
        case: usize,
        tensions: Option<&[T]>,
        start: Option<&TendonEquilibrium<T>>,
    ) -> Result<TendonEquilibrium<T>, SceneError> {
        let load = self.load(case)?;
        let tau = match tensions {
            Some(t) => t,
            None => self.tensions(case)?,
        };
        let (m, set, s) = (&self.model, &self.tendons, &self.settings);
        match self.kind {
            TendonModel::DiscreteGuides => m.solve_tendons(set, tau, load, start, s),
            TendonModel::Continuous => m.solve_tendons_continuous(set, tau, load, start, s),
            TendonModel::ConstantCurvature => m.solve_tendons_pcc_ignoring_loads(set, tau, load),
        }
        .map_err(model_error("tendon solve"))
    }

    /// Case `case`, cold.
    pub fn solve(&self, case: usize) -> Result<TendonEquilibrium<T>, SceneError> {
        self.solve_at(case, None, None)
    }

    /// The backbone of `eq` at the compared arc lengths, m.
    pub fn shape(&self, eq: &TendonEquilibrium<T>) -> Result<Vec<Vector3<f64>>, SceneError> {
        let s = arc_lengths_m(self.model.length_m());
        let mut out = vec![ShapePoint::default(); s.len()];
        let (m, set) = (&self.model, &self.tendons);
        let written = match self.kind {
            TendonModel::DiscreteGuides => m.shape_tendons(set, eq, &s, &mut out),
            TendonModel::Continuous => m.shape_tendons_continuous(set, eq, &s, &mut out),
            TendonModel::ConstantCurvature => m.shape_tendons_pcc(set, eq, &s, &mut out),
        }
        .map_err(model_error("tendon shape"))?;
        if written != SHAPE_POINTS {
            return Err(SceneError::new(
                "tendon shape",
                format!("{written} of {SHAPE_POINTS} points written"),
            ));
        }
        Ok(out.iter().map(|p| to_f64(&p.position_m)).collect())
    }

    /// RK4 steps of one sweep (none for PCC).
    pub fn rk4_steps(&self) -> u32 {
        match self.kind {
            TendonModel::ConstantCurvature => 0,
            _ => self.model.plan().total_steps(),
        }
    }
}

fn values<T: Scalar>(v: &[T]) -> Vec<f64> {
    v.iter().map(|x| x.to_f64()).collect()
}

fn case_reference(
    solver: &Solver<f64>,
    scene: &TendonScene,
    case: usize,
    tensions: Option<&[f64]>,
    steps: u16,
) -> Result<CaseReference, SceneError> {
    let eq = solver.solve_at(case, tensions, None)?;
    if !eq.is_success() {
        let label = scene.cases.get(case).map_or("", |c| c.label.as_str());
        return Err(SceneError::new(
            format!(
                "tendon reference of {} ({label}) at {steps} steps",
                scene.key
            ),
            format!("did not converge: {:?}", eq.equilibrium.report.termination),
        ));
    }
    Ok(CaseReference {
        tip_m: eq.equilibrium.tip_position_m,
        shape_m: solver.shape(&eq)?,
        paths_m: values(&eq.path_m),
        unstretched_m: values(&eq.unstretched_m),
    })
}

fn distance(a: &CaseReference, b: &CaseReference) -> f64 {
    (a.tip_m - b.tip_m)
        .norm()
        .max(max_distance(&a.shape_m, &b.shape_m))
        .max(max_difference(&a.paths_m, &b.paths_m))
}

/// The scene's reference: discrete guides, f64, [`REFERENCE_STEPS`] per section, each case and its
/// previous tick; how far the [`CHECK_STEPS`] grid and the golden rows are from it. Fails if a
/// reference solve does not converge.
pub fn reference(scene: &TendonScene) -> Result<TendonReference, SceneError> {
    let fine = Solver::<f64>::new(scene, REFERENCE_STEPS, TendonModel::DiscreteGuides)?;
    let check = Solver::<f64>::new(scene, CHECK_STEPS, TendonModel::DiscreteGuides)?;
    let mut cases = Vec::new();
    let mut previous = Vec::new();
    let mut grid_difference_m = 0.0f64;
    let mut golden: Option<f64> = None;
    for (case, actuation) in scene.cases.iter().enumerate() {
        let here = case_reference(&fine, scene, case, None, REFERENCE_STEPS)?;
        let coarse = case_reference(&check, scene, case, None, CHECK_STEPS)?;
        grid_difference_m = grid_difference_m.max(distance(&here, &coarse));
        if let Some(tip) = actuation.golden_tip_m {
            let d = (here.tip_m - Vector3::from(tip))
                .norm()
                .max(max_difference(&here.paths_m, &actuation.golden_paths_m));
            golden = Some(golden.map_or(d, |g| g.max(d)));
        }
        let scaled: Vec<f64> = actuation
            .tensions_n
            .iter()
            .map(|t| t * PREVIOUS_TICK_SCALE)
            .collect();
        previous.push(case_reference(
            &fine,
            scene,
            case,
            Some(&scaled),
            REFERENCE_STEPS,
        )?);
        cases.push(here);
    }
    Ok(TendonReference {
        cases,
        previous,
        grid_difference_m,
        golden_difference_m: golden,
    })
}

/// Whether the reference grids agree well enough.
pub fn grids_agree(reference: &TendonReference) -> bool {
    reference.grid_difference_m <= REFERENCE_AGREEMENT_M
}

/// Measures `family` (a tendon model) at `steps` per section on `scene` (PCC ignores `steps`).
pub fn measure(
    scene: &TendonScene,
    reference: &TendonReference,
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
    scene: &TendonScene,
    reference: &TendonReference,
    family: Family,
    steps: u16,
    timing: Timing,
) -> Result<Row, SceneError> {
    let kind = tendon_model(family.reduction)?;
    let steps = if kind == TendonModel::ConstantCurvature {
        0
    } else {
        steps
    };
    let solver = Solver::<T>::new(scene, steps, kind)?;
    let cases = scene.cases.len();
    let mut termination = None;
    let mut sweeps = 0u32;
    let (mut tip_m, mut backbone_m, mut path_m) = (0.0f64, 0.0f64, 0.0f64);
    for (case, expected) in reference.cases.iter().enumerate().take(cases) {
        let eq = solver.solve(case)?;
        sweeps += u32::from(eq.equilibrium.report.sweeps);
        if !eq.is_success() {
            termination.get_or_insert_with(|| {
                let label = scene.cases.get(case).map_or("", |c| c.label.as_str());
                format!("{:?} ({label})", eq.equilibrium.report.termination)
            });
            continue;
        }
        let paths = values(&eq.path_m);
        if paths.len() != expected.paths_m.len() {
            return Err(SceneError::new(
                "tendon paths",
                "count differs from the reference",
            ));
        }
        tip_m = tip_m.max((to_f64(&eq.equilibrium.tip_position_m) - expected.tip_m).norm());
        backbone_m = backbone_m.max(max_distance(&solver.shape(&eq)?, &expected.shape_m));
        path_m = path_m.max(max_difference(&paths, &expected.paths_m));
    }
    let (host_time_us, timed_runs) = time_cases(cases, timing, |case| {
        black_box(solver.solve(case)?);
        Ok(())
    })?;
    let rk4_steps_per_sweep = solver.rk4_steps();
    let sweeps_per_solve = f64::from(sweeps) / cases.max(1) as f64;
    let work_rk4_steps = sweeps_per_solve * f64::from(rk4_steps_per_sweep);
    let tendon_work = match kind {
        TendonModel::ConstantCurvature => f64::from(PCC_COST),
        _ => work_rk4_steps * f64::from(tendon_step_cost(kind)),
    };
    let converged = termination.is_none();
    let error = |e: f64| converged.then_some(e);
    Ok(Row {
        scene: scene.key.clone(),
        family,
        steps_per_section: steps,
        rk4_steps_per_sweep,
        cases,
        sweeps_per_solve,
        work_rk4_steps,
        host_time_us,
        timed_runs,
        termination: termination.unwrap_or_else(|| "Converged".into()),
        tip_error_m: error(tip_m),
        backbone_error_m: error(backbone_m),
        cable_error_m: error(path_m),
        tendon_work: Some(tendon_work),
        front_work: false,
        front_time: false,
    })
}
