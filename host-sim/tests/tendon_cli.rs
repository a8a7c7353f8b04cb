//! `host-sim solve` on tendon scenes, run as a user runs it: the golden tendon references through the
//! command line, displacement control against force control, every output format, and bad input
//! refused with the key named (exit 1), never a panic.

use std::path::PathBuf;
use std::process::Output;

use model_checks::reference::{self, csv_rows, golden_rows};
use serde_json::Value;

mod common;
use common::{code, host_sim, scene, stderr, stdout, write_scene};

fn scene_text(name: &str) -> String {
    std::fs::read_to_string(scene(name)).unwrap()
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

/// A displacement solve that finds no tensions (all three taken in 5 cm: only a rod buckled
/// between its guides shortens every path that much, a branch the solve does not leave its own
/// for) and a force-control solve that does not converge: exit 3, no numbers but the given
/// actuation, in any format.
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
    // The tendon inverse does not use cable lengths: refused rather than ignored.
    let out = host_sim(&["estimate", &bench, "--cables", "0.39,0.39,0.39"]);
    assert_eq!(code(&out), 1);
    assert!(
        stderr(&out).contains("--cables: the scene has [[tendon]]"),
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

/// The tendon bench with 50 steps (the estimates below run many forward solves), `extra` appended.
fn quick_bench(name: &str, extra: &str) -> String {
    let text = scene_text("tendon_bench.toml");
    assert!(text.contains("steps = 200"));
    write_scene(
        name,
        &format!("{}{extra}", text.replace("steps = 200", "steps = 50")),
    )
}

/// `estimate` with `args` in JSON: the exit code and the JSON.
fn estimated(args: &[&str]) -> (i32, Value) {
    let mut all = vec!["estimate"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json"]);
    let out = host_sim(&all);
    (code(&out), json_of(&out))
}

/// `value` within three of its reported standard deviations `std` of `truth`.
fn within_3_std(value: &[f64], std: &[f64], truth: &[f64], what: &str) {
    assert_eq!(value.len(), truth.len(), "{what}");
    for (i, ((v, s), t)) in value.iter().zip(std).zip(truth).enumerate() {
        assert!(s.is_finite() && *s > 0.0, "{what}[{i}]: std {s}");
        assert!(
            (v - t).abs() <= 3.0 * s + 1e-9,
            "{what}[{i}]: {v} vs {t}, {:.2} std",
            (v - t).abs() / s
        );
    }
}

/// The round trip through the command line: `solve` from tensions and a tip force, its spool
/// displacements read from its JSON, then `estimate` from those displacements with the true
/// tensions as measurements (10 mN): the tip force, the tensions and the tip come back within
/// three reported standard deviations, the force observable.
#[test]
fn tendon_estimate_round_trip_through_the_cli() {
    let path = quick_bench("round-trip", "");
    let (tensions, force) = ([3.0, 1.5, 0.5], [0.0, -0.1, 0.05]);
    let forward = solved(&[
        &path,
        &format!("--tensions={}", list(&tensions)),
        &format!("--tip-force={}", list(&force)),
    ]);
    let d = numbers(&forward["tendons"]["displacements_m"]);
    let (code, v) = estimated(&[
        &path,
        &format!("--displacements={}", list(&d)),
        &format!("--tensions-measured={}", list(&tensions)),
        "--tension-std=0.01",
    ]);
    assert_eq!(code, 0, "{}", v["status"]);
    let status = &v["status"];
    assert_eq!(status["verdict"], "answer");
    // Three taut tendons and three tensions: no datum to spare, so weak at best.
    assert_eq!(status["determination"], "Weak", "{status}");
    assert_eq!(v["consistency_tested"], false);
    assert_eq!(status["tension_determination"], "Determined", "{status}");
    assert_eq!(v["force_observable"], true);
    assert_eq!(v["fit"]["termination"], "Converged");
    within_3_std(
        &numbers(&v["tip_force_n"]),
        &numbers(&v["tip_force_std_n"]),
        &force,
        "tip force",
    );
    let t = &v["tendons"];
    within_3_std(
        &numbers(&t["tensions_n"]),
        &numbers(&t["tension_std_n"]),
        &tensions,
        "tensions",
    );
    within_3_std(
        &numbers(&v["tip_position_m"]),
        &numbers(&v["tip_position_std_m"]),
        &numbers(&forward["tip_position_m"]),
        "tip",
    );
    assert_eq!(t["states"], serde_json::json!(["taut", "taut", "taut"]));
    assert_eq!(numbers(&t["displacements_m"]), d);
    assert_eq!(numbers(&t["tensions_measured_n"]), tensions);
    assert_eq!(numbers(&t["tension_measured_std_n"]), [0.01; 3]);
    assert!(
        numbers(&t["displacement_residual_m"])
            .iter()
            .all(|r| r.abs() < 1e-9)
    );
    assert!(v["residual_rms_sigma"].is_null());
    assert_eq!(v["shape"].as_array().map(Vec::len), Some(41));
    // The settings from [estimate]: the encoder's resolution over sqrt 12.
    let sd = v["settings"]["displacement_std_m"]
        .as_f64()
        .unwrap_or_default();
    assert!((sd - 2.0 * std::f64::consts::PI * 5e-3 / 4096.0 / 12f64.sqrt()).abs() < 1e-15);
}

/// Displacements alone cannot determine a tip force: `Undetermined`, exit 0, the tip force
/// `null` (not a guess), and every format says so.
#[test]
fn tendon_estimate_from_displacements_alone_is_undetermined_and_says_so() {
    let path = quick_bench("alone", "");
    let forward = solved(&[&path, "--tensions=3,1.5,0.5", "--tip-force=0,-0.1,0.05"]);
    let d = format!(
        "--displacements={}",
        list(&numbers(&forward["tendons"]["displacements_m"]))
    );

    let (code, v) = estimated(&[&path, &d]);
    assert_eq!(code, 0, "{}", v["status"]);
    let status = &v["status"];
    assert_eq!(status["verdict"], "answer");
    assert_eq!(status["determination"], "Undetermined");
    assert_eq!(v["force_observable"], false);
    assert!(
        v["tip_force_n"].is_null() && v["tip_force_std_n"].is_null(),
        "{v}"
    );
    assert!(
        status["summary"]
            .as_str()
            .is_some_and(|s| s.contains("tip force not observable")),
        "{status}"
    );
    assert!(
        status["warnings"]
            .as_array()
            .is_some_and(|w| w.iter().any(|w| w
                .as_str()
                .is_some_and(|w| w.contains("not observable from the spool displacements")))),
        "{status}"
    );
    assert_eq!(v["tendons"]["tensions_measured_n"], Value::Null);
    assert_eq!(v["tendons"]["tensions_n"].as_array().map(Vec::len), Some(3));

    let out = host_sim(&["estimate", &path, &d]);
    assert_eq!(self::code(&out), 0);
    assert!(stderr(&out).contains("not observable"), "{}", stderr(&out));
    let text = stdout(&out);
    let first = text.lines().next().unwrap_or_default();
    assert!(
        first.contains("determination Undetermined") && first.contains("not observable"),
        "{text}"
    );
    assert!(
        text.contains("tip force: not observable from the spool displacements alone"),
        "{text}"
    );
    assert!(!text.contains("tip force ["), "{text}");
    assert!(text.contains("tensions measured: none"), "{text}");

    let out = host_sim(&["estimate", &path, &d, "--format", "csv"]);
    assert_eq!(self::code(&out), 0);
    let csv = stdout(&out);
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap_or_default().split(',').collect();
    assert_eq!(header.len(), 10 + 3 * 4 + 13 + 1, "{header:?}");
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no {name}: {header:?}"))
    };
    let (fx, observable) = (column("tip_force_x_n"), column("force_observable"));
    let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
    assert_eq!(rows.len(), 41);
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
        assert_eq!(r[fx], "", "{r:?}");
        assert_eq!(r[observable], "false");
        assert_eq!(r[column("tendon0_state")], "taut");
        assert_eq!(r[column("status")], "Converged/Unchecked/Undetermined");
    }
}

/// Displacements, measured tensions and settings from the scene itself (`[actuation]
/// displacements_m`, `[estimate.tendons]`), without the search for other answers (scan_reach 0:
/// `Determined` becomes `Unverified`); text and CSV carry the tip force and the tensions with their deviations.
#[test]
fn tendon_estimate_from_the_scene_keys_in_text_and_csv() {
    let base = quick_bench("scene-keys-forward", "");
    let forward = solved(&[&base, "--tensions=2,1,0.5", "--tip-force=0.02,-0.05,0"]);
    let d = numbers(&forward["tendons"]["displacements_m"]);
    let text = scene_text("tendon_bench.toml")
        .replace("steps = 200", "steps = 50")
        .replace(
            "tensions_n = [3.0, 1.5, 0.0]",
            &format!("displacements_m = [{}]", list(&d)),
        );
    let path = write_scene(
        "scene-keys",
        &format!(
            "{text}\n[estimate.tendons]\ntensions_measured_n = [2.0, 1.0, 0.5]\n\
             tension_stds_n = [0.01, 0.02, 0.01]\nscan_reach = 0.0\nforce_prior_std_n = 0.5\n"
        ),
    );
    let (code, v) = estimated(&[&path]);
    assert_eq!(code, 0, "{}", v["status"]);
    // Without the search a verdict is never Determined.
    let verdict = v["status"]["determination"]
        .as_str()
        .unwrap_or_default()
        .to_string();
    assert!(
        ["Weak", "Unverified"].contains(&verdict.as_str()),
        "{}",
        v["status"]
    );
    assert_eq!(v["settings"]["scan_reach"], 0.0);
    assert_eq!(v["settings"]["force_prior_std_n"], 0.5);
    assert_eq!(
        numbers(&v["tendons"]["tension_measured_std_n"]),
        [0.01, 0.02, 0.01]
    );
    within_3_std(
        &numbers(&v["tip_force_n"]),
        &numbers(&v["tip_force_std_n"]),
        &[0.02, -0.05, 0.0],
        "tip force",
    );
    // The command line's tensions and deviation override the scene's.
    let (_, over) = estimated(&[&path, "--tensions-measured=2,1,0.5", "--tension-std=0.05"]);
    assert_eq!(
        numbers(&over["tendons"]["tension_measured_std_n"]),
        [0.05; 3]
    );

    let out = host_sim(&["estimate", &path]);
    assert_eq!(self::code(&out), 0);
    let text = stdout(&out);
    assert!(text.starts_with("status: converged"), "{text}");
    assert!(text.contains(&format!("determination {verdict}")), "{text}");
    assert!(text.contains("tip force ["), "{text}");
    assert!(
        text.contains("tensions measured [2.0, 1.0, 0.5] N, 1 sd [0.01, 0.02, 0.01] N"),
        "{text}"
    );
    assert!(
        text.contains(
            "tendon  tension_n  tension_sd_n  state  path_m  slack_m  displacement_residual_m  \
             tension_residual_n"
        ),
        "{text}"
    );

    let out = host_sim(&["estimate", &path, "--format", "csv"]);
    assert_eq!(self::code(&out), 0);
    let csv = stdout(&out);
    let header: Vec<&str> = csv.lines().next().unwrap_or_default().split(',').collect();
    let row: Vec<&str> = csv.lines().nth(1).unwrap_or_default().split(',').collect();
    let cell = |name: &str| row[header.iter().position(|h| *h == name).unwrap()];
    assert!(cell("tip_force_y_n").parse::<f64>().is_ok(), "{csv}");
    assert!(
        cell("tendon1_tension_std_n").parse::<f64>().is_ok(),
        "{csv}"
    );
    assert_eq!(cell("force_observable"), "true");
    assert_eq!(cell("status"), format!("Converged/Unchecked/{verdict}"));
}

/// Displacements no tensions explain (every spool taken in 5 cm): no answer (exit 3) with every
/// estimated number null, or an inconsistent closest fit (exit 4); never a confident answer.
#[test]
fn a_failed_tendon_estimate_prints_no_numbers() {
    let path = quick_bench("failed-estimate", "");
    let (code, v) = estimated(&[
        &path,
        "--displacements=0.05,0.05,0.05",
        "--tensions-measured=1,1,1",
        "--tension-std=0.01",
    ]);
    match code {
        3 => {
            assert_eq!(v["status"]["verdict"], "no_answer");
            assert!(v["status"]["determination"].is_null(), "{}", v["status"]);
            assert!(v["status"]["tension_determination"].is_null());
            for key in host_sim::run::TENDON_ESTIMATE_KEYS {
                assert!(v[key].is_null(), "{key}: {}", v[key]);
            }
            for key in host_sim::run::TENDON_ESTIMATE_TENDON_KEYS {
                assert!(v["tendons"][key].is_null(), "{key}: {}", v["tendons"]);
            }
            assert_eq!(numbers(&v["tendons"]["displacements_m"]), [0.05; 3]);
        }
        4 => assert_eq!(v["status"]["determination"], "Inconsistent"),
        other => panic!("exit {other}: {}", v["status"]),
    }
    let out = host_sim(&[
        "estimate",
        &path,
        "--displacements=0.05,0.05,0.05",
        "--tensions-measured=1,1,1",
        "--tension-std=0.01",
    ]);
    if code == 3 {
        assert!(stdout(&out).starts_with("status: no answer"));
        assert!(!stdout(&out).contains("tip force ["), "{}", stdout(&out));
    }
}

/// `estimate` on a tendon scene refuses bad input with exit 1, naming the key: wrong counts,
/// non-finite values, deviations not positive, missing displacements or deviations, and the scene's
/// `[estimate.tendons]` keys.
#[test]
fn tendon_estimate_bad_input_is_refused_naming_the_key() {
    let path = quick_bench("estimate-bad", "");
    let d = "--displacements=0.001,0.001,-0.001";
    let t = "--tensions-measured=1,1,1";
    for (args, key, reason) in [
        (
            vec!["--displacements=0.001,0.001"],
            "--displacements",
            "2 values for 3 tendons",
        ),
        (
            vec!["--displacements=NaN,0,0"],
            "--displacements[0]",
            "finite",
        ),
        (
            vec!["--displacements=0,0.5,0"],
            "--displacements[1]",
            "whole length",
        ),
        (
            vec![d, "--tensions-measured=1,1", "--tension-std=0.01"],
            "--tensions-measured",
            "2 values for 3 tendons",
        ),
        (
            vec![d, "--tensions-measured=1,NaN,1", "--tension-std=0.01"],
            "--tensions-measured[1]",
            "finite",
        ),
        (
            vec![d, t, "--tension-std=-0.01"],
            "--tension-std",
            "positive",
        ),
        (vec![d, t, "--tension-std=0"], "--tension-std", "positive"),
        (vec![d, t, "--tension-std=NaN"], "--tension-std", "positive"),
        (
            vec![d, t, "--tension-stds=0.01,-0.01,0.01"],
            "--tension-stds[1]",
            "positive",
        ),
        (
            vec![d, t, "--tension-stds=0.01,0.01"],
            "--tension-stds",
            "2 values for 3 tendons",
        ),
        (vec![d, t], "--tensions-measured", "standard deviation"),
        (
            vec![d, "--tension-std=0.01"],
            "--tension-std",
            "without measured tensions",
        ),
        (
            vec![d, "--cables=0.39,0.39,0.39"],
            "--cables",
            "the scene has [[tendon]]",
        ),
        (vec![], "actuation.tensions_n", "spool displacements"),
        (vec![d, "--plot=/tmp/figure.pdf"], "--plot", ".svg or .png"),
        (
            vec![d, "--plot=/nonexistent/dir/figure.svg"],
            "--plot",
            "no such directory",
        ),
    ] {
        let mut all = vec!["estimate", path.as_str()];
        all.extend_from_slice(&args);
        let out = host_sim(&all);
        let err = stderr(&out);
        assert_eq!(code(&out), 1, "{args:?}: {err}");
        assert!(
            err.contains(&format!("{key}: ")) && err.contains(reason),
            "{args:?}: {err:?} lacks {key:?} / {reason:?}"
        );
    }
    // The scene's keys.
    for (name, extra, key, reason) in [
        (
            "std-neg",
            "[estimate.tendons]\ntensions_measured_n = [1.0, 1.0, 1.0]\ntension_std_n = -1.0\n",
            "estimate.tendons.tension_std_n",
            "positive",
        ),
        (
            "stds-nan",
            "[estimate.tendons]\ntensions_measured_n = [1.0, 1.0, 1.0]\ntension_stds_n = [0.1, nan, 0.1]\n",
            "estimate.tendons.tension_stds_n[1]",
            "positive",
        ),
        (
            "count",
            "[estimate.tendons]\ntensions_measured_n = [1.0, 2.0]\n",
            "estimate.tendons.tensions_measured_n",
            "2 values for 3 tendons",
        ),
        (
            "both",
            "[estimate.tendons]\ntension_std_n = 0.1\ntension_stds_n = [0.1, 0.1, 0.1]\n",
            "estimate.tendons",
            "not both",
        ),
        (
            "prior",
            "[estimate.tendons]\nforce_prior_std_n = 0.0\n",
            "estimate.tendons.force_prior_std_n",
            "positive",
        ),
        (
            "reach",
            "[estimate.tendons]\nscan_reach = nan\n",
            "estimate.tendons.scan_reach",
            "not below zero",
        ),
        (
            "model",
            "[estimate.tendons]\nmodel_length_std_m = -1e-6\n",
            "estimate.tendons.model_length_std_m",
            "not below zero",
        ),
        (
            "unknown",
            "[estimate.tendons]\ntension_sd_n = 0.1\n",
            "line",
            "unknown field",
        ),
        (
            "resolution",
            "[estimate]\nresolution_m = -1.0\n",
            "estimate.resolution_m",
            "positive",
        ),
    ] {
        let scene = quick_bench(&format!("estimate-bad-{name}"), &format!("\n{extra}"));
        let out = host_sim(&["estimate", &scene, d]);
        let err = stderr(&out);
        assert_eq!(code(&out), 1, "{name}: {err}");
        assert!(
            err.contains(key) && err.contains(reason),
            "{name}: {err:?} lacks {key:?} / {reason:?}"
        );
    }
    // Tendon keys on a scene without tendons; no --cables there is a usage error (exit 2).
    let cables = scene("bench_3d_cables.toml");
    for arg in [d, t, "--tension-std=0.01", "--tension-stds=0.01,0.01,0.01"] {
        let out = host_sim(&["estimate", &cables, arg]);
        assert_eq!(code(&out), 1, "{arg}");
        let flag = arg.split('=').next().unwrap_or_default();
        assert!(
            stderr(&out).contains(&format!("{flag}: the scene has no [[tendon]]")),
            "{}",
            stderr(&out)
        );
    }
    let out = host_sim(&["estimate", &cables]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(stderr(&out).contains("--cables"), "{}", stderr(&out));
    let out = host_sim(&[
        "estimate",
        &path,
        d,
        t,
        "--tension-std=0.1",
        "--tension-stds=0.1,0.1,0.1",
    ]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    // [estimate.tendons] without tendons.
    let text = format!(
        "{}\n[estimate.tendons]\nscan_reach = 1.0\n",
        scene_text("bench_3d_cables.toml")
    );
    let out = host_sim(&["solve", &write_scene("estimate-no-tendons", &text)]);
    assert_eq!(code(&out), 1);
    assert!(
        stderr(&out).contains("estimate.tendons: the scene has no [[tendon]]"),
        "{}",
        stderr(&out)
    );
}

/// The polylines of an SVG drawn in colour `rgb`.
fn polylines(svg: &str, rgb: (u8, u8, u8)) -> usize {
    let stroke = format!("stroke=\"#{:02X}{:02X}{:02X}\"", rgb.0, rgb.1, rgb.2);
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.split("/>").next().is_some_and(|p| p.contains(&stroke)))
        .count()
}

/// A fresh, empty directory for figures.
fn figure_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "host-sim-tendon-plot-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// `--plot` on tendon scenes: SVG and PNG written and not empty; the SVG has one polyline per
/// taut tendon in each of the three projections and the legend (a slack tendon is dashed: many
/// short ones); an estimate adds the tip's ellipse in each projection; without an answer nothing
/// is drawn.
#[test]
fn tendon_plots_are_written_for_solve_and_estimate() {
    let path = quick_bench("plots", "");
    let dir = figure_dir("tendon");
    let file = |name: &str| dir.join(name).display().to_string();
    for name in ["solve.svg", "solve.png"] {
        let out = host_sim(&["solve", &path, "--plot", &file(name)]);
        assert_eq!(code(&out), 0, "{}", stderr(&out));
        assert!(stderr(&out).contains("plot written to"), "{}", stderr(&out));
        let size = std::fs::metadata(file(name)).map(|m| m.len()).unwrap_or(0);
        assert!(size > 1000, "{name}: {size} bytes");
    }
    let png = std::fs::read(file("solve.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"), "not a PNG");
    let svg = std::fs::read_to_string(file("solve.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("x (mm)") && svg.contains("z (mm)"));
    // The scene's tensions 3, 1.5, 0: tendons 0 and 1 taut, 2 slack (dashed).
    assert_eq!(polylines(&svg, host_sim::plots::tendon_rgb(0)), 3 + 1);
    assert_eq!(polylines(&svg, host_sim::plots::tendon_rgb(1)), 3 + 1);
    assert!(polylines(&svg, host_sim::plots::tendon_rgb(2)) > 3 + 1);
    assert_eq!(polylines(&svg, host_sim::plots::ELLIPSE_RGB), 0);

    // An estimate with tensions measured (no search, for speed): all taut, and the ellipse.
    let forward = solved(&[&path, "--tensions=2,1,0.5"]);
    let d = format!(
        "--displacements={}",
        list(&numbers(&forward["tendons"]["displacements_m"]))
    );
    let quick = quick_bench("plots-estimate", "\n[estimate.tendons]\nscan_reach = 0.0\n");
    let out = host_sim(&[
        "estimate",
        &quick,
        &d,
        "--tensions-measured=2,1,0.5",
        "--tension-std=0.01",
        "--plot",
        &file("estimate.svg"),
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let svg = std::fs::read_to_string(file("estimate.svg")).unwrap();
    for j in 0..3 {
        assert_eq!(
            polylines(&svg, host_sim::plots::tendon_rgb(j)),
            3 + 1,
            "tendon {j}"
        );
    }
    assert_eq!(polylines(&svg, host_sim::plots::ELLIPSE_RGB), 3 + 1);
    assert!(
        svg.contains("tip ±1σ ellipse") && svg.contains(" ± "),
        "legend"
    );
    assert!(svg.contains("µm") || svg.contains("mm,"), "units");

    // No answer: no file, and standard error says so.
    let out = host_sim(&[
        "solve",
        &path,
        "--displacements=0.05,0.05,0.05",
        "--plot",
        &file("failed.svg"),
    ]);
    assert_eq!(code(&out), 3);
    assert!(stderr(&out).contains("nothing drawn"), "{}", stderr(&out));
    assert!(!dir.join("failed.svg").exists());
}

/// `--plot` on a scene without tendons: the backbone, guides and cables, and for an estimate the
/// ellipse.
#[test]
fn tendon_free_scenes_plot_too() {
    let dir = figure_dir("cables");
    let svg = dir.join("bench.svg").display().to_string();
    let bench = scene("bench_3d_cables.toml");
    let out = host_sim(&["solve", &bench, "--tip-force=0,-0.3,0.1", "--plot", &svg]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("passive cables"), "legend");
    assert_eq!(polylines(&text, host_sim::plots::tendon_rgb(0)), 0);
    let png = dir.join("estimate.png").display().to_string();
    let out = host_sim(&[
        "estimate",
        &bench,
        "--cables",
        "0.3912,0.3773,0.3825",
        "--plot",
        &png,
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(std::fs::metadata(&png).map(|m| m.len()).unwrap_or(0) > 1000);
}

/// Spool displacements the grid cannot meet (Rao et al.'s robot at one RK4 step between disks,
/// given the displacements its tensions (4, 0, 0, 0, 2, 0) N need at 800 steps): the displacement
/// solve stalls, and `solve` says so (exit 3, no numbers), though the forward solve at the tensions
/// it ended on converged; the text labels that solve's report as such, not as the solve's.
#[test]
fn a_displacement_solve_that_stalls_is_no_answer() {
    let coarse = scene_text("tendon_rao_two_section.toml").replace("steps = 100", "steps = 10");
    assert_eq!(coarse.matches("steps = 10\n").count(), 2);
    let path = write_scene("rao-coarse", &coarse);
    let d = "--displacements=0.006060727668387944,5.485480448508273e-5,-0.005951018059417751,\
             0.00410209534165995,0.004025730856211607,-0.007909650386145939";
    let json = host_sim(&["solve", &path, d, "--format", "json"]);
    assert_eq!(code(&json), 3, "{}", stderr(&json));
    let v = json_of(&json);
    assert_ne!(v["status"]["verdict"], "answer", "{}", v["status"]);
    assert_eq!(v["tendons"]["displacement_solve"]["termination"], "Stalled");
    assert!(v["tip_position_m"].is_null() && v["tendons"]["tensions_n"].is_null());
    let text = stdout(&host_sim(&["solve", &path, d]));
    assert!(
        text.contains("displacement solve: termination Stalled"),
        "{text}"
    );
    assert!(
        text.contains("forward solve at those tensions: Report"),
        "{text}"
    );
    assert!(!text.contains("\nsolve: "), "{text}");
}
