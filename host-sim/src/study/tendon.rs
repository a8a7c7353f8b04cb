//! The tendon scenes of the study (MODEL.md §6): the discrete-guide model (the routing the robot
//! has, and the reference), continuous routing and piecewise constant curvature, against the
//! discrete guides in f64 on a fine grid; the forward solve from tensions against displacement
//! control, cold and warm; the firmware's tendon instruction counts joined with the host; and
//! `model_core::reduction::choose_tendons`' picks checked against the study's reference.

mod actuation;
mod cases;
mod findings;
mod mcu;
mod mcu_two_section;
mod measure;
mod picker;
mod write;

use model_core::reduction::TendonModel;

use super::measure::{REFERENCE_AGREEMENT_M, Row, Timing};
use super::numbers::sig;
use super::variants::Arithmetic;
use super::{Check, check, mark_fronts};
use host_sim::scene::SceneError;

pub use actuation::ActuationRow;
pub use cases::TendonScene;
pub use mcu::TendonMcu;
pub use mcu_two_section::TwoSectionMcu;
pub use measure::{CHECK_STEPS, GOLDEN_AGREEMENT_M, REFERENCE_STEPS, TendonReference};
pub use picker::TendonPick;
pub use write::{markdown, plot};

/// Steps per section of the full tendon study.
pub const FULL_STEPS: [u16; 9] = [1, 2, 3, 5, 10, 20, 50, 100, 200];
/// Steps per section of the quick study (CI); 20 is the firmware's.
pub const QUICK_STEPS: [u16; 3] = [5, 20, 100];

/// A tendon scene with its reference.
#[derive(Clone, Debug, PartialEq)]
pub struct StudiedTendonScene {
    /// The scene.
    pub scene: TendonScene,
    /// Its reference.
    pub reference: TendonReference,
}

/// Everything the tendon section of the report is written from.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonStudy {
    /// Steps per section studied.
    pub steps: Vec<u16>,
    /// Scenes and references.
    pub scenes: Vec<StudiedTendonScene>,
    /// One per variant and scene.
    pub rows: Vec<Row>,
    /// Tensions against displacements.
    pub actuation: Vec<ActuationRow>,
    /// `choose_tendons`' picks.
    pub picks: Vec<TendonPick>,
    /// The MCU join.
    pub mcu: TendonMcu,
    /// The two-section robot's MCU join.
    pub two_section_mcu: TwoSectionMcu,
}

/// The keys of the tendon scenes.
pub fn keys() -> [&'static str; 2] {
    [cases::BENCH_KEY, cases::TWO_SECTION_KEY]
}

/// The families measured on each scene: the discrete guides in f64 and f32, continuous routing in
/// f64 (each on the step ladder), PCC in f64 (no grid).
fn families() -> [(Arithmetic, TendonModel); 4] {
    [
        (Arithmetic::F64, TendonModel::DiscreteGuides),
        (Arithmetic::F32, TendonModel::DiscreteGuides),
        (Arithmetic::F64, TendonModel::Continuous),
        (Arithmetic::F64, TendonModel::ConstantCurvature),
    ]
}

/// Runs the tendon study on the scenes among `keys` (all if empty).
pub fn run(quick: bool, keys: &[String], timing: Timing) -> Result<TendonStudy, SceneError> {
    let steps: Vec<u16> = if quick {
        QUICK_STEPS.to_vec()
    } else {
        FULL_STEPS.to_vec()
    };
    let tolerances: &[f64] = if quick {
        &picker::QUICK_TOLERANCES_M
    } else {
        &picker::FULL_TOLERANCES_M
    };
    let mut scenes = Vec::new();
    for scene in TendonScene::all(quick)?
        .into_iter()
        .filter(|s| keys.is_empty() || keys.contains(&s.key))
    {
        let reference = measure::reference(&scene)?;
        eprintln!(
            "{}: tendon reference converged; grids of {REFERENCE_STEPS} and {CHECK_STEPS} steps \
             differ by {:.1e} m, the golden rows by {:.1e} m",
            scene.key,
            reference.grid_difference_m,
            reference.golden_difference_m.unwrap_or(f64::NAN)
        );
        scenes.push(StudiedTendonScene { scene, reference });
    }
    let mut rows = Vec::new();
    let mut actuation_rows = Vec::new();
    let mut picks = Vec::new();
    for s in &scenes {
        for (arithmetic, model) in families() {
            let family = measure::tendon_family(arithmetic, model);
            let ladder: &[u16] = if model == TendonModel::ConstantCurvature {
                &[0]
            } else {
                &steps
            };
            for &n in ladder {
                rows.push(measure::measure(&s.scene, &s.reference, family, n, timing)?);
            }
        }
        for arithmetic in [Arithmetic::F64, Arithmetic::F32] {
            actuation_rows.extend(actuation::study(
                &s.scene,
                &s.reference,
                arithmetic,
                timing,
            )?);
        }
        picks.extend(picker::study(&s.scene, &s.reference, tolerances, timing)?);
        eprintln!(
            "{}: tendon variants, actuation and picks measured",
            s.scene.key
        );
    }
    mark_fronts(&mut rows);
    let mcu = mcu::study(timing)?;
    eprintln!("tendon MCU join: {} cases", mcu.rows.len());
    let two_section_mcu = mcu_two_section::study(timing)?;
    eprintln!("two-section MCU join: {} cases", two_section_mcu.rows.len());
    Ok(TendonStudy {
        steps,
        scenes,
        rows,
        actuation: actuation_rows,
        picks,
        mcu,
        two_section_mcu,
    })
}

