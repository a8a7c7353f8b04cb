//! A validated scene ready to solve: the rod, its integration plan and precomputed compliances.

use core::marker::PhantomData;

use heapless::Vec;
use nalgebra::{Matrix3, Vector3};

use crate::constitutive::Compliance;
use crate::error::{ModelError, finite_vec};
use crate::integrate::{Inputs, Tangents, sweep};
use crate::kinematics::{Attitude, Quaternion};
use crate::plan::MAX_NODES;
use crate::plan::Plan;
use crate::rod::Rod;
use crate::shape::{ShapePoint, ShapeSink};
use crate::shooting::{Equilibrium, TipLoad};
use crate::{MAX_CABLES, MAX_SECTIONS, Scalar};

/// A scene ready to solve. `A` chooses how the frame is integrated (see [`crate::kinematics`]).
#[derive(Clone, Debug)]
pub struct Model<T: Scalar, A: Attitude<T> = Quaternion<T>, const NODES: usize = MAX_NODES> {
    rod: Rod<T>,
    plan: Plan<T, NODES>,
    compliances: Vec<Compliance<T>, MAX_SECTIONS>,
    /// Each cable's hole offset in the local frame, m (zero beyond the rod's cables).
    cable_offsets: [Vector3<T>; MAX_CABLES],
    base: A,
    length_m: T,
    moment_scale_nm: T,
    _attitude: PhantomData<A>,
}

