//! `host-sim monitor`: reads the live link's records (robot-link frames, `link/FORMAT.md`) from a
//! serial port, a file, a FIFO or standard input; prints one line per record, writes them to CSV,
//! draws the latest shape, and checks them against an f64 reference.
//!
//! The pieces are here so that tests run the same code: [`Monitor`] takes bytes and hands out
//! [`Event`]s, [`record_line`] and [`csv_row`] format a record, [`Reference`] and [`Checker`]
//! hold a stream to a reference tick by tick, and [`figure`] turns a record into the plot's
//! figure.

use std::fmt::Write as _;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use nalgebra::{UnitQuaternion, Vector3};
use robot_link::{Decoder, FrameError, MAX_BACKBONE_POINTS, MAX_TENSIONS, Record};

use crate::plots::{Figure, PlotSize, draw_figure};
use crate::scene::SceneError;

/// The largest tip error against the reference by default, m: the firmware's own end-to-end
/// tolerance (`firmware/src/checks.rs`, `TIP_TOLERANCE_M`). Also each backbone point's.
pub const TIP_TOLERANCE_M: f64 = 1.0e-4;

/// The largest force error by default, N (the firmware's `FORCE_TOLERANCE_N`).
pub const FORCE_TOLERANCE_N: f64 = 5.0e-3;

/// By default the tip error may be at most this many times the tip standard deviation the record
/// reports (its per-axis vector's length; the firmware's `COVERAGE`).
pub const COVERAGE: f64 = 5.0;

/// The largest angle between the reported and the reference tip frame by default, rad: the bend
/// that moves the tip of the 0.39 m rod by the tip tolerance (about 2 x 0.1 mm / 0.39 m). The
/// recorded trajectory's worst is 0.024 mrad (f32 at 20 steps per section against f64 at 200).
pub const ANGLE_TOLERANCE_RAD: f64 = 5.0e-4;

/// The command line of `host-sim monitor`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Read the frames from this file or FIFO ("-": standard input) until it ends.
    #[arg(long, required_unless_present = "serial", conflicts_with = "serial")]
    pub input: Option<PathBuf>,
    /// Read the frames from this serial port (8N1, no flow control) until interrupted, or until
    /// --count records.
    #[arg(long)]
    pub serial: Option<String>,
    /// The serial port's rate, baud (the firmware's `config::LINK_BAUD`).
    #[arg(long, default_value_t = 921_600, requires = "serial")]
    pub baud: u32,
    /// Stop after this many records.
    #[arg(long)]
    pub count: Option<u64>,
    /// Write every record to this CSV file as it arrives (columns below).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Draw the latest shape (SVG or PNG by the extension): redrawn at most once a second while
    /// records arrive, and at the end.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// The plot's printed width: "column" (3.5 in) or "page" (7.16 in).
    #[arg(long, value_enum, default_value_t = PlotSize::Page)]
    pub plot_size: PlotSize,
    /// Check every record against this reference (CSV: `firmware/src/fixture/trajectory.csv`'s
    /// columns); exit 1 when a check fails or a frame was refused.
    #[arg(long)]
    pub check_against: Option<PathBuf>,
    /// With --check-against: the largest tip (and backbone point) error, m.
    #[arg(long, default_value_t = TIP_TOLERANCE_M)]
    pub tip_tolerance_m: f64,
    /// With --check-against: the largest tip force error, N.
    #[arg(long, default_value_t = FORCE_TOLERANCE_N)]
    pub force_tolerance_n: f64,
    /// With --check-against: the tip error may be at most this many reported standard deviations.
    #[arg(long, default_value_t = COVERAGE)]
    pub coverage: f64,
    /// With --check-against: the largest tip orientation error, rad.
    #[arg(long, default_value_t = ANGLE_TOLERANCE_RAD)]
    pub angle_tolerance_rad: f64,
    /// No line per record (the summary, refused frames and failed checks still print).
    #[arg(long)]
    pub quiet: bool,
}

/// The CSV columns and the check, for `host-sim monitor --help`.
pub const MONITOR_HELP: &str = "\
Reads robot-link frames (link/FORMAT.md): COBS-framed postcard records with a CRC-32, one per
control tick. A refused frame (damaged, truncated, another format version) is skipped, counted and
named on standard error; the stream resynchronises at the next 0x00.