/// The tendon study's checks.
pub fn checks(study: &TendonStudy) -> Vec<Check> {
    let mut out = Vec::new();
    for s in &study.scenes {
        let r = &s.reference;
        let key = &s.scene.key;
        check(
            &mut out,
            measure::grids_agree(r),
            format!(
                "{key}: tendon reference grids ({REFERENCE_STEPS} and {CHECK_STEPS} steps per \
                 section) agree to {:.1e} m (limit {REFERENCE_AGREEMENT_M:.0e} m)",
                r.grid_difference_m
            ),
        );
        let golden = r.golden_difference_m.unwrap_or(f64::INFINITY);
        check(
            &mut out,
            golden <= GOLDEN_AGREEMENT_M,
            format!(
                "{key}: the tendon reference meets the independent golden rows (tips and paths) to \
                 {golden:.1e} m (limit {GOLDEN_AGREEMENT_M:.0e} m)"
            ),
        );
        let rows: Vec<&Row> = study.rows.iter().filter(|r| &r.scene == key).collect();
        let bad: Vec<String> = rows
            .iter()
            .filter(|r| {
                !(r.host_time_us.is_finite() && r.work().is_finite())
                    || (r.converged() && !r.error_m().is_some_and(f64::is_finite))
            })
            .map(|r| format!("{} at {}", r.family.label(), r.steps_per_section))
            .collect();
        check(
            &mut out,
            bad.is_empty(),
            format!(
                "{key}: every converged tendon row has finite errors, every row a finite cost ({} \
                 rows{})",
                rows.len(),
                if bad.is_empty() {
                    String::new()
                } else {
                    format!("; not: {}", bad.join(", "))
                }
            ),
        );
        let discrete = measure::tendon_family(Arithmetic::F64, TendonModel::DiscreteGuides);
        let errors: Vec<f64> = rows
            .iter()
            .filter(|r| r.family == discrete)
            .filter_map(|r| r.error_m())
            .collect();
        let (coarse, fine) = (errors.first().copied(), errors.last().copied());
        check(
            &mut out,
            matches!((coarse, fine), (Some(c), Some(f)) if f < c / 100.0),
            format!(
                "{key}: the f64 discrete-guide error shrinks with steps ({:.1e} m at the fewest \
                 answering, {:.1e} m at the most)",
                coarse.unwrap_or(f64::NAN),
                fine.unwrap_or(f64::NAN)
            ),
        );
        let failed: Vec<String> = study
            .actuation
            .iter()
            .filter(|a| &a.scene == key && !a.converged())
            .map(|a| {
                format!(
                    "{} {}: {}",
                    a.arithmetic.label(),
                    a.mode.label(),
                    a.termination
                )
            })
            .collect();
        check(
            &mut out,
            failed.is_empty(),
            format!(
                "{key}: every solve from tensions and from displacements (cold and warm, f64 and \
                 f32) converged{}",
                if failed.is_empty() {
                    String::new()
                } else {
                    format!("; not: {}", failed.join("; "))
                }
            ),
        );
    }
    for p in &study.picks {
        let what = match (p.picked, &p.refused) {
            (Some((reduction, steps)), _) => format!(
                "{} at {steps} steps, is within it against the study's reference ({:.2e} m)",
                reduction.label(),
                p.study_error_m().unwrap_or(f64::NAN)
            ),
            (None, reason) => format!("refused: {}", reason.as_deref().unwrap_or("")),
        };
        check(
            &mut out,
            p.meets(),
            format!(
                "{} ({}): choose_tendons' pick for {:.0e} m, {what}",
                p.scene, p.case_label, p.tolerance_m
            ),
        );
    }
    let m = &study.mcu;
    check(
        &mut out,
        m.reference_converged && m.trajectory_difference <= mcu::TRAJECTORY_AGREEMENT,
        format!(
            "tendon MCU join: the host's f64 model at {} steps reproduces the firmware's recorded \
             trajectory ({} ticks) to {:.1e} (m and N; limit {:.0e}), and the reference path \
             converged",
            m.steps_per_section,
            m.ticks,
            m.trajectory_difference,
            mcu::TRAJECTORY_AGREEMENT
        ),
    );
    for r in &m.rows {
        check(
            &mut out,
            r.qemu.converged && r.host_converged,
            format!(
                "tendon MCU join, {}: QEMU and host f32 and f64 solves converged",
                r.qemu.case
            ),
        );
    }
    for r in &study.two_section_mcu.rows {
        // The forward solve is the tick's truth itself: its row checks convergence alone.
        let forward = r.qemu.case == mcu_two_section::CASES[0];
        let tips = forward
            || (r.qemu.tip_error_m <= mcu_two_section::F32_TIP_AGREEMENT_M
                && r.f32_tip_m <= mcu_two_section::F32_TIP_AGREEMENT_M
                && r.f64_tip_m <= mcu_two_section::F64_TIP_AGREEMENT_M);
        check(
            &mut out,
            r.qemu.converged && r.host_converged && tips,
            format!(
                "two-section MCU join, {}: QEMU's and the host's f32 and f64 solves converged{}",
                r.qemu.case,
                if forward {
                    String::new()
                } else {
                    format!(
                        ", their tips within {} / {} / {} um of the tick's forward solve (limits \
                         {:.0e} m in f32, {:.0e} m in f64)",
                        sig(r.qemu.tip_error_m * 1e6),
                        sig(r.f32_tip_m * 1e6),
                        sig(r.f64_tip_m * 1e6),
                        mcu_two_section::F32_TIP_AGREEMENT_M,
                        mcu_two_section::F64_TIP_AGREEMENT_M
                    )
                }
            ),
        );
    }
    out
}
