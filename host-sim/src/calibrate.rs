//! Calibration: a least-squares fit of Young's modulus (and optionally a scale on the line density) to
//! a table of hung masses and observed tips, with leave-one-out errors, so a new rod can be calibrated
//! from a few hung masses.
//!
//! Gauss-Newton on `log E` (and `log density scale`) with a forward-difference Jacobian; each residual
//! evaluation solves every row (warm-started along the table). The standard deviation of the fit comes
//! from the residual variance and the Jacobian at the optimum.
//!
//! This file fits the thesis's tables (`host-sim calibrate --table`). The submodules fit a scene to
//! the user's own measurements (`host-sim calibrate <scene.toml> --data <measurements.csv>`): the
//! data format ([`data`]), the fitted parameters ([`params`], [`pose`]), the forward model
//! ([`forward`]), Levenberg-Marquardt ([`lm`]), the uncertainty and what the data do not determine
//! ([`uncertainty`]), the fit with its residuals and leave-one-out ([`fit`]), the calibrated scene
//! ([`write`]), the report ([`text`]) and the command ([`command`]).

pub mod command;
pub mod data;
pub mod figure;
pub mod fit;
pub mod forward;
pub mod lm;
pub mod params;
pub mod pose;
pub mod text;
pub mod uncertainty;
pub mod write;

use model_checks::reference::{self, csv_rows};
use model_core::{Model, PointLoad, Rod, ShapePoint, Start, TipLoad};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::scene::{Scene, SceneError};
use crate::scenes;
use crate::thesis::{CM_PER_M, KG_PER_G};

/// Which table to fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dataset {
    /// Table 4.1: two sections, mass at the transition, both section tips observed.
    Table41,
    /// Table 4.3: guides (average mass), mass at the tip.
    Table43,
}

/// One row: a hung mass and the observed points (cm) at the given arc lengths (m).
#[derive(Debug, Clone, PartialEq)]
struct Row {
    mass_g: f64,
    s_m: Vec<f64>,
    observed_cm: Vec<(f64, f64)>,
}

/// Most Gauss-Newton iterations of a fit.
const MAX_ITERATIONS: usize = 30;

/// How a fit ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Verdict {
    /// Converged: the last step was negligible (below 1e-10 in the log-parameters), or the
    /// Gauss-Newton step at the last iterate predicts a decrease of the sum of squares below 1e-10
    /// of it (a stationary point: also when no step lowered it, or out of iterations). Otherwise
    /// the fitted values are where the fit stopped, not a minimum.
    pub converged: bool,
    /// Gauss-Newton iterations.
    pub iterations: usize,
}

impl Verdict {
    /// Nothing when converged, else " (not converged after N iterations)": what a report appends to
    /// a value fitted so.
    pub fn note(&self) -> String {
        if self.converged {
            String::new()
        } else {
            let plural = if self.iterations == 1 { "" } else { "s" };
            format!(
                " (not converged after {} iteration{plural})",
                self.iterations
            )
        }
    }
}

/// A least-squares fit: log-parameters, the Jacobian at the optimum and the residuals there.
struct Fit {
    theta: Vec<f64>,
    jacobian: DMatrix<f64>,
    residuals: DVector<f64>,
    verdict: Verdict,
}

/// The data and the scene it is fitted on.
struct Problem {
    scene: Scene,
    rod: Rod<f64>,
    /// Where the mass hangs, m (None: at the tip, as a tip force).
    load_at_m: Option<f64>,
    rows: Vec<Row>,
}

