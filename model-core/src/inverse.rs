//! The inverse problem: the tip load that explains measured cable lengths (MODEL.md "The inverse problem").
//!
//! Unknowns: the base strain `u(0)` (3) and `P` load parameters `p`, the tip load being
//! `offset + B p` ([`LoadBasis`]: a free tip force, a force of unknown size along a known direction,
//! ...). Residuals: the tip-moment condition `e` (3) and the cable-length mismatch `c(x) - c_meas`.
//!
//! Each iteration takes one sweep with six tangents (base strain and tip force), which gives the
//! blocks `J_eu, J_ep, J_cu, J_cp`. The tip-moment condition is eliminated through `J_eu^-1` (the
//! implicit function theorem: the shape follows the load), leaving the reduced least-squares problem
//! in `p` alone:
//!
//! `c~ = (c - c_meas) - J_cu J_eu^-1 e`, `G = J_cp - J_cu J_eu^-1 J_ep`,
//! `(G^T G / s^2 + mu diag) dp = -G^T c~ / s^2`, `du0 = -J_eu^-1 (e + J_ep dp)`,
//!
//! with `s` the measurement's standard deviation and a trust region on `|du0| L`. `G` is the
//! sensitivity of the cable lengths to the load with the shape re-solved, so the same matrix gives
//! the answer's quality: covariance `s^2 (G^T G)^-1`, singular values and condition number, and the
//! implied force and tip-position uncertainty. Where the data cannot determine the load (an axial
//! force, fewer cables than unknowns, a cable whose length saturates) the estimate says so.
//!
//! [`Estimator`] is the warm-started path for a control loop: it keeps the last answer and its
//! Jacobian, takes quasi-Newton (Broyden) steps with plain sweeps, and refreshes the Jacobian only
//! when a step fails or on a schedule.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::error::{ModelError, finite, finite_vec, positive};
use crate::integrate::{Sweep, Tangents, sweep};
use crate::kinematics::Attitude;
use crate::model::Model;
use crate::plan::MAX_NODES;
use crate::report::{MAX_FRAME_DRIFT, SolveReport, Termination};
use crate::shooting::{ShootingSettings, Start, TipLoad, default_tolerance};
use crate::stability::{Stability, classify};
use crate::{MAX_CABLES, Scalar};

/// Cable-length mismatches and other per-cable vectors, zero beyond the rod's cables.
pub type CableVector<T> = SVector<T, MAX_CABLES>;

/// The number of load parameters an estimate can have (1 to 3). nalgebra's singular value
/// decomposition behind [`Quality`] needs a concrete size, so each is listed here.
pub trait ParamCount<T: Scalar, const P: usize> {
    /// Singular values and right singular vectors (columns of `V`) of a `MAX_CABLES x P` matrix,
    /// `None` if the decomposition does not converge.
    #[cfg(feature = "identifiability")]
    fn svd(m: SMatrix<T, MAX_CABLES, P>) -> Option<(SVector<T, P>, SMatrix<T, P, P>)>;
}

/// The marker implementing [`ParamCount`] for the supported sizes.
#[derive(Clone, Copy, Debug)]
pub struct Params;

macro_rules! param_count {
    ($($p:literal),*) => {$(
        impl<T: Scalar> ParamCount<T, $p> for Params {
            #[cfg(feature = "identifiability")]
            fn svd(m: SMatrix<T, MAX_CABLES, $p>) -> Option<(SVector<T, $p>, SMatrix<T, $p, $p>)> {
                let svd = nalgebra::SVD::try_new(m, false, true, T::default_epsilon(), 200)?;
                Some((svd.singular_values, svd.v_t?.transpose()))
            }
        }
    )*};
}
param_count!(1, 2, 3);

/// The tip load as a function of the unknown parameters: `offset + (force_n p, moment_nm p)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadBasis<T, const P: usize> {
    /// The known part of the tip load.
    pub offset: TipLoad<T>,
    /// Tip force per unit parameter, N (global frame), one column per parameter.
    pub force_n: SMatrix<T, 3, P>,
    /// Tip moment per unit parameter, N m (global frame).
    pub moment_nm: SMatrix<T, 3, P>,
}

impl<T: Scalar> LoadBasis<T, 3> {
    /// An unknown tip force (three components, N, global frame): the product's estimator.
    pub fn tip_force() -> Self {
        Self {
            offset: TipLoad::zero(),
            force_n: Matrix3::identity(),
            moment_nm: Matrix3::zeros(),
        }
    }
}

impl<T: Scalar> LoadBasis<T, 1> {
    /// A tip force of unknown size (N) along a known direction, e.g. a mass hung at the tip
    /// (direction = gravity): the thesis bench.
    pub fn force_along(direction: &Vector3<T>) -> Result<Self, ModelError> {
        finite_vec(direction, "load direction")?;
        let norm = direction.norm();
        positive(norm, "load direction")?;
        Ok(Self {
            offset: TipLoad::zero(),
            force_n: SMatrix::<T, 3, 1>::from_column_slice((direction / norm).as_slice()),
            moment_nm: SMatrix::zeros(),
        })
    }
}

impl<T: Scalar, const P: usize> LoadBasis<T, P> {
    /// The tip load at parameters `p`.
    pub fn load(&self, p: &SVector<T, P>) -> TipLoad<T> {
        TipLoad {
            force_n: self.offset.force_n + self.force_n * p,
            moment_nm: self.offset.moment_nm + self.moment_nm * p,
        }
    }

    fn validate(&self) -> Result<(), ModelError> {
        self.offset.validate()?;
        if !crate::scalar::all_finite(&self.force_n) || !crate::scalar::all_finite(&self.moment_nm)
        {
            return Err(ModelError::NonFinite("load basis"));
        }
        Ok(())
    }
}

