//! The sampler against scripted shafts: one test per fault, and the cases that must not be one.

use std::cell::RefCell;
use std::rc::Rc;

use super::*;
use crate::config::{
    CROSS_CHECK_TOLERANCE_COUNTS, MAX_REFUSED_SAMPLES, MAX_STEP_COUNTS_PER_SAMPLE, PERSIST_SAMPLES,
    STEPPER_SCALE, sampler_settings, spools,
};
use crate::encoder::replay::ReplayError;
use crate::spool::Direction;

const TURN: i32 = 16_384;

/// The three shafts and what their sensors do.
#[derive(Clone, Debug, Default)]
pub(crate) struct World {
    /// Each shaft's position, counts (the same units as the spool's zero offset).
    pub shaft: [i32; 3],
    /// The steppers' commanded positions, counts from home (normally the shaft's own motion).
    pub commanded: [i32; 3],
    /// The magnet's offset on its shaft, counts (a slipped magnet).
    pub magnet: [i32; 3],
    /// A sensor stuck at an angle.
    pub stuck: [Option<u16>; 3],
    /// A sensor that fails every read (a bus outage).
    pub outage: [bool; 3],
}

impl World {
    /// The shafts at their spools' home, the steppers at home.
    pub fn at_home() -> Self {
        let home = spools::<f32>().map(|s| i32::try_from(s.zero_offset_counts).unwrap());
        Self {
            shaft: home,
            ..Self::default()
        }
    }

    /// Moves a shaft and its stepper together.
    pub fn drive(&mut self, cable: usize, counts: i32) {
        self.shaft[cable] += counts;
        self.commanded[cable] += counts;
    }
}

/// A sensor reading its shaft in the shared world.
#[derive(Clone, Debug)]
pub(crate) struct WorldSensor {
    cable: usize,
    world: Rc<RefCell<World>>,
}

impl AngleSensor for WorldSensor {
    type Error = ReplayError;

    fn counts_per_turn(&self) -> u32 {
        16_384
    }

    fn read_angle_counts(&mut self) -> Result<u16, ReplayError> {
        let w = self.world.borrow();
        if w.outage[self.cable] {
            return Err(ReplayError::Injected);
        }
        if let Some(angle) = w.stuck[self.cable] {
            return Ok(angle);
        }
        let position = w.shaft[self.cable] + w.magnet[self.cable];
        Ok(multiturn::angle(position, 16_384))
    }
}

/// The world's sensors and the production sampler over them.
pub(crate) fn rig(world: World) -> (Rc<RefCell<World>>, Sampler<WorldSensor>) {
    let world = Rc::new(RefCell::new(world));
    let sensors = [0, 1, 2].map(|cable| WorldSensor {
        cable,
        world: world.clone(),
    });
    let sampler = crate::config::sampler(sensors).unwrap();
    (world, sampler)
}

/// The steppers' commanded microsteps for the world's commanded counts.
pub(crate) fn steps(world: &Rc<RefCell<World>>) -> [i32; 3] {
    let scale = STEPPER_SCALE.unwrap();
    world.borrow().commanded.map(|c| scale.steps(c))
}

fn sample(
    world: &Rc<RefCell<World>>,
    sampler: &mut Sampler<WorldSensor>,
) -> Sample<SampleError<ReplayError>> {
    let steps = steps(world);
    sampler.sample(steps)
}

/// The true length of each cable.
fn truth(world: &Rc<RefCell<World>>) -> [f32; 3] {
    let shaft = world.borrow().shaft;
    let spools = spools::<f32>();
    [0, 1, 2].map(|c| spools[c].length_m(i64::from(shaft[c])))
}

fn assert_true_lengths(s: &Sample<SampleError<ReplayError>>, world: &Rc<RefCell<World>>) {
    for (reading, truth) in s.readings.iter().zip(truth(world)) {
        let length = reading.unwrap_or_else(|e| panic!("sample {}: {e:?}", s.seq));
        // Within the stepper rounding (a fifth of a microstep is a count).
        assert!(
            (length - truth).abs() < 4e-7,
            "sample {}: {length} vs {truth}",
            s.seq
        );
    }
}

