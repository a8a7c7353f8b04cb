//! The complementarity of tensions and slack (MODEL.md §6.3): a taut tendon has no slack and a
//! tension of at least zero, a slack one no tension and a slack of at least zero.
//!
//! Its residual is Fischer-Burmeister's, `FB(tau / tau_s, phi / r) = a + b - sqrt(a^2 + b^2)`, zero
//! exactly on the complementarity: the measure of every step. Two steps:
//!
//! * the semi-smooth Newton step on `FB`, for cold solves and refining steps;
//! * Josephy-Newton's step, for a warm update's first step (`joint_step.rs`): the complementarity
//!   with the slack linearised in the tensions, `phi - s (z - tau)` with `s = dN/dtau`, solved
//!   exactly for the new tensions `z` (a linear complementarity problem, by Murty's least-index
//!   principal pivoting). The tendons that change state in the step are the ones the linear model
//!   says, with the tension it says. On `FB` the step across a change of state lands short of the
//!   kink, where `FB` is curved (the firmware's recorded actuation, tick 2: 0.014 N of a slack
//!   tendon's 0.023 N), and two more steps follow. Far from the answer the linear model is too
//!   poor to trust its states: from the straight rod at zero tension it made all three of the
//!   firmware's tendons taut at up to 1.3 N where two are, at 0.93 N and 0.04 N (that cold solve
//!   took 48 sweeps instead of 39), so cold solves keep the semi-smooth step.
//!
//! Where the pivoting finds no answer (a carried sensitivity that is not a P-matrix, or pivots
//! beyond [`MAX_PIVOTS`]), Josephy's step is the semi-smooth one.

use nalgebra::{SMatrix, SVector};

use super::{MAX_TENDONS, Tendons};
use crate::Scalar;

/// Most principal pivots of a linear complementarity step. Murty's rule ends for a P-matrix (the
/// compliance `-dN/dtau` of a stable equilibrium is symmetric positive definite), but only within
/// `2^n` pivots in the worst case; the cap bounds a step's cost and covers that worst case up to
/// four tendons. Beyond the cap the step is the semi-smooth one. From the current tendons' states
/// a tick's step takes none or one.
const MAX_PIVOTS: usize = 2 * MAX_TENDONS;

/// `(a + b - sqrt(a^2 + b^2))` and its partial derivatives (at the kink, those of the smooth part
/// along `a = b`).
fn fischer_burmeister<T: Scalar>(a: T, b: T) -> (T, T, T) {
    let r = (a * a + b * b).sqrt();
    if r > T::zero() {
        (a + b - r, T::one() - a / r, T::one() - b / r)
    } else {
        let half = T::one() - T::lit(core::f64::consts::FRAC_1_SQRT_2);
        (T::zero(), half, half)
    }
}

/// The size of a residual: its largest component, or the largest number where one is not finite
/// (nalgebra's `amax` passes over NaN, which would read as met).
pub(super) fn residual_size<T: Scalar>(r: &SVector<T, MAX_TENDONS>) -> T {
    if crate::scalar::all_finite(r) {
        r.amax()
    } else {
        T::max_value().unwrap_or_else(T::one)
    }
}

/// The complementarity of tensions and slack for given spool displacements, Fischer-Burmeister:
/// each tendon's residual `FB(tau / tau_s, phi / r)` and its derivatives.
pub(super) struct Complementarity<'a, T> {
    pub tendons: &'a Tendons<T>,
    pub displacements_m: &'a [T],
    /// The tension that bends the rod a radian through the largest offset, N.
    pub tau_scale: T,
    /// The largest offset, m.
    pub radius: T,
}

/// Each tendon's `(d FB / d a, d FB / d b)` at a residual.
pub(super) type Parts<T> = [(T, T); MAX_TENDONS];

