//! Runtime glue of the MCU images (built only for the target): exit through semihosting, panic and
//! fault handlers that never hang, memory use from the linker's symbols and the painted stack,
//! instruction counting with SysTick, and the images' bodies.

// Linker symbols, the painted stack and SysTick are reached through raw pointers and registers.
#![allow(unsafe_code)]

#[cfg(feature = "board")]
pub mod board;
pub mod counter;
pub mod images;
pub mod memory;
pub mod text;

use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};

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
    crate::hostln!(
        "hard fault: pc {:#010x} lr {:#010x} xpsr {:#010x}",
        frame.pc(),
        frame.lr(),
        frame.xpsr()
    );
    exit(false)
}

/// Defines an image: `cortex-m-rt`'s entry calling `$body` (`fn() -> bool`, true on success) and
/// exiting with its verdict, a panic handler and a HardFault handler that report and exit with
/// failure, and the SysTick handler of [`counter`].
#[macro_export]
macro_rules! qemu_image {
    ($body:path) => {
        #[cortex_m_rt::entry]
        fn entry() -> ! {
            $crate::target::exit($body())
        }

        #[panic_handler]
        fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
            $crate::target::on_panic(info)
        }

        #[cortex_m_rt::exception]
        #[allow(unsafe_code)]
        unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
            $crate::target::on_hard_fault(frame)
        }

        #[cortex_m_rt::exception]
        fn SysTick() {
            $crate::target::counter::on_systick();
        }
    };
}
