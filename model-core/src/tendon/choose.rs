//! The tendon counterpart of [`crate::reduction::choose`] (MODEL.md §6.10): for a tendon scene, the
//! cheapest of discrete guides, continuous routing and piecewise constant curvature (with the fewest
//! RK4 steps on [`STEP_LADDER`]) whose tip position and path lengths stay within a tolerance of the
//! discrete-guide model on a fine grid ([`REFERENCE_STEPS`] per section).
//!
//! The discrete guides are the reference because they are the routing the robot has; continuous
//! routing differs from it by a term of order (guide spacing)^2 (`tests/tendon_variants.rs`), and
//! PCC also ignores gravity and the tip load. A variant's cost is its sweep's steps times the
//! measured cost of one step of its kind ([`tendon_step_cost`]); PCC costs [`PCC_COST`] whatever
//! the grid.

use heapless::Vec;

use super::{Tendon, TendonEquilibrium, Tendons};
use crate::error::{ModelError, positive};
use crate::kinematics::Quaternion;
use crate::reduction::{REFERENCE_STEPS, STEP_LADDER};
use crate::rod::Rod;
use crate::shooting::{ShootingSettings, TipLoad};
use crate::{Model, Scalar};

/// A tendon model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TendonModel {
    /// Chords between the guide holes, an implicit jump per guide ([`Model::solve_tendons`]).
    DiscreteGuides,
    /// Tendons along the backbone, Rucker & Webster ([`Model::solve_tendons_continuous`]).
    Continuous,
    /// Piecewise constant curvature from the tendons' moments, closed form
    /// ([`Model::solve_tendons_pcc`]).
    ConstantCurvature,
}

/// A variant of the tendon model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TendonVariant {
    /// The model.
    pub model: TendonModel,
    /// RK4 steps per section (zero for PCC, which has no grid).
    pub steps_per_section: u16,
}

/// Relative cost of one RK4 step of a plain sweep, in the units of
/// [`crate::reduction::step_cost`] (a 3D Cosserat step of the dead-load equations = 100), from
/// instruction counts (callgrind, x86-64, f64, the test profile) on the two-section, six-tendon
/// robot (14 guides, gravity, a tip force, 20 steps per section: 48 steps; at its solution;
/// `cost_probe` below): dead load 1828, discrete guides 22091 (38845 before a plain sweep's jumps
/// took chord steps and `W_next` its direct form, MODEL.md §6.5), continuous routing 18338
/// instructions per step (20499 before a sweep carried the chord matrix across the intervals of
/// one section and set of tendons). A discrete-guide step includes its share of the look-ahead
/// each implicit jump integrates (a Newton pass over the segment with six directions, then chord
/// passes of the state alone); a continuous step its four strain solves (chord steps from the
/// straight tendons). Whole cold solves there: discrete guides 25.1 M instructions (9 sweeps; 58.4 M
/// and 21 sweeps before the joint step and the trust region by the shape, §6.3, §6.5), continuous
/// routing 14.1 M (7 sweeps; 23.8 M before the chord matrix carried across intervals, the block
/// inverse of the strain solve's Jacobian and the paths read from the converged sweep, §6.8).
pub fn tendon_step_cost(model: TendonModel) -> u32 {
    match model {
        TendonModel::DiscreteGuides => DISCRETE_STEP_COST,
        TendonModel::Continuous => CONTINUOUS_STEP_COST,
        TendonModel::ConstantCurvature => 0,
    }
}

const DISCRETE_STEP_COST: u32 = 1208;
const CONTINUOUS_STEP_COST: u32 = 1003;

/// The cost of a piecewise-constant-curvature shape, in the same units: the whole closed form
/// (7442 instructions on the same robot, checks included). The grid variants' costs are one plain
/// sweep's, and a solve takes many sweeps, so PCC is cheaper still than this comparison says.
pub const PCC_COST: u32 = 407;

