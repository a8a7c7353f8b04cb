//! The Cortex-M4F's cost of the tendon model: the firmware bench's tendon cases
//! (`firmware/expected/bench.run`: discrete guides, f32, its loop's steps per section) joined with
//! the same model on the host, on the same robot and actuation: the firmware's tendon robot (the
//! bench with steel tendons behind a feed from the spools) along its recorded actuation
//! (`firmware/src/tendon.rs`).
//!
//! host-sim cannot depend on the firmware crate, so the robot's constants and the actuation's
//! displacements are repeated here; the host's f64 model at the firmware's steps must reproduce the
//! firmware's recorded f64 trajectory (`firmware/src/tendon_trajectory.in`) or the study fails.

use std::hint::black_box;

use model_core::reduction::TendonModel;
use model_core::{DisplacementSolve, Scalar, TendonEquilibrium};
use nalgebra::Vector3;

use super::super::mcu::{BENCH_RUN, bench_error, fields, lower_bound_ms, number};
use super::super::measure::{Timing, time_cases, to_f64};
use super::actuation::Actuator;
use super::cases::{Actuation, Robot, TendonScene};
use super::measure::{REFERENCE_STEPS, Solver};
use host_sim::scene::SceneError;

/// The firmware's recorded f64 trajectory (`TRAJECTORY` of `firmware/src/tendon.rs`).
const TRAJECTORY_IN: &str = include_str!("../../../../firmware/src/tendon_trajectory.in");

/// `firmware/src/tendon.rs`'s `AXIAL_STIFFNESS_N`: 0.3 mm steel wire, N.
pub const FIRMWARE_AXIAL_STIFFNESS_N: f64 = 14_000.0;
/// `firmware/src/tendon.rs`'s `FEED_LENGTH_M`, m.
pub const FIRMWARE_FEED_LENGTH_M: f64 = 0.3;
/// The host's f64 model must reproduce the firmware's recorded trajectory to this (tips in m,
/// tensions in N), as the firmware's own host test holds it.
pub const TRAJECTORY_AGREEMENT: f64 = 1e-9;

/// `firmware/src/tendon.rs`'s `displacements_m`: the recorded actuation at `tick`, m (tendon 0
/// taken in, tendon 1 paid out until slack, tendon 2 from slack to taut).
pub fn firmware_displacements_m(tick: usize) -> [f64; 3] {
    let k = tick as f64;
    [
        0.05e-3 + 0.12e-3 * k,
        0.12e-3 - 0.2e-3 * k,
        -0.05e-3 + 0.01e-3 * k,
    ]
}

/// One tick of the firmware's f64 trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tick {
    /// Tensions, N.
    pub tensions_n: [f64; 3],
    /// Tip, m.
    pub tip_m: [f64; 3],
}

fn trajectory_error(reason: impl Into<String>) -> SceneError {
    SceneError::new("firmware/src/tendon_trajectory.in", reason)
}

/// The three numbers after `key: [` on `line`.
fn triple(line: &str, key: &str) -> Result<[f64; 3], SceneError> {
    let start = line
        .find(key)
        .ok_or_else(|| trajectory_error(format!("no {key}")))?;
    let rest = line.get(start + key.len()..).unwrap_or("");
    let rest = rest
        .trim_start()
        .strip_prefix('[')
        .ok_or_else(|| trajectory_error(format!("{key} is not a list")))?;
    let end = rest
        .find(']')
        .ok_or_else(|| trajectory_error(format!("{key} is not closed")))?;
    let values: Vec<f64> = rest
        .get(..end)
        .unwrap_or("")
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| trajectory_error(format!("{key}: {e}")))?;
    match values.as_slice() {
        [a, b, c] => Ok([*a, *b, *c]),
        _ => Err(trajectory_error(format!("{key}: not three values"))),
    }
}