A serial port needs no set-up beyond --baud (8N1, raw). A file or FIFO is read to its end, e.g.
the QEMU e2e image's capture (firmware/test.sh), or `mkfifo link; host-sim monitor --input link`.

CSV columns (one row per record; empty cells where a record has no value): tick, status, reason
(a rejection's: sensor, not-in-turn, disagrees, fault, non-finite, out-of-range, jump), cable,
estimate_tick, force_{x,y,z}_n, force_std_{x,y,z}_n, tip_{x,y,z}_m, tip_std_{x,y,z}_m,
tip_q{w,x,y,z} (tip orientation, w >= 0), sweeps, backbone_points, tensions,
backbone_<i>_{x,y,z}_m for i < 16, tension_<j>_n for j < 12. Numbers as the f32 sent, exactly.

--check-against REF.csv: every frame decoded; the records are the reference's ticks, in order,
each once; each status the reference's `expected`; each estimate this tick's when fresh, else the
last fresh tick's; its tip within --tip-tolerance-m of that tick's reference and within --coverage
of its reported standard deviation, its force within --force-tolerance-n, its tip frame within
--angle-tolerance-rad and each backbone point within --tip-tolerance-m (when the reference has
them). Exit 0 when all pass, 1 when any fails, a frame was refused or the input failed.";

/// What the monitor made of the bytes so far.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A record.
    Record(Box<Record>),
    /// A frame refused, and why.
    Refused(FrameError),
}

/// A byte stream turned into [`Event`]s, with the tally.
#[derive(Debug, Default)]
pub struct Monitor {
    decoder: Decoder,
    /// Records decoded.
    pub records: u64,
    /// Frames refused.
    pub refused: u64,
    /// Bytes read.
    pub bytes: u64,
}

impl Monitor {
    /// A monitor that has read nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes the next bytes of the stream; returns the frames they completed, in order.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Event> {
        let mut events = Vec::new();
        self.bytes += bytes.len() as u64;
        self.decoder.feed(bytes, |result| match result {
            Ok(record) => {
                self.records += 1;
                events.push(Event::Record(Box::new(record)));
            }
            Err(e) => {
                self.refused += 1;
                events.push(Event::Refused(e));
            }
        });
        events
    }

    /// Bytes of an unfinished frame at the end of the stream.
    pub fn pending_bytes(&self) -> usize {
        self.decoder.pending_bytes()
    }
}

fn v3(a: [f32; 3]) -> Vector3<f64> {
    Vector3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2]))
}

/// One line for a record: tick, status, the estimate's tick, force and tip (mm) with their
/// standard deviations, tip orientation, sweeps.
pub fn record_line(record: &Record) -> String {
    let mut line = format!("tick {:6} {:28}", record.tick, record.status.to_string());
    match &record.estimate {
        None => line.push_str(" no estimate yet"),
        Some(e) => {
            let f = e.tip_force_n;
            let fs = e.tip_force_std_n.map(|x| x * 1e3);
            let p = e.tip_position_m.map(|x| x * 1e3);
            let ps = e.tip_position_std_m.map(|x| x * 1e6);
            let q = e.tip_orientation;
            let _ = write!(
                line,
                " estimate@{} force_n [{:+.4} {:+.4} {:+.4}] std_mn [{:.2} {:.2} {:.2}] \
                 tip_mm [{:+.3} {:+.3} {:+.3}] std_um [{:.1} {:.1} {:.1}] \
                 q [{:.4} {:+.4} {:+.4} {:+.4}] sweeps {}",
                e.tick,
                f[0],
                f[1],
                f[2],
                fs[0],
                fs[1],
                fs[2],
                p[0],
                p[1],
                p[2],
                ps[0],
                ps[1],
                ps[2],
                q[0],
                q[1],
                q[2],
                q[3],
                e.sweeps
            );
            if !e.tensions_n.is_empty() {
                let t: Vec<String> = e.tensions_n.iter().map(|x| format!("{x:.3}")).collect();
                let _ = write!(line, " tensions_n [{}]", t.join(" "));
            }
        }
    }
    line
}

