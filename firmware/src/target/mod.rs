//! Runtime glue of the MCU images (built only for the target): exit through semihosting, panic and
//! fault handlers that never hang, memory use from the linker's symbols and the painted stack,
//! instruction counting with SysTick, a virtual-time stopwatch (TIM2 under QEMU), and the images'
//! bodies.

// Linker symbols, the painted stack and SysTick are reached through raw pointers and registers.
#![allow(unsafe_code)]

#[cfg(feature = "board")]
pub mod board;
pub mod counter;
pub mod images;
pub mod memory;
pub mod stopwatch;
pub mod tasks;
pub mod text;

use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};

/// The STM32F405's peripheral access crate. Its `rt` feature gives every image the device's own
/// interrupt vector table (82 entries, where cortex-m-rt's default has 240: 632 B of flash less);
/// RTIC takes its interrupt numbers and priority bits from it.
pub use stm32f4::stm32f405 as device;

// Links the device's vector table into every image (cortex-m-rt's `device` feature expects it).
use stm32f4 as _;

/// Ends the run: exit code 0 when `success`, 1 otherwise (QEMU's exit status, or the debugger's).
pub fn exit(success: bool) -> ! {
    debug::exit(if success { EXIT_SUCCESS } else { EXIT_FAILURE });
    // Only reached without a semihosting host; nothing else to do.
    loop {
        cortex_m::asm::wfi();
    }
}

/// The panic handler's body: say where, then exit with failure. The message is printed when it is a
/// plain string (a formatted one would need `core::fmt`, see [`text`]).
pub fn on_panic(info: &core::panic::PanicInfo<'_>) -> ! {
    let (file, line) = info.location().map_or(("?", 0), |l| (l.file(), l.line()));
    let message = info.message().as_str().unwrap_or("(formatted message)");
    crate::hostln!("panicked at {}:{}: {}", file, line, message);
    exit(false)
}

/// The HardFault handler's body: say where, then exit with failure.
pub fn on_hard_fault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    use text::Hex;
    crate::hostln!(
        "hard fault: pc {} lr {} xpsr {}",
        Hex(frame.pc()),
        Hex(frame.lr()),
        Hex(frame.xpsr())
    );
    exit(false)
}

/// Defines an image: `cortex-m-rt`'s entry calling `$body` (`fn() -> bool`, true on success) and
/// exiting with its verdict, the handlers of [`qemu_handlers`], and the SysTick handler of
/// [`counter`].
#[macro_export]
macro_rules! qemu_image {
    ($body:path) => {
        #[cortex_m_rt::entry]
        fn entry() -> ! {
            $crate::target::exit($body())
        }

        $crate::qemu_handlers!();

        #[cortex_m_rt::exception]
        fn SysTick() {
            $crate::target::counter::on_systick();
        }
    };
}

/// A panic handler and a HardFault handler that report over semihosting and exit with failure (for
/// an image whose entry is its own, such as an RTIC application).
#[macro_export]
macro_rules! qemu_handlers {
    () => {
        #[panic_handler]
        fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
            $crate::target::on_panic(info)
        }

        #[cortex_m_rt::exception]
        #[allow(unsafe_code)]
        unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
            $crate::target::on_hard_fault(frame)
        }
    };
}
