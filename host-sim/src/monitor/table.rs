//! The CSV tables around the monitor (a reference, a load path): a header of column names, then
//! rows of comma-separated cells; `#` lines and blank lines are skipped. Every refusal names the
//! file, and the line for a cell.

use nalgebra::Vector3;

use crate::scene::SceneError;

/// A table's header and its rows, each with its line (from 1).
pub(crate) struct Table<'a> {
    origin: &'a str,
    names: Vec<&'a str>,
    rows: Vec<(usize, &'a str)>,
}

/// One row: where it is (`file:line`) and its cells.
pub(crate) struct Row<'a> {
    at: String,
    cells: Vec<&'a str>,
}

impl<'a> Table<'a> {
    /// The table in `text`, named `origin` in errors.
    ///
    /// # Errors
    /// No header.
    pub(crate) fn parse(text: &'a str, origin: &'a str) -> Result<Self, SceneError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim_start().starts_with('#') && !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(SceneError::new(origin, "no header"));
        };
        Ok(Self {
            origin,
            names: header.split(',').map(str::trim).collect(),
            rows: lines.map(|(i, l)| (i + 1, l)).collect(),
        })
    }

    /// The column named `name`, if the header has it.
    pub(crate) fn column(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| *n == name)
    }

    /// The column named `name`.
    ///
    /// # Errors
    /// The header does not have it.
    pub(crate) fn need(&self, name: &str) -> Result<usize, SceneError> {
        self.column(name)
            .ok_or_else(|| SceneError::new(self.origin, format!("no column \"{name}\"")))
    }

    /// The columns `{prefix}x{suffix}`, `{prefix}y{suffix}`, `{prefix}z{suffix}`.
    ///
    /// # Errors
    /// The header lacks one.
    pub(crate) fn axes(&self, prefix: &str, suffix: &str) -> Result<[usize; 3], SceneError> {
        Ok([
            self.need(&format!("{prefix}x{suffix}"))?,
            self.need(&format!("{prefix}y{suffix}"))?,
            self.need(&format!("{prefix}z{suffix}"))?,
        ])
    }

    /// The rows, in order.
    pub(crate) fn rows(&self) -> impl Iterator<Item = Row<'a>> + '_ {
        self.rows.iter().map(|(line, text)| Row {
            at: format!("{}:{line}", self.origin),
            cells: text.split(',').map(str::trim).collect(),
        })
    }

    /// An error about the whole table (`no rows`).
    pub(crate) fn error(&self, reason: &str) -> SceneError {
        SceneError::new(self.origin, reason)
    }
}

impl Row<'_> {
    /// The text of cell `c`.
    ///
    /// # Errors
    /// The row is shorter.
    pub(crate) fn cell(&self, c: usize) -> Result<&str, SceneError> {
        self.cells
            .get(c)
            .copied()
            .ok_or_else(|| SceneError::new(&self.at, format!("no cell {}", c + 1)))
    }

    /// Cell `c` as a finite number.
    ///
    /// # Errors
    /// Missing, or not a finite number.
    pub(crate) fn number(&self, c: usize) -> Result<f64, SceneError> {
        let text = self.cell(c)?;
        text.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| SceneError::new(&self.at, format!("\"{text}\": not a finite number")))
    }

    /// Three cells as a vector.
    ///
    /// # Errors
    /// As [`Row::number`].
    pub(crate) fn vector(&self, cols: [usize; 3]) -> Result<Vector3<f64>, SceneError> {
        Ok(Vector3::new(
            self.number(cols[0])?,
            self.number(cols[1])?,
            self.number(cols[2])?,
        ))
    }

    /// Cell `c` as a tick, later than `previous`.
    ///
    /// # Errors
    /// Not a whole number from 0 to 2^32 - 1, or not after `previous`.
    pub(crate) fn tick(&self, c: usize, previous: Option<u32>) -> Result<u32, SceneError> {
        let text = self.cell(c)?;
        let tick = text
            .parse::<u32>()
            .map_err(|e| SceneError::new(&self.at, format!("tick \"{text}\": {e}")))?;
        if previous.is_some_and(|p| p >= tick) {
            return Err(SceneError::new(&self.at, "ticks must increase"));
        }
        Ok(tick)
    }
}
