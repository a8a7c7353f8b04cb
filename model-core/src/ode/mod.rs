//! The rod's equations behind one trait, in the spirit of ode_solvers' `System` (a right-hand side
//! written into fixed-size values) and PyElastica's composable forcing (loads as objects the
//! equations apply at nodes).
//!
//! An implementation says what its state is, its rates and their linearisation (tangent rates, fed
//! the same RK4 stages as the state), what happens at a node of the plan (section changes, point
//! loads and moments, loads that read the shape), the pose observers see, and the residual of the
//! tip condition with its size for the stopping rules. One sweep (`sweep/`) walks the plan for any of
//! them; one Newton/LM and one load continuation (`solve/`) solve any of them for its `K` unknowns.
//!
//! | equations | unknowns `K` | file |
//! | --- | --- | --- |
//! | 3D Cosserat/Kirchhoff rod, internal force in closed form (dead loads: the fast path) | `u(0)`, 3 | `dead_load.rs` |
//! | 3D rod with the internal force and moment as states (loads that read the shape) | `n(0)`, `m(0)`, 6 | `force_state.rs` |
//! | the planar reduction (in-plane dead loads) | `k(0)`, 1 | `planar.rs` |
//! | a planar equilibrium's Jacobi fields out of its plane (its stability test there) | `du(0)` across the plane, 2 | `planar_lateral.rs` |
//! | tendons through discrete guides: chord forces, an implicit jump per guide | `n(0)`, `m(0)`, 6 | `tendon.rs` |
//! | tendons routed continuously (Rucker-Webster): composite force and moment as states | `N(0)`, `M(0)`, 6 | `tendon_continuous.rs` |

pub(crate) mod dead_load;
pub(crate) mod force_state;
pub(crate) mod guess;
pub(crate) mod planar;
pub(crate) mod planar_lateral;
pub(crate) mod tendon;
pub(crate) mod tendon_continuous;

use nalgebra::{Matrix3, SVector, Vector3};

use crate::Scalar;
use crate::model::Grid;
use crate::plan::{Interval, Node};
use crate::shape::ShapePoint;

/// A family of tangent directions a sweep can carry, by what seeds it: a change of the shooting
/// unknowns (`K` directions: the base strain, or the base force and moment, ...), a change of the
/// tip force (3 directions, for the inverse), or a change of one tendon's tension (the tendon
/// sensitivity, `crate::tendon::sensitivity`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Family {
    /// The shooting unknowns, one direction each.
    Unknown,
    /// The tip force, along the global x, y, z axes.
    TipForce,
    /// One tendon's tension, in the tendons' order: zero on rods without tendons.
    Tension,
}

/// Where observers see the backbone: its position in high and low parts (the sum, compensated,
/// is the position) and its frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pose<T> {
    pub position_m: Vector3<T>,
    pub position_lo_m: Vector3<T>,
    pub rotation: Matrix3<T>,
}

/// A tangent's arithmetic for the RK4 stages.
pub(crate) trait Linear<T: Scalar>: Copy {
    /// The zero tangent.
    fn zero() -> Self;
    /// `self + h k`.
    fn axpy(&self, k: &Self, h: T) -> Self;
    /// The RK4 update from four stage rates: `self + (k1 + k4) h/6 + (k2 + k3) h/3`.
    fn rk4(&self, k: &[Self; 4], h: T) -> Self;
    /// Every component finite.
    fn is_finite(&self) -> bool;
}

/// The rod's equations along the reference arc length `s`, with `K` shooting unknowns.
///
/// An implementation is cheap to copy and holds the scene, the loads and the load scale (the
/// continuation's parameter: every load is multiplied by it).
pub(crate) trait RodOde<T: Scalar, const K: usize>: Sized {
    /// What RK4 integrates.
    type State: Copy;
    /// Its derivative at one stage.
    type Rate: Copy;
    /// What a tangent's rate needs from one stage of the state's step.
    type Stage: Copy;
    /// A linearised state.
    type Tangent: Linear<T>;
    /// What stays constant along one tangent (e.g. its change of the closed-form internal force).
    type Seed: Copy;
    /// Coefficients constant over one interval of the plan.
    type Field;
    /// The conjugate-point watch's memory between grid points.
    type Track;