/// One candidate tried.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TendonTrial<T> {
    /// The variant.
    pub variant: TendonVariant,
    /// Its largest distance from the reference: tip position or any path length, m.
    pub error_m: T,
    /// Its cost.
    pub cost: u32,
    /// Whether its solve converged.
    pub converged: bool,
}

/// Most trials a choice records: PCC, then each grid model on the ladder.
pub const MAX_TENDON_TRIALS: usize = 1 + 2 * STEP_LADDER.len();

/// The pick, with every candidate tried.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonChoice<T> {
    /// The cheapest variant within the tolerance.
    pub variant: TendonVariant,
    /// Its measured distance from the reference, m.
    pub error_m: T,
    /// Its cost.
    pub cost: u32,
    /// The cost of the discrete guides at the fewest steps that meet the tolerance (the cost of
    /// the pick when none does).
    pub discrete_cost: u32,
    /// The reference: discrete guides at [`REFERENCE_STEPS`] per section.
    pub reference: TendonEquilibrium<T>,
    /// Every candidate tried.
    pub trials: Vec<TendonTrial<T>, MAX_TENDON_TRIALS>,
}

fn with_steps<T: Scalar>(rod: &Rod<T>, steps: u16) -> Rod<T> {
    let mut rod = rod.clone();
    for section in rod.sections.iter_mut() {
        section.steps = steps;
    }
    rod
}

fn solve_variant<T: Scalar>(
    rod: &Rod<T>,
    tendons: &[Tendon<T>],
    tensions_n: &[T],
    load: &TipLoad<T>,
    variant: TendonVariant,
    settings: &ShootingSettings<T>,
) -> Result<(TendonEquilibrium<T>, u32), ModelError> {
    let steps = variant.steps_per_section.max(1);
    let model = Model::<T, Quaternion<T>>::new(with_steps(rod, steps))?;
    let set = Tendons::new(&model, tendons)?;
    let cost = model
        .plan()
        .total_steps()
        .saturating_mul(tendon_step_cost(variant.model));
    Ok(match variant.model {
        TendonModel::DiscreteGuides => (
            model.solve_tendons(&set, tensions_n, load, None, settings)?,
            cost,
        ),
        TendonModel::Continuous => (
            model.solve_tendons_continuous(&set, tensions_n, load, None, settings)?,
            cost,
        ),
        TendonModel::ConstantCurvature => (
            model.solve_tendons_pcc_ignoring_loads(&set, tensions_n, load)?,
            PCC_COST,
        ),
    })
}

/// The largest distance between two tendon equilibria: tip position or any path length, m.
fn distance_m<T: Scalar>(a: &TendonEquilibrium<T>, b: &TendonEquilibrium<T>) -> T {
    let tip = (a.equilibrium.tip_position_m - b.equilibrium.tip_position_m).norm();
    a.path_m
        .iter()
        .zip(b.path_m.iter())
        .fold(tip, |m, (x, y)| m.max((*x - *y).abs()))
}

