//! `host-sim solve` on tendon scenes, run as a user runs it: the golden tendon references through the
//! command line, displacement control against force control, every output format, and bad input
//! refused with the key named (exit 1), never a panic.

use std::path::PathBuf;
use std::process::{Command, Output};

use model_checks::reference::{self, csv_rows, golden_rows};
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

fn scene_text(name: &str) -> String {
    std::fs::read_to_string(scene(name)).unwrap()
}

/// Writes `text` as a scene file in a fresh temporary directory and returns its path.
fn write_scene(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!(
        "host-sim-tendon-test-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// The exit code, and that the run did not panic or abort.
fn code(o: &Output) -> i32 {
    let err = stderr(o);
    assert!(
        !err.contains("panicked")
            && !err.contains("backtrace")
            && !err.contains("memory allocation"),
        "{err}"
    );
    o.status
        .code()
        .unwrap_or_else(|| panic!("killed by a signal: {err}"))
}

fn json_of(o: &Output) -> Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap_or_else(|| panic!("not a number: {x}")))
        .collect()
}

fn list(values: &[f64]) -> String {
    values
        .iter()
        .map(f64::to_string)
        .collect::<Vec<_>>()
        .join(",")
}

/// `solve` with `args` in JSON: an answer (exit 0), its JSON.
fn solved(args: &[&str]) -> Value {
    let mut all = vec!["solve"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json"]);
    let out = host_sim(&all);
    assert_eq!(code(&out), 0, "{args:?}: {}", stderr(&out));
    let v = json_of(&out);
    assert_eq!(v["status"]["verdict"], "answer", "{}", v["status"]);
    v
}

/// The tip and the path lengths of `v` against a golden row's, within 1 um.
fn matches_golden(v: &Value, tip_m: &[f64], path_m: &[f64], what: &str) {
    let tip = numbers(&v["tip_position_m"]);
    let off = tip
        .iter()
        .zip(tip_m)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(
        off < 1e-6,
        "{what}: tip {off:e} m off ({tip:?} vs {tip_m:?})"
    );
    let path = numbers(&v["tendons"]["path_m"]);
    assert_eq!(path.len(), path_m.len(), "{what}");
    for (j, (a, b)) in path.iter().zip(path_m).enumerate() {
        assert!(
            (a - b).abs() < 1e-6,
            "{what}: tendon {j} path {:e} m off",
            a - b
        );
    }
}

#[test]
fn tendon_bench_cli_reproduces_every_golden_row() {
    let bench = scene("tendon_bench.toml");
    let mut rows = 0;
    for (i, row) in csv_rows::<18>(reference::TENDON_BENCH_CSV).enumerate() {
        let v = row.unwrap();
        let tensions = format!("--tensions={}", list(&v[0..3]));
        let force = format!("--tip-force={}", list(&v[3..6]));
        let out = solved(&[&bench, &tensions, &force]);
        assert_eq!(out["tendons"]["control"], "tensions");
        assert_eq!(numbers(&out["tendons"]["tensions_n"]), &v[0..3]);
        assert_eq!(numbers(&out["tip_force_n"]), &v[3..6]);
        matches_golden(&out, &v[6..9], &v[12..15], &format!("row {i}"));
        rows += 1;
    }
    assert_eq!(rows, 8);
}

#[test]
fn tendon_two_section_cli_reproduces_every_golden_row() {
    let text = scene_text("tendon_two_section.toml");
    let with_gravity = "gravity_m_s2 = [0.0, -9.81, 0.0]";
    let actuation = "tensions_n = [2.0, 0.0, 0.0, 0.0, 0.0, 0.0]";
    assert!(text.contains(with_gravity) && text.contains(actuation));
    let weightless = text.replace(with_gravity, "gravity_m_s2 = [0.0, 0.0, 0.0]");
    let mut rows = 0;
    for (i, row) in csv_rows::<25>(reference::TENDON_TWO_SECTION_CSV).enumerate() {
        let v = row.unwrap();
        let base = if v[0] == 0.0 { &weightless } else { &text };
        let force = format!("--tip-force={}", list(&v[7..10]));
        // Even rows: a copy of the scene with the row's actuation; odd rows: --tensions.
        let out = if i % 2 == 0 {
            let copy = base.replace(actuation, &format!("tensions_n = [{}]", list(&v[1..7])));
            let path = write_scene(&format!("two-section-{i}"), &copy);
            solved(&[&path, &force])
        } else {
            let path = write_scene(&format!("two-section-{i}"), base);
            solved(&[&path, &format!("--tensions={}", list(&v[1..7])), &force])
        };
        assert_eq!(numbers(&out["tendons"]["tensions_n"]), &v[1..7]);
        matches_golden(&out, &v[10..13], &v[16..22], &format!("row {i}"));
        rows += 1;
    }
    assert_eq!(rows, 16);
    // The scene as shipped is row 2 (g = 9.81, tendon 0 at 2 N).
    let out = solved(&[&scene("tendon_two_section.toml")]);
    let v = csv_rows::<25>(reference::TENDON_TWO_SECTION_CSV)
        .nth(1)
        .unwrap()
        .unwrap();
    matches_golden(&out, &v[10..13], &v[16..22], "the shipped scene");
}

/// Force control, then the spool displacements it reports given back as displacement control
/// (on the command line, and as a scene's `displacements_m`): the same tensions, tip and states.
/// With inextensible tendons, and with compliant ones behind a feed length.
#[test]
fn tendon_displacement_control_reproduces_force_control_through_the_cli() {
    let text = scene_text("tendon_bench.toml");
    let compliant = text.replace(
        "radius_m = 0.01\n",
        "radius_m = 0.01\naxial_stiffness_n = 2000.0\nfeed_length_m = 0.6\n",
    );
    assert_eq!(compliant.matches("axial_stiffness_n = 2000.0").count(), 3);
    for (name, scene_text, tensions, force) in [
        ("stiff", &text, [3.0, 1.5, 0.0], "0,0,0"),
        ("stiff-loaded", &text, [1.0, 2.5, 0.5], "0,-0.2,0.1"),
        ("compliant", &compliant, [4.0, 0.5, 2.0], "0.05,-0.1,-0.15"),
    ] {
        let path = write_scene(name, scene_text);
        let force = format!("--tip-force={force}");
        let forward = solved(&[&path, &format!("--tensions={}", list(&tensions)), &force]);
        let d = numbers(&forward["tendons"]["displacements_m"]);
        assert_eq!(d.len(), 3);
        let by_cli = solved(&[&path, &format!("--displacements={}", list(&d)), &force]);
        let copy = scene_text.replace(
            "tensions_n = [3.0, 1.5, 0.0]",
            &format!("displacements_m = [{}]", list(&d)),
        );
        let by_scene = solved(&[&write_scene(&format!("{name}-d"), &copy), &force]);
        for back in [&by_cli, &by_scene] {
            let t = &back["tendons"];
            assert_eq!(t["control"], "displacements");
            assert_eq!(t["displacement_solve"]["termination"], "Converged");
            assert_eq!(numbers(&t["displacements_m"]), d);
            for (j, (found, given)) in numbers(&t["tensions_n"]).iter().zip(tensions).enumerate() {
                assert!(
                    (found - given).abs() < 1e-6,
                    "{name} tendon {j}: {found} N for {given} N"
                );
                let state = if given > 0.0 { "taut" } else { "slack" };
                assert_eq!(t["states"][j], state, "{name} tendon {j}");
            }
            for (a, b) in numbers(&back["tip_position_m"])
                .iter()
                .zip(numbers(&forward["tip_position_m"]))
            {
                assert!((a - b).abs() < 1e-9, "{name}: tip {a} vs {b}");
            }
            for (a, b) in numbers(&t["path_m"])
                .iter()
                .zip(numbers(&forward["tendons"]["path_m"]))
            {
                assert!((a - b).abs() < 1e-9, "{name}: path {a} vs {b}");
            }
        }
    }
}

/// A tendon paid out 2 mm beyond the just-taut setting goes slack by 2 mm; the others keep their
/// tensions.
#[test]
fn tendon_paid_out_is_reported_slack() {
    let bench = scene("tendon_bench.toml");
    let forward = solved(&[&bench, "--tensions=3,1,0"]);
    let mut d = numbers(&forward["tendons"]["displacements_m"]);
    d[2] -= 2e-3;
    let back = solved(&[&bench, &format!("--displacements={}", list(&d))]);
    let t = &back["tendons"];
    assert_eq!(t["states"], serde_json::json!(["taut", "taut", "slack"]));
    let slack = numbers(&t["slack_m"]);
    assert!(slack[0] == 0.0 && slack[1] == 0.0, "{slack:?}");
    assert!((slack[2] - 2e-3).abs() < 1e-9, "{slack:?}");
    let tau = numbers(&t["tensions_n"]);
    assert!((tau[0] - 3.0).abs() < 1e-6 && (tau[1] - 1.0).abs() < 1e-6 && tau[2] == 0.0);
}

#[test]
fn tendon_solve_says_its_status_and_tendons_in_every_format() {
    let bench = scene("tendon_bench.toml");
    let warning = "warning: stability not checked (tendons:";

    let out = host_sim(&["solve", &bench]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(stderr(&out).contains(warning), "{}", stderr(&out));
    let text = stdout(&out);
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "status: converged, stability NOT checked (termination Converged, stability \
             Unchecked; exit 0)"
        ),
        "{text}"
    );
    assert!(
        lines.next().unwrap_or_default().starts_with(warning),
        "{text}"
    );
    assert!(
        text.contains("tendons: force control, tensions given [3.0, 1.5, 0.0] N"),
        "{text}"
    );
    let header = "tendon  tension_n  path_m  displacement_m  state  slack_m";
    let table: Vec<&str> = text
        .lines()
        .skip_while(|l| *l != header)
        .skip(1)
        .take(3)
        .collect();
    assert_eq!(table.len(), 3, "{text}");
    assert!(table[0].starts_with("0  3  0.38616557") && table[0].ends_with("taut  0"));
    assert!(table[2].starts_with("2  0  0.39444238") && table[2].ends_with("slack  0"));

    let v = json_of(&host_sim(&["solve", &bench, "--format", "json"]));
    assert_eq!(v["status"]["stability_checked"], false);
    assert_eq!(v["status"]["stability"], "Unchecked");
    assert!(
        v["status"]["warnings"][0]
            .as_str()
            .is_some_and(|w| w.contains("no energy test of stability with tendons")),
        "{}",
        v["status"]
    );
    let t = &v["tendons"];
    for key in [
        "tensions_n",
        "path_m",
        "displacements_m",
        "states",
        "slack_m",
    ] {
        assert_eq!(t[key].as_array().map(Vec::len), Some(3), "{key}: {t}");
    }
    // Force control: a displacement is the rest length less the path (inextensible).
    let (d, path) = (numbers(&t["displacements_m"]), numbers(&t["path_m"]));
    for (d, path) in d.iter().zip(&path) {
        assert!((d - (0.39 - path)).abs() < 1e-15, "{d} {path}");
    }
    assert!(t.get("displacement_solve").is_none(), "{t}");
    assert_eq!(v["cable_lengths_m"], serde_json::json!([]));
    assert_eq!(v["shape"].as_array().map(Vec::len), Some(41));

    let out = host_sim(&["solve", &bench, "--format", "csv"]);
    assert_eq!(code(&out), 0);
    let csv = stdout(&out);
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap_or_default().split(',').collect();
    assert_eq!(header.len(), 10 + 3 * 5 + 1, "{header:?}");
    assert_eq!(header[10], "tendon0_tension_n");
    assert_eq!(header[24], "tendon2_slack_m");
    assert_eq!(header[25], "status");
    let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
    assert_eq!(rows.len(), 41);
    for r in &rows {
        assert_eq!(r.len(), header.len());
        assert_eq!(r[10], "3");
        assert_eq!(r[13], "taut");
        assert_eq!(r[23], "slack");
        assert_eq!(r[25], "Converged/Unchecked");
        assert_eq!(r[11].parse::<f64>().ok(), Some(path[0]));
    }
}

