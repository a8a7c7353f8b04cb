//! The inverse problem: the tip load that explains measured cable lengths (`MODEL.md`, "The
//! inverse").
//!
//! | concern | file |
//! | --- | --- |
//! | the load as a function of the unknown parameters, the prior | `basis.rs` |
//! | the reduced problem (variable projection), its steps and stopping rules, the cold solve | `reduced.rs` |
//! | quality: identifiability, posterior uncertainty, the verdict | `quality.rs` |
//! | the warm-started estimator for a control loop | `estimator.rs` |
//!
//! The tip load is `offset + B p` ([`LoadBasis`]: a free tip force, a force of unknown size along a
//! known direction, ...). `G`, the sensitivity of the cable lengths to the load with the shape
//! re-solved, gives the answer's quality: covariance, singular values and condition number, and the
//! implied force and tip-position uncertainty. Where the data cannot determine the load (an axial
//! force, fewer cables than unknowns, a cable whose length saturates) the estimate says so.
//!
//! [`Estimator`] is the warm-started path for a control loop: it keeps the last answer and its
//! Jacobian, and alternates sweeps with tangents and plain sweeps (chord steps), a predictor from its
//! last moves first.

mod basis;
mod estimator;
mod quality;
mod reduced;

use nalgebra::{Matrix3, SVector, Vector3};

pub use basis::{LoadBasis, ParamCount, Params};
pub use estimator::{Estimator, EstimatorSettings};
pub use quality::{Determination, Quality};

use crate::error::{ModelError, finite, finite_vec, positive};
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::report::SolveReport;
use crate::shooting::{ShootingSettings, TipLoad};
use crate::solve::newton::Work;
use crate::solve::stopping::default_tolerance;
use crate::{MAX_CABLES, Scalar};
use reduced::{Point, Problem};

/// Cable-length mismatches and other per-cable vectors, zero beyond the rod's cables.
pub type CableVector<T> = SVector<T, MAX_CABLES>;

/// Settings of the inverse solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseSettings<T> {
    /// Iterations (each one sweep with six tangents).
    pub max_iterations: u16,
    /// Most sweeps one estimate may take, the cold forward solve at its start included: the bound on
    /// its cost, whatever the measurements (data no load explains included). A step begun within it
    /// finishes (its trial sweep and the projection back onto the equilibrium, 9 sweeps at most), so
    /// an estimate takes at most `max_sweeps + 9`. Reaching it ends the solve with
    /// [`crate::Termination::IterationLimit`], or, when only the search for other answers is cut
    /// short, the verdict [`Determination::Unverified`].
    pub max_sweeps: u16,
    /// Tolerance on the dimensionless tip-moment residual (as in [`ShootingSettings::tolerance`]).
    pub tolerance: T,
    /// Cable mismatch below which the fit is exact, m.
    pub length_tolerance_m: T,
    /// A step that moves the fit (data and prior) by less than this many standard deviations, and the
    /// tip by less than `tip_tolerance_m`, ends the solve. Raised to what the scalar type resolves.
    pub step_tolerance_sigma: T,
    /// Standard deviation of one cable-length measurement, m (for an encoder of resolution `q`,
    /// `q / sqrt(12)`; see [`InverseSettings::with_resolution`]).
    pub length_std_m: T,
    /// The model's own error in a cable length, m (one standard deviation): its discretisation on
    /// this grid against the converged model (`report/accuracy_cost.md` measures it per step count).
    /// Added to the measurement's in quadrature, with the floor of the scalar type (the shooting
    /// tolerance times the cable radius: 0.24 um in f32 on the bench, negligible in f64), so that
    /// neither the fit nor the reported uncertainty claims more than the model resolves.
    pub model_length_std_m: T,
    /// The model's own error in the tip position, m (one standard deviation), added to the reported
    /// tip uncertainty in quadrature with the scalar type's floor (the shooting tolerance times the
    /// rod's length: 9.4 um in f32 on the bench).
    pub model_tip_std_m: T,
    /// A load component whose standard deviation exceeds this, N, makes the estimate
    /// [`Determination::Weak`].
    pub max_force_std_n: T,
    /// Trust region: largest change of base strain per iteration, as an angle `|du0| L`, rad.
    pub max_rotation_step_rad: T,
    /// Check the stability of the answer (free: uses the tangents already computed).
    pub check_stability: bool,
    /// The solve stops when the next step would move the tip by less than this, m (and the fit by
    /// less than `step_tolerance_sigma`). Raised to what the scalar type resolves: `L` times the
    /// default shooting tolerance (9.4 um for f32 on a 39 cm rod).
    pub tip_tolerance_m: T,
    /// A priori standard deviation of each load parameter, in units of the rod's buckling scale
    /// (`E I / L^2` for a force, `E I / L` for a moment); infinity for none. With a prior the answer is
    /// the maximum a posteriori estimate: it keeps a direction the cables barely see (an axial force,
    /// whose effect near buckling is strongly nonlinear) from wandering to one of several far-apart
    /// fits, and changes well-determined directions negligibly. The identifiability figures in
    /// [`Quality`] (singular values, condition number, [`Determination`]) stay those of the data alone.
    pub prior_std_scale: T,
    /// How far, in buckling scales, the search for other answers explaining the measurements reaches
    /// (at least three times the answer's own load): an answer is called determined only when no other
    /// answer within this reach fits the data about as well. A load beyond it that fits as well as the
    /// answer goes unseen: set it to the largest load the robot can meet.
    pub scan_reach: T,
}

