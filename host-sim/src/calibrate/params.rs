//! The calibrated parameters and their least-squares coordinates.
//!
//! Positive quantities are fitted in log scale, as scales on the scene's own values: `ln k` for
//! Young's modulus (every section's stiffness times `k`: `E`, and `G` when given, or the stiffness
//! given directly), `ln` of a scale on every section's line density, `ln` of a scale on every tendon
//! and cable hole's radius. The friction coefficient (one for every tendon) is fitted as it is, not
//! below zero. The base pose is a rotation vector (rad) and a translation (m) ([`Pose`]).
//!
//! The search stays within [`SCALE_RANGE`] of the scene's values (and a friction coefficient below
//! [`MAX_FRICTION`]): a fit that runs to the end of that range is no calibration (a unit slip, data
//! in another frame than the scene's), and says so.

use clap::ValueEnum;
use nalgebra::{DVector, Vector3};

use super::pose::Pose;
use crate::scene::{Scene, SceneError};

/// How far a scale may go from the scene's value, either way: a factor of a thousand.
pub const SCALE_RANGE: f64 = 1e3;

/// The largest friction coefficient searched.
pub const MAX_FRICTION: f64 = 5.0;

/// The largest standard deviation of a determined log-scaled parameter (E, line density, radius):
/// 20 %.
pub const UNDETERMINED_LOG_SD: f64 = 0.2;
/// The largest standard deviation of a determined friction coefficient.
pub const UNDETERMINED_FRICTION_SD: f64 = 0.1;
/// The largest standard deviation of a determined base rotation, rad (1.1 degrees).
pub const UNDETERMINED_ROTATION_SD_RAD: f64 = 0.02;
/// The largest standard deviation of a determined base translation, in rod lengths.
pub const UNDETERMINED_TRANSLATION_SD_PER_LENGTH: f64 = 0.05;

/// What `--fit` may name (`E` is always fitted).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FitParameter {
    /// Young's modulus: a common scale on every section's stiffness.
    #[value(name = "E", alias = "e")]
    E,
    /// A common scale on every section's line density (the guides' masses stay).
    #[value(name = "line_density")]
    LineDensity,
    /// A common scale on every tendon's and cable's hole radius (scenes with tendons).
    #[value(name = "cable_offset")]
    CableOffset,
    /// The measurement frame's rotation and translation from the scene's frame.
    #[value(name = "base_pose")]
    BasePose,
    /// One friction coefficient for every tendon (scenes with tendons).
    #[value(name = "friction")]
    Friction,
}

/// How a coordinate maps to its value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// `value = reference * exp(theta)`.
    Log {
        /// The scene's value (the reference of the scale), in the parameter's unit.
        reference: f64,
    },
    /// `value = theta`.
    Linear,
}

/// One fitted coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct Coordinate {
    /// Its name in reports (`E`, `line_density`, `base_rotation_x`, ...).
    pub name: String,
    /// The SI unit of its value (`Pa`, `kg/m`, `m`, `1`, `rad`).
    pub unit: &'static str,
    /// Log scale or linear.
    pub kind: Kind,
    /// The smallest value it may take, in the coordinate (`ln` scales: `-ln SCALE_RANGE`; the
    /// friction coefficient: 0).
    pub lower: Option<f64>,
    /// The largest, in the coordinate (`ln SCALE_RANGE`, [`MAX_FRICTION`]).
    pub upper: Option<f64>,
    /// Whether `lower` is a physical limit (friction 0) rather than the end of the search range.
    pub physical_lower: bool,
    /// The finite-difference step of the Jacobian, in the coordinate.
    pub step: f64,
    /// A standard deviation above which the data do not determine it, in the coordinate: 0.2 in
    /// log scale (20 %), 0.1 for a friction coefficient, 0.02 rad (1.1 degrees), a twentieth of
    /// the rod's length. A calibration that uncertain is not one: its parameter gets no number.
    pub undetermined_above: f64,
}

impl Coordinate {
    /// The value, in its unit, at coordinate `theta`.
    pub fn value(&self, theta: f64) -> f64 {
        match self.kind {
            Kind::Log { reference } => reference * theta.exp(),
            Kind::Linear => theta,
        }
    }

    /// The value's standard deviation from the coordinate's (the delta method: `value * sd` in
    /// log scale).
    pub fn value_std(&self, theta: f64, theta_std: f64) -> f64 {
        match self.kind {
            Kind::Log { .. } => self.value(theta) * theta_std,
            Kind::Linear => theta_std,
        }
    }

    /// Whether `theta` is at the end of the search range: the data pull the parameter beyond what
    /// the scene could mean.
    pub fn at_range_end(&self, theta: f64) -> bool {
        self.upper.is_some_and(|u| theta >= u)
            || (!self.physical_lower && self.lower.is_some_and(|l| theta <= l))
    }

