//! `host-sim`: run the thesis's experiments and your own scenes through the model in f64.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use host_sim::run::{self, Estimate, Solve, Status, TendonSolve, exit, with_model};
use host_sim::scene::{Actuation, Control, Scene, SceneError};
use host_sim::{calibrate, report, thesis};
use nalgebra::Vector3;

mod study;

/// The exit codes and the status in every format (`--help`; the README repeats it).
const EXIT_STATUS: &str = "\
Exit status of solve and estimate:
  0  a converged answer (stable, where stability is checked). For estimate, whatever the
     determination (Determined, Weak, Undetermined, Ambiguous: another load explains the
     lengths as well, Unverified: the search for other loads ran out of budget): the
     determination and the uncertainty say how good it is.
  1  invalid input: a bad scene file or value (a negative cable length, too many guides, ...),
     or an I/O error
  2  command-line usage error
  3  no answer: the solve did not converge, converged to an unstable equilibrium, its frame
     drifted or its grid does not resolve the bending (any termination other than
     Converged). The failed iterate is not printed.
  4  estimate only: converged, but no load of the model explains the measurements
     (Inconsistent). The closest fit is printed.
validate and study exit 1 when a check fails.

Every format says its status. Text: the first line. JSON: a top-level \"status\" object
(verdict, exit_code, termination, stability, stability_checked, for estimate determination,
summary, warnings); without an answer the shape, tip, cable lengths and forces are null. A
non-finite JSON number (a NaN residual) is written as the string \"NaN\", \"Infinity\" or
\"-Infinity\", never as null. CSV: a last column \"status\" on every row,
termination/stability[/determination] (for example Converged/Stable/Weak); without an answer the
only row has empty numbers and the status. Stability \"Unchecked\" (the scene sets
check_stability = false) or \"NonConservative\" (a moment acts) means the stability test did not
run: an unstable, wrong-branch equilibrium would be reported as converged; a warning goes to
standard error.

Tendons (host-sim/SCENES.md): solve also prints each tendon's tension, path length, spool
displacement, state and slack (JSON: a \"tendons\" object; CSV: five columns per tendon before
\"status\"); without an answer only the given tensions or displacements. Stability is always
\"Unchecked\" with tendons (no energy test yet), with the warning. Displacement control is an
answer only if the search for the tensions converged (exit 3 otherwise).";

#[derive(Parser)]
#[command(
    version,
    about = "Cosserat-rod shape model of a cable-driven continuum robot, in f64 on the host",
    after_help = EXIT_STATUS
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    /// A readable summary.
    Text,
    /// JSON (everything).
    Json,
    /// CSV of the backbone points, with a status column.
    Csv,
}

