//! Scene files (TOML): the rod and its sections, guides, cables, tendons and their actuation, loads,
//! gravity, output points, solver and estimator settings. Keys carry their units; unknown keys are
//! refused, so a typo is an error and not a silently ignored setting. `host-sim/SCENES.md` documents
//! every key. Every refusal names its line (`locate.rs`), and numbers no robot has are
//! refused or warned about with the likely unit slip (`plausible.rs`).
//!
//! A scene becomes a [`model_core::Rod`] in SI units through [`Scene::rod`], its tendons a
//! [`model_core::Tendons`] checked against the model through [`Scene::tendon_set`], their actuation
//! an [`Actuation`] through [`Scene::actuation`]; every error names the field and the reason.
//!
//! Sizes are checked before anything is sized by them: a count read from the file (`guides.count`,
//! `output.points`, the `[[tendon]]` tables and the `[actuation]` lists) is checked against its limit ([`model_core::MAX_GUIDES`],
//! [`MAX_OUTPUT_POINTS`]) before a vector is built from it, and the RK4 steps of all sections together
//! against [`MAX_TOTAL_STEPS`], so a mistyped number is a [`SceneError`] naming the key and the limit,
//! never a panic, an aborted allocation or a solve that runs for minutes. [`Scene::parse`] runs these
//! checks; the methods that expand the counts run them again, since a `Scene`'s fields are public.

use std::fmt;
use std::path::Path;

use model_core::{
    Attitude, Cable, CrossSection, Guide, GuideMass, MAX_CABLES, MAX_GUIDES, MAX_POINT_LOADS,
    MAX_SECTIONS, MAX_TENDONS, Material, Model, PointLoad, Rod, Section, ShootingSettings, Sliding,
    Stiffness, StrainModel, Tendon, TendonInverseSettings, Tendons, TipLoad,
};
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

mod drive;
mod locate;
mod plausible;

pub use drive::{ControllerSpec, DriveSpec};

pub use locate::locate;

/// Most output points (`output.points`, or the length of `output.s_m`): far more than a plot or a
/// comparison needs, and small enough that the shape (about 100 bytes a point, more as JSON) stays
/// well within memory.
pub const MAX_OUTPUT_POINTS: usize = 100_000;

/// The loosest `[solver] tolerance` a scene may set (the dimensionless tip-moment residual; the
/// tip may be off by about half of it times the rod's length). Above a millionth it is warned about.
pub const MAX_SOLVER_TOLERANCE: f64 = 1e-3;

/// Most RK4 steps in one sweep, summed over the sections' `steps`. A solve takes up to several hundred
/// sweeps (426 for a load continuation that fails on the 3D bench), at about 0.4 us a step on a
/// desktop: this many steps keep the worst solve within seconds (a scene of 8 sections x 65 535 steps
/// took 84 s), and it is 100 times what the shipped scenes use.
pub const MAX_TOTAL_STEPS: u32 = 20_000;

/// A count read from a scene file (`guides.count`, `output.points`), kept as written until it is
/// checked against its limit: any TOML number is accepted here, so that a negative, fractional or huge
/// value is refused by [`Count::checked`] with the key and the limit rather than by the TOML parser
/// with a type name. A float with a whole value (`points = 1e3`) counts as that whole number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Count {
    /// Written as an integer.
    Integer(i128),
    /// Written as a float.
    Float(f64),
}

impl Count {
    /// The count, if it is a whole number in `min..=max`; otherwise an error at `field` that names the
    /// limits (`limit` says where `max` comes from).
    pub fn checked(
        self,
        field: &str,
        min: usize,
        max: usize,
        limit: &str,
    ) -> Result<usize, SceneError> {
        let whole = match self {
            Self::Integer(n) => Some(n),
            // A whole float converts exactly, or saturates far beyond any limit.
            Self::Float(x) if x.is_finite() && x.fract() == 0.0 => Some(x as i128),
            Self::Float(_) => None,
        };
        whole
            .and_then(|n| usize::try_from(n).ok())
            .filter(|n| (min..=max).contains(n))
            .ok_or_else(|| {
                SceneError::new(
                    field,
                    format!(
                        "{self} is not allowed: must be a whole number from {min} to {max} ({limit})"
                    ),
                )
            })
    }
}

impl fmt::Display for Count {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Integer(n) => write!(f, "{n}"),
            Self::Float(x) => write!(f, "{x:?}"),
        }
    }
}

impl<'de> Deserialize<'de> for Count {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Count;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a whole number")
            }
            fn visit_i64<E>(self, n: i64) -> Result<Count, E> {
                Ok(Count::Integer(n.into()))
            }
            fn visit_u64<E>(self, n: u64) -> Result<Count, E> {
                Ok(Count::Integer(n.into()))
            }
            fn visit_f64<E>(self, x: f64) -> Result<Count, E> {
                Ok(Count::Float(x))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// Why a scene could not be used: the field and the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// Where: a file, or a dotted field path such as `section[1].length_m`.
    pub field: String,
    /// What is wrong with it.
    pub reason: String,
}

impl SceneError {
    /// An error at `field`.
    pub fn new(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.reason)
    }
}

impl std::error::Error for SceneError {}

/// A whole scene file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// What the scene is.
    #[serde(default)]
    pub name: String,
    /// Gravity, m/s^2, global frame (default: 9.81 along -y).
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
    /// The clamp.
    #[serde(default)]
    pub base: Base,
    /// Sections from base to tip.
    #[serde(rename = "section")]
    pub sections: Vec<SectionSpec>,
    /// Cable guides.
    #[serde(default)]
    pub guides: Option<Guides>,
    /// Cables through the guides (passive: they measure).
    #[serde(default, rename = "cable")]
    pub cables: Vec<CableSpec>,
    /// Tendons through the guides' holes (they pull; at most [`MAX_TENDONS`]).
    #[serde(default, rename = "tendon")]
    pub tendons: Vec<TendonSpec>,
    /// How the tendons are actuated: tensions or spool displacements, one per tendon.
    #[serde(default)]
    pub actuation: Option<ActuationSpec>,
    /// Point loads on the backbone.
    #[serde(default, rename = "load")]
    pub loads: Vec<LoadSpec>,
    /// The tip load (the unknown of the inverse; a given of `solve`).
    #[serde(default)]
    pub tip: TipSpec,
    /// Where to report the shape.
    #[serde(default)]
    pub output: Output,
    /// Forward-solver settings.
    #[serde(default)]
    pub solver: Solver,
    /// Inverse settings.
    #[serde(default)]
    pub estimate: EstimateSpec,
    /// The spools, gearheads, sensors and steppers (the firmware's; `drive.rs`).
    #[serde(default)]
    pub drive: Option<DriveSpec>,
    /// The estimator loop on the MCU (the firmware's; `drive.rs`).
    #[serde(default)]
    pub controller: Option<ControllerSpec>,
}

/// Standard gravity, m/s^2: a scene's gravity when it gives none, along global -y.
pub const STANDARD_GRAVITY_M_S2: f64 = 9.81;

