//! `pareto.svg` / `pareto.png`: error against cost, log-log, one panel per scene and cost measure
//! (deterministic work, host wall time), one series per family, the Pareto front drawn as a staircase
//! with its points ringed.
//!
//! Text is drawn with the TrueType font `host_sim::plots` registers at run time.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::Study;
use super::measure::Row;
use super::variants::{Arithmetic, Family, Frame, Reduction};
use host_sim::plots::{FONT, ensure_font};
use host_sim::scene::SceneError;

/// Figure size, pixels.
const SIZE: (u32, u32) = (1200, 1150);
/// Height of the legend strip, pixels.
const LEGEND_HEIGHT: u32 = 80;
/// Errors are drawn no lower than this, um (an f64 error can be exactly zero).
const ERROR_FLOOR_UM: f64 = 1e-9;

/// A plotting error as a scene error.
pub(super) fn plot_error(e: impl std::fmt::Display) -> SceneError {
    SceneError::new("pareto plot", e.to_string())
}

/// The colour of a frame / reduction combination (or tendon model).
pub(super) fn colour(family: &Family) -> RGBColor {
    match (family.reduction, family.frame) {
        (Reduction::Cosserat3d, Frame::Quaternion) => RGBColor(31, 119, 180),
        (Reduction::Cosserat3d, Frame::RotationMatrix) => RGBColor(255, 127, 14),
        (Reduction::Cosserat3d, Frame::LieGroup) => RGBColor(44, 160, 44),
        (Reduction::Kirchhoff3d, _) => RGBColor(214, 39, 40),
        (Reduction::Planar, _) => RGBColor(148, 103, 189),
        (Reduction::PlanarKirchhoff, _) => RGBColor(140, 86, 75),
        (Reduction::TendonDiscrete, _) => RGBColor(31, 119, 180),
        (Reduction::TendonContinuous, _) => RGBColor(255, 127, 14),
        (Reduction::TendonPcc, _) => RGBColor(214, 39, 40),
    }
}

/// The kinds the colours stand for, with a representative family each.
fn kinds() -> [(&'static str, Family); 6] {
    let f = |frame, reduction| Family {
        arithmetic: Arithmetic::F64,
        frame,
        reduction,
    };
    [
        ("quaternion 3D", f(Frame::Quaternion, Reduction::Cosserat3d)),
        (
            "rotation matrix 3D",
            f(Frame::RotationMatrix, Reduction::Cosserat3d),
        ),
        ("Lie group 3D", f(Frame::LieGroup, Reduction::Cosserat3d)),
        (
            "quaternion 3D Kirchhoff",
            f(Frame::Quaternion, Reduction::Kirchhoff3d),
        ),
        ("planar", f(Frame::Quaternion, Reduction::Planar)),
        (
            "planar Kirchhoff",
            f(Frame::Quaternion, Reduction::PlanarKirchhoff),
        ),
    ]
}

/// Which cost a panel plots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Cost {
    Work,
    Time,
}

impl Cost {
    fn of(self, row: &Row) -> f64 {
        match self {
            Self::Work => row.work(),
            Self::Time => row.host_time_us,
        }
    }
    fn on_front(self, row: &Row) -> bool {
        match self {
            Self::Work => row.front_work,
            Self::Time => row.front_time,
        }
    }
    fn label(self, tendon: bool) -> &'static str {
        match (self, tendon) {
            (Self::Work, false) => "work: sweeps x RK4 steps per cold solve",
            (Self::Work, true) => {
                "work: sweeps x RK4 steps x step cost per cold solve (choose_tendons' units)"
            }
            (Self::Time, _) => "host wall time per cold solve, us (indicative)",
        }
    }
}

fn error_um(row: &Row) -> Option<f64> {
    row.error_m()
        .filter(|e| e.is_finite())
        .map(|e| (e * 1e6).max(ERROR_FLOOR_UM))
}

/// `[lo, hi]` of positive values, widened to whole decades.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !(lo.is_finite() && hi > 0.0) {
        return (1.0, 10.0);
    }
    let lo = 10f64.powf(lo.log10().floor());
    let hi = 10f64.powf(hi.log10().ceil()).max(lo * 10.0);
    (lo, hi)
}

