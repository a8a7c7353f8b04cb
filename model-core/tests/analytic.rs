//! The model against closed-form beam solutions, in f64 and f32.
//!
//! Each case picks loads where the closed form is exact or its neglected terms are far below the
//! tolerance: small deflections for the beam formulas (the geometric correction is of order
//! `(P L^2 / E I)^2`), any size for the pure moment (an exact circle) and the axial load (an exact
//! extension, `n` stays axial). The model is shearable with `D = diag(G A, G A, E A)`, so the beam
//! formulas carry Timoshenko's shear term (shear coefficient 1): `P L / G A` for a tip load and
//! `w L^2 / 2 G A` for a uniform one (1e-5 of the bending term on this rod: enough to fail a 1e-6
//! tolerance if it were missing).

use model_core::{
    CrossSection, GuideMass, Material, Model, PointLoad, Rod, Scalar, Section, ShapePoint,
    ShootingSettings, Start, Stiffness, TipLoad,
};
use nalgebra::Vector3;

const LENGTH_M: f64 = 0.39;
const DIAMETER_M: f64 = 1.56e-3;
const YOUNGS_PA: f64 = 62.7e9;

fn stiffness<T: Scalar>() -> Stiffness<T> {
    let material = Material::isotropic(T::lit(YOUNGS_PA), T::lit(0.3)).unwrap();
    Stiffness::from_material(
        &material,
        &CrossSection::solid_circle(T::lit(DIAMETER_M)).unwrap(),
    )
    .unwrap()
}

fn bending_stiffness() -> f64 {
    stiffness::<f64>().bending_torsion_nm2.x
}

fn shear_stiffness() -> f64 {
    stiffness::<f64>().shear_axial_n.x
}

/// A straight rod along global +x, no gravity, `sections` equal sections.
fn rod<T: Scalar>(sections: usize, steps: u16, line_density: f64) -> Rod<T> {
    let mut rod = Rod::new();
    rod.gravity_m_s2 = Vector3::zeros();
    rod.guide_mass = GuideMass::Ignore;
    for _ in 0..sections {
        rod.push_section(Section {
            length_m: T::lit(LENGTH_M / sections as f64),
            stiffness: stiffness(),
            line_density_kg_per_m: T::lit(line_density),
            steps,
        })
        .unwrap();
    }
    rod
}

fn tip<T: Scalar>(model: &Model<T>, load: &TipLoad<T>) -> Vector3<f64> {
    let eq = model
        .solve(load, Start::Cold, &ShootingSettings::default())
        .unwrap();
    assert!(eq.report.termination.is_success(), "{:?}", eq.report);
    eq.tip_position_m.map(Scalar::to_f64)
}

fn cantilever_tip_load<T: Scalar>(load_ratio: f64, rel_tol: f64) {
    let model = Model::<T>::new(rod(1, 50, 0.0)).unwrap();
    let ei = bending_stiffness();
    let force = load_ratio * ei / (LENGTH_M * LENGTH_M); // P L^2 / EI
    let tip = tip(
        &model,
        &TipLoad::force(Vector3::new(T::zero(), T::lit(-force), T::zero())),
    );
    let expected = -force * LENGTH_M.powi(3) / (3.0 * ei) - force * LENGTH_M / shear_stiffness();
    let err = (tip.y - expected).abs() / expected.abs();
    assert!(
        err < rel_tol,
        "tip deflection {} vs P L^3 / 3EI + P L / GA = {expected} (rel err {err:e})",
        tip.y
    );
}

#[test]
fn cantilever_tip_load_matches_p_l3_over_3ei() {
    cantilever_tip_load::<f64>(1e-4, 1e-6);
    // f32 resolves positions to ~1e-7 m: a larger (still small) deflection keeps that below 1e-3.
    cantilever_tip_load::<f32>(1e-2, 1e-3);
}

fn cantilever_uniform_weight<T: Scalar>(load_ratio: f64, rel_tol: f64) {
    let ei = bending_stiffness();
    // w L^3 / EI = load_ratio: w is the weight per length.
    let weight_per_m = load_ratio * ei / LENGTH_M.powi(3);
    let mut r = rod::<T>(1, 50, weight_per_m / 9.81);
    r.gravity_m_s2 = Vector3::new(T::zero(), T::lit(-9.81), T::zero());
    let model = Model::<T>::new(r).unwrap();
    let tip = tip(&model, &TipLoad::zero());
    let expected = -weight_per_m * LENGTH_M.powi(4) / (8.0 * ei)
        - weight_per_m * LENGTH_M.powi(2) / (2.0 * shear_stiffness());
    let err = (tip.y - expected).abs() / expected.abs();
    assert!(
        err < rel_tol,
        "tip deflection {} vs w L^4 / 8EI + w L^2 / 2GA = {expected} (rel err {err:e})",
        tip.y
    );
}

