//! Reference scenes in SI units: the thesis's benches (ch. 4, as corrected in MODEL.md) and the 3D
//! three-cable bench of the independent golden reference (`tests/data/golden/bench_3d_cables.csv`).
//!
//! The thesis states its bench in cm and grams; the conversion happens here, once.

use nalgebra::{Vector2, Vector3};

use model_core::{
    Cable, CrossSection, Guide, GuideMass, Material, ModelError, PointLoad, Rod, Scalar, Section,
    Stiffness,
};

/// Nitinol rod diameter, m.
pub const ROD_DIAMETER_M: f64 = 1.56e-3;
/// Young's modulus fitted in the thesis, Pa (measured 61.6-62.7 GPa).
pub const YOUNGS_MODULUS_PA: f64 = 62.7e9;
/// The Young's modulus that reproduces the thesis's experiment-1 predictions (Table 4.1) to 0.02 cm.
/// The thesis does not state the value it used there; with 62.7 GPa its predicted sag is up to
/// 0.35 cm larger than this model's.
pub const EXP1_YOUNGS_MODULUS_PA: f64 = 61.0e9;
/// Poisson's ratio.
pub const POISSON_RATIO: f64 = 0.3;
/// Nitinol density, kg/m^3 (the thesis prints 6.8 "g/mm^3": g/cm^3).
pub const ROD_DENSITY_KG_M3: f64 = 6800.0;
/// Free length: 40 cm rod, 1 cm of it in the clamp, m.
pub const FREE_LENGTH_M: f64 = 0.39;
/// Experiment 1: the section transition (and the hung load) at 19.5 cm, m.
pub const EXP1_TRANSITION_M: f64 = 0.195;
/// Guides: the first starts 0.39 cm from the clamp, each is 3.01 mm thick, centres 9.5 cm apart.
pub const GUIDE_COUNT: usize = 5;
/// Guide thickness, m.
pub const GUIDE_THICKNESS_M: f64 = 3.01e-3;
/// Centre of the first guide, m: 0.39 cm + half a thickness. (The golden file's header rounds it to 0.00541.)
pub const GUIDE_FIRST_CENTRE_M: f64 = 0.0039 + GUIDE_THICKNESS_M / 2.0;
/// Guide pitch, m.
pub const GUIDE_PITCH_M: f64 = 0.095;
/// Guide mass, kg.
pub const GUIDE_MASS_KG: f64 = 2.2e-3;
/// Average-mass model: rod and guides weighed together, 14.9 g over the 40 cm rod, kg/m.
pub const AVERAGE_LINE_DENSITY_KG_M: f64 = 0.0149 / 0.40;
/// Cable offset from the backbone, m.
pub const CABLE_RADIUS_M: f64 = 0.01;
/// The three holes' directions `(cos a, sin a)` at a = 0, 120 and 240 degrees, as literals: building
/// the bench then takes no trigonometry (the firmware links no sine).
pub const CABLE_DIRECTIONS: [(f64, f64); 3] = [
    (1.0, 0.0),
    (-0.5, 0.866_025_403_784_438_6),
    (-0.5, -0.866_025_403_784_438_6),
];
/// Standard gravity used by the thesis and the golden file, m/s^2.
pub const GRAVITY_M_S2: f64 = 9.81;

/// The Nitinol rod's stiffness for a Young's modulus, Pa.
pub fn nitinol_stiffness<T: Scalar>(youngs_modulus_pa: f64) -> Result<Stiffness<T>, ModelError> {
    let material = Material::isotropic(T::lit(youngs_modulus_pa), T::lit(POISSON_RATIO))?;
    Stiffness::from_material(
        &material,
        &CrossSection::solid_circle(T::lit(ROD_DIAMETER_M))?,
    )
}

/// Line density of the bare Nitinol rod, kg/m.
pub fn bare_line_density_kg_m() -> f64 {
    ROD_DENSITY_KG_M3 * core::f64::consts::PI * ROD_DIAMETER_M * ROD_DIAMETER_M / 4.0
}

/// Which guide-mass model the experiment-2 bench uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exp2Mass {
    /// Rod and guides weighed together (14.9 g) and spread evenly; guides weightless.
    Average,
    /// Bare rod density plus each 2.2 g guide as its own segment.
    Accurate,
}

/// The thesis's experiment-1 bench: two 19.5 cm sections of bare Nitinol (Young's modulus in Pa,
/// see [`EXP1_YOUNGS_MODULUS_PA`]), no guides. The load hung at the transition is the caller's
/// ([`PointLoad::mass`] at [`EXP1_TRANSITION_M`]).
pub fn exp1_bench<T: Scalar>(
    youngs_modulus_pa: f64,
    steps_per_section: u16,
) -> Result<Rod<T>, ModelError> {
    let mut rod = Rod::new();
    rod.guide_mass = GuideMass::Ignore;
    rod.gravity_m_s2 = Vector3::new(T::zero(), T::lit(-GRAVITY_M_S2), T::zero());
    for length in [EXP1_TRANSITION_M, FREE_LENGTH_M - EXP1_TRANSITION_M] {
        rod.push_section(Section {
            length_m: T::lit(length),
            stiffness: nitinol_stiffness(youngs_modulus_pa)?,
            line_density_kg_per_m: T::lit(bare_line_density_kg_m()),
            steps: steps_per_section,
        })?;
    }
    Ok(rod)
}