/// A displacement solve that finds no tensions (all three taken in 5 cm: no tension shortens
/// every path that much) and a force-control solve that does not converge: exit 3, no numbers but
/// the given actuation, in any format.
#[test]
fn a_failed_tendon_solve_exits_3_and_prints_no_answer() {
    let bench = scene("tendon_bench.toml");
    for (args, termination) in [
        (["--displacements=0.05,0.05,0.05"], "Stalled"),
        (["--tensions=1000,0,0"], "ContinuationFailed"),
    ] {
        let out = host_sim(&["solve", &bench, args[0], "--format", "json"]);
        assert_eq!(code(&out), 3, "{}", stderr(&out));
        assert!(stderr(&out).contains("no answer"), "{}", stderr(&out));
        let v = json_of(&out);
        assert_eq!(v["status"]["verdict"], "no_answer");
        assert_eq!(v["status"]["termination"], termination);
        for key in ["tip_position_m", "tip_tangent", "cable_lengths_m", "shape"] {
            assert!(v[key].is_null(), "{key}: {}", v[key]);
        }
        let t = &v["tendons"];
        for key in ["path_m", "states", "slack_m"] {
            assert!(t[key].is_null(), "{key}: {t}");
        }
        // Only what was given.
        if termination == "Stalled" {
            assert!(t["tensions_n"].is_null(), "{t}");
            assert_eq!(numbers(&t["displacements_m"]), [0.05; 3]);
            assert_eq!(t["displacement_solve"]["termination"], "Stalled");
        } else {
            assert!(t["displacements_m"].is_null(), "{t}");
            assert_eq!(numbers(&t["tensions_n"]), [1000.0, 0.0, 0.0]);
        }

        let out = host_sim(&["solve", &bench, args[0]]);
        assert_eq!(code(&out), 3);
        let text = stdout(&out);
        assert!(text.starts_with("status: no answer"), "{text}");
        assert!(
            !text.contains("tip position [") && !text.contains("tendon  tension_n"),
            "{text}"
        );

        let out = host_sim(&["solve", &bench, args[0], "--format", "csv"]);
        assert_eq!(code(&out), 3);
        let csv = stdout(&out);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 2, "{csv}");
        let (numbers, status) = lines[1].rsplit_once(',').unwrap();
        assert_eq!(numbers.split(',').count(), 10 + 15, "{csv}");
        assert!(numbers.split(',').all(str::is_empty), "{csv}");
        assert!(status.starts_with(termination), "{csv}");
    }
}