impl Problem {
    fn new(dataset: Dataset) -> Result<Self, SceneError> {
        let table = |e: model_core::ModelError| SceneError::new("thesis table", e.to_string());
        match dataset {
            Dataset::Table41 => {
                let scene = scenes::exp1()?;
                let rod = scene.rod()?;
                let transition = scene.sections.first().map_or(0.0, |s| s.length_m);
                let length = rod.length_m();
                let rows = csv_rows::<9>(reference::TABLE_4_1_CSV)
                    .map(|r| {
                        r.map(|r| Row {
                            mass_g: r[0],
                            s_m: vec![transition, length],
                            observed_cm: vec![(r[1], r[2]), (r[3], r[4])],
                        })
                    })
                    .collect::<Result<_, _>>()
                    .map_err(table)?;
                Ok(Self {
                    scene,
                    rod,
                    load_at_m: Some(transition),
                    rows,
                })
            }
            Dataset::Table43 => {
                let scene = scenes::exp2_average()?;
                let rod = scene.rod()?;
                let length = rod.length_m();
                let rows = csv_rows::<5>(reference::TABLE_4_3_CSV)
                    .map(|r| {
                        r.map(|r| Row {
                            mass_g: r[0],
                            s_m: vec![length],
                            observed_cm: vec![(r[1], r[2])],
                        })
                    })
                    .collect::<Result<_, _>>()
                    .map_err(table)?;
                Ok(Self {
                    scene,
                    rod,
                    load_at_m: None,
                    rows,
                })
            }
        }
    }

    /// The rod with every section's stiffness scaled by `e_scale` and line density by `rho_scale`.
    fn scaled_rod(&self, e_scale: f64, rho_scale: f64) -> Rod<f64> {
        let mut rod = self.rod.clone();
        for s in rod.sections.iter_mut() {
            s.stiffness.bending_torsion_nm2 *= e_scale;
            s.stiffness.shear_axial_n *= e_scale;
            s.line_density_kg_per_m *= rho_scale;
        }
        rod
    }

    /// Predicted points (cm) for the given rows, or an error naming the row that did not converge.
    fn predict(
        &self,
        e_scale: f64,
        rho_scale: f64,
        rows: &[usize],
    ) -> Result<Vec<(f64, f64)>, SceneError> {
        let base = self.scaled_rod(e_scale, rho_scale);
        let settings = self.scene.shooting_settings()?;
        let gravity = Vector3::from(self.scene.gravity_m_s2);
        let mut out = Vec::new();
        let shared =
            Model::<f64>::new(base.clone()).map_err(|e| SceneError::new("scene", e.to_string()))?;
        for &i in rows {
            let Some(row) = self.rows.get(i) else {
                continue;
            };
            let mass_kg = row.mass_g * KG_PER_G;
            let (model, load) = match self.load_at_m {
                Some(s) => {
                    let mut rod = base.clone();
                    rod.loads.clear();
                    rod.push_load(PointLoad::mass(s, mass_kg))
                        .map_err(|e| SceneError::new("load", e.to_string()))?;
                    (
                        Model::<f64>::new(rod)
                            .map_err(|e| SceneError::new("scene", e.to_string()))?,
                        TipLoad::zero(),
                    )
                }
                None => (shared.clone(), TipLoad::force(gravity * mass_kg)),
            };
            let eq = model
                .solve(&load, Start::Cold, &settings)
                .map_err(|e| SceneError::new("tip", e.to_string()))?;
            if !eq.report.termination.is_success() {
                return Err(SceneError::new(
                    format!("row {} g", row.mass_g),
                    format!("did not converge ({:?})", eq.report.termination),
                ));
            }
            let blank = ShapePoint::default();
            let mut points = vec![blank; row.s_m.len()];
            model
                .shape(&eq, &row.s_m, &mut points)
                .map_err(|e| SceneError::new("output", e.to_string()))?;
            out.extend(
                points
                    .iter()
                    .map(|p| (p.position_m.x * CM_PER_M, p.position_m.y * CM_PER_M)),
            );
        }
        Ok(out)
    }

