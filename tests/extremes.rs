//! Property tests over the extremes (proptest, fixed seed, so a failure reproduces): tip forces up to
//! 10x the thesis's heaviest load in any direction, Young's modulus from 1 MPa to 200 GPa, rod length
//! from 1 cm to 2 m, pure tip moments up to 2.5 turns about any axis, 1 to 10^4 steps per section,
//! non-finite values in any field, cable lengths at and beyond what the rod can produce.
//!
//! The contract (as in `stress.rs`, whose named cases cover each extreme once): a solve converges to a
//! verified answer or says it did not; never NaN in a success, never a silently wrong branch.
//! "Verified" re-checks the answer independently: the tip-moment residual re-evaluated by a plain
//! sweep, the stability verdict, the frame's orthonormality, the tip within reach, and the branch:
//! the equilibrium reached by loading the rod gradually from zero (warm starts in small increments)
//! must be the one a cold solve returns. Closed forms where they exist (helix, beam formulas).

use std::f64::consts::{PI, TAU};

use model_checks::reference::{self, Exp2Mass};
use model_core::inverse::{
    Determination, InverseSettings, InverseStart, LoadBasis, cable_length_bound_m, estimate,
};
use model_core::{
    Attitude, Equilibrium, GuideMass, Model, ModelError, Rod, Scalar, Section, ShapePoint,
    ShootingSettings, Stability, Start, Termination, TipLoad,
};
use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// 24 cases per property from a fixed seed (CI); `EXTREMES_CASES` and `EXTREMES_SEED` widen a local
/// search.
fn config() -> Config {
    let env = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<u64>().ok());
    Config {
        cases: env("EXTREMES_CASES").map_or(24, |n| u32::try_from(n).unwrap_or(u32::MAX)),
        rng_seed: RngSeed::Fixed(env("EXTREMES_SEED").unwrap_or(0x0e87_7e3e)),
        failure_persistence: None,
        ..Config::default()
    }
}

const L: f64 = reference::FREE_LENGTH_M;
const G: f64 = reference::GRAVITY_M_S2;
/// A 4096-count encoder on a 5 mm-radius spool, m.
const RESOLUTION_M: f64 = 2.0 * PI * 5e-3 / 4096.0;

fn is_f64<T: Scalar>() -> bool {
    T::default_epsilon().to_f64() < 1e-10
}

fn f64s<T: Scalar>(v: &Vector3<T>) -> Vector3<f64> {
    v.map(Scalar::to_f64)
}

fn lit<T: Scalar>(v: &Vector3<f64>) -> Vector3<T> {
    v.map(T::lit)
}

/// A unit vector from its angle to the base tangent (+x) and its azimuth about it.
fn direction(polar: f64, azimuth: f64) -> Vector3<f64> {
    Vector3::new(
        polar.cos(),
        polar.sin() * azimuth.cos(),
        polar.sin() * azimuth.sin(),
    )
}

fn bare_rod<T: Scalar>(length_m: f64, e_pa: f64, steps: u16, gravity: bool) -> Rod<T> {
    let mut rod = Rod::new();
    rod.guide_mass = GuideMass::Ignore;
    if !gravity {
        rod.gravity_m_s2 = Vector3::zeros();
    }
    rod.push_section(Section {
        length_m: T::lit(length_m),
        stiffness: reference::nitinol_stiffness(e_pa).expect("valid stiffness"),
        line_density_kg_per_m: T::lit(reference::bare_line_density_kg_m()),
        steps,
    })
    .expect("one section");
    rod
}

fn exp2<T: Scalar>(steps: u16) -> Model<T> {
    Model::new(reference::exp2_bench(Exp2Mass::Average, steps, 3).expect("bench")).expect("model")
}

fn cold<T: Scalar, A: Attitude<T>>(model: &Model<T, A>, load: &TipLoad<T>) -> Equilibrium<T> {
    model
        .solve(load, Start::Cold, &ShootingSettings::default())
        .expect("valid input")
}