/// The CSV header (see [`MONITOR_HELP`]).
pub fn csv_header() -> String {
    let mut columns: Vec<String> = [
        "tick",
        "status",
        "reason",
        "cable",
        "estimate_tick",
        "force_x_n",
        "force_y_n",
        "force_z_n",
        "force_std_x_n",
        "force_std_y_n",
        "force_std_z_n",
        "tip_x_m",
        "tip_y_m",
        "tip_z_m",
        "tip_std_x_m",
        "tip_std_y_m",
        "tip_std_z_m",
        "tip_qw",
        "tip_qx",
        "tip_qy",
        "tip_qz",
        "sweeps",
        "backbone_points",
        "tensions",
    ]
    .map(String::from)
    .to_vec();
    for i in 0..MAX_BACKBONE_POINTS {
        columns.extend(["x", "y", "z"].map(|a| format!("backbone_{i}_{a}_m")));
    }
    columns.extend((0..MAX_TENSIONS).map(|j| format!("tension_{j}_n")));
    columns.join(",")
}

/// A record's CSV row, [`csv_header`]'s columns. Floats in their shortest exact form.
pub fn csv_row(record: &Record) -> String {
    let mut cells = vec![record.tick.to_string(), record.status.name().to_string()];
    match record.status {
        robot_link::Status::Rejected { reason, .. } => cells.push(reason.name().to_string()),
        _ => cells.push(String::new()),
    }
    cells.push(
        record
            .status
            .cable()
            .map_or(String::new(), |c| c.to_string()),
    );
    let number = |x: f32| format!("{x:?}");
    match &record.estimate {
        None => cells.extend(std::iter::repeat_n(String::new(), 20)),
        Some(e) => {
            cells.push(e.tick.to_string());
            let floats = e
                .tip_force_n
                .iter()
                .chain(&e.tip_force_std_n)
                .chain(&e.tip_position_m)
                .chain(&e.tip_position_std_m)
                .chain(&e.tip_orientation);
            cells.extend(floats.map(|x| number(*x)));
            cells.push(e.sweeps.to_string());
            cells.push(e.backbone_m.len().to_string());
            cells.push(e.tensions_n.len().to_string());
        }
    }
    let (points, tensions) = record.estimate.as_ref().map_or((&[][..], &[][..]), |e| {
        (e.backbone_m.as_slice(), e.tensions_n.as_slice())
    });
    for i in 0..MAX_BACKBONE_POINTS {
        match points.get(i) {
            Some(p) => cells.extend(p.map(number)),
            None => cells.extend(std::iter::repeat_n(String::new(), 3)),
        }
    }
    for j in 0..MAX_TENSIONS {
        cells.push(tensions.get(j).map_or(String::new(), |t| number(*t)));
    }
    cells.join(",")
}

/// The plot's figure of a record's estimate: the backbone from the base (at the origin, as the
/// firmware's bench has it) through its points, the tip and its standard deviation; `None`
/// without an estimate.
pub fn figure(record: &Record) -> Option<Figure> {
    let e = record.estimate.as_ref()?;
    let mut backbone_m = vec![Vector3::zeros()];
    backbone_m.extend(e.backbone_m.iter().map(|p| v3(*p)));
    let f = e.tip_force_n;
    Some(Figure {
        title: format!("live link: tick {}", record.tick),
        notes: vec![
            format!("status {}, estimate of tick {}", record.status, e.tick),
            format!("tip force [{:+.4}, {:+.4}, {:+.4}] N", f[0], f[1], f[2]),
        ],
        backbone_m,
        tip_m: Some(v3(e.tip_position_m)),
        tip_std_m: Some(v3(e.tip_position_std_m)),
        ..Figure::default()
    })
}

/// One tick of a reference (a row of `firmware/src/fixture/trajectory.csv`).
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceTick {
    /// The tick.
    pub tick: u32,
    /// The record status expected (`robot_link::Status`'s text, e.g. `fresh`).
    pub expected: String,
    /// The tip force, N.
    pub force_n: Vector3<f64>,
    /// The tip, m.
    pub tip_m: Vector3<f64>,
    /// The tip orientation `[w, x, y, z]`, if the reference has it.
    pub tip_orientation: Option<UnitQuaternion<f64>>,
    /// Backbone points, m (empty if the reference has none).
    pub backbone_m: Vec<Vector3<f64>>,
}

/// The reference a stream is checked against: one row per tick, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// The ticks.
    pub ticks: Vec<ReferenceTick>,
}

