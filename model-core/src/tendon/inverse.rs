//! The inverse for tendon-driven robots (MODEL.md §6.4): from the spool encoders' displacements,
//! and optionally measured tensions (motor current, each with its own standard deviation), the
//! tensions, an external tip force and the shape, with the posterior uncertainty and a verdict.
//!
//! Unknowns `theta = (tau_1 .. tau_n, F)`, `tau >= 0`. Each evaluation solves the shape for `theta`
//! (warm), so the fit moves on the equilibrium manifold. Whitened residuals:
//!
//! - each taut tendon's displacement, `(d_hat(theta) - d) / s_d`, with
//!   `d_hat = U0 - N`, `N` the unstretched length the equilibrium needs (`actuation.rs`); a tendon at zero tension
//!   whose spool took in less than its path needs is slack, consistent whatever the slack: no residual;
//! - each measured tension, `(tau - tau_measured) / s_tau`;
//! - the prior on the tip force, `F / s_F`.
//!
//! The displacements are far more precise than anything else, so the fit is a variable projection:
//! for each tip force the tensions are the ones the displacements give (`actuation.rs`), and
//! Levenberg-Marquardt runs on the force alone against the measured tensions and the prior, with
//! `d tau / d F` from the implicit function theorem on the taut tendons' `N(tau, F) = U0 - d`
//! (Jacobians from `sensitivity.rs`). The posterior covariance is the inverse of the whitened
//! information of the full linearisation (a bounded SVD of the stacked system, not the normal
//! matrix). What the data alone determine comes from the data rows alone: with displacements only
//! there are `n` data for `n + 3` unknowns, so the tip force is not observable and the verdict says
//! [`Determination::Undetermined`], whatever the prior makes of it; with tensions measured too it
//! becomes observable (intrinsic force sensing). Consistency needs data to spare: without, the
//! verdict is at best [`Determination::Weak`]. After a fit the search for other answers restarts
//! from tip forces of a few buckling scales along each axis: another fit as good and far from the
//! answer makes it [`Determination::Ambiguous`]. A cold fit that does not converge from its start
//! (a valley where a tendon the measured tensions say is taut is slack) fits again from those
//! starts before it fails (MODEL.md §6.4).

use heapless::Vec;
use nalgebra::{SMatrix, SVector, Vector3};

use super::sensitivity::{Sensitivity, sensitivity};
use super::{
    DisplacementSettings, DisplacementSolve, MAX_TENDONS, TendonEquilibrium, TendonState, Tendons,
};
use crate::Scalar;
use crate::error::{ModelError, finite, positive};
use crate::inverse::Determination;
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::report::Termination;
use crate::shooting::ShootingSettings;

/// Iterations a restart of the search for other answers gets.
const RESTART_ITERATIONS: u16 = 12;

/// Most unknowns: every tension and three force components.
const MAX_UNKNOWNS: usize = MAX_TENDONS + 3;
/// Most whitened rows: displacements, tensions, the force prior.
const MAX_ROWS: usize = 2 * MAX_TENDONS + 3;

/// The displacement settings of the inverse's fits: without the answer's sensitivity, which each
/// fit forms itself, with the tip force, where it needs it.
fn fit_settings<T: Scalar>() -> DisplacementSettings<T> {
    DisplacementSettings {
        answer_sensitivity: false,
        ..DisplacementSettings::default()
    }
}

type Theta<T> = SVector<T, MAX_UNKNOWNS>;
type Rows<T> = SVector<T, MAX_ROWS>;
type Jacobian<T> = SMatrix<T, MAX_ROWS, MAX_UNKNOWNS>;
/// The whitened Jacobian and the tip's change with the unknowns.
type Linear<T> = (Jacobian<T>, SMatrix<T, 3, MAX_UNKNOWNS>);
/// The reduced problem's rows: the measured tensions' misfits (first `MAX_TENDONS`), the force
/// prior (last three).
type ReducedRows<T> = SVector<T, { MAX_TENDONS + 3 }>;
type ReducedJacobian<T> = SMatrix<T, { MAX_TENDONS + 3 }, 3>;

/// Settings of the tendon inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TendonInverseSettings<T> {
    /// Levenberg-Marquardt iterations per fit.
    pub max_iterations: u16,
    /// Standard deviation of one spool displacement, m (an encoder of resolution `q`: `q / sqrt 12`).
    pub displacement_std_m: T,
    /// The model's own error in a tendon path, m, added in quadrature.
    pub model_length_std_m: T,
    /// A priori standard deviation of each tip force component, N.
    pub force_prior_std_n: T,
    /// A tip force component with a larger posterior standard deviation makes the estimate
    /// [`Determination::Weak`], N.
    pub max_force_std_n: T,
    /// A tension with a larger posterior standard deviation makes it [`Determination::Weak`], N.
    pub max_tension_std_n: T,
    /// How far the search for other answers restarts, in buckling scales `E I / L^2` of tip force
    /// (zero: no search, and a fit that would be `Determined` is `Unverified`).
    pub scan_reach: T,
}

