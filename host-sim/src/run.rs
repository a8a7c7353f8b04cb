//! `solve` and `estimate` on a scene: the forward shape and cable lengths (for a scene with tendons,
//! from their tensions or spool displacements), and the inverse from measured cable lengths. Results are plain data (serialisable to JSON and CSV), each with a
//! [`Status`] that says whether it is an answer, and the exit code that goes with it.
//!
//! A failed solve's iterate is not an answer: its shape, tip, cable lengths and forces are left out
//! (`None`, JSON `null`, no CSV data rows), so a script that reads the numbers cannot take it for one.
//!
//! JSON has no NaN or infinity, and serde_json writes them as `null`, which reads as "no value": every
//! number here is written through [`real`], which writes a non-finite one as the string `"NaN"`,
//! `"Infinity"` or `"-Infinity"`. (A solve that ended in `NonFinite` has a NaN residual.)

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use model_core::inverse::{
    Determination, EstimatorSettings, InverseSettings, InverseStart, LoadBasis, estimate,
};
use model_core::{
    Attitude, DisplacementSettings, LieGroup, Model, Quaternion, RotationMatrix, ShapePoint,
    SolveReport, Stability, Start, TendonEquilibrium, TendonState, Tendons, Termination, TipLoad,
};
use nalgebra::Vector3;
use serde::Serialize;

use crate::plots::Figure;
use crate::scene::{Actuation, AttitudeChoice, Control, Scene, SceneError};

mod figure;
mod tendon_estimate;

use figure::{FigureSpec, figure};
pub use tendon_estimate::{
    FitReport, InverseSettingsOutput, TENDON_ESTIMATE_KEYS, TENDON_ESTIMATE_TENDON_KEYS,
    TendonEstimateOutput, TendonEstimateTendons, TendonInverse, tendon_estimate_csv,
    tendon_estimate_csv_columns,
};

/// Work that needs a model of some frame representation.
pub trait WithModel {
    /// What it produces.
    type Output;
    /// Does the work.
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<Self::Output, SceneError>;
}

/// Builds the scene's model with the chosen frame representation and runs `work` on it.
pub fn with_model<W: WithModel>(scene: &Scene, work: W) -> Result<W::Output, SceneError> {
    let rod = scene.rod()?;
    let err = |e: model_core::ModelError| SceneError::new("scene", e.to_string());
    match scene.attitude()? {
        AttitudeChoice::Quaternion => {
            work.run(&Model::<f64, Quaternion<f64>>::new(rod).map_err(err)?)
        }
        AttitudeChoice::RotationMatrix => {
            work.run(&Model::<f64, RotationMatrix<f64>>::new(rod).map_err(err)?)
        }
        AttitudeChoice::LieGroup => work.run(&Model::<f64, LieGroup<f64>>::new(rod).map_err(err)?),
    }
}

/// Writes a command's output to the file `out`, or to standard output. Not `print!`, which panics
/// when the reader has gone (a closed pipe, a full disk): an I/O error, exit 1.
pub fn emit(text: &str, out: Option<&Path>) -> Result<(), SceneError> {
    match out {
        Some(path) => std::fs::write(path, text)
            .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}"))),
        None => std::io::stdout()
            .lock()
            .write_all(text.as_bytes())
            .map_err(|e| SceneError::new("standard output", format!("cannot write: {e}"))),
    }
}

/// Exit codes of `solve` and `estimate` (documented in `--help` and the README).
pub mod exit {
    /// A converged answer (stable, where stability is checked).
    pub const ANSWER: u8 = 0;
    /// Invalid input: a bad scene file, a refused value, an I/O error.
    pub const INVALID_INPUT: u8 = 1;
    /// A command-line usage error (clap's own code).
    pub const USAGE: u8 = 2;
    /// No answer: the solve did not converge, converged to an unstable equilibrium, or its frame
    /// drifted (any termination other than `Converged`).
    pub const NO_ANSWER: u8 = 3;
    /// `estimate` only: converged, but no load of the model explains the measurements.
    pub const INCONSISTENT: u8 = 4;
}

/// What an output is, in one word; it decides the exit code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Converged, and stable where stability was checked: exit 0. Its uncertainty (for `estimate`,
    /// the determination) says how good it is.
    Answer,
    /// Not converged, unstable, or the frame drifted: exit 3. The numbers of the failed iterate are
    /// left out.
    NoAnswer,
    /// `estimate`: converged, but no load explains the measurements (`Inconsistent`): exit 4. The
    /// numbers are the closest fit, printed so that the residual shows which cable disagrees.
    Inconsistent,
}

impl Verdict {
    /// The process exit code for this verdict.
    pub fn exit_code(self) -> u8 {
        match self {
            Self::Answer => exit::ANSWER,
            Self::NoAnswer => exit::NO_ANSWER,
            Self::Inconsistent => exit::INCONSISTENT,
        }
    }

    /// Whether the numbers are printed (the answer, or an inconsistent estimate's closest fit).
    pub fn has_numbers(self) -> bool {
        self != Self::NoAnswer
    }
}

/// What the stability test gives up when it did not run.
const UNCHECKED_STABILITY: &str = "an unstable equilibrium (a wrong branch: buckled, upside \
     down, looped) would be reported as converged";

/// The status of a `solve` or `estimate` output: first in every format (the text's first line, the
/// JSON's `status` object, the CSV's `status` column).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Status {
    /// What the output is.
    pub verdict: Verdict,
    /// The exit code that goes with it.
    pub exit_code: u8,
    /// Why the solve stopped (`Converged` is the only usable answer).
    pub termination: String,
    /// The stability verdict (`Unchecked` when the test did not run).
    pub stability: String,
    /// Whether the energy test of stability ran and gave a verdict. False when the scene turned it
    /// off (`check_stability = false`), when a moment of fixed direction acts (`NonConservative`: the
    /// test does not apply), or when the solve did not converge.
    pub stability_checked: bool,
    /// `estimate` only (absent for `solve`): how well the data determine the load, as model-core
    /// names it (`Determined`, `Weak`, `Undetermined`, `Inconsistent`, ...); `null` when there is no
    /// answer to judge.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub determination: Option<Option<String>>,
    /// `estimate` on a scene with tendons only (absent otherwise): the verdict on the tensions
    /// alone; `null` when there is no answer to judge.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tension_determination: Option<Option<String>>,
    /// One sentence: what the output is and why.
    pub summary: String,
    /// What the answer gives up (stability not checked), also printed to standard error.
    pub warnings: Vec<String>,
}

