//! The cheaper tendon variants against references that can fail: continuous routing (Rucker &
//! Webster) against the circular arc and a published implementation, the discrete guides
//! approaching it as `1 / K^2`, piecewise constant curvature against both.

use integration_tests::tendon_arc as arc;
use model_checks::reference;
use model_core::{
    Model, Rod, Scalar, ShootingSettings, Stability, Tendon, TendonEquilibrium, Tendons, TipLoad,
};
use nalgebra::Vector3;

fn settings<T: Scalar>() -> ShootingSettings<T> {
    ShootingSettings::default()
}

fn continuous<T: Scalar>(
    rod: Rod<T>,
    tendons: &[Tendon<T>],
    tensions_n: &[f64],
    tip_force_n: [f64; 3],
) -> (Model<T>, Tendons<T>, TendonEquilibrium<T>) {
    let model = Model::<T>::new(rod).unwrap();
    let tendons = Tendons::new(&model, tendons).unwrap();
    let tau: Vec<T> = tensions_n.iter().map(|t| T::lit(*t)).collect();
    let load = TipLoad::force(Vector3::from(tip_force_n.map(T::lit)));
    let solved = model
        .solve_tendons_continuous(&tendons, &tau, &load, None, &settings())
        .unwrap();
    assert!(solved.is_success(), "{:?}", solved.equilibrium.report);
    assert_eq!(solved.equilibrium.report.stability, Stability::Unchecked);
    (model, tendons, solved)
}

fn tendon_continuous_arc<T: Scalar>(steps: u16, tol_m: f64) {
    for tau in [0.5, 1.0, 2.0, 4.0, 8.0] {
        let (rod, tendons) = reference::tendon_dense::<T>(1, steps).unwrap();
        let (_, _, solved) = continuous(rod, &tendons, &[tau], [0.0; 3]);
        let (tip, tangent, len) = arc(tau);
        let eq = &solved.equilibrium;
        let off = (eq.tip_position_m.map(Scalar::to_f64) - tip).norm();
        let off_t = (eq.tip_tangent().map(Scalar::to_f64) - tangent).norm();
        let off_l = (solved.path_m[0].to_f64() - len).abs();
        eprintln!("tau {tau}: tip {off:.2e} m, tangent {off_t:.2e}, length {off_l:.2e} m");
        assert!(off < tol_m, "tau {tau}: tip {off:e} m off the arc");
        assert!(off_l < tol_m, "tau {tau}: length {off_l:e} m off the arc");
        assert!(
            off_t < tol_m / 0.2,
            "tau {tau}: tangent {off_t:e} off the arc"
        );
    }
}

#[test]
fn tendon_continuous_is_the_circular_arc_in_f64() {
    tendon_continuous_arc::<f64>(100, 1e-9);
}

#[test]
fn tendon_continuous_is_the_circular_arc_in_f32() {
    tendon_continuous_arc::<f32>(100, 1e-5);
}

/// J. D. Till's ContinuumRobotExamples tendon robot (Rucker & Webster's continuous routing; the
/// commit and setup are in `tests/tendon.rs`, `TILL_TENDON_ROBOT`), at its tight tolerance: tension
/// and `(lateral, axial)` tip.
const TILL_TIGHT: [(f64, [f64; 2]); 2] = [
    (1.0, [0.019577283658841843, 0.1987142466932732]),
    (2.0, [0.038_777_714_406_537_83, 0.1948914842581389]),
];

#[test]
fn tendon_continuous_matches_a_published_implementation() {
    for (tau, tight) in TILL_TIGHT {
        let (rod, tendons) = reference::tendon_dense::<f64>(1, 200).unwrap();
        let (_, _, solved) = continuous(rod, &tendons, &[tau], [0.0; 3]);
        let tip = solved.equilibrium.tip_position_m;
        let off = (nalgebra::Vector2::new(tip.y, tip.x) - nalgebra::Vector2::from(tight)).norm();
        eprintln!("tau {tau}: {off:.2e} m from the published tip");
        assert!(off < 1e-9, "tau {tau}: {off:e} m from the published tip");
        assert!(tip.z.abs() < 1e-15);
    }
}