#[derive(Subcommand)]
enum Command {
    /// Run the thesis's experiments (Tables 4.1, 4.3/4.4, 4.5): observed / thesis / ours, with errors.
    /// Exits non-zero if a reproduction tolerance is broken.
    Validate {
        /// Also draw the shapes and the cable-delta curve (SVG and PNG) into this directory.
        #[arg(long)]
        plots: Option<PathBuf>,
    },
    /// The inverse on Table 4.5: the hung mass and the tip from the single measured cable, with the
    /// uncertainty of the bench's 1 mm ruler, against the hung mass and the observed tip.
    Inverse,
    /// Fit Young's modulus (and optionally the line density) to a thesis table by least squares, with
    /// leave-one-out errors.
    Calibrate {
        /// Which table: "4.1" (two sections) or "4.3" (guides, average mass).
        #[arg(long, default_value = "4.3")]
        table: String,
        /// Also fit a scale on the line density.
        #[arg(long)]
        fit_density: bool,
    },
    /// Solve a scene: the shape and the cable lengths under its tip load; with tendons, also their
    /// tensions, path lengths, spool displacements and states (host-sim/SCENES.md).
    /// Exits 3 when the solve gives no answer (see below).
    #[command(after_help = EXIT_STATUS)]
    Solve {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Override the scene's [actuation] with tendon tensions, N, one per [[tendon]] in order:
        /// T1,T2,T3 (force control).
        #[arg(
            long,
            value_delimiter = ',',
            allow_hyphen_values = true,
            conflicts_with = "displacements"
        )]
        tensions: Option<Vec<f64>>,
        /// Override the scene's [actuation] with spool displacements, m, one per [[tendon]] in
        /// order, positive when taken in from the straight unloaded rod's zero-tension setting:
        /// D1,D2,D3 (displacement control: the tensions are solved for).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        displacements: Option<Vec<f64>>,
        /// Override the tip force, N: fx,fy,fz (global frame).
        #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
        tip_force: Option<Vector3<f64>>,
        /// Override the tip moment, N m: mx,my,mz.
        #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
        tip_moment: Option<Vector3<f64>>,
        /// Output format.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
        /// Write to this file instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Estimate the tip force of a scene's robot from measured cable lengths.
    /// Exits 3 when the solve gives no answer, 4 when no load explains the lengths (see below).
    #[command(after_help = EXIT_STATUS)]
    Estimate {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Measured cable lengths, m, one per cable: L1,L2,L3. A value may start with a minus sign
        /// (it is then refused as a length, with exit 1, not taken for an option).
        #[arg(
            long,
            value_delimiter = ',',
            required = true,
            allow_hyphen_values = true
        )]
        cables: Vec<f64>,
        /// Output format.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
        /// Write to this file instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The accuracy-vs-cost study of the model's variants (f64/f32, frames, reductions, steps):
    /// report/accuracy_cost.md, .csv and the Pareto plot. `report/study.sh` adds the micromath rows.
    /// Exits non-zero if a check fails.
    Study(study::Args),
}

fn parse_vec3(s: &str) -> Result<Vector3<f64>, String> {
    let parts: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|e| format!("\"{p}\": {e}")))
        .collect::<Result<_, _>>()?;
    match parts.as_slice() {
        [x, y, z] => Ok(Vector3::new(*x, *y, *z)),
        _ => Err(format!(
            "expected three comma-separated numbers, got {}",
            parts.len()
        )),
    }
}

fn fail(e: &dyn std::fmt::Display) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(exit::INVALID_INPUT)
}

fn emit(text: &str, out: Option<&PathBuf>) -> Result<(), SceneError> {
    match out {
        Some(path) => std::fs::write(path, text)
            .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}"))),
        // Not `print!`, which panics when the reader has gone (a closed pipe).
        None => std::io::stdout()
            .lock()
            .write_all(text.as_bytes())
            .map_err(|e| SceneError::new("standard output", format!("cannot write: {e}"))),
    }
}

fn json<T: serde::Serialize>(value: &T) -> Result<String, SceneError> {
    serde_json::to_string_pretty(value)
        .map(|s| s + "\n")
        .map_err(|e| SceneError::new("output", e.to_string()))
}

/// The status line and the warnings, first in the text format.
fn status_text(t: &mut String, status: &Status) {
    let _ = writeln!(t, "{}", status.line());
    for w in &status.warnings {
        let _ = writeln!(t, "warning: {w}");
    }
}

/// Standard error gets the warnings and, when there is no answer, why: whatever the format, and
/// also when the output goes to a file.
fn status_stderr(status: &Status) {
    for w in &status.warnings {
        eprintln!("warning: {w}");
    }
    if status.exit_code != exit::ANSWER {
        eprintln!("error: {} (exit {})", status.summary, status.exit_code);
    }
}

