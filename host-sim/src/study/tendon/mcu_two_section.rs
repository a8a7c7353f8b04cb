//! The Cortex-M4F's cost of the two-section, six-tendon robot: the firmware bench's `two_section_*`
//! cases (`firmware/expected/bench.run`, the bench image built with its `two-section-bench`
//! feature) joined with the same path on the host. The robot is the golden two-section robot
//! (`model_checks::reference::tendon_two_section`, gravity) with the firmware tendon robot's steel
//! tendons behind their feed ([`FIRMWARE_AXIAL_STIFFNESS_N`], [`FIRMWARE_FEED_LENGTH_M`]), along
//! `reference::tendon_two_section_actuation_n`. Each tick's spool displacements are those that
//! hold a forward solve at that tick's tensions, in the path's own precision, and the update must
//! find that solve's tip: the firmware's `tip_error_nm` measures the same.

use std::hint::black_box;

use model_checks::reference::{
    TENDON_TWO_SECTION_TICKS, tendon_two_section, tendon_two_section_actuation_n,
};
use model_core::{
    DisplacementSettings, DisplacementSolve, Model, Scalar, ShootingSettings, TendonEquilibrium,
    Tendons, TipLoad,
};

use super::super::mcu::BENCH_RUN;
use super::super::measure::{Timing, time_cases};
use super::mcu::{
    FIRMWARE_AXIAL_STIFFNESS_N, FIRMWARE_FEED_LENGTH_M, HostPath, QemuTendon, qemu_cases, solved,
};
use host_sim::scene::SceneError;

/// The firmware bench's two-section cases, in the table's order.
pub const CASES: [&str; 4] = [
    "two_section_forward_cold",
    "two_section_displacement_cold",
    "two_section_update_warm",
    "two_section_update_warm_median",
];

/// Gravity of the bench's two-section robot, m/s^2.
const GRAVITY_M_S2: f64 = 9.81;

/// The host's tip against the forward solve whose displacements a tick used must be within this,
/// m, in f32 (as `tests/tendon.rs` holds it; QEMU's too).
pub const F32_TIP_AGREEMENT_M: f64 = 1e-5;
/// The same in f64, m.
pub const F64_TIP_AGREEMENT_M: f64 = 1e-9;

/// One firmware case joined with the host.
#[derive(Clone, Debug, PartialEq)]
pub struct TwoSectionRow {
    /// What QEMU measured (its `tip_error_m`: the tip against the tick's forward solve).
    pub qemu: QemuTendon,
    /// Host f32 sweeps (the warm update: the most of any tick; the median: its median tick's).
    pub host_sweeps: u32,
    /// Host f64 sweeps, the same way.
    pub host_f64_sweeps: u32,
    /// Host f32 time, us (the warm update: its costliest tick; the median: its median tick).
    pub host_f32_us: f64,
    /// Host f64 time, us.
    pub host_f64_us: f64,
    /// Whether the host's f32 and f64 solves converged.
    pub host_converged: bool,
    /// The host f32 tip against the tick's f32 forward solve, m (the warm update: its worst tick).
    pub f32_tip_m: f64,
    /// The host f64 tip against the tick's f64 forward solve, m.
    pub f64_tip_m: f64,
}

/// The two-section MCU join.
#[derive(Clone, Debug, PartialEq)]
pub struct TwoSectionMcu {
    /// Steps per section of the firmware's cases.
    pub steps_per_section: u16,
    /// Ticks of the actuation.
    pub ticks: usize,
    /// One row per firmware case.
    pub rows: Vec<TwoSectionRow>,
}

/// The path on the host in `T`: the forward solves, the displacement solves, and each solve's tip
/// against its tick's forward solve (the forward solve's own: zero).
struct Path {
    host: HostPath,
    /// Per tick, the displacement solve's tip against the tick's forward solve, m.
    tip_m: Vec<f64>,
}

fn model_error(e: model_core::ModelError) -> SceneError {
    SceneError::new("two-section MCU join", e.to_string())
}