impl Status {
    /// The status of a solve that stopped with `report`; `check_stability` is the scene's setting;
    /// `determination` is the estimate's verdict (`None` for `solve`).
    pub fn new(
        report: &SolveReport<f64>,
        check_stability: bool,
        determination: Option<Determination>,
    ) -> Self {
        let converged = report.termination.is_success();
        // Model-core turns an unstable answer into `Termination::Unstable`; the stability is looked
        // at again so that no unstable equilibrium is ever an answer here.
        let stable = report.stability.is_acceptable();
        // The test ran and gave a verdict (an `Unstable` termination's verdict included).
        let stability_checked = matches!(
            report.stability,
            Stability::Stable | Stability::ConjugatePoint(_) | Stability::FreeEndUnstable
        );
        let inconsistent = determination == Some(Determination::Inconsistent);
        let verdict = if !(converged && stable) {
            Verdict::NoAnswer
        } else if inconsistent {
            Verdict::Inconsistent
        } else {
            Verdict::Answer
        };
        let mut warnings = Vec::new();
        if !check_stability {
            warnings.push(format!(
                "stability not checked (the scene sets [solver] check_stability = false): \
                 {UNCHECKED_STABILITY}"
            ));
        } else if converged && matches!(report.stability, Stability::NonConservative) {
            warnings.push(format!(
                "stability not checked (a moment of fixed direction acts: the loads are not \
                 conservative and the energy test does not apply): {UNCHECKED_STABILITY}"
            ));
        }
        let summary = match verdict {
            Verdict::NoAnswer => format!("no answer: {}", failure(report)),
            Verdict::Inconsistent => "converged, but no load of the model explains the \
                 measurements (within 3 standard deviations); the numbers are the closest fit"
                .to_string(),
            Verdict::Answer => {
                let mut t = String::from("converged");
                t.push_str(if stability_checked {
                    ", stable"
                } else {
                    ", stability NOT checked"
                });
                if let Some(d) = determination {
                    let _ = write!(t, "; determination {d:?}");
                }
                t
            }
        };
        Self {
            verdict,
            exit_code: verdict.exit_code(),
            termination: format!("{:?}", report.termination),
            stability: format!("{:?}", report.stability),
            stability_checked,
            // Determination is printed with `{:?}` and never matched exhaustively: model-core may add
            // verdicts (`Ambiguous`), which then show here as they are.
            determination: determination.map(|d| verdict.has_numbers().then(|| format!("{d:?}"))),
            tension_determination: None,
            summary,
            warnings,
        }
    }

    /// The status of a passive estimate (tip load from cable lengths): [`Status::new`] with the
    /// estimate's verdict, and a warning when the printed numbers may not be the only load that
    /// explains the lengths, or are one of many ([`doubt_of`]).
    pub fn estimate(
        report: &SolveReport<f64>,
        check_stability: bool,
        determination: Determination,
    ) -> Self {
        let mut status = Self::new(report, check_stability, Some(determination));
        status.warn_doubt(determination);
        status
    }

    /// The warning of [`doubt_of`] on an answer.
    fn warn_doubt(&mut self, determination: Determination) {
        if self.verdict == Verdict::Answer
            && let Some(doubt) = doubt_of(determination)
        {
            self.warnings.push(doubt.to_string());
        }
    }

    /// The status of a tendon solve: that of its last forward solve (`report`), and for displacement
    /// control the outcome of the search for the tensions (`displacement`: its termination), which
    /// must also have converged. Model-core has no energy test of stability with tendons yet
    /// (stability `Unchecked`): an answer says so in a warning.
    pub fn tendon(
        report: &SolveReport<f64>,
        check_stability: bool,
        displacement: Option<Termination>,
    ) -> Self {
        let mut status = Self::new(report, check_stability, None);
        if let Some(t) = displacement.filter(|t| !t.is_success()) {
            status.no_answer_from_search(
                t,
                format!(
                    "no answer: no tensions found that explain the spool displacements (the \
                     displacement solve ended {t:?}); the failed iterate's shape and numbers are \
                     not printed"
                ),
            );
        }
        status.warn_tendon_stability(report, check_stability);
        status
    }

    /// The status of a tendon estimate: that of its last forward solve (`report`), and the fit of
    /// the tensions and the tip force (`fit`), which must also have converged; with the verdicts
    /// (`determination` on the whole estimate, `tension_determination` on the tensions alone). An
    /// estimate whose tip force the data do not determine (`force_observable` false) says so in a
    /// warning; so does the unchecked stability, as for a tendon solve.
    pub fn tendon_estimate(
        report: &SolveReport<f64>,
        check_stability: bool,
        fit: Termination,
        determination: Determination,
        tension_determination: Determination,
        force_observable: bool,
        force_prior_std_n: f64,
    ) -> Self {
        let mut status = Self::new(report, check_stability, Some(determination));
        if !fit.is_success() {
            // Whether or not its last forward solve failed too, the fit is what gave no answer.
            status.verdict = Verdict::Answer;
            status.no_answer_from_search(
                fit,
                format!(
                    "no answer: the fit of the tensions and the tip force to the measurements \
                     ended {fit:?} (its last forward solve {:?}); the failed iterate's shape and \
                     numbers are not printed",
                    report.termination
                ),
            );
        }
        let answer = status.verdict.has_numbers();
        status.tension_determination = Some(answer.then(|| format!("{tension_determination:?}")));
        if status.verdict == Verdict::Answer {
            let _ = write!(status.summary, "; tensions {tension_determination:?}");
            if !force_observable {
                status.summary.push_str("; tip force not observable");
            }
        }
        status.warn_tendon_stability(report, check_stability);
        // An unobservable tip force is printed as null and has its own warning below.
        if determination != Determination::Undetermined {
            status.warn_doubt(determination);
        }
        if answer && !force_observable {
            status.warnings.push(format!(
                "the tip force is not observable from the spool displacements alone \
                 (determination Undetermined): it is not estimated (printed as null); the \
                 tensions, the tip and the shape are those at the prior's zero tip force, and \
                 their standard deviations include its {force_prior_std_n} N per component; \
                 measure the tensions too (--tensions-measured) to estimate it"
            ));
        }
        status
    }

    /// Makes an answer no answer when the search around its forward solve (for the tensions, or
    /// the fit of an estimate) ended `termination` other than converged, with `summary`.
    fn no_answer_from_search(&mut self, termination: Termination, summary: String) {
        if termination.is_success() || self.verdict == Verdict::NoAnswer {
            return;
        }
        self.verdict = Verdict::NoAnswer;
        self.exit_code = Verdict::NoAnswer.exit_code();
        self.termination = format!("{termination:?}");
        self.summary = summary;
        if self.determination.is_some() {
            self.determination = Some(None);
        }
    }

