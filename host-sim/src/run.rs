//! `solve` and `estimate` on a scene: the forward shape and cable lengths, and the inverse from
//! measured cable lengths. Results are plain data (serialisable to JSON and CSV).

use model_core::inverse::{EstimatorSettings, InverseSettings, InverseStart, LoadBasis, estimate};
use model_core::{
    Attitude, LieGroup, Model, Quaternion, RotationMatrix, ShapePoint, Start, TipLoad,
};
use nalgebra::Vector3;
use serde::Serialize;

use crate::scene::{AttitudeChoice, Scene, SceneError};

/// Work that needs a model of some frame representation.
pub trait WithModel {
    /// What it produces.
    type Output;
    /// Does the work.
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<Self::Output, SceneError>;
}

/// Builds the scene's model with the chosen frame representation and runs `work` on it.
pub fn with_model<W: WithModel>(scene: &Scene, work: W) -> Result<W::Output, SceneError> {
    let rod = scene.rod()?;
    let err = |e: model_core::ModelError| SceneError::new("scene", e.to_string());
    match scene.attitude()? {
        AttitudeChoice::Quaternion => {
            work.run(&Model::<f64, Quaternion<f64>>::new(rod).map_err(err)?)
        }
        AttitudeChoice::RotationMatrix => {
            work.run(&Model::<f64, RotationMatrix<f64>>::new(rod).map_err(err)?)
        }
        AttitudeChoice::LieGroup => work.run(&Model::<f64, LieGroup<f64>>::new(rod).map_err(err)?),
    }
}

/// One backbone point.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Point {
    /// Arc length, m.
    pub s_m: f64,
    /// Position, m.
    pub position_m: [f64; 3],
    /// Unit tangent.
    pub tangent: [f64; 3],
    /// Bending and torsion strain (body frame), 1/m.
    pub strain_per_m: [f64; 3],
}

/// How a solve went.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Report {
    /// Why it stopped ("Converged" is the only usable answer).
    pub termination: String,
    /// Stability verdict.
    pub stability: String,
    /// Iterations.
    pub iterations: u16,
    /// Sweeps.
    pub sweeps: u16,
    /// Final dimensionless residual.
    pub residual: f64,
    /// Load-continuation steps.
    pub load_steps: u16,
}

impl From<&model_core::SolveReport<f64>> for Report {
    fn from(r: &model_core::SolveReport<f64>) -> Self {
        Self {
            termination: format!("{:?}", r.termination),
            stability: format!("{:?}", r.stability),
            iterations: r.iterations,
            sweeps: r.sweeps,
            residual: r.residual,
            load_steps: r.load_steps,
        }
    }
}

/// The result of `solve`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Solution {
    /// Scene name.
    pub scene: String,
    /// Tip force, N.
    pub tip_force_n: [f64; 3],
    /// Tip moment, N m.
    pub tip_moment_nm: [f64; 3],
    /// Solve report.
    pub report: Report,
    /// Tip position, m.
    pub tip_position_m: [f64; 3],
    /// Tip tangent.
    pub tip_tangent: [f64; 3],
    /// Cable lengths, m.
    pub cable_lengths_m: Vec<f64>,
    /// Backbone at the output points.
    pub shape: Vec<Point>,
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn point(p: &ShapePoint<f64>) -> Point {
    Point {
        s_m: p.s_m,
        position_m: arr(&p.position_m),
        tangent: arr(&p.tangent()),
        strain_per_m: arr(&p.strain_per_m),
    }
}

/// `solve`: the scene under its tip load (or `load`).
#[derive(Debug)]
pub struct Solve<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The tip load.
    pub load: TipLoad<f64>,
}

impl WithModel for Solve<'_> {
    type Output = Solution;
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<Solution, SceneError> {
        let settings = self.scene.shooting_settings()?;
        let eq = model
            .solve(&self.load, Start::Cold, &settings)
            .map_err(|e| SceneError::new("tip", e.to_string()))?;
        let s = self.scene.output_points_m(model.length_m())?;
        let mut points = vec![ShapePoint::default(); s.len()];
        model
            .shape(&eq, &s, &mut points)
            .map_err(|e| SceneError::new("output", e.to_string()))?;
        Ok(Solution {
            scene: self.scene.name.clone(),
            tip_force_n: arr(&self.load.force_n),
            tip_moment_nm: arr(&self.load.moment_nm),
            report: Report::from(&eq.report),
            tip_position_m: arr(&eq.tip_position_m),
            tip_tangent: arr(&eq.tip_tangent()),
            cable_lengths_m: eq.cable_lengths_m.iter().copied().collect(),
            shape: points.iter().map(point).collect(),
        })
    }
}