impl<T: Scalar> Complementarity<'_, T> {
    /// The residual at tensions `tau` when the equilibrium needs the unstretched lengths
    /// `unstretched_m`, its parts, and the slack.
    pub(super) fn residual(
        &self,
        unstretched_m: &[T],
        tau: &[T; MAX_TENDONS],
    ) -> (SVector<T, MAX_TENDONS>, Parts<T>, [T; MAX_TENDONS]) {
        let phi = self.tendons.slack(self.displacements_m, unstretched_m);
        let mut r = SVector::<T, MAX_TENDONS>::zeros();
        let mut parts = [(T::zero(), T::zero()); MAX_TENDONS];
        for (((r, part), t), p) in r
            .iter_mut()
            .zip(parts.iter_mut())
            .zip(tau)
            .zip(&phi)
            .take(self.tendons.len())
        {
            let (v, da, db) = fischer_burmeister(*t / self.tau_scale, *p / self.radius);
            *r = v;
            *part = (da, db);
        }
        (r, parts, phi)
    }

    /// The scales of its steps.
    fn scales(&self) -> Scales<T> {
        Scales {
            count: self.tendons.len(),
            tau_scale: self.tau_scale,
            radius: self.radius,
        }
    }

    /// The semi-smooth Newton step on the residual `r` (with its `parts`), with `s = dN/dtau`.
    /// `None` where it is not finite.
    pub(super) fn newton_step(
        &self,
        (r, parts): (&SVector<T, MAX_TENDONS>, &Parts<T>),
        s: &SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    ) -> Option<SVector<T, MAX_TENDONS>> {
        self.scales().newton_step(r, parts, s)
    }

    /// Josephy-Newton's step from `tau` (each at least zero) where the slack is `phi`, else
    /// (no pivoting answer) [`Complementarity::newton_step`]. Out of line: the pivoting's
    /// matrices stay out of its callers' frames (the displacement solve's is the tendon image's
    /// deepest).
    #[inline(never)]
    pub(super) fn josephy_step(
        &self,
        tau: &[T; MAX_TENDONS],
        phi: &[T; MAX_TENDONS],
        residual: (&SVector<T, MAX_TENDONS>, &Parts<T>),
        s: &SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    ) -> Option<SVector<T, MAX_TENDONS>> {
        linear_step(&self.scales(), tau, phi, s).or_else(|| self.newton_step(residual, s))
    }
}

/// The tendons' count and the residual's scales: the tension that bends the rod a radian through
/// the largest offset, N, and that offset, m.
#[derive(Clone, Copy, Debug)]
struct Scales<T> {
    count: usize,
    tau_scale: T,
    radius: T,
}

impl<T: Scalar> Scales<T> {
    /// `d r / d tau` for a residual `r` with `parts` `(d r / d a, d r / d b)`, `a = tau / tau_s`,
    /// `b = phi / radius`, `d phi / d tau = -s` (`s` the needed unstretched lengths' sensitivity
    /// to the tensions); identity beyond the tendons.
    fn jacobian(
        &self,
        parts: &Parts<T>,
        s: &SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    ) -> SMatrix<T, MAX_TENDONS, MAX_TENDONS> {
        SMatrix::<T, MAX_TENDONS, MAX_TENDONS>::from_fn(|j, i| {
            if j >= self.count || i >= self.count {
                return if i == j { T::one() } else { T::zero() };
            }
            let (da, db) = parts.get(j).copied().unwrap_or((T::zero(), T::zero()));
            let d_phi = -s.get((j, i)).copied().unwrap_or_else(T::zero);
            let d_tau = if i == j { T::one() } else { T::zero() };
            da * d_tau / self.tau_scale + db * d_phi / self.radius
        })
    }

    /// Newton's step on a residual `r` with its `parts`. `None` where it is not finite. Out of
    /// line: both steps share it.
    #[inline(never)]
    fn newton_step(
        &self,
        r: &SVector<T, MAX_TENDONS>,
        parts: &Parts<T>,
        s: &SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    ) -> Option<SVector<T, MAX_TENDONS>> {
        self.jacobian(parts, s)
            .lu()
            .solve(&(-r))
            .filter(crate::scalar::all_finite)
    }
}