impl Reference {
    /// Parses a reference CSV (`#` lines are comments). Columns by name: `tick`, `expected`,
    /// `force_{x,y,z}_n`, `tip_{x,y,z}_m`; optional `tip_q{w,x,y,z}` and
    /// `backbone_<i>_{x,y,z}_m` from `i = 0`. `origin` names the file in errors.
    ///
    /// # Errors
    /// A missing column, a cell that is not a number, no rows, or ticks out of order.
    pub fn parse(text: &str, origin: &str) -> Result<Self, SceneError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim_start().starts_with('#') && !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(SceneError::new(origin, "no header"));
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        let column = |name: &str| names.iter().position(|n| *n == name);
        let need = |name: &str| {
            column(name).ok_or_else(|| SceneError::new(origin, format!("no column \"{name}\"")))
        };
        let axes = |prefix: &str, suffix: &str| -> Result<[usize; 3], SceneError> {
            Ok([
                need(&format!("{prefix}x{suffix}"))?,
                need(&format!("{prefix}y{suffix}"))?,
                need(&format!("{prefix}z{suffix}"))?,
            ])
        };
        let (tick_col, expected_col) = (need("tick")?, need("expected")?);
        let (force_cols, tip_cols) = (axes("force_", "_n")?, axes("tip_", "_m")?);
        let q_cols: Option<Vec<usize>> = ["tip_qw", "tip_qx", "tip_qy", "tip_qz"]
            .iter()
            .map(|n| column(n))
            .collect();
        let mut backbone_cols = Vec::new();
        while column(&format!("backbone_{}_x_m", backbone_cols.len())).is_some() {
            backbone_cols.push(axes(&format!("backbone_{}_", backbone_cols.len()), "_m")?);
        }
        let mut ticks: Vec<ReferenceTick> = Vec::new();
        for (index, line) in lines {
            let at = format!("{origin}:{}", index + 1);
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let cell = |c: usize| {
                cells
                    .get(c)
                    .copied()
                    .ok_or_else(|| SceneError::new(&at, format!("no cell {}", c + 1)))
            };
            let number = |c: usize| -> Result<f64, SceneError> {
                let text = cell(c)?;
                text.parse::<f64>()
                    .map_err(|e| SceneError::new(&at, format!("\"{text}\": {e}")))
            };
            let vector = |cols: [usize; 3]| -> Result<Vector3<f64>, SceneError> {
                Ok(Vector3::new(
                    number(cols[0])?,
                    number(cols[1])?,
                    number(cols[2])?,
                ))
            };
            let tick_text = cell(tick_col)?;
            let tick = tick_text
                .parse::<u32>()
                .map_err(|e| SceneError::new(&at, format!("tick \"{tick_text}\": {e}")))?;
            if ticks.last().is_some_and(|t| t.tick >= tick) {
                return Err(SceneError::new(&at, "ticks must increase"));
            }
            let tip_orientation = match &q_cols {
                Some(c) => {
                    let q = nalgebra::Quaternion::new(
                        number(c[0])?,
                        number(c[1])?,
                        number(c[2])?,
                        number(c[3])?,
                    );
                    Some(UnitQuaternion::from_quaternion(q))
                }
                None => None,
            };
            ticks.push(ReferenceTick {
                tick,
                expected: cell(expected_col)?.to_string(),
                force_n: vector(force_cols)?,
                tip_m: vector(tip_cols)?,
                tip_orientation,
                backbone_m: backbone_cols
                    .iter()
                    .map(|c| vector(*c))
                    .collect::<Result<_, _>>()?,
            });
        }
        if ticks.is_empty() {
            return Err(SceneError::new(origin, "no reference rows"));
        }
        Ok(Self { ticks })
    }
}

/// What a check allows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Largest tip and backbone point error, m.
    pub tip_m: f64,
    /// Largest force error, N.
    pub force_n: f64,
    /// Largest tip error in reported standard deviations (the length of their per-axis vector).
    pub coverage: f64,
    /// Largest angle between the tip frames, rad.
    pub angle_rad: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Self {
            tip_m: TIP_TOLERANCE_M,
            force_n: FORCE_TOLERANCE_N,
            coverage: COVERAGE,
            angle_rad: ANGLE_TOLERANCE_RAD,
        }
    }
}

