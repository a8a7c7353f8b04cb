//! `host-sim study`: the accuracy-vs-cost study of the model's variants.
//!
//! Every variant (f64 / f32 / f32 with micromath, quaternion / rotation-matrix / Lie-group frame,
//! 3D Cosserat / Kirchhoff / planar, 2 to 1000 steps per section) is solved cold on each scene and
//! compared with a converged f64 reference: tip, backbone and cable-length errors, deterministic work
//! (sweeps times RK4 steps) and host wall time. Add `model_core::reduction::choose`'s picks per
//! tolerance, and the firmware's QEMU instruction counts joined with the host's f32 errors. The
//! tendon scenes (`tendon.rs`) add the tendon models against the discrete guides, displacement
//! control against tensions, the firmware's tendon counts and `choose_tendons`' picks. The result is
//! `accuracy_cost.md`, `accuracy_cost.csv`, `pareto.svg` / `pareto.png` and `tendon_pareto.svg` /
//! `.png` in `--out`.
//!
//! micromath is a compile-time feature of model-core, so its rows come from a second build
//! (`--fast-math-only --rows-out FILE`) merged into the report with `--merge FILE`;
//! `report/study.sh` runs both.

mod cases;
mod findings;
mod mcu;
mod measure;
mod numbers;
mod pareto;
mod plot;
mod reductions;
mod tendon;
mod variants;
mod write;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use model_core::Scalar;
use serde::{Deserialize, Serialize};

use cases::Scene;
use host_sim::scene::SceneError;
use measure::{Reference, Row, Timing};
use reductions::ReductionCase;
use variants::{Arithmetic, Family};

/// Steps per section at which f32 is compared with f64 on the same grid.
const FLOOR_STEPS: [u16; 2] = [20, 100];

/// Arguments of `host-sim study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A few step counts (5, 20, 100), one tolerance and short timings: the same checks, for CI.
    #[arg(long)]
    quick: bool,
    /// Directory for accuracy_cost.md, accuracy_cost.csv, pareto.svg and pareto.png.
    #[arg(long, default_value = "report")]
    out: PathBuf,
    /// Only the f32 micromath rows, written as JSON to --rows-out (a build with the `fast-math`
    /// feature: `cargo run --release -p host-sim --features fast-math -- study --fast-math-only`).
    #[arg(long, requires = "rows_out")]
    fast_math_only: bool,
    /// Where --fast-math-only writes its rows.
    #[arg(long)]
    rows_out: Option<PathBuf>,
    /// Rows of a --fast-math-only run to merge into the report.
    #[arg(long)]
    merge: Option<PathBuf>,
    /// Only these scenes (keys: exp2-40.2g, exp2-83.2g, golden, tendon-bench,
    /// tendon-two-section); default all.
    #[arg(long, value_delimiter = ',')]
    scenes: Vec<String>,
}

/// Rows of the micromath build, as passed between the two runs.
#[derive(Debug, Serialize, Deserialize)]
struct MicromathRows {
    quick: bool,
    rows: Vec<Row>,
}

/// One pass/fail check of the study.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    /// What is checked.
    pub what: String,
    /// Whether it held.
    pub passed: bool,
}

/// The machine and the code the numbers come from.
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    /// `/proc/cpuinfo`'s model name.
    pub cpu: String,
    /// Available parallelism.
    pub cores: usize,
    /// `/proc/loadavg` before and after.
    pub load_before: String,
    /// See `load_before`.
    pub load_after: String,
    /// `rustc --version`.
    pub rustc: String,
    /// `git describe --always --dirty`.
    pub commit: String,
    /// `date -u`.
    pub date: String,
}

/// A scene with its reference.
#[derive(Clone, Debug, PartialEq)]
pub struct StudiedScene {
    /// The scene.
    pub scene: Scene,
    /// Its reference.
    pub reference: Reference,
    /// Whether the planar reduction applies.
    pub planar: bool,
}