impl<T: Scalar> Default for TendonInverseSettings<T> {
    fn default() -> Self {
        Self {
            max_iterations: 40,
            displacement_std_m: T::lit(2.2e-6),
            model_length_std_m: T::zero(),
            force_prior_std_n: T::lit(1.0),
            max_force_std_n: T::lit(0.05),
            max_tension_std_n: T::lit(0.05),
            scan_reach: T::lit(3.0),
        }
    }
}

impl<T: Scalar> TendonInverseSettings<T> {
    fn validate(&self) -> Result<(), ModelError> {
        positive(self.displacement_std_m, "displacement standard deviation")?;
        crate::error::non_negative(self.model_length_std_m, "model length standard deviation")?;
        positive(self.force_prior_std_n, "force prior standard deviation")?;
        positive(self.max_force_std_n, "force standard deviation limit")?;
        positive(self.max_tension_std_n, "tension standard deviation limit")?;
        crate::error::non_negative(self.scan_reach, "scan reach")?;
        Ok(())
    }
}

/// Measured tensions: each value, N, with its standard deviation, N.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredTensions<'a, T> {
    /// One per tendon, N.
    pub tensions_n: &'a [T],
    /// One per tendon, N (positive).
    pub std_n: &'a [T],
}

/// What the measurements say about the estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonQuality<T> {
    /// Posterior standard deviation of each tension, N.
    pub tension_std_n: Vec<T, MAX_TENDONS>,
    /// Posterior standard deviation of the tip force components, N (with the prior).
    pub force_std_n: Vector3<T>,
    /// Standard deviation of the tip position components, m.
    pub tip_std_m: Vector3<T>,
    /// The whitened data residuals (displacements and tensions) as an rms per spare datum (the
    /// data beyond the unknowns); not a number when there is none.
    pub residual_rms_sigma: T,
    /// Whether any datum is to spare to test the model against the data (more active data than
    /// unknowns). Without, the estimate is at best [`Determination::Weak`], and never
    /// [`Determination::Inconsistent`] (nothing could show it).
    pub consistency_tested: bool,
    /// Whether the data alone determine the tip force (rank of the data rows).
    pub force_observable: bool,
    /// The verdict on the whole estimate (tensions and tip force).
    pub determination: Determination,
    /// The verdict on the tensions alone.
    pub tension_determination: Determination,
}

/// An estimate of the tensions, the tip force and the shape.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonEstimate<T> {
    /// The equilibrium at the estimate (its `tensions_n`, its `equilibrium.load` the tip force).
    pub solved: TendonEquilibrium<T>,
    /// Each tendon's state.
    pub states: Vec<TendonState, MAX_TENDONS>,
    /// Why the fit stopped; use the estimate only when it is `Converged`.
    pub termination: Termination,
    /// Iterations of the fit that gave the answer.
    pub iterations: u16,
    /// Sweeps spent, the search included.
    pub sweeps: u32,
    /// How well the data determine it.
    pub quality: TendonQuality<T>,
}

impl<T: Scalar> TendonEstimate<T> {
    /// Whether the estimate is an answer (converged); how far to trust it is `quality.determination`.
    pub fn is_success(&self) -> bool {
        self.termination.is_success() && self.solved.is_success()
    }

    /// The estimated tip force, N.
    pub fn force_n(&self) -> Vector3<T> {
        self.solved.equilibrium.load.force_n
    }
}

/// One fit's state: the unknowns, the equilibrium there, and its whitened residuals.
struct Fit<T> {
    theta: Theta<T>,
    solved: TendonEquilibrium<T>,
    rows: Rows<T>,
    /// Rows in use: which are active (a slack tendon's displacement row is not).
    active: [bool; MAX_ROWS],
}