    /// The plan and the cables.
    fn grid(&self) -> Grid<'_, T>;
    /// Total reference length, m.
    fn length_m(&self) -> T;
    /// The same equations with every load scaled by `load_scale`.
    fn at_scale(&self, load_scale: T) -> Self;
    /// The small-deflection guess of the unknowns at this load scale.
    fn guess(&self) -> SVector<T, K>;
    /// A cold start's direct attempt at the full load starts here: [`RodOde::guess`] with its base
    /// rotation capped at [`guess::GUESS_ANGLE_RAD`], unless the equations know the bent rod's
    /// (`guess.rs`).
    fn cold_guess(&self) -> SVector<T, K> {
        let guess = self.guess();
        guess * guess::cap(self.rotation_rad(&guess))
    }
    /// Whether every section bends alike about both axes. A cold start tries the full load
    /// directly only then: on sections stiffer about one axis a load that twists the rod can have
    /// stable equilibria that the unloaded rod does not lead to, and a direct attempt landed on one
    /// (30 times stiffer about one axis, rolled 30 degrees, 0.2 kg obliquely: 0.14 m from the
    /// answer the load continuation follows, `tests/stress.rs`).
    fn bends_alike_about_both_axes(&self) -> bool {
        true
    }

    /// The state at the base for unknowns `x`.
    fn start(&self, x: &SVector<T, K>) -> Self::State;
    /// The `j`-th tangent of `family` at the base, and its seed.
    fn seed(&self, family: Family, j: usize) -> (Self::Tangent, Self::Seed);
    /// A seed that changes nothing (fills unused slots).
    fn no_seed(&self) -> Self::Seed;
    /// A blank stage record.
    fn blank_stage(&self) -> Self::Stage;
    /// The coefficients on `interval`; `None` when the scene does not have them (a corrupt plan).
    fn field(&self, interval: &Interval<T>) -> Option<Self::Field>;
    /// The same on the interval after `previous`'s (none on the first), whose coefficients it
    /// may share (a sweep walks the plan in order); by default [`RodOde::field`].
    fn next_field(
        &self,
        _previous: Option<&Self::Field>,
        interval: &Interval<T>,
    ) -> Option<Self::Field> {
        self.field(interval)
    }
    /// The bending load at `(s, y)`, 1/m^4: [`bending_load`] of the internal force there.
    fn bending_load(&self, f: &Self::Field, s: T, y: &Self::State) -> T;
    /// The same from the record of a step's first stage (at the step's start), which has the force
    /// at hand already.
    fn stage_bending_load(&self, f: &Self::Field, stage: &Self::Stage) -> T;

    /// The rates at `(s, y)`; writes what the tangents need into `record` when asked.
    fn rate(
        &self,
        f: &Self::Field,
        s: T,
        y: &Self::State,
        record: Option<&mut Self::Stage>,
    ) -> Self::Rate;
    /// The stage state `y + h k`.
    fn advance(y: &Self::State, k: &Self::Rate, h: T) -> Self::State;
    /// The step's result from the four stage rates (weights 1/6, 1/3, 1/3, 1/6).
    fn combine(y: &Self::State, k: [&Self::Rate; 4], h: T) -> Self::State;
    /// A tangent's rate at one recorded stage.
    fn tangent_rate(
        &self,
        f: &Self::Field,
        stage: &Self::Stage,
        seed: &Self::Seed,
        t: &Self::Tangent,
    ) -> Self::Tangent;
    /// After each full step (state and tangents): projections that keep the state on its manifold.
    #[inline]
    fn after_step(&self, _y: &mut Self::State, _tangents: &mut [Self::Tangent]) {}

    /// Whether the tangents at `y` are already those of the next node (a node's jump integrated
    /// them there): the sweep then steps the state alone until that node. Only for equations
    /// whose sweeps read no tangent before it (no stability test, no cables).
    #[inline]
    fn tangents_ahead(&self, _y: &Self::State) -> bool {
        false
    }

    /// The jump at an interior node (not the base, not the tip) between the intervals with
    /// coefficients `proximal` and `distal`.
    fn node(
        &self,
        node: &Node<T>,
        proximal: &Self::Field,
        distal: &Self::Field,
        y: &mut Self::State,
        tangents: &mut [Self::Tangent],
    );
    /// The tip condition's residual after the tip node (`last` the last interval's coefficients),
    /// and each tangent's change of it in `d`.
    fn tip(
        &self,
        node: Option<&Node<T>>,
        last: &Self::Field,
        y: &Self::State,
        tangents: &[Self::Tangent],
        seeds: &[Self::Seed],
        d: &mut [SVector<T, K>],
    ) -> SVector<T, K>;

