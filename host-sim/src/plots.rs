//! Plots of the experiments (plotters, SVG and PNG): the predicted backbone for each thesis row with the
//! observed and the thesis-predicted tips, like the thesis's Figures 4.9 and 4.12, and the cable-delta
//! curve predicted against observed (Table 4.5). And the figure of one answer of `solve` or
//! `estimate` (`--plot`, [`draw_figure`]): the backbone in three orthogonal projections with the
//! guides, the tendons' and cables' paths and an estimate's tip ellipse.
//!
//! Text is drawn with a TrueType font read at run time (DejaVu Sans from Debian's `fonts-dejavu-core`,
//! or the first `.ttf` found under `/usr/share/fonts`), so no font is committed and no system
//! font library is linked.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use model_core::{Model, Start, TipLoad};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use crate::scene::SceneError;
use crate::scenes;
use crate::thesis::{CM_PER_M, Curve, KG_PER_G, Table41, Table43, Table45, Validation};

/// The family name plot text is drawn in, once [`ensure_font`] has registered it.
pub const FONT: &str = "sans-serif";

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

/// Registers a TrueType font for plot text as [`FONT`], once per process.
///
/// # Errors
/// No usable TrueType font under `/usr/share/fonts`.
pub fn ensure_font() -> Result<(), SceneError> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            for path in font_paths() {
                if let Ok(bytes) = std::fs::read(&path) {
                    // plotters keeps fonts for the life of the process.
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    if plotters::style::register_font(FONT, FontStyle::Normal, bytes).is_ok() {
                        return Ok(());
                    }
                }
            }
            Err("no usable TrueType font under /usr/share/fonts (install Debian's fonts-dejavu-core)".into())
        })
        .clone()
        .map_err(|e| SceneError::new("plots", e))
}

fn plot_error(e: impl std::fmt::Display) -> SceneError {
    SceneError::new("plots", e.to_string())
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
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(plot_error)
}

/// Mass -> a colour along a fixed palette.
fn colour(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    PALETTE[i % PALETTE.len()]
}

/// Observed tips (filled circles) and the thesis's predictions (crosses) drawn over the curves.
struct TipMarks {
    observed: Vec<(f64, f64)>,
    thesis: Vec<(f64, f64)>,
}

fn shapes_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    curves: &[Curve],
    marks: &[TipMarks],
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 22))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-1.0..42.0, -40.0..5.0)
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("x (cm)")
        .y_desc("y (cm)")
        .label_style((FONT, 14))
        .draw()
        .map_err(plot_error)?;
    for (i, curve) in curves.iter().enumerate() {
        let c = colour(i);
        chart
            .draw_series(LineSeries::new(
                curve.points.iter().map(|p| (p.x, p.y)),
                c.stroke_width(2),
            ))
            .map_err(plot_error)?
            .label(format!("{} g (model)", curve.mass_g))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], c.stroke_width(2)));
        if let Some(m) = marks.get(i) {
            chart
                .draw_series(
                    m.observed
                        .iter()
                        .map(|&(x, y)| Circle::new((x, y), 5, c.filled())),
                )
                .map_err(plot_error)?;
            chart
                .draw_series(
                    m.thesis
                        .iter()
                        .map(|&(x, y)| Cross::new((x, y), 6, c.stroke_width(2))),
                )
                .map_err(plot_error)?;
        }
    }
    chart
        .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
        .map_err(plot_error)?
        .label("observed tip (filled); thesis prediction (cross)")
        .legend(|(x, y)| Circle::new((x + 9, y), 5, BLACK.filled()));
    series_labels(&mut chart, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(plot_error)
}

