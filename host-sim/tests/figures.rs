//! Figures fit for a paper: printed sizes, fonts no smaller than 7 pt at those sizes, anti-aliased
//! PNG at 300 dpi, `µm` and `±`, and axes fitted to the robot.

use std::path::PathBuf;

use host_sim::plots::{
    Figure, PNG_DPI, PNG_PIXELS_PER_METRE, PlotSize, TendonPath, UNITS_PER_PT, draw_figure,
    tendon_rgb,
};
use nalgebra::Vector3;
use resvg::tiny_skia::Pixmap;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-figures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

/// A bent robot 0.3 m long with one taut tendon and an estimate's tip deviation of tens of µm.
fn figure() -> Figure {
    let backbone_m: Vec<Vector3<f64>> = (0..=30)
        .map(|i| {
            let s = f64::from(i) * 0.01;
            Vector3::new(s, -0.4 * s * s, 0.1 * s * s)
        })
        .collect();
    let tip_m = *backbone_m.last().unwrap();
    let holes_m = backbone_m
        .iter()
        .step_by(10)
        .map(|p| p + Vector3::new(0.0, 0.01, 0.0))
        .collect();
    Figure {
        title: "a bent robot".into(),
        notes: vec!["status: converged".into()],
        backbone_m,
        tendons: vec![TendonPath {
            holes_m,
            slack: false,
            label: "tendon 0: 2.000 N".into(),
        }],
        tip_m: Some(tip_m),
        tip_std_m: Some(Vector3::new(40e-6, 60e-6, 25e-6)),
        ..Figure::default()
    }
}

/// The values of every `attribute="..."` in `svg` that parse as numbers.
fn numbers(svg: &str, attribute: &str) -> Vec<f64> {
    let key = format!("{attribute}=\"");
    svg.match_indices(&key)
        .filter_map(|(i, _)| {
            let rest = &svg[i + key.len()..];
            rest[..rest.find('"')?].parse().ok()
        })
        .collect()
}

#[test]
fn the_svg_has_its_printed_size_and_readable_fonts() {
    for (size, width_in) in [(PlotSize::Column, 3.5), (PlotSize::Page, 7.16)] {
        let path = temp(&format!("{size:?}.svg"));
        draw_figure(&figure(), &path, size).expect("drawn");
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(
            svg.contains(&format!("width=\"{width_in:.3}in\"")),
            "{size:?}: {}",
            &svg[..200]
        );
        let fonts = numbers(&svg, "font-size");
        assert!(fonts.len() > 20, "{size:?}: {} texts", fonts.len());
        let smallest_pt = fonts.iter().copied().fold(f64::MAX, f64::min) / UNITS_PER_PT;
        assert!(
            (7.0 - 1e-9..=10.0).contains(&smallest_pt),
            "{size:?}: smallest text {smallest_pt} pt"
        );
        // The deviation in µm, with ± and σ.
        assert!(svg.contains("µm") && svg.contains("±1σ"), "{size:?}");
    }
}

#[test]
fn the_png_is_300_dpi_and_anti_aliased() {
    let path = temp("column.png");
    draw_figure(&figure(), &path, PlotSize::Column).expect("drawn");
    let png = Pixmap::load_png(&path).expect("a PNG");
    assert_eq!(f64::from(png.width()), (3.5 * PNG_DPI).round());
    // The file says its resolution (pHYs, pixels per metre): 300 dpi, not a viewer's default.
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&path).expect("the PNG"),
    ));
    let reader = decoder.read_info().expect("a PNG header");
    let dims = reader.info().pixel_dims.expect("a pHYs chunk");
    assert_eq!(dims.unit, png::Unit::Meter);
    assert_eq!(
        (dims.xppu, dims.yppu),
        (PNG_PIXELS_PER_METRE, PNG_PIXELS_PER_METRE)
    );
    assert!((f64::from(dims.xppu) * 0.0254 - PNG_DPI).abs() < 0.01);
    // Anti-aliased: along the tendon's edges, pixels between its colour and the white background
    // (a line drawn without anti-aliasing has only the two).
    let (r, g, b) = tendon_rgb(0);
    let target = [f64::from(r), f64::from(g), f64::from(b)];
    let (mut full, mut blended) = (0, 0);
    for p in png.pixels() {
        let c = p.demultiply();
        let c = [
            f64::from(c.red()),
            f64::from(c.green()),
            f64::from(c.blue()),
        ];
        // The fraction t of the tendon's colour over white, fitted per channel.
        let t: Vec<f64> = (0..3)
            .filter(|&k| (255.0 - target[k]).abs() > 50.0)
            .map(|k| (255.0 - c[k]) / (255.0 - target[k]))
            .collect();
        let on_the_line = t.windows(2).all(|w| (w[0] - w[1]).abs() < 0.08);
        let mean = t.iter().sum::<f64>() / t.len() as f64;
        if on_the_line && mean > 0.95 {
            full += 1;
        } else if on_the_line && (0.2..0.8).contains(&mean) {
            blended += 1;
        }
    }
    assert!(full > 200, "{full} pixels of the tendon's colour");
    assert!(
        blended * 5 > full,
        "{blended} blended against {full} full pixels: not anti-aliased"
    );
}

#[test]
fn each_panel_is_fitted_to_the_robot() {
    let path = temp("fitted.svg");
    draw_figure(&figure(), &path, PlotSize::Page).expect("drawn");
    let svg = std::fs::read_to_string(&path).unwrap();
    // The x axis (0 to 300 mm) is labelled within the robot's extent and a margin: no tick
    // beyond 400 mm, and 300 is labelled.
    let ticks: Vec<f64> = svg
        .split("</text>")
        .filter_map(|t| t.rsplit('>').next())
        .filter_map(|t| t.trim().replace('\u{2212}', "-").parse::<f64>().ok())
        .collect();
    assert!(ticks.contains(&300.0), "{ticks:?}");
    assert!(ticks.iter().all(|t| t.abs() <= 400.0), "{ticks:?}");
}

/// `calibrate --plot`: each experiment's fitted backbone and every observed point, in each of the
/// three projections.
#[test]
fn a_calibration_draws_its_backbones_and_observed_points() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let path = temp("calibration.svg");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "calibrate",
            "--fit",
            "E,base_pose",
            "--plot-size",
            "column",
            "--plot",
        ])
        .arg(&path)
        .arg(root.join("scenes/bench_3d_cables.toml"))
        .arg("--data")
        .arg(root.join("scenes/bench_3d_calibration.csv"))
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(&path).unwrap();
    let csv = std::fs::read_to_string(root.join("scenes/bench_3d_calibration.csv")).unwrap();
    let observed = csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .count()
        - 1;
    let experiments = csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .filter_map(|l| l.split(',').next())
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    assert!(
        observed >= 10 && experiments >= 3,
        "{observed} points, {experiments} experiments"
    );
    // A ring per observed point in each projection, and one in the legend.
    assert_eq!(svg.matches("<circle").count(), 3 * observed + 1);
    // A backbone per experiment in each projection (black polylines).
    let backbones = svg
        .split("<polyline")
        .skip(1)
        .filter(|p| p.contains("stroke=\"#000000\"") && p.matches(',').count() > 30)
        .count();
    assert_eq!(
        backbones,
        3 * experiments,
        "black polylines of over 30 points"
    );
    assert!(svg.contains("backbones, one per"), "the legend names them");
}
