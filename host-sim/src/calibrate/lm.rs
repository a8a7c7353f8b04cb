//! Levenberg-Marquardt on a few parameters, with nalgebra's SVD.
//!
//! The maintained `levenberg-marquardt` crate (0.15) is built on nalgebra 0.34, and its
//! `LeastSquaresProblem` trait takes that version's matrix types; the workspace is on nalgebra
//! 0.35, so the two do not fit together. This is the same method, small: the Jacobian's columns
//! are scaled to unit length (Marquardt's scaling), the damped step is taken through the SVD of the
//! scaled Jacobian (`-sum sigma / (sigma^2 + lambda) (u . r) v`, so a rank-deficient Jacobian gives a
//! finite step), the damping falls by 3 after a step that lowers the cost and rises by 4 after one
//! that does not, or whose forward solve has no answer or whose values the model refuses. A
//! coordinate stays within its bounds; one on a bound that the gradient pushes across it is held
//! there. The Jacobian is central differences (one side at a bound or where the other side has no
//! answer).
//!
//! The outcome is data ([`Termination`]), never a panic.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::scene::SceneError;

/// Why a residual could not be evaluated.
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// Input the model refuses (exit 1).
    Invalid(SceneError),
    /// A forward solve has no answer at these parameters (a step is then rejected; at the start it
    /// ends the fit).
    NoAnswer(String),
}

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Self {
        Self::Invalid(e)
    }
}

/// Weighted residuals as a function of the coordinates.
pub trait Residuals {
    /// The weighted residuals at `theta`.
    fn residuals(&mut self, theta: &DVector<f64>) -> Result<DVector<f64>, Failure>;
}

/// One coordinate's finite-difference step and bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The difference step.
    pub h: f64,
    /// The smallest value the coordinate may take.
    pub lower: Option<f64>,
    /// The largest value the coordinate may take.
    pub upper: Option<f64>,
}

impl Step {
    /// `x` within the bounds.
    fn clamp(&self, x: f64) -> f64 {
        let x = self.lower.map_or(x, |lower| x.max(lower));
        self.upper.map_or(x, |upper| x.min(upper))
    }
}

/// Settings of a fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Most iterations (Jacobians).
    pub max_iterations: u16,
    /// A cost (weighted sum of squares) at or below which the fit has converged: the forward
    /// model's rounding.
    pub cost_floor: f64,
}

/// Why the fit stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Termination {
    /// The cost stopped falling (relative change below 1e-12), the step became negligible, or no
    /// step lowers it any more while the Gauss-Newton prediction says none could: a minimum.
    Converged,
    /// Out of iterations.
    IterationLimit,
    /// No step lowers the cost although the linearisation says one should (a forward solve fails
    /// near the parameters, or the model is not smooth there).
    NoProgress,
}

impl Termination {
    /// Whether the parameters are a minimum.
    pub fn is_success(self) -> bool {
        self == Self::Converged
    }
}

/// A finished fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The coordinates.
    pub theta: DVector<f64>,
    /// The weighted residuals there.
    pub residuals: DVector<f64>,
    /// The Jacobian of the weighted residuals there.
    pub jacobian: DMatrix<f64>,
    /// Why it stopped.
    pub termination: Termination,
    /// Iterations.
    pub iterations: u16,
}

/// The Jacobian of `problem` at `theta` (residuals `r` there) by central differences: one-sided
/// where the other side is beyond a bound, has no answer or is refused.
pub fn jacobian(
    problem: &mut impl Residuals,
    theta: &DVector<f64>,
    r: &DVector<f64>,
    steps: &[Step],
) -> Result<DMatrix<f64>, Failure> {
    let mut j = DMatrix::zeros(r.len(), theta.len());
    for (k, step) in steps.iter().enumerate().take(theta.len()) {
        let shifted = |sign: f64| {
            let mut t = theta.clone();
            if let Some(x) = t.get_mut(k) {
                *x += sign * step.h;
            }
            t
        };
        let x = theta.get(k).copied().unwrap_or(0.0);
        let low_ok = step.lower.is_none_or(|lower| x - step.h >= lower);
        let high_ok = step.upper.is_none_or(|upper| x + step.h <= upper);
        let plus = if high_ok {
            problem.residuals(&shifted(1.0)).ok()
        } else {
            None
        };
        let minus = if low_ok {
            problem.residuals(&shifted(-1.0)).ok()
        } else {
            None
        };
        let column = match (plus, minus) {
            (Some(p), Some(m)) => (p - m) / (2.0 * step.h),
            (Some(p), None) => (p - r) / step.h,
            (None, Some(m)) => (r - m) / step.h,
            (None, None) => {
                return Err(Failure::NoAnswer(format!(
                    "no forward answer on either side of coordinate {k} for its derivative"
                )));
            }
        };
        j.set_column(k, &column);
    }
    Ok(j)
}

