//! Calibration data: a CSV of observed backbone points, one row per observation, grouped by an
//! `experiment` id into loadings (`host-sim/SCENES.md`, "Calibration data"; [`DATA_HELP`]).
//!
//! Columns are found by name, in any order; lines starting with `#` are comments and blank lines are
//! skipped. Every refusal names the file's line and the column: `data.csv, line 7, column y_m:
//! "abc" is not a number`.

use std::collections::HashMap;

use crate::scene::{Control, SceneError};

/// The CSV format in a few lines (`host-sim calibrate --help`; SCENES.md says it at length).
pub const DATA_HELP: &str = "\
Calibration data (--data, CSV; host-sim/SCENES.md \"Calibration data\"): one row per observed
point. Plain comma-separated cells, no quoting; the first line that is neither blank nor a
comment (#) is the header; columns by name, in any order. SI units; vectors in the measurement
frame.
  experiment                 required: an id; rows with the same id are one loading
  x_m, y_m, z_m              required: the observed point, m
  s_m                        the arc length observed, m (empty or \"tip\": the tip; no column:
                             every row is the tip)
  tip_mass_kg                a mass hung at the tip, kg (its weight along the scene's gravity)
  tip_force_x_n, _y_n, _z_n  a force at the tip, N
  tension_<j>_n              tendon scenes: tendon j's tension, N (j from 0, one per [[tendon]])
  displacement_<j>_m         or its spool's displacement, m (not both kinds in one file); without
                             either the scene's [actuation] holds for every experiment
  weight                     relative weight of the row's squared residual (default 1)
Load and actuation cells may be left empty on all but one row of an experiment; a loading given
twice must agree. An absent or empty load is 0. The scene's [tip] is not used.";

/// One observed point.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// The line of the file it is on (from 1).
    pub line: usize,
    /// The arc length observed, m (the tip's when the row says `tip` or leaves it empty).
    pub s_m: f64,
    /// Whether the row named the tip (an empty or `tip` cell, or no `s_m` column).
    pub at_tip: bool,
    /// The observed point, m, measurement frame.
    pub position_m: [f64; 3],
    /// Relative weight of its squared residual (positive).
    pub weight: f64,
}

/// How one experiment actuates the tendons (tendon scenes).
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentActuation {
    /// Tensions or spool displacements.
    pub control: Control,
    /// One value per tendon: N for tensions, m for displacements.
    pub values: Vec<f64>,
}

/// One loading and the points observed under it.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// Its id, as written.
    pub id: String,
    /// The line of its first row.
    pub line: usize,
    /// The mass hung at the tip, kg.
    pub tip_mass_kg: f64,
    /// The force at the tip, N, measurement frame.
    pub tip_force_n: [f64; 3],
    /// The tendons' actuation from the file (`None`: the scene's `[actuation]`, or no tendons).
    pub actuation: Option<ExperimentActuation>,
    /// The points observed, in the order of the file.
    pub observations: Vec<Observation>,
}

/// A whole data file.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurements {
    /// Where it came from (named in errors and reports).
    pub origin: String,
    /// The experiments, in the order of their first rows.
    pub experiments: Vec<Experiment>,
}

impl Measurements {
    /// Every observation, experiment by experiment.
    pub fn observations(&self) -> impl Iterator<Item = (&Experiment, &Observation)> {
        self.experiments
            .iter()
            .flat_map(|e| e.observations.iter().map(move |o| (e, o)))
    }

    /// How many points are observed.
    pub fn observation_count(&self) -> usize {
        self.experiments.iter().map(|e| e.observations.len()).sum()
    }
}

/// What the data are checked against: the scene's tendon count and length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataShape {
    /// The scene's `[[tendon]]` tables.
    pub tendons: usize,
    /// The rod's length, m (the tip's arc length).
    pub length_m: f64,
}

