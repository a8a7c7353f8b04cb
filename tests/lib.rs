//! Shared helpers for the cross-crate tests in this directory. The reference data they read live in
//! `data/` (the thesis's tables and the independent golden reference), committed once and embedded by
//! `model_checks::reference`.

use model_core::{Model, Scalar, ShootingSettings, Start, TipLoad};
use nalgebra::Vector3;

/// Solves cold and returns the tip, panicking (this is test code) if the solve did not converge.
pub fn tip<T: Scalar>(model: &Model<T>, load: &TipLoad<T>) -> Vector3<f64> {
    let eq = model
        .solve(load, Start::Cold, &ShootingSettings::default())
        .expect("valid input");
    assert!(eq.report.termination.is_success(), "{:?}", eq.report);
    eq.tip_position_m.map(Scalar::to_f64)
}

/// A tip weight of `grams` along -y (the thesis benches), N.
pub fn weight<T: Scalar>(grams: f64) -> TipLoad<T> {
    TipLoad::force(Vector3::new(
        T::zero(),
        T::lit(-grams * 1e-3 * model_checks::reference::GRAVITY_M_S2),
        T::zero(),
    ))
}

/// The circular arc of one tendon on the golden dense rod (`model_checks::reference::tendon_dense`;
/// `tendon_dense_limit.csv`'s header), the continuous limit, exact here: curvature `tau r / E I` per
/// reference length, stretch `1 - tau / E A`; the tip, its tangent and the tendon length
/// `L (stretch - kappa r)`.
pub fn tendon_arc(tau_n: f64) -> (Vector3<f64>, Vector3<f64>, f64) {
    let (e, d, r, l): (f64, f64, f64, f64) = (54e9, 1.4e-3, 0.01, 0.2);
    let i = std::f64::consts::PI * d.powi(4) / 64.0;
    let a = std::f64::consts::PI * d * d / 4.0;
    let kappa = tau_n * r / (e * i);
    let stretch = 1.0 - tau_n / (e * a);
    (
        Vector3::new(
            stretch / kappa * (kappa * l).sin(),
            stretch / kappa * (1.0 - (kappa * l).cos()),
            0.0,
        ),
        Vector3::new((kappa * l).cos(), (kappa * l).sin(), 0.0),
        l * (stretch - kappa * r),
    )
}
