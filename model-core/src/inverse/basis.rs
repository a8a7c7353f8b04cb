//! The load the inverse estimates, as a function of its unknown parameters (`LoadBasis`), and the
//! prior on those parameters in units of the rod's buckling scale.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::error::{ModelError, finite_vec, positive};
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::{MAX_CABLES, Scalar};

/// The number of load parameters an estimate can have (1 to 3). nalgebra's singular value
/// decomposition behind [`Quality`](super::Quality) needs a concrete size, so each is listed here.
pub trait ParamCount<T: Scalar, const P: usize> {
    /// Singular values and right singular vectors (columns of `V`) of a `MAX_CABLES x P` matrix,
    /// `None` if the decomposition does not converge.
    #[cfg(feature = "identifiability")]
    fn svd(m: SMatrix<T, MAX_CABLES, P>) -> Option<(SVector<T, P>, SMatrix<T, P, P>)>;

    /// `(G^T G + diag(w)^2)^-1` from a QR factorisation of the stacked `[G; diag(w)]` (`R^-1 R^-T`),
    /// which keeps the precision the normal equations lose when `G`'s entries dwarf `w`. `None` when
    /// `R` is singular.
    fn covariance(g: &SMatrix<T, MAX_CABLES, P>, w: &SVector<T, P>) -> Option<SMatrix<T, P, P>>;
}

/// The marker implementing [`ParamCount`] for the supported sizes.
#[derive(Clone, Copy, Debug)]
pub struct Params;

macro_rules! param_count {
    ($($p:literal),*) => {$(
        impl<T: Scalar> ParamCount<T, $p> for Params {
            fn covariance(
                g: &SMatrix<T, MAX_CABLES, $p>,
                w: &SVector<T, $p>,
            ) -> Option<SMatrix<T, $p, $p>> {
                let mut stacked = SMatrix::<T, { MAX_CABLES + $p }, $p>::zeros();
                stacked.fixed_view_mut::<MAX_CABLES, $p>(0, 0).copy_from(g);
                stacked
                    .fixed_view_mut::<$p, $p>(MAX_CABLES, 0)
                    .copy_from(&SMatrix::<T, $p, $p>::from_diagonal(w));
                let r = stacked.qr().r();
                let r_inv = r.solve_upper_triangular(&SMatrix::<T, $p, $p>::identity())?;
                let covariance = r_inv * r_inv.transpose();
                crate::scalar::all_finite(&covariance).then_some(covariance)
            }

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

    pub(super) fn validate(&self) -> Result<(), ModelError> {
        self.offset.validate()?;
        if !crate::scalar::all_finite(&self.force_n) || !crate::scalar::all_finite(&self.moment_nm)
        {
            return Err(ModelError::NonFinite("load basis"));
        }
        Ok(())
    }
}

/// `1 / prior std` for each parameter for a prior of `std_scale` buckling scales.
pub(super) fn prior_weight_for<T: Scalar, A: Attitude<T>, const P: usize, const NODES: usize>(
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
