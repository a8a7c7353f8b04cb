//! What a scene contains: sections in series, cable guides, cables, point loads, gravity and the base.
//!
//! Everything in SI units. Arc lengths `s` are reference (unstretched) lengths from the base.

use heapless::Vec;
use nalgebra::{Matrix3, Vector2, Vector3};

use crate::constitutive::Stiffness;
use crate::error::{ModelError, finite, finite_vec, non_negative, positive};
use crate::loads::PointLoad;
use crate::{MAX_CABLES, MAX_GUIDES, MAX_POINT_LOADS, MAX_SECTIONS, Scalar};

/// One section of the backbone: uniform stiffness and line density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section<T> {
    /// Reference length, m.
    pub length_m: T,
    /// Bending, torsion, shear and axial stiffness.
    pub stiffness: Stiffness<T>,
    /// Mass per reference length of the bare rod, kg/m.
    pub line_density_kg_per_m: T,
    /// Fixed RK4 steps over the section's length (sub-intervals between breakpoints share them in
    /// proportion to their length, at least one each).
    pub steps: u16,
}

/// A cable guide (a disk on the backbone) centred at `s_m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guide<T> {
    /// Arc length of the guide's centre, m.
    pub s_m: T,
    /// Thickness along the backbone, m (the accurate-mass model spreads the mass over it).
    pub thickness_m: T,
    /// Mass, kg.
    pub mass_kg: T,
}

/// A cable running through a hole at the same place in every guide, from the first guide to its
/// termination, where it is fixed to the backbone at the same offset.
///
/// The hole is stored as a position, not as an angle and a radius, so that nothing on the controller
/// evaluates a sine: [`Cable::at_angle`] converts at the edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cable<T> {
    /// The hole in the guide's cross-section, local frame `(x, y)`, m (`z` is along the backbone).
    pub hole_m: Vector2<T>,
    /// Arc length of the termination, m (the tip for the thesis bench).
    pub end_m: T,
}

impl<T: Scalar> Cable<T> {
    /// A cable whose hole is `radius_m` from the backbone at `angle_rad` about the local z axis,
    /// from local x: `radius (cos a, sin a)`.
    pub fn at_angle(angle_rad: T, radius_m: T, end_m: T) -> Self {
        let (s, c) = angle_rad.sin_cos();
        Self {
            hole_m: Vector2::new(c, s) * radius_m,
            end_m,
        }
    }

    /// The hole's offset in the local frame, m.
    pub fn offset_local_m(&self) -> Vector3<T> {
        Vector3::new(self.hole_m.x, self.hole_m.y, T::zero())
    }

    /// Distance of the hole from the backbone, m.
    pub fn radius_m(&self) -> T {
        self.hole_m.norm()
    }
}

/// How the guides' mass enters the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GuideMass {
    /// Guides are weightless (the bare rod, or guide mass already folded into the line density).
    Ignore,
    /// Average-mass model: each section's guide mass is spread uniformly over the section.
    Average,
    /// Accurate-mass model: each guide is a short segment of its own line density, `mass / thickness`,
    /// on top of the rod's.
    #[default]
    Accurate,
}

/// Which constitutive model for shear and extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StrainModel {
    /// Shearable and extensible (Cosserat): `v = D^-1 R^T n + e3`.
    #[default]
    Cosserat,
    /// Inextensible and unshearable (Kirchhoff): `v = e3`. Cheaper; error of order `|n| / (E A)`.
    Kirchhoff,
}

/// A whole scene: the rod and everything fixed on it. The tip load is the solve's input, not part of the rod.
#[derive(Clone, Debug, PartialEq)]
pub struct Rod<T> {
    /// Sections from base to tip.
    pub sections: Vec<Section<T>, MAX_SECTIONS>,
    /// Guides in increasing arc length.
    pub guides: Vec<Guide<T>, MAX_GUIDES>,
    /// Cables.
    pub cables: Vec<Cable<T>, MAX_CABLES>,
    /// Point loads (masses, forces, moments), any order.
    pub loads: Vec<PointLoad<T>, MAX_POINT_LOADS>,
    /// How guide masses enter the mass distribution.
    pub guide_mass: GuideMass,
    /// Gravity, m/s^2, global frame.
    pub gravity_m_s2: Vector3<T>,
    /// Base position, m.
    pub base_position_m: Vector3<T>,
    /// Base orientation: columns are the local x, y, z axes in global coordinates.
    pub base_orientation: Matrix3<T>,
    /// Shear and extension model.
    pub strain_model: StrainModel,
}

impl<T: Scalar> Rod<T> {
    /// An empty rod with the thesis bench's base: clamped at the origin, local z (the tangent)
    /// along global +x, local x along global +y (the measured cable's side), gravity along -y.
    pub fn new() -> Self {
        Self {
            sections: Vec::new(),
            guides: Vec::new(),
            cables: Vec::new(),
            loads: Vec::new(),
            guide_mass: GuideMass::Accurate,
            gravity_m_s2: Vector3::new(T::zero(), T::lit(-9.81), T::zero()),
            base_position_m: Vector3::zeros(),
            base_orientation: bench_base_orientation(),
            strain_model: StrainModel::Cosserat,
        }
    }