/// The two-section, six-tendon robot of `tendon_two_section.csv` with gravity, its guides replaced
/// by `per_section` massless point guides per section (the mass distribution the same for every
/// count, so that only the routing differs).
fn two_section<T: Scalar>(per_section: usize, steps: u16) -> (Rod<T>, [Tendon<T>; 6]) {
    let (mut rod, tendons) = reference::tendon_two_section::<T>(steps, 9.81).unwrap();
    rod.guides.clear();
    rod.loads.clear();
    rod.guide_mass = model_core::GuideMass::Ignore;
    for (start, length) in [(0.15, 0.0), (0.12, 0.15)] {
        for k in 1..=per_section {
            rod.push_guide(model_core::Guide {
                s_m: T::lit(length + start * k as f64 / per_section as f64),
                thickness_m: T::zero(),
                mass_kg: T::zero(),
            })
            .unwrap();
        }
    }
    (rod, tendons)
}

/// Tensions and tip force of the convergence and PCC scenes: all six tendons, two terminations.
const TENSIONS: [f64; 6] = [1.0, 0.5, 0.0, 1.5, 0.3, 0.8];
const TIP_FORCE: [f64; 3] = [0.02, -0.05, 0.03];

fn discrete<T: Scalar>(
    rod: Rod<T>,
    tendons: &[Tendon<T>],
    tensions_n: &[f64],
    tip_force_n: [f64; 3],
) -> TendonEquilibrium<T> {
    let model = Model::<T>::new(rod).unwrap();
    let tendons = Tendons::new(&model, tendons).unwrap();
    let tau: Vec<T> = tensions_n.iter().map(|t| T::lit(*t)).collect();
    let load = TipLoad::force(Vector3::from(tip_force_n.map(T::lit)));
    let solved = model
        .solve_tendons(&tendons, &tau, &load, None, &settings())
        .unwrap();
    assert!(solved.is_success(), "{:?}", solved.equilibrium.report);
    solved
}

/// The largest distance of tip and paths between two tendon equilibria, m.
fn gap(a: &TendonEquilibrium<f64>, b: &TendonEquilibrium<f64>) -> (f64, f64) {
    let tip = (a.equilibrium.tip_position_m - b.equilibrium.tip_position_m).norm();
    let path = a
        .path_m
        .iter()
        .zip(&b.path_m)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    (tip, path)
}

/// Guides getting denser on the two-section robot with gravity, a tip force and six tendons ending
/// at two arc lengths: the discrete model approaches continuous routing as `1 / K^2`, tip and path
/// lengths alike.
#[test]
fn tendon_discrete_guides_approach_continuous_routing_as_one_over_k_squared() {
    let steps = 192;
    let (rod, tendons) = two_section::<f64>(4, steps);
    let (_, _, cont) = continuous(rod, &tendons, &TENSIONS, TIP_FORCE);
    let mut previous: Option<(f64, f64)> = None;
    for k in [4, 8, 16, 32] {
        let (rod, tendons) = two_section::<f64>(k, steps);
        let disc = discrete(rod, &tendons, &TENSIONS, TIP_FORCE);
        let (tip, path) = gap(&disc, &cont);
        let k2 = (k * k) as f64;
        eprintln!(
            "{k} guides per section: tip {tip:.3e} m (x K^2 = {:.4e}), paths {path:.3e} m (x K^2 = {:.4e})",
            tip * k2,
            path * k2
        );
        if let Some((prev_tip, prev_path)) = previous {
            // Halving the spacing divides both gaps by four, within 10 %.
            let (rt, rp) = (prev_tip / tip, prev_path / path);
            assert!((3.6..4.4).contains(&rt), "{k}: tip ratio {rt}");
            assert!((3.6..4.4).contains(&rp), "{k}: path ratio {rp}");
        }
        previous = Some((tip, path));
    }
}