/// The ticks of `tendon_trajectory.in` (a Rust array of `TickReference { tensions_n, tip_m, slack }`).
pub fn trajectory(text: &str) -> Result<Vec<Tick>, SceneError> {
    let ticks: Vec<Tick> = text
        .lines()
        .filter(|l| l.contains("TickReference"))
        .map(|l| {
            Ok(Tick {
                tensions_n: triple(l, "tensions_n:")?,
                tip_m: triple(l, "tip_m:")?,
            })
        })
        .collect::<Result<_, SceneError>>()?;
    if ticks.len() < 2 {
        return Err(trajectory_error("fewer than two ticks"));
    }
    Ok(ticks)
}

/// One tendon case of the firmware bench.
#[derive(Clone, Debug, PartialEq)]
pub struct QemuTendon {
    /// `tendon_forward_cold`, `tendon_displacement_cold`, `tendon_update_warm` or
    /// `tendon_update_warm_median` (or the same of `two_section_`).
    pub case: String,
    /// Steps per section.
    pub steps_per_section: u16,
    /// RK4 steps per sweep.
    pub total_steps: u32,
    /// Instructions (the warm update: its costliest tick; the median: its median tick).
    pub instructions: u64,
    /// Sweeps (the warm update: the most of any tick; the median: the median tick's).
    pub sweeps: u32,
    /// Whether it converged (the warm update: every tick).
    pub converged: bool,
    /// The firmware's tip error, m: against its f64 trajectory at the same steps (`tendon_`), or
    /// against the tick's own forward solve (`two_section_`).
    pub tip_error_m: f64,
}

impl QemuTendon {
    /// Instructions per sweep.
    pub fn per_sweep(&self) -> f64 {
        self.instructions as f64 / f64::from(self.sweeps.max(1))
    }

    /// Milliseconds at the MCU's clock if each instruction took one cycle: a lower bound.
    pub fn lower_bound_ms(&self) -> f64 {
        lower_bound_ms(self.instructions)
    }
}

/// The firmware bench's tendon cases.
pub fn qemu_tendon_cases(text: &str) -> Result<Vec<QemuTendon>, SceneError> {
    qemu_cases(text, "tendon_", &CASES)
}

/// The firmware bench's cases whose names start with `prefix`; every one of `cases` must be there,
/// all at one step count.
pub fn qemu_cases(text: &str, prefix: &str, cases: &[&str]) -> Result<Vec<QemuTendon>, SceneError> {
    let mut out = Vec::new();
    let start = format!("bench case={prefix}");
    for line in text.lines().filter(|l| l.starts_with(&start)) {
        let f = fields(line);
        let nm: f64 = number(&f, "tip_error_nm")?;
        out.push(QemuTendon {
            case: f.get("case").copied().unwrap_or("").to_string(),
            steps_per_section: number(&f, "steps_per_section")?,
            total_steps: number(&f, "total_steps")?,
            instructions: number(&f, "instructions")?,
            sweeps: number(&f, "sweeps")?,
            converged: f.get("converged") == Some(&"true"),
            tip_error_m: nm * 1e-9,
        });
    }
    for want in cases {
        if !out.iter().any(|c| c.case == *want) {
            return Err(bench_error(format!("no {want} line")));
        }
    }
    if out
        .iter()
        .any(|c| c.steps_per_section != out.first().map_or(0, |f| f.steps_per_section))
    {
        return Err(bench_error(format!(
            "{prefix}cases at different step counts"
        )));
    }
    Ok(out)
}

/// The firmware bench's tendon cases, in the table's order.
pub const CASES: [&str; 4] = [
    "tendon_forward_cold",
    "tendon_displacement_cold",
    "tendon_update_warm",
    "tendon_update_warm_median",
];

/// One solve of the host's path.
#[derive(Clone, Debug, PartialEq)]
pub struct HostSolve {
    /// Sweeps.
    pub sweeps: u32,
    /// Median wall time, us.
    pub host_time_us: f64,
    /// Whether it is an answer.
    pub converged: bool,
    /// Tip, m.
    pub tip_m: Vector3<f64>,
    /// Tensions, N.
    pub tensions_n: Vec<f64>,
}

