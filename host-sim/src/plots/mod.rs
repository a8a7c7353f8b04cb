//! Figures, sized for a paper: the figure of one answer of `solve`, `estimate` or `calibrate`
//! (`--plot`, [`draw_figure`]: the backbone in three orthogonal projections with the guides, the
//! tendons' and cables' paths, observed points and an estimate's tip ellipse), and the thesis's
//! experiments (`validate --plots`, [`draw_validation`]).
//!
//! Every figure is drawn once, as SVG (plotters), in points at [`UNITS_PER_PT`] SVG units a point,
//! with its physical size in inches ([`PlotSize`]: one column or two), so fonts and lines keep their
//! sizes in print. The PNG is that SVG rasterised by resvg at 300 dpi (`raster.rs`): anti-aliased
//! lines and text, and the same drawing as the SVG.
//!
//! Text is drawn with a TrueType font read at run time (DejaVu Sans from Debian's `fonts-dejavu-core`,
//! or the first `.ttf` found under `/usr/share/fonts`), so no font is committed and no system
//! font library is linked.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::scene::SceneError;

mod figure;
mod raster;
mod validation;

pub use figure::{ELLIPSE_RGB, Figure, OBSERVED_RGB, TendonPath, draw_figure, tendon_rgb};
pub use raster::{PNG_DPI, PNG_PIXELS_PER_METRE};
pub use validation::draw_validation;

/// The family name plot text is drawn in, once [`ensure_font`] has registered it.
pub const FONT: &str = "sans-serif";

/// SVG units a typographic point (1/72 inch): fine enough that a curve's points are not rounded
/// to a visible grid (plotters draws in whole units).
pub const UNITS_PER_PT: f64 = 4.0;

/// A length in points as SVG units.
fn pt(points: f64) -> i32 {
    (points * UNITS_PER_PT).round() as i32
}

/// A size in points as SVG units.
fn upt(points: f64) -> u32 {
    pt(points).unsigned_abs()
}

/// plotters sizes text by its line height, 1.24 em: its SVG's `font-size` is the size over that.
const PLOTTERS_LINE_PER_EM: f64 = 1.24;

/// A font whose em is at least `points`, as plotters takes it (whole units: its tick labels
/// truncate the size).
fn font(points: f64) -> (&'static str, f64) {
    (FONT, (points * PLOTTERS_LINE_PER_EM * UNITS_PER_PT).ceil())
}

/// Text sizes, points: what reads in print at a figure's final size.
const TICK_PT: f64 = 7.0;
const LABEL_PT: f64 = 8.0;
const LEGEND_PT: f64 = 7.0;

/// How wide a figure is printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum PlotSize {
    /// One column of a two-column paper: 3.5 inches.
    Column,
    /// The full text width of a two-column paper (two columns): 7.16 inches.
    #[default]
    Page,
}

impl PlotSize {
    /// The width, inches.
    pub fn width_in(self) -> f64 {
        match self {
            Self::Column => 3.5,
            Self::Page => 7.16,
        }
    }
}

fn font_paths() -> Vec<PathBuf> {
    let mut paths = vec![PathBuf::from(
        "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    )];
    let mut stack = vec![PathBuf::from("/usr/share/fonts")];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("ttf"))
            {
                paths.push(path);
            }
        }
    }
    paths
}

/// The plot font's bytes (the first usable TrueType font), read once per process.
fn font_bytes() -> Result<&'static [u8], SceneError> {
    static FONT_BYTES: OnceLock<Result<&'static [u8], String>> = OnceLock::new();
    FONT_BYTES
        .get_or_init(|| {
            for path in font_paths() {
                if let Ok(bytes) = std::fs::read(&path) {
                    // plotters keeps fonts for the life of the process.
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    if plotters::style::register_font(FONT, FontStyle::Normal, bytes).is_ok() {
                        return Ok(bytes);
                    }
                }
            }
            Err("no usable TrueType font under /usr/share/fonts (install Debian's fonts-dejavu-core)".into())
        })
        .clone()
        .map_err(|e| SceneError::new("plots", e))
}

/// Registers a TrueType font for plot text as [`FONT`], once per process.
///
/// # Errors
/// No usable TrueType font under `/usr/share/fonts`.
pub fn ensure_font() -> Result<(), SceneError> {
    font_bytes().map(|_| ())
}

fn plot_error(e: impl std::fmt::Display) -> SceneError {
    SceneError::new("plots", e.to_string())
}

/// The image format of a plot, from its file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlotFormat {
    /// `.svg`
    Svg,
    /// `.png`
    Png,
}

