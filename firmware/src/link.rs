//! The live link: each tick's report as a [`robot_link::Record`], written as one frame to a byte
//! stream (a UART) through `embedded_io::Write`. The format is `robot-link`'s
//! (`../link/FORMAT.md`); host-sim's `monitor` reads it.
//!
//! [`record`] turns the loop's [`TickReport`](crate::control::TickReport) into a record;
//! [`RecordWriter`] encodes it into its own buffer and writes the frame. The tip orientation is not
//! in [`TickRecord`] (the loop's output stays as small as it was): the caller reads
//! [`crate::control::EstimatorLoop::tip_rotation`] after a fresh tick, turns it into a quaternion
//! ([`orientation`]) and keeps it with the estimate.

use embedded_io::Write;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
use robot_link::heapless::Vec;
use robot_link::{EncodeError, MAX_BACKBONE_POINTS, MAX_FRAME_BYTES};

use crate::control::{SHAPE_POINTS, Status, TickRecord};
use crate::sampler::SampleError;
use crate::validate::Rejection;

// Every backbone point the loop reports fits a record.
const _: () = assert!(SHAPE_POINTS <= MAX_BACKBONE_POINTS);

/// The record format's name for a tick's status.
pub fn status<E>(status: &Status<SampleError<E>>) -> robot_link::Status {
    use robot_link::Rejection as Why;
    match status {
        Status::Fresh => robot_link::Status::Fresh,
        Status::Rejected(rejection) => {
            let (cable, reason) = match rejection {
                Rejection::Source { cable, error } => (
                    *cable,
                    match error {
                        SampleError::Sensor(_) => Why::Sensor,
                        SampleError::NotInTurn { .. } => Why::NotInTurn,
                        SampleError::Disagrees { .. } => Why::Disagrees,
                        SampleError::Fault(_) => Why::Fault,
                    },
                ),
                Rejection::NonFinite { cable } => (*cable, Why::NonFinite),
                Rejection::OutOfRange { cable, .. } => (*cable, Why::OutOfRange),
                Rejection::Jump { cable, .. } => (*cable, Why::Jump),
            };
            robot_link::Status::Rejected { cable, reason }
        }
        Status::NotConverged(_) => robot_link::Status::NotConverged,
        Status::Refused(_) => robot_link::Status::Refused,
        Status::Inconsistent { .. } => robot_link::Status::Inconsistent,
        Status::SlackCable { cable, .. } => robot_link::Status::SlackCable { cable: *cable },
        Status::Indeterminate(_) => robot_link::Status::Indeterminate,
    }
}

/// The unit quaternion `[w, x, y, z]` (`w >= 0`) of a tip frame (a rotation matrix, columns the
/// tip's axes in global coordinates).
pub fn orientation(rotation: &Matrix3<f32>) -> [f32; 4] {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rotation));
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    [q.w, q.i, q.j, q.k].map(|c| sign * c)
}

/// The record of an estimate, with its tip orientation (`[w, x, y, z]`, [`orientation`]). A
/// cable robot has no tensions to send.
pub fn estimate(record: &TickRecord, tip_orientation: [f32; 4]) -> robot_link::Estimate {
    let mut backbone_m = Vec::new();
    for point in &record.backbone_m {
        // Cannot fail: SHAPE_POINTS fits (checked above).
        let _ = backbone_m.push(*point);
    }
    robot_link::Estimate {
        tick: record.tick,
        tip_force_n: record.tip_force_n,
        tip_force_std_n: record.force_std_n,
        tip_position_m: record.tip_position_m,
        tip_position_std_m: record.tip_std_m,
        tip_orientation,
        backbone_m,
        tensions_n: Vec::new(),
        sweeps: record.sweeps,
    }
}

/// A tick's record: the tick, its status and the newest good estimate (the fields of a
/// [`TickReport`](crate::control::TickReport)), whose tip orientation is `tip_orientation`.
pub fn record<E>(
    tick: u32,
    status: &Status<SampleError<E>>,
    newest: Option<&TickRecord>,
    tip_orientation: [f32; 4],
) -> robot_link::Record {
    robot_link::Record {
        tick,
        status: self::status(status),
        estimate: newest.map(|e| estimate(e, tip_orientation)),
    }
}