/// The firmware's actuation solved on the host at one precision and step count.
#[derive(Clone, Debug, PartialEq)]
pub struct HostPath {
    /// The cold forward solve from tick 0's tensions.
    pub forward: HostSolve,
    /// The cold displacement-controlled solve of tick 0, then the warm updates of every later
    /// tick.
    pub ticks: Vec<HostSolve>,
}

impl HostPath {
    /// The warm updates (every tick but the first).
    pub fn warm(&self) -> &[HostSolve] {
        self.ticks.get(1..).unwrap_or(&[])
    }

    /// The costliest warm update by host time, and the most sweeps of any.
    pub fn worst_warm(&self) -> Option<(f64, u32)> {
        let time = self
            .warm()
            .iter()
            .map(|t| t.host_time_us)
            .reduce(f64::max)?;
        let sweeps = self.warm().iter().map(|t| t.sweeps).max()?;
        Some((time, sweeps))
    }

    /// Sweeps, host time and whether it converged, of what the firmware case `case` measures (by
    /// its name's ending): the cold forward solve, the cold displacement-controlled solve of the
    /// first tick, the median warm update, or the costliest warm update (with the most sweeps of
    /// any); the warm ones converged when every warm update did.
    pub fn case(&self, case: &str) -> (u32, f64, bool) {
        let none = (0, f64::NAN, false);
        let warm_ok = self.warm().iter().all(|t| t.converged);
        if case.ends_with("forward_cold") {
            (
                self.forward.sweeps,
                self.forward.host_time_us,
                self.forward.converged,
            )
        } else if case.ends_with("displacement_cold") {
            self.ticks
                .first()
                .map_or(none, |t| (t.sweeps, t.host_time_us, t.converged))
        } else if case.ends_with("update_warm_median") {
            self.median_warm()
                .map_or(none, |(time, sweeps)| (sweeps, time, warm_ok))
        } else {
            self.worst_warm()
                .map_or(none, |(time, sweeps)| (sweeps, time, warm_ok))
        }
    }

    /// The median warm update (the upper one of an even count), its host time and sweeps: ordered
    /// by sweeps, which are deterministic (the firmware orders its ticks by instructions, which
    /// follow the sweeps), ties by host time.
    pub fn median_warm(&self) -> Option<(f64, u32)> {
        let mut warm: Vec<(f64, u32)> = self
            .warm()
            .iter()
            .map(|t| (t.host_time_us, t.sweeps))
            .collect();
        warm.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)));
        warm.get(warm.len() / 2).copied()
    }
}

/// The firmware's robot as a tendon scene, actuated at tick 0's tensions.
pub fn firmware_scene(ticks: &[Tick]) -> Result<TendonScene, SceneError> {
    let first = ticks.first().ok_or_else(|| trajectory_error("no ticks"))?;
    Ok(TendonScene {
        key: "tendon-firmware".into(),
        title: format!(
            "the firmware's tendon robot: the bench with steel tendons ({} N) behind a {} m feed, \
             along its recorded actuation ({} ticks, no tip force)",
            FIRMWARE_AXIAL_STIFFNESS_N,
            FIRMWARE_FEED_LENGTH_M,
            ticks.len()
        ),
        robot: Robot::Firmware {
            axial_stiffness_n: FIRMWARE_AXIAL_STIFFNESS_N,
            feed_length_m: FIRMWARE_FEED_LENGTH_M,
        },
        cases: vec![Actuation {
            label: "tick 0".into(),
            tensions_n: first.tensions_n.to_vec(),
            force_n: [0.0; 3],
            golden_tip_m: None,
            golden_paths_m: Vec::new(),
        }],
    })
}

