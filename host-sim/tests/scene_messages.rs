//! What a scene's author reads when a scene is wrong: the line it is wrong at, the table's brackets,
//! and the unit slip behind a number no robot has.

use std::path::PathBuf;

use host_sim::scene::{Scene, SceneError, locate};

fn shipped(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    std::fs::read_to_string(path).expect("shipped scene")
}

/// The 3D cable bench with `from` replaced by `to` (exactly once).
fn bench_with(from: &str, to: &str) -> String {
    let text = shipped("bench_3d_cables.toml");
    assert_eq!(text.matches(from).count(), 1, "{from:?} once in the bench");
    text.replacen(from, to, 1)
}

fn refusal(text: &str) -> SceneError {
    match Scene::parse(text, "robot.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

/// The 1-based line of the first line of `text` that contains `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .map(|i| i + 1)
        .unwrap_or_else(|| panic!("{needle:?} not in the text"))
}

#[test]
fn a_scene_without_sections_is_told_so_without_a_line() {
    let text = shipped("bench_3d_cables.toml");
    let start = text.find("[[section]]").unwrap();
    let end = text.find("[guides]").unwrap();
    let e = refusal(&format!("{}{}", &text[..start], &text[end..]));
    assert_eq!(e.field, "robot.toml", "{e}");
    assert!(
        e.reason.contains("no `[[section]]` table") && !e.to_string().contains("line"),
        "{e}"
    );
}

#[test]
fn single_brackets_for_a_list_of_tables_name_the_double_ones() {
    // Three cables, the second written `[cable]`: the parser says "duplicate key".
    let text = shipped("bench_3d_cables.toml");
    let second = text.match_indices("[[cable]]").nth(1).unwrap().0;
    let text = format!(
        "{}[cable]{}",
        &text[..second],
        &text[second + "[[cable]]".len()..]
    );
    let e = refusal(&text);
    let line = text[..second].matches('\n').count() + 1;
    assert!(e.field.contains(&format!("line {line} (`[cable]`)")), "{e}");
    assert!(
        e.reason.contains("`[[cable]]` table (double brackets)"),
        "{e}"
    );
    // The only section written `[section]`: the parser says "expected a sequence".
    let text = bench_with("[[section]]", "[section]");
    let e = refusal(&text);
    assert!(
        e.field
            .contains(&format!("line {}", line_of(&text, "[section]")))
            && e.reason.contains("`[[section]]`"),
        "{e}"
    );
    // And the other way round: one tip, written as a list.
    let e = refusal(&bench_with("[tip]", "[[tip]]"));
    assert!(
        e.reason.contains("one `[tip]` table (single brackets)"),
        "{e}"
    );
}

#[test]
fn a_modulus_in_gigapascals_is_refused_at_its_line_with_the_slip_named() {
    let text = bench_with("62.7e9", "62.7");
    let e = refusal(&text);
    let line = line_of(&text, "youngs_modulus_pa = 62.7,");
    assert!(
        e.field.contains(&format!("robot.toml, line {line}"))
            && e.field.ends_with("section[0].material.youngs_modulus_pa"),
        "{e}"
    );
    assert!(
        e.reason.contains("below 1 MPa") && e.reason.contains("Did you mean 62.7e9 Pa (62.7 GPa)?"),
        "{e}"
    );
    // Megapascals read as pascals too.
    let e = refusal(&bench_with("62.7e9", "62.7e3"));
    assert!(e.reason.contains("Did you mean 62700e6 Pa"), "{e}");
    // Stiffer than diamond: refused, no guess.
    let e = refusal(&bench_with("62.7e9", "62.7e12"));
    assert!(e.reason.contains("above 1.2 TPa"), "{e}");
    // The thesis's Nitinol and a soft silicone are both accepted.
    for modulus in ["62.7e9", "2e6"] {
        let text = bench_with("62.7e9", modulus);
        Scene::parse(&text, "robot.toml").unwrap_or_else(|e| panic!("{modulus}: {e}"));
    }
}

#[test]
fn a_diameter_in_millimetres_is_refused_with_the_slip_named() {
    let e = refusal(&bench_with("diameter_m = 1.56e-3", "diameter_m = 1.2"));
    assert!(
        e.field.ends_with("section[0].cross_section.diameter_m")
            && e.reason.contains("not a slender rod")
            && e.reason.contains("Did you mean 1.2e-3 m (1.2 mm)?"),
        "{e}"
    );
    // Half the length is the limit: just under it is accepted, and warned about as wide.
    let text = bench_with("diameter_m = 1.56e-3", "diameter_m = 0.19");
    let scene = Scene::parse(&text, "robot.toml").expect("0.19 m of 0.39 m is a rod");
    let warnings = scene.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].field, "section[0].cross_section.diameter_m");
}