#[test]
fn cantilever_uniform_weight_matches_w_l4_over_8ei() {
    cantilever_uniform_weight::<f64>(1e-4, 1e-6);
    cantilever_uniform_weight::<f32>(1e-2, 1e-3);
}

/// A tip moment about global z bends the rod into a circle of radius `EI / M` in the x-y plane,
/// at any angle: here 3/4 of a turn, so the tip points back past 180 degrees.
fn pure_moment_is_a_circle<T: Scalar>(tol_m: f64) {
    let model = Model::<T>::new(rod(1, 200, 0.0)).unwrap();
    let ei = bending_stiffness();
    let angle = 1.5 * core::f64::consts::PI;
    let moment = angle * ei / LENGTH_M;
    let load = TipLoad::moment(Vector3::new(T::zero(), T::zero(), T::lit(moment)));
    let eq = model
        .solve(&load, Start::Cold, &ShootingSettings::default())
        .unwrap();
    assert!(eq.report.termination.is_success(), "{:?}", eq.report);
    let radius = ei / moment;
    // Check the whole arc, not only the tip.
    let s: Vec<T> = (0..=10)
        .map(|i| T::lit(LENGTH_M * i as f64 / 10.0))
        .collect();
    let mut out = vec![ShapePoint::default(); s.len()];
    assert_eq!(model.shape(&eq, &s, &mut out).unwrap(), s.len());
    for p in &out {
        let phi = p.s_m.to_f64() / radius;
        let expected = Vector3::new(radius * phi.sin(), radius * (1.0 - phi.cos()), 0.0);
        let err = (p.position_m.map(Scalar::to_f64) - expected).norm();
        assert!(
            err < tol_m,
            "at s = {}: {:?} vs arc {:?} (err {err:e} m)",
            p.s_m.to_f64(),
            p.position_m,
            expected
        );
        let tangent = p.tangent().map(Scalar::to_f64);
        let tangent_err = (tangent - Vector3::new(phi.cos(), phi.sin(), 0.0)).norm();
        assert!(
            tangent_err < tol_m / LENGTH_M * 10.0,
            "tangent at s = {}: err {tangent_err:e}",
            p.s_m.to_f64()
        );
    }
}

#[test]
fn pure_tip_moment_bends_into_a_circle_of_radius_ei_over_m() {
    pure_moment_is_a_circle::<f64>(1e-9);
    pure_moment_is_a_circle::<f32>(2e-5);
}

fn axial_load_extends_by_fl_over_ea<T: Scalar>(rel_tol: f64) {
    let model = Model::<T>::new(rod(1, 20, 0.0)).unwrap();
    let ea = stiffness::<f64>().shear_axial_n.z;
    let force = 50.0;
    let tip = tip(
        &model,
        &TipLoad::force(Vector3::new(T::lit(force), T::zero(), T::zero())),
    );
    let expected = force * LENGTH_M / ea;
    let err = ((tip.x - LENGTH_M) - expected).abs() / expected;
    assert!(
        err < rel_tol,
        "extension {} vs F L / EA = {expected} (rel err {err:e})",
        tip.x - LENGTH_M
    );
}

#[test]
fn axial_load_extends_by_f_l_over_ea() {
    axial_load_extends_by_fl_over_ea::<f64>(1e-9);
    // 0.2 mm of extension on 0.39 m: f32 resolves the tip to ~3e-8 m.
    axial_load_extends_by_fl_over_ea::<f32>(1e-3);
}

/// Splitting a rod into sections of the same material changes nothing, under a 3D load with
/// gravity and a hung mass.
#[test]
fn two_sections_of_one_material_equal_one_section() {
    let build = |sections| {
        let mut r = rod::<f64>(sections, 60 / sections as u16, 0.013);
        r.gravity_m_s2 = Vector3::new(0.0, -9.81, 0.0);
        r.push_load(PointLoad::mass(LENGTH_M / 2.0, 0.01)).unwrap();
        Model::<f64>::new(r).unwrap()
    };
    let load = TipLoad::force(Vector3::new(0.02, -0.1, 0.05));
    let (one, two) = (tip(&build(1), &load), tip(&build(2), &load));
    assert!((one - two).norm() < 1e-12, "{one:?} vs {two:?}");
    // And it is not trivially equal: the hung mass moves the tip by centimetres.
    assert!((one - tip(&build(1), &TipLoad::zero())).norm() > 0.01);
}