    /// Appends a section at the distal end.
    pub fn push_section(&mut self, section: Section<T>) -> Result<&mut Self, ModelError> {
        self.sections
            .push(section)
            .map_err(|_| ModelError::Capacity("sections"))?;
        Ok(self)
    }

    /// Adds a guide (guides must end up in increasing arc length).
    pub fn push_guide(&mut self, guide: Guide<T>) -> Result<&mut Self, ModelError> {
        self.guides
            .push(guide)
            .map_err(|_| ModelError::Capacity("guides"))?;
        Ok(self)
    }

    /// Adds a cable.
    pub fn push_cable(&mut self, cable: Cable<T>) -> Result<&mut Self, ModelError> {
        self.cables
            .push(cable)
            .map_err(|_| ModelError::Capacity("cables"))?;
        Ok(self)
    }

    /// Adds a point load.
    pub fn push_load(&mut self, load: PointLoad<T>) -> Result<&mut Self, ModelError> {
        self.loads
            .push(load)
            .map_err(|_| ModelError::Capacity("point loads"))?;
        Ok(self)
    }

    /// Total reference length, m.
    pub fn length_m(&self) -> T {
        self.sections
            .iter()
            .fold(T::zero(), |acc, s| acc + s.length_m)
    }

    /// Checks every field; the model refuses a rod that fails.
    pub fn validate(&self) -> Result<(), ModelError> {
        if self.sections.is_empty() {
            return Err(ModelError::Empty("sections"));
        }
        for section in &self.sections {
            positive(section.length_m, "section length")?;
            Stiffness::new(
                section.stiffness.bending_torsion_nm2,
                section.stiffness.shear_axial_n,
            )?;
            non_negative(section.line_density_kg_per_m, "line density")?;
            if section.steps == 0 {
                return Err(ModelError::NotPositive("section steps"));
            }
        }
        let length = self.length_m();
        finite(length, "rod length")?;
        let mut previous_end = T::zero();
        for guide in &self.guides {
            finite(guide.s_m, "guide position")?;
            non_negative(guide.thickness_m, "guide thickness")?;
            non_negative(guide.mass_kg, "guide mass")?;
            if guide.s_m < T::zero() || guide.s_m > length {
                return Err(ModelError::OutOfRange("guide position"));
            }
            let half = guide.thickness_m * T::lit(0.5);
            if self.guide_mass == GuideMass::Accurate && guide.mass_kg > T::zero() {
                if guide.thickness_m <= T::zero() {
                    return Err(ModelError::NotPositive("guide thickness"));
                }
                if guide.s_m - half < T::zero() || guide.s_m + half > length {
                    return Err(ModelError::OutOfRange("guide extent"));
                }
            }
            if guide.s_m - half < previous_end {
                return Err(ModelError::Unordered("guides"));
            }
            previous_end = guide.s_m + half;
        }
        if !self.cables.is_empty() && self.guides.is_empty() {
            return Err(ModelError::Empty("guides (cables need at least one)"));
        }
        for cable in &self.cables {
            finite(cable.hole_m.x, "cable hole")?;
            finite(cable.hole_m.y, "cable hole")?;
            positive(cable.radius_m(), "cable radius")?;
            finite(cable.end_m, "cable termination")?;
            let first = self.guides.first().map_or(T::zero(), |g| g.s_m);
            if cable.end_m <= first || cable.end_m > length {
                return Err(ModelError::OutOfRange("cable termination"));
            }
        }
        for load in &self.loads {
            finite(load.s_m, "load position")?;
            non_negative(load.mass_kg, "hung mass")?;
            finite_vec(&load.force_n, "point force")?;
            finite_vec(&load.moment_nm, "point moment")?;
            if load.s_m < T::zero() || load.s_m > length {
                return Err(ModelError::OutOfRange("load position"));
            }
        }
        finite_vec(&self.gravity_m_s2, "gravity")?;
        finite_vec(&self.base_position_m, "base position")?;
        if !crate::scalar::all_finite(&self.base_orientation) {
            return Err(ModelError::NonFinite("base orientation"));
        }
        let m = &self.base_orientation;
        if crate::kinematics::orthonormality_error(m) > T::lit(1e-4) || m.determinant() <= T::zero()
        {
            return Err(ModelError::OutOfRange("base orientation (not a rotation)"));
        }
        Ok(())
    }
}

impl<T: Scalar> Default for Rod<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// The thesis bench's base frame: local x -> global +y, local y -> global +z, local z -> global +x.
pub fn bench_base_orientation<T: Scalar>() -> Matrix3<T> {
    let (o, l) = (T::zero(), T::one());
    Matrix3::new(o, o, l, l, o, o, o, l, o)
}
