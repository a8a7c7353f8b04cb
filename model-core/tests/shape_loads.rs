//! Loads that read the shape, through the rod equations with the internal force and moment as
//! states (`Model::solve_with`).
//!
//! 1. Without such loads those equations must give the dead-load fast path's equilibrium: the same
//!    rod, the same grid, other states, other unknowns, another Jacobian.
//! 2. A load this file defines and model-core has never seen (a spring pulling one guide toward a
//!    fixed anchor) is a new type implementing `ShapeLoad`, nothing else; it is checked against two
//!    independent references: the closed form of a cantilever on a spring at small deflection, and,
//!    at large deflection, a fixed point of dead-load solves (the spring's force applied as a dead
//!    point force, updated from the shape until it no longer changes).

use model_checks::reference::{self, Exp2Mass};
use model_core::{
    Equilibrium, Model, NoShapeLoad, NodePose, PointLoad, PoseChange, Rod, Scalar, ShapeLoad,
    ShapePoint, ShootingSettings, Stability, Start, TipLoad, Wrench,
};
use nalgebra::Vector3;

/// A linear spring from the hole-less centre of guide `guide` to a fixed anchor (global frame):
/// force `-k (p - anchor)` on the rod at that guide. Conservative; not a dead load.
#[derive(Clone, Copy, Debug)]
struct Spring<T> {
    guide: usize,
    stiffness_n_per_m: T,
    anchor_m: Vector3<T>,
}

impl<T: Scalar> ShapeLoad<T> for Spring<T> {
    fn wrench(&self, node: &NodePose<T>, load_scale: T) -> Wrench<T> {
        if node.guide != Some(self.guide) {
            return Wrench::zero();
        }
        Wrench {
            force_n: (node.position_m - self.anchor_m) * (-self.stiffness_n_per_m * load_scale),
            moment_nm: Vector3::zeros(),
        }
    }

    fn wrench_change(&self, node: &NodePose<T>, load_scale: T, d: &PoseChange<T>) -> Wrench<T> {
        if node.guide != Some(self.guide) {
            return Wrench::zero();
        }
        Wrench {
            force_n: d.position_m * (-self.stiffness_n_per_m * load_scale),
            moment_nm: Vector3::zeros(),
        }
    }
}

fn settings<T: Scalar>() -> ShootingSettings<T> {
    ShootingSettings::default()
}

fn converged<T: Scalar>(eq: &Equilibrium<T>) {
    assert!(eq.report.termination.is_success(), "{:?}", eq.report);
}

fn f64s<T: Scalar>(v: &Vector3<T>) -> Vector3<f64> {
    v.map(Scalar::to_f64)
}

/// The golden 3D bench's rows (gravity, five guides, three cables, 3D tip forces): the force-as-state
/// equations land on the fast path's equilibrium, tip and cable lengths to the solves' tolerance in f64 and to
/// the f32 solve's resolution in f32.
fn force_state_matches_the_dead_load_path<T: Scalar>(tip_tol_m: f64, cable_tol_m: f64) {
    let model = Model::<T>::new(reference::golden_bench(100).unwrap()).unwrap();
    let mut rows = 0;
    for row in reference::golden_rows() {
        let row = row.unwrap();
        let load = TipLoad::force(row.force_n.map(T::lit).into());
        let fast = model.solve(&load, Start::Cold, &settings()).unwrap();
        let state = model
            .solve_with(&NoShapeLoad, &load, None, &settings())
            .unwrap();
        converged(&fast);
        converged(&state);
        // These equations have no energy test yet: they say so.
        assert_eq!(state.report.stability, Stability::Unchecked);
        let gap = (f64s(&fast.tip_position_m) - f64s(&state.tip_position_m)).norm();
        assert!(gap < tip_tol_m, "row {rows}: tips {gap:e} m apart");
        for (a, b) in fast.cable_lengths_m.iter().zip(&state.cable_lengths_m) {
            let d = (a.to_f64() - b.to_f64()).abs();
            assert!(d < cable_tol_m, "row {rows}: cable lengths {d:e} m apart");
        }
        // The base wrench: the clamp's reaction is the sum of the loads.
        let weight =
            model_core::mass::total_mass_kg(model.rod()).to_f64() * f64s(&model.rod().gravity_m_s2);
        let expected = Vector3::from(row.force_n) + weight;
        let force_gap = (f64s(&state.base_force_n) - expected).norm();
        assert!(
            force_gap < 1e3 * tip_tol_m,
            "row {rows}: base force {force_gap:e} N off"
        );
        let strain_gap = (f64s(&fast.base_strain_per_m) - f64s(&state.base_strain_per_m)).norm();
        assert!(strain_gap * reference::FREE_LENGTH_M < 1e2 * tip_tol_m);
        rows += 1;
    }
    assert_eq!(rows, 4);
}

#[test]
fn force_state_matches_the_dead_load_path_f64() {
    force_state_matches_the_dead_load_path::<f64>(5e-11, 5e-11);
}

