//! The thesis's experiments (`validate --plots`): the predicted backbone for each hung mass with the
//! observed and the thesis-predicted tips (experiments 1a and 2), and the upper cable's change of
//! length against the hung mass, predicted and observed (Table 4.5). One column wide each, axes
//! fitted to the data.

use std::path::{Path, PathBuf};

use model_core::{Model, Stability, Start, TipLoad};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::{
    LABEL_PT, PlotSize, equal_ranges, font, mesh, plot_error, pt, series_labels, upt, write,
};
use crate::scene::SceneError;
use crate::scenes;
use crate::thesis::{CM_PER_M, Curve, KG_PER_G, Table41, Table43, Table45, Validation};

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

/// Marker radius, points.
const MARK_PT: f64 = 2.2;
/// A model curve's line width, points.
const CURVE_PT: f64 = 0.9;

/// A model curve with its legend entry `label`; where its solve failed (`points` `None`), the
/// legend entry alone, `label: why`, and no line: a failed solve is no answer.
fn line_or_failed<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    points: Option<impl Iterator<Item = (f64, f64)>>,
    style: ShapeStyle,
    label: String,
    why: &str,
) -> Result<(), SceneError> {
    match points {
        Some(points) => {
            chart
                .draw_series(LineSeries::new(points, style))
                .map_err(plot_error)?
                .label(label)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + pt(10.0), y)], style));
        }
        None => {
            chart
                .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
                .map_err(plot_error)?
                .label(format!("{label}: {why}"));
        }
    }
    Ok(())
}

fn shapes_chart(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    title: &str,
    curves: &[Curve],
    marks: &[TipMarks],
    legend: SeriesLabelPosition,
) -> Result<(), SceneError> {
    // A curve whose solve did not converge is no answer: not drawn, named in the legend as failed.
    let mut points: Vec<(f64, f64)> = curves
        .iter()
        .filter(|c| c.converged)
        .flat_map(|c| c.points.iter().map(|p| (p.x, p.y)))
        .collect();
    points.extend(
        marks
            .iter()
            .flat_map(|m| m.observed.iter().chain(&m.thesis).copied()),
    );
    let build = |x: std::ops::Range<f64>, y: std::ops::Range<f64>| {
        ChartBuilder::on(root)
            .caption(title, font(LABEL_PT))
            .margin(pt(4.0))
            .x_label_area_size(pt(23.0))
            .y_label_area_size(pt(30.0))
            .build_cartesian_2d(x, y)
            .map_err(plot_error)
    };
    let pixels = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let (x, y) =
        equal_ranges(&points, pixels, 1.0).ok_or_else(|| plot_error("no finite point to draw"))?;
    let mut chart = build(x, y)?;
    mesh(&mut chart, "x (cm)", "y (cm)")?;
    let (mark, width) = (pt(MARK_PT), upt(CURVE_PT));
    for (i, curve) in curves.iter().enumerate() {
        let c = colour(i);
        line_or_failed(
            &mut chart,
            curve
                .converged
                .then(|| curve.points.iter().map(|p| (p.x, p.y))),
            c.stroke_width(width),
            format!("{} g", curve.mass_g),
            "not converged",
        )?;
        if let Some(m) = marks.get(i) {
            chart
                .draw_series(
                    m.observed
                        .iter()
                        .map(|&(x, y)| Circle::new((x, y), mark, c.filled())),
                )
                .map_err(plot_error)?;
            chart
                .draw_series(
                    m.thesis
                        .iter()
                        .map(|&(x, y)| Cross::new((x, y), mark, c.stroke_width(width))),
                )
                .map_err(plot_error)?;
        }
    }
    chart
        .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
        .map_err(plot_error)?
        .label("observed tip")
        .legend(move |(x, y)| Circle::new((x + pt(5.0), y), mark, BLACK.filled()));
    chart
        .draw_series(std::iter::empty::<Cross<(f64, f64), i32>>())
        .map_err(plot_error)?
        .label("thesis's tip")
        .legend(move |(x, y)| Cross::new((x + pt(5.0), y), mark, BLACK.stroke_width(width)));
    series_labels(&mut chart, legend)
}

/// The cable changes from the 0 g length `baseline_cm` (None: its solve did not converge, so no
/// curve) of the converged solves' `(mass g, length cm)`.
fn changes_from(baseline_cm: Option<f64>, lengths_cm: &[(f64, f64)]) -> Option<Vec<(f64, f64)>> {
    let base = baseline_cm?;
    Some(lengths_cm.iter().map(|&(g, l)| (g, l - base)).collect())
}

