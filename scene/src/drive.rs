//! The drive and the controller: what turns a cable's spool into a cable length (spool radius,
//! gearhead, angle sensor, stepper) and what the estimator loop runs at (loop and sampling rates,
//! RK4 steps on the MCU). The firmware reads them at build time from the same file as the host
//! (`firmware/README.md`, "Your robot"); the host's solves do not use them, and a scene without them
//! is a complete scene for the host.
//!
//! `[[section]].steps` is the host's resolution; the MCU's is `controller.steps_per_section`, since
//! a controller cannot afford the steps a reference solve takes.

use serde::Deserialize;

use super::{MAX_TOTAL_STEPS, Scene, SceneError, positive};

/// `[drive]`: the spools that pay the cables out and in, one list entry per `[[cable]]`, in order.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DriveSpec {
    /// Spool radius at the cable's centreline, m.
    pub spool_radius_m: f64,
    /// Sensor (motor shaft) turns per spool turn: the gearhead between them (1: sensor on the spool).
    pub gear_ratio: u32,
    /// Counts per turn of the angle sensor on the motor shaft.
    pub encoder_counts_per_turn: u32,
    /// Full steps per motor turn (200 for a 1.8 degree hybrid stepper).
    pub motor_full_steps_per_turn: u32,
    /// The stepper drivers' microsteps per full step.
    pub microsteps_per_full_step: u32,
    /// Fastest cable speed the drives produce, m/s.
    pub max_cable_speed_m_per_s: f64,
    /// Each cable's length at the calibration (home) pose, m, in the sense of `[[cable]]`: from the
    /// first guide to the termination.
    pub home_lengths_m: Vec<f64>,
    /// Each sensor's multi-turn count at the home pose.
    pub zero_offset_counts: Vec<i64>,
    /// For each cable, whether it reels in (shortens) as its sensor's count increases (default: every
    /// cable pays out with increasing counts).
    #[serde(default)]
    pub reel_in_with_counts: Vec<bool>,
}

/// `[controller]`: the estimator loop on the MCU.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Estimator (loop) rate, Hz.
    pub loop_rate_hz: u32,
    /// Encoder sampling rate, Hz: a whole multiple of the loop rate.
    pub sample_rate_hz: u32,
    /// RK4 steps over each section on the MCU (the host uses `[[section]].steps`).
    pub steps_per_section: u16,
}

/// Fewest sensor counts per turn a cable length can be read from.
const MIN_COUNTS_PER_TURN: u32 = 4;

/// Most sensor turns per spool turn: far beyond any gearhead, and small enough that the counts of
/// a spool turn stay a 32-bit number with a 65 536-count sensor.
pub const MAX_GEAR_RATIO: u32 = 10_000;

impl Scene {
    /// The `[drive]` and `[controller]` tables, when present: positive, finite values, one entry
    /// per `[[cable]]` in each list, a sampling rate that is a whole multiple of the loop rate and
    /// MCU steps within [`MAX_TOTAL_STEPS`].
    pub(super) fn check_drive(&self) -> Result<(), SceneError> {
        if let Some(drive) = &self.drive {
            self.check_drive_table(drive)?;
        }
        if let Some(controller) = &self.controller {
            self.check_controller_table(controller)?;
        }
        Ok(())
    }