/// The passive cables of a scene with tendons are measured too: the tendon bench with the 3D
/// bench's three cables and slack tendons is the golden 3D bench.
#[test]
fn tendon_scene_measures_its_cables() {
    let cables = "[[cable]]\nangle_deg = 0.0\nradius_m = 0.01\n\n[[cable]]\nangle_deg = 120.0\n\
                  radius_m = 0.01\n\n[[cable]]\nangle_deg = 240.0\nradius_m = 0.01\n\n";
    let text = scene_text("tendon_bench.toml").replace(
        "[actuation]\ntensions_n = [3.0, 1.5, 0.0]",
        &format!("{cables}[actuation]\ntensions_n = [0.0, 0.0, 0.0]"),
    );
    assert!(text.contains("[[cable]]"));
    let path = write_scene("cables", &text);
    for row in golden_rows().take(4) {
        let row = row.unwrap();
        let force = format!("--tip-force={}", list(&row.force_n));
        let v = solved(&[&path, &force]);
        let lengths = numbers(&v["cable_lengths_m"]);
        assert_eq!(lengths.len(), 3);
        for (i, (a, b)) in lengths.iter().zip(row.cables_m).enumerate() {
            assert!((a - b).abs() < 1e-6, "cable {i}: {a} vs {b}");
        }
        // And what the cable-only solve of the same rod measures.
        let plain = solved(&[&scene("bench_3d_cables.toml"), &force]);
        for (a, b) in lengths.iter().zip(numbers(&plain["cable_lengths_m"])) {
            assert!((a - b).abs() < 1e-8, "{a} vs {b}");
        }
    }
}

