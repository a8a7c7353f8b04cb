//! The warm-started inverse for a control loop: one bounded update per tick from the last estimate.

use nalgebra::SVector;

use super::basis::{LoadBasis, ParamCount, Params};
use super::quality::Determination;
use super::reduced::{Linearization, Point, Problem};
use super::{
    CableVector, Estimate, InverseSettings, InverseStart, estimate, validate_measurements,
};
use crate::Scalar;
use crate::error::ModelError;
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::plan::MAX_NODES;
use crate::report::Termination;
use crate::scalar::product;
use crate::shape::{MAX_SHAPE_POINTS, Shape, ShapePoint};
use crate::solve::newton::Work;
use crate::stability::Stability;

/// Settings of the warm-started [`Estimator`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorSettings<T> {
    /// The inverse solve's settings, for the first (cold) estimate and every update.
    pub inverse: InverseSettings<T>,
    /// Most sweeps one update may take (its cost bound). The first is a plain sweep; the others carry
    /// six tangents and cost about four plain sweeps each. With `1`, every update is exactly one sweep
    /// with six tangents and one Newton step (see [`Estimator::update`]): the hard real-time mode.
    pub max_sweeps: u8,
}

impl<T: Scalar> Default for EstimatorSettings<T> {
    /// See [`EstimatorSettings::with_inverse`].
    fn default() -> Self {
        Self::with_inverse(InverseSettings::default())
    }
}

impl<T: Scalar> EstimatorSettings<T> {
    /// Control-loop tolerances on top of the given inverse settings: a control loop needs the answer
    /// to a fraction of the measurement noise, not to rounding, so an update stops when the next step
    /// would move the tip by less than 10 um and the fit by less than 0.01 standard deviations, with
    /// the tip moment to 1e-5 of `E I / L` (a few um at the tip, consistent with the tip tolerance).
    /// Three sweeps per update at most.
    pub fn with_inverse(inverse: InverseSettings<T>) -> Self {
        Self {
            inverse: InverseSettings {
                tolerance: inverse.tolerance.max(T::lit(1e-5)),
                tip_tolerance_m: inverse.tip_tolerance_m.max(T::lit(1e-5)),
                step_tolerance_sigma: inverse.step_tolerance_sigma.max(T::lit(1e-2)),
                ..inverse
            },
            max_sweeps: 3,
        }
    }
}

/// The warm-started inverse for a control loop.
///
/// Each [`Estimator::update`] starts from the last estimate: a plain sweep gives the residual for
/// the new measurements, a step with the Jacobian kept from the last update (a chord step) moves
/// toward them, and the sweep at the trial point carries the six tangents, so an accepted point
/// brings its own exact Jacobian: Newton from the second step on, and a fresh Jacobian for the next
/// update. The cost is bounded by [`EstimatorSettings::max_sweeps`]; when the budget runs out the
/// report says [`Termination::IterationLimit`] and the next update carries on from there.
/// Steps are limited by the trust region, so the estimate follows its branch continuously.
#[derive(Clone, Debug)]
pub struct Estimator<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize = MAX_NODES>
{
    model: &'a Model<T, A, NODES>,
    basis: LoadBasis<T, P>,
    settings: EstimatorSettings<T>,
    x: Point<T, P>,
    lin: Linearization<T, P>,
    stability: Stability<T>,
    /// The first estimate's verdict when it could not rule out other answers
    /// ([`Determination::Ambiguous`] or [`Determination::Unverified`]): every update inherits it.
    /// An update follows one branch from the last estimate and does not look for others, so it
    /// cannot lift the doubt; a new cold start can.
    doubt: Option<Determination>,
}

impl<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>
    Estimator<'a, T, A, P, NODES>
