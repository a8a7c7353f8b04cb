//! `host-sim monitor` on streams written by robot-link's own encoder (the firmware's): every record
//! decoded exactly, the CSV's columns, a damaged frame skipped and counted, and the check against a
//! reference passing and failing where it must.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use host_sim::monitor::{
    Checker, Event, Monitor, Reference, Tolerances, csv_header, csv_row, record_line,
};
use nalgebra::{UnitQuaternion, Vector3};
use robot_link::heapless::Vec as Bounded;
use robot_link::{Estimate, MAX_FRAME_BYTES, Record, Rejection, Status, encode};

mod common;
use common::{host_sim, temp_dir};

const TICKS: u32 = 12;
/// Tick 5's reading is refused: its record carries tick 4's estimate.
const REFUSED_TICK: u32 = 5;

/// A tick's estimate: a tip moving along a circle, its frame turning about z with it.
fn estimate(tick: u32) -> Estimate {
    let a = f64::from(tick) * 0.05;
    let tip = [0.33 + 0.01 * a.cos(), -0.15 + 0.01 * a.sin(), 0.09].map(|x| x as f32);
    let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.7 + a);
    let mut backbone = Bounded::new();
    for k in 1..=4 {
        let s = k as f32 / 4.0;
        assert!(backbone.push(tip.map(|x| x * s)).is_ok());
    }
    Estimate {
        tick,
        tip_force_n: [0.01 * a.sin() as f32, -0.14, 0.12 * a.cos() as f32],
        tip_force_std_n: [1.2e-3, 0.8e-3, 0.5e-3],
        tip_position_m: tip,
        tip_position_std_m: [2.1e-5, 3.2e-5, 2.4e-5],
        tip_orientation: [q.w, q.i, q.j, q.k].map(|c| c as f32),
        backbone_m: backbone,
        tensions_n: Bounded::new(),
        sweeps: 2,
    }
}

/// The stream's records: fresh every tick but [`REFUSED_TICK`].
fn records() -> Vec<Record> {
    (0..TICKS)
        .map(|tick| {
            if tick == REFUSED_TICK {
                Record {
                    tick,
                    status: Status::Rejected {
                        cable: 1,
                        reason: Rejection::Sensor,
                    },
                    estimate: Some(estimate(tick - 1)),
                }
            } else {
                Record {
                    tick,
                    status: Status::Fresh,
                    estimate: Some(estimate(tick)),
                }
            }
        })
        .collect()
}

fn frames(records: &[Record]) -> Vec<Vec<u8>> {
    records
        .iter()
        .map(|r| {
            let mut buf = [0u8; MAX_FRAME_BYTES];
            encode(r, &mut buf).unwrap().to_vec()
        })
        .collect()
}