/// A column the format knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Column {
    Experiment,
    TipMass,
    TipForce(usize),
    Tension(usize),
    Displacement(usize),
    S,
    Position(usize),
    Weight,
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Column {
    /// The column `name` means, or why it is refused.
    fn of(name: &str, tendons: usize) -> Result<Self, String> {
        let simple = match name {
            "experiment" => Some(Self::Experiment),
            "tip_mass_kg" => Some(Self::TipMass),
            "s_m" => Some(Self::S),
            "weight" => Some(Self::Weight),
            _ => None,
        };
        if let Some(c) = simple {
            return Ok(c);
        }
        for (k, axis) in AXES.iter().enumerate() {
            if name == format!("{axis}_m") {
                return Ok(Self::Position(k));
            }
            if name == format!("tip_force_{axis}_n") {
                return Ok(Self::TipForce(k));
            }
        }
        let indexed = |prefix: &str, suffix: &str| {
            name.strip_prefix(prefix)
                .and_then(|r| r.strip_suffix(suffix))
                .map(|j| j.parse::<usize>().ok())
        };
        for (prefix, suffix, make) in [
            ("tension_", "_n", Self::Tension as fn(usize) -> Self),
            ("displacement_", "_m", Self::Displacement),
        ] {
            match indexed(prefix, suffix) {
                None => {}
                Some(None) => {
                    return Err(format!(
                        "\"{name}\": the tendon index must be a whole number from 0 \
                         ({prefix}0{suffix})"
                    ));
                }
                Some(Some(_)) if tendons == 0 => {
                    return Err(format!(
                        "\"{name}\": the scene has no [[tendon]] to actuate"
                    ));
                }
                Some(Some(j)) if j >= tendons => {
                    return Err(format!(
                        "\"{name}\": tendon {j} is beyond the scene's {tendons} [[tendon]] \
                         tables ({prefix}0{suffix} to {prefix}{}{suffix})",
                        tendons - 1
                    ));
                }
                Some(Some(j)) => return Ok(make(j)),
            }
        }
        Err(format!(
            "unknown column \"{name}\" (expected experiment, x_m, y_m, z_m and optionally s_m, \
             tip_mass_kg, tip_force_x_n, tip_force_y_n, tip_force_z_n, tension_<j>_n or \
             displacement_<j>_m, weight)"
        ))
    }

    fn is_loading(self) -> bool {
        matches!(
            self,
            Self::TipMass | Self::TipForce(_) | Self::Tension(_) | Self::Displacement(_)
        )
    }
}

/// `origin, line N, column NAME`.
fn at(origin: &str, line: usize, column: &str) -> String {
    format!("{origin}, line {line}, column {column}")
}

/// A cell as a finite number.
fn number(cell: &str, place: &str) -> Result<f64, SceneError> {
    let x: f64 = cell
        .parse()
        .map_err(|_| SceneError::new(place, format!("\"{cell}\" is not a number")))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(SceneError::new(
            place,
            format!("\"{cell}\" is not a finite number"),
        ))
    }
}

/// One data row, split and with its line.
struct Row<'a> {
    line: usize,
    cells: Vec<&'a str>,
}

/// The loading cells of one experiment, gathered over its rows: for each loading column, the value
/// and the line that gave it first.
type Loading = HashMap<Column, (f64, usize)>;