fn default_gravity() -> [f64; 3] {
    [0.0, -STANDARD_GRAVITY_M_S2, 0.0]
}

/// The clamp: position and the frame's local x and z (tangent) axes in global coordinates.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Base {
    /// Base position, m.
    #[serde(default)]
    pub position_m: [f64; 3],
    /// The local x axis (the side of cable angle 0), global coordinates.
    pub local_x: [f64; 3],
    /// The tangent (local z), global coordinates.
    pub tangent: [f64; 3],
}

impl Default for Base {
    /// The thesis bench: tangent along +x, local x (cable 0) along +y.
    fn default() -> Self {
        Self {
            position_m: [0.0; 3],
            local_x: [0.0, 1.0, 0.0],
            tangent: [1.0, 0.0, 0.0],
        }
    }
}

/// One section.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SectionSpec {
    /// Reference length, m.
    pub length_m: f64,
    /// RK4 steps over the section.
    pub steps: u16,
    /// Line density of the rod, kg/m (or give `density_kg_m3` with a diameter).
    pub line_density_kg_per_m: Option<f64>,
    /// Material density, kg/m^3 (line density = density x area).
    pub density_kg_m3: Option<f64>,
    /// Material (with `cross_section`), or `stiffness` directly.
    pub material: Option<MaterialSpec>,
    /// Cross-section (with `material`).
    pub cross_section: Option<CrossSectionSpec>,
    /// Stiffness given directly.
    pub stiffness: Option<StiffnessSpec>,
}

/// An isotropic material: Young's modulus and Poisson's ratio or shear modulus.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Young's modulus, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio (shear modulus `E / 2(1 + nu)`).
    pub poisson_ratio: Option<f64>,
    /// Shear modulus, Pa.
    pub shear_modulus_pa: Option<f64>,
}

/// A circular cross-section.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CrossSectionSpec {
    /// Outer diameter, m.
    pub diameter_m: f64,
    /// Inner diameter for a tube, m.
    #[serde(default)]
    pub inner_diameter_m: f64,
}

/// Stiffness given directly.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StiffnessSpec {
    /// E I1, E I2 and G J, N m^2.
    pub bending_torsion_nm2: [f64; 3],
    /// G A, G A and E A, N.
    pub shear_axial_n: [f64; 3],
}

/// Cable guides: evenly spaced (`first_centre_m`, `pitch_m`, `count`) or listed (`centres_m`).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Guides {
    /// How guide mass enters: "ignore", "average" or "accurate".
    #[serde(default = "default_mass_model")]
    pub mass_model: String,
    /// Centre of the first guide, m.
    pub first_centre_m: Option<f64>,
    /// Centre-to-centre spacing, m.
    pub pitch_m: Option<f64>,
    /// Number of evenly spaced guides (at most [`model_core::MAX_GUIDES`]).
    pub count: Option<Count>,
    /// Explicit centres, m.
    pub centres_m: Option<Vec<f64>>,
    /// Thickness along the backbone, m (every guide).
    #[serde(default)]
    pub thickness_m: f64,
    /// Mass of each guide, kg (every guide).
    #[serde(default)]
    pub mass_kg: f64,
    /// Thickness of each guide, m, one per guide in order (instead of `thickness_m`).
    pub thicknesses_m: Option<Vec<f64>>,
    /// Mass of each guide, kg, one per guide in order (instead of `mass_kg`).
    pub masses_kg: Option<Vec<f64>>,
}

fn default_mass_model() -> String {
    "accurate".into()
}

/// A cable.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CableSpec {
    /// Hole angle about the tangent from local x, degrees.
    pub angle_deg: f64,
    /// Hole distance from the backbone, m.
    pub radius_m: f64,
    /// Termination arc length, m (default: the tip).
    pub end_m: Option<f64>,
}

/// A tendon: it runs from its spool through a hole in the base plate and the same hole in every
/// guide up to the guide where it ends, and pulls.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TendonSpec {
    /// Hole angle about the tangent from local x, degrees.
    pub angle_deg: f64,
    /// Hole distance from the backbone, m.
    pub radius_m: f64,
    /// Arc length of the guide where it ends, m (default: the tip); must be a guide's centre.
    pub end_m: Option<f64>,
    /// Axial stiffness `E_t A_t` of the tendon, N (absent: inextensible).
    pub axial_stiffness_n: Option<f64>,
    /// Free length from the spool to the base plate's hole, m (it stretches too; default 0).
    #[serde(default)]
    pub feed_length_m: f64,
    /// Coulomb friction coefficient at the holes (capstan law; default 0, frictionless).
    #[serde(default)]
    pub friction_coefficient: f64,
}

/// How the tendons are actuated: exactly one of the two lists, one entry per `[[tendon]]`, in order.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ActuationSpec {
    /// Force control: each tendon's tension, N (not negative).
    pub tensions_n: Option<Vec<f64>>,
    /// Displacement control: each spool's displacement, m, positive when taken in, from the setting
    /// on the straight unloaded rod at zero tension.
    pub displacements_m: Option<Vec<f64>>,
    /// Which way the tendons slide through their holes, for the sign of their friction: "in" (the
    /// spools take them in: loading; default) or "out" (paying out: unloading).
    pub sliding: Option<String>,
}

/// Which quantity actuates the tendons.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Tensions given, N (force control).
    Tensions,
    /// Spool displacements given, m (displacement control): the tensions are solved for.
    Displacements,
}

/// The tendons' actuation, one value per tendon, from the scene or the command line.
#[derive(Debug, Clone, PartialEq)]
pub struct Actuation {
    /// Tensions or displacements.
    pub control: Control,
    /// One value per tendon: N for tensions, m for displacements.
    pub values: Vec<f64>,
    /// Where the values come from, to name it in errors (`actuation.tensions_n`, `--tensions`).
    pub key: String,
}

impl Actuation {
    /// Checks the values against `tendons`: one per tendon, each finite; a tension not negative; a
    /// displacement shorter than the tendon's whole length (spool to termination). Errors name
    /// `key[i]`.
    pub fn check(&self, tendons: &Tendons<f64>) -> Result<(), SceneError> {
        if self.values.len() != tendons.len() {
            return Err(SceneError::new(
                &self.key,
                format!(
                    "{} for {} (one per [[tendon]], in order)",
                    counted(self.values.len(), "value"),
                    counted(tendons.len(), "tendon")
                ),
            ));
        }
        for (i, (&x, t)) in self.values.iter().zip(tendons.tendons()).enumerate() {
            let field = format!("{}[{i}]", self.key);
            finite(&field, x)?;
            match self.control {
                Control::Tensions if x < 0.0 => {
                    return Err(SceneError::new(
                        field,
                        format!("{x} N: a tension must not be negative (a tendon only pulls)"),
                    ));
                }
                Control::Displacements => {
                    let whole_m = tendons.rest_length_m(i).unwrap_or(0.0) + t.feed_length_m;
                    if x >= whole_m {
                        return Err(SceneError::new(
                            field,
                            format!(
                                "{x} m taken in: at least the tendon's whole length, {whole_m} m \
                                 from spool to termination"
                            ),
                        ));
                    }
                }
                Control::Tensions => {}
            }
        }
        Ok(())
    }
}