#[test]
fn tracks_every_cable_at_the_speed_limit_across_many_turns() {
    let (world, mut sampler) = rig(World::at_home());
    let v = MAX_STEP_COUNTS_PER_SAMPLE as i32;
    // Out for a thousand samples (12.8 turns), back for two thousand: every reading is the truth.
    for n in 0..3000 {
        let dir = if n < 1000 { 1 } else { -1 };
        let s = sample(&world, &mut sampler);
        assert_true_lengths(&s, &world);
        let mut w = world.borrow_mut();
        w.drive(0, dir * v);
        w.drive(1, -dir * v);
        w.drive(2, dir * 7);
    }
    assert_eq!(sampler.faults(), [None; 3]);
}

#[test]
fn a_glitch_is_refused_for_its_sample_only() {
    let (world, mut sampler) = rig(World::at_home());
    for n in 0..40 {
        world.borrow_mut().drive(2, 50);
        world.borrow_mut().magnet[2] = if n == 20 { 3500 } else { 0 };
        let s = sample(&world, &mut sampler);
        if n == 20 {
            assert_eq!(
                s.readings[2],
                Err(SampleError::Disagrees {
                    deviation_counts: 3500
                })
            );
        } else {
            assert_true_lengths(&s, &world);
        }
    }
    assert_eq!(sampler.faults(), [None; 3]);
}

#[test]
fn an_outage_within_the_streak_limit_is_tracked_through_at_the_speed_limit() {
    let (world, mut sampler) = rig(World::at_home());
    let v = MAX_STEP_COUNTS_PER_SAMPLE as i32;
    let limit = u32::from(MAX_REFUSED_SAMPLES);
    for n in 0..200u32 {
        let out = (50..50 + limit - 1).contains(&n);
        world.borrow_mut().outage[1] = out;
        world.borrow_mut().drive(1, v);
        let s = sample(&world, &mut sampler);
        if out {
            assert_eq!(
                s.readings[1],
                Err(SampleError::Sensor(ReplayError::Injected))
            );
        } else {
            assert_true_lengths(&s, &world);
        }
    }
    assert_eq!(sampler.faults(), [None; 3]);
}

#[test]
fn a_long_outage_at_speed_latches_a_refusal_streak_and_never_an_aliased_count() {
    // Forty samples out at the speed limit: 8360 counts, past half a turn. A nearest-turn unwrap
    // after it would land a whole turn short; the sampler gives the turn up at 25 and says so.
    let (world, mut sampler) = rig(World::at_home());
    let v = MAX_STEP_COUNTS_PER_SAMPLE as i32;
    let mut latched_at = None;
    for n in 0..120u32 {
        world.borrow_mut().outage[1] = (10..50).contains(&n);
        world.borrow_mut().drive(1, v);
        let s = sample(&world, &mut sampler);
        match s.readings[1] {
            Ok(length) => {
                assert!(
                    latched_at.is_none(),
                    "sample {n}: a reading after the fault"
                );
                assert!((length - truth(&world)[1]).abs() < 4e-7, "sample {n}");
            }
            Err(SampleError::Fault(CableFault::RefusalStreak { samples })) => {
                assert_eq!(samples, MAX_REFUSED_SAMPLES);
                latched_at.get_or_insert(n);
            }
            Err(SampleError::Sensor(ReplayError::Injected)) => assert!(latched_at.is_none()),
            Err(other) => panic!("sample {n}: {other:?}"),
        }
        // The other cables are untouched.
        assert!(s.readings[0].is_ok() && s.readings[2].is_ok());
    }
    assert_eq!(latched_at, Some(10 + u32::from(MAX_REFUSED_SAMPLES) - 1));
    assert_eq!(
        sampler.faults()[1],
        Some(CableFault::RefusalStreak {
            samples: MAX_REFUSED_SAMPLES
        })
    );
}

#[test]
fn a_slipped_magnet_is_named_at_rest_and_in_motion() {
    for moving in [0, 60] {
        let (world, mut sampler) = rig(World::at_home());
        for _ in 0..5 {
            world.borrow_mut().drive(0, moving);
            assert_true_lengths(&sample(&world, &mut sampler), &world);
        }
        world.borrow_mut().magnet[0] = 3500;
        let mut named = None;
        for n in 1..=u32::from(PERSIST_SAMPLES) + 5 {
            world.borrow_mut().drive(0, moving);
            let s = sample(&world, &mut sampler);
            if n < u32::from(PERSIST_SAMPLES) {
                assert!(matches!(s.readings[0], Err(SampleError::Disagrees { .. })));
            } else if named.is_none() {
                named = Some((n, s.readings[0]));
            }
        }
        // The offset as measured: the slip, give or take the stepper's rounding to microsteps.
        let Some((n, Err(SampleError::Fault(fault)))) = named else {
            panic!("moving {moving}: {named:?}");
        };
        assert_eq!(n, u32::from(PERSIST_SAMPLES));
        assert!(
            matches!(fault, CableFault::SlippedMagnet { offset_counts } if offset_counts.abs_diff(3500) <= 3),
            "moving {moving}: {fault:?}"
        );
        assert_eq!(sampler.faults(), [Some(fault), None, None]);
    }
}

