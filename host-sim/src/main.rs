//! `host-sim`: run the thesis's experiments and your own scenes through the model in f64.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand, ValueEnum};
use host_sim::plots::{Figure, PlotSize};
use host_sim::run::{
    self, Estimate, Solve, Status, TendonInverse, TendonSolve, emit, exit, with_model,
};
use host_sim::scene::{self, Actuation, Control, Scene, SceneError, TensionArgs};
use host_sim::{calibrate, report, thesis};
use nalgebra::Vector3;

mod study;

/// The exit codes and the status in every format (`--help`; the README repeats it).
const EXIT_STATUS: &str = "\
Exit status of solve and estimate:
  0  a converged answer (stable, where stability is checked). For estimate, whatever the
     determination (Determined, Weak, Undetermined, Ambiguous: another load explains the
     lengths as well, Unverified: the search for other loads ran out of budget): the
     determination and the uncertainty say how good it is; Undetermined, Ambiguous and
     Unverified also warn that the tip force printed is not the only fit, or may not be.
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
answer only if the search for the tensions converged (exit 3 otherwise).

Estimate on a scene with tendons (host-sim/SCENES.md): from the spool displacements
(--displacements or [actuation] displacements_m) and optionally measured tensions
(--tensions-measured with --tension-std or --tension-stds, or [estimate.tendons]), the tensions
with their standard deviations and states, the tip force with its standard deviation, the tip and
its standard deviation, the shape; force_observable, the determination and the tensions' own
verdict (JSON status.tension_determination), the residual's rms in standard deviations, the fit's
sweeps. From displacements alone the tip force is not observable: determination Undetermined,
exit 0, and the tip force is not printed (null; empty CSV cells; a sentence in the text and a
warning), never guessed. Exit 3 when the fit did not converge, 4 when Inconsistent, as above.

--plot FILE.svg|FILE.png (solve and estimate, any scene): the robot in three projections (mm),
tendons dashed when slack, an estimate's tip 1-sigma ellipse; nothing drawn without an answer.";