fn pcc<T: Scalar>(
    rod: Rod<T>,
    tendons: &[Tendon<T>],
    tensions_n: &[f64],
    tip_force_n: [f64; 3],
) -> TendonEquilibrium<T> {
    let model = Model::<T>::new(rod).unwrap();
    let tendons = Tendons::new(&model, tendons).unwrap();
    let tau: Vec<T> = tensions_n.iter().map(|t| T::lit(*t)).collect();
    let load = TipLoad::force(Vector3::from(tip_force_n.map(T::lit)));
    // With gravity or a tip load PCC is refused unless its error is taken knowingly.
    let loaded = model.rod().gravity_m_s2 != Vector3::zeros() || tip_force_n != [0.0; 3];
    assert_eq!(
        model.solve_tendons_pcc(&tendons, &tau, &load).is_err(),
        loaded,
        "PCC must refuse exactly the loaded scenes"
    );
    let solved = model
        .solve_tendons_pcc_ignoring_loads(&tendons, &tau, &load)
        .unwrap();
    assert!(solved.is_success(), "{:?}", solved.equilibrium.report);
    solved
}

/// One section, no gravity: the constant-curvature arc is the exact answer, to rounding.
#[test]
fn tendon_pcc_is_the_circular_arc_exactly() {
    for tau in [0.5, 1.0, 2.0, 4.0, 8.0] {
        let (rod, tendons) = reference::tendon_dense::<f64>(10, 10).unwrap();
        let solved = pcc(rod, &tendons, &[tau], [0.0; 3]);
        let (tip, tangent, len) = arc(tau);
        let eq = &solved.equilibrium;
        let off = (eq.tip_position_m - tip).norm();
        let off_t = (eq.tip_tangent() - tangent).norm();
        let off_l = (solved.path_m[0] - len).abs();
        assert!(
            off < 1e-15 && off_t < 1e-14 && off_l < 1e-15,
            "tau {tau}: tip {off:e} m, tangent {off_t:e}, length {off_l:e} m"
        );
    }
}

/// Two sections, six tendons ending at two arc lengths, no gravity and no tip load: continuous
/// routing is piecewise constant curvature (MODEL.md §6.9), so the two agree to the sweep's RK4 error.
#[test]
fn tendon_pcc_equals_continuous_routing_without_external_load() {
    let (mut rod, tendons) = two_section::<f64>(4, 192);
    rod.gravity_m_s2 = Vector3::zeros();
    let (_, _, cont) = continuous(rod.clone(), &tendons, &TENSIONS, [0.0; 3]);
    let arcs = pcc(rod, &tendons, &TENSIONS, [0.0; 3]);
    let (tip, path) = gap(&arcs, &cont);
    eprintln!("PCC - continuous without load: tip {tip:.2e} m, paths {path:.2e} m");
    assert!(
        tip < 1e-10 && path < 1e-10,
        "tip {tip:e} m, paths {path:e} m"
    );
    let r = (arcs.equilibrium.tip_rotation - cont.equilibrium.tip_rotation).norm();
    assert!(r < 1e-9, "tip frame {r:e}");
}

