//! A validated scene ready to solve: the rod, its integration plan and precomputed compliances.
//!
//! Data only: the rod equations read it (`ode/`), the sweep walks its plan (`sweep/`), and the solve,
//! evaluate and shape entry points live with the solver (`shooting.rs`).

use core::marker::PhantomData;

use heapless::Vec;
use nalgebra::Vector3;

use crate::constitutive::Compliance;
use crate::error::ModelError;
use crate::kinematics::{Attitude, Quaternion};
use crate::plan::{Interval, MAX_NODES, Node, Plan};
use crate::rod::Rod;
use crate::{MAX_CABLES, MAX_SECTIONS, Scalar};

/// A scene ready to solve. `A` chooses how the frame is integrated (see [`crate::kinematics`]).
#[derive(Clone, Debug)]
pub struct Model<T: Scalar, A: Attitude<T> = Quaternion<T>, const NODES: usize = MAX_NODES> {
    rod: Rod<T>,
    plan: Plan<T, NODES>,
    compliances: Vec<Compliance<T>, MAX_SECTIONS>,
    /// Each cable's hole offset in the local frame, m (zero beyond the rod's cables).
    cable_offsets: [Vector3<T>; MAX_CABLES],
    base: A,
    length_m: T,
    moment_scale_nm: T,
    _attitude: PhantomData<A>,
}

/// What a sweep walks: the plan's nodes and intervals and the cables' hole offsets.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid<'a, T> {
    pub nodes: &'a [Node<T>],
    pub intervals: &'a [Interval<T>],
    /// One offset per cable of the rod, local frame, m.
    pub cable_offsets: &'a [Vector3<T>],
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Validates the rod and builds its plan.
    pub fn new(rod: Rod<T>) -> Result<Self, ModelError> {
        rod.validate()?;
        let plan = Plan::new(&rod)?;
        let mut compliances = Vec::new();
        let mut min_bending = T::max_value().unwrap_or_else(T::one);
        for section in &rod.sections {
            compliances
                .push(Compliance::new(&section.stiffness))
                .map_err(|_| ModelError::Capacity("sections"))?;
            min_bending = min_bending.min(section.stiffness.min_bending_nm2());
        }
        let length_m = rod.length_m();
        let mut cable_offsets = [Vector3::zeros(); MAX_CABLES];
        for (offset, cable) in cable_offsets.iter_mut().zip(&rod.cables) {
            *offset = cable.offset_local_m();
        }
        Ok(Self {
            cable_offsets,
            base: A::from_matrix(&rod.base_orientation),
            rod,
            plan,
            compliances,
            length_m,
            moment_scale_nm: min_bending / length_m,
            _attitude: PhantomData,
        })
    }

    /// The scene.
    pub fn rod(&self) -> &Rod<T> {
        &self.rod
    }

    /// The integration grid.
    pub fn plan(&self) -> &Plan<T, NODES> {
        &self.plan
    }

    /// Total reference length, m.
    pub fn length_m(&self) -> T {
        self.length_m
    }

    /// `E I_min / L`, N m: a tip-moment error of this size bends the rod by about one radian.
    pub fn moment_scale_nm(&self) -> T {
        self.moment_scale_nm
    }

    /// Whether every load on the rod plus `tip_moment_nm` is conservative (no moment acts).
    pub(crate) fn conservative(&self, tip_moment_nm: &Vector3<T>) -> bool {
        *tip_moment_nm == Vector3::zeros()
            && self
                .rod
                .loads
                .iter()
                .all(|l| l.moment_nm == Vector3::zeros())
    }

    pub(crate) fn grid(&self) -> Grid<'_, T> {
        Grid {
            nodes: &self.plan.nodes,
            intervals: &self.plan.intervals,
            cable_offsets: self
                .cable_offsets
                .get(..self.rod.cables.len())
                .unwrap_or(&[]),
        }
    }

    pub(crate) fn base_attitude(&self) -> &A {
        &self.base
    }

    pub(crate) fn compliance(&self, section: u8) -> Option<&Compliance<T>> {
        self.compliances.get(usize::from(section))
    }

    /// Whether every section's bending stiffness is the same about both axes.
    pub(crate) fn bends_alike_about_both_axes(&self) -> bool {
        self.compliances.iter().all(|c| c.c.x == c.c.y)
    }

    /// The compliance of the first section (the base's).
    pub(crate) fn base_compliance(&self) -> Option<&Compliance<T>> {
        self.compliances.first()
    }
}
