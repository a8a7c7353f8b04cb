//! The estimator loop: one [`EstimatorLoop::tick`] per control period, on the sampler's latest
//! [`Sample`].
//!
//! Readings -> validation -> warm-started f32 [`Estimator::update`] (a cold estimate on the first
//! good tick) -> tip force, tip pose and a few backbone points (from the solve's own sweeps). An
//! estimate is published ([`Status::Fresh`]) only when the solve converged and the cables determine
//! the load (`Determined` or `Weak`); anything else leaves the last good estimate in place and says
//! why: a refused reading (the sampler's refusal or latched fault included), a solve that did not
//! converge, data no load explains ([`Status::Inconsistent`], [`Status::SlackCable`]) or a load the
//! cables do not determine ([`Status::Indeterminate`]). After [`LoopConfig::restart_after`] failed
//! solves in a row the next tick starts cold again (a warm start that lost the answer does not find
//! it by itself); an estimate another answer may explain as well (`Ambiguous`, or `Unverified`
//! when the cold search for other answers ran out of budget) counts as failed, since the warm
//! updates after it inherit the doubt and only a cold start looks again. Nothing here panics.

use model_core::inverse::{Determination, Estimate, Estimator, EstimatorSettings, LoadBasis};
use model_core::shape::check_queries;
use model_core::{Attitude, Model, ModelError, ShapePoint, Termination};
use nalgebra::{Matrix3, Vector3};

use crate::sampler::Sample;
use crate::validate::{CABLES, ReadingValidator, Rejection};

/// Backbone points reported each tick.
pub const SHAPE_POINTS: usize = 4;

// The estimator hands out at most this many points from its own sweeps.
const _: () = assert!(SHAPE_POINTS <= model_core::shape::MAX_SHAPE_POINTS);

/// How the loop runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopConfig {
    /// The sampler's period, s: the loop measures time in samples ([`Sample::seq`]).
    pub sample_period_s: f32,
    /// Fastest the drives can move a cable, m/s: a reading that moved further in the elapsed time
    /// is refused.
    pub max_cable_speed_m_per_s: f32,
    /// Added to the speed limit for quantisation and noise, m.
    pub step_margin_m: f32,
    /// The warm-started inverse's settings (measurement noise, sweep budget per tick). With a budget
    /// of one sweep (model-core's hard real-time mode) every update takes one Newton step and is
    /// used as it is: [`TickRecord::converged`] says whether it had already converged.
    pub estimator: EstimatorSettings<f32>,
    /// Arc lengths of the reported backbone points, m, increasing, within the rod.
    pub shape_s_m: [f32; SHAPE_POINTS],
    /// Failed solves in a row after which the next tick starts cold (a cold estimate costs several
    /// ticks' worth of work, once).
    pub restart_after: u8,
}

/// One tick's estimate: what the loop outputs.
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct TickRecord {
    /// The tick that produced it.
    pub tick: u32,
    /// Tip force, N, global frame.
    pub tip_force_n: [f32; 3],
    /// Standard deviation of each force component, N.
    pub force_std_n: [f32; 3],
    /// Tip position, m, global frame.
    pub tip_position_m: [f32; 3],
    /// Standard deviation of each tip coordinate, m.
    pub tip_std_m: [f32; 3],
    /// Tip tangent (unit), global frame.
    pub tip_tangent: [f32; 3],
    /// Backbone positions at [`LoopConfig::shape_s_m`], m.
    pub backbone_m: [[f32; 3]; SHAPE_POINTS],
    /// The cable lengths it explains, m.
    pub cable_length_m: [f32; CABLES],
    /// Model minus measured cable length, m.
    pub cable_residual_m: [f32; CABLES],
    /// Sweeps the solve took (its cost).
    pub sweeps: u16,
    /// Whether it came from a cold start (the first estimate, or a restart).
    pub cold: bool,
    /// Whether the solve met its tolerances (always, except for a one-sweep update's step, whose
    /// tip and cable lengths are predicted linearly).
    pub converged: bool,
    /// How well the cables determine the force.
    pub determination: Determination,
}

