//! `host-sim calibrate <scene> --data <csv>`: the scene's parameters fitted to the user's own
//! observed points by weighted least squares, with their standard deviations, the residual of every
//! observation, the leave-one-out prediction error of every experiment, and a verdict that refuses
//! to give a number the data do not determine.

use nalgebra::{DVector, Vector3};
use serde::Serialize;

use super::data::Measurements;
use super::forward::Forward;
use super::lm::{self, Failure, Residuals, Step};
use super::params::{FitParameter, Layout, Values};
use super::pose::Pose;
use super::uncertainty::{self, Uncertainty};
use crate::run::{exit, real};
use crate::scene::{Scene, SceneError};

/// Millimetres per metre (residuals are reported in mm).
pub const MM_PER_M: f64 = 1e3;

/// Most Levenberg-Marquardt iterations per fit.
const MAX_ITERATIONS: u16 = 60;

/// The positions' rounding in the forward model, m: a cost below `3 sum(w) (this)^2` is a perfect
/// fit.
const POSITION_ROUNDING_M: f64 = 1e-13;

/// What the calibration is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Converged, and the data determine every fitted parameter: exit 0.
    Determined,
    /// Converged, but the data do not determine a combination of the parameters (named): its
    /// parameters get no number and no calibrated scene is written: exit 3.
    Undetermined,
    /// No fit: a forward solve has no answer at the start, or the fit did not converge: exit 3.
    NoAnswer,
}

impl Verdict {
    /// The exit code.
    pub fn exit_code(self) -> u8 {
        match self {
            Self::Determined => exit::ANSWER,
            Self::Undetermined | Self::NoAnswer => exit::NO_ANSWER,
        }
    }
}

/// The status: first in every format.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Status {
    /// What the calibration is.
    pub verdict: Verdict,
    /// The exit code.
    pub exit_code: u8,
    /// Why the fit stopped (`Converged`, `IterationLimit`, `NoProgress`, or `NoAnswer`).
    pub termination: String,
    /// Levenberg-Marquardt iterations.
    pub iterations: u16,
    /// One sentence.
    pub summary: String,
    /// What the answer gives up.
    pub warnings: Vec<String>,
}

/// A fitted parameter.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Parameter {
    /// `E` (or `stiffness_scale`), `line_density`, `cable_offset`, `friction`,
    /// `base_rotation_x` .. `_z` (rotation vector), `base_translation_x` .. `_z`.
    pub name: String,
    /// SI unit: `Pa`, `kg/m` (the first section's), `m` (the first tendon's radius), `1`, `rad`, `m`.
    pub unit: &'static str,
    /// The value the fit started from: the scene's (the base pose: a registration of the points).
    #[serde(serialize_with = "real::one")]
    pub start: f64,
    /// The fitted value; `null` when the data do not determine it or there is no fit.
    #[serde(serialize_with = "real::opt_one")]
    pub value: Option<f64>,
    /// Its standard deviation (delta method from the log scale); `null` with `value`.
    #[serde(serialize_with = "real::opt_one")]
    pub std: Option<f64>,
    /// The fitted value sits on its bound (a friction coefficient of 0).
    pub at_bound: bool,
}

/// A combination of parameters the data do not determine.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Undetermined {
    /// Its terms: coefficient and coordinate (`ln E`, `friction`, `base_rotation_x`).
    pub terms: Vec<(f64, String)>,
    /// `+1.000 ln E +1.000 ln line_density`.
    pub combination: String,
    /// Rank-deficient: the points do not change along it at all; else only too uncertain.
    pub rank_deficient: bool,
    /// Its singular value over the largest (column-scaled Jacobian).
    #[serde(serialize_with = "real::one")]
    pub singular_ratio: f64,
}

/// One observation with its fit.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Observation {
    /// Its line in the data file.
    pub line: usize,
    /// Its experiment.
    pub experiment: String,
    /// Arc length observed, m.
    #[serde(serialize_with = "real::one")]
    pub s_m: f64,
    /// Whether the row named the tip.
    pub at_tip: bool,
    /// The measured point, m, measurement frame.
    #[serde(serialize_with = "real::many")]
    pub measured_m: [f64; 3],
    /// The fitted model's point, m, measurement frame (`null` without a fit).
    #[serde(serialize_with = "real::opt_many")]
    pub predicted_m: Option<[f64; 3]>,
    /// Model minus measured, mm.
    #[serde(serialize_with = "real::opt_many")]
    pub residual_mm: Option<[f64; 3]>,
    /// Its length, mm.
    #[serde(serialize_with = "real::opt_one")]
    pub distance_mm: Option<f64>,
    /// The row's weight.
    #[serde(serialize_with = "real::one")]
    pub weight: f64,
}