/// The records as `firmware/src/fixture/trajectory.csv` writes a reference: the values each
/// fresh tick's estimate should have, here exactly the ones sent.
fn reference_csv(records: &[Record]) -> String {
    let mut text = String::from("# a reference written from the records themselves\n");
    let mut header = vec!["tick", "expected", "force_x_n", "force_y_n", "force_z_n"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    for c in [
        "tip_x_m", "tip_y_m", "tip_z_m", "tip_qw", "tip_qx", "tip_qy", "tip_qz",
    ] {
        header.push(c.into());
    }
    for i in 0..4 {
        header.extend(["x", "y", "z"].map(|a| format!("backbone_{i}_{a}_m")));
    }
    text.push_str(&header.join(","));
    text.push('\n');
    for r in records {
        let e = estimate(r.tick);
        let mut row = vec![r.tick.to_string(), r.status.to_string()];
        let numbers = e
            .tip_force_n
            .iter()
            .chain(&e.tip_position_m)
            .chain(&e.tip_orientation)
            .chain(e.backbone_m.iter().flatten());
        row.extend(numbers.map(|x| format!("{:?}", f64::from(*x))));
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// The stream with one byte in its middle changed, never into or out of a delimiter (which would
/// split a frame or join two): one frame damaged.
fn damage_one_byte(stream: &[u8]) -> Vec<u8> {
    let mut damaged = stream.to_vec();
    let at = stream.len() / 2 + usize::from(stream[stream.len() / 2] == 0);
    let flipped = damaged[at] ^ 0x80;
    damaged[at] = if flipped == 0 { 0x40 } else { flipped };
    damaged
}

fn decode_all(bytes: &[u8]) -> (Monitor, Vec<Event>) {
    let mut monitor = Monitor::new();
    // In small pieces, as a serial port hands them out.
    let events = bytes.chunks(7).flat_map(|c| monitor.feed(c)).collect();
    (monitor, events)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn every_record_of_an_encoded_stream_is_decoded_exactly() {
    let records = records();
    let (monitor, events) = decode_all(&frames(&records).concat());
    let decoded: Vec<Record> = events
        .into_iter()
        .map(|e| match e {
            Event::Record(r) => *r,
            Event::Refused(e) => panic!("refused: {e}"),
        })
        .collect();
    assert_eq!(decoded, records);
    assert_eq!((monitor.records, monitor.refused), (u64::from(TICKS), 0));
    assert_eq!(monitor.pending_bytes(), 0);
    let line = record_line(&records[REFUSED_TICK as usize]);
    assert!(line.contains("rejected:sensor:cable1"), "{line}");
    assert!(line.contains("estimate@4"), "{line}");
}

#[test]
fn the_csv_has_one_cell_per_column_and_the_f32_values_exactly() {
    let header = csv_header();
    let columns: Vec<&str> = header.split(',').collect();
    assert_eq!(columns.len(), 24 + 3 * 16 + 12);
    assert_eq!(
        columns[..8],
        [
            "tick",
            "status",
            "reason",
            "cable",
            "estimate_tick",
            "force_x_n",
            "force_y_n",
            "force_z_n"
        ]
    );
    let at = |name: &str| columns.iter().position(|c| *c == name).unwrap();
    for r in records() {
        let row = csv_row(&r);
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells.len(), columns.len(), "{row}");
        let e = r.estimate.as_ref().unwrap();
        let float = |name: &str| cells[at(name)].parse::<f32>().unwrap();
        assert_eq!(float("tip_x_m").to_bits(), e.tip_position_m[0].to_bits());
        assert_eq!(float("tip_qz").to_bits(), e.tip_orientation[3].to_bits());
        assert_eq!(float("force_std_y_n"), e.tip_force_std_n[1]);
        assert_eq!(float("backbone_3_y_m"), e.backbone_m[3][1]);
        assert_eq!(cells[at("backbone_points")], "4");
        assert_eq!(cells[at("backbone_4_x_m")], "");
        assert_eq!(cells[at("tension_0_n")], "");
        assert_eq!(cells[at("estimate_tick")], e.tick.to_string());
        if r.tick == REFUSED_TICK {
            assert_eq!(
                [cells[at("status")], cells[at("reason")], cells[at("cable")]],
                ["rejected", "sensor", "1"]
            );
        } else {
            assert_eq!(
                [cells[at("status")], cells[at("reason")], cells[at("cable")]],
                ["fresh", "", ""]
            );
        }
    }
}

#[test]
fn a_damaged_frame_is_skipped_and_counted() {
    let records = records();
    let mut frames = frames(&records);
    frames[3][9] ^= 0x10;
    let (monitor, events) = decode_all(&frames.concat());
    assert_eq!(
        (monitor.records, monitor.refused),
        (u64::from(TICKS) - 1, 1)
    );
    let ticks: Vec<u32> = events
        .iter()
        .filter_map(|e| match e {
            Event::Record(r) => Some(r.tick),
            Event::Refused(_) => None,
        })
        .collect();
    let expected: Vec<u32> = (0..TICKS).filter(|t| *t != 3).collect();
    assert_eq!(ticks, expected);
    assert!(matches!(
        events[3],
        Event::Refused(robot_link::FrameError::Crc { .. })
    ));
}

#[test]
fn the_check_passes_its_reference_and_fails_what_differs() {
    let records = records();
    let reference = Reference::parse(&reference_csv(&records), "reference").unwrap();
    let tolerances = Tolerances::default();
    let mut checker = Checker::new(reference.clone(), tolerances);
    for r in &records {
        let verdict = checker.check(r);
        assert_eq!(verdict.result.map(|e| e.tip_m), Ok(0.0), "tick {}", r.tick);
        assert!(verdict.skipped.is_empty());
    }
    assert!(checker.passed_with(0));
    assert!(!checker.passed_with(1), "a refused frame fails the check");

    // A tip 0.2 mm off, a force 6 mN off, a frame 1 mrad off, a point 0.2 mm off, the wrong
    // status, the wrong estimate: each fails its own tick, the others pass.
    let mut bad = records.clone();
    let e = |r: &Record| r.estimate.clone().unwrap();
    let mut tip = e(&bad[1]);
    tip.tip_position_m[0] += 2e-4;
    bad[1].estimate = Some(tip);
    let mut force = e(&bad[2]);
    force.tip_force_n[2] += 6e-3;
    bad[2].estimate = Some(force);
    let mut frame = e(&bad[3]);
    let q = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 1e-3)
        * UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            frame.tip_orientation[0] as f64,
            frame.tip_orientation[1] as f64,
            frame.tip_orientation[2] as f64,
            frame.tip_orientation[3] as f64,
        ));
    frame.tip_orientation = [q.w, q.i, q.j, q.k].map(|c| c as f32);
    bad[3].estimate = Some(frame);
    let mut point = e(&bad[4]);
    point.backbone_m[1][2] -= 2e-4;
    bad[4].estimate = Some(point);
    bad[6].status = Status::Inconsistent;
    bad[7].estimate = Some(estimate(6));
    // Not a number anywhere fails its tick: a NaN backbone point, a NaN force.
    let mut nan_point = e(&bad[8]);
    nan_point.backbone_m[2][0] = f32::NAN;
    bad[8].estimate = Some(nan_point);
    let mut nan_force = e(&bad[9]);
    nan_force.tip_force_n[1] = f32::NAN;
    bad[9].estimate = Some(nan_force);
    let mut checker = Checker::new(reference.clone(), tolerances);
    let failed: Vec<(u32, String)> = bad
        .iter()
        .filter_map(|r| match checker.check(r).result {
            Ok(_) => None,
            Err(why) => Some((r.tick, why.join("; "))),
        })
        .collect();
    let ticks: Vec<u32> = failed.iter().map(|(t, _)| *t).collect();
    assert_eq!(ticks, [1, 2, 3, 4, 6, 7, 8, 9], "{failed:?}");
    for (needle, (_, why)) in [
        "tip",
        "force",
        "tip frame",
        "backbone",
        "status",
        "estimate",
        "backbone",
        "force",
    ]
    .iter()
    .zip(&failed)
    {
        assert!(why.contains(needle), "{why}");
    }
    assert!(!checker.passed_with(0));

    // A lost record: its tick is missing, the stream goes on.
    let mut checker = Checker::new(reference, tolerances);
    for r in records.iter().filter(|r| r.tick != 8) {
        assert!(checker.check(r).result.is_ok(), "tick {}", r.tick);
    }
    assert_eq!(
        (checker.skipped.as_slice(), checker.missing()),
        (&[8][..], 1)
    );
    assert!(!checker.passed_with(0));
}

