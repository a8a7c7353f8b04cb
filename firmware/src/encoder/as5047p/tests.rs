//! The driver against scripted SPI transactions (embedded-hal-mock).

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::spi::{Mock, Transaction};

use super::*;

/// A response frame with `data`, the error flag and even parity.
fn response(data: u16, error_flag: bool) -> u16 {
    let frame = (data & 0x3FFF) | if error_flag { 0x4000 } else { 0 };
    if frame.count_ones() % 2 == 1 {
        frame | 0x8000
    } else {
        frame
    }
}

/// One chip-select cycle: `command` out, `reply` in.
fn frame(command: u16, reply: u16) -> [Transaction<u8>; 3] {
    [
        Transaction::transaction_start(),
        Transaction::transfer_in_place(
            command.to_be_bytes().to_vec(),
            reply.to_be_bytes().to_vec(),
        ),
        Transaction::transaction_end(),
    ]
}

fn script(frames: &[(u16, u16)]) -> Vec<Transaction<u8>> {
    frames.iter().flat_map(|&(c, r)| frame(c, r)).collect()
}

const READ_DIAAGC: u16 = 0xFFFC;
const READ_ANGLECOM: u16 = 0xFFFF;
const READ_NOP: u16 = 0xC000;
const READ_ERRFL: u16 = 0x4001;
/// DIAAGC with the offset loop finished and a mid-range gain.
const DIAAGC_OK: u16 = (1 << 8) | 0x60;

#[test]
fn commands_carry_even_parity() {
    // Datasheet values: READ ANGLECOM = 0xFFFF, READ NOP = 0xC000.
    assert_eq!(read_command(Register::AngleCom), READ_ANGLECOM);
    assert_eq!(read_command(Register::Nop), READ_NOP);
    assert_eq!(read_command(Register::Diaagc), READ_DIAAGC);
    assert_eq!(read_command(Register::Errfl), READ_ERRFL);
    assert_eq!(read_command(Register::Mag), 0x7FFD);
}

#[test]
fn reads_the_angle_after_checking_the_diagnostics() {
    let expectations = script(&[
        (READ_DIAAGC, 0x0000),
        (READ_ANGLECOM, response(DIAAGC_OK, false)),
        (READ_NOP, response(12_345, false)),
    ]);
    let mut sensor = As5047p::new(Mock::new(&expectations));
    assert_eq!(sensor.read_angle_counts(), Ok(12_345));
    sensor.release().done();
}

#[test]
fn wraps_through_a_full_turn_of_reads() {
    // Angles near the top of the range and past zero, as a spool crosses a turn.
    let angles = [16_380u16, 16_383, 2, 40];
    let expectations: Vec<_> = angles
        .iter()
        .flat_map(|&a| {
            script(&[
                (READ_DIAAGC, response(a, false)),
                (READ_ANGLECOM, response(DIAAGC_OK, false)),
                (READ_NOP, response(a, false)),
            ])
        })
        .collect();
    let mut sensor = As5047p::new(Mock::new(&expectations));
    let mut position = 16_380;
    let positions: Vec<i32> = angles
        .iter()
        .map(|_| {
            let raw = sensor.read_angle_counts().expect("good frames");
            position = crate::encoder::multiturn::nearest(position, raw, COUNTS_PER_TURN)
                .expect("within a turn");
            position
        })
        .collect();
    assert_eq!(positions, vec![16_380, 16_383, 16_386, 16_424]);
    sensor.release().done();
}

#[test]
fn a_corrupted_response_is_a_parity_error() {
    // One bit flipped in the angle frame: odd parity.
    let corrupted = response(12_345, false) ^ 0x0010;
    let expectations = script(&[
        (READ_DIAAGC, 0x0000),
        (READ_ANGLECOM, response(DIAAGC_OK, false)),
        (READ_NOP, corrupted),
    ]);
    let mut sensor = As5047p::new(Mock::new(&expectations));
    assert_eq!(sensor.read_angle_counts(), Err(Error::Parity(corrupted)));
    sensor.release().done();
}

#[test]
fn a_flagged_command_reads_and_reports_errfl() {
    // The sensor saw a parity error in our DIAAGC command: EF on its answer; ERRFL says PARERR.
    let expectations = script(&[
        (READ_DIAAGC, 0x0000),
        (READ_ANGLECOM, response(0, true)),
        (READ_NOP, response(777, false)),
        (READ_ERRFL, response(0, false)),
        (READ_NOP, response(0b100, false)),
    ]);
    let mut sensor = As5047p::new(Mock::new(&expectations));
    assert_eq!(
        sensor.read_angle_counts(),
        Err(Error::Command(ErrorFlags {
            framing: false,
            invalid_command: false,
            parity: true
        }))
    );
    sensor.release().done();
}

#[test]
fn magnet_and_cordic_flags_invalidate_the_angle() {
    let cases = [
        ((1 << 11) | (1 << 8) | 0xFF, Error::MagnetTooWeak),
        ((1 << 10) | (1 << 8), Error::MagnetTooStrong),
        ((1 << 9) | (1 << 8) | 0x40, Error::CordicOverflow),
        (0x40, Error::NotReady),
    ];
    for (diaagc, expected) in cases {
        let expectations = script(&[
            (READ_DIAAGC, 0x0000),
            (READ_ANGLECOM, response(diaagc, false)),
            (READ_NOP, response(5_000, false)),
        ]);
        let mut sensor = As5047p::new(Mock::new(&expectations));
        assert_eq!(sensor.read_angle_counts(), Err(expected));
        sensor.release().done();
    }
}

#[test]
fn diagnostics_decode_every_field() {
    let expectations = script(&[
        (READ_DIAAGC, 0x0000),
        (READ_NOP, response((1 << 10) | (1 << 8) | 0x2A, false)),
    ]);
    let mut sensor = As5047p::new(Mock::new(&expectations));
    assert_eq!(
        sensor.diagnostics(),
        Ok(Diagnostics {
            magnet_too_weak: false,
            magnet_too_strong: true,
            cordic_overflow: false,
            offset_loop_ready: true,
            agc: 0x2A,
        })
    );
    sensor.release().done();
}

/// A device whose every transaction fails, as a bus with a mode fault would.
#[derive(Debug)]
struct BrokenBus;

impl ErrorType for BrokenBus {
    type Error = ErrorKind;
}

impl SpiDevice for BrokenBus {
    fn transaction(&mut self, _: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        Err(ErrorKind::ModeFault)
    }
}

#[test]
fn a_bus_failure_is_a_comm_error() {
    let mut sensor = As5047p::new(BrokenBus);
    assert_eq!(
        sensor.read_angle_counts(),
        Err(Error::Comm(ErrorKind::ModeFault))
    );
    assert_eq!(
        AngleSensor::read_angle_counts(&mut sensor),
        Err(Error::Comm(ErrorKind::ModeFault))
    );
    assert_eq!(sensor.counts_per_turn(), 16_384);
}