#[derive(Parser)]
#[command(
    version,
    about = "Cosserat-rod shape model of a cable-driven continuum robot, in f64 on the host",
    long_about = "Cosserat-rod shape model of a cable-driven continuum robot, in f64 on the host.\n\n\
                  A scene file (TOML) describes one robot: host-sim/SCENES.md documents every key, \
                  with its unit, default and valid range, and has complete example scenes.",
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
    /// Fit Young's modulus and other parameters by least squares, with leave-one-out errors: to a
    /// thesis table, or a scene to your own measured points.
    ///
    /// With --table (the default, 4.3): the thesis's table. With SCENE --data FILE.csv: the scene
    /// fitted to the measured points, with the parameters' standard deviations, the residual of
    /// every point, leave-one-out per experiment and a verdict; exits 0 when the data determine
    /// every fitted parameter, 3 when they do not (the undetermined combination is named and no
    /// number is printed for it) or the fit fails, 1 for invalid input.
    #[command(after_help = calibrate::data::DATA_HELP)]
    Calibrate {
        /// The scene file (TOML) of the robot measured; with --data.
        #[arg(requires = "data")]
        scene: Option<PathBuf>,
        /// The measurements (CSV, format below and in host-sim/SCENES.md "Calibration data").
        #[arg(long, requires = "scene")]
        data: Option<PathBuf>,
        /// With a scene: what to fit besides E (always fitted), comma-separated: E, line_density,
        /// cable_offset (tendon scenes: a scale on every hole's radius), base_pose (rotation and
        /// translation of the measurement frame), friction (tendon scenes).
        #[arg(long, value_enum, value_delimiter = ',', requires = "scene")]
        fit: Vec<calibrate::params::FitParameter>,
        /// With a scene: write the calibrated scene here (the scene file with the fitted values in
        /// its keys, comments and layout kept); only when every fitted parameter is determined.
        #[arg(long, requires = "scene")]
        out: Option<PathBuf>,
        /// With a scene: the report's format.
        #[arg(long, value_enum, default_value_t = calibrate::command::ReportFormat::Text)]
        format: calibrate::command::ReportFormat,
        /// With a scene: also draw each experiment's backbone at the fitted values and the
        /// observed points (measurement frame) into this file, SVG or PNG by its extension.
        #[arg(long, requires = "scene")]
        plot: Option<PathBuf>,
        /// The figure's printed width: "column" (3.5 in) or "page" (7.16 in).
        #[arg(long, value_enum, default_value_t = PlotSize::Page)]
        plot_size: PlotSize,
        /// Which table: "4.1" (two sections) or "4.3" (guides, average mass).
        #[arg(long, default_value = "4.3", conflicts_with = "scene")]
        table: String,
        /// Also fit a scale on the line density (a thesis table).
        #[arg(long, conflicts_with = "scene")]
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
        /// Also draw the robot into this file, SVG or PNG by its extension: the backbone in the
        /// x-y, x-z and y-z projections (mm, equal scale on each panel's axes), the base plate and
        /// guides, each tendon's path (dashed when slack) and each cable's. Not drawn without an
        /// answer.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// The figure's printed width: "column" (3.5 in, one column of a two-column paper) or
        /// "page" (7.16 in, both columns). Fonts and lines keep their sizes in points; a PNG is
        /// 300 dpi.
        #[arg(long, value_enum, default_value_t = PlotSize::Page)]
        plot_size: PlotSize,
    },
    /// Estimate the tip force of a scene's robot: from measured cable lengths (--cables), or for a
    /// scene with tendons, the tensions, the tip force and the shape from the spool displacements
    /// and optionally measured tensions (host-sim/SCENES.md).
    /// Exits 3 when the solve gives no answer, 4 when no load explains the measurements (see below).
    #[command(after_help = EXIT_STATUS)]
    Estimate {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Measured cable lengths, m, one per cable: L1,L2,L3 (required for a scene without
        /// tendons; refused for one with tendons). A value may start with a minus sign (it is then
        /// refused as a length, with exit 1, not taken for an option).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        cables: Option<Vec<f64>>,
        /// Tendons: the spool displacements, m, one per [[tendon]] in order, positive when taken
        /// in from the straight unloaded rod's zero-tension setting: D1,D2,D3. Overrides the
        /// scene's [actuation] displacements_m. Alone they cannot determine a tip force
        /// (Undetermined: the tip force is printed as null).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        displacements: Option<Vec<f64>>,
        /// Tendons: measured tensions, N, one per [[tendon]]: T1,T2,T3 (motor current, load
        /// cells), with --tension-std or --tension-stds. With them the tip force is observable.
        /// Overrides [estimate.tendons] tensions_measured_n.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        tensions_measured: Option<Vec<f64>>,
        /// Tendons: one standard deviation for every measured tension, N.
        #[arg(long, allow_hyphen_values = true, conflicts_with = "tension_stds")]
        tension_std: Option<f64>,
        /// Tendons: a standard deviation per measured tension, N: S1,S2,S3.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        tension_stds: Option<Vec<f64>>,
        /// Output format.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
        /// Write to this file instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also draw the estimate into this file, SVG or PNG by its extension: as `solve --plot`,
        /// with the tip's 1-sigma ellipse in each projection (axis-aligned, from the tip's standard
        /// deviation along each axis). Not drawn without an answer.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// The figure's printed width: "column" (3.5 in, one column of a two-column paper) or
        /// "page" (7.16 in, both columns). Fonts and lines keep their sizes in points; a PNG is
        /// 300 dpi.
        #[arg(long, value_enum, default_value_t = PlotSize::Page)]
        plot_size: PlotSize,
    },
    /// The accuracy-vs-cost study of the model's variants (f64/f32, frames, reductions, steps):
    /// report/accuracy_cost.md, .csv and the Pareto plot. `report/study.sh` adds the micromath rows.
    /// Exits non-zero if a check fails.
    Study(study::Args),
    /// Read the live link (the firmware's records, link/FORMAT.md) from a serial port, a file, a
    /// FIFO or standard input: one line per record, --csv, --plot of the latest shape, and
    /// --check-against a reference. Exits 1 when a check fails.
    #[command(after_help = host_sim::monitor::MONITOR_HELP)]
    Monitor(host_sim::monitor::Args),
    /// The f64 reference of a load path for `monitor --check-against`: the scene solved at each
    /// tick's tip force (CSV: tick, force_x_n, force_y_n, force_z_n), with the tip, its frame and
    /// points of the backbone. Exits 1 for invalid input or a tick without a stable solve.
    Reference(host_sim::monitor::reference::Args),
}

