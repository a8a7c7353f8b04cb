//! Loads on the rod.
//!
//! - Dead loads, fixed in the global frame: the tip load ([`TipLoad`], the forward solve's input) and
//!   point loads on the backbone ([`PointLoad`]: hung masses, forces, moments; part of the scene).
//!   Together with gravity they fix the internal force `n(s)` before any sweep (`plan.rs` sums them),
//!   which is the fast path of the rod equations (`ode/dead_load.rs`).
//! - Loads that read the shape ([`ShapeLoad`]), in the spirit of PyElastica's forcing classes: at
//!   each node of the plan they see the pose there and return a force and a moment. A new such load
//!   is a new type implementing the trait; the sweep, the plan and the solver do not change. The rod
//!   equations with the internal force and moment as states (`ode/force_state.rs`) apply them, as
//!   jumps `n(s+) = n(s-) - F`, `m(s+) = m(s-) - M` at the node, with their linearisation in the
//!   shooting Jacobian.

use nalgebra::{Matrix3, Vector3};

use crate::Scalar;
use crate::error::{ModelError, finite_vec};

/// The load at the tip, global frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipLoad<T> {
    /// Force, N.
    pub force_n: Vector3<T>,
    /// Moment, N m.
    pub moment_nm: Vector3<T>,
}

impl<T: Scalar> TipLoad<T> {
    /// No tip load.
    pub fn zero() -> Self {
        Self {
            force_n: Vector3::zeros(),
            moment_nm: Vector3::zeros(),
        }
    }
    /// A tip force only.
    pub fn force(force_n: Vector3<T>) -> Self {
        Self {
            force_n,
            moment_nm: Vector3::zeros(),
        }
    }
    /// A tip moment only.
    pub fn moment(moment_nm: Vector3<T>) -> Self {
        Self {
            force_n: Vector3::zeros(),
            moment_nm,
        }
    }
    pub(crate) fn validate(&self) -> Result<(), ModelError> {
        finite_vec(&self.force_n, "tip force")?;
        finite_vec(&self.moment_nm, "tip moment")
    }
}

/// A load at one point of the backbone: a hung mass, a force and a moment, all fixed in the global
/// frame (dead loads). A load at the tip adds to the tip load.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLoad<T> {
    /// Arc length, m.
    pub s_m: T,
    /// Hung mass, kg (its weight follows gravity).
    pub mass_kg: T,
    /// Force, N, global frame.
    pub force_n: Vector3<T>,
    /// Moment, N m, global frame.
    pub moment_nm: Vector3<T>,
}

impl<T: Scalar> PointLoad<T> {
    /// A mass hung at `s_m`.
    pub fn mass(s_m: T, mass_kg: T) -> Self {
        Self {
            s_m,
            mass_kg,
            force_n: Vector3::zeros(),
            moment_nm: Vector3::zeros(),
        }
    }
    /// A force at `s_m`.
    pub fn force(s_m: T, force_n: Vector3<T>) -> Self {
        Self {
            s_m,
            mass_kg: T::zero(),
            force_n,
            moment_nm: Vector3::zeros(),
        }
    }
    /// A moment at `s_m`.
    pub fn moment(s_m: T, moment_nm: Vector3<T>) -> Self {
        Self {
            s_m,
            mass_kg: T::zero(),
            force_n: Vector3::zeros(),
            moment_nm,
        }
    }
}

/// Where a load that reads the shape is evaluated: one node of the plan and the pose there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodePose<T> {
    /// Reference arc length, m.
    pub s_m: T,
    /// The guide centred at this node (index into the rod's guides), if any.
    pub guide: Option<usize>,
    /// Whether the node is the tip.
    pub tip: bool,
    /// Position of the backbone, m, global frame.
    pub position_m: Vector3<T>,
    /// Frame: columns are the local x, y, z (tangent) axes in global coordinates.
    pub rotation: Matrix3<T>,
}

/// A small change of pose at a node: `r -> r + dr`, `R -> R (I + hat(dtheta))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseChange<T> {
    /// Change of position, m, global frame.
    pub position_m: Vector3<T>,
    /// Rotation, rad, body frame.
    pub rotation_rad: Vector3<T>,
}

/// A force, N, and a moment about the backbone point, N m, both global frame, applied to the rod.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wrench<T> {
    /// Force, N.
    pub force_n: Vector3<T>,
    /// Moment about the backbone point, N m (a force applied at an offset `R d` adds `(R d) x F`).
    pub moment_nm: Vector3<T>,
}

impl<T: Scalar> Wrench<T> {
    /// No force, no moment.
    pub fn zero() -> Self {
        Self {
            force_n: Vector3::zeros(),
            moment_nm: Vector3::zeros(),
        }
    }
}

/// A load that reads the shape, applied at nodes of the plan (guides and the tip are always nodes).
///
/// Implementations return zero where they do not act. Every value is scaled by `load_scale`, the
/// load continuation's parameter (0: unloaded rod, 1: the full load), so that a cold solve can follow
/// the branch connected to the unloaded rod.
pub trait ShapeLoad<T: Scalar> {
    /// The wrench applied to the rod at `node`.
    fn wrench(&self, node: &NodePose<T>, load_scale: T) -> Wrench<T>;
    /// The first-order change of [`ShapeLoad::wrench`] for a change `change` of the pose at `node`.
    fn wrench_change(&self, node: &NodePose<T>, load_scale: T, change: &PoseChange<T>)
    -> Wrench<T>;
}

/// No load that reads the shape: the internal-force-as-state equations under dead loads only (the
/// same equilibrium as the closed-form fast path, at more cost).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoShapeLoad;

impl<T: Scalar> ShapeLoad<T> for NoShapeLoad {
    #[inline]
    fn wrench(&self, _: &NodePose<T>, _: T) -> Wrench<T> {
        Wrench::zero()
    }
    #[inline]
    fn wrench_change(&self, _: &NodePose<T>, _: T, _: &PoseChange<T>) -> Wrench<T> {
        Wrench::zero()
    }
}
