//! The forward model of a calibration: every experiment's observed points predicted by the scene's
//! model at given parameter values, with the calls `solve` makes (`run.rs`: [`with_model`],
//! `Model::solve`, `Scene::tendon_set`, `Model::solve_tendons`, `Model::solve_displacements`).
//!
//! Each experiment warm-starts from its own last equilibrium (the previous parameter values: the
//! fit moves them a little), else from the experiment before it in the data; a warm start that
//! fails is retried cold. A solve whose inputs have not changed (a Jacobian column of the base
//! pose, which only moves the points) is not repeated.

use model_core::{
    Attitude, DisplacementSettings, Model, ShapePoint, ShootingSettings, Start, TendonEquilibrium,
    Tendons, TipLoad,
};
use nalgebra::Vector3;

use super::data::{ExperimentActuation, Measurements};
use super::params::Values;
use crate::run::{WithModel, with_model};
use crate::scene::{Control, Scene, SceneError};

/// Why a prediction has no answer: which experiment, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct NoAnswer {
    /// The experiment and its line.
    pub experiment: String,
    /// The termination, in words.
    pub why: String,
}

/// Where an experiment's solve may start.
#[derive(Debug, Clone)]
enum Warm {
    /// A dead-load equilibrium's base strain, 1/m.
    DeadLoad(Vector3<f64>),
    /// A tendon equilibrium.
    Tendons(Box<TendonEquilibrium<f64>>),
}

/// An experiment's last solve.
#[derive(Debug, Clone)]
struct Cached {
    /// The physical values and the tip force (scene frame) it was solved at.
    key: [f64; 7],
    /// Its observed points, scene frame, m.
    points_m: Vec<Vector3<f64>>,
    warm: Warm,
}

/// The forward model over a data set.
#[derive(Debug)]
pub struct Forward<'a> {
    scene: &'a Scene,
    data: &'a Measurements,
    settings: ShootingSettings<f64>,
    /// The scene's actuation, for experiments whose rows give none.
    scene_actuation: Option<ExperimentActuation>,
    cache: Vec<Option<Cached>>,
    /// Forward solves run so far.
    pub solves: u64,
}

impl<'a> Forward<'a> {
    /// The forward model of `scene` over `data`. A tendon scene needs an actuation: the data's, or
    /// the scene's `[actuation]` for every experiment.
    pub fn new(scene: &'a Scene, data: &'a Measurements) -> Result<Self, SceneError> {
        let settings = scene.shooting_settings()?;
        let needs_scene_actuation = data.experiments.iter().any(|e| e.actuation.is_none());
        let scene_actuation = if !scene.tendons.is_empty() && needs_scene_actuation {
            let a = scene.actuation()?.ok_or_else(|| {
                SceneError::new(
                    "actuation",
                    "missing: the data give no tension_<j>_n or displacement_<j>_m columns, and \
                     the scene has no [actuation]",
                )
            })?;
            Some(ExperimentActuation {
                control: a.control,
                values: a.values,
            })
        } else {
            None
        };
        Ok(Self {
            scene,
            data,
            settings,
            scene_actuation,
            cache: vec![None; data.experiments.len()],
            solves: 0,
        })
    }

    /// The tip force of experiment `i` in the scene's frame, N: its mass's weight and its force
    /// (given in the measurement frame).
    fn tip_force_n(&self, i: usize, values: &Values) -> Vector3<f64> {
        let Some(e) = self.data.experiments.get(i) else {
            return Vector3::zeros();
        };
        Vector3::from(self.scene.gravity_m_s2) * e.tip_mass_kg
            + values.pose.vector_to_scene(&Vector3::from(e.tip_force_n))
    }