/// Our predicted cable change over a fine mass grid (to show the saturation), cm, for one scene.
fn delta_curve(accurate: bool, masses_g: &[f64]) -> Result<Vec<(f64, f64)>, SceneError> {
    let scene = if accurate {
        scenes::exp2_accurate()?
    } else {
        scenes::exp2_average()?
    };
    let model =
        Model::<f64>::new(scene.rod()?).map_err(|e| SceneError::new("scene", e.to_string()))?;
    let settings = scene.shooting_settings()?;
    let gravity = Vector3::from(scene.gravity_m_s2);
    let mut out = Vec::new();
    let mut start = Start::Cold;
    let mut reference = None;
    for &g in masses_g {
        let eq = model
            .solve(&TipLoad::force(gravity * (g * KG_PER_G)), start, &settings)
            .map_err(|e| SceneError::new("tip", e.to_string()))?;
        if !eq.report.termination.is_success() {
            continue;
        }
        start = Start::Warm(eq.base_strain_per_m);
        let length_cm = eq.cable_lengths_m.first().copied().unwrap_or(f64::NAN) * CM_PER_M;
        let base = *reference.get_or_insert(length_cm);
        out.push((g, length_cm - base));
    }
    Ok(out)
}

fn delta_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    table: &Table45,
    curves: &[Vec<(f64, f64)>; 2],
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let max_mass = curves.iter().flatten().map(|p| p.0).fold(100.0, f64::max);
    let mut chart = ChartBuilder::on(root)
        .caption("Table 4.5: change of the upper cable's length", (FONT, 22))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..max_mass, 0.0..1.2)
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("tip mass (g)")
        .y_desc("cable change (cm)")
        .label_style((FONT, 14))
        .draw()
        .map_err(plot_error)?;
    for (m, (name, c)) in [("average", colour(0)), ("accurate", colour(1))]
        .into_iter()
        .enumerate()
    {
        chart
            .draw_series(LineSeries::new(
                curves[m].iter().copied(),
                c.stroke_width(2),
            ))
            .map_err(plot_error)?
            .label(format!("this model, {name} mass"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], c.stroke_width(2)));
        chart
            .draw_series(
                table
                    .rows
                    .iter()
                    .map(|r| Cross::new((r.mass_g, r.thesis_cm[m]), 6, c.stroke_width(2))),
            )
            .map_err(plot_error)?
            .label(format!("thesis, {name} mass"))
            .legend(move |(x, y)| Cross::new((x + 9, y), 6, c.stroke_width(2)));
    }
    // The ruler reads to 1 mm: draw the observations with that as error bars.
    chart
        .draw_series(table.rows.iter().map(|r| {
            ErrorBar::new_vertical(
                r.mass_g,
                r.observed_cm - 0.05,
                r.observed_cm,
                r.observed_cm + 0.05,
                BLACK,
                8,
            )
        }))
        .map_err(plot_error)?;
    chart
        .draw_series(
            table
                .rows
                .iter()
                .map(|r| Circle::new((r.mass_g, r.observed_cm), 5, BLACK.filled())),
        )
        .map_err(plot_error)?
        .label("observed (ruler, +-0.5 mm)")
        .legend(|(x, y)| Circle::new((x + 9, y), 5, BLACK.filled()));
    series_labels(&mut chart, SeriesLabelPosition::LowerRight)?;
    root.present().map_err(plot_error)
}

/// Draws one figure as `name.svg` and `name.png` in `dir`, `size` pixels.
fn both(
    dir: &Path,
    name: &str,
    size: (u32, u32),
    draw_svg: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), SceneError>,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), SceneError>,
) -> Result<Vec<PathBuf>, SceneError> {
    let svg = dir.join(format!("{name}.svg"));
    let png = dir.join(format!("{name}.png"));
    draw_svg(&SVGBackend::new(&svg, size).into_drawing_area())?;
    draw_png(&BitMapBackend::new(&png, size).into_drawing_area())?;
    Ok(vec![svg, png])
}

fn exp1_marks(t: &Table41) -> Vec<TipMarks> {
    t.section1
        .iter()
        .zip(&t.section2)
        .map(|(a, b)| TipMarks {
            observed: vec![(a.observed.x, a.observed.y), (b.observed.x, b.observed.y)],
            thesis: vec![(a.thesis.x, a.thesis.y), (b.thesis.x, b.thesis.y)],
        })
        .collect()
}

fn exp2_marks(t: &Table43) -> Vec<TipMarks> {
    t.rows
        .iter()
        .map(|r| TipMarks {
            observed: vec![(r.observed.x, r.observed.y)],
            thesis: vec![(r.thesis.x, r.thesis.y)],
        })
        .collect()
}

