use super::*;
use crate::frame::{encode_payload, encode_version};

fn estimate(tick: u32, points: usize, tensions: usize) -> Estimate {
    let mut backbone_m = Vec::new();
    for i in 0..points {
        let s = i as f32 * 0.1;
        assert!(backbone_m.push([0.3 * s, -0.1 * s, 0.1 + s]).is_ok());
    }
    let mut tensions_n = Vec::new();
    for i in 0..tensions {
        assert!(tensions_n.push(1.5 + i as f32 * 0.25).is_ok());
    }
    Estimate {
        tick,
        tip_force_n: [0.012_345_678, -0.14, 0.119_784_06],
        tip_force_std_n: [1.1e-3, 2.2e-3, 3.3e-4],
        tip_position_m: [0.330_769_2, -0.160_665_85, 0.099_017_02],
        tip_position_std_m: [9.4e-6, 1.2e-5, 7.7e-6],
        tip_orientation: [0.923_879_5, 0.0, 0.382_683_43, 0.0],
        backbone_m,
        tensions_n,
        sweeps: 2,
    }
}

fn record(tick: u32) -> Record {
    Record {
        tick,
        status: Status::Fresh,
        estimate: Some(estimate(tick, 4, 0)),
    }
}

/// The largest record: every variable part at capacity, every varint at its widest.
fn largest() -> Record {
    let mut e = estimate(u32::MAX, MAX_BACKBONE_POINTS, MAX_TENSIONS);
    e.sweeps = u16::MAX;
    Record {
        tick: u32::MAX,
        status: Status::Rejected {
            cable: u8::MAX,
            reason: Rejection::Jump,
        },
        estimate: Some(e),
    }
}

fn frame_of(record: &Record) -> std::vec::Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_BYTES];
    encode(record, &mut buf).unwrap().to_vec()
}

fn decode_all(stream: &[u8]) -> (std::vec::Vec<Record>, std::vec::Vec<FrameError>) {
    let (mut records, mut errors) = (std::vec::Vec::new(), std::vec::Vec::new());
    Decoder::new().feed(stream, |r| match r {
        Ok(record) => records.push(record),
        Err(e) => errors.push(e),
    });
    (records, errors)
}

#[test]
fn a_record_round_trips_through_its_frame() {
    let statuses = [
        Status::Fresh,
        Status::Rejected {
            cable: 1,
            reason: Rejection::Sensor,
        },
        Status::NotConverged,
        Status::Refused,
        Status::Inconsistent,
        Status::SlackCable { cable: 2 },
        Status::Indeterminate,
    ];
    for (tick, status) in statuses.into_iter().enumerate() {
        let mut original = record(tick as u32);
        original.status = status;
        let mut frame = frame_of(&original);
        // One delimiter, at the end: COBS keeps it out of the body.
        assert_eq!(frame.iter().filter(|b| **b == DELIMITER).count(), 1);
        assert_eq!(frame.last(), Some(&DELIMITER));
        assert_eq!(decode(&mut frame), Ok(original));
    }
    let empty = Record {
        tick: 0,
        status: Status::Refused,
        estimate: None,
    };
    assert_eq!(decode(&mut frame_of(&empty)), Ok(empty));
}

#[test]
fn f32_values_are_exact_after_a_round_trip() {
    let specials = [
        0.0f32,
        -0.0,
        f32::MIN_POSITIVE,
        f32::MIN_POSITIVE / 3.0,
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::from_bits(0x7fc0_1234),
        0.1,
        -1.0e-7,
    ];
    let mut original = record(7);
    let e = original.estimate.as_mut().unwrap();
    e.tip_force_n.copy_from_slice(&specials[..3]);
    e.tip_force_std_n.copy_from_slice(&specials[3..6]);
    e.tip_orientation.copy_from_slice(&specials[6..10]);
    e.tensions_n.extend(specials.iter().copied());
    let decoded = decode(&mut frame_of(&original)).unwrap();
    let bits = |r: &Record| {
        let e = r.estimate.as_ref().unwrap();
        let mut all = std::vec::Vec::new();
        all.extend(e.tip_force_n.map(f32::to_bits));
        all.extend(e.tip_force_std_n.map(f32::to_bits));
        all.extend(e.tip_position_m.map(f32::to_bits));
        all.extend(e.tip_position_std_m.map(f32::to_bits));
        all.extend(e.tip_orientation.map(f32::to_bits));
        all.extend(e.backbone_m.iter().flatten().map(|x| x.to_bits()));
        all.extend(e.tensions_n.iter().map(|x| x.to_bits()));
        all
    };
    assert_eq!(bits(&decoded), bits(&original));
}

