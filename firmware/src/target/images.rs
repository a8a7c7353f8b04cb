//! The bodies of the QEMU images (`src/bin/*.rs`): each prints plain text over semihosting and
//! returns whether it passed. The closing line `N passed, N failed` is what CI reads.

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m_semihosting::hprintln;

use super::counter::{self, Counter};
use super::memory;
use super::stopwatch::Stopwatch;
use super::tasks;
use crate::checks::{self, BenchLoop, Expected, ReplayReport, TickCheck};
use crate::config::{SAMPLE_RATE_HZ, SAMPLES_PER_TICK};
use crate::control::Status;
use crate::encoder::replay::ReplayError;
use crate::fixture::{JUMP_TICK, RecordedSensor, RecordedSteppers, SENSOR_FAULT_TICK, TICK_COUNT};
use crate::sampler::{Sample, SampleError, Sampler};
use crate::validate::Rejection;

fn report_memory() {
    let m = memory::measure();
    crate::hostln!(
        "memory: flash {} B, static RAM {} B, stack high-water {} B, RAM total {} B",
        m.flash_bytes,
        m.static_ram_bytes,
        m.stack_bytes,
        m.ram_bytes()
    );
}

/// Nanometres (or micronewtons) for a length in metres (force in newtons), saturating.
fn micro(x: f64, scale: f64) -> u32 {
    let v = x * scale;
    if v.is_finite() && v < f64::from(u32::MAX) {
        v as u32
    } else {
        u32::MAX
    }
}

/// The robot's estimator model, or `None` once it has said why the model refused the robot.
fn the_model() -> Option<crate::config::BenchModel> {
    crate::config::model()
        .map_err(|e| hprintln!("model refused: {}", e))
        .ok()
}

/// A check's summary, or `None` once it has said why the check could not start.
fn started<S, E: core::fmt::Debug>(result: Result<S, E>) -> Option<S> {
    result.map_err(|e| hprintln!("setup refused: {:?}", e)).ok()
}

/// model-core's no_std self-checks in f32.
pub fn selftest() -> bool {
    hprintln!("selftest: model-core self-checks in f32 on the Cortex-M4F");
    let (passed, failed) = model_checks::selftest::run_all::<f32>(|name, outcome| match outcome {
        Ok(()) => hprintln!("ok   {}", name),
        Err(f) => hprintln!(
            "FAIL {}: {} = {:e} (limit {:e})",
            name,
            f.check,
            f.value,
            f.limit
        ),
    });
    report_memory();
    hprintln!("{} passed, {} failed", passed, failed);
    failed == 0 && passed > 0
}

fn status_name<E>(status: &Status<SampleError<E>>) -> &'static str {
    match status {
        Status::Fresh => "fresh",
        Status::Rejected(Rejection::Source { error, .. }) => match error {
            SampleError::Sensor(_) => "rejected:sensor",
            SampleError::NotInTurn { .. } => "rejected:not-in-turn",
            SampleError::Disagrees { .. } => "rejected:disagrees",
            SampleError::Fault(_) => "rejected:fault",
        },
        Status::Rejected(Rejection::NonFinite { .. }) => "rejected:non-finite",
        Status::Rejected(Rejection::OutOfRange { .. }) => "rejected:out-of-range",
        Status::Rejected(Rejection::Jump { .. }) => "rejected:jump",
        Status::NotConverged(_) => "not-converged",
        Status::Refused(_) => "refused",
        Status::Inconsistent { .. } => "inconsistent",
        Status::SlackCable { .. } => "slack-cable",
        Status::Indeterminate(_) => "indeterminate",
    }
}

/// The live link as the images drive it: each tick's record framed onto USART1, QEMU's first
/// serial port, which `test.sh` captures for host-sim; the newest fresh estimate's tip frame kept
/// with it.
#[cfg(feature = "link")]
struct LinkOut {
    writer: crate::link::RecordWriter<super::uart::Usart1Tx>,
    tip_orientation: [f32; 4],
    records: u32,
    bytes: usize,
    unsent: u32,
}

#[cfg(feature = "link")]
impl LinkOut {
    fn take() -> Option<Self> {
        use super::uart::{RESET_PCLK2_HZ, Usart1Tx};
        let device = super::device::Peripherals::take()?;
        let port = Usart1Tx::new(device.USART1, RESET_PCLK2_HZ, crate::config::LINK_BAUD);
        Some(Self {
            writer: crate::link::RecordWriter::new(port),
            tip_orientation: [1.0, 0.0, 0.0, 0.0],
            records: 0,
            bytes: 0,
            unsent: 0,
        })
    }

