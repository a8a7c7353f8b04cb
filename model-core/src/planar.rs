//! The planar reduction: when every load lies in one plane through the base tangent (forces in the
//! plane, moments normal to it) and the cross-section bends freely about the plane's normal, the rod
//! stays in that plane, and five planar states with one shooting unknown `k(0)` replace the 3D
//! statics (the equations: `ode/planar.rs`). The sweep, the Newton iteration and the load
//! continuation are the 3D solve's own (`sweep/`, `solve/`).
//!
//! The stability test during the solve is the in-plane one (`d theta / d k(0) > 0` along the rod and
//! a positive free-end stiffness); the answer then gets the 3D test (one 3D sweep with its Jacobi
//! fields), since an instability out of the plane is invisible to the reduction.

use nalgebra::SVector;

use crate::error::{ModelError, finite_vec};
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::dead_load::DeadLoadRod;
pub use crate::ode::planar::Plane;
use crate::ode::planar::{PlanarRod, PlanarSection};
use crate::plan::MAX_NODES;
use crate::report::Termination;
use crate::shape::ShapePoint;
use crate::shooting::{Equilibrium, ShootingSettings, equilibrium, shape_of};
use crate::sweep::{TangentSet, sweep};
use crate::{MAX_SECTIONS, Scalar};

/// How far from planar (relative to `1 +` the magnitude tested) a scene may be for the reduction.
const PLANE_TOLERANCE: f64 = 1e-9;

/// The plane a rod and a tip load stay in, if they do: every force (gravity, point loads, tip)
/// perpendicular to one normal that is perpendicular to the base tangent, every moment along it, and
/// the section's bending stiffness about that normal a principal one. `None` otherwise.
pub fn plane_of<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    load: &TipLoad<T>,
) -> Option<Plane<T>> {
    let rod = model.rod();
    let tol = T::lit(PLANE_TOLERANCE);
    let tangent = rod.base_orientation.column(2).into_owned();
    let forces = core::iter::once(rod.gravity_m_s2)
        .chain(core::iter::once(load.force_n))
        .chain(rod.loads.iter().map(|l| l.force_n));
    let moments = core::iter::once(load.moment_nm).chain(rod.loads.iter().map(|l| l.moment_nm));
    // The normal: from the first force with a component across the tangent, else the first moment,
    // else the base's local x axis (any plane through the tangent will do).
    let candidate = forces
        .clone()
        .map(|f| tangent.cross(&f))
        .chain(moments.clone())
        .find(|v| v.norm() > tol)
        .unwrap_or_else(|| rod.base_orientation.column(0).into_owned());
    let normal = candidate.try_normalize(T::default_epsilon())?;
    if normal.dot(&tangent).abs() > tol {
        return None;
    }
    let in_plane = forces
        .clone()
        .all(|f| f.dot(&normal).abs() <= tol * (T::one() + f.norm()));
    let along = moments
        .clone()
        .all(|m| (m - normal * m.dot(&normal)).norm() <= tol * (T::one() + m.norm()));
    // The normal in the base's local frame must be a principal axis unless the section is isotropic.
    let local = rod.base_orientation.tr_mul(&normal);
    let principal = rod.sections.iter().all(|s| {
        let c = s.stiffness.bending_torsion_nm2;
        (c.x - c.y).abs() <= tol * c.x || local.x.abs() <= tol || local.y.abs() <= tol
    });
    (in_plane && along && principal && local.z.abs() <= tol).then(|| Plane {
        e1: tangent,
        e2: normal.cross(&tangent),
        normal,
    })
}

