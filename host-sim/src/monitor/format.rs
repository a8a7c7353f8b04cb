//! One record as a line of text, a CSV row and a figure.

use std::fmt::Write as _;

use nalgebra::Vector3;
use robot_link::{MAX_BACKBONE_POINTS, MAX_TENSIONS, Record};

use crate::plots::Figure;

pub(super) fn v3(a: [f32; 3]) -> Vector3<f64> {
    Vector3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2]))
}

/// One line for a record: tick, status, the estimate's tick, force and tip (mm) with their
/// standard deviations, tip orientation, sweeps.
pub fn record_line(record: &Record) -> String {
    let mut line = format!("tick {:6} {:28}", record.tick, record.status.to_string());
    match &record.estimate {
        None => line.push_str(" no estimate yet"),
        Some(e) => {
            let f = e.tip_force_n;
            let fs = e.tip_force_std_n.map(|x| x * 1e3);
            let p = e.tip_position_m.map(|x| x * 1e3);
            let ps = e.tip_position_std_m.map(|x| x * 1e6);
            let q = e.tip_orientation;
            let _ = write!(
                line,
                " estimate@{} force_n [{:+.4} {:+.4} {:+.4}] std_mn [{:.2} {:.2} {:.2}] \
                 tip_mm [{:+.3} {:+.3} {:+.3}] std_um [{:.1} {:.1} {:.1}] \
                 q [{:.4} {:+.4} {:+.4} {:+.4}] sweeps {}",
                e.tick,
                f[0],
                f[1],
                f[2],
                fs[0],
                fs[1],
                fs[2],
                p[0],
                p[1],
                p[2],
                ps[0],
                ps[1],
                ps[2],
                q[0],
                q[1],
                q[2],
                q[3],
                e.sweeps
            );
            if !e.tensions_n.is_empty() {
                let t: Vec<String> = e.tensions_n.iter().map(|x| format!("{x:.3}")).collect();
                let _ = write!(line, " tensions_n [{}]", t.join(" "));
            }
        }
    }
    line
}

/// The CSV header (see [`MONITOR_HELP`]).
pub fn csv_header() -> String {
    let mut columns: Vec<String> = [
        "tick",
        "status",
        "reason",
        "cable",
        "estimate_tick",
        "force_x_n",
        "force_y_n",
        "force_z_n",
        "force_std_x_n",
        "force_std_y_n",
        "force_std_z_n",
        "tip_x_m",
        "tip_y_m",
        "tip_z_m",
        "tip_std_x_m",
        "tip_std_y_m",
        "tip_std_z_m",
        "tip_qw",
        "tip_qx",
        "tip_qy",
        "tip_qz",
        "sweeps",
        "backbone_points",
        "tensions",
    ]
    .map(String::from)
    .to_vec();
    for i in 0..MAX_BACKBONE_POINTS {
        columns.extend(["x", "y", "z"].map(|a| format!("backbone_{i}_{a}_m")));
    }
    columns.extend((0..MAX_TENSIONS).map(|j| format!("tension_{j}_n")));
    columns.join(",")
}

/// A record's CSV row, [`csv_header`]'s columns. Floats in their shortest exact form.
pub fn csv_row(record: &Record) -> String {
    let mut cells = vec![record.tick.to_string(), record.status.name().to_string()];
    match record.status {
        robot_link::Status::Rejected { reason, .. } => cells.push(reason.name().to_string()),
        _ => cells.push(String::new()),
    }
    cells.push(
        record
            .status
            .cable()
            .map_or(String::new(), |c| c.to_string()),
    );
    let number = |x: f32| format!("{x:?}");
    match &record.estimate {
        None => cells.extend(std::iter::repeat_n(String::new(), 20)),
        Some(e) => {
            cells.push(e.tick.to_string());
            let floats = e
                .tip_force_n
                .iter()
                .chain(&e.tip_force_std_n)
                .chain(&e.tip_position_m)
                .chain(&e.tip_position_std_m)
                .chain(&e.tip_orientation);
            cells.extend(floats.map(|x| number(*x)));
            cells.push(e.sweeps.to_string());
            cells.push(e.backbone_m.len().to_string());
            cells.push(e.tensions_n.len().to_string());
        }
    }
    let (points, tensions) = record.estimate.as_ref().map_or((&[][..], &[][..]), |e| {
        (e.backbone_m.as_slice(), e.tensions_n.as_slice())
    });
    for i in 0..MAX_BACKBONE_POINTS {
        match points.get(i) {
            Some(p) => cells.extend(p.map(number)),
            None => cells.extend(std::iter::repeat_n(String::new(), 3)),
        }
    }
    for j in 0..MAX_TENSIONS {
        cells.push(tensions.get(j).map_or(String::new(), |t| number(*t)));
    }
    cells.join(",")
}

/// The plot's figure of a record's estimate: the backbone from the base (at the origin, as the
/// firmware's bench has it) through its points, the tip and its standard deviation; `None`
/// without an estimate.
pub fn figure(record: &Record) -> Option<Figure> {
    let e = record.estimate.as_ref()?;
    let mut backbone_m = vec![Vector3::zeros()];
    backbone_m.extend(e.backbone_m.iter().map(|p| v3(*p)));
    let f = e.tip_force_n;
    Some(Figure {
        title: format!("live link: tick {}", record.tick),
        notes: vec![
            format!("status {}, estimate of tick {}", record.status, e.tick),
            format!("tip force [{:+.4}, {:+.4}, {:+.4}] N", f[0], f[1], f[2]),
        ],
        backbone_m,
        tip_m: Some(v3(e.tip_position_m)),
        tip_std_m: Some(v3(e.tip_position_std_m)),
        ..Figure::default()
    })
}