/// Why a record was not sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum SendError<E> {
    /// The record did not encode (cannot happen with the writer's own buffer).
    Encode,
    /// The port's write failed; part of the frame may have gone out (the receiver refuses it and
    /// resynchronises at the next frame's delimiter).
    Port(E),
}

impl<E> From<EncodeError> for SendError<E> {
    fn from(_: EncodeError) -> Self {
        Self::Encode
    }
}

/// Writes records to a byte stream, one frame each, from its own buffer of
/// [`MAX_FRAME_BYTES`]. Takes the port and hands it back ([`RecordWriter::release`]).
#[derive(Debug)]
pub struct RecordWriter<W> {
    port: W,
    buf: [u8; MAX_FRAME_BYTES],
}

impl<W: Write> RecordWriter<W> {
    /// A writer on `port`.
    pub fn new(port: W) -> Self {
        Self {
            port,
            buf: [0; MAX_FRAME_BYTES],
        }
    }

    /// Encodes `record` and writes its frame (blocking until the port took every byte). Returns
    /// the frame's length, bytes.
    ///
    /// # Errors
    /// [`SendError::Port`] when the port fails.
    pub fn send(&mut self, record: &robot_link::Record) -> Result<usize, SendError<W::Error>> {
        let frame = robot_link::encode(record, &mut self.buf)?;
        self.port.write_all(frame).map_err(SendError::Port)?;
        Ok(frame.len())
    }

