//! The real board: STM32F405 at 168 MHz (8 MHz crystal), SPI1 on PA5 (SCK), PA6 (MISO), PA7 (MOSI)
//! at 4 MHz in mode 1, shared by three AS5047P with chip selects PA4, PB0 and PB1 (cables 0, 1, 2).
//! The task structure of the estimator image ([`super::tasks`]): the sampler in a SysTick task at
//! 1 kHz, priority 2 (three sensors of three 16-bit frames each: about 40 us of the millisecond at
//! 4 MHz), the estimator loop in RTIC's `idle` every 10 ms on the latest sample, each tick's report
//! and its cycle count over defmt (RTT), and each tick's record on the live link: USART1's TX on
//! PA9 at [`crate::config::LINK_BAUD`] 8N1 (`crate::link`; about 1.4 ms of the 10 ms tick,
//! blocking, preempted by the sampler).
//!
//! The steppers' commanded positions come from [`COMMANDED_STEPS`], which the step generator must
//! advance as it issues steps. The step generator is not in this firmware yet: until it is, the
//! counts stay at zero, the cross-check takes the motors to hold still at home, and any cable motion
//! is a named fault (README.md, "Faults").
//!
//! Between two frames to one sensor chip select stays high for the bus driver's software path
//! (well over the sensor's 350 ns minimum at 168 MHz).
//!
//! Failure never hangs silently: a panic logs its message over defmt (panic-probe) and ends in a
//! HardFault (`udf`); a HardFault logs over defmt (an overflowed stack as such, see
//! [`crate::hard_fault_entry`]), then stops at a breakpoint when a debugger is attached (probe-rs
//! prints the backtrace) and resets the MCU otherwise. After that reset (or any but a power-up:
//! [`crate::reset`]) the sampler does not take the cables to be at home: every cable is faulted
//! (`HomeUnknown`) until re-homed, which on this board means powering up at home.

use core::cell::RefCell;
use core::sync::atomic::{AtomicI32, Ordering};

use cortex_m::peripheral::{DCB, DWT, SCB, SYST};
use critical_section::Mutex;
use embedded_hal_bus::spi::{CriticalSectionDevice, NoDelay};
use stm32f4xx_hal::gpio::{AnyPin, Output};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::serial::{Serial, Tx};
use stm32f4xx_hal::spi::Spi;

use super::tasks;
use crate::config::{SAMPLE_RATE_HZ, loop_config};
use crate::control::{EstimatorLoop, Status};
use crate::encoder::AngleSensor;
use crate::encoder::as5047p::{self, As5047p};
use crate::link::{self, RecordWriter};
use crate::reset::ResetCause;
use crate::sampler::{Sample, SampleError, Sampler};

/// The sensors' shared bus.
pub type Bus = Spi<pac::SPI1>;

/// One cable's sensor.
pub type BoardSensor = As5047p<CriticalSectionDevice<'static, Bus, AnyPin<Output>, NoDelay>>;

/// The board's sample.
pub type BoardSample = Sample<SampleError<<BoardSensor as AngleSensor>::Error>>;

/// The live link's port: USART1's transmitter (PA9).
pub type LinkPort = Tx<pac::USART1>;

/// The steppers' commanded positions, microsteps since power-up (cables 0, 1, 2): written by the
/// step generator as it issues steps, read by the sampler every millisecond.
pub static COMMANDED_STEPS: [AtomicI32; 3] = [const { AtomicI32::new(0) }; 3];

/// Core clock, Hz.
const SYSCLK_HZ: u32 = 168_000_000;

const _: () = assert!(
    tasks::systick_can_sample(SYSCLK_HZ, SAMPLE_RATE_HZ),
    "the robot file's controller.sample_rate_hz: SysTick cannot interrupt at it on the 168 MHz \
     core clock (it must divide the clock and be at least 11 Hz)"
);

/// Ends the run after a failure: breakpoint under a debugger, reset otherwise.
fn stop() -> ! {
    if DCB::is_debugger_attached() {
        cortex_m::asm::bkpt();
    }
    SCB::sys_reset()
}

/// The HardFault handler's body.
pub fn on_hard_fault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    defmt::error!(
        "hard fault: pc {=u32:#x} lr {=u32:#x} xpsr {=u32:#x}",
        frame.pc(),
        frame.lr(),
        frame.xpsr()
    );
    stop()
}

/// The HardFault handler's body when the stack has overflowed: `sp` (the exception frame's address)
/// is below the stack's bottom, the bottom of RAM under flip-link.
pub fn on_stack_overflow(sp: u32) -> ! {
    defmt::error!(
        "hard fault: stack overflow: sp {=u32:#x} below the stack's bottom {=u32:#x}",
        sp,
        super::memory::stack_bottom()
    );
    stop()
}