fn solve_text(s: &run::Solution) -> String {
    let mut t = String::new();
    status_text(&mut t, &s.status);
    let _ = writeln!(t, "scene: {}", s.scene);
    let _ = writeln!(
        t,
        "tip force {:?} N, tip moment {:?} N m",
        s.tip_force_n, s.tip_moment_nm
    );
    if let Some(tendons) = &s.tendons {
        tendon_given_text(&mut t, tendons);
    }
    let _ = writeln!(t, "solve: {:?}", s.report);
    match (
        &s.tip_position_m,
        &s.tip_tangent,
        &s.cable_lengths_m,
        &s.shape,
    ) {
        (Some(tip), Some(tangent), Some(cables), Some(shape)) => {
            let _ = writeln!(t, "tip position {tip:?} m, tangent {tangent:?}");
            let _ = writeln!(t, "cable lengths {cables:?} m");
            if let Some(tendons) = &s.tendons {
                tendon_table_text(&mut t, tendons);
            }
            t.push_str(&run::shape_csv(Some(shape), &s.status));
        }
        _ => {
            let what = if s.tendons.is_some() {
                "no tip position, cable lengths, tendon tensions, paths or shape"
            } else {
                "no tip position, cable lengths or shape"
            };
            let _ = writeln!(t, "no answer: {what} (the failed iterate is not printed)");
        }
    }
    t
}

/// The tendons' actuation as given, and for displacement control how the search for the tensions
/// went.
fn tendon_given_text(t: &mut String, tendons: &run::TendonOutput) {
    match (
        tendons.control,
        &tendons.tensions_n,
        &tendons.displacements_m,
    ) {
        ("tensions", Some(tau), _) => {
            let _ = writeln!(t, "tendons: force control, tensions given {tau:?} N");
        }
        (_, _, Some(d)) => {
            let _ = writeln!(
                t,
                "tendons: displacement control, spool displacements given {d:?} m"
            );
        }
        _ => {}
    }
    if let Some(d) = &tendons.displacement_solve {
        let _ = writeln!(
            t,
            "displacement solve: termination {}, {} iterations, {} sweeps",
            d.termination, d.iterations, d.sweeps
        );
    }
}

/// One row per tendon: tension, path, spool displacement, state, slack.
fn tendon_table_text(t: &mut String, tendons: &run::TendonOutput) {
    let (Some(tau), Some(path), Some(d), Some(states), Some(slack)) = (
        &tendons.tensions_n,
        &tendons.path_m,
        &tendons.displacements_m,
        &tendons.states,
        &tendons.slack_m,
    ) else {
        return;
    };
    let _ = writeln!(
        t,
        "tendon  tension_n  path_m  displacement_m  state  slack_m"
    );
    for (j, ((((tau, path), d), state), slack)) in tau
        .iter()
        .zip(path)
        .zip(d)
        .zip(states)
        .zip(slack)
        .enumerate()
    {
        let _ = writeln!(t, "{j}  {tau}  {path}  {d}  {state}  {slack}");
    }
}

