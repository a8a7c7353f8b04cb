//! The real board: STM32F405 at 168 MHz (8 MHz crystal), SPI1 on PA5 (SCK), PA6 (MISO), PA7 (MOSI)
//! at 4 MHz in mode 1, shared by three AS5047P with chip selects PA4, PB0 and PB1 (cables 0, 1, 2).
//! The task structure of the estimator image ([`super::tasks`]): the sampler in a SysTick task at
//! 1 kHz, priority 2 (three sensors of three 16-bit frames each: about 40 us of the millisecond at
//! 4 MHz), the estimator loop in RTIC's `idle` every 10 ms on the latest sample, each tick's report
//! and its cycle count over defmt (RTT).
//!
//! The steppers' commanded positions come from [`COMMANDED_STEPS`], which the step generator must
//! advance as it issues steps. The step generator is not in this firmware yet: until it is, the
//! counts stay at zero, the cross-check takes the motors to hold still at home, and any cable motion
//! is a named fault (README.md, "Faults").
//!
//! Between two frames to one sensor chip select stays high for the bus driver's software path
//! (well over the sensor's 350 ns minimum at 168 MHz).
//!
//! Failure never hangs silently: a panic or HardFault logs over defmt, then stops at a breakpoint
//! when a debugger is attached (probe-rs prints the backtrace) and resets the MCU otherwise.

use core::cell::RefCell;
use core::sync::atomic::{AtomicI32, Ordering};

use cortex_m::peripheral::{DCB, DWT, SCB, SYST};
use critical_section::Mutex;
use embedded_hal_bus::spi::{CriticalSectionDevice, NoDelay};
use stm32f4xx_hal::gpio::{AnyPin, Output};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::spi::Spi;

use super::tasks;
use crate::config::{SAMPLE_RATE_HZ, loop_config};
use crate::control::EstimatorLoop;
use crate::encoder::AngleSensor;
use crate::encoder::as5047p::{self, As5047p};
use crate::sampler::{Sample, SampleError, Sampler};

/// The sensors' shared bus.
pub type Bus = Spi<pac::SPI1>;

/// One cable's sensor.
pub type BoardSensor = As5047p<CriticalSectionDevice<'static, Bus, AnyPin<Output>, NoDelay>>;

/// The board's sample.
pub type BoardSample = Sample<SampleError<<BoardSensor as AngleSensor>::Error>>;

/// The steppers' commanded positions, microsteps since power-up (cables 0, 1, 2): written by the
/// step generator as it issues steps, read by the sampler every millisecond.
pub static COMMANDED_STEPS: [AtomicI32; 3] = [const { AtomicI32::new(0) }; 3];

/// Core clock, Hz.
const SYSCLK_HZ: u32 = 168_000_000;

/// Ends the run after a failure: breakpoint under a debugger, reset otherwise.
fn stop() -> ! {
    if DCB::is_debugger_attached() {
        cortex_m::asm::bkpt();
    }
    SCB::sys_reset()
}

/// The panic handler's body. The message is logged when it is a plain string: a formatted one would
/// need `core::fmt`, 4 KB of flash.
pub fn on_panic(info: &core::panic::PanicInfo<'_>) -> ! {
    let (file, line) = info.location().map_or(("?", 0), |l| (l.file(), l.line()));
    let message = info.message().as_str().unwrap_or("(formatted message)");
    defmt::error!("panicked at {}:{}: {}", file, line, message);
    stop()
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

/// The board's `init`: clocks, SPI1 and the three sensors, the sampler, the cycle counter, and
/// SysTick interrupting at the sampler's rate. Stops (see [`stop`]) if the hardware or the settings
/// are refused.
pub fn init(
    dp: pac::Peripherals,
    syst: SYST,
    dcb: &mut DCB,
    dwt: &mut DWT,
) -> Sampler<BoardSensor> {
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
    let sampler = match crate::config::sampler([a, b, c]) {
        Ok(sampler) => sampler,
        Err(e) => {
            defmt::error!("sampler refused: {}", e);
            stop()
        }
    };
    dcb.enable_trace();
    dwt.enable_cycle_counter();
    tasks::start_sampling(syst, SYSCLK_HZ, SAMPLE_RATE_HZ);
    sampler
}

/// The sampler task's body: one sample at the steppers' commanded positions now.
pub fn sample(sampler: &mut Sampler<BoardSensor>) -> BoardSample {
    sampler.sample(
        COMMANDED_STEPS
            .each_ref()
            .map(|s| s.load(Ordering::Relaxed)),
    )
}

/// The board's `idle`: the estimator loop every 10 ms on the latest sample, forever.
pub fn idle(latest: &mut dyn FnMut() -> Option<BoardSample>) -> ! {
    let model = crate::config::model();
    match &model {
        Ok(model) => run_loop(model, latest),
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
) -> ! {
    let Ok(mut estimator) = EstimatorLoop::new(model, loop_config()) else {
        defmt::error!("loop settings refused");
        stop()
    };
    let mut due = 0;
    loop {
        let sample = tasks::wait_for(latest, due);
        let start = DWT::cycle_count();
        let report = estimator.tick(&sample);
        let cycles = DWT::cycle_count().wrapping_sub(start);
        defmt::info!("{} cycles={=u32}", report, cycles);
        let finished = latest().map_or(sample.seq, |s| s.seq);
        if finished.wrapping_sub(sample.seq) >= crate::config::SAMPLES_PER_TICK {
            defmt::warn!("tick {} overran its period", report.tick);
        }
        due = tasks::next_due(finished);
    }
}
