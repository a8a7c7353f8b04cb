//! The continuum robot's live link: each control tick's estimate as one framed binary record, the
//! same types on the MCU (which encodes) and on the host (which decodes).
//!
//! A frame is `COBS(payload ++ CRC-32(payload)) ++ 0x00`, the payload being postcard's encoding of
//! [`FORMAT_VERSION`] followed by a [`Record`]. `FORMAT.md` documents every byte: the fields and
//! their units, the framing, the checksum and the version policy.
//!
//! * [`encode`] writes one frame into the caller's buffer (no allocation; [`MAX_FRAME_BYTES`]
//!   always suffices).
//! * [`decode`] reads one frame in place; [`Decoder`] splits a byte stream at its delimiters and
//!   resynchronises after a damaged or truncated frame at the next `0x00`.
//!
//! A frame is refused, never half-read: a checksum that does not match ([`FrameError::Crc`]), a
//! format version other than this crate's ([`FrameError::Version`]) and a payload that is not a
//! record ([`FrameError::Malformed`]) are typed errors.

#![cfg_attr(not(test), no_std)]

mod bounded;
mod frame;

use core::fmt;

use heapless::Vec;
use serde::{Deserialize, Serialize};

/// The `heapless` the record's vectors come from (the same version for every user).
pub use heapless;

pub use frame::{
    DELIMITER, Decoder, EncodeError, FrameError, MAX_FRAME_BYTES, MAX_PAYLOAD_BYTES, decode, encode,
};

/// The record format's version: the first byte of every payload. Raised whenever the payload's
/// layout or meaning changes (a field added, removed or reordered, a unit, an enum's variants); a
/// decoder refuses any other ([`FrameError::Version`]). `FORMAT.md`, "Versions", lists them.
pub const FORMAT_VERSION: u8 = 1;

/// Most backbone points one record carries (the cable robot's loop sends four).
pub const MAX_BACKBONE_POINTS: usize = 16;

/// Most tendon tensions one record carries (the cable robot sends none).
pub const MAX_TENSIONS: usize = 12;

/// One control tick: what happened, and the newest good estimate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// The control tick, counting from 0 at power-up (wraps after 2^32 ticks).
    pub tick: u32,
    /// What the tick did with its readings.
    pub status: Status,
    /// The newest good estimate: this tick's when [`Status::Fresh`], else an earlier tick's (its
    /// own [`Estimate::tick`] says which); `None` until the first estimate succeeds.
    pub estimate: Option<Estimate>,
}

/// An estimate of the tip load and the shape it implies, in the model's global frame (`MODEL.md`):
/// the base clamped at the origin; on the firmware's bench the rod leaves it along +x, with
/// gravity along -y.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// The tick whose readings produced it.
    pub tick: u32,
    /// Tip force, N.
    pub tip_force_n: [f32; 3],
    /// Standard deviation of each force component, N.
    pub tip_force_std_n: [f32; 3],
    /// Tip position, m.
    pub tip_position_m: [f32; 3],
    /// Standard deviation of each tip coordinate, m.
    pub tip_position_std_m: [f32; 3],
    /// Tip orientation: the unit quaternion `[w, x, y, z]`, `w >= 0`, of the tip frame (it rotates
    /// the global axes onto the tip's local axes, the third of which is the backbone's tangent).
    pub tip_orientation: [f32; 4],
    /// Backbone points from the base towards the tip, m (at arc lengths the firmware's
    /// configuration fixes).
    #[serde(with = "bounded")]
    pub backbone_m: Vec<[f32; 3], MAX_BACKBONE_POINTS>,
    /// Tendon tensions, N, one per tendon; empty for a robot whose cables are only measured.
    #[serde(with = "bounded")]
    pub tensions_n: Vec<f32, MAX_TENSIONS>,
    /// Sweeps of the rod's equations the estimate took (its cost).
    pub sweeps: u16,
}

/// What a tick did. Only [`Status::Fresh`] brings a new estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Status {
    /// A new estimate from this tick's readings: converged, and the cables determine the load.
    Fresh,
    /// A reading was refused; the readings were not used.
    Rejected {
        /// The cable whose reading was refused, from 0.
        cable: u8,
        /// Why.
        reason: Rejection,
    },
    /// The solve did not converge within its budget (or converged to an unstable equilibrium).
    NotConverged,
    /// The model refused the input or its settings.
    Refused,
    /// No load of the model explains the readings.
    Inconsistent,
    /// As [`Status::Inconsistent`], every cable longer than any shape makes it: a slack cable.
    SlackCable {
        /// The cable taken to be slack, from 0.
        cable: u8,
    },
    /// The solve converged but the cables do not determine the load (or another load may explain
    /// them as well).
    Indeterminate,
}

/// Why a reading was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rejection {
    /// The sensor's read failed (bus, parity, magnet).
    Sensor,
    /// The sensor returned an angle beyond one turn.
    NotInTurn,
    /// Sensor and stepper disagree beyond the tolerance (a glitch, or a slipped magnet).
    Disagrees,
    /// A latched fault: no length until the cable is re-homed.
    Fault,
    /// The length is NaN or infinite.
    NonFinite,
    /// The length is outside what the model can produce.
    OutOfRange,
    /// The length moved further than the cable can travel in the time.
    Jump,
}

impl Status {
    /// A short lower-case name, for text and CSV (`fresh`, `rejected`, `not-converged`, `refused`,
    /// `inconsistent`, `slack-cable`, `indeterminate`).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Fresh => "fresh",
            Self::Rejected { .. } => "rejected",
            Self::NotConverged => "not-converged",
            Self::Refused => "refused",
            Self::Inconsistent => "inconsistent",
            Self::SlackCable { .. } => "slack-cable",
            Self::Indeterminate => "indeterminate",
        }
    }

    /// The cable it names, if any.
    pub fn cable(&self) -> Option<u8> {
        match self {
            Self::Rejected { cable, .. } | Self::SlackCable { cable } => Some(*cable),
            _ => None,
        }
    }
}

impl Rejection {
    /// A short lower-case name (`sensor`, `not-in-turn`, `disagrees`, `fault`, `non-finite`,
    /// `out-of-range`, `jump`).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Sensor => "sensor",
            Self::NotInTurn => "not-in-turn",
            Self::Disagrees => "disagrees",
            Self::Fault => "fault",
            Self::NonFinite => "non-finite",
            Self::OutOfRange => "out-of-range",
            Self::Jump => "jump",
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Rejected { cable, reason } => {
                write!(f, "rejected:{}:cable{}", reason.name(), cable)
            }
            Self::SlackCable { cable } => write!(f, "slack-cable:cable{cable}"),
            other => f.write_str(other.name()),
        }
    }
}

#[cfg(test)]
mod tests;
