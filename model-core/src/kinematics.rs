//! Kinematics of the backbone frame (thesis eqs. 2.3 and 2.4): `r' = R v`, `R' = R hat(u)`.
//!
//! The position is integrated as a vector. The orientation has three interchangeable
//! representations, all fourth order with the classical RK4 tableau; they differ in cost and in
//! how they keep `R` a rotation, which matters in `f32`:
//!
//! - [`RotationMatrix`]: RK4 on the nine entries of `R`, as in the thesis's MATLAB code. Cheapest
//!   per stage, but `R` drifts from orthonormal.
//! - [`Quaternion`]: RK4 on a quaternion, normalised after every step.
//! - [`LieGroup`]: Runge-Kutta-Munthe-Kaas (RKMK4) on SO(3): every stage is `R0 exp(theta)`, an
//!   exact rotation, but the frame is a product of rounded matrices that is never re-orthonormalised,
//!   so in `f32` its drift grows with the step count (about 3.6e-4 at 10^4 steps per section,
//!   `report/f32_limits.md`); costs an exponential map per stage.

use core::fmt::Debug;

use nalgebra::{Matrix3, Quaternion as Quat, Vector3};

use crate::Scalar;

/// A representation of the backbone frame along `s`, integrated with the RK4 tableau.
///
/// `stage(base, k, h)` is the RK4 stage state `base (+) h k`; `combine` the final weighted update.
pub trait Attitude<T: Scalar>: Copy + Debug {
    /// What a stage contributes: the derivative in whatever coordinates the representation uses.
    type Rate: Copy;
    /// A short name for reports.
    const NAME: &'static str;
    /// From a rotation matrix (assumed orthonormal).
    fn from_matrix(m: &Matrix3<T>) -> Self;
    /// The rotation matrix (local to global).
    fn matrix(&self) -> Matrix3<T>;
    /// The stage derivative for body angular rate `u`; `m` is `self.matrix()`, already at hand.
    fn rate(&self, m: &Matrix3<T>, u: &Vector3<T>) -> Self::Rate;
    /// The stage state `base (+) h k`.
    fn stage(base: &Self, k: &Self::Rate, h: T) -> Self;
    /// The step's result from the four stage rates with weights 1/6, 1/3, 1/3, 1/6.
    fn combine(base: &Self, k: &[Self::Rate; 4], h: T) -> Self;
}

#[inline]
fn rk4_weights<T: Scalar>(h: T) -> (T, T) {
    let sixth = h / T::lit(6.0);
    (sixth, sixth + sixth)
}

/// The rotation matrix itself, integrated entry-wise (no re-orthonormalisation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationMatrix<T: Scalar>(pub Matrix3<T>);

impl<T: Scalar> Attitude<T> for RotationMatrix<T> {
    type Rate = Matrix3<T>;
    const NAME: &'static str = "rotation-matrix RK4";
    #[inline]
    fn from_matrix(m: &Matrix3<T>) -> Self {
        Self(*m)
    }
    #[inline]
    fn matrix(&self) -> Matrix3<T> {
        self.0
    }
    #[inline]
    fn rate(&self, m: &Matrix3<T>, u: &Vector3<T>) -> Matrix3<T> {
        m * u.cross_matrix()
    }
    #[inline]
    fn stage(base: &Self, k: &Matrix3<T>, h: T) -> Self {
        Self(base.0 + k * h)
    }
    #[inline]
    fn combine(base: &Self, k: &[Matrix3<T>; 4], h: T) -> Self {
        let (w1, w2) = rk4_weights(h);
        Self(base.0 + (k[0] + k[3]) * w1 + (k[1] + k[2]) * w2)
    }
}

/// A quaternion `(w, x, y, z)`, normalised after each step (stage values are left unnormalised and
/// mapped to a rotation homogeneously, which is the same as normalising them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion<T: Scalar>(pub Quat<T>);

