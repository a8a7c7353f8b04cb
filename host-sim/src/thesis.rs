//! The thesis's experiments (ch. 4): Table 4.1 (two sections), Tables 4.3/4.4 (tip with guides, average
//! and accurate mass) and Table 4.5 (cable deflection), run through the model in f64.
//!
//! The tables are in cm and grams; they are converted here, once, and the model works in SI.

use model_checks::reference::{self, csv_rows};
use model_core::{Model, PointLoad, ShapePoint, Stability, Start, TipLoad};
use nalgebra::Vector3;

use crate::scene::{Scene, SceneError};
use crate::scenes;

/// Centimetres per metre.
pub const CM_PER_M: f64 = 100.0;
/// Kilograms per gram.
pub const KG_PER_G: f64 = 1e-3;

/// The thesis's own mean errors, as printed: Table 4.1 (section 1, section 2, % of the section length),
/// Table 4.3 (% of the rod length), Table 4.5 (cm, average-mass and accurate-mass models).
pub const THESIS_MEAN_ERR_4_1_PCT: [f64; 2] = [0.919, 1.33];
/// See [`THESIS_MEAN_ERR_4_1_PCT`].
pub const THESIS_MEAN_ERR_4_3_PCT: f64 = 1.269;
/// See [`THESIS_MEAN_ERR_4_1_PCT`].
pub const THESIS_MEAN_ERR_4_5_CM: [f64; 2] = [0.0819, 0.111];

/// Reproduction tolerances: how close this model must come to the thesis's predictions.
pub const TOL_4_1_CM: f64 = 0.1;
/// Table 4.5: cable deltas, cm.
pub const TOL_4_5_CM: f64 = 0.01;
/// Tables 4.3/4.4: the thesis's predictions are not reproduced by the corrected model (see README);
/// the check is that every row converges to a stable equilibrium and the mean error against the
/// observed tips stays within this, % of the rod length (the thesis reports 1.27 %).
pub const TOL_4_3_MEAN_PCT: f64 = 2.0;

/// A point in the grid plane, cm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointCm {
    /// x along the clamped rod, cm.
    pub x: f64,
    /// y up, cm.
    pub y: f64,
}

impl PointCm {
    fn from_m(v: &Vector3<f64>) -> Self {
        Self {
            x: v.x * CM_PER_M,
            y: v.y * CM_PER_M,
        }
    }

    /// Distance to another point, cm.
    pub fn distance(&self, other: &Self) -> f64 {
        ((self.x - other.x).powi(2) + (self.y - other.y).powi(2)).sqrt()
    }
}

/// One solved row: the observed point, the thesis's prediction and ours.
#[derive(Debug, Clone, PartialEq)]
pub struct TipRow {
    /// Hung mass, g.
    pub mass_g: f64,
    /// Observed on the grid.
    pub observed: PointCm,
    /// The thesis's model.
    pub thesis: PointCm,
    /// This model.
    pub ours: PointCm,
    /// Did the solve converge to a stable equilibrium?
    pub converged: bool,
    /// The solve's stability verdict.
    pub stability: Stability<f64>,
}

impl TipRow {
    /// Our error against the observation, cm.
    pub fn error_cm(&self) -> f64 {
        self.ours.distance(&self.observed)
    }
    /// The thesis's error against the observation, cm.
    pub fn thesis_error_cm(&self) -> f64 {
        self.thesis.distance(&self.observed)
    }
    /// How far we are from the thesis's prediction, cm.
    pub fn reproduction_cm(&self) -> f64 {
        self.ours.distance(&self.thesis)
    }
}

/// The backbone of one solved row, for plots, cm.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Hung mass, g.
    pub mass_g: f64,
    /// Backbone points, cm.
    pub points: Vec<PointCm>,
    /// Did its solve converge to a stable equilibrium? If not, the points are no answer: not drawn.
    pub converged: bool,
}

/// Experiment 1a: both section tips per row.
#[derive(Debug, Clone, PartialEq)]
pub struct Table41 {
    /// Section-1 tips.
    pub section1: Vec<TipRow>,
    /// Section-2 tips.
    pub section2: Vec<TipRow>,
    /// Backbones.
    pub curves: Vec<Curve>,
    /// Section length, cm (errors in % are of this, as in the thesis).
    pub section_length_cm: f64,
}

