//! The forward problem's entry points: the equilibrium of a model under a tip load (thesis ch. 2.5: a
//! shooting problem), one sweep without solving, and the shape of a solved equilibrium.
//!
//! Under dead loads the unknowns are the base strain `u(0)` and the tip condition is
//! `R(L) C u(L) = tau_tip` (three unknowns, three residuals: `ode/dead_load.rs`). With loads that
//! read the shape ([`crate::loads::ShapeLoad`]) the internal force and moment become states and the
//! unknowns are `n(0)`, `m(0)` (`ode/force_state.rs`). Either is solved by `solve/`.

use heapless::Vec;
use nalgebra::{Matrix3, SVector, Vector3};

use crate::error::{ModelError, finite_vec};
use crate::kinematics::Attitude;
use crate::loads::ShapeLoad;
pub use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::RodOde;
use crate::ode::dead_load::DeadLoadRod;
use crate::ode::force_state::ForceStateRod;
use crate::report::{SolveReport, Termination};
use crate::shape::{ShapePoint, ShapeSink, check_queries};
pub use crate::solve::ShootingSettings;
pub use crate::solve::stopping::default_tolerance;
use crate::solve::{Failed, Solved};
use crate::stability::Stability;
use crate::sweep::{TangentSet, sweep};
use crate::{MAX_CABLES, Scalar};

/// Where a solve starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start<T> {
    /// From nothing: the bent rod's guess (MODEL.md §3.12), then load continuation if needed.
    Cold,
    /// From a previous base strain, 1/m: Newton with the tangents from the first sweep.
    Warm(Vector3<T>),
    /// From a solved neighbour ([`Equilibrium::next_start`]), the cheap path when the loads changed
    /// a little: secant steps from its base strain and shooting Jacobian (Broyden's update) on plain
    /// sweeps while they contract, and one sweep with the tangents for the stability test at the
    /// answer (MODEL.md §3.13, `solve/secant.rs`). Where the steps do not converge, Newton goes on
    /// from where they stopped, as from [`Start::Warm`].
    Neighbour(Neighbour<T>),
}

/// A solved equilibrium to start the next solve from ([`Start::Neighbour`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour<T> {
    /// The base strain `u(0)`, 1/m, body frame.
    pub base_strain_per_m: Vector3<T>,
    /// The shooting Jacobian there, `d (C u(L) - R(L)^T tau_tip) / d u(0)`, N m^2, body frame.
    pub jacobian_nm2: Matrix3<T>,
}

/// A solved equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium<T> {
    /// The base strain `u(0)`, 1/m, body frame (the dead-load shooting unknown).
    pub base_strain_per_m: Vector3<T>,
    /// The internal force just distal of the clamp, N, global frame (the clamp's reaction is its
    /// negative).
    pub base_force_n: Vector3<T>,
    /// The internal moment just distal of the clamp, N m, global frame.
    pub base_moment_nm: Vector3<T>,
    /// The tip load it was solved for.
    pub load: TipLoad<T>,
    /// Tip position, m.
    pub tip_position_m: Vector3<T>,
    /// Tip frame.
    pub tip_rotation: Matrix3<T>,
    /// Cable lengths, m, in the rod's cable order.
    pub cable_lengths_m: Vec<T, MAX_CABLES>,
    /// The shooting Jacobian at the answer, `d (C u(L) - R(L)^T tau_tip) / d u(0)`, N m^2, for the
    /// next start ([`Equilibrium::next_start`]): from the tangents of the answer's sweep, or, from a
    /// neighbour with the stability test off, the secant steps' estimate (Broyden's). `None` for the
    /// solves other than [`Model::solve`] and for failed ones.
    pub jacobian_nm2: Option<Matrix3<T>>,
    /// How the solve went; only `report.termination.is_success()` makes the rest trustworthy.
    pub report: SolveReport<T>,
}

impl<T: Scalar> Equilibrium<T> {
    /// The tip tangent (local z) in global coordinates.
    pub fn tip_tangent(&self) -> Vector3<T> {
        self.tip_rotation.column(2).into_owned()
    }