    fn observed(&self, rows: &[usize]) -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|&i| self.rows.get(i))
            .flat_map(|r| r.observed_cm.iter().copied())
            .collect()
    }

    /// Residuals (cm, x and y interleaved) at log-parameters `theta`.
    fn residuals(
        &self,
        theta: &[f64],
        fit_density: bool,
        rows: &[usize],
    ) -> Result<DVector<f64>, SceneError> {
        let e_scale = theta.first().copied().unwrap_or(0.0).exp();
        let rho_scale = if fit_density {
            theta.get(1).copied().unwrap_or(0.0).exp()
        } else {
            1.0
        };
        let predicted = self.predict(e_scale, rho_scale, rows)?;
        let observed = self.observed(rows);
        Ok(DVector::from_iterator(
            predicted.len() * 2,
            predicted
                .iter()
                .zip(&observed)
                .flat_map(|(p, o)| [p.0 - o.0, p.1 - o.1]),
        ))
    }

    /// Gauss-Newton on the log-parameters over `rows`: the parameters, the Jacobian at the optimum,
    /// the residuals there and the verdict.
    fn fit(&self, fit_density: bool, rows: &[usize]) -> Result<Fit, SceneError> {
        self.fit_at_most(fit_density, rows, MAX_ITERATIONS)
    }

    /// [`Problem::fit`] with at most `max_iterations`.
    fn fit_at_most(
        &self,
        fit_density: bool,
        rows: &[usize],
        max_iterations: usize,
    ) -> Result<Fit, SceneError> {
        let n = if fit_density { 2 } else { 1 };
        let mut theta = vec![0.0; n];
        let mut r = self.residuals(&theta, fit_density, rows)?;
        let mut jacobian = DMatrix::zeros(r.len(), n);
        let mut verdict = Verdict {
            converged: false,
            iterations: 0,
        };
        for iteration in 1..=max_iterations {
            verdict.iterations = iteration;
            for k in 0..n {
                let mut t = theta.clone();
                let h = 1e-5;
                if let Some(v) = t.get_mut(k) {
                    *v += h;
                }
                let rk = self.residuals(&t, fit_density, rows)?;
                jacobian.set_column(k, &((rk - &r) / h));
            }
            let jtj = jacobian.tr_mul(&jacobian);
            let step = jtj
                .clone()
                .cholesky()
                .map(|c| c.solve(&(-jacobian.tr_mul(&r))))
                .ok_or_else(|| {
                    SceneError::new("calibration", "the data do not determine the parameters")
                })?;
            // Stationary: the linearisation predicts a negligible decrease for the full step.
            verdict.converged = (&jacobian * &step).norm_squared() <= 1e-10 * r.norm_squared();
            // Halve the step until the sum of squares decreases.
            let mut scale = 1.0;
            let mut accepted = false;
            for _ in 0..20 {
                let trial: Vec<f64> = theta
                    .iter()
                    .zip(step.iter())
                    .map(|(t, s)| t + scale * s)
                    .collect();
                if let Ok(rt) = self.residuals(&trial, fit_density, rows)
                    && rt.norm_squared() <= r.norm_squared()
                {
                    theta = trial;
                    r = rt;
                    accepted = true;
                    break;
                }
                scale *= 0.5;
            }
            if !accepted || step.norm() * scale < 1e-10 {
                // (A step made tiny by halving is no minimum: only a full step that small.)
                verdict.converged |= accepted && step.norm() < 1e-10;
                break;
            }
        }
        Ok(Fit {
            theta,
            jacobian,
            residuals: r,
            verdict,
        })
    }
}

/// A leave-one-out fold.
#[derive(Debug, Clone, PartialEq)]
pub struct LooRow {
    /// The row left out, g.
    pub mass_g: f64,
    /// Young's modulus fitted without it, Pa.
    pub youngs_modulus_pa: f64,
    /// Error of the prediction for the left-out row (rms over its points), cm.
    pub error_cm: f64,
    /// How the fit without it ended.
    pub verdict: Verdict,
}

/// A calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Which table.
    pub dataset: Dataset,
    /// The scene's Young's modulus (of its first section), Pa.
    pub start_youngs_modulus_pa: f64,
    /// Fitted Young's modulus, Pa.
    pub youngs_modulus_pa: f64,
    /// How the fit ended: a value not converged is where the fit stopped, not a minimum.
    pub verdict: Verdict,
    /// Its standard deviation, Pa.
    pub youngs_std_pa: f64,
    /// Fitted line-density scale and its standard deviation, when fitted.
    pub density_scale: Option<(f64, f64)>,
    /// Rms error of the fit over all points, cm.
    pub rms_cm: f64,
    /// Rms error at the scene's own parameters, cm.
    pub start_rms_cm: f64,
    /// Leave-one-out folds.
    pub loo: Vec<LooRow>,
    /// Rms leave-one-out error, cm.
    pub loo_rms_cm: f64,
}

