//! The tendon-driven robot on the MCU: the robot of its robot file (by default the thesis bench
//! with three tendons that the spools pull, steel wire behind a feed from the spools), estimated
//! in f32 from the spools' displacements.
//! Target-agnostic: the `tendon` image runs these checks under QEMU, the host tests run the same
//! code.
//!
//! * [`run_golden`]: the golden tendon rows (`tendon_bench.csv`, inextensible tendons) from their
//!   displacements alone (each row's tip force known): tensions found by displacement control, the
//!   tip within [`TIP_TOLERANCE_M`] of the independent f64 reference.
//! * [`run_trajectory`]: a recorded actuation ([`displacements_m`]: tendon 0 taken in, tendon 1
//!   paid out until slack, tendon 2 from slack to taut) tick by tick with warm updates, against the
//!   f64 model ([`TRAJECTORY`], regenerated and checked by a host test): tip, tensions and each
//!   tendon's state.

use model_checks::reference::{self, csv_rows};
use model_core::{
    DisplacementSettings, DisplacementSolve, Model, ModelError, Quaternion, ShootingSettings,
    TendonEquilibrium, TendonState, Tendons, TipLoad,
};
use nalgebra::Vector3;

// The robot: read at build time from its robot file (`TENDON_ROBOT=path/to/robot.toml`,
// `robots/tendon_bench.toml` by default) by `build.rs`: `TENDON_ROBOT_FILE`, `TENDON_COUNT`,
// `STEPS_PER_SECTION` (the file's `controller.steps_per_section`), `TENDON_NODES` (its plan's),
// `push_tendon_robot` and `tendon_specs`.
include!(concat!(env!("OUT_DIR"), "/tendon_robot.rs"));

/// The tendon estimator's model: f32, quaternion attitude.
pub type TendonModel = Model<f32, Quaternion<f32>, TENDON_NODES>;

/// Largest tip error against the f64 reference, m (0.1 mm).
pub const TIP_TOLERANCE_M: f64 = 1.0e-4;

/// Largest tension error against the f64 reference, N.
pub const TENSION_TOLERANCE_N: f64 = 0.02;

/// Ticks of the recorded actuation.
pub const TRAJECTORY_TICKS: usize = 12;

/// The spool displacements at `tick`, m (positive taken in).
pub fn displacements_m(tick: usize) -> [f64; 3] {
    let k = tick as f64;
    [
        0.05e-3 + 0.12e-3 * k,
        0.12e-3 - 0.2e-3 * k,
        -0.05e-3 + 0.01e-3 * k,
    ]
}

/// One tick of the f64 reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickReference {
    /// Spool tensions, N.
    pub tensions_n: [f64; 3],
    /// Tip position, m.
    pub tip_m: [f64; 3],
    /// Whether each tendon is slack.
    pub slack: [bool; 3],
}

/// The tendon robot of the robot file in `T` at `steps_per_section`, and its tendons: as the file
/// has them with `compliant` (the default file: the trajectory's steel tendons behind their feed),
/// else inextensible (the golden reference's convention).
///
/// # Errors
/// If the model refuses the rod (the build ruled it out).
pub fn rod_and_tendons<T: model_core::Scalar>(
    steps_per_section: u16,
    compliant: bool,
) -> Result<(model_core::Rod<T>, [model_core::Tendon<T>; TENDON_COUNT]), ModelError> {
    let mut rod = model_core::Rod::new();
    push_tendon_robot(&mut rod, steps_per_section)?;
    let mut tendons = tendon_specs::<T>();
    if !compliant {
        for t in tendons.iter_mut() {
            t.axial_stiffness_n = None;
            t.feed_length_m = T::zero();
        }
    }
    Ok((rod, tendons))
}

/// The tendon robot's f32 model at [`STEPS_PER_SECTION`] and its tendons ([`rod_and_tendons`]).
///
/// # Errors
/// If the model refuses the robot (the build ruled it out).
pub fn robot(compliant: bool) -> Result<(TendonModel, Tendons<f32>), ModelError> {
    let (rod, tendons) = rod_and_tendons::<f32>(STEPS_PER_SECTION, compliant)?;
    let model = TendonModel::new(rod)?;
    let tendons = Tendons::new(&model, &tendons)?;
    Ok((model, tendons))
}

