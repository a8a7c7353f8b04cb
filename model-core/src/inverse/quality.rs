//! What the measurements say about the load at an estimate: identifiability from the data alone
//! (singular values, condition number, the weakest direction), uncertainty from data and prior
//! together (the posterior covariance, the force and tip standard deviations), and the verdict.

use nalgebra::{SMatrix, SVector, Vector3};

use super::basis::{ParamCount, Params};
use super::reduced::{Linearization, Problem, Reduced, Widen};
use crate::Scalar;
use crate::kinematics::Attitude;
use crate::scalar::product;

/// How well the measurements determine the load.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Determination {
    /// Every load component's standard deviation is within
    /// [`InverseSettings::max_force_std_n`](super::InverseSettings::max_force_std_n).
    Determined,
    /// Some direction of the load is poorly determined (its standard deviation exceeds the limit).
    Weak,
    /// The data cannot determine some direction at all (rank deficient: fewer independent cables
    /// than unknowns).
    Undetermined,
    /// No load of the model explains the measurements within three standard deviations.
    Inconsistent,
    /// Two or more loads far apart, both within the search's reach
    /// ([`crate::inverse::InverseSettings::scan_reach`]), explain the measurements about as well
    /// (three cables and three force components admit several exact fits): the answer is the one
    /// the prior prefers, and the data alone cannot tell. A `Weak` answer stays `Weak` when its
    /// deviations already reach the other answer (within three of them in every load parameter and
    /// tip coordinate).
    Ambiguous,
    /// The search for other answers ran out of its sweep budget
    /// ([`crate::inverse::InverseSettings::max_sweeps`]) before it could rule them out, or never
    /// ran (a cold estimate that did not converge): the answer may be one of several.
    Unverified,
}

impl Determination {
    /// This verdict or `to`, whichever vouches for the answer less (see [`Determination::doubt`]):
    /// a `Weak` answer where another answer may explain the data as well is `Ambiguous` (or
    /// `Unverified`): its deviations describe its own valley, not the other answer.
    pub fn at_best(self, to: Self) -> Self {
        if to.doubt() > self.doubt() { to } else { self }
    }

    /// How little the verdict vouches for the answer, from `Determined` (0) up:
    /// - `Weak`: one answer, wide in some direction, and its deviations say how wide;
    /// - `Unverified`: other answers were not ruled out;
    /// - `Ambiguous`: another answer, far from this one, explains the data as well;
    /// - `Undetermined`: some direction is not determined at all (infinite deviation, which
    ///   covers any other answer along it);
    /// - `Inconsistent`: no load of the model explains the data.
    pub fn doubt(self) -> u8 {
        match self {
            Self::Determined => 0,
            Self::Weak => 1,
            Self::Unverified => 2,
            Self::Ambiguous => 3,
            Self::Undetermined => 4,
            Self::Inconsistent => 5,
        }
    }
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

/// What the cable data alone determine at the estimate.
pub(super) struct DataOnly<T, const P: usize> {
    rank_deficient: bool,
    /// The parameters' covariance from the data alone (none when rank deficient).
    covariance: Option<SMatrix<T, P, P>>,
}

impl<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize> Problem<'_, T, A, P, NODES> {
    /// The fit's quality: identifiability from the data alone, uncertainty from data and prior
    /// together.
    pub(super) fn quality(
        &self,
        lin: &Linearization<T, P>,
        red: Option<&Reduced<T, P>>,
        widen: Option<&Widen<T, P>>,
    ) -> Quality<T, P>
    where
        Params: ParamCount<T, P>,
    {
        let inv_std = T::one() / self.length_std_m;
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
            // The inverse information from a QR factorisation of the whitened system `[G / s; W]`,
            // not from `G^T G / s^2 + W^2`: near the buckling load G's entries are huge and the
            // normal matrix loses the prior's rows to rounding.
            match Params::covariance(&red.g, &self.prior_weight) {
                Some(c) => c,
                None => return quality,
            }
        };
        let covariance = match widen {
            Some(w) => {
                let along = (w.direction.transpose() * covariance * w.direction).x;
                let extra = w.std * w.std - along;
                if extra > T::zero() {
                    covariance + w.direction * w.direction.transpose() * extra
                } else {
                    covariance
                }
            }
            None => covariance,
        };
        // A covariance that is not finite is no posterior: its deviations' `max(0)` would read NaN
        // as zero spread.
        if !crate::scalar::all_finite(&covariance) {
            return quality;
        }
        quality.param_std = covariance.diagonal().map(|x| x.max(T::zero()).sqrt());
        quality.force_std_n = deviations(&self.basis.force_n, &covariance, T::zero());
        // The tip moves with p directly and through the re-solved shape: dtip/dp = T_p - T_u J_eu^-1 J_ep.
        let d_tip = lin.d_tip_p - product(&lin.d_tip_u, &red.a);
        let model_tip = self.model_tip_std_m * self.model_tip_std_m;
        quality.tip_std_m = deviations(&d_tip, &covariance, model_tip);
        let moment_std = deviations(&self.basis.moment_nm, &covariance, T::zero());
        let worst = quality.force_std_n.max().max(moment_std.max());
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
    fn data_only(&self, red: &Reduced<T, P>, _: &mut Quality<T, P>) -> Option<DataOnly<T, P>>
    where
        Params: ParamCount<T, P>,
    {
        let covariance = (self.cables >= P)
            .then(|| Params::covariance(&red.g, &SVector::zeros()))
            .flatten();
        Some(DataOnly {
            rank_deficient: covariance.is_none(),
            covariance,
        })
    }
}

/// The standard deviations of `a p` for parameters of covariance `c`, each with `extra` added to its
/// variance: the square roots of the diagonal of `a c a^T` (the diagonal alone).
// Out of line: one copy for the force, the moment and the tip.
#[inline(never)]
fn deviations<T: Scalar, const P: usize>(
    a: &SMatrix<T, 3, P>,
    c: &SMatrix<T, P, P>,
    extra: T,
) -> Vector3<T> {
    (a * c)
        .component_mul(a)
        .column_sum()
        .map(|v| (v.max(T::zero()) + extra).sqrt())
}

#[cfg(test)]
mod tests {
    use super::Determination::{self, *};

    const ALL: [Determination; 6] = [
        Determined,
        Weak,
        Unverified,
        Ambiguous,
        Undetermined,
        Inconsistent,
    ];

    #[test]
    fn a_verdict_is_only_ever_lowered() {
        for a in ALL {
            for b in ALL {
                let lowered = a.at_best(b);
                assert!(
                    lowered == a || lowered == b,
                    "{a:?} at best {b:?}: {lowered:?}"
                );
                assert!(lowered.doubt() >= a.doubt().max(b.doubt()));
                assert_eq!(lowered, b.at_best(a), "{a:?}, {b:?}");
            }
        }
        // A wide answer that another may explain as well says so (it stayed `Weak`, which the
        // firmware publishes, and lost the doubt along a chain of warm updates).
        assert_eq!(Weak.at_best(Ambiguous), Ambiguous);
        assert_eq!(Weak.at_best(Unverified), Unverified);
        assert_eq!(Ambiguous.at_best(Unverified), Ambiguous);
        assert_eq!(Undetermined.at_best(Ambiguous), Undetermined);
        assert_eq!(Inconsistent.at_best(Unverified), Inconsistent);
        assert_eq!(Determined.at_best(Weak), Weak);
    }
}