/// Draws every validation figure into `dir` (created if missing); returns the files written.
pub fn draw_validation(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>, SceneError> {
    ensure_font()?;
    std::fs::create_dir_all(dir)
        .map_err(|e| SceneError::new(dir.display().to_string(), format!("cannot create: {e}")))?;
    let mut files = Vec::new();
    let exp1 = exp1_marks(&v.table_4_1);
    let title1 = "Experiment 1a (Fig. 4.9): two sections, mass at 19.5 cm";
    // Equal scales on x and y: 43 cm by 45 cm of grid plus the label areas.
    let shapes_size = (925, 1010);
    files.extend(both(
        dir,
        "exp1a_shapes",
        shapes_size,
        |a| shapes_chart(a, title1, &v.table_4_1.curves, &exp1),
        |a| shapes_chart(a, title1, &v.table_4_1.curves, &exp1),
    )?);
    for (table, name, title) in [
        (
            &v.table_4_3_average,
            "exp2_average_shapes",
            "Experiment 2 (Fig. 4.12): guides, average mass",
        ),
        (
            &v.table_4_4_accurate,
            "exp2_accurate_shapes",
            "Experiment 2: guides, accurate mass",
        ),
    ] {
        let marks = exp2_marks(table);
        files.extend(both(
            dir,
            name,
            shapes_size,
            |a| shapes_chart(a, title, &table.curves, &marks),
            |a| shapes_chart(a, title, &table.curves, &marks),
        )?);
    }
    let masses: Vec<f64> = (0..=30).map(|i| f64::from(i) * 5.0).collect();
    let curves = [delta_curve(false, &masses)?, delta_curve(true, &masses)?];
    files.extend(both(
        dir,
        "cable_delta",
        (1000, 760),
        |a| delta_chart(a, &v.table_4_5, &curves),
        |a| delta_chart(a, &v.table_4_5, &curves),
    )?);
    Ok(files)
}

/// A solved or estimated robot, ready to draw: the backbone, the base plate and the guides as
/// disks, each tendon's path and each cable's, in global coordinates, m.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// The figure's title (the scene and the command).
    pub title: String,
    /// Lines under the title: the status, the tip force.
    pub notes: Vec<String>,
    /// Backbone points, base to tip, m.
    pub backbone_m: Vec<Vector3<f64>>,
    /// Outline of the base plate (first) and of each guide, m.
    pub disks_m: Vec<Vec<Vector3<f64>>>,
    /// Each tendon: its holes from the base plate's to its termination's.
    pub tendons: Vec<TendonPath>,
    /// Each passive cable: its holes from the first guide's to its termination.
    pub cables: Vec<Vec<Vector3<f64>>>,
    /// The tip, m.
    pub tip_m: Vector3<f64>,
    /// An estimate's tip standard deviation per axis, m (drawn as an axis-aligned ellipse).
    pub tip_std_m: Option<Vector3<f64>>,
}

/// One tendon's path: straight chords between its holes.
#[derive(Debug, Clone, PartialEq)]
pub struct TendonPath {
    /// The holes, base plate first, m.
    pub holes_m: Vec<Vector3<f64>>,
    /// Slack (drawn dashed).
    pub slack: bool,
    /// Its legend entry (tension, state).
    pub label: String,
}

/// The colour of tendon `j` (12 distinct colours, as many as model-core's `MAX_TENDONS`), as
/// red, green, blue: an SVG holds it as `stroke="#RRGGBB"`.
pub fn tendon_rgb(j: usize) -> (u8, u8, u8) {
    const PALETTE: [(u8, u8, u8); 12] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (188, 189, 34),
        (23, 190, 207),
        (0, 0, 128),
        (0, 100, 0),
        (128, 0, 64),
        (214, 39, 40),
    ];
    PALETTE[j % PALETTE.len()]
}

fn tendon_colour(j: usize) -> RGBColor {
    let (r, g, b) = tendon_rgb(j);
    RGBColor(r, g, b)
}

