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

use crate::scalar::product;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::basis::{LoadBasis, ParamCount, Params, prior_weight_for};
use super::{CableVector, Determination, Estimate, InverseSettings};
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::ode::Family;
use crate::ode::dead_load::DeadLoadRod;
use crate::report::{MAX_FRAME_DRIFT, SolveReport, Termination};
use crate::shape::ShapeSink;
use crate::solve::newton::{NewtonOptions, Work, newton_in_place};
use crate::solve::resolved;
use crate::solve::stopping::{self, default_tolerance};
use crate::stability::{Stability, classify};
use crate::sweep::{Sweep, TangentSet, sweep};
use crate::{MAX_CABLES, Scalar};

/// Newton iterations (each one sweep) a projection back onto the equilibrium may take.
const PROJECTION_ITERATIONS: u16 = 8;

/// The continuation in the prior starts this many times tighter than the final prior.
const PRIOR_START: f64 = 256.0;

/// Each level of that continuation loosens the prior by this factor.
const PRIOR_STEP: f64 = 0.25;

/// Gauss-Newton iterations at most per level.
const PRIOR_ITERATIONS: u16 = 6;

/// A level is settled when the next step would lower the merit (in squared standard deviations) by
/// less than this.
const PRIOR_SETTLED: f64 = 0.01;

/// On the way to the answer (the prior's continuation, the profile), iterates are brought back onto
/// the equilibrium only to this many times the reduced model's final tolerance: their merit need not
/// be exact, and a tight projection costs sweeps at every step.
const LOOSE_PROJECTION: f64 = 10.0;

/// Sweeps kept for the search for other answers out of [`InverseSettings::max_sweeps`].
const SCAN_SWEEPS: u16 = 40;

/// The profile reaches loads this many times the answer's (in buckling scales), or
/// [`InverseSettings::scan_reach`] buckling scales, whichever is larger.
const SCAN_FACTOR: f64 = 3.0;

/// The profile's first step, as a fraction of the answer's load (at least one buckling scale).
const SCAN_FIRST: f64 = 0.125;

/// Each step of the profile is this many times the last (halved where a point is not reached).
const SCAN_GROWTH: f64 = 1.5;

/// Damped Gauss-Newton steps at most per point of the profile.
const SCAN_ITERATIONS: u16 = 2;

/// Another answer whose misfit is within this many squared standard deviations of the answer's
/// explains the data as well (three standard deviations in one direction).
const ALTERNATIVE_CHI2: f64 = 9.0;

/// Power iterations for the weakest direction.
const WEAKEST_ITERATIONS: u16 = 30;

/// The posterior's standard deviation along a unit direction of the parameters, where the profile
/// of the merit along it (the other parameters re-solved) rises more slowly than the linearisation
/// at the answer predicts: near the buckling load a tiny axial change moves the cables a lot to
/// first order, and the linearised standard deviation can be ten times too small.
#[derive(Clone, Copy, Debug)]
pub(super) struct Widen<T, const P: usize> {
    pub(super) direction: SVector<T, P>,
    pub(super) std: T,
}

/// What the search for other answers found, once its leads are followed.
#[derive(Clone, Copy, Debug)]
enum Scan<T, const P: usize> {
    /// No other answer within its reach.
    Unique,
    /// Another answer within the search's reach explains the data about as well.
    Ambiguous(Rival<T, P>),
    /// Another answer scores clearly better (data and prior, by more than [`ALTERNATIVE_CHI2`]) and
    /// replaced the first; with the first when it explains the data about as well.
    Better(Option<Rival<T, P>>),
    /// The budget ran out before the search was done.
    Incomplete,
}

/// Another answer that explains the data about as well as the one returned.
#[derive(Clone, Copy, Debug)]
struct Rival<T, const P: usize> {
    params: SVector<T, P>,
    tip_m: Vector3<T>,
}

impl<T: Scalar, const P: usize> Rival<T, P> {
    /// The rival at `x`, linearised by `lin`.
    fn at(x: &Point<T, P>, lin: &Linearization<T, P>) -> Self {
        Self {
            params: x.p,
            tip_m: lin.tip_position_m,
        }
    }

    /// Within three of `out`'s standard deviations in every parameter and every tip coordinate:
    /// what the deviations already say the data leave open.
    fn covered_by(&self, out: &Estimate<T, P>) -> bool {
        let within = |((a, b), std): ((&T, &T), &T)| (*a - *b).abs() <= T::lit(3.0) * *std;
        let q = &out.quality;
        let params = self.params.iter().zip(out.params.iter());
        let tip = self.tip_m.iter().zip(out.tip_position_m.iter());
        params.zip(q.param_std.iter()).all(within) && tip.zip(q.tip_std_m.iter()).all(within)
    }
}

/// Where the profile along the weakest direction suggests other answers: on each side, the lowest
/// point of a descent past a crest and the first point whose free step sees another answer (each on
/// the equilibrium at its own load).
struct Leads<T, const P: usize> {
    starts: [Option<Point<T, P>>; 4],
    /// The posterior's width along the profile's direction, where the profile measured it.
    widen: Option<Widen<T, P>>,
}

