//! Model only what a scene requires: what `model_core::reduction::choose` picks for each scene and
//! tolerance, each candidate reduction's fewest steps, error and speedup, measured again against the
//! study's reference with host wall times, and the one reduction `choose` does not try under gravity
//! (skipping the guides' mass bookkeeping).

use model_checks::reference::Exp2Mass;
use model_core::reduction::{Choice, Trial, choose};
use model_core::{Model, ShootingSettings};
use nalgebra::Vector3;

use super::cases::{Bench, Scene};
use super::measure::{Reference, Row, Timing, measure};
use super::variants::{Family, Reduction};
use host_sim::scene::SceneError;

/// The tolerance the detailed tables use, m (0.01 mm: the project's accuracy target for the tip).
pub const MAIN_TOLERANCE_M: f64 = 1e-5;
/// Tolerances of the full study, m.
pub const FULL_TOLERANCES_M: [f64; 3] = [1e-4, 1e-5, 1e-6];
/// Tolerances of the quick study, m.
pub const QUICK_TOLERANCES_M: [f64; 1] = [MAIN_TOLERANCE_M];

/// One reduction's best candidate for a case and tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// The reduction.
    pub reduction: Reduction,
    /// The fewest ladder steps per section meeting the tolerance, if any does.
    pub steps: Option<u16>,
    /// The error `choose` measured at those steps (tip or any cable, against its own reference), m;
    /// if none meets the tolerance, the smallest error on the ladder.
    pub choose_error_m: Option<f64>,
    /// `choose`'s cost model: RK4 steps times the relative cost of one step.
    pub model_cost: Option<u32>,
    /// The same variant measured by the study (f64, quaternion frame).
    pub row: Option<Row>,
}

/// Skipping the guides' mass bookkeeping: average instead of accurate guide mass, so the guide edges
/// are no breakpoints.
#[derive(Clone, Debug, PartialEq)]
pub struct Bookkeeping {
    /// Steps per section compared (the full model's fewest for the tolerance).
    pub steps: u16,
    /// The full model with the accurate guide mass.
    pub accurate: Row,
    /// The average-mass model, against the accurate reference.
    pub average: Row,
    /// RK4 steps per sweep of the accurate-mass bench without gravity (the plan drops the guide
    /// edges by itself there).
    pub no_gravity_rk4_steps: u32,
}

/// `choose` on one case at one tolerance, and the study's measurements of its candidates.
#[derive(Clone, Debug, PartialEq)]
pub struct ReductionCase {
    /// Scene key.
    pub scene: String,
    /// The case.
    pub case_label: String,
    /// The tolerance asked for, m.
    pub tolerance_m: f64,
    /// The pick.
    pub picked: Reduction,
    /// Its steps per section.
    pub picked_steps: u16,
    /// Its error according to `choose`, m.
    pub picked_error_m: f64,
    /// Its cost, and that of the full model at its fewest steps meeting the tolerance (`choose`'s
    /// cost model).
    pub cost: u32,
    /// See `cost`.
    pub full_cost: u32,
    /// The pick's error against the study's reference (tip and cables, as `choose` measures), m.
    pub picked_study_error_m: Option<f64>,
    /// The pick's error with the backbone points too (the study's error), m: `choose` promises
    /// only tip and cables.
    pub picked_shape_error_m: Option<f64>,
    /// Every reduction's best candidate (at the main tolerance only; empty otherwise).
    pub candidates: Vec<Candidate>,
    /// The mass-bookkeeping comparison (accurate-mass scenes at the main tolerance).
    pub bookkeeping: Option<Bookkeeping>,
}

impl ReductionCase {
    /// Whether the pick meets the tolerance against the study's reference too, on tip and cables
    /// (what `choose` promises).
    pub fn meets(&self) -> bool {
        self.picked_study_error_m
            .is_some_and(|e| e.is_finite() && e <= self.tolerance_m)
    }

    /// Whether the pick is within the tolerance on the whole backbone too.
    pub fn shape_within(&self) -> bool {
        self.picked_shape_error_m
            .is_some_and(|e| e.is_finite() && e <= self.tolerance_m)
    }

    /// The full model's candidate.
    pub fn full(&self) -> Option<&Candidate> {
        self.candidates
            .iter()
            .find(|c| c.reduction == Reduction::Cosserat3d)
    }
}

fn model_error(what: &'static str) -> impl Fn(model_core::ModelError) -> SceneError {
    move |e| SceneError::new(what, e.to_string())
}