/// One leave-one-out fold: the fit without an experiment, and how well it predicts it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Fold {
    /// The experiment left out.
    pub experiment: String,
    /// Its observations.
    pub observations: usize,
    /// The fit without it.
    pub verdict: Verdict,
    /// The first parameter (`E`) fitted without it, in its unit (`null` unless determined).
    #[serde(serialize_with = "real::opt_one")]
    pub first_parameter: Option<f64>,
    /// The rms distance of its predicted points from its measured ones, mm (`null` unless
    /// determined).
    #[serde(serialize_with = "real::opt_one")]
    pub rms_mm: Option<f64>,
}

/// A calibration from the user's data.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Calibration {
    /// What it is.
    pub status: Status,
    /// The scene's name.
    pub scene: String,
    /// The data file.
    pub data: String,
    /// Experiments in it.
    pub experiments: usize,
    /// Observed points in it (three residuals each).
    pub observations: usize,
    /// Residuals minus fitted coordinates.
    pub dof: usize,
    /// What was fitted.
    pub fitted: Vec<String>,
    /// Every fitted coordinate.
    pub parameters: Vec<Parameter>,
    /// The combinations the data do not determine (empty when determined).
    pub undetermined: Vec<Undetermined>,
    /// rms distance of the fitted points from the measured ones, mm.
    #[serde(serialize_with = "real::opt_one")]
    pub rms_mm: Option<f64>,
    /// The same at the start (the scene's values; the registered pose), mm.
    #[serde(serialize_with = "real::opt_one")]
    pub start_rms_mm: Option<f64>,
    /// The residual standard deviation of one coordinate at unit weight, `s`, mm.
    #[serde(serialize_with = "real::opt_one")]
    pub residual_sd_mm: Option<f64>,
    /// Every observation.
    pub residuals: Vec<Observation>,
    /// Leave-one-out, one fold per experiment (none with a single experiment).
    pub leave_one_out: Vec<Fold>,
    /// rms of the folds' errors over their points, mm (`null` unless every fold is determined).
    #[serde(serialize_with = "real::opt_one")]
    pub leave_one_out_rms_mm: Option<f64>,
    /// Forward solves spent.
    pub forward_solves: u64,
    /// The calibrated scene written (`--out`), if any.
    pub written: Option<String>,
    /// The fitted values, for writing the calibrated scene (determined fits only).
    #[serde(skip)]
    pub values: Option<Values>,
}

/// The least-squares problem over some experiments.
struct Objective<'f, 'a> {
    forward: &'f mut Forward<'a>,
    layout: &'f Layout,
    data: &'a Measurements,
    which: Vec<usize>,
}

impl Objective<'_, '_> {
    /// The measured points of the experiments in use and the square roots of their weights.
    fn measured(&self) -> Vec<(Vector3<f64>, f64)> {
        self.which
            .iter()
            .filter_map(|&i| self.data.experiments.get(i))
            .flat_map(|e| {
                e.observations
                    .iter()
                    .map(|o| (Vector3::from(o.position_m), o.weight.sqrt()))
            })
            .collect()
    }

    /// The predicted points of the experiments in use, measurement frame.
    fn predicted(&mut self, values: &Values) -> Result<Vec<Vector3<f64>>, Failure> {
        match self.forward.predict(values, &self.which)? {
            Ok(p) => Ok(p),
            Err(no) => Err(Failure::NoAnswer(format!("{}: {}", no.experiment, no.why))),
        }
    }
}

impl Residuals for Objective<'_, '_> {
    fn residuals(&mut self, theta: &DVector<f64>) -> Result<DVector<f64>, Failure> {
        let values = self.layout.values(theta);
        let predicted = self.predicted(&values)?;
        let measured = self.measured();
        if predicted.len() != measured.len() {
            return Err(Failure::Invalid(SceneError::new(
                &self.data.origin,
                format!(
                    "{} points predicted for {} measured",
                    predicted.len(),
                    measured.len()
                ),
            )));
        }
        Ok(DVector::from_iterator(
            3 * measured.len(),
            predicted
                .iter()
                .zip(&measured)
                .flat_map(|(p, (o, w))| ((p - o) * *w).iter().copied().collect::<Vec<_>>()),
        ))
    }
}