/// Experiment 2: the tip per row, one mass model.
#[derive(Debug, Clone, PartialEq)]
pub struct Table43 {
    /// "average" or "accurate".
    pub model: &'static str,
    /// Tips.
    pub rows: Vec<TipRow>,
    /// Backbones.
    pub curves: Vec<Curve>,
    /// Rod length, cm.
    pub rod_length_cm: f64,
}

/// Table 4.5: the measured cable's change of length.
#[derive(Debug, Clone, PartialEq)]
pub struct DeltaRow {
    /// Hung mass, g.
    pub mass_g: f64,
    /// Observed change, cm.
    pub observed_cm: f64,
    /// The thesis's predicted change, cm (average, accurate).
    pub thesis_cm: [f64; 2],
    /// Ours (average, accurate), cm.
    pub ours_cm: [f64; 2],
    /// Our predicted cable lengths (average, accurate), cm.
    pub ours_length_cm: [f64; 2],
    /// Did this row's solve and the 0 g reference's converge to a stable equilibrium (average,
    /// accurate)? If not, the row's values of that model are NaN: failed, no answer.
    pub converged: [bool; 2],
}

impl DeltaRow {
    /// A row from our cable lengths and the 0 g reference's, cm (None: the solve did not converge
    /// to a stable equilibrium).
    fn new(
        mass_g: f64,
        observed_cm: f64,
        thesis_cm: [f64; 2],
        length_cm: [Option<f64>; 2],
        reference_cm: [Option<f64>; 2],
    ) -> Self {
        let delta = |m: usize| match (length_cm[m], reference_cm[m]) {
            (Some(l), Some(r)) => Some(l - r),
            _ => None,
        };
        Self {
            mass_g,
            observed_cm,
            thesis_cm,
            ours_cm: [0, 1].map(|m| delta(m).unwrap_or(f64::NAN)),
            ours_length_cm: length_cm.map(|l| l.unwrap_or(f64::NAN)),
            converged: [0, 1].map(|m| delta(m).is_some()),
        }
    }
}

/// Table 4.5.
#[derive(Debug, Clone, PartialEq)]
pub struct Table45 {
    /// Rows.
    pub rows: Vec<DeltaRow>,
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// Our mean error over the rows that converged to a stable equilibrium, cm (the others are no
/// answer: see [`not_converged`]).
fn mean_converged_error_cm(rows: &[TipRow]) -> f64 {
    mean(rows.iter().filter(|r| r.converged).map(TipRow::error_cm))
}

/// How many rows did not converge to a stable equilibrium (left out of our means).
pub fn not_converged(rows: &[TipRow]) -> usize {
    rows.iter().filter(|r| !r.converged).count()
}

/// " (n rows not converged, left out)" when n > 0: the note on a mean or worst over the converged
/// rows.
pub fn left_out_note(n: usize) -> String {
    match n {
        0 => String::new(),
        1 => " (1 row not converged, left out)".into(),
        n => format!(" ({n} rows not converged, left out)"),
    }
}

impl Table41 {
    /// Mean error against the observations over the converged rows, cm (sections 1 and 2).
    pub fn mean_error_cm(&self) -> [f64; 2] {
        [&self.section1, &self.section2].map(|rows| mean_converged_error_cm(rows))
    }
    /// Mean error against the observations over the converged rows, % of the section length
    /// (sections 1 and 2).
    pub fn mean_error_pct(&self) -> [f64; 2] {
        self.mean_error_cm()
            .map(|cm| cm / self.section_length_cm * 100.0)
    }
    /// The thesis's mean error recomputed from its table, %.
    pub fn thesis_mean_error_pct(&self) -> [f64; 2] {
        [&self.section1, &self.section2].map(|rows| {
            mean(rows.iter().map(TipRow::thesis_error_cm)) / self.section_length_cm * 100.0
        })
    }
    /// Largest distance from the thesis's predictions over the converged rows, cm.
    pub fn worst_reproduction_cm(&self) -> f64 {
        self.section1
            .iter()
            .chain(&self.section2)
            .filter(|r| r.converged)
            .map(TipRow::reproduction_cm)
            .fold(0.0, f64::max)
    }
}

impl Table43 {
    /// Mean error against the observations over the converged rows, cm.
    pub fn mean_error_cm(&self) -> f64 {
        mean_converged_error_cm(&self.rows)
    }
    /// Mean error against the observations over the converged rows, % of the rod length.
    pub fn mean_error_pct(&self) -> f64 {
        self.mean_error_cm() / self.rod_length_cm * 100.0
    }
    /// The thesis's mean error recomputed from its table, %.
    pub fn thesis_mean_error_pct(&self) -> f64 {
        mean(self.rows.iter().map(TipRow::thesis_error_cm)) / self.rod_length_cm * 100.0
    }
    /// Largest distance from the thesis's predictions, cm.
    pub fn worst_reproduction_cm(&self) -> f64 {
        self.rows
            .iter()
            .map(TipRow::reproduction_cm)
            .fold(0.0, f64::max)
    }
}

impl Table45 {
    /// Mean absolute error of our deltas against the observations over the converged rows, cm
    /// (average, accurate).
    pub fn mean_error_cm(&self) -> [f64; 2] {
        [0, 1].map(|m| {
            mean(
                self.rows
                    .iter()
                    .filter(|r| r.converged[m])
                    .map(|r| (r.ours_cm[m] - r.observed_cm).abs()),
            )
        })
    }
    /// Largest distance from the thesis's predicted deltas over the converged rows, cm (average,
    /// accurate).
    pub fn worst_reproduction_cm(&self) -> [f64; 2] {
        [0, 1].map(|m| {
            self.rows
                .iter()
                .filter(|r| r.converged[m])
                .map(|r| (r.ours_cm[m] - r.thesis_cm[m]).abs())
                .fold(0.0, f64::max)
        })
    }
    /// How many rows did not converge to a stable equilibrium (average, accurate).
    pub fn not_converged(&self) -> [usize; 2] {
        [0, 1].map(|m| self.rows.iter().filter(|r| !r.converged[m]).count())
    }
}

/// Everything `validate` computes.
#[derive(Debug, Clone, PartialEq)]
pub struct Validation {
    /// Experiment 1a.
    pub table_4_1: Table41,
    /// Experiment 2, average mass.
    pub table_4_3_average: Table43,
    /// Experiment 2, accurate mass.
    pub table_4_4_accurate: Table43,
    /// Cable deflection.
    pub table_4_5: Table45,
}

/// A reproduction check.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// What.
    pub name: String,
    /// Measured.
    pub value: f64,
    /// Limit.
    pub limit: f64,
    /// Passed?
    pub passed: bool,
}

