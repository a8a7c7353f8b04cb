//! The estimator attacked as an adversary would: random tip forces over the three-cable bench, from
//! 0.01 to 100 buckling scales (`E I / L^2`, 0.12 N) in every direction, the cables read through
//! either encoder (the firmware's 2.397e-7 m per count, the scene file's 7.67e-6 m), estimated
//! cold in f64 and in f32. The contract: no estimate that the firmware would publish (`Converged`,
//! and `Determined` or `Weak`) is more than five of its reported standard deviations from the
//! truth, in any component of the force or of the tip. Other verdicts (`Ambiguous`, `Unverified`,
//! `Undetermined`, `Inconsistent`, a refusal) are allowed: they say the answer is not to be trusted.
//! CI's 40 attacks per configuration hold it; 20 000 do not yet: 12 `Weak` answers break it
//! (`report/attack.md` lists them and why).
//!
//! Loads drawn by proptest's runner from a fixed seed, so a run reproduces: 40 per configuration in
//! CI; `ATTACK_CASES` and `ATTACK_SEED` run a large attack (`report/attack.md` has one). Each
//! configuration prints its tally of verdicts and lists every answer that breaks the contract.

use model_checks::reference;
use model_core::inverse::{Determination, InverseSettings, InverseStart, LoadBasis, estimate};
use model_core::{Model, Scalar, ShootingSettings, Stability, Start, TipLoad};
use nalgebra::Vector3;
use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::{Config, RngSeed, TestRunner};
use std::collections::BTreeMap;

/// The firmware's encoder: a 4096-count sensor on its spool, m per count.
const FIRMWARE_RESOLUTION_M: f64 = 2.397e-7;
/// `bench_3d_cables.toml`'s encoder, m per count.
const SCENE_RESOLUTION_M: f64 = 7.67e-6;
/// Steps per section: the host's 40 (100 buckling scales take 0.25 rad of bending phase a step) and
/// the controller's 20 (0.5 rad: the largest loads are refused as under-resolved there).
const HOST_STEPS: u16 = 40;
const MCU_STEPS: u16 = 20;
/// The largest load attacked, in buckling scales.
const MAX_SCALES: f64 = 100.0;
/// Most reported standard deviations a published answer may be from the truth.
const COVERAGE: f64 = 5.0;

/// The unit vector at `polar` from the rod's axis (`x`, along the unloaded rod) and `azimuth` about it.
fn direction(cos_polar: f64, azimuth: f64) -> Vector3<f64> {
    let sin_polar = (1.0 - cos_polar * cos_polar).max(0.0).sqrt();
    Vector3::new(
        cos_polar,
        sin_polar * azimuth.cos(),
        sin_polar * azimuth.sin(),
    )
}

/// One attack: the truth at `buckling_scales` times `E I / L^2` along `(cos_polar, azimuth)`,
/// solved in f64 on the grid of `steps`; its cable lengths read at `resolution_m`; a cold estimate
/// in `T` on the same grid. Returns the verdict (`None` when the truth is not a stable equilibrium)
/// and, for a published estimate (`Converged`, `Determined` or `Weak`) beyond [`COVERAGE`] standard
/// deviations, what breaks the contract.
fn attack<T: Scalar>(
    steps: u16,
    resolution_m: f64,
    buckling_scales: f64,
    cos_polar: f64,
    azimuth: f64,
) -> Option<(String, Option<String>)> {
    let truth_model =
        Model::<f64>::new(reference::golden_bench(steps).expect("bench")).expect("model");
    let model = Model::<T>::new(reference::golden_bench(steps).expect("bench")).expect("model");
    let scale_n = truth_model.moment_scale_nm() / truth_model.length_m();
    let force = direction(cos_polar, azimuth) * buckling_scales * scale_n;
    let truth = truth_model
        .solve(
            &TipLoad::force(force),
            Start::Cold,
            &ShootingSettings::default(),
        )
        .expect("valid load");
    // Only a stable equilibrium is a robot's state.
    if !(truth.report.termination.is_success() && truth.report.stability == Stability::Stable) {
        return None;
    }
    let read: Vec<T> = truth
        .cable_lengths_m
        .iter()
        .map(|l| T::lit((l / resolution_m).round() * resolution_m))
        .collect();
    // The search for other answers reaches the largest load attacked: `scan_reach` is the largest
    // load the robot can meet, and a rival beyond it is not looked for.
    let settings = InverseSettings {
        scan_reach: T::lit(MAX_SCALES),
        ..InverseSettings::with_resolution(T::lit(resolution_m))
    };
    let Ok(est) = estimate(
        &model,
        &LoadBasis::tip_force(),
        &read,
        InverseStart::Params(Vector3::zeros()),
        &settings,
    ) else {
        // Refused as input (a reading beyond what the rod can produce): not an answer.
        return Some(("refused".into(), None));
    };
    let verdict = format!(
        "{:?}/{:?}",
        est.report.termination, est.quality.determination
    );
    if !(est.report.termination.is_success()
        && matches!(
            est.quality.determination,
            Determination::Determined | Determination::Weak
        ))
    {
        return Some((verdict, None));
    }
    let f64s = |v: &Vector3<T>| v.map(Scalar::to_f64);
    let force_sigma = (f64s(&est.params) - force)
        .component_div(&f64s(&est.quality.force_std_n))
        .amax();
    let tip_sigma = (f64s(&est.tip_position_m) - truth.tip_position_m)
        .component_div(&f64s(&est.quality.tip_std_m))
        .amax();
    let broken = (force_sigma > COVERAGE || tip_sigma > COVERAGE).then(|| {
        format!(
            "{:?} {:.4?} N for the truth {:.4?} N: force {:.1} and tip {:.1} standard \
             deviations off (tip {:.2e} m; {:?})",
            est.quality.determination,
            f64s(&est.params).as_slice(),
            force.as_slice(),
            force_sigma,
            tip_sigma,
            (f64s(&est.tip_position_m) - truth.tip_position_m).norm(),
            est.report
        )
    });
    Some((verdict, broken))
}