/// The errors of one record against its reference.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Errors {
    /// Tip error, m.
    pub tip_m: f64,
    /// Tip error over the reported standard deviations' length.
    pub tip_sigma: f64,
    /// Force error, N.
    pub force_n: f64,
    /// Angle between the tip frames, rad (0 without a reference orientation).
    pub angle_rad: f64,
    /// Worst backbone point error, m (0 without reference points).
    pub backbone_m: f64,
}

impl Errors {
    fn worst(self, other: Self) -> Self {
        Self {
            tip_m: self.tip_m.max(other.tip_m),
            tip_sigma: self.tip_sigma.max(other.tip_sigma),
            force_n: self.force_n.max(other.force_n),
            angle_rad: self.angle_rad.max(other.angle_rad),
            backbone_m: self.backbone_m.max(other.backbone_m),
        }
    }
}

/// One record's check.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Reference ticks passed over without a record (a frame lost before this one).
    pub skipped: Vec<u32>,
    /// The record's errors, or why it failed.
    pub result: Result<Errors, Vec<String>>,
}

/// A stream held to a [`Reference`], record by record.
#[derive(Debug, Clone)]
pub struct Checker {
    reference: Reference,
    tolerances: Tolerances,
    /// The next reference row expected.
    next: usize,
    /// The last tick expected fresh so far.
    last_fresh: Option<u32>,
    /// Reference ticks passed over without a record.
    pub skipped: Vec<u32>,
    /// Records that passed.
    pub passed: u64,
    /// Records that failed (unexpected ones included).
    pub failed: u64,
    /// The worst errors of the records checked.
    pub worst: Errors,
}

impl Checker {
    /// A checker at the reference's first tick.
    pub fn new(reference: Reference, tolerances: Tolerances) -> Self {
        Self {
            reference,
            tolerances,
            next: 0,
            last_fresh: None,
            skipped: Vec::new(),
            passed: 0,
            failed: 0,
            worst: Errors::default(),
        }
    }

    /// Checks the next record. Its tick must be one the reference has not passed yet: the ticks
    /// before it with no record are skipped (and counted missing).
    pub fn check(&mut self, record: &Record) -> Verdict {
        let before = self.skipped.len();
        let result = self.judge(record);
        match &result {
            Ok(errors) => {
                self.passed += 1;
                self.worst = self.worst.worst(*errors);
            }
            Err(_) => self.failed += 1,
        }
        Verdict {
            skipped: self.skipped.get(before..).unwrap_or_default().to_vec(),
            result,
        }
    }

    fn judge(&mut self, record: &Record) -> Result<Errors, Vec<String>> {
        let rest = self.reference.ticks.get(self.next..).unwrap_or_default();
        let Some(offset) = rest.iter().position(|t| t.tick == record.tick) else {
            return Err(vec![format!(
                "tick {}: not among the reference's ticks still to come",
                record.tick
            )]);
        };
        for row in rest.get(..=offset).unwrap_or_default() {
            if row.tick != record.tick {
                self.skipped.push(row.tick);
            }
            if row.expected == "fresh" {
                self.last_fresh = Some(row.tick);
            }
        }
        let Some(row) = rest.get(offset).cloned() else {
            return Err(vec![format!("tick {}: not in the reference", record.tick)]);
        };
        self.next += offset + 1;
        let mut why = Vec::new();
        let status = record.status.to_string();
        if status != row.expected {
            why.push(format!("status {status}, expected {}", row.expected));
        }
        let Some(want) = self.last_fresh else {
            return Err(why);
        };
        let Some(e) = &record.estimate else {
            why.push(format!("no estimate, expected tick {want}'s"));
            return Err(why);
        };
        if e.tick != want {
            why.push(format!(
                "the estimate of tick {}, expected tick {want}'s",
                e.tick
            ));
        }
        let Some(truth) = self.reference.ticks.iter().find(|t| t.tick == e.tick) else {
            why.push(format!(
                "the estimate's tick {} is not in the reference",
                e.tick
            ));
            return Err(why);
        };
        let t = self.tolerances;
        let tip_m = (v3(e.tip_position_m) - truth.tip_m).norm();
        let std_m = v3(e.tip_position_std_m).norm();
        let mut errors = Errors {
            tip_m,
            tip_sigma: tip_m / std_m,
            force_n: (v3(e.tip_force_n) - truth.force_n).norm(),
            ..Errors::default()
        };
        if !within(tip_m, t.tip_m) {
            why.push(format!(
                "tip {:.1} um off (limit {:.1})",
                tip_m * 1e6,
                t.tip_m * 1e6
            ));
        }
        if !within(tip_m, t.coverage * std_m) {
            why.push(format!(
                "tip {:.1} um off, {:.1} of its standard deviations (limit {})",
                tip_m * 1e6,
                errors.tip_sigma,
                t.coverage
            ));
        }
        if !within(errors.force_n, t.force_n) {
            why.push(format!(
                "force {:.2} mN off (limit {:.2})",
                errors.force_n * 1e3,
                t.force_n * 1e3
            ));
        }
        if let Some(q_ref) = truth.tip_orientation {
            let [w, x, y, z] = e.tip_orientation.map(f64::from);
            let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
            errors.angle_rad = q.angle_to(&q_ref);
            if !within(errors.angle_rad, t.angle_rad) {
                why.push(format!(
                    "tip frame {:.3} mrad off (limit {:.3})",
                    errors.angle_rad * 1e3,
                    t.angle_rad * 1e3
                ));
            }
        }
        if !truth.backbone_m.is_empty() {
            if e.backbone_m.len() == truth.backbone_m.len() {
                errors.backbone_m = e
                    .backbone_m
                    .iter()
                    .zip(&truth.backbone_m)
                    .map(|(p, r)| (v3(*p) - r).norm())
                    .fold(0.0, f64::max);
                if !within(errors.backbone_m, t.tip_m) {
                    why.push(format!(
                        "a backbone point {:.1} um off (limit {:.1})",
                        errors.backbone_m * 1e6,
                        t.tip_m * 1e6
                    ));
                }
            } else {
                why.push(format!(
                    "{} backbone points, the reference has {}",
                    e.backbone_m.len(),
                    truth.backbone_m.len()
                ));
            }
        }
        if why.is_empty() { Ok(errors) } else { Err(why) }
    }