    /// Sends a tick's record (outside the measured tick), reading the tip frame of a fresh
    /// estimate from the loop.
    fn send<E>(
        &mut self,
        report: &crate::control::TickReport<SampleError<E>>,
        estimator: &BenchLoop<'_>,
    ) {
        if matches!(report.status, Status::Fresh)
            && let Some(rotation) = estimator.tip_rotation()
        {
            self.tip_orientation = crate::link::orientation(&rotation);
        }
        let estimate = report.estimate.as_ref();
        let record =
            crate::link::record(report.tick, &report.status, estimate, self.tip_orientation);
        match self.writer.send(&record) {
            Ok(n) => (self.records, self.bytes) = (self.records + 1, self.bytes + n),
            Err(_) => self.unsent += 1,
        }
    }

    /// Prints the tally; whether `ticks` records went out.
    fn close(&self, image: &str, ticks: usize) -> bool {
        hprintln!(
            "{}: live link: {} records, {} bytes on USART1, {} not sent",
            image,
            self.records,
            self.bytes,
            self.unsent
        );
        self.unsent == 0 && self.records as usize == ticks
    }
}

/// The recorded trajectory through the encoders and the estimator loop, against the f64 reference
/// ([`e2e_trajectory`]), each tick's record sent on the live link ([`LinkOut`]), which host-sim
/// checks against the same reference. Passes when the checks pass and every tick's record went
/// out.
#[cfg(feature = "link")]
pub fn e2e() -> bool {
    let Some(mut link) = LinkOut::take() else {
        return false;
    };
    let passed = e2e_trajectory(&mut |_, report, estimator| link.send(report, estimator));
    link.close("e2e", TICK_COUNT) && passed
}

/// Any robot end to end ([`crate::robot_check`]): the robot of the robot file the image was built
/// from along its load path, each applied force printed and each tick's record sent on the live
/// link, for host-sim to check against its own f64 solves of the same file. Passes when every tick
/// is fresh with the applied force and every record went out.
#[cfg(feature = "link")]
pub fn robot() -> bool {
    use crate::config::{MODEL_NODES, ROBOT_FILE, ROBOT_NAME, STEPS_PER_SECTION};
    use crate::robot_check::{self, PATH_TICKS};

    let Some(model) = the_model() else {
        return false;
    };
    let Some(peripherals) = cortex_m::Peripherals::take() else {
        return false;
    };
    let Some(mut link) = LinkOut::take() else {
        return false;
    };
    let counter = Counter::start(peripherals.SYST);
    hprintln!(
        "robot: {} ({}): {} nodes, {} steps per section, {} ticks; force tolerance {} uN",
        ROBOT_FILE,
        ROBOT_NAME,
        MODEL_NODES,
        STEPS_PER_SECTION,
        PATH_TICKS,
        micro(
            robot_check::force_tolerance_n(robot_check::bending_scale_n(&model)),
            1e6
        )
    );
    let clock = || counter::instructions(counter.ticks());
    let result = robot_check::run_path(&model, &clock, |t, report, estimator| {
        // The applied force in full (host-sim solves the robot file at it).
        hprintln!(
            "applied tick={} force_n={:?},{:?},{:?}",
            t.tick,
            t.applied_n.x,
            t.applied_n.y,
            t.applied_n.z
        );
        hprintln!(
            "tick {:2} {:22} force_err_uN {:5} sweeps {} instructions {:7} {}",
            t.tick,
            status_name(&t.status),
            micro(t.force_error_n, 1e6),
            t.sweeps,
            t.cost,
            if t.passed { "pass" } else { "FAIL" }
        );
        link.send(report, estimator);
    });
    let Some(summary) = started(result) else {
        return false;
    };
    hprintln!(
        "worst force error {} uN, most sweeps {}, most instructions per warm tick {}",
        micro(summary.worst_force_error_n, 1e6),
        summary.max_sweeps,
        summary.max_warm_cost
    );
    report_memory();
    let sent = link.close("robot", PATH_TICKS);
    hprintln!(
        "robot: {} passed, {} failed",
        summary.passed,
        summary.failed
    );
    sent && summary.failed == 0 && summary.passed > 0
}