fn parse_vec3(s: &str) -> Result<Vector3<f64>, String> {
    let parts: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|e| format!("\"{p}\": {e}")))
        .collect::<Result<_, _>>()?;
    match parts.as_slice() {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok(Vector3::new(*x, *y, *z)),
        [_, _, _] => Err("every component must be a finite number".into()),
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
    // Under displacement control the report is the last forward solve's, at the tensions the
    // displacement solve ended on (it may converge where the displacement solve stalled): the
    // status and the displacement solve's line above are the verdict.
    let displaced = s
        .tendons
        .as_ref()
        .is_some_and(|t| t.displacement_solve.is_some());
    let label = if displaced {
        "forward solve at those tensions"
    } else {
        "solve"
    };
    let _ = writeln!(t, "{label}: {:?}", s.report);
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

/// The tendons' estimate, as text.
fn tendon_estimate_text(e: &run::TendonEstimateOutput) -> String {
    let mut t = String::new();
    status_text(&mut t, &e.status);
    let _ = writeln!(t, "scene: {}", e.scene);
    let given = &e.tendons;
    let _ = writeln!(t, "spool displacements given {:?} m", given.displacements_m);
    match (&given.tensions_measured_n, &given.tension_measured_std_n) {
        (Some(v), Some(s)) => {
            let _ = writeln!(t, "tensions measured {v:?} N, 1 sd {s:?} N");
        }
        _ => {
            let _ = writeln!(t, "tensions measured: none");
        }
    }
    let s = &e.settings;
    let _ = writeln!(
        t,
        "settings: displacement sd {:e} m, model length sd {:e} m, force prior sd {} N, \
         max force sd {} N, max tension sd {} N, scan reach {}",
        s.displacement_std_m,
        s.model_length_std_m,
        s.force_prior_std_n,
        s.max_force_std_n,
        s.max_tension_std_n,
        s.scan_reach
    );
    let _ = writeln!(
        t,
        "fit: termination {}, {} iterations, {} sweeps",
        e.fit.termination, e.fit.iterations, e.fit.sweeps
    );
    let _ = writeln!(t, "solve: {:?}", e.report);
    let (
        Some(shape),
        Some(tip),
        Some(tip_sd),
        Some(observable),
        Some(tau),
        Some(tau_sd),
        Some(states),
        Some(path),
        Some(slack),
        Some(residual),
    ) = (
        &e.shape,
        &e.tip_position_m,
        &e.tip_position_std_m,
        e.force_observable,
        &given.tensions_n,
        &given.tension_std_n,
        &given.states,
        &given.path_m,
        &given.slack_m,
        &given.displacement_residual_m,
    )
    else {
        let _ = writeln!(
            t,
            "no answer: no tensions, tip force, tip position or shape (the failed iterate is not \
             printed)"
        );
        return t;
    };
    let _ = writeln!(
        t,
        "tendon  tension_n  tension_sd_n  state  path_m  slack_m  displacement_residual_m{}",
        if given.tension_residual_n.is_some() {
            "  tension_residual_n"
        } else {
            ""
        }
    );
    for j in 0..tau.len() {
        let cell = |v: &[f64]| v.get(j).map_or(String::new(), f64::to_string);
        let mut row = format!(
            "{j}  {}  {}  {}  {}  {}  {}",
            cell(tau),
            cell(tau_sd),
            states.get(j).copied().unwrap_or_default(),
            cell(path),
            cell(slack),
            cell(residual)
        );
        if let Some(r) = &given.tension_residual_n {
            let _ = write!(row, "  {}", cell(r));
        }
        let _ = writeln!(t, "{row}");
    }
    match (&e.tip_force_n, &e.tip_force_std_n) {
        (Some(f), Some(sd)) => {
            let _ = writeln!(t, "tip force {f:?} N");
            let _ = writeln!(t, "  1 sd    {sd:?} N");
        }
        _ => {
            let _ = writeln!(
                t,
                "tip force: not observable from the spool displacements alone (Undetermined): \
                 not estimated; measure the tensions too (--tensions-measured)"
            );
        }
    }
    let _ = writeln!(t, "tip position {tip:?} m");
    let _ = writeln!(t, "  1 sd        {tip_sd:?} m");
    let verdict = |d: &Option<Option<String>>| match d {
        Some(Some(d)) => d.clone(),
        _ => "none".to_string(),
    };
    let consistency = match e.residual_rms_sigma {
        Some(rms) => format!("residual rms {rms:.3} sd per spare datum"),
        None => "no datum to spare: the model is not tested against the data".to_string(),
    };
    let _ = writeln!(
        t,
        "determination: {}; tensions: {}; force observable: {}; {consistency}",
        verdict(&e.status.determination),
        verdict(&e.status.tension_determination),
        if observable { "yes" } else { "no" }
    );
    t.push_str(&run::shape_csv(Some(shape), &e.status));
    t
}

/// Draws `figure` into `path` when asked; says on standard error what became of it.
fn draw_plot(
    path: Option<&PathBuf>,
    size: PlotSize,
    figure: Option<&Figure>,
) -> Result<(), SceneError> {
    let Some(path) = path else {
        return Ok(());
    };
    match figure {
        Some(f) => {
            host_sim::plots::draw_figure(f, path, size)?;
            eprintln!("plot written to {}", path.display());
        }
        None => eprintln!(
            "--plot: nothing drawn to {}: there is no answer to draw",
            path.display()
        ),
    }
    Ok(())
}

/// Checks a `--plot` path and the font before the work, so that a bad path fails at once.
fn check_plot(path: Option<&PathBuf>) -> Result<(), SceneError> {
    if let Some(path) = path {
        host_sim::plots::PlotFormat::of(path)?;
        host_sim::plots::ensure_font()?;
    }
    Ok(())
}

/// `estimate` on a scene with tendons: the displacements from the command line or the scene's
/// `[actuation]`, the measured tensions from either ([`Scene::tension_measurement`]).
fn estimate_tendons(
    scene: &Scene,
    displacements: Option<Vec<f64>>,
    tensions: TensionArgs,
    format: Format,
    out: Option<PathBuf>,
    (plot, plot_size): (Option<PathBuf>, PlotSize),
) -> Result<u8, SceneError> {
    let given = displacements.map(|values| Actuation {
        control: Control::Displacements,
        values,
        key: "--displacements".into(),
    });
    let missing = || {
        SceneError::new(
            "actuation",
            "missing: estimate needs the spool displacements: give [actuation] displacements_m \
             or --displacements D1,D2,D3 (m, one per [[tendon]])",
        )
    };
    if given.is_none() && scene.actuation.is_none() {
        return Err(missing());
    }
    let actuation = scene.actuation_or(given)?.ok_or_else(missing)?;
    if actuation.control != Control::Displacements {
        return Err(SceneError::new(
            actuation.key,
            "estimate needs the spool displacements, not tensions: give [actuation] \
             displacements_m or --displacements (to use tensions as measurements, give \
             --tensions-measured with --tension-std, or [estimate.tendons] tensions_measured_n)",
        ));
    }
    let measured = scene.tension_measurement(tensions)?;
    let settings = scene.tendon_inverse_settings()?;
    let estimate = with_model(
        scene,
        TendonInverse {
            scene,
            displacements: actuation,
            measured,
            settings,
            plot: plot.is_some(),
        },
    )?;
    status_stderr(&estimate.status);
    let text = match format {
        Format::Text => tendon_estimate_text(&estimate),
        Format::Json => json(&estimate)?,
        Format::Csv => run::tendon_estimate_csv(&estimate),
    };
    emit(&text, out.as_deref())?;
    draw_plot(plot.as_ref(), plot_size, estimate.figure.as_ref())?;
    Ok(estimate.status.exit_code)
}

/// Reads and parses the scene at `path`, and prints its warnings (unusual values, each at its line).
fn open_scene(path: &Path) -> Result<Scene, SceneError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(&origin, format!("cannot read: {e}")))?;
    let scene = Scene::parse(&text, &origin)?;
    for w in scene.warnings() {
        eprintln!("warning: {}", scene::locate(w, &text, &origin));
    }
    Ok(scene)
}