impl<T: Scalar> Attitude<T> for Quaternion<T> {
    type Rate = Quat<T>;
    const NAME: &'static str = "quaternion RK4";
    fn from_matrix(m: &Matrix3<T>) -> Self {
        let rot = nalgebra::Rotation3::from_matrix_unchecked(*m);
        Self(*nalgebra::UnitQuaternion::from_rotation_matrix(&rot).quaternion())
    }
    #[inline]
    fn matrix(&self) -> Matrix3<T> {
        let q = &self.0;
        let (w, x, y, z) = (q.w, q.i, q.j, q.k);
        let norm2 = w * w + x * x + y * y + z * z;
        let s = T::lit(2.0) / norm2;
        let (xx, yy, zz) = (x * x * s, y * y * s, z * z * s);
        let (xy, xz, yz) = (x * y * s, x * z * s, y * z * s);
        let (wx, wy, wz) = (w * x * s, w * y * s, w * z * s);
        let one = T::one();
        Matrix3::new(
            one - yy - zz,
            xy - wz,
            xz + wy,
            xy + wz,
            one - xx - zz,
            yz - wx,
            xz - wy,
            yz + wx,
            one - xx - yy,
        )
    }
    #[inline]
    fn rate(&self, _m: &Matrix3<T>, u: &Vector3<T>) -> Quat<T> {
        // q' = q (0, u) / 2: body-frame angular rate multiplies on the right.
        let q = &self.0;
        let half = T::lit(0.5);
        let qv = q.imag();
        let w = -qv.dot(u) * half;
        let v = (u * q.w + qv.cross(u)) * half;
        Quat::new(w, v.x, v.y, v.z)
    }
    #[inline]
    fn stage(base: &Self, k: &Quat<T>, h: T) -> Self {
        Self(base.0 + k * h)
    }
    #[inline]
    fn combine(base: &Self, k: &[Quat<T>; 4], h: T) -> Self {
        let (w1, w2) = rk4_weights(h);
        let q = base.0 + (k[0] + k[3]) * w1 + (k[1] + k[2]) * w2;
        let norm = q.norm_squared().sqrt_hot();
        Self(q / norm)
    }
}

/// RKMK4 on SO(3): `R = R_base exp(hat(theta))` with `theta' = dexp^-1(u)`, truncated after the
/// second commutator (enough for order four). `theta` is the offset from the step's base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LieGroup<T: Scalar> {
    /// The frame.
    pub matrix: Matrix3<T>,
    theta: Vector3<T>,
}

impl<T: Scalar> Attitude<T> for LieGroup<T> {
    type Rate = Vector3<T>;
    const NAME: &'static str = "Lie-group RKMK4";
    #[inline]
    fn from_matrix(m: &Matrix3<T>) -> Self {
        Self {
            matrix: *m,
            theta: Vector3::zeros(),
        }
    }
    #[inline]
    fn matrix(&self) -> Matrix3<T> {
        self.matrix
    }
    #[inline]
    fn rate(&self, _m: &Matrix3<T>, u: &Vector3<T>) -> Vector3<T> {
        // Right-trivialised dexp^-1_{-theta}(u) = u + theta x u / 2 + theta x (theta x u) / 12 + ...
        let tu = self.theta.cross(u);
        u + tu * T::lit(0.5) + self.theta.cross(&tu) / T::lit(12.0)
    }
    #[inline]
    fn stage(base: &Self, k: &Vector3<T>, h: T) -> Self {
        let theta = k * h;
        Self {
            matrix: base.matrix * exp_so3(&theta),
            theta,
        }
    }
    #[inline]
    fn combine(base: &Self, k: &[Vector3<T>; 4], h: T) -> Self {
        let (w1, w2) = rk4_weights(h);
        let theta = (k[0] + k[3]) * w1 + (k[1] + k[2]) * w2;
        Self {
            matrix: base.matrix * exp_so3(&theta),
            theta: Vector3::zeros(),
        }
    }
}

/// The exponential map of so(3) (Rodrigues' formula), with a series near zero.
pub fn exp_so3<T: Scalar>(theta: &Vector3<T>) -> Matrix3<T> {
    let angle2 = theta.norm_squared();
    let (a, b) = if angle2 < T::lit(1e-4) {
        // sin(x)/x and (1 - cos x)/x^2 to O(x^6): far below f64 rounding at this size.
        let a = T::one() - angle2 / T::lit(6.0) * (T::one() - angle2 / T::lit(20.0));
        let b = T::lit(0.5) - angle2 / T::lit(24.0) * (T::one() - angle2 / T::lit(30.0));
        (a, b)
    } else {
        let angle = angle2.sqrt_hot();
        let (s, c) = angle.sin_cos_hot();
        (s / angle, (T::one() - c) / angle2)
    };
    let k = theta.cross_matrix();
    Matrix3::identity() + k * a + k * k * b
}

/// The rotation vector of a rotation matrix near the identity (the small-angle `vee` of its skew part).
/// Used for orientation differences between nearby frames.
#[inline]
pub fn small_rotation_vector<T: Scalar>(m: &Matrix3<T>) -> Vector3<T> {
    let half = T::lit(0.5);
    Vector3::new(
        (m.m32 - m.m23) * half,
        (m.m13 - m.m31) * half,
        (m.m21 - m.m12) * half,
    )
}

/// How far `R` is from a rotation: the Frobenius norm of `R^T R - I`.
pub fn orthonormality_error<T: Scalar>(m: &Matrix3<T>) -> T {
    (m.transpose() * m - Matrix3::identity()).norm()
}
