//! The figure of one answer (`solve`, `estimate`, `calibrate`: `--plot`): the robot in its three
//! orthogonal projections, each at one scale on both of its axes and fitted to the robot, with the
//! guides, the tendons' and cables' paths, observed points and an estimate's tip ellipse; the
//! legend and the status in the fourth quarter.

use std::path::Path;

use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::{LABEL_PT, LEGEND_PT, PlotSize, equal_ranges, font, mesh, plot_error, pt, upt, write};
use crate::scene::SceneError;

/// A solved or estimated robot, ready to draw: the backbone, the base plate and the guides as
/// disks, each tendon's path and each cable's, in global coordinates, m.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Figure {
    /// The figure's title (the scene and the command).
    pub title: String,
    /// Lines under the title: the status, the tip force.
    pub notes: Vec<String>,
    /// Backbone points, base to tip, m.
    pub backbone_m: Vec<Vector3<f64>>,
    /// Further backbones (a calibration's other experiments), drawn as the first, m.
    pub more_backbones_m: Vec<Vec<Vector3<f64>>>,
    /// Outline of the base plate (first) and of each guide, m.
    pub disks_m: Vec<Vec<Vector3<f64>>>,
    /// Each tendon: its holes from the base plate's to its termination's.
    pub tendons: Vec<TendonPath>,
    /// Each passive cable: its holes from the first guide's to its termination.
    pub cables: Vec<Vec<Vector3<f64>>>,
    /// The tip, m (marked with a cross; none for a calibration's many experiments).
    pub tip_m: Option<Vector3<f64>>,
    /// An estimate's tip standard deviation per axis, m (drawn as an axis-aligned ellipse).
    pub tip_std_m: Option<Vector3<f64>>,
    /// Measured points (a calibration's observations), m, in the robot's frame.
    pub observed_m: Vec<Vector3<f64>>,
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
/// Observed points (`#000000` rings).
pub const OBSERVED_RGB: (u8, u8, u8) = (0, 0, 0);
const OBSERVED: RGBColor = RGBColor(OBSERVED_RGB.0, OBSERVED_RGB.1, OBSERVED_RGB.2);
const GUIDE: RGBColor = RGBColor(150, 150, 150);
const CABLE: RGBColor = RGBColor(110, 110, 110);
/// Dash and gap of a slack tendon, points.
const DASH_PT: (f64, f64) = (2.5, 1.8);
/// Line widths, points.
const BACKBONE_PT: f64 = 1.2;
const TENDON_PT: f64 = 0.8;
const THIN_PT: f64 = 0.4;
/// Marker size (tip cross, observed ring), points.
const MARK_PT: f64 = 2.2;
const MM_PER_M: f64 = 1e3;
const UM_PER_M: f64 = 1e6;

/// Height over width of the figure: two rows of panels, a little taller in one column.
fn aspect(size: PlotSize) -> f64 {
    match size {
        PlotSize::Column => 1.05,
        PlotSize::Page => 0.8,
    }
}

/// Draws `figure` into `path`, SVG or PNG by its extension ([`super::PlotFormat::of`]), `size`
/// wide.
///
/// # Errors
/// A refused path, no font, or a file that cannot be written.
pub fn draw_figure(figure: &Figure, path: &Path, size: PlotSize) -> Result<(), SceneError> {
    let width_in = size.width_in();
    write(path, (width_in, width_in * aspect(size)), |root| {
        figure_chart(root, figure)
    })
    .map_err(|e| SceneError::new("--plot", format!("{}: {}", path.display(), e)))
}

fn figure_chart(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    figure: &Figure,
) -> Result<(), SceneError> {
    let (w, h) = root.dim_in_pixel();
    let (top, bottom) = root.split_vertically(h / 2);
    let (xy, yz) = top.split_horizontally(w / 2);
    let (xz, legend) = bottom.split_horizontally(w / 2);
    panel(&xy, figure, (0, 1))?;
    panel(&yz, figure, (1, 2))?;
    panel(&xz, figure, (0, 2))?;
    legend_box(&legend, figure)
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
    let tip = figure.tip_m?;
    let (sa, sb) = (std[a] * MM_PER_M, std[b] * MM_PER_M);
    let (ca, cb) = (tip[a] * MM_PER_M, tip[b] * MM_PER_M);
    Some(
        (0..=72)
            .map(|k| {
                let phi = f64::from(k) * std::f64::consts::TAU / 72.0;
                (ca + sa * phi.cos(), cb + sb * phi.sin())
            })
            .collect(),
    )
}

