//! The conclusions of the tendon study, computed from its rows (so that the quick run's report says
//! what its own numbers say).

use model_core::reduction::TendonModel;

use super::super::findings::{Spread, converged_ratio_text, join};
use super::super::measure::Row;
use super::super::numbers::{sig, us};
use super::super::variants::{Arithmetic, Family, Reduction};
use super::actuation::Mode;
use super::measure::tendon_family;
use super::{TendonStudy, picker};

/// Tolerances the "fastest within" paragraph reads, m.
pub const TOLERANCES_M: [f64; 6] = picker::FULL_TOLERANCES_M;

/// A scene's rows of one family, by steps per section.
pub fn series<'a>(study: &'a TendonStudy, scene: &str, family: &Family) -> Vec<&'a Row> {
    let mut rows: Vec<&Row> = study
        .rows
        .iter()
        .filter(|r| r.scene == scene && r.family == *family)
        .collect();
    rows.sort_by_key(|r| r.steps_per_section);
    rows
}

fn keys(study: &TendonStudy) -> Vec<&str> {
    study.scenes.iter().map(|s| s.scene.key.as_str()).collect()
}

fn um(e: Option<f64>) -> String {
    e.map_or("n/a".into(), |e| sig(e * 1e6))
}

fn discrete(arithmetic: Arithmetic) -> Family {
    tendon_family(arithmetic, TendonModel::DiscreteGuides)
}

fn continuous() -> Family {
    tendon_family(Arithmetic::F64, TendonModel::Continuous)
}

fn pcc() -> Family {
    tendon_family(Arithmetic::F64, TendonModel::ConstantCurvature)
}

/// The refused rows of a series, as "UnderResolved at 1, 2, 3 steps".
fn refusals(rows: &[&Row]) -> Option<String> {
    let mut groups: Vec<(String, Vec<String>)> = Vec::new();
    for r in rows.iter().filter(|r| !r.converged()) {
        let t = r
            .termination
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_string();
        match groups.iter_mut().find(|g| g.0 == t) {
            Some(g) => g.1.push(r.steps_per_section.to_string()),
            None => groups.push((t, vec![r.steps_per_section.to_string()])),
        }
    }
    if groups.is_empty() {
        return None;
    }
    Some(join(
        &groups
            .into_iter()
            .map(|(t, steps)| format!("{t} at {} steps", steps.join(", ")))
            .collect::<Vec<_>>(),
    ))
}

fn steps(study: &TendonStudy) -> String {
    let f = discrete(Arithmetic::F64);
    let mut parts = Vec::new();
    let mut orders = Vec::new();
    for key in keys(study) {
        let rows = series(study, key, &f);
        let fewest = |tol: f64| {
            rows.iter()
                .find(|r| r.error_m().is_some_and(|e| e <= tol))
                .map_or("none of the step counts".into(), |r| {
                    format!(
                        "{} ({} um, {} us)",
                        r.steps_per_section,
                        um(r.error_m()),
                        us(r.host_time_us)
                    )
                })
        };
        let refused = refusals(&rows)
            .map(|r| format!("; refused: {r}"))
            .unwrap_or_default();
        parts.push(format!(
            "on {key} within 10 um from {} and within 1 um from {} steps per section{refused}",
            fewest(1e-5),
            fewest(1e-6)
        ));
        let e = |n: u16| {
            rows.iter()
                .find(|r| r.steps_per_section == n)
                .and_then(|r| r.error_m())
        };
        if let (Some(a), Some(b)) = (e(20), e(100)) {
            orders.push((a / b).ln() / 5f64.ln());
        }
    }
    let order = Spread::of(&orders)
        .map(|s| {
            format!(
                " Between 20 and 100 steps the error falls as steps^-{:.1} to steps^-{:.1}.",
                s.min, s.max
            )
        })
        .unwrap_or_default();
    format!(
        "**Discrete guides (f64, the reference's model).** The error (worst of tip, backbone points \
         and path lengths against the reference) is {}.{order} A grid too coarse for the tendons' \
         compression between guides is refused as `UnderResolved`: no answer rather than a wrong one.",
        join(&parts)
    )
}