/// Picks the cheapest tendon variant for `rod` with `tendons` at `tensions_n` under `load` whose tip
/// position and path lengths stay within `tolerance_m` of the discrete-guide model on a fine grid.
///
/// Fails on invalid input, or with `OutOfRange("tolerance")` if the reference does not converge or
/// no variant meets the tolerance (not even the discrete guides at the ladder's top).
pub fn choose_tendons<T: Scalar>(
    rod: &Rod<T>,
    tendons: &[Tendon<T>],
    tensions_n: &[T],
    load: &TipLoad<T>,
    tolerance_m: T,
    settings: &ShootingSettings<T>,
) -> Result<TendonChoice<T>, ModelError> {
    positive(tolerance_m, "tolerance")?;
    let full = TendonVariant {
        model: TendonModel::DiscreteGuides,
        steps_per_section: REFERENCE_STEPS,
    };
    let (reference, _) = solve_variant(rod, tendons, tensions_n, load, full, settings)?;
    if !reference.is_success() {
        return Err(ModelError::OutOfRange(
            "tolerance (the reference solve did not converge)",
        ));
    }
    let mut trials: Vec<TendonTrial<T>, MAX_TENDON_TRIALS> = Vec::new();
    let mut best: Option<TendonTrial<T>> = None;
    let mut discrete_cost = None;
    let pcc = [0u16];
    for model in [
        TendonModel::ConstantCurvature,
        TendonModel::Continuous,
        TendonModel::DiscreteGuides,
    ] {
        let ladder: &[u16] = if model == TendonModel::ConstantCurvature {
            &pcc
        } else {
            &STEP_LADDER
        };
        for &steps in ladder {
            let variant = TendonVariant {
                model,
                steps_per_section: steps,
            };
            let (eq, cost) = solve_variant(rod, tendons, tensions_n, load, variant, settings)?;
            let converged = eq.is_success();
            let error_m = if converged {
                distance_m(&eq, &reference)
            } else {
                T::max_value().unwrap_or_else(T::one)
            };
            let trial = TendonTrial {
                variant,
                error_m,
                cost,
                converged,
            };
            // Cannot overflow: at most MAX_TENDON_TRIALS candidates.
            let _ = trials.push(trial);
            if converged && error_m <= tolerance_m {
                if model == TendonModel::DiscreteGuides && discrete_cost.is_none() {
                    discrete_cost = Some(cost);
                }
                if best.is_none_or(|b| cost < b.cost) {
                    best = Some(trial);
                }
                // More steps only cost more.
                break;
            }
        }
    }
    let best = best.ok_or(ModelError::OutOfRange("tolerance (no variant meets it)"))?;
    Ok(TendonChoice {
        variant: best.variant,
        error_m: best.error_m,
        cost: best.cost,
        discrete_cost: discrete_cost.unwrap_or(best.cost),
        reference,
        trials,
    })
}

/// Instruction counts behind [`tendon_step_cost`]: run the test binary of
/// `cargo test -p model-core --lib tendon_cost_probe -- --ignored` under
/// `valgrind --tool=callgrind --toggle-collect='*cost_probe::sweep_*'
/// --toggle-collect='*cost_probe::solve_*'`, and divide each sweep probe's inclusive count by the
/// sweeps and steps it prints (`callgrind_annotate --inclusive=yes`).
#[cfg(test)]
mod cost_probe {
    use nalgebra::{SVector, Vector3};

    use super::*;
    use crate::ode::RodOde;
    use crate::ode::dead_load::DeadLoadRod;
    use crate::ode::tendon::TendonRod;
    use crate::ode::tendon_continuous::ContinuousTendonRod;
    use crate::sweep::{TangentSet, sweep};
    use crate::tendon::MAX_TENDONS;
    use crate::{CrossSection, Guide, GuideMass, Material, Section, Stiffness};

    /// The golden two-section, six-tendon robot with massless guides (`tests/data/golden`).
    fn robot(steps: u16) -> (Rod<f64>, [Tendon<f64>; 6]) {
        let mut rod = Rod::new();
        rod.gravity_m_s2 = Vector3::new(0.0, -9.81, 0.0);
        rod.guide_mass = GuideMass::Ignore;
        for (length, d) in [(0.15, 1.2e-3), (0.12, 1.0e-3)] {
            let material = Material::isotropic(58e9, 0.3).unwrap();
            rod.push_section(Section {
                length_m: length,
                stiffness: Stiffness::from_material(
                    &material,
                    &CrossSection::solid_circle(d).unwrap(),
                )
                .unwrap(),
                line_density_kg_per_m: 6450.0 * core::f64::consts::PI * d * d / 4.0,
                steps,
            })
            .unwrap();
        }
        let centres = (1..=8)
            .map(|k| 0.15 * f64::from(k) / 8.0)
            .chain((1..=6).map(|k| 0.15 + 0.02 * f64::from(k)));
        for s in centres {
            rod.push_guide(Guide {
                s_m: s,
                thickness_m: 0.0,
                mass_kg: 0.0,
            })
            .unwrap();
        }
        let t = |deg: f64, end: f64| Tendon::at_angle(deg.to_radians(), 8e-3, end);
        (
            rod,
            [
                t(60.0, 0.15),
                t(180.0, 0.15),
                t(300.0, 0.15),
                t(0.0, 0.27),
                t(120.0, 0.27),
                t(240.0, 0.27),
            ],
        )
    }