    /// The warning that an answer with tendons had no stability test.
    fn warn_tendon_stability(&mut self, report: &SolveReport<f64>, check_stability: bool) {
        if self.verdict.has_numbers()
            && check_stability
            && matches!(report.stability, Stability::Unchecked)
        {
            self.warnings.push(format!(
                "stability not checked (tendons: model-core has no energy test of stability with \
                 tendons yet): {UNCHECKED_STABILITY}"
            ));
        }
    }

    /// The text format's first line.
    pub fn line(&self) -> String {
        let mut t = format!("status: {}", self.summary);
        let _ = write!(
            t,
            " (termination {}, stability {}",
            self.termination, self.stability
        );
        if let Some(Some(d)) = &self.determination {
            let _ = write!(t, ", determination {d}");
        }
        if let Some(Some(d)) = &self.tension_determination {
            let _ = write!(t, ", tensions {d}");
        }
        let _ = write!(t, "; exit {})", self.exit_code);
        t
    }

    /// The CSV's `status` cell: `termination/stability`, and `/determination` for an estimate.
    pub fn csv_cell(&self) -> String {
        let mut cell = format!("{}/{}", self.termination, self.stability);
        if let Some(Some(d)) = &self.determination {
            let _ = write!(cell, "/{d}");
        }
        cell
    }
}

/// Why a solve is not an answer, in words.
fn failure(report: &SolveReport<f64>) -> String {
    let t = report.termination;
    // Not exhaustive on purpose: a termination model-core adds later is still reported (by name).
    let why = match t {
        Termination::Converged => {
            return format!(
                "converged to an unstable equilibrium ({:?}): a wrong branch",
                report.stability
            );
        }
        Termination::Unstable => {
            "the solve converged to an unstable equilibrium (a wrong branch)".to_string()
        }
        Termination::FrameDrift => "the solve converged, but its frame drifted from a rotation \
             (too few steps for the frame representation; use more steps or the quaternion frame)"
            .to_string(),
        Termination::UnderResolved => "the solve converged, but the grid's steps are too long for \
             the bending this load causes (its shape and stability are not resolved; use more steps \
             per section)"
            .to_string(),
        other => format!("the solve did not converge ({other:?})"),
    };
    format!("{why}; the failed iterate's shape and numbers are not printed")
}

/// JSON numbers: a finite `f64` as a number, a non-finite one as the string `"NaN"`, `"Infinity"` or
/// `"-Infinity"` (JSON has none of them, and serde_json would write `null`). For `serialize_with`.
pub mod real {
    use serde::Serializer;
    use serde::ser::Serialize;

    /// One number.
    #[derive(Debug, Clone, Copy)]
    struct Real(f64);

    impl Serialize for Real {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            let x = self.0;
            if x.is_finite() {
                s.serialize_f64(x)
            } else if x.is_nan() {
                s.serialize_str("NaN")
            } else if x > 0.0 {
                s.serialize_str("Infinity")
            } else {
                s.serialize_str("-Infinity")
            }
        }
    }

    /// An `f64`.
    pub fn one<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        Real(*x).serialize(s)
    }

    /// An array or vector of `f64`.
    pub fn many<S: Serializer, V: AsRef<[f64]>>(v: &V, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.as_ref().iter().map(|x| Real(*x)))
    }

    /// An optional array or vector of `f64` (`null` when absent).
    pub fn opt_many<S: Serializer, V: AsRef<[f64]>>(
        v: &Option<V>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match v {
            Some(v) => many(v, s),
            None => s.serialize_none(),
        }
    }

    /// An optional `f64` (`null` when absent).
    pub fn opt_one<S: Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        match x {
            Some(x) => one(x, s),
            None => s.serialize_none(),
        }
    }
}

/// One backbone point.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Point {
    /// Arc length, m.
    #[serde(serialize_with = "real::one")]
    pub s_m: f64,
    /// Position, m.
    #[serde(serialize_with = "real::many")]
    pub position_m: [f64; 3],
    /// Unit tangent.
    #[serde(serialize_with = "real::many")]
    pub tangent: [f64; 3],
    /// Bending and torsion strain (body frame), 1/m.
    #[serde(serialize_with = "real::many")]
    pub strain_per_m: [f64; 3],
}

/// How a solve went (diagnostics, also for a failed solve: how far it got).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Report {
    /// Why it stopped ("Converged" is the only usable answer).
    pub termination: String,
    /// Stability verdict.
    pub stability: String,
    /// Iterations.
    pub iterations: u16,
    /// Sweeps.
    pub sweeps: u16,
    /// Final dimensionless residual (NaN after a `NonFinite` sweep: see [`real`]).
    #[serde(serialize_with = "real::one")]
    pub residual: f64,
    /// Load-continuation steps.
    pub load_steps: u16,
    /// The largest bending phase per step on the grid, rad (the limit is
    /// `model_core::MAX_PHASE_PER_STEP_RAD`).
    #[serde(serialize_with = "real::one")]
    pub phase_per_step_rad: f64,
}

impl From<&model_core::SolveReport<f64>> for Report {
    fn from(r: &model_core::SolveReport<f64>) -> Self {
        Self {
            termination: format!("{:?}", r.termination),
            stability: format!("{:?}", r.stability),
            iterations: r.iterations,
            sweeps: r.sweeps,
            residual: r.residual,
            load_steps: r.load_steps,
            phase_per_step_rad: r.phase_per_step_rad,
        }
    }
}

/// The result of `solve`. The answer's numbers are `None` unless `status.verdict` has them.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Solution {
    /// Whether this is an answer, and why not.
    pub status: Status,
    /// Scene name.
    pub scene: String,
    /// Tip force, N (the input).
    #[serde(serialize_with = "real::many")]
    pub tip_force_n: [f64; 3],
    /// Tip moment, N m (the input).
    #[serde(serialize_with = "real::many")]
    pub tip_moment_nm: [f64; 3],
    /// Solve report.
    pub report: Report,
    /// Tip position, m.
    #[serde(serialize_with = "real::opt_many")]
    pub tip_position_m: Option<[f64; 3]>,
    /// Tip tangent.
    #[serde(serialize_with = "real::opt_many")]
    pub tip_tangent: Option<[f64; 3]>,
    /// Cable lengths, m.
    #[serde(serialize_with = "real::opt_many")]
    pub cable_lengths_m: Option<Vec<f64>>,
    /// Backbone at the output points.
    pub shape: Option<Vec<Point>>,
    /// The tendons (absent, also from JSON, for a scene without tendons).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tendons: Option<TendonOutput>,
    /// The figure (`--plot`), for an answer only.
    #[serde(skip)]
    pub figure: Option<Figure>,
}