/// The tip's uncertainty ellipse (`#FF0000`, no tendon's colour).
pub const ELLIPSE_RGB: (u8, u8, u8) = (255, 0, 0);
const ELLIPSE: RGBColor = RGBColor(ELLIPSE_RGB.0, ELLIPSE_RGB.1, ELLIPSE_RGB.2);
const GUIDE: RGBColor = RGBColor(150, 150, 150);
const CABLE: RGBColor = RGBColor(110, 110, 110);
/// Dash and gap of a slack tendon, pixels.
const DASH: (u32, u32) = (7, 5);
const MM_PER_M: f64 = 1e3;
const UM_PER_M: f64 = 1e6;

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

/// Figure size, pixels: the title strip, then x-y over x-z on the left, y-z over the legend on the
/// right.
const FIGURE_SIZE: (u32, u32) = (1500, 1100);
const TITLE_HEIGHT: u32 = 100;
const LEFT_WIDTH: u32 = 980;

/// Draws `figure` into `path`, SVG or PNG by its extension ([`PlotFormat::of`]).
///
/// # Errors
/// A refused path, no font, or a file that cannot be written.
pub fn draw_figure(figure: &Figure, path: &Path) -> Result<(), SceneError> {
    let format = PlotFormat::of(path)?;
    ensure_font()?;
    let written = |e: SceneError| SceneError::new("--plot", format!("{}: {}", path.display(), e));
    match format {
        PlotFormat::Svg => figure_chart(
            &SVGBackend::new(path, FIGURE_SIZE).into_drawing_area(),
            figure,
        )
        .map_err(written),
        PlotFormat::Png => figure_chart(
            &BitMapBackend::new(path, FIGURE_SIZE).into_drawing_area(),
            figure,
        )
        .map_err(written),
    }
}

fn figure_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    figure: &Figure,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let (title, body) = root.split_vertically(TITLE_HEIGHT);
    title
        .draw(&Text::new(figure.title.clone(), (20, 10), (FONT, 24)))
        .map_err(plot_error)?;
    for (i, note) in figure.notes.iter().take(3).enumerate() {
        let y = 42 + 19 * i32::try_from(i).unwrap_or(0);
        title
            .draw(&Text::new(note.clone(), (20, y), (FONT, 16)))
            .map_err(plot_error)?;
    }
    let (left, right) = body.split_horizontally(LEFT_WIDTH);
    let body_height = FIGURE_SIZE.1 - TITLE_HEIGHT;
    let (xy, xz) = left.split_vertically(body_height / 2);
    let (yz, legend) = right.split_vertically(body_height / 2);
    panel(&xy, figure, (0, 1))?;
    panel(&xz, figure, (0, 2))?;
    panel(&yz, figure, (1, 2))?;
    legend_box(&legend, figure)?;
    root.present().map_err(plot_error)
}

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// The robot's length along its backbone, m.
fn length_m(figure: &Figure) -> f64 {
    figure
        .backbone_m
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .sum()
}

/// Whether the tip's ellipse is drawn: its deviations finite and none larger than the robot (a
/// larger one would shrink the robot to a dot).
fn ellipse_drawn(figure: &Figure) -> bool {
    figure.tip_std_m.is_some_and(|std| {
        std.iter()
            .all(|s| s.is_finite() && *s >= 0.0 && *s <= length_m(figure))
    })
}

/// The tip's 1-sigma ellipse in the projection `(a, b)`, mm, if it is drawn.
fn ellipse_mm(figure: &Figure, (a, b): (usize, usize)) -> Option<Vec<(f64, f64)>> {
    if !ellipse_drawn(figure) {
        return None;
    }
    let std = figure.tip_std_m?;
    let (sa, sb) = (std[a] * MM_PER_M, std[b] * MM_PER_M);
    let (ca, cb) = (figure.tip_m[a] * MM_PER_M, figure.tip_m[b] * MM_PER_M);
    Some(
        (0..=72)
            .map(|k| {
                let phi = f64::from(k) * std::f64::consts::TAU / 72.0;
                (ca + sa * phi.cos(), cb + sb * phi.sin())
            })
            .collect(),
    )
}

