//! The conclusions of a study run, computed from its rows (so that the quick run's report says what
//! its own numbers say).

use super::Study;
use super::measure::Row;
use super::numbers::{sig, us};
use super::reductions::MAIN_TOLERANCE_M;
use super::variants::{Arithmetic, Family, Frame, Reduction};

/// The reference family with another arithmetic, frame or reduction.
pub fn family(arithmetic: Arithmetic, frame: Frame, reduction: Reduction) -> Family {
    Family {
        arithmetic,
        frame,
        reduction,
    }
}

/// A scene's rows of one family, by steps per section.
pub fn series<'a>(study: &'a Study, scene: &str, family: &Family) -> Vec<&'a Row> {
    let mut rows: Vec<&Row> = study
        .rows
        .iter()
        .filter(|r| r.scene == scene && r.family == *family)
        .collect();
    rows.sort_by_key(|r| r.steps_per_section);
    rows
}

/// The first row of a series whose error is within `tolerance_m`.
pub fn fewest<'a>(rows: &[&'a Row], tolerance_m: f64) -> Option<&'a Row> {
    rows.iter()
        .copied()
        .find(|r| r.error_m().is_some_and(|e| e <= tolerance_m))
}

/// Median, smallest and largest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// Of finite values; `None` if there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        let median = super::measure::median(&mut v);
        Some(Self {
            median,
            min: v.first().copied().unwrap_or(median),
            max: v.last().copied().unwrap_or(median),
        })
    }

    /// "1.2x (1.1-1.4x)".
    pub fn ratio(&self) -> String {
        format!("{:.2}x ({:.2}-{:.2}x)", self.median, self.min, self.max)
    }
}

/// `f(a, b)` over every pair of rows of families `a` and `b` on the same scene and step count
/// (`min_steps` and up).
pub fn paired(
    rows: &[Row],
    a: &Family,
    b: &Family,
    min_steps: u16,
    f: impl Fn(&Row, &Row) -> Option<f64>,
) -> Vec<f64> {
    rows.iter()
        .filter(|r| r.family == *a && r.steps_per_section >= min_steps)
        .filter_map(|r| {
            rows.iter()
                .find(|q| {
                    q.family == *b
                        && q.scene == r.scene
                        && q.steps_per_section == r.steps_per_section
                })
                .and_then(|q| f(r, q))
        })
        .collect()
}

/// A cost `cost` of one solve against another's (for [`paired`]), where both converged: a failed
/// solve's time or sweeps (cut short, or run to its limit) are no cost of an answer.
pub fn converged_ratio(cost: fn(&Row) -> f64) -> impl Fn(&Row, &Row) -> Option<f64> {
    move |a, b| (a.converged() && b.converged()).then(|| cost(a) / cost(b))
}

/// The spread of `cost` of family `a` against `b` over their pairs where both converged (any step
/// count), as a report shows it ("n/a" without a pair).
pub fn converged_ratio_text(rows: &[Row], a: &Family, b: &Family, cost: fn(&Row) -> f64) -> String {
    Spread::of(&paired(rows, a, b, 0, converged_ratio(cost))).map_or("n/a".into(), |s| s.ratio())
}

/// The host time of one solve against another's, where both converged ([`converged_ratio`]).
fn time_ratio(a: &Row, b: &Row) -> Option<f64> {
    converged_ratio(|r| r.host_time_us)(a, b)
}

fn error_ratio(a: &Row, b: &Row) -> Option<f64> {
    Some(a.error_m()? / b.error_m()?)
}

fn keys(study: &Study) -> Vec<&str> {
    study.scenes.iter().map(|s| s.scene.key.as_str()).collect()
}