/// Our predicted cable change from 0 g over a fine mass grid from 0 g (to show the saturation), cm,
/// for one scene; None when the 0 g solve did not converge.
fn delta_curve(accurate: bool, masses_g: &[f64]) -> Result<Option<Vec<(f64, f64)>>, SceneError> {
    let scene = if accurate {
        scenes::exp2_accurate()?
    } else {
        scenes::exp2_average()?
    };
    let model =
        Model::<f64>::new(scene.rod()?).map_err(|e| SceneError::new("scene", e.to_string()))?;
    let settings = scene.shooting_settings()?;
    let gravity = Vector3::from(scene.gravity_m_s2);
    let mut lengths = Vec::new();
    let mut baseline_cm = None;
    let mut start = Start::Cold;
    for &g in masses_g {
        let eq = model
            .solve(&TipLoad::force(gravity * (g * KG_PER_G)), start, &settings)
            .map_err(|e| SceneError::new("tip", e.to_string()))?;
        // An answer as the tables take one: converged to a stable equilibrium.
        if !(eq.report.termination.is_success() && eq.report.stability == Stability::Stable) {
            continue;
        }
        start = Start::Warm(eq.base_strain_per_m);
        let length_cm = eq.cable_lengths_m.first().copied().unwrap_or(f64::NAN) * CM_PER_M;
        if g == 0.0 {
            baseline_cm = Some(length_cm);
        }
        lengths.push((g, length_cm));
    }
    Ok(changes_from(baseline_cm, &lengths))
}

fn delta_chart(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    table: &Table45,
    curves: &[Option<Vec<(f64, f64)>>; 2],
) -> Result<(), SceneError> {
    let all = curves
        .iter()
        .flatten()
        .flatten()
        .copied()
        .chain(table.rows.iter().map(|r| (r.mass_g, r.observed_cm + 0.05)))
        .chain(
            table
                .rows
                .iter()
                .flat_map(|r| r.thesis_cm.map(|c| (r.mass_g, c))),
        );
    let (mut max_mass, mut max_cm) = (0.0_f64, 0.0_f64);
    for (m, c) in all.filter(|(m, c)| m.is_finite() && c.is_finite()) {
        max_mass = max_mass.max(m);
        max_cm = max_cm.max(c);
    }
    let mut chart = ChartBuilder::on(root)
        .caption("upper cable's change of length", font(LABEL_PT))
        .margin(pt(4.0))
        .x_label_area_size(pt(23.0))
        .y_label_area_size(pt(30.0))
        .build_cartesian_2d(0.0..max_mass * 1.03, 0.0..max_cm * 1.08)
        .map_err(plot_error)?;
    mesh(&mut chart, "tip mass (g)", "cable change (cm)")?;
    let (mark, width) = (pt(MARK_PT), upt(CURVE_PT));
    for (m, (name, c)) in [("average", colour(0)), ("accurate", colour(1))]
        .into_iter()
        .enumerate()
    {
        // No change without the 0 g length it is a change from.
        line_or_failed(
            &mut chart,
            curves[m].as_ref().map(|curve| curve.iter().copied()),
            c.stroke_width(width),
            format!("model, {name} guide mass"),
            "0 g not converged",
        )?;
        chart
            .draw_series(
                table
                    .rows
                    .iter()
                    .map(|r| Cross::new((r.mass_g, r.thesis_cm[m]), mark, c.stroke_width(width))),
            )
            .map_err(plot_error)?
            .label(format!("thesis, {name} guide mass"))
            .legend(move |(x, y)| Cross::new((x + pt(5.0), y), mark, c.stroke_width(width)));
    }
    // The ruler reads to 1 mm: the observations with half of it as error bars.
    chart
        .draw_series(table.rows.iter().map(|r| {
            ErrorBar::new_vertical(
                r.mass_g,
                r.observed_cm - 0.05,
                r.observed_cm,
                r.observed_cm + 0.05,
                BLACK.stroke_width(upt(0.5)),
                pt(4.0) as u32,
            )
        }))
        .map_err(plot_error)?;
    chart
        .draw_series(
            table
                .rows
                .iter()
                .map(|r| Circle::new((r.mass_g, r.observed_cm), mark, BLACK.filled())),
        )
        .map_err(plot_error)?
        .label("observed (ruler, ±0.5 mm)")
        .legend(move |(x, y)| Circle::new((x + pt(5.0), y), mark, BLACK.filled()));
    series_labels(&mut chart, SeriesLabelPosition::LowerRight)
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

/// Writes one figure as `name.svg` and `name.png` in `dir`.
fn both(
    dir: &Path,
    name: &str,
    size_in: (f64, f64),
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), SceneError>,
) -> Result<Vec<PathBuf>, SceneError> {
    let files = [
        dir.join(format!("{name}.svg")),
        dir.join(format!("{name}.png")),
    ];
    for file in &files {
        write(file, size_in, &draw)?;
    }
    Ok(files.to_vec())
}

