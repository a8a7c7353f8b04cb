//! Displacement control (MODEL.md §6.3): the spool encoders give each tendon's displacement and the
//! tensions are unknowns.
//!
//! Tendon `j` was set on the straight, unloaded rod with zero tension: its unstretched free length,
//! spool to termination, was `U0 = feed + rest`, `rest` its path there (its termination's arc
//! length). The spool has since taken in `d_j` (positive shortens), leaving `U0 - d`. The
//! equilibrium at tensions `tau` needs the unstretched length `N(tau, F)` (`paths.rs`: the feed and
//! every chord, each shortened by its own tension's stretch `tau / E_t A_t`). The gap
//! `phi = U0 - d - N` is the slack: a taut tendon has `phi = 0` and `tau >= 0`, a slack one
//! `tau = 0` and `phi >= 0`; never a negative tension, never a tendon longer than its stretch
//! allows. This complementarity is solved as
//! `FB(tau / tau_s, phi / r) = a + b - sqrt(a^2 + b^2) = 0` (Fischer-Burmeister) by a semi-smooth
//! Newton with a backtracking line search; `tau_s` bends the rod about a radian through the largest
//! offset `r`. Each iteration is a forward solve from tensions (`forward.rs`), warm, and the path's
//! sensitivity to the tensions (`sensitivity.rs`: from tangents, frictionless; else differences),
//! carried with Broyden's secants between fresh ones.

use heapless::Vec;
use nalgebra::{SMatrix, SVector, Vector3};

use super::complementarity::{Complementarity, residual_size};
use super::joint_step::Sensitivities;
use super::sensitivity::{sensitivity, tension_scale_n, traceable};
use super::{MAX_TENDONS, TendonEquilibrium, Tendons};
use crate::Scalar;
use crate::error::{ModelError, finite, positive};
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::tendon::JumpMemory;
use crate::report::Termination;
use crate::shooting::ShootingSettings;
use crate::solve::stopping::default_tolerance;
use crate::solve::{Chord, Confirm};

/// Settings of the displacement-controlled solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplacementSettings<T> {
    /// Semi-smooth Newton iterations.
    pub max_iterations: u16,
    /// Tolerance on the complementarity residual, dimensionless (a path error over the largest
    /// offset, a tension over the tension that bends the rod a radian). The iteration goes on to
    /// the rounding floor while it still improves; an answer must at least meet this.
    pub tolerance: T,
    /// Whether a solve that carries no sensitivity in ([`Model::solve_displacements`]) traces its
    /// answer's when its residual reaches the rounding floor, for the warm update after it (two
    /// sweeps; frictionless, at most six tendons; MODEL.md §6.3). The tendon inverse, which forms
    /// its own with the tip force there, does without.
    pub answer_sensitivity: bool,
}

impl<T: Scalar> Default for DisplacementSettings<T> {
    fn default() -> Self {
        Self {
            max_iterations: 40,
            tolerance: default_tolerance::<T>() * T::lit(10.0),
            answer_sensitivity: true,
        }
    }
}

/// Whether a tendon carries tension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TendonState {
    /// Tension above zero, no slack.
    Taut,
    /// Zero tension: its path is shorter than its length.
    Slack,
}

