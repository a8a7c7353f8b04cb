//! Deterministic instruction counts on QEMU from SysTick.
//!
//! Under `qemu-system-arm -icount shift=3` virtual time advances 8 ns per instruction and SysTick,
//! clocked by the 168 MHz core clock, ticks 1.344 times per instruction: instructions = ticks /
//! 1.344, the same on every run. The 24-bit counter wraps every 2^24 ticks (12.5 M instructions);
//! its exception counts the wraps, so long regions are measured too. On silicon the same code
//! counts core cycles instead (the DWT cycle counter is not modelled by QEMU).

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;

/// SysTick ticks per 1000 instructions under `-icount shift=3` at 168 MHz.
pub const TICKS_PER_KILO_INSTRUCTION: u64 = 1344;

const RELOAD: u32 = 0x00FF_FFFF;

static WRAPS: AtomicU32 = AtomicU32::new(0);

/// The SysTick exception's body: one more wrap.
pub fn on_systick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// A free-running SysTick counter.
pub struct Counter {
    _syst: SYST,
}

impl core::fmt::Debug for Counter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Counter(SysTick)")
    }
}

impl Counter {
    /// Starts SysTick on the core clock, wrapping every 2^24 ticks with an exception.
    pub fn start(mut syst: SYST) -> Self {
        syst.disable_counter();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
        Self { _syst: syst }
    }

    /// Ticks since start.
    pub fn ticks(&self) -> u64 {
        loop {
            let before = WRAPS.load(Ordering::SeqCst);
            let current = SYST::get_current();
            let after = WRAPS.load(Ordering::SeqCst);
            if before == after {
                return u64::from(before) * (u64::from(RELOAD) + 1) + u64::from(RELOAD - current);
            }
        }
    }

    /// SysTick ticks taken by `f`, less the cost of measuring nothing.
    pub fn ticks_of(&self, f: &mut dyn FnMut()) -> u64 {
        let empty = {
            let start = self.ticks();
            let end = self.ticks();
            end - start
        };
        let start = self.ticks();
        f();
        let end = self.ticks();
        (end - start).saturating_sub(empty)
    }
}

/// Instructions for a tick count under `-icount shift=3`.
pub fn instructions(ticks: u64) -> u64 {
    (ticks * 1000 + TICKS_PER_KILO_INSTRUCTION / 2) / TICKS_PER_KILO_INSTRUCTION
}

/// Runs a loop of exactly `2 n` instructions (`subs; bne`), to calibrate the tick rate.
pub fn known_loop(n: u32) {
    if n == 0 {
        return;
    }
    // SAFETY: a register-only countdown loop; touches no memory.
    unsafe {
        core::arch::asm!(
            "1:",
            "subs {0}, #1",
            "bne 1b",
            inout(reg) n => _,
            options(nomem, nostack),
        );
    }
}
