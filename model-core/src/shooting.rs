//! The forward problem: find the base strain `u(0)` that meets the tip-moment condition
//! `R(L) C u(L) = tau_tip` (thesis ch. 2.5: a shooting problem with three unknowns and three residuals).
//!
//! Damped Newton with a trust region on the change of base strain; the Jacobian comes from the sweep's
//! forward sensitivities. A cold start first tries Newton from the small-deflection guess and keeps the
//! answer only if the Jacobi-field stability test passes; otherwise it ramps all loads from zero
//! (load continuation, secant predictor, adaptive step), which follows the branch connected to the
//! unloaded rod. A converged but unstable equilibrium (the thesis's exp-2 scene at 62-83 g from a zero
//! start lands on one) is reported as [`Termination::Unstable`], never as success.

use heapless::Vec;
use nalgebra::{Matrix3, Vector3};

use crate::error::{ModelError, finite_vec};
use crate::integrate::{Sweep, Tangents, sweep};
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::report::{MAX_FRAME_DRIFT, SolveReport, Termination};
use crate::stability::Stability;
use crate::{MAX_CABLES, Scalar};

/// The load at the tip, global frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipLoad<T> {
    /// Force, N.
    pub force_n: Vector3<T>,
    /// Moment, N m.
    pub moment_nm: Vector3<T>,
}

impl<T: Scalar> TipLoad<T> {
    /// No tip load.
    pub fn zero() -> Self {
        Self {
            force_n: Vector3::zeros(),
            moment_nm: Vector3::zeros(),
        }
    }
    /// A tip force only.
    pub fn force(force_n: Vector3<T>) -> Self {
        Self {
            force_n,
            moment_nm: Vector3::zeros(),
        }
    }
    /// A tip moment only.
    pub fn moment(moment_nm: Vector3<T>) -> Self {
        Self {
            force_n: Vector3::zeros(),
            moment_nm,
        }
    }
    pub(crate) fn validate(&self) -> Result<(), ModelError> {
        finite_vec(&self.force_n, "tip force")?;
        finite_vec(&self.moment_nm, "tip moment")
    }
}

/// Where a solve starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start<T> {
    /// From nothing: small-deflection guess, then load continuation if needed.
    Cold,
    /// From a previous base strain, 1/m (the cheap path when loads change a little).
    Warm(Vector3<T>),
}

/// Settings of the shooting solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShootingSettings<T> {
    /// Newton iterations per solve (per load step during continuation).
    pub max_iterations: u16,
    /// Tolerance on the dimensionless residual `|tip moment error| L / (E I)`, relative to the base
    /// rotation `|u0| L` when that exceeds one radian.
    pub tolerance: T,
    /// Trust region: largest change of base strain per iteration, as an angle `|du0| L`, rad.
    pub max_rotation_step_rad: T,
    /// Most load steps during continuation.
    pub max_load_steps: u16,
    /// Run the Jacobi-field stability test on the answer (one extra sweep with six tangents).
    pub check_stability: bool,
    /// When a warm start fails, start again cold.
    pub cold_fallback: bool,
}

impl<T: Scalar> Default for ShootingSettings<T> {
    fn default() -> Self {
        Self {
            max_iterations: 40,
            tolerance: default_tolerance(),
            max_rotation_step_rad: T::lit(1.0),
            max_load_steps: 64,
            check_stability: true,
            cold_fallback: true,
        }
    }
}

/// The default dimensionless tolerance: `1e-11` in f64, `200 eps` (2.4e-5) in f32: a few times the
/// rounding floor of a sweep.
pub fn default_tolerance<T: Scalar>() -> T {
    (T::default_epsilon() * T::lit(200.0)).max(T::lit(1e-11))
}

/// A solved equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium<T> {
    /// The shooting unknown `u(0)`, 1/m, body frame.
    pub base_strain_per_m: Vector3<T>,
    /// The tip load it was solved for.
    pub load: TipLoad<T>,
    /// Tip position, m.
    pub tip_position_m: Vector3<T>,
    /// Tip frame.
    pub tip_rotation: Matrix3<T>,
    /// Cable lengths, m, in the rod's cable order.
    pub cable_lengths_m: Vec<T, MAX_CABLES>,
    /// How the solve went; only `report.termination.is_success()` makes the rest trustworthy.
    pub report: SolveReport<T>,
}