/// The recorded trajectory through the encoders and the estimator loop, against the f64 reference,
/// calling `tap` after each tick with its verdict, the loop's report and the loop (for [`e2e`]'s
/// live link; outside the measured tick).
pub fn e2e_trajectory(tap: &mut dyn FnMut(&TickCheck, &ReplayReport, &BenchLoop<'_>)) -> bool {
    let Some(model) = the_model() else {
        return false;
    };
    let Some(peripherals) = cortex_m::Peripherals::take() else {
        return false;
    };
    let counter = Counter::start(peripherals.SYST);
    hprintln!(
        "e2e: {} recorded ticks; tolerances tip {} nm, force {} uN",
        crate::fixture::TICK_COUNT,
        micro(checks::TIP_TOLERANCE_M, 1e9),
        micro(checks::FORCE_TOLERANCE_N, 1e6)
    );
    let clock = || counter::instructions(counter.ticks());
    let result = checks::run_trajectory(&model, &clock, |c, report, estimator| {
        let expected = match c.expected {
            Expected::Fresh => "",
            Expected::SensorFault => " (injected sensor fault)",
            Expected::Jump => " (injected glitch)",
        };
        hprintln!(
            "tick {:2} {:22} estimate@{:2} tip_err_nm {:6} force_err_uN {:5} sweeps {} instructions {:7} {}{}",
            c.tick,
            status_name(&c.status),
            c.estimate_tick.unwrap_or(u32::MAX),
            micro(c.tip_error_m, 1e9),
            micro(c.force_error_n, 1e6),
            c.sweeps,
            c.cost,
            if c.passed { "pass" } else { "FAIL" },
            expected
        );
        tap(c, report, estimator);
    });
    let Some(summary) = started(result) else {
        return false;
    };
    hprintln!(
        "worst tip error {} nm, worst force error {} uN, most sweeps {}, most instructions per warm tick {}, per sample {}",
        micro(summary.worst_tip_error_m, 1e9),
        micro(summary.worst_force_error_n, 1e6),
        summary.max_sweeps,
        summary.max_warm_cost,
        summary.max_sample_cost
    );
    report_memory();
    hprintln!("e2e: {} passed, {} failed", summary.passed, summary.failed);
    summary.failed == 0 && summary.passed > 0
}

/// The golden rows from their cable lengths alone.
pub fn golden() -> bool {
    let Some(model) = the_model() else {
        return false;
    };
    hprintln!(
        "golden: f32 cold estimate per golden row at {} steps; tolerance tip {} nm",
        crate::config::STEPS_PER_SECTION,
        micro(checks::TIP_TOLERANCE_M, 1e9)
    );
    let result = checks::run_golden(&model, |r| {
        hprintln!(
            "row {} {:?} tip_err_nm {:6} force_err_uN {:5} force_std_uN {:5} sweeps {:2} {}",
            r.row,
            r.termination,
            micro(r.tip_error_m, 1e9),
            micro(r.force_error_n, 1e6),
            micro(r.force_std_n, 1e6),
            r.sweeps,
            if r.passed { "pass" } else { "FAIL" }
        );
    });
    let Some(summary) = started(result) else {
        return false;
    };
    hprintln!(
        "worst tip error {} nm",
        micro(summary.worst_tip_error_m, 1e9)
    );
    report_memory();
    hprintln!(
        "golden: {} passed, {} failed",
        summary.passed,
        summary.failed
    );
    summary.failed == 0 && summary.passed > 0
}

/// The tendon-driven robot in f32: the golden tendon rows from their displacements, then the
/// recorded actuation with warm updates, each against its f64 reference.
pub fn tendon() -> bool {
    let Some(peripherals) = cortex_m::Peripherals::take() else {
        return false;
    };
    let counter = Counter::start(peripherals.SYST);
    let clock = || counter::instructions(counter.ticks());
    hprintln!(
        "tendon: f32 displacement control at {} steps; tolerances tip {} nm, tension {} uN",
        crate::tendon::STEPS_PER_SECTION,
        micro(crate::tendon::TIP_TOLERANCE_M, 1e9),
        micro(crate::tendon::TENSION_TOLERANCE_N, 1e6)
    );
    let line = |what: &str, c: &crate::tendon::CaseCheck| {
        hprintln!(
            "{} {:2} tip_err_nm {:6} tension_err_uN {:6} states {} sweeps {:4} instructions {:9} {}",
            what,
            c.index,
            micro(c.tip_error_m, 1e9),
            micro(c.tension_error_n, 1e6),
            if c.states_match { "match" } else { "DIFFER" },
            c.sweeps,
            c.cost,
            if c.passed { "pass" } else { "FAIL" }
        );
    };
    let golden = crate::tendon::run_golden(&clock, &mut |c| line("golden row", c));
    let trajectory = crate::tendon::run_trajectory(&clock, &mut |c| line("tick", c));
    let (Ok(golden), Ok(trajectory)) = (golden, trajectory) else {
        hprintln!("tendon: setup refused");
        return false;
    };
    hprintln!(
        "worst tip error {} nm, worst tension error {} uN; cold solve {} instructions, most per warm update {}",
        micro(
            golden.worst_tip_error_m.max(trajectory.worst_tip_error_m),
            1e9
        ),
        micro(
            golden
                .worst_tension_error_n
                .max(trajectory.worst_tension_error_n),
            1e6
        ),
        trajectory.cold_cost,
        trajectory.max_warm_cost
    );
    report_memory();
    let (passed, failed) = (
        golden.passed + trajectory.passed,
        golden.failed + trajectory.failed,
    );
    hprintln!("tendon: {} passed, {} failed", passed, failed);
    failed == 0 && passed > 0
}

/// Takes the undefined-instruction trap: the HardFault handler must report it and exit with 1.
pub fn fault() -> bool {
    hprintln!("fault: executing an undefined instruction");
    cortex_m::asm::udf()
}

/// Frames the `overflow` image's recursion has entered (a static: at the top of RAM under flip-link,
/// just above the stack without it, where an overflowing stack would write over it).
static OVERFLOW_FRAMES: AtomicU32 = AtomicU32::new(0);

/// Words the overflowing stack would overwrite without flip-link (`.data`, next to the counter):
/// 128 B, more than a level of the recursion, so that one of the levels written in full before the
/// fault lands on them.
static OVERFLOW_CANARY: [AtomicU32; 32] = [const { AtomicU32::new(CANARY) }; 32];

/// The canary's value: no frame of the recursion holds it (they hold `u32::MAX` minus the depth).
const CANARY: u32 = 0x5afe_c0de;

/// Bytes of stack each level of the recursion fills (its frame adds the saved registers): small,
/// so that the recursion writes every word on its way down, the statics' too where they lie in its
/// path (without flip-link), before a write leaves RAM.
const OVERFLOW_FRAME_BYTES: usize = 64;

/// Recurses past the stack: every level fills 64 B of it, until the stack leaves RAM at its bottom
/// and the access faults. The HardFault must say so ([`overflow_report`]); returning is a failure.
pub fn overflow() -> bool {
    let stack = memory::stack_top() - memory::stack_bottom();
    hprintln!(
        "overflow: recursing {} B a frame through the stack's {} B",
        OVERFLOW_FRAME_BYTES,
        stack
    );
    let depth = recurse(core::hint::black_box(u32::MAX));
    hprintln!("overflow: the recursion returned ({}): no fault", depth);
    false
}

/// One level of [`overflow`]'s recursion: 64 B of the stack written, and a count of the levels.
#[inline(never)]
fn recurse(limit: u32) -> u32 {
    OVERFLOW_FRAMES.fetch_add(1, Ordering::Relaxed);
    let frame = [limit; OVERFLOW_FRAME_BYTES / 4];
    core::hint::black_box(&frame);
    if limit == 0 {
        return 0;
    }
    // Not a tail call: the frame stays live across it.
    recurse(limit - 1).wrapping_add(core::hint::black_box(&frame).len() as u32)
}

/// The `overflow` image's report of the HardFault on its overflowed stack: how deep it went and
/// whether the statics survived, then the shared report (and exit with failure).
pub fn overflow_report(sp: u32) -> ! {
    let frames = OVERFLOW_FRAMES.load(Ordering::Relaxed);
    if OVERFLOW_CANARY
        .iter()
        .all(|word| word.load(Ordering::Relaxed) == CANARY)
    {
        crate::hostln!("overflow: {} frames deep, the statics intact", frames);
    } else {
        crate::hostln!("overflow: {} frames deep, the statics OVERWRITTEN", frames);
    }
    super::on_stack_overflow(sp)
}

/// Panics: the panic handler must report it and exit with 1.
#[allow(clippy::panic)]
pub fn panic() -> bool {
    hprintln!("panic: panicking on purpose");
    panic!("deliberate panic from the `panic` image")
}

/// Instruction counts of the model's building blocks (run under `-icount shift=3`).
pub fn bench() -> bool {
    let Some(peripherals) = cortex_m::Peripherals::take() else {
        return false;
    };
    let counter = Counter::start(peripherals.SYST);
    // The known loop checks the tick rate: 2 n instructions must read as 2 n.
    let n = 100_000u32;
    let loop_instructions = counter::instructions(counter.ticks_of(&mut || counter::known_loop(n)));
    hprintln!(
        "bench calibration instructions_expected={} instructions_measured={}",
        2 * n,
        loop_instructions
    );
    let calibrated = loop_instructions.abs_diff(u64::from(2 * n)) <= 16;
    let mut converged = true;
    let result = crate::bench::run(
        &mut |f| counter::instructions(counter.ticks_of(f)),
        &mut |l| {
            converged &= l.converged || !crate::bench::must_converge(l.case);
            hprintln!(
                "bench case={} steps_per_section={} total_steps={} instructions={} sweeps={} converged={} tip_error_nm={}",
                l.case,
                l.steps_per_section,
                l.total_steps,
                l.cost,
                l.sweeps,
                l.converged,
                micro(f64::from(l.tip_error_m), 1e9)
            );
        },
    );
    if let Err(e) = result {
        hprintln!("bench refused: {}", e);
        return false;
    }
    print_load();
    report_memory();
    calibrated && converged
}

/// Prints the bench's tip force, [`crate::bench::LOAD_FORCE_NANONEWTON`], as the line
/// `bench load force_nanonewton=<x>,<y>,<z>` (whole nanonewtons: each divided by 1e9 in f64 is the
/// recorded force, exactly), which host-sim's accuracy study reads from `expected/bench.run`.
/// After the cases, out of line, and through the formatting their lines already use (`str`, `u64`):
/// printed before them, inlined, or with an `i64` formatter, it moved some counts by one to three
/// instructions (measured), though the measured code is the same.
#[inline(never)]
fn print_load() {
    let [x, y, z] = crate::bench::LOAD_FORCE_NANONEWTON
        .map(|f| (if f < 0 { "-" } else { "" }, f.unsigned_abs()));
    hprintln!(
        "bench load force_nanonewton={}{},{}{},{}{}",
        x.0,
        x.1,
        y.0,
        y.1,
        z.0,
        z.1
    );
}

/// The estimator image's sample type.
pub type ReplaySample = Sample<SampleError<ReplayError>>;

/// Core clock under QEMU (netduinoplus2: `cpuclk` 168 MHz), Hz.
pub const QEMU_CORE_CLOCK_HZ: u32 = 168_000_000;

const _: () = assert!(
    tasks::systick_can_sample(QEMU_CORE_CLOCK_HZ, SAMPLE_RATE_HZ),
    "the robot file's controller.sample_rate_hz: SysTick cannot interrupt at it on the 168 MHz \
     core clock (it must divide the clock and be at least 11 Hz)"
);

/// Samples the estimator image holds the bench at home before the recording plays: the cold first
/// estimate (about 120 ms of QEMU's virtual time) runs while the bench rests, as after power-up.
pub const ESTIMATOR_HOLD_SAMPLES: u32 = 200;

/// The estimator image's sampler task state: the recording replayed at 1 kHz after
/// [`ESTIMATOR_HOLD_SAMPLES`] at home, cross-checked against the recorded steppers.
#[derive(Debug)]
pub struct Sampling {
    sampler: Sampler<RecordedSensor>,
    steppers: RecordedSteppers,
}

impl Sampling {
    /// One sample (the sampler task's body).
    pub fn sample(&mut self) -> ReplaySample {
        let steps = self.steppers.commanded_steps(self.sampler.next_seq());
        self.sampler.sample(steps)
    }
}

/// The estimator image's `init`: the sampler, and SysTick interrupting at its rate. Exits with
/// failure if the sampler refuses its settings.
pub fn estimator_init(syst: cortex_m::peripheral::SYST) -> Sampling {
    let sensors = [0, 1, 2].map(|c| RecordedSensor::new(c, ESTIMATOR_HOLD_SAMPLES));
    let Ok(sampler) = crate::config::sampler(sensors) else {
        crate::hostln!("estimator: sampler settings refused");
        super::exit(false)
    };
    tasks::start_sampling(syst, QEMU_CORE_CLOCK_HZ, SAMPLE_RATE_HZ);
    Sampling {
        sampler,
        steppers: RecordedSteppers::new(ESTIMATOR_HOLD_SAMPLES),
    }
}

/// The estimator image's `idle`: the production loop on the latest sample every 10 ms, each
/// tick's report over defmt (RTT: decoded by `probe-rs run` on a board, unread under QEMU); the
/// timing of the cold first estimate, the memory report and the verdict over semihosting. Passes
/// when the sampler ran at 1 kHz of virtual time throughout the cold estimate, and every tick but
/// the two injected faults (named as injected) gave a fresh estimate.
pub fn estimator_idle(latest: &mut dyn FnMut() -> Option<ReplaySample>) -> bool {
    // The model stays where `config::model` wrote it (borrowed, not moved out of the `Result`), and
    // the loop runs in its own frame: the plan's construction and the solves never share the stack.
    let model = crate::config::model();
    match &model {
        Ok(model) => run_estimator(model, latest),
        Err(e) => {
            defmt::error!("model refused: {}", e);
            crate::hostln!("model refused (the reason is in the defmt log)");
            false
        }
    }
}

#[inline(never)]
fn run_estimator(
    model: &crate::config::BenchModel,
    latest: &mut dyn FnMut() -> Option<ReplaySample>,
) -> bool {
    use crate::config::loop_config;
    use crate::control::EstimatorLoop;

    let Ok(mut estimator) = EstimatorLoop::new(model, loop_config()) else {
        crate::hostln!("loop settings refused");
        return false;
    };
    let stopwatch = Stopwatch::start();
    // The recording's last tick is at this sample; its injected faults at these.
    let end = ESTIMATOR_HOLD_SAMPLES + (TICK_COUNT as u32 - 1) * SAMPLES_PER_TICK;
    let at = |tick: usize| ESTIMATOR_HOLD_SAMPLES + tick as u32 * SAMPLES_PER_TICK;
    let (mut ticks, mut fresh, mut injected) = (0u32, 0u32, 0u32);
    // The first tick's virtual time (us) and the samples taken meanwhile.
    let mut cold = None;
    let mut due = 0;
    loop {
        let sample = tasks::wait_for(latest, due);
        let started = stopwatch.micros();
        let report = estimator.tick(&sample);
        let finished_at = latest().map_or(sample.seq, |s| s.seq);
        let took_us = stopwatch.micros().wrapping_sub(started);
        cold.get_or_insert((took_us, finished_at.wrapping_sub(sample.seq)));
        defmt::info!("{}", report);
        ticks += 1;
        match report.status {
            Status::Fresh => fresh += 1,
            Status::Rejected(Rejection::Source {
                cable: 1,
                error: SampleError::Sensor(ReplayError::Injected),
            }) if sample.seq == at(SENSOR_FAULT_TICK) => injected += 1,
            Status::Rejected(Rejection::Source {
                cable: 2,
                error: SampleError::Disagrees { .. },
            }) if sample.seq == at(JUMP_TICK) => injected += 1,
            _ => crate::hostln!("tick {} at sample {}: not fresh", report.tick, sample.seq),
        }
        if sample.seq >= end {
            break;
        }
        due = tasks::next_due(finished_at);
    }
    let (cold_us, cold_samples) = cold.unwrap_or((0, 0));
    // At 1 kHz: one sample per 1000 us of virtual time, give or take the one in progress.
    let expected = cold_us / 1000;
    let sampled = cold_samples + 1 >= expected && cold_samples <= expected + 1 && expected > 20;
    crate::hostln!(
        "estimator: sampling during the cold estimate: {} samples in {} us of virtual time ({})",
        cold_samples,
        cold_us,
        if sampled { "1 kHz" } else { "SLOW" }
    );
    report_memory();
    crate::hostln!(
        "estimator: {} ticks, {} fresh, {} injected faults refused",
        ticks,
        fresh,
        injected
    );
    sampled && injected == 2 && fresh + 2 == ticks
}
