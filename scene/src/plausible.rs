//! Numbers that parse but that no continuum robot has: most often a unit slipped (a modulus in GPa,
//! a diameter in millimetres, a mass in grams, an angle in radians). Each check names the key, the
//! value and the slip that would make it plausible.
//!
//! Two kinds: a value for which the rod model means nothing (a modulus below 1 MPa or above 1.2 TPa, a
//! cross-section at least half as wide as the rod is long: not a slender rod) is refused; a value
//! that is merely far outside what such robots have (a 12 m section, a 1 kg guide) is warned about,
//! and the run goes on with it. host-sim/SCENES.md lists them.

use super::{Scene, SceneError};

/// Young's and shear moduli a backbone may have, Pa: from below the softest elastomer to diamond's
/// (1.05-1.2 TPa).
const MODULUS_PA: (f64, f64) = (1e6, 1.2e12);

/// Longest plausible section, m.
const SECTION_LENGTH_M: f64 = 10.0;
/// Widest plausible backbone, m.
const DIAMETER_M: f64 = 0.05;
/// Heaviest plausible backbone, kg/m.
const LINE_DENSITY_KG_PER_M: f64 = 10.0;
/// Material densities, kg/m^3: from foams to tungsten.
const DENSITY_KG_M3: (f64, f64) = (500.0, 25_000.0);
/// Farthest plausible cable or tendon hole from the backbone, m.
const HOLE_RADIUS_M: f64 = 0.1;
/// Heaviest plausible guide, kg.
const GUIDE_MASS_KG: f64 = 1.0;
/// Thickest plausible guide along the backbone, m.
const GUIDE_THICKNESS_M: f64 = 0.05;
/// Largest plausible gravity, m/s^2 (ten times the Earth's).
const GRAVITY_M_S2: f64 = 100.0;
/// A `[solver] tolerance` above this is warned about (up to `MAX_SOLVER_TOLERANCE`, refused above).
const LOOSE_TOLERANCE: f64 = 1e-6;
/// Spool radii a cable drive has, m: 0.5 mm to 10 cm.
const SPOOL_RADIUS_M: (f64, f64) = (5e-4, 0.1);