/// The ranges of a panel whose plotting area is `pixels` wide and high, fitted to `points` (mm)
/// with a margin, at one scale on both axes (a millimetre as long across as up).
fn equal_ranges(
    points: &[(f64, f64)],
    pixels: (u32, u32),
    least_span_mm: f64,
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
    let span = (hi.0 - lo.0).max(hi.1 - lo.1).max(least_span_mm);
    let margin = 0.06 * span;
    let (w, h) = (f64::from(pixels.0.max(1)), f64::from(pixels.1.max(1)));
    // Pixels per millimetre: the larger span (with its margins) fills its side.
    let scale = (w / (hi.0 - lo.0 + 2.0 * margin).max(least_span_mm))
        .min(h / (hi.1 - lo.1 + 2.0 * margin).max(least_span_mm));
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let (ca, cb) = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
    let (ha, hb) = (w / scale / 2.0, h / scale / 2.0);
    Some(((ca - ha)..(ca + ha), (cb - hb)..(cb + hb)))
}

/// One projection: horizontal axis `a`, vertical axis `b` (0 x, 1 y, 2 z).
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    figure: &Figure,
    (a, b): (usize, usize),
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    let mm = |p: &Vector3<f64>| (p[a] * MM_PER_M, p[b] * MM_PER_M);
    let (name_a, name_b) = (AXIS_NAMES[a], AXIS_NAMES[b]);
    let (caption, area) = area.split_vertically(34);
    caption
        .draw(&Text::new(
            format!("{name_a}-{name_b} projection"),
            (70, 8),
            (FONT, 19),
        ))
        .map_err(plot_error)?;
    let mut points: Vec<(f64, f64)> = figure.backbone_m.iter().map(mm).collect();
    points.extend(figure.disks_m.iter().flatten().map(mm));
    points.extend(figure.tendons.iter().flat_map(|t| t.holes_m.iter().map(mm)));
    points.extend(figure.cables.iter().flatten().map(mm));
    points.push(mm(&figure.tip_m));
    let length_mm = length_m(figure) * MM_PER_M;
    // The ellipse widens the view.
    let ellipse = ellipse_mm(figure, (a, b));
    if let Some(e) = &ellipse {
        points.extend(e.iter().copied());
    }
    let build = |x: std::ops::Range<f64>, y: std::ops::Range<f64>| {
        ChartBuilder::on(&area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x, y)
            .map_err(plot_error)
    };
    let pixels = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let least = (0.02 * length_mm).max(1.0);
    let (x, y) = equal_ranges(&points, pixels, least)
        .ok_or_else(|| plot_error("no finite point to draw"))?;
    let mut chart = build(x, y)?;
    chart
        .configure_mesh()
        .x_desc(format!("{name_a} (mm)"))
        .y_desc(format!("{name_b} (mm)"))
        .label_style((FONT, 14))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(plot_error)?;
    for disk in &figure.disks_m {
        chart
            .draw_series(LineSeries::new(disk.iter().map(mm), GUIDE.stroke_width(1)))
            .map_err(plot_error)?;
    }
    for cable in &figure.cables {
        chart
            .draw_series(LineSeries::new(cable.iter().map(mm), CABLE.stroke_width(1)))
            .map_err(plot_error)?;
    }
    chart
        .draw_series(LineSeries::new(
            figure.backbone_m.iter().map(mm),
            BLACK.stroke_width(3),
        ))
        .map_err(plot_error)?;
    for (j, tendon) in figure.tendons.iter().enumerate() {
        let style = tendon_colour(j).stroke_width(2);
        if tendon.slack {
            chart
                .draw_series(DashedLineSeries::new(
                    tendon.holes_m.iter().map(mm),
                    DASH.0,
                    DASH.1,
                    style,
                ))
                .map_err(plot_error)?;
        } else {
            chart
                .draw_series(LineSeries::new(tendon.holes_m.iter().map(mm), style))
                .map_err(plot_error)?;
        }
    }
    chart
        .draw_series(std::iter::once(Cross::new(
            mm(&figure.tip_m),
            6,
            ELLIPSE.stroke_width(2),
        )))
        .map_err(plot_error)?;
    if let Some(e) = ellipse {
        chart
            .draw_series(LineSeries::new(e, ELLIPSE.stroke_width(2)))
            .map_err(plot_error)?;
    }
    Ok(())
}