impl Validation {
    /// The reproduction checks `validate` enforces.
    pub fn checks(&self) -> Vec<Check> {
        let check = |name: &str, value: f64, limit: f64| Check {
            name: name.into(),
            value,
            limit,
            passed: value.is_finite() && value <= limit,
        };
        let count = |rows: &[TipRow]| not_converged(rows) as f64;
        let t45 = self.table_4_5.worst_reproduction_cm();
        let t45_failed = self.table_4_5.not_converged();
        let mean_4_3 = |number: &str, t: &Table43| {
            format!(
                "Table {number} ({}): mean tip error vs observed, % of rod{}",
                t.model,
                left_out_note(not_converged(&t.rows))
            )
        };
        vec![
            check(
                &format!(
                    "Table 4.1: worst distance from the thesis's predicted section tips, cm{}",
                    // (A row's two section tips come from one solve: a row, as the check below
                    // counts them, is a section 1 tip.)
                    left_out_note(not_converged(&self.table_4_1.section1))
                ),
                self.table_4_1.worst_reproduction_cm(),
                TOL_4_1_CM,
            ),
            check(
                "Table 4.1: rows not converged to a stable equilibrium",
                count(&self.table_4_1.section1),
                0.0,
            ),
            check(
                "Table 4.3 (average): rows not converged to a stable equilibrium",
                count(&self.table_4_3_average.rows),
                0.0,
            ),
            check(
                "Table 4.4 (accurate): rows not converged to a stable equilibrium",
                count(&self.table_4_4_accurate.rows),
                0.0,
            ),
            check(
                &mean_4_3("4.3", &self.table_4_3_average),
                self.table_4_3_average.mean_error_pct(),
                TOL_4_3_MEAN_PCT,
            ),
            check(
                &mean_4_3("4.4", &self.table_4_4_accurate),
                self.table_4_4_accurate.mean_error_pct(),
                TOL_4_3_MEAN_PCT,
            ),
            check(
                "Table 4.5 (average): rows not converged to a stable equilibrium",
                t45_failed[0] as f64,
                0.0,
            ),
            check(
                "Table 4.5 (accurate): rows not converged to a stable equilibrium",
                t45_failed[1] as f64,
                0.0,
            ),
            check(
                &format!(
                    "Table 4.5 (average): worst distance from the thesis's deltas, cm{}",
                    left_out_note(t45_failed[0])
                ),
                t45[0],
                TOL_4_5_CM,
            ),
            check(
                &format!(
                    "Table 4.5 (accurate): worst distance from the thesis's deltas, cm{}",
                    left_out_note(t45_failed[1])
                ),
                t45[1],
                TOL_4_5_CM,
            ),
        ]
    }
}