struct Problem<'a, T: Scalar, A: Attitude<T>, const NODES: usize> {
    model: &'a Model<T, A, NODES>,
    tendons: &'a Tendons<T>,
    displacements_m: &'a [T],
    measured: Option<MeasuredTensions<'a, T>>,
    settings: TendonInverseSettings<T>,
    shooting: ShootingSettings<T>,
    count: usize,
    /// Displacement standard deviation with the model's error, m.
    s_d: T,
    sweeps: u32,
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Problem<'_, T, A, NODES> {
    fn unknowns(&self) -> usize {
        self.count + 3
    }

    fn tensions(&self, theta: &Theta<T>) -> [T; MAX_TENDONS] {
        let mut tau = [T::zero(); MAX_TENDONS];
        for (t, v) in tau.iter_mut().zip(theta.iter()).take(self.count) {
            *t = *v;
        }
        tau
    }

    fn load(&self, theta: &Theta<T>) -> TipLoad<T> {
        let f = |i: usize| theta.get(self.count + i).copied().unwrap_or_else(T::zero);
        TipLoad::force(Vector3::new(f(0), f(1), f(2)))
    }

    /// The displacement a taut tendon `j` reads when the equilibrium needs the unstretched length
    /// `needed_m`.
    fn predicted(&self, j: usize, needed_m: T) -> T {
        self.tendons.home_length_m(j) - needed_m
    }

    /// Solves the shape at `theta` (warm from `near`) and its residuals.
    fn evaluate(
        &mut self,
        theta: &Theta<T>,
        near: Option<&TendonEquilibrium<T>>,
    ) -> Result<Option<Fit<T>>, ModelError> {
        let tau = self.tensions(theta);
        let solved = self.model.solve_tendons(
            self.tendons,
            tau.get(..self.count).unwrap_or(&[]),
            &self.load(theta),
            near,
            &self.shooting,
        )?;
        self.sweeps += u32::from(solved.equilibrium.report.sweeps);
        if !solved.is_success() {
            return Ok(None);
        }
        let mut rows = Rows::zeros();
        let mut active = [false; MAX_ROWS];
        for j in 0..self.count {
            let (Some(d), Some(needed), Some(t)) = (
                self.displacements_m.get(j),
                solved.unstretched_m.get(j),
                tau.get(j),
            ) else {
                continue;
            };
            let d_hat = self.predicted(j, *needed);
            // Slack: no tension, and the spool took in less than the path needs.
            let slack = *t <= T::zero() && *d <= d_hat;
            if let (Some(r), Some(a)) = (rows.get_mut(j), active.get_mut(j)) {
                *r = if slack {
                    T::zero()
                } else {
                    (d_hat - *d) / self.s_d
                };
                *a = !slack;
            }
        }
        if let Some(m) = self.measured {
            for j in 0..self.count {
                let (Some(v), Some(s), Some(t)) = (m.tensions_n.get(j), m.std_n.get(j), tau.get(j))
                else {
                    continue;
                };
                if let (Some(r), Some(a)) =
                    (rows.get_mut(self.count + j), active.get_mut(self.count + j))
                {
                    *r = (*t - *v) / *s;
                    *a = true;
                }
            }
        }
        let prior = 2 * self.count;
        let force = self.load(theta).force_n;
        for i in 0..3 {
            if let (Some(r), Some(a), Some(f)) = (
                rows.get_mut(prior + i),
                active.get_mut(prior + i),
                force.get(i),
            ) {
                *r = *f / self.settings.force_prior_std_n;
                *a = true;
            }
        }
        Ok(Some(Fit {
            theta: *theta,
            solved,
            rows,
            active,
        }))
    }

    /// The whitened Jacobian at `fit` (inactive rows zero), and the tip's change with `theta`, from
    /// the sensitivity `sens` there.
    fn jacobian(&self, fit: &Fit<T>, sens: &Sensitivity<T>) -> Linear<T> {
        let count = self.count;
        let mut jac = Jacobian::zeros();
        let mut d_tip = SMatrix::<T, 3, MAX_UNKNOWNS>::zeros();
        for c in 0..self.unknowns() {
            for j in 0..count {
                if !fit.active.get(j).copied().unwrap_or(false) {
                    continue;
                }
                let d_needed = if c < count {
                    sens.d_length_d_tension.get((j, c)).copied()
                } else {
                    sens.d_length_d_force.get((j, c - count)).copied()
                }
                .unwrap_or_else(T::zero);
                if let Some(e) = jac.get_mut((j, c)) {
                    *e = -d_needed / self.s_d;
                }
            }
            if let Some(m) = self.measured
                && c < count
                && let (Some(s), Some(e)) = (m.std_n.get(c), jac.get_mut((count + c, c)))
            {
                *e = T::one() / *s;
            }
            if c >= count
                && let Some(e) = jac.get_mut((2 * count + (c - count), c))
            {
                *e = T::one() / self.settings.force_prior_std_n;
            }
            for i in 0..3 {
                let v = if c < count {
                    sens.d_tip_d_tension.get((i, c)).copied()
                } else {
                    sens.d_tip_d_force.get((i, c - count)).copied()
                }
                .unwrap_or_else(T::zero);
                if let Some(e) = d_tip.get_mut((i, c)) {
                    *e = v;
                }
            }
        }
        (jac, d_tip)
    }

    /// The sensitivity at `solved` under the tip force `force_n`, its sweeps counted.
    fn sensitivity(
        &mut self,
        solved: &TendonEquilibrium<T>,
        force_n: &Vector3<T>,
    ) -> Result<Result<Sensitivity<T>, Termination>, ModelError> {
        let load = TipLoad::force(*force_n);
        let sens = sensitivity(
            self.model,
            self.tendons,
            solved,
            &load,
            true,
            &self.shooting,
        )?;
        if let Ok(s) = &sens {
            self.sweeps += s.sweeps;
        }
        Ok(sens)
    }

    fn cost(fit: &Fit<T>) -> T {
        fit.rows.norm_squared()
    }
}

/// A fit's outcome: where it ended, why, after how many iterations, and its linearisation there.
struct Outcome<T> {
    fit: Fit<T>,
    termination: Termination,
    iterations: u16,
    linear: Option<Linear<T>>,
    /// Each tendon's state, as the displacement solve at the answer judged it.
    states: Vec<TendonState, MAX_TENDONS>,
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Problem<'_, T, A, NODES> {
    /// The step below which a fit has converged, in standard deviations of the fit: what the
    /// sensitivity resolves in the scalar type (forward differences, with friction).
    fn step_tolerance_sigma() -> T {
        (T::default_epsilon() * T::lit(1e4)).max(T::lit(1e-5))
    }