/// One projection: horizontal axis `a`, vertical axis `b` (0 x, 1 y, 2 z).
fn panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    figure: &Figure,
    (a, b): (usize, usize),
) -> Result<(), SceneError> {
    let mm = |p: &Vector3<f64>| (p[a] * MM_PER_M, p[b] * MM_PER_M);
    let (name_a, name_b) = (AXIS_NAMES[a], AXIS_NAMES[b]);
    let mut points: Vec<(f64, f64)> = figure.backbone_m.iter().map(mm).collect();
    points.extend(figure.disks_m.iter().flatten().map(mm));
    points.extend(figure.tendons.iter().flat_map(|t| t.holes_m.iter().map(mm)));
    points.extend(figure.cables.iter().flatten().map(mm));
    points.extend(figure.observed_m.iter().map(mm));
    points.extend(figure.more_backbones_m.iter().flatten().map(mm));
    points.extend(figure.tip_m.iter().map(mm));
    let length_mm = length_m(figure) * MM_PER_M;
    // The ellipse widens the view.
    let ellipse = ellipse_mm(figure, (a, b));
    if let Some(e) = &ellipse {
        points.extend(e.iter().copied());
    }
    let caption = format!("{name_a}-{name_b} projection");
    let build = |x: std::ops::Range<f64>, y: std::ops::Range<f64>| {
        ChartBuilder::on(area)
            .caption(&caption, font(LABEL_PT))
            .margin(pt(3.0))
            .x_label_area_size(pt(22.0))
            .y_label_area_size(pt(34.0))
            .build_cartesian_2d(x, y)
            .map_err(plot_error)
    };
    let pixels = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let least = (0.02 * length_mm).max(1.0);
    let (x, y) = equal_ranges(&points, pixels, least)
        .ok_or_else(|| plot_error("no finite point to draw"))?;
    let mut chart = build(x, y)?;
    mesh(
        &mut chart,
        &format!("{name_a} (mm)"),
        &format!("{name_b} (mm)"),
    )?;
    let thin = upt(THIN_PT);
    for disk in &figure.disks_m {
        chart
            .draw_series(LineSeries::new(
                disk.iter().map(mm),
                GUIDE.stroke_width(thin),
            ))
            .map_err(plot_error)?;
    }
    for cable in &figure.cables {
        chart
            .draw_series(LineSeries::new(
                cable.iter().map(mm),
                CABLE.stroke_width(thin),
            ))
            .map_err(plot_error)?;
    }
    for backbone in std::iter::once(&figure.backbone_m).chain(&figure.more_backbones_m) {
        chart
            .draw_series(LineSeries::new(
                backbone.iter().map(mm),
                BLACK.stroke_width(upt(BACKBONE_PT)),
            ))
            .map_err(plot_error)?;
    }
    for (j, tendon) in figure.tendons.iter().enumerate() {
        let style = tendon_colour(j).stroke_width(upt(TENDON_PT));
        if tendon.slack {
            chart
                .draw_series(DashedLineSeries::new(
                    tendon.holes_m.iter().map(mm),
                    upt(DASH_PT.0),
                    upt(DASH_PT.1),
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
        .draw_series(
            figure
                .observed_m
                .iter()
                .map(|p| Circle::new(mm(p), pt(MARK_PT), OBSERVED.stroke_width(thin))),
        )
        .map_err(plot_error)?;
    chart
        .draw_series(
            figure
                .tip_m
                .iter()
                .map(|tip| Cross::new(mm(tip), pt(MARK_PT), ELLIPSE.stroke_width(upt(TENDON_PT)))),
        )
        .map_err(plot_error)?;
    if let Some(e) = ellipse {
        chart
            .draw_series(LineSeries::new(e, ELLIPSE.stroke_width(upt(TENDON_PT))))
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
        "tip ±1σ ellipse (from each axis's σ)".to_string()
    } else {
        "tip ±1σ: larger than the robot, not drawn".to_string()
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

/// The legend: the title and status, then a sample of each kind of line and its meaning, each
/// text wrapped to the quarter's width.
fn legend_box(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    figure: &Figure,
) -> Result<(), SceneError> {
    let x0 = pt(8.0);
    let indent = pt(16.0);
    let step = pt(LEGEND_PT * 1.3);
    let width = area.dim_in_pixel().0;
    let mut y = pt(10.0);
    // Text at `x`, wrapped to what is left of the width; `y` moves down a line for each line.
    let say = |label: &str, x: i32, size: f64, y: &mut i32| -> Result<(), SceneError> {
        let style = TextStyle::from(font(size));
        let room = width.saturating_sub((x + pt(4.0)).unsigned_abs());
        for line in super::wrap(area, label, &style, room) {
            area.draw(&Text::new(line, (x, *y - pt(size * 0.6)), style.clone()))
                .map_err(plot_error)?;
            *y += pt(size * 1.3);
        }
        Ok(())
    };
    // The title and the notes above the legend, as many of them as leave room for it (a column's
    // quarter is small): the legend's own lines first.
    let lines = |text: &str, x: i32, size: f64| {
        let room = width.saturating_sub((x + pt(4.0)).unsigned_abs());
        super::wrap(area, text, &TextStyle::from(font(size)), room).len()
    };
    let heading: Vec<(&String, f64)> = std::iter::once(&figure.title)
        .chain(&figure.notes)
        .filter(|n| !n.is_empty())
        .take(4)
        .enumerate()
        .map(|(i, n)| (n, if i == 0 { LABEL_PT } else { LEGEND_PT }))
        .collect();
    let heading_height = |count: usize| -> i32 {
        heading
            .iter()
            .take(count)
            .map(|(n, size)| pt(size * 1.3) * lines(n, x0, *size) as i32)
            .sum::<i32>()
            + if count > 0 { step / 2 } else { 0 }
    };

    let sample = |y: i32| vec![(x0, y), (x0 + pt(12.0), y)];
    let centre = |y: i32| (x0 + pt(6.0), y);
    let thin = upt(THIN_PT);
    let mut entries: Vec<(Marker<'_>, String)> = Vec::new();
    let line = |style: ShapeStyle| -> Marker<'_> {
        Box::new(move |y| {
            area.draw(&PathElement::new(sample(y), style))
                .map_err(plot_error)
        })
    };
    let backbone = if figure.more_backbones_m.is_empty() {
        "backbone"
    } else {
        "backbones, one per experiment"
    };
    entries.push((line(BLACK.stroke_width(upt(BACKBONE_PT))), backbone.into()));
    if !figure.disks_m.is_empty() {
        entries.push((
            line(GUIDE.stroke_width(thin)),
            "base plate and guides".into(),
        ));
    }
    if !figure.cables.is_empty() {
        entries.push((line(CABLE.stroke_width(thin)), "passive cables".into()));
    }
    for (j, tendon) in figure.tendons.iter().enumerate() {
        let style = tendon_colour(j).stroke_width(upt(TENDON_PT));
        if tendon.slack {
            entries.push((
                Box::new(move |y| {
                    area.draw(&DashedPathElement::new(
                        sample(y),
                        upt(DASH_PT.0),
                        upt(DASH_PT.1),
                        style,
                    ))
                    .map_err(plot_error)
                }),
                format!("{} (dashed)", tendon.label),
            ));
        } else {
            entries.push((line(style), tendon.label.clone()));
        }
    }
    if !figure.observed_m.is_empty() {
        entries.push((
            Box::new(move |y| {
                area.draw(&Circle::new(
                    centre(y),
                    pt(MARK_PT),
                    OBSERVED.stroke_width(thin),
                ))
                .map_err(plot_error)
            }),
            "observed points".into(),
        ));
    }
    if figure.tip_m.is_some() {
        entries.push((
            Box::new(move |y| {
                area.draw(&Cross::new(
                    centre(y),
                    pt(MARK_PT),
                    ELLIPSE.stroke_width(upt(TENDON_PT)),
                ))
                .map_err(plot_error)
            }),
            "tip".into(),
        ));
    }
    if let Some(std) = &figure.tip_std_m {
        let drawn = ellipse_drawn(figure);
        entries.push((
            Box::new(move |y| {
                if !drawn {
                    return Ok(());
                }
                let ring: Vec<(i32, i32)> = (0..=36)
                    .map(|k| {
                        let phi = f64::from(k) * std::f64::consts::TAU / 36.0;
                        let (cx, cy) = centre(y);
                        (
                            cx + (f64::from(pt(5.0)) * phi.cos()).round() as i32,
                            cy + (f64::from(pt(2.5)) * phi.sin()).round() as i32,
                        )
                    })
                    .collect();
                area.draw(&PathElement::new(
                    ring,
                    ELLIPSE.stroke_width(upt(TENDON_PT)),
                ))
                .map_err(plot_error)
            }),
            tip_std_words(figure, std).join(": "),
        ));
    }
    let legend_height: i32 = entries
        .iter()
        .map(|(_, label)| {
            pt(LEGEND_PT * 1.3) * lines(label, x0 + indent, LEGEND_PT) as i32 + pt(LEGEND_PT * 0.3)
        })
        .sum::<i32>()
        + step / 2
        + pt(LEGEND_PT * 1.3) * lines(FOOTNOTE, x0, LEGEND_PT) as i32;
    let height = i32::try_from(area.dim_in_pixel().1).unwrap_or(i32::MAX);
    let shown = (0..=heading.len())
        .rev()
        .find(|&k| y + heading_height(k) + legend_height <= height)
        .unwrap_or(0);
    for (note, size) in heading.iter().take(shown) {
        say(note, x0, *size, &mut y)?;
    }
    if shown > 0 {
        y += step / 2;
    }
    for (marker, label) in &entries {
        marker(y)?;
        say(label, x0 + indent, LEGEND_PT, &mut y)?;
        y += pt(LEGEND_PT * 0.3);
    }
    y += step / 2;
    say(FOOTNOTE, x0, LEGEND_PT, &mut y)
}

/// Draws a legend entry's sample at a height.
type Marker<'a> = Box<dyn Fn(i32) -> Result<(), SceneError> + 'a>;

/// The legend's last line.
const FOOTNOTE: &str = "each panel at one scale on both of its axes";