#[test]
fn a_stuck_sensor_is_named_once_the_stepper_has_moved_away() {
    let (world, mut sampler) = rig(World::at_home());
    sample(&world, &mut sampler);
    // Stuck where it is: nothing to see while the stepper holds still.
    let stuck = multiturn::angle(world.borrow().shaft[2], 16_384);
    world.borrow_mut().stuck[2] = Some(stuck);
    for _ in 0..100 {
        assert_true_lengths(&sample(&world, &mut sampler), &world);
    }
    // The stepper moves 40 counts a sample: past the tolerance in two or three, named on the tenth
    // refusal.
    let (mut first_refused, mut fault) = (None, None);
    for n in 0..30 {
        world.borrow_mut().drive(2, 40);
        let s = sample(&world, &mut sampler);
        match s.readings[2] {
            Err(SampleError::Disagrees { .. }) => {
                first_refused.get_or_insert(n);
            }
            Err(SampleError::Fault(f)) => {
                fault.get_or_insert((n, f));
            }
            _ => {}
        }
    }
    let (n, f) = fault.expect("named");
    let first = first_refused.expect("refused first");
    assert!((1..=2).contains(&first), "{first}");
    assert_eq!(n, first + i32::from(PERSIST_SAMPLES) - 1);
    assert!(
        matches!(f, CableFault::StuckSensor { angle_counts, commanded_move_counts }
            if angle_counts == stuck && commanded_move_counts.abs_diff((n + 1) * 40) <= 3),
        "{f:?}"
    );
}

#[test]
fn a_turn_lost_in_an_outage_is_turn_aliasing() {
    // The shaft turns 1.1 turns in ten samples (faster than the drives' limit: pushed, or a
    // runaway command) while the sensor is out. Placed nearest its last reading, the angle is a turn
    // short of the stepper: refused, and named once it holds.
    let (world, mut sampler) = rig(World::at_home());
    sample(&world, &mut sampler);
    for n in 0..40 {
        world.borrow_mut().outage[0] = n < 10;
        if n < 10 {
            world.borrow_mut().drive(0, 18_000 / 10);
        }
        let s = sample(&world, &mut sampler);
        if n >= 10 {
            assert!(
                s.readings[0].is_err(),
                "sample {n}: an aliased reading accepted"
            );
        }
    }
    assert_eq!(
        sampler.faults()[0],
        Some(CableFault::TurnAliasing { turns: -1 })
    );
}

#[test]
fn power_up_away_from_home_is_named_within_half_a_turn_either_way() {
    // 2.5 mm of cable is 10 430 counts: the angle reads 5954 counts the other side of home.
    let metres_per_count = spools::<f64>()[1].metres_per_count();
    let off = (2.5e-3 / metres_per_count).round() as i32;
    assert_eq!(off, 10_430);
    for (offset, seen) in [
        (off, off - TURN),
        (-off, TURN - off),
        (1000, 1000),
        (-400, -400),
    ] {
        let mut w = World::at_home();
        w.shaft[1] += offset;
        let (world, mut sampler) = rig(w);
        let mut last = None;
        for _ in 0..PERSIST_SAMPLES {
            last = Some(sample(&world, &mut sampler).readings[1]);
        }
        let fault = CableFault::PowerUpOffHome {
            offset_counts: seen,
        };
        assert_eq!(last, Some(Err(SampleError::Fault(fault))), "{offset}");
        assert_eq!(sampler.faults(), [None, Some(fault), None]);
    }
}

#[test]
fn power_up_within_the_tolerance_locks_and_a_whole_turn_is_invisible() {
    // Within a full step of home: tracked. A whole sensor turn away reads like home: no single-turn
    // sensor can see it (the limit, in README.md "Faults").
    let tolerance = CROSS_CHECK_TOLERANCE_COUNTS as i32;
    for offset in [0, tolerance, -tolerance, TURN] {
        let mut w = World::at_home();
        w.shaft[0] += offset;
        let (world, mut sampler) = rig(w);
        for _ in 0..20 {
            assert!(sample(&world, &mut sampler).readings[0].is_ok(), "{offset}");
        }
    }
}