    /// The pose observers see.
    fn pose(&self, y: &Self::State) -> Pose<T>;
    /// A tangent's change of the pose at state `y`: position (global, m) and rotation (body frame).
    fn tangent_pose(&self, y: &Self::State, t: &Self::Tangent) -> (Vector3<T>, Vector3<T>);
    /// The backbone at arc length `s` (on an interval with coefficients `f`) for the shape output.
    fn shape_point(&self, s: T, y: &Self::State, f: &Self::Field) -> ShapePoint<T>;
    /// Every component of the state and the tangents finite.
    fn finite(&self, y: &Self::State, tangents: &[Self::Tangent]) -> bool;

    /// Whether the equations have an energy test of stability (Jacobi fields from the unknowns'
    /// tangents). Without it, a solve follows the branch connected to the unloaded rod by load
    /// continuation and reports the stability as unchecked.
    fn has_stability_test(&self) -> bool;
    /// Whether every load is conservative (the energy test applies).
    fn conservative(&self) -> bool;
    /// A fresh conjugate-point watch.
    fn track(&self) -> Self::Track;
    /// Whether a conjugate point lies in the step of `step_m` just taken (ending at state `y`) on an
    /// interval with coefficients `f`; `tangents` starts with the `K` unknowns' tangents.
    fn crosses(
        &self,
        track: &mut Self::Track,
        y: &Self::State,
        tangents: &[Self::Tangent],
        f: &Self::Field,
        step_m: T,
    ) -> bool;
    /// The free-end Jacobi coordinates of a tip rotation tangent (body frame).
    fn jacobi_rotation(&self, d_rotation: &Vector3<T>) -> SVector<T, K>;

    /// The dimensionless size of a residual (an angle, rad: a tip-moment error of this size times
    /// `E I / L`).
    fn residual_size(&self, r: &SVector<T, K>) -> T;

    /// How far unknowns `x` turn the rod, rad, for the stopping rules' relative tolerance (the
    /// base strain's `|x| L` unless the unknowns hold more than a rotation).
    #[inline]
    fn rotation_rad(&self, x: &SVector<T, K>) -> T {
        x.norm() * self.length_m()
    }

    /// How far a change `dx` of the unknowns moves the rod, rad: Newton's trust region, the load
    /// continuation's bound on a step's answer against its prediction, and the size of its first
    /// step (the base strain's `|dx| L` unless the unknowns hold more than a rotation). Chord
    /// steps (`solve/newton.rs`) bound `|dx| L` itself.
    #[inline]
    fn change_rad(&self, dx: &SVector<T, K>) -> T {
        dx.norm() * self.length_m()
    }
}

/// `e_j`, the `j`-th unit vector.
#[inline]
pub(crate) fn unit<T: Scalar, const N: usize>(j: usize) -> SVector<T, N> {
    SVector::from_fn(|i, _| if i == j { T::one() } else { T::zero() })
}

/// [`bending_load`] of a force `n_local` in the section's own frame (tangent `z`).
#[inline]
pub(crate) fn local_bending_load<T: Scalar>(n_local: &Vector3<T>, compliance_squared: T) -> T {
    bending_load(n_local, &Vector3::z(), compliance_squared)
}

/// The bending load `(F / EI)^2`, 1/m^4, of the internal force `n` on a section with tangent `t`
/// (unit) and `compliance_squared` `(1 / EI)^2` about its softer axis: `F` is the force that sets how fast a bend
/// turns into a deflection and back (`sqrt(F / EI)` radians of bending phase per metre, see
/// [`crate::report::MAX_PHASE_PER_STEP_RAD`]): the whole force where it compresses the section,
/// its lateral part where it pulls (a straight rod in tension does not bend). No square root: the
/// sweep keeps the largest and takes the roots once.
#[inline]
pub(crate) fn bending_load<T: Scalar, const D: usize>(
    n: &SVector<T, D>,
    t: &SVector<T, D>,
    compliance_squared: T,
) -> T {
    // Comparisons rather than `max`: this runs at every step.
    let axial = n.dot(t);
    let pull = if axial > T::zero() {
        axial * axial
    } else {
        T::zero()
    };
    let force_squared = n.norm_squared() - pull;
    let force_squared = if force_squared > T::zero() {
        force_squared
    } else {
        T::zero()
    };
    force_squared * compliance_squared
}