/// The smallest of [`TOLERANCES_M`] an error is within.
fn reach(error_m: f64) -> Option<f64> {
    TOLERANCES_M
        .iter()
        .copied()
        .filter(|t| error_m <= *t)
        .reduce(f64::min)
}

fn continuous_paragraph(study: &TendonStudy) -> String {
    let c = continuous();
    let d = discrete(Arithmetic::F64);
    let mut floors = Vec::new();
    let mut reaches = Vec::new();
    for key in keys(study) {
        let rows = series(study, key, &c);
        let best = rows.iter().filter_map(|r| r.error_m()).reduce(f64::min);
        let at_one = rows
            .iter()
            .find(|r| r.converged())
            .map_or(String::new(), |r| {
                format!(
                    ", {} um already at {} steps per section ({} us)",
                    um(r.error_m()),
                    r.steps_per_section,
                    us(r.host_time_us)
                )
            });
        let refused = refusals(&rows)
            .map(|r| format!("; refused: {r}"))
            .unwrap_or_default();
        floors.push(format!("{} um on {key}{at_one}{refused}", um(best)));
        reaches.push(match best.and_then(reach) {
            Some(t) => format!("{t:.0e} m on {key}"),
            None => format!("none of the tolerances on {key}"),
        });
    }
    let time = converged_ratio_text(&study.rows, &c, &d, |r| r.host_time_us);
    let sweeps = converged_ratio_text(&study.rows, &c, &d, |r| r.sweeps_per_solve);
    format!(
        "**Continuous routing** (Rucker & Webster) stops improving at {}: the routing's modelling \
         error (the tendon follows the backbone instead of running in chords between guides; the \
         bench's guides are 9.5 cm apart, the two-section robot's 2-1.9 cm), not the grid's. At \
         equal steps it takes {time} the discrete guides' host time per cold solve and {sweeps} \
         their sweeps (where both answer): no implicit jump with a look-ahead at each guide. So it \
         serves tolerances down to {} and no finer.",
        join(&floors),
        join(&reaches)
    )
}

fn pcc_paragraph(study: &TendonStudy) -> String {
    let p = pcc();
    let d = discrete(Arithmetic::F64);
    let mut parts = Vec::new();
    for key in keys(study) {
        if let Some(r) = series(study, key, &p).first() {
            let cheapest = series(study, key, &d)
                .into_iter()
                .filter(|q| q.converged())
                .map(|q| q.host_time_us)
                .reduce(f64::min);
            parts.push(format!(
                "{} mm on {key} in {} us ({} the discrete guides' cheapest answering grid)",
                sig(r.error_m().unwrap_or(f64::NAN) * 1e3),
                us(r.host_time_us),
                cheapest.map_or("n/a".into(), |c| format!("1/{:.0} of", c / r.host_time_us))
            ));
        }
    }
    format!(
        "**PCC** (piecewise constant curvature, closed form, no sweep) is off by {}: it ignores \
         gravity and the tip force, so its error is the rod's own sag and the load's deflection.",
        join(&parts)
    )
}

fn f32_paragraph(study: &TendonStudy) -> String {
    let f = discrete(Arithmetic::F32);
    let mut parts = Vec::new();
    for key in keys(study) {
        let rows = series(study, key, &f);
        let best = rows.iter().filter_map(|r| r.error_m()).reduce(f64::min);
        let refused = refusals(&rows)
            .map(|r| format!(" (refused: {r})"))
            .unwrap_or_default();
        parts.push(format!("{} um on {key}{refused}", um(best)));
    }
    let time = converged_ratio_text(&study.rows, &f, &discrete(Arithmetic::F64), |r| {
        r.host_time_us
    });
    let sweeps = converged_ratio_text(&study.rows, &f, &discrete(Arithmetic::F64), |r| {
        r.sweeps_per_solve
    });
    format!(
        "**f32 discrete guides** bottom out at {} (best over the step counts); on the host they take \
         {time} f64's time and {sweeps} its sweeps per cold solve at equal steps.",
        join(&parts)
    )
}