/// Settings of the inverse solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseSettings<T> {
    /// Iterations (each one sweep with six tangents).
    pub max_iterations: u16,
    /// Tolerance on the dimensionless tip-moment residual (as in [`ShootingSettings::tolerance`]).
    pub tolerance: T,
    /// Cable mismatch below which the fit is exact, m.
    pub length_tolerance_m: T,
    /// A step that moves the fit (data and prior) by less than this many standard deviations, and the
    /// tip by less than `tip_tolerance_m`, ends the solve. Raised to what the scalar type resolves.
    pub step_tolerance_sigma: T,
    /// Standard deviation of one cable-length measurement, m (for an encoder of resolution `q`,
    /// `q / sqrt(12)`; see [`InverseSettings::with_resolution`]).
    pub length_std_m: T,
    /// A load component whose standard deviation exceeds this, N, makes the estimate
    /// [`Determination::Weak`].
    pub max_force_std_n: T,
    /// Trust region: largest change of base strain per iteration, as an angle `|du0| L`, rad.
    pub max_rotation_step_rad: T,
    /// Check the stability of the answer (free: uses the tangents already computed).
    pub check_stability: bool,
    /// The solve stops when the next step would move the tip by less than this, m (and the fit by
    /// less than `step_tolerance_sigma`). Raised to what the scalar type resolves: `4 L` times the
    /// default shooting tolerance (37 um for f32 on a 39 cm rod).
    pub tip_tolerance_m: T,
    /// A priori standard deviation of each load parameter, in units of the rod's buckling scale
    /// (`E I / L^2` for a force, `E I / L` for a moment); infinity for none. With a prior the answer is
    /// the maximum a posteriori estimate: it keeps a direction the cables barely see (an axial force,
    /// whose effect near buckling is strongly nonlinear) from wandering to one of several far-apart
    /// fits, and changes well-determined directions negligibly. The identifiability figures in
    /// [`Quality`] (singular values, condition number, [`Determination`]) stay those of the data alone.
    pub prior_std_scale: T,
}

impl<T: Scalar> Default for InverseSettings<T> {
    fn default() -> Self {
        let eps = T::default_epsilon();
        Self {
            max_iterations: 60,
            tolerance: default_tolerance(),
            length_tolerance_m: (eps * T::lit(10.0)).max(T::lit(1e-12)),
            step_tolerance_sigma: T::lit(1e-4),
            length_std_m: T::lit(1e-6),
            max_force_std_n: T::lit(0.05),
            max_rotation_step_rad: T::lit(1.0),
            check_stability: true,
            tip_tolerance_m: T::lit(1e-7),
            prior_std_scale: T::lit(10.0),
        }
    }
}

impl<T: Scalar> InverseSettings<T> {
    /// Default settings for length measurements quantised at `resolution_m` (std `resolution / sqrt 12`).
    pub fn with_resolution(resolution_m: T) -> Self {
        Self {
            length_std_m: resolution_m / T::lit(12.0).sqrt(),
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), ModelError> {
        positive(self.tolerance, "inverse tolerance")?;
        positive(self.length_tolerance_m, "length tolerance")?;
        positive(self.step_tolerance_sigma, "step tolerance")?;
        positive(self.length_std_m, "length standard deviation")?;
        positive(self.max_force_std_n, "force standard deviation limit")?;
        positive(self.max_rotation_step_rad, "trust region")?;
        positive(self.tip_tolerance_m, "tip tolerance")?;
        // Infinity (no prior) is allowed; NaN, zero and negative are not.
        if self.prior_std_scale.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
            return Err(ModelError::NotPositive("prior standard deviation"));
        }
        Ok(())
    }
}

/// How well the measurements determine the load.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Determination {
    /// Every load component's standard deviation is within [`InverseSettings::max_force_std_n`].
    Determined,
    /// Some direction of the load is poorly determined (its standard deviation exceeds the limit).
    Weak,
    /// The data cannot determine some direction at all (rank deficient: fewer independent cables
    /// than unknowns).
    Undetermined,
    /// No load of the model explains the measurements within three standard deviations.
    Inconsistent,
}

/// What the measurements say about the load, at the estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quality<T, const P: usize> {
    /// Singular values of the weighted sensitivity `G / s` (per unit parameter), decreasing.
    #[cfg(feature = "identifiability")]
    pub singular_values: SVector<T, P>,
    /// Largest over smallest singular value (infinite when rank deficient).
    #[cfg(feature = "identifiability")]
    pub condition_number: T,
    /// Standard deviation of each parameter (infinite when undetermined).
    pub param_std: SVector<T, P>,
    /// Standard deviation of the tip force components, N, global frame.
    pub force_std_n: Vector3<T>,
    /// Standard deviation of the tip position components, m, global frame.
    pub tip_std_m: Vector3<T>,
    /// The parameter direction the data determine worst (unit vector).
    #[cfg(feature = "identifiability")]
    pub weakest_direction: SVector<T, P>,
    /// Rms of `(model - measured) / s` over the cables.
    pub residual_rms_sigma: T,
    /// The verdict.
    pub determination: Determination,
}

/// An estimate of the tip load and the shape it implies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate<T, const P: usize> {
    /// The load parameters.
    pub params: SVector<T, P>,
    /// The tip load they give.
    pub load: TipLoad<T>,
    /// The base strain of the equilibrium, 1/m.
    pub base_strain_per_m: Vector3<T>,
    /// Tip position, m.
    pub tip_position_m: Vector3<T>,
    /// Tip frame.
    pub tip_rotation: Matrix3<T>,
    /// Model minus measured cable length, m (zero beyond the rod's cables).
    pub cable_residual_m: CableVector<T>,
    /// How the solve went. Use the estimate only when `report.termination.is_success()`.
    pub report: SolveReport<T>,
    /// How well the data determine it.
    pub quality: Quality<T, P>,
}

/// What the cable data alone determine at the estimate.
struct DataOnly<T, const P: usize> {
    rank_deficient: bool,
    /// The parameters' covariance from the data alone (none when rank deficient).
    covariance: Option<SMatrix<T, P, P>>,
}

/// The linearisation of the residuals at one point.
#[derive(Clone, Copy, Debug)]
struct Linearization<T, const P: usize> {
    e: Vector3<T>,
    rc: CableVector<T>,
    j_eu: Matrix3<T>,
    j_ep: SMatrix<T, 3, P>,
    j_cu: SMatrix<T, MAX_CABLES, 3>,
    j_cp: SMatrix<T, MAX_CABLES, P>,
    tip_position_m: Vector3<T>,
    tip_rotation: Matrix3<T>,
    d_tip_u: Matrix3<T>,
    d_tip_p: SMatrix<T, 3, P>,
    d_theta_tip_u: Matrix3<T>,
    conjugate_point_m: Option<T>,
    frame_drift: T,
}

