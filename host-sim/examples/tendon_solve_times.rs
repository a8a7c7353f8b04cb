//! Forward solves of a tendon scene, f64, timed for a side-by-side comparison with another
//! implementation (`report/host_timings.md`, "Tendon robots").
//!
//! `cargo run --release -p host-sim --example tendon_solve_times -- SCENE.toml [t0 t1 ... fx fy fz]`
//! solves the scene's robot at the given tensions (N, one per tendon; default the scene's
//! actuation) and tip force (N, global frame; default none) and prints one line per way of solving:
//! the discrete guides from tensions, cold and warm from the answer at every tension times 0.95;
//! from the spool displacements the reference needs, cold and as a warm update from the solve at
//! the 0.95 tensions' displacements; and the continuous routing from tensions, cold. Each line
//! gives the termination, sweeps, load steps, the median wall time per solve (`BATCHES` batches of
//! `REPEATS` solves, the median of the batch means; defaults 11 and 5), the tip and its distance
//! from the reference (the same model at 800 RK4 steps per section) and the tensions. `STEPS` sets
//! the steps per section of the timed solves (default the scene's), `CONTINUOUS_STEPS` those of the
//! continuous routing's (default `STEPS`): at equal accuracy the two models need different grids.
//! Lines starting with `#` give each model's RK4 steps in all.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use host_sim::scene::{Scene, SceneError};
use model_core::{
    DisplacementSettings, Model, ShootingSettings, TendonEquilibrium, Tendons, Termination, TipLoad,
};
use nalgebra::Vector3;

fn env<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

fn refused(what: &'static str) -> impl Fn(model_core::ModelError) -> SceneError {
    move |e| SceneError::new(what, e.to_string())
}

/// The scene's robot with every section at `steps` RK4 steps, and its tendons.
fn robot(scene: &Scene, steps: Option<u16>) -> Result<(Model<f64>, Tendons<f64>), SceneError> {
    let mut scene = scene.clone();
    if let Some(steps) = steps {
        for section in &mut scene.sections {
            section.steps = steps;
        }
    }
    let model = Model::new(scene.rod()?).map_err(refused("model"))?;
    let tendons = scene
        .tendon_set(&model)?
        .ok_or_else(|| SceneError::new("tendon", "the scene has no [[tendon]]"))?;
    Ok((model, tendons))
}

/// Median over batches of the mean wall time per call of `solve`, us.
fn time_us<X>(mut solve: impl FnMut() -> X) -> f64 {
    let (batches, repeats) = (env("BATCHES").unwrap_or(11), env("REPEATS").unwrap_or(5));
    let mut means: Vec<f64> = (0..batches)
        .map(|_| {
            let t0 = Instant::now();
            for _ in 0..repeats {
                black_box(solve());
            }
            t0.elapsed().as_secs_f64() * 1e6 / f64::from(repeats)
        })
        .collect();
    means.sort_by(f64::total_cmp);
    means[means.len() / 2]
}