/// What happened in a tick. Only [`Status::Fresh`] publishes an estimate.
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub enum Status<E> {
    /// A new estimate was made from this tick's readings: converged, and the cables determine the
    /// load (`Determined` or `Weak`; the record says which).
    Fresh,
    /// A reading was refused; the readings were not used. A sampler fault (`E` =
    /// [`crate::sampler::SampleError`]) is named here every tick until the sampler is re-homed.
    Rejected(Rejection<E>),
    /// The solve did not converge (or converged to an unstable equilibrium) within its budget; the
    /// next tick carries on from where it stopped.
    NotConverged(Termination),
    /// The model refused the input or the settings.
    Refused(ModelError),
    /// The solve ended (converged or stalled) with no load of the model explaining the lengths
    /// within three standard deviations (model-core's `Inconsistent`), and the misfit is not the
    /// slack pattern below. Not published.
    Inconsistent {
        /// Rms of the cable misfits in standard deviations.
        residual_rms_sigma: f32,
    },
    /// As [`Status::Inconsistent`], with every cable measuring longer than the model's path (model
    /// minus measured below minus three standard deviations on all three): the lengths are longer
    /// than any shape of the rod makes, which a slack cable does. The misfit is spread over the
    /// cables almost alike whichever is slack (README.md, "Faults"), so `cable` is the one that
    /// paid out most since the last fresh estimate. Not published.
    SlackCable {
        /// The cable taken to be slack.
        cable: u8,
        /// The largest misfit, measured minus model, m.
        excess_m: f32,
    },
    /// The solve converged but the cables do not determine the load (model-core's `Undetermined`,
    /// or any verdict other than `Determined`, `Weak` and `Inconsistent`). Not published.
    Indeterminate(Determination),
}

/// A tick's report: its status and the newest good estimate (this tick's when the status is
/// [`Status::Fresh`], else the last good one; `None` until a first estimate succeeds).
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct TickReport<E> {
    /// The tick, counting from 0.
    pub tick: u32,
    /// The sample the tick used ([`Sample::seq`]).
    pub sample: u32,
    /// What happened.
    pub status: Status<E>,
    /// The newest good estimate.
    pub estimate: Option<TickRecord>,
}

/// The estimator loop over an f32 model of the three-cable rod, with attitude `A` and room for
/// `NODES` plan nodes (the firmware's is `config::BenchModel`, built by [`crate::config::model`]).
#[derive(Debug)]
pub struct EstimatorLoop<'m, A: Attitude<f32>, const NODES: usize> {
    model: &'m Model<f32, A, NODES>,
    config: LoopConfig,
    validator: ReadingValidator,
    estimator: Option<WarmEstimator<'m, A, NODES>>,
    last: Option<TickRecord>,
    next_tick: u32,
    failures_in_row: u8,
    /// The last cold solve found no load explaining the data.
    cold_misfit: bool,
}

impl<'m, A: Attitude<f32>, const NODES: usize> EstimatorLoop<'m, A, NODES> {
    /// A loop over `model` (three cables).
    ///
    /// # Errors
    /// [`ModelError`] for a model without three cables or a non-positive period, speed or margin.
    pub fn new(model: &'m Model<f32, A, NODES>, config: LoopConfig) -> Result<Self, ModelError> {
        if !(config.sample_period_s.is_finite() && config.sample_period_s > 0.0) {
            return Err(ModelError::NotPositive("sample period"));
        }
        let validator = ReadingValidator::new(
            model,
            config.max_cable_speed_m_per_s * config.sample_period_s,
            config.step_margin_m,
        )?;
        // The backbone's arc lengths, checked once here (the solves write the points each tick).
        check_queries(&config.shape_s_m, SHAPE_POINTS, model.length_m())?;
        Ok(Self {
            model,
            config,
            validator,
            estimator: None,
            last: None,
            next_tick: 0,
            failures_in_row: 0,
            cold_misfit: false,
        })
    }

    /// The newest good estimate.
    pub fn last_estimate(&self) -> Option<&TickRecord> {
        self.last.as_ref()
    }

    /// The tip frame at the estimator's current point (columns: the tip's axes in global
    /// coordinates): that of the estimate a tick just published when its status is
    /// [`Status::Fresh`] (after any other status it may be a failed update's). `None` before the first estimate and after a
    /// restart. Not part of [`TickRecord`], so that the loop's own output stays as small as it was;
    /// the live link reads it after each fresh tick.
    pub fn tip_rotation(&self) -> Option<Matrix3<f32>> {
        self.estimator.as_ref().map(Estimator::tip_rotation)
    }

