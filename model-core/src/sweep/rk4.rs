//! The fixed-step classical RK4 stepper, for any rod equations, with forward sensitivities.
//!
//! Each step first advances the state and records its four stages; every tangent then takes the same
//! RK4 step over those stages. That is the derivative of the discrete sweep (to the order of the
//! scheme), with no finite-difference cancellation: the Jacobians of the shooting and inverse solves,
//! and the Jacobi fields of the stability test, all come from here.

use crate::Scalar;
use crate::ode::{Linear, RodOde};

/// One RK4 step of length `h` from `s`; writes its four stages into `stages` when given (in place: a
/// plain step neither stores nor copies them).
#[inline]
pub(crate) fn step<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    f: &O::Field,
    s: T,
    h: T,
    y: &O::State,
    stages: Option<&mut [O::Stage; 4]>,
) -> O::State {
    let [r1, r2, r3, r4] = match stages {
        Some(stages) => stages.each_mut().map(Some),
        None => [None, None, None, None],
    };
    let half = h * T::lit(0.5);
    let k1 = ode.rate(f, s, y, r1);
    let k2 = ode.rate(f, s + half, &O::advance(y, &k1, half), r2);
    let k3 = ode.rate(f, s + half, &O::advance(y, &k2, half), r3);
    let k4 = ode.rate(f, s + h, &O::advance(y, &k3, h), r4);
    O::combine(y, [&k1, &k2, &k3, &k4], h)
}

/// The same RK4 step for one tangent, over the stages of the state's step.
#[inline]
pub(crate) fn tangent_step<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    f: &O::Field,
    stages: &[O::Stage; 4],
    seed: &O::Seed,
    h: T,
    t: &O::Tangent,
) -> O::Tangent {
    let half = h * T::lit(0.5);
    let [s1, s2, s3, s4] = stages;
    let k1 = ode.tangent_rate(f, s1, seed, t);
    let k2 = ode.tangent_rate(f, s2, seed, &t.axpy(&k1, half));
    let k3 = ode.tangent_rate(f, s3, seed, &t.axpy(&k2, half));
    let k4 = ode.tangent_rate(f, s4, seed, &t.axpy(&k3, h));
    t.rk4(&[k1, k2, k3, k4], h)
}

/// Every tangent's RK4 step over the stages of the state's step (out of line: the sweep's step loop
/// stays small).
#[inline(never)]
pub(crate) fn tangent_steps<T: Scalar, O: RodOde<T, K>, const K: usize>(
    ode: &O,
    f: &O::Field,
    stages: &[O::Stage; 4],
    seeds: &[O::Seed],
    h: T,
    tangents: &mut [O::Tangent],
) {
    for (t, seed) in tangents.iter_mut().zip(seeds) {
        *t = tangent_step(ode, f, stages, seed, h, t);
    }
}