    /// Where the next solve of the same model should start when the loads change a little: from
    /// this answer as a [`Start::Neighbour`] when it has its Jacobian, as a [`Start::Warm`] when not,
    /// and cold when this solve failed.
    pub fn next_start(&self) -> Start<T> {
        if !self.report.termination.is_success() {
            return Start::Cold;
        }
        match self.jacobian_nm2 {
            Some(jacobian_nm2) => Start::Neighbour(Neighbour {
                base_strain_per_m: self.base_strain_per_m,
                jacobian_nm2,
            }),
            None => Start::Warm(self.base_strain_per_m),
        }
    }
}

/// One sweep at a given base strain and tip load, without solving: for diagnostics and tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Evaluation<T> {
    /// Tip position, m.
    pub tip_position_m: Vector3<T>,
    /// Tip frame.
    pub tip_rotation: Matrix3<T>,
    /// `C u(L) - R(L)^T tau_tip`, N m, body frame.
    pub moment_residual_nm: Vector3<T>,
    /// Cable lengths, m, one per cable (the rest zero).
    pub cable_lengths_m: [T; MAX_CABLES],
    /// Largest `|R^T R - I|` met at the nodes (rotation drift of the integrator).
    pub frame_drift: T,
}

/// The base of an equilibrium: strain (1/m, body), internal force (N) and moment (N m), global.
pub(crate) type Base<T> = (Vector3<T>, Vector3<T>, Vector3<T>);

/// An equilibrium with no solve to show, ended by `termination`: zeros, an identity frame, and a
/// residual that is not a number (rather than a zero that reads as exact).
pub(crate) fn failed_equilibrium<T: Scalar>(
    load: &TipLoad<T>,
    termination: Termination,
) -> Equilibrium<T> {
    Equilibrium {
        base_strain_per_m: Vector3::zeros(),
        base_force_n: Vector3::zeros(),
        base_moment_nm: Vector3::zeros(),
        load: *load,
        tip_position_m: Vector3::zeros(),
        tip_rotation: Matrix3::identity(),
        cable_lengths_m: Vec::new(),
        jacobian_nm2: None,
        report: SolveReport {
            termination,
            iterations: 0,
            sweeps: 0,
            residual: T::lit(f64::NAN),
            load_steps: 0,
            stability: Stability::Unchecked,
            phase_per_step_rad: T::zero(),
        },
    }
}

/// The equilibrium a solve ended with; `base` maps the unknowns to the base's strain, force, moment.
pub(crate) fn equilibrium<T: Scalar, const K: usize>(
    load: &TipLoad<T>,
    cables: usize,
    outcome: Result<Solved<T, K>, Failed>,
    base: impl Fn(&SVector<T, K>) -> Base<T>,
) -> Equilibrium<T> {
    let solved = match outcome {
        Ok(solved) => solved,
        Err(failed) => {
            let mut eq = failed_equilibrium(load, Termination::ContinuationFailed);
            eq.report.iterations = failed.work.iterations;
            eq.report.sweeps = failed.work.sweeps;
            eq.report.load_steps = failed.load_steps;
            return eq;
        }
    };
    let outcome = &solved.newton;
    let mut cable_lengths_m = Vec::new();
    for c in outcome.sweep.cable_m.iter().take(cables) {
        // Cannot overflow: at most MAX_CABLES cables.
        let _ = cable_lengths_m.push(*c);
    }
    let (base_strain_per_m, base_force_n, base_moment_nm) = base(&outcome.x);
    Equilibrium {
        base_strain_per_m,
        base_force_n,
        base_moment_nm,
        load: *load,
        tip_position_m: outcome.sweep.tip_position_m,
        tip_rotation: outcome.sweep.tip_rotation,
        cable_lengths_m,
        jacobian_nm2: None,
        report: SolveReport {
            termination: outcome.termination,
            iterations: solved.work.iterations,
            sweeps: solved.work.sweeps,
            residual: outcome.residual,
            load_steps: solved.load_steps,
            stability: solved.stability,
            phase_per_step_rad: outcome.sweep.phase_per_step_rad,
        },
    }
}