    /// One control tick on the sampler's latest sample (one length per cable, m, or why not).
    pub fn tick<E: Copy>(&mut self, sample: &Sample<E>) -> TickReport<E> {
        let tick = self.next_tick;
        self.next_tick = self.next_tick.wrapping_add(1);
        let status = match self.validator.check(sample.seq, &sample.readings) {
            Err(rejection) => {
                // The next update covers two ticks of motion: no predictor from one.
                if let Some(estimator) = self.estimator.as_mut() {
                    estimator.forget_motion();
                }
                Status::Rejected(rejection)
            }
            Ok(lengths_m) => {
                self.validator.accept(sample.seq, lengths_m);
                self.estimate(tick, &lengths_m)
            }
        };
        TickReport {
            tick,
            sample: sample.seq,
            status,
            estimate: self.last,
        }
    }

    /// Starts over after the sampler was re-homed: the next good tick is a cold estimate and its
    /// readings are not jump-checked against the ones before. The last good estimate is kept (its
    /// tick says how old it is).
    pub fn restart(&mut self) {
        self.estimator = None;
        self.validator.forget();
        self.failures_in_row = 0;
        self.cold_misfit = false;
    }

    fn estimate<E>(&mut self, tick: u32, lengths_m: &[f32; CABLES]) -> Status<E> {
        let (status, solved) = self.solve(tick, lengths_m);
        if solved {
            self.failures_in_row = 0;
        } else {
            self.failures_in_row = self.failures_in_row.saturating_add(1);
            if self.failures_in_row >= self.config.restart_after {
                self.estimator = None;
                self.failures_in_row = 0;
            }
        }
        status
    }

    /// The tick's status, and whether the solve finished (a failed one counts toward a restart).
    fn solve<E>(&mut self, tick: u32, lengths_m: &[f32; CABLES]) -> (Status<E>, bool) {
        let is_cold = self.estimator.is_none();
        // The backbone comes from the solve's own sweeps (no sweep more).
        let mut points = [ShapePoint::default(); SHAPE_POINTS];
        let shape_s_m = &self.config.shape_s_m;
        let result = match &mut self.estimator {
            Some(estimator) => warm(estimator, lengths_m, shape_s_m, &mut points),
            None => cold(
                self.model,
                lengths_m,
                self.config.estimator,
                shape_s_m,
                &mut points,
            )
            .map(|(estimator, first)| {
                self.estimator = Some(estimator);
                first
            }),
        };
        let estimate = match result {
            Ok(estimate) => estimate,
            Err(error) => return (Status::Refused(error), false),
        };
        let termination = estimate.report.termination;
        let converged = termination.is_success();
        // A one-sweep update always stops at its step (`IterationLimit`); that step is its answer.
        let one_step = !is_cold
            && self.config.estimator.max_sweeps == 1
            && termination == Termination::IterationLimit;
        let finished = converged || one_step;
        // A stall (no step reduces the misfit) says the data fit no load only when a cold solve
        // reached it, or a warm one on data a cold solve already found so: a warm update that lost
        // track stalls with a large misfit on good data too.
        let stall_judges = termination == Termination::Stalled && (is_cold || self.cold_misfit);
        if is_cold {
            self.cold_misfit = false;
        }
        // Anything but `Determined` and `Weak` is not published (model-core may add verdicts).
        match estimate.quality.determination {
            Determination::Determined | Determination::Weak if finished => {}
            Determination::Inconsistent if finished || stall_judges => {
                self.cold_misfit |= is_cold;
                let status = self.misfit(lengths_m, &estimate);
                return (status, finished);
            }
            _ if !finished => return (Status::NotConverged(termination), false),
            // Another answer may explain the data as well (or could not be ruled out): the warm
            // updates that follow inherit the doubt, so the loop counts it toward a cold restart,
            // which looks again.
            doubt @ (Determination::Ambiguous | Determination::Unverified) => {
                return (Status::Indeterminate(doubt), false);
            }
            other => return (Status::Indeterminate(other), true),
        }
        self.cold_misfit = false;
        self.last = Some(record(
            tick, lengths_m, &estimate, &points, is_cold, converged,
        ));
        (Status::Fresh, true)
    }