    const TENSIONS: [f64; 6] = [1.0, 0.5, 0.0, 1.5, 0.3, 0.8];

    #[inline(never)]
    fn sweep_dead_load<O: RodOde<f64, 3>>(ode: &O, x: &SVector<f64, 3>) -> bool {
        sweep(ode, x, TangentSet::NONE, None).finite
    }

    #[inline(never)]
    fn sweep_discrete<O: RodOde<f64, 6>>(ode: &O, x: &SVector<f64, 6>) -> bool {
        sweep(ode, x, TangentSet::NONE, None).finite
    }

    #[inline(never)]
    fn sweep_continuous<O: RodOde<f64, 6>>(ode: &O, x: &SVector<f64, 6>) -> bool {
        sweep(ode, x, TangentSet::NONE, None).finite
    }

    #[inline(never)]
    fn sweep_pcc(model: &Model<f64>, set: &Tendons<f64>, load: &TipLoad<f64>) -> bool {
        model
            .solve_tendons_pcc_ignoring_loads(set, &TENSIONS, load)
            .is_ok_and(|s| s.is_success())
    }

    #[inline(never)]
    fn solve_discrete(model: &Model<f64>, set: &Tendons<f64>, load: &TipLoad<f64>) -> u16 {
        let settings = ShootingSettings::default();
        let eq = model.solve_tendons(set, &TENSIONS, load, None, &settings);
        eq.map_or(0, |e| e.equilibrium.report.sweeps)
    }

    #[inline(never)]
    fn solve_continuous(model: &Model<f64>, set: &Tendons<f64>, load: &TipLoad<f64>) -> u16 {
        let settings = ShootingSettings::default();
        let eq = model.solve_tendons_continuous(set, &TENSIONS, load, None, &settings);
        eq.map_or(0, |e| e.equilibrium.report.sweeps)
    }

    #[test]
    #[ignore = "a measurement: run under callgrind (see the module's doc)"]
    fn tendon_cost_probe() {
        let (rod, tendons) = robot(20);
        let model = Model::<f64>::new(rod).unwrap();
        let set = Tendons::new(&model, &tendons).unwrap();
        let load = TipLoad::force(Vector3::new(0.02, -0.05, 0.03));
        let settings = ShootingSettings::default();
        let mut tau = [0.0; MAX_TENDONS];
        tau[..6].copy_from_slice(&TENSIONS);
        let discrete = model
            .solve_tendons(&set, &TENSIONS, &load, None, &settings)
            .unwrap();
        let continuous = model
            .solve_tendons_continuous(&set, &TENSIONS, &load, None, &settings)
            .unwrap();
        let dead = model.solve(&load, crate::Start::Cold, &settings).unwrap();
        let d_ode = TendonRod::new(&model, &set, &tau, &load, 1.0);
        let c_ode = ContinuousTendonRod::new(&model, &set, &tau, &load, 1.0);
        let eq = &discrete.equilibrium;
        let xd = d_ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        let eq = &continuous.equilibrium;
        let xc = c_ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        let dl = DeadLoadRod::new(&model, &load, 1.0);
        let repeat = 10;
        for _ in 0..repeat {
            assert!(sweep_dead_load(&dl, &dead.base_strain_per_m));
            assert!(sweep_discrete(&d_ode, &xd));
            assert!(sweep_continuous(&c_ode, &xc));
            assert!(sweep_pcc(&model, &set, &load));
        }
        eprintln!(
            "{repeat} sweeps of {} steps each (PCC: {repeat} shapes)",
            model.plan().total_steps()
        );
        // Whole cold solves (`--toggle-collect='*cost_probe::solve_*'`).
        eprintln!(
            "cold solves: discrete {} sweeps, continuous {} sweeps",
            solve_discrete(&model, &set, &load),
            solve_continuous(&model, &set, &load)
        );
    }
}
