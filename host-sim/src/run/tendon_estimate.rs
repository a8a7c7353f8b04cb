//! `estimate` on a scene with tendons: the tensions, the tip force and the shape from the spool
//! displacements and optionally measured tensions (model-core's `Model::estimate_tendons`, MODEL.md
//! §6.4), with their standard deviations and verdicts.
//!
//! As for the cable estimate, a failed fit's numbers are not printed (`null`), an inconsistent fit's
//! are (its residuals show which measurement disagrees), and a tip force the data do not determine
//! (displacements alone) is not printed either: `tip_force_n` is `null`, `force_observable` false,
//! and the status and a warning say why.

use model_core::inverse::Determination;
use model_core::{
    Attitude, MeasuredTensions, Model, ModelError, TendonEstimate, TendonInverseSettings,
    TendonState, Tendons,
};
use serde::Serialize;

use super::figure::{FigureSpec, figure};
use super::{Point, Report, Status, WithModel, arr, point, real, state_name, tendon_shape};
use crate::plots::Figure;
use crate::scene::{Actuation, Scene, SceneError, TensionMeasurement};

/// `estimate` on a scene with tendons.
#[derive(Debug)]
pub struct TendonInverse<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The spool displacements (displacement control: the scene's `[actuation] displacements_m`
    /// or `--displacements`), m.
    pub displacements: Actuation,
    /// Measured tensions, if any.
    pub measured: Option<TensionMeasurement>,
    /// The inverse's settings ([`Scene::tendon_inverse_settings`]).
    pub settings: TendonInverseSettings<f64>,
    /// Also compute the figure (`--plot`).
    pub plot: bool,
}

/// The settings an estimate used (in JSON, so that its standard deviations can be traced).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct InverseSettingsOutput {
    /// Standard deviation of a spool displacement, m (`[estimate] resolution_m / sqrt 12`).
    #[serde(serialize_with = "real::one")]
    pub displacement_std_m: f64,
    /// The model's error in a tendon path, m, in quadrature with the encoder's.
    #[serde(serialize_with = "real::one")]
    pub model_length_std_m: f64,
    /// The prior's standard deviation of each tip force component, N.
    #[serde(serialize_with = "real::one")]
    pub force_prior_std_n: f64,
    /// A larger tip force deviation makes the estimate `Weak`, N.
    #[serde(serialize_with = "real::one")]
    pub max_force_std_n: f64,
    /// A larger tension deviation makes it `Weak`, N.
    #[serde(serialize_with = "real::one")]
    pub max_tension_std_n: f64,
    /// How far the search for other answers restarts, buckling scales of tip force.
    #[serde(serialize_with = "real::one")]
    pub scan_reach: f64,
    /// Levenberg-Marquardt iterations per fit.
    pub max_iterations: u16,
}

impl From<&TendonInverseSettings<f64>> for InverseSettingsOutput {
    fn from(s: &TendonInverseSettings<f64>) -> Self {
        Self {
            displacement_std_m: s.displacement_std_m,
            model_length_std_m: s.model_length_std_m,
            force_prior_std_n: s.force_prior_std_n,
            max_force_std_n: s.max_force_std_n,
            max_tension_std_n: s.max_tension_std_n,
            scan_reach: s.scan_reach,
            max_iterations: s.max_iterations,
        }
    }
}

/// How the fit went (also for a failed fit: how far it got).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FitReport {
    /// Why the fit stopped ("Converged" is the only answer).
    pub termination: String,
    /// Iterations of the fit that gave the answer.
    pub iterations: u16,
    /// Sweeps spent, the search for other answers included.
    pub sweeps: u32,
}

/// The tendons of an estimate: what was given (always printed), and what was estimated (`None`,
/// JSON `null`, without an answer).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TendonEstimateTendons {
    /// The spool displacements given, m.
    #[serde(serialize_with = "real::many")]
    pub displacements_m: Vec<f64>,
    /// The measured tensions given, N (`null`: none).
    #[serde(serialize_with = "real::opt_many")]
    pub tensions_measured_n: Option<Vec<f64>>,
    /// Their standard deviations, N (`null`: none).
    #[serde(serialize_with = "real::opt_many")]
    pub tension_measured_std_n: Option<Vec<f64>>,
    /// Each tension estimated, N.
    #[serde(serialize_with = "real::opt_many")]
    pub tensions_n: Option<Vec<f64>>,
    /// Its posterior standard deviation, N.
    #[serde(serialize_with = "real::opt_many")]
    pub tension_std_n: Option<Vec<f64>>,
    /// Each tendon's state: `"taut"` or `"slack"` (zero tension).
    pub states: Option<Vec<&'static str>>,
    /// Each tendon's path length at the estimate, m.
    #[serde(serialize_with = "real::opt_many")]
    pub path_m: Option<Vec<f64>>,
    /// Each slack tendon's slack, m (zero when taut).
    #[serde(serialize_with = "real::opt_many")]
    pub slack_m: Option<Vec<f64>>,
    /// Each taut tendon's displacement, model minus measured, m (zero for a slack one: any slack
    /// is consistent).
    #[serde(serialize_with = "real::opt_many")]
    pub displacement_residual_m: Option<Vec<f64>>,
    /// Each tension, estimated minus measured, N (`null` without measured tensions).
    #[serde(serialize_with = "real::opt_many")]
    pub tension_residual_n: Option<Vec<f64>>,
}

