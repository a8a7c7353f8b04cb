//! Solver outcomes as data: why a solve stopped, after how much work, with what residual.

/// Why a solve stopped. Only [`Termination::Converged`] is a usable answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Termination {
    /// The residual met the tolerance and every check passed.
    Converged,
    /// The iteration budget ran out first.
    IterationLimit,
    /// A sweep produced NaN or infinity.
    NonFinite,
    /// The Jacobian could not be factorised.
    Singular,
    /// No step decreased the residual (the residual sits above the tolerance).
    Stalled,
    /// The residual converged, but to an unstable equilibrium (see [`crate::stability`]): a wrong branch.
    Unstable,
    /// Load continuation could not reach the full load.
    ContinuationFailed,
    /// The residual converged, but the integrated frame drifted from a rotation by more than
    /// [`MAX_FRAME_DRIFT`]: the steps are too long for the attitude representation, and positions
    /// and cable lengths are off by about that fraction (a finer grid, or the quaternion frame,
    /// fixes it).
    FrameDrift,
    /// The residual converged, but the grid's steps are too long for the bending the load causes:
    /// more than [`MAX_PHASE_PER_STEP_RAD`] of bending phase per step somewhere on the rod. There
    /// the fixed-step integrator misjudges the shape and, worse, the stability test (an unstable
    /// equilibrium can pass as stable); more steps per section fix it.
    UnderResolved,
}

/// The largest `|R^T R - I|` an answer's frames may have: a frame that far from a rotation misplaces
/// points by that fraction of their distance from the base (0.4 mm on the 39 cm bench). Drift comes
/// from steps too long for the representation (the rotation-matrix frame past about one radian per
/// step); rounding alone stays far below (f32, 10^4 steps: quaternion 4e-7, Lie group 4e-4).
pub const MAX_FRAME_DRIFT: f64 = 1e-3;

/// The most bending phase an answer's grid may have per step, rad: `h sqrt(|n| / EI)` for a step
/// `h`, the internal force `n` and the section's smaller bending stiffness (the rate at which a
/// small bend turns into a deflection and back, one radian of it per `sqrt(EI / |n|)` of arc).
/// Random bench solves that were `Converged` and `Stable` yet unstable at four times the steps all
/// had more than about 0.59 rad per step; below 0.5 the fourth-order steps follow the bending to
/// about 0.1 % per step.
pub const MAX_PHASE_PER_STEP_RAD: f64 = 0.5;

impl Termination {
    /// `true` only for a converged, verified answer.
    pub fn is_success(self) -> bool {
        self == Self::Converged
    }
}

/// How a solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SolveReport<T> {
    /// Why it stopped.
    pub termination: Termination,
    /// Newton (or Gauss-Newton) iterations, summed over load steps.
    pub iterations: u16,
    /// Sweeps (integrations base to tip), the unit of cost.
    pub sweeps: u16,
    /// Final residual, dimensionless: tip moment error times `L / (E I)` (an angle, rad), and for the
    /// inverse the larger of that and the rms cable-length error over the rod length.
    pub residual: T,
    /// Load-continuation steps taken (0 when the direct solve succeeded).
    pub load_steps: u16,
    /// The stability verdict on the answer.
    pub stability: crate::stability::Stability<T>,
    /// The largest bending phase per step on the grid at the answer, rad (at most
    /// [`MAX_PHASE_PER_STEP_RAD`] for an answer; zero when no sweep finished): how close the grid
    /// is to the load it can resolve.
    pub phase_per_step_rad: T,
}
