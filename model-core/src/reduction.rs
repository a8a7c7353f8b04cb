//! Model only what a scene requires: from what a scene contains, pick the cheapest variant of the
//! model that still meets a requested tolerance on the tip position and the cable lengths.
//!
//! The candidates, from the full model down:
//!
//! - **planar**: every load in one plane through the base tangent ([`crate::planar`]);
//! - **Kirchhoff**: inextensible and unshearable, `v = e3` (error of order `|n| / E A`);
//! - **fewer steps**: the fewest RK4 steps per section on a ladder;
//! - **no mass bookkeeping**: without gravity, guide edges are not breakpoints (done by the plan
//!   for every variant, so it is always taken).
//!
//! Each candidate is solved and compared with the full 3D Cosserat model on a fine grid
//! ([`REFERENCE_STEPS`] per section); its cost is its step count times the cost of one step of its
//! kind, measured once (see [`step_cost`]). The pick is the cheapest candidate within the tolerance,
//! and its measured error comes with it, so a caller can see the pick meets the tolerance.
//!
//! Tendons that pull have their own picker, [`choose_tendons`]: discrete guides, continuous routing
//! or piecewise constant curvature, against the discrete guides on a fine grid
//! (`crate::tendon` `choose.rs`).

use heapless::Vec;

use crate::error::{ModelError, positive};
use crate::kinematics::Quaternion;
use crate::planar::PlanarModel;
use crate::rod::{Rod, StrainModel};
use crate::shooting::{Equilibrium, ShootingSettings, TipLoad};
use crate::{Model, Scalar};

pub use crate::tendon::{
    MAX_TENDON_TRIALS, PCC_COST, TendonChoice, TendonModel, TendonTrial, TendonVariant,
    choose_tendons, tendon_step_cost,
};

/// Steps per section of the reference the candidates are measured against.
pub const REFERENCE_STEPS: u16 = 512;

/// The step-count ladder tried for each structural variant.
pub const STEP_LADDER: [u16; 12] = [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 64, 128];

/// A variant of the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Variant {
    /// The planar reduction.
    pub planar: bool,
    /// Inextensible and unshearable.
    pub kirchhoff: bool,
    /// RK4 steps per section.
    pub steps_per_section: u16,
}

/// Relative cost of one RK4 step of a plain sweep (3D Cosserat = 100), from instruction counts on
/// x86-64 (callgrind, f64, the thesis's exp-2 bench with guide masses and three cables, 20 steps;
/// `planar.rs`'s `step_cost_probe`): 3D Cosserat 1802, 3D Kirchhoff 1794 (99.6, rounded down: it
/// does strictly less), planar Cosserat 945, planar Kirchhoff 893 instructions per step. (With the
/// planar direction stepped as a unit vector, before it was the half-turn pair, the same probe gave
/// 834 and 794; an earlier measurement on another bench, 59 and 49.)
pub fn step_cost(planar: bool, kirchhoff: bool) -> u32 {
    match (planar, kirchhoff) {
        (false, false) => 100,
        (false, true) => 99,
        (true, false) => 52,
        (true, true) => 50,
    }
}

/// One candidate tried.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trial<T> {
    /// The variant.
    pub variant: Variant,
    /// Its largest error against the reference: tip position or any cable length, m.
    pub error_m: T,
    /// Its cost: steps times step cost.
    pub cost: u32,
    /// Whether its solve converged.
    pub converged: bool,
}

/// Most trials a choice records.
pub const MAX_TRIALS: usize = 2 * 2 * STEP_LADDER.len();

/// The pick, with every candidate tried.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice<T> {
    /// The cheapest variant within the tolerance.
    pub variant: Variant,
    /// Its measured error against the reference, m.
    pub error_m: T,
    /// Its cost.
    pub cost: u32,
    /// The cost of the full model (3D Cosserat) at the fewest steps that meet the tolerance.
    pub full_cost: u32,
    /// Every candidate tried.
    pub trials: Vec<Trial<T>, MAX_TRIALS>,
}