fn describe(r: &Row) -> String {
    if r.family.reduction == Reduction::TendonPcc {
        r.family.label()
    } else {
        format!("{} at {}", r.family.label(), r.steps_per_section)
    }
}

fn fastest(study: &TendonStudy) -> String {
    let mut parts = Vec::new();
    for key in keys(study) {
        let rows: Vec<&Row> = study.rows.iter().filter(|r| r.scene == key).collect();
        let mut picks = Vec::new();
        for tol in TOLERANCES_M {
            let within = || {
                rows.iter()
                    .filter(move |r| r.error_m().is_some_and(|e| e <= tol))
            };
            let by_time = within().min_by(|a, b| a.host_time_us.total_cmp(&b.host_time_us));
            let by_work = within().min_by(|a, b| a.work().total_cmp(&b.work()));
            picks.push(match (by_time, by_work) {
                (Some(t), Some(w))
                    if t.family == w.family && t.steps_per_section == w.steps_per_section =>
                {
                    format!("{tol:.0e} m: {} ({} us)", describe(t), us(t.host_time_us))
                }
                (Some(t), Some(w)) => format!(
                    "{tol:.0e} m: {} ({} us; by work {}, {} us)",
                    describe(t),
                    us(t.host_time_us),
                    describe(w),
                    us(w.host_time_us)
                ),
                _ => format!("{tol:.0e} m: none studied"),
            });
        }
        parts.push(format!("on {key}, {}", picks.join("; ")));
    }
    format!(
        "**Fastest within a tolerance** (least host time per cold solve among the studied rows, \
         error with the backbone; where the least deterministic work picks another row, it follows \
         in brackets): {}.",
        parts.join(". And ")
    )
}

fn actuation_paragraph(study: &TendonStudy) -> String {
    let mut parts = Vec::new();
    for key in keys(study) {
        for arithmetic in [Arithmetic::F64, Arithmetic::F32] {
            let row = |mode: Mode| {
                study
                    .actuation
                    .iter()
                    .find(|a| a.scene == key && a.arithmetic == arithmetic && a.mode == mode)
            };
            let (Some(cold), Some(dcold), Some(dwarm), Some(twarm)) = (
                row(Mode::TensionsCold),
                row(Mode::DisplacementsCold),
                row(Mode::DisplacementsWarm),
                row(Mode::TensionsWarm),
            ) else {
                continue;
            };
            parts.push(format!(
                "{key} {}: {} sweeps from tensions ({} us, tip {} um off), {} from displacements \
                 in {} iterations ({:.1}x the time, tip {} um off), a warm update {} in {} \
                 ({:.1}x; warm from tensions {}, {:.1}x)",
                arithmetic.label(),
                sig(cold.sweeps_per_solve),
                us(cold.host_time_us),
                um(cold.tip_error_m),
                sig(dcold.sweeps_per_solve),
                sig(dcold.iterations.unwrap_or(f64::NAN)),
                dcold.host_time_us / cold.host_time_us,
                um(dcold.tip_error_m),
                sig(dwarm.sweeps_per_solve),
                sig(dwarm.iterations.unwrap_or(f64::NAN)),
                dwarm.host_time_us / cold.host_time_us,
                sig(twarm.sweeps_per_solve),
                twarm.host_time_us / cold.host_time_us,
            ));
        }
    }
    format!(
        "**From tensions or from displacements** (discrete guides, {} steps per section, per \
         solve, against a cold solve from tensions): {}. Displacement control pays for its \
         sensitivity (frictionless, two or three sweeps with tangents; with friction, forward \
         differences, one warm solve per tendon) and its semi-smooth Newton iterations; its warm update keeps the sensitivity (Broyden) and starts at the last \
         tensions, but, like the cold solve, it iterates on to the rounding floor while it still \
         improves ({}). From displacements the grid's error in the path lengths becomes an error in the \
         tensions (up to {} N here, f64), which moves the tip otherwise than the same grid driven \
         by the exact tensions.",
        super::actuation::ACTUATION_STEPS,
        join(&parts),
        warm_iterations(study),
        sig(study
            .actuation
            .iter()
            .filter(|a| a.arithmetic == Arithmetic::F64)
            .filter_map(|a| a.tension_error_n)
            .fold(0.0, f64::max))
    )
}

