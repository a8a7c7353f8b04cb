//! The firmware's robot files are scenes: host-sim reads and solves them as any other, and
//! `host-sim reference` turns one and a load path into the reference `monitor --check-against`
//! reads, each tick the robot's own forward solve.

mod common;

use common::{code, host_sim, stderr, stdout, temp_dir};
use host_sim::monitor::Reference;
use host_sim::monitor::reference::{AppliedForce, parse_forces, reference_csv};
use host_sim::scene::Scene;
use model_core::{Model, ShootingSettings, Start, TipLoad};
use nalgebra::Vector3;

const ROBOTS: [&str; 2] = ["bench.toml", "two_section.toml"];

fn robot_path(name: &str) -> String {
    format!("{}/../firmware/robots/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn robot(name: &str) -> Scene {
    let path = robot_path(name);
    let text = std::fs::read_to_string(&path).expect("the robot file reads");
    Scene::parse(&text, &path).expect("the robot file parses")
}

#[test]
fn the_firmware_robot_files_solve_on_the_host() {
    for name in ROBOTS {
        let scene = robot(name);
        let (Some(drive), Some(controller)) = (&scene.drive, &scene.controller) else {
            panic!("{name}: no [drive] or [controller]");
        };
        assert_eq!(drive.home_lengths_m.len(), scene.cables.len(), "{name}");
        // The MCU's resolution is the controller's, the host's the sections' own.
        let mcu = scene.at_controller_steps().expect("a controller");
        assert!(
            mcu.sections
                .iter()
                .all(|s| s.steps == controller.steps_per_section)
        );
        let out = host_sim(&["solve", &robot_path(name)]);
        assert_eq!(code(&out), 0, "{name}: {}", stderr(&out));
        assert!(stdout(&out).contains("status: converged, stable"), "{name}");
    }
}

#[test]
fn the_home_lengths_of_the_two_section_robot_are_its_unloaded_cable_lengths() {
    // The file says they are the robot under its own weight: hold it to that, to a micrometre.
    let scene = robot("two_section.toml");
    let model = Model::<f64>::new(scene.rod().expect("rod")).expect("model");
    let settings = scene.shooting_settings().expect("settings");
    let eq = model
        .solve(&TipLoad::force(Vector3::zeros()), Start::Cold, &settings)
        .expect("solve");
    let home = &scene.drive.as_ref().expect("drive").home_lengths_m;
    for (h, l) in home.iter().zip(eq.cable_lengths_m.iter()) {
        assert!((h - l).abs() < 1e-6, "{h} against {l}");
    }
}

#[test]
fn a_reference_is_the_robots_forward_solve_at_each_tick() {
    let scene = robot("two_section.toml");
    let path: Vec<AppliedForce> = (0..3)
        .map(|k| AppliedForce {
            tick: k * 2,
            force_n: Vector3::new(0.002 * f64::from(k), -0.01, 0.005),
        })
        .collect();
    let csv = reference_csv(&scene, &path, 4).expect("a reference");
    let reference = Reference::parse(&csv, "reference").expect("monitor reads it");
    assert_eq!(reference.ticks.len(), 3);
    let model = Model::<f64>::new(scene.rod().expect("rod")).expect("model");
    for (tick, applied) in reference.ticks.iter().zip(&path) {
        assert_eq!(tick.tick, applied.tick);
        assert_eq!(tick.expected, "fresh");
        assert_eq!(tick.force_n, applied.force_n);
        assert_eq!(tick.backbone_m.len(), 4);
        let eq = model
            .solve(
                &TipLoad::force(applied.force_n),
                Start::Cold,
                &ShootingSettings::default(),
            )
            .expect("solve");
        // Warm or cold, the same equilibrium to the solver's tolerance; the last backbone point
        // is the tip.
        assert!((tick.tip_m - eq.tip_position_m).norm() < 1e-9);
        assert!((tick.backbone_m[3] - tick.tip_m).norm() < 1e-12);
        assert!(tick.tip_orientation.is_some());
    }
}

/// The reference solves the robot the file describes: in the file's frame representation, and
/// not at all a robot with tendons (a load path of tip forces does not say their actuation; its
/// rod alone, solved before, was another robot, and the reference said nothing).
#[test]
fn a_reference_is_of_the_files_robot_or_refused() {
    let path = [AppliedForce {
        tick: 0,
        force_n: Vector3::new(0.0, -0.01, 0.005),
    }];
    let scenes = format!("{}/scenes", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(format!("{scenes}/tendon_bench.toml")).expect("reads");
    let tendons = Scene::parse(&text, "tendon_bench.toml").expect("parses");
    let e = reference_csv(&tendons, &path, 4).expect_err("a tendon robot is refused");
    assert!(e.reason.contains("tendons"), "{e}");
    let mut scene = robot("two_section.toml");
    let quaternion = reference_csv(&scene, &path, 4).expect("a reference");
    scene.solver.attitude = "rotation-matrix".into();
    let matrix = reference_csv(&scene, &path, 4).expect("a reference");
    let tip = |csv: &str| {
        Reference::parse(csv, "reference")
            .expect("monitor reads it")
            .ticks[0]
            .tip_m
    };
    // Another discretisation of the frame (the matrix's RK4 steps are not the quaternion's):
    // close, not equal.
    let moved = (tip(&quaternion) - tip(&matrix)).norm();
    assert!(moved > 0.0 && moved < 1e-5, "{moved}");
    for bad in [0, 100_001] {
        assert!(reference_csv(&scene, &path, bad).is_err(), "{bad} points");
    }
}

#[test]
fn a_load_path_that_cannot_be_read_is_refused() {
    for (text, says) in [
        (
            "tick,force_x_n,force_y_n\n0,1,2\n",
            "no column \"force_z_n\"",
        ),
        (
            "tick,force_x_n,force_y_n,force_z_n\n1,0,0,0\n1,0,0,0\n",
            "ticks must increase",
        ),
        (
            "tick,force_x_n,force_y_n,force_z_n\n0,0,nan,0\n",
            "not a finite number",
        ),
        ("tick,force_x_n,force_y_n,force_z_n\n", "no rows"),
        (
            "tick,force_x_n,force_y_n,force_z_n\n-1,0,0,0\n",
            "tick \"-1\"",
        ),
    ] {
        let e = parse_forces(text, "path.csv").expect_err(text);
        assert!(e.to_string().contains(says), "{text}: {e}");
    }
}

#[test]
fn host_sim_reference_writes_the_file_and_refuses_bad_input() {
    let dir = temp_dir("robot_files_reference");
    let forces = dir.join("forces.csv");
    std::fs::write(
        &forces,
        "tick,force_x_n,force_y_n,force_z_n\n0,0.0,-0.02,0.02\n1,0.003,-0.024,0.028\n",
    )
    .expect("write");
    let out_path = dir.join("reference.csv");
    let bench = robot_path("bench.toml");
    let out = host_sim(&[
        "reference",
        &bench,
        "--forces",
        forces.to_str().expect("utf-8"),
        "--out",
        out_path.to_str().expect("utf-8"),
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let written = std::fs::read_to_string(&out_path).expect("written");
    assert_eq!(
        Reference::parse(&written, "reference")
            .expect("monitor reads it")
            .ticks
            .len(),
        2
    );
    std::fs::write(&forces, "tick,force_x_n\n0,1\n").expect("write");
    let out = host_sim(&[
        "reference",
        &bench,
        "--forces",
        forces.to_str().expect("utf-8"),
    ]);
    assert_eq!(code(&out), 1);
    assert!(stderr(&out).contains("no column"), "{}", stderr(&out));
}

/// A tolerance loose enough that a "converged" answer is none is refused (at 1.0 the bench's tip
/// came out 11 mm off, converged in no iteration), a loose one warned about; an empty list of
/// output points, which would leave a CSV without even its status, is refused.
#[test]
fn a_loose_tolerance_and_no_output_points_are_refused() {
    let mut scene = robot("bench.toml");
    for (tolerance, refused, warned) in [
        (1.0, true, false),
        (2e-3, true, false),
        (1e-3, false, true),
        (1e-4, false, true),
        (1e-8, false, false),
    ] {
        scene.solver.tolerance = Some(tolerance);
        assert_eq!(
            scene.shooting_settings().is_err(),
            refused,
            "tolerance {tolerance}"
        );
        let warnings = scene.warnings();
        assert_eq!(
            warnings.iter().any(|w| w.field == "solver.tolerance"),
            warned,
            "tolerance {tolerance}: {warnings:?}"
        );
    }
    scene.output.s_m = Some(Vec::new());
    let e = scene.output_point_count().expect_err("no points");
    assert_eq!(e.field, "output.s_m");
    scene.output.s_m = Some(vec![0.1]);
    assert_eq!(scene.output_point_count().ok(), Some(1));
}
