//! The stopping rules of every solve, in one place.
//!
//! Sizes are dimensionless: a residual as an angle (a tip-moment error times `L / (E I)`), the
//! unknowns as the base rotation they cause (`|x| L`, every set of unknowns being scaled to 1/m), a
//! tip move as a fraction of the rod's length. Rounding grows with the base rotation, so tolerances
//! are relative to it once it exceeds one radian.

use crate::Scalar;

/// The default dimensionless tolerance: `1e-11` in f64, `200 eps` (2.4e-5) in f32: a few times the
/// rounding floor of a sweep.
pub fn default_tolerance<T: Scalar>() -> T {
    (T::default_epsilon() * T::lit(200.0)).max(T::lit(1e-11))
}

/// Whether a residual of size `residual` meets `tolerance` at unknowns of size `unknowns` (relative to
/// the base rotation once that exceeds one radian).
#[inline]
pub(crate) fn residual_converged<T: Scalar>(residual: T, unknowns: T, tolerance: T) -> bool {
    residual <= tolerance * unknowns.max(T::one())
}

/// Whether a Newton correction of size `step` (at unknowns of size `unknowns`) is negligible: it turns
/// the base by less than `tolerance`, and moves the tip (`tip_move_m`, predicted by the sweep's
/// tangents) by less than `tolerance L`, both relative to the base rotation beyond one radian (the
/// reduced inverse's test; Newton's is [`correction_at_floor`]).
#[inline]
pub(crate) fn step_negligible<T: Scalar>(
    step: T,
    unknowns: T,
    tip_move_m: T,
    length_m: T,
    tolerance: T,
) -> bool {
    within(step, tolerance, unknowns, tip_move_m, length_m, tolerance)
}

/// Whether a correction turns the base by less than `turn` and moves the tip by less than
/// `tolerance L`, both relative to the base rotation beyond one radian.
#[inline]
fn within<T: Scalar>(
    step: T,
    turn: T,
    unknowns: T,
    tip_move_m: T,
    length_m: T,
    tolerance: T,
) -> bool {
    let relative = unknowns.max(T::one());
    step <= turn * relative && tip_move_m <= tolerance * length_m * relative
}

/// The rounding floor of a long sweep's residual, in rounding units: a Newton correction that turns
/// the base by less than this (or the tolerance, when larger) may be at the floor
/// ([`correction_at_floor`]). On the bench's 22 steps the floor is about 200 eps, the f32 tolerance;
/// in f32 on the two-section robot (74 steps, 14 guides' implicit jumps) the residual stops at
/// 280-460 eps, where corrections of 260-460 eps move the tip by about a micrometre and lower the
/// residual only by chance: bounded by the tolerance, each such forward solve took four to eight
/// damped sweeps more. A property of the arithmetic, not of the tolerance asked for: in f64 the
/// tolerance (1e-11, 45 000 eps) is the larger, and a displacement solve, which goes on to its own
/// floor, needs its forward solves' last corrections taken (with four tolerances instead, the f64
/// two-section robot's eleven warm ticks took 214 sweeps, one of them 42, where they take 186).
const SWEEP_FLOOR_EPS: f64 = 800.0;

/// Whether a Newton correction of size `step` (at unknowns of size `unknowns`) may be at the
/// rounding floor: it turns the base by less than `tolerance` or [`SWEEP_FLOOR_EPS`] rounding units,
/// whichever is larger, and moves the tip (`tip_move_m`, predicted by the sweep's tangents) by less
/// than `tolerance L`, both relative to the base rotation beyond one radian.
/// [`tip_move_negligible`] then says whether the answer is already there without trying the step.
#[inline]
pub(crate) fn correction_at_floor<T: Scalar>(
    step: T,
    unknowns: T,
    tip_move_m: T,
    length_m: T,
    tolerance: T,
) -> bool {
    let turn = tolerance.max(T::default_epsilon() * T::lit(SWEEP_FLOOR_EPS));
    within(step, turn, unknowns, tip_move_m, length_m, tolerance)
}

/// Whether a Newton correction's predicted tip move is below `tolerance L`, not relative: in f32 the
/// tip resolves to a few micrometres even at `|u0| L = 12` (measured), while the relative bound of
/// [`step_negligible`] would accept 0.1 mm there.
#[inline]
pub(crate) fn tip_move_negligible<T: Scalar>(tip_move_m: T, length_m: T, tolerance: T) -> bool {
    tip_move_m <= tolerance * length_m
}

/// The tip move the scalar type resolves on a rod of `length_m`: the shooting tolerance (an angle)
/// times the length (9.4 um for f32 on a 39 cm rod).
pub(crate) fn tip_floor_m<T: Scalar>(length_m: T) -> T {
    length_m * default_tolerance::<T>()
}

/// The smallest fit change, in standard deviations of a length measurement `length_std_m`, the scalar
/// type can resolve: cable lengths are sums of chords about as long as the rod, rounded to about
/// `2 eps L`.
pub(crate) fn fit_floor_sigma<T: Scalar>(length_m: T, length_std_m: T) -> T {
    T::default_epsilon() * T::lit(2.0) * length_m / length_std_m
}
