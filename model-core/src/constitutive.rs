//! The linear constitutive law of the backbone (thesis eqs. 2.9 and 2.12; MODEL.md "Statics of one section").
//!
//! Internal force and moment in the body frame: `n_l = D (v - e3)`, `m_l = C u`, with
//! `C = diag(E I1, E I2, G J)` and `D = diag(G A, G A, E A)`.

use nalgebra::Vector3;

use crate::Scalar;
use crate::error::{ModelError, positive};

/// An isotropic elastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material<T> {
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: T,
    /// Shear modulus G, Pa.
    pub shear_modulus_pa: T,
}

impl<T: Scalar> Material<T> {
    /// From E and Poisson's ratio: `G = E / (2 (1 + nu))`. (The thesis prints `G = E (1 + nu)`, a misprint.)
    ///
    /// Fails if E is not positive or nu is outside (-1, 0.5].
    pub fn isotropic(youngs_modulus_pa: T, poisson_ratio: T) -> Result<Self, ModelError> {
        positive(youngs_modulus_pa, "Young's modulus")?;
        crate::error::finite(poisson_ratio, "Poisson's ratio")?;
        if poisson_ratio <= -T::one() || poisson_ratio > T::lit(0.5) {
            return Err(ModelError::OutOfRange("Poisson's ratio"));
        }
        let shear_modulus_pa = youngs_modulus_pa / (T::lit(2.0) * (T::one() + poisson_ratio));
        Ok(Self {
            youngs_modulus_pa,
            shear_modulus_pa,
        })
    }
}

/// Cross-section properties of the backbone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossSection<T> {
    /// Area A, m^2.
    pub area_m2: T,
    /// Second moments of area about the local x and y axes (I1, I2), m^4.
    pub second_moment_m4: [T; 2],
    /// Torsion constant J (the polar moment for a circle), m^4.
    pub polar_moment_m4: T,
}

impl<T: Scalar> CrossSection<T> {
    /// A solid circle of diameter `d`: `A = pi d^2 / 4`, `I = pi d^4 / 64`, `J = 2 I`.
    pub fn solid_circle(diameter_m: T) -> Result<Self, ModelError> {
        positive(diameter_m, "rod diameter")?;
        let pi = T::pi();
        let d2 = diameter_m * diameter_m;
        let i = pi * d2 * d2 / T::lit(64.0);
        Ok(Self {
            area_m2: pi * d2 / T::lit(4.0),
            second_moment_m4: [i, i],
            polar_moment_m4: i + i,
        })
    }

    /// A circular tube with outer and inner diameters.
    pub fn tube(outer_diameter_m: T, inner_diameter_m: T) -> Result<Self, ModelError> {
        positive(outer_diameter_m, "tube outer diameter")?;
        crate::error::non_negative(inner_diameter_m, "tube inner diameter")?;
        if inner_diameter_m >= outer_diameter_m {
            return Err(ModelError::OutOfRange("tube inner diameter"));
        }
        let pi = T::pi();
        let (o2, i2) = (
            outer_diameter_m * outer_diameter_m,
            inner_diameter_m * inner_diameter_m,
        );
        let i = pi * (o2 * o2 - i2 * i2) / T::lit(64.0);
        Ok(Self {
            area_m2: pi * (o2 - i2) / T::lit(4.0),
            second_moment_m4: [i, i],
            polar_moment_m4: i + i,
        })
    }
}

/// The diagonal stiffness matrices of a section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiffness<T> {
    /// Diagonal of C: bending about local x and y, and torsion (E I1, E I2, G J), N m^2.
    pub bending_torsion_nm2: Vector3<T>,
    /// Diagonal of D: shear along local x and y, and axial (G A, G A, E A), N.
    pub shear_axial_n: Vector3<T>,
}

impl<T: Scalar> Stiffness<T> {
    /// From a material and a cross-section.
    pub fn from_material(
        material: &Material<T>,
        section: &CrossSection<T>,
    ) -> Result<Self, ModelError> {
        let (e, g) = (material.youngs_modulus_pa, material.shear_modulus_pa);
        Self::new(
            Vector3::new(
                e * section.second_moment_m4[0],
                e * section.second_moment_m4[1],
                g * section.polar_moment_m4,
            ),
            Vector3::new(
                g * section.area_m2,
                g * section.area_m2,
                e * section.area_m2,
            ),
        )
    }

    /// Given directly; every entry must be positive and finite.
    pub fn new(
        bending_torsion_nm2: Vector3<T>,
        shear_axial_n: Vector3<T>,
    ) -> Result<Self, ModelError> {
        for x in bending_torsion_nm2.iter() {
            positive(*x, "bending/torsion stiffness")?;
        }
        for x in shear_axial_n.iter() {
            positive(*x, "shear/axial stiffness")?;
        }
        Ok(Self {
            bending_torsion_nm2,
            shear_axial_n,
        })
    }

    /// The smaller bending stiffness, N m^2: the scale of moment residuals.
    pub fn min_bending_nm2(&self) -> T {
        self.bending_torsion_nm2.x.min(self.bending_torsion_nm2.y)
    }
}

/// Stiffness with the inverses precomputed, as the integrator uses it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Compliance<T> {
    pub c: Vector3<T>,
    pub c_inv: Vector3<T>,
    pub d_inv: Vector3<T>,
}

impl<T: Scalar> Compliance<T> {
    /// `1 / EI` about the section's softer bending axis, 1/(N m^2).
    #[inline]
    pub fn max_bending_compliance(&self) -> T {
        self.c_inv.x.max(self.c_inv.y)
    }

    pub fn new(stiffness: &Stiffness<T>) -> Self {
        let one = Vector3::repeat(T::one());
        Self {
            c: stiffness.bending_torsion_nm2,
            c_inv: one.component_div(&stiffness.bending_torsion_nm2),
            d_inv: one.component_div(&stiffness.shear_axial_n),
        }
    }

    /// Shear and extension strain from the body-frame internal force (thesis eq. 2.10):
    /// `v = D^-1 n_l + e3`, or `e3` for an inextensible, unshearable (Kirchhoff) rod.
    #[inline]
    pub fn shear_strain(&self, n_local: &Vector3<T>, kirchhoff: bool) -> Vector3<T> {
        if kirchhoff {
            Vector3::z()
        } else {
            let mut v = self.d_inv.component_mul(n_local);
            v.z += T::one();
            v
        }
    }

    /// Rate of the bending/torsion strain (thesis eq. 2.13, no distributed moment, no precurvature):
    /// `u' = -C^-1 (u x C u + v x n_l)`; `cu` is `C u`, already at hand.
    #[inline]
    pub fn strain_rate(
        &self,
        u: &Vector3<T>,
        cu: &Vector3<T>,
        v: &Vector3<T>,
        n_local: &Vector3<T>,
    ) -> Vector3<T> {
        -self.c_inv.component_mul(&(u.cross(cu) + v.cross(n_local)))
    }
}
