//! AS5047P 14-bit absolute magnetic rotary encoder over SPI (embedded-hal 1.0 `SpiDevice`).
//!
//! The bus must run in SPI mode 1 ([`MODE`]), at most 10 MHz, with chip select released between
//! 16-bit frames: every frame here is its own `SpiDevice` transaction of two bytes, MSB first.
//!
//! Frames (datasheet, "SPI Interface"): a command is `PARC | R/W | ADDR[13:0]`, a response
//! `PARD | EF | DATA[13:0]`; bit 15 makes the frame's parity even. A read's data arrives in the
//! frame *after* its command, so [`As5047p::read_angle_counts`] pipelines three frames: read DIAAGC,
//! read ANGLECOM (answers DIAAGC), NOP (answers ANGLECOM). A response with EF set means the
//! previous command failed; the driver then reads (and so clears) ERRFL to say why.

use embedded_hal::spi::{MODE_1, Mode, SpiDevice};

use super::AngleSensor;

/// The SPI mode the sensor needs (CPOL = 0, CPHA = 1).
pub const MODE: Mode = MODE_1;

/// Counts in one turn (14 bits).
pub const COUNTS_PER_TURN: u32 = 1 << 14;

/// Register addresses (volatile registers only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
#[repr(u16)]
pub enum Register {
    /// No operation; reading it clocks out the previous read's data.
    Nop = 0x0000,
    /// Error flags of the SPI interface (cleared by reading).
    Errfl = 0x0001,
    /// Diagnostics and automatic gain control.
    Diaagc = 0x3FFC,
    /// CORDIC magnitude.
    Mag = 0x3FFD,
    /// Angle without dynamic angle error compensation.
    AngleUnc = 0x3FFE,
    /// Angle with dynamic angle error compensation.
    AngleCom = 0x3FFF,
}

/// The SPI interface's error flags (ERRFL): which of the sensor's checks the previous command failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct ErrorFlags {
    /// FRERR: a frame was not 16 bits long.
    pub framing: bool,
    /// INVCOMM: a command addressed an invalid register.
    pub invalid_command: bool,
    /// PARERR: a command's parity was wrong (a bit error on MOSI).
    pub parity: bool,
}

impl ErrorFlags {
    /// The flags from ERRFL's data bits.
    pub fn from_bits(data: u16) -> Self {
        Self {
            framing: data & 0b001 != 0,
            invalid_command: data & 0b010 != 0,
            parity: data & 0b100 != 0,
        }
    }
}

/// The magnetic diagnostics (DIAAGC).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct Diagnostics {
    /// MAGL: the field is too weak (magnet too far).
    pub magnet_too_weak: bool,
    /// MAGH: the field is too strong (magnet too close).
    pub magnet_too_strong: bool,
    /// COF: the CORDIC overflowed; the angle is invalid.
    pub cordic_overflow: bool,
    /// LF: the internal offset compensation has finished (false right after power-up).
    pub offset_loop_ready: bool,
    /// Automatic gain control value, 0 (strong field) to 255 (weak field).
    pub agc: u8,
}

impl Diagnostics {
    /// The diagnostics from DIAAGC's data bits.
    pub fn from_bits(data: u16) -> Self {
        Self {
            magnet_too_weak: data & (1 << 11) != 0,
            magnet_too_strong: data & (1 << 10) != 0,
            cordic_overflow: data & (1 << 9) != 0,
            offset_loop_ready: data & (1 << 8) != 0,
            agc: (data & 0xFF) as u8,
        }
    }
}

/// Why a read failed. Each variant names the culprit; `E` is the bus's error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Error<E> {
    /// The SPI bus (or chip select) failed.
    Comm(E),
    /// A response frame's parity is odd: a bit error on MISO. The frame as received.
    Parity(u16),
    /// The sensor flagged the previous command (EF); ERRFL says which check it failed.
    Command(ErrorFlags),
    /// The field is too weak for a valid angle (MAGL).
    MagnetTooWeak,
    /// The field is too strong for a valid angle (MAGH).
    MagnetTooStrong,
    /// The CORDIC overflowed: the angle is invalid (COF).
    CordicOverflow,
    /// The offset compensation loop has not finished since power-up (LF = 0).
    NotReady,
}

/// Bit 15 of a frame that makes its parity even over all 16 bits.
fn with_even_parity(frame: u16) -> u16 {
    let low = frame & 0x7FFF;
    if !low.count_ones().is_multiple_of(2) {
        low | 0x8000
    } else {
        low
    }
}