/// One case's verdict.
#[derive(Clone, Copy, Debug, PartialEq, defmt::Format)]
pub struct CaseCheck {
    /// Row or tick.
    pub index: usize,
    /// Tip error against the reference, m.
    pub tip_error_m: f64,
    /// Largest tension error, N.
    pub tension_error_n: f64,
    /// Whether every tendon's state (taut or slack) matches.
    pub states_match: bool,
    /// Sweeps spent.
    pub sweeps: u32,
    /// Cost in the caller's clock units.
    pub cost: u64,
    /// Whether it passed.
    pub passed: bool,
}

/// The tally.
#[derive(Clone, Copy, Debug, Default, PartialEq, defmt::Format)]
pub struct Summary {
    /// Cases passed.
    pub passed: usize,
    /// Cases failed.
    pub failed: usize,
    /// Worst tip error, m.
    pub worst_tip_error_m: f64,
    /// Worst tension error, N.
    pub worst_tension_error_n: f64,
    /// The costliest warm update (every tick but the first), in the caller's clock units.
    pub max_warm_cost: u64,
    /// The cold first solve's cost.
    pub cold_cost: u64,
}

impl Summary {
    fn add(&mut self, c: &CaseCheck, warm: bool) {
        if c.passed {
            self.passed += 1;
        } else {
            self.failed += 1;
        }
        self.worst_tip_error_m = self.worst_tip_error_m.max(c.tip_error_m);
        self.worst_tension_error_n = self.worst_tension_error_n.max(c.tension_error_n);
        if warm {
            self.max_warm_cost = self.max_warm_cost.max(c.cost);
        } else {
            self.cold_cost = c.cost;
        }
    }
}

fn tip_error(solved: &TendonEquilibrium<f32>, tip_m: [f64; 3]) -> f64 {
    let tip = solved.equilibrium.tip_position_m;
    let d = Vector3::new(
        f64::from(tip.x) - tip_m[0],
        f64::from(tip.y) - tip_m[1],
        f64::from(tip.z) - tip_m[2],
    );
    d.norm()
}

fn tension_error(solved: &TendonEquilibrium<f32>, tensions_n: &[f64]) -> f64 {
    solved
        .tensions_n
        .iter()
        .zip(tensions_n)
        .fold(0.0, |w, (a, b)| w.max((f64::from(*a) - b).abs()))
}

/// The golden tendon rows from their displacements (`rest - len`), each row's tip force known.
///
/// # Errors
/// If the model refuses the bench or an input.
// Out of line, as `run_trajectory`: each has its own model and solves, so the two never share
// a frame (the image's RAM budget).
#[inline(never)]
pub fn run_golden(
    clock: &dyn Fn() -> u64,
    report: &mut dyn FnMut(&CaseCheck),
) -> Result<Summary, ModelError> {
    let (model, tendons) = robot(false)?;
    let shooting = ShootingSettings::default();
    let mut summary = Summary::default();
    for (index, row) in csv_rows::<18>(reference::TENDON_BENCH_CSV).enumerate() {
        let [
            t0,
            t1,
            t2,
            fx,
            fy,
            fz,
            x,
            y,
            z,
            _,
            _,
            _,
            l0,
            l1,
            l2,
            _,
            _,
            _,
        ] = row?;
        let mut d = [0.0f32; 3];
        for (j, (out, len)) in d.iter_mut().zip([l0, l1, l2]).enumerate() {
            let rest = tendons.rest_length_m(j).unwrap_or(0.0);
            *out = rest - len as f32;
        }
        let load = TipLoad::force(Vector3::new(fx as f32, fy as f32, fz as f32));
        let start = clock();
        let out = model.solve_displacements(
            &tendons,
            &d,
            &load,
            None,
            &shooting,
            &DisplacementSettings::default(),
        )?;
        let cost = clock() - start;
        let tip_error_m = tip_error(&out.solved, [x, y, z]);
        let tension_error_n = tension_error(&out.solved, &[t0, t1, t2]);
        let check = CaseCheck {
            index,
            tip_error_m,
            tension_error_n,
            // A tendon the reference pulls must be taut; at zero tension it is just taut and just
            // slack, either state right.
            states_match: out
                .states
                .iter()
                .zip([t0, t1, t2])
                .all(|(s, t)| t <= 0.0 || *s == TendonState::Taut),
            sweeps: out.sweeps,
            cost,
            passed: out.is_success()
                && tip_error_m < TIP_TOLERANCE_M
                && tension_error_n < TENSION_TOLERANCE_N,
        };
        let check = CaseCheck {
            passed: check.passed && check.states_match,
            ..check
        };
        report(&check);
        summary.add(&check, false);
    }
    Ok(summary)
}

