//! `host-sim reference`: the f64 reference a stream is checked against, made from a scene: the
//! robot solved in f64 at each tick's tip force (a load path, such as the forces the firmware's
//! `robot` image applies), written in the columns `--check-against` reads (`check.rs`).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use model_core::{Attitude, Model, ShapePoint, ShootingSettings, Start, TipLoad};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use super::table::Table;
use crate::run::WithModel;
use crate::scene::{MAX_OUTPUT_POINTS, Scene, SceneError};

/// The command line of `host-sim reference`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// The scene (robot) file.
    pub scene: PathBuf,
    /// The load path (CSV): columns `tick`, `force_x_n`, `force_y_n`, `force_z_n` (global frame),
    /// ticks increasing; `#` lines are comments.
    #[arg(long)]
    pub forces: PathBuf,
    /// Backbone points per tick, at `L (i + 1) / N` (the firmware loop's: the quarters of the rod).
    #[arg(long, default_value_t = 4)]
    pub backbone_points: usize,
    /// Write the reference here (default: standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// One tick of a load path: its number and the tip force, N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AppliedForce {
    /// The tick.
    pub tick: u32,
    /// The tip force, N, global frame.
    pub force_n: Vector3<f64>,
}

/// Parses a load path (see [`Args::forces`]); `origin` names it in errors.
///
/// # Errors
/// A missing column, a cell that is not a finite number, no rows, or ticks out of order.
pub fn parse_forces(text: &str, origin: &str) -> Result<Vec<AppliedForce>, SceneError> {
    let table = Table::parse(text, origin)?;
    let (tick_col, force_cols) = (table.need("tick")?, table.axes("force_", "_n")?);
    let mut path: Vec<AppliedForce> = Vec::new();
    for row in table.rows() {
        path.push(AppliedForce {
            tick: row.tick(tick_col, path.last().map(|p| p.tick))?,
            force_n: row.vector(force_cols)?,
        });
    }
    if path.is_empty() {
        return Err(table.error("no rows"));
    }
    Ok(path)
}

/// The reference CSV: `scene`'s robot solved in f64 (its own `[[section]].steps`, solver settings
/// and guides; the path's force replacing its `[tip]`) at every force of `path`, each solve warm
/// from the last, with `backbone_points` points of the backbone at `L (i + 1) / N`.
///
/// # Errors
/// The scene's own errors, a `backbone_points` of zero, or a tick whose solve does not converge to
/// a stable answer (named with its tick and termination).
pub fn reference_csv(
    scene: &Scene,
    path: &[AppliedForce],
    backbone_points: usize,
) -> Result<String, SceneError> {
    if !(1..=MAX_OUTPUT_POINTS).contains(&backbone_points) {
        return Err(SceneError::new(
            "--backbone-points",
            format!("1 to {MAX_OUTPUT_POINTS}"),
        ));
    }
    // A tendon robot's reference would need each tick's actuation, which a load path of tip
    // forces does not give: solving its rod without the tendons would be another robot's.
    if !scene.tendons.is_empty() || scene.actuation.is_some() {
        return Err(SceneError::new(
            "scene",
            "it has tendons: `reference` solves a load path of tip forces on a robot whose cables \
             only measure, and a tendon robot's needs its actuation at every tick",
        ));
    }
    crate::run::with_model(
        scene,
        Reference {
            name: &scene.name,
            settings: scene.shooting_settings()?,
            path,
            backbone_points,
        },
    )
}

/// The reference's solves, on the model in the scene's frame representation.
struct Reference<'a> {
    name: &'a str,
    settings: ShootingSettings<f64>,
    path: &'a [AppliedForce],
    backbone_points: usize,
}

impl WithModel for Reference<'_> {
    type Output = String;

    fn run<A: Attitude<f64>>(self, model: &Model<f64, A>) -> Result<String, SceneError> {
        let Reference {
            name,
            settings,
            path,
            backbone_points,
        } = self;
        let length_m = model.length_m();
        let s_m: Vec<f64> = (1..=backbone_points)
            .map(|i| length_m * i as f64 / backbone_points as f64)
            .collect();
        let mut out = String::new();
        let w = |e: std::fmt::Error| SceneError::new("reference", e.to_string());
        writeln!(
            out,
            "# The f64 reference of a load path: host-sim reference of the scene \"{}\" (forward \
             solves at each tick's tip force); backbone_<i>_*: the backbone at arc lengths {} m.",
            name,
            s_m.iter()
                .map(|s| format!("{s}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
        .map_err(w)?;
        let mut header = String::from(
            "tick,expected,force_x_n,force_y_n,force_z_n,tip_x_m,tip_y_m,tip_z_m,tip_qw,tip_qx,\
             tip_qy,tip_qz",
        );
        for i in 0..backbone_points {
            for axis in ["x", "y", "z"] {
                write!(header, ",backbone_{i}_{axis}_m").map_err(w)?;
            }
        }
        writeln!(out, "{header}").map_err(w)?;
        let mut start = Start::Cold;
        let mut points = vec![ShapePoint::default(); backbone_points];
        for applied in path {
            let at_tick = |e: String| SceneError::new(format!("tick {}", applied.tick), e);
            let eq = model
                .solve(&TipLoad::force(applied.force_n), start, &settings)
                .map_err(|e| at_tick(format!("{e:?}")))?;
            if !eq.report.termination.is_success() || !eq.report.stability.is_acceptable() {
                return Err(at_tick(format!(
                    "the solve ended {:?} ({:?}): no reference",
                    eq.report.termination, eq.report.stability
                )));
            }
            start = eq.next_start();
            model
                .shape(&eq, &s_m, &mut points)
                .map_err(|e| at_tick(format!("{e:?}")))?;
            let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                eq.tip_rotation,
            ));
            let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
            let (f, tip) = (applied.force_n, eq.tip_position_m);
            let mut row = format!(
                "{},fresh,{:?},{:?},{:?},{:?},{:?},{:?}",
                applied.tick, f.x, f.y, f.z, tip.x, tip.y, tip.z
            );
            for c in [q.w, q.i, q.j, q.k] {
                write!(row, ",{:?}", sign * c).map_err(w)?;
            }
            for p in &points {
                let p = p.position_m;
                write!(row, ",{:?},{:?},{:?}", p.x, p.y, p.z).map_err(w)?;
            }
            writeln!(out, "{row}").map_err(w)?;
        }
        Ok(out)
    }
}

/// `host-sim reference`: exit 0 with the reference written, 1 for invalid input or a tick without
/// a converged, stable solve.
pub fn main(args: &Args) -> ExitCode {
    let run = || -> Result<(), SceneError> {
        let origin = args.scene.display().to_string();
        let text = std::fs::read_to_string(&args.scene)
            .map_err(|e| SceneError::new(&origin, e.to_string()))?;
        let scene = Scene::parse(&text, &origin)?;
        let forces_origin = args.forces.display().to_string();
        let forces = std::fs::read_to_string(&args.forces)
            .map_err(|e| SceneError::new(&forces_origin, e.to_string()))?;
        let path = parse_forces(&forces, &forces_origin)?;
        let csv = reference_csv(&scene, &path, args.backbone_points)?;
        crate::run::emit(&csv, args.out.as_deref())
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("host-sim reference: {e}");
            ExitCode::FAILURE
        }
    }
}
