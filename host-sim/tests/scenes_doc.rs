//! host-sim/SCENES.md against the parser: every complete scene in it parses, builds and solves, and
//! every key the parser accepts is documented in its table's section, and no other.

use std::collections::BTreeSet;

use host_sim::run::{self, Estimate, Solution, Solve, TendonSolve, with_model};
use host_sim::scene::{Scene, SceneError, TensionArgs};

const DOC: &str = include_str!("../SCENES.md");

/// The key no table has.
const BOGUS: &str = "zz_not_a_key = 1";

/// A scene with every table (and each inline table of a section), built and solved as the examples
/// are; each case below writes [`BOGUS`] into one of its tables.
const EVERY_TABLE: &str = r#"
name = "every table"
gravity_m_s2 = [0.0, -9.81, 0.0]

[base]
position_m = [0.0, 0.0, 0.0]
tangent = [1.0, 0.0, 0.0]
local_x = [0.0, 1.0, 0.0]

[[section]]
length_m = 0.2
steps = 40
density_kg_m3 = 6450.0
material = { youngs_modulus_pa = 60e9, poisson_ratio = 0.3 }
cross_section = { diameter_m = 1.2e-3 }

[[section]]
length_m = 0.1
steps = 20
line_density_kg_per_m = 0.0073
stiffness = { bending_torsion_nm2 = [6.1e-3, 6.1e-3, 4.7e-3], shear_axial_n = [2.6e4, 2.6e4, 6.8e4] }

[guides]
mass_model = "ignore"
centres_m = [0.1, 0.2, 0.3]

[[cable]]
angle_deg = 90.0
radius_m = 5e-3

[[tendon]]
angle_deg = 0.0
radius_m = 5e-3

[actuation]
tensions_n = [0.1]

[[load]]
s_m = 0.15
mass_kg = 1e-3

[tip]
force_n = [0.0, 0.0, 0.0]

[output]
points = 11

[solver]
attitude = "quaternion"

[estimate]
resolution_m = 1e-5

[estimate.tendons]
scan_reach = 3.0

[drive]
spool_radius_m = 0.005
gear_ratio = 8
encoder_counts_per_turn = 16384
motor_full_steps_per_turn = 200
microsteps_per_full_step = 16
max_cable_speed_m_per_s = 0.05
home_lengths_m = [0.3]
zero_offset_counts = [0]
reel_in_with_counts = [false]

[controller]
loop_rate_hz = 100
sample_rate_hz = 1000
steps_per_section = 20
"#;