/// `error` at its line in the scene file `path`, when it names one of the file's keys.
fn in_scene(error: SceneError, path: Option<&Path>) -> SceneError {
    match path.and_then(|p| Some((std::fs::read_to_string(p).ok()?, p.display().to_string()))) {
        Some((text, origin)) => scene::locate(error, &text, &origin),
        None => error,
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let scene_file = match &cli.command {
        Command::Solve { scene, .. } | Command::Estimate { scene, .. } => Some(scene.clone()),
        _ => None,
    };
    let result = match cli.command {
        Command::Study(args) => return study::main(&args),
        Command::Monitor(args) => return host_sim::monitor::main(&args),
        Command::Reference(args) => return host_sim::monitor::reference::main(&args),
        Command::Validate { plots } => match thesis::validate() {
            Ok(v) => {
                if let Err(e) = emit(&report::validation(&v), None) {
                    return fail(&e);
                }
                if let Some(dir) = plots {
                    if let Err(e) = host_sim::plots::draw_validation(&v, &dir) {
                        return fail(&e);
                    }
                    if let Err(e) = emit(&format!("\nplots written to {}\n", dir.display()), None) {
                        return fail(&e);
                    }
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
                emit(
                    &report::inverse(name, &thesis::inverse_table(accurate)?),
                    None,
                )?;
            }
            Ok(exit::ANSWER)
        })(),
        Command::Calibrate {
            scene: Some(scene),
            data: Some(data),
            fit,
            out,
            format,
            plot,
            plot_size,
            ..
        } => calibrate::command::run(&calibrate::command::Args {
            scene,
            data,
            fit,
            out,
            format,
            plot: plot.map(|p| (p, plot_size)),
        }),
        Command::Calibrate {
            table, fit_density, ..
        } => (|| {
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
            emit(&report::calibration(&result?), None)?;
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
            plot,
            plot_size,
        } => (|| {
            let scene = open_scene(&scene)?;
            check_plot(plot.as_ref())?;
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
                        plot: plot.is_some(),
                    },
                )?,
                None => with_model(
                    &scene,
                    Solve {
                        scene: &scene,
                        load,
                        plot: plot.is_some(),
                    },
                )?,
            };
            status_stderr(&solution.status);
            let text = match format {
                Format::Text => solve_text(&solution),
                Format::Json => json(&solution)?,
                Format::Csv => run::solution_csv(&solution),
            };
            emit(&text, out.as_deref())?;
            draw_plot(plot.as_ref(), plot_size, solution.figure.as_ref())?;
            Ok(solution.status.exit_code)
        })(),
        Command::Estimate {
            scene,
            cables,
            displacements,
            tensions_measured,
            tension_std,
            tension_stds,
            format,
            out,
            plot,
            plot_size,
        } => (|| {
            let scene = open_scene(&scene)?;
            check_plot(plot.as_ref())?;
            if !scene.tendons.is_empty() {
                if cables.is_some() {
                    return Err(SceneError::new(
                        "--cables",
                        "the scene has [[tendon]]: it is estimated from the spool displacements \
                         (--displacements or [actuation] displacements_m) and optionally \
                         measured tensions (--tensions-measured); the tendon inverse does not \
                         use cable lengths",
                    ));
                }
                let tensions = TensionArgs {
                    tensions_n: tensions_measured,
                    std_n: tension_std,
                    stds_n: tension_stds,
                };
                return estimate_tendons(
                    &scene,
                    displacements,
                    tensions,
                    format,
                    out,
                    (plot, plot_size),
                );
            }
            for (given, key) in [
                (displacements.is_some(), "--displacements"),
                (tensions_measured.is_some(), "--tensions-measured"),
                (tension_std.is_some(), "--tension-std"),
                (tension_stds.is_some(), "--tension-stds"),
            ] {
                if given {
                    return Err(SceneError::new(
                        key,
                        "the scene has no [[tendon]] (this is for the tendon inverse; a scene \
                         without tendons is estimated from --cables)",
                    ));
                }
            }
            let Some(cables) = cables else {
                let message = "the scene has no [[tendon]]: give the measured cable lengths, \
                               --cables L1,L2,L3";
                let kind = clap::error::ErrorKind::MissingRequiredArgument;
                let mut cli = Cli::command();
                cli.build();
                let error = match cli.find_subcommand_mut("estimate") {
                    Some(estimate) => estimate.error(kind, message),
                    None => cli.error(kind, message),
                };
                let _ = error.print();
                return Ok(exit::USAGE);
            };
            if scene.cables.is_empty() {
                return Err(SceneError::new(
                    "--cables",
                    "the scene has no [[cable]] (and no [[tendon]]): nothing measures its shape",
                ));
            }
            let estimate = with_model(
                &scene,
                Estimate {
                    scene: &scene,
                    measured_m: cables,
                    plot: plot.is_some(),
                },
            )?;
            status_stderr(&estimate.status);
            let shape = estimate.numbers.as_ref().map(|n| n.shape.as_slice());
            let text = match format {
                Format::Text => estimate_text(&estimate),
                Format::Json => json(&estimate)?,
                Format::Csv => run::shape_csv(shape, &estimate.status),
            };
            emit(&text, out.as_deref())?;
            draw_plot(plot.as_ref(), plot_size, estimate.figure.as_ref())?;
            Ok(estimate.status.exit_code)
        })(),
    };
    match result {
        Ok(code) => ExitCode::from(code),
        Err(e) => fail(&in_scene(e, scene_file.as_deref())),
    }
}
