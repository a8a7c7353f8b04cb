//! Plain text to the semihosting host through `ufmt` instead of `core::fmt`: the handlers every image
//! shares and the budgeted estimator image print this way, which keeps `core::fmt`'s formatting
//! machinery (about 4 KB of flash) out of the estimator image. The test images keep `hprintln!`.

use cortex_m_semihosting::hio::{self, HostStream};

/// The host's standard output, if a semihosting host is attached.
pub struct HostOut(HostStream);

impl core::fmt::Debug for HostOut {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("HostOut")
    }
}

impl HostOut {
    /// Opens the host's standard output (`None` without a semihosting host: nothing is printed).
    pub fn open() -> Option<Self> {
        hio::hstdout().ok().map(Self)
    }
}

impl ufmt::uWrite for HostOut {
    type Error = ();

    fn write_str(&mut self, s: &str) -> Result<(), ()> {
        self.0.write_all(s.as_bytes())
    }
}

/// A `u32` printed as `0x` and eight hex digits through `ufmt`'s `{}`: a tenth of the flash of
/// `ufmt`'s own `{:#010x}` (508 B), which only the fault handler used.
#[derive(Clone, Copy, Debug)]
pub struct Hex(pub u32);

impl ufmt::uDisplay for Hex {
    fn fmt<W: ufmt::uWrite + ?Sized>(
        &self,
        f: &mut ufmt::Formatter<'_, W>,
    ) -> Result<(), W::Error> {
        let mut text = *b"0x00000000";
        for (index, digit) in text.iter_mut().skip(2).enumerate() {
            let nibble = (self.0 >> (28 - 4 * index)) & 0xF;
            *digit = match nibble {
                0..=9 => b'0' + nibble as u8,
                _ => b'a' + (nibble as u8 - 10),
            };
        }
        // SAFETY: every byte is ASCII ("0x" and hex digits), so valid UTF-8.
        f.write_str(unsafe { core::str::from_utf8_unchecked(&text) })
    }
}

/// `hprintln!` through `ufmt`: `{}` and `{:?}` ([`Hex`] for hexadecimal), no floats.
#[macro_export]
macro_rules! hostln {
    ($($arg:tt)*) => {{
        if let Some(mut out) = $crate::target::text::HostOut::open() {
            // Nothing to do when the host refuses the text.
            let _ = ufmt::uwriteln!(&mut out, $($arg)*);
        }
    }};
}