/// One solve's record: its sweeps, time, whether it is an answer, its tip and tensions.
pub fn solved<T: Scalar>(eq: &TendonEquilibrium<T>, sweeps: u32, time: f64, ok: bool) -> HostSolve {
    HostSolve {
        sweeps,
        host_time_us: time,
        converged: ok && eq.is_success(),
        tip_m: to_f64(&eq.equilibrium.tip_position_m),
        tensions_n: eq.tensions_n.iter().map(|t| t.to_f64()).collect(),
    }
}

/// The firmware's path on the host in `T` at `steps`, timed with `timing` (`None`: untimed, the
/// reference). `warm_as_firmware_reference`: later ticks solved as the firmware's f64 reference
/// does (`solve_displacements` from the previous equilibrium) instead of `update_displacements`.
pub fn host_path<T: Scalar>(
    scene: &TendonScene,
    steps: u16,
    ticks: usize,
    timing: Option<Timing>,
    warm_as_firmware_reference: bool,
) -> Result<HostPath, SceneError> {
    let solver = Solver::<T>::new(scene, steps, TendonModel::DiscreteGuides)?;
    let actuator = Actuator::new(&solver);
    let time = |run: &mut dyn FnMut() -> Result<(), SceneError>| -> Result<f64, SceneError> {
        match timing {
            Some(t) => time_cases(1, t, |_| run()).map(|(us, _)| us),
            None => Ok(f64::NAN),
        }
    };
    let eq = solver.solve(0)?;
    let t = time(&mut || {
        black_box(solver.solve(0)?);
        Ok(())
    })?;
    let forward = solved(&eq, u32::from(eq.equilibrium.report.sweeps), t, true);
    let mut out: Vec<HostSolve> = Vec::new();
    let mut previous: Option<DisplacementSolve<T>> = None;
    for tick in 0..ticks {
        let d: Vec<T> = firmware_displacements_m(tick)
            .iter()
            .map(|x| T::lit(*x))
            .collect();
        let step = || -> Result<DisplacementSolve<T>, SceneError> {
            match (&previous, warm_as_firmware_reference) {
                (None, _) => actuator.cold(0, &d),
                (Some(p), false) => actuator.warm(0, &d, p),
                (Some(p), true) => actuator.cold_from(0, &d, &p.solved),
            }
        };
        let solve = step()?;
        let t = time(&mut || {
            black_box(step()?);
            Ok(())
        })?;
        out.push(solved(&solve.solved, solve.sweeps, t, solve.is_success()));
        previous = Some(solve);
    }
    Ok(HostPath {
        forward,
        ticks: out,
    })
}

/// One firmware case joined with the host.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonMcuRow {
    /// What QEMU measured.
    pub qemu: QemuTendon,
    /// Host f32 sweeps (the warm update: the most of any tick; the median: its median tick's).
    pub host_sweeps: u32,
    /// Host f32 time, us (the warm update: its costliest tick; the median: its median tick).
    pub host_f32_us: f64,
    /// Host f64 time at the same steps, us.
    pub host_f64_us: f64,
    /// Whether the host's f32 and f64 solves converged.
    pub host_converged: bool,
    /// The host f32 tip against the converged f64 reference, m (the warm update: its worst tick).
    pub f32_error_m: f64,
    /// The f64 model at the same steps against the converged reference, m: its discretisation.
    pub f64_error_m: f64,
    /// The host f32 tip against the firmware's f64 trajectory (what the firmware's `tip_error_nm`
    /// measures), m.
    pub host_vs_trajectory_m: f64,
}

/// The tendon MCU join.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonMcu {
    /// The robot and actuation.
    pub scene: TendonScene,
    /// Steps per section of the firmware's cases.
    pub steps_per_section: u16,
    /// Ticks of the recorded actuation.
    pub ticks: usize,
    /// Largest difference between the host's f64 model at those steps and the firmware's recorded
    /// trajectory (tips, m, and tensions, N).
    pub trajectory_difference: f64,
    /// Whether every reference solve converged.
    pub reference_converged: bool,
    /// One row per firmware case.
    pub rows: Vec<TendonMcuRow>,
}