impl<T: Scalar, const P: usize> Linearization<T, P> {
    fn empty() -> Self {
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
        }
    }

    /// New residuals and tip pose from a plain sweep; the Jacobian blocks stay.
    fn set_residual(&mut self, sw: &Sweep<T>, rc: CableVector<T>) {
        self.e = sw.moment_residual_nm;
        self.rc = rc;
        self.tip_position_m = sw.tip_position_m;
        self.tip_rotation = sw.tip_rotation;
        self.frame_drift = sw.frame_drift;
    }
}

/// The reduced Gauss-Newton system at a linearisation.
struct Reduced<T, const P: usize> {
    /// `J_eu^-1 J_ep`.
    a: SMatrix<T, 3, P>,
    /// `J_eu^-1 e`.
    b: Vector3<T>,
    /// Weighted sensitivity `G / s`.
    g: SMatrix<T, MAX_CABLES, P>,
    /// Weighted reduced residual `c~ / s`.
    c: CableVector<T>,
}

/// The state the solve moves: base strain and load parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Point<T, const P: usize> {
    u0: Vector3<T>,
    p: SVector<T, P>,
}

#[derive(Clone, Copy)]
struct Problem<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize> {
    model: &'a Model<T, A, NODES>,
    basis: LoadBasis<T, P>,
    measured: CableVector<T>,
    settings: InverseSettings<T>,
    cables: usize,
    /// `1 / prior std` of each parameter (zero: no prior).
    prior_weight: SVector<T, P>,
    /// The largest tip-moment residual (dimensionless) at which the reduced model is trusted: its
    /// second-order cable error, about `r e^2`, stays below a tenth of a standard deviation.
    max_moment_residual: T,
}