#[test]
fn the_largest_record_fills_the_declared_sizes_exactly() {
    let largest = largest();
    let mut buf = [0u8; 2 * MAX_FRAME_BYTES];
    let payload = postcard::to_slice(&(FORMAT_VERSION, &largest), &mut buf).unwrap();
    assert_eq!(payload.len(), MAX_PAYLOAD_BYTES);
    let frame = frame_of(&largest);
    assert!(frame.len() <= MAX_FRAME_BYTES, "{}", frame.len());
    // FORMAT.md's figures.
    assert_eq!((MAX_PAYLOAD_BYTES, MAX_FRAME_BYTES), (324, 331));
    assert_eq!(decode(&mut frame.clone()), Ok(largest.clone()));
    // One byte short is refused, not truncated.
    let mut short = [0u8; MAX_FRAME_BYTES];
    assert_eq!(
        encode(&largest, &mut short[..frame.len() - 1]),
        Err(EncodeError::BufferFull)
    );
}

#[test]
fn every_single_byte_corruption_is_refused() {
    let frame = frame_of(&record(3));
    for at in 0..frame.len() - 1 {
        for flip in [0x01u8, 0x80, 0xff] {
            let mut damaged = frame.clone();
            damaged[at] ^= flip;
            let result = decode(&mut damaged);
            assert!(result.is_err(), "byte {at} ^ {flip:#x}: {result:?}");
        }
    }
    // A flipped payload bit is a checksum error, naming both checksums.
    let mut damaged = frame.clone();
    damaged[10] ^= 0x04;
    assert!(matches!(
        decode(&mut damaged),
        Err(FrameError::Crc { computed, received }) if computed != received
    ));
}

#[test]
fn another_version_is_refused_with_the_version_it_carries() {
    let mut buf = [0u8; MAX_FRAME_BYTES];
    let frame = encode_version(FORMAT_VERSION + 1, &record(1), &mut buf).unwrap();
    assert_eq!(
        decode(frame),
        Err(FrameError::Version {
            found: FORMAT_VERSION + 1
        })
    );
}

#[test]
fn a_truncated_stream_resynchronises_at_the_next_delimiter() {
    let frames: std::vec::Vec<_> = (0..4).map(|t| frame_of(&record(t))).collect();
    let whole: std::vec::Vec<u8> = frames.concat();
    let (records, errors) = decode_all(&whole);
    assert_eq!(records, (0..4).map(record).collect::<std::vec::Vec<_>>());
    assert!(errors.is_empty());

    // Joined mid-frame: the first frame's tail is refused, the rest decode.
    let (records, errors) = decode_all(&whole[9..]);
    assert_eq!(records, (1..4).map(record).collect::<std::vec::Vec<_>>());
    assert_eq!(errors.len(), 1);

    // A frame that lost bytes in the middle swallows the next one up to its delimiter: both are
    // refused as one, and the stream carries on from there.
    let mut lossy = frames[0].clone();
    lossy.extend_from_slice(&frames[1][..20]);
    lossy.extend_from_slice(&frames[2][25..]);
    lossy.extend_from_slice(&frames[3]);
    let (records, errors) = decode_all(&lossy);
    assert_eq!(records, [record(0), record(3)]);
    assert_eq!(errors.len(), 1);

    // Cut at the end: the unfinished frame is held, not reported.
    let mut decoder = Decoder::new();
    let mut count = 0;
    decoder.feed(&whole[..whole.len() - 5], |r| {
        assert!(r.is_ok());
        count += 1;
    });
    assert_eq!(count, 3);
    assert_eq!(decoder.pending_bytes(), frames[3].len() - 5);
}