    fn check_drive_table(&self, drive: &DriveSpec) -> Result<(), SceneError> {
        positive("drive.spool_radius_m", drive.spool_radius_m)?;
        positive(
            "drive.max_cable_speed_m_per_s",
            drive.max_cable_speed_m_per_s,
        )?;
        let at_least = |key: &str, x: u32, least: u32| {
            if x >= least {
                Ok(())
            } else {
                Err(SceneError::new(
                    format!("drive.{key}"),
                    format!("{x}: at least {least}"),
                ))
            }
        };
        at_least("gear_ratio", drive.gear_ratio, 1)?;
        if drive.gear_ratio > MAX_GEAR_RATIO {
            return Err(SceneError::new(
                "drive.gear_ratio",
                format!(
                    "{}: at most {MAX_GEAR_RATIO} (sensor turns per spool turn)",
                    drive.gear_ratio
                ),
            ));
        }
        at_least(
            "encoder_counts_per_turn",
            drive.encoder_counts_per_turn,
            MIN_COUNTS_PER_TURN,
        )?;
        at_least(
            "motor_full_steps_per_turn",
            drive.motor_full_steps_per_turn,
            1,
        )?;
        at_least(
            "microsteps_per_full_step",
            drive.microsteps_per_full_step,
            1,
        )?;
        let cables = self.cables.len();
        let one_per_cable = |key: &str, len: usize| {
            if len == cables {
                Ok(())
            } else {
                Err(SceneError::new(
                    format!("drive.{key}"),
                    format!(
                        "{len} entries; one per [[cable]] ({cables}), in the order of the \
                         [[cable]] tables"
                    ),
                ))
            }
        };
        one_per_cable("home_lengths_m", drive.home_lengths_m.len())?;
        one_per_cable("zero_offset_counts", drive.zero_offset_counts.len())?;
        if !drive.reel_in_with_counts.is_empty() {
            one_per_cable("reel_in_with_counts", drive.reel_in_with_counts.len())?;
        }
        for (i, x) in drive.home_lengths_m.iter().enumerate() {
            positive(&format!("drive.home_lengths_m[{i}]"), *x)?;
        }
        Ok(())
    }

    fn check_controller_table(&self, controller: &ControllerSpec) -> Result<(), SceneError> {
        let ControllerSpec {
            loop_rate_hz,
            sample_rate_hz,
            steps_per_section,
        } = *controller;
        if loop_rate_hz == 0 {
            return Err(SceneError::new(
                "controller.loop_rate_hz",
                "0: at least 1 Hz",
            ));
        }
        if sample_rate_hz < loop_rate_hz || sample_rate_hz % loop_rate_hz != 0 {
            return Err(SceneError::new(
                "controller.sample_rate_hz",
                format!(
                    "{sample_rate_hz} Hz: a whole multiple of loop_rate_hz ({loop_rate_hz} Hz), \
                     so that every tick has the same samples"
                ),
            ));
        }
        let total = u32::from(steps_per_section) * self.sections.len() as u32;
        if steps_per_section == 0 || total > MAX_TOTAL_STEPS {
            return Err(SceneError::new(
                "controller.steps_per_section",
                format!(
                    "{steps_per_section}: at least 1, and at most {MAX_TOTAL_STEPS} over all the \
                     sections"
                ),
            ));
        }
        Ok(())
    }