/// Each variant's distance from the discrete-guide golden references (independent solver), tip
/// and paths, m: what choosing a cheaper variant costs on the benches, printed and bounded on both
/// sides (a change of either model moves them). Continuous routing differs from discrete guides by
/// the guide spacing's `1 / K^2` term: centimetres with the thesis bench's six guides 9.5 cm apart,
/// millimetres with the two-section robot's 14. PCC also ignores gravity and the tip force: up to
/// 25 cm on the bench, whose rod sags 5.7 cm under its own weight alone. Where nothing but tendons
/// acts (the two-section rows without gravity and tip force) PCC and continuous routing agree.
#[test]
fn tendon_variants_measured_against_the_golden_discrete_references() {
    use model_checks::reference::csv_rows;
    /// Scene, row, and each variant's tip and worst path distance (continuous: `[0]`, PCC: `[1]`).
    struct Row {
        scene: &'static str,
        row: usize,
        tip: [f64; 2],
        path: [f64; 2],
    }
    let mut rows: Vec<Row> = Vec::new();
    let measure = |eq: &TendonEquilibrium<f64>, tip: [f64; 3], paths: &[f64]| {
        let t = (eq.equilibrium.tip_position_m - Vector3::from(tip)).norm();
        let p = eq
            .path_m
            .iter()
            .zip(paths)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        (t, p)
    };
    for (k, row) in csv_rows::<18>(reference::TENDON_BENCH_CSV).enumerate() {
        let v = row.unwrap();
        let (rod, tendons) = reference::tendon_bench::<f64>(200).unwrap();
        let (_, _, cont) = continuous(rod.clone(), &tendons, &v[0..3], [v[3], v[4], v[5]]);
        let arcs = pcc(rod, &tendons, &v[0..3], [v[3], v[4], v[5]]);
        let (ct, cp) = measure(&cont, [v[6], v[7], v[8]], &v[12..15]);
        let (pt, pp) = measure(&arcs, [v[6], v[7], v[8]], &v[12..15]);
        rows.push(Row {
            scene: "bench",
            row: k,
            tip: [ct, pt],
            path: [cp, pp],
        });
    }
    for (k, row) in csv_rows::<25>(reference::TENDON_TWO_SECTION_CSV).enumerate() {
        let v = row.unwrap();
        let (rod, tendons) = reference::tendon_two_section::<f64>(100, v[0]).unwrap();
        let force = [v[7], v[8], v[9]];
        let (_, _, cont) = continuous(rod.clone(), &tendons, &v[1..7], force);
        let arcs = pcc(rod, &tendons, &v[1..7], force);
        let (ct, cp) = measure(&cont, [v[10], v[11], v[12]], &v[16..22]);
        let (pt, pp) = measure(&arcs, [v[10], v[11], v[12]], &v[16..22]);
        rows.push(Row {
            scene: "two-section",
            row: k,
            tip: [ct, pt],
            path: [cp, pp],
        });
    }
    for r in &rows {
        eprintln!(
            "{} row {}: continuous tip {:.3e} paths {:.3e}; PCC tip {:.3e} paths {:.3e}",
            r.scene, r.row, r.tip[0], r.path[0], r.tip[1], r.path[1]
        );
    }
    let worst = |scene: &str, pick: fn(&Row) -> f64| {
        rows.iter()
            .filter(|r| r.scene == scene)
            .map(pick)
            .fold(0.0f64, f64::max)
    };
    // (scene, variant, worst tip, worst path) measured, each bounded within 10 %.
    let bounds: [(&str, &str, f64, f64, f64, f64); 4] = [
        (
            "bench",
            "continuous",
            worst("bench", |r| r.tip[0]),
            4.744e-2,
            worst("bench", |r| r.path[0]),
            3.918e-3,
        ),
        (
            "bench",
            "PCC",
            worst("bench", |r| r.tip[1]),
            2.534e-1,
            worst("bench", |r| r.path[1]),
            9.600e-3,
        ),
        (
            "two-section",
            "continuous",
            worst("two-section", |r| r.tip[0]),
            2.559e-3,
            worst("two-section", |r| r.path[0]),
            1.983e-4,
        ),
        (
            "two-section",
            "PCC",
            worst("two-section", |r| r.tip[1]),
            9.160e-2,
            worst("two-section", |r| r.path[1]),
            4.262e-3,
        ),
    ];
    for (scene, variant, tip, tip_expected, path, path_expected) in bounds {
        for (what, got, expected) in [("tip", tip, tip_expected), ("path", path, path_expected)] {
            assert!(
                (got / expected - 1.0).abs() < 0.1,
                "{scene} {variant}: worst {what} {got:e} m, measured {expected:e} m"
            );
        }
    }
    // No gravity, no tip force (two-section rows 0, 2, 4, 6, 8): PCC is continuous routing.
    for r in rows
        .iter()
        .filter(|r| r.scene == "two-section" && r.row % 2 == 0 && r.row < 10)
    {
        assert!(
            (r.tip[1] - r.tip[0]).abs() < 1e-9 && (r.path[1] - r.path[0]).abs() < 1e-9,
            "two-section row {}: PCC {:e} continuous {:e}",
            r.row,
            r.tip[1],
            r.tip[0]
        );
    }
}

