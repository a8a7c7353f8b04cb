//! The inverse's reduced problem (variable projection): the tip-moment condition is eliminated
//! through the shooting Jacobian, leaving a least-squares problem in the load parameters alone.
//!
//! Unknowns: the base strain `u(0)` (3) and `P` load parameters `p`. Residuals: the tip-moment
//! condition `e` (3) and the cable-length mismatch `c(x) - c_meas`. Each iteration takes one sweep
//! with the tangents of the base strain and the tip force, which give the blocks `J_eu, J_ep, J_cu,
//! J_cp`, and
//!
//! `c~ = (c - c_meas) - J_cu J_eu^-1 e`, `G = J_cp - J_cu J_eu^-1 J_ep`,
//! `(G^T G / s^2 + W^2 + mu diag) dp = -(G^T c~ / s^2 + W^2 p)`, `du0 = -J_eu^-1 (e + J_ep dp)`,
//!
//! with `s` the measurement's standard deviation, `W` the prior's weights and a trust region on
//! `|du0| L`. An iterate whose tip-moment residual is too large for the reduced model is brought back
//! onto the equilibrium at its load by the forward solve's Newton iteration (`solve/newton.rs`).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::basis::{LoadBasis, ParamCount, Params, prior_weight_for};
use super::{CableVector, Estimate, InverseSettings};
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::ode::Family;
use crate::ode::dead_load::DeadLoadRod;
use crate::report::{MAX_FRAME_DRIFT, SolveReport, Termination};
use crate::scalar::from_columns;
use crate::shape::ShapeSink;
use crate::solve::newton::{NewtonOptions, Work, newton};
use crate::solve::stopping;
use crate::stability::{Stability, classify};
use crate::sweep::{Sweep, TangentSet, sweep};
use crate::{MAX_CABLES, Scalar};

/// Newton iterations (each one sweep) a projection back onto the equilibrium may take.
const PROJECTION_ITERATIONS: u16 = 8;

/// The linearisation of the residuals at one point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Linearization<T, const P: usize> {
    pub(super) e: Vector3<T>,
    pub(super) rc: CableVector<T>,
    pub(super) j_eu: Matrix3<T>,
    pub(super) j_ep: SMatrix<T, 3, P>,
    pub(super) j_cu: SMatrix<T, MAX_CABLES, 3>,
    pub(super) j_cp: SMatrix<T, MAX_CABLES, P>,
    pub(super) tip_position_m: Vector3<T>,
    pub(super) tip_rotation: Matrix3<T>,
    pub(super) d_tip_u: Matrix3<T>,
    pub(super) d_tip_p: SMatrix<T, 3, P>,
    pub(super) d_theta_tip_u: Matrix3<T>,
    pub(super) conjugate_point_m: Option<T>,
    pub(super) frame_drift: T,
}

impl<T: Scalar, const P: usize> Linearization<T, P> {
    pub(super) fn empty() -> Self {
        Self {
            e: Vector3::zeros(),
            rc: CableVector::zeros(),
            j_eu: Matrix3::identity(),
            j_ep: SMatrix::zeros(),
            j_cu: SMatrix::zeros(),
            j_cp: SMatrix::zeros(),
            tip_position_m: Vector3::zeros(),
            tip_rotation: Matrix3::identity(),
            d_tip_u: Matrix3::zeros(),
            d_tip_p: SMatrix::zeros(),
            d_theta_tip_u: Matrix3::identity(),
            conjugate_point_m: None,
            frame_drift: T::zero(),
        }
    }

    /// New residuals and tip pose from a plain sweep; the Jacobian blocks stay.
    pub(super) fn set_residual(&mut self, sw: &Sweep<T, 3>, rc: CableVector<T>) {
        self.e = sw.residual;
        self.rc = rc;
        self.tip_position_m = sw.tip_position_m;
        self.tip_rotation = sw.tip_rotation;
        self.frame_drift = sw.frame_drift;
    }
}

/// The reduced Gauss-Newton system at a linearisation.
pub(super) struct Reduced<T, const P: usize> {
    /// `J_eu^-1 J_ep`.
    pub(super) a: SMatrix<T, 3, P>,
    /// `J_eu^-1 e`.
    pub(super) b: Vector3<T>,
    /// Weighted sensitivity `G / s`.
    pub(super) g: SMatrix<T, MAX_CABLES, P>,
    /// Weighted reduced residual `c~ / s`.
    pub(super) c: CableVector<T>,
}