/// The column norms of `j` (1 for a zero column, which then does not move).
pub fn column_scales(j: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(
        j.ncols(),
        j.column_iter().map(|c| {
            let n = c.norm();
            if n > 0.0 && n.is_finite() { n } else { 1.0 }
        }),
    )
}

/// The damped step in the coordinates, and the cost the linearisation predicts after it.
fn damped_step(
    svd: &nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
    scales: &DVector<f64>,
    r: &DVector<f64>,
    lambda: f64,
) -> Option<(DVector<f64>, f64)> {
    let u = svd.u.as_ref()?;
    let v_t = svd.v_t.as_ref()?;
    let mut step = DVector::zeros(scales.len());
    let mut explained = 0.0;
    for (i, sigma) in svd.singular_values.iter().enumerate() {
        if sigma.is_nan() || *sigma <= 0.0 {
            continue;
        }
        let ur = u.column(i).dot(r);
        let factor = sigma / (sigma * sigma + lambda);
        step -= v_t.row(i).transpose() * (factor * ur);
        // The linearised residual loses sigma * factor of its component along u_i.
        let kept = 1.0 - sigma * factor;
        explained += ur * ur * (1.0 - kept * kept);
    }
    let predicted = r.norm_squared() - explained;
    Some((step.component_div(scales), predicted))
}

