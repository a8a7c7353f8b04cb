//! The warm-started inverse for a control loop: one bounded update per tick from the last estimate.

use nalgebra::{Matrix3, SVector, Vector3};

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
use crate::shape::{MAX_SHAPE_POINTS, Shape, ShapePoint};
use crate::solve::newton::Work;
use crate::stability::Stability;

/// The largest load step, in buckling scales (`E I / L^2` of force), taken on a plain sweep (a
/// chord step): the chord step after a tracking update's predictor is a few thousandths (on the
/// bench's path, whose load moves 5-8 mN a tick, 0.045-0.067 buckling scales of 0.12 N); a jump
/// of the data (slack paid out at once) takes Newton steps.
const CHORD_STEP: f64 = 0.05;

/// Settings of the warm-started [`Estimator`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorSettings<T> {
    /// The inverse solve's settings, for the first (cold) estimate and every update.
    pub inverse: InverseSettings<T>,
    /// Most sweeps one update may take (its cost bound): plain sweeps, and sweeps with the six
    /// tangents (see [`Estimator`]), which cost about four plain ones and count as one. With
    /// `1`, every update is one Newton step and one sweep with tangents (see [`Estimator::update`]):
    /// the hard real-time mode.
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
    /// Five sweeps per update at most (two a typical update, one with tangents).
    pub fn with_inverse(inverse: InverseSettings<T>) -> Self {
        Self {
            inverse: InverseSettings {
                tolerance: inverse.tolerance.max(T::lit(1e-5)),
                tip_tolerance_m: inverse.tip_tolerance_m.max(T::lit(1e-5)),
                step_tolerance_sigma: inverse.step_tolerance_sigma.max(T::lit(1e-2)),
                ..inverse
            },
            max_sweeps: 5,
        }
    }
}

