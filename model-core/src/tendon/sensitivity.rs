//! How an equilibrium under tendons moves with the tensions and the tip force: the changes of the
//! unstretched lengths the tendons need (path and stretch together) and of the tip position, by forward differences of warm solves (each a few sweeps
//! from the equilibrium it perturbs). Both the displacement-controlled solve and the inverse need
//! them.
//!
//! The step is a fixed fraction (`max(2 eps^(1/3), 1e-3)`) of the tension that bends the rod by about a radian
//! (`E I / (L r)`) and of the force that does (`E I / L^2`): large enough to stand above the
//! solves' own error (their tolerance) in f32 and along weakly seen directions, small enough that
//! the curvature of the map costs a fraction of that in f64.

use nalgebra::{SMatrix, SVector};

use super::{MAX_TENDONS, TendonEquilibrium, Tendons};
use crate::Scalar;
use crate::error::ModelError;
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::report::Termination;
use crate::shooting::ShootingSettings;

/// The changes of the tendons' needed unstretched lengths (rows, m) and of the tip position (m) per
/// unit change of each tension (N) and tip force component (N).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sensitivity<T> {
    pub d_length_d_tension: SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    pub d_length_d_force: SMatrix<T, MAX_TENDONS, 3>,
    pub d_tip_d_tension: SMatrix<T, 3, MAX_TENDONS>,
    pub d_tip_d_force: SMatrix<T, 3, 3>,
    /// The base's internal force (rows 0-2, N) and moment (rows 3-5, N m) per unit tension.
    pub d_base_d_tension: SMatrix<T, 6, MAX_TENDONS>,
    /// Sweeps spent.
    pub sweeps: u32,
}

/// The tension, N, that bends `model`'s rod by about a radian through a tendon at the largest
/// offset of `tendons`.
pub(crate) fn tension_scale_n<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    tendons: &Tendons<T>,
) -> T {
    let radius = tendons.largest_offset_m();
    let radius = if radius > T::zero() {
        radius
    } else {
        model.length_m()
    };
    model.moment_scale_nm() / radius
}

/// The relative forward-difference step, `max(2 eps^(1/3), 1e-3)`: the solves' own error (their
/// tolerance, about `1e-11 L` in f64) over the step must stay small where the lengths see a direction
/// weakly (an axial tip force changes them a thousand times less than a lateral one); the truncation
/// error, about the step relative, only slows the Newton-type iterations that use it, by that factor
/// per iteration.
fn relative_step<T: Scalar>() -> T {
    (T::default_epsilon().powf(T::lit(1.0 / 3.0)) * T::lit(2.0)).max(T::lit(1e-3))
}

/// The sensitivity of `at` (a converged equilibrium of `tendons` on `model`, under `load`) to the
/// tensions and, when `with_force`, to the tip force.
pub(crate) fn sensitivity<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    tendons: &Tendons<T>,
    at: &TendonEquilibrium<T>,
    load: &TipLoad<T>,
    with_force: bool,
    settings: &ShootingSettings<T>,
) -> Result<Result<Sensitivity<T>, Termination>, ModelError> {
    let mut out = Sensitivity {
        d_length_d_tension: SMatrix::zeros(),
        d_length_d_force: SMatrix::zeros(),
        d_tip_d_tension: SMatrix::zeros(),
        d_tip_d_force: SMatrix::zeros(),
        d_base_d_tension: SMatrix::zeros(),
        sweeps: 0,
    };
    let count = tendons.len();
    let tau_step = tension_scale_n(model, tendons) * relative_step::<T>();
    let force_step = model.moment_scale_nm() / model.length_m() * relative_step::<T>();
    let base_tip = at.equilibrium.tip_position_m;
    let columns = count + if with_force { 3 } else { 0 };
    for c in 0..columns {
        let mut tau = [T::zero(); MAX_TENDONS];
        for (t, a) in tau.iter_mut().zip(&at.tensions_n) {
            *t = *a;
        }
        let mut perturbed = *load;
        let h = if c < count {
            if let Some(t) = tau.get_mut(c) {
                *t += tau_step;
            }
            tau_step
        } else {
            perturbed.force_n += crate::ode::unit::<T, 3>(c - count) * force_step;
            force_step
        };
        let tau = tau.get(..count).unwrap_or(&[]);
        let moved = model.solve_tendons(tendons, tau, &perturbed, Some(at), settings)?;
        out.sweeps += u32::from(moved.equilibrium.report.sweeps);
        if !moved.is_success()
            || moved.unstretched_m.len() != count
            || at.unstretched_m.len() != count
        {
            return Ok(Err(moved.equilibrium.report.termination));
        }
        let d_tip = (moved.equilibrium.tip_position_m - base_tip) / h;
        let d_length = SVector::<T, MAX_TENDONS>::from_fn(|j, _| {
            match (moved.unstretched_m.get(j), at.unstretched_m.get(j)) {
                (Some(a), Some(b)) => (*a - *b) / h,
                _ => T::zero(),
            }
        });
        if c < count {
            out.d_base_d_tension
                .set_column(c, &((moved.base() - at.base()) / h));
            out.d_length_d_tension.set_column(c, &d_length);
            out.d_tip_d_tension.set_column(c, &d_tip);
        } else {
            out.d_length_d_force.set_column(c - count, &d_length);
            out.d_tip_d_force.set_column(c - count, &d_tip);
        }
    }
    Ok(Ok(out))
}