/// What a tendon solve gives for its tendons. The actuation given (tensions or displacements) is
/// printed also without an answer, as the tip force is; everything solved for is `None` (JSON
/// `null`) then.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TendonOutput {
    /// `"tensions"` (force control: tensions given) or `"displacements"` (displacement control:
    /// spool displacements given, tensions solved for).
    pub control: &'static str,
    /// Displacement control only: how the search for the tensions went.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub displacement_solve: Option<DisplacementReport>,
    /// Each tendon's tension, N.
    #[serde(serialize_with = "real::opt_many")]
    pub tensions_n: Option<Vec<f64>>,
    /// Each tendon's path length, m: chords from the base plate's hole through every guide's hole to
    /// its termination.
    #[serde(serialize_with = "real::opt_many")]
    pub path_m: Option<Vec<f64>>,
    /// Each spool's displacement, m, positive when taken in from the setting on the straight,
    /// unloaded rod at zero tension. Under force control: the displacement that holds the tendon
    /// at its tension (a tendon at zero tension just taut).
    #[serde(serialize_with = "real::opt_many")]
    pub displacements_m: Option<Vec<f64>>,
    /// Each tendon's state: `"taut"` (tension above zero) or `"slack"` (zero tension).
    pub states: Option<Vec<&'static str>>,
    /// Each tendon's slack, m: how much longer it is than its path (zero when taut; under force
    /// control always zero).
    #[serde(serialize_with = "real::opt_many")]
    pub slack_m: Option<Vec<f64>>,
}

/// How a displacement-controlled solve went.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DisplacementReport {
    /// Why the semi-smooth Newton on the tensions stopped ("Converged" is an answer).
    pub termination: String,
    /// Its iterations.
    pub iterations: u16,
    /// Sweeps spent, forward solves and sensitivities together.
    pub sweeps: u32,
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn point(p: &ShapePoint<f64>) -> Point {
    Point {
        s_m: p.s_m,
        position_m: arr(&p.position_m),
        tangent: arr(&p.tangent()),
        strain_per_m: arr(&p.strain_per_m),
    }
}

/// `solve`: the scene under its tip load (or `load`).
#[derive(Debug)]
pub struct Solve<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The tip load.
    pub load: TipLoad<f64>,
    /// Also compute the figure (`--plot`).
    pub plot: bool,
}

/// The notes under a solve's figure title: its status and its tip load.
fn solve_notes(status: &Status, load: &TipLoad<f64>) -> Vec<String> {
    let (f, m) = (load.force_n, load.moment_nm);
    vec![
        status.line(),
        format!(
            "tip force ({:.4}, {:.4}, {:.4}) N, tip moment ({:.4}, {:.4}, {:.4}) N m",
            f.x, f.y, f.z, m.x, m.y, m.z
        ),
    ]
}

/// The shape of a dead-load answer at `s_m`.
fn dead_load_shape<A: Attitude<f64>>(
    model: &Model<f64, A>,
    base_strain_per_m: &Vector3<f64>,
    load: &TipLoad<f64>,
    s_m: &[f64],
) -> Result<Vec<ShapePoint<f64>>, SceneError> {
    let mut points = vec![ShapePoint::default(); s_m.len()];
    let written = model
        .shape_at(base_strain_per_m, load, s_m, &mut points)
        .map_err(|e| SceneError::new("output", e.to_string()))?;
    points.truncate(written);
    Ok(points)
}

impl WithModel for Solve<'_> {
    type Output = Solution;
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<Solution, SceneError> {
        let settings = self.scene.shooting_settings()?;
        let eq = model
            .solve(&self.load, Start::Cold, &settings)
            .map_err(|e| SceneError::new("tip", e.to_string()))?;
        let status = Status::new(&eq.report, settings.check_stability, None);
        // A failed iterate is not an answer: nothing of it is printed (and its shape may not even
        // be computable: a NonFinite iterate's base strain is NaN).
        let answer = status.verdict.has_numbers();
        let shape = if answer {
            let s = self.scene.output_points_m(model.length_m())?;
            let points = dead_load_shape(model, &eq.base_strain_per_m, &eq.load, &s)?;
            Some(points.iter().map(point).collect())
        } else {
            None
        };
        let figure = if answer && self.plot {
            let shape = |s: &[f64]| dead_load_shape(model, &eq.base_strain_per_m, &eq.load, s);
            Some(figure(
                model,
                &shape,
                FigureSpec {
                    title: format!("solve: {}", self.scene.name),
                    notes: solve_notes(&status, &self.load),
                    tendons: None,
                    tip_std_m: None,
                },
            )?)
        } else {
            None
        };
        Ok(Solution {
            scene: self.scene.name.clone(),
            tip_force_n: arr(&self.load.force_n),
            tip_moment_nm: arr(&self.load.moment_nm),
            report: Report::from(&eq.report),
            tip_position_m: answer.then(|| arr(&eq.tip_position_m)),
            tip_tangent: answer.then(|| arr(&eq.tip_tangent())),
            cable_lengths_m: answer.then(|| eq.cable_lengths_m.iter().copied().collect()),
            shape,
            tendons: None,
            figure,
            status,
        })
    }
}

/// `solve` on a scene with tendons: the equilibrium under the tendons' tensions (force control) or
/// their spool displacements (displacement control), the scene's dead loads and the tip load.
#[derive(Debug)]
pub struct TendonSolve<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The tip load.
    pub load: TipLoad<f64>,
    /// The actuation: the scene's ([`Scene::actuation`]) or the command line's.
    pub actuation: Actuation,
    /// Also compute the figure (`--plot`).
    pub plot: bool,
}

