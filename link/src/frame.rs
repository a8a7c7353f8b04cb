//! Frames: `COBS(payload ++ CRC-32(payload)) ++ 0x00`, the payload postcard's encoding of
//! `(FORMAT_VERSION, Record)`.

use core::fmt;

use heapless::Vec;
use postcard::ser_flavors::crc::CrcModifier;
use postcard::ser_flavors::{Cobs, Slice};

use crate::{FORMAT_VERSION, MAX_BACKBONE_POINTS, MAX_TENSIONS, Record};

/// Ends every frame; COBS keeps it out of the frame's body.
pub const DELIMITER: u8 = 0x00;

/// The checksum after the payload: CRC-32/ISO-HDLC (zlib's `crc32`: reflected polynomial
/// 0xEDB88320, initial and final XOR 0xFFFFFFFF), little-endian.
static CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

const CRC_BYTES: usize = 4;

// postcard's sizes: a u32 is a varint of at most 5 bytes, a u16 at most 3, an f32 4 bytes
// little-endian, an enum's variant and a sequence's length varints (one byte below 128), an
// `Option` one byte before its value.
const U32_MAX_BYTES: usize = 5;
const U16_MAX_BYTES: usize = 3;
const F32_BYTES: usize = 4;

// The lengths of the backbone and the tensions are single-byte varints.
const _: () = assert!(MAX_BACKBONE_POINTS < 128 && MAX_TENSIONS < 128);

/// Largest estimate: tick, 4 x 3 floats (force, its deviation, position, its deviation), the
/// quaternion, the backbone and the tensions at capacity with their lengths, sweeps.
const MAX_ESTIMATE_BYTES: usize = U32_MAX_BYTES
    + 12 * F32_BYTES
    + 4 * F32_BYTES
    + 1
    + MAX_BACKBONE_POINTS * 3 * F32_BYTES
    + 1
    + MAX_TENSIONS * F32_BYTES
    + U16_MAX_BYTES;

/// Largest payload, bytes: the version, the tick, the largest status (`Rejected`: variant, cable,
/// reason), the `Option` tag and the largest estimate.
pub const MAX_PAYLOAD_BYTES: usize = 1 + U32_MAX_BYTES + 3 + 1 + MAX_ESTIMATE_BYTES;

/// COBS-encoded payload and checksum, at most (one overhead byte per 254).
const MAX_ENCODED_BYTES: usize = cobs::max_encoding_length(MAX_PAYLOAD_BYTES + CRC_BYTES);

/// Largest frame, delimiter included, bytes: a buffer of this size holds any record's frame.
pub const MAX_FRAME_BYTES: usize = MAX_ENCODED_BYTES + 1;

/// Why a record could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EncodeError {
    /// The buffer is shorter than the frame ([`MAX_FRAME_BYTES`] always suffices).
    BufferFull,
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferFull => write!(f, "the frame does not fit the buffer"),
        }
    }
}

impl core::error::Error for EncodeError {}

/// Why a frame was refused. A refused frame yields nothing: no field of it is used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// More than [`MAX_FRAME_BYTES`] bytes came before a delimiter (bytes lost, or not this
    /// format); they were dropped up to the delimiter.
    Overlong,
    /// The bytes are not valid COBS (a delimiter inside, or a code byte pointing past the end).
    Encoding,
    /// Too short for a version byte and a checksum.
    Short {
        /// Bytes after COBS decoding.
        bytes: usize,
    },
    /// The checksum does not match: the frame was damaged (or truncated and joined to the next).
    Crc {
        /// The checksum of the bytes received.
        computed: u32,
        /// The checksum the frame carries.
        received: u32,
    },
    /// Intact, but written in another format version.
    Version {
        /// The frame's version.
        found: u8,
    },
    /// Intact and of this version, but not a record (or bytes left over after it): the writer and
    /// this decoder disagree on the format.
    Malformed,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Overlong => write!(f, "no delimiter within {MAX_FRAME_BYTES} bytes"),
            Self::Encoding => write!(f, "not valid COBS"),
            Self::Short { bytes } => write!(f, "{bytes} bytes: too short for a frame"),
            Self::Crc { computed, received } => write!(
                f,
                "checksum mismatch: computed {computed:#010x}, frame carries {received:#010x}"
            ),
            Self::Version { found } => write!(
                f,
                "format version {found}, this decoder reads version {FORMAT_VERSION}"
            ),
            Self::Malformed => write!(
                f,
                "intact frame that is not a version {FORMAT_VERSION} record"
            ),
        }
    }
}

impl core::error::Error for FrameError {}