/// The tendon model picker on the golden two-section robot (14 guides with mass, gravity, a tip
/// force): a loose tolerance takes PCC, a middling one continuous routing, a tight one the discrete
/// guides; each pick within its tolerance of the reference, and the cheapest that is.
#[test]
fn tendon_choose_picks_the_cheapest_variant_within_tolerance() {
    use model_core::reduction::{TendonModel, choose_tendons};
    let (rod, tendons) = reference::tendon_two_section::<f64>(10, 9.81).unwrap();
    let load = TipLoad::force(Vector3::from(TIP_FORCE));
    for (tolerance_m, expected) in [
        (0.2, TendonModel::ConstantCurvature),
        (5e-3, TendonModel::Continuous),
        (1e-5, TendonModel::DiscreteGuides),
    ] {
        let choice =
            choose_tendons(&rod, &tendons, &TENSIONS, &load, tolerance_m, &settings()).unwrap();
        for t in &choice.trials {
            eprintln!(
                "tol {tolerance_m:e}: {:?} {} steps: error {:.3e} m, cost {}, converged {}",
                t.variant.model, t.variant.steps_per_section, t.error_m, t.cost, t.converged
            );
        }
        assert_eq!(choice.variant.model, expected, "tolerance {tolerance_m}");
        assert!(choice.error_m <= tolerance_m);
        // Nothing cheaper met the tolerance.
        for t in &choice.trials {
            assert!(
                !(t.converged && t.error_m <= tolerance_m && t.cost < choice.cost),
                "{t:?} beats {:?}",
                choice.variant
            );
        }
        assert!(choice.cost <= choice.discrete_cost);
    }
    assert!(choose_tendons(&rod, &tendons, &TENSIONS, &load, -1.0, &settings()).is_err());
}

/// A warm start (from the other tendon model too) lands on the cold answer in a few sweeps; the
/// shape reaches the tip; f32 follows f64.
#[test]
fn tendon_continuous_warm_start_shape_and_f32() {
    let (rod, tendons) = two_section::<f64>(4, 40);
    let (model, set, cold) = continuous(rod.clone(), &tendons, &TENSIONS, TIP_FORCE);
    let load = TipLoad::force(Vector3::from(TIP_FORCE));
    let disc = model
        .solve_tendons(&set, &TENSIONS, &load, None, &settings())
        .unwrap();
    // From its own answer one sweep; from the discrete guides' (3.3 mm away) a few Newton steps
    // (7 measured; the cold solve took 7 sweeps).
    for (start, sweeps) in [(&cold, 1), (&disc, 10)] {
        let warm = model
            .solve_tendons_continuous(&set, &TENSIONS, &load, Some(start), &settings())
            .unwrap();
        assert!(warm.is_success());
        assert!(
            warm.equilibrium.report.sweeps <= sweeps,
            "{:?}",
            warm.equilibrium.report
        );
        let (tip, path) = gap(&warm, &cold);
        assert!(tip < 1e-12 && path < 1e-12, "{tip:e} {path:e}");
    }
    let s = [0.0, 0.15, 0.27];
    let mut out = [model_core::ShapePoint::default(); 3];
    let written = model
        .shape_tendons_continuous(&set, &cold, &s, &mut out)
        .unwrap();
    assert_eq!(written, 3);
    assert!((out[2].position_m - cold.equilibrium.tip_position_m).norm() < 1e-15);
    assert!(out[0].position_m.norm() < 1e-15);
    assert!((out[0].strain_per_m - cold.equilibrium.base_strain_per_m).norm() < 1e-9);
    // f32: the same answer within 10 um.
    let (rod32, tendons32) = two_section::<f32>(4, 40);
    let (_, _, single) = continuous(rod32, &tendons32, &TENSIONS, TIP_FORCE);
    let tip =
        (single.equilibrium.tip_position_m.map(f64::from) - cold.equilibrium.tip_position_m).norm();
    let path = single
        .path_m
        .iter()
        .zip(&cold.path_m)
        .fold(0.0f64, |m, (a, b)| m.max((f64::from(*a) - b).abs()));
    eprintln!("f32 - f64: tip {tip:.2e} m, paths {path:.2e} m");
    assert!(
        tip < 1e-5 && path < 1e-5,
        "f32: tip {tip:e} m, paths {path:e} m"
    );
}