/// The sweep budget ran out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct OutOfBudget;

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
    pub(super) phase_per_step_rad: T,
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
            phase_per_step_rad: T::zero(),
        }
    }

    /// The Jacobian blocks of `other` (tangents taken at a point nearby); the residuals and tip pose
    /// stay.
    pub(super) fn take_jacobian(&mut self, other: &Self) {
        self.j_eu = other.j_eu;
        self.j_ep = other.j_ep;
        self.j_cu = other.j_cu;
        self.j_cp = other.j_cp;
        self.d_tip_u = other.d_tip_u;
        self.d_tip_p = other.d_tip_p;
    }

    /// New residuals and tip pose from a plain sweep; the Jacobian blocks stay.
    pub(super) fn set_residual(&mut self, sw: &Sweep<T, 3>, rc: CableVector<T>) {
        self.e = sw.residual;
        self.rc = rc;
        self.tip_position_m = sw.tip_position_m;
        self.tip_rotation = sw.tip_rotation;
        self.frame_drift = sw.frame_drift;
        self.phase_per_step_rad = sw.phase_per_step_rad;
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

/// A change of the unknowns: of the base strain and of the load parameters.
pub(super) type Move<T, const P: usize> = (Vector3<T>, SVector<T, P>);

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
    /// A profile's constraint on the parameters, when this problem is one point of a profile.
    pub(super) fix: Option<Fix<T, P>>,
    /// One standard deviation of a cable length as the fit weighs it, m: the measurement's, the
    /// model's own and the scalar type's floor, in quadrature.
    pub(super) length_std_m: T,
    /// The same for the tip position, m: the model's own and the floor (the measurement's part comes
    /// from the load's covariance).
    pub(super) model_tip_std_m: T,
    /// `1 / D` for each parameter, `D` its buckling scale (`E I / L^2` of force, `E I / L` of moment
    /// per unit parameter): distances between answers are measured in these units.
    pub(super) buckling_weight: SVector<T, P>,
}

