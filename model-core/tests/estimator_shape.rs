//! The warm estimator hands out the backbone from its own sweeps (no sweep more): the points must be
//! exactly those of a separate shape sweep at the estimate, on every update, in both update modes,
//! in f64 and f32.

use model_checks::reference;
use model_core::inverse::{Estimator, EstimatorSettings, InverseSettings, LoadBasis};
use model_core::shape::MAX_SHAPE_POINTS;
use model_core::{
    Model, ModelError, Scalar, ShapePoint, ShootingSettings, Start, Termination, TipLoad,
};
use nalgebra::Vector3;

/// Cable lengths of the golden bench under a tip force moving along a short 3D path.
fn lengths<T: Scalar>(model: &Model<T>, k: usize) -> [T; 3] {
    let t = k as f64 * 0.07;
    let force = Vector3::new(
        0.03 * t.sin(),
        -0.12 + 0.08 * (1.3 * t).sin(),
        0.15 * t.cos(),
    );
    let eq = model
        .solve(
            &TipLoad::force(force.map(T::lit)),
            Start::Cold,
            &ShootingSettings::default(),
        )
        .unwrap();
    assert!(eq.report.termination.is_success());
    [
        eq.cable_lengths_m[0],
        eq.cable_lengths_m[1],
        eq.cable_lengths_m[2],
    ]
}

fn check<T: Scalar>(max_sweeps: u8) {
    let model = Model::<T>::new(reference::golden_bench(30).unwrap()).unwrap();
    let s: [T; 4] = [0.1, 0.2, 0.3, 0.39].map(T::lit);
    let settings = EstimatorSettings {
        max_sweeps,
        ..EstimatorSettings::with_inverse(InverseSettings::with_resolution(T::lit(2.4e-7)))
    };
    let mut points = [ShapePoint::default(); 4];
    let (mut estimator, first) = Estimator::new_with_shape(
        &model,
        LoadBasis::tip_force(),
        &lengths(&model, 0),
        Vector3::zeros(),
        settings,
        &s,
        &mut points,
    )
    .unwrap();
    // The estimator's tip frame is the estimate's, after the first estimate and every update.
    assert_eq!(estimator.tip_rotation(), first.tip_rotation);
    let mut estimates = vec![(first, points)];
    for k in 1..10 {
        let estimate = estimator
            .update_with_shape(&lengths(&model, k), &s, &mut points)
            .unwrap();
        assert_eq!(
            estimator.tip_rotation(),
            estimate.tip_rotation,
            "update {k}"
        );
        // A budget that runs out (`IterationLimit`) still reports the point it reached, with its shape.
        assert!(
            matches!(
                estimate.report.termination,
                Termination::Converged | Termination::IterationLimit
            ),
            "{:?}",
            estimate.report
        );
        if max_sweeps == 1 {
            // The stepped point's shape comes from the step's own sweep.
            assert_eq!(estimate.report.sweeps, 1);
        }
        estimates.push((estimate, points));
    }
    for (k, (estimate, points)) in estimates.iter().enumerate() {
        let mut expected = [ShapePoint::default(); 4];
        model
            .shape_at(
                &estimate.base_strain_per_m,
                &estimate.load,
                &s,
                &mut expected,
            )
            .unwrap();
        assert_eq!(points, &expected, "update {k}");
        // The last point is the tip the estimate reports.
        assert_eq!(points[3].position_m, estimate.tip_position_m);
    }
}

#[test]
fn warm_updates_hand_out_the_estimates_backbone_f64() {
    check::<f64>(5);
}

#[test]
fn warm_updates_hand_out_the_estimates_backbone_f32() {
    check::<f32>(5);
}

#[test]
fn one_sweep_updates_hand_out_the_stepped_backbone() {
    check::<f64>(1);
}

#[test]
fn shape_queries_are_checked() {
    let model = Model::<f64>::new(reference::golden_bench(20).unwrap()).unwrap();
    let settings = EstimatorSettings::default();
    let measured = lengths(&model, 0);
    let start = |s: &[f64], out: &mut [ShapePoint<f64>]| {
        Estimator::new_with_shape(
            &model,
            LoadBasis::tip_force(),
            &measured,
            Vector3::zeros(),
            settings,
            s,
            out,
        )
        .map(|_| ())
    };
    let mut out = [ShapePoint::default(); MAX_SHAPE_POINTS + 1];
    let too_many: Vec<f64> = (0..=MAX_SHAPE_POINTS).map(|k| 0.01 * k as f64).collect();
    assert_eq!(
        start(&too_many, &mut out),
        Err(ModelError::Capacity("shape points"))
    );
    assert_eq!(
        start(&[0.2, 0.1], &mut out),
        Err(ModelError::Unordered("shape arc lengths"))
    );
    assert_eq!(
        start(&[0.5], &mut out),
        Err(ModelError::OutOfRange("shape arc length"))
    );
    assert_eq!(
        start(&[0.1, 0.2], &mut out[..1]),
        Err(ModelError::Mismatch("shape queries and output buffer"))
    );
}