/// The result of `estimate`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EstimateOutput {
    /// Scene name.
    pub scene: String,
    /// Measured cable lengths, m.
    pub measured_m: Vec<f64>,
    /// Estimated tip force, N.
    pub tip_force_n: [f64; 3],
    /// Its standard deviation, N.
    pub tip_force_std_n: [f64; 3],
    /// Tip position, m.
    pub tip_position_m: [f64; 3],
    /// Its standard deviation, m.
    pub tip_position_std_m: [f64; 3],
    /// Model minus measured, m.
    pub cable_residual_m: Vec<f64>,
    /// Singular values of the weighted sensitivity (per N), largest first.
    pub singular_values: [f64; 3],
    /// Their ratio.
    pub condition_number: f64,
    /// The least determined force direction (unit).
    pub weakest_direction: [f64; 3],
    /// "Determined", "Weak", "Undetermined" or "Inconsistent".
    pub determination: String,
    /// Solve report.
    pub report: Report,
    /// Backbone at the output points.
    pub shape: Vec<Point>,
}

/// `estimate`: the tip force from measured cable lengths (m), one per cable.
#[derive(Debug)]
pub struct Estimate<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Measured lengths, m.
    pub measured_m: Vec<f64>,
}

impl Estimate<'_> {
    /// The inverse settings from the scene.
    pub fn settings(scene: &Scene) -> Result<InverseSettings<f64>, SceneError> {
        let e = &scene.estimate;
        if !(e.resolution_m.is_finite() && e.resolution_m > 0.0) {
            return Err(SceneError::new(
                "estimate.resolution_m",
                "must be a positive number",
            ));
        }
        if !(e.max_force_std_n.is_finite() && e.max_force_std_n > 0.0) {
            return Err(SceneError::new(
                "estimate.max_force_std_n",
                "must be a positive number",
            ));
        }
        let shooting = scene.shooting_settings()?;
        Ok(InverseSettings {
            max_force_std_n: e.max_force_std_n,
            tolerance: shooting.tolerance,
            check_stability: shooting.check_stability,
            ..InverseSettings::with_resolution(e.resolution_m)
        })
    }

    /// Settings for a warm-started estimator on this scene.
    pub fn estimator_settings(scene: &Scene) -> Result<EstimatorSettings<f64>, SceneError> {
        Ok(EstimatorSettings::with_inverse(Self::settings(scene)?))
    }
}

impl WithModel for Estimate<'_> {
    type Output = EstimateOutput;
    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<EstimateOutput, SceneError> {
        let settings = Self::settings(self.scene)?;
        let est = estimate(
            model,
            &LoadBasis::tip_force(),
            &self.measured_m,
            InverseStart::Params(Vector3::zeros()),
            &settings,
        )
        .map_err(|e| SceneError::new("--cables", e.to_string()))?;
        let s = self.scene.output_points_m(model.length_m())?;
        let mut points = vec![ShapePoint::default(); s.len()];
        model
            .shape_at(&est.base_strain_per_m, &est.load, &s, &mut points)
            .map_err(|e| SceneError::new("output", e.to_string()))?;
        let q = &est.quality;
        Ok(EstimateOutput {
            scene: self.scene.name.clone(),
            measured_m: self.measured_m.clone(),
            tip_force_n: arr(&est.params),
            tip_force_std_n: arr(&q.force_std_n),
            tip_position_m: arr(&est.tip_position_m),
            tip_position_std_m: arr(&q.tip_std_m),
            cable_residual_m: est
                .cable_residual_m
                .iter()
                .take(self.measured_m.len())
                .copied()
                .collect(),
            singular_values: arr(&q.singular_values),
            condition_number: q.condition_number,
            weakest_direction: arr(&q.weakest_direction),
            determination: format!("{:?}", q.determination),
            report: Report::from(&est.report),
            shape: points.iter().map(point).collect(),
        })
    }
}

/// The shape as CSV: `s_m,x_m,y_m,z_m,tx,ty,tz,ux,uy,uz`.
pub fn shape_csv(shape: &[Point]) -> String {
    let mut out = String::from("s_m,x_m,y_m,z_m,tan_x,tan_y,tan_z,u_x_per_m,u_y_per_m,u_z_per_m\n");
    for p in shape {
        let [x, y, z] = p.position_m;
        let [tx, ty, tz] = p.tangent;
        let [ux, uy, uz] = p.strain_per_m;
        out.push_str(&format!(
            "{},{x},{y},{z},{tx},{ty},{tz},{ux},{uy},{uz}\n",
            p.s_m
        ));
    }
    out
}