#[test]
fn unusual_values_are_warned_about_with_their_slips() {
    // The shipped scenes have none.
    for name in [
        "bench_3d_cables.toml",
        "tendon_bench.toml",
        "tendon_two_section.toml",
        "thesis_exp1_two_sections.toml",
        "thesis_exp2_accurate.toml",
        "thesis_exp2_average.toml",
    ] {
        let scene = Scene::parse(&shipped(name), name).expect("shipped scene");
        assert_eq!(scene.warnings(), Vec::new(), "{name}");
    }
    let cases = [
        (
            ("length_m = 0.39", "length_m = 390.0"),
            "section[0].length_m",
            "Did you mean 390e-3 m (390 mm)?",
        ),
        (
            ("mass_kg = 0.0", "mass_kg = 2.0"),
            "guides.mass_kg",
            "Did you mean 2e-3 kg (2 g)?",
        ),
        (
            ("thickness_m = 3.01e-3", "thickness_m = 3.01"),
            "guides.thickness_m",
            "Did you mean 3.01e-3 m (3.01 mm)?",
        ),
        (
            (
                "line_density_kg_per_m = 0.03725",
                "line_density_kg_per_m = 37.25",
            ),
            "section[0].line_density_kg_per_m",
            "Did you mean 37.25e-3 kg/m (37.25 g/m)?",
        ),
        (
            (
                "gravity_m_s2 = [0.0, -9.81, 0.0]",
                "gravity_m_s2 = [0.0, -981.0, 0.0]",
            ),
            "gravity_m_s2",
            "ten times the Earth's",
        ),
        (
            ("angle_deg = 120.0", "angle_deg = 2.0944"),
            "cable[1].angle_deg",
            "Did you mean 120.0003 degrees (2.0944 rad)?",
        ),
    ];
    for ((from, to), field, advice) in cases {
        let mut text = bench_with(from, to);
        if field.contains("angle") {
            text = text.replacen("angle_deg = 240.0", "angle_deg = 4.1888", 1);
        }
        let scene = Scene::parse(&text, "robot.toml").expect("a warning, not a refusal");
        let warnings = scene.warnings();
        assert_eq!(warnings.len(), 1, "{to}: {warnings:?}");
        let w = &warnings[0];
        assert!(w.field == field && w.reason.contains(advice), "{to}: {w}");
        // Located, it names the line that holds the value.
        let located = locate(w.clone(), &text, "robot.toml");
        let line = line_of(&text, to.split(" = ").last().unwrap().trim_end_matches(']'));
        assert!(
            located
                .field
                .starts_with(&format!("robot.toml, line {line} ")),
            "{to}: {located}"
        );
    }
    // A density in g/cm^3.
    let text = bench_with("line_density_kg_per_m = 0.03725", "density_kg_m3 = 6.45");
    let w = Scene::parse(&text, "robot.toml").unwrap().warnings();
    assert!(
        w.len() == 1
            && w[0]
                .reason
                .contains("Did you mean 6.45e3 kg/m^3 (6.45 g/cm^3)?"),
        "{w:?}"
    );
}

#[test]
fn an_error_is_located_at_its_key_or_at_the_table_that_lacks_it() {
    let text = shipped("tendon_bench.toml");
    // A key that is written: its own line.
    let e = locate(
        SceneError::new("section[0].steps", "test"),
        &text,
        "robot.toml",
    );
    assert!(
        e.field
            .starts_with(&format!("robot.toml, line {} ", line_of(&text, "steps ="))),
        "{e}"
    );
    // A key left at its default (the first tendon's end_m): the line of its `[[tendon]]`.
    assert!(
        !text.contains("end_m ="),
        "the bench's tendons end at the tip by default"
    );
    let e = locate(
        SceneError::new("tendon[1].end_m", "test"),
        &text,
        "robot.toml",
    );
    let second = text.match_indices("[[tendon]]").nth(1).unwrap().0;
    let line = text[..second].matches('\n').count() + 1;
    assert!(
        e.field
            .starts_with(&format!("robot.toml, line {line} (`[[tendon]]`)")),
        "{e}"
    );
    // A command-line option or a table the file does not have stays as it was.
    for field in ["--tensions", "estimate.tendons", "robot.toml, line 3 (`x`)"] {
        let e = locate(SceneError::new(field, "test"), &text, "robot.toml");
        assert_eq!(e.field, field);
    }
}

#[test]
fn a_bad_cable_or_load_is_located_at_its_own_table_not_the_first() {
    // The third cable ends beyond the rod: the model's check names no cable; the error must.
    let third = shipped("bench_3d_cables.toml")
        .match_indices("[[cable]]")
        .nth(2)
        .map(|(at, _)| at)
        .expect("three cables");
    let mut text = shipped("bench_3d_cables.toml");
    text.insert_str(third + "[[cable]]\n".len(), "end_m = 5.0\n");
    // The file reads; the rod is refused (as `solve` builds it), and located as main.rs does.
    let scene = Scene::parse(&text, "robot.toml").expect("it parses");
    let e = locate(scene.rod().expect_err("refused"), &text, "robot.toml");
    let header = text[..third].matches('\n').count() + 1;
    assert!(e.field.contains("cable[2]"), "{e}");
    assert!(
        e.field.starts_with(&format!("robot.toml, line {header} "))
            || e.field.starts_with(&format!(
                "robot.toml, line {} ",
                line_of(&text, "end_m = 5.0")
            )),
        "{e}"
    );
    // A path into the list without an item keeps no place rather than blame the first table.
    let e = locate(SceneError::new("cable.end_m", "test"), &text, "robot.toml");
    assert_eq!(e.field, "cable.end_m");
}

#[test]
fn a_value_that_is_not_finite_is_refused_not_warned_about() {
    for (from, to, key) in [
        ("length_m = 0.39", "length_m = inf", "section[0].length_m"),
        ("radius_m = 0.01", "radius_m = inf", "cable[0].radius_m"),
    ] {
        let text = shipped("bench_3d_cables.toml").replacen(from, to, 1);
        let scene = Scene::parse(&text, "robot.toml").expect("read; refused when the rod is built");
        let warnings = scene.warnings();
        assert!(
            warnings.iter().all(|w| !w.field.contains(key)),
            "{to}: {warnings:?}"
        );
        let e = scene.rod().expect_err(to);
        assert!(e.field.contains(key), "{to}: {e}");
    }
}