/// Measured tensions from the command line, for [`Scene::tension_measurement`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TensionArgs {
    /// `--tensions-measured`, N.
    pub tensions_n: Option<Vec<f64>>,
    /// `--tension-std`, N (one for all).
    pub std_n: Option<f64>,
    /// `--tension-stds`, N (one per tendon).
    pub stds_n: Option<Vec<f64>>,
}

/// Measured tensions, checked: one value and one standard deviation per tendon, N.
#[derive(Debug, Clone, PartialEq)]
pub struct TensionMeasurement {
    /// The measured tensions, N.
    pub tensions_n: Vec<f64>,
    /// Their standard deviations, N (positive).
    pub std_n: Vec<f64>,
    /// Where the tensions come from (`--tensions-measured` or
    /// `estimate.tendons.tensions_measured_n`).
    pub key: String,
    /// Where the standard deviations come from.
    pub std_key: String,
}

/// A point load.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Arc length, m.
    pub s_m: f64,
    /// Hung mass, kg.
    #[serde(default)]
    pub mass_kg: f64,
    /// Force, N, global frame.
    #[serde(default)]
    pub force_n: [f64; 3],
    /// Moment, N m, global frame.
    #[serde(default)]
    pub moment_nm: [f64; 3],
}

/// The tip load.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TipSpec {
    /// Force, N, global frame.
    #[serde(default)]
    pub force_n: [f64; 3],
    /// Moment, N m, global frame.
    #[serde(default)]
    pub moment_nm: [f64; 3],
    /// A mass hung at the tip, kg (its weight adds to the force).
    #[serde(default)]
    pub mass_kg: f64,
}

/// Output points: explicit arc lengths, or `points` evenly spaced from base to tip.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Arc lengths, m, increasing.
    pub s_m: Option<Vec<f64>>,
    /// Evenly spaced points including both ends (at most [`MAX_OUTPUT_POINTS`]).
    #[serde(default = "default_points")]
    pub points: Count,
}

fn default_points() -> Count {
    Count::Integer(41)
}

impl Default for Output {
    fn default() -> Self {
        Self {
            s_m: None,
            points: default_points(),
        }
    }
}

/// Forward-solver settings.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Solver {
    /// Frame integration: "quaternion", "rotation-matrix" or "lie-group".
    #[serde(default = "default_attitude")]
    pub attitude: String,
    /// "cosserat" (shear and extension) or "kirchhoff" (neither).
    #[serde(default = "default_strain_model")]
    pub strain_model: String,
    /// Dimensionless tolerance on the tip-moment residual (default: model-core's).
    pub tolerance: Option<f64>,
    /// Newton iterations.
    #[serde(default = "default_iterations")]
    pub max_iterations: u16,
    /// Run the stability test on answers. Without it an unstable equilibrium (a wrong branch: buckled,
    /// upside down, looped) is reported as converged; `solve` and `estimate` warn and say so in their
    /// status.
    #[serde(default = "default_true")]
    pub check_stability: bool,
}

fn default_attitude() -> String {
    "quaternion".into()
}
fn default_strain_model() -> String {
    "cosserat".into()
}
fn default_iterations() -> u16 {
    40
}
fn default_true() -> bool {
    true
}

impl Default for Solver {
    fn default() -> Self {
        Self {
            attitude: default_attitude(),
            strain_model: default_strain_model(),
            tolerance: None,
            max_iterations: default_iterations(),
            check_stability: true,
        }
    }
}

/// Inverse settings.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EstimateSpec {
    /// Resolution of a cable-length measurement, m (standard deviation = resolution / sqrt 12).
    #[serde(default = "default_resolution")]
    pub resolution_m: f64,
    /// A force component with a larger standard deviation makes the estimate "weak", N.
    #[serde(default = "default_max_force_std")]
    pub max_force_std_n: f64,
    /// The tendon inverse's own settings and measured tensions (`[estimate.tendons]`); only for a
    /// scene with `[[tendon]]`.
    #[serde(default)]
    pub tendons: Option<TendonEstimateSpec>,
}

/// `[estimate.tendons]`: what the tendon inverse needs besides the spool displacements and the
/// `[estimate]` table's `resolution_m` and `max_force_std_n`. Every key is optional.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TendonEstimateSpec {
    /// Measured tensions (motor current, a load cell), N, one per `[[tendon]]`.
    pub tensions_measured_n: Option<Vec<f64>>,
    /// One standard deviation for every measured tension, N.
    pub tension_std_n: Option<f64>,
    /// A standard deviation per measured tension, N, one per `[[tendon]]`.
    pub tension_stds_n: Option<Vec<f64>>,
    /// The model's own error in a tendon path, m, added in quadrature to the encoder's (default 0).
    pub model_length_std_m: Option<f64>,
    /// The prior's standard deviation of each tip force component, N (default 1).
    pub force_prior_std_n: Option<f64>,
    /// A tension with a larger standard deviation makes the estimate "weak", N (default 0.05).
    pub max_tension_std_n: Option<f64>,
    /// How far the search for other answers restarts, in buckling scales `E I / L^2` of tip force
    /// (default 3; 0: no search, and the verdict is at best `Unverified`).
    pub scan_reach: Option<f64>,
    /// Levenberg-Marquardt iterations per fit (default 40).
    pub max_iterations: Option<u16>,
}

fn default_resolution() -> f64 {
    // A 4096-count encoder on a 5 mm-radius spool.
    2.0 * std::f64::consts::PI * 5e-3 / 4096.0
}
fn default_max_force_std() -> f64 {
    0.05
}

impl Default for EstimateSpec {
    fn default() -> Self {
        Self {
            resolution_m: default_resolution(),
            max_force_std_n: default_max_force_std(),
            tendons: None,
        }
    }
}

/// How the frame is integrated (see `model_core::kinematics`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AttitudeChoice {
    /// Quaternion RK4 (the default).
    Quaternion,
    /// Rotation-matrix RK4 (as the thesis).
    RotationMatrix,
    /// Lie-group RKMK4.
    LieGroup,
}

fn vec3(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v)
}

fn finite(field: &str, x: f64) -> Result<f64, SceneError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(SceneError::new(field, "must be a finite number"))
    }
}

/// `x` if it is finite and above zero; else an error at `field` that shows it.
fn positive(field: &str, x: f64) -> Result<f64, SceneError> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(SceneError::new(
            field,
            format!("{x}: must be a positive number"),
        ))
    }
}

impl Scene {
    /// Parses a scene from TOML text; `origin` names it in errors. Checks every size (see the
    /// module's documentation) before returning.
    ///
    /// Refuses the values the rod model cannot mean (`plausible.rs`: a modulus below 1 MPa, a
    /// diameter half the rod's length), naming the likely unit slip; [`Scene::warnings`] lists the
    /// merely unusual ones. Every error names its line in `text` ([`locate`]).
    pub fn parse(text: &str, origin: &str) -> Result<Self, SceneError> {
        let scene: Self =
            toml::from_str(text).map_err(|e| locate::explain_parse(&e, text, origin))?;
        scene
            .check_sizes()
            .and_then(|()| scene.check_drive())
            .and_then(|()| scene.check_plausible())
            .map_err(|e| locate(e, text, origin))?;
        Ok(scene)
    }

