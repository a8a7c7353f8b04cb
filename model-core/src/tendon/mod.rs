//! Tendons that pull: cables whose tension bends the backbone (MODEL.md §6).
//!
//! A tendon runs in straight chords from its fixed hole in the base plate (`s = 0`, not part of the
//! rod) through the hole at the same body offset in every guide up to the guide where it terminates.
//! Frictionless, with one tension along its whole length, it pulls each guide's hole toward both
//! neighbouring holes, and its termination toward the previous one: point forces at the holes and
//! their moments about the backbone (`guide_force.rs`). Those forces read the shape, including the
//! next guide's pose, so the rod equations with the internal force as state carry them with an
//! implicit jump at each guide (`crate::ode` `tendon.rs`).
//!
//! | concept | file |
//! | --- | --- |
//! | a tendon's routing and its compliance; a validated set of tendons | here |
//! | the chord forces at a guide and their linearisation | `guide_force.rs` |
//! | path lengths from the guides' poses | `paths.rs` |
//! | the forward solve from tensions | `forward.rs` |
//! | how paths and tip move with tensions and tip force | `sensitivity.rs` |
//! | the forward solve from spool displacements: compliance and slack | `actuation.rs` |
//! | the complementarity of tension and slack: its residual and its step | `complementarity.rs` |
//! | the inverse: tensions, tip force and shape from displacements (and tensions) | `inverse.rs` |
//! | continuous routing (Rucker-Webster): the cross-section's law with tendons along it | `distributed.rs` |
//! | continuous routing: the forward solve and its path lengths | `continuous.rs` |
//! | piecewise constant curvature: arcs from the tendons' moments, closed form | `pcc.rs` |
//! | the cheapest of the three within a tolerance of the discrete guides | `choose.rs` |

mod actuation;
mod choose;
mod complementarity;
mod continuous;
pub(crate) mod distributed;
mod forward;
pub(crate) mod guide_force;
mod inverse;
mod joint_step;
mod paths;
mod pcc;
mod sensitivity;

pub use actuation::{DisplacementSettings, DisplacementSolve, TendonState};
pub use choose::{
    MAX_TENDON_TRIALS, PCC_COST, TendonChoice, TendonModel, TendonTrial, TendonVariant,
    choose_tendons, tendon_step_cost,
};
pub use forward::TendonEquilibrium;
pub use inverse::{MeasuredTensions, TendonEstimate, TendonInverseSettings, TendonQuality};

use heapless::Vec;
use nalgebra::{Vector2, Vector3};

use crate::Scalar;
use crate::error::{ModelError, finite, non_negative, positive};
use crate::kinematics::Attitude;
use crate::model::Model;

/// Most tendons (three per section on four sections).
pub const MAX_TENDONS: usize = 12;

/// One tendon: its hole in every guide, where it ends, and what lies between the spool and the base
/// plate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tendon<T> {
    /// The hole in each guide's cross-section (and in the base plate), local frame `(x, y)`, m.
    pub hole_m: Vector2<T>,
    /// Arc length of the guide where it terminates, m (must be a guide's centre).
    pub end_m: T,
    /// Axial stiffness `E_t A_t` of the tendon, N; `None` for an inextensible tendon.
    pub axial_stiffness_n: Option<T>,
    /// Free length from the spool to the base plate's hole, m (it stretches under tension too).
    pub feed_length_m: T,
    /// Coulomb friction coefficient between the tendon and each hole it passes (the base plate's
    /// and the guides'), for the capstan law; zero: frictionless.
    pub friction_coefficient: T,
}

impl<T: Scalar> Tendon<T> {
    /// An inextensible tendon whose hole is `radius_m` from the backbone at `angle_rad` about the
    /// local z axis, from local x, ending at the guide at `end_m`.
    pub fn at_angle(angle_rad: T, radius_m: T, end_m: T) -> Self {
        let (s, c) = angle_rad.sin_cos();
        Self {
            hole_m: Vector2::new(c, s) * radius_m,
            end_m,
            axial_stiffness_n: None,
            feed_length_m: T::zero(),
            friction_coefficient: T::zero(),
        }
    }

    /// The hole's offset in the local frame, m.
    pub fn offset_local_m(&self) -> Vector3<T> {
        Vector3::new(self.hole_m.x, self.hole_m.y, T::zero())
    }

    /// The unstretched length of a stretch of this tendon `length_m` long under `tension_n`:
    /// `l / (1 + tau / E_t A_t)` (the length itself for an inextensible tendon).
    pub(crate) fn unstretched_m(&self, length_m: T, tension_n: T) -> T {
        match self.axial_stiffness_n {
            Some(k) => length_m / (T::one() + tension_n / k),
            None => length_m,
        }
    }

    /// [`Tendon::unstretched_m`]'s change per unit tension, m/N:
    /// `-l / (E_t A_t (1 + tau / E_t A_t)^2)` (zero for an inextensible tendon).
    pub(crate) fn d_unstretched_d_tension(&self, length_m: T, tension_n: T) -> T {
        match self.axial_stiffness_n {
            Some(k) => {
                let f = T::one() + tension_n / k;
                -length_m / (k * f * f)
            }
            None => T::zero(),
        }
    }
}

/// Which way a tendon slides through its holes, which sets the sign of the capstan friction: the
/// tension falls away from the spool while it pulls in, and rises while it pays out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sliding {
    /// The spool takes the tendon in (loading): each hole passed lowers the tension by `exp(-mu theta)`.
    #[default]
    In,
    /// The spool pays the tendon out (unloading): each hole raises it by `exp(mu theta)`.
    Out,
}