impl<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>
    Problem<'a, T, A, P, NODES>
{
    fn new(
        model: &'a Model<T, A, NODES>,
        basis: LoadBasis<T, P>,
        measured: CableVector<T>,
        settings: InverseSettings<T>,
    ) -> Self {
        Self {
            model,
            basis,
            measured,
            settings,
            cables: model.rod().cables.len(),
            prior_weight: prior_weight(model, &basis, &settings),
            max_moment_residual: {
                let radius = model
                    .rod()
                    .cables
                    .iter()
                    .fold(T::zero(), |r, c| r.max(c.radius_m()));
                (settings.length_std_m * T::lit(0.1) / radius).sqrt()
            },
        }
    }

    /// Brings a point back onto the equilibrium at its load when its tip-moment residual is too large
    /// for the reduced model: Newton steps on the base strain alone (variable projection). Returns the
    /// projected point and its linearisation, or `None` if that does not converge.
    fn project(
        &self,
        mut x: Point<T, P>,
        mut lin: Linearization<T, P>,
        work: &mut crate::shooting::Work,
    ) -> Option<(Point<T, P>, Linearization<T, P>)> {
        for _ in 0..8 {
            if self.model.moment_residual(&lin.e) <= self.max_moment_residual {
                return Some((x, lin));
            }
            let mut du = lin.j_eu.lu().solve(&-lin.e)?;
            let turn = du.norm() * self.model.length_m();
            if turn > self.settings.max_rotation_step_rad {
                du *= self.settings.max_rotation_step_rad / turn;
            }
            x.u0 += du;
            work.sweeps = work.sweeps.saturating_add(1);
            let sw = self.full_sweep(&x);
            if !sw.finite {
                return None;
            }
            lin = self.linearize(&sw);
        }
        (self.model.moment_residual(&lin.e) <= self.max_moment_residual).then_some((x, lin))
    }

    /// The same problem with other prior weights.
    fn with_prior(&self, prior_weight: SVector<T, P>) -> Self {
        Self {
            prior_weight,
            ..*self
        }
    }

    /// The graduated prior's weights at relaxation `relax` (1 at the start, halving): the start weights
    /// scaled down, but never below the final prior's; tiny ones become the final ones.
    fn graduated(&self, start: &SVector<T, P>, relax: T) -> SVector<T, P> {
        if relax < T::lit(1e-6) {
            return self.prior_weight;
        }
        start.zip_map(&self.prior_weight, |s, f| (s * relax).max(f))
    }

    fn full_sweep(&self, x: &Point<T, P>) -> Sweep<T> {
        let load = self.basis.load(&x.p);
        sweep(
            self.model,
            &self.model.inputs(&x.u0, &load, T::one()),
            Tangents::all(self.settings.check_stability),
            None,
        )
    }

    fn plain_sweep(&self, x: &Point<T, P>) -> Sweep<T> {
        let load = self.basis.load(&x.p);
        sweep(
            self.model,
            &self.model.inputs(&x.u0, &load, T::one()),
            Tangents::NONE,
            None,
        )
    }

    fn cable_residual(&self, sw: &Sweep<T>) -> CableVector<T> {
        CableVector::from_fn(|c, _| {
            match (c < self.cables, sw.cable_m.get(c), self.measured.get(c)) {
                (true, Some(model), Some(measured)) => *model - *measured,
                _ => T::zero(),
            }
        })
    }

    fn linearize(&self, sw: &Sweep<T>) -> Linearization<T, P> {
        let j_eu = Matrix3::from_columns(&[sw.d_moment(0), sw.d_moment(1), sw.d_moment(2)]);
        let j_ef = Matrix3::from_columns(&[sw.d_moment(3), sw.d_moment(4), sw.d_moment(5)]);
        // e = C u - R^T tau: d e / d tau = -R^T.
        let j_ep = j_ef * self.basis.force_n - sw.tip_rotation.tr_mul(&self.basis.moment_nm);
        let cable = |c: usize, j: usize| {
            if c < self.cables {
                sw.d_cable_length(c, j)
            } else {
                T::zero()
            }
        };
        let j_cu = SMatrix::<T, MAX_CABLES, 3>::from_fn(&cable);
        let j_cf = SMatrix::<T, MAX_CABLES, 3>::from_fn(|c, j| cable(c, j + 3));
        let tip = |j: usize| sw.d_position(j);
        let theta = |j: usize| sw.d_rotation(j);
        Linearization {
            e: sw.moment_residual_nm,
            rc: self.cable_residual(sw),
            j_eu,
            j_ep,
            j_cu,
            j_cp: j_cf * self.basis.force_n,
            tip_position_m: sw.tip_position_m,
            tip_rotation: sw.tip_rotation,
            d_tip_u: Matrix3::from_columns(&[tip(0), tip(1), tip(2)]),
            d_tip_p: Matrix3::from_columns(&[tip(3), tip(4), tip(5)]) * self.basis.force_n,
            d_theta_tip_u: Matrix3::from_columns(&[theta(0), theta(1), theta(2)]),
            conjugate_point_m: sw.conjugate_point_m,
            frame_drift: sw.frame_drift,
        }
    }

    fn reduce(&self, lin: &Linearization<T, P>) -> Option<Reduced<T, P>> {
        let lu = lin.j_eu.lu();
        let a = lu.solve(&lin.j_ep)?;
        let b = lu.solve(&lin.e)?;
        let inv_std = T::one() / self.settings.length_std_m;
        let g = (lin.j_cp - lin.j_cu * a) * inv_std;
        let c = (lin.rc - lin.j_cu * b) * inv_std;
        let ok = crate::scalar::all_finite(&g)
            && crate::scalar::all_finite(&c)
            && crate::scalar::all_finite(&a);
        ok.then_some(Reduced { a, b, g, c })
    }

    /// The merit a step must decrease: the squared cable mismatch, in standard deviations, left once
    /// the tip-moment condition is restored to first order (`|c~|^2` of the reduced system, which
    /// the step minimises), plus the prior's `|p / prior std|^2`. Judging the full residual instead
    /// would let the moment condition's curvature veto steps along a weakly determined direction.
    fn merit(&self, p: &SVector<T, P>, lin: &Linearization<T, P>) -> T {
        self.reduce(lin).map_or_else(
            || T::max_value().unwrap_or_else(T::one),
            |red| red.c.norm_squared() + p.component_mul(&self.prior_weight).norm_squared(),
        )
    }

    /// Whether the equilibrium at a linearisation may be accepted: not found unstable (an unstable
    /// equilibrium is not a physical answer, and a step onto one is rejected like a failed step).
    fn acceptable(&self, p: &SVector<T, P>, lin: &Linearization<T, P>) -> bool {
        !self.settings.check_stability || self.stability(p, lin).is_acceptable()
    }

    fn stability(&self, p: &SVector<T, P>, lin: &Linearization<T, P>) -> Stability<T> {
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
    fn predicted_decrease(&self, red: &Reduced<T, P>, p: &SVector<T, P>, dp: &SVector<T, P>) -> T {
        let w = &self.prior_weight;
        red.c.norm_squared() + p.component_mul(w).norm_squared()
            - (red.c + red.g * dp).norm_squared()
            - (p + dp).component_mul(w).norm_squared()
    }

    /// The information matrix `G^T G / s^2 + W^2` (data and prior).
    fn information(&self, red: &Reduced<T, P>) -> SMatrix<T, P, P> {
        let w2 = self.prior_weight.component_mul(&self.prior_weight);
        red.g.tr_mul(&red.g) + SMatrix::from_diagonal(&w2)
    }

    /// The damped step from `p` (`mu = 0`: Gauss-Newton), limited by the trust region on the base
    /// rotation. The base-strain change has two parts: `-J_eu^-1 e`, which restores the tip-moment
    /// condition at the current load, and `-J_eu^-1 J_ep dp`, which follows the load step. The trust
    /// region shortens the load step first; shortening the first part too would leave the iterate off
    /// the equilibrium, where the reduced model no longer describes the problem.
    fn step(
        &self,
        red: &Reduced<T, P>,
        p: &SVector<T, P>,
        mu: T,
    ) -> Option<(Vector3<T>, SVector<T, P>)> {
        let normal = self.information(red);
        let w2 = self.prior_weight.component_mul(&self.prior_weight);
        let gradient = red.g.tr_mul(&red.c) + w2.component_mul(p);
        // A tiny ridge keeps an undetermined direction from blowing the step up; LM damping on top.
        let ridge = normal.diagonal().max().max(T::one()) * T::default_epsilon() * T::lit(16.0);
        let damped = normal + SMatrix::from_diagonal(&(normal.diagonal() * mu).add_scalar(ridge));
        let dp = damped.cholesky()?.solve(&-gradient);
        let length = self.model.length_m();
        let limit = self.settings.max_rotation_step_rad;
        let restore = -red.b;
        let follow = -(red.a * dp);
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

    /// The fit's quality: identifiability from the data alone, uncertainty from data and prior
    /// together.
    fn quality(&self, lin: &Linearization<T, P>, red: Option<&Reduced<T, P>>) -> Quality<T, P>
    where
        Params: ParamCount<T, P>,
    {
        let inv_std = T::one() / self.settings.length_std_m;
        let residual_rms_sigma = if self.cables > 0 {
            (lin.rc.norm_squared() / T::lit(self.cables as f64)).sqrt() * inv_std
        } else {
            T::zero()
        };
        let infinite: T = T::max_value().unwrap_or_else(|| T::lit(1e300));
        let mut quality: Quality<T, P> = Quality {
            #[cfg(feature = "identifiability")]
            singular_values: SVector::zeros(),
            #[cfg(feature = "identifiability")]
            condition_number: infinite,
            param_std: SVector::repeat(infinite),
            force_std_n: Vector3::repeat(infinite),
            tip_std_m: Vector3::repeat(infinite),
            #[cfg(feature = "identifiability")]
            weakest_direction: SVector::zeros(),
            residual_rms_sigma,
            // A misfit beyond three standard deviations is the verdict whatever else is known: no
            // load explains the data, however well or badly the data would determine one.
            determination: if residual_rms_sigma > T::lit(3.0) {
                Determination::Inconsistent
            } else {
                Determination::Undetermined
            },
        };
        let Some(red) = red else {
            return quality;
        };
        let Some(data) = self.data_only(red, &mut quality) else {
            return quality;
        };
        // Covariance of p: the inverse information, from the data alone when there is no prior.
        let covariance = if self.prior_weight.iter().all(|w| *w == T::zero()) {
            match data.covariance {
                Some(c) if !data.rank_deficient => c,
                _ => return quality,
            }
        } else {
            match self.information(red).cholesky() {
                Some(c) => c.inverse(),
                None => return quality,
            }
        };
        quality.param_std = covariance.diagonal().map(|x| x.max(T::zero()).sqrt());
        let force_cov = self.basis.force_n * covariance * self.basis.force_n.transpose();
        quality.force_std_n = force_cov.diagonal().map(|v| v.max(T::zero()).sqrt());
        // The tip moves with p directly and through the re-solved shape: dtip/dp = T_p - T_u J_eu^-1 J_ep.
        let d_tip = lin.d_tip_p - lin.d_tip_u * red.a;
        let tip_cov = d_tip * covariance * d_tip.transpose();
        quality.tip_std_m = tip_cov.diagonal().map(|v| v.max(T::zero()).sqrt());
        let moment_cov = self.basis.moment_nm * covariance * self.basis.moment_nm.transpose();
        let worst = quality
            .force_std_n
            .max()
            .max(moment_cov.diagonal().max().max(T::zero()).sqrt());
        quality.determination = if residual_rms_sigma > T::lit(3.0) {
            Determination::Inconsistent
        } else if data.rank_deficient {
            Determination::Undetermined
        } else if worst > self.settings.max_force_std_n {
            Determination::Weak
        } else {
            Determination::Determined
        };
        quality
    }

    /// What the data alone say, from the singular values of `G` (not of `G^T G`: the normal matrix
    /// squares the condition number, which f32 cannot hold for the axial direction). Fills the
    /// singular values, condition number and weakest direction; `None` if the SVD does not converge.
    #[cfg(feature = "identifiability")]
    fn data_only(&self, red: &Reduced<T, P>, quality: &mut Quality<T, P>) -> Option<DataOnly<T, P>>
    where
        Params: ParamCount<T, P>,
    {
        let (singular, v) = Params::svd(red.g)?;
        let (mut largest, mut smallest, mut weakest) =
            (T::zero(), quality.condition_number, 0usize);
        for (i, &value) in singular.iter().enumerate() {
            largest = largest.max(value);
            if value < smallest {
                (smallest, weakest) = (value, i);
            }
        }
        let mut sorted = singular;
        crate::scalar::insertion_sort(sorted.as_mut_slice(), |a, b| a > b);
        quality.singular_values = sorted;
        quality.weakest_direction = v.column(weakest).into_owned();
        let rank_deficient =
            smallest <= largest * T::default_epsilon() * T::lit(100.0) || largest == T::zero();
        if !rank_deficient {
            quality.condition_number = largest / smallest;
        }
        // V diag(1 / sigma^2) V^T.
        let covariance = (!rank_deficient).then(|| {
            v * SMatrix::<T, P, P>::from_diagonal(&singular.map(|x| T::one() / (x * x)))
                * v.transpose()
        });
        Some(DataOnly {
            rank_deficient,
            covariance,
        })
    }

    /// What the data alone say, without the SVD (the controller's flash): rank deficient when there
    /// are fewer cables than parameters or `G^T G` is not positive definite. A direction the data
    /// determine only numerically badly then shows as [`Determination::Weak`] through its standard
    /// deviation rather than as [`Determination::Undetermined`].
    #[cfg(not(feature = "identifiability"))]
    fn data_only(&self, red: &Reduced<T, P>, _: &mut Quality<T, P>) -> Option<DataOnly<T, P>> {
        let covariance = (self.cables >= P)
            .then(|| red.g.tr_mul(&red.g).cholesky().map(|c| c.inverse()))
            .flatten();
        Some(DataOnly {
            rank_deficient: covariance.is_none(),
            covariance,
        })
    }

    /// The smallest fit change, in standard deviations, the scalar type can resolve: cable lengths are
    /// sums of chords about as long as the rod, rounded to about `2 eps L`.
    fn fit_floor_sigma(&self) -> T {
        T::default_epsilon() * T::lit(2.0) * self.model.length_m() / self.settings.length_std_m
    }

    /// Converged when the tip-moment condition holds and the rest of the way is negligible: the next
    /// Gauss-Newton step, plus what the steps still to come would add when the iteration converges
    /// only linearly (`step q / (1 - q)` for a contraction `q` from the previous step's tip move),
    /// would move the tip by less than the tip tolerance, and the fit (data and prior, in standard
    /// deviations) by less than the step tolerance. Both tolerances are raised to what the scalar type
    /// resolves. Returns the verdict and the step's tip move.
    fn converged(
        &self,
        x: &Point<T, P>,
        lin: &Linearization<T, P>,
        red: &Reduced<T, P>,
        previous_tip_move: Option<T>,
    ) -> (bool, T) {
        let infinite = T::max_value().unwrap_or_else(T::one);
        let Some((du, dp)) = self.step(red, &x.p, T::zero()) else {
            return (false, infinite);
        };
        let tip_move = (lin.d_tip_u * du + lin.d_tip_p * dp).norm();
        // The tip-moment condition holds when its residual is small or, at the rounding floor, when
        // the correction it asks for (`J_eu^-1 e`) turns the base negligibly (what it does to the
        // tip is in `tip_move` below, against the tip tolerance).
        let moment_ok = self
            .model
            .moment_converged(&lin.e, &x.u0, self.settings.tolerance)
            || self
                .model
                .step_converged(&red.b, &x.u0, T::zero(), self.settings.tolerance);
        let remaining = match previous_tip_move {
            Some(previous) if previous > T::zero() && tip_move < previous => {
                let q = tip_move / previous;
                tip_move * q / (T::one() - q)
            }
            Some(_) => infinite,
            None => T::zero(),
        };
        // f32 resolves the tip to about the shooting tolerance (an angle) times the rod length.
        let tip_floor = self.model.length_m() * default_tolerance::<T>();
        let fit_move = (dp.transpose() * self.information(red) * dp)
            .x
            .max(T::zero())
            .sqrt();
        let fit_tolerance = self
            .settings
            .step_tolerance_sigma
            .max(self.fit_floor_sigma());
        let done = moment_ok
            && tip_move + remaining <= self.settings.tip_tolerance_m.max(tip_floor)
            && fit_move <= fit_tolerance;
        (done, tip_move)
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

/// `1 / prior std` for each parameter for a prior of `std_scale` buckling scales.
fn prior_weight_for<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>(
    model: &Model<T, A, NODES>,
    basis: &LoadBasis<T, P>,
    std_scale: T,
) -> SVector<T, P> {
    let moment_scale = model.moment_scale_nm();
    let force_scale = moment_scale / model.length_m();
    SVector::from_fn(|j, _| {
        // A parameter's effect, measured in units of the buckling scale.
        let effect = basis.force_n.column(j).norm() / force_scale
            + basis.moment_nm.column(j).norm() / moment_scale;
        let std = std_scale / effect;
        if std.is_finite() && std > T::zero() {
            T::one() / std
        } else {
            T::zero()
        }
    })
}

/// Where an inverse solve starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InverseStart<T, const P: usize> {
    /// From load parameters (the shape is solved cold for them first).
    Params(SVector<T, P>),
    /// From a previous estimate's parameters and base strain.
    Warm {
        /// Load parameters.
        params: SVector<T, P>,
        /// Base strain, 1/m.
        base_strain_per_m: Vector3<T>,
    },
}

fn validate_measurements<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    measured_m: &[T],
) -> Result<CableVector<T>, ModelError> {
    let rod = model.rod();
    if measured_m.len() != rod.cables.len() {
        return Err(ModelError::Mismatch("measured cable lengths and cables"));
    }
    if measured_m.is_empty() {
        return Err(ModelError::Empty("cable lengths"));
    }
    let mut out = CableVector::zeros();
    for (c, (&length, cable)) in measured_m.iter().zip(rod.cables.iter()).enumerate() {
        positive(length, "cable length")?;
        if length > cable_length_bound_m(rod, cable) {
            return Err(ModelError::OutOfRange(
                "cable length (longer than the rod can produce)",
            ));
        }
        if let Some(slot) = out.get_mut(c) {
            *slot = length;
        }
    }
    Ok(out)
}

/// An upper bound on a cable's length: every chord between consecutive holes is at most the arc
/// between them stretched by 10 % plus twice the hole offset.
pub fn cable_length_bound_m<T: Scalar>(rod: &crate::Rod<T>, cable: &crate::Cable<T>) -> T {
    let mut previous: Option<T> = None;
    let mut bound = T::zero();
    let holes = rod
        .guides
        .iter()
        .map(|g| g.s_m)
        .filter(|s| *s <= cable.end_m)
        .chain(core::iter::once(cable.end_m));
    for s in holes {
        if let Some(prev) = previous {
            bound += (s - prev) * T::lit(1.1) + cable.radius_m() * T::lit(2.0);
        }
        previous = Some(s);
    }
    bound
}

/// Estimates the load parameters from measured cable lengths (one per cable, m), starting from `start`.
///
/// Fails only on invalid input. The answer is usable when `report.termination.is_success()`; how
/// well the data determine it is in `quality`.
pub fn estimate<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>(
    model: &Model<T, A, NODES>,
    basis: &LoadBasis<T, P>,
    measured_m: &[T],
    start: InverseStart<T, P>,
    settings: &InverseSettings<T>,
) -> Result<Estimate<T, P>, ModelError>
where
    Params: ParamCount<T, P>,
{
    basis.validate()?;
    settings.validate()?;
    let measured = validate_measurements(model, measured_m)?;
    let problem = Problem::new(model, *basis, measured, *settings);
    let mut work = crate::shooting::Work::default();
    let x = match start {
        InverseStart::Params(p) => {
            for v in p.iter() {
                finite(*v, "start parameters")?;
            }
            let shooting = ShootingSettings {
                tolerance: settings.tolerance,
                max_rotation_step_rad: settings.max_rotation_step_rad,
                ..ShootingSettings::default()
            };
            let eq = model.solve(&basis.load(&p), Start::Cold, &shooting)?;
            work.iterations = eq.report.iterations;
            work.sweeps = eq.report.sweeps;
            let x = Point {
                u0: eq.base_strain_per_m,
                p,
            };
            if !eq.report.termination.is_success() {
                let lin = problem.linearize(&problem.full_sweep(&x));
                return Ok(problem.finish(x, &lin, eq.report.termination, work));
            }
            x
        }
        InverseStart::Warm {
            params,
            base_strain_per_m,
        } => {
            finite_vec(&base_strain_per_m, "warm-start base strain")?;
            for v in params.iter() {
                finite(*v, "start parameters")?;
            }
            Point {
                u0: base_strain_per_m,
                p: params,
            }
        }
    };
    Ok(problem.solve(x, work))
}

impl<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize> Problem<'_, T, A, P, NODES>
where
    Params: ParamCount<T, P>,
{
    fn solve(&self, mut x: Point<T, P>, mut work: crate::shooting::Work) -> Estimate<T, P> {
        work.sweeps = work.sweeps.saturating_add(1);
        let sw = self.full_sweep(&x);
        if !sw.finite {
            let lin = self.linearize(&sw);
            return self.finish(x, &lin, Termination::NonFinite, work);
        }
        let mut lin = self.linearize(&sw);
        // A graduated prior: the first steps hold the load to a tenth of the buckling scale, then the
        // prior relaxes by half each accepted step to its final value. From a cold start the linear
        // model can trade a large axial force for bending (at the sagging shape an axial force and a
        // lateral one bend the rod alike); the tight start finds the bending-consistent answer first.
        let start_weight = prior_weight_for(self.model, &self.basis, T::lit(0.1));
        let mut relax = T::one();
        let mut stage = self.with_prior(self.graduated(&start_weight, relax));
        let mut merit = stage.merit(&x.p, &lin);
        // Levenberg-Marquardt with Nielsen's damping update: the gain ratio (actual over predicted
        // decrease) sets the damping. It starts as Gauss-Newton.
        let mut mu = T::lit(1e-12);
        let mut nu = T::lit(2.0);
        let mut previous_tip_move = None;
        for _ in 0..self.settings.max_iterations {
            let Some(red) = self.reduce(&lin) else {
                return self.finish(x, &lin, Termination::Singular, work);
            };
            let final_stage = stage.prior_weight == self.prior_weight;
            let (done, tip_move) = stage.converged(&x, &lin, &red, previous_tip_move);
            if done && final_stage {
                return self.finish(x, &lin, Termination::Converged, work);
            }
            if done {
                // The tight prior has found the basin: go to the final prior at once.
                stage = *self;
                merit = stage.merit(&x.p, &lin);
                previous_tip_move = None;
                continue;
            }
            let Some((du, dp)) = stage.step(&red, &x.p, mu) else {
                return self.finish(x, &lin, Termination::Singular, work);
            };
            work.iterations = work.iterations.saturating_add(1);
            let trial = Point {
                u0: x.u0 + du,
                p: x.p + dp,
            };
            work.sweeps = work.sweeps.saturating_add(1);
            let sw = self.full_sweep(&trial);
            let projected = if sw.finite {
                self.project(trial, self.linearize(&sw), &mut work)
            } else {
                None
            };
            let predicted = stage.predicted_decrease(&red, &x.p, &dp);
            match projected.map(|(t, l)| {
                let m = stage.merit(&t.p, &l);
                (t, l, m)
            }) {
                Some((trial, l, m))
                    if m < merit && predicted > T::zero() && self.acceptable(&trial.p, &l) =>
                {
                    let rho = (merit - m) / predicted;
                    let t = T::lit(2.0) * rho - T::one();
                    mu = (mu * (T::one() - t * t * t).max(T::lit(1.0 / 3.0))).max(T::lit(1e-15));
                    nu = T::lit(2.0);
                    (x, lin, merit) = (trial, l, m);
                    previous_tip_move = Some(tip_move);
                    if !final_stage {
                        relax *= T::lit(0.5);
                        stage = self.with_prior(self.graduated(&start_weight, relax));
                        merit = stage.merit(&x.p, &lin);
                        previous_tip_move = None;
                    }
                }
                _ => {
                    mu = (mu * nu).max(T::lit(1e-6));
                    nu *= T::lit(2.0);
                    if mu > T::lit(1e12) && !final_stage {
                        // Stuck under the graduated prior: release it and go on.
                        stage = *self;
                        merit = stage.merit(&x.p, &lin);
                        previous_tip_move = None;
                        mu = T::lit(1e-12);
                        nu = T::lit(2.0);
                    } else if mu > T::lit(1e12) {
                        // No step improves the fit. If the last Gauss-Newton step is itself negligible,
                        // this is the rounding floor, not a failure.
                        let termination = if stage.converged(&x, &lin, &red, None).0 {
                            Termination::Converged
                        } else {
                            Termination::Stalled
                        };
                        return self.finish(x, &lin, termination, work);
                    }
                }
            }
        }
        let final_stage = stage.prior_weight == self.prior_weight;
        let done = final_stage
            && self
                .reduce(&lin)
                .is_some_and(|r| self.converged(&x, &lin, &r, previous_tip_move).0);
        let termination = if done {
            Termination::Converged
        } else {
            Termination::IterationLimit
        };
        self.finish(x, &lin, termination, work)
    }

    fn finish(
        &self,
        x: Point<T, P>,
        lin: &Linearization<T, P>,
        termination: Termination,
        work: crate::shooting::Work,
    ) -> Estimate<T, P> {
        let red = self.reduce(lin);
        let quality = self.quality(lin, red.as_ref());
        let mut termination = termination;
        if termination.is_success()
            && !(lin.frame_drift.is_finite() && lin.frame_drift <= T::lit(MAX_FRAME_DRIFT))
        {
            termination = Termination::FrameDrift;
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
        let moment = self.model.moment_residual(&lin.e);
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
            },
            quality,
        }
    }
}

/// Settings of the warm-started [`Estimator`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorSettings<T> {
    /// The inverse solve's settings, for the first (cold) estimate and every update.
    pub inverse: InverseSettings<T>,
    /// Most sweeps one update may take (its cost bound). The first is a plain sweep; the others carry
    /// six tangents and cost about four plain sweeps each. With `1`, every update is exactly one sweep
    /// with six tangents and one Newton step (see [`Estimator::update`]): the hard real-time mode.
    pub max_sweeps: u8,
}