impl PlotFormat {
    /// `.svg` or `.png` (any case); anything else is refused, naming `--plot`. The directory must
    /// exist.
    ///
    /// # Errors
    /// Another extension, or no such directory.
    pub fn of(path: &Path) -> Result<Self, SceneError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let format = match ext.as_deref() {
            Some("svg") => Self::Svg,
            Some("png") => Self::Png,
            _ => {
                return Err(SceneError::new(
                    "--plot",
                    format!(
                        "{}: the file must end in .svg or .png (the extension picks the format)",
                        path.display()
                    ),
                ));
            }
        };
        if path.is_dir() {
            return Err(SceneError::new(
                "--plot",
                format!("{}: is a directory", path.display()),
            ));
        }
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
            && !dir.is_dir()
        {
            return Err(SceneError::new(
                "--plot",
                format!("{}: no such directory", dir.display()),
            ));
        }
        Ok(format)
    }
}

/// Draws a figure `width_in` by `height_in` inches with `draw` and writes it to `path`, SVG or PNG
/// by its extension: the SVG with its physical size, the PNG rasterised from it.
fn write(
    path: &Path,
    (width_in, height_in): (f64, f64),
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let format = PlotFormat::of(path)?;
    ensure_font()?;
    let units = (upt(width_in * 72.0), upt(height_in * 72.0));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, units).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        draw(&root)?;
        root.present().map_err(plot_error)?;
    }
    // The physical size, so that a point is a point wherever the SVG is placed.
    let svg = svg.replacen(
        &format!("width=\"{}\" height=\"{}\"", units.0, units.1),
        &format!("width=\"{width_in:.3}in\" height=\"{height_in:.3}in\""),
        1,
    );
    match format {
        PlotFormat::Svg => std::fs::write(path, svg)
            .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}"))),
        PlotFormat::Png => raster::write_png(&svg, path),
    }
}

/// The series' labels in a framed box at `position`.
fn series_labels<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .label_font(font(LEGEND_PT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.stroke_width(upt(0.4)))
        .margin(upt(3.0))
        .legend_area_size(upt(14.0))
        .position(position)
        .draw()
        .map_err(plot_error)
}

/// The ranges of a chart whose plotting area is `pixels` wide and high, fitted to `points` with a
/// margin, at one scale on both axes (a millimetre as long across as up). The smaller span is at
/// least `least_span`.
fn equal_ranges(
    points: &[(f64, f64)],
    pixels: (u32, u32),
    least_span: f64,
) -> Option<(std::ops::Range<f64>, std::ops::Range<f64>)> {
    let finite: Vec<_> = points
        .iter()
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    let first = finite.first()?;
    let (mut lo, mut hi) = ((first.0, first.1), (first.0, first.1));
    for (a, b) in &finite {
        lo = (lo.0.min(*a), lo.1.min(*b));
        hi = (hi.0.max(*a), hi.1.max(*b));
    }
    let span = (hi.0 - lo.0).max(hi.1 - lo.1).max(least_span);
    let margin = 0.06 * span;
    let (w, h) = (f64::from(pixels.0.max(1)), f64::from(pixels.1.max(1)));
    // Units per data unit: the larger span (with its margins) fills its side.
    let scale = (w / (hi.0 - lo.0 + 2.0 * margin).max(least_span))
        .min(h / (hi.1 - lo.1 + 2.0 * margin).max(least_span));
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let (ca, cb) = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
    let (ha, hb) = (w / scale / 2.0, h / scale / 2.0);
    Some(((ca - ha)..(ca + ha), (cb - hb)..(cb + hb)))
}

/// A tick label: no more decimals than it needs, and a typographic minus.
fn tick(v: f64) -> String {
    let text = if (v - v.round()).abs() < 1e-9 * v.abs().max(1.0) {
        format!("{v:.0}")
    } else {
        let t = format!("{v:.3}");
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    };
    match text.strip_prefix('-') {
        Some("0") => "0".to_string(),
        Some(rest) => format!("\u{2212}{rest}"),
        None => text,
    }
}

/// `text` broken at spaces into lines no wider than `width` units in `style`.
fn wrap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    style: &TextStyle<'_>,
    width: u32,
) -> Vec<String> {
    let fits = |line: &str| {
        area.estimate_text_size(line, style)
            .is_ok_and(|(w, _)| w <= width)
    };
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if fits(&format!("{line} {word}")) => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// A chart's mesh: axis names, tick labels, no grid.
fn mesh<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    x: &str,
    y: &str,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(x)
        .y_desc(y)
        .label_style(font(TICK_PT))
        .axis_desc_style(font(LABEL_PT))
        .axis_style(BLACK.stroke_width(upt(0.5)))
        .x_labels(4)
        .y_labels(5)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .set_all_tick_mark_size(upt(2.5))
        .draw()
        .map_err(plot_error)
}