    /// The port back.
    pub fn release(self) -> W {
        self.port
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encoder::replay::ReplayError;
    use crate::sampler::CableFault;

    use crate::control::TickReport;

    type Report = TickReport<SampleError<ReplayError>>;

    fn tick_record() -> TickRecord {
        TickRecord {
            tick: 6,
            tip_force_n: [0.01, -0.13, 0.11],
            force_std_n: [1e-3, 2e-3, 3e-3],
            tip_position_m: [0.33, -0.15, 0.1],
            tip_std_m: [1e-5, 2e-5, 3e-5],
            tip_tangent: [0.8, -0.6, 0.0],
            backbone_m: [
                [0.1, 0.0, 0.0],
                [0.2, 0.0, 0.0],
                [0.3, 0.0, 0.0],
                [0.33, -0.15, 0.1],
            ],
            cable_length_m: [0.39, 0.38, 0.38],
            cable_residual_m: [0.0; 3],
            sweeps: 2,
            cold: false,
            converged: true,
            determination: model_core::inverse::Determination::Determined,
        }
    }

    /// A port that keeps what it is given, taking at most `chunk` bytes a write.
    struct Port {
        bytes: std::vec::Vec<u8>,
        chunk: usize,
    }

    impl embedded_io::ErrorType for Port {
        type Error = core::convert::Infallible;
    }

    impl Write for Port {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
            let n = buf.len().min(self.chunk);
            self.bytes.extend_from_slice(&buf[..n]);
            Ok(n)
        }

        fn flush(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
    }

    #[test]
    fn a_tick_report_arrives_whole_on_the_host() {
        let report = Report {
            tick: 7,
            sample: 70,
            status: Status::Rejected(Rejection::Source {
                cable: 1,
                error: SampleError::Sensor(ReplayError::Injected),
            }),
            estimate: Some(tick_record()),
        };
        let q = [0.5f32, 0.5, -0.5, 0.5];
        let mut writer = RecordWriter::new(Port {
            bytes: std::vec::Vec::new(),
            chunk: 7,
        });
        let out = record(report.tick, &report.status, report.estimate.as_ref(), q);
        let sent = writer.send(&out).unwrap();
        writer.send(&out).unwrap();
        let mut bytes = writer.release().bytes;
        assert_eq!(bytes.len(), 2 * sent);
        let decoded = robot_link::decode(&mut bytes[..sent]).unwrap();
        assert_eq!(decoded.tick, 7);
        assert_eq!(
            decoded.status,
            robot_link::Status::Rejected {
                cable: 1,
                reason: robot_link::Rejection::Sensor
            }
        );
        let e = decoded.estimate.unwrap();
        let r = tick_record();
        assert_eq!(e.tick, 6);
        assert_eq!(e.tip_force_n, r.tip_force_n);
        assert_eq!(e.tip_force_std_n, r.force_std_n);
        assert_eq!(e.tip_position_m, r.tip_position_m);
        assert_eq!(e.tip_position_std_m, r.tip_std_m);
        assert_eq!(e.tip_orientation, q);
        assert_eq!(e.backbone_m.as_slice(), r.backbone_m.as_slice());
        assert!(e.tensions_n.is_empty());
        assert_eq!(e.sweeps, 2);
    }

    #[test]
    fn every_status_has_its_name_and_cable() {
        use robot_link::{Rejection as Why, Status as Link};
        let cases: [(Status<SampleError<ReplayError>>, Link); 11] = [
            (Status::Fresh, Link::Fresh),
            (
                Status::Rejected(Rejection::Source {
                    cable: 2,
                    error: SampleError::Disagrees {
                        deviation_counts: 3500,
                    },
                }),
                Link::Rejected {
                    cable: 2,
                    reason: Why::Disagrees,
                },
            ),
            (
                Status::Rejected(Rejection::Source {
                    cable: 0,
                    error: SampleError::NotInTurn { raw_counts: 17000 },
                }),
                Link::Rejected {
                    cable: 0,
                    reason: Why::NotInTurn,
                },
            ),
            (
                Status::Rejected(Rejection::Source {
                    cable: 1,
                    error: SampleError::Fault(CableFault::SlippedMagnet { offset_counts: 900 }),
                }),
                Link::Rejected {
                    cable: 1,
                    reason: Why::Fault,
                },
            ),
            (
                Status::Rejected(Rejection::NonFinite { cable: 2 }),
                Link::Rejected {
                    cable: 2,
                    reason: Why::NonFinite,
                },
            ),
            (
                Status::Rejected(Rejection::OutOfRange {
                    cable: 0,
                    length_m: 2.0,
                }),
                Link::Rejected {
                    cable: 0,
                    reason: Why::OutOfRange,
                },
            ),
            (
                Status::Rejected(Rejection::Jump {
                    cable: 1,
                    step_m: 0.01,
                    limit_m: 0.001,
                }),
                Link::Rejected {
                    cable: 1,
                    reason: Why::Jump,
                },
            ),
            (
                Status::NotConverged(model_core::Termination::IterationLimit),
                Link::NotConverged,
            ),
            (
                Status::Inconsistent {
                    residual_rms_sigma: 9.0,
                },
                Link::Inconsistent,
            ),
            (
                Status::SlackCable {
                    cable: 2,
                    excess_m: 0.003,
                },
                Link::SlackCable { cable: 2 },
            ),
            (
                Status::Indeterminate(model_core::inverse::Determination::Undetermined),
                Link::Indeterminate,
            ),
        ];
        for (firmware, link) in cases {
            assert_eq!(status(&firmware), link, "{firmware:?}");
        }
    }

    #[test]
    fn the_orientation_is_the_frames_quaternion() {
        // A quarter turn about x: the tip's z axis along -y.
        let rotation = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0);
        let [w, x, y, z] = orientation(&rotation);
        let h = core::f32::consts::FRAC_1_SQRT_2;
        for (got, want) in [w, x, y, z].into_iter().zip([h, h, 0.0, 0.0]) {
            assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        }
        // The half turn's two quaternions come out with w >= 0.
        let half = Matrix3::new(-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0);
        let q = orientation(&half);
        assert!(q[0] >= 0.0 && (q[3].abs() - 1.0).abs() < 1e-6, "{q:?}");
    }
}