impl Measurements {
    /// Parses the CSV `text` (`origin` names it in errors), checking it against the scene (`shape`).
    pub fn parse(text: &str, origin: &str, shape: DataShape) -> Result<Self, SceneError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let Some((header_line, header)) = lines.next() else {
            return Err(SceneError::new(
                origin,
                "no header: the first line that is not blank or a comment names the columns \
                 (experiment, x_m, y_m, z_m, ...)",
            ));
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        let mut columns = Vec::with_capacity(names.len());
        for name in &names {
            let place = at(origin, header_line, name);
            let column = Column::of(name, shape.tendons).map_err(|e| SceneError::new(&place, e))?;
            if columns.contains(&column) {
                return Err(SceneError::new(place, "the column is given twice"));
            }
            columns.push(column);
        }
        let has = |c: Column| columns.contains(&c);
        for (column, name) in [
            (Column::Experiment, "experiment"),
            (Column::Position(0), "x_m"),
            (Column::Position(1), "y_m"),
            (Column::Position(2), "z_m"),
        ] {
            if !has(column) {
                return Err(SceneError::new(
                    at(origin, header_line, name),
                    format!("missing column \"{name}\" (the header names every column)"),
                ));
            }
        }
        let control = check_actuation_columns(&columns, shape.tendons)
            .map_err(|(name, e)| SceneError::new(at(origin, header_line, &name), e))?;

        let rows: Vec<Row<'_>> = lines
            .map(|(line, l)| Row {
                line,
                cells: l.split(',').map(str::trim).collect(),
            })
            .collect();
        let mut experiments: Vec<Experiment> = Vec::new();
        let mut loadings: Vec<Loading> = Vec::new();
        for row in &rows {
            if row.cells.len() != names.len() {
                return Err(SceneError::new(
                    format!("{origin}, line {}", row.line),
                    format!(
                        "{} cells, but the header (line {header_line}) names {} columns",
                        row.cells.len(),
                        names.len()
                    ),
                ));
            }
            let mut id = "";
            let mut position = [0.0; 3];
            let mut s = None;
            let mut weight = 1.0;
            let mut given: Vec<(Column, f64, &str)> = Vec::new();
            for ((&column, &name), &cell) in columns.iter().zip(&names).zip(&row.cells) {
                let place = at(origin, row.line, name);
                match column {
                    Column::Experiment => {
                        if cell.is_empty() {
                            return Err(SceneError::new(
                                place,
                                "empty: every row names its experiment",
                            ));
                        }
                        id = cell;
                    }
                    Column::Position(k) => {
                        if cell.is_empty() {
                            return Err(SceneError::new(place, "empty: the point is required"));
                        }
                        if let Some(p) = position.get_mut(k) {
                            *p = number(cell, &place)?;
                        }
                    }
                    // An empty `s_m` or `tip` is the tip; an empty weight is 1.
                    Column::S if !(cell.is_empty() || cell.eq_ignore_ascii_case("tip")) => {
                        let x = number(cell, &place)?;
                        if !(0.0..=shape.length_m).contains(&x) {
                            return Err(SceneError::new(
                                place,
                                format!(
                                    "{x} m is not on the rod (0 to its tip, {} m)",
                                    shape.length_m
                                ),
                            ));
                        }
                        s = Some(x);
                    }
                    Column::Weight if !cell.is_empty() => {
                        let w = number(cell, &place)?;
                        if w <= 0.0 {
                            return Err(SceneError::new(
                                place,
                                format!("{w}: a weight must be positive"),
                            ));
                        }
                        weight = w;
                    }
                    c if c.is_loading() && !cell.is_empty() => {
                        let x = number(cell, &place)?;
                        match c {
                            Column::TipMass | Column::Tension(_) if x < 0.0 => {
                                return Err(SceneError::new(
                                    place,
                                    format!("{x}: must not be negative"),
                                ));
                            }
                            _ => {}
                        }
                        given.push((c, x, name));
                    }
                    _ => {}
                }
            }
            let index = match experiments.iter().position(|e| e.id == id) {
                Some(i) => i,
                None => {
                    experiments.push(Experiment {
                        id: id.to_string(),
                        line: row.line,
                        tip_mass_kg: 0.0,
                        tip_force_n: [0.0; 3],
                        actuation: None,
                        observations: Vec::new(),
                    });
                    loadings.push(Loading::new());
                    experiments.len() - 1
                }
            };
            if let Some(loading) = loadings.get_mut(index) {
                for (column, x, name) in given {
                    match loading.get(&column) {
                        Some(&(first, line)) if first != x => {
                            return Err(SceneError::new(
                                at(origin, row.line, name),
                                format!(
                                    "{x}, but line {line} gives {first} for experiment \"{id}\": \
                                     one loading per experiment (leave the cell empty or repeat \
                                     the value)"
                                ),
                            ));
                        }
                        Some(_) => {}
                        None => {
                            loading.insert(column, (x, row.line));
                        }
                    }
                }
            }
            if let Some(e) = experiments.get_mut(index) {
                e.observations.push(Observation {
                    line: row.line,
                    s_m: s.unwrap_or(shape.length_m),
                    at_tip: s.is_none(),
                    position_m: position,
                    weight,
                });
            }
        }
        if experiments.is_empty() {
            return Err(SceneError::new(
                format!("{origin}, line {header_line}"),
                "no observations after the header",
            ));
        }
        for (e, loading) in experiments.iter_mut().zip(&loadings) {
            let value = |c: Column| loading.get(&c).map(|v| v.0);
            e.tip_mass_kg = value(Column::TipMass).unwrap_or(0.0);
            e.tip_force_n = [0, 1, 2].map(|k| value(Column::TipForce(k)).unwrap_or(0.0));
            if let Some((control, make, prefix, suffix)) = control {
                let mut values = Vec::with_capacity(shape.tendons);
                for j in 0..shape.tendons {
                    let v = value(make(j)).ok_or_else(|| {
                        SceneError::new(
                            at(origin, e.line, &format!("{prefix}{j}{suffix}")),
                            format!(
                                "experiment \"{}\" gives no value on any of its rows (one per \
                                 experiment)",
                                e.id
                            ),
                        )
                    })?;
                    values.push(v);
                }
                e.actuation = Some(ExperimentActuation { control, values });
            }
        }
        Ok(Self {
            origin: origin.to_string(),
            experiments,
        })
    }
}

