//! The forward solve from tensions (force control): the equilibrium of the rod under the tendons'
//! tensions, the scene's gravity and point loads and a tip load, and each tendon's path length.

use heapless::Vec;
use nalgebra::SVector;

use super::paths::{Lengths, lengths};
use super::{MAX_TENDONS, Tendons};

use crate::error::{ModelError, finite_vec};
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::tendon::TendonRod;
use crate::report::Termination;
use crate::shape::ShapePoint;
use crate::shooting::{Equilibrium, ShootingSettings, equilibrium, shape_of};
use crate::{MAX_GUIDES, Scalar};

/// An equilibrium under tendon tensions.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonEquilibrium<T> {
    /// The rod's equilibrium (base force and moment, tip pose, the solve's report).
    pub equilibrium: Equilibrium<T>,
    /// The tensions it was solved for, N, one per tendon.
    pub tensions_n: Vec<T, MAX_TENDONS>,
    /// Each tendon's path length, m (empty unless the solve succeeded).
    pub path_m: Vec<T, MAX_TENDONS>,
    /// Each tendon's unstretched length from spool to termination that the equilibrium needs, m:
    /// its feed and chords, each shortened by its own tension's stretch (the path plus the feed for
    /// an inextensible tendon). Empty unless the solve succeeded.
    pub unstretched_m: Vec<T, MAX_TENDONS>,
}

impl<T: Scalar> TendonEquilibrium<T> {
    /// Whether the solve converged to an accepted equilibrium.
    pub fn is_success(&self) -> bool {
        self.equilibrium.report.termination.is_success()
    }
}

impl<T: Scalar> Tendons<T> {
    /// What a shape sweep of `solved` on `model` needs checked: these tendons against the model,
    /// the tensions, a finite base and a valid tip load. Returns the tensions.
    pub(super) fn check_solved<A: Attitude<T>, const NODES: usize>(
        &self,
        model: &Model<T, A, NODES>,
        solved: &TendonEquilibrium<T>,
    ) -> Result<[T; MAX_TENDONS], ModelError> {
        self.check_model(model)?;
        let tau = self.check_tensions(&solved.tensions_n)?;
        let eq = &solved.equilibrium;
        finite_vec(&eq.base_force_n, "base force")?;
        finite_vec(&eq.base_moment_nm, "base moment")?;
        eq.load.validate()?;
        Ok(tau)
    }

    /// Whether these tendons were checked against a model with `model`'s guides.
    pub(super) fn check_model<A: Attitude<T>, const NODES: usize>(
        &self,
        model: &Model<T, A, NODES>,
    ) -> Result<(), ModelError> {
        let guides = &model.rod().guides;
        if guides.len() != self.guide_s_m.len()
            || guides.iter().zip(&self.guide_s_m).any(|(g, s)| g.s_m != *s)
        {
            return Err(ModelError::Mismatch("tendons and the model's guides"));
        }
        Ok(())
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Solves the equilibrium under tendon tensions `tensions_n` (N, one per tendon, none negative),
    /// the scene's dead loads and `load` at the tip, and each tendon's path length.
    ///
    /// From a cold start the tensions and loads are ramped from zero (load continuation): there is
    /// no energy test of stability with tendons yet, and `report.stability` says
    /// [`crate::Stability::Unchecked`]. A warm start takes a previous equilibrium.
    ///
    /// Fails only on invalid input; a solve that does not converge returns `Ok` with the reason in
    /// the report.
    pub fn solve_tendons(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        load: &TipLoad<T>,
        start: Option<&TendonEquilibrium<T>>,
        settings: &ShootingSettings<T>,
    ) -> Result<TendonEquilibrium<T>, ModelError> {
        tendons.check_model(self)?;
        let tau = tendons.check_tensions(tensions_n)?;
        load.validate()?;
        settings.validate()?;
        let ode = TendonRod::new(self, tendons, &tau, load, T::one());
        // A failed equilibrium is no start: its zeros would send a direct Newton off at full load.
        let start = match start.filter(|s| s.is_success()) {
            Some(previous) => {
                let eq = &previous.equilibrium;
                finite_vec(&eq.base_force_n, "warm-start base force")?;
                finite_vec(&eq.base_moment_nm, "warm-start base moment")?;
                Some(ode.unknowns(&eq.base_force_n, &eq.base_moment_nm))
            }
            None => None,
        };
        let outcome = crate::solve::solve(&ode, start, settings);
        let x = outcome.as_ref().ok().map(|s| s.newton.x);
        let mut eq = equilibrium(load, 0, outcome, |x| ode.base(x));
        let mut tensions = Vec::new();
        for t in tensions_n {
            // Cannot overflow: checked against MAX_TENDONS.
            let _ = tensions.push(*t);
        }
        let mut path_m = Vec::new();
        let mut unstretched_m = Vec::new();
        if let (true, Some(x)) = (eq.report.termination.is_success(), x) {
            match self
                .tendon_lengths(tendons, tensions_n, &ode, &x)
                .filter(|l| {
                    l.path_m
                        .iter()
                        .chain(&l.unstretched_m)
                        .all(|v| v.is_finite())
                }) {
                Some(lengths) => {
                    for (p, u) in lengths
                        .path_m
                        .iter()
                        .zip(&lengths.unstretched_m)
                        .take(tendons.len())
                    {
                        // Cannot overflow: at most MAX_TENDONS.
                        let _ = path_m.push(*p);
                        let _ = unstretched_m.push(*u);
                    }
                }
                None => eq.report.termination = Termination::NonFinite,
            }
        }
        Ok(TendonEquilibrium {
            equilibrium: eq,
            tensions_n: tensions,
            path_m,
            unstretched_m,
        })
    }

    fn tendon_lengths(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        ode: &TendonRod<'_, T, A, NODES>,
        x: &SVector<T, 6>,
    ) -> Option<Lengths<T>> {
        let mut guides = [ShapePoint::default(); MAX_GUIDES];
        let count = tendons.guide_s_m.len();
        let out = guides.get_mut(..count)?;
        let written = shape_of(ode, x, &tendons.guide_s_m, out).ok()?;
        let rod = self.rod();
        lengths(
            tendons,
            tensions_n,
            &rod.base_position_m,
            &rod.base_orientation,
            guides.get(..written)?,
        )
    }

    /// The backbone of a tendon equilibrium at the arc lengths `s_m` (see [`Model::shape`]).
    pub fn shape_tendons(
        &self,
        tendons: &Tendons<T>,
        solved: &TendonEquilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        let tau = tendons.check_solved(self, solved)?;
        let eq = &solved.equilibrium;
        let ode = TendonRod::new(self, tendons, &tau, &eq.load, T::one());
        let x = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        shape_of(&ode, &x, s_m, out)
    }
}