    /// The tensions the displacements give under the tip force `force_n` (warm from `previous`
    /// when given, else from `near`).
    fn tensions_at(
        &mut self,
        force_n: &Vector3<T>,
        previous: Option<&DisplacementSolve<T>>,
        near: Option<&TendonEquilibrium<T>>,
    ) -> Result<DisplacementSolve<T>, ModelError> {
        let load = TipLoad::force(*force_n);
        let control = fit_settings();
        let out = match previous {
            Some(p) => self.model.update_displacements(
                self.tendons,
                self.displacements_m,
                &load,
                p,
                &self.shooting,
                &control,
            )?,
            None => self.model.solve_displacements(
                self.tendons,
                self.displacements_m,
                &load,
                near,
                &self.shooting,
                &control,
            )?,
        };
        self.sweeps += out.sweeps;
        Ok(out)
    }

    /// The reduced residuals at `disp` (its tensions and the tip force `force_n`): the measured
    /// tensions' misfits and the force prior. The displacements hold exactly (the tensions are
    /// the ones they give), so only these rows remain.
    fn reduced_rows(&self, disp: &DisplacementSolve<T>, force_n: &Vector3<T>) -> ReducedRows<T> {
        let mut rows = ReducedRows::zeros();
        if let Some(m) = self.measured {
            for (j, r) in rows.iter_mut().enumerate().take(self.count) {
                let (Some(t), Some(v), Some(s)) = (
                    disp.solved.tensions_n.get(j),
                    m.tensions_n.get(j),
                    m.std_n.get(j),
                ) else {
                    continue;
                };
                *r = (*t - *v) / *s;
            }
        }
        for (i, f) in force_n.iter().enumerate() {
            if let Some(r) = rows.get_mut(MAX_TENDONS + i) {
                *r = *f / self.settings.force_prior_std_n;
            }
        }
        rows
    }

    /// The reduced Jacobian: `d tau / d F` of the tensions the displacements give (the implicit
    /// function theorem on the taut tendons' `N(tau, F) = U0 - d`; a slack tendon's tension stays
    /// zero), whitened, over the prior's identity.
    fn reduced_jacobian(
        &self,
        disp: &DisplacementSolve<T>,
        sens: &Sensitivity<T>,
    ) -> Option<ReducedJacobian<T>> {
        let taut = |j: usize| disp.states.get(j) == Some(&TendonState::Taut);
        let a = SMatrix::<T, MAX_TENDONS, MAX_TENDONS>::from_fn(|j, i| {
            if j < self.count && taut(j) {
                if i < self.count {
                    sens.d_length_d_tension
                        .get((j, i))
                        .copied()
                        .unwrap_or_else(T::zero)
                } else {
                    T::zero()
                }
            } else if i == j {
                T::one()
            } else {
                T::zero()
            }
        });
        let rhs = SMatrix::<T, MAX_TENDONS, 3>::from_fn(|j, c| {
            if j < self.count && taut(j) {
                -sens
                    .d_length_d_force
                    .get((j, c))
                    .copied()
                    .unwrap_or_else(T::zero)
            } else {
                T::zero()
            }
        });
        let d_tau = a.lu().solve(&rhs)?;
        let mut jac = ReducedJacobian::zeros();
        if let Some(m) = self.measured {
            for j in 0..self.count {
                let s = m.std_n.get(j).copied().unwrap_or_else(T::one);
                for c in 0..3 {
                    if let (Some(e), Some(d)) = (jac.get_mut((j, c)), d_tau.get((j, c))) {
                        *e = *d / s;
                    }
                }
            }
        }
        for c in 0..3 {
            if let Some(e) = jac.get_mut((MAX_TENDONS + c, c)) {
                *e = T::one() / self.settings.force_prior_std_n;
            }
        }
        crate::scalar::all_finite(&jac).then_some(jac)
    }