/// Encodes `record` as one frame into `buf` (delimiter included) and returns the frame.
///
/// # Errors
/// [`EncodeError::BufferFull`] when `buf` is too short; [`MAX_FRAME_BYTES`] always suffices.
pub fn encode<'a>(record: &Record, buf: &'a mut [u8]) -> Result<&'a mut [u8], EncodeError> {
    encode_version(FORMAT_VERSION, record, buf)
}

/// [`encode`] with any version byte (the tests write other versions).
pub(crate) fn encode_version<'a>(
    version: u8,
    record: &Record,
    buf: &'a mut [u8],
) -> Result<&'a mut [u8], EncodeError> {
    encode_payload(&(version, record), buf)
}

/// Frames any payload (the tests frame what is not a record).
pub(crate) fn encode_payload<'a, T: serde::Serialize>(
    payload: &T,
    buf: &'a mut [u8],
) -> Result<&'a mut [u8], EncodeError> {
    // The checksum covers the payload; COBS then encodes both and appends the delimiter.
    let cobs = Cobs::try_new(Slice::new(buf)).map_err(|_| EncodeError::BufferFull)?;
    postcard::serialize_with_flavor(payload, CrcModifier::new(cobs, CRC.digest()))
        .map_err(|_| EncodeError::BufferFull)
}

/// Decodes one frame in place: its bytes up to the delimiter (a trailing delimiter is allowed).
/// `frame` is overwritten (COBS decodes in place), also when the frame is refused.
///
/// # Errors
/// [`FrameError`]: the first check the frame fails, in the order COBS, length, checksum, version,
/// record.
pub fn decode(frame: &mut [u8]) -> Result<Record, FrameError> {
    let frame = match frame.split_last_mut() {
        Some((&mut DELIMITER, body)) => body,
        _ => frame,
    };
    if frame.is_empty() {
        return Err(FrameError::Short { bytes: 0 });
    }
    if frame.contains(&DELIMITER) {
        return Err(FrameError::Encoding);
    }
    let len = cobs::decode_in_place(frame).map_err(|_| FrameError::Encoding)?;
    let bytes = frame.get(..len).ok_or(FrameError::Encoding)?;
    let Some(payload_len) = len.checked_sub(CRC_BYTES).filter(|n| *n > 0) else {
        return Err(FrameError::Short { bytes: len });
    };
    let (payload, carried) = bytes.split_at(payload_len);
    let mut received = [0u8; CRC_BYTES];
    received.copy_from_slice(carried);
    let (computed, received) = (CRC.checksum(payload), u32::from_le_bytes(received));
    if computed != received {
        return Err(FrameError::Crc { computed, received });
    }
    match payload.first() {
        Some(&FORMAT_VERSION) => {}
        Some(&found) => return Err(FrameError::Version { found }),
        None => return Err(FrameError::Short { bytes: len }),
    }
    match postcard::take_from_bytes::<(u8, Record)>(payload) {
        Ok(((_, record), [])) => Ok(record),
        _ => Err(FrameError::Malformed),
    }
}

/// Splits a byte stream into frames at its delimiters and decodes each: one frame's bytes held at a
/// time (at most [`MAX_FRAME_BYTES`]), no allocation.
///
/// A stream joined mid-frame, or a frame that lost bytes, yields one refused frame (the damaged
/// bytes up to the next delimiter) and then the next frames whole. Empty frames (delimiters in a
/// row) are skipped: a writer may send a lone `0x00` to end whatever a receiver holds.
#[derive(Clone, Debug, Default)]
pub struct Decoder {
    buf: Vec<u8, MAX_ENCODED_BYTES>,
    overlong: bool,
}

impl Decoder {
    /// An empty decoder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes one byte of the stream: a delimiter ends the frame held, which is decoded and
    /// returned (a record, or why it was refused); any other byte returns `None`.
    pub fn push(&mut self, byte: u8) -> Option<Result<Record, FrameError>> {
        if byte != DELIMITER {
            if self.buf.push(byte).is_err() {
                self.overlong = true;
            }
            return None;
        }
        if core::mem::take(&mut self.overlong) {
            self.buf.clear();
            return Some(Err(FrameError::Overlong));
        }
        if self.buf.is_empty() {
            return None;
        }
        let result = decode(&mut self.buf);
        self.buf.clear();
        Some(result)
    }

    /// Takes the bytes in order, calling `on_frame` with each frame's outcome.
    pub fn feed(&mut self, bytes: &[u8], mut on_frame: impl FnMut(Result<Record, FrameError>)) {
        for byte in bytes {
            if let Some(result) = self.push(*byte) {
                on_frame(result);
            }
        }
    }

    /// Bytes of an unfinished frame held (at the end of a stream: a truncated last frame).
    pub fn pending_bytes(&self) -> usize {
        self.buf.len()
    }
}