#[test]
fn force_state_matches_the_dead_load_path_f32() {
    force_state_matches_the_dead_load_path::<f32>(5e-5, 1e-5);
}

/// Two sections of different stiffness, a hung mass and a point moment at the transition, gravity:
/// the jumps of the force-as-state equations (in `n` and `m`) against those of the fast path (in the
/// closed-form force and in `u`), with the shape compared along the whole rod.
#[test]
fn force_state_jumps_match_the_dead_load_path() {
    let mut rod: Rod<f64> = reference::exp1_bench(reference::EXP1_YOUNGS_MODULUS_PA, 80).unwrap();
    if let Some(distal) = rod.sections.get_mut(1) {
        distal.stiffness.bending_torsion_nm2 *= 0.6;
        distal.stiffness.shear_axial_n *= 0.6;
    }
    rod.push_load(PointLoad {
        s_m: reference::EXP1_TRANSITION_M,
        mass_kg: 0.02,
        force_n: Vector3::new(0.0, 0.0, 0.05),
        moment_nm: Vector3::new(0.004, 0.0, 0.0),
    })
    .unwrap();
    let model = Model::<f64>::new(rod).unwrap();
    let load = TipLoad::force(Vector3::new(0.02, -0.05, 0.03));
    let fast = model.solve(&load, Start::Cold, &settings()).unwrap();
    let state = model
        .solve_with(&NoShapeLoad, &load, None, &settings())
        .unwrap();
    converged(&fast);
    converged(&state);
    let s: Vec<f64> = (0..=13).map(|k| 0.39 * k as f64 / 13.0).collect();
    let mut a = vec![ShapePoint::default(); s.len()];
    let mut b = vec![ShapePoint::default(); s.len()];
    model.shape(&fast, &s, &mut a).unwrap();
    model.shape_with(&NoShapeLoad, &state, &s, &mut b).unwrap();
    for (p, q) in a.iter().zip(&b) {
        let gap = (p.position_m - q.position_m).norm();
        assert!(gap < 5e-11, "s = {}: {gap:e} m apart", p.s_m);
        let strain_gap = (p.strain_per_m - q.strain_per_m).norm();
        assert!(
            strain_gap < 1e-9,
            "s = {}: strain {strain_gap:e} /m apart",
            p.s_m
        );
    }
}

/// A weightless straight cantilever whose tip is pulled toward an anchor `a` (offset `d` across the
/// rod from the unloaded tip) by a spring of stiffness `k`: at small deflection the tip moves by
/// `d k / (k + k_b)`, `k_b = 1 / (L^3 / 3 E I + L / G A)` the cantilever's own tip stiffness
/// (Timoshenko, shear coefficient 1).
#[test]
fn spring_at_the_tip_matches_the_linear_cantilever() {
    let mut rod: Rod<f64> = reference::exp2_bench(Exp2Mass::Average, 200, 0).unwrap();
    rod.gravity_m_s2 = Vector3::zeros();
    let model = Model::<f64>::new(rod).unwrap();
    let stiffness = reference::nitinol_stiffness::<f64>(reference::YOUNGS_MODULUS_PA).unwrap();
    let (ei, ga) = (stiffness.bending_torsion_nm2.x, stiffness.shear_axial_n.x);
    let l = reference::FREE_LENGTH_M;
    let k_beam = 1.0 / (l * l * l / (3.0 * ei) + l / ga);
    let last_guide = model.rod().guides.len() - 1;
    // The spring sits at the last guide; put the anchor's offset there and compare there.
    let s_guide = model.rod().guides[last_guide].s_m;
    let k_guide = 1.0 / (s_guide * s_guide * s_guide / (3.0 * ei) + s_guide / ga);
    for k in [0.05 * k_beam, k_beam, 20.0 * k_beam] {
        let d = 1e-5;
        let spring = Spring {
            guide: last_guide,
            stiffness_n_per_m: k,
            anchor_m: Vector3::new(s_guide, d, 0.0),
        };
        let eq = model
            .solve_with(&spring, &TipLoad::zero(), None, &settings())
            .unwrap();
        converged(&eq);
        let mut p = [ShapePoint::default()];
        model.shape_with(&spring, &eq, &[s_guide], &mut p).unwrap();
        let expected = d * k / (k + k_guide);
        let got = p[0].position_m.y;
        assert!(
            (got - expected).abs() < 1e-6 * expected,
            "k = {k:.4} N/m: guide moved {got:e} m, linear cantilever {expected:e} m"
        );
        assert!(p[0].position_m.z.abs() < 1e-15);
    }
}