/// The warm displacement updates' iterations by precision, "8 and 10 iterations in f64, 3.75 and
/// 2.25 in f32".
fn warm_iterations(study: &TendonStudy) -> String {
    let per = |arithmetic: Arithmetic| {
        let its: Vec<String> = study
            .actuation
            .iter()
            .filter(|a| a.arithmetic == arithmetic && a.mode == Mode::DisplacementsWarm)
            .filter_map(|a| a.iterations.map(sig))
            .collect();
        format!("{} in {}", join(&its), arithmetic.label())
    };
    format!(
        "the warm updates' mean iterations per scene: {} against {}",
        per(Arithmetic::F64),
        per(Arithmetic::F32)
    )
}

fn mcu_paragraph(study: &TendonStudy) -> String {
    let m = &study.mcu;
    let cases: Vec<String> = m
        .rows
        .iter()
        .map(|r| {
            let q = &r.qemu;
            format!(
                "{} {} instructions ({} sweeps, {:.0} per sweep; {:.1} ms at 168 MHz if each took \
                 one cycle), f32 tip {} um from the converged reference (host f32, QEMU's sweeps \
                 {} against the host's {})",
                q.case,
                q.instructions,
                q.sweeps,
                q.per_sweep(),
                q.lower_bound_ms(),
                sig(r.f32_error_m * 1e6),
                q.sweeps,
                r.host_sweeps
            )
        })
        .collect();
    let same: Vec<&str> = m
        .rows
        .iter()
        .filter(|r| r.qemu.sweeps == r.host_sweeps)
        .map(|r| r.qemu.case.as_str())
        .collect();
    let differ: Vec<&str> = m
        .rows
        .iter()
        .filter(|r| r.qemu.sweeps != r.host_sweeps)
        .map(|r| r.qemu.case.as_str())
        .collect();
    let worst_vs_trajectory = m
        .rows
        .iter()
        .map(|r| r.host_vs_trajectory_m.max(r.qemu.tip_error_m))
        .fold(0.0, f64::max);
    let agreement = if differ.is_empty() {
        " The host's f32 solves take QEMU's sweeps in every case.".to_string()
    } else {
        format!(
            " The host's f32 solves take QEMU's sweeps in {} and not in {}: either f32's last bits \
             steer displacement control's semi-smooth Newton another way on the target, or the \
             committed `firmware/expected/bench.run` is older than the code (`firmware/test.sh` \
             compares it with a fresh QEMU run); the join is only as current as that file. Both \
             converge; their tips lie within {} um of the firmware's f64 trajectory at the same \
             steps.",
            if same.is_empty() {
                "none".to_string()
            } else {
                same.join(", ")
            },
            differ.join(", "),
            sig(worst_vs_trajectory * 1e6)
        )
    };
    format!(
        "**Cortex-M4F** (the firmware's tendon robot, f32 discrete guides at {} steps per section, \
         QEMU instruction counts): {}.{agreement} {}",
        m.steps_per_section,
        join(&cases),
        two_section_sentence(study)
    )
}