/// A tendon checked against a model: its offset, the index of its termination guide, and the
/// capstan exponent per radian of wrap, `-mu` pulling in and `mu` paying out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Routed<T> {
    pub offset_m: Vector3<T>,
    pub end_guide: usize,
    pub capstan_per_rad: T,
}

/// The tendons of one model, checked against its guides.
#[derive(Clone, Debug, PartialEq)]
pub struct Tendons<T> {
    tendons: Vec<Tendon<T>, MAX_TENDONS>,
    pub(crate) routed: Vec<Routed<T>, MAX_TENDONS>,
    /// Arc length of every guide, m (the routing's copy, so that lengths need no model).
    pub(crate) guide_s_m: Vec<T, { crate::MAX_GUIDES }>,
}

impl<T: Scalar> Tendons<T> {
    /// Checks `tendons` against `model`: at least one, at most [`MAX_TENDONS`]; each ends at a guide
    /// (within a micrometre of its centre); the first guide lies distal of the base plate; offsets,
    /// stiffnesses and feed lengths finite and in range.
    pub fn new<A: Attitude<T>, const NODES: usize>(
        model: &Model<T, A, NODES>,
        tendons: &[Tendon<T>],
    ) -> Result<Self, ModelError> {
        if tendons.is_empty() {
            return Err(ModelError::Empty("tendons"));
        }
        if tendons.len() > MAX_TENDONS {
            return Err(ModelError::Capacity("tendons"));
        }
        let guides = &model.rod().guides;
        let first = guides
            .first()
            .ok_or(ModelError::Empty("guides (tendons need at least one)"))?;
        if first.s_m <= T::zero() {
            return Err(ModelError::OutOfRange(
                "first guide (a tendon's first chord starts at the base plate, s = 0)",
            ));
        }
        let mut out = Self {
            tendons: Vec::new(),
            routed: Vec::new(),
            guide_s_m: Vec::new(),
        };
        let mut previous = T::zero();
        for guide in guides {
            if guide.s_m <= previous {
                return Err(ModelError::Unordered(
                    "guides (tendon holes need distinct guides)",
                ));
            }
            previous = guide.s_m;
            out.guide_s_m
                .push(guide.s_m)
                .map_err(|_| ModelError::Capacity("guides"))?;
        }
        let tol = T::lit(1e-6);
        for tendon in tendons {
            finite(tendon.hole_m.x, "tendon hole")?;
            finite(tendon.hole_m.y, "tendon hole")?;
            finite(tendon.end_m, "tendon termination")?;
            non_negative(tendon.feed_length_m, "tendon feed length")?;
            non_negative(tendon.friction_coefficient, "tendon friction coefficient")?;
            if let Some(k) = tendon.axial_stiffness_n {
                positive(k, "tendon axial stiffness")?;
            }
            let end_guide = guides
                .iter()
                .position(|g| (g.s_m - tendon.end_m).abs() <= tol)
                .ok_or(ModelError::OutOfRange(
                    "tendon termination (no guide centred there)",
                ))?;
            out.tendons
                .push(*tendon)
                .map_err(|_| ModelError::Capacity("tendons"))?;
            out.routed
                .push(Routed {
                    offset_m: tendon.offset_local_m(),
                    end_guide,
                    capstan_per_rad: -tendon.friction_coefficient,
                })
                .map_err(|_| ModelError::Capacity("tendons"))?;
        }
        Ok(out)
    }

    /// Sets which way tendon `tendon` slides (the sign of its friction); `false` if there is no such
    /// tendon. Without friction it changes nothing.
    pub fn set_sliding(&mut self, tendon: usize, sliding: Sliding) -> bool {
        let (Some(r), Some(t)) = (self.routed.get_mut(tendon), self.tendons.get(tendon)) else {
            return false;
        };
        r.capstan_per_rad = match sliding {
            Sliding::In => -t.friction_coefficient,
            Sliding::Out => t.friction_coefficient,
        };
        true
    }

    /// The tendons, in the order given.
    pub fn tendons(&self) -> &[Tendon<T>] {
        &self.tendons
    }

    /// How many tendons.
    pub fn len(&self) -> usize {
        self.tendons.len()
    }

    /// Whether there are none (never, once built).
    pub fn is_empty(&self) -> bool {
        self.tendons.is_empty()
    }

    /// Each tendon's rest path length, m: the chords of the straight, unloaded rod, from the base
    /// plate to its termination guide (its arc length).
    pub fn rest_length_m(&self, tendon: usize) -> Option<T> {
        let routed = self.routed.get(tendon)?;
        self.guide_s_m.get(routed.end_guide).copied()
    }

    /// The largest hole offset of any tendon, m.
    pub(crate) fn largest_offset_m(&self) -> T {
        self.routed
            .iter()
            .fold(T::zero(), |r, t| r.max(t.offset_m.norm()))
    }

    /// Checks tensions: one per tendon, each finite and not negative.
    pub(crate) fn check_tensions(&self, tensions_n: &[T]) -> Result<[T; MAX_TENDONS], ModelError> {
        if tensions_n.len() != self.len() {
            return Err(ModelError::Mismatch("tensions and tendons"));
        }
        let mut out = [T::zero(); MAX_TENDONS];
        for (o, t) in out.iter_mut().zip(tensions_n) {
            *o = non_negative(*t, "tendon tension")?;
        }
        Ok(out)
    }
}