/// `ATTACK_CASES` attacks (40 by default) drawn from `ATTACK_SEED`: prints the tally of verdicts and
/// fails listing every answer that breaks the contract.
fn campaign<T: Scalar>(name: &str, steps: u16, resolution_m: f64) {
    let env = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<u64>().ok());
    let cases = env("ATTACK_CASES").unwrap_or(40);
    let mut runner = TestRunner::new(Config {
        rng_seed: RngSeed::Fixed(env("ATTACK_SEED").unwrap_or(0x0a77_ac4e)),
        ..Config::default()
    });
    // Load from 0.01 to 100 buckling scales (log-uniform), direction uniform on the sphere.
    let loads = (-2.0f64..2.0, -1.0f64..1.0, 0.0f64..std::f64::consts::TAU);
    // Verdicts by decade of load: 0.01-0.1, 0.1-1, 1-10, 10-100 buckling scales.
    let mut tally: BTreeMap<String, [u64; 4]> = BTreeMap::new();
    let mut broken = Vec::new();
    for _ in 0..cases {
        let (log_scales, cos_polar, azimuth) =
            loads.new_tree(&mut runner).expect("a load").current();
        let scales = 10f64.powf(log_scales);
        let decade = ((log_scales + 2.0).floor().max(0.0) as usize).min(3);
        let verdict = attack::<T>(steps, resolution_m, scales, cos_polar, azimuth);
        let (name, bad) = verdict.unwrap_or_else(|| ("truth not stable (skipped)".into(), None));
        if let Some(cell) = tally.entry(name).or_default().get_mut(decade) {
            *cell += 1;
        }
        broken.extend(bad.map(|b| {
            format!("{scales:.4} EI/L^2 (attack::<_>({steps}, {resolution_m:e}, {scales:?}, {cos_polar:?}, {azimuth:?})): {b}")
        }));
    }
    println!("{name}: {cases} attacks at {steps} steps per section, {resolution_m:e} m per count");
    println!("  | verdict | 0.01-0.1 | 0.1-1 | 1-10 | 10-100 EI/L^2 |");
    println!("  | --- | ---: | ---: | ---: | ---: |");
    for (verdict, [a, b, c, d]) in &tally {
        println!("  | {verdict} | {a} | {b} | {c} | {d} |");
    }
    println!(
        "  {:>6}  Converged/Determined or Weak beyond {COVERAGE} sigma",
        broken.len()
    );
    assert!(broken.is_empty(), "{name}:\n{}", broken.join("\n"));
}

#[test]
fn f64_firmware_encoder() {
    campaign::<f64>("f64, firmware encoder", HOST_STEPS, FIRMWARE_RESOLUTION_M);
}

#[test]
fn f64_scene_encoder() {
    campaign::<f64>("f64, scene encoder", HOST_STEPS, SCENE_RESOLUTION_M);
}

#[test]
fn f32_firmware_encoder() {
    campaign::<f32>("f32, firmware encoder", MCU_STEPS, FIRMWARE_RESOLUTION_M);
}

#[test]
fn f32_scene_encoder() {
    campaign::<f32>("f32, scene encoder", MCU_STEPS, SCENE_RESOLUTION_M);
}
