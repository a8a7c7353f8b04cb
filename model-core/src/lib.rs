//! Cosserat-rod statics of a cable-driven continuum robot, `no_std` and allocation-free.
//!
//! The model (thesis "Modeling and Verification of a Multi-section Continuum Robot", corrected in
//! `MODEL.md`): a backbone of sections in series under gravity, guide masses, point loads and a tip
//! load; cables through guides at a fixed offset. From a tip load, [`Model::solve`] finds the shape
//! and the cable lengths; from measured cable lengths, [`inverse`] finds the tip load.
//!
//! Where each equation lives:
//!
//! | concept | module |
//! | --- | --- |
//! | kinematics `r' = R v`, `R' = R hat(u)`; frame representations | [`kinematics`] |
//! | constitutive law, `v`, `u'` (eqs. 2.9-2.13) | [`constitutive`] |
//! | the scene: sections, guides, cables, base | [`rod`] |
//! | loads: tip load, point loads, loads that read the shape | [`loads`] |
//! | mass distribution, average and accurate guide mass (ch. 3.6-3.8) | [`mass`] |
//! | section transitions and point moments (ch. 3.4-3.5) | [`transitions`] |
//! | the integration grid (breakpoints, distal forces) | [`plan`] |
//! | the rod's equations behind one trait: dead loads, force as state, planar | `ode` |
//! | one RK4 sweep over the plan with tangents and observers | `sweep` |
//! | cable lengths (ch. 3.8.1), an observer of the sweep | `sweep::cables` |
//! | one damped Newton/LM, one load continuation, the stopping rules | `solve` |
//! | the forward entry points: solve, evaluate, shape | [`shooting`] |
//! | the planar reduction (in-plane loads) | [`planar`] |
//! | picking the cheapest variant that meets a tolerance | [`reduction`] |
//! | elastic stability of an equilibrium (Jacobi fields) | [`stability`] |
//! | the inverse: tip load from cable lengths | [`inverse`] |
//! | tendons that pull: routing, guide forces, path lengths, actuation | [`tendon`] |
//! | shape output | [`shape`] |
//!
//! The model's document, with every equation and the corrections to the thesis: `MODEL.md` at the
//! repository's root.
//!
//! SI units throughout; names carry them (`length_m`, `force_n`).

#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod constitutive;
pub mod error;
pub mod inverse;
pub mod kinematics;
pub mod loads;
pub mod mass;
pub mod model;
mod ode;
pub mod plan;
pub mod planar;
pub mod reduction;
pub mod report;
pub mod rod;
pub mod scalar;
pub mod shape;
pub mod shooting;
mod solve;
pub mod stability;
mod sweep;
pub mod tendon;
pub mod transitions;

pub use constitutive::{CrossSection, Material, Stiffness};
pub use error::ModelError;
pub use kinematics::{Attitude, LieGroup, Quaternion, RotationMatrix};
pub use loads::{NoShapeLoad, NodePose, PointLoad, PoseChange, ShapeLoad, TipLoad, Wrench};
pub use mass::GuideMass;
pub use model::Model;
pub use report::{MAX_FRAME_DRIFT, MAX_PHASE_PER_STEP_RAD, SolveReport, Termination};
pub use rod::{Cable, Guide, Rod, Section, StrainModel};
pub use scalar::Scalar;
pub use shape::ShapePoint;
pub use shooting::{Equilibrium, Evaluation, Neighbour, ShootingSettings, Start};
pub use stability::Stability;
pub use tendon::{
    DisplacementSettings, DisplacementSolve, MAX_TENDONS, MeasuredTensions, Sliding, Tendon,
    TendonEquilibrium, TendonEstimate, TendonInverseSettings, TendonQuality, TendonState, Tendons,
};

/// Most sections in a rod.
pub const MAX_SECTIONS: usize = 8;
/// Most cable guides: 16 on a controller; 128 with the `many-guides` feature (a host studying dense
/// guides, e.g. the tendon model's limit of continuous routing).
pub const MAX_GUIDES: usize = if cfg!(feature = "many-guides") {
    128
} else {
    16
};
/// Most cables (a cable's termination bit must fit a `u8`).
pub const MAX_CABLES: usize = 6;
/// Most point loads (hung masses, forces, moments).
pub const MAX_POINT_LOADS: usize = 8;
