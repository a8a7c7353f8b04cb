//! The two tasks of the RTIC images (`estimator`, `board`), what they share, and how the slow one
//! is paced.
//!
//! * The sampler: a hardware task bound to SysTick at priority 2, every millisecond. It reads the
//!   three sensors, tracks and cross-checks them ([`crate::sampler::Sampler::sample`]) and writes
//!   the sample into the latest-sample slot: an RTIC shared resource (an `Option<Sample>`, 28
//!   bytes), copied in and out under RTIC's priority-ceiling lock, which masks the sampler for the
//!   copy only (tens of cycles).
//! * The estimator: RTIC's `idle` (priority 0, preempted by the sampler at any point). It waits for
//!   the sample of the next 10 ms instant ([`wait_for`]: `wfi` between samples), runs the loop on
//!   it, and takes the next instant after the one it finished in ([`next_due`]): a tick that
//!   overruns (a cold estimate, about 90 ms) skips instants instead of queueing them, and the
//!   sampler never waits.

use crate::config::SAMPLES_PER_TICK;
use crate::sampler::Sample;

/// SysTick reload for one sample period at the core clock.
pub const fn systick_reload(core_clock_hz: u32, sample_rate_hz: u32) -> u32 {
    core_clock_hz / sample_rate_hz - 1
}

/// Whether SysTick can interrupt at exactly `sample_rate_hz` on `core_clock_hz`: the rate divides
/// the clock, and one period fits the 24-bit reload (at 168 MHz, 11 Hz and up). The images assert
/// it for the robot file's `controller.sample_rate_hz` at their clock.
pub const fn systick_can_sample(core_clock_hz: u32, sample_rate_hz: u32) -> bool {
    sample_rate_hz > 0
        && core_clock_hz.is_multiple_of(sample_rate_hz)
        && systick_reload(core_clock_hz, sample_rate_hz) <= 0x00FF_FFFF
}

/// Starts SysTick interrupting at `sample_rate_hz` (the sampler's period) on the core clock.
pub fn start_sampling(
    mut syst: cortex_m::peripheral::SYST,
    core_clock_hz: u32,
    sample_rate_hz: u32,
) {
    use cortex_m::peripheral::syst::SystClkSource;
    syst.disable_counter();
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(systick_reload(core_clock_hz, sample_rate_hz));
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Waits (`wfi` between interrupts) until the latest sample's number is at least `due`, and
/// returns that sample. Interrupts are masked between the check and the `wfi`, so a sample written
/// in between still wakes it (a pending interrupt ends `wfi` even when masked).
pub fn wait_for<E: Copy>(latest: &mut dyn FnMut() -> Option<Sample<E>>, due: u32) -> Sample<E> {
    loop {
        cortex_m::interrupt::disable();
        if let Some(sample) = latest().filter(|s| s.seq.wrapping_sub(due) < u32::MAX / 2) {
            // SAFETY: re-enabling what this function masked; no critical section is open here.
            unsafe { cortex_m::interrupt::enable() };
            return sample;
        }
        cortex_m::asm::wfi();
        // SAFETY: as above; the pending sampler interrupt runs now.
        unsafe { cortex_m::interrupt::enable() };
    }
}

/// The next tick instant (a multiple of [`SAMPLES_PER_TICK`]) after sample `seq`.
pub fn next_due(seq: u32) -> u32 {
    (seq / SAMPLES_PER_TICK)
        .wrapping_add(1)
        .wrapping_mul(SAMPLES_PER_TICK)
}