fn max_tip(a: &[HostSolve], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x.tip_m - y).norm())
        .fold(0.0, f64::max)
}

/// The join: the firmware's tendon cases, and the same solves on the host in f32 and f64 at the
/// firmware's steps, against the discrete-guide f64 reference at [`REFERENCE_STEPS`].
pub fn study(timing: Timing) -> Result<TendonMcu, SceneError> {
    let qemu = qemu_tendon_cases(BENCH_RUN)?;
    let steps = qemu.first().map_or(0, |q| q.steps_per_section);
    let ticks = trajectory(TRAJECTORY_IN)?;
    let scene = firmware_scene(&ticks)?;
    let n = ticks.len();
    let reference = host_path::<f64>(&scene, REFERENCE_STEPS, n, None, false)?;
    let reference_converged =
        reference.forward.converged && reference.ticks.iter().all(|t| t.converged);
    let recorded = host_path::<f64>(&scene, steps, n, None, true)?;
    let trajectory_difference = recorded
        .ticks
        .iter()
        .zip(&ticks)
        .map(|(h, t)| {
            let tip = (h.tip_m - Vector3::from(t.tip_m)).norm();
            let tension = h
                .tensions_n
                .iter()
                .zip(t.tensions_n)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if h.converged {
                tip.max(tension)
            } else {
                f64::INFINITY
            }
        })
        .fold(0.0, f64::max);
    let narrow = host_path::<f32>(&scene, steps, n, Some(timing), false)?;
    let wide = host_path::<f64>(&scene, steps, n, Some(timing), false)?;
    let ref_tips: Vec<Vector3<f64>> = reference.ticks.iter().map(|t| t.tip_m).collect();
    let recorded_tips: Vec<Vector3<f64>> = ticks.iter().map(|t| Vector3::from(t.tip_m)).collect();
    let mut rows = Vec::new();
    for q in qemu {
        let error = |p: &HostPath, against: &[Vector3<f64>], forward: &Vector3<f64>| match q
            .case
            .as_str()
        {
            "tendon_forward_cold" => (p.forward.tip_m - forward).norm(),
            "tendon_displacement_cold" => max_tip(p.ticks.get(..1).unwrap_or(&[]), against),
            _ => max_tip(p.warm(), against.get(1..).unwrap_or(&[])),
        };
        let (host_sweeps, host_f32_us, f32_ok) = narrow.case(&q.case);
        let (_, host_f64_us, f64_ok) = wide.case(&q.case);
        let first_recorded = recorded_tips.first().copied().unwrap_or_default();
        rows.push(TendonMcuRow {
            host_sweeps,
            host_f32_us,
            host_f64_us,
            host_converged: f32_ok && f64_ok,
            f32_error_m: error(&narrow, &ref_tips, &reference.forward.tip_m),
            f64_error_m: error(&wide, &ref_tips, &reference.forward.tip_m),
            host_vs_trajectory_m: error(&narrow, &recorded_tips, &first_recorded),
            qemu: q,
        });
    }
    Ok(TendonMcu {
        scene,
        steps_per_section: steps,
        ticks: n,
        trajectory_difference,
        reference_converged,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_firmware_files_parse() {
        let ticks = trajectory(TRAJECTORY_IN).expect("trajectory");
        assert_eq!(ticks.len(), 12);
        assert!(ticks[0].tensions_n[0] > 0.5 && ticks[0].tensions_n[2] == 0.0);
        let cases = qemu_tendon_cases(BENCH_RUN).expect("tendon cases");
        assert_eq!(cases.len(), CASES.len());
        assert!(cases.iter().all(|c| c.instructions > 0 && c.sweeps > 0));
        assert!(trajectory("TickReference { tensions_n: [1, 2], tip_m: [0, 0, 0] }").is_err());
        assert!(qemu_tendon_cases("bench case=tendon_forward_cold steps_per_section=20").is_err());
    }
}