/// The result of `estimate` on a scene with tendons. Without an answer every estimated number is
/// `null`; the inputs, the settings and the reports stay.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TendonEstimateOutput {
    /// Whether this is an answer, and why not; with the verdicts.
    pub status: Status,
    /// Scene name.
    pub scene: String,
    /// The inverse's settings.
    pub settings: InverseSettingsOutput,
    /// How the fit went.
    pub fit: FitReport,
    /// The last forward solve's report.
    pub report: Report,
    /// Whether the data alone determine the tip force (displacements alone: false).
    pub force_observable: Option<bool>,
    /// The estimated tip force, N (`null` without an answer, or when not observable).
    #[serde(serialize_with = "real::opt_many")]
    pub tip_force_n: Option<[f64; 3]>,
    /// Its standard deviation, N (`null` likewise).
    #[serde(serialize_with = "real::opt_many")]
    pub tip_force_std_n: Option<[f64; 3]>,
    /// Tip position, m.
    #[serde(serialize_with = "real::opt_many")]
    pub tip_position_m: Option<[f64; 3]>,
    /// Its standard deviation, m.
    #[serde(serialize_with = "real::opt_many")]
    pub tip_position_std_m: Option<[f64; 3]>,
    /// Whether any datum was to spare to test the model against the data (model-core's
    /// `consistency_tested`); without, the estimate is at best weak and cannot be found inconsistent.
    pub consistency_tested: Option<bool>,
    /// Rms of the whitened data residuals (displacements and measured tensions) per spare datum,
    /// standard deviations (`null` when none is to spare).
    #[serde(serialize_with = "real::opt_one")]
    pub residual_rms_sigma: Option<f64>,
    /// The tendons, given and estimated.
    pub tendons: TendonEstimateTendons,
    /// Backbone at the output points.
    pub shape: Option<Vec<Point>>,
    /// The figure (`--plot`), for an answer or an inconsistent estimate's closest fit.
    #[serde(skip)]
    pub figure: Option<Figure>,
}

/// The top-level keys of [`TendonEstimateOutput`] that are `null` without an answer.
pub const TENDON_ESTIMATE_KEYS: [&str; 8] = [
    "force_observable",
    "consistency_tested",
    "tip_force_n",
    "tip_force_std_n",
    "tip_position_m",
    "tip_position_std_m",
    "residual_rms_sigma",
    "shape",
];

/// The keys of its `tendons` object that are `null` without an answer.
pub const TENDON_ESTIMATE_TENDON_KEYS: [&str; 7] = [
    "tensions_n",
    "tension_std_n",
    "states",
    "path_m",
    "slack_m",
    "displacement_residual_m",
    "tension_residual_n",
];

impl TendonInverse<'_> {
    /// The key a refusal from model-core names.
    fn key_of(&self, e: &ModelError) -> String {
        use ModelError::*;
        let what = match e {
            NonFinite(w) | NotPositive(w) | OutOfRange(w) | Unordered(w) | Capacity(w)
            | Empty(w) | Mismatch(w) => *w,
        };
        match &self.measured {
            Some(m) if what.starts_with("measured tension") => m.key.clone(),
            Some(m) if what.starts_with("tension standard") => m.std_key.clone(),
            _ if what.starts_with("tendon displacement") || what.starts_with("displacements") => {
                self.displacements.key.clone()
            }
            _ => "estimate".to_string(),
        }
    }
}