    /// Fits the tip force from `force0` (the tensions follow from the displacements at each
    /// force: variable projection, which keeps the stiff directions the displacements fix out of
    /// the search), by Levenberg-Marquardt on the reduced residuals.
    fn fit(
        &mut self,
        force0: Vector3<T>,
        near: Option<&TendonEquilibrium<T>>,
    ) -> Result<Result<Outcome<T>, Termination>, ModelError> {
        let mut force = force0;
        let mut disp = self.tensions_at(&force, None, near)?;
        if !disp.is_success() {
            let forward = disp.solved.equilibrium.report.termination;
            return Ok(Err(if forward.is_success() {
                disp.termination
            } else {
                forward
            }));
        }
        let mut mu = T::lit(1e-3);
        let mut iterations = 0u16;
        let mut termination = Termination::IterationLimit;
        let mut last = None;
        for _ in 0..self.settings.max_iterations {
            let sens = match self.sensitivity(&disp.solved, &force)? {
                Ok(s) => s,
                Err(t) => return Ok(Err(t)),
            };
            let rows = self.reduced_rows(&disp, &force);
            let Some(jac) = self.reduced_jacobian(&disp, &sens) else {
                return Ok(Err(Termination::Singular));
            };
            last = Some(sens);
            let g = jac.tr_mul(&rows);
            let h = jac.tr_mul(&jac);
            let cost = rows.norm_squared();
            let mut accepted = None;
            // Converged when the undamped Gauss-Newton step moves the fit by less than the
            // tolerance (in standard deviations): a step made small by the damping is not.
            let gauss_newton = h.cholesky().map(|c| (jac * c.solve(&(-g))).norm());
            let converged = gauss_newton.is_some_and(|size| size <= Self::step_tolerance_sigma());
            for _ in 0..12 {
                if converged {
                    break;
                }
                let damped = h + SMatrix::<T, 3, 3>::from_diagonal(&h.diagonal()) * mu;
                let Some(step) = damped.cholesky().map(|c| c.solve(&(-g))) else {
                    mu *= T::lit(10.0);
                    continue;
                };
                let trial_force = force + step;
                let trial = self.tensions_at(&trial_force, Some(&disp), None)?;
                if trial.is_success()
                    && self.reduced_rows(&trial, &trial_force).norm_squared() < cost
                {
                    accepted = Some((trial_force, trial));
                    mu = (mu / T::lit(3.0)).max(T::lit(1e-9));
                    break;
                }
                mu *= T::lit(10.0);
            }
            if converged {
                termination = Termination::Converged;
                break;
            }
            iterations += 1;
            match accepted {
                Some((f, d)) => {
                    force = f;
                    disp = d;
                }
                None => {
                    // No step lowers the misfit: the rounding floor of the solves, where the
                    // undamped step is a hundredth of a standard deviation or less (statistically
                    // nothing), or a stall short of the answer.
                    termination = if gauss_newton.is_some_and(|size| size <= T::lit(1e-2)) {
                        Termination::Converged
                    } else {
                        Termination::Stalled
                    };
                    break;
                }
            }
        }
        // The full linearisation at the answer, for its quality.
        let mut theta = Theta::zeros();
        for (t, v) in theta.iter_mut().zip(&disp.solved.tensions_n) {
            *t = *v;
        }
        for (i, f) in force.iter().enumerate() {
            if let Some(t) = theta.get_mut(self.count + i) {
                *t = *f;
            }
        }
        let Some(fit) = self.evaluate(&theta, Some(&disp.solved))? else {
            return Ok(Err(Termination::NonFinite));
        };
        let linear = match (termination, last) {
            (Termination::Converged | Termination::Stalled, Some(sens)) => {
                Some(self.jacobian(&fit, &sens))
            }
            _ => None,
        };
        Ok(Ok(Outcome {
            fit,
            termination,
            iterations,
            linear,
            states: disp.states.clone(),
        }))
    }

    /// `jac` with a unit row for each unused unknown (so that its SVD sees only the used ones), and
    /// the prior rows dropped when `data_only`.
    fn padded(&self, jac: &Jacobian<T>, data_only: bool) -> Jacobian<T> {
        let n = self.unknowns();
        let prior = 2 * self.count;
        let mut out = *jac;
        if data_only {
            for i in 0..3 {
                out.row_mut(prior + i).fill(T::zero());
            }
        }
        for c in n..MAX_UNKNOWNS {
            if let Some(e) = out.get_mut((prior + 3 + (c - n), c)) {
                *e = T::one();
            }
        }
        out
    }

