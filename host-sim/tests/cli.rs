//! The `host-sim` command line, run as a user runs it: exit codes, printed numbers, files.

use std::path::PathBuf;
use std::process::{Command, Output};

use model_checks::reference::golden_rows;
use serde_json::Value;

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn scene(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .display()
        .to_string()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The number after `label` on the line that contains it.
fn number_after(text: &str, label: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("no line with {label:?} in:\n{text}"));
    let rest = &line[line.find(label).unwrap() + label.len()..];
    rest.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .find(|s| !s.is_empty() && s.parse::<f64>().is_ok())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no number after {label:?} in {line:?}"))
}

#[test]
fn validate_reproduces_the_thesis_and_exits_zero() {
    let out = host_sim(&["validate"]);
    let text = stdout(&out);
    assert!(
        out.status.success(),
        "validate failed:\n{text}\n{}",
        stderr(&out)
    );
    assert!(!text.contains("[FAIL]"), "{text}");
    // The reproduction figures themselves, not only the verdicts.
    let t41 = number_after(
        &text,
        "Table 4.1: worst distance from the thesis's predicted section tips, cm:",
    );
    assert!(t41 < 0.05, "Table 4.1 reproduction {t41} cm");
    let t45a = number_after(
        &text,
        "Table 4.5 (average): worst distance from the thesis's deltas, cm:",
    );
    let t45b = number_after(
        &text,
        "Table 4.5 (accurate): worst distance from the thesis's deltas, cm:",
    );
    assert!(
        t45a < 0.005 && t45b < 0.005,
        "Table 4.5 reproduction {t45a} / {t45b} cm"
    );
    // Our mean errors against the observations, next to the thesis's printed ones.
    assert!(
        text.contains("printed: 0.92 %")
            && text.contains("printed: 1.33 %")
            && text.contains("printed: 1.27 %")
    );
    let mean_avg = number_after(
        &text,
        "Table 4.3 (average): mean tip error vs observed, % of rod:",
    );
    assert!(
        (1.0..1.8).contains(&mean_avg),
        "Table 4.3 mean error {mean_avg} %"
    );
}