/// A displacement-controlled equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplacementSolve<T> {
    /// The equilibrium at the tensions found (its `tensions_n` are the answer).
    pub solved: TendonEquilibrium<T>,
    /// Each tendon's slack, m (zero when taut).
    pub slack_m: Vec<T, MAX_TENDONS>,
    /// Each tendon's state.
    pub states: Vec<TendonState, MAX_TENDONS>,
    /// Why it stopped; only `Converged` with a successful `solved` is an answer.
    pub termination: Termination,
    /// The size of the complementarity residual where it stopped, dimensionless as
    /// [`DisplacementSettings::tolerance`] (the largest number after a failed forward solve):
    /// within the tolerance wherever `termination` is `Converged`.
    pub residual: T,
    /// Semi-smooth Newton iterations.
    pub iterations: u16,
    /// Sweeps spent, forward solves and sensitivities together.
    pub sweeps: u32,
    /// How the needed unstretched lengths change with the tensions near the answer, m/N (from
    /// tangents, or with capstan friction forward differences; refined by Broyden updates along the
    /// steps): what a warm update ([`Model::update_displacements`]) starts from instead of forming
    /// it again.
    pub d_length_d_tension: SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    /// Whether [`DisplacementSolve::d_length_d_tension`] holds a sensitivity (not after a failure
    /// before the first one).
    pub has_sensitivity: bool,
    /// How the base's internal force (N, rows 0-2) and moment (N m, rows 3-5) change with the
    /// tensions, per N (secants along the steps taken, or the sensitivity's): each
    /// forward solve of a step starts where it predicts, a warm update's too. Zero until a step
    /// was taken.
    pub d_base_d_tension: SMatrix<T, 6, MAX_TENDONS>,
    /// Each tendon's capstan exponent per radian when this was solved: its friction coefficient,
    /// signed by its sliding direction ([`Tendons::set_sliding`]). A warm update whose tendons
    /// slide otherwise solves its start again.
    pub capstan_per_rad: [T; MAX_TENDONS],
}

impl<T: Scalar> DisplacementSolve<T> {
    /// Whether the tensions are an answer.
    pub fn is_success(&self) -> bool {
        self.termination.is_success() && self.solved.is_success()
    }
}

/// What a warm update carries into the solve from the previous answer: its sensitivities, and
/// whether it is this problem's equilibrium (same load and sliding), not to be solved again.
#[derive(Clone, Copy, Debug)]
struct Carried<'a, T> {
    sensitivities: Sensitivities<'a, T>,
    same: bool,
}

/// `a - b`, as a vector.
pub(super) fn difference<T: Scalar>(
    a: &[T; MAX_TENDONS],
    b: &[T; MAX_TENDONS],
) -> SVector<T, MAX_TENDONS> {
    SVector::<T, MAX_TENDONS>::from_fn(|j, _| {
        a.get(j).copied().unwrap_or_else(T::zero) - b.get(j).copied().unwrap_or_else(T::zero)
    })
}

/// Broyden's rank-one update of `m`, the change of `R` quantities per unit tension, so that it
/// maps the step `dt` onto the change `dy` it caused (nothing for a zero step). Out of line: its
/// temporaries stay out of the solve's frame.
#[inline(never)]
fn secant<T: Scalar, const R: usize>(
    m: &mut SMatrix<T, R, MAX_TENDONS>,
    dy: &SVector<T, R>,
    dt: &SVector<T, MAX_TENDONS>,
) {
    let norm2 = dt.norm_squared();
    if norm2 > T::zero() {
        *m += (dy - *m * dt) * dt.transpose() / norm2;
    }
}

/// The largest predicted move of the base a forward solve starts from: a tracking step, as a
/// fraction of the moment that bends the rod a radian (a lateral force counted by its moment over
/// the rod's length) and, for the axial force, of the tension that does through the largest
/// offset (the compression that buckles the rod between its guides grows with it). Beyond it the
/// solve starts from the equilibrium itself: a long linear prediction can land Newton on another
/// branch (measured when the bound was set at 0.05: all three of the bench's tendons taken in 5 cm
/// from rest, where the start converges nowhere, reached a rod buckled between its guides; that
/// case now ends `Stalled` with the bound lifted altogether, and no test reaches another branch
/// without it, so the bound is a guard kept, not one a test shows needed). A quarter: the
/// two-section robot's ticks predict moves of 0.17-0.24 (a tenth of a newton on six tendons); at
/// 0.05 each of them started from the last equilibrium (four sweeps, no joint step). Its warm
/// updates up to eight ticks away give the cold solve's answer (`tests/tendon.rs`).
const PREDICTED_BASE_MOVE: f64 = 0.25;