impl<T: Scalar> Default for InverseSettings<T> {
    fn default() -> Self {
        let eps = T::default_epsilon();
        Self {
            max_iterations: 60,
            max_sweeps: 400,
            tolerance: default_tolerance(),
            length_tolerance_m: (eps * T::lit(10.0)).max(T::lit(1e-12)),
            step_tolerance_sigma: T::lit(1e-4),
            length_std_m: T::lit(1e-6),
            model_length_std_m: T::zero(),
            model_tip_std_m: T::zero(),
            max_force_std_n: T::lit(0.05),
            max_rotation_step_rad: T::lit(1.0),
            check_stability: true,
            tip_tolerance_m: T::lit(1e-7),
            prior_std_scale: T::lit(10.0),
            scan_reach: T::lit(48.0),
        }
    }
}

impl<T: Scalar> InverseSettings<T> {
    /// Default settings for length measurements quantised at `resolution_m` (std `resolution / sqrt 12`).
    pub fn with_resolution(resolution_m: T) -> Self {
        Self {
            length_std_m: resolution_m / T::lit(12.0).sqrt(),
            ..Self::default()
        }
    }

    pub(crate) fn validate(&self) -> Result<(), ModelError> {
        if self.max_sweeps == 0 {
            return Err(ModelError::NotPositive("inverse sweep budget"));
        }
        positive(self.tolerance, "inverse tolerance")?;
        positive(self.length_tolerance_m, "length tolerance")?;
        positive(self.step_tolerance_sigma, "step tolerance")?;
        positive(self.length_std_m, "length standard deviation")?;
        crate::error::non_negative(self.model_length_std_m, "model length standard deviation")?;
        crate::error::non_negative(self.model_tip_std_m, "model tip standard deviation")?;
        positive(self.max_force_std_n, "force standard deviation limit")?;
        positive(self.max_rotation_step_rad, "trust region")?;
        positive(self.tip_tolerance_m, "tip tolerance")?;
        positive(self.scan_reach, "scan reach")?;
        // Infinity (no prior) is allowed; NaN, zero and negative are not.
        if self.prior_std_scale.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
            return Err(ModelError::NotPositive("prior standard deviation"));
        }
        Ok(())
    }
}

/// An estimate of the tip load and the shape it implies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate<T, const P: usize> {
    /// The load parameters.
    pub params: SVector<T, P>,
    /// The tip load they give.
    pub load: TipLoad<T>,
    /// The base strain of the equilibrium, 1/m.
    pub base_strain_per_m: Vector3<T>,
    /// Tip position, m.
    pub tip_position_m: Vector3<T>,
    /// Tip frame.
    pub tip_rotation: Matrix3<T>,
    /// Model minus measured cable length, m (zero beyond the rod's cables).
    pub cable_residual_m: CableVector<T>,
    /// How the solve went. Use the estimate only when `report.termination.is_success()`.
    pub report: SolveReport<T>,
    /// How well the data determine it.
    pub quality: Quality<T, P>,
}

