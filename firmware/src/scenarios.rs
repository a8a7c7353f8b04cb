//! The scenarios ("never confidently wrong"), one host test each, through the production
//! sampler (turn tracking and stepper cross-check at 1 kHz), the reading validator and the estimator
//! loop (a tick every ten samples), on scripted shafts that follow the recorded trajectory.
//! The sixth, a cold estimate not blocking sampling, needs real preemption: the QEMU `estimator`
//! image checks it (`target::images`).

use std::cell::RefCell;
use std::rc::Rc;

use model_core::Quaternion;

use crate::config::{
    BenchModel, MAX_STEP_COUNTS_PER_SAMPLE, MODEL_NODES, SAMPLES_PER_TICK, loop_config, model,
    spools,
};
use crate::control::{EstimatorLoop, Status, TickReport};
use crate::encoder::multiturn;
use crate::encoder::replay::ReplayError;
use crate::fixture::{REFERENCE, RecordedMotion, TICK_COUNT, home_counts};
use crate::sampler::tests::{World, WorldSensor, rig, steps};
use crate::sampler::{CableFault, Sample, SampleError, Sampler};
use crate::validate::Rejection;

type Report = TickReport<SampleError<ReplayError>>;

/// Tip error of a record against the recorded tick's reference, m.
fn tip_error(tip: [f32; 3], tick: usize) -> f64 {
    let r = &REFERENCE[tick.min(TICK_COUNT - 1)].tip_m;
    (0..3)
        .map(|i| (f64::from(tip[i]) - r[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The rig: scripted shafts and steppers, the sampler, the loop.
struct Bench<'m> {
    world: Rc<RefCell<World>>,
    sampler: Sampler<WorldSensor>,
    lp: EstimatorLoop<'m, Quaternion<f32>, MODEL_NODES>,
    motion: [RecordedMotion; 3],
    home: [i32; 3],
    /// Motion of shaft and stepper beyond the recording, counts.
    extra: [i32; 3],
    /// Offset of the shaft alone (moved while the power was off), counts.
    shaft_offset: [i32; 3],
    /// Every accepted reading was within this of the truth, m.
    worst_accepted_error_m: f32,
}

impl<'m> Bench<'m> {
    /// The recording, held at home for `hold` samples first.
    fn new(model: &'m BenchModel, hold: u32) -> Self {
        let (world, sampler) = rig(World::at_home());
        Self {
            world,
            sampler,
            lp: EstimatorLoop::new(model, loop_config()).unwrap(),
            motion: [0, 1, 2].map(|c| RecordedMotion::new(c, hold)),
            home: [0, 1, 2].map(home_counts),
            extra: [0; 3],
            shaft_offset: [0; 3],
            worst_accepted_error_m: 0.0,
        }
    }

    /// One sample with the shafts where the recording (and the scenario) puts them.
    fn sample(&mut self) -> Sample<SampleError<ReplayError>> {
        let n = self.sampler.next_seq();
        {
            let mut w = self.world.borrow_mut();
            for c in 0..3 {
                let p = self.motion[c].position_counts(n) + self.extra[c];
                w.shaft[c] = p + self.shaft_offset[c];
                w.commanded[c] = p - self.home[c];
            }
        }
        let sample = self.sampler.sample(steps(&self.world));
        // No accepted reading is further from its shaft than the stepper tolerance (19.5 um).
        let spools = spools::<f32>();
        let shaft = self.world.borrow().shaft;
        for c in 0..3 {
            if let Ok(length) = sample.readings[c] {
                let truth = spools[c].length_m(i64::from(shaft[c]));
                self.worst_accepted_error_m =
                    self.worst_accepted_error_m.max((length - truth).abs());
            }
        }
        sample
    }

    /// Samples up to the next tick instant, then a loop tick on the last sample.
    fn tick(&mut self) -> Report {
        loop {
            let s = self.sample();
            // Ticks at samples 0, 10, 20, ...
            if s.seq.is_multiple_of(SAMPLES_PER_TICK) {
                return self.lp.tick(&s);
            }
        }
    }
}

/// The cable and fault a report names, if it names a latched fault.
fn fault_of(report: &Report) -> Option<(u8, CableFault)> {
    match report.status {
        Status::Rejected(Rejection::Source {
            cable,
            error: SampleError::Fault(fault),
        }) => Some((cable, fault)),
        _ => None,
    }
}

/// Every fresh estimate is within 0.1 mm of the reference at its recorded tick.
fn assert_fresh_is_right(report: &Report, recorded_tick: usize) {
    if report.status == Status::Fresh {
        let record = report.estimate.unwrap();
        let error = tip_error(record.tip_position_m, recorded_tick);
        assert!(
            error < 1e-4,
            "tick {}: fresh, {:.3} mm off",
            report.tick,
            error * 1e3
        );
    }
}

#[test]
fn scenario_1_a_four_tick_spi_outage_at_speed_is_named_never_aliased() {
    // Robot at home; then cable 1 reeled at the drives' speed limit (209 counts a sample) while
    // its sensor is out for four ticks (40 samples, 8360 counts: past half a turn, where a
    // nearest-turn unwrap after the outage would land a whole turn, 3.93 mm, short).
    let model = model().unwrap();
    let mut bench = Bench::new(&model, u32::MAX);
    for _ in 0..10 {
        assert_eq!(bench.tick().status, Status::Fresh);
    }
    let before = bench.sampler.positions_counts()[1].unwrap();
    let v = MAX_STEP_COUNTS_PER_SAMPLE as i32;
    let mut reports = Vec::new();
    for n in 0..120u32 {
        bench.world.borrow_mut().outage[1] = (10..50).contains(&n);
        bench.extra[1] += if n < 60 { v } else { 0 };
        let s = bench.sample();
        if s.seq.is_multiple_of(SAMPLES_PER_TICK) {
            reports.push(bench.lp.tick(&s));
        }
    }
    // What a nearest-turn unwrap from the last reading before the outage would say now: a turn off.
    let shaft = bench.world.borrow().shaft[1];
    let naive =
        multiturn::nearest(before + 9 * v, multiturn::angle(shaft, 16_384), 16_384).unwrap();
    assert_eq!(
        (shaft - naive) / 16_000,
        1,
        "the outage is long enough to alias"
    );
    // The sampler gave the turn up instead, named it, and accepted nothing wrong.
    let fault = CableFault::RefusalStreak { samples: 25 };
    assert_eq!(bench.sampler.faults(), [None, Some(fault), None]);
    assert!(
        bench.worst_accepted_error_m < 2e-5,
        "{}",
        bench.worst_accepted_error_m
    );
    // The loop named the outage on every tick from its start: first the sensor, then the fault.
    for r in &reports {
        assert_ne!(r.status, Status::Fresh, "tick {}", r.tick);
    }
    let named: Vec<_> = reports.iter().filter_map(fault_of).collect();
    assert!(
        named.len() >= 8 && named.iter().all(|f| *f == (1, fault)),
        "{named:?}"
    );
    // Driven back home and re-homed: fresh and right again.
    for _ in 0..60 {
        bench.extra[1] -= v;
        bench.sample();
    }
    assert_eq!(bench.extra[1], 0);
    bench.sampler.rehome();
    bench.lp.restart();
    let r = bench.tick();
    assert_eq!(r.status, Status::Fresh);
    assert!(r.estimate.unwrap().cold);
    assert_fresh_is_right(&r, 0);
    assert_eq!(bench.sampler.faults(), [None; 3]);
}

#[test]
fn scenario_1_tracking_does_not_wait_for_a_cold_estimate() {
    // The estimator's first tick is cold (90 ms on the MCU). Meanwhile cable 1 is reeled at the
    // speed limit (90 samples: 18 810 counts, more than a sensor turn) with a four-sample SPI
    // outage: the sampler keeps every turn, and the next tick's lengths are the shafts'.
    let model = model().unwrap();
    let mut bench = Bench::new(&model, u32::MAX);
    assert_eq!(bench.tick().status, Status::Fresh);
    let v = MAX_STEP_COUNTS_PER_SAMPLE as i32;
    for n in 0..90 {
        bench.world.borrow_mut().outage[1] = (40..44).contains(&n);
        bench.extra[1] += v;
        let s = bench.sample();
        assert_eq!(
            s.readings[1].is_err(),
            (40..44).contains(&n),
            "sample {}",
            s.seq
        );
    }
    assert_eq!(bench.sampler.faults(), [None; 3]);
    assert!(bench.worst_accepted_error_m < 1e-6);
    let shaft = bench.world.borrow().shaft[1];
    assert_eq!(bench.sampler.positions_counts()[1], Some(shaft));
}

#[test]
fn scenario_2_a_permanently_slipped_magnet_is_named_and_never_fresh() {
    // Cable 2's magnet slips 0.84 mm (3500 counts) in the middle of tick 15 and stays slipped.
    let model = model().unwrap();
    let mut bench = Bench::new(&model, 0);
    let mut named_at = None;
    for tick in 0..TICK_COUNT {
        if tick == 15 {
            // Half way to the tick: the slip happens between ticks.
            for _ in 0..5 {
                bench.sample();
            }
            bench.world.borrow_mut().magnet[2] = 3500;
        }
        let r = bench.tick();
        assert_fresh_is_right(&r, tick);
        if tick < 15 {
            assert_eq!(r.status, Status::Fresh, "tick {tick}");
            continue;
        }
        // From the slip on: refused, then named, never fresh; the last good estimate is tick 14's.
        assert_ne!(r.status, Status::Fresh, "tick {tick}");
        assert_eq!(r.estimate.unwrap().tick, 14);
        match fault_of(&r) {
            Some((2, CableFault::SlippedMagnet { offset_counts })) => {
                assert!(offset_counts.abs_diff(3500) <= 3);
                named_at.get_or_insert(tick);
            }
            other => {
                assert!(
                    named_at.is_none(),
                    "tick {tick}: the fault is not named: {other:?}"
                );
                assert!(
                    matches!(
                        r.status,
                        Status::Rejected(Rejection::Source {
                            cable: 2,
                            error: SampleError::Disagrees { .. }
                        })
                    ),
                    "tick {tick}: {:?}",
                    r.status
                );
            }
        }
    }
    assert_eq!(named_at, Some(16));
}

#[test]
fn scenario_3_power_up_two_and_a_half_millimetres_from_home_is_named() {
    // Cable 1 was moved 2.5 mm (10 430 counts, 0.64 sensor turn) while the power was off; the
    // steppers start at home. The angle reads 5954 counts the other side of home.
    let model = model().unwrap();
    let mut bench = Bench::new(&model, u32::MAX);
    let off = (2.5e-3 / spools::<f64>()[1].metres_per_count()).round() as i32;
    bench.shaft_offset[1] = off;
    let mut named = None;
    for tick in 0..20 {
        let r = bench.tick();
        assert_ne!(r.status, Status::Fresh, "tick {tick}");
        assert_eq!(r.estimate, None);
        // Refused from the first sample, named from the tick after the tenth.
        match fault_of(&r) {
            Some((1, fault @ CableFault::PowerUpOffHome { .. })) => {
                assert!(tick >= 1);
                assert_eq!(*named.get_or_insert(fault), fault);
            }
            other => assert!(tick == 0, "tick {tick}: {other:?}"),
        }
    }
    // The recording's home is one count from the calibration's: the offset reads 5953 or 5954.
    let fault = named.expect("named");
    assert!(
        matches!(fault, CableFault::PowerUpOffHome { offset_counts } if offset_counts.abs_diff(off - 16_384) <= 1),
        "{fault:?}"
    );
    assert_eq!(bench.sampler.faults(), [None, Some(fault), None]);
    // The homing routine drives cable 1 home (the stepper counts it) and re-homes.
    for _ in 0..50 {
        bench.extra[1] -= off / 50;
        bench.sample();
    }
    bench.extra[1] = -off;
    bench.sample();
    assert_eq!(bench.world.borrow().shaft[1], home_counts(1));
    bench.sampler.rehome();
    bench.lp.restart();
    let r = bench.tick();
    assert_eq!(r.status, Status::Fresh);
    assert_fresh_is_right(&r, 0);
}

#[test]
fn scenario_4_a_stuck_sensor_is_named() {
    // Cable 0's sensor freezes in the middle of tick 5, while cable 0 pays out about 50 counts a
    // sample: refused three samples later, named ten refusals after that.
    let model = model().unwrap();
    let mut bench = Bench::new(&model, 0);
    let mut named = None;
    for tick in 0..TICK_COUNT {
        if tick == 6 {
            for _ in 0..5 {
                bench.sample();
            }
            let angle = multiturn::angle(bench.world.borrow().shaft[0], 16_384);
            bench.world.borrow_mut().stuck[0] = Some(angle);
        }
        let r = bench.tick();
        assert_fresh_is_right(&r, tick);
        if tick < 6 {
            assert_eq!(r.status, Status::Fresh);
            continue;
        }
        assert_ne!(r.status, Status::Fresh, "tick {tick}");
        if let Some((0, CableFault::StuckSensor { .. })) = fault_of(&r) {
            named.get_or_insert(tick);
        } else {
            assert!(named.is_none(), "tick {tick}: {:?}", r.status);
        }
    }
    assert_eq!(named, Some(7));
    assert!(matches!(
        bench.sampler.faults()[0],
        Some(CableFault::StuckSensor { .. })
    ));
}

#[test]
fn scenario_5_a_slack_cable_is_named() {
    // At the home pose, cable 2 is paid out 0.1 mm a tick for 15 ticks while the rod stays put:
    // the cable goes slack. Encoders and steppers agree (the spool did turn): only the model can
    // tell, once no shape of the rod makes the lengths.
    let model = model().unwrap();
    let mut bench = Bench::new(&model, u32::MAX);
    let per_tick = (1e-4 / spools::<f64>()[2].metres_per_count()).round() as i32;
    assert_eq!(bench.tick().status, Status::Fresh);
    let mut first_named = None;
    let mut worst_fresh_error = 0.0f64;
    let mut statuses = Vec::new();
    for tick in 1..=40 {
        if tick <= 15 {
            bench.extra[2] += per_tick;
        }
        let r = bench.tick();
        if r.status == Status::Fresh {
            worst_fresh_error =
                worst_fresh_error.max(tip_error(r.estimate.unwrap().tip_position_m, 0));
        }
        if let Status::SlackCable { cable, excess_m } = r.status {
            assert_eq!(cable, 2, "tick {tick}");
            assert!(excess_m > 0.0);
            first_named.get_or_insert(tick);
        }
        statuses.push((tick, r.status));
    }
    println!("worst fresh tip error {:.2} mm", worst_fresh_error * 1e3);
    for s in &statuses {
        println!("{s:?}");
    }
    let first = first_named.expect("slack named");
    // Named while the slack is at most a millimetre, and never fresh again while it lasts.
    assert!(first <= 10, "first named at tick {first}");
    assert!(
        statuses
            .iter()
            .filter(|(tick, _)| *tick >= first)
            .all(|(_, s)| *s != Status::Fresh),
        "{statuses:?}"
    );
    assert_eq!(bench.sampler.faults(), [None; 3]);
}

/// The limit of scenario 5 (README.md, "Faults"): slack that creeps in at 10 um a tick is explained
/// by a wrong force, `Determined` and published, until it nears 0.2 mm: three cables and three force
/// components leave no redundancy but the rod's reachable lengths. Measured here: fresh estimates up
/// to about 11 mm off before the slack is named. If this fails because the loop does better, update
/// the README's numbers.
#[test]
fn limit_creeping_slack_is_published_as_a_wrong_force_until_it_is_large() {
    let model = model().unwrap();
    let mut bench = Bench::new(&model, u32::MAX);
    let per_tick = (1e-5 / spools::<f64>()[2].metres_per_count()).round() as i32;
    let (mut worst_fresh_m, mut named) = (0.0f64, None);
    for tick in 0..TICK_COUNT {
        bench.extra[2] += per_tick;
        let r = bench.tick();
        if r.status == Status::Fresh && named.is_none() {
            worst_fresh_m = worst_fresh_m.max(tip_error(r.estimate.unwrap().tip_position_m, 0));
        }
        if let Status::SlackCable { cable, .. } = r.status {
            named.get_or_insert((tick, cable));
        }
    }
    println!(
        "creeping slack: worst fresh tip error {:.2} mm before it was named; named {named:?}",
        worst_fresh_m * 1e3
    );
    assert!(worst_fresh_m > 1e-3, "{worst_fresh_m}");
    let (tick, cable) = named.expect("named eventually");
    assert_eq!(cable, 2);
    assert!(tick <= 30, "{tick}");
}