/// A scene's rod solved under a tip weight: the cable lengths and the report.
pub(crate) struct Solved {
    pub cables_m: Vec<f64>,
    pub converged: bool,
    pub stability: Stability<f64>,
}

impl Solved {
    /// Converged to a stable equilibrium: an answer.
    pub fn is_answer(&self) -> bool {
        self.converged && self.stability == Stability::Stable
    }
}

/// A backbone at each of several sets of arc lengths.
pub(crate) type Shapes<const N: usize> = [Vec<ShapePoint<f64>>; N];

/// Solves a scene's rod under `load` (cold), and its backbone at each set of arc lengths in
/// `point_sets` (each increasing), from the one solve.
pub(crate) fn solve_rows<const N: usize>(
    model: &Model<f64>,
    scene: &Scene,
    load: &TipLoad<f64>,
    point_sets: [&[f64]; N],
) -> Result<(Solved, Shapes<N>), SceneError> {
    let settings = scene.shooting_settings()?;
    let eq = model
        .solve(load, Start::Cold, &settings)
        .map_err(|e| SceneError::new("tip", e.to_string()))?;
    let mut shapes: Shapes<N> = core::array::from_fn(|_| Vec::new());
    for (points, s_m) in shapes.iter_mut().zip(point_sets) {
        points.resize(s_m.len(), ShapePoint::default());
        model
            .shape(&eq, s_m, points)
            .map_err(|e| SceneError::new("output", e.to_string()))?;
    }
    let solved = Solved {
        cables_m: eq.cable_lengths_m.iter().copied().collect(),
        converged: eq.report.termination.is_success(),
        stability: eq.report.stability,
    };
    Ok((solved, shapes))
}

fn weight(scene: &Scene, mass_g: f64) -> TipLoad<f64> {
    TipLoad::force(Vector3::from(scene.gravity_m_s2) * (mass_g * KG_PER_G))
}

fn table_error(e: model_core::ModelError) -> SceneError {
    SceneError::new("thesis table", e.to_string())
}

/// Runs experiment 1a on the shipped two-section scene, one hung mass per row.
pub fn table_4_1() -> Result<Table41, SceneError> {
    let scene = scenes::exp1()?;
    let transition_m = scene.sections.first().map_or(0.0, |s| s.length_m);
    let base_rod = scene.rod()?;
    let length_m = base_rod.length_m();
    let curve_s = scene.output_points_m(length_m)?;
    let mut out = Table41 {
        section1: Vec::new(),
        section2: Vec::new(),
        curves: Vec::new(),
        section_length_cm: transition_m * CM_PER_M,
    };
    for row in csv_rows::<9>(reference::TABLE_4_1_CSV) {
        let row = row.map_err(table_error)?;
        let mass_g = row[0];
        let mut rod = base_rod.clone();
        rod.loads.clear();
        rod.push_load(PointLoad::mass(transition_m, mass_g * KG_PER_G))
            .map_err(|e| SceneError::new("load", e.to_string()))?;
        let model = Model::<f64>::new(rod).map_err(|e| SceneError::new("scene", e.to_string()))?;
        // The section tips and the curve from one solve.
        let (solved, [tips, curve]) = solve_rows(
            &model,
            &scene,
            &TipLoad::zero(),
            [&[transition_m, length_m], &curve_s],
        )?;
        let converged = solved.is_answer();
        for (i, (section, observed, thesis)) in [
            (&mut out.section1, (row[1], row[2]), (row[5], row[6])),
            (&mut out.section2, (row[3], row[4]), (row[7], row[8])),
        ]
        .into_iter()
        .enumerate()
        {
            let ours = tips.get(i).map_or(
                PointCm {
                    x: f64::NAN,
                    y: f64::NAN,
                },
                |p| PointCm::from_m(&p.position_m),
            );
            section.push(TipRow {
                mass_g,
                observed: PointCm {
                    x: observed.0,
                    y: observed.1,
                },
                thesis: PointCm {
                    x: thesis.0,
                    y: thesis.1,
                },
                ours,
                converged,
                stability: solved.stability,
            });
        }
        out.curves.push(Curve {
            mass_g,
            points: curve
                .iter()
                .map(|p| PointCm::from_m(&p.position_m))
                .collect(),
            converged,
        });
    }
    Ok(out)
}

