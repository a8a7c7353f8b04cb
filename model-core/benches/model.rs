//! Host wall-clock benchmarks of the model: `cargo bench -p model-core`.
//!
//! What is measured, in f64 and f32:
//!
//! - `sweep`: one plain sweep (`Model::evaluate`) of the golden bench at a solved base strain;
//! - `forward_3d` / `forward_planar`: a cold forward solve of the thesis's experiment-2 scene
//!   (average mass, one cable, 40.2 g at the tip) at several steps per section, in 3D and through the
//!   planar reduction;
//! - `inverse`: a cold inverse estimate (tip force from three cable lengths) on the golden bench,
//!   and a warm `Estimator::update` following a slowly moving tip force;
//! - `attitude`: the cold forward solve with each frame representation;
//! - `start`: the forward solve of the experiment-2 scene at 40.2 g, 10 steps per section, cold,
//!   warm from the base strain at a 1 % lighter load (`Start::Warm`), and from that answer as a
//!   neighbour (`Start::Neighbour`: its Jacobian, secant steps on plain sweeps).
//!
//! Every solve is checked once before it is timed: a benchmark of a solve that does not converge
//! would time the wrong thing. The groups are small (short warm-up and measurement) so that the whole
//! run takes a few minutes; the numbers are indicative on a shared machine, and ratios within one run
//! (planar/3D, f32/f64, Lie/quaternion) mean more than absolute times. `report/host_timings.md`
//! holds a run's numbers.

use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use model_checks::reference::{self, Exp2Mass};
use model_core::inverse::{
    Estimator, EstimatorSettings, InverseSettings, InverseStart, LoadBasis, estimate,
};
use model_core::planar::PlanarModel;
use model_core::{
    Attitude, LieGroup, Model, Quaternion, RotationMatrix, Scalar, ShootingSettings, Start, TipLoad,
};
use nalgebra::Vector3;

/// Steps per section for the forward-solve ladder.
const STEP_LADDER: [u16; 5] = [5, 10, 20, 40, 100];
/// Steps per section for the golden-bench sweeps, inverse and attitude comparisons.
const STEPS: u16 = 40;
/// The thesis's 40.2 g tip mass (Tables 4.3-4.5), kg.
const TIP_MASS_KG: f64 = 0.0402;
/// A 4096-count encoder on a 5 mm-radius spool, m.
const RESOLUTION_M: f64 = 2.0 * std::f64::consts::PI * 5e-3 / 4096.0;
/// Points on the closed load path the warm estimator follows (one update per point).
const PATH_POINTS: usize = 64;

fn configure(group: &mut BenchmarkGroup<'_, WallTime>) {
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
}

fn tip_weight<T: Scalar>() -> TipLoad<T> {
    TipLoad::force(Vector3::new(
        T::zero(),
        T::lit(-TIP_MASS_KG * reference::GRAVITY_M_S2),
        T::zero(),
    ))
}

fn exp2<T: Scalar, A: Attitude<T>>(steps: u16) -> Model<T, A> {
    Model::new(reference::exp2_bench(Exp2Mass::Average, steps, 1).expect("bench")).expect("model")
}

fn golden<T: Scalar, A: Attitude<T>>(steps: u16) -> Model<T, A> {
    Model::new(reference::golden_bench(steps).expect("bench")).expect("model")
}

fn lit3<T: Scalar>(v: [f64; 3]) -> Vector3<T> {
    Vector3::new(T::lit(v[0]), T::lit(v[1]), T::lit(v[2]))
}

/// The second golden row's tip force, (0, -0.2, 0.1) N: a load out of the vertical plane.
fn golden_force<T: Scalar>() -> Vector3<T> {
    let row = reference::golden_rows()
        .nth(1)
        .expect("a golden row")
        .expect("a valid golden row");
    lit3(row.force_n)
}

fn converged<T: Scalar>(eq: &model_core::Equilibrium<T>, what: &str) {
    assert!(
        eq.report.termination.is_success(),
        "{what}: {:?}",
        eq.report
    );
}

fn sweep<T: Scalar>(c: &mut Criterion, label: &str) {
    let model = golden::<T, Quaternion<T>>(STEPS);
    let load = TipLoad::force(golden_force());
    let eq = model
        .solve(&load, Start::Cold, &ShootingSettings::default())
        .expect("valid input");
    converged(&eq, "sweep set-up");
    let mut group = c.benchmark_group("sweep");
    configure(&mut group);
    group.bench_function(label, |b| {
        b.iter(|| {
            model
                .evaluate(black_box(&eq.base_strain_per_m), black_box(&load))
                .expect("finite sweep")
        })
    });
    group.finish();
}