/// How far above the forward solve's tolerance a start's expected residual may be for its first
/// sweep to go without tangents, when chord steps can follow it (`crate::solve::Chord`): one chord
/// step took the firmware's state-change tick from 4.3 times the tolerance to 0.25 times it.
const CHORD_REACH: f64 = 16.0;

/// How far above the rounding floor a step must start for the base sensitivity's secant along it:
/// from closer, the base's change is mostly the forward solves' rounding, and a secant along it
/// spoils the predictions the next steps and the next tick start from.
const SECANT_FLOOR: f64 = 64.0;

/// How far above the rounding floor a step must start for the needed lengths' secant along it:
/// a step from within a few times the floor changes the lengths by little more than their
/// rounding, and its secant turns the carried `dN/dtau` along the step by that noise over the
/// step. On the two-section robot in f32 (floor 3.3e-5) most ticks end on such a step (4e-5 to
/// 7e-6); with its secant, the next tick's Josephy step and its predicted move of the base came
/// out up to twice the true ones (0.43 where 0.21), beyond a tracking step, and those ticks took
/// 9-21 sweeps. Lower than [`SECANT_FLOOR`]: at 64 the tendon inverse's moving-load test, whose
/// gradient the lengths' secants feed, reached its iteration limit.
const LENGTHS_SECANT_FLOOR: f64 = 4.0;

/// How far above the rounding floor a step must end for its slow gain to form the sensitivity
/// afresh: closer, no sensitivity can show a gain of four.
const REDIFFERENCE_FLOOR: f64 = 4.0;

/// Newton iterations of the forward solve a joint step starts (`joint_step.rs`): from a tracking
/// start it converges in one or two.
const JOINT_ITERATIONS: u16 = 3;

/// A base force (N) and moment (N m).
pub(super) type BaseWrench<T> = (Vector3<T>, Vector3<T>);

/// A tracking step of the base: within [`PREDICTED_BASE_MOVE`] of `moment_scale_nm` (bending)
/// and of `tension_scale_n` (axial, along the base `tangent`).
pub(super) struct Tracking<T> {
    pub tangent: Vector3<T>,
    pub length_m: T,
    pub moment_scale_nm: T,
    pub tension_scale_n: T,
}

impl<T: Scalar> Tracking<T> {
    /// A move of the base force (N) and moment (N m) in these scales: bending and axial.
    pub(super) fn size(&self, force_n: &Vector3<T>, moment_nm: &Vector3<T>) -> (T, T) {
        let axial = self.tangent.dot(force_n);
        let lateral = force_n - self.tangent * axial;
        (
            (lateral.norm() * self.length_m + moment_nm.norm()) / self.moment_scale_nm,
            axial.abs() / self.tension_scale_n,
        )
    }

    /// Whether a move of the base force (N) and moment (N m) is a tracking step.
    pub(super) fn allows(&self, force_n: &Vector3<T>, moment_nm: &Vector3<T>) -> bool {
        let (bending, axial) = self.size(force_n, moment_nm);
        let limit = T::lit(PREDICTED_BASE_MOVE);
        bending <= limit && axial <= limit
    }

    /// The squared size of a predicted move of the base in these scales, bending and axial
    /// summed: the residual a forward solve started there is expected to have from the carried
    /// sensitivity's error, which grows with the move.
    pub(super) fn squared(&self, (force_n, moment_nm): &BaseWrench<T>) -> T {
        let (bending, axial) = self.size(force_n, moment_nm);
        bending * bending + axial * axial
    }
}

/// The base's predicted move, force (N) and moment (N m), for tensions changed by `dt`:
/// `d_base dt`.
pub(super) fn base_move<T: Scalar>(
    d_base: &SMatrix<T, 6, MAX_TENDONS>,
    dt: &SVector<T, MAX_TENDONS>,
) -> BaseWrench<T> {
    let moved = d_base * dt;
    (
        moved.fixed_rows::<3>(0).into_owned(),
        moved.fixed_rows::<3>(3).into_owned(),
    )
}

