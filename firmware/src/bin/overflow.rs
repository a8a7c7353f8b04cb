//! overflow image: see `firmware::target::images::overflow`. Its HardFault entry reports an
//! overflowed stack (`firmware::hard_fault_entry!`).
#![no_std]
#![no_main]

#[cortex_m_rt::entry]
fn entry() -> ! {
    firmware::target::exit(firmware::target::images::overflow())
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    firmware::target::on_panic(info)
}

firmware::hard_fault_entry!(
    firmware::target::on_hard_fault,
    firmware::target::images::overflow_report
);
