//! The variants of the model the study compares: arithmetic (f64, f32 with libm, f32 with
//! micromath), frame representation, reduction (3D Cosserat, Kirchhoff, planar) and steps per section.

use serde::{Deserialize, Serialize};

/// Steps per section of the full study.
pub const FULL_STEPS: [u16; 10] = [2, 3, 5, 10, 20, 50, 100, 200, 500, 1000];
/// Steps per section of the quick study (CI).
pub const QUICK_STEPS: [u16; 3] = [5, 20, 100];

/// The scalar type and the functions on the integrator's hot path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Arithmetic {
    /// f64 (exact sqrt, sin, cos).
    F64,
    /// f32 with the exact (libm / hardware) sqrt, sin, cos.
    F32,
    /// f32 with micromath's approximations (model-core's `fast-math` feature).
    F32Micromath,
}

impl Arithmetic {
    /// `f64` or `f32`.
    pub fn precision(self) -> &'static str {
        match self {
            Self::F64 => "f64",
            Self::F32 | Self::F32Micromath => "f32",
        }
    }

    /// Where sqrt, sin and cos come from.
    pub fn math(self) -> &'static str {
        match self {
            Self::F64 | Self::F32 => "libm",
            Self::F32Micromath => "micromath",
        }
    }

    /// A short label.
    pub fn label(self) -> &'static str {
        match self {
            Self::F64 => "f64",
            Self::F32 => "f32",
            Self::F32Micromath => "f32 micromath",
        }
    }
}

/// How the frame is integrated (`model_core::kinematics`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Frame {
    /// RK4 on a quaternion, normalised every step (the default).
    Quaternion,
    /// RK4 on the nine entries of `R`.
    RotationMatrix,
    /// RKMK4 on SO(3): an exponential map per stage.
    LieGroup,
}

impl Frame {
    /// A short label.
    pub fn label(self) -> &'static str {
        match self {
            Self::Quaternion => "quaternion",
            Self::RotationMatrix => "rotation matrix",
            Self::LieGroup => "Lie group",
        }
    }
}

/// Which model: the full 3D Cosserat rod or one of `model_core::reduction`'s reductions, or, for
/// the tendon scenes, one of the tendon models (`model_core::TendonModel`, MODEL.md §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Reduction {
    /// The full model: 3D, shearable and extensible.
    Cosserat3d,
    /// 3D, inextensible and unshearable.
    Kirchhoff3d,
    /// The planar reduction (`PlanarModel`), shearable and extensible.
    Planar,
    /// The planar reduction of the Kirchhoff rod.
    PlanarKirchhoff,
    /// Tendons in chords between the guide holes (`Model::solve_tendons`): the tendon reference.
    TendonDiscrete,
    /// Tendons routed along the backbone (`Model::solve_tendons_continuous`, Rucker & Webster).
    TendonContinuous,
    /// Piecewise constant curvature from the tendons' moments (`Model::solve_tendons_pcc_ignoring_loads`: gravity and loads taken as its error).
    TendonPcc,
}

impl Reduction {
    /// Every reduction of the dead-load model, the full model first.
    pub const ALL: [Self; 4] = [
        Self::Cosserat3d,
        Self::Kirchhoff3d,
        Self::Planar,
        Self::PlanarKirchhoff,
    ];

    /// Through `PlanarModel`.
    pub fn planar(self) -> bool {
        matches!(self, Self::Planar | Self::PlanarKirchhoff)
    }

    /// With `StrainModel::Kirchhoff`.
    pub fn kirchhoff(self) -> bool {
        matches!(self, Self::Kirchhoff3d | Self::PlanarKirchhoff)
    }

    /// The reduction of `model_core::reduction::Variant`'s flags.
    pub fn of(planar: bool, kirchhoff: bool) -> Self {
        match (planar, kirchhoff) {
            (false, false) => Self::Cosserat3d,
            (false, true) => Self::Kirchhoff3d,
            (true, false) => Self::Planar,
            (true, true) => Self::PlanarKirchhoff,
        }
    }

    /// A short label.
    pub fn label(self) -> &'static str {
        match self {
            Self::Cosserat3d => "3D",
            Self::Kirchhoff3d => "3D Kirchhoff",
            Self::Planar => "planar",
            Self::PlanarKirchhoff => "planar Kirchhoff",
            Self::TendonDiscrete => "discrete guides",
            Self::TendonContinuous => "continuous routing",
            Self::TendonPcc => "PCC",
        }
    }

    /// One of the tendon models.
    pub fn tendon(self) -> bool {
        matches!(
            self,
            Self::TendonDiscrete | Self::TendonContinuous | Self::TendonPcc
        )
    }
}

/// A series of the study: everything but the step count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Family {
    /// Scalar and math functions.
    pub arithmetic: Arithmetic,
    /// Frame representation.
    pub frame: Frame,
    /// Model reduction.
    pub reduction: Reduction,
}

impl Family {
    /// The reference's family: f64, quaternion, full 3D model.
    pub const REFERENCE: Self = Self {
        arithmetic: Arithmetic::F64,
        frame: Frame::Quaternion,
        reduction: Reduction::Cosserat3d,
    };

    /// A label such as "f32 Lie group 3D" (the frame is left out of the planar reduction's, which
    /// integrates no frame, and of the tendon models', which the study runs with the quaternion only).
    pub fn label(&self) -> String {
        if self.reduction.planar() || self.reduction.tendon() {
            format!("{} {}", self.arithmetic.label(), self.reduction.label())
        } else {
            format!(
                "{} {} {}",
                self.arithmetic.label(),
                self.frame.label(),
                self.reduction.label()
            )
        }
    }
}

/// The families studied for each arithmetic: the three frames of the full model, then the
/// reductions with the quaternion frame (the planar reduction integrates no frame but the
/// quaternion's part in the plane).
pub fn families(arithmetics: &[Arithmetic], planar_allowed: bool) -> Vec<Family> {
    let mut out = Vec::new();
    for &arithmetic in arithmetics {
        let with = |frame, reduction| Family {
            arithmetic,
            frame,
            reduction,
        };
        out.push(with(Frame::Quaternion, Reduction::Cosserat3d));
        out.push(with(Frame::RotationMatrix, Reduction::Cosserat3d));
        out.push(with(Frame::LieGroup, Reduction::Cosserat3d));
        out.push(with(Frame::Quaternion, Reduction::Kirchhoff3d));
        if planar_allowed {
            out.push(with(Frame::Quaternion, Reduction::Planar));
            out.push(with(Frame::Quaternion, Reduction::PlanarKirchhoff));
        }
    }
    out
}