/// At large deflection (the thesis bench under gravity, its middle guide pulled up and sideways
/// toward an anchor 15 cm away): the equilibrium is the fixed point of dead-load solves, where the
/// spring's force, applied as a dead point force at the guide, is the force the spring exerts at the
/// shape it produces. Checked to 1e-10 m along the whole rod in f64, and the f32 solve within 0.05 mm.
#[test]
fn spring_matches_a_fixed_point_of_dead_load_solves() {
    let rod: Rod<f64> = reference::exp2_bench(Exp2Mass::Accurate, 100, 3).unwrap();
    let guide = 2;
    let s_guide = rod.guides[guide].s_m;
    let spring = Spring {
        guide,
        stiffness_n_per_m: 0.6,
        anchor_m: Vector3::new(0.12, 0.1, 0.08),
    };
    let load = TipLoad::force(Vector3::new(0.0, -0.0402 * reference::GRAVITY_M_S2, 0.0));
    let model = Model::<f64>::new(rod.clone()).unwrap();
    let eq = model.solve_with(&spring, &load, None, &settings()).unwrap();
    converged(&eq);
    assert!(
        eq.report.load_steps > 0,
        "a cold solve follows the branch from the unloaded rod"
    );

    // The reference: dead-load solves, the spring's force at the last shape as a point force.
    let mut force = Vector3::zeros();
    let mut start = Start::Cold;
    let mut reference = None;
    for iteration in 0.. {
        assert!(iteration < 400, "the fixed point did not settle");
        let mut dead = rod.clone();
        dead.push_load(PointLoad::force(s_guide, force)).unwrap();
        let dead = Model::<f64>::new(dead).unwrap();
        let solved = dead.solve(&load, start, &settings()).unwrap();
        converged(&solved);
        start = Start::Warm(solved.base_strain_per_m);
        let mut at = [ShapePoint::default()];
        dead.shape(&solved, &[s_guide], &mut at).unwrap();
        let next = (at[0].position_m - spring.anchor_m) * -spring.stiffness_n_per_m;
        let change = (next - force).norm();
        // Relaxed fixed-point iteration: the spring's contraction factor here is about 0.7.
        force += (next - force) * 0.5;
        if change < 1e-13 {
            reference = Some((dead, solved));
            break;
        }
    }
    let (dead, solved) = reference.unwrap();
    // The deflection is large: the guide moves centimetres.
    let mut straight = [ShapePoint::default()];
    dead.shape(&solved, &[s_guide], &mut straight).unwrap();
    assert!((straight[0].position_m - Vector3::new(s_guide, 0.0, 0.0)).norm() > 0.02);

    let s: Vec<f64> = (0..=20).map(|k| 0.39 * k as f64 / 20.0).collect();
    let mut a = vec![ShapePoint::default(); s.len()];
    let mut b = vec![ShapePoint::default(); s.len()];
    dead.shape(&solved, &s, &mut a).unwrap();
    model.shape_with(&spring, &eq, &s, &mut b).unwrap();
    for (p, q) in a.iter().zip(&b) {
        let gap = (p.position_m - q.position_m).norm();
        assert!(gap < 1e-10, "s = {}: {gap:e} m apart", p.s_m);
    }
    for (x, y) in solved.cable_lengths_m.iter().zip(&eq.cable_lengths_m) {
        assert!((x - y).abs() < 1e-10);
    }

    // f32: the same scene, the same load type (generic over the scalar).
    let rod32: Rod<f32> = reference::exp2_bench(Exp2Mass::Accurate, 100, 3).unwrap();
    let model32 = Model::<f32>::new(rod32).unwrap();
    let spring32 = Spring {
        guide,
        stiffness_n_per_m: 0.6f32,
        anchor_m: spring.anchor_m.map(|x| x as f32),
    };
    let load32 = TipLoad::force(load.force_n.map(|x| x as f32));
    let eq32 = model32
        .solve_with(&spring32, &load32, None, &settings())
        .unwrap();
    converged(&eq32);
    let gap = (f64s(&eq32.tip_position_m) - eq.tip_position_m).norm();
    assert!(gap < 5e-5, "f32 tip {gap:e} m from f64");

    // A warm start from the answer converges at once to the same equilibrium.
    let again = model
        .solve_with(&spring, &load, Some(&eq), &settings())
        .unwrap();
    converged(&again);
    assert!((again.tip_position_m - eq.tip_position_m).norm() < 1e-12);
    assert!(again.report.sweeps <= 2, "{:?}", again.report);
}

/// Invalid input to the force-as-state entry points is a typed error, never a panic.
#[test]
fn force_state_refuses_invalid_input() {
    let model = Model::<f64>::new(reference::golden_bench(20).unwrap()).unwrap();
    let nan = TipLoad::force(Vector3::new(f64::NAN, 0.0, 0.0));
    assert!(
        model
            .solve_with(&NoShapeLoad, &nan, None, &settings())
            .is_err()
    );
    let eq = model
        .solve_with(&NoShapeLoad, &TipLoad::zero(), None, &settings())
        .unwrap();
    let mut out = [ShapePoint::default(); 1];
    assert!(
        model
            .shape_with(&NoShapeLoad, &eq, &[0.5], &mut out)
            .is_err()
    );
    let mut bad = eq.clone();
    bad.base_force_n.x = f64::INFINITY;
    assert!(
        model
            .solve_with(&NoShapeLoad, &TipLoad::zero(), Some(&bad), &settings())
            .is_err()
    );
}