impl WithModel for TendonSolve<'_> {
    type Output = Solution;
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<Solution, SceneError> {
        let settings = self.scene.shooting_settings()?;
        let tendons = self
            .scene
            .tendon_set(model)?
            .ok_or_else(|| SceneError::new("tendon", "the scene has no [[tendon]]"))?;
        let actuation = &self.actuation;
        actuation.check(&tendons)?;
        let refused = |e: model_core::ModelError| SceneError::new(&actuation.key, e.to_string());
        let (solved, displacement) = match actuation.control {
            Control::Tensions => {
                let solved = model
                    .solve_tendons(&tendons, &actuation.values, &self.load, None, &settings)
                    .map_err(refused)?;
                (solved, None)
            }
            Control::Displacements => {
                let d = model
                    .solve_displacements(
                        &tendons,
                        &actuation.values,
                        &self.load,
                        None,
                        &settings,
                        &DisplacementSettings::default(),
                    )
                    .map_err(refused)?;
                (d.solved.clone(), Some(d))
            }
        };
        let eq = &solved.equilibrium;
        let status = Status::tendon(
            &eq.report,
            settings.check_stability,
            displacement.as_ref().map(|d| d.termination),
        );
        let answer = status.verdict.has_numbers();
        let (shape, cable_lengths_m) = if answer {
            let s = self.scene.output_points_m(model.length_m())?;
            let points = tendon_shape(model, &tendons, &solved, &s)?;
            (
                Some(points.iter().map(point).collect()),
                Some(cable_lengths(model, &tendons, &solved)?),
            )
        } else {
            (None, None)
        };
        let given = Some(actuation.values.clone());
        let mut out = TendonOutput {
            control: match actuation.control {
                Control::Tensions => "tensions",
                Control::Displacements => "displacements",
            },
            displacement_solve: displacement.as_ref().map(|d| DisplacementReport {
                termination: format!("{:?}", d.termination),
                iterations: d.iterations,
                sweeps: d.sweeps,
            }),
            tensions_n: None,
            path_m: None,
            displacements_m: None,
            states: None,
            slack_m: None,
        };
        match (&displacement, answer) {
            (None, false) => out.tensions_n = given,
            (Some(_), false) => out.displacements_m = given,
            (None, true) => {
                out.tensions_n = given;
                out.displacements_m = Some(tendons.displacements_holding_m(&solved).to_vec());
                out.states = Some(
                    solved
                        .tensions_n
                        .iter()
                        .map(|t| {
                            state_name(if *t > 0.0 {
                                TendonState::Taut
                            } else {
                                TendonState::Slack
                            })
                        })
                        .collect(),
                );
                out.slack_m = Some(vec![0.0; tendons.len()]);
            }
            (Some(d), true) => {
                out.tensions_n = Some(solved.tensions_n.iter().copied().collect());
                out.displacements_m = given;
                out.states = Some(d.states.iter().copied().map(state_name).collect());
                out.slack_m = Some(d.slack_m.iter().copied().collect());
            }
        }
        if answer {
            out.path_m = Some(solved.path_m.iter().copied().collect());
        }
        let figure = match (&out.tensions_n, &out.states) {
            (Some(tau), Some(states)) if self.plot && answer => {
                let meta = tau
                    .iter()
                    .zip(states)
                    .enumerate()
                    .map(|(j, (t, state))| {
                        let slack = *state == "slack";
                        let label = if slack {
                            format!("tendon {j}: {t:.3} N, slack")
                        } else {
                            format!("tendon {j}: {t:.3} N")
                        };
                        (slack, label)
                    })
                    .collect();
                let shape = |s: &[f64]| tendon_shape(model, &tendons, &solved, s);
                Some(figure(
                    model,
                    &shape,
                    FigureSpec {
                        title: format!("solve: {}", self.scene.name),
                        notes: solve_notes(&status, &self.load),
                        tendons: Some((&tendons, meta)),
                        tip_std_m: None,
                    },
                )?)
            }
            _ => None,
        };
        Ok(Solution {
            scene: self.scene.name.clone(),
            tip_force_n: arr(&self.load.force_n),
            tip_moment_nm: arr(&self.load.moment_nm),
            report: Report::from(&eq.report),
            tip_position_m: answer.then(|| arr(&eq.tip_position_m)),
            tip_tangent: answer.then(|| arr(&eq.tip_tangent())),
            cable_lengths_m,
            shape,
            tendons: Some(out),
            figure,
            status,
        })
    }
}

fn state_name(state: TendonState) -> &'static str {
    match state {
        TendonState::Taut => "taut",
        TendonState::Slack => "slack",
    }
}

/// The backbone of a tendon equilibrium at the arc lengths `s_m`.
fn tendon_shape<A: Attitude<f64>>(
    model: &Model<f64, A>,
    tendons: &Tendons<f64>,
    solved: &TendonEquilibrium<f64>,
    s_m: &[f64],
) -> Result<Vec<ShapePoint<f64>>, SceneError> {
    let mut points = vec![ShapePoint::default(); s_m.len()];
    let written = model
        .shape_tendons(tendons, solved, s_m, &mut points)
        .map_err(|e| SceneError::new("output", e.to_string()))?;
    points.truncate(written);
    Ok(points)
}

/// The passive cables' lengths on a tendon equilibrium (model-core's tendon solve measures only the
/// tendons): as model-core's cable sweep measures them, straight chords from the hole in the first
/// guide through each guide's hole up to the termination, where the cable is fixed at the same
/// offset.
fn cable_lengths<A: Attitude<f64>>(
    model: &Model<f64, A>,
    tendons: &Tendons<f64>,
    solved: &TendonEquilibrium<f64>,
) -> Result<Vec<f64>, SceneError> {
    let rod = model.rod();
    rod.cables
        .iter()
        .map(|cable| {
            let mut s: Vec<f64> = rod
                .guides
                .iter()
                .map(|g| g.s_m)
                .filter(|s| *s <= cable.end_m)
                .collect();
            s.push(cable.end_m);
            let offset = cable.offset_local_m();
            let holes: Vec<_> = tendon_shape(model, tendons, solved, &s)?
                .iter()
                .map(|p| p.position_m + p.rotation * offset)
                .collect();
            Ok(holes.windows(2).map(|w| (w[1] - w[0]).norm()).sum())
        })
        .collect()
}

/// The numbers of an estimate (present for an answer and for an inconsistent estimate's closest fit).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EstimateNumbers {
    /// Estimated tip force, N.
    #[serde(serialize_with = "real::many")]
    pub tip_force_n: [f64; 3],
    /// Its standard deviation, N.
    #[serde(serialize_with = "real::many")]
    pub tip_force_std_n: [f64; 3],
    /// Tip position, m.
    #[serde(serialize_with = "real::many")]
    pub tip_position_m: [f64; 3],
    /// Its standard deviation, m.
    #[serde(serialize_with = "real::many")]
    pub tip_position_std_m: [f64; 3],
    /// Model minus measured, m.
    #[serde(serialize_with = "real::many")]
    pub cable_residual_m: Vec<f64>,
    /// Singular values of the weighted sensitivity (per N), largest first.
    #[serde(serialize_with = "real::many")]
    pub singular_values: [f64; 3],
    /// Their ratio.
    #[serde(serialize_with = "real::one")]
    pub condition_number: f64,
    /// The least determined force direction (unit).
    #[serde(serialize_with = "real::many")]
    pub weakest_direction: [f64; 3],
    /// Backbone at the output points.
    pub shape: Vec<Point>,
}