/// Runs `solve` on a copy of the tendon bench with `from` replaced by `to` (and `args`): exit 1,
/// and standard error names `key` and says `reason`.
fn refused(name: &str, from: &str, to: &str, args: &[&str], key: &str, reason: &str) {
    let text = scene_text("tendon_bench.toml");
    assert!(text.contains(from), "{name}: no {from:?}");
    let path = write_scene(name, &text.replacen(from, to, 1));
    let mut all = vec!["solve", path.as_str()];
    all.extend_from_slice(args);
    let out = host_sim(&all);
    let err = stderr(&out);
    assert_eq!(code(&out), 1, "{name}: {err}");
    assert!(
        err.contains(key) && err.contains(reason),
        "{name}: {err:?} lacks {key:?} / {reason:?}"
    );
}

#[test]
fn tendon_bad_input_is_refused_naming_the_key() {
    let act = "tensions_n = [3.0, 1.5, 0.0]";
    let t1 = "angle_deg = 120.0\nradius_m = 0.01\n";
    for (name, from, to, args, key, reason) in [
        // The actuation in the scene.
        (
            "neg",
            act,
            "tensions_n = [3.0, -1.5, 0.0]",
            &[][..],
            "actuation.tensions_n[1]",
            "negative",
        ),
        (
            "nan",
            act,
            "tensions_n = [nan, 1.5, 0.0]",
            &[],
            "actuation.tensions_n[0]",
            "finite",
        ),
        (
            "inf",
            act,
            "tensions_n = [3.0, 1.5, inf]",
            &[],
            "actuation.tensions_n[2]",
            "finite",
        ),
        (
            "count",
            act,
            "tensions_n = [3.0, 1.5]",
            &[],
            "actuation.tensions_n",
            "2 values for 3 tendons",
        ),
        (
            "dcount",
            act,
            "displacements_m = [0.0]",
            &[],
            "actuation.displacements_m",
            "1 value for 3 tendons",
        ),
        (
            "both",
            act,
            "tensions_n = [3.0, 1.5, 0.0]\ndisplacements_m = [0.0, 0.0, 0.0]",
            &[],
            "actuation",
            "not both",
        ),
        ("neither", act, "", &[], "actuation", "give tensions_n"),
        (
            "missing",
            "[actuation]\ntensions_n = [3.0, 1.5, 0.0]",
            "",
            &[],
            "actuation",
            "missing",
        ),
        (
            "dnan",
            act,
            "displacements_m = [0.0, nan, 0.0]",
            &[],
            "actuation.displacements_m[1]",
            "finite",
        ),
        (
            "dlong",
            act,
            "displacements_m = [0.0, 0.5, 0.0]",
            &[],
            "actuation.displacements_m[1]",
            "whole length",
        ),
        (
            "typo",
            act,
            "tension_n = [3.0, 1.5, 0.0]",
            &[],
            "unknown field `tension_n`",
            "line",
        ),
        // The command line.
        (
            "cli-neg",
            "",
            "",
            &["--tensions=-1,0,0"],
            "--tensions[0]",
            "negative",
        ),
        (
            "cli-nan",
            "",
            "",
            &["--tensions=NaN,0,0"],
            "--tensions[0]",
            "finite",
        ),
        (
            "cli-count",
            "",
            "",
            &["--tensions=1,2"],
            "--tensions",
            "2 values for 3 tendons",
        ),
        (
            "cli-dinf",
            "",
            "",
            &["--displacements=0,inf,0"],
            "--displacements[1]",
            "finite",
        ),
        (
            "cli-dlong",
            "",
            "",
            &["--displacements=0.39,0,0"],
            "--displacements[0]",
            "whole length",
        ),
        // The tendons.
        (
            "end",
            t1,
            &format!("{t1}end_m = 0.2\n"),
            &[],
            "tendon[1].end_m",
            "not a guide's centre",
        ),
        (
            "end-tip",
            ", 0.39]",
            "]",
            &[],
            "tendon[0].end_m",
            "(the tip, the default)",
        ),
        (
            "end-nan",
            t1,
            &format!("{t1}end_m = nan\n"),
            &[],
            "tendon[1].end_m",
            "finite",
        ),
        (
            "radius",
            "radius_m = 0.01",
            "radius_m = -0.01",
            &[],
            "tendon[0].radius_m",
            "negative",
        ),
        (
            "angle",
            "angle_deg = 240.0",
            "angle_deg = nan",
            &[],
            "tendon[2].angle_deg",
            "finite",
        ),
        (
            "stiff",
            t1,
            &format!("{t1}axial_stiffness_n = -5.0\n"),
            &[],
            "tendon[1].axial_stiffness_n",
            "positive",
        ),
        (
            "feed",
            t1,
            &format!("{t1}feed_length_m = -0.1\n"),
            &[],
            "tendon[1].feed_length_m",
            "negative",
        ),
        (
            "unknown",
            t1,
            &format!("{t1}radius_mm = 10\n"),
            &[],
            "unknown field `radius_mm`",
            "line",
        ),
        (
            "first-guide",
            "centres_m = [0.005405,",
            "centres_m = [0.0, 0.005405,",
            &[],
            "guides",
            "first guide",
        ),
        (
            "thicknesses",
            "thickness_m = 0.0",
            "thicknesses_m = [0.0]",
            &[],
            "guides.thicknesses_m",
            "1 value for 6 guides",
        ),
    ] {
        refused(name, from, to, args, key, reason);
    }
    // Thirteen tendons: more than model-core holds.
    let many = "[[tendon]]\nangle_deg = 0.0\nradius_m = 0.01\n\n".repeat(13);
    refused(
        "many",
        "[actuation]\ntensions_n = [3.0, 1.5, 0.0]",
        &many,
        &[],
        "tendon",
        "at most 12",
    );
    // A scene without guides.
    let text = scene_text("tendon_bench.toml");
    let start = text.find("[guides]").unwrap();
    let end = text.find("[[tendon]]").unwrap();
    let bare = format!("{}{}", &text[..start], &text[end..]);
    let out = host_sim(&["solve", &write_scene("bare", &bare)]);
    assert_eq!(code(&out), 1);
    assert!(
        stderr(&out).contains("guides: tendons need guides"),
        "{}",
        stderr(&out)
    );
    // Both on the command line: a usage error (clap's exit 2) naming both.
    let bench = scene("tendon_bench.toml");
    let out = host_sim(&["solve", &bench, "--tensions=1,1,1", "--displacements=0,0,0"]);
    assert_eq!(code(&out), 2);
    assert!(
        stderr(&out).contains("--tensions") && stderr(&out).contains("--displacements"),
        "{}",
        stderr(&out)
    );
    // Tendon keys on a scene without tendons.
    let cables = scene("bench_3d_cables.toml");
    let out = host_sim(&["solve", &cables, "--tensions=1,1,1"]);
    assert_eq!(code(&out), 1);
    assert!(
        stderr(&out).contains("--tensions: the scene has no [[tendon]]"),
        "{}",
        stderr(&out)
    );
    let with_actuation = format!(
        "{}\n[actuation]\ntensions_n = [1.0]\n",
        scene_text("bench_3d_cables.toml")
    );
    let out = host_sim(&["solve", &write_scene("no-tendons", &with_actuation)]);
    assert_eq!(code(&out), 1);
    assert!(
        stderr(&out).contains("actuation: the scene has no [[tendon]]"),
        "{}",
        stderr(&out)
    );
    // The inverse does not model tendons: refused rather than wrong.
    let out = host_sim(&["estimate", &bench, "--cables", "0.39,0.39,0.39"]);
    assert_eq!(code(&out), 1);
    assert!(
        stderr(&out).contains("tendon: estimate does not model tendons"),
        "{}",
        stderr(&out)
    );
}

