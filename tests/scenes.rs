//! The shipped scene files describe exactly the reference benches of model-core (which the no_std
//! self-checks and the firmware use), so the two descriptions cannot drift apart.

use host_sim::scenes;
use integration_tests::{tip, weight};
use model_checks::reference::{self, Exp2Mass};
use model_core::{Model, PointLoad, ShootingSettings, Tendon, Tendons, TipLoad};
use nalgebra::Vector3;

fn same_physics(a: &Model<f64>, b: &Model<f64>, loads: &[TipLoad<f64>]) {
    assert_eq!(a.plan().total_steps(), b.plan().total_steps());
    assert_eq!(a.plan().interval_count(), b.plan().interval_count());
    assert!((a.plan().base_force_n() - b.plan().base_force_n()).norm() < 1e-12);
    for load in loads {
        let (ta, tb) = (tip(a, load), tip(b, load));
        assert!((ta - tb).norm() < 1e-12, "{ta:?} vs {tb:?}");
    }
}

#[test]
fn exp2_scenes_are_the_reference_benches() {
    let loads = [
        weight(0.0),
        weight(40.2),
        TipLoad::force(Vector3::new(0.02, -0.1, 0.05)),
    ];
    for (scene, mass) in [
        (scenes::exp2_average(), Exp2Mass::Average),
        (scenes::exp2_accurate(), Exp2Mass::Accurate),
    ] {
        let from_scene = Model::new(scene.unwrap().rod().unwrap()).unwrap();
        let reference = Model::new(reference::exp2_bench(mass, 100, 1).unwrap()).unwrap();
        same_physics(&from_scene, &reference, &loads);
    }
}

#[test]
fn exp1_scene_is_the_reference_bench() {
    let mut rod = scenes::exp1().unwrap().rod().unwrap();
    let mut bench = reference::exp1_bench::<f64>(reference::EXP1_YOUNGS_MODULUS_PA, 50).unwrap();
    bench
        .push_load(PointLoad::mass(reference::EXP1_TRANSITION_M, 0.021))
        .unwrap();
    rod.loads.truncate(1);
    same_physics(
        &Model::new(rod).unwrap(),
        &Model::new(bench).unwrap(),
        &[TipLoad::zero()],
    );
}

#[test]
fn bench_3d_scene_is_the_golden_bench() {
    let from_scene = Model::new(scenes::bench_3d().unwrap().rod().unwrap()).unwrap();
    let reference = Model::new(reference::golden_bench(200).unwrap()).unwrap();
    let loads: Vec<_> = reference::golden_rows()
        .map(|r| TipLoad::force(Vector3::from(r.unwrap().force_n)))
        .collect();
    same_physics(&from_scene, &reference, &loads);
    // The scene gives the holes as angles; the reference bench as literal directions.
    let holes = |m: &Model<f64>| m.rod().cables.iter().map(|c| c.hole_m).collect::<Vec<_>>();
    let (a, b) = (holes(&from_scene), holes(&reference));
    assert_eq!(a.len(), 3);
    for (a, b) in a.iter().zip(&b) {
        assert!((a - b).norm() < 1e-17, "{a:?} vs {b:?}");
    }
}

/// A tendon scene against its reference builder: the same plan and dead load, the same tendons,
/// and the same tendon equilibria (tip and path lengths) under `cases` (tensions, tip force).
fn same_tendon_robot(
    scene: &host_sim::scene::Scene,
    rod: model_core::Rod<f64>,
    tendons: &[Tendon<f64>],
    cases: &[(Vec<f64>, [f64; 3])],
) {
    let from_scene = Model::new(scene.rod().unwrap()).unwrap();
    let reference = Model::new(rod).unwrap();
    same_physics(&from_scene, &reference, &[]);
    let a = scene.tendon_set(&from_scene).unwrap().expect("tendons");
    let b = Tendons::new(&reference, tendons).unwrap();
    assert_eq!(a.len(), b.len());
    for (j, (x, y)) in a.tendons().iter().zip(b.tendons()).enumerate() {
        assert!(
            (x.hole_m - y.hole_m).norm() < 1e-17,
            "tendon {j}: {x:?} vs {y:?}"
        );
        assert!(
            (x.end_m - y.end_m).abs() < 1e-15,
            "tendon {j}: {x:?} vs {y:?}"
        );
        assert_eq!(x.axial_stiffness_n, y.axial_stiffness_n);
        assert_eq!(x.feed_length_m, y.feed_length_m);
        assert_eq!(a.rest_length_m(j), b.rest_length_m(j));
    }
    let settings = ShootingSettings::default();
    for (tau, force) in cases {
        let load = TipLoad::force(Vector3::from(*force));
        let ea = from_scene
            .solve_tendons(&a, tau, &load, None, &settings)
            .unwrap();
        let eb = reference
            .solve_tendons(&b, tau, &load, None, &settings)
            .unwrap();
        assert!(ea.is_success() && eb.is_success(), "{tau:?}");
        let gap = (ea.equilibrium.tip_position_m - eb.equilibrium.tip_position_m).norm();
        assert!(gap < 1e-12, "{tau:?}: tips {gap:e} m apart");
        for (x, y) in ea.path_m.iter().zip(&eb.path_m) {
            assert!((x - y).abs() < 1e-12, "{tau:?}: paths {x} vs {y}");
        }
    }
}

#[test]
fn tendon_bench_scene_is_the_reference_tendon_bench() {
    let scene = scenes::tendon_bench().unwrap();
    let (rod, tendons) = reference::tendon_bench::<f64>(200).unwrap();
    let cases: Vec<_> = reference::csv_rows::<18>(reference::TENDON_BENCH_CSV)
        .map(Result::unwrap)
        .filter(|v| v[0] + v[1] + v[2] > 0.0)
        .take(3)
        .map(|v| (v[0..3].to_vec(), [v[3], v[4], v[5]]))
        .collect();
    same_tendon_robot(&scene, rod, &tendons, &cases);
    // The scene's own actuation is a golden row's.
    let actuation = scene.actuation().unwrap().expect("an actuation");
    assert_eq!(actuation.values, [3.0, 1.5, 0.0]);
}

#[test]
fn tendon_two_section_scene_is_the_reference_tendon_robot() {
    let scene = scenes::tendon_two_section().unwrap();
    let (rod, tendons) = reference::tendon_two_section::<f64>(100, 9.81).unwrap();
    let cases: Vec<_> = reference::csv_rows::<25>(reference::TENDON_TWO_SECTION_CSV)
        .map(Result::unwrap)
        .filter(|v| v[0] > 0.0)
        .take(3)
        .map(|v| (v[1..7].to_vec(), [v[7], v[8], v[9]]))
        .collect();
    same_tendon_robot(&scene, rod, &tendons, &cases);
}
