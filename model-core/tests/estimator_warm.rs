//! The warm estimator's updates (chord steps on plain sweeps between sweeps with tangents) report what
//! a cold estimate at the same measurements reports: the same load within a small fraction of its
//! standard deviation, and standard deviations within a few percent. The Jacobian feeds the
//! posterior, so an update must not claim a precision the exact one would not give.

use model_checks::reference;
use model_core::inverse::{
    Determination, Estimator, EstimatorSettings, InverseSettings, InverseStart, LoadBasis, estimate,
};
use model_core::{Model, ShootingSettings, Start, Termination, TipLoad};
use nalgebra::Vector3;

/// The tip force at update `k` of a path moving a few millinewtons an update.
fn force(k: usize) -> Vector3<f64> {
    let t = k as f64 * 0.05;
    Vector3::new(
        0.03 * t.sin(),
        -0.12 + 0.08 * (1.3 * t).sin(),
        0.15 * t.cos(),
    )
}

fn lengths(model: &Model<f64>, k: usize) -> [f64; 3] {
    let eq = model
        .solve(
            &TipLoad::force(force(k)),
            Start::Cold,
            &ShootingSettings::default(),
        )
        .expect("valid input");
    assert!(eq.report.termination.is_success());
    [
        eq.cable_lengths_m[0],
        eq.cable_lengths_m[1],
        eq.cable_lengths_m[2],
    ]
}

#[test]
fn warm_updates_report_the_cold_estimates_load_and_uncertainty() {
    let model = Model::<f64>::new(reference::golden_bench(20).expect("bench")).expect("model");
    let inverse = InverseSettings::with_resolution(7.7e-6);
    let settings = EstimatorSettings::with_inverse(inverse);
    let (mut estimator, _) = Estimator::new(
        &model,
        LoadBasis::tip_force(),
        &lengths(&model, 0),
        Vector3::zeros(),
        settings,
    )
    .expect("valid input");
    let (mut worst_load_sigma, mut worst_std_ratio) = (0.0f64, 0.0f64);
    for k in 1..40 {
        let measured = lengths(&model, k);
        let warm = estimator.update(&measured).expect("valid input");
        assert_eq!(
            warm.report.termination,
            Termination::Converged,
            "update {k}"
        );
        // The cold estimate at the same data, from the warm answer (its own search skipped: the
        // comparison is of one answer's two linearisations).
        let cold = estimate(
            &model,
            &LoadBasis::tip_force(),
            &measured,
            InverseStart::Params(warm.params),
            &InverseSettings {
                scan_reach: 1e-3,
                ..settings.inverse
            },
        )
        .expect("valid input");
        assert!(cold.report.termination.is_success(), "update {k}");
        for i in 0..3 {
            let (sw, sc) = (warm.quality.force_std_n[i], cold.quality.force_std_n[i]);
            worst_std_ratio = worst_std_ratio.max((sw / sc - 1.0).abs());
            worst_load_sigma = worst_load_sigma.max((warm.params[i] - cold.params[i]).abs() / sc);
        }
    }
    println!(
        "worst load difference {worst_load_sigma:.3} sd, worst standard deviation ratio {:.3}",
        1.0 + worst_std_ratio
    );
    // Measured: 0.010 sd and within 1.5 % (with Broyden-updated Jacobians a quarter of a buckling
    // scale from the tangents, an earlier design, the deviations were off by 0.35-2.4 times: this
    // failed it).
    assert!(worst_load_sigma < 0.05, "{worst_load_sigma}");
    assert!(worst_std_ratio < 0.05, "{worst_std_ratio}");
}

/// A first estimate that did not converge (here its sweep budget is too small) never searched for
/// other answers: every warm update after it is unverified, however well it converges, whatever
/// the first estimate's own verdict (an unconverged fit far off reads `Inconsistent`). The
/// firmware's loop kept such an estimator and published its next converged update as determined:
/// on the bench at a tip force of (0, -0.6, 0.2) N the cold estimate runs out of its 100 sweeps in
/// f32; here in f64 with budgets of 50-56 sweeps it stops short, its verdict `Inconsistent` at 50
/// and 53 and `Unverified` at 56, and the next update converges.
#[test]
fn updates_after_a_first_estimate_that_did_not_converge_are_unverified() {
    let model = Model::<f64>::new(reference::golden_bench(20).expect("bench")).expect("model");
    let eq = model
        .solve(
            &TipLoad::force(Vector3::new(0.0, -0.6, 0.2)),
            Start::Cold,
            &ShootingSettings::default(),
        )
        .expect("valid input");
    let measured = [
        eq.cable_lengths_m[0],
        eq.cable_lengths_m[1],
        eq.cable_lengths_m[2],
    ];
    let mut converged = 0;
    for max_sweeps in [50, 53, 56] {
        let inverse = InverseSettings {
            max_sweeps,
            ..InverseSettings::with_resolution(7.7e-6)
        };
        let (mut estimator, first) = Estimator::new(
            &model,
            LoadBasis::tip_force(),
            &measured,
            Vector3::zeros(),
            EstimatorSettings::with_inverse(inverse),
        )
        .expect("valid input");
        assert!(!first.report.termination.is_success(), "{:?}", first.report);
        // The cold estimate itself is not called determined: unconverged far off it reads
        // `Inconsistent` (50, 53 sweeps), near its answer `Unverified` (56).
        let expected = if max_sweeps < 56 {
            Determination::Inconsistent
        } else {
            Determination::Unverified
        };
        assert_eq!(first.quality.determination, expected, "budget {max_sweeps}");
        for update in 0..3 {
            let warm = estimator.update(&measured).expect("valid input");
            converged += usize::from(warm.report.termination.is_success());
            assert_eq!(
                warm.quality.determination,
                Determination::Unverified,
                "budget {max_sweeps}, update {update}"
            );
        }
    }
    assert!(converged > 0, "no update converged: the test shows nothing");
}