/// Where a case writes [`BOGUS`].
#[derive(Clone, Copy, Debug)]
enum Place {
    /// At the top of the file.
    Top,
    /// On the line after this table header.
    After(&'static str),
    /// First inside this inline table (the text up to and including its `{`).
    Inline(&'static str),
}

/// Each table of the format: its key path, the heading of its section in SCENES.md (the heading's
/// text starts with it) and where its bogus key goes.
const TABLES: [(&str, &str, Place); 18] = [
    ("", "Top level", Place::Top),
    ("base", "`[base]`", Place::After("[base]")),
    ("section", "`[[section]]`", Place::After("[[section]]")),
    (
        "section.material",
        "`material`",
        Place::Inline("material = {"),
    ),
    (
        "section.cross_section",
        "`cross_section`",
        Place::Inline("cross_section = {"),
    ),
    (
        "section.stiffness",
        "`stiffness`",
        Place::Inline("stiffness = {"),
    ),
    ("guides", "`[guides]`", Place::After("[guides]")),
    ("cable", "`[[cable]]`", Place::After("[[cable]]")),
    ("tendon", "`[[tendon]]`", Place::After("[[tendon]]")),
    ("actuation", "`[actuation]`", Place::After("[actuation]")),
    ("load", "`[[load]]`", Place::After("[[load]]")),
    ("tip", "`[tip]`", Place::After("[tip]")),
    ("output", "`[output]`", Place::After("[output]")),
    ("solver", "`[solver]`", Place::After("[solver]")),
    ("estimate", "`[estimate]`", Place::After("[estimate]")),
    (
        "estimate.tendons",
        "`[estimate.tendons]`",
        Place::After("[estimate.tendons]"),
    ),
    ("drive", "`[drive]`", Place::After("[drive]")),
    ("controller", "`[controller]`", Place::After("[controller]")),
];

/// `text` with [`BOGUS`] written at `place`.
fn with_bogus(text: &str, place: Place) -> String {
    match place {
        Place::Top => format!("{BOGUS}\n{text}"),
        Place::After(header) => {
            let mut lines: Vec<&str> = text.lines().collect();
            let at = lines
                .iter()
                .position(|l| l.trim() == header)
                .unwrap_or_else(|| panic!("no {header} in the scene"));
            lines.insert(at + 1, BOGUS);
            lines.join("\n")
        }
        Place::Inline(open) => {
            assert!(text.contains(open), "no {open} in the scene");
            text.replacen(open, &format!("{open} {BOGUS},"), 1)
        }
    }
}

/// Parses `text` and does what `solve` does with it: the rod, the settings, the output points, the
/// tendons and their actuation when it has them, and the solve itself.
fn solve(text: &str, origin: &str) -> Result<Solution, SceneError> {
    let scene = Scene::parse(text, origin)?;
    let rod = scene.rod()?;
    scene.attitude()?;
    scene.shooting_settings()?;
    scene.output_points_m(rod.length_m())?;
    Estimate::settings(&scene)?;
    let load = scene.tip_load()?;
    match scene.actuation()? {
        Some(actuation) => {
            scene.tendon_inverse_settings()?;
            scene.tension_measurement(TensionArgs::default())?;
            with_model(
                &scene,
                TendonSolve {
                    scene: &scene,
                    load,
                    actuation,
                    plot: false,
                },
            )
        }
        None => with_model(
            &scene,
            Solve {
                scene: &scene,
                load,
                plot: false,
            },
        ),
    }
}

/// The ```toml blocks of the document: the line of the fence (from 1) and the text.
fn toml_blocks(doc: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut open: Option<(usize, Vec<&str>)> = None;
    for (i, line) in doc.lines().enumerate() {
        match &mut open {
            None if line.trim() == "```toml" => open = Some((i + 1, Vec::new())),
            None => {}
            Some(_) if line.trim() == "```" => {
                if let Some((at, lines)) = open.take() {
                    blocks.push((at, lines.join("\n")));
                }
            }
            Some((_, lines)) => lines.push(line),
        }
    }
    assert!(open.is_none(), "a ```toml block is not closed");
    blocks
}

/// One heading of the document outside code blocks, and the table rows under it before the next
/// heading: each row's key (its first cell, in backticks) and unit (second cell).
#[derive(Debug)]
struct Part {
    title: String,
    rows: Vec<(String, String)>,
}

fn parts(doc: &str) -> Vec<Part> {
    let mut parts: Vec<Part> = Vec::new();
    let mut fenced = false;
    for line in doc.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if line.starts_with('#') {
            parts.push(Part {
                title: line.trim_start_matches('#').trim().to_string(),
                rows: Vec::new(),
            });
            continue;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // `| a | b |` splits into ["", "a", "b", ""].
        if line.starts_with('|')
            && let (Some(first), Some(unit), Some(part)) =
                (cells.get(1), cells.get(2), parts.last_mut())
            && let Some(key) = first.strip_prefix('`').and_then(|k| k.strip_suffix('`'))
        {
            part.rows.push((key.to_string(), unit.to_string()));
        }
    }
    parts
}

/// The field names serde lists in its unknown-field error: "unknown field `x`, expected one of `a`,
/// `b`" (or "expected `a` or `b`", "expected `a`").
fn expected_fields(message: &str) -> BTreeSet<String> {
    let Some((_, list)) = message.split_once("expected") else {
        return BTreeSet::new();
    };
    list.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

#[test]
fn every_complete_scene_in_the_doc_parses_builds_and_solves() {
    let scenes: Vec<(usize, String)> = toml_blocks(DOC)
        .into_iter()
        .filter(|(_, text)| {
            text.lines()
                .any(|l| l.trim_start().starts_with("[[section]]"))
        })
        .collect();
    // Examples (a) and (b), and the tendon example.
    assert!(
        scenes.len() >= 3,
        "{} complete scenes in SCENES.md",
        scenes.len()
    );
    for (line, text) in &scenes {
        let origin = format!("SCENES.md, the block at line {line}");
        let solution = solve(text, &origin).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            solution.status.exit_code,
            run::exit::ANSWER,
            "{origin}: {:?}",
            solution.status
        );
        assert!(solution.tip_position_m.is_some(), "{origin}: no tip");
    }
    // The check refuses a broken scene: the first, with a section of no steps.
    let (line, text) = &scenes[0];
    let broken = text.replacen("steps =", "steps = 0 #", 1);
    assert!(
        solve(&broken, "broken").is_err(),
        "the block at line {line} with steps = 0 was accepted"
    );
}

#[test]
fn every_key_the_parser_accepts_is_documented_in_its_table() {
    let solution = solve(EVERY_TABLE, "EVERY_TABLE").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(solution.status.exit_code, run::exit::ANSWER);
    let parts = parts(DOC);
    let mut covered = BTreeSet::new();
    for (path, heading, place) in TABLES {
        let text = with_bogus(EVERY_TABLE, place);
        let error = Scene::parse(&text, "bogus").expect_err(&format!(
            "{BOGUS} in the table `{path}` was accepted:\n{text}"
        ));
        assert!(
            error.reason.contains("unknown field `zz_not_a_key`"),
            "table `{path}`: {error}"
        );
        let accepted = expected_fields(&error.reason);
        assert!(!accepted.is_empty(), "table `{path}`: no fields in {error}");

        let found: Vec<&Part> = parts
            .iter()
            .filter(|p| p.title.starts_with(heading))
            .collect();
        let [part] = found.as_slice() else {
            panic!("{} headings in SCENES.md start with {heading}", found.len());
        };
        let documented: BTreeSet<String> = part.rows.iter().map(|(k, _)| k.clone()).collect();
        let missing: Vec<&String> = accepted.difference(&documented).collect();
        let unknown: Vec<&String> = documented.difference(&accepted).collect();
        assert!(
            missing.is_empty() && unknown.is_empty(),
            "SCENES.md \"{heading}\": keys the parser accepts but the table lacks {missing:?}; \
             rows the parser does not accept {unknown:?}"
        );
        // A key documented as a table must be one of the cases.
        for (key, unit) in &part.rows {
            if unit.contains("table") {
                let sub = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                covered.insert(sub);
            }
        }
    }
    let cases: BTreeSet<String> = TABLES
        .iter()
        .map(|(path, _, _)| path.to_string())
        .filter(|p| !p.is_empty())
        .collect();
    assert_eq!(
        covered, cases,
        "the tables SCENES.md documents against the tables this test writes into"
    );
}
