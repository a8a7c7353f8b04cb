//! The text report of a calibration from the user's data.

use std::fmt::Write as _;

use super::fit::{Calibration, Verdict};

/// `n` and `what`, plural unless one.
fn counted(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// A number with its unit, short.
fn with_unit(x: f64, unit: &str) -> String {
    if unit == "1" {
        format!("{x:.6}")
    } else {
        format!("{x:.6e} {unit}")
    }
}

/// The whole report: the status line and warnings, the parameters, what is undetermined, the
/// residuals per observation, leave-one-out.
pub fn report(c: &Calibration) -> String {
    let mut t = String::new();
    let s = &c.status;
    let _ = writeln!(
        t,
        "status: {} (verdict {:?}, fit {}, {} iterations; exit {})",
        s.summary, s.verdict, s.termination, s.iterations, s.exit_code
    );
    for w in &s.warnings {
        let _ = writeln!(t, "warning: {w}");
    }
    let _ = writeln!(t, "scene: {}", c.scene);
    let _ = writeln!(
        t,
        "data: {}: {}, {} ({} residuals, {} to spare)",
        c.data,
        counted(c.experiments, "experiment"),
        counted(c.observations, "observed point"),
        3 * c.observations,
        c.dof
    );
    let _ = writeln!(
        t,
        "fitted: {} ({} forward solves)",
        c.fitted.join(", "),
        c.forward_solves
    );
    let _ = writeln!(
        t,
        "\nparameter            start                fitted               1 sd"
    );
    for p in &c.parameters {
        let (value, sd) = match (p.value, p.std) {
            (Some(v), Some(sd)) => (with_unit(v, p.unit), with_unit(sd, p.unit)),
            _ if s.verdict == Verdict::NoAnswer => ("no fit".into(), String::new()),
            _ => ("undetermined".into(), String::new()),
        };
        let bound = if p.at_bound { "  (on its bound)" } else { "" };
        let row = format!(
            "{:<20} {:<20} {:<20} {sd}{bound}",
            p.name,
            with_unit(p.start, p.unit),
            value
        );
        let _ = writeln!(t, "{}", row.trim_end());
    }
    for u in &c.undetermined {
        let _ = writeln!(
            t,
            "undetermined combination: {} ({}; singular value {:.1e} of the largest)",
            u.combination,
            if u.rank_deficient {
                "the observed points do not change along it"
            } else {
                "its standard deviation is beyond its limit"
            },
            u.singular_ratio
        );
    }
    match (c.rms_mm, c.residual_sd_mm) {
        (Some(rms), Some(sd)) => {
            let _ = writeln!(
                t,
                "\nrms distance: {rms:.4} mm fitted; residual sd {sd:.4} mm per coordinate (unit \
                 weight)"
            );
        }
        (Some(rms), None) => {
            let _ = writeln!(t, "\nrms distance: {rms:.4} mm fitted");
        }
        _ => {}
    }
    if let Some(start) = c.start_rms_mm {
        let _ = writeln!(t, "rms distance at the start: {start:.4} mm");
    }
    if c.rms_mm.is_some() {
        let _ = writeln!(
            t,
            "\nresiduals, model minus measured, mm (measurement frame)\n\
             line  experiment  s_m  dx_mm  dy_mm  dz_mm  distance_mm  weight"
        );
        for o in &c.residuals {
            if let (Some(r), Some(d)) = (o.residual_mm, o.distance_mm) {
                let s = if o.at_tip {
                    "tip".to_string()
                } else {
                    format!("{:.6}", o.s_m)
                };
                let _ = writeln!(
                    t,
                    "{}  {}  {s}  {:+.4}  {:+.4}  {:+.4}  {:.4}  {}",
                    o.line, o.experiment, r[0], r[1], r[2], d, o.weight
                );
            }
        }
    }
    if !c.leave_one_out.is_empty() {
        let first = c
            .parameters
            .first()
            .map_or("first parameter".to_string(), |p| {
                format!("{} without it ({})", p.name, p.unit)
            });
        let _ = writeln!(
            t,
            "\nleave-one-out: fit without the experiment, predict its points\n\
             experiment  points  {first}  prediction rms_mm"
        );
        for f in &c.leave_one_out {
            let cell =
                |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map_or_else(|| "-".to_string(), f);
            let _ = writeln!(
                t,
                "{}  {}  {}  {}{}",
                f.experiment,
                f.observations,
                cell(f.first_parameter, &|x| format!("{x:.6e}")),
                cell(f.rms_mm, &|x| format!("{x:.4}")),
                match f.verdict {
                    Verdict::Determined => "",
                    Verdict::Undetermined => "  (undetermined without it)",
                    Verdict::NoAnswer => "  (no fit without it)",
                }
            );
        }
        if let Some(rms) = c.leave_one_out_rms_mm {
            let _ = writeln!(t, "rms leave-one-out error: {rms:.4} mm");
        }
    } else if c.experiments < 2 {
        let _ = writeln!(t, "\nleave-one-out: needs two experiments or more");
    }
    if let Some(path) = &c.written {
        let _ = writeln!(t, "\ncalibrated scene written to {path}");
    }
    t
}