/// The result of `estimate`. In JSON the numbers sit at the top level next to `status`, and are all
/// `null` when there is no answer.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EstimateOutput {
    /// Whether this is an answer, and why not; with the determination.
    pub status: Status,
    /// Scene name.
    pub scene: String,
    /// Measured cable lengths, m (the input).
    #[serde(serialize_with = "real::many")]
    pub measured_m: Vec<f64>,
    /// Solve report.
    pub report: Report,
    /// The estimate, unless there is no answer.
    #[serde(flatten, serialize_with = "numbers_or_nulls")]
    pub numbers: Option<EstimateNumbers>,
    /// The figure (`--plot`), for an answer or an inconsistent estimate's closest fit.
    #[serde(skip)]
    pub figure: Option<Figure>,
}

/// Flattens the estimate's numbers into the output, or writes each of their keys as `null`.
fn numbers_or_nulls<S: serde::Serializer>(
    numbers: &Option<EstimateNumbers>,
    s: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    match numbers {
        Some(n) => n.serialize(s),
        None => {
            let mut map = s.serialize_map(Some(ESTIMATE_KEYS.len()))?;
            for key in ESTIMATE_KEYS {
                map.serialize_entry(key, &())?;
            }
            map.end()
        }
    }
}

/// The keys of [`EstimateNumbers`], in order.
const ESTIMATE_KEYS: [&str; 9] = [
    "tip_force_n",
    "tip_force_std_n",
    "tip_position_m",
    "tip_position_std_m",
    "cable_residual_m",
    "singular_values",
    "condition_number",
    "weakest_direction",
    "shape",
];
/// `estimate`: the tip force from measured cable lengths (m), one per cable.
#[derive(Debug)]
pub struct Estimate<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Measured lengths, m.
    pub measured_m: Vec<f64>,
    /// Also compute the figure (`--plot`).
    pub plot: bool,
}

impl Estimate<'_> {
    /// The inverse settings from the scene.
    pub fn settings(scene: &Scene) -> Result<InverseSettings<f64>, SceneError> {
        let e = &scene.estimate;
        if !(e.resolution_m.is_finite() && e.resolution_m > 0.0) {
            return Err(SceneError::new(
                "estimate.resolution_m",
                "must be a positive number",
            ));
        }
        if !(e.max_force_std_n.is_finite() && e.max_force_std_n > 0.0) {
            return Err(SceneError::new(
                "estimate.max_force_std_n",
                "must be a positive number",
            ));
        }
        let shooting = scene.shooting_settings()?;
        Ok(InverseSettings {
            max_force_std_n: e.max_force_std_n,
            tolerance: shooting.tolerance,
            check_stability: shooting.check_stability,
            ..InverseSettings::with_resolution(e.resolution_m)
        })
    }

    /// Settings for a warm-started estimator on this scene.
    pub fn estimator_settings(scene: &Scene) -> Result<EstimatorSettings<f64>, SceneError> {
        Ok(EstimatorSettings::with_inverse(Self::settings(scene)?))
    }
}

impl WithModel for Estimate<'_> {
    type Output = EstimateOutput;
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<EstimateOutput, SceneError> {
        let settings = Self::settings(self.scene)?;
        let est = estimate(
            model,
            &LoadBasis::tip_force(),
            &self.measured_m,
            InverseStart::Params(Vector3::zeros()),
            &settings,
        )
        .map_err(|e| SceneError::new("--cables", e.to_string()))?;
        let q = &est.quality;
        let status = Status::estimate(&est.report, settings.check_stability, q.determination);
        let numbers = if status.verdict.has_numbers() {
            let s = self.scene.output_points_m(model.length_m())?;
            let points = dead_load_shape(model, &est.base_strain_per_m, &est.load, &s)?;
            Some(EstimateNumbers {
                tip_force_n: arr(&est.params),
                tip_force_std_n: arr(&q.force_std_n),
                tip_position_m: arr(&est.tip_position_m),
                tip_position_std_m: arr(&q.tip_std_m),
                cable_residual_m: est
                    .cable_residual_m
                    .iter()
                    .take(self.measured_m.len())
                    .copied()
                    .collect(),
                singular_values: arr(&q.singular_values),
                condition_number: q.condition_number,
                weakest_direction: arr(&q.weakest_direction),
                shape: points.iter().map(point).collect(),
            })
        } else {
            None
        };
        let figure = if status.verdict.has_numbers() && self.plot {
            let shape = |s: &[f64]| dead_load_shape(model, &est.base_strain_per_m, &est.load, s);
            let (f, sd) = (est.params, q.force_std_n);
            let mut notes = vec![
                status.line(),
                format!(
                    "tip force: Fx {:.4} ± {:.4}, Fy {:.4} ± {:.4}, Fz {:.4} ± {:.4} N",
                    f.x, sd.x, f.y, sd.y, f.z, sd.z
                ),
            ];
            if q.determination == Determination::Inconsistent {
                notes.push(
                    "INCONSISTENT: no load explains the cable lengths; this is the closest fit"
                        .to_string(),
                );
            }
            Some(figure(
                model,
                &shape,
                FigureSpec {
                    title: format!("estimate: {}", self.scene.name),
                    notes,
                    tendons: None,
                    tip_std_m: Some(q.tip_std_m),
                },
            )?)
        } else {
            None
        };
        Ok(EstimateOutput {
            status,
            scene: self.scene.name.clone(),
            measured_m: self.measured_m.clone(),
            report: Report::from(&est.report),
            numbers,
            figure,
        })
    }
}

/// The CSV's columns: the backbone point, then the status.
pub const CSV_HEADER: &str =
    "s_m,x_m,y_m,z_m,tan_x,tan_y,tan_z,u_x_per_m,u_y_per_m,u_z_per_m,status";

/// The shape as CSV: [`CSV_HEADER`], then one row per point with the status ([`Status::csv_cell`]) in
/// its last column. Without an answer (`shape` is `None`) the only row after the header has empty
/// number fields and the status, so the file itself says why it holds no shape, and a reader that
/// parses the numbers gets empty fields (NaN, or an error), never a failed iterate's.
pub fn shape_csv(shape: Option<&[Point]>, status: &Status) -> String {
    csv_table(shape, &[], &[], status)
}

/// The columns a scene with `count` tendons adds to the CSV, before `status`: five per tendon `j`,
/// `tendon{j}_tension_n`, `tendon{j}_path_m`, `tendon{j}_displacement_m`, `tendon{j}_state`
/// (`taut` or `slack`) and `tendon{j}_slack_m`.
pub fn tendon_csv_columns(count: usize) -> Vec<String> {
    (0..count)
        .flat_map(|j| {
            ["tension_n", "path_m", "displacement_m", "state", "slack_m"]
                .map(|c| format!("tendon{j}_{c}"))
        })
        .collect()
}

