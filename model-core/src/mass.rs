//! The mass distribution along the backbone (thesis ch. 3.6-3.8; MODEL.md "Mass of the cable guides").
//!
//! The internal force needs only the mass distal to `s`: `n(s) = F_tip + g M(s) + distal point forces`.
//! The line density is piecewise constant between breakpoints (section ends, guide edges), so `M(s)`
//! is piecewise linear and exact; the thesis's modulo arithmetic computes the same function.

use crate::Scalar;
pub use crate::rod::GuideMass;
use crate::rod::Rod;

/// Whether a guide's mass is placed as its own segment (and so its edges are breakpoints).
pub(crate) fn guide_is_segment<T: Scalar>(rod: &Rod<T>, guide: &crate::Guide<T>) -> bool {
    rod.guide_mass == GuideMass::Accurate
        && guide.mass_kg > T::zero()
        && guide.thickness_m > T::zero()
}

/// Line density, kg/m, on an interval of section `section` with midpoint `s_mid` (no breakpoint inside it).
pub(crate) fn line_density_kg_per_m<T: Scalar>(
    rod: &Rod<T>,
    section: usize,
    section_start_m: T,
    s_mid: T,
) -> T {
    let Some(sec) = rod.sections.get(section) else {
        return T::zero();
    };
    let mut density = sec.line_density_kg_per_m;
    match rod.guide_mass {
        GuideMass::Ignore => {}
        GuideMass::Average => {
            let end = section_start_m + sec.length_m;
            let guides_kg = rod
                .guides
                .iter()
                .filter(|g| {
                    g.s_m >= section_start_m
                        && (g.s_m < end || (g.s_m <= end && is_last(rod, section)))
                })
                .fold(T::zero(), |acc, g| acc + g.mass_kg);
            density += guides_kg / sec.length_m;
        }
        GuideMass::Accurate => {
            for guide in rod.guides.iter().filter(|g| guide_is_segment(rod, g)) {
                let half = guide.thickness_m * T::lit(0.5);
                if s_mid > guide.s_m - half && s_mid < guide.s_m + half {
                    density += guide.mass_kg / guide.thickness_m;
                }
            }
        }
    }
    density
}

fn is_last<T>(rod: &Rod<T>, section: usize) -> bool {
    section + 1 == rod.sections.len()
}

/// Total mass carried by the backbone beyond the clamp, kg: rod, guides and hung masses.
pub fn total_mass_kg<T: Scalar>(rod: &Rod<T>) -> T {
    let rod_kg = rod.sections.iter().fold(T::zero(), |acc, s| {
        acc + s.line_density_kg_per_m * s.length_m
    });
    let guides_kg = match rod.guide_mass {
        GuideMass::Ignore => T::zero(),
        GuideMass::Average | GuideMass::Accurate => {
            rod.guides.iter().fold(T::zero(), |acc, g| acc + g.mass_kg)
        }
    };
    let hung_kg = rod.loads.iter().fold(T::zero(), |acc, l| acc + l.mass_kg);
    rod_kg + guides_kg + hung_kg
}
