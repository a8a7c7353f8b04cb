//! board image: the estimator on an STM32F405 board with three AS5047P on SPI1, logging with
//! defmt over RTT. The RTIC task structure of the estimator image: the sampler in a SysTick task at
//! 1 kHz (priority 2), the estimator loop in `idle`; see `firmware::target::board`.
#![no_std]
#![no_main]

use defmt_rtt as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use firmware::sampler::Sampler;
    use firmware::target::board::{self, BoardSample, BoardSensor};

    #[shared]
    struct Shared {
        /// The latest sample: written by the sampler, read by the estimator.
        latest: Option<BoardSample>,
    }

    #[local]
    struct Local {
        sampler: Sampler<BoardSensor>,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut core = cx.core;
        let sampler = board::init(cx.device, core.SYST, &mut core.DCB, &mut core.DWT);
        (Shared { latest: None }, Local { sampler })
    }

    #[idle(shared = [latest])]
    fn idle(mut cx: idle::Context) -> ! {
        board::idle(&mut || cx.shared.latest.lock(|latest| *latest))
    }

    #[task(binds = SysTick, priority = 2, shared = [latest], local = [sampler])]
    fn sample(mut cx: sample::Context) {
        let sample = board::sample(cx.local.sampler);
        cx.shared.latest.lock(|latest| *latest = Some(sample));
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    firmware::target::board::on_panic(info)
}

#[cortex_m_rt::exception]
#[allow(unsafe_code)]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    firmware::target::board::on_hard_fault(frame)
}