/// A scene without `[actuation]` solves from the command line's.
#[test]
fn tendon_actuation_may_come_from_the_command_line_alone() {
    let text =
        scene_text("tendon_bench.toml").replace("[actuation]\ntensions_n = [3.0, 1.5, 0.0]\n", "");
    let path = write_scene("cli-only", &text);
    let v = solved(&[&path, "--tensions=2,2,2"]);
    let golden = csv_rows::<18>(reference::TENDON_BENCH_CSV)
        .nth(2)
        .unwrap()
        .unwrap();
    assert_eq!(&golden[0..3], [2.0, 2.0, 2.0]);
    matches_golden(&v, &golden[6..9], &golden[12..15], "row 2");
}

/// The complete example of `host-sim/SCENES.md` is a valid scene and does what the text says:
/// spool 0 pulls at 1.32 N, tendon 1 hangs 0.98 mm slack, and its cable is measured.
#[test]
fn tendon_example_of_scenes_md_solves_as_documented() {
    let doc = std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("SCENES.md"))
        .unwrap();
    let start = doc.find("```toml\n").expect("a TOML example") + "```toml\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let v = solved(&[&write_scene("scenes-md", &doc[start..end])]);
    let t = &v["tendons"];
    assert_eq!(t["control"], "displacements");
    assert_eq!(t["states"], serde_json::json!(["taut", "slack"]));
    let tau = numbers(&t["tensions_n"]);
    assert!((tau[0] - 1.32).abs() < 0.005 && tau[1] == 0.0, "{tau:?}");
    let slack = numbers(&t["slack_m"]);
    assert!((slack[1] - 0.98e-3).abs() < 0.005e-3, "{slack:?}");
    assert_eq!(numbers(&v["cable_lengths_m"]).len(), 1);
    // And `--help` points to the tendon keys.
    let help = stdout(&host_sim(&["solve", "--help"]));
    assert!(
        help.contains("--tensions")
            && help.contains("--displacements")
            && help.contains("SCENES.md"),
        "{help}"
    );
}

