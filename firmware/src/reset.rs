//! Why the MCU last started, from the reset flags in RCC_CSR (STM32F405, reference manual RM0090), and
//! whether the cables may be taken to be at home.
//!
//! The sampler takes every cable to start at home, where the steppers' counts start
//! ([`crate::sampler`]): true after a power-up at home, the operator's procedure. After any other
//! reset the motors may have left home: the firmware's own reset after a fault (panic, HardFault:
//! `target::board`'s `stop`), a watchdog, the reset pin (a debug probe's reset after flashing
//! too), a brownout. A cable then left a whole number of sensor turns from home reads like home,
//! so the board's sampler does not trust home after such a reset
//! ([`crate::sampler::Sampler::distrust_home`]).
//!
//! The brownout flag comes alone only when the brownout detector is on (the option bytes' BOR
//! level; the chip ships with it off, and this firmware does not set it): with it off, a supply
//! dip deep enough to reset the MCU is a power-down and reads as a power-on, like any power loss.
//!
//! The flags accumulate until cleared; the board reads them once at start-up and clears them, so the
//! next start sees only its own cause.

/// RCC_CSR's reset flags, bit positions (RM0090).
mod bit {
    pub const BORRSTF: u32 = 1 << 25;
    pub const PINRSTF: u32 = 1 << 26;
    pub const PORRSTF: u32 = 1 << 27;
    pub const SFTRSTF: u32 = 1 << 28;
    pub const IWDGRSTF: u32 = 1 << 29;
    pub const WWDGRSTF: u32 = 1 << 30;
    pub const LPWRRSTF: u32 = 1 << 31;
}

/// The cause of the last reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ResetCause {
    /// Power-on (or power-down) reset: the supply came up.
    PowerOn,
    /// A reset requested by software (the firmware's own, after a fault).
    Software,
    /// The independent or the window watchdog.
    Watchdog,
    /// Entering Standby or Stop when the option bytes make that a reset.
    LowPower,
    /// The supply dipped below the brownout threshold without a full power-down.
    Brownout,
    /// The NRST pin alone (the reset button, or a debug probe).
    Pin,
    /// No flag set (the flags were cleared and nothing set them since).
    Unknown,
}

impl ResetCause {
    /// The cause that RCC_CSR's value `csr` records. A power-on sets the pin and brownout flags
    /// too, and any internal reset sets the pin flag, so the flags are read from the most specific:
    /// one of a reset the firmware or a watchdog caused wins over power-on (they can only be set
    /// together when the flags were not cleared since the power came up).
    pub fn from_csr(csr: u32) -> Self {
        if csr & (bit::IWDGRSTF | bit::WWDGRSTF) != 0 {
            Self::Watchdog
        } else if csr & bit::SFTRSTF != 0 {
            Self::Software
        } else if csr & bit::LPWRRSTF != 0 {
            Self::LowPower
        } else if csr & bit::PORRSTF != 0 {
            Self::PowerOn
        } else if csr & bit::BORRSTF != 0 {
            Self::Brownout
        } else if csr & bit::PINRSTF != 0 {
            Self::Pin
        } else {
            Self::Unknown
        }
    }

    /// Whether the cables may be taken to be at home: after a power-on only (the procedure powers
    /// the robot up at home). After any other reset the motors may have been anywhere.
    pub fn home_is_known(self) -> bool {
        self == Self::PowerOn
    }
}

#[cfg(test)]
mod tests {
    use super::bit::*;
    use super::*;

    #[test]
    fn only_a_power_on_vouches_for_home() {
        // What the flags read after each kind of reset on the STM32F4 (every internal reset pulls
        // NRST low for 20 us, so the pin flag comes along).
        let cases = [
            (PORRSTF | PINRSTF | BORRSTF, ResetCause::PowerOn),
            (SFTRSTF | PINRSTF, ResetCause::Software),
            (IWDGRSTF | PINRSTF, ResetCause::Watchdog),
            (WWDGRSTF | PINRSTF, ResetCause::Watchdog),
            (LPWRRSTF | PINRSTF, ResetCause::LowPower),
            (BORRSTF | PINRSTF, ResetCause::Brownout),
            (PINRSTF, ResetCause::Pin),
            (0, ResetCause::Unknown),
            // Flags not cleared since power-up: the later reset is the one to believe.
            (PORRSTF | PINRSTF | BORRSTF | SFTRSTF, ResetCause::Software),
            (PORRSTF | PINRSTF | BORRSTF | IWDGRSTF, ResetCause::Watchdog),
        ];
        for (csr, cause) in cases {
            // The clock bits below the flags must not matter.
            for low in [0, 0b11, 0x00ff_ffff] {
                assert_eq!(ResetCause::from_csr(csr | low), cause, "{csr:#x}");
            }
            assert_eq!(cause.home_is_known(), cause == ResetCause::PowerOn);
        }
    }
}
