//! board image: the estimator loop on an STM32F405 board with three AS5047P on SPI1, logging with
//! defmt over RTT; see `firmware::target::board`.
#![no_std]
#![no_main]

use defmt_rtt as _;

#[cortex_m_rt::entry]
fn entry() -> ! {
    firmware::target::board::run()
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
