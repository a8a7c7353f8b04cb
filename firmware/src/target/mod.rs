//! Runtime glue of the MCU images (built only for the target): exit through semihosting, panic and
//! fault handlers that never hang, memory use from the linker's symbols and the painted stack,
//! instruction counting with SysTick, a virtual-time stopwatch (TIM2 under QEMU), the live link's
//! UART under QEMU, and the images' bodies.

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
#[cfg(feature = "link")]
pub mod uart;

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

/// The report of a HardFault taken on an overflowed stack ([`crate::hard_fault_entry`]): where the
/// stack pointer was, then exit with failure. `sp` is the exception frame's address, below the
/// stack's bottom (`_stack_end`, the bottom of RAM under flip-link).
pub fn on_stack_overflow(sp: u32) -> ! {
    use text::Hex;
    crate::hostln!(
        "hard fault: stack overflow: sp {} below the stack's bottom {}",
        Hex(sp),
        Hex(memory::stack_bottom())
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

/// A HardFault entry that still reports when the stack has overflowed.
///
/// With flip-link's layout an overflowing stack leaves RAM at its bottom and the access faults; the
/// core then stacks the exception frame below RAM too, and a handler that pushes anything there
/// faults again inside HardFault: lockup (QEMU stops with "Lockup: can't escalate 3 to HardFault").
/// This entry looks at the frame's address before it touches the stack: below the stack's bottom
/// (`_stack_end`) it moves the stack pointer back to the stack's top (`_stack_start`; what was on
/// the stack is lost, and the handler never returns) and calls `$on_overflow(sp: u32) -> !` with the
/// frame's address; otherwise it calls `$on_fault(frame: &cortex_m_rt::ExceptionFrame) -> !` as
/// `#[exception] HardFault` would. It replaces `#[exception] HardFault` and its trampoline: it is
/// the vector itself, and takes the frame's address from MSP or PSP as the trampoline does.
#[macro_export]
macro_rules! hard_fault_entry {
    ($on_fault:path, $on_overflow:path) => {
        extern "C" fn hard_fault_frame(frame: &cortex_m_rt::ExceptionFrame) -> ! {
            $on_fault(frame)
        }

        extern "C" fn hard_fault_overflow(sp: u32) -> ! {
            $on_overflow(sp)
        }

        /// cortex-m-rt's `HardFault`: no stack used before the frame's address is checked.
        #[allow(unsafe_code, non_snake_case)]
        #[unsafe(naked)]
        #[unsafe(export_name = "HardFault")]
        #[unsafe(link_section = ".HardFault.user")]
        extern "C" fn HardFault() -> ! {
            core::arch::naked_asm!(
                // The frame's address: bit 2 of EXC_RETURN says which stack it is on.
                "tst lr, #4",
                "ite eq",
                "mrseq r0, msp",
                "mrsne r0, psp",
                "movw r1, :lower16:_stack_end",
                "movt r1, :upper16:_stack_end",
                "cmp r0, r1",
                "bhs 1f",
                "movw r1, :lower16:_stack_start",
                "movt r1, :upper16:_stack_start",
                "mov sp, r1",
                "b {overflow}",
                "1:",
                "b {fault}",
                overflow = sym hard_fault_overflow,
                fault = sym hard_fault_frame,
            )
        }
    };
}