    /// The scene as the MCU models it: every section at `controller.steps_per_section` RK4 steps.
    ///
    /// # Errors
    /// The scene has no `[controller]` table.
    pub fn at_controller_steps(&self) -> Result<Scene, SceneError> {
        let Some(controller) = &self.controller else {
            return Err(SceneError::new(
                "controller",
                "no [controller] table: the firmware needs steps_per_section, loop_rate_hz and \
                 sample_rate_hz (host-sim/SCENES.md, \"The drive and the controller\")",
            ));
        };
        let mut scene = self.clone();
        for section in &mut scene.sections {
            section.steps = controller.steps_per_section;
        }
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BENCH: &str = r#"
[[section]]
length_m = 0.39
steps = 200
line_density_kg_per_m = 0.03725
material = { youngs_modulus_pa = 62.7e9, poisson_ratio = 0.3 }
cross_section = { diameter_m = 1.56e-3 }

[[cable]]
angle_deg = 0
radius_m = 0.01

[[cable]]
angle_deg = 120
radius_m = 0.01

[drive]
spool_radius_m = 0.005
gear_ratio = 8
encoder_counts_per_turn = 16384
motor_full_steps_per_turn = 200
microsteps_per_full_step = 16
max_cable_speed_m_per_s = 0.05
home_lengths_m = [0.389, 0.377]
zero_offset_counts = [16380, -100]

[controller]
loop_rate_hz = 100
sample_rate_hz = 1000
steps_per_section = 20
"#;

    #[test]
    fn a_drive_and_a_controller_parse_and_set_the_mcu_steps() -> Result<(), SceneError> {
        let scene = Scene::parse(BENCH, "bench")?;
        assert_eq!(scene.sections[0].steps, 200);
        assert_eq!(scene.at_controller_steps()?.sections[0].steps, 20);
        let drive = scene
            .drive
            .as_ref()
            .ok_or(SceneError::new("drive", "none"))?;
        assert_eq!(drive.zero_offset_counts, [16380, -100]);
        assert!(drive.reel_in_with_counts.is_empty());
        Ok(())
    }

    #[test]
    fn a_drive_that_does_not_match_the_cables_is_refused_at_its_line() {
        for (from, to, key) in [
            ("[0.389, 0.377]", "[0.389]", "drive.home_lengths_m"),
            ("[16380, -100]", "[1, 2, 3]", "drive.zero_offset_counts"),
            ("gear_ratio = 8", "gear_ratio = 0", "drive.gear_ratio"),
            ("gear_ratio = 8", "gear_ratio = 20000", "drive.gear_ratio"),
            (
                "spool_radius_m = 0.005",
                "spool_radius_m = -0.005",
                "drive.spool_radius_m",
            ),
            (
                "sample_rate_hz = 1000",
                "sample_rate_hz = 1050",
                "controller.sample_rate_hz",
            ),
            (
                "steps_per_section = 20",
                "steps_per_section = 0",
                "controller.steps_per_section",
            ),
        ] {
            let text = BENCH.replace(from, to);
            let line = text
                .lines()
                .position(|l| l.contains(to))
                .map_or(0, |i| i + 1);
            match Scene::parse(&text, "bench") {
                Ok(_) => panic!("{to} accepted"),
                Err(e) => {
                    let shown = e.to_string();
                    assert!(shown.contains(key), "{to}: {shown}");
                    assert!(
                        shown.contains(&format!("bench, line {line} ")),
                        "{to}: {shown}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_spool_radius_in_millimetres_is_warned_about_with_the_slip() -> Result<(), SceneError> {
        let scene = Scene::parse(
            &BENCH.replace("spool_radius_m = 0.005", "spool_radius_m = 5"),
            "b",
        )?;
        let warnings = scene.warnings();
        assert!(
            warnings.iter().any(|w| w.field == "drive.spool_radius_m"
                && w.reason.contains("Did you mean 5e-3 m (5 mm)?")),
            "{warnings:?}"
        );
        assert!(Scene::parse(BENCH, "b")?.warnings().is_empty());
        Ok(())
    }

    #[test]
    fn more_cables_than_model_core_holds_are_refused_naming_the_limit() {
        let seven = "[[cable]]\nangle_deg = 0\nradius_m = 0.01\n".repeat(7);
        let text = BENCH
            .split("[[cable]]")
            .next()
            .unwrap_or_default()
            .to_string()
            + &seven;
        match Scene::parse(&text, "b") {
            Ok(_) => panic!("seven cables accepted"),
            Err(e) => assert!(
                e.to_string()
                    .contains("at most 6 (model-core's MAX_CABLES)"),
                "{e}"
            ),
        }
    }

    #[test]
    fn a_scene_without_a_controller_has_no_mcu_steps() -> Result<(), SceneError> {
        let text = BENCH.split("[drive]").next().unwrap_or_default();
        let scene = Scene::parse(text, "bench")?;
        assert!(scene.drive.is_none() && scene.controller.is_none());
        assert!(scene.at_controller_steps().is_err());
        Ok(())
    }
}
