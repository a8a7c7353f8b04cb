//! `host-sim monitor`: reads the live link's records (robot-link frames, `link/FORMAT.md`) from a
//! serial port, a file, a FIFO or standard input; prints one line per record, writes them to CSV,
//! draws the latest shape, and checks them against an f64 reference.
//!
//! The pieces are public so that tests run the same code: [`Monitor`] takes bytes and hands out
//! [`Event`]s (`stream.rs`), [`record_line`] and [`csv_row`] format a record and [`figure`] turns
//! it into the plot's figure (`format.rs`), [`Reference`] and [`Checker`] hold a stream to a
//! reference tick by tick (`check.rs`); `host-sim reference` makes a reference from a scene
//! (`reference.rs`). This file is the command.

use std::fmt::Write as _;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use crate::plots::{Figure, PlotFormat, PlotSize, draw_figure, ensure_font};
use crate::scene::SceneError;

mod check;
mod format;
pub mod reference;
mod stream;
mod table;

pub use check::*;
pub use format::*;
pub use stream::*;

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
    /// Stop after this many records (at least 1).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
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
    // A bad --plot path fails before anything is read, not at the first record.
    if let Some(path) = &args.plot {
        PlotFormat::of(path)?;
        ensure_font()?;
    }
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
         worst of the passing records: tip error {:.1} um ({:.2} sigma), force {:.3} mN, tip \
         frame {:.4} mrad, \
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

fn io_error(path: &Path, e: &io::Error) -> SceneError {
    SceneError::new(path.display().to_string(), format!("cannot write: {e}"))
}
