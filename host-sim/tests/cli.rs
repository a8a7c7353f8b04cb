//! The `host-sim` command line, run as a user runs it: exit codes, printed numbers, files.

use std::process::Output;

use model_checks::reference::golden_rows;
use serde_json::Value;

mod common;
use common::{code, host_sim, scene, stderr, stdout, temp_dir, write_scene};

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
        assert_eq!(v["status"]["verdict"], "answer");
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
        assert_eq!(v["status"]["exit_code"], 0);
        assert!(v["status"]["determination"].is_string(), "{}", v["status"]);
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
        "s_m,x_m,y_m,z_m,tan_x,tan_y,tan_z,u_x_per_m,u_y_per_m,u_z_per_m,status"
    );
    assert_eq!(lines.len(), 1 + 41);
    // The unloaded bench sags 5.70 cm at the tip (Table 4.3, this model); the status last.
    let (numbers, status) = lines[41].rsplit_once(',').unwrap();
    assert_eq!(status, "Converged/Stable");
    let last: Vec<f64> = numbers.split(',').map(|x| x.parse().unwrap()).collect();
    assert!(
        (last[0] - 0.39).abs() < 1e-12 && (last[2] + 0.0570).abs() < 2e-4,
        "{last:?}"
    );

    let json = dir.join("shape.json");
    let out = host_sim(&[
        "solve",
        &scene("thesis_exp2_average.toml"),
        "--format",
        "json",
        "--out",
        json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["status"]["verdict"], "answer");
    assert_eq!(v["shape"].as_array().map(Vec::len), Some(41));
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
    // Found when the rod is built, after parsing: still at its line.
    let line = good
        .lines()
        .position(|l| l.contains("length_m = 0.39"))
        .unwrap()
        + 1;
    assert!(
        err.contains(&format!(
            "line {line} (`length_m = -0.39`): section[0].length_m"
        )) && err.contains("positive"),
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
fn an_unusual_value_is_warned_about_at_its_line_and_the_solve_goes_on() {
    let good = std::fs::read_to_string(scene("bench_3d_cables.toml")).unwrap();
    let text = good.replacen("mass_kg = 0.0", "mass_kg = 2.0", 1);
    let path = write_scene("warned", &text);
    let out = host_sim(&["solve", &path]);
    let err = stderr(&out);
    let line = text.lines().position(|l| l == "mass_kg = 2.0").unwrap() + 1;
    assert!(
        out.status.success()
            && err.contains(&format!(
                "warning: {path}, line {line} (`mass_kg = 2.0`): guides.mass_kg: 2 kg is a heavy \
                 guide"
            ))
            && err.contains("Did you mean 2e-3 kg (2 g)?"),
        "{err}"
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
        "## Tendons that pull",
        "### Conclusions (tendons)",
        "### From tensions or from displacements",
        "### Cortex-M4F instruction counts (tendons)",
        "### `choose_tendons`",
    ] {
        assert!(report.contains(section), "no {section}");
    }

    // One CSV line per scene, family and step count: three step counts in quick mode; the planar
    // reductions only on the in-plane exp-2 scenes. Then the two tendon scenes: the discrete guides
    // (f64, f32) and continuous routing on the three step counts, and PCC (no grid).
    let csv = std::fs::read_to_string(dir.join("accuracy_cost.csv")).expect("csv");
    let lines: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(lines.len(), 3 * (12 + 12 + 8) + 2 * (3 * 3 + 1), "{csv}");
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
    let scene = column("scene");
    let mut tendon_rows = 0;
    for line in &lines {
        let fields: Vec<&str> = line.split(',').collect();
        if fields[reduction] == "3D" && fields[steps] == "100" && fields[1] == "f64" {
            let e: f64 = fields[error].parse().expect("an error in um");
            assert!(e < 0.01, "f64 3D at 100 steps: {line}");
        }
        if fields[scene].starts_with("tendon-") {
            tendon_rows += 1;
            // The discrete guides converge on the reference; PCC ignores gravity and is cm off.
            let e: Option<f64> = fields[error].parse().ok();
            match (fields[reduction], fields[steps], fields[1]) {
                ("discrete guides", "100", "f64") => {
                    assert!(e.is_some_and(|e| e < 0.1), "{line}")
                }
                ("PCC", _, _) => assert!(e.is_some_and(|e| e > 1e4), "{line}"),
                _ => {}
            }
        }
    }
    assert_eq!(tendon_rows, 20, "{csv}");

    for (name, min_bytes) in [
        ("pareto.svg", 20_000),
        ("pareto.png", 50_000),
        ("tendon_pareto.svg", 10_000),
        ("tendon_pareto.png", 30_000),
    ] {
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

// ---- Failures look like failures: exit codes, the status in every format, no failed iterate. ----

fn bench_text() -> String {
    std::fs::read_to_string(scene("bench_3d_cables.toml")).unwrap()
}

/// The JSON output.
fn json_of(o: &Output) -> Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

/// The unloaded golden bench's cable lengths, m (`solve` on the scene with no tip force).
const BENCH_UNLOADED_CABLES_M: [f64; 3] = [0.391_175_475_8, 0.377_302_163_5, 0.382_546_440_7];

#[test]
fn help_documents_the_exit_codes() {
    for command in ["solve", "estimate"] {
        let out = host_sim(&[command, "--help"]);
        let text = stdout(&out);
        assert_eq!(code(&out), 0);
        for line in [
            "0  a converged answer",
            "1  invalid input",
            "2  command-line usage error",
            "3  no answer",
            "4  estimate only",
        ] {
            assert!(
                text.contains(line),
                "{command} --help lacks {line:?}:\n{text}"
            );
        }
    }
}

/// 100 N on the 39 cm bench: load continuation fails (`ContinuationFailed`). The failed iterate
/// (cable lengths of 0.18 m) must not be printed in any format, and the exit code is 3.
#[test]
fn a_failed_solve_exits_3_and_prints_no_answer_in_any_format() {
    let bench = scene("bench_3d_cables.toml");
    let force = "--tip-force=0,-100,0";

    let out = host_sim(&["solve", &bench, force]);
    assert_eq!(code(&out), 3, "{}", stdout(&out));
    let text = stdout(&out);
    let first = text.lines().next().unwrap_or_default();
    assert!(
        first.starts_with("status: no answer") && first.contains("ContinuationFailed"),
        "{text}"
    );
    assert!(text.contains("\nno answer"), "{text}");
    assert!(
        !text.contains("cable lengths [")
            && !text.contains("tip position [")
            && !text.contains("s_m,"),
        "{text}"
    );
    assert!(stderr(&out).contains("no answer"), "{}", stderr(&out));

    let out = host_sim(&["solve", &bench, force, "--format", "json"]);
    assert_eq!(code(&out), 3);
    let v = json_of(&out);
    assert_eq!(v["status"]["verdict"], "no_answer");
    assert_eq!(v["status"]["exit_code"], 3);
    assert_eq!(v["status"]["termination"], "ContinuationFailed");
    for key in ["tip_position_m", "tip_tangent", "cable_lengths_m", "shape"] {
        assert!(v[key].is_null(), "{key}: {}", v[key]);
    }
    // The inputs and the report (how far the solve got) stay.
    assert_eq!(v["tip_force_n"][1], -100.0);
    assert!(v["report"]["residual"].is_number(), "{}", v["report"]);

    let out = host_sim(&["solve", &bench, force, "--format", "csv"]);
    assert_eq!(code(&out), 3);
    let text = stdout(&out);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(lines[0].ends_with(",status"), "{text}");
    let (numbers, status) = lines[1].rsplit_once(',').unwrap();
    assert!(numbers.split(',').all(str::is_empty), "{text}");
    assert!(status.starts_with("ContinuationFailed/"), "{text}");
}

#[test]
fn a_converged_solve_exits_0_with_its_status_in_every_format() {
    let bench = scene("bench_3d_cables.toml");

    let out = host_sim(&["solve", &bench]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.starts_with(
            "status: converged, stable (termination Converged, stability Stable; exit 0)\n"
        ),
        "{text}"
    );
    assert!(text.contains("cable lengths ["), "{text}");
    assert!(stderr(&out).is_empty(), "{}", stderr(&out));

    let out = host_sim(&["solve", &bench, "--format", "json"]);
    assert_eq!(code(&out), 0);
    let v = json_of(&out);
    let status = &v["status"];
    assert_eq!(status["verdict"], "answer");
    assert_eq!(status["exit_code"], 0);
    assert_eq!(status["termination"], "Converged");
    assert_eq!(status["stability"], "Stable");
    assert_eq!(status["stability_checked"], true);
    assert!(status.get("determination").is_none(), "{status}");
    assert_eq!(status["warnings"].as_array().map(Vec::len), Some(0));
    assert_eq!(v["cable_lengths_m"].as_array().map(Vec::len), Some(3));

    let out = host_sim(&["solve", &bench, "--format", "csv"]);
    assert_eq!(code(&out), 0);
    let text = stdout(&out);
    let rows: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(rows.len(), 41);
    assert!(
        rows.iter().all(|r| r.ends_with(",Converged/Stable")),
        "{text}"
    );
}

/// A tip moment of 1e300 N m: the sweeps overflow, no equilibrium is reached and the residual is not
/// a number. JSON has no such number; it must be written as a string, not as `null` (which reads as
/// "no value").
#[test]
fn a_non_finite_residual_is_a_string_in_json_not_null() {
    let out = host_sim(&[
        "solve",
        &scene("bench_3d_cables.toml"),
        "--tip-moment=0,0,1e300",
        "--format",
        "json",
    ]);
    assert_eq!(code(&out), 3);
    let v = json_of(&out);
    let residual = &v["report"]["residual"];
    let text = residual
        .as_str()
        .unwrap_or_else(|| panic!("residual {residual}"));
    assert!(
        ["NaN", "Infinity", "-Infinity"].contains(&text),
        "{residual}"
    );
    // The only nulls are the answer's numbers, left out on purpose.
    let nulls: Vec<&String> = v
        .as_object()
        .unwrap()
        .iter()
        .filter(|(_, x)| x.is_null())
        .map(|(k, _)| k)
        .collect();
    assert_eq!(
        nulls,
        ["cable_lengths_m", "shape", "tip_position_m", "tip_tangent"],
        "{v}"
    );
}

#[test]
fn a_negative_cable_length_is_a_value_refused_by_model_core() {
    let bench = scene("bench_3d_cables.toml");
    for args in [
        ["--cables", "-0.39,0.39,0.39"],
        ["--cables", "0.39,-0.39,0.39"],
    ] {
        let out = host_sim(&["estimate", &bench, args[0], args[1]]);
        let err = stderr(&out);
        assert_eq!(code(&out), 1, "{err}");
        // model-core's typed error (ModelError::NotPositive), not clap's "unexpected argument".
        assert!(
            err.contains("--cables: cable length must be positive"),
            "{err}"
        );
        assert!(!err.contains("unexpected argument"), "{err}");
    }
    // A usage error stays clap's, with clap's code.
    let out = host_sim(&["estimate", &bench, "--cables", "0.39,zero,0.39"]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
}

#[test]
fn huge_counts_are_refused_before_anything_is_allocated() {
    let good = bench_text();
    for (name, from, to, key, limit) in [
        (
            "count-max",
            "count = 5",
            "count = 9223372036854775807",
            "guides.count",
            "128",
        ),
        (
            "count-float",
            "count = 5",
            "count = 1e12",
            "guides.count",
            "128",
        ),
        (
            "count-half",
            "count = 5",
            "count = 2.5",
            "guides.count",
            "128",
        ),
        (
            "count-neg",
            "count = 5",
            "count = -1",
            "guides.count",
            "128",
        ),
        (
            "points-float",
            "points = 41",
            "points = 1e12",
            "output.points",
            "100000",
        ),
        (
            "points-int",
            "points = 41",
            "points = 1000000000000",
            "output.points",
            "100000",
        ),
    ] {
        assert!(good.contains(from));
        let path = write_scene(name, &good.replace(from, to));
        // Refused with the key and the limit (a count expanded first would abort on allocation).
        let out = host_sim(&["solve", &path]);
        let err = stderr(&out);
        assert_eq!(code(&out), 1, "{to}: {err}");
        assert!(err.contains(key) && err.contains(limit), "{to}: {err}");
    }
    // Explicit lists are checked too.
    let centres: Vec<String> = (0..129)
        .map(|k| format!("{}", 0.001 + 0.0025 * f64::from(k)))
        .collect();
    let listed = good
        .replace("first_centre_m = 0.005405\n", "")
        .replace("pitch_m = 0.095\n", "")
        .replace(
            "count = 5\n",
            &format!("centres_m = [{}]\n", centres.join(", ")),
        );
    let out = host_sim(&["solve", &write_scene("centres", &listed)]);
    let err = stderr(&out);
    assert_eq!(code(&out), 1, "{err}");
    assert!(
        err.contains("guides.centres_m") && err.contains("128"),
        "{err}"
    );
    // A whole count written as a float is that count.
    let out = host_sim(&[
        "solve",
        &write_scene("points-1e1", &good.replace("points = 41", "points = 1e1")),
        "--format",
        "csv",
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert_eq!(stdout(&out).lines().count(), 1 + 10);
}

/// Eight sections of 65 535 RK4 steps each: one solve took 84 s. Refused, naming the limit.
#[test]
fn a_scene_with_too_many_steps_is_refused_quickly() {
    let good = bench_text();
    let (start, end) = (
        good.find("[[section]]").unwrap(),
        good.find("[guides]").unwrap(),
    );
    let section = good[start..end]
        .replace("length_m = 0.39", "length_m = 0.04875")
        .replace("steps = 200", "steps = 65535");
    let huge = format!("{}{}{}", &good[..start], section.repeat(8), &good[end..]);
    let path = write_scene("steps", &huge);
    // The refusal names the scene's total and the limit: it comes from the scene check, before
    // any model is built or solved.
    for command in [
        vec!["solve", &path],
        vec!["estimate", &path, "--cables", "0.39,0.38,0.38"],
    ] {
        let out = host_sim(&command);
        let err = stderr(&out);
        assert_eq!(code(&out), 1, "{err}");
        assert!(
            err.contains("steps") && err.contains("524280") && err.contains("at most 20000"),
            "{err}"
        );
    }
}

#[test]
fn unchecked_stability_warns_and_every_format_says_so() {
    let path = write_scene(
        "unchecked",
        &format!("{}\n[solver]\ncheck_stability = false\n", bench_text()),
    );
    let warning =
        "warning: stability not checked (the scene sets [solver] check_stability = false)";

    let out = host_sim(&["solve", &path]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(stderr(&out).contains(warning), "{}", stderr(&out));
    let text = stdout(&out);
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .unwrap_or_default()
            .contains("stability NOT checked"),
        "{text}"
    );
    let second = lines.next().unwrap_or_default();
    assert!(
        second.starts_with(warning) && second.contains("unstable equilibrium"),
        "{text}"
    );

    let out = host_sim(&["solve", &path, "--format", "json"]);
    assert_eq!(code(&out), 0);
    assert!(stderr(&out).contains(warning), "{}", stderr(&out));
    let status = json_of(&out)["status"].clone();
    assert_eq!(status["stability"], "Unchecked");
    assert_eq!(status["stability_checked"], false);
    assert!(
        status["warnings"][0]
            .as_str()
            .is_some_and(|w| w.contains("would be reported as converged")),
        "{status}"
    );

    let out = host_sim(&["solve", &path, "--format", "csv"]);
    assert_eq!(code(&out), 0);
    assert!(stderr(&out).contains(warning), "{}", stderr(&out));
    assert!(
        stdout(&out)
            .lines()
            .skip(1)
            .all(|r| r.ends_with(",Converged/Unchecked")),
        "{}",
        stdout(&out)
    );

    let cables = BENCH_UNLOADED_CABLES_M.map(|x| x.to_string()).join(",");
    let out = host_sim(&["estimate", &path, "--cables", &cables, "--format", "json"]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(stderr(&out).contains(warning), "{}", stderr(&out));
    assert_eq!(json_of(&out)["status"]["stability_checked"], false);
}

/// The bench read with the thesis's 1 mm ruler, one cable 5 mm shorter than any tip force makes it:
/// the fit converges, and no load explains the lengths. Exit 4, marked in every format; the closest
/// fit is printed (its residual shows which cable disagrees).
#[test]
fn an_inconsistent_estimate_exits_4() {
    let path = write_scene(
        "inconsistent",
        &bench_text().replace("resolution_m = 7.67e-6", "resolution_m = 1e-3"),
    );
    let [a, b, c] = BENCH_UNLOADED_CABLES_M;
    let cables = format!("{},{b},{c}", a - 5e-3);

    let out = host_sim(&["estimate", &path, "--cables", &cables, "--format", "json"]);
    assert_eq!(code(&out), 4, "{}\n{}", stdout(&out), stderr(&out));
    let v = json_of(&out);
    assert_eq!(v["status"]["verdict"], "inconsistent");
    assert_eq!(v["status"]["termination"], "Converged");
    assert_eq!(v["status"]["determination"], "Inconsistent");
    assert!(
        v["cable_residual_m"][0].as_f64().is_some_and(|r| r > 1e-3),
        "{v}"
    );
    assert!(
        stderr(&out).contains("no load of the model explains"),
        "{}",
        stderr(&out)
    );

    let out = host_sim(&["estimate", &path, "--cables", &cables]);
    assert_eq!(code(&out), 4);
    let text = stdout(&out);
    assert!(
        text.starts_with("status: converged, but no load of the model explains"),
        "{text}"
    );

    let out = host_sim(&["estimate", &path, "--cables", &cables, "--format", "csv"]);
    assert_eq!(code(&out), 4);
    assert!(
        stdout(&out)
            .lines()
            .skip(1)
            .all(|r| r.ends_with(",Converged/Stable/Inconsistent")),
        "{}",
        stdout(&out)
    );
}

/// Other verdicts keep exit 0 (the answer converged; its uncertainty says how good it is), and are
/// visible in every format: one cable cannot determine a 3D tip force (`Undetermined`).
#[test]
fn an_undetermined_estimate_exits_0_and_says_so() {
    let single = scene("thesis_exp2_average.toml");
    let out = host_sim(&["solve", &single, "--format", "json"]);
    let unloaded = json_of(&out)["cable_lengths_m"][0].as_f64().unwrap();
    let cables = format!("{}", unloaded - 5e-3);

    let out = host_sim(&["estimate", &single, "--cables", &cables, "--format", "json"]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let status = json_of(&out)["status"].clone();
    assert_eq!(status["verdict"], "answer");
    assert_eq!(status["determination"], "Undetermined");
    // The printed force is one of many that fit: said in the status and on standard error.
    assert!(
        status["warnings"][0]
            .as_str()
            .is_some_and(|w| w.contains("do not determine the load")),
        "{status}"
    );
    assert!(stderr(&out).contains("warning: the cables do not determine the load"));

    let out = host_sim(&["estimate", &single, "--cables", &cables]);
    assert_eq!(code(&out), 0);
    assert!(
        stdout(&out)
            .lines()
            .next()
            .unwrap_or_default()
            .contains("determination Undetermined"),
        "{}",
        stdout(&out)
    );

    let out = host_sim(&["estimate", &single, "--cables", &cables, "--format", "csv"]);
    assert_eq!(code(&out), 0);
    assert!(
        stdout(&out)
            .lines()
            .skip(1)
            .all(|r| r.ends_with(",Converged/Stable/Undetermined")),
        "{}",
        stdout(&out)
    );
}

/// Lengths 1 mm longer than the unloaded bench's, read with the encoder: the fit stalls. Exit 3,
/// and none of the estimate's numbers, nor a determination for the failed iterate.
#[test]
fn a_failed_estimate_exits_3_with_its_numbers_null() {
    let bench = scene("bench_3d_cables.toml");
    let cables = BENCH_UNLOADED_CABLES_M
        .map(|x| (x + 1e-3).to_string())
        .join(",");
    let out = host_sim(&["estimate", &bench, "--cables", &cables, "--format", "json"]);
    assert_eq!(code(&out), 3, "{}", stderr(&out));
    let v = json_of(&out);
    assert_eq!(v["status"]["verdict"], "no_answer");
    assert!(v["status"]["determination"].is_null(), "{}", v["status"]);
    for key in [
        "tip_force_n",
        "tip_force_std_n",
        "tip_position_m",
        "tip_position_std_m",
        "cable_residual_m",
        "singular_values",
        "condition_number",
        "weakest_direction",
        "shape",
    ] {
        assert!(v.get(key).is_some_and(Value::is_null), "{key}: {v}");
    }
    let out = host_sim(&["estimate", &bench, "--cables", &cables]);
    assert_eq!(code(&out), 3);
    assert!(!stdout(&out).contains("tip force ["), "{}", stdout(&out));
}

/// A rotation-matrix frame with two steps on the rod, bent hard: the residual converges, but the
/// frame drifts from a rotation (`FrameDrift`). Not an answer either: exit 3.
#[test]
fn a_drifted_frame_is_no_answer() {
    let path = write_scene(
        "drift",
        &format!(
            "{}\n[solver]\nattitude = \"rotation-matrix\"\n",
            bench_text().replace("steps = 200", "steps = 2")
        ),
    );
    let out = host_sim(&["solve", &path, "--tip-force=0,-3,0", "--format", "json"]);
    assert_eq!(code(&out), 3, "{}", stdout(&out));
    let v = json_of(&out);
    assert_eq!(v["status"]["termination"], "FrameDrift");
    assert!(v["cable_lengths_m"].is_null(), "{v}");
}

/// A reader that has gone (a closed pipe, a full disk) is an I/O error, exit 1, not a panic
/// (`print!` panicked with exit 101); a tip force that is not a number is a usage error, exit 2
/// (it was blamed on the scene file's `[tip]`).
#[test]
fn output_that_cannot_be_written_and_a_tip_force_that_is_no_number_are_errors() {
    let full = || std::fs::OpenOptions::new().write(true).open("/dev/full");
    for args in [
        vec!["inverse"],
        vec!["validate"],
        vec!["solve", &scene("bench_3d_cables.toml")],
    ] {
        let Ok(sink) = full() else {
            return; // (no /dev/full here)
        };
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(&args)
            .stdout(sink)
            .output()
            .expect("host-sim runs");
        assert_eq!(code(&out), 1, "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("cannot write"), "{args:?}");
    }
    let out = host_sim(&[
        "solve",
        &scene("bench_3d_cables.toml"),
        "--tip-force",
        "nan,0,0",
    ]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(stderr(&out).contains("finite"), "{}", stderr(&out));
}

/// A scene with neither cables nor tendons has nothing to estimate from, and says so (it said the
/// measured lengths and the cables "do not match in size").
#[test]
fn estimate_on_a_scene_without_cables_says_so() {
    let text = std::fs::read_to_string(scene("bench_3d_cables.toml")).expect("reads");
    let mut kept = Vec::new();
    let mut in_cable = false;
    for line in text.lines() {
        if line.starts_with('[') {
            in_cable = line == "[[cable]]";
        }
        if !in_cable {
            kept.push(line);
        }
    }
    let path = write_scene("no-cables", &kept.join("\n"));
    let out = host_sim(&["estimate", &path, "--cables", "0.3,0.3,0.3"]);
    assert_eq!(code(&out), 1, "{}", stderr(&out));
    assert!(stderr(&out).contains("no [[cable]]"), "{}", stderr(&out));
}