/// One sweep at a given base strain and tip load, without solving: for diagnostics and tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Evaluation<T> {
    /// Tip position, m.
    pub tip_position_m: Vector3<T>,
    /// Tip frame.
    pub tip_rotation: Matrix3<T>,
    /// `C u(L) - R(L)^T tau_tip`, N m, body frame.
    pub moment_residual_nm: Vector3<T>,
    /// Cable lengths, m, one per cable (the rest zero).
    pub cable_lengths_m: [T; MAX_CABLES],
    /// Largest `|R^T R - I|` met at the nodes (rotation drift of the integrator).
    pub frame_drift: T,
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// Validates the rod and builds its plan.
    pub fn new(rod: Rod<T>) -> Result<Self, ModelError> {
        rod.validate()?;
        let plan = Plan::new(&rod)?;
        let mut compliances = Vec::new();
        let mut min_bending = T::max_value().unwrap_or_else(T::one);
        for section in &rod.sections {
            compliances
                .push(Compliance::new(&section.stiffness))
                .map_err(|_| ModelError::Capacity("sections"))?;
            min_bending = min_bending.min(section.stiffness.min_bending_nm2());
        }
        let length_m = rod.length_m();
        let mut cable_offsets = [Vector3::zeros(); MAX_CABLES];
        for (offset, cable) in cable_offsets.iter_mut().zip(&rod.cables) {
            *offset = cable.offset_local_m();
        }
        Ok(Self {
            cable_offsets,
            base: A::from_matrix(&rod.base_orientation),
            rod,
            plan,
            compliances,
            length_m,
            moment_scale_nm: min_bending / length_m,
            _attitude: PhantomData,
        })
    }

    /// The scene.
    pub fn rod(&self) -> &Rod<T> {
        &self.rod
    }

    /// The integration grid.
    pub fn plan(&self) -> &Plan<T, NODES> {
        &self.plan
    }

    /// Total reference length, m.
    pub fn length_m(&self) -> T {
        self.length_m
    }

    /// `E I_min / L`, N m: a tip-moment error of this size bends the rod by about one radian.
    pub fn moment_scale_nm(&self) -> T {
        self.moment_scale_nm
    }

    /// Whether every load on the rod plus `tip_moment_nm` is conservative (no moment acts).
    pub(crate) fn conservative(&self, tip_moment_nm: &Vector3<T>) -> bool {
        *tip_moment_nm == Vector3::zeros()
            && self
                .rod
                .loads
                .iter()
                .all(|l| l.moment_nm == Vector3::zeros())
    }

    pub(crate) fn cable_offsets(&self) -> &[Vector3<T>; MAX_CABLES] {
        &self.cable_offsets
    }

    pub(crate) fn base_attitude(&self) -> &A {
        &self.base
    }

    pub(crate) fn compliance(&self, section: u8) -> Option<&Compliance<T>> {
        self.compliances.get(usize::from(section))
    }

    /// The dimensionless size of a tip-moment residual (see [`crate::SolveReport::residual`]).
    pub(crate) fn moment_residual(&self, e: &Vector3<T>) -> T {
        e.norm() / self.moment_scale_nm
    }

    /// Whether a Newton correction `du0` of the base strain is negligible: it turns the base by less
    /// than `tolerance`, and moves the tip (`tip_move_m`, predicted by the sweep's tangents) by less
    /// than `tolerance L`, both relative to `|u0| L` beyond one radian, as for the residual. This is
    /// where the rounding floor may lie; [`Model::tip_move_negligible`] says whether the answer is
    /// already there without trying the step.
    pub(crate) fn step_converged(
        &self,
        du0: &Vector3<T>,
        u0: &Vector3<T>,
        tip_move_m: T,
        tolerance: T,
    ) -> bool {
        let relative = (u0.norm() * self.length_m).max(T::one());
        du0.norm() * self.length_m <= tolerance * relative
            && tip_move_m <= tolerance * self.length_m * relative
    }

    /// Whether a Newton correction's predicted tip move is below `tolerance L`, not relative: in f32
    /// the tip resolves to a few micrometres even at `|u0| L = 12` (measured), while the relative bound
    /// of [`Model::step_converged`] would accept 0.1 mm there.
    pub(crate) fn tip_move_negligible(&self, tip_move_m: T, tolerance: T) -> bool {
        tip_move_m <= tolerance * self.length_m
    }

    /// Whether a tip-moment residual meets `tolerance` at base strain `u0`: the tolerance is relative
    /// to the base rotation `|u0| L` once that exceeds one radian, because rounding grows with it.
    pub(crate) fn moment_converged(&self, e: &Vector3<T>, u0: &Vector3<T>, tolerance: T) -> bool {
        self.moment_residual(e) <= tolerance * (u0.norm() * self.length_m).max(T::one())
    }

    /// One sweep at base strain `u0` (1/m) under `load`, without solving for the boundary condition.
    pub fn evaluate(
        &self,
        base_strain_per_m: &Vector3<T>,
        load: &TipLoad<T>,
    ) -> Result<Evaluation<T>, ModelError> {
        finite_vec(base_strain_per_m, "base strain")?;
        load.validate()?;
        let out = sweep(
            self,
            &self.inputs(base_strain_per_m, load, T::one()),
            Tangents::NONE,
            None,
        );
        if !out.finite {
            return Err(ModelError::NonFinite("sweep result"));
        }
        Ok(Evaluation {
            tip_position_m: out.tip_position_m,
            tip_rotation: out.tip_rotation,
            moment_residual_nm: out.moment_residual_nm,
            cable_lengths_m: out.cable_m,
            frame_drift: out.frame_drift,
        })
    }

    /// The shape of a solved equilibrium at the arc lengths `s_m` (increasing, within `[0, L]`),
    /// written into `out` (at least as long). Returns how many points were written.
    pub fn shape(
        &self,
        equilibrium: &Equilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        self.shape_at(&equilibrium.base_strain_per_m, &equilibrium.load, s_m, out)
    }

    /// The shape at a given base strain and tip load (see [`Model::shape`]).
    pub fn shape_at(
        &self,
        base_strain_per_m: &Vector3<T>,
        load: &TipLoad<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        finite_vec(base_strain_per_m, "base strain")?;
        load.validate()?;
        if out.len() < s_m.len() {
            return Err(ModelError::Mismatch("shape queries and output buffer"));
        }
        let mut previous = T::zero();
        for &s in s_m {
            crate::error::finite(s, "shape arc length")?;
            if s < previous {
                return Err(ModelError::Unordered("shape arc lengths"));
            }
            if s > self.length_m {
                return Err(ModelError::OutOfRange("shape arc length"));
            }
            previous = s;
        }
        let mut sink = ShapeSink {
            s_m,
            out,
            written: 0,
        };
        let sw = sweep(
            self,
            &self.inputs(base_strain_per_m, load, T::one()),
            Tangents::NONE,
            Some(&mut sink),
        );
        if !sw.finite {
            return Err(ModelError::NonFinite("sweep result"));
        }
        Ok(sink.written)
    }

    pub(crate) fn inputs(&self, u0: &Vector3<T>, load: &TipLoad<T>, load_scale: T) -> Inputs<T> {
        Inputs {
            u0: *u0,
            tip_force_n: load.force_n,
            tip_moment_nm: load.moment_nm,
            load_scale,
        }
    }

    /// The small-deflection guess for the base strain: the base moment of all loads on the straight rod,
    /// `m(0) = tau + sum(tau_k) + t x integral(n ds)`, `u0 = C^-1 R0^T m(0)`.
    pub(crate) fn linear_guess(&self, load: &TipLoad<T>, load_scale: T) -> Vector3<T> {
        let tangent = self.rod.base_orientation.column(2).into_owned();
        let g = self.rod.gravity_m_s2;
        let half = T::lit(0.5);
        let mut force_integral = Vector3::zeros();
        let mut moments = load.moment_nm;
        for (interval, node) in self
            .plan
            .intervals
            .iter()
            .zip(self.plan.nodes.iter().skip(1))
        {
            let len = interval.s1_m - interval.s0_m;
            force_integral += (load.force_n + interval.distal_force_n) * len
                + g * (interval.line_density_kg_per_m * len * len * half);
            moments += node.moment_nm;
        }
        let m0 = (moments + tangent.cross(&force_integral)) * load_scale;
        let c_inv = self
            .compliances
            .first()
            .map_or(Vector3::zeros(), |c| c.c_inv);
        c_inv.component_mul(&self.rod.base_orientation.tr_mul(&m0))
    }
}
