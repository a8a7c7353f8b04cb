//! What the data determine: the covariance of the fitted coordinates and the combinations they
//! leave free.
//!
//! At the optimum the weighted Jacobian `J` (rows `sqrt(w)` times the residual's derivatives) and
//! the residual variance `s^2 = sum w r^2 / (m - n)` (`m` residuals, `n` coordinates) give the
//! covariance `s^2 (J^T W J)^-1` of the coordinates, taken through the SVD of `J` with its columns
//! scaled to unit length. A singular value below [`RANK_TOLERANCE`] times the largest is a
//! combination the data do not determine at all (the points do not change along it, to the
//! resolution of the finite differences and the forward solves): the Jacobian is rank-deficient,
//! the combination is named, and no coordinate in it gets a number. A coordinate whose standard
//! deviation exceeds its own limit ([`super::params::Coordinate::undetermined_above`]) is not
//! determined either, and the weakest combination is named with it.

use nalgebra::{DMatrix, DVector};

use super::lm::column_scales;
use super::params::Layout;

/// Singular values of the column-scaled Jacobian below this fraction of the largest span the
/// combinations the data do not determine. The Jacobian's columns are central differences of
/// forward solves converged to about 1e-13 of the rod's length, over steps of 1e-4 (log scale):
/// their rounding leaves an exactly free combination at most about 1e-9 of the largest singular
/// value (E and the line density scaled together under the rod's weight alone: 2e-14), while a
/// combination the points resolve at all stands far above 1e-6.
pub const RANK_TOLERANCE: f64 = 1e-6;

/// A coefficient below this fraction of the largest leaves a coordinate out of a combination.
const TERM_TOLERANCE: f64 = 0.05;

/// One term of a combination: a coefficient on a coordinate (`ln E`, `friction`).
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    /// The coordinate's index.
    pub index: usize,
    /// Its coefficient (the largest in the combination is 1 in size).
    pub coefficient: f64,
}

/// A direction in the coordinates that the data do not determine.
#[derive(Debug, Clone, PartialEq)]
pub struct Combination {
    /// Its terms, largest first.
    pub terms: Vec<Term>,
    /// Its singular value over the largest (below [`RANK_TOLERANCE`]: rank-deficient).
    pub singular_ratio: f64,
    /// Rank-deficient (true) or only too uncertain (false).
    pub rank_deficient: bool,
}

/// The covariance and the verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Uncertainty {
    /// Each coordinate's standard deviation; `None` when the data do not determine it.
    pub theta_std: Vec<Option<f64>>,
    /// The combinations the data do not determine (empty when every coordinate is determined).
    pub undetermined: Vec<Combination>,
    /// Residuals minus coordinates.
    pub dof: usize,
    /// The residual standard deviation `s` (weighted residual units, m); `None` without a spare
    /// residual.
    pub residual_sd: Option<f64>,
}

impl Uncertainty {
    /// Whether every coordinate is determined.
    pub fn is_determined(&self) -> bool {
        self.undetermined.is_empty() && self.theta_std.iter().all(Option::is_some)
    }
}

/// The terms of the direction `v` (in scaled coordinates) in the coordinates themselves.
fn terms(v: &DVector<f64>, scales: &DVector<f64>) -> Vec<Term> {
    let c = v.component_div(scales);
    let largest = c.amax();
    let mut out: Vec<Term> = c
        .iter()
        .enumerate()
        .filter(|(_, x)| largest > 0.0 && x.abs() >= TERM_TOLERANCE * largest)
        .map(|(index, x)| Term {
            index,
            coefficient: x / largest,
        })
        .collect();
    // The sign: the first term positive.
    if out.first().is_some_and(|t| t.coefficient < 0.0) {
        for t in &mut out {
            t.coefficient = -t.coefficient;
        }
    }
    out.sort_by(|a, b| b.coefficient.abs().total_cmp(&a.coefficient.abs()));
    out
}

/// The uncertainty of the fit with weighted Jacobian `j` and weighted residuals `r`.
pub fn analyse(j: &DMatrix<f64>, r: &DVector<f64>, layout: &Layout) -> Uncertainty {
    let (m, n) = (j.nrows(), j.ncols());
    let dof = m.saturating_sub(n);
    let residual_sd = (dof > 0).then(|| (r.norm_squared() / dof as f64).sqrt());
    let scales = column_scales(j);
    let scaled = DMatrix::from_fn(m, n, |i, k| {
        j[(i, k)] / scales.get(k).copied().unwrap_or(1.0)
    });
    let svd = scaled.svd(false, true);
    let Some(v_t) = svd.v_t.as_ref() else {
        return Uncertainty {
            theta_std: vec![None; n],
            undetermined: Vec::new(),
            dof,
            residual_sd,
        };
    };
    let sigma = &svd.singular_values;
    let sigma_max = sigma.max();
    let mut undetermined = Vec::new();
    let mut free = vec![false; n];
    let mut covariance = DMatrix::<f64>::zeros(n, n);
    let mut weakest: Option<(f64, DVector<f64>)> = None;
    for (i, s) in sigma.iter().enumerate() {
        let v: DVector<f64> = v_t.row(i).transpose();
        let ratio = if sigma_max > 0.0 { s / sigma_max } else { 0.0 };
        if ratio.is_nan() || ratio <= RANK_TOLERANCE {
            let t = terms(&v, &scales);
            for term in &t {
                if let Some(f) = free.get_mut(term.index) {
                    *f = true;
                }
            }
            undetermined.push(Combination {
                terms: t,
                singular_ratio: ratio,
                rank_deficient: true,
            });
            continue;
        }
        covariance += &v * v.transpose() / (s * s);
        if weakest.as_ref().is_none_or(|(w, _)| ratio < *w) {
            weakest = Some((ratio, v));
        }
    }
    let theta_std: Vec<Option<f64>> = (0..n)
        .map(|k| {
            let scale = scales.get(k).copied().unwrap_or(1.0);
            let limit = layout
                .coordinates
                .get(k)
                .map_or(f64::INFINITY, |c| c.undetermined_above);
            let sd = residual_sd? * covariance.get((k, k))?.max(0.0).sqrt() / scale;
            (!free.get(k).copied().unwrap_or(true) && sd.is_finite() && sd <= limit).then_some(sd)
        })
        .collect();
    let too_uncertain = theta_std
        .iter()
        .zip(&free)
        .any(|(sd, f)| sd.is_none() && !f && residual_sd.is_some());
    if too_uncertain && let Some((ratio, v)) = weakest {
        undetermined.push(Combination {
            terms: terms(&v, &scales),
            singular_ratio: ratio,
            rank_deficient: false,
        });
    }
    Uncertainty {
        theta_std,
        undetermined,
        dof,
        residual_sd,
    }
}
