//! board image: the estimator on an STM32F405 board with three AS5047P on SPI1, logging with
//! defmt over RTT and sending each tick's record on the live link (USART1, PA9). The RTIC task
//! structure of the estimator image: the sampler in a SysTick task at 1 kHz (priority 2), the
//! estimator loop in `idle`; see `firmware::target::board`.
#![no_std]
#![no_main]

use defmt_rtt as _;
// The panic handler: the message over defmt, then a HardFault (`udf`).
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use firmware::sampler::Sampler;
    use firmware::target::board::{self, BoardSample, BoardSensor, LinkPort};

    #[shared]
    struct Shared {
        /// The latest sample: written by the sampler, read by the estimator.
        latest: Option<BoardSample>,
    }

    #[local]
    struct Local {
        sampler: Sampler<BoardSensor>,
        /// The live link's USART1 (each tick's record, `firmware::link`).
        link: LinkPort,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut core = cx.core;
        let (sampler, link) = board::init(cx.device, core.SYST, &mut core.DCB, &mut core.DWT);
        (Shared { latest: None }, Local { sampler, link })
    }

    #[idle(shared = [latest], local = [link])]
    fn idle(mut cx: idle::Context) -> ! {
        board::idle(
            &mut || cx.shared.latest.lock(|latest| *latest),
            cx.local.link,
        )
    }

    #[task(binds = SysTick, priority = 2, shared = [latest], local = [sampler])]
    fn sample(mut cx: sample::Context) {
        let sample = board::sample(cx.local.sampler);
        cx.shared.latest.lock(|latest| *latest = Some(sample));
    }
}

firmware::hard_fault_entry!(
    firmware::target::board::on_hard_fault,
    firmware::target::board::on_stack_overflow
);