/// The two-section robot's MCU cases in one sentence.
fn two_section_sentence(study: &TendonStudy) -> String {
    let m = &study.two_section_mcu;
    let cases: Vec<String> = m
        .rows
        .iter()
        .map(|r| {
            let q = &r.qemu;
            format!(
                "{} {} instructions ({} sweeps; {:.1} ms at 168 MHz; host f32 {} sweeps, f64 {})",
                q.case,
                q.instructions,
                q.sweeps,
                q.lower_bound_ms(),
                r.host_sweeps,
                r.host_f64_sweeps
            )
        })
        .collect();
    let worst_tip = m
        .rows
        .iter()
        .map(|r| r.qemu.tip_error_m.max(r.f32_tip_m))
        .fold(0.0, f64::max);
    format!(
        "The two-section, six-tendon robot (its own table, {} ticks, {} steps per section): {}; \
         every f32 tip within {} um of the forward solve whose displacements its tick used. Its \
         warm update is {} to {} times the bench robot's median tick.",
        m.ticks,
        m.steps_per_section,
        join(&cases),
        sig(worst_tip * 1e6),
        ratio(
            study,
            "two_section_update_warm_median",
            "tendon_update_warm_median"
        ),
        ratio(
            study,
            "two_section_update_warm",
            "tendon_update_warm_median"
        ),
    )
}

/// QEMU's instructions of the two-section case `two` over the bench robot's case `bench`.
fn ratio(study: &TendonStudy, two: &str, bench: &str) -> String {
    let two = study
        .two_section_mcu
        .rows
        .iter()
        .find(|r| r.qemu.case == two)
        .map(|r| r.qemu.instructions as f64);
    let bench = study
        .mcu
        .rows
        .iter()
        .find(|r| r.qemu.case == bench)
        .map(|r| r.qemu.instructions as f64);
    match (two, bench) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.0}", a / b),
        _ => "n/a".into(),
    }
}

fn picker_paragraph(study: &TendonStudy) -> String {
    let total = study.picks.len();
    let met = study.picks.iter().filter(|p| p.meets()).count();
    let shape = study.picks.iter().filter(|p| p.shape_within()).count();
    let mut by_tol = Vec::new();
    for tol in TOLERANCES_M {
        let mut picks: Vec<String> = study
            .picks
            .iter()
            .filter(|p| p.tolerance_m == tol)
            .filter_map(|p| p.picked)
            .map(|(r, n)| {
                if r == Reduction::TendonPcc {
                    r.label().to_string()
                } else {
                    format!("{} at {n}", r.label())
                }
            })
            .collect();
        if picks.is_empty() {
            continue;
        }
        picks.sort();
        picks.dedup();
        by_tol.push(format!("{tol:.0e} m: {}", picks.join(" or ")));
    }
    let speedup_of = |model: Reduction| {
        let values: Vec<f64> = study
            .picks
            .iter()
            .filter(|p| p.picked.is_some_and(|(r, _)| r == model))
            .filter_map(|p| p.speedup())
            .collect();
        Spread::of(&values).map(|s| {
            format!(
                "{} picks {} ({} to {})",
                model.label(),
                format_ratio(s.median),
                format_ratio(s.min),
                format_ratio(s.max)
            )
        })
    };
    let speedups: Vec<String> = [Reduction::TendonPcc, Reduction::TendonContinuous]
        .into_iter()
        .filter_map(speedup_of)
        .collect();
    let speedup = if speedups.is_empty() {
        "it picked no model other than the discrete guides".to_string()
    } else {
        format!(
            "against the discrete guides at their own fewest ladder steps for the same tolerance, \
             measured on the host, the {} faster",
            join(&speedups)
        )
    };
    format!(
        "**choose_tendons.** Its pick meets its tolerance on tip and path lengths against this \
         study's reference in {met} of {total} cases (on the whole backbone too in {shape}). Picks \
         by tolerance: {}; {speedup}.",
        join(&by_tol)
    )
}

/// A speed ratio such as "3.2x" or "3500x".
fn format_ratio(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}x")
    } else {
        format!("{x:.1}x")
    }
}

/// The conclusions of the tendon study, one paragraph each.
pub fn conclusions(study: &TendonStudy) -> Vec<String> {
    vec![
        fastest(study),
        steps(study),
        continuous_paragraph(study),
        pcc_paragraph(study),
        f32_paragraph(study),
        actuation_paragraph(study),
        mcu_paragraph(study),
        picker_paragraph(study),
    ]
}
