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

/// `hprintln!` through `ufmt`: `{}`, `{:?}` and `{:#010x}`-style hex, no floats.
#[macro_export]
macro_rules! hostln {
    ($($arg:tt)*) => {{
        if let Some(mut out) = $crate::target::text::HostOut::open() {
            // Nothing to do when the host refuses the text.
            let _ = ufmt::uwriteln!(&mut out, $($arg)*);
        }
    }};
}