impl WithModel for TendonInverse<'_> {
    type Output = TendonEstimateOutput;
    fn run<A: Attitude<f64>>(
        self,
        model: &Model<f64, A>,
    ) -> Result<TendonEstimateOutput, SceneError> {
        let shooting = self.scene.shooting_settings()?;
        let tendons = self
            .scene
            .tendon_set(model)?
            .ok_or_else(|| SceneError::new("tendon", "the scene has no [[tendon]]"))?;
        self.displacements.check(&tendons)?;
        let d = &self.displacements.values;
        let measured = self.measured.as_ref().map(|m| MeasuredTensions {
            tensions_n: &m.tensions_n,
            std_n: &m.std_n,
        });
        let est = model
            .estimate_tendons(&tendons, d, measured, None, &shooting, &self.settings)
            .map_err(|e| SceneError::new(self.key_of(&e), e.to_string()))?;
        let q = &est.quality;
        let report = &est.solved.equilibrium.report;
        let status = Status::tendon_estimate(
            report,
            shooting.check_stability,
            est.termination,
            q.determination,
            q.tension_determination,
            q.force_observable,
            self.settings.force_prior_std_n,
        );
        let answer = status.verdict.has_numbers();
        let mut out = TendonEstimateOutput {
            status,
            scene: self.scene.name.clone(),
            settings: InverseSettingsOutput::from(&self.settings),
            fit: FitReport {
                termination: format!("{:?}", est.termination),
                iterations: est.iterations,
                sweeps: est.sweeps,
            },
            report: Report::from(report),
            force_observable: None,
            tip_force_n: None,
            tip_force_std_n: None,
            tip_position_m: None,
            tip_position_std_m: None,
            consistency_tested: None,
            residual_rms_sigma: None,
            tendons: TendonEstimateTendons {
                displacements_m: d.clone(),
                tensions_measured_n: self.measured.as_ref().map(|m| m.tensions_n.clone()),
                tension_measured_std_n: self.measured.as_ref().map(|m| m.std_n.clone()),
                tensions_n: None,
                tension_std_n: None,
                states: None,
                path_m: None,
                slack_m: None,
                displacement_residual_m: None,
                tension_residual_n: None,
            },
            shape: None,
            figure: None,
        };
        if !answer {
            return Ok(out);
        }
        let observable = q.force_observable;
        out.force_observable = Some(observable);
        out.tip_force_n = observable.then(|| arr(&est.force_n()));
        out.tip_force_std_n = observable.then(|| arr(&q.force_std_n));
        out.tip_position_m = Some(arr(&est.solved.equilibrium.tip_position_m));
        out.tip_position_std_m = Some(arr(&q.tip_std_m));
        out.consistency_tested = Some(q.consistency_tested);
        out.residual_rms_sigma = q.consistency_tested.then_some(q.residual_rms_sigma);
        self.fill_tendons(&mut out.tendons, &tendons, &est);
        let s = self.scene.output_points_m(model.length_m())?;
        let points = tendon_shape(model, &tendons, &est.solved, &s)?;
        out.shape = Some(points.iter().map(point).collect());
        if self.plot {
            out.figure = Some(self.figure(model, &tendons, &est, &out)?);
        }
        Ok(out)
    }
}