fn variant_rod<T: Scalar>(rod: &Rod<T>, kirchhoff: bool, steps: u16) -> Rod<T> {
    let mut rod = rod.clone();
    rod.strain_model = if kirchhoff {
        StrainModel::Kirchhoff
    } else {
        StrainModel::Cosserat
    };
    for section in rod.sections.iter_mut() {
        section.steps = steps;
    }
    rod
}

fn solve_variant<T: Scalar>(
    rod: &Rod<T>,
    load: &TipLoad<T>,
    variant: Variant,
    settings: &ShootingSettings<T>,
) -> Result<(Equilibrium<T>, u32), ModelError> {
    let model = Model::<T, Quaternion<T>>::new(variant_rod(
        rod,
        variant.kirchhoff,
        variant.steps_per_section,
    ))?;
    let cost = model
        .plan()
        .total_steps()
        .saturating_mul(step_cost(variant.planar, variant.kirchhoff));
    let eq = if variant.planar {
        match PlanarModel::new(&model, load) {
            Some(planar) => planar.solve(load, settings)?,
            None => {
                return Err(ModelError::OutOfRange(
                    "planar variant of a scene that is not planar",
                ));
            }
        }
    } else {
        model.solve_dead_load(load, None, settings)?
    };
    Ok((eq, cost))
}

fn error_m<T: Scalar>(a: &Equilibrium<T>, b: &Equilibrium<T>) -> T {
    let tip = (a.tip_position_m - b.tip_position_m).norm();
    a.cable_lengths_m
        .iter()
        .zip(b.cable_lengths_m.iter())
        .fold(tip, |m, (x, y)| m.max((*x - *y).abs()))
}

/// Picks the cheapest variant of `rod` under `load` whose tip position and cable lengths stay within
/// `tolerance_m` of the full model. Fails on invalid input, or with `OutOfRange("tolerance")` if even
/// the full model on the largest ladder step does not meet it (or the reference does not converge).
pub fn choose<T: Scalar>(
    rod: &Rod<T>,
    load: &TipLoad<T>,
    tolerance_m: T,
    settings: &ShootingSettings<T>,
) -> Result<Choice<T>, ModelError> {
    positive(tolerance_m, "tolerance")?;
    let full = Variant {
        planar: false,
        kirchhoff: false,
        steps_per_section: REFERENCE_STEPS,
    };
    let (reference, _) = solve_variant(rod, load, full, settings)?;
    if !reference.report.termination.is_success() {
        return Err(ModelError::OutOfRange(
            "tolerance (the reference solve did not converge)",
        ));
    }
    let probe = Model::<T, Quaternion<T>>::new(rod.clone())?;
    let planar_possible = PlanarModel::new(&probe, load).is_some();
    let mut trials: Vec<Trial<T>, MAX_TRIALS> = Vec::new();
    let mut best: Option<Trial<T>> = None;
    let mut full_cost = None;
    for planar in [false, true] {
        if planar && !planar_possible {
            continue;
        }
        for kirchhoff in [false, true] {
            for &steps in &STEP_LADDER {
                let variant = Variant {
                    planar,
                    kirchhoff,
                    steps_per_section: steps,
                };
                let (eq, cost) = solve_variant(rod, load, variant, settings)?;
                let converged = eq.report.termination.is_success();
                let error = if converged {
                    error_m(&eq, &reference)
                } else {
                    T::max_value().unwrap_or_else(T::one)
                };
                let trial = Trial {
                    variant,
                    error_m: error,
                    cost,
                    converged,
                };
                // Cannot overflow: at most MAX_TRIALS candidates.
                let _ = trials.push(trial);
                if converged && error <= tolerance_m {
                    if !planar && !kirchhoff && full_cost.is_none() {
                        full_cost = Some(cost);
                    }
                    if best.is_none_or(|b| cost < b.cost) {
                        best = Some(trial);
                    }
                    // More steps only cost more.
                    break;
                }
            }
        }
    }
    let best = best.ok_or(ModelError::OutOfRange("tolerance (no variant meets it)"))?;
    Ok(Choice {
        variant: best.variant,
        error_m: best.error_m,
        cost: best.cost,
        full_cost: full_cost.unwrap_or(best.cost),
        trials,
    })
}