/// Where a forward solve starts, base force (N) and moment (N m): those given, plus the predicted
/// `moved` ([`base_move`]), if that move is a tracking step (else `None`: the solve starts from
/// those given).
pub(super) fn predict<T: Scalar>(
    (force_n, moment_nm): BaseWrench<T>,
    (force, moment): &BaseWrench<T>,
    tracking: &Tracking<T>,
) -> Option<BaseWrench<T>> {
    tracking
        .allows(force, moment)
        .then(|| (force_n + force, moment_nm + moment))
}

impl<T: Scalar> Tendons<T> {
    /// The slack `phi_j`, m, of each tendon after spool displacements `d` when the equilibrium
    /// needs the unstretched lengths `unstretched_m`: what the spool left minus what is needed.
    pub(crate) fn slack(&self, displacements_m: &[T], unstretched_m: &[T]) -> [T; MAX_TENDONS] {
        let mut out = [T::zero(); MAX_TENDONS];
        for (j, phi) in out.iter_mut().enumerate().take(self.len()) {
            let (Some(d), Some(needed)) = (displacements_m.get(j), unstretched_m.get(j)) else {
                continue;
            };
            *phi = self.home_length_m(j) - *d - *needed;
        }
        out
    }

    /// The spool displacements, m (positive taken in), that hold the tendons of `solved` at its
    /// tensions with no slack: each tendon's home length (feed and rest path) minus the
    /// unstretched length the equilibrium needs. What a displacement-controlled solve of them gives
    /// back (the round trip from tensions); empty when `solved` did not succeed (it has no
    /// unstretched lengths) or has another number of tendons.
    pub fn displacements_holding_m(&self, solved: &TendonEquilibrium<T>) -> Vec<T, MAX_TENDONS> {
        if solved.unstretched_m.len() != self.len() {
            return Vec::new();
        }
        solved
            .unstretched_m
            .iter()
            .enumerate()
            .map(|(j, needed)| self.home_length_m(j) - *needed)
            .collect()
    }

    /// Each tendon's capstan exponent per radian (zero beyond the last tendon).
    pub(crate) fn capstans(&self) -> [T; MAX_TENDONS] {
        let mut out = [T::zero(); MAX_TENDONS];
        for (c, r) in out.iter_mut().zip(&self.routed) {
            *c = r.capstan_per_rad;
        }
        out
    }

    /// Whether no tendon has capstan friction.
    pub(crate) fn frictionless(&self) -> bool {
        self.routed.iter().all(|r| r.capstan_per_rad == T::zero())
    }

    /// Tendon `j`'s unstretched length at home (the straight, unloaded rod at zero tension), spool
    /// to termination, m.
    pub(crate) fn home_length_m(&self, j: usize) -> T {
        let feed = self.tendons.get(j).map_or(T::zero(), |t| t.feed_length_m);
        feed + self.rest_length_m(j).unwrap_or_else(T::zero)
    }