impl TendonInverse<'_> {
    /// The estimated tendon numbers of an answer.
    fn fill_tendons(
        &self,
        out: &mut TendonEstimateTendons,
        tendons: &Tendons<f64>,
        est: &TendonEstimate<f64>,
    ) {
        let d = &self.displacements.values;
        let predicted = tendons.displacements_holding_m(&est.solved);
        let slack: Vec<bool> = (0..tendons.len())
            .map(|j| est.states.get(j) == Some(&TendonState::Slack))
            .collect();
        let mut slack_m = Vec::new();
        let mut residual_m = Vec::new();
        for (j, (p, d)) in predicted.iter().zip(d).enumerate() {
            // Model minus measured; a slack tendon's spool left more than its path needs.
            let gap = p - d;
            let is_slack = slack.get(j).copied().unwrap_or(false) && gap >= 0.0;
            slack_m.push(if is_slack { gap } else { 0.0 });
            residual_m.push(if is_slack { 0.0 } else { gap });
        }
        out.tensions_n = Some(est.solved.tensions_n.iter().copied().collect());
        out.tension_std_n = Some(est.quality.tension_std_n.iter().copied().collect());
        out.states = Some(est.states.iter().copied().map(state_name).collect());
        out.path_m = Some(est.solved.path_m.iter().copied().collect());
        out.slack_m = Some(slack_m);
        out.displacement_residual_m = Some(residual_m);
        out.tension_residual_n = self.measured.as_ref().map(|m| {
            est.solved
                .tensions_n
                .iter()
                .zip(&m.tensions_n)
                .map(|(t, v)| t - v)
                .collect()
        });
    }

    fn figure<A: Attitude<f64>>(
        &self,
        model: &Model<f64, A>,
        tendons: &Tendons<f64>,
        est: &TendonEstimate<f64>,
        out: &TendonEstimateOutput,
    ) -> Result<Figure, SceneError> {
        let q = &est.quality;
        let meta = est
            .solved
            .tensions_n
            .iter()
            .zip(&q.tension_std_n)
            .zip(&est.states)
            .enumerate()
            .map(|(j, ((t, s), state))| {
                let slack = *state == TendonState::Slack;
                let label = if slack {
                    format!("tendon {j}: {t:.3} ± {s:.3} N, slack")
                } else {
                    format!("tendon {j}: {t:.3} ± {s:.3} N")
                };
                (slack, label)
            })
            .collect();
        let force = if q.force_observable {
            let f = est.force_n();
            let s = q.force_std_n;
            format!(
                "tip force: Fx {:.4} ± {:.4}, Fy {:.4} ± {:.4}, Fz {:.4} ± {:.4} N",
                f.x, s.x, f.y, s.y, f.z, s.z
            )
        } else {
            "tip force: not observable from the spool displacements alone (Undetermined): not \
             estimated; tip and shape at the prior's zero tip force"
                .to_string()
        };
        let mut notes = vec![out.status.line(), force];
        if q.determination == Determination::Inconsistent {
            notes.push(
                "INCONSISTENT: no tensions and tip force explain the measurements; this is the \
                 closest fit"
                    .to_string(),
            );
        }
        let solved = &est.solved;
        let shape = |s: &[f64]| tendon_shape(model, tendons, solved, s);
        figure(
            model,
            &shape,
            FigureSpec {
                title: format!("estimate: {}", self.scene.name),
                notes,
                tendons: Some((tendons, meta)),
                tip_std_m: Some(q.tip_std_m),
            },
        )
    }
}

/// The columns a tendon estimate adds to the CSV before `status`: four per tendon `j`
/// (`tendon{j}_displacement_m` as given, `tendon{j}_tension_n`, `tendon{j}_tension_std_n`,
/// `tendon{j}_state`), then the tip force and its deviation, the tip's deviation, and the fit's
/// figures.
pub fn tendon_estimate_csv_columns(count: usize) -> Vec<String> {
    let mut columns: Vec<String> = (0..count)
        .flat_map(|j| {
            ["displacement_m", "tension_n", "tension_std_n", "state"]
                .map(|c| format!("tendon{j}_{c}"))
        })
        .collect();
    for c in [
        "tip_force_x_n",
        "tip_force_y_n",
        "tip_force_z_n",
        "tip_force_std_x_n",
        "tip_force_std_y_n",
        "tip_force_std_z_n",
        "tip_std_x_m",
        "tip_std_y_m",
        "tip_std_z_m",
        "force_observable",
        "tension_determination",
        "residual_rms_sigma",
        "sweeps",
    ] {
        columns.push(c.to_string());
    }
    columns
}

/// A tendon estimate as CSV: the shape, each row with [`tendon_estimate_csv_columns`] (the same on
/// every row) and the status. A tip force that is not observable leaves its cells empty. Without an
/// answer the only row has empty numbers and the status.
pub fn tendon_estimate_csv(out: &TendonEstimateOutput) -> String {
    let t = &out.tendons;
    let count = t.displacements_m.len();
    let number = |v: Option<&f64>| v.map_or(String::new(), f64::to_string);
    let mut cells = Vec::new();
    if out.shape.is_some() {
        for j in 0..count {
            cells.push(number(t.displacements_m.get(j)));
            cells.push(number(t.tensions_n.as_ref().and_then(|v| v.get(j))));
            cells.push(number(t.tension_std_n.as_ref().and_then(|v| v.get(j))));
            cells.push(
                t.states
                    .as_ref()
                    .and_then(|v| v.get(j))
                    .map_or(String::new(), |s| (*s).to_string()),
            );
        }
        for v in [
            &out.tip_force_n,
            &out.tip_force_std_n,
            &out.tip_position_std_m,
        ] {
            for i in 0..3 {
                cells.push(number(v.as_ref().and_then(|v| v.get(i))));
            }
        }
        cells.push(
            out.force_observable
                .map_or(String::new(), |b| b.to_string()),
        );
        cells.push(
            out.status
                .tension_determination
                .clone()
                .flatten()
                .unwrap_or_default(),
        );
        cells.push(number(out.residual_rms_sigma.as_ref()));
        cells.push(out.fit.sweeps.to_string());
    }
    super::csv_table(
        out.shape.as_deref(),
        &tendon_estimate_csv_columns(count),
        &cells,
        &out.status,
    )
}