/// Inextensible (Kirchhoff) rods: both variants give the arc with no stretch.
#[test]
fn tendon_variants_kirchhoff_arc() {
    let tau = 2.0;
    let (rod, tendons) = reference::tendon_dense::<f64>(4, 100).unwrap();
    let mut rod = rod;
    rod.strain_model = model_core::StrainModel::Kirchhoff;
    let kappa = tau * 0.01 / (54e9 * std::f64::consts::PI * 1.4e-3f64.powi(4) / 64.0);
    let tip = Vector3::new((kappa * 0.2).sin(), 1.0 - (kappa * 0.2).cos(), 0.0) / kappa;
    let len = 0.2 * (1.0 - kappa * 0.01);
    let (_, _, cont) = continuous(rod.clone(), &tendons, &[tau], [0.0; 3]);
    let arcs = pcc(rod, &tendons, &[tau], [0.0; 3]);
    for (name, eq, tol) in [("continuous", &cont, 1e-11), ("PCC", &arcs, 1e-15)] {
        let off = (eq.equilibrium.tip_position_m - tip).norm();
        let off_l = (eq.path_m[0] - len).abs();
        assert!(
            off < tol && off_l < tol,
            "{name}: tip {off:e}, length {off_l:e}"
        );
    }
}

/// Bad input is a typed error, never a panic, for both variants.
#[test]
fn tendon_variants_refuse_bad_input() {
    let (rod, tendons) = reference::tendon_bench::<f64>(20).unwrap();
    let model = Model::<f64>::new(rod).unwrap();
    let set = Tendons::new(&model, &tendons).unwrap();
    let zero = TipLoad::zero();
    for bad in [
        vec![-1.0, 0.0, 0.0],
        vec![f64::NAN, 0.0, 0.0],
        vec![1.0, 1.0],
    ] {
        assert!(
            model
                .solve_tendons_continuous(&set, &bad, &zero, None, &settings())
                .is_err()
        );
        assert!(
            model
                .solve_tendons_pcc_ignoring_loads(&set, &bad, &zero)
                .is_err()
        );
    }
    let nan_load = TipLoad::force(Vector3::new(f64::NAN, 0.0, 0.0));
    assert!(
        model
            .solve_tendons_pcc_ignoring_loads(&set, &[1.0; 3], &nan_load)
            .is_err()
    );
    let (other, _) = reference::tendon_dense::<f64>(4, 20).unwrap();
    let other = Model::<f64>::new(other).unwrap();
    assert!(
        other
            .solve_tendons_continuous(&set, &[1.0; 3], &zero, None, &settings())
            .is_err()
    );
    assert!(
        other
            .solve_tendons_pcc_ignoring_loads(&set, &[1.0; 3], &zero)
            .is_err()
    );
}