/// What makes an actuation column, its name's prefix and suffix.
type ActuationColumns = (Control, fn(usize) -> Column, &'static str, &'static str);

/// The actuation the header gives: none, or one column of one kind per tendon. Errors name the
/// column.
fn check_actuation_columns(
    columns: &[Column],
    tendons: usize,
) -> Result<Option<ActuationColumns>, (String, String)> {
    let tensions = columns.iter().any(|c| matches!(c, Column::Tension(_)));
    let displacements = columns.iter().any(|c| matches!(c, Column::Displacement(_)));
    let kind: ActuationColumns = match (tensions, displacements) {
        (false, false) => return Ok(None),
        (true, true) => {
            return Err((
                "displacement_0_m".into(),
                "tension and displacement columns together: give one kind (force or \
                 displacement control) for every experiment"
                    .into(),
            ));
        }
        (true, false) => (Control::Tensions, Column::Tension, "tension_", "_n"),
        (false, true) => (
            Control::Displacements,
            Column::Displacement,
            "displacement_",
            "_m",
        ),
    };
    for j in 0..tendons {
        if !columns.contains(&(kind.1)(j)) {
            let name = format!("{}{j}{}", kind.2, kind.3);
            return Err((
                name.clone(),
                format!(
                    "missing column \"{name}\": one {} column per [[tendon]] ({tendons})",
                    kind.2.trim_end_matches('_')
                ),
            ));
        }
    }
    Ok(Some(kind))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHAPE: DataShape = DataShape {
        tendons: 2,
        length_m: 0.3,
    };

    #[test]
    fn rows_group_into_experiments_with_their_loading() {
        let text = "# a comment\n\
            experiment, s_m, x_m, y_m, z_m, tension_1_n, tension_0_n, weight\n\
            a, 0.1, 0.1, 0, 0, 1.5, 2, \n\
            b, tip, 0.3, 0.01, 0, 0, 0, 2\n\
            \n\
            a, , 0.29, -0.02, 0, , , \n";
        let m = Measurements::parse(text, "d.csv", SHAPE).expect("parses");
        assert_eq!(m.experiments.len(), 2);
        let a = &m.experiments[0];
        assert_eq!(a.id, "a");
        assert_eq!(
            a.actuation,
            Some(ExperimentActuation {
                control: Control::Tensions,
                values: vec![2.0, 1.5]
            })
        );
        assert_eq!(a.observations.len(), 2);
        assert_eq!(a.observations[1].line, 6);
        assert_eq!(a.observations[1].s_m, 0.3);
        assert!(a.observations[1].at_tip);
        assert_eq!(m.experiments[1].observations[0].weight, 2.0);
        assert_eq!(m.observation_count(), 3);
    }

    #[test]
    fn refusals_name_the_line_and_the_column() {
        let cases = [
            ("experiment,x_m,y_m\na,1,2\n", "line 1, column z_m"),
            ("experiment,x_m,y_m,z_m\na,1,abc,0\n", "line 2, column y_m"),
            (
                "experiment,x_m,y_m,z_m,tension_0_n,tension_1_n,tension_2_n\n",
                "line 1, column tension_2_n",
            ),
            ("experiment,x_m,y_m,z_m,tension_0_n\n", "column tension_1_n"),
            (
                "experiment,x_m,y_m,z_m,tip_mass_kg\na,1,0,0,0.1\na,1,0,0,0.2\n",
                "line 3, column tip_mass_kg",
            ),
            (
                "experiment,s_m,x_m,y_m,z_m\na,0.5,1,0,0\n",
                "line 2, column s_m",
            ),
            ("experiment,x_m,y_m,z_m,wieght\n", "column wieght"),
            ("experiment,x_m,y_m,z_m\n#\na,1,0\n", "line 3"),
        ];
        for (text, place) in cases {
            let e = Measurements::parse(text, "d.csv", SHAPE).expect_err(text);
            assert!(e.field.contains(place), "{text}: {e}");
        }
    }
}