    /// The observed points of experiments `which`, in their order, predicted in the measurement
    /// frame, m. `Ok(Err(..))` when a solve has no answer at these values; `Err` for input the
    /// model refuses.
    pub fn predict(
        &mut self,
        values: &Values,
        which: &[usize],
    ) -> Result<Result<Vec<Vector3<f64>>, NoAnswer>, SceneError> {
        let physical = values.physical_key();
        let keys: Vec<(usize, [f64; 7])> = which
            .iter()
            .map(|&i| {
                let f = self.tip_force_n(i, values);
                (
                    i,
                    [
                        physical[0],
                        physical[1],
                        physical[2],
                        physical[3],
                        f.x,
                        f.y,
                        f.z,
                    ],
                )
            })
            .collect();
        let stale: Vec<(usize, [f64; 7])> = keys
            .iter()
            .filter(|(i, key)| !matches!(self.cache.get(*i), Some(Some(c)) if same(&c.key, key)))
            .copied()
            .collect();
        if !stale.is_empty() {
            let scene = values.apply(self.scene);
            let pass = Pass {
                scene: &scene,
                data: self.data,
                settings: &self.settings,
                scene_actuation: self.scene_actuation.as_ref(),
                cache: &mut self.cache,
                stale: &stale,
                solves: &mut self.solves,
            };
            if let Err(no) = with_model(&scene, pass)? {
                return Ok(Err(no));
            }
        }
        let mut out = Vec::new();
        for &i in which {
            let Some(Some(c)) = self.cache.get(i) else {
                return Err(SceneError::new(
                    format!("experiment {i}"),
                    "not in the data (no solve of it)",
                ));
            };
            out.extend(c.points_m.iter().map(|p| values.pose.to_measurement(p)));
        }
        Ok(Ok(out))
    }
}

/// Bitwise-equal keys (NaN for "no friction fitted" equals itself here).
fn same(a: &[f64; 7], b: &[f64; 7]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// One pass of solves on one model: the experiments whose inputs changed.
struct Pass<'p> {
    scene: &'p Scene,
    data: &'p Measurements,
    settings: &'p ShootingSettings<f64>,
    scene_actuation: Option<&'p ExperimentActuation>,
    cache: &'p mut Vec<Option<Cached>>,
    stale: &'p [(usize, [f64; 7])],
    solves: &'p mut u64,
}

/// The sorted, distinct arc lengths of a list, and where each of the list's falls in it.
fn sorted_queries(s_m: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut sorted = s_m.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let index = s_m
        .iter()
        .map(|s| sorted.partition_point(|x| x < s))
        .collect();
    (sorted, index)
}

impl WithModel for Pass<'_> {
    type Output = Result<(), NoAnswer>;

    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<Self::Output, SceneError> {
        let tendons = self.scene.tendon_set(model)?;
        let mut previous: Option<Warm> = None;
        for &(i, key) in self.stale {
            let Some(e) = self.data.experiments.get(i) else {
                continue;
            };
            let name = format!(
                "experiment \"{}\" ({}, line {})",
                e.id, self.data.origin, e.line
            );
            let load = TipLoad {
                force_n: Vector3::new(key[4], key[5], key[6]),
                moment_nm: Vector3::zeros(),
            };
            let own = self
                .cache
                .get(i)
                .and_then(|c| c.as_ref())
                .map(|c| c.warm.clone());
            let start = own.or_else(|| previous.clone());
            let s_m: Vec<f64> = e.observations.iter().map(|o| o.s_m).collect();
            let (queries, index) = sorted_queries(&s_m);
            let mut shape = vec![ShapePoint::default(); queries.len()];
            let refused = |err: model_core::ModelError| SceneError::new(&name, err.to_string());
            let (warm, written) = match &tendons {
                None => {
                    let warm_strain = match &start {
                        Some(Warm::DeadLoad(u)) => Some(*u),
                        _ => None,
                    };
                    let Some(eq) = dead_load(model, &load, warm_strain, self.settings, self.solves)
                        .map_err(refused)?
                    else {
                        return Ok(Err(NoAnswer {
                            experiment: name,
                            why: "the forward solve did not converge to a stable equilibrium"
                                .into(),
                        }));
                    };
                    let written = model.shape(&eq, &queries, &mut shape).map_err(refused)?;
                    (Warm::DeadLoad(eq.base_strain_per_m), written)
                }
                Some(set) => {
                    let Some(actuation) = e.actuation.as_ref().or(self.scene_actuation) else {
                        return Err(SceneError::new(&name, "no actuation for the tendons"));
                    };
                    let warm_eq = match &start {
                        Some(Warm::Tendons(eq)) => Some(eq.as_ref()),
                        _ => None,
                    };
                    let solved = tendon_solve(
                        model,
                        set,
                        actuation,
                        &load,
                        warm_eq,
                        self.settings,
                        self.solves,
                    )
                    .map_err(refused)?;
                    let Some(solved) = solved else {
                        return Ok(Err(NoAnswer {
                            experiment: name,
                            why: "the tendon solve did not converge".into(),
                        }));
                    };
                    let written = model
                        .shape_tendons(set, &solved, &queries, &mut shape)
                        .map_err(refused)?;
                    (Warm::Tendons(Box::new(solved)), written)
                }
            };
            shape.truncate(written);
            let points_m = index
                .iter()
                .map(|&k| shape.get(k).map(|p| p.position_m))
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| SceneError::new(&name, "the shape sweep stopped short"))?;
            previous = Some(warm.clone());
            if let Some(slot) = self.cache.get_mut(i) {
                *slot = Some(Cached {
                    key,
                    points_m,
                    warm,
                });
            }
        }
        Ok(Ok(()))
    }
}