/// The constraint `v.p = a` of one point of a profile along the unit vector `v`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Fix<T, const P: usize> {
    pub(super) direction: SVector<T, P>,
    pub(super) value: T,
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
        let radius = model
            .rod()
            .cables
            .iter()
            .fold(T::zero(), |r, c| r.max(c.radius_m()));
        let floor = radius * default_tolerance::<T>();
        let length_std_m = (settings.length_std_m * settings.length_std_m
            + settings.model_length_std_m * settings.model_length_std_m
            + floor * floor)
            .sqrt();
        Self {
            model,
            basis,
            measured,
            settings,
            cables: model.rod().cables.len(),
            prior_weight: prior_weight(model, &basis, &settings),
            max_moment_residual: (length_std_m * T::lit(0.1) / radius).sqrt(),
            fix: None,
            length_std_m,
            model_tip_std_m: {
                let floor = stopping::tip_floor_m(model.length_m());
                (settings.model_tip_std_m * settings.model_tip_std_m + floor * floor).sqrt()
            },
            buckling_weight: prior_weight_for(model, &basis, T::one()),
        }
    }

    /// Brings a point back onto the equilibrium at its load when its tip-moment residual is too large
    /// for the reduced model: the forward solve's Newton iteration on the base strain alone (variable
    /// projection), to the residual the reduced model trusts. `sw` is the (finite) sweep at `x`;
    /// both follow the projection. False if it does not converge.
    fn project(&self, x: &mut Point<T, P>, sw: &mut Sweep<T, 3>, work: &mut Work) -> bool {
        if self.moment_residual(&sw.residual) <= self.max_moment_residual {
            return true;
        }
        let options = NewtonOptions {
            tolerance: self.max_moment_residual,
            to_rounding: false,
            max_step_rad: self.settings.max_rotation_step_rad,
            max_iterations: PROJECTION_ITERATIONS,
            tangents: self.tangents(),
            plain_first: false,
        };
        let mut inner = Work::default();
        let (_, termination) =
            newton_in_place(&self.ode(&x.p), &mut x.u0, sw, &options, &mut inner);
        work.sweeps = work.sweeps.saturating_add(inner.sweeps);
        termination.is_success()
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
        let j_ef: Matrix3<T> = sw.residual_block(f);
        // e = C u - R^T tau: d e / d tau = -R^T.
        let j_ep =
            product(&j_ef, &self.basis.force_n) - sw.tip_rotation.tr_mul(&self.basis.moment_nm);
        let j_cf: SMatrix<T, MAX_CABLES, 3> = sw.cable_block(f);
        let d_tip_f: Matrix3<T> = sw.position_block(f);
        Linearization {
            e: sw.residual,
            rc: self.cable_residual(sw),
            j_eu: sw.residual_block(u),
            j_ep,
            j_cu: sw.cable_block(u),
            j_cp: product(&j_cf, &self.basis.force_n),
            tip_position_m: sw.tip_position_m,
            tip_rotation: sw.tip_rotation,
            d_tip_u: sw.position_block(u),
            d_tip_p: product(&d_tip_f, &self.basis.force_n),
            d_theta_tip_u: sw.rotation_block(u),
            conjugate_point_m: sw.conjugate_point_m,
            frame_drift: sw.frame_drift,
            phase_per_step_rad: sw.phase_per_step_rad,
        }
    }

    pub(super) fn reduce(&self, lin: &Linearization<T, P>) -> Option<Reduced<T, P>> {
        let lu = lin.j_eu.lu();
        let a = lu.solve(&lin.j_ep)?;
        let b = lu.solve(&lin.e)?;
        let inv_std = T::one() / self.length_std_m;
        let g = (lin.j_cp - product(&lin.j_cu, &a)) * inv_std;
        let c = (lin.rc - product(&lin.j_cu, &b)) * inv_std;
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
        self.merit_of(p, self.reduce(lin).as_ref())
    }

    /// [`Problem::merit`] from the reduced system at the linearisation (`None`: singular).
    pub(super) fn merit_of(&self, p: &SVector<T, P>, red: Option<&Reduced<T, P>>) -> T {
        red.map_or_else(
            || T::max_value().unwrap_or_else(T::one),
            |red| red.c.norm_squared() + self.penalty(p),
        )
    }

    /// The prior's quadratic form `|W p|^2`.
    fn penalty(&self, p: &SVector<T, P>) -> T {
        p.component_mul(&self.prior_weight).norm_squared()
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
        red.c.norm_squared() + self.penalty(p)
            - (red.c + red.g * dp).norm_squared()
            - self.penalty(&(p + dp))
    }

    /// The information matrix `G^T G / s^2 + W^2` (data and prior).
    pub(super) fn information(&self, red: &Reduced<T, P>) -> SMatrix<T, P, P> {
        let w2 = self.prior_weight.component_mul(&self.prior_weight);
        red.g.tr_mul(&red.g) + SMatrix::from_diagonal(&w2)
    }

    /// The merit's gradient (halved): `G^T c~ + W^2 p`.
    fn gradient(&self, red: &Reduced<T, P>, p: &SVector<T, P>) -> SVector<T, P> {
        let w2 = self.prior_weight.component_mul(&self.prior_weight);
        red.g.tr_mul(&red.c) + w2.component_mul(p)
    }

    /// The damped step from `p` (`mu = 0`: Gauss-Newton), limited by the trust region on the base
    /// rotation. The base-strain change has two parts: `-J_eu^-1 e`, which restores the tip-moment
    /// condition at the current load, and `-J_eu^-1 J_ep dp`, which follows the load step. The trust
    /// region shortens the load step first; shortening the first part too would leave the iterate off
    /// the equilibrium, where the reduced model no longer describes the problem.
    pub(super) fn step(&self, red: &Reduced<T, P>, p: &SVector<T, P>, mu: T) -> Option<Move<T, P>> {
        let normal = self.information(red);
        let gradient = self.gradient(red, p);
        // A tiny ridge keeps an undetermined direction from blowing the step up; LM damping on top.
        let ridge = normal.diagonal().max().max(T::one()) * T::default_epsilon() * T::lit(16.0);
        let damped = normal + SMatrix::from_diagonal(&(normal.diagonal() * mu).add_scalar(ridge));
        let dp = match self.fix {
            None => damped.cholesky()?.solve(&-gradient),
            Some(fix) => {
                // On the constraint `v.p = a`: the smallest change onto it, then the best change
                // along it (the null-space method: `v` is held out of the system by its own pivot).
                let v = fix.direction;
                let onto = v * (fix.value - v.dot(p));
                let across = SMatrix::<T, P, P>::identity() - v * v.transpose();
                let system = across * damped * across + v * v.transpose() * damped.diagonal().max();
                let z = system
                    .cholesky()?
                    .solve(&-(across * (gradient + normal * onto)));
                onto + across * z
            }
        };
        let length = self.model.length_m();
        let limit = self.settings.max_rotation_step_rad;
        let restore = -red.b;
        let follow = -product(&red.a, &dp);
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
        let (done, tip_move, _) = self.converged_step(x, lin, red, previous_tip_move);
        (done, tip_move)
    }

    /// [`Problem::converged`], and the Gauss-Newton step it judged (`None` when singular).
    pub(super) fn converged_step(
        &self,
        x: &Point<T, P>,
        lin: &Linearization<T, P>,
        red: &Reduced<T, P>,
        previous_tip_move: Option<T>,
    ) -> (bool, T, Option<Move<T, P>>) {
        let infinite = T::max_value().unwrap_or_else(T::one);
        let Some((du, dp)) = self.step(red, &x.p, T::zero()) else {
            return (false, infinite, None);
        };
        let tip_move = (product(&lin.d_tip_u, &du) + product(&lin.d_tip_p, &dp)).norm();
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
            .max(stopping::fit_floor_sigma(length, self.length_std_m));
        let done = moment_ok
            && tip_move + remaining <= self.settings.tip_tolerance_m.max(tip_floor)
            && fit_move <= fit_tolerance;
        (done, tip_move, Some((du, dp)))
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
    /// The inverse from `x`, an equilibrium at its own load (a cold forward solve at the start
    /// parameters, or a previous estimate), to the maximum a posteriori estimate:
    ///
    /// 1. continuation in the prior, from a prior [`PRIOR_START`] times tighter than the final one
    ///    down to it ([`Problem::follow_prior`]): a tight prior holds the load near the start, where
    ///    the problem is nearly linear and its answer unique, and each loosening moves the answer
    ///    along its branch. From the start alone, a Gauss-Newton step takes the linear model's word
    ///    that a small lateral load is a large axial one (both bend the sagging rod alike to first
    ///    order) and can settle on that far answer;
    /// 2. Levenberg-Marquardt to convergence ([`Problem::refine`]);
    /// 3. a search for other answers that explain the measurements, along the direction the data
    ///    determine worst ([`Problem::alternatives`]): three cables and three force components admit
    ///    several exact fits (a small load and a large tension; two tensions). The one the prior
    ///    prefers is returned; when another fits the data about as well, the verdict says so
    ///    ([`Determination::Ambiguous`]) instead of calling either answer determined, and when the
    ///    budget runs out before the search is done, that too ([`Determination::Unverified`]).
    pub(super) fn solve(&self, mut x: Point<T, P>, mut work: Work) -> Estimate<T, P> {
        let Some(mut lin) = self.linearize_at(&x, &mut work) else {
            let lin = Linearization::empty();
            return self.finish_unsearched(x, &lin, Termination::NonFinite, work);
        };
        // The scan's sweeps are kept out of the budget of the solve itself.
        let budget = self.settings.max_sweeps.saturating_sub(SCAN_SWEEPS);
        let termination = match self.follow_prior(&mut x, &mut lin, budget, &mut work) {
            Ok(()) => self.refine(&mut x, &mut lin, budget, &mut work),
            Err(stopped) => stopped,
        };
        if !termination.is_success() {
            return self.finish_unsearched(x, &lin, termination, work);
        }
        let limit = self.settings.max_sweeps;
        let (scan, widen) = match self.alternatives(&x, &lin, limit, &mut work) {
            Err(OutOfBudget) => (Scan::Incomplete, None),
            Ok(leads) => {
                let scan = self.weigh(&mut x, &mut lin, &leads.starts, limit, &mut work);
                // A better answer elsewhere has its own width: this one's profile does not
                // describe it.
                let widen = if matches!(scan, Scan::Better(_)) {
                    None
                } else {
                    leads.widen
                };
                (scan, widen)
            }
        };
        let mut out = self.finish_widened(x, &lin, termination, work, widen.as_ref());
        let cap = match scan {
            Scan::Unique | Scan::Better(None) => None,
            // A wide answer whose deviations reach the rival already says what the data leave
            // open; a rival beyond them, or next to a determined answer, makes it ambiguous.
            Scan::Ambiguous(rival) | Scan::Better(Some(rival)) => {
                let covered =
                    out.quality.determination == Determination::Weak && rival.covered_by(&out);
                (!covered).then_some(Determination::Ambiguous)
            }
            Scan::Incomplete => Some(Determination::Unverified),
        };
        if let Some(cap) = cap {
            out.quality.determination = out.quality.determination.at_best(cap);
        }
        out
    }

    /// Continuation in the prior: from a prior [`PRIOR_START`] times tighter than the final one to
    /// the final prior in factors of [`PRIOR_STEP`], up to [`PRIOR_ITERATIONS`] damped Gauss-Newton
    /// steps at each level. Moves `x` to the point at the final prior, or to where it stopped and
    /// says why.
    // Out of line: its locals (linearisations, sweeps) need not share a frame with the caller's.
    #[inline(never)]
    fn follow_prior(
        &self,
        x: &mut Point<T, P>,
        lin: &mut Linearization<T, P>,
        budget: u16,
        work: &mut Work,
    ) -> Result<(), Termination> {
        let mut scale = T::lit(PRIOR_START);
        loop {
            let stage = Self {
                prior_weight: self.prior_weight * scale,
                max_moment_residual: self.max_moment_residual * T::lit(LOOSE_PROJECTION),
                ..*self
            };
            stage.damped_steps(x, lin, PRIOR_ITERATIONS, budget, work)?;
            if scale <= T::one() {
                return Ok(());
            }
            scale = (scale * T::lit(PRIOR_STEP)).max(T::one());
        }
    }

    /// Up to `iterations` damped Gauss-Newton steps on this problem's merit from `x`, in place,
    /// stopping early once the next step would gain less than [`PRIOR_SETTLED`]: the damping falls
    /// by 4 after a step that lowers the merit and rises by 16 after one that does not. Fails when
    /// the budget runs out or the system is singular.
    fn damped_steps(
        &self,
        x: &mut Point<T, P>,
        lin: &mut Linearization<T, P>,
        iterations: u16,
        budget: u16,
        work: &mut Work,
    ) -> Result<(), Termination> {
        let mut mu = T::lit(1e-12);
        for _ in 0..iterations {
            if work.sweeps >= budget {
                return Err(Termination::IterationLimit);
            }
            let red = self.reduce(lin).ok_or(Termination::Singular)?;
            let step = self.step(&red, &x.p, mu).ok_or(Termination::Singular)?;
            if self.predicted_decrease(&red, &x.p, &step.1) <= T::lit(PRIOR_SETTLED) {
                break;
            }
            let before = self.merit(&x.p, lin);
            mu = match self.try_step(x, lin, step, before, work) {
                Some(_) => (mu * T::lit(0.25)).max(T::lit(1e-12)),
                None => (mu * T::lit(16.0)).max(T::lit(1e-4)),
            };
        }
        Ok(())
    }

    /// The linearisation at `x`, an equilibrium at its own load: one sweep with every tangent.
    /// `None` when the sweep is not finite.
    // Out of line: the sweep need not share a frame with the caller's locals.
    #[inline(never)]
    fn linearize_at(&self, x: &Point<T, P>, work: &mut Work) -> Option<Linearization<T, P>> {
        work.sweeps = work.sweeps.saturating_add(1);
        let sw = self.full_sweep(x);
        sw.finite.then(|| self.linearize(&sw))
    }

    /// The step `(du, dp)` from `x`: the point after it, brought back onto the equilibrium at its
    /// load, replaces `x` and `lin` when its merit is below `below`; returns that merit. `None`
    /// (and `x`, `lin` unchanged) when the sweep or the projection fails, the equilibrium is
    /// unstable or the merit is not below `below`.
    // Out of line: its locals (linearisations, sweeps) need not share a frame with the caller's.
    #[inline(never)]
    fn try_step(
        &self,
        x: &mut Point<T, P>,
        lin: &mut Linearization<T, P>,
        (du, dp): (Vector3<T>, SVector<T, P>),
        below: T,
        work: &mut Work,
    ) -> Option<T> {
        work.iterations = work.iterations.saturating_add(1);
        work.sweeps = work.sweeps.saturating_add(1);
        let mut trial = Point {
            u0: x.u0 + du,
            p: x.p + dp,
        };
        let mut sw = self.full_sweep(&trial);
        if !(sw.finite && self.project(&mut trial, &mut sw, work)) {
            return None;
        }
        let trial_lin = self.linearize(&sw);
        if !self.acceptable(&trial.p, &trial_lin) {
            return None;
        }
        let merit = self.merit(&trial.p, &trial_lin);
        (merit < below).then(|| {
            (*x, *lin) = (trial, trial_lin);
            merit
        })
    }

    /// Levenberg-Marquardt to convergence from a point near the answer: Nielsen's damping update,
    /// the gain ratio (actual over predicted decrease) setting the damping. Moves `x` (and its
    /// linearisation) to where it stopped and says why.
    // Out of line: its locals (linearisations, sweeps) need not share a frame with the caller's.
    #[inline(never)]
    fn refine(
        &self,
        x: &mut Point<T, P>,
        lin: &mut Linearization<T, P>,
        budget: u16,
        work: &mut Work,
    ) -> Termination {
        let mut merit = self.merit(&x.p, lin);
        let mut mu = T::lit(1e-12);
        let mut nu = T::lit(2.0);
        let mut previous_tip_move = None;
        for _ in 0..self.settings.max_iterations {
            let Some(red) = self.reduce(lin) else {
                return Termination::Singular;
            };
            let (done, tip_move) = self.converged(x, lin, &red, previous_tip_move);
            if done {
                return Termination::Converged;
            }
            if work.sweeps >= budget {
                return Termination::IterationLimit;
            }
            let Some(step) = self.step(&red, &x.p, mu) else {
                return Termination::Singular;
            };
            let predicted = self.predicted_decrease(&red, &x.p, &step.1);
            // A step the linear model says cannot help is not tried.
            let accepted = if predicted > T::zero() {
                self.try_step(x, lin, step, merit, work)
            } else {
                None
            };
            match accepted {
                Some(m) => {
                    let rho = (merit - m) / predicted;
                    let t = T::lit(2.0) * rho - T::one();
                    mu = (mu * (T::one() - t * t * t).max(T::lit(1.0 / 3.0))).max(T::lit(1e-15));
                    nu = T::lit(2.0);
                    merit = m;
                    previous_tip_move = Some(tip_move);
                }
                None => {
                    mu = (mu * nu).max(T::lit(1e-6));
                    nu *= T::lit(2.0);
                    if mu > T::lit(1e12) {
                        // No step improves the fit. If the last Gauss-Newton step is itself negligible,
                        // this is the rounding floor, not a failure.
                        return if self.converged(x, lin, &red, None).0 {
                            Termination::Converged
                        } else {
                            Termination::Stalled
                        };
                    }
                }
            }
        }
        let done = self
            .reduce(lin)
            .is_some_and(|r| self.converged(x, lin, &r, previous_tip_move).0);
        if done {
            Termination::Converged
        } else {
            Termination::IterationLimit
        }
    }

    /// The data's misfit at a linearisation: `|c~|^2`, in squared standard deviations.
    fn misfit(&self, lin: &Linearization<T, P>) -> Option<T> {
        self.reduce(lin).map(|red| red.c.norm_squared())
    }

    /// The direction of the parameters the data determine worst: the smallest eigenvector of the
    /// data's information `G^T G` (power iteration on the data-only covariance, from the QR
    /// factorisation of `G`). `None` when the data do not determine every direction (the verdict
    /// already says so).
    // Out of line: its locals (linearisations, sweeps) need not share a frame with the caller's.
    #[inline(never)]
    fn weakest_direction(&self, lin: &Linearization<T, P>) -> Option<SVector<T, P>> {
        let red = self.reduce(lin)?;
        let covariance = Params::covariance(&red.g, &SVector::zeros())?;
        let mut v = SVector::<T, P>::repeat(T::one()).normalize();
        for _ in 0..WEAKEST_ITERATIONS {
            let next = covariance * v;
            let norm = next.norm();
            if !(norm.is_finite() && norm > T::zero()) {
                return None;
            }
            v = next / norm;
        }
        Some(v)
    }

    /// Whether the free Gauss-Newton step from a point of a profile (`at`, linearised by `lin`) ends
    /// more than half a buckling scale from the answer `x` with the data explained (its predicted
    /// misfit within [`ALTERNATIVE_CHI2`] of `best_misfit`): the linear model there sees another
    /// answer.
    fn points_elsewhere(
        &self,
        at: &Point<T, P>,
        lin: &Linearization<T, P>,
        x: &Point<T, P>,
        best_misfit: T,
    ) -> bool {
        let Some(red) = self.reduce(lin) else {
            return false;
        };
        let Some((_, dp)) = self.step(&red, &at.p, T::zero()) else {
            return false;
        };
        let predicted = (red.c + product(&red.g, &dp)).norm_squared();
        self.apart(&(at.p + dp), &x.p) && predicted <= best_misfit + T::lit(ALTERNATIVE_CHI2)
    }

    /// The size of parameters `p`, in buckling scales.
    fn scales(&self, p: &SVector<T, P>) -> T {
        p.component_mul(&self.buckling_weight).norm()
    }

    /// Whether two parameter vectors are different answers: more than half a buckling scale apart.
    fn apart(&self, a: &SVector<T, P>, b: &SVector<T, P>) -> bool {
        self.scales(&(a - b)) > T::lit(0.5)
    }

    /// How far the search for other answers around `p` reaches, in buckling scales: three times
    /// `p`'s own size, or [`InverseSettings::scan_reach`], whichever is larger.
    fn reach_scales(&self, p: &SVector<T, P>) -> T {
        (self.scales(p) * T::lit(SCAN_FACTOR)).max(self.settings.scan_reach)
    }

    /// Leads to other answers that explain the measurements: a profile of the merit along the
    /// direction `v` the data determine worst. The parameters' component along `v` is held at values
    /// stepping away from the answer's on either side (from [`SCAN_FIRST`] of the answer's load or
    /// one buckling scale `D`, growing by [`SCAN_GROWTH`], halving where a point is not reached), the
    /// rest re-solved from the previous point; where the merit falls outward along the profile (its
    /// slope along `v` turns, or its misfit drops) past a crest, another minimum lies further out,
    /// and the lowest point of that descent is a lead for [`Problem::weigh`]; so is the first point
    /// past the crest whose free step sees another answer ([`Problem::points_elsewhere`]). The
    /// profile reaches loads [`SCAN_FACTOR`] times
    /// the answer's, or [`InverseSettings::scan_reach`] buckling scales, whichever is larger. On the
    /// way it measures the posterior's width along `v` ([`Widen`]).
    // Out of line: its locals (linearisations, sweeps) need not share a frame with the caller's.
    #[inline(never)]
    fn alternatives(
        &self,
        x: &Point<T, P>,
        lin: &Linearization<T, P>,
        limit: u16,
        work: &mut Work,
    ) -> Result<Leads<T, P>, OutOfBudget> {
        let mut leads = Leads {
            starts: [None; 4],
            widen: None,
        };
        let (Some(v), Some(best_misfit)) = (self.weakest_direction(lin), self.misfit(lin)) else {
            return Ok(leads);
        };
        // One buckling scale along v, in parameter units.
        let scale = T::one() / self.scales(&v);
        if !(scale.is_finite() && scale > T::zero()) {
            return Ok(leads);
        }
        let best_merit = self.merit(&x.p, lin);
        // The posterior's width along v as the profile shows it (see `Widen`).
        let mut width = T::zero();
        let size = self.scales(&x.p);
        let reach = self.reach_scales(&x.p) * scale;
        let base = v.dot(&x.p);
        for (side, starts) in [T::one(), -T::one()]
            .into_iter()
            .zip(leads.starts.chunks_exact_mut(2))
        {
            let (mut here, mut here_lin) = (*x, *lin);
            // Steps relative to the answer's own size: the profile's scale of change grows with it.
            let (mut offset, mut step) =
                (T::zero(), scale * (size * T::lit(SCAN_FIRST)).max(T::one()));
            // The lowest point of a descent along the profile, past a crest, and its misfit.
            let mut lowest: Option<(Point<T, P>, T)> = None;
            // The first point whose free step sees another answer.
            let mut pointed: Option<Point<T, P>> = None;
            let mut first = true;
            // The highest misfit on the profile so far: another answer lies beyond a crest.
            let mut crest = best_misfit;
            // The misfit at the previous point of the profile.
            let mut previous = best_misfit;
            while offset < reach && step >= scale * T::lit(0.25) {
                if work.sweeps >= limit {
                    return Err(OutOfBudget);
                }
                let next = (offset + step).min(reach);
                let profile = Self {
                    fix: Some(Fix {
                        direction: v,
                        value: base + side * next,
                    }),
                    max_moment_residual: self.max_moment_residual * T::lit(LOOSE_PROJECTION),
                    ..*self
                };
                let Some(slope) = profile.profile_point(&mut here, &mut here_lin, limit, work)
                else {
                    step *= T::lit(0.5);
                    continue;
                };
                offset = next;
                step *= T::lit(SCAN_GROWTH);
                let misfit = self.misfit(&here_lin).unwrap_or(best_misfit);
                let falling = misfit < previous;
                previous = misfit;
                // The profile's rise over the answer: within one unit the load is inside the
                // posterior's one-standard-deviation interval; at the first point, the rise gives the
                // width a quadratic through it would have.
                let rise = self.merit(&here.p, &here_lin) - best_merit;
                if rise <= T::one() {
                    width = width.max(next);
                }
                if first && rise > T::zero() {
                    width = width.max(next / rise.sqrt());
                }
                first = false;
                crest = crest.max(misfit);
                if crest <= best_misfit + T::lit(ALTERNATIVE_CHI2) {
                    // Still in the answer's own valley (never three standard deviations above it):
                    // a flat valley, not another answer; the posterior reaches at least this far
                    // within three standard deviations.
                    width = width.max(next / T::lit(3.0));
                    continue;
                }
                // Out of the answer's valley, the linear model at this point may already see another
                // answer: its free Gauss-Newton step ends far from the answer with the data
                // explained. That point is a lead (the profile's steps, growing, can stride over a
                // narrow valley that the samples' misfits and slopes never show).
                if pointed.is_none() && self.points_elsewhere(&here, &here_lin, x, best_misfit) {
                    pointed = Some(here);
                }
                // Past a crest the merit falls outward: follow the profile down to its next valley
                // (where the slope turns again, or the data are explained); the lowest point seen
                // since the crest is the lead. Falling is read from the slope and from the misfit
                // against the previous point: a point a few steps short of the profile's floor can
                // have its slope wrong.
                let descending = side * slope < T::zero() || falling;
                if descending || lowest.is_some() {
                    if lowest.is_none_or(|(_, m)| misfit < m) {
                        lowest = Some((here, misfit));
                    }
                    if descending && misfit > best_misfit + T::lit(ALTERNATIVE_CHI2) {
                        continue;
                    }
                    break;
                }
            }
            // A descent cut short by the reach or a point not reached is a lead where it got to.
            if let [descent, free] = starts {
                *descent = lowest.map(|(point, _)| point);
                *free = pointed;
            }
        }
        leads.widen = (width > T::zero()).then_some(Widen {
            direction: v,
            std: width,
        });
        Ok(leads)
    }

    /// Follows the leads of [`Problem::alternatives`]: an unconstrained solve from each, to
    /// convergence or a stall within the budget (a lead whose solve the budget cuts short leaves
    /// the question open: [`Scan::Incomplete`]). A point more than half a buckling scale from the
    /// answer `x` is another answer; the best of them replaces `x` and `lin` when it scores better.
    // Out of line: its locals (linearisations, sweeps) need not share a frame with the caller's.
    #[inline(never)]
    fn weigh(
        &self,
        x: &mut Point<T, P>,
        lin: &mut Linearization<T, P>,
        starts: &[Option<Point<T, P>>; 4],
        limit: u16,
        work: &mut Work,
    ) -> Scan<T, P> {
        let Some(best_misfit) = self.misfit(lin) else {
            return Scan::Unique;
        };
        let best_merit = self.merit(&x.p, lin);
        // The best other answer reached, its merit, and whether its solve converged (else it
        // stalled: no step improves it, a local minimum as far as the solve can tell).
        let mut found: Option<(Point<T, P>, T, bool)> = None;
        for start in starts.iter().flatten() {
            if work.sweeps >= limit {
                return Scan::Incomplete;
            }
            // A lead is on the equilibrium at its own load: one sweep linearises it.
            let mut reached = *start;
            let Some(mut reached_lin) = self.linearize_at(&reached, work) else {
                continue;
            };
            let termination = self.refine(&mut reached, &mut reached_lin, limit, work);
            if termination == Termination::IterationLimit {
                return Scan::Incomplete;
            }
            let merit = self.merit(&reached.p, &reached_lin);
            if self.apart(&reached.p, &x.p) && found.is_none_or(|(_, m, _)| m > merit) {
                found = Some((reached, merit, termination.is_success()));
            }
        }
        let Some((alt, alt_merit, converged)) = found else {
            return Scan::Unique;
        };
        // The point's linearisation again (one sweep: the same point gives the same sweep).
        if work.sweeps >= limit {
            return Scan::Incomplete;
        }
        let Some(alt_lin) = self.linearize_at(&alt, work) else {
            return Scan::Incomplete;
        };
        let alt_misfit = self.misfit(&alt_lin).unwrap_or(best_misfit);
        // A rival explains the data about as well (the prior aside: it is a guess at the loads the
        // robot meets, not a measurement) and lies within the search's reach, the loads the robot
        // can meet (a pull a hundred buckling scales strong straightens the rod as a small load
        // does, and is no rival to it when the robot cannot pull that hard).
        let within_reach = |p: &SVector<T, P>| self.scales(p) <= self.reach_scales(&x.p);
        let chi2 = T::lit(ALTERNATIVE_CHI2);
        if converged && alt_merit < best_merit - chi2 {
            // The other answer scores clearly better (data and prior): it is returned, and
            // ambiguous if this one is a rival to it.
            let this_fits = best_misfit <= alt_misfit + chi2 && within_reach(&x.p);
            let this = this_fits.then(|| Rival::at(x, lin));
            (*x, *lin) = (alt, alt_lin);
            Scan::Better(this)
        } else if alt_merit < best_merit
            || (alt_misfit <= best_misfit + chi2 && within_reach(&alt.p))
        {
            // A rival, or an answer scoring a little better: this one is kept (the one its branch
            // leads to; two equally good fits do not swap on rounding), and not called determined.
            Scan::Ambiguous(Rival::at(&alt, &alt_lin))
        } else {
            Scan::Unique
        }
    }

    /// One point of a profile from the previous one: a constrained Gauss-Newton step onto it, then
    /// up to [`SCAN_ITERATIONS`] damped ones along it. Moves `here` to the new point and returns the
    /// merit's slope along the profile's direction there; `None` when the point is not reached
    /// (`here` may have moved toward it).
    fn profile_point(
        &self,
        here: &mut Point<T, P>,
        here_lin: &mut Linearization<T, P>,
        limit: u16,
        work: &mut Work,
    ) -> Option<T> {
        let fix = self.fix?;
        let red = self.reduce(here_lin)?;
        let step = self.step(&red, &here.p, T::lit(1e-12))?;
        let anywhere = T::max_value().unwrap_or_else(T::one);
        self.try_step(here, here_lin, step, anywhere, work)?;
        // The trust region may have shortened the step: on the way, but not on the constraint.
        if (fix.direction.dot(&here.p) - fix.value).abs()
            > T::lit(1e-3) / self.buckling_weight.max().max(T::default_epsilon())
        {
            return None;
        }
        self.damped_steps(here, here_lin, SCAN_ITERATIONS, limit, work)
            .ok()?;
        let red = self.reduce(here_lin)?;
        Some(fix.direction.dot(&self.gradient(&red, &here.p)))
    }

    pub(super) fn finish(
        &self,
        x: Point<T, P>,
        lin: &Linearization<T, P>,
        termination: Termination,
        work: Work,
    ) -> Estimate<T, P> {
        self.finish_widened(x, lin, termination, work, None)
    }

    /// [`Problem::finish`] of a solve that did not converge and so never searched for other
    /// answers: its verdict is [`Determination::Unverified`] at best.
    pub(super) fn finish_unsearched(
        &self,
        x: Point<T, P>,
        lin: &Linearization<T, P>,
        termination: Termination,
        work: Work,
    ) -> Estimate<T, P> {
        let mut out = self.finish_widened(x, lin, termination, work, None);
        out.quality.determination = out.quality.determination.at_best(Determination::Unverified);
        out
    }

    /// [`Problem::finish`], with the posterior widened along a direction where the profile showed
    /// it wider than the linearisation does.
    fn finish_widened(
        &self,
        x: Point<T, P>,
        lin: &Linearization<T, P>,
        termination: Termination,
        work: Work,
        widen: Option<&Widen<T, P>>,
    ) -> Estimate<T, P> {
        let red = self.reduce(lin);
        let quality = self.quality(lin, red.as_ref(), widen);
        let mut termination = termination;
        if termination.is_success()
            && !(lin.frame_drift.is_finite() && lin.frame_drift <= T::lit(MAX_FRAME_DRIFT))
        {
            termination = Termination::FrameDrift;
        }
        if termination.is_success() && !resolved(lin.phase_per_step_rad) {
            termination = Termination::UnderResolved;
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
                phase_per_step_rad: lin.phase_per_step_rad,
            },
            quality,
        }
    }
}