fn estimate_text(e: &run::EstimateOutput) -> String {
    let mut t = String::new();
    status_text(&mut t, &e.status);
    let _ = writeln!(t, "scene: {}", e.scene);
    let _ = writeln!(t, "measured cable lengths {:?} m", e.measured_m);
    let _ = writeln!(t, "solve: {:?}", e.report);
    let Some(n) = &e.numbers else {
        let _ = writeln!(
            t,
            "no answer: no tip force, tip position or shape (the failed iterate is not printed)"
        );
        return t;
    };
    let _ = writeln!(t, "tip force {:?} N", n.tip_force_n);
    let _ = writeln!(t, "  1 sd     {:?} N", n.tip_force_std_n);
    let _ = writeln!(t, "tip position {:?} m", n.tip_position_m);
    let _ = writeln!(t, "  1 sd        {:?} m", n.tip_position_std_m);
    let _ = writeln!(
        t,
        "cable residual (model - measured) {:?} m",
        n.cable_residual_m
    );
    let determination = match &e.status.determination {
        Some(Some(d)) => d.as_str(),
        _ => "none",
    };
    let _ = writeln!(
        t,
        "determination: {determination}; condition number {:.3e}; singular values {:?}; weakest direction {:?}",
        n.condition_number, n.singular_values, n.weakest_direction
    );
    t.push_str(&run::shape_csv(Some(&n.shape), &e.status));
    t
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Study(args) => return study::main(&args),
        Command::Validate { plots } => match thesis::validate() {
            Ok(v) => {
                print!("{}", report::validation(&v));
                if let Some(dir) = plots {
                    if let Err(e) = host_sim::plots::draw_validation(&v, &dir) {
                        return fail(&e);
                    }
                    println!("\nplots written to {}", dir.display());
                }
                return if v.checks().iter().all(|c| c.passed) {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::FAILURE
                };
            }
            Err(e) => Err(e),
        },
        Command::Inverse => (|| {
            for (name, accurate) in [("average", false), ("accurate", true)] {
                print!(
                    "{}",
                    report::inverse(name, &thesis::inverse_table(accurate)?)
                );
            }
            Ok(exit::ANSWER)
        })(),
        Command::Calibrate { table, fit_density } => (|| {
            let dataset = match table.as_str() {
                "4.1" => calibrate::Dataset::Table41,
                "4.3" => calibrate::Dataset::Table43,
                other => {
                    return Err(SceneError::new(
                        "--table",
                        format!("unknown \"{other}\" (expected 4.1 or 4.3)"),
                    ));
                }
            };
            // Drawn on a terminal only; piped output stays clean.
            let bar = indicatif::ProgressBar::new(calibrate::fit_count(dataset)?);
            bar.set_message("fits (all rows, then leave-one-out)");
            let result = calibrate::calibrate(dataset, fit_density, || bar.inc(1));
            bar.finish_and_clear();
            print!("{}", report::calibration(&result?));
            Ok(exit::ANSWER)
        })(),
        Command::Solve {
            scene,
            tensions,
            displacements,
            tip_force,
            tip_moment,
            format,
            out,
        } => (|| {
            let scene = Scene::load(&scene)?;
            let mut load = scene.tip_load()?;
            if let Some(f) = tip_force {
                load.force_n = f;
            }
            if let Some(m) = tip_moment {
                load.moment_nm = m;
            }
            let given = match (tensions, displacements) {
                (Some(values), _) => Some(Actuation {
                    control: Control::Tensions,
                    values,
                    key: "--tensions".into(),
                }),
                (None, Some(values)) => Some(Actuation {
                    control: Control::Displacements,
                    values,
                    key: "--displacements".into(),
                }),
                (None, None) => None,
            };
            let solution = match scene.actuation_or(given)? {
                Some(actuation) => with_model(
                    &scene,
                    TendonSolve {
                        scene: &scene,
                        load,
                        actuation,
                    },
                )?,
                None => with_model(
                    &scene,
                    Solve {
                        scene: &scene,
                        load,
                    },
                )?,
            };
            status_stderr(&solution.status);
            let text = match format {
                Format::Text => solve_text(&solution),
                Format::Json => json(&solution)?,
                Format::Csv => run::solution_csv(&solution),
            };
            emit(&text, out.as_ref())?;
            Ok(solution.status.exit_code)
        })(),
        Command::Estimate {
            scene,
            cables,
            format,
            out,
        } => (|| {
            let scene = Scene::load(&scene)?;
            if !scene.tendons.is_empty() {
                return Err(SceneError::new(
                    "tendon",
                    "estimate does not model tendons yet: the inverse would ignore their pull \
                     (solve a tendon scene with `host-sim solve`)",
                ));
            }
            let estimate = with_model(
                &scene,
                Estimate {
                    scene: &scene,
                    measured_m: cables,
                },
            )?;
            status_stderr(&estimate.status);
            let shape = estimate.numbers.as_ref().map(|n| n.shape.as_slice());
            let text = match format {
                Format::Text => estimate_text(&estimate),
                Format::Json => json(&estimate)?,
                Format::Csv => run::shape_csv(shape, &estimate.status),
            };
            emit(&text, out.as_ref())?;
            Ok(estimate.status.exit_code)
        })(),
    };
    match result {
        Ok(code) => ExitCode::from(code),
        Err(e) => fail(&e),
    }
}