pub fn join(parts: &[String]) -> String {
    match parts {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

fn convergence(study: &Study) -> String {
    let reference = Family::REFERENCE;
    let mut tens = Vec::new();
    let mut ones = Vec::new();
    let mut orders = Vec::new();
    for key in keys(study) {
        let rows = series(study, key, &reference);
        let at = |tol: f64| match fewest(&rows, tol) {
            Some(r) => format!(
                "{} on {key} ({} um, {} us)",
                r.steps_per_section,
                sig(r.error_m().unwrap_or(f64::NAN) * 1e6),
                us(r.host_time_us)
            ),
            None => format!("none of the step counts on {key}"),
        };
        tens.push(at(MAIN_TOLERANCE_M));
        ones.push(at(1e-6));
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
            let fourth = if s.min > 3.5 && s.max < 4.5 {
                ": RK4's fourth order"
            } else {
                ""
            };
            format!(
                " Between 20 and 100 steps the error falls as steps^-{:.1} to steps^-{:.1}{fourth}.",
                s.min, s.max
            )
        })
        .unwrap_or_default();
    format!(
        "**Steps (f64, quaternion, full 3D model).** The error (worst of tip, backbone points and cable \
         lengths) is within 10 um from {} steps per section; within 1 um from {}.{order}",
        join(&tens),
        join(&ones)
    )
}

fn failures(study: &Study, arithmetics: &[Arithmetic]) -> Vec<String> {
    let mut groups: Vec<(String, Vec<u16>)> = Vec::new();
    for r in study
        .rows
        .iter()
        .filter(|r| !r.converged() && arithmetics.contains(&r.family.arithmetic))
    {
        let termination = r
            .termination
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_string();
        let label = format!("{} on {}: {termination}", r.family.label(), r.scene);
        match groups.iter_mut().find(|g| g.0 == label) {
            Some(g) => g.1.push(r.steps_per_section),
            None => groups.push((label, vec![r.steps_per_section])),
        }
    }
    groups
        .into_iter()
        .map(|(label, steps)| {
            let steps: Vec<String> = steps.iter().map(u16::to_string).collect();
            format!("{label} at {} steps", steps.join(", "))
        })
        .collect()
}

fn frames(study: &Study) -> String {
    let q = Family::REFERENCE;
    let rm = family(
        Arithmetic::F64,
        Frame::RotationMatrix,
        Reduction::Cosserat3d,
    );
    let lg = family(Arithmetic::F64, Frame::LieGroup, Reduction::Cosserat3d);
    let spread = |v: Vec<f64>| Spread::of(&v);
    let show = |s: Option<Spread>| s.map_or("n/a".into(), |s| s.ratio());
    let (rm_error, lg_error) = (
        spread(paired(&study.rows, &rm, &q, 10, error_ratio)),
        spread(paired(&study.rows, &lg, &q, 10, error_ratio)),
    );
    let (rm_time, lg_time) = (
        spread(paired(&study.rows, &rm, &q, 10, time_ratio)),
        spread(paired(&study.rows, &lg, &q, 10, time_ratio)),
    );
    let most_accurate = [(&rm_error, "rotation matrix"), (&lg_error, "Lie group")]
        .iter()
        .filter(|(e, _)| e.is_some_and(|e| e.median < 1.0))
        .map(|(_, name)| *name)
        .collect::<Vec<_>>();
    let always = [&rm_error, &lg_error]
        .iter()
        .all(|e| e.is_some_and(|e| e.min > 1.0));
    let verdict = if most_accurate.is_empty() {
        if always {
            "At equal steps the quaternion is the most accurate of the three in every pair"
                .to_string()
        } else {
            "At equal steps the quaternion is the most accurate of the three by the median"
                .to_string()
        }
    } else {
        format!(
            "At equal steps the {} beats the quaternion's accuracy",
            most_accurate.join(" and the ")
        )
    };
    // At fourth order, an error `r` times larger takes `r^(1/4)` times the steps to make up. Time
    // ratios within 5 % of one are within the host's noise.
    let trade = |name: &str, error: &Option<Spread>, time: &Option<Spread>| match (error, time) {
        (Some(_), Some(t)) if (t.median - 1.0).abs() <= 0.05 => Some(format!(
            "the {name} frame is about as fast as the quaternion"
        )),
        (Some(e), Some(t)) if t.median < 1.0 => Some(format!(
            "the {name} frame saves {:.0} % of the time per solve at equal steps, while matching the \
             quaternion's error would take about {:.2}x the steps (RK4's fourth order: the error \
             ratio to the 1/4)",
            (1.0 - t.median) * 100.0,
            e.median.max(1.0).powf(0.25)
        )),
        _ => None,
    };
    let trades: Vec<String> = [
        trade("rotation-matrix", &rm_error, &rm_time),
        trade("Lie-group", &lg_error, &lg_time),
    ]
    .into_iter()
    .flatten()
    .collect();
    let cost = if trades.is_empty() {
        ", and no other frame is cheaper per solve".to_string()
    } else {
        format!("; {}", trades.join("; "))
    };
    let failed = failures(study, &[Arithmetic::F64, Arithmetic::F32]);
    let failed = if failed.is_empty() {
        "Every libm solve converged.".to_string()
    } else {
        format!(
            "Solves refused (a row with its termination, no error): {}.",
            failed.join("; ")
        )
    };
    format!(
        "**Frames (f64, same steps).** Against the quaternion, the rotation-matrix frame's error is \
         {} and the Lie group's {}; their time per solve is {} and {} (10 steps per section and up, \
         all scenes). {verdict}{cost}. {failed}",
        show(rm_error),
        show(lg_error),
        show(rm_time),
        show(lg_time),
    )
}

fn kirchhoff(study: &Study) -> String {
    let k = family(Arithmetic::F64, Frame::Quaternion, Reduction::Kirchhoff3d);
    let mut floors = Vec::new();
    let mut values = Vec::new();
    for key in keys(study) {
        let best = series(study, key, &k)
            .iter()
            .filter_map(|r| r.error_m())
            .reduce(f64::min);
        if let Some(e) = best {
            floors.push(format!("{} um on {key}", sig(e * 1e6)));
            values.push(e);
        }
    }
    let worst = values.iter().copied().fold(0.0, f64::max);
    let best = values.iter().copied().fold(f64::INFINITY, f64::min);
    let enough = if worst <= MAIN_TOLERANCE_M && best > 1e-6 {
        ", enough for a 10 um tolerance and not for 1 um"
    } else {
        ""
    };
    let time = converged_ratio_text(&study.rows, &k, &Family::REFERENCE, |r| r.host_time_us);
    format!(
        "**Kirchhoff** (inextensible, unshearable) stops improving at {}: its modelling \
         error{enough}. Its time per solve is {time} the Cosserat model's.",
        join(&floors)
    )
}

/// The median sweeps per cold solve of `family` over its pairs with `other` (same scene and step
/// count) where both converged: the same pairs from either side, as the time ratios take them.
fn median_sweeps(rows: &[Row], family: &Family, other: &Family) -> Option<f64> {
    let sweeps = paired(rows, family, other, 0, |a, b| {
        (a.converged() && b.converged()).then_some(a.sweeps_per_solve)
    });
    Spread::of(&sweeps).map(|s| s.median)
}

fn planar(study: &Study) -> Option<String> {
    let p = family(Arithmetic::F64, Frame::Quaternion, Reduction::Planar);
    let q = Family::REFERENCE;
    let time = Spread::of(&paired(&study.rows, &p, &q, 0, time_ratio))?;
    let error = Spread::of(&paired(&study.rows, &p, &q, 0, error_ratio))?;
    let (sp, sq) = (
        median_sweeps(&study.rows, &p, &q)?,
        median_sweeps(&study.rows, &q, &p)?,
    );
    let work = if sp >= sq {
        "Its deterministic work is no smaller"
    } else {
        "Its deterministic work is smaller"
    };
    Some(format!(
        "**Planar reduction** (in-plane scenes): at equal steps an error {} the 3D model's in {} \
         of its time per cold solve. {work} ({} sweeps per solve against {} on the same scenes, the \
         last one the stability test out of the plane): its steps are cheaper, five states and one \
         tangent (two in the last sweep) against sixteen states and three tangents.",
        error.ratio(),
        time.ratio(),
        sig(sp),
        sig(sq)
    ))
}

fn f32_floor(study: &Study) -> String {
    let q32 = family(Arithmetic::F32, Frame::Quaternion, Reduction::Cosserat3d);
    let mut best = Vec::new();
    for key in keys(study) {
        if let Some(e) = series(study, key, &q32)
            .iter()
            .filter_map(|r| r.error_m())
            .reduce(f64::min)
        {
            best.push(format!("{} um on {key}", sig(e * 1e6)));
        }
    }
    // Per scene: the f32 solve against the f64 solve on the same grid, and one f32 sweep at the f64
    // root (how well f32 represents the right answer). The stopping rule sets the floor where the
    // solve is much further off than the sweep.
    let causes: Vec<String> = keys(study)
        .into_iter()
        .filter_map(|key| {
            let of = |f: fn(&super::measure::F32Floor) -> f64| {
                study
                    .floors
                    .iter()
                    .filter(|x| x.scene == key)
                    .map(f)
                    .reduce(f64::max)
            };
            let (solve, sweep) = (of(|x| x.solve_m)?, of(|x| x.sweep_m)?);
            let cause = if solve > 3.0 * sweep {
                "the f32 solve's stopping tolerance (2.4e-5 of E I / L), not f32 arithmetic"
            } else {
                "f32 arithmetic as much as the stopping rule"
            };
            Some(format!(
                "on {key} the f32 solve's tip lies up to {} um from f64's on the same grid and one \
                 f32 sweep at the f64 answer's base strain up to {} um: {cause}",
                sig(solve * 1e6),
                sig(sweep * 1e6)
            ))
        })
        .collect();
    let time = converged_ratio_text(&study.rows, &q32, &Family::REFERENCE, |r| r.host_time_us);
    let sweeps =
        |f: &Family, other: &Family| median_sweeps(&study.rows, f, other).unwrap_or(f64::NAN);
    format!(
        "**f32 (libm)** bottoms out at {} (best over the step counts). What sets the floor: {}. On \
         the host f32 takes {time} f64's time per cold solve, with fewer sweeps ({} per solve \
         against {}) and a plain sweep hardly cheaper (`report/host_timings.md`).",
        join(&best),
        causes.join("; "),
        sig(sweeps(&q32, &Family::REFERENCE)),
        sig(sweeps(&Family::REFERENCE, &q32))
    )
}

/// Steps per section from which the micromath paragraph compares cable errors (below it the
/// discretisation error of either arithmetic dominates).
const MICROMATH_MIN_STEPS: u16 = 10;

fn micromath(study: &Study) -> String {
    if !study.micromath {
        return "**micromath**: not in this run (`report/study.sh` builds with `--features \
                fast-math` and merges its rows)."
            .into();
    }
    let mm: Vec<&Row> = study
        .rows
        .iter()
        .filter(|r| r.family.arithmetic == Arithmetic::F32Micromath)
        .collect();
    let cable = |planar: bool, arithmetic: Arithmetic| {
        study
            .rows
            .iter()
            .filter(|r| {
                r.family.arithmetic == arithmetic
                    && r.family.reduction.planar() == planar
                    && r.steps_per_section >= MICROMATH_MIN_STEPS
            })
            .filter_map(|r| r.cable_error_m)
            .fold(0.0, f64::max)
    };
    let q = |a| family(a, Frame::Quaternion, Reduction::Cosserat3d);
    let tip = Spread::of(&paired(
        &study.rows,
        &q(Arithmetic::F32Micromath),
        &q(Arithmetic::F32),
        0,
        |a, b| Some(a.tip_error_m? / b.tip_error_m?),
    ))
    .map_or("n/a".into(), |s| s.ratio());
    let lie: Vec<&&Row> = mm
        .iter()
        .filter(|r| r.family.frame == Frame::LieGroup)
        .collect();
    let drift = lie
        .iter()
        .filter(|r| r.termination.starts_with("FrameDrift"))
        .count();
    let lie_worst = lie.iter().filter_map(|r| r.tip_error_m).fold(0.0, f64::max);
    let time: Vec<f64> = mm
        .iter()
        .filter(|r| !r.family.reduction.planar())
        .filter_map(|r| {
            let libm = Family {
                arithmetic: Arithmetic::F32,
                ..r.family
            };
            study
                .rows
                .iter()
                .find(|q| {
                    q.family == libm
                        && q.scene == r.scene
                        && q.steps_per_section == r.steps_per_section
                })
                .and_then(|q| time_ratio(r, q))
        })
        .collect();
    let time = Spread::of(&time).map_or("n/a".into(), |s| s.ratio());
    format!(
        "**micromath** (model-core's `fast-math`, f32): from {MICROMATH_MIN_STEPS} steps per section \
         on, cable lengths are off by up to {} mm in the 3D families (its square root, up to about 6 % off and exact only at powers of 4, \
         sums the chords between guides), against {} um with libm, while the solves report \
         `Converged`. Tips with the quaternion frame are {tip} libm's (the frame's \
         normalisation sits near 1, where the approximation is good). The Lie-group frame breaks: \
         {drift} of its {} rows (scene and step count) end in FrameDrift, and those that pass the drift test are up to {} mm \
         off at the tip. The 3D families' time per solve is {time} libm's, timed in a separate run of \
         a separate build (so the ratio also carries the machine's drift between runs): whatever it \
         saves, the cable lengths are unusable.",
        sig(cable(false, Arithmetic::F32Micromath) * 1e3),
        sig(cable(false, Arithmetic::F32) * 1e6),
        lie.len(),
        sig(lie_worst * 1e3),
    )
}

/// The warm-update instruction target of the Cortex-M4F, per update.
const UPDATE_TARGET_INSTRUCTIONS: u64 = 150_000;
/// The accuracy that must come with it: the tip within this of the converged f64 answer, m.
const UPDATE_TARGET_TIP_M: f64 = 1e-4;

fn mcu(study: &Study) -> Option<String> {
    let m = &study.mcu;
    let at = |n: u16| m.rows.iter().find(|r| r.qemu.steps_per_section == n);
    let firmware = at(20).or_else(|| m.rows.first())?;
    let fewest = m.rows.first()?;
    let describe = |r: &super::mcu::McuRow| {
        format!(
            "{} steps per section: {} instructions ({:.2} ms at 168 MHz if each took one cycle, a \
             lower bound), error {} um",
            r.qemu.steps_per_section,
            r.qemu.cold_instructions,
            super::mcu::lower_bound_ms(r.qemu.cold_instructions),
            sig(r.host_f32.error_m().unwrap_or(f64::NAN) * 1e6)
        )
    };
    let floor_from = m
        .rows
        .iter()
        .find(|r| {
            matches!(
                (r.host_f64.error_m(), r.host_f32.error_m()),
                (Some(e64), Some(e32)) if e64 < e32 / 4.0
            )
        })
        .map_or("none of the step counts".into(), |r| {
            format!("{} steps per section", r.qemu.steps_per_section)
        });
    // The one-sweep update against the converged f64 answer: its worst lag behind the same f32
    // model's forward solve along the bench's path plus that model's error at the path's first force
    // (an estimate: the model's error is measured at one force of the path only).
    let updates: Vec<String> = m
        .rows
        .iter()
        .filter_map(|r| {
            let n = r.qemu.update_one_sweep_instructions?;
            let bound = r.qemu.update_one_sweep_lag_m? + r.host_f32.error_m()?;
            let meets = n <= UPDATE_TARGET_INSTRUCTIONS && bound <= UPDATE_TARGET_TIP_M;
            Some(format!(
                "{} steps: {n} instructions, tip within about {} um{}",
                r.qemu.steps_per_section,
                sig(bound * 1e6),
                if meets { " (meets both)" } else { "" }
            ))
        })
        .collect();
    // A warm-update count per step count, as "N at S steps".
    let per_steps = |count: fn(&super::mcu::QemuCase) -> Option<u64>| {
        let listed: Vec<String> = m
            .rows
            .iter()
            .filter_map(|r| {
                Some(format!(
                    "{} at {} steps",
                    count(&r.qemu)?,
                    r.qemu.steps_per_section
                ))
            })
            .collect();
        join(&listed)
    };
    let warm = per_steps(|q| q.update_warm_instructions);
    let median = per_steps(|q| q.update_warm_median_instructions);
    Some(format!(
        "**Cortex-M4F** (QEMU instruction counts; errors computed on the host in f32): a plain sweep \
         costs {:.0} instructions per RK4 step. A cold f32 solve of the golden bench at {}; at {}. \
         The f32 error is f32's floor (the f64 model's is under a quarter of it) from {floor_from}. \
         The target of a warm 3D update within {UPDATE_TARGET_INSTRUCTIONS} instructions with the tip \
         within {} mm of the converged f64 answer: the update that converges every tick takes, on its \
         costliest tick of the bench's path, {warm} (instructions), and on its median tick {median}; \
         the one-sweep update (one Newton step and one sweep with six tangents per tick), with its tip \
         estimated as its worst lag behind \
         the same model's forward solve on the path plus that model's error at the path's first \
         force: {}.",
        m.instructions_per_step,
        describe(firmware),
        describe(fewest),
        UPDATE_TARGET_TIP_M * 1e3,
        join(&updates)
    ))
}

fn reductions(study: &Study) -> String {
    let total = study.reductions.len();
    let met = study.reductions.iter().filter(|r| r.meets()).count();
    let mut picks = Vec::new();
    let mut speedups = Vec::new();
    for r in study
        .reductions
        .iter()
        .filter(|r| r.tolerance_m == MAIN_TOLERANCE_M)
    {
        picks.push(format!(
            "{} at {} steps ({}, {})",
            r.picked.label(),
            r.picked_steps,
            r.scene,
            r.case_label.split(':').next().unwrap_or("")
        ));
        let full = r.full().and_then(|c| c.row.as_ref());
        let pick = r
            .candidates
            .iter()
            .find(|c| c.reduction == r.picked)
            .and_then(|c| c.row.as_ref());
        if let Some(x) = full.zip(pick).and_then(|(f, p)| time_ratio(f, p)) {
            speedups.push(x);
        }
    }
    let speedup = Spread::of(&speedups).map_or("n/a".into(), |s| s.ratio());
    let slower = speedups.iter().filter(|x| **x < 1.0).count();
    let slower = if slower == 0 {
        String::new()
    } else {
        format!(
            " ({slower} of {} picks slower on the host than the full model, which `choose`'s \
             machine-independent cost model does not see)",
            speedups.len()
        )
    };
    let shape = study.reductions.iter().filter(|r| r.shape_within()).count();
    let off_shape: Vec<String> = study
        .reductions
        .iter()
        .filter(|r| r.meets() && !r.shape_within())
        .map(|r| {
            format!(
                "{} at {} steps for {:.0e} m on {} ({} um)",
                r.picked.label(),
                r.picked_steps,
                r.tolerance_m,
                r.scene,
                sig(r.picked_shape_error_m.unwrap_or(f64::NAN) * 1e6)
            )
        })
        .collect();
    let shape = if off_shape.is_empty() {
        format!(" On the whole backbone (the study's error) {shape} of {total} are within it too.")
    } else {
        format!(
            " `choose` promises tip and cable lengths only: on the whole backbone {shape} of {total} \
             are within the tolerance; not {}.",
            join(&off_shape)
        )
    };
    let mut far = true;
    let bookkeeping: Vec<String> = study
        .reductions
        .iter()
        .filter_map(|r| {
            let b = r.bookkeeping.as_ref()?;
            let e = b.average.error_m()?;
            far &= e > 10.0 * MAIN_TOLERANCE_M;
            Some(format!("{} um on {}", sig(e * 1e6), r.scene))
        })
        .collect();
    let far = if far { ", far beyond 10 um" } else { "" };
    let bookkeeping = if bookkeeping.is_empty() {
        String::new()
    } else {
        format!(
            " Skipping the guides' mass bookkeeping under gravity (average instead of accurate guide \
             mass) is a different model, not a cheaper discretisation: {} off{far}; without \
             gravity the plan drops it by itself, at no error.",
            join(&bookkeeping)
        )
    };
    format!(
        "**Reductions.** `reduction::choose`'s pick meets its tolerance on tip and cable lengths \
         against this study's reference in {met} of {total} cases.{shape} For 10 um it picks {}; \
         measured on the host, {speedup} faster than the full 3D model at its own fewest steps for \
         the tolerance{slower}.{bookkeeping}",
        join(&picks)
    )
}

fn fronts(study: &Study) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for r in study.rows.iter().filter(|r| r.front_time) {
        let label = r.family.label();
        match counts.iter_mut().find(|c| c.0 == label) {
            Some(c) => c.1 += 1,
            None => counts.push((label, 1)),
        }
    }
    counts.sort_by_key(|c| std::cmp::Reverse(c.1));
    let list: Vec<String> = counts
        .iter()
        .map(|(label, n)| format!("{label} ({n})"))
        .collect();
    format!(
        "**Pareto fronts** (host time against error, all scenes): {}.",
        join(&list)
    )
}