/// rms of point distances, mm.
fn rms_mm(predicted: &[Vector3<f64>], measured: &[Vector3<f64>]) -> Option<f64> {
    (!predicted.is_empty() && predicted.len() == measured.len()).then(|| {
        let sum: f64 = predicted
            .iter()
            .zip(measured)
            .map(|(p, o)| (p - o).norm_squared())
            .sum();
        (sum / predicted.len() as f64).sqrt() * MM_PER_M
    })
}

/// The finite-difference steps and bounds of the layout.
fn steps(layout: &Layout) -> Vec<Step> {
    layout
        .coordinates
        .iter()
        .map(|c| Step {
            h: c.step,
            lower: c.lower,
            upper: c.upper,
        })
        .collect()
}

fn settings(data: &Measurements, which: &[usize]) -> lm::Settings {
    let weights: f64 = which
        .iter()
        .filter_map(|&i| data.experiments.get(i))
        .flat_map(|e| e.observations.iter().map(|o| o.weight))
        .sum();
    lm::Settings {
        max_iterations: MAX_ITERATIONS,
        cost_floor: 3.0 * weights * POSITION_ROUNDING_M * POSITION_ROUNDING_M,
    }
}

/// A combination in words: `+1.000 ln E -0.500 friction`.
fn combination_text(terms: &[(f64, String)]) -> String {
    terms
        .iter()
        .map(|(c, s)| format!("{c:+.3} {s}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// How many fits [`calibrate`] runs: one, and one per experiment left out (for a progress bar).
pub fn fit_count(data: &Measurements) -> u64 {
    let n = data.experiments.len() as u64;
    if n >= 2 { n + 1 } else { 1 }
}

/// Fits `E` and the parameters `fit` of `scene` to `data`. `progress` is called after each fit
/// ([`fit_count`]). Fails only on invalid input; a fit without an answer is a [`Verdict`].
pub fn calibrate(
    scene: &Scene,
    data: &Measurements,
    fit: &[FitParameter],
    mut progress: impl FnMut(),
) -> Result<Calibration, SceneError> {
    let layout = Layout::new(scene, fit)?;
    let mut forward = Forward::new(scene, data)?;
    let all: Vec<usize> = (0..data.experiments.len()).collect();
    let measured: Vec<Vector3<f64>> = data
        .observations()
        .map(|(_, o)| Vector3::from(o.position_m))
        .collect();
    let mut fitted = vec!["E".to_string()];
    for p in fit {
        let name = match p {
            FitParameter::E => continue,
            FitParameter::LineDensity => "line_density",
            FitParameter::CableOffset => "cable_offset",
            FitParameter::BasePose => "base_pose",
            FitParameter::Friction => "friction",
        };
        if !fitted.iter().any(|f| f == name) {
            fitted.push(name.to_string());
        }
    }
    let mut warnings = Vec::new();
    let mut result = Calibration {
        status: Status {
            verdict: Verdict::NoAnswer,
            exit_code: Verdict::NoAnswer.exit_code(),
            termination: "NoAnswer".into(),
            iterations: 0,
            summary: String::new(),
            warnings: Vec::new(),
        },
        scene: scene.name.clone(),
        data: data.origin.clone(),
        experiments: data.experiments.len(),
        observations: measured.len(),
        dof: (3 * measured.len()).saturating_sub(layout.len()),
        fitted,
        parameters: Vec::new(),
        undetermined: Vec::new(),
        rms_mm: None,
        start_rms_mm: None,
        residual_sd_mm: None,
        residuals: data
            .observations()
            .map(|(e, o)| Observation {
                line: o.line,
                experiment: e.id.clone(),
                s_m: o.s_m,
                at_tip: o.at_tip,
                measured_m: o.position_m,
                predicted_m: None,
                residual_mm: None,
                distance_mm: None,
                weight: o.weight,
            })
            .collect(),
        leave_one_out: Vec::new(),
        leave_one_out_rms_mm: None,
        forward_solves: 0,
        written: None,
        values: None,
    };

    // The start: the scene's values, and for the base pose the rigid registration of the predicted
    // points onto the measured ones.
    let identity = Pose::identity();
    let at_scene = layout.values(&layout.start(&identity));
    let start_points = match forward.predict(&at_scene, &all)? {
        Ok(p) => p,
        Err(no) => {
            result.status.summary = format!(
                "no answer: at the scene's own parameters {}: {}",
                no.experiment, no.why
            );
            result.forward_solves = forward.solves;
            return Ok(result);
        }
    };
    let pose = if layout.fits_pose() {
        let weights: Vec<f64> = data.observations().map(|(_, o)| o.weight).collect();
        Pose::register(&start_points, &measured, &weights).unwrap_or_else(|| {
            warnings.push(
                "the observed points lie on a line (or are fewer than three): they do not fix a \
                 rotation, and the base pose starts at the identity"
                    .to_string(),
            );
            identity
        })
    } else {
        identity
    };
    let theta0 = layout.start(&pose);
    let start_values = layout.values(&theta0);
    let steps = steps(&layout);
    let mut objective = Objective {
        forward: &mut forward,
        layout: &layout,
        data,
        which: all.clone(),
    };
    let start_predicted = match objective.predicted(&start_values) {
        Ok(p) => Some(p),
        Err(Failure::Invalid(e)) => return Err(e),
        Err(Failure::NoAnswer(_)) => None,
    };
    result.start_rms_mm = start_predicted.and_then(|p| rms_mm(&p, &measured));
    result.parameters = layout
        .coordinates
        .iter()
        .zip(theta0.iter())
        .map(|(c, t)| Parameter {
            name: c.name.clone(),
            unit: c.unit,
            start: c.value(*t),
            value: None,
            std: None,
            at_bound: false,
        })
        .collect();

    let outcome = match lm::minimize(&mut objective, theta0, &steps, &settings(data, &all)) {
        Ok(o) => o,
        Err(Failure::Invalid(e)) => return Err(e),
        Err(Failure::NoAnswer(why)) => {
            result.status.summary = format!("no answer: {why}");
            result.status.warnings = warnings;
            result.forward_solves = objective.forward.solves;
            progress();
            return Ok(result);
        }
    };
    progress();
    result.status.termination = format!("{:?}", outcome.termination);
    result.status.iterations = outcome.iterations;
    let values = layout.values(&outcome.theta);
    let predicted = match objective.predicted(&values) {
        Ok(p) => p,
        Err(Failure::Invalid(e)) => return Err(e),
        Err(Failure::NoAnswer(why)) => {
            result.status.summary = format!("no answer: {why}");
            result.forward_solves = objective.forward.solves;
            return Ok(result);
        }
    };
    let at_range_end: Vec<&str> = layout
        .coordinates
        .iter()
        .zip(outcome.theta.iter())
        .filter(|(c, t)| c.at_range_end(**t))
        .map(|(c, _)| c.name.as_str())
        .collect();
    if !outcome.termination.is_success() || !at_range_end.is_empty() {
        result.status.summary = if at_range_end.is_empty() {
            format!(
                "no answer: the fit did not converge ({:?}); nothing fitted is printed",
                outcome.termination
            )
        } else {
            format!(
                "no answer: {} ran to the end of its search range ({} times the scene's value \
                 either way): the scene does not explain the data (a unit slip? data in another \
                 frame than the scene's: fit base_pose); nothing fitted is printed",
                at_range_end.join(", "),
                super::params::SCALE_RANGE
            )
        };
        result.status.warnings = warnings;
        result.forward_solves = objective.forward.solves;
        return Ok(result);
    }
    let u = uncertainty::analyse(&outcome.jacobian, &outcome.residuals, &layout);
    result.dof = u.dof;
    result.residual_sd_mm = u.residual_sd.map(|s| s * MM_PER_M);
    result.rms_mm = rms_mm(&predicted, &measured);
    for (o, p) in result.residuals.iter_mut().zip(&predicted) {
        let r = (p - Vector3::from(o.measured_m)) * MM_PER_M;
        o.predicted_m = Some([p.x, p.y, p.z]);
        o.residual_mm = Some([r.x, r.y, r.z]);
        o.distance_mm = Some(r.norm());
    }
    for ((p, c), (t, sd)) in result
        .parameters
        .iter_mut()
        .zip(&layout.coordinates)
        .zip(outcome.theta.iter().zip(&u.theta_std))
    {
        if let Some(sd) = sd {
            p.value = Some(c.value(*t));
            p.std = Some(c.value_std(*t, *sd));
        }
        p.at_bound = c.at_physical_bound(*t);
    }
    result.undetermined = u
        .undetermined
        .iter()
        .map(|c| {
            let terms: Vec<(f64, String)> = c
                .terms
                .iter()
                .map(|t| {
                    (
                        t.coefficient,
                        layout
                            .coordinates
                            .get(t.index)
                            .map_or_else(String::new, |c| c.symbol()),
                    )
                })
                .collect();
            Undetermined {
                combination: combination_text(&terms),
                terms,
                rank_deficient: c.rank_deficient,
                singular_ratio: c.singular_ratio,
            }
        })
        .collect();
    if result.parameters.iter().any(|p| p.at_bound) {
        warnings.push(
            "a parameter sits on its bound (friction 0): its standard deviation is that of the \
             unbounded fit"
                .to_string(),
        );
    }
    let determined = u.is_determined();
    result.status.verdict = if determined {
        Verdict::Determined
    } else {
        Verdict::Undetermined
    };
    result.status.summary = summary(&u, &result.undetermined);
    if determined {
        result.values = Some(values);
    }

    // Leave-one-out: each experiment's points predicted by the fit without it.
    if all.len() >= 2 {
        let theta_hat = outcome.theta.clone();
        for &left_out in &all {
            let rest: Vec<usize> = all.iter().copied().filter(|&i| i != left_out).collect();
            let fold_settings = settings(data, &rest);
            objective.which = rest;
            let fold = lm::minimize(&mut objective, theta_hat.clone(), &steps, &fold_settings);
            let e = data.experiments.get(left_out);
            let mut out = Fold {
                experiment: e.map_or_else(String::new, |e| e.id.clone()),
                observations: e.map_or(0, |e| e.observations.len()),
                verdict: Verdict::NoAnswer,
                first_parameter: None,
                rms_mm: None,
            };
            match fold {
                Err(Failure::Invalid(e)) => return Err(e),
                Err(Failure::NoAnswer(_)) => {}
                Ok(f) if !f.termination.is_success() => {}
                Ok(f) => {
                    let fu: Uncertainty = uncertainty::analyse(&f.jacobian, &f.residuals, &layout);
                    if fu.is_determined() {
                        out.verdict = Verdict::Determined;
                        out.first_parameter = layout
                            .coordinates
                            .first()
                            .zip(f.theta.get(0))
                            .map(|(c, t)| c.value(*t));
                        objective.which = vec![left_out];
                        let measured: Vec<Vector3<f64>> =
                            objective.measured().iter().map(|m| m.0).collect();
                        out.rms_mm = match objective.predicted(&layout.values(&f.theta)) {
                            Ok(p) => rms_mm(&p, &measured),
                            Err(Failure::Invalid(e)) => return Err(e),
                            Err(Failure::NoAnswer(_)) => None,
                        };
                        if out.rms_mm.is_none() {
                            out.verdict = Verdict::NoAnswer;
                        }
                    } else {
                        out.verdict = Verdict::Undetermined;
                    }
                }
            }
            result.leave_one_out.push(out);
            progress();
        }
        let folds = &result.leave_one_out;
        if folds.iter().all(|f| f.rms_mm.is_some()) {
            let (sum, count) = folds.iter().fold((0.0, 0usize), |(s, n), f| {
                let r = f.rms_mm.unwrap_or(0.0);
                (s + r * r * f.observations as f64, n + f.observations)
            });
            result.leave_one_out_rms_mm = (count > 0).then(|| (sum / count as f64).sqrt());
        }
    }
    result.status.exit_code = result.status.verdict.exit_code();
    result.status.warnings = warnings;
    result.forward_solves = objective.forward.solves;
    Ok(result)
}

/// The status sentence of a converged fit.
fn summary(u: &Uncertainty, undetermined: &[Undetermined]) -> String {
    if u.is_determined() {
        return "calibrated: every fitted parameter is determined by the data".to_string();
    }
    if u.residual_sd.is_none() {
        return "undetermined: no observation to spare (as many residuals as parameters), so the \
                residual variance and the standard deviations are unknown; nothing is written"
            .to_string();
    }
    let what: Vec<String> = undetermined
        .iter()
        .map(|c| {
            if c.rank_deficient {
                format!("{} (the points do not change along it)", c.combination)
            } else {
                format!("{} (too uncertain)", c.combination)
            }
        })
        .collect();
    format!(
        "undetermined: the data do not determine {}; its parameters are not printed and nothing \
         is written",
        what.join("; ")
    )
}