/// The recorded actuation, tick by tick: a cold displacement-controlled solve at the first tick,
/// then warm updates from the previous tick's answer (`Model::update_displacements`).
///
/// # Errors
/// If the model refuses the bench or an input.
#[inline(never)]
pub fn run_trajectory(
    clock: &dyn Fn() -> u64,
    report: &mut dyn FnMut(&CaseCheck),
) -> Result<Summary, ModelError> {
    // Read in place, not moved out of the result: a move kept both copies in the frame.
    let robot = robot(true);
    let (model, tendons) = match &robot {
        Ok((model, tendons)) => (model, tendons),
        Err(e) => return Err(*e),
    };
    let shooting = ShootingSettings::default();
    let mut summary = Summary::default();
    let mut previous: Option<DisplacementSolve<f32>> = None;
    for (tick, reference) in TRAJECTORY.iter().enumerate() {
        let d = displacements_m(tick).map(|x| x as f32);
        let settings = DisplacementSettings::default();
        let start = clock();
        let out = match &previous {
            None => model.solve_displacements(
                tendons,
                &d,
                &TipLoad::zero(),
                None,
                &shooting,
                &settings,
            )?,
            Some(p) => model.update_displacements(
                tendons,
                &d,
                &TipLoad::zero(),
                p,
                &shooting,
                &settings,
            )?,
        };
        let cost = clock() - start;
        let tip_error_m = tip_error(&out.solved, reference.tip_m);
        let tension_error_n = tension_error(&out.solved, &reference.tensions_n);
        let states_match = out
            .states
            .iter()
            .zip(reference.slack)
            .all(|(s, slack)| (*s == TendonState::Slack) == slack);
        let check = CaseCheck {
            index: tick,
            tip_error_m,
            tension_error_n,
            states_match,
            sweeps: out.sweeps,
            cost,
            passed: out.is_success()
                && states_match
                && tip_error_m < TIP_TOLERANCE_M
                && tension_error_n < TENSION_TOLERANCE_N,
        };
        report(&check);
        summary.add(&check, tick > 0);
        previous = Some(out);
    }
    Ok(summary)
}

