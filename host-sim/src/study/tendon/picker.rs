//! `model_core::reduction::choose_tendons` checked against the study: for each tendon scene, case
//! and tolerance, its pick (PCC, continuous routing or discrete guides at the fewest ladder steps)
//! is measured again against the study's reference, on tip and path lengths (what it promises) and
//! with the backbone too, and timed against the discrete guides at their own fewest ladder steps.

use std::collections::BTreeMap;

use model_core::ShootingSettings;
use model_core::reduction::{TendonChoice, TendonModel, choose_tendons};

use super::super::measure::{Row, Timing};
use super::super::variants::{Arithmetic, Reduction};
use super::cases::TendonScene;
use super::measure::{TendonReference, measure, tendon_family};
use host_sim::scene::SceneError;

/// Tolerances of the full study, m: from PCC's reach to the discrete guides'.
pub const FULL_TOLERANCES_M: [f64; 6] = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
/// Tolerances of the quick study, m.
pub const QUICK_TOLERANCES_M: [f64; 1] = [1e-5];

/// `choose_tendons` on one case at one tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonPick {
    /// Scene key.
    pub scene: String,
    /// The case.
    pub case_label: String,
    /// The tolerance asked for, m.
    pub tolerance_m: f64,
    /// The pick and its steps per section (zero for PCC); `None` if `choose_tendons` refused.
    pub picked: Option<(Reduction, u16)>,
    /// Why it refused.
    pub refused: Option<String>,
    /// The pick's error by `choose_tendons` (tip or any path, against its own reference), m.
    pub choose_error_m: f64,
    /// Its cost and the discrete guides' at their fewest steps (`choose_tendons`' cost model).
    pub cost: u32,
    /// See `cost`.
    pub discrete_cost: u32,
    /// The discrete guides' fewest ladder steps within the tolerance, if any.
    pub discrete_steps: Option<u16>,
    /// The pick measured by the study (f64).
    pub pick_row: Option<Row>,
    /// The discrete guides at their fewest ladder steps, measured by the study (f64).
    pub discrete_row: Option<Row>,
}

impl TendonPick {
    /// The pick's error against the study's reference on tip and paths (what `choose_tendons`
    /// measures and promises), m.
    pub fn study_error_m(&self) -> Option<f64> {
        let r = self.pick_row.as_ref()?;
        Some(r.tip_error_m?.max(r.cable_error_m?))
    }

    /// Whether the pick meets the tolerance against the study's reference.
    pub fn meets(&self) -> bool {
        self.study_error_m()
            .is_some_and(|e| e.is_finite() && e <= self.tolerance_m)
    }

    /// Whether the whole backbone is within the tolerance too.
    pub fn shape_within(&self) -> bool {
        self.pick_row
            .as_ref()
            .and_then(Row::error_m)
            .is_some_and(|e| e.is_finite() && e <= self.tolerance_m)
    }

    /// The discrete guides' host time over the pick's, each at its own fewest steps.
    pub fn speedup(&self) -> Option<f64> {
        Some(self.discrete_row.as_ref()?.host_time_us / self.pick_row.as_ref()?.host_time_us)
    }
}

fn reduction(model: TendonModel) -> Reduction {
    tendon_family(Arithmetic::F64, model).reduction
}

/// The discrete guides' fewest ladder steps within `tolerance_m` in `choice`'s trials.
fn discrete_steps(choice: &TendonChoice<f64>, tolerance_m: f64) -> Option<u16> {
    choice
        .trials
        .iter()
        .find(|t| {
            t.variant.model == TendonModel::DiscreteGuides
                && t.converged
                && t.error_m <= tolerance_m
        })
        .map(|t| t.variant.steps_per_section)
}

/// `choose_tendons` on every case of `scene` at each tolerance.
pub fn study(
    scene: &TendonScene,
    reference: &TendonReference,
    tolerances_m: &[f64],
    timing: Timing,
) -> Result<Vec<TendonPick>, SceneError> {
    let settings = ShootingSettings::<f64>::default();
    let mut out = Vec::new();
    for case in 0..scene.cases.len() {
        let one = scene.only(case)?;
        let one_reference = reference.only(case)?;
        let (rod, tendons) = one.rod::<f64>(1)?;
        let tensions = one.tensions::<f64>(0)?;
        let load = one.load::<f64>(0)?;
        // Rows already measured for this case, by model and steps.
        let mut measured: BTreeMap<(Reduction, u16), Row> = BTreeMap::new();
        let mut row = |model: TendonModel, steps: u16| -> Result<Row, SceneError> {
            let key = (reduction(model), steps);
            if let Some(r) = measured.get(&key) {
                return Ok(r.clone());
            }
            let family = tendon_family(Arithmetic::F64, model);
            let r = measure(&one, &one_reference, family, steps, timing)?;
            measured.insert(key, r.clone());
            Ok(r)
        };
        for &tolerance_m in tolerances_m {
            let case_label = one
                .cases
                .first()
                .map(|c| c.label.clone())
                .unwrap_or_default();
            let choice =
                match choose_tendons(&rod, &tendons, &tensions, &load, tolerance_m, &settings) {
                    Ok(c) => c,
                    Err(e) => {
                        out.push(TendonPick {
                            scene: scene.key.clone(),
                            case_label,
                            tolerance_m,
                            picked: None,
                            refused: Some(e.to_string()),
                            choose_error_m: f64::NAN,
                            cost: 0,
                            discrete_cost: 0,
                            discrete_steps: None,
                            pick_row: None,
                            discrete_row: None,
                        });
                        continue;
                    }
                };
            let steps = choice.variant.steps_per_section;
            let pick_row = row(choice.variant.model, steps)?;
            let discrete = discrete_steps(&choice, tolerance_m);
            let discrete_row = discrete
                .map(|n| row(TendonModel::DiscreteGuides, n))
                .transpose()?;
            out.push(TendonPick {
                scene: scene.key.clone(),
                case_label,
                tolerance_m,
                picked: Some((reduction(choice.variant.model), steps)),
                refused: None,
                choose_error_m: choice.error_m,
                cost: choice.cost,
                discrete_cost: choice.discrete_cost,
                discrete_steps: discrete,
                pick_row: Some(pick_row),
                discrete_row,
            });
        }
    }
    Ok(out)
}