impl<T: Scalar> Default for EstimatorSettings<T> {
    /// See [`EstimatorSettings::with_inverse`].
    fn default() -> Self {
        Self::with_inverse(InverseSettings::default())
    }
}

impl<T: Scalar> EstimatorSettings<T> {
    /// Control-loop tolerances on top of the given inverse settings: a control loop needs the answer
    /// to a fraction of the measurement noise, not to rounding, so an update stops when the next step
    /// would move the tip by less than 10 um and the fit by less than 0.01 standard deviations, with
    /// the tip moment to 1e-5 of `E I / L` (a few um at the tip, consistent with the tip tolerance).
    /// Three sweeps per update at most.
    pub fn with_inverse(inverse: InverseSettings<T>) -> Self {
        Self {
            inverse: InverseSettings {
                tolerance: inverse.tolerance.max(T::lit(1e-5)),
                tip_tolerance_m: inverse.tip_tolerance_m.max(T::lit(1e-5)),
                step_tolerance_sigma: inverse.step_tolerance_sigma.max(T::lit(1e-2)),
                ..inverse
            },
            max_sweeps: 3,
        }
    }
}

/// The warm-started inverse for a control loop.
///
/// Each [`Estimator::update`] starts from the last estimate: a plain sweep gives the residual for
/// the new measurements, a step with the Jacobian kept from the last update (a chord step) moves
/// toward them, and the sweep at the trial point carries the six tangents, so an accepted point
/// brings its own exact Jacobian: Newton from the second step on, and a fresh Jacobian for the next
/// update. The cost is bounded by [`EstimatorSettings::max_sweeps`]; when the budget runs out the
/// report says [`Termination::IterationLimit`] and the next update carries on from there.
/// Steps are limited by the trust region, so the estimate follows its branch continuously.
#[derive(Clone, Debug)]
pub struct Estimator<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize = MAX_NODES>
{
    model: &'a Model<T, A, NODES>,
    basis: LoadBasis<T, P>,
    settings: EstimatorSettings<T>,
    x: Point<T, P>,
    lin: Linearization<T, P>,
    stability: Stability<T>,
}