    /// Reference ticks without a record: skipped ones, and those after the last record.
    pub fn missing(&self) -> usize {
        self.skipped.len() + self.reference.ticks.len().saturating_sub(self.next)
    }

    /// Whether the stream passed: every reference tick reached, every record passed, and
    /// `refused` frames none.
    pub fn passed_with(&self, refused: u64) -> bool {
        self.failed == 0 && self.missing() == 0 && refused == 0 && self.passed > 0
    }
}

/// The byte source.
fn open_input(args: &Args) -> Result<Box<dyn Read>, SceneError> {
    if let Some(port) = &args.serial {
        let port = serialport::new(port, args.baud)
            .timeout(Duration::from_millis(200))
            .open()
            .map_err(|e| SceneError::new(port.as_str(), format!("cannot open: {e}")))?;
        return Ok(Box::new(port));
    }
    match args.input.as_deref() {
        Some(path) if path == Path::new("-") => Ok(Box::new(io::stdin())),
        Some(path) => std::fs::File::open(path)
            .map(|f| Box::new(f) as Box<dyn Read>)
            .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot open: {e}"))),
        None => Err(SceneError::new("--input", "give --input or --serial")),
    }
}

/// Draws `figure` into `path` through a temporary file beside it, so that a viewer never reads
/// half a plot.
fn draw(figure: &Figure, path: &Path, size: PlotSize) -> Result<(), SceneError> {
    let name = path
        .file_name()
        .map_or("plot".into(), |n| n.to_string_lossy());
    let extension = path
        .extension()
        .map_or("svg".into(), |e| e.to_string_lossy());
    let partial = path.with_file_name(format!(".{name}.partial.{extension}"));
    draw_figure(figure, &partial, size)?;
    std::fs::rename(&partial, path)
        .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}")))
}