impl<T: Scalar> Equilibrium<T> {
    /// The tip tangent (local z) in global coordinates.
    pub fn tip_tangent(&self) -> Vector3<T> {
        self.tip_rotation.column(2).into_owned()
    }
}

/// Work counters shared by the stages of one solve.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Work {
    pub iterations: u16,
    pub sweeps: u16,
}

impl Work {
    fn sweep(&mut self) {
        self.sweeps = self.sweeps.saturating_add(1);
    }
}

/// The outcome of one Newton solve at a fixed load scale.
pub(crate) struct Newton<T> {
    pub u0: Vector3<T>,
    pub sweep: Sweep<T>,
    pub residual: T,
    pub termination: Termination,
}

impl<T: Scalar> Newton<T> {
    /// The stability verdict from the final sweep's Jacobi fields.
    fn stability(&self, conservative: bool, length_m: T) -> Stability<T> {
        crate::stability::of_sweep(conservative, &self.sweep, length_m)
    }
}

/// Rejected steps tolerated in a row before the solve is declared stalled.
const MAX_REJECTIONS: u8 = 8;

/// A cold start's first guess is the small-deflection one with its base rotation `|u0| L` capped at
/// this angle, rad (the true rotation grows more slowly than the linear estimate).
const GUESS_ANGLE_RAD: f64 = 2.5;

/// During continuation a corrected solution may differ from its prediction by at most this base
/// rotation, rad; a larger jump is treated as a hop to another branch and the load step is halved.
const PREDICTOR_TRUST_RAD: f64 = 0.5;

/// Newton iterations a cold start gives the full load before it falls back to continuation.
const DIRECT_ITERATIONS: u16 = 12;

/// Levenberg-Marquardt on `u(0)` at load scale `alpha`: the Newton step when it reduces the residual
/// (`mu = 0`), a damped step `(J^T J + mu diag(J^T J)) du = -J^T e` when it does not, with a trust region
/// on `|du| L`.
pub(crate) fn newton<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    load: &TipLoad<T>,
    alpha: T,
    start: Vector3<T>,
    settings: &ShootingSettings<T>,
    max_iterations: u16,
    work: &mut Work,
) -> Newton<T> {
    let run = |u: &Vector3<T>, work: &mut Work| {
        work.sweep();
        sweep(
            model,
            &model.inputs(u, load, alpha),
            Tangents::base_strain(settings.check_stability),
            None,
        )
    };
    let mut u0 = start;
    let mut sw = run(&u0, work);
    if !sw.finite {
        return Newton {
            u0,
            sweep: sw,
            residual: T::zero(),
            termination: Termination::NonFinite,
        };
    }
    let mut residual = model.moment_residual(&sw.moment_residual_nm);
    let max_step = settings.max_rotation_step_rad / model.length_m();
    let mut mu = T::zero();
    let mut rejections = 0u8;
    for _ in 0..max_iterations {
        if model.moment_converged(&sw.moment_residual_nm, &u0, settings.tolerance) {
            return Newton {
                u0,
                sweep: sw,
                residual,
                termination: Termination::Converged,
            };
        }
        let jacobian = Matrix3::from_columns(&[sw.d_moment(0), sw.d_moment(1), sw.d_moment(2)]);
        let step = if mu == T::zero() {
            jacobian.lu().solve(&-sw.moment_residual_nm)
        } else {
            let jtj = jacobian.tr_mul(&jacobian);
            let damped = jtj + Matrix3::from_diagonal(&jtj.diagonal()) * mu;
            damped
                .cholesky()
                .map(|c| c.solve(&-jacobian.tr_mul(&sw.moment_residual_nm)))
        };
        let Some(mut step) = step.filter(|d| d.iter().all(|x| x.is_finite())) else {
            if mu == T::zero() {
                mu = T::lit(1e-3);
                continue;
            }
            return Newton {
                u0,
                sweep: sw,
                residual,
                termination: Termination::Singular,
            };
        };
        // At the rounding floor the residual stops decreasing. A Newton correction that turns the base
        // and moves the tip by less than the tolerance may mean the answer is as good as the scalar
        // type allows: it is when the tip move is negligible outright, or when the correction, tried,
        // no longer lowers the residual. On a badly conditioned rod a correction that small can still
        // lower the residual a hundredfold and move the tip by a tenth of a millimetre.
        let tip_move =
            (sw.d_position(0) * step.x + sw.d_position(1) * step.y + sw.d_position(2) * step.z)
                .norm();
        let at_floor =
            mu == T::zero() && model.step_converged(&step, &u0, tip_move, settings.tolerance);
        if at_floor && model.tip_move_negligible(tip_move, settings.tolerance) {
            return Newton {
                u0,
                sweep: sw,
                residual,
                termination: Termination::Converged,
            };
        }
        let norm = step.norm();
        if norm > max_step {
            step *= max_step / norm;
        }
        work.iterations = work.iterations.saturating_add(1);
        let trial_u = u0 + step;
        let trial = run(&trial_u, work);
        let trial_residual = if trial.finite {
            model.moment_residual(&trial.moment_residual_nm)
        } else {
            residual
        };
        if trial.finite && trial_residual < residual {
            (u0, sw, residual) = (trial_u, trial, trial_residual);
            mu *= T::lit(0.25);
            if mu < T::lit(1e-6) {
                mu = T::zero();
            }
            rejections = 0;
        } else if at_floor {
            return Newton {
                u0,
                sweep: sw,
                residual,
                termination: Termination::Converged,
            };
        } else {
            mu = if mu == T::zero() {
                T::lit(1e-3)
            } else {
                mu * T::lit(8.0)
            };
            rejections += 1;
            if rejections >= MAX_REJECTIONS {
                let termination =
                    if model.moment_converged(&sw.moment_residual_nm, &u0, settings.tolerance) {
                        Termination::Converged
                    } else {
                        Termination::Stalled
                    };
                return Newton {
                    u0,
                    sweep: sw,
                    residual,
                    termination,
                };
            }
        }
    }
    let termination = if model.moment_converged(&sw.moment_residual_nm, &u0, settings.tolerance) {
        Termination::Converged
    } else {
        Termination::IterationLimit
    };
    Newton {
        u0,
        sweep: sw,
        residual,
        termination,
    }
}