/// The bench's path in `T` at `steps`, timed with `timing`.
fn path<T: Scalar>(steps: u16, timing: Timing) -> Result<Path, SceneError> {
    let (rod, mut specs) = tendon_two_section::<T>(steps, GRAVITY_M_S2).map_err(model_error)?;
    for t in specs.iter_mut() {
        t.axial_stiffness_n = Some(T::lit(FIRMWARE_AXIAL_STIFFNESS_N));
        t.feed_length_m = T::lit(FIRMWARE_FEED_LENGTH_M);
    }
    let model = Model::<T>::new(rod).map_err(model_error)?;
    let tendons = Tendons::new(&model, &specs).map_err(model_error)?;
    let settings = ShootingSettings::default();
    let control = DisplacementSettings::default();
    let zero = TipLoad::zero();
    let time = |run: &mut dyn FnMut() -> Result<(), SceneError>| {
        time_cases(1, timing, |_| run()).map(|(us, _)| us)
    };
    let mut truth: Option<TendonEquilibrium<T>> = None;
    let mut previous: Option<DisplacementSolve<T>> = None;
    let mut forward_cold = None;
    let mut ticks = Vec::new();
    let mut tip_m = Vec::new();
    for tick in 0..TENDON_TWO_SECTION_TICKS {
        let tensions = tendon_two_section_actuation_n(tick).map(T::lit);
        let forward = |start: Option<&TendonEquilibrium<T>>| {
            model
                .solve_tendons(&tendons, &tensions, &zero, start, &settings)
                .map_err(model_error)
        };
        let held = forward(truth.as_ref())?;
        if tick == 0 {
            let us = time(&mut || forward(None).map(|s| drop(black_box(s))))?;
            let sweeps = u32::from(held.equilibrium.report.sweeps);
            forward_cold = Some(solved(&held, sweeps, us, true));
        }
        let d = tendons.displacements_holding_m(&held);
        let step = || {
            match &previous {
                None => model.solve_displacements(&tendons, &d, &zero, None, &settings, &control),
                Some(p) => model.update_displacements(&tendons, &d, &zero, p, &settings, &control),
            }
            .map_err(model_error)
        };
        let out = step()?;
        let us = time(&mut || step().map(|s| drop(black_box(s))))?;
        let tip = (out.solved.equilibrium.tip_position_m - held.equilibrium.tip_position_m)
            .norm()
            .to_f64();
        tip_m.push(tip);
        // As the firmware: a tick counts as converged when its forward solve did too.
        let ok = out.is_success() && held.is_success();
        ticks.push(solved(&out.solved, out.sweeps, us, ok));
        truth = Some(held);
        previous = Some(out);
    }
    let forward =
        forward_cold.ok_or_else(|| SceneError::new("two-section MCU join", "no ticks"))?;
    Ok(Path {
        host: HostPath { forward, ticks },
        tip_m,
    })
}

impl Path {
    /// Sweeps, time, convergence ([`HostPath::case`]) and tip error of what `case` measures: the
    /// forward solve's none (it is the truth), the cold displacement solve's at the first tick, a
    /// warm update's the worst of the later ticks.
    fn case(&self, case: &str) -> (u32, f64, bool, f64) {
        let (sweeps, us, converged) = self.host.case(case);
        let tip = if case.ends_with("forward_cold") {
            0.0
        } else if case.ends_with("displacement_cold") {
            self.tip_m.first().copied().unwrap_or(f64::NAN)
        } else {
            match self.tip_m.get(1..) {
                Some(warm) if !warm.is_empty() => warm.iter().copied().fold(0.0, f64::max),
                _ => f64::NAN,
            }
        };
        (sweeps, us, converged, tip)
    }
}

/// The join: the firmware's two-section cases, and the same path on the host in f32 and f64 at
/// the firmware's steps.
pub fn study(timing: Timing) -> Result<TwoSectionMcu, SceneError> {
    let qemu = qemu_cases(BENCH_RUN, "two_section_", &CASES)?;
    let steps = qemu.first().map_or(0, |q| q.steps_per_section);
    let narrow = path::<f32>(steps, timing)?;
    let wide = path::<f64>(steps, timing)?;
    let rows = qemu
        .into_iter()
        .map(|q| {
            let (host_sweeps, host_f32_us, f32_ok, f32_tip_m) = narrow.case(&q.case);
            let (host_f64_sweeps, host_f64_us, f64_ok, f64_tip_m) = wide.case(&q.case);
            TwoSectionRow {
                host_sweeps,
                host_f64_sweeps,
                host_f32_us,
                host_f64_us,
                host_converged: f32_ok && f64_ok,
                f32_tip_m,
                f64_tip_m,
                qemu: q,
            }
        })
        .collect();
    Ok(TwoSectionMcu {
        steps_per_section: steps,
        ticks: TENDON_TWO_SECTION_TICKS,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_section_lines_parse() {
        let cases = qemu_cases(BENCH_RUN, "two_section_", &CASES).expect("two-section cases");
        assert_eq!(cases.len(), CASES.len());
        assert!(
            cases
                .iter()
                .all(|c| c.instructions > 0 && c.sweeps > 0 && c.converged)
        );
        assert!(
            qemu_cases(
                "bench case=two_section_forward_cold",
                "two_section_",
                &CASES
            )
            .is_err()
        );
    }
}