#[test]
fn the_command_reads_a_file_and_a_pipe_writes_csv_and_checks() {
    let dir = temp_dir("cli");
    let records = records();
    let stream = frames(&records).concat();
    let (input, csv, reference, plot) = (
        dir.join("link.bin"),
        dir.join("link.csv"),
        dir.join("reference.csv"),
        dir.join("shape.svg"),
    );
    std::fs::write(&input, &stream).unwrap();
    std::fs::write(&reference, reference_csv(&records)).unwrap();
    let path = |p: &PathBuf| p.display().to_string();
    let out = host_sim(&[
        "monitor",
        "--input",
        &path(&input),
        "--csv",
        &path(&csv),
        "--plot",
        &path(&plot),
        "--check-against",
        &path(&reference),
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert_eq!(
        stdout.lines().filter(|l| l.ends_with("check pass")).count(),
        12
    );
    assert!(
        stdout.contains("monitor: 12 records, 0 frames refused"),
        "{stdout}"
    );
    assert!(stdout.contains(": PASS"), "{stdout}");
    let written = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(written.lines().count(), 1 + records.len());
    assert_eq!(written.lines().next(), Some(csv_header().as_str()));
    assert!(std::fs::read_to_string(&plot).unwrap().contains("<svg"));

    // Damaged: the frame is refused and named, the others decode, the check fails (exit 1).
    let damaged = damage_one_byte(&stream);
    std::fs::write(&input, &damaged).unwrap();
    let out = host_sim(&[
        "monitor",
        "--input",
        &path(&input),
        "--check-against",
        &path(&reference),
        "--quiet",
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("monitor: 11 records, 1 frames refused"),
        "{stdout}"
    );
    assert!(stdout.contains("check FAIL: no record"), "{stdout}");
    assert!(text(&out.stderr).contains("frame refused"));

    // Without a check a refused frame is reported, not an error; standard input as a pipe.
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["monitor", "--input", "-", "--count", "4"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&damaged).unwrap();
    let out = child.wait_with_output().unwrap();
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert_eq!(stdout.lines().filter(|l| l.starts_with("tick")).count(), 4);
    assert!(stdout.contains("monitor: 4 records"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_reference_without_its_columns_is_refused_by_name() {
    let error = Reference::parse("tick,expected,force_x_n\n0,fresh,0.1\n", "ref.csv").unwrap_err();
    assert!(error.to_string().contains("force_y_n"), "{error}");
    let error =
        Reference::parse(&reference_csv(&records()).replace("\n3,", "\n1,"), "r").unwrap_err();
    assert!(error.to_string().contains("increase"), "{error}");
}

/// `--serial`: a pseudo-terminal stands in for the USB serial adapter. The monitor opens it by path
/// (flushing what came before), so the frames are written until it has read three records.
#[cfg(unix)]
#[test]
fn the_command_reads_a_serial_port() {
    use std::time::{Duration, Instant};

    let (mut master, slave) = serialport::TTYPort::pair().unwrap();
    let name = serialport::SerialPort::name(&slave).unwrap();
    // The monitor opens the port itself (exclusively): the pair's own slave end must be closed.
    drop(slave);
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "monitor", "--serial", &name, "--baud", "921600", "--count", "3",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stream = frames(&records()).concat();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no three records"
        );
        let _ = master.write_all(&stream);
        std::thread::sleep(Duration::from_millis(100));
    }
    let out = child.wait_with_output().unwrap();
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert_eq!(stdout.lines().filter(|l| l.starts_with("tick")).count(), 3);
    assert!(stdout.contains("monitor: 3 records"), "{stdout}");
}