/// The board's `init`: clocks, SPI1 and the three sensors, the sampler, the live link's USART1,
/// the cycle counter, and SysTick interrupting at the sampler's rate. Stops (see [`stop`]) if the
/// hardware or the settings are refused.
pub fn init(
    dp: pac::Peripherals,
    syst: SYST,
    dcb: &mut DCB,
    dwt: &mut DWT,
) -> (Sampler<BoardSensor>, LinkPort) {
    // Why the MCU started, read before the clocks are set up; the flags are cleared so that the
    // next start sees its own cause alone.
    let reset = ResetCause::from_csr(dp.RCC.csr().read().bits());
    dp.RCC.csr().modify(|_, w| w.rmvf().clear());
    let mut rcc = dp.RCC.freeze(Config::hse(8.MHz()).sysclk(SYSCLK_HZ.Hz()));
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let spi = Spi::new(
        dp.SPI1,
        (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
        as5047p::MODE,
        4.MHz(),
        &mut rcc,
    );
    let Some(bus) = cortex_m::singleton!(: Mutex<RefCell<Bus>> = Mutex::new(RefCell::new(spi)))
    else {
        defmt::error!("SPI bus already taken");
        stop()
    };
    let bus: &'static Mutex<RefCell<Bus>> = bus;
    let select: [AnyPin<Output>; 3] = [
        gpioa.pa4.into_push_pull_output().erase(),
        gpiob.pb0.into_push_pull_output().erase(),
        gpiob.pb1.into_push_pull_output().erase(),
    ];
    let link_config = crate::config::LINK_BAUD.bps();
    let Ok(link) = Serial::tx(dp.USART1, gpioa.pa9, link_config, &mut rcc) else {
        defmt::error!(
            "live link: USART1 refused {} baud",
            crate::config::LINK_BAUD
        );
        stop()
    };
    let [c0, c1, c2] = select;
    let sensor = |cs| {
        CriticalSectionDevice::new(bus, cs, NoDelay)
            .ok()
            .map(As5047p::new)
    };
    let (Some(a), Some(b), Some(c)) = (sensor(c0), sensor(c1), sensor(c2)) else {
        defmt::error!("encoder setup refused");
        stop()
    };
    let mut sampler = match crate::config::sampler([a, b, c]) {
        Ok(sampler) => sampler,
        Err(e) => {
            defmt::error!("sampler refused: {}", e);
            stop()
        }
    };
    if !reset.home_is_known() {
        // The motors may have left home since the power came up (the firmware's own reset after
        // a fault, a watchdog, the reset pin): no cable gives a length until re-homed.
        defmt::warn!(
            "reset: {}: home unknown, every cable faulted until re-homed",
            reset
        );
        sampler.distrust_home();
    }
    dcb.enable_trace();
    dwt.enable_cycle_counter();
    tasks::start_sampling(syst, SYSCLK_HZ, SAMPLE_RATE_HZ);
    (sampler, link)
}

/// The sampler task's body: one sample at the steppers' commanded positions now.
pub fn sample(sampler: &mut Sampler<BoardSensor>) -> BoardSample {
    sampler.sample(
        COMMANDED_STEPS
            .each_ref()
            .map(|s| s.load(Ordering::Relaxed)),
    )
}

/// The board's `idle`: the estimator loop every 10 ms on the latest sample, forever, each tick's
/// record on `link`.
pub fn idle(latest: &mut dyn FnMut() -> Option<BoardSample>, link: &mut LinkPort) -> ! {
    let model = crate::config::model();
    match &model {
        Ok(model) => run_loop(model, latest, RecordWriter::new(link)),
        Err(e) => {
            defmt::error!("model refused: {}", e);
            stop()
        }
    }
}

#[inline(never)]
fn run_loop(
    model: &crate::config::BenchModel,
    latest: &mut dyn FnMut() -> Option<BoardSample>,
    mut writer: RecordWriter<&mut LinkPort>,
) -> ! {
    let Ok(mut estimator) = EstimatorLoop::new(model, loop_config()) else {
        defmt::error!("loop settings refused");
        stop()
    };
    let mut due = 0;
    // The newest estimate's tip frame, read after the tick that published it.
    let mut tip_orientation = [1.0, 0.0, 0.0, 0.0];
    loop {
        let sample = tasks::wait_for(latest, due);
        let start = DWT::cycle_count();
        let report = estimator.tick(&sample);
        let cycles = DWT::cycle_count().wrapping_sub(start);
        defmt::info!("{} cycles={=u32}", report, cycles);
        if let (Status::Fresh, Some(rotation)) = (report.status, estimator.tip_rotation()) {
            tip_orientation = link::orientation(&rotation);
        }
        let estimate = report.estimate.as_ref();
        let record = link::record(report.tick, &report.status, estimate, tip_orientation);
        if let Err(e) = writer.send(&record) {
            let e = defmt::Debug2Format(&e);
            defmt::warn!("live link: tick {} not sent: {}", report.tick, e);
        }
        let finished = latest().map_or(sample.seq, |s| s.seq);
        if finished.wrapping_sub(sample.seq) >= crate::config::SAMPLES_PER_TICK {
            defmt::warn!("tick {} overran its period", report.tick);
        }
        due = tasks::next_due(finished);
    }
}