/// The command frame reading `register`.
pub fn read_command(register: Register) -> u16 {
    with_even_parity(0x4000 | register as u16)
}

/// A received frame, checked: its parity must be even and its EF bit clear.
enum Response {
    Data(u16),
    ErrorFlag,
}

fn check<E>(frame: u16) -> Result<Response, Error<E>> {
    if !frame.count_ones().is_multiple_of(2) {
        return Err(Error::Parity(frame));
    }
    Ok(if frame & 0x4000 != 0 {
        Response::ErrorFlag
    } else {
        Response::Data(frame & 0x3FFF)
    })
}

/// An AS5047P on an SPI device (its own chip select).
#[derive(Debug)]
pub struct As5047p<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice> As5047p<SPI> {
    /// The sensor on `spi` (mode 1, at most 10 MHz).
    pub fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// One 16-bit frame: sends `command`, returns what the sensor sent meanwhile.
    fn frame(&mut self, command: u16) -> Result<u16, Error<SPI::Error>> {
        let mut buffer = command.to_be_bytes();
        self.spi
            .transfer_in_place(&mut buffer)
            .map_err(Error::Comm)?;
        Ok(u16::from_be_bytes(buffer))
    }

    /// Reads ERRFL (clearing it) after a response carried EF.
    fn error_flags_after_flag(&mut self) -> Result<ErrorFlags, Error<SPI::Error>> {
        self.frame(read_command(Register::Errfl))?;
        match check(self.frame(read_command(Register::Nop))?)? {
            Response::Data(bits) => Ok(ErrorFlags::from_bits(bits)),
            // ERRFL itself flagged: report what is known, a command error of unknown kind.
            Response::ErrorFlag => Ok(ErrorFlags::from_bits(0)),
        }
    }

    fn data(&mut self, frame: u16) -> Result<u16, Error<SPI::Error>> {
        match check(frame)? {
            Response::Data(bits) => Ok(bits),
            Response::ErrorFlag => Err(Error::Command(self.error_flags_after_flag()?)),
        }
    }

    /// Reads one register's 14 data bits (two frames).
    ///
    /// # Errors
    /// [`Error::Comm`] from the bus, [`Error::Parity`] for a corrupted response,
    /// [`Error::Command`] when the sensor flagged the command.
    pub fn read_register(&mut self, register: Register) -> Result<u16, Error<SPI::Error>> {
        self.frame(read_command(register))?;
        let response = self.frame(read_command(Register::Nop))?;
        self.data(response)
    }

    /// Reads the magnetic diagnostics (DIAAGC).
    ///
    /// # Errors
    /// As [`As5047p::read_register`].
    pub fn diagnostics(&mut self) -> Result<Diagnostics, Error<SPI::Error>> {
        self.read_register(Register::Diaagc)
            .map(Diagnostics::from_bits)
    }

    /// Reads the compensated angle, counts in `[0, 16384)`, after checking the diagnostics read in
    /// the same burst of three frames.
    ///
    /// # Errors
    /// [`Error::Comm`], [`Error::Parity`] or [`Error::Command`] for the transfer;
    /// [`Error::MagnetTooWeak`], [`Error::MagnetTooStrong`], [`Error::CordicOverflow`] or
    /// [`Error::NotReady`] when the diagnostics say the angle is not valid.
    pub fn read_angle_counts(&mut self) -> Result<u16, Error<SPI::Error>> {
        self.frame(read_command(Register::Diaagc))?;
        let diaagc = self.frame(read_command(Register::AngleCom))?;
        let angle = self.frame(read_command(Register::Nop))?;
        let diagnostics = Diagnostics::from_bits(self.data(diaagc)?);
        let angle = self.data(angle)?;
        if diagnostics.magnet_too_weak {
            Err(Error::MagnetTooWeak)
        } else if diagnostics.magnet_too_strong {
            Err(Error::MagnetTooStrong)
        } else if diagnostics.cordic_overflow {
            Err(Error::CordicOverflow)
        } else if !diagnostics.offset_loop_ready {
            Err(Error::NotReady)
        } else {
            Ok(angle)
        }
    }
}

impl<SPI: SpiDevice> AngleSensor for As5047p<SPI>
where
    SPI::Error: Copy,
{
    type Error = Error<SPI::Error>;

    fn counts_per_turn(&self) -> u32 {
        COUNTS_PER_TURN
    }

    fn read_angle_counts(&mut self) -> Result<u16, Self::Error> {
        As5047p::read_angle_counts(self)
    }
}

#[cfg(test)]
mod tests;