/// The state the solve moves: base strain and load parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Point<T, const P: usize> {
    pub(super) u0: Vector3<T>,
    pub(super) p: SVector<T, P>,
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Problem<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize> {
    pub(super) model: &'a Model<T, A, NODES>,
    pub(super) basis: LoadBasis<T, P>,
    pub(super) measured: CableVector<T>,
    pub(super) settings: InverseSettings<T>,
    pub(super) cables: usize,
    /// `1 / prior std` of each parameter (zero: no prior).
    pub(super) prior_weight: SVector<T, P>,
    /// The largest tip-moment residual (dimensionless) at which the reduced model is trusted: its
    /// second-order cable error, about `r e^2`, stays below a tenth of a standard deviation.
    pub(super) max_moment_residual: T,
}

impl<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>
    Problem<'a, T, A, P, NODES>
{
    pub(super) fn new(
        model: &'a Model<T, A, NODES>,
        basis: LoadBasis<T, P>,
        measured: CableVector<T>,
        settings: InverseSettings<T>,
    ) -> Self {
        Self {
            model,
            basis,
            measured,
            settings,
            cables: model.rod().cables.len(),
            prior_weight: prior_weight(model, &basis, &settings),
            max_moment_residual: {
                let radius = model
                    .rod()
                    .cables
                    .iter()
                    .fold(T::zero(), |r, c| r.max(c.radius_m()));
                (settings.length_std_m * T::lit(0.1) / radius).sqrt()
            },
        }
    }

    /// Brings a point back onto the equilibrium at its load when its tip-moment residual is too large
    /// for the reduced model: the forward solve's Newton iteration on the base strain alone (variable
    /// projection), to the residual the reduced model trusts. `sw` is the (finite) sweep at `x`.
    /// Returns the projected point and its linearisation, or `None` if that does not converge.
    pub(super) fn project(
        &self,
        mut x: Point<T, P>,
        sw: Sweep<T, 3>,
        work: &mut Work,
    ) -> Option<(Point<T, P>, Linearization<T, P>)> {
        if self.moment_residual(&sw.residual) <= self.max_moment_residual {
            return Some((x, self.linearize(&sw)));
        }
        let options = NewtonOptions {
            tolerance: self.max_moment_residual,
            to_rounding: false,
            max_step_rad: self.settings.max_rotation_step_rad,
            max_iterations: PROJECTION_ITERATIONS,
            tangents: self.tangents(),
        };
        let mut inner = Work::default();
        let out = newton(&self.ode(&x.p), x.u0, Some(sw), &options, &mut inner);
        work.sweeps = work.sweeps.saturating_add(inner.sweeps);
        if !out.termination.is_success() {
            return None;
        }
        x.u0 = out.x;
        Some((x, self.linearize(&out.sweep)))
    }

    /// The same problem with other prior weights.
    pub(super) fn with_prior(&self, prior_weight: SVector<T, P>) -> Self {
        Self {
            prior_weight,
            ..*self
        }
    }

    /// The graduated prior's weights at relaxation `relax` (1 at the start, halving): the start weights
    /// scaled down, but never below the final prior's; tiny ones become the final ones.
    pub(super) fn graduated(&self, start: &SVector<T, P>, relax: T) -> SVector<T, P> {
        if relax < T::lit(1e-6) {
            return self.prior_weight;
        }
        start.zip_map(&self.prior_weight, |s, f| (s * relax).max(f))
    }

    /// The rod equations at load parameters `p`.
    fn ode(&self, p: &SVector<T, P>) -> DeadLoadRod<'a, T, A, NODES> {
        DeadLoadRod::new(self.model, &self.basis.load(p), T::one())
    }

    /// The tangents of every linearisation: the base strain's and the tip force's.
    fn tangents(&self) -> TangentSet {
        TangentSet::with_tip_force(self.settings.check_stability)
    }

    /// The dimensionless size of a tip-moment residual, as in the forward solve.
    pub(super) fn moment_residual(&self, e: &Vector3<T>) -> T {
        e.norm() / self.model.moment_scale_nm()
    }

    pub(super) fn full_sweep(&self, x: &Point<T, P>) -> Sweep<T, 3> {
        self.sweep(x, true, None)
    }

    /// A sweep at `x`, with every tangent (`linearise`) or none, writing shape points into `shape`.
    pub(super) fn sweep(
        &self,
        x: &Point<T, P>,
        linearise: bool,
        shape: Option<&mut ShapeSink<'_, T>>,
    ) -> Sweep<T, 3> {
        let which = if linearise {
            self.tangents()
        } else {
            TangentSet::NONE
        };
        sweep(&self.ode(&x.p), &x.u0, which, shape)
    }

    pub(super) fn cable_residual(&self, sw: &Sweep<T, 3>) -> CableVector<T> {
        CableVector::from_fn(|c, _| {
            match (c < self.cables, sw.cable_m.get(c), self.measured.get(c)) {
                (true, Some(model), Some(measured)) => *model - *measured,
                _ => T::zero(),
            }
        })
    }

    pub(super) fn linearize(&self, sw: &Sweep<T, 3>) -> Linearization<T, P> {
        let (u, f) = (Family::Unknown, Family::TipForce);
        let j_eu = from_columns(|j| sw.d_residual(u, j));
        let j_ef: Matrix3<T> = from_columns(|j| sw.d_residual(f, j));
        // e = C u - R^T tau: d e / d tau = -R^T.
        let j_ep = j_ef * self.basis.force_n - sw.tip_rotation.tr_mul(&self.basis.moment_nm);
        let cable = |c: usize, family: Family, j: usize| {
            if c < self.cables {
                sw.d_cable_length(c, family, j)
            } else {
                T::zero()
            }
        };
        let j_cu = SMatrix::<T, MAX_CABLES, 3>::from_fn(|c, j| cable(c, u, j));
        let j_cf = SMatrix::<T, MAX_CABLES, 3>::from_fn(|c, j| cable(c, f, j));
        let tip = |family: Family| -> Matrix3<T> { from_columns(|j| sw.d_position(family, j)) };
        Linearization {
            e: sw.residual,
            rc: self.cable_residual(sw),
            j_eu,
            j_ep,
            j_cu,
            j_cp: j_cf * self.basis.force_n,
            tip_position_m: sw.tip_position_m,
            tip_rotation: sw.tip_rotation,
            d_tip_u: tip(u),
            d_tip_p: tip(f) * self.basis.force_n,
            d_theta_tip_u: from_columns(|j| sw.d_rotation(u, j)),
            conjugate_point_m: sw.conjugate_point_m,
            frame_drift: sw.frame_drift,
        }
    }

    pub(super) fn reduce(&self, lin: &Linearization<T, P>) -> Option<Reduced<T, P>> {
        let lu = lin.j_eu.lu();
        let a = lu.solve(&lin.j_ep)?;
        let b = lu.solve(&lin.e)?;
        let inv_std = T::one() / self.settings.length_std_m;
        let g = (lin.j_cp - lin.j_cu * a) * inv_std;
        let c = (lin.rc - lin.j_cu * b) * inv_std;
        let ok = crate::scalar::all_finite(&g)
            && crate::scalar::all_finite(&c)
            && crate::scalar::all_finite(&a);
        ok.then_some(Reduced { a, b, g, c })
    }

    /// The merit a step must decrease: the squared cable mismatch, in standard deviations, left once
    /// the tip-moment condition is restored to first order (`|c~|^2` of the reduced system, which
    /// the step minimises), plus the prior's `|p / prior std|^2`. Judging the full residual instead
    /// would let the moment condition's curvature veto steps along a weakly determined direction.
    pub(super) fn merit(&self, p: &SVector<T, P>, lin: &Linearization<T, P>) -> T {
        self.reduce(lin).map_or_else(
            || T::max_value().unwrap_or_else(T::one),
            |red| red.c.norm_squared() + p.component_mul(&self.prior_weight).norm_squared(),
        )
    }

    /// Whether the equilibrium at a linearisation may be accepted: not found unstable (an unstable
    /// equilibrium is not a physical answer, and a step onto one is rejected like a failed step).
    pub(super) fn acceptable(&self, p: &SVector<T, P>, lin: &Linearization<T, P>) -> bool {
        !self.settings.check_stability || self.stability(p, lin).is_acceptable()
    }

    pub(super) fn stability(&self, p: &SVector<T, P>, lin: &Linearization<T, P>) -> Stability<T> {
        let conservative = self.model.conservative(&self.basis.load(p).moment_nm);
        classify(
            conservative,
            lin.conjugate_point_m,
            &lin.j_eu,
            &lin.d_theta_tip_u,
            self.model.length_m(),
        )
    }

    /// The merit decrease the linear model predicts for a step `dp` from `p`.
    pub(super) fn predicted_decrease(
        &self,
        red: &Reduced<T, P>,
        p: &SVector<T, P>,
        dp: &SVector<T, P>,
    ) -> T {
        let w = &self.prior_weight;
        red.c.norm_squared() + p.component_mul(w).norm_squared()
            - (red.c + red.g * dp).norm_squared()
            - (p + dp).component_mul(w).norm_squared()
    }

    /// The information matrix `G^T G / s^2 + W^2` (data and prior).
    pub(super) fn information(&self, red: &Reduced<T, P>) -> SMatrix<T, P, P> {
        let w2 = self.prior_weight.component_mul(&self.prior_weight);
        red.g.tr_mul(&red.g) + SMatrix::from_diagonal(&w2)
    }

    /// The damped step from `p` (`mu = 0`: Gauss-Newton), limited by the trust region on the base
    /// rotation. The base-strain change has two parts: `-J_eu^-1 e`, which restores the tip-moment
    /// condition at the current load, and `-J_eu^-1 J_ep dp`, which follows the load step. The trust
    /// region shortens the load step first; shortening the first part too would leave the iterate off
    /// the equilibrium, where the reduced model no longer describes the problem.
    pub(super) fn step(
        &self,
        red: &Reduced<T, P>,
        p: &SVector<T, P>,
        mu: T,
    ) -> Option<(Vector3<T>, SVector<T, P>)> {
        let normal = self.information(red);
        let w2 = self.prior_weight.component_mul(&self.prior_weight);
        let gradient = red.g.tr_mul(&red.c) + w2.component_mul(p);
        // A tiny ridge keeps an undetermined direction from blowing the step up; LM damping on top.
        let ridge = normal.diagonal().max().max(T::one()) * T::default_epsilon() * T::lit(16.0);
        let damped = normal + SMatrix::from_diagonal(&(normal.diagonal() * mu).add_scalar(ridge));
        let dp = damped.cholesky()?.solve(&-gradient);
        let length = self.model.length_m();
        let limit = self.settings.max_rotation_step_rad;
        let restore = -red.b;
        let follow = -(red.a * dp);
        let (du, dp) = if (restore + follow).norm() * length <= limit {
            (restore + follow, dp)
        } else if restore.norm() * length >= limit {
            (
                restore * (limit / (restore.norm() * length)),
                SVector::zeros(),
            )
        } else {
            // The largest fraction k of the load step with |restore + k follow| L <= limit.
            let (a, b, c) = (
                follow.norm_squared(),
                restore.dot(&follow),
                restore.norm_squared() - (limit / length) * (limit / length),
            );
            let k = if a > T::zero() {
                ((b * b - a * c).max(T::zero()).sqrt() - b) / a
            } else {
                T::zero()
            };
            let k = k.max(T::zero()).min(T::one());
            (restore + follow * k, dp * k)
        };
        let finite = crate::scalar::all_finite(&du) && crate::scalar::all_finite(&dp);
        finite.then_some((du, dp))
    }

    /// Converged when the tip-moment condition holds and the rest of the way is negligible: the next
    /// Gauss-Newton step, plus what the steps still to come would add when the iteration converges
    /// only linearly (`step q / (1 - q)` for a contraction `q` from the previous step's tip move),
    /// would move the tip by less than the tip tolerance, and the fit (data and prior, in standard
    /// deviations) by less than the step tolerance. Both tolerances are raised to what the scalar type
    /// resolves. Returns the verdict and the step's tip move.
    pub(super) fn converged(
        &self,
        x: &Point<T, P>,
        lin: &Linearization<T, P>,
        red: &Reduced<T, P>,
        previous_tip_move: Option<T>,
    ) -> (bool, T) {
        let infinite = T::max_value().unwrap_or_else(T::one);
        let Some((du, dp)) = self.step(red, &x.p, T::zero()) else {
            return (false, infinite);
        };
        let tip_move = (lin.d_tip_u * du + lin.d_tip_p * dp).norm();
        // The tip-moment condition holds when its residual is small or, at the rounding floor, when
        // the correction it asks for (`J_eu^-1 e`) turns the base negligibly (what it does to the
        // tip is in `tip_move` below, against the tip tolerance).
        let length = self.model.length_m();
        let tolerance = self.settings.tolerance;
        let moment_ok = stopping::residual_converged(
            self.moment_residual(&lin.e),
            x.u0.norm() * length,
            tolerance,
        ) || stopping::step_negligible(
            red.b.norm() * length,
            x.u0.norm() * length,
            T::zero(),
            length,
            tolerance,
        );
        let remaining = match previous_tip_move {
            Some(previous) if previous > T::zero() && tip_move < previous => {
                let q = tip_move / previous;
                tip_move * q / (T::one() - q)
            }
            Some(_) => infinite,
            None => T::zero(),
        };
        // f32 resolves the tip to about the shooting tolerance (an angle) times the rod length.
        let tip_floor = stopping::tip_floor_m(length);
        let fit_move = (dp.transpose() * self.information(red) * dp)
            .x
            .max(T::zero())
            .sqrt();
        let fit_tolerance = self
            .settings
            .step_tolerance_sigma
            .max(stopping::fit_floor_sigma(
                length,
                self.settings.length_std_m,
            ));
        let done = moment_ok
            && tip_move + remaining <= self.settings.tip_tolerance_m.max(tip_floor)
            && fit_move <= fit_tolerance;
        (done, tip_move)
    }
}

