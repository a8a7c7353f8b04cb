//! `host-sim`: run the thesis's experiments and your own scenes through the model in f64.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use host_sim::run::{self, Estimate, Solve, with_model};
use host_sim::scene::{Scene, SceneError};
use host_sim::{calibrate, report, thesis};
use nalgebra::Vector3;

mod study;

#[derive(Parser)]
#[command(
    version,
    about = "Cosserat-rod shape model of a cable-driven continuum robot, in f64 on the host"
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
    /// CSV of the backbone points.
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
    /// Solve a scene: the shape and the cable lengths under its tip load.
    Solve {
        /// The scene file (TOML).
        scene: PathBuf,
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
    Estimate {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Measured cable lengths, m, one per cable: L1,L2,L3.
        #[arg(long, value_delimiter = ',', required = true)]
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
    ExitCode::FAILURE
}

fn emit(text: &str, out: Option<&PathBuf>) -> Result<(), SceneError> {
    match out {
        Some(path) => std::fs::write(path, text)
            .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}"))),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn json<T: serde::Serialize>(value: &T) -> Result<String, SceneError> {
    serde_json::to_string_pretty(value)
        .map(|s| s + "\n")
        .map_err(|e| SceneError::new("output", e.to_string()))
}

fn solve_text(s: &run::Solution) -> String {
    let mut t = String::new();
    let _ = writeln!(t, "scene: {}", s.scene);
    let _ = writeln!(
        t,
        "tip force {:?} N, tip moment {:?} N m",
        s.tip_force_n, s.tip_moment_nm
    );
    let _ = writeln!(t, "solve: {:?}", s.report);
    let _ = writeln!(
        t,
        "tip position {:?} m, tangent {:?}",
        s.tip_position_m, s.tip_tangent
    );
    let _ = writeln!(t, "cable lengths {:?} m", s.cable_lengths_m);
    t.push_str(&run::shape_csv(&s.shape));
    t
}

fn estimate_text(e: &run::EstimateOutput) -> String {
    let mut t = String::new();
    let _ = writeln!(t, "scene: {}", e.scene);
    let _ = writeln!(t, "measured cable lengths {:?} m", e.measured_m);
    let _ = writeln!(t, "solve: {:?}", e.report);
    let _ = writeln!(t, "tip force {:?} N", e.tip_force_n);
    let _ = writeln!(t, "  1 sd     {:?} N", e.tip_force_std_n);
    let _ = writeln!(t, "tip position {:?} m", e.tip_position_m);
    let _ = writeln!(t, "  1 sd        {:?} m", e.tip_position_std_m);
    let _ = writeln!(
        t,
        "cable residual (model - measured) {:?} m",
        e.cable_residual_m
    );
    let _ = writeln!(
        t,
        "determination: {}; condition number {:.3e}; singular values {:?}; weakest direction {:?}",
        e.determination, e.condition_number, e.singular_values, e.weakest_direction
    );
    t.push_str(&run::shape_csv(&e.shape));
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
            Ok(())
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
            Ok(())
        })(),
        Command::Solve {
            scene,
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
            let solution = with_model(
                &scene,
                Solve {
                    scene: &scene,
                    load,
                },
            )?;
            let text = match format {
                Format::Text => solve_text(&solution),
                Format::Json => json(&solution)?,
                Format::Csv => run::shape_csv(&solution.shape),
            };
            emit(&text, out.as_ref())
        })(),
        Command::Estimate {
            scene,
            cables,
            format,
            out,
        } => (|| {
            let scene = Scene::load(&scene)?;
            let estimate = with_model(
                &scene,
                Estimate {
                    scene: &scene,
                    measured_m: cables,
                },
            )?;
            let text = match format {
                Format::Text => estimate_text(&estimate),
                Format::Json => json(&estimate)?,
                Format::Csv => run::shape_csv(&estimate.shape),
            };
            emit(&text, out.as_ref())
        })(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(&e),
    }
}
