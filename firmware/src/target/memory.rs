//! Memory use of the running image: flash and static RAM from cortex-m-rt's linker symbols, stack
//! from the high-water mark left in the painted stack (`cortex-m-rt` feature `paint-stack` fills the
//! stack region, `[_stack_end, _stack_start)`, with [`cortex_m_rt::STACK_PAINT_VALUE`] before
//! `main`).
//!
//! The images are linked by flip-link (`.cargo/config.toml`): the statics sit at the top of RAM and
//! the stack below them, growing down towards the bottom of RAM (`_stack_end` is RAM's origin,
//! `_stack_start` the statics' start). The measurement holds for either layout: the statics are
//! `[__sdata, __euninit)` and the stack `[_stack_end, _stack_start)` in both.

use core::ptr::addr_of;

unsafe extern "C" {
    static __vector_table: u32;
    static __sdata: u32;
    static __edata: u32;
    static __sidata: u32;
    static __euninit: u32;
    static _stack_end: u32;
    static _stack_start: u32;
}

/// What the image occupies, bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryUse {
    /// Flash programmed: vector table, code, read-only data and `.data`'s initial values.
    pub flash_bytes: u32,
    /// RAM taken by statics (`.data`, `.bss`, `.uninit`).
    pub static_ram_bytes: u32,
    /// Deepest stack use since reset.
    pub stack_bytes: u32,
}

impl MemoryUse {
    /// Static RAM plus the stack's high-water mark, bytes.
    pub fn ram_bytes(&self) -> u32 {
        self.static_ram_bytes + self.stack_bytes
    }
}

/// Measures the image's memory use now (the stack figure is the deepest point reached so far).
pub fn measure() -> MemoryUse {
    let vector_table = addr_of!(__vector_table) as u32;
    let data_start = addr_of!(__sdata) as u32;
    let data_end = addr_of!(__edata) as u32;
    let data_load = addr_of!(__sidata) as u32;
    let statics_end = addr_of!(__euninit) as u32;
    let stack_end = addr_of!(_stack_end) as u32;
    let stack_start = addr_of!(_stack_start) as u32;
    MemoryUse {
        flash_bytes: data_load + (data_end - data_start) - vector_table,
        static_ram_bytes: statics_end - data_start,
        stack_bytes: stack_start - lowest_used_stack_word(stack_end, stack_start),
    }
}

/// The stack's bottom (`_stack_end`): the lowest address the stack may use (RAM's origin under
/// flip-link).
pub fn stack_bottom() -> u32 {
    addr_of!(_stack_end) as u32
}

/// The stack's top (`_stack_start`): the initial stack pointer (the statics' start under flip-link).
pub fn stack_top() -> u32 {
    addr_of!(_stack_start) as u32
}

/// The lowest stack address whose paint has been scrubbed off.
fn lowest_used_stack_word(stack_end: u32, stack_start: u32) -> u32 {
    let mut address = stack_end;
    while address < stack_start {
        // SAFETY: `[stack_end, stack_start)` is the stack region, word-aligned RAM that cortex-m-rt
        // painted at reset; reading it races with nothing (single core, no DMA into the stack).
        let word = unsafe { core::ptr::read_volatile(address as *const u32) };
        if word != cortex_m_rt::STACK_PAINT_VALUE {
            break;
        }
        address += 4;
    }
    address
}
