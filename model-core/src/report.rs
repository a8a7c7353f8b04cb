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
}

/// The largest `|R^T R - I|` an answer's frames may have: a frame that far from a rotation misplaces
/// points by that fraction of their distance from the base (0.4 mm on the 39 cm bench). Drift comes
/// from steps too long for the representation (the rotation-matrix frame past about one radian per
/// step); rounding alone stays far below (f32, 10^4 steps: quaternion 4e-7, Lie group 4e-4).
pub const MAX_FRAME_DRIFT: f64 = 1e-3;

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
}