/// A dead-load equilibrium under `load`, warm from `warm` when given (cold again if that fails);
/// `None` when neither converges to an acceptable equilibrium.
fn dead_load<A: Attitude<f64>>(
    model: &Model<f64, A>,
    load: &TipLoad<f64>,
    warm: Option<Vector3<f64>>,
    settings: &ShootingSettings<f64>,
    solves: &mut u64,
) -> Result<Option<model_core::Equilibrium<f64>>, model_core::ModelError> {
    let ok = |eq: &model_core::Equilibrium<f64>| {
        eq.report.termination.is_success() && eq.report.stability.is_acceptable()
    };
    *solves += 1;
    let eq = model.solve(load, warm.map_or(Start::Cold, Start::Warm), settings)?;
    if ok(&eq) {
        return Ok(Some(eq));
    }
    if warm.is_none() {
        return Ok(None);
    }
    *solves += 1;
    let eq = model.solve(load, Start::Cold, settings)?;
    Ok(ok(&eq).then_some(eq))
}

/// A tendon equilibrium under `actuation` and `load`, warm from `warm` when given (cold again if
/// that fails); `None` when neither converges.
fn tendon_solve<A: Attitude<f64>>(
    model: &Model<f64, A>,
    tendons: &Tendons<f64>,
    actuation: &ExperimentActuation,
    load: &TipLoad<f64>,
    warm: Option<&TendonEquilibrium<f64>>,
    settings: &ShootingSettings<f64>,
    solves: &mut u64,
) -> Result<Option<TendonEquilibrium<f64>>, model_core::ModelError> {
    let attempt = |start: Option<&TendonEquilibrium<f64>>| match actuation.control {
        Control::Tensions => {
            let eq = model.solve_tendons(tendons, &actuation.values, load, start, settings)?;
            Ok(eq
                .equilibrium
                .report
                .stability
                .is_acceptable()
                .then_some(eq)
                .filter(TendonEquilibrium::is_success))
        }
        Control::Displacements => {
            let d = model.solve_displacements(
                tendons,
                &actuation.values,
                load,
                start,
                settings,
                &DisplacementSettings::default(),
            )?;
            Ok(d.is_success().then_some(d.solved))
        }
    };
    *solves += 1;
    if let Some(eq) = attempt(warm)? {
        return Ok(Some(eq));
    }
    if warm.is_none() {
        return Ok(None);
    }
    *solves += 1;
    attempt(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_are_sorted_and_indexed() {
        let (sorted, index) = sorted_queries(&[0.3, 0.1, 0.3, 0.2]);
        assert_eq!(sorted, vec![0.1, 0.2, 0.3]);
        assert_eq!(index, vec![2, 0, 2, 1]);
    }
}