/// Where an inverse solve starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InverseStart<T, const P: usize> {
    /// From load parameters (the shape is solved cold for them first).
    Params(SVector<T, P>),
    /// From a previous estimate's parameters and base strain.
    Warm {
        /// Load parameters.
        params: SVector<T, P>,
        /// Base strain, 1/m.
        base_strain_per_m: Vector3<T>,
    },
}

pub(crate) fn validate_measurements<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    measured_m: &[T],
) -> Result<CableVector<T>, ModelError> {
    let rod = model.rod();
    if measured_m.len() != rod.cables.len() {
        return Err(ModelError::Mismatch("measured cable lengths and cables"));
    }
    if measured_m.is_empty() {
        return Err(ModelError::Empty("cable lengths"));
    }
    let mut out = CableVector::zeros();
    for (c, (&length, cable)) in measured_m.iter().zip(rod.cables.iter()).enumerate() {
        positive(length, "cable length")?;
        if length > cable_length_bound_m(rod, cable) {
            return Err(ModelError::OutOfRange(
                "cable length (longer than the rod can produce)",
            ));
        }
        if let Some(slot) = out.get_mut(c) {
            *slot = length;
        }
    }
    Ok(out)
}

/// An upper bound on a cable's length: every chord between consecutive holes is at most the arc
/// between them stretched by 10 % plus twice the hole offset.
pub fn cable_length_bound_m<T: Scalar>(rod: &crate::Rod<T>, cable: &crate::Cable<T>) -> T {
    let mut previous: Option<T> = None;
    let mut bound = T::zero();
    let holes = rod
        .guides
        .iter()
        .map(|g| g.s_m)
        .filter(|s| *s <= cable.end_m)
        .chain(core::iter::once(cable.end_m));
    for s in holes {
        if let Some(prev) = previous {
            bound += (s - prev) * T::lit(1.1) + cable.radius_m() * T::lit(2.0);
        }
        previous = Some(s);
    }
    bound
}

/// Estimates the load parameters from measured cable lengths (one per cable, m), starting from `start`.
///
/// Fails only on invalid input. The answer is usable when `report.termination.is_success()`; how
/// well the data determine it is in `quality`.
pub fn estimate<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>(
    model: &Model<T, A, NODES>,
    basis: &LoadBasis<T, P>,
    measured_m: &[T],
    start: InverseStart<T, P>,
    settings: &InverseSettings<T>,
) -> Result<Estimate<T, P>, ModelError>
where
    Params: ParamCount<T, P>,
{
    basis.validate()?;
    settings.validate()?;
    let measured = validate_measurements(model, measured_m)?;
    let problem = Problem::new(model, *basis, measured, *settings);
    let mut work = Work::default();
    let x = match start {
        InverseStart::Params(p) => {
            for v in p.iter() {
                finite(*v, "start parameters")?;
            }
            let shooting = ShootingSettings {
                tolerance: settings.tolerance,
                max_rotation_step_rad: settings.max_rotation_step_rad,
                ..ShootingSettings::default()
            };
            let eq = model.solve_dead_load(&basis.load(&p), None, &shooting)?;
            work.iterations = eq.report.iterations;
            work.sweeps = eq.report.sweeps;
            let x = Point {
                u0: eq.base_strain_per_m,
                p,
            };
            if !eq.report.termination.is_success() {
                let lin = problem.linearize(&problem.full_sweep(&x));
                return Ok(problem.finish_unsearched(x, &lin, eq.report.termination, work));
            }
            x
        }
        InverseStart::Warm {
            params,
            base_strain_per_m,
        } => {
            finite_vec(&base_strain_per_m, "warm-start base strain")?;
            for v in params.iter() {
                finite(*v, "start parameters")?;
            }
            Point {
                u0: base_strain_per_m,
                p: params,
            }
        }
    };
    Ok(problem.solve(x, work))
}