    /// The quality of the estimate at `fit` with whitened Jacobian `jac` and tip change `d_tip`.
    fn quality(
        &self,
        fit: &Fit<T>,
        jac: &Jacobian<T>,
        d_tip: &SMatrix<T, 3, MAX_UNKNOWNS>,
    ) -> TendonQuality<T> {
        let n = self.unknowns();
        let infinite = T::max_value().unwrap_or_else(|| T::lit(1e300));
        let data_rows = 2 * self.count;
        let (mut sum, mut used) = (T::zero(), 0usize);
        for (r, a) in fit.rows.iter().zip(&fit.active).take(data_rows) {
            if *a {
                sum += *r * *r;
                used += 1;
            }
        }
        // The misfit per degree of freedom the data leave after the unknowns: with no spare datum
        // (three taut tendons and three measured tensions for three tensions and a force) nothing
        // tests the model against the data.
        let spare = used.saturating_sub(n);
        let consistency_tested = spare > 0;
        let residual_rms_sigma = if consistency_tested {
            (sum / T::lit(spare as f64)).sqrt()
        } else {
            T::lit(f64::NAN)
        };
        let mut quality = TendonQuality {
            tension_std_n: Vec::new(),
            force_std_n: Vector3::repeat(infinite),
            tip_std_m: Vector3::repeat(infinite),
            residual_rms_sigma,
            consistency_tested,
            force_observable: false,
            determination: Determination::Undetermined,
            tension_determination: Determination::Undetermined,
        };
        for _ in 0..self.count {
            let _ = quality.tension_std_n.push(infinite);
        }
        if consistency_tested && residual_rms_sigma > T::lit(3.0) {
            quality.determination = Determination::Inconsistent;
            quality.tension_determination = Determination::Inconsistent;
        }
        // What the data alone determine: the data rows' singular values (a bounded SVD: it gives
        // up rather than iterate without end on data it cannot decompose).
        let eps = T::default_epsilon();
        let Some(data) = nalgebra::SVD::try_new(self.padded(jac, true), false, false, eps, 200)
        else {
            return quality;
        };
        let largest = data.singular_values.max();
        let threshold = largest * eps * T::lit(1e3);
        quality.force_observable =
            largest > T::zero() && data.singular_values.iter().all(|s| *s > threshold);
        // The posterior: data and prior, V diag(1 / sigma^2) V^T.
        let Some(svd) = nalgebra::SVD::try_new(self.padded(jac, false), false, true, eps, 200)
        else {
            return quality;
        };
        let Some(v_t) = svd.v_t else {
            return quality;
        };
        if svd.singular_values.iter().any(|s| *s <= T::zero()) {
            return quality;
        }
        let inv = svd.singular_values.map(|s| T::one() / (s * s));
        let covariance =
            v_t.transpose() * SMatrix::<T, MAX_UNKNOWNS, MAX_UNKNOWNS>::from_diagonal(&inv) * v_t;
        // (A singular value whose square underflows makes it infinite and the product NaN, which
        // the deviations' `max(0)` would read as zero spread: no posterior then.)
        if !crate::scalar::all_finite(&covariance) {
            return quality;
        }
        let std = |i: usize| {
            covariance
                .get((i, i))
                .map_or(infinite, |v| v.max(T::zero()).sqrt())
        };
        for (j, s) in quality.tension_std_n.iter_mut().enumerate() {
            *s = std(j);
        }
        quality.force_std_n =
            Vector3::new(std(self.count), std(self.count + 1), std(self.count + 2));
        let tip_cov = d_tip * covariance * d_tip.transpose();
        let floor = self.model.length_m() * crate::solve::stopping::default_tolerance::<T>();
        quality.tip_std_m = tip_cov
            .diagonal()
            .map(|v| (v.max(T::zero()) + floor * floor).sqrt());
        let _ = n;
        if quality.determination == Determination::Inconsistent {
            return quality;
        }
        let worst_tension = quality
            .tension_std_n
            .iter()
            .fold(T::zero(), |a, b| a.max(*b));
        quality.tension_determination = if worst_tension > self.settings.max_tension_std_n {
            Determination::Weak
        } else {
            Determination::Determined
        };
        quality.determination = if !quality.force_observable {
            Determination::Undetermined
        } else if quality.force_std_n.max() > self.settings.max_force_std_n
            || worst_tension > self.settings.max_tension_std_n
            // Determined needs data to spare: without, a model error (a tension sensor's bias, a
            // wrong stiffness) lands in the force unseen.
            || !consistency_tested
        {
            Determination::Weak
        } else {
            Determination::Determined
        };
        quality
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Estimates the tensions, the tip force and the shape from spool displacements (m, one per
    /// tendon, positive taken in; see [`Model::solve_displacements`]) and optionally measured
    /// tensions, with the posterior uncertainty and a verdict.
    ///
    /// From `start` (a previous estimate: the per-tick warm update) the fit starts there and skips
    /// the search for other answers, keeping the previous verdict's doubt. Fails only on invalid
    /// input; the outcome is data.
    pub fn estimate_tendons(
        &self,
        tendons: &Tendons<T>,
        displacements_m: &[T],
        measured: Option<MeasuredTensions<'_, T>>,
        start: Option<&TendonEstimate<T>>,
        shooting: &ShootingSettings<T>,
        settings: &TendonInverseSettings<T>,
    ) -> Result<TendonEstimate<T>, ModelError> {
        settings.validate()?;
        let count = tendons.len();
        tendons.check_displacements(displacements_m)?;
        if let Some(m) = measured {
            if m.tensions_n.len() != count || m.std_n.len() != count {
                return Err(ModelError::Mismatch("measured tensions and tendons"));
            }
            for (t, s) in m.tensions_n.iter().zip(m.std_n) {
                finite(*t, "measured tension")?;
                positive(*s, "tension standard deviation")?;
            }
        }
        let s_d = (settings.displacement_std_m * settings.displacement_std_m
            + settings.model_length_std_m * settings.model_length_std_m)
            .sqrt();
        let mut problem = Problem {
            model: self,
            tendons,
            displacements_m,
            measured,
            settings: *settings,
            shooting: *shooting,
            count,
            s_d,
            sweeps: 0,
        };

        // The start: the previous estimate, or the tensions the displacements give at no tip force
        // (measured tensions where there are some).
        let mut theta = Theta::zeros();
        let mut near = None;
        // A failed estimate is no start.
        let start = start.filter(|s| s.is_success());
        match start {
            Some(previous) => {
                for (t, v) in theta.iter_mut().zip(&previous.solved.tensions_n) {
                    *t = v.max(T::zero());
                }
                for i in 0..3 {
                    if let (Some(t), Some(f)) =
                        (theta.get_mut(count + i), previous.force_n().get(i))
                    {
                        *t = *f;
                    }
                }
                near = Some(&previous.solved);
            }
            None => match measured {
                Some(m) => {
                    for (t, v) in theta.iter_mut().zip(m.tensions_n) {
                        *t = v.max(T::zero());
                    }
                }
                None => {
                    let d = self.solve_displacements(
                        tendons,
                        displacements_m,
                        &TipLoad::zero(),
                        None,
                        shooting,
                        &fit_settings(),
                    )?;
                    problem.sweeps += d.sweeps;
                    if d.is_success() {
                        for (t, v) in theta.iter_mut().zip(&d.solved.tensions_n) {
                            *t = *v;
                        }
                    }
                }
            },
        }
        let force0 = problem.load(&theta).force_n;
        let outcome = match problem.fit(force0, near)? {
            Ok(o) => o,
            Err(t) => return Ok(problem.failed(&theta, t)),
        };
        let stopped_at = Problem::<T, A, NODES>::cost(&outcome.fit);
        let mut best = problem.finish(outcome);
        if !best.is_success() && start.is_none() {
            // From the start the fit can run into a valley where a tendon the measured tensions
            // say is taut is slack: its tension then stays zero whatever the force, so its misfit
            // shows the fit no way out. A cold estimate tries the search's starts before it fails
            // (a rescue must fit better than where the fit stopped).
            if let Some(rescued) = problem.rescue(&theta, stopped_at)? {
                best = rescued;
            }
        }
        if !best.is_success() {
            // Never searched around: unverified at best.
            best.quality.determination = best
                .quality
                .determination
                .at_best(Determination::Unverified);
            best.sweeps = problem.sweeps;
            return Ok(best);
        }
        match start {
            Some(previous) => {
                let doubt = previous.quality.determination;
                if matches!(doubt, Determination::Ambiguous | Determination::Unverified) {
                    best.quality.determination = best.quality.determination.at_best(doubt);
                }
            }
            None => problem.search(&mut best)?,
        }
        best.sweeps = problem.sweeps;
        Ok(best)
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Problem<'_, T, A, NODES> {
    /// An estimate that has no equilibrium to show.
    fn failed(&self, theta: &Theta<T>, termination: Termination) -> TendonEstimate<T> {
        let mut tensions = Vec::new();
        for t in theta.iter().take(self.count) {
            let _ = tensions.push(*t);
        }
        let eq = crate::shooting::failed_equilibrium(&self.load(theta), termination);
        TendonEstimate {
            solved: TendonEquilibrium {
                equilibrium: eq,
                tensions_n: tensions,
                path_m: Vec::new(),
                unstretched_m: Vec::new(),
            },
            states: Vec::new(),
            termination,
            iterations: 0,
            sweeps: self.sweeps,
            quality: TendonQuality {
                tension_std_n: Vec::new(),
                force_std_n: Vector3::repeat(T::lit(f64::NAN)),
                tip_std_m: Vector3::repeat(T::lit(f64::NAN)),
                residual_rms_sigma: T::lit(f64::NAN),
                consistency_tested: false,
                force_observable: false,
                determination: Determination::Undetermined,
                tension_determination: Determination::Undetermined,
            },
        }
    }

    /// The estimate of a finished fit.
    fn finish(&self, outcome: Outcome<T>) -> TendonEstimate<T> {
        let Outcome {
            fit,
            termination,
            iterations,
            linear,
            states,
        } = outcome;
        let quality = match &linear {
            Some((jac, d_tip)) => self.quality(&fit, jac, d_tip),
            None => self.failed(&fit.theta, termination).quality,
        };
        TendonEstimate {
            solved: fit.solved,
            states,
            termination,
            iterations,
            sweeps: self.sweeps,
            quality,
        }
    }

    /// Restarts from tip forces of `scan_reach` buckling scales along each axis, both signs: a fit
    /// as good (within 9 in the sum of squares, three standard deviations) and more than three
    /// posterior standard deviations away makes the answer ambiguous; a clearly better one replaces
    /// it. A restart that ends unconverged, as good and as far, makes it unverified (one that stops on
    /// the answer is no rival).
    fn search(&mut self, best: &mut TendonEstimate<T>) -> Result<(), ModelError> {
        if !matches!(
            best.quality.determination,
            Determination::Determined | Determination::Weak
        ) {
            return Ok(());
        }
        if self.settings.scan_reach <= T::zero() {
            best.quality.determination = best
                .quality
                .determination
                .at_best(Determination::Unverified);
            return Ok(());
        }
        let nine = T::lit(9.0);
        let mut verdict = best.quality.determination;
        let best_theta = |e: &TendonEstimate<T>, count: usize| {
            let mut theta = Theta::zeros();
            for (t, v) in theta.iter_mut().zip(&e.solved.tensions_n) {
                *t = *v;
            }
            for i in 0..3 {
                if let (Some(t), Some(f)) = (theta.get_mut(count + i), e.force_n().get(i)) {
                    *t = *f;
                }
            }
            theta
        };
        let answer = best_theta(best, self.count);
        // The answer's own misfit, evaluated again: where that fails, no rival can be judged
        // against it, and the search vouches for nothing.
        let Some(best_cost) = self.cost_of(&answer, &best.solved)? else {
            best.quality.determination = verdict.at_best(Determination::Unverified);
            return Ok(());
        };
        // A restart gets a dozen iterations: one that has not come within reach of the answer's
        // misfit by then is no rival; one that has, but unconverged, leaves the answer unverified.
        let full = self.settings.max_iterations;
        self.settings.max_iterations = full.min(RESTART_ITERATIONS);
        for force0 in self.scan_starts(&answer) {
            let Ok(outcome) = self.fit(force0, None)? else {
                continue;
            };
            let cost = Problem::<T, A, NODES>::cost(&outcome.fit);
            if cost > best_cost + nine {
                continue;
            }
            // A restart that ended on the answer (within three of its deviations) is no rival,
            // converged or not.
            let apart = self.apart_sigma(&outcome.fit.theta, &answer, best);
            if apart <= T::lit(3.0) {
                continue;
            }
            if !outcome.termination.is_success() {
                verdict = verdict.at_best(Determination::Unverified);
                continue;
            }
            if cost + nine < best_cost {
                // A clearly better answer: it replaces this one, and the search does not vouch
                // for it (it was not searched around).
                let mut better = self.finish(outcome);
                better.quality.determination = better
                    .quality
                    .determination
                    .at_best(Determination::Unverified);
                *best = better;
                self.settings.max_iterations = full;
                return Ok(());
            }
            verdict = Determination::Ambiguous;
        }
        self.settings.max_iterations = full;
        best.quality.determination = verdict;
        Ok(())
    }

    /// The search's starts around `theta`: its tip force moved by `scan_reach` buckling scales
    /// (`E I / L^2`) along each axis, both signs (none with `scan_reach = 0`).
    fn scan_starts(&self, theta: &Theta<T>) -> heapless::Vec<Vector3<T>, 6> {
        let scale = self.model.moment_scale_nm() / self.model.length_m() * self.settings.scan_reach;
        let force = self.load(theta).force_n;
        let mut starts = heapless::Vec::new();
        if scale > T::zero() {
            for axis in 0..3 {
                for sign in [T::one(), -T::one()] {
                    let mut start = force;
                    if let Some(f) = start.get_mut(axis) {
                        *f += sign * scale;
                    }
                    // Cannot overflow: six starts.
                    let _ = starts.push(start);
                }
            }
        }
        starts
    }

    /// Fits from the search's starts around `theta` ([`Problem::scan_starts`]), each with the full
    /// budget: the converged one with the smallest misfit below `below`, if any.
    fn rescue(
        &mut self,
        theta: &Theta<T>,
        below: T,
    ) -> Result<Option<TendonEstimate<T>>, ModelError> {
        let mut best: Option<(T, Outcome<T>)> = None;
        for force0 in self.scan_starts(theta) {
            let Ok(outcome) = self.fit(force0, None)? else {
                continue;
            };
            let cost = Problem::<T, A, NODES>::cost(&outcome.fit);
            if outcome.termination.is_success()
                && cost < below
                && best.as_ref().is_none_or(|(c, _)| cost < *c)
            {
                best = Some((cost, outcome));
            }
        }
        Ok(best.map(|(_, outcome)| self.finish(outcome)))
    }

    /// The sum of squares at `theta` on `solved` (`None` where its forward solve fails).
    fn cost_of(
        &mut self,
        theta: &Theta<T>,
        solved: &TendonEquilibrium<T>,
    ) -> Result<Option<T>, ModelError> {
        Ok(self
            .evaluate(theta, Some(solved))?
            .map(|f| Problem::<T, A, NODES>::cost(&f)))
    }

    /// How far apart two estimates are, in the answer's posterior standard deviations (the largest
    /// over the unknowns).
    fn apart_sigma(&self, a: &Theta<T>, b: &Theta<T>, best: &TendonEstimate<T>) -> T {
        let mut worst = T::zero();
        for (j, s) in best.quality.tension_std_n.iter().enumerate() {
            let d = (a.get(j).copied().unwrap_or_else(T::zero)
                - b.get(j).copied().unwrap_or_else(T::zero))
            .abs();
            worst = worst.max(d / s.max(T::default_epsilon()));
        }
        for i in 0..3 {
            let c = self.count + i;
            let d = (a.get(c).copied().unwrap_or_else(T::zero)
                - b.get(c).copied().unwrap_or_else(T::zero))
            .abs();
            let s = best
                .quality
                .force_std_n
                .get(i)
                .copied()
                .unwrap_or_else(T::one);
            worst = worst.max(d / s.max(T::default_epsilon()));
        }
        worst
    }
}