/// Height over width of a shape figure: the curves' extent, with room for the axes and the title,
/// so that the figure is not mostly empty.
fn shapes_aspect(curves: &[Curve]) -> f64 {
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for p in curves
        .iter()
        .filter(|c| c.converged)
        .flat_map(|c| &c.points)
    {
        lo = (lo.0.min(p.x), lo.1.min(p.y));
        hi = (hi.0.max(p.x), hi.1.max(p.y));
    }
    let ratio = (hi.1 - lo.1) / (hi.0 - lo.0);
    if ratio.is_finite() {
        (ratio * 1.15 + 0.3).clamp(0.5, 1.1)
    } else {
        0.75
    }
}

/// Draws every validation figure into `dir` (created if missing), one column wide; returns the
/// files written.
pub fn draw_validation(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>, SceneError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| SceneError::new(dir.display().to_string(), format!("cannot create: {e}")))?;
    let width = PlotSize::Column.width_in();
    let mut files = Vec::new();
    let exp1 = exp1_marks(&v.table_4_1);
    files.extend(both(
        dir,
        "exp1a_shapes",
        (width, width * shapes_aspect(&v.table_4_1.curves)),
        |a| {
            shapes_chart(
                a,
                "two sections, mass at 19.5 cm",
                &v.table_4_1.curves,
                &exp1,
                SeriesLabelPosition::LowerLeft,
            )
        },
    )?);
    for (table, name, title) in [
        (
            &v.table_4_3_average,
            "exp2_average_shapes",
            "guides of average mass, mass at the tip",
        ),
        (
            &v.table_4_4_accurate,
            "exp2_accurate_shapes",
            "guides of accurate mass, mass at the tip",
        ),
    ] {
        let marks = exp2_marks(table);
        let size = (width, width * shapes_aspect(&table.curves));
        files.extend(both(dir, name, size, |a| {
            // The curves droop to the lower left: the legend goes below the lightest loads' tips.
            shapes_chart(
                a,
                title,
                &table.curves,
                &marks,
                SeriesLabelPosition::LowerRight,
            )
        })?);
    }
    let masses: Vec<f64> = (0..=30).map(|i| f64::from(i) * 5.0).collect();
    let curves = [delta_curve(false, &masses)?, delta_curve(true, &masses)?];
    files.extend(both(dir, "cable_delta", (width, width * 0.75), |a| {
        delta_chart(a, &v.table_4_5, &curves)
    })?);
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thesis::PointCm;

    #[test]
    fn the_cable_change_is_from_0_g_or_not_drawn() {
        // 0 g did not converge: no curve, not one against the first mass that did.
        assert_eq!(changes_from(None, &[(5.0, 38.1), (10.0, 38.3)]), None);
        let curve = changes_from(Some(38.0), &[(5.0, 38.1), (10.0, 38.3)]).expect("a curve");
        assert_eq!(curve.len(), 2);
        assert!((curve[0].1 - 0.1).abs() < 1e-12 && (curve[1].1 - 0.3).abs() < 1e-12);
    }

    #[test]
    fn a_curve_that_did_not_converge_is_named_not_drawn() {
        let curve = |mass_g: f64, drop_cm: f64, converged| Curve {
            mass_g,
            points: vec![
                PointCm { x: 0.0, y: 0.0 },
                PointCm {
                    x: 30.0,
                    y: -drop_cm,
                },
            ],
            converged,
        };
        let curves = [curve(10.0, 5.0, true), curve(20.0, 80.0, false)];
        let file = std::env::temp_dir().join(format!("thesis-shapes-{}.svg", std::process::id()));
        write(&file, (3.5, 3.0), |a| {
            shapes_chart(a, "test", &curves, &[], SeriesLabelPosition::LowerLeft)
        })
        .expect("drawn");
        let svg = std::fs::read_to_string(&file).expect("read");
        let _ = std::fs::remove_file(&file);
        let hex = |c: RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        assert!(
            svg.contains(&hex(colour(0))),
            "the converged curve is drawn"
        );
        assert!(
            !svg.to_uppercase().contains(&hex(colour(1))),
            "the failed curve is drawn"
        );
        assert!(svg.contains("20 g: not converged"), "not named as failed");
    }
}