impl<'a, T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>
    Estimator<'a, T, A, P, NODES>
where
    Params: ParamCount<T, P>,
{
    /// Starts from a cold estimate for the first measurements; returns the estimator and that estimate.
    pub fn new(
        model: &'a Model<T, A, NODES>,
        basis: LoadBasis<T, P>,
        measured_m: &[T],
        start_params: SVector<T, P>,
        settings: EstimatorSettings<T>,
    ) -> Result<(Self, Estimate<T, P>), ModelError> {
        if settings.max_sweeps == 0 {
            return Err(ModelError::NotPositive("estimator sweep budget"));
        }
        let first = estimate(
            model,
            &basis,
            measured_m,
            InverseStart::Params(start_params),
            &settings.inverse,
        )?;
        let mut estimator = Estimator {
            model,
            basis,
            settings,
            x: Point {
                u0: first.base_strain_per_m,
                p: first.params,
            },
            lin: Linearization::empty(),
            stability: first.report.stability,
        };
        let problem = estimator.problem(validate_measurements(model, measured_m)?);
        let sw = problem.full_sweep(&estimator.x);
        if sw.finite {
            estimator.lin = problem.linearize(&sw);
        }
        Ok((estimator, first))
    }

    /// The current parameters.
    pub fn params(&self) -> SVector<T, P> {
        self.x.p
    }

    fn problem(&self, measured: CableVector<T>) -> Problem<'a, T, A, P, NODES> {
        Problem::new(self.model, self.basis, measured, self.settings.inverse)
    }

    /// One estimate for new measurements (one per cable, m), warm-started from the last.
    ///
    /// With a budget of one sweep ([`EstimatorSettings::max_sweeps`] `= 1`) the update is exactly one
    /// sweep with six tangents at the last estimate, for the new measurements, and one Newton step
    /// from it: the cost is fixed, and the estimate returned is the one after the step, its tip and
    /// cable lengths predicted linearly (the error is second order in the change since the last
    /// update, and the next update measures it). It reports [`Termination::Converged`] when the
    /// last estimate already met the tolerances, [`Termination::IterationLimit`] when it took a step.
    pub fn update(&mut self, measured_m: &[T]) -> Result<Estimate<T, P>, ModelError> {
        let problem = self.problem(validate_measurements(self.model, measured_m)?);
        let mut work = crate::shooting::Work::default();
        let budget = u16::from(self.settings.max_sweeps);
        if budget == 1 {
            return Ok(self.one_step(&problem, work));
        }

        // The residual at the last estimate for the new measurements; the Jacobian is the last one.
        work.sweeps += 1;
        let sw = problem.plain_sweep(&self.x);
        if !sw.finite {
            return Ok(problem.finish(self.x, &self.lin, Termination::NonFinite, work));
        }
        self.lin.set_residual(&sw, problem.cable_residual(&sw));
        let mut merit = problem.merit(&self.x.p, &self.lin);
        let mut exact = false;
        loop {
            let Some(red) = problem.reduce(&self.lin) else {
                return Ok(self.finish(&problem, Termination::Singular, work));
            };
            if problem.converged(&self.x, &self.lin, &red, None).0 {
                return Ok(self.finish(&problem, Termination::Converged, work));
            }
            let Some((du, dp)) = problem.step(&red, &self.x.p, T::zero()) else {
                return Ok(self.finish(&problem, Termination::Singular, work));
            };
            if work.sweeps >= budget {
                return Ok(self.finish(&problem, Termination::IterationLimit, work));
            }
            work.iterations = work.iterations.saturating_add(1);
            work.sweeps += 1;
            let trial = Point {
                u0: self.x.u0 + du,
                p: self.x.p + dp,
            };
            let sw = problem.full_sweep(&trial);
            if sw.finite {
                let lin = problem.linearize(&sw);
                let trial_merit = problem.merit(&trial.p, &lin);
                if trial_merit < merit && problem.acceptable(&trial.p, &lin) {
                    (self.x, self.lin, merit, exact) = (trial, lin, trial_merit, true);
                    self.stability = self.verdict(&problem);
                    continue;
                }
            }
            // The step failed. With a stale Jacobian, refresh it here once; with an exact one, stop.
            if exact || work.sweeps >= budget {
                return Ok(self.finish(&problem, Termination::Stalled, work));
            }
            work.sweeps += 1;
            let sw = problem.full_sweep(&self.x);
            if !sw.finite {
                return Ok(self.finish(&problem, Termination::NonFinite, work));
            }
            self.lin = problem.linearize(&sw);
            self.stability = self.verdict(&problem);
            exact = true;
        }
    }

    /// The hard real-time update: one exact linearisation at the last estimate, one Newton step.
    fn one_step(
        &mut self,
        problem: &Problem<'_, T, A, P, NODES>,
        mut work: crate::shooting::Work,
    ) -> Estimate<T, P> {
        work.sweeps = 1;
        let sw = problem.full_sweep(&self.x);
        if !sw.finite {
            return problem.finish(self.x, &self.lin, Termination::NonFinite, work);
        }
        self.lin = problem.linearize(&sw);
        self.stability = self.verdict(problem);
        let Some(red) = problem.reduce(&self.lin) else {
            return self.finish(problem, Termination::Singular, work);
        };
        if problem.converged(&self.x, &self.lin, &red, None).0 {
            return self.finish(problem, Termination::Converged, work);
        }
        let Some((du, dp)) = problem.step(&red, &self.x.p, T::zero()) else {
            return self.finish(problem, Termination::Singular, work);
        };
        work.iterations = 1;
        // The state after the step, predicted by the exact linearisation just taken.
        let lin = &mut self.lin;
        lin.e += lin.j_eu * du + lin.j_ep * dp;
        lin.rc += lin.j_cu * du + lin.j_cp * dp;
        lin.tip_position_m += lin.d_tip_u * du + lin.d_tip_p * dp;
        self.x = Point {
            u0: self.x.u0 + du,
            p: self.x.p + dp,
        };
        let mut out = problem.finish(self.x, &self.lin, Termination::IterationLimit, work);
        out.report.stability = self.stability;
        out
    }

    fn verdict(&self, problem: &Problem<'_, T, A, P, NODES>) -> Stability<T> {
        if problem.settings.check_stability {
            problem.stability(&self.x.p, &self.lin)
        } else {
            Stability::Unchecked
        }
    }

    fn finish(
        &self,
        problem: &Problem<'_, T, A, P, NODES>,
        termination: Termination,
        work: crate::shooting::Work,
    ) -> Estimate<T, P> {
        let mut out = problem.finish(self.x, &self.lin, termination, work);
        // Stability is judged at the last exact Jacobian.
        if out.report.termination.is_success() {
            out.report.stability = self.stability;
            if !self.stability.is_acceptable() {
                out.report.termination = Termination::Unstable;
            }
        }
        out
    }
}