/// The f64 reference of the recorded actuation: [`robot`]`(true)` in f64 at the same steps, each
/// tick solved warm from the previous. Regenerated and held equal by the host test
/// `tendon::tests::the_trajectory_reference_is_the_f64_model`.
pub const TRAJECTORY: [TickReference; TRAJECTORY_TICKS] = include!("tendon_trajectory.in");

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::Model;

    /// The f64 model along the recorded actuation.
    fn reference_in_f64() -> Vec<TickReference> {
        let (rod, tendons) = rod_and_tendons::<f64>(STEPS_PER_SECTION, true).unwrap();
        let model = Model::<f64, Quaternion<f64>, TENDON_NODES>::new(rod).unwrap();
        let set = Tendons::new(&model, &tendons).unwrap();
        let mut previous: Option<TendonEquilibrium<f64>> = None;
        (0..TRAJECTORY_TICKS)
            .map(|tick| {
                let out = model
                    .solve_displacements(
                        &set,
                        &displacements_m(tick),
                        &TipLoad::zero(),
                        previous.as_ref(),
                        &ShootingSettings::default(),
                        &DisplacementSettings::default(),
                    )
                    .unwrap();
                assert!(out.is_success(), "tick {tick}: {:?}", out.termination);
                let tip = out.solved.equilibrium.tip_position_m;
                let r = TickReference {
                    tensions_n: [0, 1, 2].map(|j| out.solved.tensions_n[j]),
                    tip_m: [tip.x, tip.y, tip.z],
                    slack: [0, 1, 2].map(|j| out.states[j] == TendonState::Slack),
                };
                previous = Some(out.solved);
                r
            })
            .collect()
    }

    #[test]
    fn the_default_tendon_robot_file_is_the_golden_tendon_bench() -> Result<(), ModelError> {
        // Inextensible, as the reference; the file's own tendons are the trajectory's steel wire.
        for steps in [STEPS_PER_SECTION, 40] {
            let (rod, tendons) = rod_and_tendons::<f64>(steps, false)?;
            let (reference_rod, reference_tendons) = reference::tendon_bench::<f64>(steps)?;
            crate::checks::assert_same_rod(&rod, &reference_rod, f64::EPSILON, 4.0);
            let (rod32, _) = rod_and_tendons::<f32>(steps, false)?;
            let (reference32, _) = reference::tendon_bench::<f32>(steps)?;
            crate::checks::assert_same_rod(&rod32, &reference32, f64::from(f32::EPSILON), 4.0);
            for (t, r) in tendons.iter().zip(&reference_tendons) {
                assert!((t.hole_m - r.hole_m).norm() < 1e-17 && t.end_m == r.end_m);
                assert_eq!(t.axial_stiffness_n, None);
                assert_eq!(t.friction_coefficient, 0.0);
            }
        }
        let (_, compliant) = rod_and_tendons::<f64>(STEPS_PER_SECTION, true)?;
        for t in compliant {
            assert_eq!(
                (t.axial_stiffness_n, t.feed_length_m),
                (Some(14_000.0), 0.3)
            );
        }
        Ok(())
    }

    #[test]
    fn the_trajectory_reference_is_the_f64_model() {
        let fresh = reference_in_f64();
        if std::env::var_os("UPDATE_TENDON_TRAJECTORY").is_some() {
            let mut text = String::from("[\n");
            for r in &fresh {
                text += &format!(
                    "    TickReference {{ tensions_n: {:?}, tip_m: {:?}, slack: {:?} }},\n",
                    r.tensions_n, r.tip_m, r.slack
                );
            }
            text += "]\n";
            std::fs::write("src/tendon_trajectory.in", text).unwrap();
        }
        for (tick, (a, b)) in fresh.iter().zip(TRAJECTORY.iter()).enumerate() {
            assert_eq!(a.slack, b.slack, "tick {tick}");
            for (x, y) in a
                .tip_m
                .iter()
                .zip(b.tip_m)
                .chain(a.tensions_n.iter().zip(b.tensions_n))
            {
                assert!((x - y).abs() < 1e-9, "tick {tick}: {x} vs {y}");
            }
        }
        // The actuation does what it says: tendon 1 goes slack, tendon 2 becomes taut.
        assert!(!TRAJECTORY[0].slack[1] && TRAJECTORY[TRAJECTORY_TICKS - 1].slack[1]);
        assert!(TRAJECTORY[0].slack[2] && !TRAJECTORY[TRAJECTORY_TICKS - 1].slack[2]);
    }

    #[test]
    fn the_golden_tendon_rows_come_back_from_displacements_in_f32() {
        let summary = run_golden(&|| 0, &mut |c| println!("{c:?}")).unwrap();
        assert_eq!(summary.failed, 0, "{summary:?}");
        assert_eq!(summary.passed, 8);
    }

    #[test]
    fn the_recorded_actuation_is_tracked_in_f32() {
        let summary = run_trajectory(&|| 0, &mut |c| println!("{c:?}")).unwrap();
        assert_eq!(summary.failed, 0, "{summary:?}");
        assert_eq!(summary.passed, TRAJECTORY_TICKS);
    }
}