/// Everything the report is written from.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// Quick mode.
    pub quick: bool,
    /// Steps per section studied.
    pub steps: Vec<u16>,
    /// Machine and code.
    pub machine: Machine,
    /// Scenes and references.
    pub scenes: Vec<StudiedScene>,
    /// One per variant and scene.
    pub rows: Vec<Row>,
    /// Whether the micromath rows were merged in.
    pub micromath: bool,
    /// `choose`'s picks.
    pub reductions: Vec<ReductionCase>,
    /// The MCU join.
    pub mcu: mcu::Mcu,
    /// f32 against f64 on the same grid, per scene.
    pub floors: Vec<measure::F32Floor>,
    /// The tendon scenes (none when `--scenes` names none of them).
    pub tendon: Option<tendon::TendonStudy>,
    /// Wall time of this run, s.
    pub elapsed_s: f64,
    /// Its checks.
    pub checks: Vec<Check>,
}

fn command_output(program: &str, args: &[&str]) -> String {
    std::process::Command::new(program)
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

fn read_trimmed(path: &str) -> String {
    std::fs::read_to_string(path)
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "unknown".into())
}

fn machine() -> Machine {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    Machine {
        cpu,
        cores: std::thread::available_parallelism().map_or(0, |n| n.get()),
        load_before: read_trimmed("/proc/loadavg"),
        load_after: String::new(),
        rustc: command_output("rustc", &["--version"]),
        commit: command_output("git", &["describe", "--always", "--dirty", "--abbrev=7"]),
        date: command_output("date", &["-u", "+%Y-%m-%d %H:%M UTC"]),
    }
}

/// Whether this build's f32 hot-path functions are micromath's (model-core's `fast-math`).
fn micromath_active() -> bool {
    let x = 2.0f32;
    (x.sqrt_hot() - x.sqrt()).abs() > 1e-6
}

fn scenes(keys: &[String]) -> Result<Vec<StudiedScene>, SceneError> {
    let all = Scene::all()?;
    let tendon_keys = tendon::keys();
    if let Some(unknown) = keys
        .iter()
        .find(|k| !all.iter().any(|s| &s.key == *k) && !tendon_keys.contains(&k.as_str()))
    {
        let known: Vec<&str> = all
            .iter()
            .map(|s| s.key.as_str())
            .chain(tendon_keys)
            .collect();
        return Err(SceneError::new(
            "--scenes",
            format!("unknown \"{unknown}\" (known: {})", known.join(", ")),
        ));
    }
    let mut out = Vec::new();
    for scene in all
        .into_iter()
        .filter(|s| keys.is_empty() || keys.contains(&s.key))
    {
        let reference = measure::reference(&scene)?;
        eprintln!(
            "{}: reference converged; grids of {} and {} steps differ by {:.1e} m",
            scene.key,
            measure::REFERENCE_STEPS,
            measure::CHECK_STEPS,
            reference.grid_difference_m
        );
        let planar = scene.planar()?;
        out.push(StudiedScene {
            scene,
            reference,
            planar,
        });
    }
    Ok(out)
}

fn measure_all(
    scenes: &[StudiedScene],
    arithmetics: &[Arithmetic],
    steps: &[u16],
    timing: Timing,
) -> Result<Vec<Row>, SceneError> {
    let mut rows = Vec::new();
    for s in scenes {
        let families = variants::families(arithmetics, s.planar);
        for family in families {
            for &n in steps {
                rows.push(measure::measure(&s.scene, &s.reference, family, n, timing)?);
            }
        }
        eprintln!("{}: {} variants measured", s.scene.key, rows.len());
    }
    Ok(rows)
}

/// Marks each scene's Pareto fronts (work and host time against error) over its converged rows.
pub fn mark_fronts(rows: &mut [Row]) {
    let keys: Vec<String> = rows.iter().map(|r| r.scene.clone()).collect();
    for key in keys.iter() {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| &rows[i].scene == key).collect();
        let point = |r: &Row, cost: f64| (cost, r.error_m().unwrap_or(f64::NAN));
        let work: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| point(&rows[i], rows[i].work()))
            .collect();
        let time: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| point(&rows[i], rows[i].host_time_us))
            .collect();
        for ((&i, w), t) in idx
            .iter()
            .zip(pareto::front(&work))
            .zip(pareto::front(&time))
        {
            rows[i].front_work = w;
            rows[i].front_time = t;
        }
    }
}

