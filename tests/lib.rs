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