/// The contract of a success (see `stress.rs`, `verify`, for the reasons behind each limit):
/// finite; re-evaluated tip-moment residual within 1e-5 (f64) / 5e-3 (f32) of `E I / L`; the same tip
/// as that sweep; `Stable` under dead loads, `NonConservative` with a moment; frame drift within 1e-9
/// (f64) / 1e-3 (f32); the tip within the stretched rod's reach. `Ok(false)`: a non-success.
fn verify<T: Scalar, A: Attitude<T>>(
    model: &Model<T, A>,
    eq: &Equilibrium<T>,
) -> Result<bool, String> {
    let phase = eq.report.phase_per_step_rad.to_f64();
    let resolved = phase <= model_core::MAX_PHASE_PER_STEP_RAD;
    if eq.report.termination == Termination::UnderResolved
        && (resolved || eq.report.stability != Stability::Unchecked)
    {
        return Err(format!("refused as under-resolved at {phase} rad per step"));
    }
    if !eq.report.termination.is_success() {
        return Ok(false);
    }
    if !resolved {
        return Err(format!(
            "a success at {phase} rad of bending phase per step"
        ));
    }
    let finite = eq.tip_position_m.iter().all(|x| x.is_finite())
        && eq.tip_rotation.iter().all(|x| x.is_finite())
        && eq.base_strain_per_m.iter().all(|x| x.is_finite())
        && eq.cable_lengths_m.iter().all(|x| x.is_finite());
    if !finite {
        return Err(format!("non-finite success {eq:?}"));
    }
    let ev = model
        .evaluate(&eq.base_strain_per_m, &eq.load)
        .map_err(|e| format!("re-evaluation refused: {e}"))?;
    let residual = ev.moment_residual_nm.norm().to_f64() / model.moment_scale_nm().to_f64();
    let (limit, drift_limit, same) = if is_f64::<T>() {
        (1e-5, 1e-9, 1e-12)
    } else {
        (5e-3, 1e-3, 1e-6)
    };
    if residual.is_nan() || residual > limit {
        return Err(format!(
            "re-evaluated residual {residual:e} ({:?})",
            eq.report
        ));
    }
    if f64s(&(ev.tip_position_m - eq.tip_position_m)).norm() > same {
        return Err("solve and re-evaluation disagree on the tip".into());
    }
    let conservative = eq.load.moment_nm == Vector3::zeros()
        && model
            .rod()
            .loads
            .iter()
            .all(|l| l.moment_nm == Vector3::zeros());
    let expected = if conservative {
        Stability::Stable
    } else {
        Stability::NonConservative
    };
    if eq.report.stability != expected {
        return Err(format!(
            "stability {:?}, expected {expected:?}",
            eq.report.stability
        ));
    }
    let drift = ev.frame_drift.to_f64();
    if drift.is_nan() || drift > drift_limit {
        return Err(format!("frame drift {drift:e}"));
    }
    let rod = model.rod();
    let weight = model_core::mass::total_mass_kg(rod).to_f64() * f64s(&rod.gravity_m_s2).norm();
    let ea = rod.sections[0].stiffness.shear_axial_n.min().to_f64();
    let reach = model.length_m().to_f64()
        * (1.0 + (f64s(&eq.load.force_n).norm() + weight) / ea)
        * (1.0 + 1e-5)
        + 1e-9;
    if f64s(&(eq.tip_position_m - rod.base_position_m)).norm() > reach {
        return Err(format!("tip beyond the reach {reach} m"));
    }
    Ok(true)
}

/// The equilibrium reached by loading from zero: warm starts in `n` equal increments of every load
/// (tip load and gravity together), without the cold fallback. `None` if a step fails.
fn loading_path(rod: &Rod<f64>, load: &TipLoad<f64>, n: usize) -> Option<Equilibrium<f64>> {
    let settings = ShootingSettings {
        cold_fallback: false,
        ..ShootingSettings::default()
    };
    let mut u = Vector3::zeros();
    let mut last = None;
    for k in 1..=n {
        let alpha = k as f64 / n as f64;
        let mut scaled = rod.clone();
        scaled.gravity_m_s2 *= alpha;
        let model = Model::<f64>::new(scaled).ok()?;
        let step = TipLoad {
            force_n: load.force_n * alpha,
            moment_nm: load.moment_nm * alpha,
        };
        let eq = model.solve(&step, Start::Warm(u), &settings).ok()?;
        if !eq.report.termination.is_success() {
            return None;
        }
        u = eq.base_strain_per_m;
        last = Some(eq);
    }
    last
}