fn check(checks: &mut Vec<Check>, passed: bool, what: String) {
    checks.push(Check { what, passed });
}

fn checks(study: &Study, merged: Option<usize>) -> Vec<Check> {
    let mut out = Vec::new();
    for s in &study.scenes {
        let d = s.reference.grid_difference_m;
        check(
            &mut out,
            d <= measure::REFERENCE_AGREEMENT_M,
            format!(
                "{}: reference grids ({} and {} steps per section) agree to {d:.1e} m (limit {:.0e} m)",
                s.scene.key,
                measure::REFERENCE_STEPS,
                measure::CHECK_STEPS,
                measure::REFERENCE_AGREEMENT_M
            ),
        );
        let rows: Vec<&Row> = study
            .rows
            .iter()
            .filter(|r| r.scene == s.scene.key)
            .collect();
        let bad: Vec<String> = rows
            .iter()
            .filter(|r| {
                !(r.host_time_us.is_finite() && r.work_rk4_steps.is_finite())
                    || (r.converged() && !r.error_m().is_some_and(f64::is_finite))
            })
            .map(|r| format!("{} at {}", r.family.label(), r.steps_per_section))
            .collect();
        check(
            &mut out,
            bad.is_empty(),
            format!(
                "{}: every converged row has finite errors, every row a finite cost ({} rows{})",
                s.scene.key,
                rows.len(),
                if bad.is_empty() {
                    String::new()
                } else {
                    format!("; not: {}", bad.join(", "))
                }
            ),
        );
        // The fewest and the most steps that give an answer (a grid too coarse for the load refuses:
        // `UnderResolved`).
        let reference_errors: Vec<f64> = rows
            .iter()
            .filter(|r| r.family == Family::REFERENCE)
            .filter_map(|r| r.error_m())
            .collect();
        let coarse = reference_errors.first().copied();
        let fine = reference_errors.last().copied();
        check(
            &mut out,
            matches!((coarse, fine), (Some(c), Some(f)) if f < c / 100.0),
            format!(
                "{}: the f64 quaternion 3D error shrinks with steps ({:.1e} m at the fewest answering, {:.1e} m at the most)",
                s.scene.key,
                coarse.unwrap_or(f64::NAN),
                fine.unwrap_or(f64::NAN)
            ),
        );
    }
    for r in &study.reductions {
        check(
            &mut out,
            r.meets(),
            format!(
                "{} ({}): the pick for {:.0e} m, {} at {} steps, is within it against the study's reference ({:.2e} m)",
                r.scene,
                r.case_label,
                r.tolerance_m,
                r.picked.label(),
                r.picked_steps,
                r.picked_study_error_m.unwrap_or(f64::NAN)
            ),
        );
    }
    for m in &study.mcu.rows {
        check(
            &mut out,
            m.qemu.converged && m.host_f32.converged() && m.host_f64.converged(),
            format!(
                "MCU join at {} steps per section: QEMU and host solves converged",
                m.qemu.steps_per_section
            ),
        );
    }
    if let Some(n) = merged {
        check(&mut out, n > 0, format!("{n} micromath rows merged"));
    }
    if let Some(t) = &study.tendon {
        out.extend(tendon::checks(t));
    }
    out
}

fn read_micromath(path: &Path, quick: bool) -> Result<Vec<Row>, SceneError> {
    let at = || path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(at(), format!("cannot read: {e}")))?;
    let rows: MicromathRows =
        serde_json::from_str(&text).map_err(|e| SceneError::new(at(), e.to_string()))?;
    if rows.quick != quick {
        return Err(SceneError::new(
            at(),
            "written by a run of the other mode (--quick differs)",
        ));
    }
    Ok(rows.rows)
}