/// Capstan friction from the scene: with `friction_coefficient` the same spool displacements need
/// different tensions loading (`sliding = "in"`) and unloading (`"out"`), each a round trip of its
/// own force-controlled solve; `sliding` is checked.
#[test]
fn tendon_friction_and_sliding_from_the_scene() {
    let text = scene_text("tendon_bench.toml").replace(
        "radius_m = 0.01\n",
        "radius_m = 0.01\nfriction_coefficient = 0.15\n",
    );
    assert_eq!(text.matches("friction_coefficient = 0.15").count(), 3);
    let act = "tensions_n = [3.0, 1.5, 0.0]";
    let tensions = [2.5, 0.5, 1.0];
    let loading = text.replace(act, &format!("tensions_n = [{}]", list(&tensions)));
    let forward = solved(&[&write_scene("friction-in", &loading)]);
    let d = numbers(&forward["tendons"]["displacements_m"]);
    let mut found = Vec::new();
    for sliding in ["in", "out"] {
        let copy = text.replace(
            act,
            &format!("displacements_m = [{}]\nsliding = \"{sliding}\"", list(&d)),
        );
        let back = solved(&[&write_scene(&format!("friction-{sliding}-d"), &copy)]);
        assert_eq!(
            back["tendons"]["displacement_solve"]["termination"],
            "Converged"
        );
        found.push(numbers(&back["tendons"]["tensions_n"]));
    }
    for (a, b) in found[0].iter().zip(tensions) {
        assert!((a - b).abs() < 1e-6, "loading: {a} N for {b} N");
    }
    // Unloading, friction holds part of the shape: the top tendon's spool pulls less.
    assert!(found[1][0] < tensions[0] - 0.05, "{:?}", found[1]);
    refused(
        "sliding-bad",
        act,
        "tensions_n = [3.0, 1.5, 0.0]\nsliding = \"sideways\"",
        &[],
        "actuation.sliding",
        "sideways",
    );
    refused(
        "friction-negative",
        "radius_m = 0.01\n",
        "radius_m = 0.01\nfriction_coefficient = -0.1\n",
        &[],
        "tendon[0].friction_coefficient",
        "negative",
    );
}