fn main() -> Result<(), SceneError> {
    let mut args = std::env::args().skip(1);
    let path: PathBuf = args
        .next()
        .ok_or_else(|| SceneError::new("arguments", "a scene file"))?
        .into();
    let numbers: Vec<f64> = args.filter_map(|a| a.parse().ok()).collect();
    let scene = Scene::load(&path)?;
    let (model, tendons) = robot(&scene, env("STEPS"))?;
    println!(
        "# discrete guides: {} RK4 steps in all",
        model.plan().total_steps()
    );
    let count = tendons.len();
    let tensions: Vec<f64> = match numbers.get(..count) {
        Some(t) => t.to_vec(),
        None => scene
            .actuation()?
            .map(|a| a.values)
            .ok_or_else(|| SceneError::new("actuation", "give the tensions"))?,
    };
    let force = match numbers.get(count..count + 3) {
        Some(f) => Vector3::new(f[0], f[1], f[2]),
        None => Vector3::zeros(),
    };
    let load = TipLoad::force(force);
    let settings = ShootingSettings::default();
    let control = DisplacementSettings::default();

    let (fine, fine_tendons) = robot(&scene, Some(800))?;
    let reference = fine
        .solve_tendons(&fine_tendons, &tensions, &load, None, &settings)
        .map_err(refused("reference"))?;
    let reference_tip = reference.equilibrium.tip_position_m;
    let target = fine_tendons.displacements_holding_m(&reference);

    let lighter: Vec<f64> = tensions.iter().map(|t| t * 0.95).collect();
    let previous = model
        .solve_tendons(&tendons, &lighter, &load, None, &settings)
        .map_err(refused("previous tick"))?;
    let previous_displacement = model
        .solve_displacements(
            &tendons,
            &tendons.displacements_holding_m(&previous),
            &load,
            None,
            &settings,
            &control,
        )
        .map_err(refused("previous tick's displacement solve"))?;

    let continuous_reference = fine
        .solve_tendons_continuous(&fine_tendons, &tensions, &load, None, &settings)
        .map_err(refused("continuous reference"))?
        .equilibrium
        .tip_position_m;
    // Each line's termination is its own solve's: a displacement solve's, not that of the forward
    // solve at the tensions it ended on (which converges where the displacement solve stalls).
    let print = |name: &str,
                 eq: &TendonEquilibrium<f64>,
                 termination: Termination,
                 sweeps: u32,
                 us: f64| {
        let reference_tip = if name.starts_with("continuous") {
            continuous_reference
        } else {
            reference_tip
        };
        let tip = eq.equilibrium.tip_position_m;
        println!(
            "solve={name} termination={:?} sweeps={sweeps} load_steps={} median_us={us:.1} tip_m=({:.9},{:.9},{:.9}) from_reference_m={:.2e} tensions_n={:?}",
            termination,
            eq.equilibrium.report.load_steps,
            tip.x,
            tip.y,
            tip.z,
            (tip - reference_tip).norm(),
            eq.tensions_n
                .iter()
                .map(|t| (t * 1e6).round() / 1e6)
                .collect::<Vec<_>>(),
        );
    };
    let forward = |start: Option<&TendonEquilibrium<f64>>| {
        model.solve_tendons(&tendons, &tensions, &load, start, &settings)
    };
    let cold = forward(None).map_err(refused("cold"))?;
    print(
        "tensions_cold",
        &cold,
        cold.equilibrium.report.termination,
        u32::from(cold.equilibrium.report.sweeps),
        time_us(|| forward(None)),
    );
    let warm = forward(Some(&previous)).map_err(refused("warm"))?;
    let us = time_us(|| forward(Some(&previous)));
    print(
        "tensions_warm",
        &warm,
        warm.equilibrium.report.termination,
        u32::from(warm.equilibrium.report.sweeps),
        us,
    );

    let displaced = |previous: Option<&_>| match previous {
        None => model.solve_displacements(&tendons, &target, &load, None, &settings, &control),
        Some(p) => model.update_displacements(&tendons, &target, &load, p, &settings, &control),
    };
    let d = displaced(None).map_err(refused("displacements"))?;
    print(
        "displacements_cold",
        &d.solved,
        d.termination,
        d.sweeps,
        time_us(|| displaced(None)),
    );
    let d = displaced(Some(&previous_displacement)).map_err(refused("update"))?;
    let us = time_us(|| displaced(Some(&previous_displacement)));
    print("displacements_warm", &d.solved, d.termination, d.sweeps, us);

    let (model, tendons) = match env("CONTINUOUS_STEPS") {
        Some(steps) => robot(&scene, Some(steps))?,
        None => (model, tendons),
    };
    println!(
        "# continuous routing: {} RK4 steps in all",
        model.plan().total_steps()
    );
    let continuous = || model.solve_tendons_continuous(&tendons, &tensions, &load, None, &settings);
    let c = continuous().map_err(refused("continuous"))?;
    print(
        "continuous_cold",
        &c,
        c.equilibrium.report.termination,
        u32::from(c.equilibrium.report.sweeps),
        time_us(continuous),
    );
    Ok(())
}