    /// Whether `theta` is on a physical limit (a friction coefficient of 0).
    pub fn at_physical_bound(&self, theta: f64) -> bool {
        self.physical_lower && self.lower.is_some_and(|l| theta <= l)
    }

    /// The coordinate as it appears in a combination: `ln E` or `friction`.
    pub fn symbol(&self) -> String {
        match self.kind {
            Kind::Log { .. } => format!("ln {}", self.name),
            Kind::Linear => self.name.clone(),
        }
    }
}

/// Which parameters are fitted, and where they sit in the coordinate vector: `ln k` first, then
/// `ln` line-density scale, `ln` radius scale, friction, rotation vector (3), translation (3), each
/// when fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The coordinates, in order.
    pub coordinates: Vec<Coordinate>,
    line_density: Option<usize>,
    cable_offset: Option<usize>,
    friction: Option<usize>,
    base_pose: Option<usize>,
    /// The scene's friction coefficient, the start of a friction fit.
    friction_start: f64,
}

/// The physical values at one coordinate vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Values {
    /// Scale on every section's stiffness.
    pub stiffness_scale: f64,
    /// Scale on every section's line density.
    pub density_scale: f64,
    /// Scale on every hole's radius.
    pub radius_scale: f64,
    /// The tendons' common friction coefficient, when fitted.
    pub friction: Option<f64>,
    /// The registration of the measurement frame.
    pub pose: Pose,
}

impl Values {
    /// What a forward solve depends on besides the loads (the pose only moves its points).
    pub fn physical_key(&self) -> [f64; 4] {
        [
            self.stiffness_scale,
            self.density_scale,
            self.radius_scale,
            self.friction.unwrap_or(f64::NAN),
        ]
    }

    /// The scene with these values: stiffness, line densities and hole radii scaled, the friction
    /// set on every tendon. The base pose is not the scene's: it maps the scene's frame onto the
    /// measurement frame (see [`super::write`] for a scene written in the measurement frame).
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut out = scene.clone();
        let k = self.stiffness_scale;
        for section in &mut out.sections {
            if let Some(m) = &mut section.material {
                m.youngs_modulus_pa *= k;
                if let Some(g) = &mut m.shear_modulus_pa {
                    *g *= k;
                }
            }
            if let Some(s) = &mut section.stiffness {
                for x in s
                    .bending_torsion_nm2
                    .iter_mut()
                    .chain(s.shear_axial_n.iter_mut())
                {
                    *x *= k;
                }
            }
            if let Some(l) = &mut section.line_density_kg_per_m {
                *l *= self.density_scale;
            }
            if let Some(d) = &mut section.density_kg_m3 {
                *d *= self.density_scale;
            }
        }
        for t in &mut out.tendons {
            t.radius_m *= self.radius_scale;
            if let Some(mu) = self.friction {
                t.friction_coefficient = mu;
            }
        }
        for c in &mut out.cables {
            c.radius_m *= self.radius_scale;
        }
        out
    }
}