/// Minimises the weighted sum of squares of `problem` from `theta`. Fails when the residuals at
/// the start cannot be evaluated (then `Invalid` is invalid input) or the Jacobian cannot.
pub fn minimize(
    problem: &mut impl Residuals,
    theta: DVector<f64>,
    steps: &[Step],
    settings: &Settings,
) -> Result<Outcome, Failure> {
    let clamp = |mut t: DVector<f64>| {
        for (x, s) in t.iter_mut().zip(steps) {
            *x = s.clamp(*x);
        }
        t
    };
    let mut theta = clamp(theta);
    let mut r = problem.residuals(&theta)?;
    let mut cost = r.norm_squared();
    let mut j = jacobian(problem, &theta, &r, steps)?;
    let mut lambda: Option<f64> = None;
    let mut iterations = 0u16;
    let mut termination = Termination::IterationLimit;
    while iterations < settings.max_iterations {
        iterations += 1;
        if cost <= settings.cost_floor {
            termination = Termination::Converged;
            break;
        }
        let scales = column_scales(&j);
        // A coordinate on its bound that the cost's gradient pushes across it stays there: its
        // column is left out of the step.
        let gradient = j.tr_mul(&r);
        let held: Vec<bool> = steps
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let (Some(x), Some(g)) = (theta.get(k), gradient.get(k)) else {
                    return false;
                };
                s.lower.is_some_and(|lower| *x <= lower && *g > 0.0)
                    || s.upper.is_some_and(|upper| *x >= upper && *g < 0.0)
            })
            .collect();
        let scaled = DMatrix::from_fn(j.nrows(), j.ncols(), |i, k| {
            if held.get(k).copied().unwrap_or(false) {
                0.0
            } else {
                j[(i, k)] / scales.get(k).copied().unwrap_or(1.0)
            }
        });
        let svd = scaled.svd(true, true);
        let sigma_max = svd.singular_values.max();
        if sigma_max.is_nan() || sigma_max <= 0.0 {
            // The residuals do not depend on the coordinates at all.
            termination = Termination::Converged;
            break;
        }
        let mut damping = lambda.unwrap_or(1e-3 * sigma_max * sigma_max);
        let mut accepted = None;
        while damping <= 1e16 * sigma_max * sigma_max {
            let Some((step, _)) = damped_step(&svd, &scales, &r, damping) else {
                break;
            };
            let trial = clamp(&theta + &step);
            // A trial without an answer, or with values the model refuses, is too long a step.
            match problem.residuals(&trial) {
                Ok(rt) if rt.norm_squared() < cost => {
                    accepted = Some((trial, rt, step));
                    break;
                }
                _ => damping *= 4.0,
            }
        }
        let Some((trial, rt, step)) = accepted else {
            // No step lowers the cost: a minimum if Gauss-Newton predicts no useful decrease.
            let gauss_newton = damped_step(&svd, &scales, &r, 0.0).map_or(cost, |(_, p)| p);
            termination = if cost - gauss_newton <= 1e-10 * cost + settings.cost_floor {
                Termination::Converged
            } else {
                Termination::NoProgress
            };
            break;
        };
        let new_cost = rt.norm_squared();
        let small_step = step.component_mul(&scales).norm()
            <= 1e-10 * (1.0 + theta.component_mul(&scales).norm());
        let small_change = cost - new_cost <= 1e-12 * cost;
        theta = trial;
        r = rt;
        cost = new_cost;
        lambda = Some(damping / 3.0);
        j = jacobian(problem, &theta, &r, steps)?;
        if small_step || small_change {
            termination = Termination::Converged;
            break;
        }
    }
    Ok(Outcome {
        theta,
        residuals: r,
        jacobian: j,
        termination,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y = a exp(b x)` at a few points, in log coordinates of `a`.
    struct Exponential {
        x: Vec<f64>,
        y: Vec<f64>,
    }

    impl Residuals for Exponential {
        fn residuals(&mut self, theta: &DVector<f64>) -> Result<DVector<f64>, Failure> {
            let (a, b) = (theta[0].exp(), theta[1]);
            Ok(DVector::from_iterator(
                self.x.len(),
                self.x
                    .iter()
                    .zip(&self.y)
                    .map(|(x, y)| a * (b * x).exp() - y),
            ))
        }
    }

    #[test]
    fn fits_an_exponential_from_far_away() {
        let x: Vec<f64> = (0..8).map(|i| f64::from(i) * 0.25).collect();
        let y = x.iter().map(|x| 2.5 * (-1.3 * x).exp()).collect();
        let mut p = Exponential { x, y };
        let step = Step {
            h: 1e-6,
            lower: None,
            upper: None,
        };
        let out = minimize(
            &mut p,
            DVector::from_vec(vec![0.0, 0.5]),
            &[step, step],
            &Settings {
                max_iterations: 100,
                cost_floor: 1e-28,
            },
        )
        .expect("fits");
        assert_eq!(out.termination, Termination::Converged);
        assert!((out.theta[0].exp() - 2.5).abs() < 1e-9, "{}", out.theta);
        assert!((out.theta[1] + 1.3).abs() < 1e-9, "{}", out.theta);
    }

    #[test]
    fn a_bound_holds() {
        // The minimum is at b = -1.3, below the bound 0: the fit stops on the bound.
        let x: Vec<f64> = (0..8).map(|i| f64::from(i) * 0.25).collect();
        let y = x.iter().map(|x| 2.5 * (-1.3 * x).exp()).collect();
        let mut p = Exponential { x, y };
        let steps = [
            Step {
                h: 1e-6,
                lower: None,
                upper: None,
            },
            Step {
                h: 1e-6,
                lower: Some(0.0),
                upper: Some(10.0),
            },
        ];
        let out = minimize(
            &mut p,
            DVector::from_vec(vec![0.0, 0.5]),
            &steps,
            &Settings {
                max_iterations: 200,
                cost_floor: 0.0,
            },
        )
        .expect("fits");
        assert_eq!(out.termination, Termination::Converged);
        assert_eq!(out.theta[1], 0.0, "{}", out.theta);
    }
}