/// A planar view of a model.
#[derive(Clone, Debug)]
pub struct PlanarModel<'a, T: Scalar, A: Attitude<T>, const NODES: usize = MAX_NODES> {
    model: &'a Model<T, A, NODES>,
    plane: Plane<T>,
    /// Per section: bending stiffness about the normal, `1 / G A`, `1 / E A`.
    sections: heapless::Vec<PlanarSection<T>, MAX_SECTIONS>,
}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> PlanarModel<'a, T, A, NODES> {
    /// The planar reduction of `model` under `load`, if the scene stays in a plane ([`plane_of`]).
    pub fn new(model: &'a Model<T, A, NODES>, load: &TipLoad<T>) -> Option<Self> {
        let plane = plane_of(model, load)?;
        let axis = model.rod().base_orientation.tr_mul(&plane.normal);
        let mut sections = heapless::Vec::new();
        for s in &model.rod().sections {
            let c = s.stiffness.bending_torsion_nm2;
            let d = s.stiffness.shear_axial_n;
            // Bending about the normal: the local normal is (a, b, 0), a principal axis or isotropic.
            let ei = c.x * axis.x * axis.x + c.y * axis.y * axis.y;
            let ga = d.x * axis.y * axis.y + d.y * axis.x * axis.x;
            sections.push((ei, T::one() / ga, T::one() / d.z)).ok()?;
        }
        Some(Self {
            model,
            plane,
            sections,
        })
    }

    /// The plane.
    pub fn plane(&self) -> &Plane<T> {
        &self.plane
    }

    fn ode(&self, load: &TipLoad<T>) -> PlanarRod<'_, T, A, NODES> {
        PlanarRod::new(self.model, self.plane, &self.sections, load, T::one())
    }

    /// The equilibrium under `load`, by the 3D solve's strategy and solver: Newton on `k(0)` from the
    /// bent rod's guess (MODEL.md §3.12), and if that fails or lands on an unstable equilibrium, load
    /// continuation from the unloaded rod. The answer is an [`Equilibrium`] like the 3D solve's; a
    /// failure is reported, not hidden.
    ///
    /// # Errors
    /// [`ModelError::OutOfRange`] when `load` leaves the plane (a force across it or a moment not
    /// along its normal): the reduction would drop that part. Use [`plane_of`] for the load, or the
    /// 3D solve.
    pub fn solve(
        &self,
        load: &TipLoad<T>,
        settings: &ShootingSettings<T>,
    ) -> Result<Equilibrium<T>, ModelError> {
        finite_vec(&load.force_n, "tip force")?;
        finite_vec(&load.moment_nm, "tip moment")?;
        let n = self.plane.normal;
        let tol = T::lit(PLANE_TOLERANCE);
        let across = load.force_n.dot(&n).abs() > tol * (T::one() + load.force_n.norm());
        let askew = (load.moment_nm - n * load.moment_nm.dot(&n)).norm()
            > tol * (T::one() + load.moment_nm.norm());
        if across || askew {
            return Err(ModelError::OutOfRange("tip load (it leaves the plane)"));
        }
        crate::error::positive(settings.tolerance, "solver tolerance")?;
        crate::error::positive(settings.max_rotation_step_rad, "trust region")?;
        let model = self.model;
        let ode = self.ode(load);
        let normal = ode.local_normal();
        let mut outcome = crate::solve::solve(&ode, None, settings);
        if let Ok(solved) = &mut outcome
            && solved.newton.termination.is_success()
            && settings.check_stability
        {
            // Out of the plane (bending across it with twist: lateral buckling) the reduction sees
            // nothing, so the answer gets the 3D test: one sweep with the Jacobi fields.
            solved.work.sweep();
            let full = DeadLoadRod::new(model, load, T::one());
            let u0 = normal * solved.newton.x.x;
            let swept = sweep(&full, &u0, TangentSet::unknowns(true), None);
            solved.stability = crate::solve::verdict(&full, &swept);
            if !solved.stability.is_acceptable() {
                solved.newton.termination = Termination::Unstable;
            }
        }
        Ok(equilibrium(
            load,
            model.rod().cables.len(),
            outcome,
            |k: &SVector<T, 1>| model.dead_load_base(load, &(normal * k[0])),
        ))
    }

    /// The shape of a planar equilibrium at the arc lengths `s_m` (increasing, within `[0, L]`).
    pub fn shape(
        &self,
        equilibrium: &Equilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        let ode = self.ode(&equilibrium.load);
        let k0 = equilibrium.base_strain_per_m.dot(&ode.local_normal());
        shape_of(&ode, &SVector::<T, 1>::new(k0), s_m, out)
    }
}