/// `1 / prior std` for each parameter of `basis` (zero when the prior scale is infinite).
fn prior_weight<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>(
    model: &Model<T, A, NODES>,
    basis: &LoadBasis<T, P>,
    settings: &InverseSettings<T>,
) -> SVector<T, P> {
    prior_weight_for(model, basis, settings.prior_std_scale)
}

impl<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize> Problem<'_, T, A, P, NODES>
where
    Params: ParamCount<T, P>,
{
    pub(super) fn solve(&self, mut x: Point<T, P>, mut work: Work) -> Estimate<T, P> {
        work.sweeps = work.sweeps.saturating_add(1);
        let sw = self.full_sweep(&x);
        if !sw.finite {
            let lin = self.linearize(&sw);
            return self.finish(x, &lin, Termination::NonFinite, work);
        }
        let mut lin = self.linearize(&sw);
        // A graduated prior: the first steps hold the load to a tenth of the buckling scale, then the
        // prior relaxes by half each accepted step to its final value. From a cold start the linear
        // model can trade a large axial force for bending (at the sagging shape an axial force and a
        // lateral one bend the rod alike); the tight start finds the bending-consistent answer first.
        let start_weight = prior_weight_for(self.model, &self.basis, T::lit(0.1));
        let mut relax = T::one();
        let mut stage = self.with_prior(self.graduated(&start_weight, relax));
        let mut merit = stage.merit(&x.p, &lin);
        // Levenberg-Marquardt with Nielsen's damping update: the gain ratio (actual over predicted
        // decrease) sets the damping. It starts as Gauss-Newton.
        let mut mu = T::lit(1e-12);
        let mut nu = T::lit(2.0);
        let mut previous_tip_move = None;
        for _ in 0..self.settings.max_iterations {
            let Some(red) = self.reduce(&lin) else {
                return self.finish(x, &lin, Termination::Singular, work);
            };
            let final_stage = stage.prior_weight == self.prior_weight;
            let (done, tip_move) = stage.converged(&x, &lin, &red, previous_tip_move);
            if done && final_stage {
                return self.finish(x, &lin, Termination::Converged, work);
            }
            if done {
                // The tight prior has found the basin: go to the final prior at once.
                stage = *self;
                merit = stage.merit(&x.p, &lin);
                previous_tip_move = None;
                continue;
            }
            let Some((du, dp)) = stage.step(&red, &x.p, mu) else {
                return self.finish(x, &lin, Termination::Singular, work);
            };
            work.iterations = work.iterations.saturating_add(1);
            let trial = Point {
                u0: x.u0 + du,
                p: x.p + dp,
            };
            work.sweeps = work.sweeps.saturating_add(1);
            let sw = self.full_sweep(&trial);
            let projected = if sw.finite {
                self.project(trial, sw, &mut work)
            } else {
                None
            };
            let predicted = stage.predicted_decrease(&red, &x.p, &dp);
            match projected.map(|(t, l)| {
                let m = stage.merit(&t.p, &l);
                (t, l, m)
            }) {
                Some((trial, l, m))
                    if m < merit && predicted > T::zero() && self.acceptable(&trial.p, &l) =>
                {
                    let rho = (merit - m) / predicted;
                    let t = T::lit(2.0) * rho - T::one();
                    mu = (mu * (T::one() - t * t * t).max(T::lit(1.0 / 3.0))).max(T::lit(1e-15));
                    nu = T::lit(2.0);
                    (x, lin, merit) = (trial, l, m);
                    previous_tip_move = Some(tip_move);
                    if !final_stage {
                        relax *= T::lit(0.5);
                        stage = self.with_prior(self.graduated(&start_weight, relax));
                        merit = stage.merit(&x.p, &lin);
                        previous_tip_move = None;
                    }
                }
                _ => {
                    mu = (mu * nu).max(T::lit(1e-6));
                    nu *= T::lit(2.0);
                    if mu > T::lit(1e12) && !final_stage {
                        // Stuck under the graduated prior: release it and go on.
                        stage = *self;
                        merit = stage.merit(&x.p, &lin);
                        previous_tip_move = None;
                        mu = T::lit(1e-12);
                        nu = T::lit(2.0);
                    } else if mu > T::lit(1e12) {
                        // No step improves the fit. If the last Gauss-Newton step is itself negligible,
                        // this is the rounding floor, not a failure.
                        let termination = if stage.converged(&x, &lin, &red, None).0 {
                            Termination::Converged
                        } else {
                            Termination::Stalled
                        };
                        return self.finish(x, &lin, termination, work);
                    }
                }
            }
        }
        let final_stage = stage.prior_weight == self.prior_weight;
        let done = final_stage
            && self
                .reduce(&lin)
                .is_some_and(|r| self.converged(&x, &lin, &r, previous_tip_move).0);
        let termination = if done {
            Termination::Converged
        } else {
            Termination::IterationLimit
        };
        self.finish(x, &lin, termination, work)
    }

    pub(super) fn finish(
        &self,
        x: Point<T, P>,
        lin: &Linearization<T, P>,
        termination: Termination,
        work: Work,
    ) -> Estimate<T, P> {
        let red = self.reduce(lin);
        let quality = self.quality(lin, red.as_ref());
        let mut termination = termination;
        if termination.is_success()
            && !(lin.frame_drift.is_finite() && lin.frame_drift <= T::lit(MAX_FRAME_DRIFT))
        {
            termination = Termination::FrameDrift;
        }
        let stability = if termination.is_success() && self.settings.check_stability {
            let verdict = self.stability(&x.p, lin);
            if !verdict.is_acceptable() {
                termination = Termination::Unstable;
            }
            verdict
        } else {
            Stability::Unchecked
        };
        let moment = self.moment_residual(&lin.e);
        let cables = if self.cables > 0 {
            T::lit(self.cables as f64)
        } else {
            T::one()
        };
        let length_residual = (lin.rc.norm_squared() / cables).sqrt() / self.model.length_m();
        Estimate {
            params: x.p,
            load: self.basis.load(&x.p),
            base_strain_per_m: x.u0,
            tip_position_m: lin.tip_position_m,
            tip_rotation: lin.tip_rotation,
            cable_residual_m: lin.rc,
            report: SolveReport {
                termination,
                iterations: work.iterations,
                sweeps: work.sweeps,
                residual: moment.max(length_residual),
                load_steps: 0,
                stability,
            },
            quality,
        }
    }
}
