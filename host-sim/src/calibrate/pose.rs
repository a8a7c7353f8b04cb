//! The base pose: a rigid registration of the measurement frame (a motion-capture system's, a
//! ruler's) to the scene's frame. A point `p` of the scene's frame is `R p + t` in the measurement
//! frame, `R` a rotation given by its rotation vector (axis times angle, rad) and `t` in m.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// A rigid transformation from the scene's frame to the measurement frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// The rotation vector of `R`, rad.
    pub rotation_rad: Vector3<f64>,
    /// The translation `t`, m.
    pub translation_m: Vector3<f64>,
}

impl Pose {
    /// The identity: the data are in the scene's frame.
    pub fn identity() -> Self {
        Self {
            rotation_rad: Vector3::zeros(),
            translation_m: Vector3::zeros(),
        }
    }

    /// `R`.
    pub fn rotation(&self) -> Rotation3<f64> {
        Rotation3::from_scaled_axis(self.rotation_rad)
    }

    /// A point of the scene's frame in the measurement frame, m.
    pub fn to_measurement(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation() * p + self.translation_m
    }

    /// A vector (a force) of the measurement frame in the scene's frame.
    pub fn vector_to_scene(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.rotation().inverse() * v
    }

    /// The pose that carries the points `from` (scene frame) closest onto `to` (measurement frame)
    /// in the weighted least-squares sense (Kabsch: the SVD of the weighted cross-covariance, with
    /// the sign fixed so that `R` is a rotation). `None` for fewer than three points or points on a
    /// line, which do not fix a rotation.
    pub fn register(from: &[Vector3<f64>], to: &[Vector3<f64>], weights: &[f64]) -> Option<Self> {
        let total: f64 = weights.iter().sum();
        if from.len() < 3 || from.len() != to.len() || from.len() != weights.len() || total <= 0.0 {
            return None;
        }
        let centroid = |points: &[Vector3<f64>]| {
            points
                .iter()
                .zip(weights)
                .fold(Vector3::zeros(), |acc, (p, w)| acc + p * *w)
                / total
        };
        let (cf, ct) = (centroid(from), centroid(to));
        let mut h = Matrix3::zeros();
        for ((p, q), w) in from.iter().zip(to).zip(weights) {
            h += (p - cf) * (q - ct).transpose() * *w;
        }
        let svd = h.svd(true, true);
        let (u, v_t) = (svd.u?, svd.v_t?);
        // Points on a line leave a rotation about it free: two singular values vanish.
        let s = svd.singular_values;
        if s.max().is_nan() || s.max() <= 0.0 || s[1] <= 1e-9 * s.max() {
            return None;
        }
        let v = v_t.transpose();
        let d = (v * u.transpose()).determinant().signum();
        let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
        let rotation = Rotation3::from_matrix_unchecked(r);
        Some(Self {
            rotation_rad: rotation.scaled_axis(),
            translation_m: ct - rotation * cf,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registration_recovers_a_known_pose() {
        let pose = Pose {
            rotation_rad: Vector3::new(0.3, -0.2, 1.1),
            translation_m: Vector3::new(0.5, -1.0, 0.25),
        };
        let from = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.2, 0.01, 0.0),
            Vector3::new(0.35, -0.05, 0.02),
            Vector3::new(0.1, 0.0, 0.03),
        ];
        let to: Vec<_> = from.iter().map(|p| pose.to_measurement(p)).collect();
        let found = Pose::register(&from, &to, &[1.0; 4]).expect("registered");
        assert!((found.rotation_rad - pose.rotation_rad).norm() < 1e-12);
        assert!((found.translation_m - pose.translation_m).norm() < 1e-12);
        // On a line the rotation about it is free: no registration.
        let line = [Vector3::x(), Vector3::x() * 2.0, Vector3::x() * 3.0];
        assert_eq!(Pose::register(&line, &line, &[1.0; 3]), None);
    }
}
