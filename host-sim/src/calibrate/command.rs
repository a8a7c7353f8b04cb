//! `host-sim calibrate <scene.toml> --data <measurements.csv>`: read both files, fit, write the
//! calibrated scene (`--out`, only for a determined fit) and print the report (text or JSON).

use std::path::PathBuf;

use clap::ValueEnum;

use super::data::{DataShape, Measurements};
use super::fit::{Calibration, Verdict, calibrate, fit_count};
use super::params::FitParameter;
use super::{text, write};
use crate::plots::{PlotFormat, PlotSize, draw_figure, ensure_font};
use crate::scene::{self, Scene, SceneError};

/// The report's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReportFormat {
    /// A readable report.
    Text,
    /// JSON (everything).
    Json,
}

/// The command's arguments.
#[derive(Debug, Clone, PartialEq)]
pub struct Args {
    /// The scene file.
    pub scene: PathBuf,
    /// The data file.
    pub data: PathBuf,
    /// What to fit besides `E`.
    pub fit: Vec<FitParameter>,
    /// Where to write the calibrated scene.
    pub out: Option<PathBuf>,
    /// The report's format.
    pub format: ReportFormat,
    /// Where to draw the fitted backbones and the observed points, and how wide.
    pub plot: Option<(PathBuf, PlotSize)>,
}

fn read(path: &PathBuf) -> Result<(String, String), SceneError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(&origin, format!("cannot read: {e}")))?;
    Ok((text, origin))
}

/// The comment lines on top of a calibrated scene: where its values come from.
fn header(c: &Calibration) -> Vec<String> {
    let mut lines = vec![format!(
        "Calibrated with `host-sim calibrate --data {}` (fitted: {}): rms {} mm over {} points{}.",
        c.data,
        c.fitted.join(", "),
        c.rms_mm.map_or_else(|| "-".into(), |x| format!("{x:.4}")),
        c.observations,
        c.leave_one_out_rms_mm
            .map_or_else(String::new, |x| format!(", leave-one-out rms {x:.4} mm"))
    )];
    for p in &c.parameters {
        if let (Some(v), Some(sd)) = (p.value, p.std) {
            lines.push(format!(
                "  {} = {v:.6e} ± {sd:.2e} {} (1 sd)",
                p.name, p.unit
            ));
        }
    }
    if c.fitted.iter().any(|f| f == "base_pose") {
        lines.push(
            "  The base pose is fitted: this scene is written in the data's measurement frame \
             (base, gravity and loads rotated and moved)."
                .to_string(),
        );
    }
    lines
}

/// Runs the command; the exit code of the calibration's verdict (0 determined, 3 otherwise), or an
/// error (exit 1).
pub fn run(args: &Args) -> Result<u8, SceneError> {
    let (scene_text, scene_origin) = read(&args.scene)?;
    let scene = Scene::parse(&scene_text, &scene_origin)?;
    for w in scene.warnings() {
        eprintln!("warning: {}", scene::locate(w, &scene_text, &scene_origin));
    }
    let in_scene = |e: SceneError| scene::locate(e, &scene_text, &scene_origin);
    if let Some((path, _)) = &args.plot {
        PlotFormat::of(path)?;
        ensure_font()?;
    }
    let (data_text, data_origin) = read(&args.data)?;
    let shape = DataShape {
        tendons: scene.tendons.len(),
        length_m: scene.rod().map_err(in_scene)?.length_m(),
    };
    let data = Measurements::parse(&data_text, &data_origin, shape)?;
    // Drawn on a terminal only; piped output stays clean.
    let bar = indicatif::ProgressBar::new(fit_count(&data));
    bar.set_message("fits (all experiments, then leave-one-out)");
    let result = calibrate(&scene, &data, &args.fit, || bar.inc(1));
    bar.finish_and_clear();
    let mut c = result.map_err(in_scene)?;
    if let Some(out) = &args.out {
        match &c.values {
            Some(values) if c.status.verdict == Verdict::Determined => {
                let origin = out.display().to_string();
                let written =
                    write::calibrated_scene(&scene_text, &scene, values, &c.fitted, &header(&c))
                        .map_err(in_scene)?;
                // What is written must read back as a scene.
                Scene::parse(&written, &origin)?;
                std::fs::write(out, written)
                    .map_err(|e| SceneError::new(&origin, format!("cannot write: {e}")))?;
                c.written = Some(origin);
            }
            _ => eprintln!(
                "--out: nothing written to {}: the calibration is not determined",
                out.display()
            ),
        }
    }
    if let Some((path, size)) = &args.plot {
        let drawn = match &c.values {
            Some(values) => super::figure::figure(&scene, &data, values, &c).map_err(in_scene)?,
            None => None,
        };
        match drawn {
            Some(f) => {
                draw_figure(&f, path, *size)?;
                eprintln!("plot written to {}", path.display());
            }
            None => eprintln!(
                "--plot: nothing drawn to {}: the fit has no answer to draw",
                path.display()
            ),
        }
    }
    for w in &c.status.warnings {
        eprintln!("warning: {w}");
    }
    if c.status.exit_code != 0 {
        eprintln!("error: {} (exit {})", c.status.summary, c.status.exit_code);
    }
    let report = match args.format {
        ReportFormat::Text => text::report(&c),
        ReportFormat::Json => serde_json::to_string_pretty(&c)
            .map(|s| s + "\n")
            .map_err(|e| SceneError::new("output", e.to_string()))?,
    };
    crate::run::emit(&report, None)?;
    Ok(c.status.exit_code)
}