    /// Every count and size the scene expands into vectors or work, against its limit: the sections
    /// (at most [`MAX_SECTIONS`]) and their steps summed ([`MAX_TOTAL_STEPS`]), the guides, the output
    /// points. Nothing here allocates in proportion to a number read from the file.
    pub fn check_sizes(&self) -> Result<(), SceneError> {
        if self.sections.len() > MAX_SECTIONS {
            return Err(SceneError::new(
                "section",
                format!(
                    "{} sections; at most {MAX_SECTIONS} (model-core's MAX_SECTIONS)",
                    self.sections.len()
                ),
            ));
        }
        self.total_steps()?;
        if let Some(guides) = &self.guides {
            guides.count()?;
        }
        for (key, count, limit, name) in [
            ("cable", self.cables.len(), MAX_CABLES, "MAX_CABLES"),
            ("load", self.loads.len(), MAX_POINT_LOADS, "MAX_POINT_LOADS"),
        ] {
            if count > limit {
                return Err(SceneError::new(
                    key,
                    format!("{count} [[{key}]] tables; at most {limit} (model-core's {name})"),
                ));
            }
        }
        self.output_point_count()?;
        self.check_tendon_counts()?;
        Ok(())
    }

    /// The `[[tendon]]` tables (at most [`MAX_TENDONS`]) and the `[actuation]` table: exactly one of
    /// its lists, one entry per tendon, and no actuation without tendons.
    fn check_tendon_counts(&self) -> Result<(), SceneError> {
        let n = self.tendons.len();
        if n > MAX_TENDONS {
            return Err(SceneError::new(
                "tendon",
                format!("{n} [[tendon]] tables; at most {MAX_TENDONS} (model-core's MAX_TENDONS)"),
            ));
        }
        self.check_tendon_estimate_counts()?;
        let Some(a) = &self.actuation else {
            return Ok(());
        };
        let (key, len) = match (&a.tensions_n, &a.displacements_m) {
            (Some(t), None) => ("actuation.tensions_n", t.len()),
            (None, Some(d)) => ("actuation.displacements_m", d.len()),
            (Some(_), Some(_)) => {
                return Err(SceneError::new(
                    "actuation",
                    "give either tensions_n (force control) or displacements_m (displacement \
                     control), not both",
                ));
            }
            (None, None) => {
                let only_sliding = if a.sliding.is_some() {
                    " (sliding alone says which way they move, not how far or how hard)"
                } else {
                    ""
                };
                return Err(SceneError::new(
                    "actuation",
                    format!(
                        "give tensions_n (force control) or displacements_m (displacement \
                         control), one entry per [[tendon]]{only_sliding}"
                    ),
                ));
            }
        };
        if n == 0 {
            return Err(SceneError::new(
                "actuation",
                "the scene has no [[tendon]] to actuate",
            ));
        }
        if len != n {
            return Err(SceneError::new(
                key,
                format!(
                    "{} for {} (one per [[tendon]], in order)",
                    counted(len, "value"),
                    counted(n, "tendon")
                ),
            ));
        }
        Ok(())
    }

