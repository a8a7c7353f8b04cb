//! The forward solve of continuously routed tendons (Rucker & Webster 2011; MODEL.md §6.8): the same
//! routing as the discrete guides (constant body offsets, terminations at guides), with each tendon
//! running along the backbone instead of in chords between holes. Six unknowns, single shooting;
//! no look-ahead at the guides, so a sweep costs a strain solve per stage instead of an implicit jump
//! per guide. Guides still carry mass and place terminations; their holes play no part.

use heapless::Vec;
use nalgebra::SVector;

use super::{MAX_TENDONS, TendonEquilibrium, Tendons};
use crate::Scalar;
use crate::error::{ModelError, finite_vec};
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::tendon_continuous::{ContinuousTendonRod, PathRecord};
use crate::report::Termination;
use crate::shape::ShapePoint;
use crate::shooting::{ShootingSettings, equilibrium, shape_of};
use crate::sweep::{TangentSet, sweep};

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Solves the equilibrium under continuously routed tendons at tensions `tensions_n` (N, one
    /// per tendon, none negative), the scene's dead loads and `load` at the tip, and each tendon's
    /// path length: the length of its curve from the base plate's hole to its termination.
    ///
    /// The rest length is the discrete model's ([`Tendons::rest_length_m`]): on the straight,
    /// unloaded rod both paths are the termination's arc length.
    ///
    /// A cold start ramps tensions and loads from zero; `report.stability` is
    /// [`crate::Stability::Unchecked`]. A warm start takes a previous equilibrium of either tendon
    /// model (the rod's own base force and moment). Fails only on invalid input.
    pub fn solve_tendons_continuous(
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
        let record = PathRecord::new();
        let ode = ContinuousTendonRod::new(self, tendons, &tau, load, T::one());
        let ode = ode.recording(&record);
        let start = match start {
            Some(previous) => {
                let eq = &previous.equilibrium;
                finite_vec(&eq.base_force_n, "warm-start base force")?;
                finite_vec(&eq.base_moment_nm, "warm-start base moment")?;
                let x = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
                if !crate::scalar::all_finite(&x) {
                    return Err(ModelError::NonFinite(
                        "warm-start base (a tendon folds back)",
                    ));
                }
                Some(x)
            }
            None => None,
        };
        let outcome = crate::solve::solve(&ode, start, settings);
        let x = outcome.as_ref().ok().map(|s| s.newton.x);
        let mut eq = equilibrium(load, self.rod().cables.len(), outcome, |x| ode.base(x));
        let mut tensions = Vec::new();
        for t in tensions_n {
            // Cannot overflow: checked against MAX_TENDONS.
            let _ = tensions.push(*t);
        }
        let mut path_m = Vec::new();
        if let (true, Some(x)) = (eq.report.termination.is_success(), x) {
            match continuous_paths(&ode, &record, &x) {
                Some(lengths) => {
                    for l in lengths.iter().take(tendons.len()) {
                        let _ = path_m.push(*l);
                    }
                }
                None => eq.report.termination = Termination::NonFinite,
            }
        }
        let unstretched_m = super::paths::uniform_unstretched(tendons, &tensions, &path_m);
        Ok(TendonEquilibrium {
            equilibrium: eq,
            tensions_n: tensions,
            path_m,
            unstretched_m,
        })
    }

    /// The backbone of an equilibrium from [`Model::solve_tendons_continuous`] at the arc lengths
    /// `s_m` (see [`Model::shape`]).
    pub fn shape_tendons_continuous(
        &self,
        tendons: &Tendons<T>,
        solved: &TendonEquilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        let tau = tendons.check_solved(self, solved)?;
        let eq = &solved.equilibrium;
        let ode = ContinuousTendonRod::new(self, tendons, &tau, &eq.load, T::one());
        let x = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        if !crate::scalar::all_finite(&x) {
            return Err(ModelError::NonFinite("base (a tendon folds back)"));
        }
        shape_of(&ode, &x, s_m, out)
    }
}

/// The path lengths at unknowns `x`: those the solve's last sweep integrated when it ran at `x`
/// (the converged sweep), else one plain sweep's.
fn continuous_paths<T: Scalar, A: Attitude<T>, const NODES: usize>(
    ode: &ContinuousTendonRod<'_, T, A, NODES>,
    record: &PathRecord<T>,
    x: &SVector<T, 6>,
) -> Option<[T; MAX_TENDONS]> {
    if let Some(paths) = record.paths_at(x) {
        return Some(paths);
    }
    let sw = sweep(ode, x, TangentSet::NONE, None);
    let paths = record.paths_at(x);
    sw.finite.then_some(paths).flatten()
}