fn candidate(trials: &[Trial<f64>], reduction: Reduction, tolerance_m: f64) -> Candidate {
    let mine = trials.iter().filter(|t| {
        Reduction::of(t.variant.planar, t.variant.kirchhoff) == reduction && t.converged
    });
    let meeting = mine.clone().find(|t| t.error_m <= tolerance_m);
    match meeting {
        Some(t) => Candidate {
            reduction,
            steps: Some(t.variant.steps_per_section),
            choose_error_m: Some(t.error_m),
            model_cost: Some(t.cost),
            row: None,
        },
        None => Candidate {
            reduction,
            steps: None,
            choose_error_m: mine.map(|t| t.error_m).reduce(f64::min),
            model_cost: None,
            row: None,
        },
    }
}

/// The pick's error as `choose` measures it (tip and cables), against the study's reference.
fn tip_and_cables(row: &Row) -> Option<f64> {
    Some(row.tip_error_m?.max(row.cable_error_m?))
}

fn quaternion(reduction: Reduction) -> Family {
    Family {
        reduction,
        ..Family::REFERENCE
    }
}

/// `choose` on every case of `scene` at each tolerance (the candidates measured at the main one).
pub fn study(
    scene: &Scene,
    reference: &Reference,
    tolerances_m: &[f64],
    timing: Timing,
) -> Result<Vec<ReductionCase>, SceneError> {
    let settings = ShootingSettings::<f64>::default();
    let mut out = Vec::new();
    for case in 0..scene.forces_n.len() {
        let one = scene.only(case)?;
        let one_reference = reference.only(case)?;
        let rod = one.rod::<f64>(1, false)?;
        let load = one.load::<f64>(0)?;
        for &tolerance_m in tolerances_m {
            let choice: Choice<f64> =
                choose(&rod, &load, tolerance_m, &settings).map_err(model_error("choose"))?;
            let picked = Reduction::of(choice.variant.planar, choice.variant.kirchhoff);
            let picked_steps = choice.variant.steps_per_section;
            let picked_row = measure(
                &one,
                &one_reference,
                quaternion(picked),
                picked_steps,
                timing,
            )?;
            let main = tolerance_m == MAIN_TOLERANCE_M;
            let mut candidates = Vec::new();
            if main {
                for reduction in Reduction::ALL {
                    let mut c = candidate(&choice.trials, reduction, tolerance_m);
                    let tried = choice
                        .trials
                        .iter()
                        .any(|t| Reduction::of(t.variant.planar, t.variant.kirchhoff) == reduction);
                    if !tried {
                        continue;
                    }
                    if let Some(steps) = c.steps {
                        c.row = Some(measure(
                            &one,
                            &one_reference,
                            quaternion(reduction),
                            steps,
                            timing,
                        )?);
                    }
                    candidates.push(c);
                }
            }
            let mut result = ReductionCase {
                scene: scene.key.clone(),
                case_label: one.case_labels.first().cloned().unwrap_or_default(),
                tolerance_m,
                picked,
                picked_steps,
                picked_error_m: choice.error_m,
                cost: choice.cost,
                full_cost: choice.full_cost,
                picked_study_error_m: tip_and_cables(&picked_row),
                picked_shape_error_m: picked_row.error_m(),
                candidates,
                bookkeeping: None,
            };
            if main && one.bench == Bench::Exp2(Exp2Mass::Accurate) {
                result.bookkeeping = result
                    .full()
                    .and_then(|c| c.row.clone())
                    .map(|full| bookkeeping(&one, &one_reference, full, timing))
                    .transpose()?;
            }
            out.push(result);
        }
    }
    Ok(out)
}

fn bookkeeping(
    scene: &Scene,
    reference: &Reference,
    accurate: Row,
    timing: Timing,
) -> Result<Bookkeeping, SceneError> {
    let steps = accurate.steps_per_section;
    let average = measure(
        &scene.on_bench(Bench::Exp2(Exp2Mass::Average)),
        reference,
        Family::REFERENCE,
        steps,
        timing,
    )?;
    let mut weightless = scene.rod::<f64>(steps, false)?;
    weightless.gravity_m_s2 = Vector3::zeros();
    let no_gravity_rk4_steps = Model::<f64>::new(weightless)
        .map_err(model_error("weightless model"))?
        .plan()
        .total_steps();
    Ok(Bookkeeping {
        steps,
        accurate,
        average,
        no_gravity_rk4_steps,
    })
}
