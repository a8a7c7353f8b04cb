//! Plots of the experiments (plotters, SVG and PNG): the predicted backbone for each thesis row with the
//! observed and the thesis-predicted tips, like the thesis's Figures 4.9 and 4.12, and the cable-delta
//! curve predicted against observed (Table 4.5).
//!
//! Text is drawn with a TrueType font read at run time (DejaVu Sans from Debian's `fonts-dejavu-core`,
//! or the first `.ttf` found under `/usr/share/fonts`), so no font is committed and no system
//! font library is linked.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use model_core::{Model, Start, TipLoad};
use nalgebra::Vector3;
use plotters::coord::Shift;
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
