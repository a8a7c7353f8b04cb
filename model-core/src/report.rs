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
}

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