/// The shape of `ode` at unknowns `x`, at the arc lengths `s_m`, into `out`.
pub(crate) fn shape_of<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    x: &SVector<T, K>,
    s_m: &[T],
    out: &mut [ShapePoint<T>],
) -> Result<usize, ModelError> {
    check_queries(s_m, out.len(), ode.length_m())?;
    let mut sink = ShapeSink {
        s_m,
        out,
        written: 0,
    };
    let sw = sweep(ode, x, TangentSet::NONE, Some(&mut sink));
    if !sw.finite {
        return Err(ModelError::NonFinite("sweep result"));
    }
    Ok(sink.written)
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
        match start {
            Start::Cold => self.solve_dead_load(load, None, settings),
            Start::Warm(u) => {
                finite_vec(&u, "warm-start base strain")?;
                self.solve_dead_load(load, Some(u), settings)
            }
            Start::Neighbour(n) => self.solve_near(load, &n, settings),
        }
    }

    /// [`Model::solve`] cold (`start` `None`) or warm from a base strain.
    pub(crate) fn solve_dead_load(
        &self,
        load: &TipLoad<T>,
        start: Option<Vector3<T>>,
        settings: &ShootingSettings<T>,
    ) -> Result<Equilibrium<T>, ModelError> {
        load.validate()?;
        settings.validate()?;
        let ode = DeadLoadRod::new(self, load, T::one());
        let outcome = crate::solve::solve(&ode, start, settings);
        Ok(self.dead_load_equilibrium(load, outcome, None))
    }

    /// [`Model::solve`] from a solved neighbour ([`Start::Neighbour`]). Out of line, and apart from
    /// [`Model::solve_dead_load`]: the images that never start from a neighbour (the estimator's)
    /// do not carry its secant steps.
    #[inline(never)]
    fn solve_near(
        &self,
        load: &TipLoad<T>,
        near: &Neighbour<T>,
        settings: &ShootingSettings<T>,
    ) -> Result<Equilibrium<T>, ModelError> {
        load.validate()?;
        finite_vec(&near.base_strain_per_m, "warm-start base strain")?;
        if !crate::scalar::all_finite(&near.jacobian_nm2) {
            return Err(ModelError::NonFinite("warm-start Jacobian"));
        }
        settings.validate()?;
        let ode = DeadLoadRod::new(self, load, T::one());
        let (outcome, secant) = crate::solve::secant::solve_near(
            &ode,
            near.base_strain_per_m,
            &near.jacobian_nm2,
            settings,
        );
        Ok(self.dead_load_equilibrium(load, outcome, Some(&secant)))
    }

    /// The equilibrium a dead-load solve ended with, with the Jacobian at its answer: its sweep's,
    /// or where that carried no tangents (a neighbour's secant steps with the stability test off),
    /// the secant steps' (`secant`: the neighbour's, updated by Broyden's rule along them).
    fn dead_load_equilibrium(
        &self,
        load: &TipLoad<T>,
        outcome: Result<Solved<T, 3>, Failed>,
        secant: Option<&Matrix3<T>>,
    ) -> Equilibrium<T> {
        let jacobian_nm2 = match &outcome {
            Ok(solved) if solved.newton.sweep.has_jacobian() => {
                Some(solved.newton.sweep.jacobian())
            }
            Ok(_) => secant.copied(),
            Err(_) => None,
        };
        let mut eq = equilibrium(load, self.rod().cables.len(), outcome, |u| {
            self.dead_load_base(load, u)
        });
        eq.jacobian_nm2 = jacobian_nm2;
        eq
    }

    /// The base of a dead-load equilibrium with base strain `u0`: the internal force is the sum of the
    /// loads, the moment `R0 C u0`.
    pub(crate) fn dead_load_base(&self, load: &TipLoad<T>, u0: &Vector3<T>) -> Base<T> {
        let c = self.base_compliance().map_or(Vector3::zeros(), |c| c.c);
        (
            *u0,
            load.force_n + self.plan().base_force_n(),
            self.rod().base_orientation * c.component_mul(u0),
        )
    }

    /// One sweep at base strain `u0` (1/m) under `load`, without solving for the boundary condition.
    pub fn evaluate(
        &self,
        base_strain_per_m: &Vector3<T>,
        load: &TipLoad<T>,
    ) -> Result<Evaluation<T>, ModelError> {
        finite_vec(base_strain_per_m, "base strain")?;
        load.validate()?;
        let ode = DeadLoadRod::new(self, load, T::one());
        let out = sweep(&ode, base_strain_per_m, TangentSet::NONE, None);
        if !out.finite {
            return Err(ModelError::NonFinite("sweep result"));
        }
        Ok(Evaluation {
            tip_position_m: out.tip_position_m,
            tip_rotation: out.tip_rotation,
            moment_residual_nm: out.residual,
            cable_lengths_m: out.cable_m,
            frame_drift: out.frame_drift,
        })
    }

    /// The shape of a solved equilibrium at the arc lengths `s_m` (increasing, within `[0, L]`),
    /// written into `out` (at least as long). Returns how many points were written.
    pub fn shape(
        &self,
        equilibrium: &Equilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        self.shape_at(&equilibrium.base_strain_per_m, &equilibrium.load, s_m, out)
    }

    /// The shape at a given base strain and tip load (see [`Model::shape`]).
    pub fn shape_at(
        &self,
        base_strain_per_m: &Vector3<T>,
        load: &TipLoad<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        finite_vec(base_strain_per_m, "base strain")?;
        load.validate()?;
        let ode = DeadLoadRod::new(self, load, T::one());
        shape_of(&ode, base_strain_per_m, s_m, out)
    }

    /// Solves the equilibrium under `load`, the scene's dead loads and `shape_loads`, loads that read
    /// the shape (a spring pulling a guide, later the tendons), with the internal force and moment as
    /// states: six unknowns `n(0)`, `m(0)`.
    ///
    /// From `Start::Cold` the loads are ramped from zero (load continuation), which follows the branch
    /// connected to the unloaded rod: these equations have no energy test of stability yet, and the
    /// answer's `report.stability` is [`Stability::Unchecked`]. `Start::Warm` takes a previous
    /// equilibrium's base force and moment (from this method or [`Model::solve`]).
    ///
    /// Fails only on invalid input, like [`Model::solve`].
    pub fn solve_with<L: ShapeLoad<T>>(
        &self,
        shape_loads: &L,
        load: &TipLoad<T>,
        start: Option<&Equilibrium<T>>,
        settings: &ShootingSettings<T>,
    ) -> Result<Equilibrium<T>, ModelError> {
        load.validate()?;
        settings.validate()?;
        let ode = ForceStateRod::new(self, shape_loads, load, T::one());
        let start = match start {
            Some(eq) => {
                finite_vec(&eq.base_force_n, "warm-start base force")?;
                finite_vec(&eq.base_moment_nm, "warm-start base moment")?;
                Some(ode.unknowns(&eq.base_force_n, &eq.base_moment_nm))
            }
            None => None,
        };
        let outcome = crate::solve::solve(&ode, start, settings);
        Ok(equilibrium(load, self.rod().cables.len(), outcome, |x| {
            ode.base(x)
        }))
    }

    /// The shape of an equilibrium from [`Model::solve_with`] under the same `shape_loads` (see
    /// [`Model::shape`]).
    pub fn shape_with<L: ShapeLoad<T>>(
        &self,
        shape_loads: &L,
        equilibrium: &Equilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        finite_vec(&equilibrium.base_force_n, "base force")?;
        finite_vec(&equilibrium.base_moment_nm, "base moment")?;
        equilibrium.load.validate()?;
        let ode = ForceStateRod::new(self, shape_loads, &equilibrium.load, T::one());
        let x = ode.unknowns(&equilibrium.base_force_n, &equilibrium.base_moment_nm);
        shape_of(&ode, &x, s_m, out)
    }
}