#[test]
fn rehoming_takes_the_angle_at_home_and_clears_the_fault() {
    let (world, mut sampler) = rig(World::at_home());
    sample(&world, &mut sampler);
    world.borrow_mut().magnet[0] = 5000;
    for _ in 0..PERSIST_SAMPLES {
        sample(&world, &mut sampler);
    }
    assert!(matches!(
        sampler.faults()[0],
        Some(CableFault::SlippedMagnet { .. })
    ));
    // Driven home (here: it never left) and re-homed: the slipped angle is home now.
    sampler.rehome();
    let s = sample(&world, &mut sampler);
    assert_true_lengths(&s, &world);
    assert_eq!(sampler.faults(), [None; 3]);
    // And tracked from there, stepper and sensor agreeing.
    for _ in 0..100 {
        world.borrow_mut().drive(0, -150);
        assert_true_lengths(&sample(&world, &mut sampler), &world);
    }
}

#[test]
fn after_a_reset_that_was_no_power_up_no_cable_is_taken_to_be_at_home() {
    // The case power-up cannot see (above): cable 1 a whole sensor turn from home, cable 2 at
    // home. After a reset the board reads as no power-up, every cable latches `HomeUnknown` and
    // gives no length, the one at home too (nothing tells them apart); re-homed at home, each is
    // tracked again.
    let mut w = World::at_home();
    w.shaft[1] += TURN;
    let (world, mut sampler) = rig(w);
    sampler.distrust_home();
    for _ in 0..3 * MAX_REFUSED_SAMPLES {
        let s = sample(&world, &mut sampler);
        assert_eq!(
            s.readings,
            [Err(SampleError::Fault(CableFault::HomeUnknown)); 3]
        );
    }
    assert_eq!(sampler.faults(), [Some(CableFault::HomeUnknown); 3]);
    assert_eq!(sampler.positions_counts(), [None; 3]);
    // Driven home and re-homed there: tracked from home, stepper and sensor agreeing.
    world.borrow_mut().shaft[1] -= TURN;
    sampler.rehome();
    assert_true_lengths(&sample(&world, &mut sampler), &world);
    for _ in 0..100 {
        world.borrow_mut().drive(1, 150);
        assert_true_lengths(&sample(&world, &mut sampler), &world);
    }
    assert_eq!(sampler.faults(), [None; 3]);
}

#[test]
fn lengths_follow_a_geared_spool_across_a_wrap() {
    // Home at 16380 on cable 0 (paid out with counts): +10 counts wraps the angle to 6.
    let (world, mut sampler) = rig(World::at_home());
    let s0 = spools::<f64>()[0];
    assert_eq!(s0.direction, Direction::PayOutWithCounts);
    let at_home = sample(&world, &mut sampler).readings[0].unwrap();
    world.borrow_mut().drive(0, 10);
    let s = sample(&world, &mut sampler);
    assert_eq!(multiturn::angle(world.borrow().shaft[0], 16_384), 6);
    let moved = f64::from(s.readings[0].unwrap() - at_home);
    assert!(
        (moved - 10.0 * s0.metres_per_count()).abs() < 6e-8,
        "{moved}"
    );
    assert_eq!(sampler.positions_counts()[0], Some(16_390));
}

#[test]
fn settings_that_could_alias_are_refused() {
    let sensors = || [0, 1, 2].map(|_| crate::encoder::replay::ReplaySensor::new(16_384, &[]));
    let scale = STEPPER_SCALE.unwrap();
    let good = sampler_settings();
    assert!(Sampler::new(sensors(), spools(), scale, good).is_ok());
    let mut fast = good;
    fast.max_step_counts_per_sample = 400;
    assert_eq!(
        Sampler::new(sensors(), spools(), scale, fast).err(),
        Some(SamplerError::Settings)
    );
    let mut eager = good;
    eager.persist_samples = 0;
    assert_eq!(
        Sampler::new(sensors(), spools(), scale, eager).err(),
        Some(SamplerError::Settings)
    );
    let mut bad = spools::<f32>();
    bad[2].radius_m = 0.0;
    assert_eq!(
        Sampler::new(sensors(), bad, scale, good).err(),
        Some(SamplerError::Calibration(CalibrationError::Radius))
    );
}