/// The conclusions, one paragraph each.
pub fn conclusions(study: &Study) -> Vec<String> {
    let mut out = vec![convergence(study), frames(study), kirchhoff(study)];
    out.extend(planar(study));
    out.push(f32_floor(study));
    out.push(micromath(study));
    out.extend(mcu(study));
    out.push(reductions(study));
    out.push(fronts(study));
    if study.tendon.is_some() {
        out.push(
            "**Tendons** (the section *Tendons that pull* below, with its own conclusions): the \
             discrete guides against continuous routing and piecewise constant curvature on the \
             thesis bench with three tendons and the two-section robot with six, the forward \
             solve from tensions against displacement control, the firmware's tendon instruction \
             counts and `choose_tendons`' picks."
                .into(),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(termination: &str, host_time_us: f64) -> Row {
        Row {
            scene: "s".into(),
            family: Family::REFERENCE,
            steps_per_section: 3,
            rk4_steps_per_sweep: 3,
            cases: 1,
            sweeps_per_solve: 4.0,
            work_rk4_steps: 12.0,
            host_time_us,
            timed_runs: 1,
            termination: termination.into(),
            tip_error_m: None,
            backbone_error_m: None,
            cable_error_m: None,
            tendon_work: None,
            front_work: false,
            front_time: false,
        }
    }

    /// A solve that failed (here refused as under-resolved, or drifted) has a time but no answer:
    /// no speed ratio is taken from it (the study's micromath ratio once reached 1.70 on such a
    /// pair: 0.94-1.70x over every pair of that run, 0.94-1.03x over those that converged).
    #[test]
    fn no_time_ratio_is_taken_from_a_failed_solve() {
        let ok = row("Converged", 10.0);
        assert_eq!(time_ratio(&row("Converged", 5.0), &ok), Some(0.5));
        assert_eq!(time_ratio(&row("UnderResolved (case 0)", 5.0), &ok), None);
        assert_eq!(time_ratio(&ok, &row("FrameDrift (case 1)", 5.0)), None);
    }

    /// Two families' median sweeps come from the same pairs: a scene where either failed counts
    /// for neither (the planar reduction's sweeps were once its converged rows, the 3D model's
    /// every converged row on a scene the reduction was measured on, converged or not).
    #[test]
    fn median_sweeps_compare_the_same_pairs() {
        let planar = family(Arithmetic::F64, Frame::Quaternion, Reduction::Planar);
        let at = |scene: &str, family: Family, termination: &str, sweeps: f64| Row {
            scene: scene.into(),
            family,
            sweeps_per_solve: sweeps,
            ..row(termination, 1.0)
        };
        let rows = [
            at("a", Family::REFERENCE, "Converged", 3.0),
            at("a", planar, "Converged", 5.0),
            at("b", Family::REFERENCE, "Converged", 9.0),
            at("b", planar, "UnderResolved (case 0)", 1.0),
            at("c", Family::REFERENCE, "Converged", 9.0),
        ];
        assert_eq!(median_sweeps(&rows, &planar, &Family::REFERENCE), Some(5.0));
        assert_eq!(median_sweeps(&rows, &Family::REFERENCE, &planar), Some(3.0));
    }
}