/// A solution as CSV: the shape ([`shape_csv`]); for a scene with tendons, every row also carries
/// the tendons' columns ([`tendon_csv_columns`]), the same on every row. Without an answer the only
/// row has empty numbers, the tendons' included, and the status.
pub fn solution_csv(solution: &Solution) -> String {
    let Some(t) = &solution.tendons else {
        return shape_csv(solution.shape.as_deref(), &solution.status);
    };
    let count = t
        .tensions_n
        .as_ref()
        .or(t.displacements_m.as_ref())
        .map_or(0, Vec::len);
    let cells: Vec<String> = match (
        &t.tensions_n,
        &t.path_m,
        &t.displacements_m,
        &t.states,
        &t.slack_m,
    ) {
        (Some(tau), Some(path), Some(d), Some(states), Some(slack)) if solution.shape.is_some() => {
            (0..count)
                .flat_map(|j| {
                    let number = |v: &[f64]| v.get(j).map_or(String::new(), f64::to_string);
                    [
                        number(tau),
                        number(path),
                        number(d),
                        states.get(j).map_or(String::new(), |s| (*s).to_string()),
                        number(slack),
                    ]
                })
                .collect()
        }
        _ => Vec::new(),
    };
    csv_table(
        solution.shape.as_deref(),
        &tendon_csv_columns(count),
        &cells,
        &solution.status,
    )
}

/// [`CSV_HEADER`] with `columns` before `status`; each shape row with `cells` (as many as
/// `columns`) before its status; without a shape one row of empty fields and the status.
fn csv_table(
    shape: Option<&[Point]>,
    columns: &[String],
    cells: &[String],
    status: &Status,
) -> String {
    let cell = csv_field(&status.csv_cell());
    let header = CSV_HEADER.strip_suffix(",status").unwrap_or(CSV_HEADER);
    let mut out = String::from(header);
    for c in columns {
        out.push(',');
        out.push_str(c);
    }
    out.push_str(",status\n");
    let extra: String = cells.iter().map(|c| format!(",{}", csv_field(c))).collect();
    match shape {
        Some(shape) => {
            for p in shape {
                let [x, y, z] = p.position_m;
                let [tx, ty, tz] = p.tangent;
                let [ux, uy, uz] = p.strain_per_m;
                let _ = writeln!(
                    out,
                    "{},{x},{y},{z},{tx},{ty},{tz},{ux},{uy},{uz}{extra},{cell}",
                    p.s_m
                );
            }
        }
        None => {
            let empty = ",".repeat(9 + columns.len());
            let _ = writeln!(out, "{empty},{cell}");
        }
    }
    out
}