fn forward<T: Scalar>(c: &mut Criterion, label: &str) {
    let settings = ShootingSettings::default();
    let load = tip_weight::<T>();
    let mut group = c.benchmark_group(format!("forward_3d_{label}"));
    configure(&mut group);
    for steps in STEP_LADDER {
        let model = exp2::<T, Quaternion<T>>(steps);
        converged(
            &model.solve(&load, Start::Cold, &settings).expect("input"),
            "forward set-up",
        );
        group.bench_with_input(BenchmarkId::from_parameter(steps), &model, |b, m| {
            b.iter(|| {
                m.solve(black_box(&load), Start::Cold, &settings)
                    .expect("valid input")
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group(format!("forward_planar_{label}"));
    configure(&mut group);
    for steps in STEP_LADDER {
        let model = exp2::<T, Quaternion<T>>(steps);
        let planar = PlanarModel::new(&model, &load).expect("the exp-2 scene is planar");
        converged(
            &planar.solve(&load, &settings).expect("input"),
            "planar set-up",
        );
        group.bench_with_input(BenchmarkId::from_parameter(steps), &planar, |b, p| {
            b.iter(|| p.solve(black_box(&load), &settings).expect("valid input"))
        });
    }
    group.finish();
}

/// A closed path of tip forces (N) around the second golden row's, so that the estimator's last
/// update leads smoothly into its first.
fn path_force(k: usize) -> [f64; 3] {
    let t = 2.0 * std::f64::consts::PI * k as f64 / PATH_POINTS as f64;
    let f = golden_force::<f64>();
    [
        f.x + 0.01 * t.sin(),
        f.y + 0.02 * (2.0 * t).sin(),
        f.z + 0.03 * t.cos(),
    ]
}

fn inverse<T: Scalar>(c: &mut Criterion, label: &str)
where
    model_core::inverse::Params: model_core::inverse::ParamCount<T, 3>,
{
    let model = golden::<T, Quaternion<T>>(STEPS);
    let lengths = |force: Vector3<T>| -> Vec<T> {
        let eq = model
            .solve(
                &TipLoad::force(force),
                Start::Cold,
                &ShootingSettings::default(),
            )
            .expect("valid input");
        converged(&eq, "inverse set-up");
        eq.cable_lengths_m.to_vec()
    };
    let settings = InverseSettings::with_resolution(T::lit(RESOLUTION_M));
    let measured = lengths(golden_force());
    let basis = LoadBasis::tip_force();
    let start = InverseStart::Params(Vector3::zeros());
    let est = estimate(&model, &basis, &measured, start, &settings).expect("input");
    assert!(est.report.termination.is_success(), "{:?}", est.report);

    let mut group = c.benchmark_group("inverse_cold");
    configure(&mut group);
    group.bench_function(label, |b| {
        b.iter(|| {
            estimate(&model, &basis, black_box(&measured), start, &settings).expect("valid input")
        })
    });
    group.finish();

    let path: Vec<Vec<T>> = (0..PATH_POINTS)
        .map(|k| lengths(lit3(path_force(k))))
        .collect();
    let (mut estimator, first) = Estimator::new(
        &model,
        basis,
        &path[0],
        Vector3::zeros(),
        EstimatorSettings::with_inverse(settings),
    )
    .expect("valid input");
    assert!(first.report.termination.is_success(), "{:?}", first.report);
    // One lap before timing: every update along the path must converge within its budget, or the
    // benchmark would time updates that fail (with `fast-math`, micromath's 5 % square root puts
    // centimetres of error into the cable lengths and none converges: then this one is skipped).
    let failed = path
        .iter()
        .skip(1)
        .chain(path.iter().take(1))
        .filter(|lengths| {
            !estimator
                .update(lengths)
                .expect("valid input")
                .report
                .termination
                .is_success()
        })
        .count();
    if failed > 0 {
        eprintln!(
            "estimator_update/{label} skipped: {failed} of {PATH_POINTS} updates did not converge"
        );
        return;
    }
    let mut group = c.benchmark_group("estimator_update");
    configure(&mut group);
    let mut k = 0usize;
    group.bench_function(label, |b| {
        b.iter(|| {
            k = (k + 1) % PATH_POINTS;
            estimator.update(black_box(&path[k])).expect("valid input")
        })
    });
    group.finish();
}

fn attitude_one<T: Scalar, A: Attitude<T>>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    label: &str,
    name: &str,
) {
    let model = exp2::<T, A>(STEPS);
    let load = tip_weight::<T>();
    let settings = ShootingSettings::default();
    converged(
        &model.solve(&load, Start::Cold, &settings).expect("input"),
        "attitude set-up",
    );
    group.bench_function(format!("{name}/{label}"), |b| {
        b.iter(|| {
            model
                .solve(black_box(&load), Start::Cold, &settings)
                .expect("valid input")
        })
    });
}

fn attitude<T: Scalar>(c: &mut Criterion, label: &str) {
    let mut group = c.benchmark_group("attitude");
    configure(&mut group);
    attitude_one::<T, Quaternion<T>>(&mut group, label, "quaternion");
    attitude_one::<T, RotationMatrix<T>>(&mut group, label, "rotation_matrix");
    attitude_one::<T, LieGroup<T>>(&mut group, label, "lie_group");
    group.finish();
}

fn start<T: Scalar>(c: &mut Criterion, label: &str) {
    let settings = ShootingSettings::default();
    let model = exp2::<T, Quaternion<T>>(10);
    let load = tip_weight::<T>();
    let lighter = model
        .solve(
            &TipLoad::force(load.force_n * T::lit(0.99)),
            Start::Cold,
            &settings,
        )
        .expect("valid input");
    converged(&lighter, "start set-up");
    let mut group = c.benchmark_group("start");
    configure(&mut group);
    for (name, from) in [
        ("cold", Start::Cold),
        ("warm", Start::Warm(lighter.base_strain_per_m)),
        ("neighbour", lighter.next_start()),
    ] {
        converged(
            &model.solve(&load, from, &settings).expect("input"),
            "start set-up",
        );
        group.bench_function(format!("{name}_{label}"), |b| {
            b.iter(|| {
                model
                    .solve(black_box(&load), from, &settings)
                    .expect("valid input")
            })
        });
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    sweep::<f64>(c, "f64");
    sweep::<f32>(c, "f32");
    forward::<f64>(c, "f64");
    forward::<f32>(c, "f32");
    inverse::<f64>(c, "f64");
    inverse::<f32>(c, "f32");
    attitude::<f64>(c, "f64");
    attitude::<f32>(c, "f32");
    start::<f64>(c, "f64");
    start::<f32>(c, "f32");
}

criterion_group!(all, benches);
criterion_main!(all);
