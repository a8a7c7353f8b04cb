//! Forward then inverse, over random 3D tip forces: the three cable lengths of a solved shape give back
//! the force and the tip. Deterministic (fixed seed), so a failure reproduces.
//!
//! Two contracts. Where the rod bends under its load (the tip pulled down, the common case), the
//! estimate must converge and be right. Over the whole range, including the nearly straight rod whose
//! axial force the cables barely see (and where an axial force near buckling acts strongly
//! nonlinearly), the estimate may fail to converge, but whenever it reports success its error must lie
//! within the uncertainty it reports: never a confident wrong number.

use model_checks::reference;
use model_core::inverse::{Estimate, InverseSettings, InverseStart, LoadBasis, estimate};
use model_core::{Equilibrium, Model, ShootingSettings, Start, TipLoad};
use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config() -> Config {
    Config {
        cases: 24,
        rng_seed: RngSeed::Fixed(0x5eed_ca61),
        failure_persistence: None,
        ..Config::default()
    }
}

/// 4096 counts per turn on a 5 mm-radius spool.
const RESOLUTION_M: f64 = 2.0 * std::f64::consts::PI * 5e-3 / 4096.0;

fn forward(force: Vector3<f64>) -> Option<Equilibrium<f64>> {
    let model = Model::<f64>::new(reference::golden_bench(60).unwrap()).unwrap();
    let eq = model
        .solve(
            &TipLoad::force(force),
            Start::Cold,
            &ShootingSettings::default(),
        )
        .unwrap();
    eq.report.termination.is_success().then_some(eq)
}

fn inverse(lengths: &[f64], settings: &InverseSettings<f64>) -> Estimate<f64, 3> {
    let model = Model::<f64>::new(reference::golden_bench(60).unwrap()).unwrap();
    estimate(
        &model,
        &LoadBasis::tip_force(),
        lengths,
        InverseStart::Params(Vector3::zeros()),
        settings,
    )
    .unwrap()
}

fn inverse_f32(lengths: &[f64]) -> Estimate<f32, 3> {
    let model = Model::<f32>::new(reference::golden_bench(60).unwrap()).unwrap();
    let lengths: Vec<f32> = lengths.iter().map(|x| *x as f32).collect();
    let settings = InverseSettings::with_resolution(RESOLUTION_M as f32);
    estimate(
        &model,
        &LoadBasis::tip_force(),
        &lengths,
        InverseStart::Params(Vector3::zeros()),
        &settings,
    )
    .unwrap()
}

/// Whether a successful estimate's errors lie within `k` of its reported standard deviations.
fn within_reported(
    est: &Estimate<f64, 3>,
    force: &Vector3<f64>,
    tip: &Vector3<f64>,
    k: f64,
) -> Result<(), String> {
    for i in 0..3 {
        let (err, sd) = ((est.params[i] - force[i]).abs(), est.quality.force_std_n[i]);
        if err > k * sd {
            return Err(format!(
                "force {i}: error {err:e} N beyond {k} x sd {sd:e} N"
            ));
        }
        let (err, sd) = (
            (est.tip_position_m[i] - tip[i]).abs(),
            est.quality.tip_std_m[i],
        );
        if err > k * sd + 1e-6 {
            return Err(format!("tip {i}: error {err:e} m beyond {k} x sd {sd:e} m"));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    /// Bending-dominated loads, exact lengths: converges; the data alone (no prior) give back the force
    /// to a hundredth of its uncertainty and the tip to 1 um; the f32 estimator gives the tip within
    /// 0.1 mm.
    #[test]
    fn bending_dominated_loads_are_recovered(fx in -0.1f64..0.1, fy in -0.3f64..-0.05, fz in -0.3f64..0.3) {
        let force = Vector3::new(fx, fy, fz);
        let Some(eq) = forward(force) else { return Err(TestCaseError::reject("forward solve failed")) };
        let settings = InverseSettings { prior_std_scale: f64::INFINITY, ..InverseSettings::with_resolution(RESOLUTION_M) };
        let est = inverse(&eq.cable_lengths_m, &settings);
        prop_assert!(est.report.termination.is_success(), "{:?}", est.report);
        prop_assert!(within_reported(&est, &force, &eq.tip_position_m, 1e-2).is_ok(), "{:?}", within_reported(&est, &force, &eq.tip_position_m, 1e-2));
        prop_assert!((est.tip_position_m - eq.tip_position_m).norm() < 1e-6);

        let est32 = inverse_f32(&eq.cable_lengths_m);
        prop_assert!(est32.report.termination.is_success(), "{:?}", est32.report);
        let tip_err = (est32.tip_position_m.map(f64::from) - eq.tip_position_m).norm();
        prop_assert!(tip_err < 1e-4, "f32 tip off by {:e} m", tip_err);
    }

    /// The whole range, exact and encoder-quantised lengths, default settings (a weak prior on the
    /// load): whenever the estimate reports success, force and tip are within 4 reported standard
    /// deviations (and the f32 tip within 0.1 mm or 4 of its standard deviations).
    #[test]
    fn success_is_never_confidently_wrong(fx in -0.1f64..0.1, fy in -0.3f64..0.1, fz in -0.3f64..0.3) {
        let force = Vector3::new(fx, fy, fz);
        let Some(eq) = forward(force) else { return Err(TestCaseError::reject("forward solve failed")) };
        let quantised: Vec<f64> = eq.cable_lengths_m.iter().map(|l| (l / RESOLUTION_M).round() * RESOLUTION_M).collect();
        let settings = InverseSettings::with_resolution(RESOLUTION_M);
        for lengths in [eq.cable_lengths_m.as_slice(), quantised.as_slice()] {
            let est = inverse(lengths, &settings);
            if est.report.termination.is_success() {
                let check = within_reported(&est, &force, &eq.tip_position_m, 4.0);
                prop_assert!(check.is_ok(), "{:?}", check);
            }
        }
        let est32 = inverse_f32(&eq.cable_lengths_m);
        if est32.report.termination.is_success() {
            let tip_err = (est32.tip_position_m.map(f64::from) - eq.tip_position_m).norm();
            let sd = f64::from(est32.quality.tip_std_m.norm());
            prop_assert!(tip_err < 1e-4 || tip_err < 4.0 * sd, "f32 tip off by {:e} m, sd {:e} m", tip_err, sd);
        }
    }
}