/// The tip's deviation in words for the legend, µm or mm: two lines.
fn tip_std_words(figure: &Figure, std: &Vector3<f64>) -> [String; 2] {
    if !std.iter().all(|s| s.is_finite()) {
        return [
            "tip ±1σ: not determined (infinite)".to_string(),
            "no ellipse drawn".to_string(),
        ];
    }
    let largest = std.max() * UM_PER_M;
    let (unit, per_m) = if largest < 1e3 {
        ("µm", UM_PER_M)
    } else {
        ("mm", MM_PER_M)
    };
    let first = if ellipse_drawn(figure) {
        "tip ±1σ ellipse (axis-aligned, from each axis's σ)".to_string()
    } else {
        "tip ±1σ: larger than the robot, no ellipse drawn".to_string()
    };
    [
        first,
        format!(
            "σx {:.1} {unit}, σy {:.1} {unit}, σz {:.1} {unit}",
            std.x * per_m,
            std.y * per_m,
            std.z * per_m
        ),
    ]
}

/// The legend: a sample of each kind of line and its meaning.
fn legend_box<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    figure: &Figure,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    let x0 = 30;
    let mut y = 50;
    let step = 26;
    let text = |label: &str, y: i32| Text::new(label.to_string(), (x0 + 48, y - 9), (FONT, 15));
    let sample = |y: i32| vec![(x0, y), (x0 + 36, y)];
    let line = |label: &str, style: ShapeStyle, y: &mut i32| -> Result<(), SceneError> {
        area.draw(&PathElement::new(sample(*y), style))
            .map_err(plot_error)?;
        area.draw(&text(label, *y)).map_err(plot_error)?;
        *y += step;
        Ok(())
    };
    area.draw(&Text::new("legend".to_string(), (x0, 15), (FONT, 19)))
        .map_err(plot_error)?;
    line("backbone", BLACK.stroke_width(3), &mut y)?;
    line(
        "base plate and guides (disks at the holes' radius)",
        GUIDE.stroke_width(1),
        &mut y,
    )?;
    if !figure.cables.is_empty() {
        line("passive cables", CABLE.stroke_width(1), &mut y)?;
    }
    for (j, tendon) in figure.tendons.iter().enumerate() {
        let style = tendon_colour(j).stroke_width(2);
        if tendon.slack {
            area.draw(&DashedPathElement::new(sample(y), DASH.0, DASH.1, style))
                .map_err(plot_error)?;
            area.draw(&text(&format!("{} (dashed)", tendon.label), y))
                .map_err(plot_error)?;
            y += step;
        } else {
            line(&tendon.label, style, &mut y)?;
        }
    }
    area.draw(&Cross::new((x0 + 18, y), 6, ELLIPSE.stroke_width(2)))
        .map_err(plot_error)?;
    area.draw(&text("tip", y)).map_err(plot_error)?;
    y += step;
    if let Some(std) = &figure.tip_std_m {
        let ring: Vec<(i32, i32)> = (0..=36)
            .map(|k| {
                let phi = f64::from(k) * std::f64::consts::TAU / 36.0;
                (
                    x0 + 18 + (16.0 * phi.cos()).round() as i32,
                    y + (7.0 * phi.sin()).round() as i32,
                )
            })
            .collect();
        if ellipse_drawn(figure) {
            area.draw(&PathElement::new(ring, ELLIPSE.stroke_width(2)))
                .map_err(plot_error)?;
        }
        let [first, second] = tip_std_words(figure, std);
        area.draw(&text(&first, y)).map_err(plot_error)?;
        y += step - 6;
        area.draw(&text(&second, y)).map_err(plot_error)?;
        y += step;
    }
    area.draw(&Text::new(
        "each panel at its own scale, the same on both of its axes".to_string(),
        (x0, y),
        (FONT, 13),
    ))
    .map_err(plot_error)?;
    Ok(())
}