/// One panel: error against `cost` of `rows`, a series per family, the front ringed.
pub(super) fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    rows: &[&Row],
    families: &[Family],
    cost: Cost,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    let (x0, x1) = decades(rows.iter().map(|r| cost.of(r)));
    let (y0, y1) = decades(rows.iter().filter_map(|r| error_um(r)));
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 16))
        .margin(8)
        .x_label_area_size(38)
        .y_label_area_size(62)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc(cost.label(families.iter().any(|f| f.reduction.tendon())))
        .y_desc("error, um")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(plot_error)?;
    for family in families {
        let mut points: Vec<(f64, f64, u16)> = rows
            .iter()
            .filter(|r| r.family == *family && r.converged())
            .filter_map(|r| error_um(r).map(|e| (cost.of(r), e, r.steps_per_section)))
            .collect();
        points.sort_by_key(|p| p.2);
        let c = colour(family);
        let xy: Vec<(f64, f64)> = points.iter().map(|p| (p.0, p.1)).collect();
        chart
            .draw_series(LineSeries::new(
                xy.iter().copied(),
                c.mix(0.5).stroke_width(1),
            ))
            .map_err(plot_error)?;
        match family.arithmetic {
            Arithmetic::F64 => chart
                .draw_series(xy.iter().map(|&p| Circle::new(p, 4, c.filled())))
                .map(|_| ()),
            Arithmetic::F32 => chart
                .draw_series(xy.iter().map(|&p| TriangleMarker::new(p, 5, c.filled())))
                .map(|_| ()),
            Arithmetic::F32Micromath => chart
                .draw_series(xy.iter().map(|&p| Cross::new(p, 5, c.stroke_width(2))))
                .map(|_| ()),
        }
        .map_err(plot_error)?;
    }
    let mut front: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| cost.on_front(r))
        .filter_map(|r| error_um(r).map(|e| (cost.of(r), e)))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut stairs = Vec::new();
    for (i, p) in front.iter().enumerate() {
        if let Some(prev) = i.checked_sub(1).and_then(|j| front.get(j)) {
            stairs.push((p.0, prev.1));
        }
        stairs.push(*p);
    }
    chart
        .draw_series(DashedLineSeries::new(stairs, 6, 4, BLACK.stroke_width(1)))
        .map_err(plot_error)?;
    chart
        .draw_series(
            front
                .iter()
                .map(|&p| Circle::new(p, 8, BLACK.stroke_width(1))),
        )
        .map_err(plot_error)?;
    Ok(())
}

fn legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    micromath: bool,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    let text = (FONT, 14).into_font().color(&BLACK);
    let mut x = 20;
    let y = 22;
    for (label, family) in kinds() {
        let c = colour(&family);
        area.draw(&PathElement::new(
            vec![(x, y), (x + 22, y)],
            c.stroke_width(3),
        ))
        .map_err(plot_error)?;
        area.draw(&Text::new(label, (x + 28, y - 8), text.clone()))
            .map_err(plot_error)?;
        x += 40 + 9 * i32::try_from(label.len()).unwrap_or(20);
    }
    let y = 60;
    let mut x = 20;
    let grey = RGBColor(90, 90, 90);
    area.draw(&Circle::new((x + 6, y), 4, grey.filled()))
        .map_err(plot_error)?;
    area.draw(&Text::new("f64", (x + 16, y - 8), text.clone()))
        .map_err(plot_error)?;
    x += 70;
    area.draw(&TriangleMarker::new((x + 6, y), 5, grey.filled()))
        .map_err(plot_error)?;
    area.draw(&Text::new("f32 (libm)", (x + 16, y - 8), text.clone()))
        .map_err(plot_error)?;
    x += 120;
    let micromath_label = if micromath {
        "f32 micromath"
    } else {
        "f32 micromath (not in this run)"
    };
    area.draw(&Cross::new((x + 6, y), 5, grey.stroke_width(2)))
        .map_err(plot_error)?;
    area.draw(&Text::new(micromath_label, (x + 16, y - 8), text.clone()))
        .map_err(plot_error)?;
    x += 40 + 9 * i32::try_from(micromath_label.len()).unwrap_or(20);
    area.draw(&Circle::new((x + 6, y), 8, BLACK.stroke_width(1)))
        .map_err(plot_error)?;
    area.draw(&Text::new(
        "Pareto front (dashed staircase); solves that did not converge are not drawn",
        (x + 20, y - 8),
        text,
    ))
    .map_err(plot_error)?;
    Ok(())
}

fn figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    study: &Study,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let root = root
        .titled(
            "Error against cost of the model's variants (error: worst of tip, backbone points, cable lengths)",
            (FONT, 20),
        )
        .map_err(plot_error)?;
    let (height, _) = (root.dim_in_pixel().1, ());
    let (charts, legend_area) = root.split_vertically(height.saturating_sub(LEGEND_HEIGHT));
    let scenes = study.scenes.len().max(1);
    let panels = charts.split_evenly((scenes, 2));
    for (s, studied) in study.scenes.iter().enumerate() {
        let rows: Vec<&Row> = study
            .rows
            .iter()
            .filter(|r| r.scene == studied.scene.key)
            .collect();
        let mut families: Vec<Family> = rows.iter().map(|r| r.family).collect();
        families.sort();
        families.dedup();
        for (c, cost) in [Cost::Work, Cost::Time].into_iter().enumerate() {
            if let Some(area) = panels.get(2 * s + c) {
                panel(area, &studied.scene.key, &rows, &families, cost)?;
            }
        }
    }
    legend(&legend_area, study.micromath)?;
    root.present().map_err(plot_error)
}

/// Draws `pareto.svg` and `pareto.png` into `dir`.
pub fn pareto(study: &Study, dir: &Path) -> Result<(), SceneError> {
    ensure_font()?;
    let svg = dir.join("pareto.svg");
    let png = dir.join("pareto.png");
    figure(&SVGBackend::new(&svg, SIZE).into_drawing_area(), study)?;
    figure(&BitMapBackend::new(&png, SIZE).into_drawing_area(), study)
}
