//! Reads the robot the firmware runs from its robot file, the same TOML the host tools read
//! (`ROBOT=path/to/robot.toml`, relative to this directory; `robots/bench.toml` by default), and
//! writes it as Rust constants (`$OUT_DIR/robot.rs`, included by `src/config.rs`). Puts the
//! repository's `memory.x` (STM32F405 memory map) on the linker's search path for target builds,
//! and adds defmt's linker script to the images that log with defmt.
//!
//! A robot that does not fit the firmware is a build error that names the capacity and the value:
//! the file's own errors at their line (as `host-sim` reports them), and the generated constants
//! carry compile-time assertions against the image's capacities (`src/config.rs`).

use std::fmt::Write as _;
use std::{env, fs, path::PathBuf};

use model_core::{Model, Quaternion, Rod};
use robot_scene::{ControllerSpec, DriveSpec, Scene};

/// Images that log with defmt (over RTT).
const DEFMT_IMAGES: &[&str] = &["estimator", "board"];

/// The robot when `ROBOT` is not set: the thesis bench of the golden reference.
const DEFAULT_ROBOT: &str = "robots/bench.toml";

/// The tendon image's robot when `TENDON_ROBOT` is not set: the bench of the golden tendon reference.
const DEFAULT_TENDON_ROBOT: &str = "robots/tendon_bench.toml";

/// Cables, spools and angle sensors the firmware reads: the sampler's and the loop's capacity (one
/// AS5047P per spool). `config::CABLE_COUNT` is this.
const CABLE_COUNT: usize = 3;

/// Tendons the tendon image drives: its displacement and tension arrays' length.
/// `tendon::TENDON_COUNT` is this.
const TENDON_COUNT: usize = 3;

/// A robot file named by `variable` (relative to this directory, or `default`): its name as given
/// and its text. Cargo reruns this script when either changes.
fn robot_file(
    manifest: &std::path::Path,
    variable: &str,
    default: &str,
) -> Result<(String, String), String> {
    println!("cargo:rerun-if-env-changed={variable}");
    let robot = match env::var_os(variable) {
        None => default.to_string(),
        Some(given) => match given.into_string() {
            Ok(given) if !given.trim().is_empty() => given,
            _ => {
                return Err(format!(
                    "{variable} is set but names no file (empty, or not UTF-8): unset it for \
                     {default}, or give the robot file's path"
                ));
            }
        },
    };
    if robot != default {
        println!("cargo:warning=building for the robot of {robot} ({variable}), not {default}");
    }
    let path = manifest.join(&robot);
    println!("cargo:rerun-if-changed={}", path.display());
    let text = fs::read_to_string(&path)
        .map_err(|e| format!("the robot file {robot} ({}): {e}", path.display()))?;
    Ok((robot, text))
}