where
    Params: ParamCount<T, P>,
{
    /// Starts from a cold estimate for the first measurements; returns the estimator and that estimate.
    pub fn new(
        model: &'a Model<T, A, NODES>,
        basis: LoadBasis<T, P>,
        measured_m: &[T],
        start_params: SVector<T, P>,
        settings: EstimatorSettings<T>,
    ) -> Result<(Self, Estimate<T, P>), ModelError> {
        Self::start(model, basis, measured_m, start_params, settings, None)
    }

    /// [`Estimator::new`], and the backbone of the first estimate at the arc lengths `s_m`
    /// (increasing, within `[0, L]`, at most [`MAX_SHAPE_POINTS`]) written into `out`, from the sweep
    /// that linearises it: no sweep more.
    pub fn new_with_shape(
        model: &'a Model<T, A, NODES>,
        basis: LoadBasis<T, P>,
        measured_m: &[T],
        start_params: SVector<T, P>,
        settings: EstimatorSettings<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<(Self, Estimate<T, P>), ModelError> {
        let shape = Shape::new(model.length_m(), s_m, out)?;
        Self::start(
            model,
            basis,
            measured_m,
            start_params,
            settings,
            Some(shape),
        )
    }

    fn start(
        model: &'a Model<T, A, NODES>,
        basis: LoadBasis<T, P>,
        measured_m: &[T],
        start_params: SVector<T, P>,
        settings: EstimatorSettings<T>,
        mut shape: Option<Shape<'_, T>>,
    ) -> Result<(Self, Estimate<T, P>), ModelError> {
        if settings.max_sweeps == 0 {
            return Err(ModelError::NotPositive("estimator sweep budget"));
        }
        let first = estimate(
            model,
            &basis,
            measured_m,
            InverseStart::Params(start_params),
            &settings.inverse,
        )?;
        let mut estimator = Estimator {
            model,
            basis,
            settings,
            x: Point {
                u0: first.base_strain_per_m,
                p: first.params,
            },
            lin: Linearization::empty(),
            stability: first.report.stability,
            doubt: match first.quality.determination {
                d @ (Determination::Ambiguous | Determination::Unverified) => Some(d),
                _ => None,
            },
        };
        let problem = estimator.problem(validate_measurements(model, measured_m)?);
        let sw = problem.sweep(&estimator.x, true, shape.as_mut().map(Shape::sink).as_mut());
        if sw.finite {
            estimator.lin = problem.linearize(&sw);
        }
        Ok((estimator, first))
    }

    /// The current parameters.
    pub fn params(&self) -> SVector<T, P> {
        self.x.p
    }

    fn problem(&self, measured: CableVector<T>) -> Problem<'a, T, A, P, NODES> {
        Problem::new(self.model, self.basis, measured, self.settings.inverse)
    }

    /// One estimate for new measurements (one per cable, m), warm-started from the last.
    ///
    /// With a budget of one sweep ([`EstimatorSettings::max_sweeps`] `= 1`) the update is exactly one
    /// sweep with six tangents at the last estimate, for the new measurements, and one Newton step
    /// from it: the cost is fixed, and the estimate returned is the one after the step, its tip and
    /// cable lengths predicted linearly (the error is second order in the change since the last
    /// update, and the next update measures it). It reports [`Termination::Converged`] when the
    /// last estimate already met the tolerances, [`Termination::IterationLimit`] when it took a step.
    pub fn update(&mut self, measured_m: &[T]) -> Result<Estimate<T, P>, ModelError> {
        self.update_inner(measured_m, None)
            .map(|out| self.with_doubt(out))
    }

    /// [`Estimator::update`], and the backbone of the estimate at the arc lengths `s_m` (increasing,
    /// within `[0, L]`, at most [`MAX_SHAPE_POINTS`]) written into `out`, from the update's own
    /// sweeps: no sweep more. (The one-sweep update's estimate is a linear prediction that no sweep
    /// has seen: it takes one plain sweep more for its shape, and counts it.) The points are valid
    /// when the estimate is: on a failed update they belong to the last good estimate.
    pub fn update_with_shape(
        &mut self,
        measured_m: &[T],
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<Estimate<T, P>, ModelError> {
        let shape = Shape::new(self.model.length_m(), s_m, out)?;
        self.update_inner(measured_m, Some(shape))
            .map(|out| self.with_doubt(out))
    }

    /// An update's estimate with the first estimate's doubt, if any (see [`Estimator`]).
    fn with_doubt(&self, mut out: Estimate<T, P>) -> Estimate<T, P> {
        if let Some(doubt) = self.doubt {
            out.quality.determination = out.quality.determination.at_best(doubt);
        }
        out
    }

    fn update_inner(
        &mut self,
        measured_m: &[T],
        mut shape: Option<Shape<'_, T>>,
    ) -> Result<Estimate<T, P>, ModelError> {
        let problem = self.problem(validate_measurements(self.model, measured_m)?);
        let mut work = Work::default();
        let budget = u16::from(self.settings.max_sweeps);
        if budget == 1 {
            let mut out = self.one_step(&problem, work);
            if let Some(mut shape) = shape {
                // The stepped point's shape, from one plain sweep at it.
                out.report.sweeps = out.report.sweeps.saturating_add(1);
                problem.sweep(&self.x, false, Some(&mut shape.sink()));
            }
            return Ok(out);
        }

        // The residual at the last estimate for the new measurements; the Jacobian is the last one.
        work.sweeps += 1;
        let sw = problem.sweep(&self.x, false, shape.as_mut().map(Shape::sink).as_mut());
        if !sw.finite {
            return Ok(problem.finish(self.x, &self.lin, Termination::NonFinite, work));
        }
        self.lin.set_residual(&sw, problem.cable_residual(&sw));
        let mut merit = problem.merit(&self.x.p, &self.lin);
        let mut exact = false;
        let mut scratch = [ShapePoint::default(); MAX_SHAPE_POINTS];
        loop {
            let Some(red) = problem.reduce(&self.lin) else {
                return Ok(self.finish(&problem, Termination::Singular, work));
            };
            if problem.converged(&self.x, &self.lin, &red, None).0 {
                return Ok(self.finish(&problem, Termination::Converged, work));
            }
            let Some((du, dp)) = problem.step(&red, &self.x.p, T::zero()) else {
                return Ok(self.finish(&problem, Termination::Singular, work));
            };
            if work.sweeps >= budget {
                return Ok(self.finish(&problem, Termination::IterationLimit, work));
            }
            work.iterations = work.iterations.saturating_add(1);
            work.sweeps += 1;
            let trial = Point {
                u0: self.x.u0 + du,
                p: self.x.p + dp,
            };
            // A trial's shape goes into the scratch buffer, kept only if the trial is.
            let mut trial_shape = shape.as_ref().map(|s| Shape {
                s_m: s.s_m,
                out: scratch.get_mut(..s.s_m.len()).unwrap_or(&mut []),
            });
            let sw = problem.sweep(&trial, true, trial_shape.as_mut().map(Shape::sink).as_mut());
            if sw.finite {
                let lin = problem.linearize(&sw);
                let trial_merit = problem.merit(&trial.p, &lin);
                if trial_merit < merit && problem.acceptable(&trial.p, &lin) {
                    (self.x, self.lin, merit, exact) = (trial, lin, trial_merit, true);
                    self.stability = self.verdict(&problem);
                    if let (Some(shape), Some(trial)) = (shape.as_mut(), trial_shape) {
                        shape.take(trial);
                    }
                    continue;
                }
            }
            // The step failed. With a stale Jacobian, refresh it here once; with an exact one, stop.
            if exact || work.sweeps >= budget {
                return Ok(self.finish(&problem, Termination::Stalled, work));
            }
            work.sweeps += 1;
            let sw = problem.full_sweep(&self.x);
            if !sw.finite {
                return Ok(self.finish(&problem, Termination::NonFinite, work));
            }
            self.lin = problem.linearize(&sw);
            self.stability = self.verdict(&problem);
            exact = true;
        }
    }

    /// The hard real-time update: one exact linearisation at the last estimate, one Newton step.
    fn one_step(
        &mut self,
        problem: &Problem<'_, T, A, P, NODES>,
        mut work: Work,
    ) -> Estimate<T, P> {
        work.sweeps = 1;
        let sw = problem.full_sweep(&self.x);
        if !sw.finite {
            return problem.finish(self.x, &self.lin, Termination::NonFinite, work);
        }
        self.lin = problem.linearize(&sw);
        self.stability = self.verdict(problem);
        let Some(red) = problem.reduce(&self.lin) else {
            return self.finish(problem, Termination::Singular, work);
        };
        if problem.converged(&self.x, &self.lin, &red, None).0 {
            return self.finish(problem, Termination::Converged, work);
        }
        let Some((du, dp)) = problem.step(&red, &self.x.p, T::zero()) else {
            return self.finish(problem, Termination::Singular, work);
        };
        work.iterations = 1;
        // The state after the step, predicted by the exact linearisation just taken.
        let lin = &mut self.lin;
        lin.e += product(&lin.j_eu, &du) + product(&lin.j_ep, &dp);
        lin.rc += product(&lin.j_cu, &du) + product(&lin.j_cp, &dp);
        lin.tip_position_m += product(&lin.d_tip_u, &du) + product(&lin.d_tip_p, &dp);
        self.x = Point {
            u0: self.x.u0 + du,
            p: self.x.p + dp,
        };
        let mut out = problem.finish(self.x, &self.lin, Termination::IterationLimit, work);
        out.report.stability = self.stability;
        out
    }

    fn verdict(&self, problem: &Problem<'_, T, A, P, NODES>) -> Stability<T> {
        if problem.settings.check_stability {
            problem.stability(&self.x.p, &self.lin)
        } else {
            Stability::Unchecked
        }
    }

    fn finish(
        &self,
        problem: &Problem<'_, T, A, P, NODES>,
        termination: Termination,
        work: Work,
    ) -> Estimate<T, P> {
        let mut out = problem.finish(self.x, &self.lin, termination, work);
        // Stability is judged at the last exact Jacobian.
        if out.report.termination.is_success() {
            out.report.stability = self.stability;
            if !self.stability.is_acceptable() {
                out.report.termination = Termination::Unstable;
            }
        }
        out
    }
}
