//! The figure of a solved or estimated robot (`--plot`): its backbone, base plate and guides, and
//! each tendon's and cable's path, computed from the shape at the guides (a hole is `p + R d`: the
//! guide's centre, its frame and the hole's offset in it).

use model_core::{Attitude, Model, ShapePoint, Tendons};
use nalgebra::Vector3;

use crate::plots::{Figure, TendonPath};
use crate::scene::SceneError;

/// Backbone points drawn, base and tip included.
const BACKBONE_POINTS: usize = 101;
/// Points on a disk's outline.
const DISK_POINTS: usize = 48;

/// The shape of an answer at increasing arc lengths.
pub(crate) type ShapeFn<'a> = dyn Fn(&[f64]) -> Result<Vec<ShapePoint<f64>>, SceneError> + 'a;

/// Each tendon's legend: whether it is slack, and its label.
pub(crate) type TendonLegend = Vec<(bool, String)>;

/// What a figure shows besides the shape.
#[derive(Debug)]
pub(crate) struct FigureSpec<'a> {
    /// Its title.
    pub title: String,
    /// Lines under the title.
    pub notes: Vec<String>,
    /// The tendons, and for each whether it is slack and its legend entry.
    pub tendons: Option<(&'a Tendons<f64>, TendonLegend)>,
    /// An estimate's tip standard deviation per axis, m.
    pub tip_std_m: Option<Vector3<f64>>,
}

/// The figure of the answer whose shape `shape` gives, on `model`.
pub(crate) fn figure<A: Attitude<f64>>(
    model: &Model<f64, A>,
    shape: &ShapeFn<'_>,
    spec: FigureSpec<'_>,
) -> Result<Figure, SceneError> {
    let length_m = model.length_m();
    let grid: Vec<f64> = (0..BACKBONE_POINTS)
        .map(|i| length_m * i as f64 / (BACKBONE_POINTS - 1) as f64)
        .collect();
    let backbone_m: Vec<Vector3<f64>> = shape(&grid)?.iter().map(|p| p.position_m).collect();
    let tip_m = *backbone_m
        .last()
        .ok_or_else(|| SceneError::new("--plot", "no backbone point"))?;
    let rod = model.rod();
    let mut guide_s: Vec<f64> = rod
        .guides
        .iter()
        .map(|g| g.s_m)
        .filter(|s| s.is_finite() && *s > 0.0 && *s <= length_m)
        .collect();
    guide_s.sort_by(f64::total_cmp);
    guide_s.dedup();
    // The base plate (s = 0), then every guide.
    let mut frame_s = vec![0.0];
    frame_s.extend(&guide_s);
    let frames = shape(&frame_s)?;
    let tendon_offsets: Vec<Vector3<f64>> = spec
        .tendons
        .as_ref()
        .map(|(set, _)| set.tendons().iter().map(|t| t.offset_local_m()).collect())
        .unwrap_or_default();
    let radius_m = tendon_offsets
        .iter()
        .map(Vector3::norm)
        .chain(rod.cables.iter().map(|c| c.radius_m()))
        .fold(0.0, f64::max);
    let disk_radius_m = if radius_m > 0.0 {
        1.25 * radius_m
    } else {
        0.03 * length_m
    };
    let disks_m = frames
        .iter()
        .map(|f| {
            (0..=DISK_POINTS)
                .map(|k| {
                    let phi = std::f64::consts::TAU * k as f64 / DISK_POINTS as f64;
                    let local = Vector3::new(phi.cos(), phi.sin(), 0.0) * disk_radius_m;
                    f.position_m + f.rotation * local
                })
                .collect()
        })
        .collect();
    let mut tendons = Vec::new();
    if let Some((set, meta)) = &spec.tendons {
        for ((t, offset), (slack, label)) in set.tendons().iter().zip(&tendon_offsets).zip(meta) {
            let holes_m = frames
                .iter()
                .take_while(|f| f.s_m <= t.end_m + 1e-6)
                .map(|f| f.position_m + f.rotation * offset)
                .collect();
            tendons.push(TendonPath {
                holes_m,
                slack: *slack,
                label: label.clone(),
            });
        }
    }
    let mut cables = Vec::new();
    for cable in &rod.cables {
        let mut s: Vec<f64> = guide_s
            .iter()
            .copied()
            .filter(|s| *s <= cable.end_m)
            .collect();
        if s.last().is_none_or(|last| *last < cable.end_m) && cable.end_m <= length_m {
            s.push(cable.end_m);
        }
        let offset = cable.offset_local_m();
        cables.push(
            shape(&s)?
                .iter()
                .map(|p| p.position_m + p.rotation * offset)
                .collect(),
        );
    }
    Ok(Figure {
        title: spec.title,
        notes: spec.notes,
        backbone_m,
        disks_m,
        tendons,
        cables,
        tip_m: Some(tip_m),
        tip_std_m: spec.tip_std_m,
        ..Figure::default()
    })
}