fn main() {
    // The robot file's errors as host-sim says them, one per line, without a Debug dump around them.
    if let Err(e) = run() {
        eprintln!("{e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    println!("cargo:rerun-if-changed=build.rs");
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR")?);
    let out = PathBuf::from(env::var("OUT_DIR")?);

    let (robot, text) = robot_file(&manifest, "ROBOT", DEFAULT_ROBOT)?;
    let generated = generate(&robot, &text).map_err(|e| format!("the robot file {e}"))?;
    fs::write(out.join("robot.rs"), generated)?;
    let (robot, text) = robot_file(&manifest, "TENDON_ROBOT", DEFAULT_TENDON_ROBOT)?;
    let generated =
        generate_tendon(&robot, &text).map_err(|e| format!("the tendon robot file {e}"))?;
    fs::write(out.join("tendon_robot.rs"), generated)?;

    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return Ok(());
    }
    let memory = manifest.join("..").join("memory.x");
    println!("cargo:rerun-if-changed={}", memory.display());
    fs::copy(&memory, out.join("memory.x"))?;
    println!("cargo:rustc-link-search={}", out.display());
    // defmt's linker script needs a global logger: only the images that log with defmt get it.
    for image in DEFMT_IMAGES {
        println!("cargo:rustc-link-arg-bin={image}=-Tdefmt.x");
    }
    Ok(())
}

/// The robot file `origin` (its text) as the constants of `src/config.rs`.
fn generate(origin: &str, text: &str) -> Result<String, String> {
    let scene = Scene::parse(text, origin).map_err(|e| e.to_string())?;
    let (Some(drive), Some(controller)) = (&scene.drive, &scene.controller) else {
        return Err(format!(
            "{origin}: the firmware needs its [drive] and [controller] tables \
             (host-sim/SCENES.md, \"The drive and the controller\")"
        ));
    };
    let (rod, model) = mcu_rod(origin, text, &scene)?;
    if !scene.tendons.is_empty() {
        println!(
            "cargo:warning={origin}: its [[tendon]] tables are not read by the cable estimator \
             (a tendon robot's file goes in TENDON_ROBOT)"
        );
    }
    if rod.cables.len() != CABLE_COUNT {
        return Err(format!(
            "{origin}: {} [[cable]] tables; the firmware reads exactly {CABLE_COUNT} cables \
             (CABLE_COUNT in firmware/build.rs: one angle sensor and spool each)",
            rod.cables.len()
        ));
    }
    let mut g = String::new();
    let written = (|| -> std::fmt::Result {
        header(&mut g, origin, &scene, "")?;
        writeln!(
            g,
            "/// Cables, spools and angle sensors the firmware reads (one AS5047P per spool)."
        )?;
        writeln!(g, "pub const CABLE_COUNT: usize = {CABLE_COUNT};")?;
        writeln!(g, "/// Length of the rod, m: its sections' together.")?;
        writeln!(g, "pub const ROD_LENGTH_M: f64 = {};", lit(rod.length_m()))?;
        write_push(&mut g, "push_robot", &rod)?;
        write_drive(&mut g, origin, drive, controller)
    })();
    written.map_err(|e| e.to_string())?;
    write_plan(&mut g, &rod, &model, "PLAN_NODES").map_err(|e| format!("{origin}: {e}"))?;
    Ok(g)
}

/// The tendon robot file `origin` (its text) as the constants of `src/tendon.rs`: the rod, the
/// tendons (checked against its guides), the MCU's steps.
fn generate_tendon(origin: &str, text: &str) -> Result<String, String> {
    let scene = Scene::parse(text, origin).map_err(|e| e.to_string())?;
    let located = |e: robot_scene::SceneError| robot_scene::locate(e, text, origin).to_string();
    let Some(controller) = &scene.controller else {
        return Err(format!(
            "{origin}: the firmware needs its [controller] table (host-sim/SCENES.md, \
             \"The drive and the controller\")"
        ));
    };
    let (rod, model) = mcu_rod(origin, text, &scene)?;
    if !scene.cables.is_empty() {
        println!(
            "cargo:warning={origin}: its [[cable]] tables are not read by the tendon image (a \
             cable robot's file goes in ROBOT)"
        );
    }
    // Checked against the guides as host-sim checks them (each must end at a guide's centre).
    let set = scene.tendon_set(&model).map_err(located)?;
    let tendons = set.as_ref().map_or(&[][..], |s| s.tendons());
    if tendons.len() != TENDON_COUNT {
        return Err(format!(
            "{origin}: {} [[tendon]] tables; the tendon image drives exactly {TENDON_COUNT} \
             tendons (TENDON_COUNT in firmware/build.rs)",
            tendons.len()
        ));
    }
    let mut g = String::new();
    let written = (|| -> std::fmt::Result {
        header(&mut g, origin, &scene, "TENDON_")?;
        writeln!(g, "/// Tendons the tendon image drives.")?;
        writeln!(g, "pub const TENDON_COUNT: usize = {TENDON_COUNT};")?;
        writeln!(g, "/// RK4 steps over each section on the MCU.")?;
        writeln!(
            g,
            "pub const STEPS_PER_SECTION: u16 = {};",
            controller.steps_per_section
        )?;
        write_push(&mut g, "push_tendon_robot", &rod)?;
        let specs = tendons.iter().map(|k| {
            format!(
                "model_core::Tendon {{ hole_m: nalgebra::Vector2::new({}, {}), end_m: {}, \
                 axial_stiffness_n: {}, feed_length_m: {}, friction_coefficient: {} }}",
                t(k.hole_m.x),
                t(k.hole_m.y),
                t(k.end_m),
                k.axial_stiffness_n
                    .map_or_else(|| "None".to_string(), |x| format!("Some({})", t(x))),
                t(k.feed_length_m),
                t(k.friction_coefficient)
            )
        });
        writeln!(
            g,
            "\n/// The robot file's tendons, in the order of its `[[tendon]]` tables."
        )?;
        writeln!(
            g,
            "#[inline(always)]\nfn tendon_specs<T: model_core::Scalar>() -> [model_core::Tendon<T>; \
             TENDON_COUNT] {{\n    {}\n}}",
            list(specs)
        )
    })();
    written.map_err(|e| e.to_string())?;
    write_plan(&mut g, &rod, &model, "TENDON_NODES").map_err(|e| format!("{origin}: {e}"))?;
    Ok(g)
}

/// A robot's model in f64, at model-core's largest capacity.
type HostModel = Model<f64, Quaternion<f64>>;

/// The scene's rod at the controller's steps, and its model in f64 (which checks it). The file's
/// warnings (host-sim's: unusual values, the likely unit slip) become the build's.
fn mcu_rod(origin: &str, text: &str, scene: &Scene) -> Result<(Rod<f64>, HostModel), String> {
    let located = |e: robot_scene::SceneError| robot_scene::locate(e, text, origin).to_string();
    for warning in scene.warnings() {
        println!("cargo:warning={}", located(warning));
    }
    let rod = scene
        .at_controller_steps()
        .and_then(|s| s.rod())
        .map_err(located)?;
    let model = HostModel::new(rod.clone())
        .map_err(|e| format!("{origin}: the model refuses the robot: {e:?}"))?;
    Ok((rod, model))
}

/// The generated file's first lines: what it is made from.
fn header(g: &mut String, origin: &str, scene: &Scene, prefix: &str) -> std::fmt::Result {
    writeln!(
        g,
        "// Generated by build.rs from the robot file {origin}: do not edit; edit the file."
    )?;
    writeln!(g, "/// The robot file this image was built from.")?;
    writeln!(g, "pub const {prefix}ROBOT_FILE: &str = {origin:?};")?;
    writeln!(g, "/// Its `name`.")?;
    writeln!(g, "pub const {prefix}ROBOT_NAME: &str = {:?};", scene.name)
}

/// The plan's node count: the image's model capacity, `name`. The firmware's plan is f32's, which
/// merges breakpoints closer than a millionth of the rod as f64's does but rounds them first: the
/// larger of the two counts. (model-core's other capacities, guides, sections, cables, loads, are
/// the parser's: a robot beyond one is refused with the key and the limit.)
fn write_plan(g: &mut String, rod: &Rod<f64>, model: &HostModel, name: &str) -> Result<(), String> {
    let nodes_f32 = Model::<f32, Quaternion<f32>>::new(in_f32(rod))
        .map_err(|e| format!("the model refuses the robot in f32: {e:?}"))?
        .plan()
        .interval_count()
        + 1;
    let nodes = (model.plan().interval_count() + 1).max(nodes_f32);
    let written = (|| -> std::fmt::Result {
        writeln!(
            g,
            "/// Nodes of the robot's plan: the estimator model's capacity."
        )?;
        writeln!(g, "pub const {name}: usize = {nodes};")
    })();
    written.map_err(|e| e.to_string())
}

/// The rod rounded to f32, field by field, as the firmware's `T::lit` rounds it.
fn in_f32(rod: &Rod<f64>) -> Rod<f32> {
    let v3 = |v: &nalgebra::Vector3<f64>| v.map(|x| x as f32);
    let mut out = Rod::<f32>::new();
    out.gravity_m_s2 = v3(&rod.gravity_m_s2);
    out.base_position_m = v3(&rod.base_position_m);
    out.base_orientation = rod.base_orientation.map(|x| x as f32);
    out.strain_model = rod.strain_model;
    out.guide_mass = rod.guide_mass;
    for s in &rod.sections {
        let _ = out.sections.push(model_core::Section {
            length_m: s.length_m as f32,
            stiffness: model_core::Stiffness {
                bending_torsion_nm2: v3(&s.stiffness.bending_torsion_nm2),
                shear_axial_n: v3(&s.stiffness.shear_axial_n),
            },
            line_density_kg_per_m: s.line_density_kg_per_m as f32,
            steps: s.steps,
        });
    }
    for q in &rod.guides {
        let _ = out.guides.push(model_core::Guide {
            s_m: q.s_m as f32,
            thickness_m: q.thickness_m as f32,
            mass_kg: q.mass_kg as f32,
        });
    }
    for c in &rod.cables {
        let _ = out.cables.push(model_core::Cable {
            hole_m: c.hole_m.map(|x| x as f32),
            end_m: c.end_m as f32,
        });
    }
    for l in &rod.loads {
        let _ = out.loads.push(model_core::PointLoad {
            s_m: l.s_m as f32,
            mass_kg: l.mass_kg as f32,
            force_n: v3(&l.force_n),
            moment_nm: v3(&l.moment_nm),
        });
    }
    out
}

/// `text` as a string literal for a generated `assert!`: escaped, and its braces doubled (the
/// message is a format string), whatever the robot file's path holds.
fn message(text: &str) -> String {
    format!("{:?}", text.replace('{', "{{").replace('}', "}}"))
}

/// A float as a Rust literal that reads back to the same `f64`.
fn lit(x: f64) -> String {
    format!("{x:?}")
}

/// `T::lit(x)`: converted to the scalar where it is used, a constant the compiler folds.
fn t(x: f64) -> String {
    format!("T::lit({})", lit(x))
}

fn list(xs: impl IntoIterator<Item = String>) -> String {
    format!("[{}]", xs.into_iter().collect::<Vec<_>>().join(", "))
}

fn v3(v: &nalgebra::Vector3<f64>) -> String {
    format!("nalgebra::Vector3::new({}, {}, {})", t(v.x), t(v.y), t(v.z))
}

/// The rod as straight-line Rust (`name`): every number a literal of the robot file's f64 value,
/// converted to the scalar where it is used (a constant the compiler folds: nothing converts a
/// double at run time, which the Cortex-M4F's single-precision unit cannot).
fn write_push(g: &mut String, name: &str, rod: &Rod<f64>) -> std::fmt::Result {
    // Straight-line and inlined where `config::rod` calls it: the compiler sees the whole rod where
    // it is built, and folds each conversion and each of the model's checks of it.
    writeln!(
        g,
        "\n/// The robot file's rod pushed onto `rod` (a `Rod::new()`), each section at \
         `steps_per_section`."
    )?;
    writeln!(
        g,
        "#[inline(always)]\nfn {name}<T: model_core::Scalar>(\n    rod: &mut model_core::Rod<T>,\n    \
         steps_per_section: u16,\n) -> Result<(), model_core::ModelError> {{"
    )?;
    // Every field of the frame and the models, though `Rod::new()` has defaults: set here, the
    // compiler knows them and folds the model's checks of them (the bench's gravity left to
    // `Rod::new()` cost 1.3 KB of flash, measured).
    writeln!(g, "    rod.gravity_m_s2 = {};", v3(&rod.gravity_m_s2))?;
    writeln!(g, "    rod.base_position_m = {};", v3(&rod.base_position_m))?;
    let m = &rod.base_orientation;
    let rows: Vec<String> = (0..3)
        .flat_map(|r| (0..3).map(move |c| (r, c)))
        .map(|(r, c)| t(m[(r, c)]))
        .collect();
    writeln!(
        g,
        "    rod.base_orientation = nalgebra::Matrix3::new({});",
        rows.join(", ")
    )?;
    writeln!(
        g,
        "    rod.strain_model = model_core::StrainModel::{:?};",
        rod.strain_model
    )?;
    writeln!(
        g,
        "    rod.guide_mass = model_core::GuideMass::{:?};",
        rod.guide_mass
    )?;
    for s in &rod.sections {
        writeln!(
            g,
            "    rod.push_section(model_core::Section {{\n        length_m: {},\n        \
             stiffness: model_core::Stiffness {{\n            bending_torsion_nm2: {},\n            \
             shear_axial_n: {},\n        }},\n        line_density_kg_per_m: {},\n        \
             steps: steps_per_section,\n    }})?;",
            t(s.length_m),
            v3(&s.stiffness.bending_torsion_nm2),
            v3(&s.stiffness.shear_axial_n),
            t(s.line_density_kg_per_m)
        )?;
    }
    for q in &rod.guides {
        writeln!(
            g,
            "    rod.push_guide(model_core::Guide {{ s_m: {}, thickness_m: {}, mass_kg: {} }})?;",
            t(q.s_m),
            t(q.thickness_m),
            t(q.mass_kg)
        )?;
    }
    for c in &rod.cables {
        writeln!(
            g,
            "    rod.push_cable(model_core::Cable {{ hole_m: nalgebra::Vector2::new({}, {}), end_m: {} }})?;",
            t(c.hole_m.x),
            t(c.hole_m.y),
            t(c.end_m)
        )?;
    }
    for l in &rod.loads {
        writeln!(
            g,
            "    rod.push_load(model_core::PointLoad {{ s_m: {}, mass_kg: {}, force_n: {}, moment_nm: {} }})?;",
            t(l.s_m),
            t(l.mass_kg),
            v3(&l.force_n),
            v3(&l.moment_nm)
        )?;
    }
    writeln!(g, "    Ok(())\n}}")?;
    Ok(())
}

/// The drive's and the controller's constants, and the spools as straight-line Rust.
fn write_drive(
    g: &mut String,
    origin: &str,
    drive: &DriveSpec,
    controller: &ControllerSpec,
) -> std::fmt::Result {
    let cables = drive.home_lengths_m.len();
    writeln!(g, "/// Spool radius at the cable's centreline, m.")?;
    writeln!(
        g,
        "pub const SPOOL_RADIUS_M: f64 = {};",
        lit(drive.spool_radius_m)
    )?;
    writeln!(g, "/// Sensor (motor shaft) turns per spool turn.")?;
    writeln!(g, "pub const GEAR_RATIO: u32 = {};", drive.gear_ratio)?;
    writeln!(
        g,
        "const _: () = assert!({c} == crate::encoder::as5047p::COUNTS_PER_TURN, {});",
        message(&format!(
            "{origin}: encoder_counts_per_turn = {}; the firmware's sensor driver (AS5047P) \
             counts COUNTS_PER_TURN (16384) a turn",
            drive.encoder_counts_per_turn
        )),
        c = drive.encoder_counts_per_turn
    )?;
    writeln!(g, "/// Full steps per motor turn.")?;
    writeln!(
        g,
        "pub const MOTOR_FULL_STEPS_PER_TURN: u32 = {};",
        drive.motor_full_steps_per_turn
    )?;
    writeln!(g, "/// The drivers' microstepping.")?;
    writeln!(
        g,
        "pub const MICROSTEPS_PER_FULL_STEP: u32 = {};",
        drive.microsteps_per_full_step
    )?;
    writeln!(g, "/// Fastest cable speed the drives can produce, m/s.")?;
    writeln!(
        g,
        "pub const MAX_CABLE_SPEED_M_PER_S: f32 = {};",
        lit(drive.max_cable_speed_m_per_s)
    )?;
    writeln!(g, "/// Cable lengths at the calibration (home) pose, m.")?;
    writeln!(
        g,
        "pub const HOME_LENGTHS_M: [f64; {cables}] = {};",
        list(drive.home_lengths_m.iter().map(|x| lit(*x)))
    )?;
    writeln!(g, "/// Each sensor's multi-turn count at the home pose.")?;
    writeln!(
        g,
        "pub const ZERO_OFFSET_COUNTS: [i64; {cables}] = {};",
        list(drive.zero_offset_counts.iter().map(i64::to_string))
    )?;
    writeln!(g, "/// Estimator (loop) rate, Hz.")?;
    writeln!(
        g,
        "pub const LOOP_RATE_HZ: u32 = {};",
        controller.loop_rate_hz
    )?;
    writeln!(g, "/// Encoder sampling rate, Hz.")?;
    writeln!(
        g,
        "pub const SAMPLE_RATE_HZ: u32 = {};",
        controller.sample_rate_hz
    )?;
    writeln!(g, "/// RK4 steps over each section on the MCU.")?;
    writeln!(
        g,
        "pub const STEPS_PER_SECTION: u16 = {};",
        controller.steps_per_section
    )?;
    let spools = drive
        .home_lengths_m
        .iter()
        .zip(&drive.zero_offset_counts)
        .enumerate()
        .map(|(i, (home, zero))| {
            let reel_in = drive.reel_in_with_counts.get(i).copied().unwrap_or(false);
            format!(
                "crate::spool::SpoolCalibration {{ radius_m: {}, counts_per_spool_turn: T::lit(f64::from(GEAR_RATIO * \
                 crate::encoder::as5047p::COUNTS_PER_TURN)), zero_offset_counts: {zero}, length_at_zero_m: {}, direction: \
                 crate::spool::Direction::{} }}",
                t(drive.spool_radius_m),
                t(*home),
                if reel_in {
                    "ReelInWithCounts"
                } else {
                    "PayOutWithCounts"
                }
            )
        });
    writeln!(
        g,
        "\n/// The spools, calibrated at the home pose ([`HOME_LENGTHS_M`], [`ZERO_OFFSET_COUNTS`]), \
         each reeling in or paying out with increasing counts as the robot file says."
    )?;
    writeln!(
        g,
        "pub fn spools<T: model_core::Scalar>() -> [crate::spool::SpoolCalibration<T>; CABLE_COUNT] {{\n    {}\n}}",
        list(spools)
    )
}