/// Fits Young's modulus (and the density scale when `fit_density`) to a table. `progress` is called
/// once per completed fit (1 + one per row).
pub fn calibrate(
    dataset: Dataset,
    fit_density: bool,
    mut progress: impl FnMut(),
) -> Result<Calibration, SceneError> {
    let problem = Problem::new(dataset)?;
    let e0 = problem
        .scene
        .sections
        .first()
        .and_then(|s| s.material.as_ref())
        .map(|m| m.youngs_modulus_pa)
        .ok_or_else(|| {
            SceneError::new(
                "section[0].material",
                "calibration fits Young's modulus: give a material",
            )
        })?;
    let all: Vec<usize> = (0..problem.rows.len()).collect();
    let points = |r: &DVector<f64>| (r.norm_squared() / (r.len() as f64 / 2.0)).sqrt();
    let start_rms_cm = points(&problem.residuals(&[0.0, 0.0], fit_density, &all)?);
    let Fit {
        theta,
        jacobian,
        residuals: r,
        verdict,
    } = problem.fit(fit_density, &all)?;
    progress();
    let dof = (r.len() as f64 - theta.len() as f64).max(1.0);
    let variance = r.norm_squared() / dof;
    let covariance = jacobian
        .tr_mul(&jacobian)
        .try_inverse()
        .map(|c| c * variance)
        .ok_or_else(|| SceneError::new("calibration", "singular normal matrix"))?;
    let e_scale = theta.first().copied().unwrap_or(0.0).exp();
    let std_log_e = covariance
        .get((0, 0))
        .copied()
        .unwrap_or(f64::NAN)
        .max(0.0)
        .sqrt();
    let density_scale = fit_density.then(|| {
        let log_rho = theta.get(1).copied().unwrap_or(0.0);
        let std = covariance
            .get((1, 1))
            .copied()
            .unwrap_or(f64::NAN)
            .max(0.0)
            .sqrt();
        (log_rho.exp(), log_rho.exp() * std)
    });
    let mut loo = Vec::new();
    for &left_out in &all {
        let rest: Vec<usize> = all.iter().copied().filter(|&i| i != left_out).collect();
        let fold = problem.fit(fit_density, &rest)?;
        let theta_k = fold.theta;
        let r_k = problem.residuals(&theta_k, fit_density, &[left_out])?;
        loo.push(LooRow {
            mass_g: problem.rows.get(left_out).map_or(f64::NAN, |r| r.mass_g),
            youngs_modulus_pa: e0 * theta_k.first().copied().unwrap_or(0.0).exp(),
            error_cm: points(&r_k),
            verdict: fold.verdict,
        });
        progress();
    }
    let loo_rms_cm =
        (loo.iter().map(|l| l.error_cm * l.error_cm).sum::<f64>() / loo.len() as f64).sqrt();
    Ok(Calibration {
        dataset,
        start_youngs_modulus_pa: e0,
        youngs_modulus_pa: e0 * e_scale,
        verdict,
        youngs_std_pa: e0 * e_scale * std_log_e,
        density_scale,
        rms_cm: points(&r),
        start_rms_cm,
        loo,
        loo_rms_cm,
    })
}

/// How many fits [`calibrate`] runs (for a progress bar).
pub fn fit_count(dataset: Dataset) -> Result<u64, SceneError> {
    Ok(Problem::new(dataset)?.rows.len() as u64 + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fit_cut_short_says_it_did_not_converge() {
        let problem = Problem::new(Dataset::Table43).expect("table 4.3");
        let all: Vec<usize> = (0..problem.rows.len()).collect();
        let fit = problem.fit(false, &all).expect("fit");
        assert!(fit.verdict.converged, "{:?}", fit.verdict);
        assert_eq!(fit.verdict.note(), "");
        // One iteration from the scene's E moves it by 1.6 %: no minimum yet.
        let short = problem.fit_at_most(false, &all, 1).expect("fit");
        assert_eq!(
            short.verdict,
            Verdict {
                converged: false,
                iterations: 1
            }
        );
        assert_eq!(short.verdict.note(), " (not converged after 1 iteration)");
    }
}