#[test]
fn empty_frames_are_skipped_and_overlong_ones_refused() {
    let mut stream = vec![DELIMITER, DELIMITER];
    stream.extend(frame_of(&record(5)));
    stream.extend(std::iter::repeat_n(0x55u8, 2 * MAX_FRAME_BYTES));
    stream.push(DELIMITER);
    stream.extend(frame_of(&record(6)));
    let (records, errors) = decode_all(&stream);
    assert_eq!(records, [record(5), record(6)]);
    assert_eq!(errors, [FrameError::Overlong]);
}

#[test]
fn statuses_print_their_cable() {
    let rejected = Status::Rejected {
        cable: 1,
        reason: Rejection::Sensor,
    };
    assert_eq!(rejected.to_string(), "rejected:sensor:cable1");
    assert_eq!(
        Status::SlackCable { cable: 2 }.to_string(),
        "slack-cable:cable2"
    );
    assert_eq!(Status::Fresh.to_string(), "fresh");
    assert_eq!(rejected.cable(), Some(1));
    assert_eq!(Status::Fresh.cable(), None);
}

#[test]
fn an_intact_frame_that_is_not_a_record_is_malformed() {
    // The record's layout with one backbone point more than the capacity.
    #[derive(serde::Serialize)]
    struct Wider<'a> {
        tick: u32,
        status: Status,
        some: u8,
        estimate_tick: u32,
        floats: [f32; 16],
        backbone_m: &'a [[f32; 3]],
        tensions_n: &'a [f32],
        sweeps: u16,
    }
    let points = [[0.1f32, 0.2, 0.3]; MAX_BACKBONE_POINTS + 1];
    let wider = |n: usize| Wider {
        tick: 1,
        status: Status::Fresh,
        some: 1,
        estimate_tick: 1,
        floats: [0.5; 16],
        backbone_m: &points[..n],
        tensions_n: &[],
        sweeps: 2,
    };
    let mut buf = [0u8; 2 * MAX_FRAME_BYTES];
    // At capacity it is a record: the layout above is the record's.
    let frame = encode_payload(&(FORMAT_VERSION, wider(MAX_BACKBONE_POINTS)), &mut buf).unwrap();
    let full = decode(frame).unwrap();
    assert_eq!(full.estimate.unwrap().backbone_m.len(), MAX_BACKBONE_POINTS);
    let frame =
        encode_payload(&(FORMAT_VERSION, wider(MAX_BACKBONE_POINTS + 1)), &mut buf).unwrap();
    assert_eq!(decode(frame), Err(FrameError::Malformed));
    // Bytes left over after a record.
    let frame = encode_payload(&(FORMAT_VERSION, record(3), 7u8), &mut buf).unwrap();
    assert_eq!(decode(frame), Err(FrameError::Malformed));
}

#[test]
fn the_example_frame_in_format_md_decodes_as_described() {
    let doc = include_str!("../FORMAT.md");
    let example = doc
        .split("## An example")
        .nth(1)
        .and_then(|s| s.split("```text").nth(1))
        .and_then(|s| s.split("```").next())
        .unwrap();
    let mut frame: std::vec::Vec<u8> = example
        .split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect();
    assert_eq!(frame.len(), 128);
    let record = decode(&mut frame).unwrap();
    assert_eq!(record.tick, 15);
    assert_eq!(
        record.status,
        Status::Rejected {
            cable: 1,
            reason: Rejection::Sensor
        }
    );
    let e = record.estimate.unwrap();
    assert_eq!((e.tick, e.sweeps, e.backbone_m.len()), (14, 2, 4));
    assert_eq!(e.tip_force_n[0].to_bits(), 0x3d00_b41f);
    assert!((e.tip_position_m[0] - 0.359_525).abs() < 1e-6);
    assert_eq!(e.backbone_m[3], e.tip_position_m);
    assert!(e.tensions_n.is_empty());
}