/// A CSV field, quoted if it holds a comma, a quote or a line break (RFC 4180).
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// What an estimate's verdict leaves out of its printed numbers, as a warning, when it does: a tip
/// force the cables do not determine, or one that may not be the only load explaining them (its
/// standard deviations are this answer's alone). `Determined` and `Weak` say it in their deviations.
fn doubt_of(determination: Determination) -> Option<&'static str> {
    match determination {
        Determination::Undetermined => Some(
            "the cables do not determine the load (determination Undetermined): the tip force \
             printed is one of many that explain the lengths",
        ),
        Determination::Ambiguous => Some(
            "another load within the search's reach explains the lengths as well (determination \
             Ambiguous): the tip force printed is one of the answers, and its standard deviations \
             do not cover the other",
        ),
        Determination::Unverified => Some(
            "the search for other loads that explain the lengths ran out of its budget \
             (determination Unverified): another answer was not ruled out, and the standard \
             deviations printed are this answer's alone",
        ),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::Stability;

    fn report(termination: Termination, stability: Stability<f64>) -> SolveReport<f64> {
        SolveReport {
            termination,
            iterations: 3,
            sweeps: 4,
            residual: f64::NAN,
            load_steps: 0,
            stability,
            phase_per_step_rad: 0.1,
        }
    }

    #[test]
    fn an_estimate_that_may_not_be_the_only_answer_warns() {
        let converged = report(Termination::Converged, Stability::Stable);
        for (determination, warned) in [
            (Determination::Determined, false),
            (Determination::Weak, false),
            (Determination::Undetermined, true),
            (Determination::Ambiguous, true),
            (Determination::Unverified, true),
        ] {
            let status = Status::estimate(&converged, true, determination);
            assert_eq!(status.verdict, Verdict::Answer);
            let named = format!("determination {determination:?})");
            assert_eq!(
                status.warnings.iter().any(|w| w.contains(&named)),
                warned,
                "{determination:?}: {:?}",
                status.warnings
            );
        }
        // No answer: nothing printed, nothing to warn about.
        let stalled = report(Termination::Stalled, Stability::Unchecked);
        let status = Status::estimate(&stalled, true, Determination::Ambiguous);
        assert!(status.warnings.is_empty(), "{:?}", status.warnings);
    }

    #[test]
    fn non_finite_numbers_are_strings_in_json() {
        let r = Report::from(&report(Termination::NonFinite, Stability::Unchecked));
        let v = serde_json::to_value(&r).unwrap();
        assert_eq!(v["residual"], "NaN");
        let p = Point {
            s_m: 0.0,
            position_m: [f64::INFINITY, f64::NEG_INFINITY, 1.5],
            tangent: [0.0; 3],
            strain_per_m: [0.0; 3],
        };
        let v = serde_json::to_value(&p).unwrap();
        assert_eq!(
            v["position_m"],
            serde_json::json!(["Infinity", "-Infinity", 1.5])
        );
    }

    #[test]
    fn a_failed_estimate_has_the_same_keys_as_an_answer_all_null() {
        let numbers = EstimateNumbers {
            tip_force_n: [0.0; 3],
            tip_force_std_n: [0.0; 3],
            tip_position_m: [0.0; 3],
            tip_position_std_m: [0.0; 3],
            cable_residual_m: vec![0.0],
            singular_values: [0.0; 3],
            condition_number: 1.0,
            weakest_direction: [0.0; 3],
            shape: Vec::new(),
        };
        let keys = |v: &serde_json::Value| -> Vec<String> {
            v.as_object().unwrap().keys().cloned().collect()
        };
        let answer = serde_json::to_value(&numbers).unwrap();
        // serde_json's map is sorted by key.
        let mut expected = ESTIMATE_KEYS.map(String::from).to_vec();
        expected.sort();
        assert_eq!(keys(&answer), expected);
        let status = Status::new(
            &report(Termination::Stalled, Stability::Unchecked),
            true,
            Some(Determination::Determined),
        );
        let failed = EstimateOutput {
            status,
            scene: String::new(),
            measured_m: vec![0.39],
            report: Report::from(&report(Termination::Stalled, Stability::Unchecked)),
            numbers: None,
            figure: None,
        };
        let v = serde_json::to_value(&failed).unwrap();
        for key in ESTIMATE_KEYS {
            assert!(v.get(key).is_some_and(serde_json::Value::is_null), "{key}");
        }
        assert!(v["status"]["determination"].is_null());
    }

    #[test]
    fn the_verdict_follows_termination_stability_and_determination() {
        let stable = Stability::Stable;
        let cases = [
            (Termination::Converged, stable, None, Verdict::Answer),
            (Termination::Stalled, stable, None, Verdict::NoAnswer),
            (Termination::FrameDrift, stable, None, Verdict::NoAnswer),
            (
                Termination::UnderResolved,
                Stability::Unchecked,
                None,
                Verdict::NoAnswer,
            ),
            (
                Termination::Unstable,
                Stability::ConjugatePoint(0.2),
                None,
                Verdict::NoAnswer,
            ),
            // Converged but unstable (model-core reports it as `Unstable`; never an answer here).
            (
                Termination::Converged,
                Stability::FreeEndUnstable,
                None,
                Verdict::NoAnswer,
            ),
            (
                Termination::Converged,
                stable,
                Some(Determination::Inconsistent),
                Verdict::Inconsistent,
            ),
            (
                Termination::Converged,
                stable,
                Some(Determination::Weak),
                Verdict::Answer,
            ),
            (
                Termination::Converged,
                stable,
                Some(Determination::Undetermined),
                Verdict::Answer,
            ),
            // No answer comes first: an inconsistent verdict on a failed iterate is exit 3.
            (
                Termination::IterationLimit,
                Stability::Unchecked,
                Some(Determination::Inconsistent),
                Verdict::NoAnswer,
            ),
        ];
        for (termination, stability, determination, verdict) in cases {
            let s = Status::new(&report(termination, stability), true, determination);
            assert_eq!(
                s.verdict, verdict,
                "{termination:?} {stability:?} {determination:?}"
            );
            assert_eq!(s.exit_code, verdict.exit_code());
        }
    }

    #[test]
    fn a_tendon_status_needs_the_displacement_solve_and_warns_of_unchecked_stability() {
        let converged = report(Termination::Converged, Stability::Unchecked);
        // Force control, converged: an answer, with the tendons' warning.
        let s = Status::tendon(&converged, true, None);
        assert_eq!((s.verdict, s.exit_code), (Verdict::Answer, 0));
        assert!(!s.stability_checked);
        assert_eq!(s.warnings.len(), 1);
        assert!(s.warnings[0].contains("tendons"), "{:?}", s.warnings);
        // The scene turned the test off: its own warning, not two.
        let s = Status::tendon(&converged, false, None);
        assert_eq!(s.warnings.len(), 1);
        assert!(s.warnings[0].contains("check_stability = false"));
        // Displacement control: the search for the tensions must also converge.
        let s = Status::tendon(&converged, true, Some(Termination::Converged));
        assert_eq!(s.verdict, Verdict::Answer);
        let s = Status::tendon(&converged, true, Some(Termination::Stalled));
        assert_eq!((s.verdict, s.exit_code), (Verdict::NoAnswer, 3));
        assert_eq!(s.termination, "Stalled");
        assert!(
            s.summary.starts_with("no answer") && s.warnings.is_empty(),
            "{s:?}"
        );
        // A failed forward solve is no answer whatever the search says.
        let failed = report(Termination::ContinuationFailed, Stability::Unchecked);
        let s = Status::tendon(&failed, true, Some(Termination::Converged));
        assert_eq!(
            (s.verdict, s.termination.as_str()),
            (Verdict::NoAnswer, "ContinuationFailed")
        );
    }

    #[test]
    fn a_tendon_estimate_status_needs_the_fit_and_says_what_is_not_observable() {
        use Determination::*;
        let converged = report(Termination::Converged, Stability::Unchecked);
        let status = |fit, d, t, observable| {
            Status::tendon_estimate(&converged, true, fit, d, t, observable, 1.0)
        };
        // Tensions measured: an answer with both verdicts.
        let s = status(Termination::Converged, Weak, Determined, true);
        assert_eq!((s.verdict, s.exit_code), (Verdict::Answer, 0));
        assert_eq!(s.determination, Some(Some("Weak".into())));
        assert_eq!(s.tension_determination, Some(Some("Determined".into())));
        assert!(s.line().contains("determination Weak, tensions Determined"));
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        // Displacements alone: an answer that says the force is not observable.
        let s = status(Termination::Converged, Undetermined, Weak, false);
        assert_eq!(s.verdict, Verdict::Answer);
        assert!(s.summary.contains("tip force not observable"), "{s:?}");
        assert!(s.warnings.iter().any(|w| w.contains("not observable")));
        // Inconsistent: exit 4, the closest fit's verdicts kept.
        let s = status(Termination::Converged, Inconsistent, Inconsistent, true);
        assert_eq!((s.verdict, s.exit_code), (Verdict::Inconsistent, 4));
        assert_eq!(s.tension_determination, Some(Some("Inconsistent".into())));
        // A fit that did not converge: no answer, no verdicts, no warnings about the answer.
        let s = status(Termination::Stalled, Undetermined, Undetermined, false);
        assert_eq!((s.verdict, s.exit_code), (Verdict::NoAnswer, 3));
        assert_eq!(s.termination, "Stalled");
        assert_eq!(s.determination, Some(None));
        assert_eq!(s.tension_determination, Some(None));
        assert!(s.summary.starts_with("no answer: the fit"), "{s:?}");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // Its last forward solve failed too: still the fit's termination and words.
        let failed = report(Termination::Stalled, Stability::Unchecked);
        let s = Status::tendon_estimate(&failed, true, Termination::Stalled, Weak, Weak, true, 1.0);
        assert_eq!(s.verdict, Verdict::NoAnswer);
        assert!(s.summary.starts_with("no answer: the fit"), "{s:?}");
        // The fit converged but its forward solve did not: no answer either.
        let s =
            Status::tendon_estimate(&failed, true, Termination::Converged, Weak, Weak, true, 1.0);
        assert_eq!((s.verdict, s.exit_code), (Verdict::NoAnswer, 3));
        assert_eq!(s.tension_determination, Some(None));
    }

    #[test]
    fn csv_status_cells_are_quoted_when_needed() {
        assert_eq!(csv_field("Converged/Stable"), "Converged/Stable");
        assert_eq!(csv_field("A { b: 1, c: 2 }"), "\"A { b: 1, c: 2 }\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
    }
}
