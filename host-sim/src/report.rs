//! Text reports of the experiments: aligned tables, one row per thesis row.

use std::fmt::Write;

use crate::thesis::{
    Check, THESIS_MEAN_ERR_4_1_PCT, THESIS_MEAN_ERR_4_3_PCT, THESIS_MEAN_ERR_4_5_CM, Table41,
    Table43, Table45, TipRow, Validation, left_out_note, not_converged,
};

fn tip_row(out: &mut String, r: &TipRow, length_cm: f64) {
    let _ = writeln!(
        out,
        "{:>7.1} | {:>6.2} {:>6.2} | {:>6.2} {:>6.2} | {:>6.2} {:>6.2} | {:>6.3} {:>6.2} | {:>6.3} {:>6.2} | {:>6.3} | {}",
        r.mass_g,
        r.observed.x,
        r.observed.y,
        r.thesis.x,
        r.thesis.y,
        r.ours.x,
        r.ours.y,
        r.thesis_error_cm(),
        r.thesis_error_cm() / length_cm * 100.0,
        r.error_cm(),
        r.error_cm() / length_cm * 100.0,
        r.reproduction_cm(),
        if r.converged {
            "stable"
        } else {
            "NOT CONVERGED/STABLE"
        },
    );
}

const TIP_HEADER: &str = "mass(g) |   observed    |    thesis     |     ours      | thesis err(cm,%) |  our err(cm,%)  | |ours-thesis|(cm)\n";

fn table_4_1(out: &mut String, t: &Table41) {
    let _ = writeln!(
        out,
        "\nTable 4.1 (experiment 1a): two 19.5 cm sections, mass hung at the transition; x, y in cm; % of the section length\n"
    );
    for (name, rows, i) in [
        ("section 1 tip", &t.section1, 0usize),
        ("section 2 tip", &t.section2, 1),
    ] {
        let _ = writeln!(out, "{name}");
        out.push_str(TIP_HEADER);
        for r in rows {
            tip_row(out, r, t.section_length_cm);
        }
        let ours = t.mean_error_pct()[i];
        let thesis = t.thesis_mean_error_pct()[i];
        let cm = t.mean_error_cm()[i];
        let _ = writeln!(
            out,
            "mean error vs observed: ours {cm:.3} cm = {ours:.2} %{}; thesis {thesis:.2} % (printed: {:.2} %)\n",
            left_out_note(not_converged(rows)),
            THESIS_MEAN_ERR_4_1_PCT[i]
        );
    }
}

fn table_4_3(out: &mut String, t: &Table43, number: &str) {
    let _ = writeln!(
        out,
        "\nTable {number} (experiment 2, {} mass): five guides, mass hung at the tip; x, y in cm; % of the {:.0} cm rod\n",
        t.model, t.rod_length_cm
    );
    out.push_str(TIP_HEADER);
    for r in &t.rows {
        tip_row(out, r, t.rod_length_cm);
    }
    let _ = writeln!(
        out,
        "mean error vs observed: ours {:.3} cm = {:.2} %{}; thesis {:.2} % (printed: {THESIS_MEAN_ERR_4_3_PCT:.2} %)",
        t.mean_error_cm(),
        t.mean_error_pct(),
        left_out_note(not_converged(&t.rows)),
        t.thesis_mean_error_pct()
    );
}

fn table_4_5(out: &mut String, t: &Table45) {
    let _ = writeln!(
        out,
        "\nTable 4.5: change of the upper cable's length from 0 g, cm (observed on the bench's ruler)\n"
    );
    let _ = writeln!(
        out,
        "mass(g) | observed | thesis avg | ours avg | err avg | thesis acc | ours acc | err acc | ours-thesis avg, acc"
    );
    for r in &t.rows {
        let _ = writeln!(
            out,
            "{:>7.1} | {:>8.3} | {:>10.4} | {:>8.4} | {:>7.4} | {:>10.4} | {:>8.4} | {:>7.4} | {:>+7.4} {:>+7.4}{}",
            r.mass_g,
            r.observed_cm,
            r.thesis_cm[0],
            r.ours_cm[0],
            (r.ours_cm[0] - r.observed_cm).abs(),
            r.thesis_cm[1],
            r.ours_cm[1],
            (r.ours_cm[1] - r.observed_cm).abs(),
            r.ours_cm[0] - r.thesis_cm[0],
            r.ours_cm[1] - r.thesis_cm[1],
            match r.converged {
                [true, true] => "",
                [false, true] => " | NOT CONVERGED/STABLE (average)",
                [true, false] => " | NOT CONVERGED/STABLE (accurate)",
                [false, false] => " | NOT CONVERGED/STABLE",
            },
        );
    }
    let ours = t.mean_error_cm();
    let failed = t.not_converged();
    let _ = writeln!(
        out,
        "mean |error| vs observed: ours {:.4} cm (average){}, {:.4} cm (accurate){}; thesis printed {:.4} / {:.3} cm",
        ours[0],
        left_out_note(failed[0]),
        ours[1],
        left_out_note(failed[1]),
        THESIS_MEAN_ERR_4_5_CM[0],
        THESIS_MEAN_ERR_4_5_CM[1]
    );
    let _ = writeln!(
        out,
        "our predicted reference lengths at 0 g: {:.3} cm (average), {:.3} cm (accurate); thesis 38.72 / 38.75 cm",
        t.rows.first().map_or(f64::NAN, |r| r.ours_length_cm[0]),
        t.rows.first().map_or(f64::NAN, |r| r.ours_length_cm[1]),
    );
}