    /// The status of an estimate no load explains: [`Status::SlackCable`] when every cable measures
    /// longer than the model's path by more than three standard deviations, else
    /// [`Status::Inconsistent`].
    fn misfit<E>(&self, lengths_m: &[f32; CABLES], estimate: &Estimate<f32, 3>) -> Status<E> {
        let noise_m = 3.0 * self.config.estimator.inverse.length_std_m;
        let (mut excess_m, mut cable) = (f32::NEG_INFINITY, 0u8);
        let mut all_long = true;
        for (index, residual) in estimate.cable_residual_m.iter().take(CABLES).enumerate() {
            all_long &= *residual < -noise_m;
            if -residual > excess_m {
                (excess_m, cable) = (-residual, index as u8);
            }
        }
        if !all_long {
            return Status::Inconsistent {
                residual_rms_sigma: estimate.quality.residual_rms_sigma,
            };
        }
        // The cable that paid out most since the last fresh estimate (with no history, the one
        // with the largest misfit).
        if let Some(last) = &self.last {
            let mut most = f32::NEG_INFINITY;
            for (index, (now, then)) in lengths_m.iter().zip(last.cable_length_m).enumerate() {
                if now - then > most {
                    most = now - then;
                    cable = index as u8;
                }
            }
        }
        Status::SlackCable { cable, excess_m }
    }
}

/// The tick's output record of a converged estimate and its backbone points.
fn record(
    tick: u32,
    lengths_m: &[f32; CABLES],
    estimate: &Estimate<f32, 3>,
    points: &[ShapePoint<f32>; SHAPE_POINTS],
    cold: bool,
    converged: bool,
) -> TickRecord {
    let array = |v: &Vector3<f32>| [v.x, v.y, v.z];
    let mut residual = [0.0f32; CABLES];
    for (slot, value) in residual.iter_mut().zip(estimate.cable_residual_m.iter()) {
        *slot = *value;
    }
    TickRecord {
        tick,
        tip_force_n: array(&estimate.params),
        force_std_n: array(&estimate.quality.force_std_n),
        tip_position_m: array(&estimate.tip_position_m),
        tip_std_m: array(&estimate.quality.tip_std_m),
        tip_tangent: array(&estimate.tip_rotation.column(2).into_owned()),
        backbone_m: points.map(|p| array(&p.position_m)),
        cable_length_m: *lengths_m,
        cable_residual_m: residual,
        sweeps: estimate.report.sweeps,
        cold,
        converged,
        determination: estimate.quality.determination,
    }
}

type WarmEstimator<'m, A, const NODES: usize> = Estimator<'m, f32, A, 3, NODES>;

/// The first estimate: a cold inverse solve. Kept out of line so that its frame (a cold forward
/// solve with load continuation) is not added to the warm path's on the stack.
#[inline(never)]
fn cold<'m, A: Attitude<f32>, const NODES: usize>(
    model: &'m Model<f32, A, NODES>,
    lengths_m: &[f32; CABLES],
    settings: EstimatorSettings<f32>,
    shape_s_m: &[f32; SHAPE_POINTS],
    points: &mut [ShapePoint<f32>; SHAPE_POINTS],
) -> Result<(WarmEstimator<'m, A, NODES>, Estimate<f32, 3>), ModelError> {
    Estimator::new_with_shape(
        model,
        LoadBasis::tip_force(),
        lengths_m,
        Vector3::zeros(),
        settings,
        shape_s_m,
        points,
    )
}

/// A warm update, out of line for the same reason as [`cold`].
#[inline(never)]
fn warm<A: Attitude<f32>, const NODES: usize>(
    estimator: &mut WarmEstimator<'_, A, NODES>,
    lengths_m: &[f32; CABLES],
    shape_s_m: &[f32; SHAPE_POINTS],
    points: &mut [ShapePoint<f32>; SHAPE_POINTS],
) -> Result<Estimate<f32, 3>, ModelError> {
    estimator.update_with_shape(lengths_m, shape_s_m, points)
}

#[cfg(test)]
mod tests;
