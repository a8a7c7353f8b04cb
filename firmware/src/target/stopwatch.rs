//! Virtual time under QEMU, apart from SysTick (which paces the sampler): TIM2 counting
//! microseconds.
//!
//! QEMU 7.2's netduinoplus2 emulates TIM2..TIM5 (`stm32f2xx-timer`) with a fixed 1 GHz input clock
//! (`info qtree`: `clock-frequency = 1000000000`), its counter computed from the virtual clock, which
//! `-icount` makes count instructions. A prescaler of 1000 makes it count microseconds of virtual
//! time. (On the STM32F405 TIM2 runs from the APB1 timer clock, 84 MHz on the board: the prescaler
//! would be 84. Only the QEMU images use this.)

use core::ptr::{read_volatile, write_volatile};

const RCC_APB1ENR: *mut u32 = 0x4002_3840 as *mut u32;
const TIM2: usize = 0x4000_0000;
const CR1: usize = 0x00;
const EGR: usize = 0x14;
const CNT: usize = 0x24;
const PSC: usize = 0x28;
const ARR: usize = 0x2C;

/// TIM2's input clock under QEMU, Hz.
pub const QEMU_TIMER_CLOCK_HZ: u32 = 1_000_000_000;

/// TIM2, free-running at 1 MHz of QEMU's virtual time.
#[derive(Debug)]
pub struct Stopwatch(());

impl Stopwatch {
    /// Starts TIM2 counting microseconds (32 bits: 71 minutes before it wraps).
    pub fn start() -> Self {
        // SAFETY: TIM2 and RCC's APB1ENR are this MCU's registers at these addresses; nothing else
        // in the QEMU images uses TIM2, and setting APB1ENR's TIM2EN bit (read-modify-write, at init,
        // before any interrupt that could touch RCC) changes nothing else.
        unsafe {
            write_volatile(RCC_APB1ENR, read_volatile(RCC_APB1ENR) | 1);
            let register = |offset: usize| (TIM2 + offset) as *mut u32;
            write_volatile(register(PSC), QEMU_TIMER_CLOCK_HZ / 1_000_000 - 1);
            write_volatile(register(ARR), u32::MAX);
            // An update event loads the prescaler (silicon does at the next update only).
            write_volatile(register(EGR), 1);
            write_volatile(register(CR1), 1);
        }
        Self(())
    }

    /// Microseconds since [`Stopwatch::start`] (wrapping).
    pub fn micros(&self) -> u32 {
        // SAFETY: reading TIM2's counter has no side effect.
        unsafe { read_volatile((TIM2 + CNT) as *const u32) }
    }
}
