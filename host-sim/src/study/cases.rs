//! The scenes of the study: the thesis's experiment-2 bench with a hung mass (in-plane, gravity,
//! accurate guide mass, three cables) and the golden 3D bench under its rows' tip forces.

use model_checks::reference::{self, Exp2Mass};
use model_core::planar::PlanarModel;
use model_core::{Model, Rod, Scalar, StrainModel, TipLoad};
use nalgebra::Vector3;

use host_sim::scene::SceneError;

/// Which bench a scene is built on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bench {
    /// `reference::exp2_bench` with this guide-mass model and three cables.
    Exp2(Exp2Mass),
    /// `reference::golden_bench` (experiment 2, average mass, three cables).
    Golden,
}

/// One scene: a bench and one or more tip loads (its cases).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Short key (CSV, command line).
    pub key: String,
    /// What it is, for the report.
    pub title: String,
    /// The bench.
    pub bench: Bench,
    /// Tip force of each case, N, global frame.
    pub forces_n: Vec<[f64; 3]>,
    /// A label per case.
    pub case_labels: Vec<String>,
}

/// The thesis's tip masses in the study, g.
pub const EXP2_MASSES_G: [f64; 2] = [40.2, 83.2];

fn model_error(what: &str) -> impl Fn(model_core::ModelError) -> SceneError + '_ {
    move |e| SceneError::new(what, e.to_string())
}

impl Scene {
    /// Experiment 2 (accurate guide mass, three cables) with `mass_g` hung at the tip.
    pub fn exp2(mass_g: f64) -> Self {
        Self {
            key: format!("exp2-{mass_g}g"),
            title: format!(
                "thesis exp. 2, accurate guide mass, {mass_g} g at the tip (in-plane, gravity)"
            ),
            bench: Bench::Exp2(Exp2Mass::Accurate),
            forces_n: vec![[0.0, -reference::GRAVITY_M_S2 * mass_g * 1e-3, 0.0]],
            case_labels: vec![format!("{mass_g} g")],
        }
    }

    /// The golden 3D bench under every golden row's tip force.
    pub fn golden() -> Result<Self, SceneError> {
        let mut forces_n = Vec::new();
        let mut case_labels = Vec::new();
        for (i, row) in reference::golden_rows().enumerate() {
            let row = row.map_err(model_error("golden rows"))?;
            forces_n.push(row.force_n);
            let [x, y, z] = row.force_n;
            case_labels.push(format!("row {i}: F = ({x}, {y}, {z}) N"));
        }
        Ok(Self {
            key: "golden".into(),
            title: format!(
                "golden 3D bench (exp. 2, average mass, three cables), its {} rows' tip forces",
                forces_n.len()
            ),
            bench: Bench::Golden,
            forces_n,
            case_labels,
        })
    }

    /// The scenes of the study.
    pub fn all() -> Result<Vec<Self>, SceneError> {
        let mut scenes: Vec<Self> = EXP2_MASSES_G.iter().map(|&m| Self::exp2(m)).collect();
        scenes.push(Self::golden()?);
        Ok(scenes)
    }

    /// The same scene with only case `case`.
    pub fn only(&self, case: usize) -> Result<Self, SceneError> {
        let missing = || SceneError::new(&self.key, format!("no case {case}"));
        Ok(Self {
            key: self.key.clone(),
            title: self.title.clone(),
            bench: self.bench,
            forces_n: vec![*self.forces_n.get(case).ok_or_else(missing)?],
            case_labels: vec![self.case_labels.get(case).ok_or_else(missing)?.clone()],
        })
    }

    /// The same scene on another bench (for the mass-bookkeeping comparison).
    pub fn on_bench(&self, bench: Bench) -> Self {
        Self {
            bench,
            ..self.clone()
        }
    }

    /// The rod at `steps` per section, Kirchhoff or Cosserat.
    pub fn rod<T: Scalar>(&self, steps: u16, kirchhoff: bool) -> Result<Rod<T>, SceneError> {
        let mut rod = match self.bench {
            Bench::Exp2(mass) => reference::exp2_bench(mass, steps, 3),
            Bench::Golden => reference::golden_bench(steps),
        }
        .map_err(model_error("bench"))?;
        if kirchhoff {
            rod.strain_model = StrainModel::Kirchhoff;
        }
        Ok(rod)
    }

    /// The tip load of case `case`.
    pub fn load<T: Scalar>(&self, case: usize) -> Result<TipLoad<T>, SceneError> {
        let f = self
            .forces_n
            .get(case)
            .ok_or_else(|| SceneError::new(&self.key, format!("no case {case}")))?;
        Ok(TipLoad::force(Vector3::new(
            T::lit(f[0]),
            T::lit(f[1]),
            T::lit(f[2]),
        )))
    }

    /// Every case's tip load.
    pub fn loads<T: Scalar>(&self) -> Result<Vec<TipLoad<T>>, SceneError> {
        (0..self.forces_n.len()).map(|c| self.load(c)).collect()
    }

    /// Whether every case stays in a plane (the planar reduction applies).
    pub fn planar(&self) -> Result<bool, SceneError> {
        let model = Model::<f64>::new(self.rod(10, false)?).map_err(model_error("planar probe"))?;
        Ok(self
            .loads::<f64>()?
            .iter()
            .all(|load| PlanarModel::new(&model, load).is_some()))
    }
}
