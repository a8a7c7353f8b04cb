//! The real board: STM32F405 at 168 MHz (8 MHz crystal), SPI1 on PA5 (SCK), PA6 (MISO), PA7 (MOSI)
//! at 4 MHz in mode 1, shared by three AS5047P with chip selects PA4, PB0 and PB1 (cables 0, 1, 2),
//! a 100 Hz loop timed by the DWT cycle counter, every tick's report over defmt (RTT).
//!
//! Between two frames to one sensor chip select stays high for the bus driver's software path
//! (well over the sensor's 350 ns minimum at 168 MHz).
//!
//! Failure never hangs silently: a panic or HardFault logs over defmt, then stops at a breakpoint
//! when a debugger is attached (probe-rs prints the backtrace) and resets the MCU otherwise.

use core::cell::RefCell;

use cortex_m::peripheral::{DCB, DWT, SCB};
use embedded_hal_bus::spi::{NoDelay, RefCellDevice};
use stm32f4xx_hal::gpio::{AnyPin, Output};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::spi::Spi;

use crate::config::{MAX_UNWRAP_STEP_COUNTS, TICK_PERIOD_S, loop_config, spools};
use crate::control::{EstimatorLoop, read_all};
use crate::encoder::SpoolEncoder;
use crate::encoder::as5047p::{self, As5047p};

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

/// Sets up the board and runs the loop forever.
pub fn run() -> ! {
    let model = crate::config::model();
    match &model {
        Ok(model) => run_loop(model),
        Err(e) => {
            defmt::error!("model refused: {}", e);
            stop()
        }
    }
}

#[inline(never)]
fn run_loop(model: &crate::config::BenchModel) -> ! {
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        defmt::error!("peripherals already taken");
        stop()
    };
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
    let bus = RefCell::new(spi);
    let select: [AnyPin<Output>; 3] = [
        gpioa.pa4.into_push_pull_output().erase(),
        gpiob.pb0.into_push_pull_output().erase(),
        gpiob.pb1.into_push_pull_output().erase(),
    ];
    let [s0, s1, s2] = spools::<f32>();
    let [c0, c1, c2] = select;
    let spool = |cs, calibration| {
        let device = RefCellDevice::new(&bus, cs, NoDelay).ok()?;
        SpoolEncoder::new(As5047p::new(device), calibration, MAX_UNWRAP_STEP_COUNTS).ok()
    };
    let (Some(a), Some(b), Some(c)) = (spool(c0, s0), spool(c1, s1), spool(c2, s2)) else {
        defmt::error!("encoder setup refused");
        stop()
    };
    let mut sources = [a, b, c];
    let Ok(mut estimator) = EstimatorLoop::new(model, loop_config()) else {
        defmt::error!("loop settings refused");
        stop()
    };

    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();
    let period = (SYSCLK_HZ as f32 * TICK_PERIOD_S) as u32;
    let mut next = DWT::cycle_count();
    loop {
        let start = DWT::cycle_count();
        let report = estimator.tick(&read_all(&mut sources));
        let cycles = DWT::cycle_count().wrapping_sub(start);
        defmt::info!("{} cycles={=u32}", report, cycles);
        next = next.wrapping_add(period);
        if (DWT::cycle_count().wrapping_sub(next) as i32) > 0 {
            defmt::warn!("tick {} overran its period", report.tick);
            next = DWT::cycle_count();
        }
        while (DWT::cycle_count().wrapping_sub(next) as i32) < 0 {}
    }
}