/// Runs experiment 2 (Table 4.3 with the average-mass scene, Table 4.4 with the accurate one).
pub fn table_4_3(accurate: bool) -> Result<Table43, SceneError> {
    let scene = if accurate {
        scenes::exp2_accurate()?
    } else {
        scenes::exp2_average()?
    };
    let rod = scene.rod()?;
    let length_m = rod.length_m();
    let curve_s = scene.output_points_m(length_m)?;
    let model = Model::<f64>::new(rod).map_err(|e| SceneError::new("scene", e.to_string()))?;
    let mut out = Table43 {
        model: if accurate { "accurate" } else { "average" },
        rows: Vec::new(),
        curves: Vec::new(),
        rod_length_cm: length_m * CM_PER_M,
    };
    for row in csv_rows::<5>(reference::TABLE_4_3_CSV) {
        let row = row.map_err(table_error)?;
        let mass_g = row[0];
        let (solved, [points]) = solve_rows(&model, &scene, &weight(&scene, mass_g), [&curve_s])?;
        let tip = points.last().map_or(
            PointCm {
                x: f64::NAN,
                y: f64::NAN,
            },
            |p| PointCm::from_m(&p.position_m),
        );
        out.rows.push(TipRow {
            mass_g,
            observed: PointCm {
                x: row[1],
                y: row[2],
            },
            thesis: PointCm {
                x: row[3],
                y: row[4],
            },
            ours: tip,
            converged: solved.is_answer(),
            stability: solved.stability,
        });
        out.curves.push(Curve {
            mass_g,
            points: points
                .iter()
                .map(|p| PointCm::from_m(&p.position_m))
                .collect(),
            converged: solved.is_answer(),
        });
    }
    Ok(out)
}