fn fast_math_only(args: &Args, steps: &[u16], timing: Timing) -> Result<(), SceneError> {
    if !micromath_active() {
        return Err(SceneError::new(
            "--fast-math-only",
            "this build's f32 sqrt is exact: build with `--features fast-math`",
        ));
    }
    let path = args
        .rows_out
        .as_ref()
        .ok_or_else(|| SceneError::new("--rows-out", "required with --fast-math-only"))?;
    let scenes = scenes(&args.scenes)?;
    let rows = measure_all(&scenes, &[Arithmetic::F32Micromath], steps, timing)?;
    let text = serde_json::to_string(&MicromathRows {
        quick: args.quick,
        rows,
    })
    .map_err(|e| SceneError::new("rows", e.to_string()))?;
    std::fs::write(path, text)
        .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}")))
}

fn run(args: &Args) -> Result<Study, SceneError> {
    let started = Instant::now();
    let mut machine = machine();
    let steps: Vec<u16> = if args.quick {
        variants::QUICK_STEPS.to_vec()
    } else {
        variants::FULL_STEPS.to_vec()
    };
    let timing = if args.quick {
        Timing::QUICK
    } else {
        Timing::FULL
    };
    let tolerances: &[f64] = if args.quick {
        &reductions::QUICK_TOLERANCES_M
    } else {
        &reductions::FULL_TOLERANCES_M
    };
    if micromath_active() {
        return Err(SceneError::new(
            "study",
            "this build has model-core's fast-math feature: its f32 rows are micromath's; \
             run it with --fast-math-only, or use report/study.sh",
        ));
    }
    let scenes = scenes(&args.scenes)?;
    let mut rows = measure_all(&scenes, &[Arithmetic::F64, Arithmetic::F32], &steps, timing)?;
    let merged = match &args.merge {
        Some(path) => {
            let extra: Vec<Row> = read_micromath(path, args.quick)?
                .into_iter()
                .filter(|r| scenes.iter().any(|s| s.scene.key == r.scene))
                .collect();
            let n = extra.len();
            rows.extend(extra);
            Some(n)
        }
        None => None,
    };
    mark_fronts(&mut rows);
    let mut reductions = Vec::new();
    for s in &scenes {
        reductions.extend(reductions::study(
            &s.scene,
            &s.reference,
            tolerances,
            timing,
        )?);
    }
    eprintln!("reductions: {} picks", reductions.len());
    let mcu = mcu::study(timing)?;
    let mut floors = Vec::new();
    for s in &scenes {
        for steps in FLOOR_STEPS {
            floors.push(measure::f32_floor(&s.scene, steps)?);
        }
    }
    let tendon_keys: Vec<String> = args
        .scenes
        .iter()
        .filter(|k| tendon::keys().contains(&k.as_str()))
        .cloned()
        .collect();
    let tendon = if args.scenes.is_empty() || !tendon_keys.is_empty() {
        Some(tendon::run(args.quick, &tendon_keys, timing)?)
    } else {
        None
    };
    machine.load_after = read_trimmed("/proc/loadavg");
    let mut study = Study {
        quick: args.quick,
        steps,
        machine,
        scenes,
        rows,
        micromath: merged.is_some(),
        reductions,
        mcu,
        floors,
        tendon,
        elapsed_s: started.elapsed().as_secs_f64(),
        checks: Vec::new(),
    };
    study.checks = checks(&study, merged);
    write::all(&study, &args.out)?;
    plot::pareto(&study, &args.out)?;
    if let Some(t) = &study.tendon {
        tendon::plot(t, &args.out)?;
    }
    Ok(study)
}

/// Runs `host-sim study`; non-zero exit on an error or a failed check.
pub fn main(args: &Args) -> ExitCode {
    let steps: &[u16] = if args.quick {
        &variants::QUICK_STEPS
    } else {
        &variants::FULL_STEPS
    };
    if args.fast_math_only {
        let timing = if args.quick {
            Timing::QUICK
        } else {
            Timing::FULL
        };
        return match fast_math_only(args, steps, timing) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        };
    }
    match run(args) {
        Ok(study) => {
            for c in &study.checks {
                println!("{} {}", if c.passed { "ok  " } else { "FAIL" }, c.what);
            }
            println!(
                "report written to {} ({:.1} s)",
                args.out.display(),
                study.elapsed_s
            );
            if study.checks.iter().all(|c| c.passed) {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