impl Layout {
    /// The coordinates for fitting `fit` (and `E`) on `scene`. Refuses a parameter the scene cannot
    /// have: a hole radius or a friction without tendons (cables only measure: the points cannot
    /// see their holes).
    pub fn new(scene: &Scene, fit: &[FitParameter]) -> Result<Self, SceneError> {
        let wants = |p: FitParameter| fit.contains(&p);
        let rod = scene.rod()?;
        let length_m = rod.length_m();
        let mut coordinates = Vec::new();
        let first = scene.sections.first();
        let (name, unit, reference) = match first.and_then(|s| s.material.as_ref()) {
            Some(m) => ("E", "Pa", m.youngs_modulus_pa),
            None => ("stiffness_scale", "1", 1.0),
        };
        let log = |name: &str, unit: &'static str, reference: f64| Coordinate {
            name: name.to_string(),
            unit,
            kind: Kind::Log { reference },
            lower: Some(-SCALE_RANGE.ln()),
            upper: Some(SCALE_RANGE.ln()),
            physical_lower: false,
            step: 1e-4,
            undetermined_above: UNDETERMINED_LOG_SD,
        };
        coordinates.push(log(name, unit, reference));
        let mut layout = Self {
            coordinates,
            line_density: None,
            cable_offset: None,
            friction: None,
            base_pose: None,
            friction_start: 0.0,
        };
        if wants(FitParameter::LineDensity) {
            let reference = rod
                .sections
                .first()
                .map_or(1.0, |s| s.line_density_kg_per_m);
            if reference.is_nan() || reference <= 0.0 {
                return Err(SceneError::new(
                    "--fit line_density",
                    "the first section's line density is zero: there is no weight to scale",
                ));
            }
            layout.line_density = Some(layout.coordinates.len());
            layout
                .coordinates
                .push(log("line_density", "kg/m", reference));
        }
        let no_tendons = |what: &str| {
            SceneError::new(
                format!("--fit {what}"),
                "the scene has no [[tendon]]: cables only measure and do not move the backbone, \
                 so observed points cannot determine this",
            )
        };
        if wants(FitParameter::CableOffset) {
            let Some(t) = scene.tendons.first() else {
                return Err(no_tendons("cable_offset"));
            };
            if t.radius_m.is_nan() || t.radius_m <= 0.0 {
                return Err(SceneError::new(
                    "--fit cable_offset",
                    "tendon[0].radius_m is zero: there is no radius to scale",
                ));
            }
            layout.cable_offset = Some(layout.coordinates.len());
            layout
                .coordinates
                .push(log("cable_offset", "m", t.radius_m));
        }
        if wants(FitParameter::Friction) {
            let Some(t) = scene.tendons.first() else {
                return Err(no_tendons("friction"));
            };
            layout.friction_start = t.friction_coefficient.max(0.0);
            layout.friction = Some(layout.coordinates.len());
            layout.coordinates.push(Coordinate {
                name: "friction".into(),
                unit: "1",
                kind: Kind::Linear,
                lower: Some(0.0),
                upper: Some(MAX_FRICTION),
                physical_lower: true,
                step: 1e-4,
                undetermined_above: UNDETERMINED_FRICTION_SD,
            });
        }
        if wants(FitParameter::BasePose) {
            layout.base_pose = Some(layout.coordinates.len());
            for axis in ["x", "y", "z"] {
                layout.coordinates.push(Coordinate {
                    name: format!("base_rotation_{axis}"),
                    unit: "rad",
                    kind: Kind::Linear,
                    lower: None,
                    upper: None,
                    physical_lower: false,
                    step: 1e-6,
                    undetermined_above: UNDETERMINED_ROTATION_SD_RAD,
                });
            }
            for axis in ["x", "y", "z"] {
                layout.coordinates.push(Coordinate {
                    name: format!("base_translation_{axis}"),
                    unit: "m",
                    kind: Kind::Linear,
                    lower: None,
                    upper: None,
                    physical_lower: false,
                    step: 1e-6,
                    undetermined_above: length_m * UNDETERMINED_TRANSLATION_SD_PER_LENGTH,
                });
            }
        }
        Ok(layout)
    }

    /// How many coordinates.
    pub fn len(&self) -> usize {
        self.coordinates.len()
    }

    /// Whether there is none (never: `E` is always fitted).
    pub fn is_empty(&self) -> bool {
        self.coordinates.is_empty()
    }

    /// Whether the base pose is fitted.
    pub fn fits_pose(&self) -> bool {
        self.base_pose.is_some()
    }

    /// The coordinates of the scene's own values, with the base pose `pose`.
    pub fn start(&self, pose: &Pose) -> DVector<f64> {
        let mut theta = DVector::zeros(self.len());
        if let Some(i) = self.friction
            && let Some(x) = theta.get_mut(i)
        {
            *x = self.friction_start;
        }
        self.set_pose(&mut theta, pose);
        theta
    }

    /// Writes `pose` into the coordinates (when the pose is fitted).
    pub fn set_pose(&self, theta: &mut DVector<f64>, pose: &Pose) {
        if let Some(i) = self.base_pose {
            for k in 0..3 {
                if let Some(x) = theta.get_mut(i + k) {
                    *x = pose.rotation_rad[k];
                }
                if let Some(x) = theta.get_mut(i + 3 + k) {
                    *x = pose.translation_m[k];
                }
            }
        }
    }

    /// The values at coordinates `theta`.
    pub fn values(&self, theta: &DVector<f64>) -> Values {
        let at = |i: Option<usize>| i.and_then(|i| theta.get(i).copied());
        let pose = match self.base_pose {
            Some(i) => {
                let v = |k: usize| theta.get(i + k).copied().unwrap_or(0.0);
                Pose {
                    rotation_rad: Vector3::new(v(0), v(1), v(2)),
                    translation_m: Vector3::new(v(3), v(4), v(5)),
                }
            }
            None => Pose::identity(),
        };
        Values {
            stiffness_scale: at(Some(0)).unwrap_or(0.0).exp(),
            density_scale: at(self.line_density).unwrap_or(0.0).exp(),
            radius_scale: at(self.cable_offset).unwrap_or(0.0).exp(),
            friction: at(self.friction).map(|mu| mu.max(0.0)),
            pose,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_map_to_values_and_back() {
        let c = Coordinate {
            name: "E".into(),
            unit: "Pa",
            kind: Kind::Log { reference: 60e9 },
            lower: None,
            upper: None,
            physical_lower: false,
            step: 1e-4,
            undetermined_above: 1.0,
        };
        assert!((c.value(0.1f64.ln()) - 6e9).abs() < 1e-3);
        // A 2 % standard deviation in ln E is 2 % of E.
        assert!((c.value_std(0.0, 0.02) - 1.2e9).abs() < 1e-3);
        assert_eq!(c.symbol(), "ln E");
    }
}