/// The thesis's experiment-2 bench: one 39 cm section with five guides and `cables` (at most three)
/// cables at 120 degrees (cable 0 on the upper side, +y at the base, as measured on the bench), each terminated at
/// the tip.
pub fn exp2_bench<T: Scalar>(
    mass: Exp2Mass,
    steps: u16,
    cables: usize,
) -> Result<Rod<T>, ModelError> {
    let mut rod = Rod::new();
    rod.gravity_m_s2 = Vector3::new(T::zero(), T::lit(-GRAVITY_M_S2), T::zero());
    let (line_density, guide_mass, model) = match mass {
        Exp2Mass::Average => (AVERAGE_LINE_DENSITY_KG_M, 0.0, GuideMass::Ignore),
        Exp2Mass::Accurate => (bare_line_density_kg_m(), GUIDE_MASS_KG, GuideMass::Accurate),
    };
    rod.guide_mass = model;
    rod.push_section(Section {
        length_m: T::lit(FREE_LENGTH_M),
        stiffness: nitinol_stiffness(YOUNGS_MODULUS_PA)?,
        line_density_kg_per_m: T::lit(line_density),
        steps,
    })?;
    for k in 0..GUIDE_COUNT {
        rod.push_guide(Guide {
            s_m: T::lit(GUIDE_FIRST_CENTRE_M + k as f64 * GUIDE_PITCH_M),
            thickness_m: T::lit(GUIDE_THICKNESS_M),
            mass_kg: T::lit(guide_mass),
        })?;
    }
    for (x, y) in CABLE_DIRECTIONS.iter().take(cables) {
        rod.push_cable(Cable {
            hole_m: Vector2::new(T::lit(x * CABLE_RADIUS_M), T::lit(y * CABLE_RADIUS_M)),
            end_m: T::lit(FREE_LENGTH_M),
        })?;
    }
    Ok(rod)
}

/// The golden reference's bench: experiment 2, average mass, three cables.
pub fn golden_bench<T: Scalar>(steps: u16) -> Result<Rod<T>, ModelError> {
    exp2_bench(Exp2Mass::Average, steps, 3)
}

/// A hung mass at the tip of a thesis bench as a point load (kg).
pub fn tip_mass<T: Scalar>(mass_kg: T) -> PointLoad<T> {
    PointLoad::mass(T::lit(FREE_LENGTH_M), mass_kg)
}

/// The golden reference data, as committed.
pub const GOLDEN_CSV: &str = include_str!("../../tests/data/golden/bench_3d_cables.csv");
/// Thesis Table 4.1 (experiment 1a), cm and g.
pub const TABLE_4_1_CSV: &str = include_str!("../../tests/data/thesis/exp1a_multisection.csv");
/// Thesis Tables 4.3/4.4 (experiment 2, tip positions), cm and g.
pub const TABLE_4_3_CSV: &str = include_str!("../../tests/data/thesis/exp2_cable_guides_tip.csv");
/// Thesis Table 4.5 (experiment 2, cable deflection), cm and g.
pub const TABLE_4_5_CSV: &str = include_str!("../../tests/data/thesis/exp2_cable_deflection.csv");

/// The numeric rows of a CSV table (comment lines `#` and the header skipped), `N` columns each,
/// without allocation.
pub fn csv_rows<const N: usize>(
    csv: &str,
) -> impl Iterator<Item = Result<[f64; N], ModelError>> + '_ {
    csv.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|line| {
            let mut values = [0.0f64; N];
            let mut fields = line.split(',');
            for v in values.iter_mut() {
                let field = fields
                    .next()
                    .ok_or(ModelError::Mismatch("CSV row fields"))?;
                *v = field
                    .trim()
                    .parse()
                    .map_err(|_| ModelError::NonFinite("CSV value"))?;
            }
            Ok(values)
        })
}

/// One row of the golden reference: a tip force and what an independent f64 solver found for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GoldenRow {
    /// Tip force, N, global frame.
    pub force_n: [f64; 3],
    /// Tip position, m.
    pub tip_m: [f64; 3],
    /// Tip tangent (unit).
    pub tangent: [f64; 3],
    /// Cable lengths, m (cables at 0, 120, 240 degrees).
    pub cables_m: [f64; 3],
}

impl GoldenRow {
    fn from_values(values: [f64; 12]) -> Self {
        let [fx, fy, fz, x, y, z, tx, ty, tz, c0, c1, c2] = values;
        Self {
            force_n: [fx, fy, fz],
            tip_m: [x, y, z],
            tangent: [tx, ty, tz],
            cables_m: [c0, c1, c2],
        }
    }
}

/// The golden rows.
pub fn golden_rows() -> impl Iterator<Item = Result<GoldenRow, ModelError>> {
    csv_rows::<12>(GOLDEN_CSV).map(|r| r.map(GoldenRow::from_values))
}
