//! The shipped scene files describe exactly the reference benches of model-core (which the no_std
//! self-checks and the firmware use), so the two descriptions cannot drift apart.

use host_sim::scenes;
use integration_tests::{tip, weight};
use model_checks::reference::{self, Exp2Mass};
use model_core::{Model, PointLoad, TipLoad};
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
