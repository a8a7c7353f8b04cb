//! The figure of a calibration (`calibrate --plot`): each experiment's backbone at the fitted
//! values and the points observed, in the measurement frame, in the three projections of
//! [`crate::plots::draw_figure`].

use nalgebra::Vector3;

use super::data::{Measurements, Observation};
use super::fit::Calibration;
use super::forward::Forward;
use super::params::Values;
use crate::plots::Figure;
use crate::scene::{Scene, SceneError};

/// Points drawn along each experiment's backbone, base to tip.
const BACKBONE_POINTS: usize = 61;

/// The figure of calibration `c` of `scene` on `data` at its fitted `values`: `None` when a solve
/// at those values has no answer (nothing to draw).
pub fn figure(
    scene: &Scene,
    data: &Measurements,
    values: &Values,
    c: &Calibration,
) -> Result<Option<Figure>, SceneError> {
    let length_m = scene.rod()?.length_m();
    // The same experiments, observed densely along the whole backbone.
    let mut dense = data.clone();
    for e in &mut dense.experiments {
        e.observations = (0..BACKBONE_POINTS)
            .map(|k| Observation {
                line: e.line,
                s_m: length_m * k as f64 / (BACKBONE_POINTS - 1) as f64,
                at_tip: k + 1 == BACKBONE_POINTS,
                position_m: [0.0; 3],
                weight: 1.0,
            })
            .collect();
    }
    let all: Vec<usize> = (0..dense.experiments.len()).collect();
    let Ok(points) = Forward::new(scene, &dense)?.predict(values, &all)? else {
        return Ok(None);
    };
    let mut backbones: Vec<Vec<Vector3<f64>>> = points
        .chunks(BACKBONE_POINTS)
        .map(<[Vector3<f64>]>::to_vec)
        .collect();
    if backbones.is_empty() {
        return Ok(None);
    }
    let backbone_m = backbones.remove(0);
    let rms = c
        .rms_mm
        .map_or_else(String::new, |r| format!(", rms {r:.3} mm"));
    Ok(Some(Figure {
        title: format!("calibrate: {}", c.scene),
        notes: vec![format!(
            "fitted {} to {} points in {} experiments{rms}; measurement frame",
            c.fitted.join(", "),
            data.observation_count(),
            data.experiments.len(),
        )],
        backbone_m,
        more_backbones_m: backbones,
        observed_m: data
            .observations()
            .map(|(_, o)| Vector3::from(o.position_m))
            .collect(),
        ..Figure::default()
    }))
}