    /// Checks spool displacements: one per tendon, each finite and less than the tendon's whole
    /// length (a spool cannot take in more tendon than there is).
    pub(crate) fn check_displacements(&self, displacements_m: &[T]) -> Result<(), ModelError> {
        if displacements_m.len() != self.len() {
            return Err(ModelError::Mismatch("displacements and tendons"));
        }
        for (j, d) in displacements_m.iter().enumerate() {
            finite(*d, "tendon displacement")?;
            if *d >= self.home_length_m(j) {
                return Err(ModelError::OutOfRange(
                    "tendon displacement (more than the tendon's whole length)",
                ));
            }
        }
        Ok(())
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Solves for the tensions that spool displacements `displacements_m` (m, one per tendon,
    /// positive taken in from the straight unloaded rod's setting) produce, with each tendon's
    /// compliance and slack, under the scene's dead loads and `load`.
    ///
    /// `start` may hold a previous equilibrium (its tensions start the iteration). Fails only on
    /// invalid input; the outcome is data (`termination`).
    pub fn solve_displacements(
        &self,
        tendons: &Tendons<T>,
        displacements_m: &[T],
        load: &TipLoad<T>,
        start: Option<&TendonEquilibrium<T>>,
        shooting: &ShootingSettings<T>,
        settings: &DisplacementSettings<T>,
    ) -> Result<DisplacementSolve<T>, ModelError> {
        self.displacement_solve(
            tendons,
            displacements_m,
            load,
            start,
            None,
            shooting,
            settings,
        )
    }

    /// The warm update of a control loop: the tensions for new displacements, from `previous`'s
    /// equilibrium and its sensitivities (Broyden-updated along the steps; formed afresh when a
    /// step fails or gains too little). `previous` must come from this model and these
    /// tendons (their sliding may have changed since: that is seen). Same outcome as
    /// [`Model::solve_displacements`], at a fraction of the sweeps.
    pub fn update_displacements(
        &self,
        tendons: &Tendons<T>,
        displacements_m: &[T],
        load: &TipLoad<T>,
        previous: &DisplacementSolve<T>,
        shooting: &ShootingSettings<T>,
        settings: &DisplacementSettings<T>,
    ) -> Result<DisplacementSolve<T>, ModelError> {
        // A failed solve is no start: the update is then a cold one.
        let usable = previous.is_success();
        // The previous answer is this problem's equilibrium at its tensions, not to be solved
        // again, when the load and every tendon's sliding are the same (`previous` comes from this
        // model and these tendons: their sliding is the one thing a loop changes between ticks).
        let same = usable
            && previous.solved.equilibrium.load == *load
            && previous.solved.tensions_n.len() == tendons.len()
            && previous.solved.unstretched_m.len() == tendons.len()
            && previous.capstan_per_rad == tendons.capstans();
        let carried = (usable && previous.has_sensitivity).then_some(Carried {
            sensitivities: Sensitivities {
                d_length_d_tension: &previous.d_length_d_tension,
                d_base_d_tension: &previous.d_base_d_tension,
            },
            same,
        });
        self.displacement_solve(
            tendons,
            displacements_m,
            load,
            usable.then_some(&previous.solved),
            carried,
            shooting,
            settings,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn displacement_solve(
        &self,
        tendons: &Tendons<T>,
        displacements_m: &[T],
        load: &TipLoad<T>,
        start: Option<&TendonEquilibrium<T>>,
        carried: Option<Carried<'_, T>>,
        shooting: &ShootingSettings<T>,
        settings: &DisplacementSettings<T>,
    ) -> Result<DisplacementSolve<T>, ModelError> {
        tendons.check_displacements(displacements_m)?;
        positive(settings.tolerance, "displacement tolerance")?;
        let count = tendons.len();
        let tau_scale = tension_scale_n(self, tendons);
        let radius = tendons
            .largest_offset_m()
            .max(self.length_m() * T::lit(1e-3));

        // Success, wherever the solve stops: the residual within the tolerance (a NaN meets none;
        // the one rule, applied where the loop ends and, to stop it, at the floor).
        let met = |size: T| size <= settings.tolerance;
        // The rounding floor of the residual: a path resolved to a few `eps L`.
        let floor = T::default_epsilon() * T::lit(8.0) * (self.length_m() / radius + T::one());
        let mut tau = [T::zero(); MAX_TENDONS];
        if let Some(s) = start {
            for (t, s) in tau.iter_mut().zip(&s.tensions_n) {
                *t = s.max(T::zero());
            }
        }
        let mut sweeps = 0u32;
        // A warm update of the same problem starts from its previous answer as it is.
        let same = carried.is_some_and(|c| c.same);
        let mut current = match start.filter(|_| same) {
            Some(s) => s.clone(),
            None => {
                let solved = self.solve_tendons(
                    tendons,
                    tau.get(..count).unwrap_or(&[]),
                    load,
                    start,
                    shooting,
                )?;
                sweeps += u32::from(solved.equilibrium.report.sweeps);
                solved
            }
        };

        let fb = Complementarity {
            tendons,
            displacements_m,
            tau_scale,
            radius,
        };
        let residual_of =
            |eq: &TendonEquilibrium<T>, tau: &[T; MAX_TENDONS]| fb.residual(&eq.unstretched_m, tau);

        let mut termination = Termination::IterationLimit;
        let mut iterations = 0u16;
        // d N / d tau, and whether it was formed at the current point (else carried and
        // Broyden-updated).
        let tracking = Tracking {
            tangent: self.rod().base_orientation.column(2).into_owned(),
            length_m: self.length_m(),
            moment_scale_nm: self.moment_scale_nm(),
            tension_scale_n: tau_scale,
        };
        // The joint step (`joint_step.rs`) serves a control loop's tick: a warm update of the same
        // problem (so not the tendon inverse's fits, whose trial forces change the load: an earlier
        // form with joint steps in every solve left its moving-load test at 40 iterations where
        // plain steps take 14), without capstan friction.
        let joint = same && tendons.frictionless();
        let mut sens = carried.map(|c| *c.sensitivities.d_length_d_tension);
        let mut d_base = carried.map_or_else(SMatrix::zeros, |c| *c.sensitivities.d_base_d_tension);
        let mut fresh = false;
        // The joint step's Jacobian of the tip condition (`joint_step.rs`), for the chord steps of
        // this update's later forward solves, and the expected residual a start within their reach
        // has: a chord step took the state-change tick's start from four times the tolerance to a
        // quarter of it.
        let mut chord: Option<SMatrix<T, 6, 6>> = None;
        let reach = shooting.tolerance * T::lit(CHORD_REACH);
        // Where the guides' jumps converged in this solve's sweeps: its plain sweeps start there.
        let memory = JumpMemory::new();
        // A solve that carried no sensitivity in (not a control loop's warm update) hands on its
        // answer's, traced there when its residual reaches the floor (two sweeps: frictionless,
        // at most six tendons), not the one its path left: formed at some earlier iterate and
        // Broyden-updated along the steps since, that is right along those steps only. In f32 on
        // the tendon bench it was 1-15 % off its answer's, and the first step of the warm update
        // after it up to 0.3 N too far along the tendons' common tension, which the lengths see
        // least (MODEL.md §6.3). A warm update keeps its secants: a tick moves little, and two
        // sweeps would double the bench robot's. (A solve that ends otherwise, at its iteration
        // limit within tolerance or stalled at the floor, hands on what it holds.)
        let hand_on = settings.answer_sensitivity && carried.is_none() && traceable(tendons);
        for _ in 0..settings.max_iterations {
            if !current.is_success() {
                termination = current.equilibrium.report.termination;
                break;
            }
            let (r, parts, phi) = residual_of(&current, &tau);
            let size = residual_size(&r);
            // At the rounding floor, an answer where that meets the tolerance. (A path resolved to
            // a few `eps L` may be more than a tolerance times the offset, in f32 with offsets
            // below about L / 250 at the default tolerance: the floor is an estimate, so the
            // steps go on, and where none improves the solve ends `Stalled` below.)
            if size <= floor && met(size) {
                termination = Termination::Converged;
                if fresh || !hand_on {
                    break;
                }
                // The answer's own sensitivity, formed below, then the end.
                sens = None;
            } else {
                iterations += 1;
            }
            let s = match sens {
                Some(s) => s,
                None => match sensitivity(self, tendons, &current, load, false, shooting)? {
                    Ok(d) => {
                        sweeps += d.sweeps;
                        fresh = true;
                        sens = Some(d.d_length_d_tension);
                        d_base = d.d_base_d_tension;
                        d.d_length_d_tension
                    }
                    Err(t) => {
                        // (A converged answer stays one, without a sensitivity to hand on.)
                        if !termination.is_success() {
                            termination = t;
                        }
                        break;
                    }
                },
            };
            if termination.is_success() {
                break;
            }
            // A warm update's first step (the tick's) solves the complementarity linearised with
            // the carried sensitivity exactly (Josephy-Newton, as the joint step does): where the
            // tick's start is beyond a tracking step the joint step declines, and the semi-smooth
            // step on `FB` lands off where `FB` is curved: along a section's common tension, which
            // only stretches the tendons and compresses the backbone, the two-section robot's
            // first steps overshot by 0.17 N a tick that moved 0.1 N. Refining steps, a retry
            // after a first step the carried sensitivity misled, and cold solves keep the
            // semi-smooth step (MODEL.md §6.3).
            let step = if same && iterations == 1 {
                fb.josephy_step(&tau, &phi, (&r, &parts), &s)
            } else {
                fb.newton_step((&r, &parts), &s)
            };
            let Some(step) = step else {
                termination = Termination::Singular;
                break;
            };
            // Backtracking on |r|: the full step, then halves.
            let mut accepted = None;
            let mut alpha = T::one();
            // The full step's first trial goes on the tensions and the base together where it can
            // (`joint_step.rs`); when that trial fails, the plain full step is tried before halves.
            // (on the update's first step: the tick's; refining steps near the floor are plain)
            let mut joint_pending = joint && iterations == 1;
            let mut plain_trials = 0u8;
            let anchor = (
                current.equilibrium.base_force_n,
                current.equilibrium.base_moment_nm,
            );
            while plain_trials < 12 {
                let mut trial = tau;
                for ((t, now), d) in trial.iter_mut().zip(&tau).zip(step.iter()).take(count) {
                    *t = (*now + *d * alpha).max(T::zero());
                }
                let mut dt = difference(&trial, &tau);
                let moved = base_move(&d_base, &dt);
                let tracked = predict(anchor, &moved, &tracking);
                let mut predicted = tracked.unwrap_or(anchor);
                let mut forward = *shooting;
                // Whether the start is expected within reach of the joint step's chord steps: its
                // first sweep then goes without tangents, and where it does not confirm, chord
                // steps with the joint step's Jacobian follow (`crate::solve::Chord`). The joint
                // start's expected residual is `JointStep::expected_residual`; a later step's, the
                // squared size of its predicted move of the base in tracking scales.
                let mut confirm = chord.is_some() && tracking.squared(&moved) <= reach;
                // (Not beyond a tracking step: its start would be refused.)
                let jointed = core::mem::take(&mut joint_pending) && tracked.is_some() && {
                    let carried = Sensitivities {
                        d_length_d_tension: &s,
                        d_base_d_tension: &d_base,
                    };
                    let stepped = self.joint_step(
                        tendons, load, &fb, &trial, predicted, anchor, &carried, &tracking, &memory,
                    );
                    sweeps += 1; // its one sweep, whatever the outcome
                    stepped.is_some_and(|j| {
                        (trial, predicted) = (j.tensions_n, j.base);
                        dt = difference(&trial, &tau);
                        chord = Some(j.jacobian);
                        confirm = j.expected_residual <= reach;
                        true
                    })
                };
                if jointed {
                    // A joint start converges in a sweep or two where the step is a tracking
                    // one; otherwise the plain step is taken instead (no cold start from here).
                    forward = ShootingSettings {
                        max_iterations: JOINT_ITERATIONS,
                        cold_fallback: false,
                        ..forward
                    };
                }
                let moved = self.solve_tendons_from(
                    tendons,
                    trial.get(..count).unwrap_or(&[]),
                    load,
                    Some(predicted),
                    &forward,
                    confirm.then_some(Confirm {
                        chord: chord.as_ref().map(|jacobian| Chord { jacobian }),
                    }),
                    Some(&memory),
                )?;
                sweeps += u32::from(moved.equilibrium.report.sweeps);
                if moved.is_success() {
                    let (r_trial, _, _) = residual_of(&moved, &trial);
                    let r_new = residual_size(&r_trial);
                    if r_new < size {
                        accepted = Some((trial, moved, dt, r_new));
                        break;
                    }
                }
                if !jointed {
                    plain_trials += 1;
                    alpha *= T::lit(0.5);
                }
            }
            match accepted {
                Some((trial, moved, dt, r_new)) => {
                    // A carried sensitivity that gained less than a factor four is formed afresh
                    // next time: Broyden's secants alone converge slowly near the answer, and a
                    // fresh one costs two or three sweeps with tangents (differences with
                    // friction: a forward solve per tendon), a Broyden step none. Not within four
                    // times the rounding floor: there, a fresh sensitivity could not gain a factor
                    // four either (on the two-section robot in f32 most ticks ended on a step to
                    // twice the floor and differenced six tendons afresh).
                    let slow = !fresh
                        && r_new > size * T::lit(0.25)
                        && r_new > floor * T::lit(REDIFFERENCE_FLOOR);
                    // Broyden: the secant along the step taken.
                    let dn = SVector::<T, MAX_TENDONS>::from_fn(|j, _| {
                        match (moved.unstretched_m.get(j), current.unstretched_m.get(j)) {
                            (Some(a), Some(b)) => *a - *b,
                            _ => T::zero(),
                        }
                    });
                    if slow {
                        sens = None;
                    } else if let Some(s) = sens.as_mut()
                        && size > floor * T::lit(LENGTHS_SECANT_FLOOR)
                    {
                        secant(s, &dn, &dt);
                    }
                    // (Not along a step from within SECANT_FLOOR of the floor.)
                    if size > floor * T::lit(SECANT_FLOOR) {
                        secant(&mut d_base, &(moved.base() - current.base()), &dt);
                    }
                    fresh = false;
                    tau = trial;
                    current = moved;
                }
                None if !fresh => {
                    // A carried sensitivity misled the step: form it afresh and retry.
                    sens = None;
                }
                None => {
                    // At the floor of the forward solves' rounding (an answer if within the
                    // tolerance: below).
                    termination = Termination::Stalled;
                    break;
                }
            }
        }
        let (r, _, phi) = residual_of(&current, &tau);
        // (A failed forward solve has no paths: no residual either.)
        let residual = if current.is_success() {
            residual_size(&r)
        } else {
            T::max_value().unwrap_or_else(T::one)
        };
        // Wherever the loop stopped (at the floor, where no step improved, at its iteration limit,
        // where a sensitivity or a step could not be formed), the answer is one exactly when its
        // forward solve succeeded within the tolerance.
        termination = match (current.is_success() && met(residual), termination) {
            (true, _) => Termination::Converged,
            (false, Termination::Converged) => Termination::Stalled,
            (false, stopped) => stopped,
        };
        let mut slack_m = Vec::new();
        let mut states = Vec::new();
        for (t, p) in tau.iter().zip(&phi).take(count) {
            // The side of the complementarity the answer is on: more slack than tension (both
            // scaled as in the residual) is slack, whatever rounding left of the tension; so is no
            // tension at all, whatever rounding left of the slack (at the kink, where both are
            // zero, the path a rounding error longer than the tendon).
            let slack = *t == T::zero() || *t / tau_scale < *p / radius;
            // Cannot overflow: at most MAX_TENDONS.
            let _ = slack_m.push(if slack { p.max(T::zero()) } else { T::zero() });
            let _ = states.push(if slack {
                TendonState::Slack
            } else {
                TendonState::Taut
            });
        }
        Ok(DisplacementSolve {
            solved: current,
            slack_m,
            states,
            termination,
            residual,
            iterations,
            sweeps,
            has_sensitivity: sens.is_some(),
            d_length_d_tension: sens.unwrap_or_else(SMatrix::zeros),
            d_base_d_tension: d_base,
            capstan_per_rad: tendons.capstans(),
        })
    }
}
