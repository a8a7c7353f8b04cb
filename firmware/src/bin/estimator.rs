//! estimator image: the production task structure on QEMU. An RTIC application: the sampler (the
//! recorded encoders and steppers, cross-checked) in a SysTick task at 1 kHz, priority 2; the
//! estimator loop (warm f32 estimator, defmt output) in `idle`, every 10 ms on the latest sample.
//! See `firmware::target::tasks` and `firmware::target::images::estimator_idle`.
#![no_std]
#![no_main]

use defmt_rtt as _;

firmware::qemu_handlers!();

#[rtic::app(device = stm32f4::stm32f405, peripherals = false)]
mod app {
    use firmware::target::images::{ReplaySample, Sampling, estimator_idle, estimator_init};

    #[shared]
    struct Shared {
        /// The latest sample: written by the sampler, read by the estimator.
        latest: Option<ReplaySample>,
    }

    #[local]
    struct Local {
        sampling: Sampling,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let sampling = estimator_init(cx.core.SYST);
        (Shared { latest: None }, Local { sampling })
    }

    #[idle(shared = [latest])]
    fn idle(mut cx: idle::Context) -> ! {
        let passed = estimator_idle(&mut || cx.shared.latest.lock(|latest| *latest));
        firmware::target::exit(passed)
    }

    #[task(binds = SysTick, priority = 2, shared = [latest], local = [sampling])]
    fn sample(mut cx: sample::Context) {
        let sample = cx.local.sampling.sample();
        cx.shared.latest.lock(|latest| *latest = Some(sample));
    }
}