/// Josephy-Newton's step: `z - tau` where the new tensions `z >= 0` and the linearised slack
/// `w = phi - s (z - tau) >= 0` are complementary. With the taut set `A`, `z_A` solves `w_A = 0`
/// and the rest of `z` is zero: Newton's step on the residual `phi / radius` of the taut tendons
/// and `tau / tau_s` of the slack ones. Murty's rule flips the first tendon that breaks a sign (a
/// taut one with `z < 0`, a slack one with `w < 0`) until none does. Starts from the tendons taut
/// now or overstretched. `None` where a taut set's system is singular or the pivots run out.
fn linear_step<T: Scalar>(
    scales: &Scales<T>,
    tau: &[T; MAX_TENDONS],
    phi: &[T; MAX_TENDONS],
    s: &SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
) -> Option<SVector<T, MAX_TENDONS>> {
    let count = scales.count.min(MAX_TENDONS);
    let at = |m: &[T], j: usize| m.get(j).copied().unwrap_or_else(T::zero);
    let mut taut = [false; MAX_TENDONS];
    for (j, taut) in taut.iter_mut().enumerate().take(count) {
        *taut = at(tau, j) > T::zero() || at(phi, j) < T::zero();
    }
    for _ in 0..MAX_PIVOTS {
        let mut r = SVector::<T, MAX_TENDONS>::zeros();
        let mut parts = [(T::zero(), T::zero()); MAX_TENDONS];
        for (j, ((r, part), taut)) in r
            .iter_mut()
            .zip(&mut parts)
            .zip(&taut)
            .enumerate()
            .take(count)
        {
            (*r, *part) = if *taut {
                (at(phi, j) / scales.radius, (T::zero(), T::one()))
            } else {
                (at(tau, j) / scales.tau_scale, (T::one(), T::zero()))
            };
        }
        let step = scales.newton_step(&r, &parts, s)?;
        let broken = taut.iter().enumerate().take(count).position(|(j, t)| {
            if *t {
                at(tau, j) + at(step.as_slice(), j) < T::zero()
            } else {
                // `w = phi - s step`, row `j`.
                let moved = (0..count).fold(T::zero(), |a, k| {
                    a + s.get((j, k)).copied().unwrap_or_else(T::zero) * at(step.as_slice(), k)
                });
                at(phi, j) - moved < T::zero()
            }
        });
        match broken.and_then(|j| taut.get_mut(j)) {
            Some(flip) => *flip = !*flip,
            None => return Some(step),
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// A residual with a component that is not a number is no answer: its size meets no tolerance
    /// (nalgebra's `amax` alone passed over NaN and gave the largest of the others).
    #[test]
    fn a_residual_that_is_not_a_number_meets_no_tolerance() {
        let mut r = SVector::<f64, MAX_TENDONS>::zeros();
        r[1] = -3e-5;
        assert_eq!(residual_size(&r), 3e-5);
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            r[0] = bad;
            assert!(residual_size(&r) >= f64::MAX, "{bad}");
        }
    }

    /// Unit scales for `count` tendons.
    fn unit(count: usize) -> Scales<f64> {
        Scales {
            count,
            tau_scale: 1.0,
            radius: 1.0,
        }
    }

    /// `(z, w)` of a step: the new tensions and the linearised slack there.
    fn solved(
        count: usize,
        tau: &[f64; MAX_TENDONS],
        phi: &[f64; MAX_TENDONS],
        s: &SMatrix<f64, MAX_TENDONS, MAX_TENDONS>,
        step: &SVector<f64, MAX_TENDONS>,
    ) -> (Vec<f64>, Vec<f64>) {
        let now = SVector::<f64, MAX_TENDONS>::from_fn(|j, _| tau[j]);
        let w = SVector::<f64, MAX_TENDONS>::from_fn(|j, _| phi[j]) - s * step;
        let z = now + step;
        (
            (0..count).map(|j| z[j]).collect(),
            (0..count).map(|j| w[j]).collect(),
        )
    }

    /// Two tendons, by hand: `s = -[[2, 1], [1, 2]]`, from zero tension with slack `(-1, 1)`:
    /// the first alone taut, at `1/2`, leaves the second `1 + 1/2` of slack (its antagonist's
    /// tension gives it more).
    #[test]
    fn tendon_linear_complementarity_by_hand() {
        let mut s = SMatrix::<f64, MAX_TENDONS, MAX_TENDONS>::zeros();
        s[(0, 0)] = -2.0;
        s[(0, 1)] = -1.0;
        s[(1, 0)] = -1.0;
        s[(1, 1)] = -2.0;
        let tau = [0.0; MAX_TENDONS];
        let mut phi = [0.0; MAX_TENDONS];
        phi[0] = -1.0;
        phi[1] = 1.0;
        let step = linear_step(&unit(2), &tau, &phi, &s).unwrap();
        let (z, w) = solved(2, &tau, &phi, &s, &step);
        assert!((z[0] - 0.5).abs() < 1e-15 && z[1] == 0.0, "{z:?}");
        assert!(w[0].abs() < 1e-15 && (w[1] - 1.5).abs() < 1e-15, "{w:?}");
        // The same slack from a start where the second was taut: it goes slack.
        let mut tau = [0.0; MAX_TENDONS];
        tau[1] = 3.0;
        // The slack at that tension: `(-1, 1) + [[2, 1], [1, 2]] (0, 3)`, the same problem.
        phi[0] = -1.0 + 3.0;
        phi[1] = 1.0 + 6.0;
        let step = linear_step(&unit(2), &tau, &phi, &s).unwrap();
        let (z, _) = solved(2, &tau, &phi, &s, &step);
        assert!((z[0] - 0.5).abs() < 1e-14 && z[1].abs() < 1e-14, "{z:?}");
    }

    proptest! {
        /// For a symmetric positive definite compliance `-s` (a P-matrix: the complementarity has
        /// one answer) the step lands on it from any start: tensions and linearised slack at least
        /// zero, one of them zero for each tendon; up to four tendons it always finds it.
        #[test]
        fn tendon_linear_complementarity_is_solved(
            count in 1usize..=MAX_TENDONS,
            a in proptest::collection::vec(-1.0f64..1.0, MAX_TENDONS * MAX_TENDONS),
            tau in proptest::collection::vec(prop_oneof![Just(0.0), 0.0f64..3.0], MAX_TENDONS),
            phi in proptest::collection::vec(-2.0f64..2.0, MAX_TENDONS),
        ) {
            let a = SMatrix::<f64, MAX_TENDONS, MAX_TENDONS>::from_iterator(a);
            let compliance = a * a.transpose()
                + SMatrix::<f64, MAX_TENDONS, MAX_TENDONS>::identity() * 0.05;
            let s = -compliance;
            let tau: [f64; MAX_TENDONS] = core::array::from_fn(|j| tau[j]);
            let phi: [f64; MAX_TENDONS] = core::array::from_fn(|j| phi[j]);
            let step = linear_step(&unit(count), &tau, &phi, &s);
            // (Within the pivots' cap, Murty's worst case, up to four tendons; beyond, a step
            // given is the answer.)
            prop_assert!(step.is_some() || count > 4);
            let Some(step) = step else { return Ok(()) };
            let (z, w) = solved(count, &tau, &phi, &s, &step);
            let scale = 1e-9 * (1.0 + compliance.amax()) * 10.0;
            for j in 0..count {
                prop_assert!(z[j] >= -scale && w[j] >= -scale, "{j}: z {} w {}", z[j], w[j]);
                prop_assert!(z[j].min(w[j]).abs() <= scale, "{j}: z {} w {}", z[j], w[j]);
            }
        }

        /// Any matrix, however far from a compliance: no panic, and a step given is an answer.
        #[test]
        fn tendon_linear_complementarity_of_any_matrix_is_an_answer_or_none(
            count in 1usize..=4,
            a in proptest::collection::vec(-1.0f64..1.0, MAX_TENDONS * MAX_TENDONS),
            phi in proptest::collection::vec(-2.0f64..2.0, MAX_TENDONS),
        ) {
            let s = SMatrix::<f64, MAX_TENDONS, MAX_TENDONS>::from_iterator(a);
            let tau = [0.0; MAX_TENDONS];
            let phi: [f64; MAX_TENDONS] = core::array::from_fn(|j| phi[j]);
            if let Some(step) = linear_step(&unit(count), &tau, &phi, &s) {
                let (z, w) = solved(count, &tau, &phi, &s, &step);
                for j in 0..count {
                    prop_assert!(z[j] >= -1e-9 && w[j] >= -1e-9, "{j}: z {} w {}", z[j], w[j]);
                    prop_assert!(z[j].min(w[j]).abs() <= 1e-9, "{j}: z {} w {}", z[j], w[j]);
                }
            }
        }
    }
}