/// The warm-started inverse for a control loop.
///
/// Each [`Estimator::update`] starts from the last estimate, whose residual for the new
/// measurements needs no sweep (the model's cable lengths there are known; only the measurements
/// moved), and alternates sweeps with the six tangents (about four plain sweeps each) and plain
/// ones:
///
/// 1. The first trial continues the motion of the last two updates (second-order extrapolation of
///    the base strain and the load), its sweep carrying the tangents: an exact Jacobian where the
///    answer is near.
/// 2. Then a Gauss-Newton step of the reduced problem on a plain sweep (a chord step: the
///    Jacobian of those tangents): usually the last step. Only small steps go on a plain sweep
///    (0.05 buckling scales); a larger one is a Newton step with its tangents, judged on its own
///    stability test. The step after a plain one takes the tangents again, so an answer is always
///    published at most one step from its tangents: its posterior and stability verdict are those
///    of the Jacobian there (a cold estimate at the same data reports the same standard deviations
///    within 1.5 %).
/// 3. A rejected step on tangents taken elsewhere takes them at the last estimate; a step from
///    tangents taken there, judged on a plain sweep, is tried once more with the trial's own;
///    judged on tangents at both ends, the update stops (`Stalled`). An update after one that did
///    not converge (or after a cold estimate that did not) takes every trial with its tangents and
///    no predictor: the path that converges fast on data no load explains.
///
/// On the firmware's recorded path this is two sweeps an update (one with tangents), where Newton
/// from a chord step took three (two with tangents). The cost is bounded by
/// [`EstimatorSettings::max_sweeps`]; when the budget runs out the report says
/// [`Termination::IterationLimit`] and the next update carries on from there. Steps are limited by
/// the trust region, so the estimate follows its branch continuously.
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
    /// ([`Determination::Ambiguous`], or [`Determination::Unverified`], which includes a first
    /// estimate that did not converge and so was never searched around): every update inherits it.
    /// An update follows one branch from the last estimate and does not look for others, so it
    /// cannot lift the doubt; a new cold start can.
    doubt: Option<Determination>,
    /// The measurements `lin`'s cable residual refers to.
    measured: CableVector<T>,
    /// Steps on plain sweeps since `lin`'s Jacobian came from tangents (0: from tangents at `x`).
    /// An answer is published at most one such step from its tangents.
    age: u8,
    /// Whether the last update failed to converge: this one takes Newton steps (every trial with
    /// its tangents), as the chord steps did not carry it. Data no load explains (a slack cable)
    /// is a least-squares problem with a large residual, where only Newton's steps converge fast.
    newton: bool,
    /// The last update's move (when it converged or ran out of budget on the way): the next
    /// update's first trial continues it.
    velocity: Option<Point<T, P>>,
    /// The move of the update before it, for the extrapolation's second order.
    before: Option<Point<T, P>>,
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
            // A first estimate that did not converge was never searched around, whatever its
            // verdict (an unconverged fit can read `Inconsistent` and its updates then converge).
            doubt: match first.quality.determination {
                _ if !first.report.termination.is_success() => Some(Determination::Unverified),
                d @ (Determination::Ambiguous | Determination::Unverified) => Some(d),
                _ => None,
            },
            measured: CableVector::zeros(),
            age: u8::MAX,
            velocity: None,
            before: None,
            newton: first.report.termination != Termination::Converged,
        };
        let problem = estimator.problem(validate_measurements(model, measured_m)?);
        let sw = problem.sweep(&estimator.x, true, shape.as_mut().map(Shape::sink).as_mut());
        if sw.finite {
            estimator.lin = problem.linearize(&sw);
        }
        estimator.measured = problem.measured;
        estimator.age = if sw.finite { 0 } else { u8::MAX };
        Ok((estimator, first))
    }

    /// Forgets the last updates' motion, so that the next update takes no predictor: for a caller
    /// that skipped a tick (refused readings), whose next update covers two ticks of motion, not
    /// the one the predictor would continue.
    pub fn forget_motion(&mut self) {
        (self.velocity, self.before) = (None, None);
    }

    /// The current parameters.
    pub fn params(&self) -> SVector<T, P> {
        self.x.p
    }

    /// The tip frame at the current parameters (columns: the tip's axes in global coordinates):
    /// the last estimate's [`Estimate::tip_rotation`], whether that update converged or not.
    pub fn tip_rotation(&self) -> Matrix3<T> {
        self.lin.tip_rotation
    }

    fn problem(&self, measured: CableVector<T>) -> Problem<'a, T, A, P, NODES> {
        Problem::new(self.model, self.basis, measured, self.settings.inverse)
    }

    /// One estimate for new measurements (one per cable, m), warm-started from the last.
    ///
    /// With a budget of one sweep ([`EstimatorSettings::max_sweeps`] `= 1`) the update is one
    /// Gauss-Newton step from the last estimate with the Jacobian of its own sweep, and one sweep
    /// with the six tangents at the stepped point, which serve the next update: the cost is fixed
    /// (the hard real-time mode), and the estimate returned is the stepped point as that sweep saw
    /// it. It reports [`Termination::Converged`] when the last estimate already met the tolerances
    /// (or the step did), [`Termination::IterationLimit`] when it took a step.
    pub fn update(&mut self, measured_m: &[T]) -> Result<Estimate<T, P>, ModelError> {
        let out = self.update_inner(measured_m, None)?;
        Ok(self.settled(out))
    }

    /// [`Estimator::update`], and the backbone of the estimate at the arc lengths `s_m` (increasing,
    /// within `[0, L]`, at most [`MAX_SHAPE_POINTS`]) written into `out`, from the update's own
    /// sweeps: no sweep more (an update that needs no step takes one plain sweep for them, and
    /// counts it). The points are valid when the estimate is: on a failed update they belong to the
    /// last good estimate.
    pub fn update_with_shape(
        &mut self,
        measured_m: &[T],
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<Estimate<T, P>, ModelError> {
        let shape = Shape::new(self.model.length_m(), s_m, out)?;
        let out = self.update_inner(measured_m, Some(shape))?;
        Ok(self.settled(out))
    }

    /// An update's estimate as returned: the next update takes Newton steps when this one did not
    /// converge, and the first estimate's doubt carries over.
    fn settled(&mut self, out: Estimate<T, P>) -> Estimate<T, P> {
        let termination = out.report.termination;
        // (One sweep an update takes Newton steps anyway.)
        self.newton = self.settings.max_sweeps > 1 && termination != Termination::Converged;
        self.with_doubt(out)
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
        // The residual at the last estimate for the new measurements, without a sweep: the model's
        // cable lengths there are what they were, only the measurements moved.
        self.lin.rc += self.measured - problem.measured;
        self.measured = problem.measured;
        let start = self.x;
        // The first trial continues the motion of the last updates (when they converged or ran out
        // of budget on the way): their last move, plus its change since the one before
        // (second-order extrapolation). Not with one sweep an update, whose step must read the
        // new measurements, nor in Newton's steps after a failure.
        let velocity = self.velocity.take();
        let before = self.before.take();
        let mut predictor = velocity
            .map(|v| match before {
                Some(b) => Point {
                    u0: v.u0 * T::lit(2.0) - b.u0,
                    p: v.p * T::lit(2.0) - b.p,
                },
                None => v,
            })
            .filter(|v| {
                budget > 1
                    && !self.newton
                    && v.u0.norm() * self.model.length_m()
                        <= self.settings.inverse.max_rotation_step_rad
            });
        let mut red = problem.reduce(&self.lin);
        let mut current = problem.merit_of(&self.x.p, red.as_ref());
        // Whether `shape` holds the current point's backbone (written by a sweep of this update).
        let mut shaped = false;
        // Whether the next trial takes the tangents: a point that would pass the stopping test too
        // far from them, or a step from them retried on its own.
        let mut tangents_next = false;
        let mut refresh_next = false;
        let mut scratch = [ShapePoint::default(); MAX_SHAPE_POINTS];
        let termination = loop {
            let Some(reduced) = red.as_ref() else {
                break Termination::Singular;
            };
            let (done, _, step) = problem.converged_step(&self.x, &self.lin, reduced, None);
            // An answer is published at most one step from its tangents: the posterior and the
            // stability verdict read the whole Jacobian, and one taken further away reports other
            // standard deviations (with Broyden-updated Jacobians between tangents a quarter of a
            // buckling scale apart: 0.35-2.4 times a cold estimate's; one step from them, within
            // 1.5 %: `tests/estimator_warm.rs`). A point that passes further from them is tried
            // again with the tangents.
            let unproven = done && self.age > 1;
            let done = done && !unproven;
            tangents_next |= unproven;
            if done {
                if let (false, Some(shape)) = (shaped, shape.as_mut()) {
                    // Nothing moved enough to sweep: the shape takes one plain sweep.
                    work.sweeps += 1;
                    problem.sweep(&self.x, false, Some(&mut shape.sink()));
                }
                break Termination::Converged;
            }
            // The tangents at the last estimate, taken as a trial of no step (accepted as it is).
            let refresh = core::mem::take(&mut refresh_next);
            let predicted = if refresh { None } else { predictor.take() };
            let Some((du, dp)) = (if refresh {
                Some((Vector3::zeros(), SVector::zeros()))
            } else {
                predicted.map(|v| (v.u0, v.p)).or(step)
            }) else {
                break Termination::Singular;
            };
            if work.sweeps >= budget {
                break Termination::IterationLimit;
            }
            if !refresh {
                work.iterations = work.iterations.saturating_add(1);
            }
            work.sweeps += 1;
            let trial = Point {
                u0: self.x.u0 + du,
                p: self.x.p + dp,
            };
            // The tangents on every other sweep: a step from them goes on a plain sweep (a chord
            // step, its Jacobian that of the last tangents), the step after takes them again, so
            // the predictor's sweep carries them and the step from it, usually the last, is plain.
            // With one sweep an update, every trial takes them (they serve the next update). A
            // large step is a Newton step, judged on its trial's own stability test: a plain
            // sweep's reads the last tangents, and a step that could cross to another branch
            // must not be judged there.
            let large = dp.component_mul(&problem.buckling_weight).norm() > T::lit(CHORD_STEP);
            let linearise =
                refresh || budget == 1 || self.newton || self.age >= 1 || tangents_next || large;
            // A trial's shape goes into the scratch buffer, kept only if the trial is.
            let mut trial_shape = shape.as_ref().map(|s| Shape {
                s_m: s.s_m,
                out: scratch.get_mut(..s.s_m.len()).unwrap_or(&mut []),
            });
            let sw = problem.sweep(
                &trial,
                linearise,
                trial_shape.as_mut().map(Shape::sink).as_mut(),
            );
            if !sw.finite && refresh {
                break Termination::NonFinite;
            }
            if sw.finite {
                let lin = if linearise {
                    problem.linearize(&sw)
                } else {
                    let mut lin = self.lin;
                    lin.set_residual(&sw, problem.cable_residual(&sw));
                    lin
                };
                let trial_red = problem.reduce(&lin);
                let trial_merit = problem.merit_of(&trial.p, trial_red.as_ref());
                if refresh || (trial_merit < current && problem.acceptable(&trial.p, &lin)) {
                    tangents_next = false;
                    (self.x, self.lin, red, current) = (trial, lin, trial_red, trial_merit);
                    self.age = if linearise {
                        0
                    } else {
                        self.age.saturating_add(1)
                    };
                    if linearise {
                        self.stability = self.verdict(&problem);
                    }
                    if let (Some(shape), Some(trial)) = (shape.as_mut(), trial_shape) {
                        shape.take(trial);
                        shaped = true;
                    }
                    continue;
                }
                if linearise && !self.newton && self.age > 0 {
                    // The failed trial's tangents, taken next to here, serve here (a chord's).
                    self.lin.take_jacobian(&lin);
                    red = problem.reduce(&self.lin);
                    current = problem.merit_of(&self.x.p, red.as_ref());
                }
            }
            // A predictor that missed: a step from here instead. A failed step on tangents taken
            // elsewhere takes them here. A step from tangents taken here, judged on a plain sweep
            // (with them, where the tip-moment condition does not hold), is tried once more with
            // the trial's own; judged on tangents at both ends, the update stops.
            if predicted.is_some() {
                continue;
            }
            if self.age == 0 && !linearise && sw.finite && work.sweeps < budget {
                tangents_next = true;
                continue;
            }
            if self.age == 0 || work.sweeps >= budget {
                break Termination::Stalled;
            }
            refresh_next = true;
        };
        // The move of an update that converged, or ran out of budget on the way, predicts the
        // next one's.
        (self.before, self.velocity) = match termination {
            Termination::Converged | Termination::IterationLimit => (
                velocity,
                Some(Point {
                    u0: self.x.u0 - start.u0,
                    p: self.x.p - start.p,
                }),
            ),
            _ => (None, None),
        };
        Ok(self.finish(&problem, termination, work))
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