/// The contract of a cold solve under a tip force of `kg` times g along `direction(polar, azimuth)`
/// on the thesis bench (100 steps): verified or refused; a success equals the loading path's answer.
fn tip_force_contract(kg: f64, polar: f64, azimuth: f64) -> Result<(), TestCaseError> {
    let rod = reference::exp2_bench::<f64>(Exp2Mass::Average, 100, 3).expect("bench");
    let model = Model::<f64>::new(rod.clone()).expect("model");
    let load = TipLoad::force(direction(polar, azimuth) * kg * G);
    let eq = cold(&model, &load);
    let ok = verify(&model, &eq);
    prop_assert!(ok.is_ok(), "{:?}", ok);
    if ok == Ok(true)
        && let Some(path) = loading_path(&rod, &load, 40)
    {
        let gap = (path.tip_position_m - eq.tip_position_m).norm();
        prop_assert!(
            gap < 1e-6,
            "cold answer {} m from the loading path's (tip {:?} vs {:?})",
            gap,
            eq.tip_position_m,
            path.tip_position_m
        );
    }
    // The thesis range (up to 83.2 g, up to 135 degrees from the tangent) must converge.
    if kg <= 0.0832 && polar <= 0.75 * PI {
        prop_assert_eq!(ok, Ok(true), "{:?}", eq.report);
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    /// Tip forces from 0 to 832 g in any direction up to 150 degrees from the tangent (pushing back
    /// up to 60 degrees off the rod's axis) on the thesis bench (three cables, 100 steps): every cold
    /// solve converges to a verified answer or says it did not; a success is the equilibrium reached
    /// by loading gradually from zero (when that path can be followed), to 1 um. The whole sphere of
    /// directions: pushing straight back along the rod, past its buckling load, is where two
    /// conjugate points coincide (stress.rs `coincident_conjugate_points_are_found_at_100_steps`).
    #[test]
    fn tip_forces_to_832g_in_any_direction(kg in 0.0f64..0.832, polar in 0.0f64..PI, azimuth in 0.0f64..TAU) {
        tip_force_contract(kg, polar, azimuth)?;
    }

    /// Young's modulus from 1 MPa to 200 GPa and length from 1 cm to 2 m, weightless, a small tip
    /// force in a random transverse direction (`P L^2 / E I = 1e-4`): the tip deflects along the force
    /// by `P L^3 / 3 E I + P L / G A` to 1e-6 (relative). Under gravity with a tip mass up to 832 g:
    /// the contract, and convergence wherever `lambda = L sqrt(F / E I) <= 8`.
    #[test]
    fn stiffness_and_length_across_five_decades(
        log_e in 6.0f64..11.31, log_l in -2.0f64..0.302, azimuth in 0.0f64..TAU, kg in 0.0f64..0.832,
    ) {
        let (e_pa, length) = (10f64.powf(log_e), 10f64.powf(log_l));
        let model = Model::<f64>::new(bare_rod(length, e_pa, 50, false)).expect("model");
        let k = reference::nitinol_stiffness::<f64>(e_pa).expect("stiffness");
        let (ei, ga) = (k.bending_torsion_nm2.x, k.shear_axial_n.x);
        let p = 1e-4 * ei / (length * length);
        let dir = direction(PI / 2.0, azimuth);
        let eq = cold(&model, &TipLoad::force(dir * p));
        prop_assert_eq!(verify(&model, &eq), Ok(true));
        let deflection = eq.tip_position_m - Vector3::new(length, 0.0, 0.0);
        let expected = p * length.powi(3) / (3.0 * ei) + p * length / ga;
        let along = deflection.dot(&dir);
        prop_assert!(((along - expected) / expected).abs() < 1e-6, "deflection {} vs {}", along, expected);
        // Sideways of the force: only the geometric shortening along x (order (P L^2 / E I)^2).
        prop_assert!((deflection - dir * along).norm() < 1e-3 * expected);

        let weighted = Model::<f64>::new(bare_rod(length, e_pa, 20, true)).expect("model");
        let load = TipLoad::force(Vector3::new(0.0, -kg * G, 0.0));
        let eq = cold(&weighted, &load);
        let ok = verify(&weighted, &eq);
        prop_assert!(ok.is_ok(), "{:?}", ok);
        let total_n = (kg + reference::bare_line_density_kg_m() * length) * G;
        let lambda = length * (total_n / ei).sqrt();
        if lambda <= 8.0 {
            prop_assert_eq!(ok, Ok(true), "lambda {}: {:?}", lambda, eq.report);
        }
    }

    /// A pure tip moment about any axis, up to 2.5 turns of the tangent: the rod is a helix about the
    /// moment's axis (a circle when the axis is across the rod), f64 to 1e-6 m and f32 to 2e-5 m on
    /// 200 steps (RK4 at up to 0.08 rad a step: 1.7e-7 m measured; f32 resolves ~1e-6 m).
    #[test]
    fn pure_tip_moments_make_helices(turns in 0.05f64..2.5, polar in 0.0f64..PI, azimuth in 0.0f64..TAU) {
        let e_pa = reference::YOUNGS_MODULUS_PA;
        let ei = reference::nitinol_stiffness::<f64>(e_pa).expect("stiffness").bending_torsion_nm2.x;
        let axis = direction(polar, azimuth);
        let m = axis * (turns * TAU * ei / L);
        // The tangent turns about the axis at |m| / E I: r = (t0.a) a s + sin(ws)/w t_perp + (1 - cos(ws))/w a x t_perp.
        let w = m.norm() / ei;
        let t0 = Vector3::x();
        let perp = t0 - axis * t0.dot(&axis);
        let helix = |s: f64| axis * (t0.dot(&axis) * s) + perp * ((w * s).sin() / w) + axis.cross(&perp) * ((1.0 - (w * s).cos()) / w);
        let s: Vec<f64> = (0..=8).map(|i| L * i as f64 / 8.0).collect();

        let model = Model::<f64>::new(bare_rod(L, e_pa, 200, false)).expect("model");
        let eq = cold(&model, &TipLoad::moment(m));
        prop_assert_eq!(verify(&model, &eq), Ok(true), "{:?}", eq.report);
        let mut out = vec![ShapePoint::default(); s.len()];
        model.shape(&eq, &s, &mut out).expect("valid queries");
        let worst = out.iter().map(|p| (p.position_m - helix(p.s_m)).norm()).fold(0.0, f64::max);
        prop_assert!(worst < 1e-6, "f64: {} m off the helix", worst);

        let m32 = Model::<f32>::new(bare_rod(L, e_pa, 200, false)).expect("model");
        let eq = cold(&m32, &TipLoad::moment(lit(&m)));
        prop_assert_eq!(verify(&m32, &eq), Ok(true), "{:?}", eq.report);
        let s32: Vec<f32> = s.iter().map(|x| *x as f32).collect();
        let mut out = vec![ShapePoint::default(); s.len()];
        m32.shape(&eq, &s32, &mut out).expect("valid queries");
        let worst = out.iter().map(|p| (f64s(&p.position_m) - helix(f64::from(p.s_m))).norm()).fold(0.0, f64::max);
        prop_assert!(worst < 2e-5, "f32: {} m off the helix", worst);
    }

    /// 1 to 10^4 steps per section on the thesis bench under up to 83.2 g at most 120 degrees from
    /// the tangent: the cold solve is verified and within 0.3 mm of a 2000-step reference (1 to 4
    /// steps give six one-step intervals), within 0.05 mm from 5 steps and 1 um from 40; f32 on the
    /// same grid within 0.1 mm of f64. Where a step takes more than `MAX_PHASE_PER_STEP_RAD` of
    /// bending phase (1 to 4 steps from about 40 g) the solve refuses as `UnderResolved` instead;
    /// from 5 steps it must answer.
    #[test]
    fn one_to_ten_thousand_steps(log_steps in 0.0f64..4.0, kg in 0.0f64..0.0832, polar in 0.0f64..(2.0 * PI / 3.0), azimuth in 0.0f64..TAU) {
        let steps = 10f64.powf(log_steps).round() as u16;
        let force = direction(polar, azimuth) * kg * G;
        let model = exp2::<f64>(steps);
        let eq = cold(&model, &TipLoad::force(force));
        if steps < 5 && eq.report.termination == Termination::UnderResolved {
            prop_assert_eq!(verify(&model, &eq), Ok(false));
            return Ok(());
        }
        prop_assert_eq!(verify(&model, &eq), Ok(true), "{} steps: {:?}", steps, eq.report);
        let reference = cold(&exp2::<f64>(2000), &TipLoad::force(force));
        prop_assert_eq!(verify(&exp2::<f64>(2000), &reference), Ok(true));
        let err = (eq.tip_position_m - reference.tip_position_m).norm();
        let limit = if steps >= 40 { 1e-6 } else if steps >= 5 { 5e-5 } else { 3e-4 };
        prop_assert!(err < limit, "{} steps: tip error {:e} m", steps, err);
        let m32 = exp2::<f32>(steps);
        let e32 = cold(&m32, &TipLoad::force(lit(&force)));
        // At the limit f32's phase may round to the other side of it.
        let at_limit = eq.report.phase_per_step_rad > 0.99 * model_core::MAX_PHASE_PER_STEP_RAD;
        if !(at_limit && e32.report.termination == Termination::UnderResolved) {
            prop_assert_eq!(verify(&m32, &e32), Ok(true), "f32 {} steps: {:?}", steps, e32.report);
            let gap = (f64s(&e32.tip_position_m) - eq.tip_position_m).norm();
            prop_assert!(gap < 1e-4, "f32 {} steps: {:e} m from f64", steps, gap);
        }
    }

    /// f32 (the MCU) against f64 under tip forces up to 200 g in any direction within 120 degrees of
    /// the tangent, on the thesis bench at 20 steps: converged, verified, within 0.1 mm.
    #[test]
    fn f32_within_a_tenth_of_a_millimetre_to_200g(kg in 0.0f64..0.2, polar in 0.0f64..(2.0 * PI / 3.0), azimuth in 0.0f64..TAU) {
        let force = direction(polar, azimuth) * kg * G;
        let (m32, m64) = (exp2::<f32>(20), exp2::<f64>(20));
        let e32 = cold(&m32, &TipLoad::force(lit(&force)));
        prop_assert_eq!(verify(&m32, &e32), Ok(true), "{:?}", e32.report);
        let e64 = cold(&m64, &TipLoad::force(force));
        let gap = (f64s(&e32.tip_position_m) - e64.tip_position_m).norm();
        prop_assert!(gap < 1e-4, "f32 {:e} m from f64", gap);
    }

    /// A non-finite value (NaN, +inf, -inf) in any scalar field of a scene, of a random size: the model
    /// refuses it, naming the field. (`stress.rs` lists the fields one by one.)
    #[test]
    fn non_finite_anywhere_is_refused(field in 0usize..13, which in 0usize..3, log_e in 6.0f64..11.3, log_l in -1.0f64..0.3) {
        let x = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][which];
        let length = 10f64.powf(log_l);
        let mut rod = bare_rod::<f64>(length, 10f64.powf(log_e), 20, true);
        rod.push_guide(model_core::Guide { s_m: length / 2.0, thickness_m: 0.003, mass_kg: 0.002 }).expect("guide");
        let mut cable = reference::golden_bench::<f64>(2).expect("bench").cables[0];
        cable.end_m = length;
        rod.push_cable(cable).expect("cable");
        rod.push_load(model_core::PointLoad::force(length / 3.0, Vector3::new(0.0, -0.01, 0.0))).expect("load");
        let expected = match field {
            0 => { rod.sections[0].length_m = x; "section length" }
            1 => { rod.sections[0].stiffness.bending_torsion_nm2[which] = x; "bending/torsion stiffness" }
            2 => { rod.sections[0].stiffness.shear_axial_n[which] = x; "shear/axial stiffness" }
            3 => { rod.sections[0].line_density_kg_per_m = x; "line density" }
            4 => { rod.guides[0].s_m = x; "guide position" }
            5 => { rod.guides[0].mass_kg = x; "guide mass" }
            6 => { rod.cables[0].hole_m[which % 2] = x; "cable hole" }
            7 => { rod.cables[0].end_m = x; "cable termination" }
            8 => { rod.loads[0].force_n[which] = x; "point force" }
            9 => { rod.loads[0].s_m = x; "load position" }
            10 => { rod.gravity_m_s2[which] = x; "gravity" }
            11 => { rod.base_position_m[which] = x; "base position" }
            _ => { rod.base_orientation[(which, 2 - which)] = x; "base orientation" }
        };
        prop_assert_eq!(Model::<f64>::new(rod).err(), Some(ModelError::NonFinite(expected)));
    }

    /// Measured cable lengths from a 3D tip force up to 400 g, offset by up to 2 cm per cable (far
    /// beyond what the rod produces): beyond the upper bound the input is refused; otherwise an
    /// estimate that succeeds is an equilibrium of its load (a forward solve warm-started at its base
    /// strain stays there, verified) and, unless it says the data are inconsistent or undetermined, its
    /// load explains the measurements (the forward lengths within 3 standard deviations): never a
    /// confident wrong answer. Exact lengths are recovered.
    #[test]
    fn cable_lengths_at_and_beyond_reach(
        kg in 0.0f64..0.4, polar in 0.3f64..(PI / 2.0), azimuth in 0.0f64..TAU,
        offsets in prop::array::uniform3(-0.02f64..0.02), exact in prop::bool::weighted(0.25),
    ) {
        let model = Model::<f64>::new(reference::golden_bench(40).expect("bench")).expect("model");
        let forward = cold(&model, &TipLoad::force(direction(polar, azimuth) * kg * G));
        prop_assert_eq!(verify(&model, &forward), Ok(true));
        let measured: Vec<f64> = forward.cable_lengths_m.iter().zip(offsets)
            .map(|(l, d)| if exact { *l } else { l + d }).collect();
        let settings = InverseSettings::with_resolution(RESOLUTION_M);
        let result = estimate(&model, &LoadBasis::tip_force(), &measured, InverseStart::Params(Vector3::zeros()), &settings);
        let beyond = model.rod().cables.iter().zip(&measured).any(|(c, m)| *m > cable_length_bound_m(model.rod(), c));
        if beyond {
            prop_assert!(matches!(result, Err(ModelError::OutOfRange(_))), "{:?}", result.map(|e| e.report));
            return Ok(());
        }
        let est = result.expect("valid input");
        if exact {
            prop_assert!(est.report.termination.is_success(), "exact lengths: {:?}", est.report);
        }
        if est.report.termination.is_success() {
            prop_assert!(est.params.iter().chain(est.tip_position_m.iter()).all(|x| x.is_finite()));
            let settings = ShootingSettings { cold_fallback: false, ..ShootingSettings::default() };
            let again = model.solve(&est.load, Start::Warm(est.base_strain_per_m), &settings).expect("valid input");
            prop_assert_eq!(verify(&model, &again), Ok(true), "{:?}", again.report);
            prop_assert!((again.tip_position_m - est.tip_position_m).norm() < 1e-6);
            let confident = matches!(est.quality.determination, Determination::Determined | Determination::Weak);
            if confident {
                let sigma = RESOLUTION_M / 12f64.sqrt();
                for (a, b) in again.cable_lengths_m.iter().zip(&measured) {
                    prop_assert!((a - b).abs() < 3.0 * sigma, "{:?}, but its load gives {} for {}", est.quality.determination, a, b);
                }
            }
        }
    }
}
