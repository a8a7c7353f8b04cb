//! Cold and warm forward solves of the thesis's bare rod (experiment 2's rod without guides, clamped
//! along +x, gravity along -y) with a mass at the tip, f64, for a side-by-side timing against another
//! implementation (`report/host_timings.md`).
//!
//! `cargo run --release -p model-core --example cold_tip_masses -- [grams ...]` prints one line per
//! mass: the termination, sweeps, load steps, the median wall time per solve (31 batches of 50
//! solves, the median of the batch means) and the tip. `STEPS` sets the RK4 steps (default 12),
//! `TOLERANCE` the solver's (default `ShootingSettings::default`'s); with a tolerance, the line
//! also gives the tip's distance from the default tolerance's answer. `WARM=1` adds two lines per
//! mass: the solve warm from the answer at a 1 % lighter mass, from its base strain
//! (`Start::Warm`) and from the neighbour (`Equilibrium::next_start`). `PLANAR=1` adds one line per
//! mass: the planar reduction's cold solve (`PlanarModel`, with its stability sweep out of the plane), its tip
//! compared, as every line's, with the 3D solve's at the default tolerance.

use std::time::Instant;

use model_checks::reference;
use model_core::planar::PlanarModel;
use model_core::rod::{GuideMass, Rod, Section};
use model_core::{Model, ModelError, Quaternion, ShootingSettings, Start, TipLoad};
use nalgebra::Vector3;

/// What a line times: the 3D solve from a start, or the planar reduction's cold solve.
enum Solver<'a> {
    Full(Start<f64>),
    Planar(PlanarModel<'a, f64, Quaternion<f64>>),
}

fn env<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

fn main() -> Result<(), ModelError> {
    let mut rod = Rod::<f64>::new();
    rod.guide_mass = GuideMass::Ignore;
    rod.push_section(Section {
        length_m: reference::FREE_LENGTH_M,
        stiffness: reference::nitinol_stiffness(reference::YOUNGS_MODULUS_PA)?,
        line_density_kg_per_m: reference::bare_line_density_kg_m(),
        steps: env("STEPS").unwrap_or(12),
    })?;
    let model = Model::<f64>::new(rod)?;
    let mut grams: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    if grams.is_empty() {
        grams = vec![0.0, 10.0, 20.0, 40.2, 50.0, 60.0, 83.2, 100.0, 120.0];
    }
    let tight = ShootingSettings::default();
    let settings = ShootingSettings {
        tolerance: env("TOLERANCE").unwrap_or(tight.tolerance),
        ..tight
    };
    let warm = env::<u8>("WARM").is_some_and(|w| w != 0);
    let planar = env::<u8>("PLANAR").is_some_and(|w| w != 0);
    let hang = |grams: f64| {
        TipLoad::force(Vector3::new(
            0.0,
            -grams * 1e-3 * reference::GRAVITY_M_S2,
            0.0,
        ))
    };
    for g in grams {
        let load = hang(g);
        let converged = model.solve(&load, Start::Cold, &tight)?;
        if !converged.report.termination.is_success() {
            // Every line's from_converged_m is measured against it: no reference, no distance.
            eprintln!(
                "mass_g={g}: the reference solve (cold, default tolerance) did not converge ({:?})",
                converged.report.termination
            );
            std::process::exit(1);
        }
        let lighter = model.solve(&hang(g * 0.99), Start::Cold, &settings)?;
        let mut solvers = vec![("cold", Solver::Full(Start::Cold))];
        if warm {
            let start = Start::Warm(lighter.base_strain_per_m);
            solvers.push(("warm", Solver::Full(start)));
            solvers.push(("neighbour", Solver::Full(lighter.next_start())));
        }
        if let Some(reduced) = PlanarModel::new(&model, &load).filter(|_| planar) {
            solvers.push(("planar", Solver::Planar(reduced)));
        }
        for (name, solver) in &solvers {
            let solve = |load: &TipLoad<f64>| match solver {
                Solver::Full(start) => model.solve(load, *start, &settings),
                Solver::Planar(reduced) => reduced.solve(load, &settings),
            };
            let eq = solve(&load)?;
            let mut batches = Vec::new();
            for _ in 0..31 {
                let t0 = Instant::now();
                for _ in 0..50 {
                    std::hint::black_box(solve(std::hint::black_box(&load))?);
                }
                batches.push(t0.elapsed().as_secs_f64() * 1e6 / 50.0);
            }
            batches.sort_by(f64::total_cmp);
            let tip = eq.tip_position_m;
            println!(
                "mass_g={g} start={name} termination={:?} sweeps={} load_steps={} median_us={:.2} tip_m=({:.9},{:.9},{:.9}) from_converged_m={:.1e}",
                eq.report.termination,
                eq.report.sweeps,
                eq.report.load_steps,
                batches[batches.len() / 2],
                tip.x,
                tip.y,
                tip.z,
                (tip - converged.tip_position_m).norm(),
            );
        }
    }
    Ok(())
}
