//! The live link's port on the QEMU images: USART1's transmitter (0x4001_1000), written
//! register by register through the PAC, behind `embedded_io::Write`.
//!
//! QEMU's netduinoplus2 models the STM32F405's USARTs (its `stm32f2xx-usart`) and connects the
//! first `-serial` backend to USART1: `qemu.sh` with `QEMU_SERIAL=<file>` captures what this
//! writes. QEMU models no clock tree, so stm32f4xx-hal's serial driver (which waits for the RCC's
//! clocks to lock) cannot run there; this driver touches only the USART. On silicon it would also
//! need USART1's clock enabled (RCC APB2ENR) and PA9 in alternate function 7: the board image uses
//! stm32f4xx-hal's `Tx` instead, which does both.
//!
//! Transmit only, blocking: each byte waits for an empty data register (TXE). QEMU sends a byte at
//! once (TXE stays set); on silicon at 921 600 baud a 128-byte record takes 1.4 ms.

use core::convert::Infallible;

use super::device::USART1;

/// APB2's clock after reset (the 16 MHz HSI, no prescaler), Hz: the QEMU images leave the clock
/// tree as it is.
pub const RESET_PCLK2_HZ: u32 = 16_000_000;

/// USART1's transmitter. Takes the peripheral and hands it back ([`Usart1Tx::release`]).
#[derive(Debug)]
pub struct Usart1Tx {
    usart: USART1,
}

impl Usart1Tx {
    /// Enables USART1's transmitter: 8 data bits, no parity, one stop bit, at `baud` from an APB2
    /// clock of `pclk2_hz` (16x oversampling: BRR = `pclk2_hz / baud`, rounded).
    pub fn new(usart: USART1, pclk2_hz: u32, baud: u32) -> Self {
        // USARTDIV in sixteenths: 12 bits of mantissa, 4 of fraction.
        let divider = ((pclk2_hz + baud / 2) / baud.max(1)).min(0xffff) as u16;
        usart.brr().write(|w| {
            w.div_mantissa()
                .set(divider >> 4)
                .div_fraction()
                .set((divider & 0xf) as u8)
        });
        usart.cr1().write(|w| w.ue().set_bit().te().set_bit());
        Self { usart }
    }

    /// Disables the USART and hands it back.
    pub fn release(self) -> USART1 {
        self.usart.cr1().reset();
        self.usart
    }
}

impl embedded_io::ErrorType for Usart1Tx {
    type Error = Infallible;
}

impl embedded_io::Write for Usart1Tx {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        for byte in buf {
            while self.usart.sr().read().txe().bit_is_clear() {}
            self.usart.dr().write(|w| w.dr().set(u16::from(*byte)));
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        while self.usart.sr().read().tc().bit_is_clear() {}
        Ok(())
    }
}