/// Runs Table 4.5: the measured cable's length per row, for both mass models, as a change from 0 g.
pub fn table_4_5() -> Result<Table45, SceneError> {
    let scenes = [scenes::exp2_average()?, scenes::exp2_accurate()?];
    let models = scenes
        .iter()
        .map(|s| Model::<f64>::new(s.rod()?).map_err(|e| SceneError::new("scene", e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let mut rows = Vec::new();
    let mut reference_cm = [None; 2];
    for (i, row) in csv_rows::<7>(reference::TABLE_4_5_CSV).enumerate() {
        let row = row.map_err(table_error)?;
        let mass_g = row[0];
        let mut length_cm = [None; 2];
        for (m, (model, scene)) in models.iter().zip(&scenes).enumerate() {
            let (solved, []) = solve_rows(model, scene, &weight(scene, mass_g), [])?;
            length_cm[m] = solved
                .is_answer()
                .then(|| solved.cables_m.first().copied().unwrap_or(f64::NAN) * CM_PER_M);
            if i == 0 {
                reference_cm[m] = length_cm[m];
            }
        }
        rows.push(DeltaRow::new(
            mass_g,
            row[2],
            [row[4], row[6]],
            length_cm,
            reference_cm,
        ));
    }
    Ok(Table45 { rows })
}

/// Runs every experiment.
pub fn validate() -> Result<Validation, SceneError> {
    Ok(Validation {
        table_4_1: table_4_1()?,
        table_4_3_average: table_4_3(false)?,
        table_4_4_accurate: table_4_3(true)?,
        table_4_5: table_4_5()?,
    })
}

/// One row of `host-sim inverse`: the hung mass estimated from the single measured cable's change.
#[derive(Debug, Clone, PartialEq)]
pub struct InverseRow {
    /// The mass actually hung, g.
    pub hung_g: f64,
    /// The observed cable change, cm.
    pub observed_delta_cm: f64,
    /// Estimated mass, g.
    pub estimate_g: f64,
    /// Its standard deviation from the ruler's resolution, g.
    pub std_g: f64,
    /// Estimated tip, cm.
    pub tip: PointCm,
    /// Its standard deviation, cm (x, y).
    pub tip_std_cm: [f64; 2],
    /// The observed tip (Table 4.3), cm.
    pub observed_tip: PointCm,
    /// Model minus measured cable length, cm.
    pub residual_cm: f64,
    /// Why the solve stopped.
    pub termination: model_core::Termination,
    /// How well the data determine the mass.
    pub determination: model_core::inverse::Determination,
}

/// `host-sim inverse`: for each row of Table 4.5, the tip load and tip position from the observed
/// change of the one measured cable (measured length = the model's 0 g length + the observed change),
/// with the uncertainty implied by the ruler's resolution (the scene's `estimate.resolution_m`, 1 mm).
pub fn inverse_table(accurate: bool) -> Result<Vec<InverseRow>, SceneError> {
    use model_core::inverse::{InverseSettings, InverseStart, LoadBasis, estimate};
    let scene = if accurate {
        scenes::exp2_accurate()?
    } else {
        scenes::exp2_average()?
    };
    let model =
        Model::<f64>::new(scene.rod()?).map_err(|e| SceneError::new("scene", e.to_string()))?;
    let gravity = Vector3::from(scene.gravity_m_s2);
    let g = gravity.norm();
    let basis = LoadBasis::force_along(&gravity)
        .map_err(|e| SceneError::new("gravity_m_s2", e.to_string()))?;
    let settings = InverseSettings {
        max_force_std_n: scene.estimate.max_force_std_n,
        ..InverseSettings::with_resolution(scene.estimate.resolution_m)
    };
    let (unloaded, []) = solve_rows(&model, &scene, &TipLoad::zero(), [])?;
    if !unloaded.is_answer() {
        return Err(SceneError::new(
            "0 g reference",
            format!(
                "did not converge to a stable equilibrium (converged {}, {:?}): no reference length",
                unloaded.converged, unloaded.stability
            ),
        ));
    }
    let reference_m = unloaded.cables_m.first().copied().unwrap_or(f64::NAN);
    let observed_tips: Vec<[f64; 5]> = csv_rows::<5>(reference::TABLE_4_3_CSV)
        .collect::<Result<_, _>>()
        .map_err(table_error)?;
    let mut rows = Vec::new();
    for row in csv_rows::<7>(reference::TABLE_4_5_CSV) {
        let row = row.map_err(table_error)?;
        let (hung_g, delta_cm) = (row[0], row[2]);
        let measured = [reference_m + delta_cm / CM_PER_M];
        let est = estimate(
            &model,
            &basis,
            &measured,
            InverseStart::Params(nalgebra::Vector1::new(0.0)),
            &settings,
        )
        .map_err(|e| SceneError::new("cable length", e.to_string()))?;
        let observed = observed_tips
            .iter()
            .find(|t| (t[0] - hung_g).abs() < 1e-9)
            .map_or(
                PointCm {
                    x: f64::NAN,
                    y: f64::NAN,
                },
                |t| PointCm { x: t[1], y: t[2] },
            );
        rows.push(InverseRow {
            hung_g,
            observed_delta_cm: delta_cm,
            estimate_g: est.params[0] / g / KG_PER_G,
            std_g: est.quality.param_std[0] / g / KG_PER_G,
            tip: PointCm::from_m(&est.tip_position_m),
            tip_std_cm: [
                est.quality.tip_std_m.x * CM_PER_M,
                est.quality.tip_std_m.y * CM_PER_M,
            ],
            observed_tip: observed,
            residual_cm: est.cable_residual_m[0] * CM_PER_M,
            termination: est.report.termination,
            determination: est.quality.determination,
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tip_row(ours_x_cm: f64, converged: bool) -> TipRow {
        TipRow {
            mass_g: 10.0,
            observed: PointCm { x: 0.0, y: 0.0 },
            thesis: PointCm { x: 0.0, y: 0.0 },
            ours: PointCm {
                x: ours_x_cm,
                y: 0.0,
            },
            converged,
            stability: if converged {
                Stability::Stable
            } else {
                Stability::FreeEndUnstable
            },
        }
    }

    fn table_4_3(rows: Vec<TipRow>) -> Table43 {
        Table43 {
            model: "average",
            rows,
            curves: Vec::new(),
            rod_length_cm: 80.0,
        }
    }

    fn delta_row(ours_cm: [f64; 2], converged: [bool; 2]) -> DeltaRow {
        DeltaRow {
            mass_g: 20.0,
            observed_cm: 0.5,
            thesis_cm: [0.5, 0.5],
            ours_cm,
            ours_length_cm: [38.0, 38.0],
            converged,
        }
    }

    #[test]
    fn a_failed_solve_gives_no_cable_delta() {
        let row = DeltaRow::new(20.0, 0.5, [0.5, 0.5], [Some(38.5), None], [Some(38.0); 2]);
        assert_eq!(row.converged, [true, false]);
        assert!((row.ours_cm[0] - 0.5).abs() < 1e-12, "{row:?}");
        assert!(
            row.ours_cm[1].is_nan() && row.ours_length_cm[1].is_nan(),
            "{row:?}"
        );
        // A failed 0 g reference fails every delta against it.
        let row = DeltaRow::new(20.0, 0.5, [0.5, 0.5], [Some(38.5); 2], [None, Some(38.0)]);
        assert_eq!(row.converged, [false, true]);
        assert!(
            row.ours_cm[0].is_nan() && row.ours_length_cm[0] == 38.5,
            "{row:?}"
        );
    }

    #[test]
    fn means_and_checks_leave_out_failed_rows_and_fail_on_them() {
        // 1 cm off where converged; the failed rows are far off and must not count.
        let rows = vec![
            tip_row(1.0, true),
            tip_row(1.0, true),
            tip_row(100.0, false),
        ];
        let t43 = table_4_3(rows.clone());
        assert!((t43.mean_error_cm() - 1.0).abs() < 1e-12);
        assert!((t43.mean_error_pct() - 1.25).abs() < 1e-12);
        let t41 = Table41 {
            section1: rows.clone(),
            section2: rows,
            curves: Vec::new(),
            section_length_cm: 20.0,
        };
        assert_eq!(t41.mean_error_pct(), [5.0, 5.0]);
        let v = Validation {
            table_4_1: t41,
            table_4_3_average: t43,
            table_4_4_accurate: table_4_3(vec![tip_row(1.0, true)]),
            table_4_5: Table45 {
                rows: vec![
                    delta_row([0.501, 0.502], [true, true]),
                    delta_row([0.9, 0.9], [true, false]),
                ],
            },
        };
        let checks = v.checks();
        let find = |name: &str| {
            checks
                .iter()
                .find(|c| c.name.starts_with(name))
                .unwrap_or_else(|| panic!("no check {name:?} in {checks:?}"))
        };
        let mean = find("Table 4.3 (average): mean tip error vs observed, % of rod");
        assert!(mean.passed && (mean.value - 1.25).abs() < 1e-12, "{mean:?}");
        assert!(
            mean.name.ends_with("(1 row not converged, left out)"),
            "{mean:?}"
        );
        assert!(!find("Table 4.3 (average): rows not converged").passed);
        assert!(find("Table 4.4 (accurate): rows not converged").passed);
        // Table 4.5: the failed accurate row fails the table and is not a distance from the thesis.
        assert!(find("Table 4.5 (average): rows not converged").passed);
        let failed = find("Table 4.5 (accurate): rows not converged");
        assert!(!failed.passed && failed.value == 1.0, "{failed:?}");
        let worst = find("Table 4.5 (accurate): worst distance from the thesis's deltas, cm");
        assert!((worst.value - 0.002).abs() < 1e-12, "{worst:?}");
        assert!(
            worst.name.ends_with("(1 row not converged, left out)"),
            "{worst:?}"
        );
        let worst = find("Table 4.5 (average): worst distance from the thesis's deltas, cm");
        assert!((worst.value - 0.4).abs() < 1e-12, "{worst:?}");
        assert!((v.table_4_5.mean_error_cm()[1] - 0.002).abs() < 1e-12);
    }

    #[test]
    fn only_a_converged_stable_solve_is_an_answer() {
        let solved = |converged, stability| Solved {
            cables_m: Vec::new(),
            converged,
            stability,
        };
        assert!(solved(true, Stability::Stable).is_answer());
        assert!(!solved(false, Stability::Stable).is_answer());
        assert!(!solved(true, Stability::FreeEndUnstable).is_answer());
    }
}