/// The checks, one line each.
pub fn checks(out: &mut String, checks: &[Check]) {
    let _ = writeln!(out, "\nReproduction checks");
    for c in checks {
        let _ = writeln!(
            out,
            "  [{}] {}: {:.4} (limit {})",
            if c.passed { "ok" } else { "FAIL" },
            c.name,
            c.value,
            c.limit
        );
    }
}

/// The whole `validate` report.
pub fn validation(v: &Validation) -> String {
    let mut out = String::new();
    table_4_1(&mut out, &v.table_4_1);
    table_4_3(&mut out, &v.table_4_3_average, "4.3");
    table_4_3(&mut out, &v.table_4_4_accurate, "4.4");
    table_4_5(&mut out, &v.table_4_5);
    checks(&mut out, &v.checks());
    out
}

/// The `inverse` report.
pub fn inverse(model: &str, rows: &[crate::thesis::InverseRow]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nInverse on Table 4.5 ({model} mass): hung mass and tip from the one measured cable; 1 sd from the ruler's 1 mm\n"
    );
    let _ = writeln!(
        out,
        "hung(g) | delta(cm) | estimate(g)        | tip estimate (cm)          | observed tip | residual(cm) | verdict"
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{:>7.1} | {:>9.3} | {:>7.1} +- {:>7.1} | {:>6.2} +- {:>5.2}, {:>6.2} +- {:>5.2} | {:>5.1} {:>5.1} | {:>+12.4} | {:?}, {:?}",
            r.hung_g,
            r.observed_delta_cm,
            r.estimate_g,
            r.std_g,
            r.tip.x,
            r.tip_std_cm[0],
            r.tip.y,
            r.tip_std_cm[1],
            r.observed_tip.x,
            r.observed_tip.y,
            r.residual_cm,
            r.termination,
            r.determination,
        );
    }
    out
}

/// The `calibrate` report.
pub fn calibration(c: &crate::calibrate::Calibration) -> String {
    let mut out = String::new();
    let table = match c.dataset {
        crate::calibrate::Dataset::Table41 => "Table 4.1 (two sections, both section tips)",
        crate::calibrate::Dataset::Table43 => "Table 4.3 (guides, average mass, tip)",
    };
    let _ = writeln!(
        out,
        "\nCalibration on {table}: least squares on the observed points\n"
    );
    let _ = writeln!(
        out,
        "Young's modulus{}: {:.2} GPa +- {:.2} GPa (1 sd; the scene's value {:.2} GPa)",
        c.verdict.note(),
        c.youngs_modulus_pa / 1e9,
        c.youngs_std_pa / 1e9,
        c.start_youngs_modulus_pa / 1e9
    );
    if let Some((scale, std)) = c.density_scale {
        let _ = writeln!(out, "line-density scale: {scale:.3} +- {std:.3} (1 sd)");
    }
    let _ = writeln!(
        out,
        "rms error: {:.3} cm fitted, {:.3} cm at the scene's parameters",
        c.rms_cm, c.start_rms_cm
    );
    let _ = writeln!(out, "\nleave-one-out: fit without the row, predict it");
    let _ = writeln!(
        out,
        "mass(g) | E without it (GPa) | error of its prediction (cm)"
    );
    for l in &c.loo {
        let _ = writeln!(
            out,
            "{:>7.1} | {:>17.2} | {:>8.3}{}",
            l.mass_g,
            l.youngs_modulus_pa / 1e9,
            l.error_cm,
            l.verdict.note()
        );
    }
    let _ = writeln!(out, "rms leave-one-out error: {:.3} cm", c.loo_rms_cm);
    out
}
