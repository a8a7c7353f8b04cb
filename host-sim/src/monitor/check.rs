//! A stream held to an f64 reference tick by tick, with the tolerances it must meet.

use nalgebra::{UnitQuaternion, Vector3};
use robot_link::Record;

use crate::scene::SceneError;

use super::format::v3;
use super::table::Table;

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
        let table = Table::parse(text, origin)?;
        let (tick_col, expected_col) = (table.need("tick")?, table.need("expected")?);
        let (force_cols, tip_cols) = (table.axes("force_", "_n")?, table.axes("tip_", "_m")?);
        let q_cols: Option<Vec<usize>> = ["tip_qw", "tip_qx", "tip_qy", "tip_qz"]
            .iter()
            .map(|n| table.column(n))
            .collect();
        let mut backbone_cols = Vec::new();
        while table
            .column(&format!("backbone_{}_x_m", backbone_cols.len()))
            .is_some()
        {
            backbone_cols.push(table.axes(&format!("backbone_{}_", backbone_cols.len()), "_m")?);
        }
        let mut ticks: Vec<ReferenceTick> = Vec::new();
        for row in table.rows() {
            let tick = row.tick(tick_col, ticks.last().map(|t| t.tick))?;
            let tip_orientation = match &q_cols {
                Some(c) => {
                    let q = nalgebra::Quaternion::new(
                        row.number(c[0])?,
                        row.number(c[1])?,
                        row.number(c[2])?,
                        row.number(c[3])?,
                    );
                    Some(UnitQuaternion::from_quaternion(q))
                }
                None => None,
            };
            ticks.push(ReferenceTick {
                tick,
                expected: row.cell(expected_col)?.to_string(),
                force_n: row.vector(force_cols)?,
                tip_m: row.vector(tip_cols)?,
                tip_orientation,
                backbone_m: backbone_cols
                    .iter()
                    .map(|c| row.vector(*c))
                    .collect::<Result<_, _>>()?,
            });
        }
        if ticks.is_empty() {
            return Err(table.error("no reference rows"));
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
                    // A NaN point is the worst, not skipped (`f64::max` would drop it).
                    .fold(
                        0.0,
                        |worst, x| if x.is_nan() || x > worst { x } else { worst },
                    );
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

/// `error <= limit`, false for NaN.
fn within(error: f64, limit: f64) -> bool {
    error <= limit
}