/// Instruction counts behind [`crate::reduction::step_cost`]: run the test binary of
/// `cargo test --release -p model-core --lib step_cost_probe -- --ignored` under
/// `valgrind --tool=callgrind --toggle-collect='*step_cost_probe::sweep_*'`, with `KIRCHHOFF=1` for
/// the Kirchhoff rod, and divide each sweep probe's inclusive count (`callgrind_annotate
/// --inclusive=yes`) by the sweeps and steps it prints.
#[cfg(test)]
mod step_cost_probe {
    use nalgebra::{SVector, Vector3};

    use super::*;
    use crate::ode::RodOde;
    use crate::rod::{Cable, Guide, Rod, Section, StrainModel};
    use crate::sweep::TangentSet;
    use crate::{CrossSection, GuideMass, Material, Start, Stiffness};

    /// The thesis's exp-2 bench: one 0.39 m section of 1.56 mm Nitinol, five 2.2 g guides (their
    /// mass spread over their thickness), three cables at 10 mm, gravity.
    fn bench(strain_model: StrainModel) -> Rod<f64> {
        let mut rod = Rod::new();
        rod.gravity_m_s2 = Vector3::new(0.0, -9.81, 0.0);
        rod.guide_mass = GuideMass::Accurate;
        rod.strain_model = strain_model;
        let d = 1.56e-3;
        let material = Material::isotropic(62.7e9, 0.3).unwrap();
        rod.push_section(Section {
            length_m: 0.39,
            stiffness: Stiffness::from_material(&material, &CrossSection::solid_circle(d).unwrap())
                .unwrap(),
            line_density_kg_per_m: 6800.0 * core::f64::consts::PI * d * d / 4.0,
            steps: 20,
        })
        .unwrap();
        for k in 0..5 {
            rod.push_guide(Guide {
                s_m: 0.0039 + 3.01e-3 / 2.0 + f64::from(k) * 0.095,
                thickness_m: 3.01e-3,
                mass_kg: 2.2e-3,
            })
            .unwrap();
        }
        for deg in [90.0_f64, 210.0, 330.0] {
            rod.push_cable(Cable::at_angle(deg.to_radians(), 0.01, 0.39))
                .unwrap();
        }
        rod
    }

    #[inline(never)]
    fn sweep_3d<O: RodOde<f64, 3>>(ode: &O, x: &SVector<f64, 3>) -> bool {
        crate::sweep::sweep(ode, x, TangentSet::NONE, None).finite
    }

    #[inline(never)]
    fn sweep_planar<O: RodOde<f64, 1>>(ode: &O, x: &SVector<f64, 1>) -> bool {
        crate::sweep::sweep(ode, x, TangentSet::NONE, None).finite
    }

    #[test]
    #[ignore = "a measurement: run under callgrind (see the module's doc)"]
    fn step_cost_probe() {
        let load = TipLoad::force(Vector3::new(0.0, -0.0402 * 9.81, 0.0));
        let settings = ShootingSettings::default();
        let repeat = 10;
        // One strain model a run, so that callgrind counts each apart.
        let strain_model = if std::env::var("KIRCHHOFF").is_ok_and(|v| v == "1") {
            StrainModel::Kirchhoff
        } else {
            StrainModel::Cosserat
        };
        let model = Model::<f64>::new(bench(strain_model)).unwrap();
        let full = model.solve(&load, Start::Cold, &settings).unwrap();
        let planar = PlanarModel::new(&model, &load).unwrap();
        let reduced = planar.solve(&load, &settings).unwrap();
        let dead = DeadLoadRod::new(&model, &load, 1.0);
        let ode = planar.ode(&load);
        let k0 = SVector::<f64, 1>::new(reduced.base_strain_per_m.dot(&ode.local_normal()));
        for _ in 0..repeat {
            assert!(sweep_3d(&dead, &full.base_strain_per_m));
            assert!(sweep_planar(&ode, &k0));
        }
        eprintln!(
            "{strain_model:?}: {repeat} sweeps of {} steps each, 3D and planar",
            model.plan().total_steps()
        );
    }
}