/// Load continuation from the unloaded rod (where `u(0) = 0` is exact) to the full load.
/// `first_step` is the first load increment (a fraction of the full load).
pub(crate) fn continuation<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    load: &TipLoad<T>,
    settings: &ShootingSettings<T>,
    first_step: T,
    work: &mut Work,
    load_steps: &mut u16,
) -> Option<Newton<T>> {
    let (mut alpha, mut u0) = (T::zero(), Vector3::zeros());
    let (mut prev_alpha, mut prev_u0) = (T::zero(), Vector3::zeros());
    let mut step = first_step;
    let min_step = T::lit(1.0 / 4096.0);
    let corrector_iterations = settings.max_iterations.min(12);
    // Every load step is checked for stability and for staying near its prediction, so that a large
    // step cannot hop onto another branch.
    let tracked = ShootingSettings {
        check_stability: true,
        ..*settings
    };
    let trust = T::lit(PREDICTOR_TRUST_RAD) / model.length_m();
    while *load_steps < settings.max_load_steps {
        let target = (alpha + step).min(T::one());
        // Secant predictor along the branch.
        let guess = if alpha > prev_alpha {
            u0 + (u0 - prev_u0) * ((target - alpha) / (alpha - prev_alpha))
        } else {
            model.linear_guess(load, target)
        };
        *load_steps = load_steps.saturating_add(1);
        let iterations_before = work.iterations;
        let out = newton(
            model,
            load,
            target,
            guess,
            &tracked,
            corrector_iterations,
            work,
        );
        let accepted = out.termination.is_success()
            && (out.u0 - guess).norm() <= trust
            && out
                .stability(model.conservative(&load.moment_nm), model.length_m())
                .is_acceptable();
        if accepted {
            (prev_alpha, prev_u0) = (alpha, u0);
            (alpha, u0) = (target, out.u0);
            if alpha >= T::one() {
                return Some(out);
            }
            let easy = work.iterations.saturating_sub(iterations_before) <= 3;
            step *= if easy { T::lit(2.0) } else { T::lit(1.25) };
        } else {
            step *= T::lit(0.5);
            if step < min_step {
                return None;
            }
        }
    }
    None
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Solves the forward problem: the equilibrium under `load` (plus the scene's gravity and point loads).
    ///
    /// Fails only on invalid input; a solve that does not converge, or converges to an unstable
    /// equilibrium, returns `Ok` with the reason in `report.termination`.
    pub fn solve(
        &self,
        load: &TipLoad<T>,
        start: Start<T>,
        settings: &ShootingSettings<T>,
    ) -> Result<Equilibrium<T>, ModelError> {
        load.validate()?;
        if let Start::Warm(u) = &start {
            finite_vec(u, "warm-start base strain")?;
        }
        crate::error::positive(settings.tolerance, "solver tolerance")?;
        crate::error::positive(settings.max_rotation_step_rad, "trust region")?;
        let mut work = Work::default();
        let mut load_steps = 0u16;

        // A cold start tries the full load from the capped small-deflection guess; if that fails, load
        // continuation starts with a step that bends the linear rod by about the same angle.
        let (direct_start, direct_iterations, first_step) = match start {
            Start::Cold => {
                let guess = self.linear_guess(load, T::one());
                let angle = guess.norm() * self.length_m();
                let limit = T::lit(GUESS_ANGLE_RAD);
                let scale = if angle > limit {
                    limit / angle
                } else {
                    T::one()
                };
                (
                    guess * scale,
                    settings.max_iterations.min(DIRECT_ITERATIONS),
                    scale.min(T::lit(0.5)),
                )
            }
            Start::Warm(u) => (u, settings.max_iterations, T::lit(0.25)),
        };
        let check = |out: &mut Newton<T>| {
            if out.termination.is_success() && settings.check_stability {
                let verdict = out.stability(self.conservative(&load.moment_nm), self.length_m());
                if !verdict.is_acceptable() {
                    out.termination = Termination::Unstable;
                }
                verdict
            } else {
                Stability::Unchecked
            }
        };
        let mut result = Some({
            let mut out = newton(
                self,
                load,
                T::one(),
                direct_start,
                settings,
                direct_iterations,
                &mut work,
            );
            let stability = check(&mut out);
            (out, stability)
        });
        let cold_allowed = matches!(start, Start::Cold) || settings.cold_fallback;
        let succeeded = result
            .as_ref()
            .is_some_and(|(out, _)| out.termination.is_success());
        if !succeeded && cold_allowed {
            result =
                match continuation(self, load, settings, first_step, &mut work, &mut load_steps) {
                    Some(mut out) => {
                        let stability = check(&mut out);
                        Some((out, stability))
                    }
                    None => result.map(|(mut out, stability)| {
                        out.termination = Termination::ContinuationFailed;
                        (out, stability)
                    }),
                };
        }
        let Some((mut outcome, stability)) = result else {
            return Ok(self.failed(load, Termination::ContinuationFailed, work, load_steps));
        };
        if outcome.termination.is_success()
            && !(outcome.sweep.frame_drift.is_finite()
                && outcome.sweep.frame_drift <= T::lit(MAX_FRAME_DRIFT))
        {
            outcome.termination = Termination::FrameDrift;
        }

        let mut cables = Vec::new();
        for c in outcome.sweep.cable_m.iter().take(self.rod().cables.len()) {
            // Cannot overflow: at most MAX_CABLES cables.
            let _ = cables.push(*c);
        }
        Ok(Equilibrium {
            base_strain_per_m: outcome.u0,
            load: *load,
            tip_position_m: outcome.sweep.tip_position_m,
            tip_rotation: outcome.sweep.tip_rotation,
            cable_lengths_m: cables,
            report: SolveReport {
                termination: outcome.termination,
                iterations: work.iterations,
                sweeps: work.sweeps,
                residual: outcome.residual,
                load_steps,
                stability,
            },
        })
    }

    fn failed(
        &self,
        load: &TipLoad<T>,
        termination: Termination,
        work: Work,
        load_steps: u16,
    ) -> Equilibrium<T> {
        Equilibrium {
            base_strain_per_m: Vector3::zeros(),
            load: *load,
            tip_position_m: Vector3::zeros(),
            tip_rotation: Matrix3::identity(),
            cable_lengths_m: Vec::new(),
            report: SolveReport {
                termination,
                iterations: work.iterations,
                sweeps: work.sweeps,
                residual: T::zero(),
                load_steps,
                stability: Stability::Unchecked,
            },
        }
    }
}