/// A number as a reader takes it in: plain between 0.001 and 10 million, else with an exponent
/// (`1.5e12`, not `1500000000000`).
fn shown(x: f64) -> String {
    if (1e-3..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The first of `slips` (a factor and how the value reads with it, e.g. `(1e9, "e9 Pa", "GPa")`)
/// that brings `x` into `lo..=hi`, as advice: ` Did you mean 60e9 Pa (60 GPa)?`.
fn slip(x: f64, lo: f64, hi: f64, slips: &[(f64, &str, &str)]) -> String {
    slips
        .iter()
        .find(|(factor, _, _)| (lo..=hi).contains(&(x * factor)))
        .map_or_else(String::new, |(_, written, unit)| {
            format!(" Did you mean {x}{written} ({x} {unit})?")
        })
}

/// Advice for a length written in millimetres, centimetres or micrometres.
fn length_slip(x: f64, lo: f64, hi: f64) -> String {
    slip(
        x,
        lo,
        hi,
        &[
            (1e-3, "e-3 m", "mm"),
            (1e-2, "e-2 m", "cm"),
            (1e-6, "e-6 m", "µm"),
        ],
    )
}

/// A guide value's check: the per-guide list's key and values, the one-for-all key and value, the
/// limit, and the words for a value above it.
type GuideCheck<'a> = (
    &'static str,
    &'a Option<Vec<f64>>,
    &'static str,
    f64,
    f64,
    fn(f64) -> String,
);

impl Scene {
    /// The refusals: a modulus outside 1 MPa..1.2 TPa, a diameter at least half the rod's length.
    pub(super) fn check_plausible(&self) -> Result<(), SceneError> {
        let length_m: f64 = self.sections.iter().map(|s| s.length_m).sum();
        for (i, s) in self.sections.iter().enumerate() {
            if let Some(material) = &s.material {
                let moduli = [
                    ("youngs_modulus_pa", Some(material.youngs_modulus_pa)),
                    ("shear_modulus_pa", material.shear_modulus_pa),
                ];
                for (key, value) in moduli {
                    let Some(x) = value.filter(|x| x.is_finite() && *x > 0.0) else {
                        continue;
                    };
                    let (lo, hi) = MODULUS_PA;
                    let field = format!("section[{i}].material.{key}");
                    if x < lo {
                        // Only a slip that lands on a backbone material (10 MPa up) is advice.
                        let advice =
                            slip(x, 1e7, hi, &[(1e9, "e9 Pa", "GPa"), (1e6, "e6 Pa", "MPa")]);
                        return Err(SceneError::new(
                            field,
                            format!(
                                "{} Pa is below 1 MPa, softer than any backbone material (the \
                                 unit is Pa).{advice}",
                                shown(x)
                            ),
                        ));
                    }
                    if x > hi {
                        return Err(SceneError::new(
                            field,
                            format!(
                                "{} Pa is above 1.2 TPa, stiffer than diamond (the unit is Pa)",
                                shown(x)
                            ),
                        ));
                    }
                }
            }
            if let Some(c) = &s.cross_section
                && c.diameter_m.is_finite()
                && length_m.is_finite()
                && length_m > 0.0
                && c.diameter_m >= length_m / 2.0
            {
                let x = c.diameter_m;
                return Err(SceneError::new(
                    format!("section[{i}].cross_section.diameter_m"),
                    format!(
                        "{x} m is at least half the rod's length ({length_m} m): not a slender \
                         rod, which the model needs (the unit is m).{}",
                        length_slip(x, 0.0, (length_m / 2.0).min(DIAMETER_M))
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The warnings: values far outside what continuum robots have, each with the key, the value
    /// and the likely slip. The run goes on with them. A value that is not finite is not warned
    /// about: building the rod refuses it, naming the key.
    pub fn warnings(&self) -> Vec<SceneError> {
        let mut out = Vec::new();
        let mut warn = |field: String, reason: String| out.push(SceneError::new(field, reason));
        let g = self.gravity_m_s2.iter().map(|x| x * x).sum::<f64>().sqrt();
        if g.is_finite() && g > GRAVITY_M_S2 {
            warn(
                "gravity_m_s2".into(),
                format!(
                    "{g} m/s^2 is more than ten times the Earth's gravity (the unit is m/s^2; the \
                     Earth's is 9.81)"
                ),
            );
        }
        if let Some(drive) = &self.drive {
            let (lo, hi) = SPOOL_RADIUS_M;
            let x = drive.spool_radius_m;
            if x.is_finite() && !(lo..=hi).contains(&x) {
                warn(
                    "drive.spool_radius_m".into(),
                    format!(
                        "{x} m is outside {lo}..{hi} m, the spools cable drives have (the unit is \
                         m).{}",
                        length_slip(x, lo, hi)
                    ),
                );
            }
        }
        for (i, s) in self.sections.iter().enumerate() {
            if s.length_m.is_finite() && s.length_m > SECTION_LENGTH_M {
                warn(
                    format!("section[{i}].length_m"),
                    format!(
                        "{} m is a long section for a continuum robot (the unit is m).{}",
                        s.length_m,
                        length_slip(s.length_m, 1e-3, SECTION_LENGTH_M)
                    ),
                );
            }
            if let Some(c) = &s.cross_section
                && c.diameter_m.is_finite()
                && c.diameter_m > DIAMETER_M
            {
                warn(
                    format!("section[{i}].cross_section.diameter_m"),
                    format!(
                        "{} m is a wide backbone (the unit is m).{}",
                        c.diameter_m,
                        length_slip(c.diameter_m, 1e-5, DIAMETER_M)
                    ),
                );
            }
            if let Some(x) = s.line_density_kg_per_m
                && x.is_finite()
                && x > LINE_DENSITY_KG_PER_M
            {
                warn(
                    format!("section[{i}].line_density_kg_per_m"),
                    format!(
                        "{x} kg/m is a heavy backbone (the unit is kg per metre).{}",
                        slip(x, 0.0, LINE_DENSITY_KG_PER_M, &[(1e-3, "e-3 kg/m", "g/m")])
                    ),
                );
            }
            if let Some(x) = s.density_kg_m3
                && x.is_finite()
                && x > 0.0
                && !(DENSITY_KG_M3.0..=DENSITY_KG_M3.1).contains(&x)
            {
                let (lo, hi) = DENSITY_KG_M3;
                warn(
                    format!("section[{i}].density_kg_m3"),
                    format!(
                        "{x} kg/m^3 is outside {lo}..{hi} kg/m^3, foams to tungsten (the unit is \
                         kg/m^3).{}",
                        slip(x, lo, hi, &[(1e3, "e3 kg/m^3", "g/cm^3")])
                    ),
                );
            }
        }
        for (kind, holes) in [
            (
                "cable",
                self.cables
                    .iter()
                    .map(|c| (c.angle_deg, c.radius_m))
                    .collect::<Vec<_>>(),
            ),
            (
                "tendon",
                self.tendons
                    .iter()
                    .map(|t| (t.angle_deg, t.radius_m))
                    .collect(),
            ),
        ] {
            for (i, (_, r)) in holes.iter().enumerate() {
                if r.is_finite() && *r > HOLE_RADIUS_M {
                    warn(
                        format!("{kind}[{i}].radius_m"),
                        format!(
                            "{r} m is far from the backbone for a {kind} hole (the unit is m).{}",
                            length_slip(*r, 1e-5, HOLE_RADIUS_M)
                        ),
                    );
                }
            }
        }
        // Hole angles all within a turn in radians, with one not zero: radians where degrees belong.
        let angles: Vec<(String, f64)> = self
            .cables
            .iter()
            .enumerate()
            .map(|(i, c)| (format!("cable[{i}].angle_deg"), c.angle_deg))
            .chain(
                self.tendons
                    .iter()
                    .enumerate()
                    .map(|(i, t)| (format!("tendon[{i}].angle_deg"), t.angle_deg)),
            )
            .collect();
        let turn = core::f64::consts::TAU + 1e-9;
        if angles.len() >= 2
            && angles.iter().all(|(_, a)| a.abs() <= turn)
            && let Some((field, a)) = angles.iter().find(|(_, a)| *a != 0.0)
        {
            warn(
                field.clone(),
                format!(
                    "{a} degrees, and every hole angle of the scene is within one turn in \
                     radians (the unit is degrees). Did you mean {:.4} degrees ({a} rad)?",
                    a.to_degrees()
                ),
            );
        }
        if let Some(tolerance) = self
            .solver
            .tolerance
            .filter(|t| *t > LOOSE_TOLERANCE && *t <= crate::MAX_SOLVER_TOLERANCE)
        {
            warn(
                "solver.tolerance".into(),
                format!(
                    "{tolerance} is a loose tolerance: the tip may be off by about half of it times \
                     the rod's length (the default is about 1e-11 in f64)"
                ),
            );
        }
        if let Some(guides) = &self.guides {
            // Each guide's value (the per-guide list, then the one for all), the limit and the
            // words and slip of a value above it.
            let checks: [GuideCheck<'_>; 2] = [
                (
                    "masses_kg",
                    &guides.masses_kg,
                    "mass_kg",
                    guides.mass_kg,
                    GUIDE_MASS_KG,
                    |m| {
                        format!(
                            "{m} kg is a heavy guide (the unit is kg).{}",
                            slip(m, 0.0, GUIDE_MASS_KG, &[(1e-3, "e-3 kg", "g")])
                        )
                    },
                ),
                (
                    "thicknesses_m",
                    &guides.thicknesses_m,
                    "thickness_m",
                    guides.thickness_m,
                    GUIDE_THICKNESS_M,
                    |t| {
                        format!(
                            "{t} m is a thick guide (the unit is m).{}",
                            length_slip(t, 0.0, GUIDE_THICKNESS_M)
                        )
                    },
                ),
            ];
            for (list_key, list, key, value, limit, words) in checks {
                let values = list
                    .iter()
                    .flatten()
                    .enumerate()
                    .map(|(i, x)| (format!("guides.{list_key}[{i}]"), *x))
                    .chain(core::iter::once((format!("guides.{key}"), value)));
                for (field, x) in values.filter(|(_, x)| x.is_finite() && *x > limit) {
                    warn(field, words(x));
                }
            }
        }
        out
    }
}