/// `host-sim monitor`: runs [`Args`] and prints as it goes; the exit code says how it ended.
pub fn main(args: &Args) -> ExitCode {
    match run(args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Reads the stream to its end (or `--count` records); whether the check (if any) passed.
///
/// # Errors
/// An input, output or reference that cannot be opened, read or written.
pub fn run(args: &Args) -> Result<bool, SceneError> {
    let mut checker = match &args.check_against {
        Some(path) => {
            let origin = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .map_err(|e| SceneError::new(&origin, format!("cannot read: {e}")))?;
            let tolerances = Tolerances {
                tip_m: args.tip_tolerance_m,
                force_n: args.force_tolerance_n,
                coverage: args.coverage,
                angle_rad: args.angle_tolerance_rad,
            };
            Some(Checker::new(Reference::parse(&text, &origin)?, tolerances))
        }
        None => None,
    };
    let mut csv = match &args.csv {
        Some(path) => {
            let file = std::fs::File::create(path).map_err(|e| {
                SceneError::new(path.display().to_string(), format!("cannot write: {e}"))
            })?;
            let mut w = BufWriter::new(file);
            writeln!(w, "{}", csv_header()).map_err(|e| io_error(path, &e))?;
            Some((w, path.clone()))
        }
        None => None,
    };
    let mut input = open_input(args)?;
    let mut monitor = Monitor::new();
    let mut stdout = io::stdout().lock();
    let mut latest: Option<Figure> = None;
    let mut drawn_at: Option<Instant> = None;
    let mut buf = [0u8; 4096];
    // Records and refused frames handled (with --count, a read may decode more than are handled).
    let (mut records, mut refused) = (0u64, 0u64);
    'read: loop {
        let n = match input.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            // A serial port's timeout: nothing arrived yet.
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
                ) =>
            {
                continue;
            }
            Err(e) => return Err(SceneError::new("input", format!("cannot read: {e}"))),
        };
        for event in monitor.feed(&buf[..n]) {
            let record = match event {
                Event::Refused(e) => {
                    refused += 1;
                    eprintln!("frame refused: {e}");
                    continue;
                }
                Event::Record(record) => record,
            };
            records += 1;
            let mut line = if args.quiet {
                String::new()
            } else {
                record_line(&record)
            };
            if let Some(checker) = checker.as_mut() {
                let verdict = checker.check(&record);
                for tick in verdict.skipped {
                    let _ = writeln!(stdout, "tick {tick} check FAIL: no record");
                }
                match verdict.result {
                    Ok(_) if !args.quiet => line.push_str(" check pass"),
                    Ok(_) => {}
                    Err(why) => {
                        if args.quiet {
                            line = format!("tick {}", record.tick);
                        }
                        let _ = write!(line, " check FAIL: {}", why.join("; "));
                    }
                }
            }
            if !line.is_empty() {
                // A closed standard output (`| head`) ends the listing, not the run.
                let _ = writeln!(stdout, "{line}");
            }
            if let Some((w, path)) = csv.as_mut() {
                writeln!(w, "{}", csv_row(&record))
                    .and_then(|()| w.flush())
                    .map_err(|e| io_error(path, &e))?;
            }
            if let Some(f) = figure(&record) {
                latest = Some(f);
            }
            if let (Some(path), Some(f)) = (&args.plot, &latest)
                && drawn_at.is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
            {
                draw(f, path, args.plot_size)?;
                drawn_at = Some(Instant::now());
            }
            if args.count.is_some_and(|c| records >= c) {
                break 'read;
            }
        }
    }
    if let (Some(path), Some(f)) = (&args.plot, &latest) {
        draw(f, path, args.plot_size)?;
    }
    let mut summary = format!(
        "monitor: {records} records, {refused} frames refused, {} bytes read",
        monitor.bytes
    );
    if args.count.is_none() && monitor.pending_bytes() > 0 {
        let _ = write!(
            summary,
            ", {} bytes of an unfinished frame at the end",
            monitor.pending_bytes()
        );
    }
    let _ = writeln!(stdout, "{summary}");
    let Some(checker) = checker else {
        return Ok(true);
    };
    let w = checker.worst;
    let passed = checker.passed_with(refused);
    let _ = writeln!(
        stdout,
        "monitor check: {} passed, {} failed, {} reference ticks without a record, {} frames refused; \
         worst tip error {:.1} um ({:.2} sigma), force {:.3} mN, tip frame {:.4} mrad, \
         backbone {:.1} um: {}",
        checker.passed,
        checker.failed,
        checker.missing(),
        refused,
        w.tip_m * 1e6,
        w.tip_sigma,
        w.force_n * 1e3,
        w.angle_rad * 1e3,
        w.backbone_m * 1e6,
        if passed { "PASS" } else { "FAIL" }
    );
    Ok(passed)
}

/// `error <= limit`, false for NaN.
fn within(error: f64, limit: f64) -> bool {
    error <= limit
}

fn io_error(path: &Path, e: &io::Error) -> SceneError {
    SceneError::new(path.display().to_string(), format!("cannot write: {e}"))
}