    /// `[estimate.tendons]`: only with tendons; its lists one entry per tendon; not both
    /// `tension_std_n` and `tension_stds_n`.
    fn check_tendon_estimate_counts(&self) -> Result<(), SceneError> {
        let Some(t) = &self.estimate.tendons else {
            return Ok(());
        };
        let n = self.tendons.len();
        if n == 0 {
            return Err(SceneError::new(
                "estimate.tendons",
                "the scene has no [[tendon]] to estimate",
            ));
        }
        if t.tension_std_n.is_some() && t.tension_stds_n.is_some() {
            return Err(SceneError::new(
                "estimate.tendons",
                "give either tension_std_n (one for all) or tension_stds_n (one per tendon), not \
                 both",
            ));
        }
        for (key, list) in [
            (
                "estimate.tendons.tensions_measured_n",
                &t.tensions_measured_n,
            ),
            ("estimate.tendons.tension_stds_n", &t.tension_stds_n),
        ] {
            if let Some(v) = list
                && v.len() != n
            {
                return Err(SceneError::new(
                    key,
                    format!(
                        "{} for {} (one per [[tendon]], in order)",
                        counted(v.len(), "value"),
                        counted(n, "tendon")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The tendon inverse's settings: the displacement's standard deviation from
    /// `[estimate] resolution_m` (`resolution / sqrt 12`), `max_force_std_n` from `[estimate]`, the
    /// rest from `[estimate.tendons]` or model-core's defaults. Each value is checked, naming its key.
    pub fn tendon_inverse_settings(&self) -> Result<TendonInverseSettings<f64>, SceneError> {
        let e = &self.estimate;
        let non_negative = |key: &str, x: f64| {
            if x.is_finite() && x >= 0.0 {
                Ok(x)
            } else {
                Err(SceneError::new(
                    key,
                    format!("{x}: must be a number not below zero"),
                ))
            }
        };
        let defaults = TendonInverseSettings::<f64>::default();
        let t = e.tendons.clone().unwrap_or_default();
        Ok(TendonInverseSettings {
            max_iterations: t.max_iterations.unwrap_or(defaults.max_iterations),
            displacement_std_m: positive("estimate.resolution_m", e.resolution_m)? / 12f64.sqrt(),
            model_length_std_m: non_negative(
                "estimate.tendons.model_length_std_m",
                t.model_length_std_m.unwrap_or(defaults.model_length_std_m),
            )?,
            force_prior_std_n: positive(
                "estimate.tendons.force_prior_std_n",
                t.force_prior_std_n.unwrap_or(defaults.force_prior_std_n),
            )?,
            max_force_std_n: positive("estimate.max_force_std_n", e.max_force_std_n)?,
            max_tension_std_n: positive(
                "estimate.tendons.max_tension_std_n",
                t.max_tension_std_n.unwrap_or(defaults.max_tension_std_n),
            )?,
            scan_reach: non_negative(
                "estimate.tendons.scan_reach",
                t.scan_reach.unwrap_or(defaults.scan_reach),
            )?,
        })
    }

    /// The measured tensions for the tendon inverse, if any: the command line's (`--tensions-measured`
    /// with `--tension-std` or `--tension-stds`) before the scene's (`[estimate.tendons]`). Measured
    /// tensions need a standard deviation; a standard deviation from the command line needs measured
    /// tensions (one in the scene alone is the sensor's, kept for when tensions are given). One value
    /// per tendon, each finite; every standard deviation positive. Errors name the key and the index.
    pub fn tension_measurement(
        &self,
        given: TensionArgs,
    ) -> Result<Option<TensionMeasurement>, SceneError> {
        let n = self.tendons.len();
        let spec = self.estimate.tendons.clone().unwrap_or_default();
        let tensions = match (given.tensions_n, spec.tensions_measured_n) {
            (Some(v), _) => Some((v, "--tensions-measured")),
            (None, Some(v)) => Some((v, "estimate.tendons.tensions_measured_n")),
            (None, None) => None,
        };
        // (values, key, whether the key is one value for all, whether from the command line)
        let stds = match (
            given.std_n,
            given.stds_n,
            spec.tension_std_n,
            spec.tension_stds_n,
        ) {
            (Some(s), _, _, _) => Some((vec![s; n], "--tension-std", true, true)),
            (None, Some(v), _, _) => Some((v, "--tension-stds", false, true)),
            (None, None, Some(s), _) => {
                Some((vec![s; n], "estimate.tendons.tension_std_n", true, false))
            }
            (None, None, None, Some(v)) => {
                Some((v, "estimate.tendons.tension_stds_n", false, false))
            }
            (None, None, None, None) => None,
        };
        if n == 0 {
            let key = tensions
                .as_ref()
                .map(|t| t.1)
                .or(stds.as_ref().filter(|s| s.3).map(|s| s.1));
            return match key {
                Some(key) => Err(SceneError::new(key, "the scene has no [[tendon]]")),
                None => Ok(None),
            };
        }
        let (tensions_n, key) = match (tensions, &stds) {
            (None, Some((_, key, _, true))) => {
                return Err(SceneError::new(
                    *key,
                    "a tension standard deviation without measured tensions (give \
                     --tensions-measured, one per [[tendon]])",
                ));
            }
            (None, _) => return Ok(None),
            (Some(t), _) => t,
        };
        let Some((std_n, std_key, one_for_all, _)) = stds else {
            return Err(SceneError::new(
                key,
                "measured tensions need their standard deviation: give --tension-std (one for \
                 all, N) or --tension-stds (one per tendon, N), or tension_std_n or \
                 tension_stds_n in [estimate.tendons]",
            ));
        };
        for (list, key) in [(&tensions_n, key), (&std_n, std_key)] {
            if list.len() != n {
                return Err(SceneError::new(
                    key,
                    format!(
                        "{} for {} (one per [[tendon]], in order)",
                        counted(list.len(), "value"),
                        counted(n, "tendon")
                    ),
                ));
            }
        }
        for (i, t) in tensions_n.iter().enumerate() {
            finite(&format!("{key}[{i}]"), *t)?;
        }
        for (i, s) in std_n.iter().enumerate() {
            let field = if one_for_all {
                std_key.to_string()
            } else {
                format!("{std_key}[{i}]")
            };
            if !(s.is_finite() && *s > 0.0) {
                return Err(SceneError::new(
                    field,
                    format!("{s} N: a standard deviation must be a positive number"),
                ));
            }
        }
        Ok(Some(TensionMeasurement {
            tensions_n,
            std_n,
            key: key.to_string(),
            std_key: std_key.to_string(),
        }))
    }

    /// The tendons' actuation as the scene gives it (`None` for a scene without tendons). A scene
    /// with tendons needs an `[actuation]` table (the command line may give one instead: see
    /// [`Scene::actuation_or`]).
    pub fn actuation(&self) -> Result<Option<Actuation>, SceneError> {
        self.actuation_or(None)
    }

    /// The tendons' actuation: `given` (from the command line) if any, else the scene's. The counts
    /// are checked here; the values against the tendons by [`Actuation::check`].
    pub fn actuation_or(&self, given: Option<Actuation>) -> Result<Option<Actuation>, SceneError> {
        self.check_tendon_counts()?;
        if self.tendons.is_empty() {
            return match given {
                Some(a) => Err(SceneError::new(
                    a.key,
                    "the scene has no [[tendon]] to actuate",
                )),
                None => Ok(None),
            };
        }
        if let Some(a) = given {
            return Ok(Some(a));
        }
        match &self.actuation {
            Some(ActuationSpec {
                tensions_n: Some(t),
                ..
            }) => Ok(Some(Actuation {
                control: Control::Tensions,
                values: t.clone(),
                key: "actuation.tensions_n".into(),
            })),
            Some(ActuationSpec {
                displacements_m: Some(d),
                ..
            }) => Ok(Some(Actuation {
                control: Control::Displacements,
                values: d.clone(),
                key: "actuation.displacements_m".into(),
            })),
            _ => Err(SceneError::new(
                "actuation",
                "missing: a scene with [[tendon]] needs an [actuation] table with tensions_n or \
                 displacements_m (or give --tensions or --displacements)",
            )),
        }
    }

    /// The tendons in SI units, each checked on its own (the fields that need no model):
    /// `end_m` defaults to the tip.
    pub fn tendon_specs(&self) -> Result<Vec<Tendon<f64>>, SceneError> {
        self.check_tendon_counts()?;
        let length_m: f64 = self.sections.iter().map(|s| s.length_m).sum();
        self.tendons
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let field = |key: &str| format!("tendon[{i}].{key}");
                let angle = finite(&field("angle_deg"), t.angle_deg)?;
                let radius = finite(&field("radius_m"), t.radius_m)?;
                if radius < 0.0 {
                    return Err(SceneError::new(
                        field("radius_m"),
                        "must not be negative (the angle gives the side)",
                    ));
                }
                let end = finite(&field("end_m"), t.end_m.unwrap_or(length_m))?;
                let feed = finite(&field("feed_length_m"), t.feed_length_m)?;
                if feed < 0.0 {
                    return Err(SceneError::new(
                        field("feed_length_m"),
                        "must not be negative",
                    ));
                }
                let mu = finite(&field("friction_coefficient"), t.friction_coefficient)?;
                if mu < 0.0 {
                    return Err(SceneError::new(
                        field("friction_coefficient"),
                        "must not be negative (0: frictionless)",
                    ));
                }
                if let Some(k) = t.axial_stiffness_n
                    && !(k.is_finite() && k > 0.0)
                {
                    return Err(SceneError::new(
                        field("axial_stiffness_n"),
                        "must be a positive number (leave it out for an inextensible tendon)",
                    ));
                }
                Ok(Tendon {
                    axial_stiffness_n: t.axial_stiffness_n,
                    feed_length_m: feed,
                    friction_coefficient: mu,
                    ..Tendon::at_angle(angle.to_radians(), radius, end)
                })
            })
            .collect()
    }

    /// The tendons checked against `model`'s guides (`None` for a scene without tendons). Each must
    /// end at a guide's centre (within a micrometre, as model-core requires); the guides must lie
    /// distal of the base plate.
    pub fn tendon_set<A: Attitude<f64>, const NODES: usize>(
        &self,
        model: &Model<f64, A, NODES>,
    ) -> Result<Option<Tendons<f64>>, SceneError> {
        let specs = self.tendon_specs()?;
        if specs.is_empty() {
            return Ok(None);
        }
        let guides = &model.rod().guides;
        if guides.is_empty() {
            return Err(SceneError::new(
                "guides",
                "tendons need guides: a [[tendon]] runs through the guides' holes and ends at one",
            ));
        }
        for (i, (t, spec)) in specs.iter().zip(&self.tendons).enumerate() {
            if !guides.iter().any(|g| (g.s_m - t.end_m).abs() <= 1e-6) {
                let which = if spec.end_m.is_some() {
                    format!("{} m", t.end_m)
                } else {
                    format!("{} m (the tip, the default)", t.end_m)
                };
                return Err(SceneError::new(
                    format!("tendon[{i}].end_m"),
                    format!(
                        "{which} is not a guide's centre: a tendon ends at a guide (give a guide's \
                         centre, or add a guide there)"
                    ),
                ));
            }
        }
        Tendons::new(model, &specs)
            .map_err(|e| {
                use model_core::ModelError::*;
                let what = match &e {
                    NonFinite(w) | NotPositive(w) | OutOfRange(w) | Unordered(w) | Capacity(w)
                    | Empty(w) | Mismatch(w) => *w,
                };
                // A refusal of one tendon names the first refused on its own; of the guides, the guides.
                let field = if what.starts_with("tendons") {
                    "tendon".to_string()
                } else if what.starts_with("tendon") {
                    specs
                        .iter()
                        .position(|t| Tendons::new(model, core::slice::from_ref(t)).is_err())
                        .map_or_else(|| "tendon".to_string(), |i| format!("tendon[{i}]"))
                } else {
                    "guides".to_string()
                };
                SceneError::new(field, e.to_string())
            })
            .and_then(|mut set| {
                let sliding = match self.actuation.as_ref().and_then(|a| a.sliding.as_deref()) {
                    None | Some("in") => Sliding::In,
                    Some("out") => Sliding::Out,
                    Some(other) => {
                        return Err(SceneError::new(
                            "actuation.sliding",
                            format!("\"{other}\" is not \"in\" (loading) or \"out\" (unloading)"),
                        ));
                    }
                };
                for j in 0..set.len() {
                    set.set_sliding(j, sliding);
                }
                Ok(Some(set))
            })
    }

    /// RK4 steps in one sweep, summed over the sections (the plan adds at most one a guide, load or
    /// section end), if within [`MAX_TOTAL_STEPS`].
    pub fn total_steps(&self) -> Result<u32, SceneError> {
        // u16 steps over at most a few sections: no overflow in u64 whatever the section count.
        let total: u64 = self.sections.iter().map(|s| u64::from(s.steps)).sum();
        u32::try_from(total)
            .ok()
            .filter(|t| *t <= MAX_TOTAL_STEPS)
            .ok_or_else(|| {
                SceneError::new(
                    "section[].steps",
                    format!(
                        "the sections' steps add up to {total} RK4 steps per sweep; at most \
                         {MAX_TOTAL_STEPS} (host-sim's limit: a solve takes up to several hundred \
                         sweeps, and this keeps it within seconds)"
                    ),
                )
            })
    }

    /// How many output points the scene asks for, if within [`MAX_OUTPUT_POINTS`].
    pub fn output_point_count(&self) -> Result<usize, SceneError> {
        match &self.output.s_m {
            Some(s) if s.len() > MAX_OUTPUT_POINTS => Err(SceneError::new(
                "output.s_m",
                format!(
                    "{} arc lengths; at most {MAX_OUTPUT_POINTS} (host-sim's MAX_OUTPUT_POINTS)",
                    s.len()
                ),
            )),
            // (A CSV of no rows would not even say the status.)
            Some(s) if s.is_empty() => Err(SceneError::new(
                "output.s_m",
                "no arc lengths: at least one (or leave it out for `points`)",
            )),
            Some(s) => Ok(s.len()),
            None => self.output.points.checked(
                "output.points",
                2,
                MAX_OUTPUT_POINTS,
                "host-sim's MAX_OUTPUT_POINTS",
            ),
        }
    }

    /// Reads and parses a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            SceneError::new(path.display().to_string(), format!("cannot read: {e}"))
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The frame integration chosen in `[solver]`.
    pub fn attitude(&self) -> Result<AttitudeChoice, SceneError> {
        match self.solver.attitude.as_str() {
            "quaternion" => Ok(AttitudeChoice::Quaternion),
            "rotation-matrix" => Ok(AttitudeChoice::RotationMatrix),
            "lie-group" => Ok(AttitudeChoice::LieGroup),
            other => Err(SceneError::new(
                "solver.attitude",
                format!(
                    "unknown \"{other}\" (expected \"quaternion\", \"rotation-matrix\" or \"lie-group\")"
                ),
            )),
        }
    }

    /// The forward-solver settings.
    pub fn shooting_settings(&self) -> Result<ShootingSettings<f64>, SceneError> {
        let mut settings = ShootingSettings {
            max_iterations: self.solver.max_iterations,
            check_stability: self.solver.check_stability,
            ..ShootingSettings::default()
        };
        if let Some(tolerance) = self.solver.tolerance {
            if !(tolerance.is_finite() && tolerance > 0.0) {
                return Err(SceneError::new(
                    "solver.tolerance",
                    "must be a positive number",
                ));
            }
            // The residual is the tip moment's error in bending scales: the tip may be off by
            // about half the tolerance times the rod's length, and above a thousandth a
            // "converged" answer is no answer (at 1.0 the bench's tip was 11 mm off, converged in
            // no iteration).
            if tolerance > MAX_SOLVER_TOLERANCE {
                return Err(SceneError::new(
                    "solver.tolerance",
                    format!(
                        "{tolerance} is above {MAX_SOLVER_TOLERANCE}: the tip may be off by about \
                         half of it times the rod's length (the default is about 1e-11 in f64)"
                    ),
                ));
            }
            settings.tolerance = tolerance;
        }
        Ok(settings)
    }

    /// The tip load, in SI (the tip mass's weight along gravity added to the force).
    pub fn tip_load(&self) -> Result<TipLoad<f64>, SceneError> {
        for (field, v) in [
            ("tip.force_n", self.tip.force_n),
            ("tip.moment_nm", self.tip.moment_nm),
        ] {
            for x in v {
                finite(field, x)?;
            }
        }
        if !(self.tip.mass_kg.is_finite() && self.tip.mass_kg >= 0.0) {
            return Err(SceneError::new(
                "tip.mass_kg",
                "must be a non-negative number",
            ));
        }
        Ok(TipLoad {
            force_n: vec3(self.tip.force_n) + vec3(self.gravity_m_s2) * self.tip.mass_kg,
            moment_nm: vec3(self.tip.moment_nm),
        })
    }

    /// The output arc lengths, m (their number checked before they are built).
    pub fn output_points_m(&self, length_m: f64) -> Result<Vec<f64>, SceneError> {
        let n = self.output_point_count()?;
        match &self.output.s_m {
            Some(s) => {
                let mut previous = 0.0;
                for (i, &x) in s.iter().enumerate() {
                    let field = format!("output.s_m[{i}]");
                    finite(&field, x)?;
                    if x < previous {
                        return Err(SceneError::new(field, "arc lengths must increase"));
                    }
                    if x > length_m {
                        return Err(SceneError::new(
                            field,
                            format!("{x} m is beyond the tip ({length_m} m)"),
                        ));
                    }
                    previous = x;
                }
                Ok(s.clone())
            }
            None => {
                // n >= 2 (output_point_count).
                Ok((0..n)
                    .map(|i| length_m * i as f64 / (n - 1) as f64)
                    .collect())
            }
        }
    }

    /// The rod in SI units. Fails with the first field that is missing, inconsistent or out of range.
    pub fn rod(&self) -> Result<Rod<f64>, SceneError> {
        let mut rod = Rod::new();
        let cap = |what: &str| SceneError::new(what, "more than the model's fixed capacity");
        for (i, x) in self.gravity_m_s2.iter().enumerate() {
            finite(&format!("gravity_m_s2[{i}]"), *x)?;
        }
        rod.gravity_m_s2 = vec3(self.gravity_m_s2);
        rod.base_position_m = vec3(self.base.position_m);
        rod.base_orientation = self.base_orientation()?;
        rod.strain_model = match self.solver.strain_model.as_str() {
            "cosserat" => StrainModel::Cosserat,
            "kirchhoff" => StrainModel::Kirchhoff,
            other => {
                return Err(SceneError::new(
                    "solver.strain_model",
                    format!("unknown \"{other}\" (expected \"cosserat\" or \"kirchhoff\")"),
                ));
            }
        };
        if self.sections.is_empty() {
            return Err(SceneError::new(
                "section",
                "at least one [[section]] is needed",
            ));
        }
        self.check_sizes()?;
        for (i, spec) in self.sections.iter().enumerate() {
            let section = spec.section(&format!("section[{i}]"))?;
            rod.push_section(section).map_err(|_| cap("section"))?;
        }
        let length_m: f64 = self.sections.iter().map(|s| s.length_m).sum();
        if let Some(guides) = &self.guides {
            rod.guide_mass = match guides.mass_model.as_str() {
                "ignore" => GuideMass::Ignore,
                "average" => GuideMass::Average,
                "accurate" => GuideMass::Accurate,
                other => {
                    return Err(SceneError::new(
                        "guides.mass_model",
                        format!(
                            "unknown \"{other}\" (expected \"ignore\", \"average\" or \"accurate\")"
                        ),
                    ));
                }
            };
            for guide in guides.guides()? {
                rod.push_guide(guide).map_err(|_| cap("guides"))?;
            }
        }
        for (i, c) in self.cables.iter().enumerate() {
            let field = format!("cable[{i}]");
            if c.radius_m < 0.0 {
                return Err(SceneError::new(
                    format!("{field}.radius_m"),
                    format!(
                        "{} m: a hole's distance from the backbone is not negative (to put it on \
                         the other side, add 180 to angle_deg)",
                        c.radius_m
                    ),
                ));
            }
            rod.push_cable(Cable::at_angle(
                finite(&format!("{field}.angle_deg"), c.angle_deg)?.to_radians(),
                finite(&format!("{field}.radius_m"), c.radius_m)?,
                finite(&format!("{field}.end_m"), c.end_m.unwrap_or(length_m))?,
            ))
            .map_err(|_| cap("cables"))?;
        }
        for (i, l) in self.loads.iter().enumerate() {
            rod.push_load(PointLoad {
                s_m: l.s_m,
                mass_kg: l.mass_kg,
                force_n: vec3(l.force_n),
                moment_nm: vec3(l.moment_nm),
            })
            .map_err(|_| cap(&format!("load[{i}]")))?;
        }
        rod.validate().map_err(|e| Self::which_item(&rod, &e))?;
        Ok(rod)
    }

    /// The scene field of a model-core validation error. An error about a cable or a point load
    /// names no item: the item is the first whose rod, with the items before it, fails the same
    /// way, so that the error points at its own `[[cable]]` or `[[load]]` table, not the first.
    fn which_item(rod: &Rod<f64>, e: &model_core::ModelError) -> SceneError {
        let field = field_of(e);
        let failing = |keep: usize| {
            let mut prefix = rod.clone();
            match field {
                "cable" => prefix.cables.truncate(keep),
                _ => prefix.loads.truncate(keep),
            }
            prefix.validate().err() == Some(*e)
        };
        let count = match field {
            "cable" => rod.cables.len(),
            "load" => rod.loads.len(),
            _ => 0,
        };
        match (1..=count).find(|&n| failing(n)) {
            Some(n) => SceneError::new(format!("{field}[{}]", n - 1), e.to_string()),
            None => SceneError::new(field, e.to_string()),
        }
    }

    fn base_orientation(&self) -> Result<Matrix3<f64>, SceneError> {
        let x = vec3(self.base.local_x);
        let z = vec3(self.base.tangent);
        let (nx, nz) = (x.norm(), z.norm());
        if !(nx.is_finite() && nx > 0.0) {
            return Err(SceneError::new("base.local_x", "must be a non-zero vector"));
        }
        if !(nz.is_finite() && nz > 0.0) {
            return Err(SceneError::new("base.tangent", "must be a non-zero vector"));
        }
        let (x, z) = (x / nx, z / nz);
        if x.dot(&z).abs() > 1e-9 {
            return Err(SceneError::new(
                "base.local_x",
                "must be perpendicular to base.tangent",
            ));
        }
        Ok(Matrix3::from_columns(&[x, z.cross(&x), z]))
    }
}

/// Which scene field a model-core validation error points at.
fn field_of(e: &model_core::ModelError) -> &'static str {
    use model_core::ModelError::*;
    let what = match e {
        NonFinite(w) | NotPositive(w) | OutOfRange(w) | Unordered(w) | Capacity(w) | Empty(w)
        | Mismatch(w) => *w,
    };
    match what {
        w if w.starts_with("section") || w.contains("stiffness") || w.contains("density") => {
            "section"
        }
        w if w.starts_with("guide") => "guides",
        w if w.starts_with("cable") => "cable",
        w if w.contains("load") || w.contains("mass") || w.contains("point") => "load",
        w if w.contains("gravity") => "gravity_m_s2",
        w if w.contains("base") => "base",
        _ => "scene",
    }
}

impl SectionSpec {
    fn section(&self, field: &str) -> Result<Section<f64>, SceneError> {
        let length_m = finite(&format!("{field}.length_m"), self.length_m)?;
        if length_m <= 0.0 {
            return Err(SceneError::new(
                format!("{field}.length_m"),
                "must be positive",
            ));
        }
        if self.steps == 0 {
            return Err(SceneError::new(
                format!("{field}.steps"),
                "must be at least 1",
            ));
        }
        let err = |sub: &str, e: model_core::ModelError| {
            SceneError::new(format!("{field}.{sub}"), e.to_string())
        };
        let (stiffness, area) = match (&self.stiffness, &self.material, &self.cross_section) {
            (Some(k), None, None) => (
                Stiffness::new(vec3(k.bending_torsion_nm2), vec3(k.shear_axial_n))
                    .map_err(|e| err("stiffness", e))?,
                None,
            ),
            (None, Some(m), Some(c)) => {
                let material = match (m.poisson_ratio, m.shear_modulus_pa) {
                    (Some(nu), None) => Material::isotropic(m.youngs_modulus_pa, nu)
                        .map_err(|e| err("material", e))?,
                    (None, Some(g)) => Material {
                        youngs_modulus_pa: m.youngs_modulus_pa,
                        shear_modulus_pa: g,
                    },
                    _ => {
                        return Err(SceneError::new(
                            format!("{field}.material"),
                            "give exactly one of poisson_ratio and shear_modulus_pa",
                        ));
                    }
                };
                if !(c.inner_diameter_m.is_finite() && c.inner_diameter_m >= 0.0) {
                    return Err(SceneError::new(
                        format!("{field}.cross_section.inner_diameter_m"),
                        format!(
                            "{}: must be a number not below zero (0, the default, is a solid rod)",
                            c.inner_diameter_m
                        ),
                    ));
                }
                let section = if c.inner_diameter_m > 0.0 {
                    CrossSection::tube(c.diameter_m, c.inner_diameter_m)
                } else {
                    CrossSection::solid_circle(c.diameter_m)
                }
                .map_err(|e| err("cross_section", e))?;
                (
                    Stiffness::from_material(&material, &section)
                        .map_err(|e| err("material", e))?,
                    Some(section.area_m2),
                )
            }
            _ => {
                return Err(SceneError::new(
                    field,
                    "give either [stiffness], or both [material] and [cross_section]",
                ));
            }
        };
        let line_density_kg_per_m = match (self.line_density_kg_per_m, self.density_kg_m3, area) {
            (Some(l), None, _) => l,
            (None, Some(rho), Some(a)) => rho * a,
            (None, Some(_), None) => {
                return Err(SceneError::new(
                    format!("{field}.density_kg_m3"),
                    "needs a cross_section; with direct stiffness give line_density_kg_per_m",
                ));
            }
            (Some(_), Some(_), _) => {
                return Err(SceneError::new(
                    field,
                    "give one of line_density_kg_per_m and density_kg_m3, not both",
                ));
            }
            (None, None, _) => {
                return Err(SceneError::new(
                    format!("{field}.line_density_kg_per_m"),
                    "missing (or give density_kg_m3 with a cross_section)",
                ));
            }
        };
        if !(line_density_kg_per_m.is_finite() && line_density_kg_per_m >= 0.0) {
            let key = if self.density_kg_m3.is_some() {
                "density_kg_m3"
            } else {
                "line_density_kg_per_m"
            };
            return Err(SceneError::new(
                format!("{field}.{key}"),
                "must be a non-negative number",
            ));
        }
        Ok(Section {
            length_m,
            stiffness,
            line_density_kg_per_m,
            steps: self.steps,
        })
    }
}

impl Guides {
    /// How many guides: `count`, or the length of `centres_m`, if within [`MAX_GUIDES`].
    pub fn count(&self) -> Result<usize, SceneError> {
        match (&self.centres_m, self.count) {
            (Some(c), None) if c.len() > MAX_GUIDES => Err(SceneError::new(
                "guides.centres_m",
                format!(
                    "{} centres; at most {MAX_GUIDES} (model-core's MAX_GUIDES)",
                    c.len()
                ),
            )),
            (Some(c), None) => Ok(c.len()),
            (None, Some(count)) => {
                count.checked("guides.count", 0, MAX_GUIDES, "model-core's MAX_GUIDES")
            }
            _ => Err(SceneError::new(
                "guides",
                "give either centres_m, or all of first_centre_m, pitch_m and count",
            )),
        }
    }

    fn guides(&self) -> Result<Vec<Guide<f64>>, SceneError> {
        let count = self.count()?;
        let centres: Vec<f64> = match (&self.centres_m, self.first_centre_m, self.pitch_m) {
            (Some(c), None, None) => c.clone(),
            (None, Some(first), Some(pitch)) => {
                let first = finite("guides.first_centre_m", first)?;
                let pitch = finite("guides.pitch_m", pitch)?;
                (0..count).map(|k| first + k as f64 * pitch).collect()
            }
            _ => {
                return Err(SceneError::new(
                    "guides",
                    "give either centres_m, or all of first_centre_m, pitch_m and count",
                ));
            }
        };
        let thicknesses = per_guide(
            "thickness_m",
            self.thickness_m,
            "thicknesses_m",
            self.thicknesses_m.as_deref(),
            count,
        )?;
        let masses = per_guide(
            "mass_kg",
            self.mass_kg,
            "masses_kg",
            self.masses_kg.as_deref(),
            count,
        )?;
        centres
            .iter()
            .zip(thicknesses.iter().zip(&masses))
            .enumerate()
            .map(|(i, (&s, (&thickness_m, &mass_kg)))| {
                Ok(Guide {
                    s_m: finite(&format!("guides.centres_m[{i}]"), s)?,
                    thickness_m,
                    mass_kg,
                })
            })
            .collect()
    }
}

/// `n` and `what`, plural unless one: "1 value", "3 values".
fn counted(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// One value per guide: the list `many` (`guides.<many_key>`, one per guide) or the single value
/// `one` (`guides.<one_key>`) for all; each finite. A non-zero single value next to a list is refused.
fn per_guide(
    one_key: &str,
    one: f64,
    many_key: &str,
    many: Option<&[f64]>,
    count: usize,
) -> Result<Vec<f64>, SceneError> {
    match many {
        None => Ok(vec![finite(&format!("guides.{one_key}"), one)?; count]),
        Some(_) if one != 0.0 => Err(SceneError::new(
            format!("guides.{one_key}"),
            format!("give {one_key} (every guide) or {many_key} (one per guide), not both"),
        )),
        Some(list) if list.len() != count => Err(SceneError::new(
            format!("guides.{many_key}"),
            format!(
                "{} for {} (one per guide)",
                counted(list.len(), "value"),
                counted(count, "guide")
            ),
        )),
        Some(list) => list
            .iter()
            .enumerate()
            .map(|(i, &x)| finite(&format!("guides.{many_key}[{i}]"), x))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_checked_against_their_limit() {
        let check = |c: Count| c.checked("k", 2, 16, "the limit");
        assert_eq!(check(Count::Integer(16)), Ok(16));
        assert_eq!(check(Count::Float(1e1)), Ok(10));
        for bad in [
            Count::Integer(17),
            Count::Integer(1),
            Count::Integer(-1),
            Count::Integer(i128::from(i64::MAX)),
            Count::Float(2.5),
            Count::Float(1e12),
            Count::Float(1e300),
            Count::Float(f64::NAN),
            Count::Float(f64::INFINITY),
            Count::Float(-3.0),
        ] {
            let e = check(bad).unwrap_err();
            assert_eq!(e.field, "k");
            assert!(
                e.reason.contains("from 2 to 16") && e.reason.contains("the limit"),
                "{e}"
            );
        }
    }
}