#[test]
fn inverse_recovers_light_loads_and_widens_where_the_cable_saturates() {
    let out = host_sim(&["inverse"]);
    let text = stdout(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    // Average-mass table: rows "hung | delta | estimate +- sd | ...".
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip_while(|l| !l.contains("average mass"))
        .filter(|l| {
            l.trim_start()
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_digit())
        })
        .take(6)
        .map(|l| {
            l.split(['|', '+', ','])
                .filter_map(|f| f.trim().trim_start_matches('-').trim().parse::<f64>().ok())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 6, "{text}");
    // 17.2 g and 27.2 g: the estimate lies within 2 sd of the hung mass, and the sd is a few grams.
    for r in &rows[1..3] {
        let (est, sd) = (r[2], r[3]);
        assert!((est - r[0]).abs() < 2.0 * sd, "row {r:?}");
        assert!(sd < 5.0, "row {r:?}");
    }
    // Saturation: at 62.2 and 83.2 g the sd is wider than the estimate's distance from any light load.
    assert!(rows[4][3] > 50.0 && rows[5][3] > 50.0, "{text}");
    // And the 83.2 g row, beyond what any load on the prior's scale explains, is flagged.
    let last = text
        .lines()
        .skip_while(|l| !l.contains("average mass"))
        .find(|l| l.trim_start().starts_with("83.2"))
        .unwrap_or_default();
    assert!(last.ends_with("Inconsistent"), "{text}");
}

#[test]
fn solve_and_estimate_reproduce_every_golden_row() {
    let bench = scene("bench_3d_cables.toml");
    for row in golden_rows() {
        let row = row.unwrap();
        let f = format!("{},{},{}", row.force_n[0], row.force_n[1], row.force_n[2]);
        let out = host_sim(&["solve", &bench, "--tip-force", &f, "--format", "json"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let v: Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(v["report"]["termination"], "Converged");
        for i in 0..3 {
            let tip = v["tip_position_m"][i].as_f64().unwrap();
            assert!(
                (tip - row.tip_m[i]).abs() < 1e-5,
                "tip {i}: {tip} vs {}",
                row.tip_m[i]
            );
            let cable = v["cable_lengths_m"][i].as_f64().unwrap();
            assert!(
                (cable - row.cables_m[i]).abs() < 1e-6,
                "cable {i}: {cable} vs {}",
                row.cables_m[i]
            );
        }
        let c = format!(
            "{},{},{}",
            row.cables_m[0], row.cables_m[1], row.cables_m[2]
        );
        let out = host_sim(&["estimate", &bench, "--cables", &c, "--format", "json"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let v: Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(v["report"]["termination"], "Converged");
        let tip_err: f64 = (0..3)
            .map(|i| (v["tip_position_m"][i].as_f64().unwrap() - row.tip_m[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(tip_err < 1e-4, "estimated tip off by {tip_err} m");
        for i in 0..3 {
            let err = (v["tip_force_n"][i].as_f64().unwrap() - row.force_n[i]).abs();
            let sd = v["tip_force_std_n"][i].as_f64().unwrap();
            assert!(
                err <= sd,
                "force {i}: error {err} N beyond its reported sd {sd} N"
            );
        }
    }
}

#[test]
fn solve_writes_csv_and_json_files() {
    let dir = temp_dir("solve");
    let csv = dir.join("shape.csv");
    let out = host_sim(&[
        "solve",
        &scene("thesis_exp2_average.toml"),
        "--format",
        "csv",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "s_m,x_m,y_m,z_m,tan_x,tan_y,tan_z,u_x_per_m,u_y_per_m,u_z_per_m"
    );
    assert_eq!(lines.len(), 1 + 41);
    // The unloaded bench sags 5.70 cm at the tip (Table 4.3, this model).
    let last: Vec<f64> = lines[41].split(',').map(|x| x.parse().unwrap()).collect();
    assert!(
        (last[0] - 0.39).abs() < 1e-12 && (last[2] + 0.0570).abs() < 2e-4,
        "{last:?}"
    );
}

fn bad_scene(name: &str, text: &str) -> String {
    let dir = temp_dir(name);
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let out = host_sim(&["solve", path.to_str().unwrap()]);
    assert!(!out.status.success(), "a bad scene must fail");
    let err = stderr(&out);
    assert!(
        !err.contains("panicked") && !err.contains("backtrace"),
        "{err}"
    );
    err
}

#[test]
fn bad_scenes_name_the_field_and_the_reason() {
    let good = std::fs::read_to_string(scene("thesis_exp2_average.toml")).unwrap();
    let err = bad_scene("neg", &good.replace("length_m = 0.39", "length_m = -0.39"));
    assert!(
        err.contains("section[0].length_m") && err.contains("positive"),
        "{err}"
    );
    let err = bad_scene("typo", &good.replace("steps = 100", "stepz = 100"));
    assert!(
        err.contains("unknown field `stepz`") && err.contains("line 13"),
        "{err}"
    );
    let err = bad_scene("type", &good.replace("steps = 100", "steps = \"many\""));
    assert!(
        err.contains("line 13") && err.contains("steps") && err.contains("expected u16"),
        "{err}"
    );
    let err = bad_scene("guide", &good.replace("pitch_m = 0.095", "pitch_m = 0.2"));
    assert!(err.contains("guides") && err.contains("range"), "{err}");
    let err = bad_scene(
        "attitude",
        &format!("{good}\n[solver]\nattitude = \"euler\"\n"),
    );
    assert!(
        err.contains("solver.attitude") && err.contains("euler"),
        "{err}"
    );
    let err = bad_scene(
        "nostiff",
        &good.replace(
            "material = { youngs_modulus_pa = 62.7e9, poisson_ratio = 0.3 }\n",
            "",
        ),
    );
    assert!(
        err.contains("section[0]") && err.contains("material"),
        "{err}"
    );
    let out = host_sim(&["solve", "/nonexistent/scene.toml"]);
    assert!(!out.status.success() && stderr(&out).contains("cannot read"));
    let out = host_sim(&[
        "estimate",
        &scene("bench_3d_cables.toml"),
        "--cables",
        "0.39,0.39",
    ]);
    assert!(
        !out.status.success() && stderr(&out).contains("cable"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn plots_are_written_and_not_trivial() {
    let dir = temp_dir("plots");
    let out = host_sim(&["validate", "--plots", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    for name in [
        "exp1a_shapes",
        "exp2_average_shapes",
        "exp2_accurate_shapes",
        "cable_delta",
    ] {
        let png = std::fs::read(dir.join(format!("{name}.png"))).unwrap();
        assert!(
            png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 20_000,
            "{name}.png: {} bytes",
            png.len()
        );
        let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).unwrap();
        // One polyline per predicted curve, and text drawn (axis labels).
        let curves = svg.matches("<polyline").count();
        assert!(curves >= 5, "{name}.svg has {curves} polylines");
        assert!(
            svg.contains("<text") && svg.contains("cm"),
            "{name}.svg has no labels"
        );
    }
}

#[test]
fn calibrate_fits_a_modulus_inside_the_measured_range() {
    let out = host_sim(&["calibrate", "--table", "4.3"]);
    let text = stdout(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    // The thesis measured 61.6-62.7 GPa; the fit must land near and explain the data about as well.
    let e = number_after(&text, "Young's modulus:");
    assert!((60.0..64.0).contains(&e), "{text}");
    let loo = number_after(&text, "rms leave-one-out error:");
    let fitted = number_after(&text, "rms error:");
    assert!(fitted < 0.7 && loo < 1.0 && loo >= fitted, "{text}");
    // Piped: no progress bar on stdout or stderr.
    assert!(!stderr(&out).contains("fits"), "{}", stderr(&out));
}

#[test]
fn quick_study_writes_its_report_and_every_check_passes() {
    let dir = temp_dir("study");
    let out = host_sim(&["study", "--quick", "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}\n{}", stdout(&out), stderr(&out));
    let text = stdout(&out);
    assert!(!text.contains("FAIL"), "{text}");
    assert!(
        text.matches("\nok ").count() + usize::from(text.starts_with("ok ")) >= 15,
        "{text}"
    );

    let report = std::fs::read_to_string(dir.join("accuracy_cost.md")).expect("report");
    assert!(report.contains(" passed, 0 failed)"), "{report}");
    for section in [
        "## Conclusions from this run",
        "## Error and cost by variant",
        "## Model only what a scene requires",
        "## Cortex-M4F instruction counts",
    ] {
        assert!(report.contains(section), "no {section}");
    }

    // One CSV line per scene, family and step count: three step counts in quick mode; the planar
    // reductions only on the in-plane exp-2 scenes.
    let csv = std::fs::read_to_string(dir.join("accuracy_cost.csv")).expect("csv");
    let lines: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(lines.len(), 3 * (12 + 12 + 8), "{csv}");
    let column = |name: &str| {
        csv.lines()
            .next()
            .and_then(|h| h.split(',').position(|c| c == name))
            .expect(name)
    };
    let (reduction, steps, error) = (
        column("reduction"),
        column("steps_per_section"),
        column("error_um"),
    );
    for line in &lines {
        let fields: Vec<&str> = line.split(',').collect();
        if fields[reduction] == "3D" && fields[steps] == "100" && fields[1] == "f64" {
            let e: f64 = fields[error].parse().expect("an error in um");
            assert!(e < 0.01, "f64 3D at 100 steps: {line}");
        }
    }

    for (name, min_bytes) in [("pareto.svg", 20_000), ("pareto.png", 50_000)] {
        let len = std::fs::metadata(dir.join(name)).map_or(0, |m| m.len());
        assert!(len > min_bytes, "{name}: {len} bytes");
    }
}

#[test]
fn study_refuses_an_unknown_scene() {
    let dir = temp_dir("study-bad");
    let out = host_sim(&[
        "study",
        "--quick",
        "--scenes",
        "nowhere",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("unknown \"nowhere\""),
        "{}",
        stderr(&out)
    );
}
