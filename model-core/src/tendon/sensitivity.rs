//! How an equilibrium under tendons moves with the tensions and the tip force: the changes of the
//! unstretched lengths the tendons need (path and stretch together), of the tip position and of
//! the base's force and moment. Both the displacement-controlled solve and the inverse need them.
//!
//! Frictionless, from tangents (the implicit function theorem, MODEL.md §6.3): at the answer's
//! unknowns `x`, one sweep with the unknowns' tangents gives the tip condition's Jacobian `J` and
//! the paths' and the tip's changes along them; one or two sweeps with the parameters' tangents
//! (each tension, the tip force) at the same `x` give the tip condition's change `dr/dp` and the
//! paths' and tip's with `x` held. On the equilibrium `dx/dp = -J^-1 dr/dp`, so each total change
//! is the held one plus the unknowns' along `dx/dp`; a tendon's stretch adds its own tension's
//! share. Two or three sweeps where differences take a warm solve per column.
//!
//! With capstan friction (the chords' tensions read the wrap angles, which the tangents do not
//! carry into the stretch), with more than six tendons (a sweep's slots), or where a sweep fails or
//! its result is not finite, by forward differences of warm solves (each a
//! few sweeps from the equilibrium it perturbs). Their step is a fixed fraction
//! (`max(2 eps^(1/3), 1e-3)`) of the tension that bends the rod by about a radian (`E I / (L r)`)
//! and of the force that does (`E I / L^2`): large enough to stand above the solves' own error
//! (their tolerance) in f32 and along weakly seen directions, small enough that the curvature of
//! the map costs a fraction of that in f64.

use nalgebra::{SMatrix, SVector, Vector3};

use super::{MAX_TENDONS, TendonEquilibrium, Tendons};
use crate::Scalar;
use crate::error::ModelError;
use crate::kinematics::Attitude;
use crate::loads::TipLoad;
use crate::model::Model;
use crate::ode::Family;
use crate::ode::tendon::{GuideRecord, PathChanges, TendonRod};
use crate::report::Termination;
use crate::shooting::ShootingSettings;
use crate::sweep::{MAX_TANGENTS, TangentSet, sweep};

/// The changes of the tendons' needed unstretched lengths (rows, m) and of the tip position (m) per
/// unit change of each tension (N) and tip force component (N).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sensitivity<T> {
    pub d_length_d_tension: SMatrix<T, MAX_TENDONS, MAX_TENDONS>,
    pub d_length_d_force: SMatrix<T, MAX_TENDONS, 3>,
    pub d_tip_d_tension: SMatrix<T, 3, MAX_TENDONS>,
    pub d_tip_d_force: SMatrix<T, 3, 3>,
    /// The base's internal force (rows 0-2, N) and moment (rows 3-5, N m) per unit tension.
    pub d_base_d_tension: SMatrix<T, 6, MAX_TENDONS>,
    /// Sweeps spent.
    pub sweeps: u32,
}

impl<T: Scalar> Sensitivity<T> {
    fn zero() -> Self {
        Self {
            d_length_d_tension: SMatrix::zeros(),
            d_length_d_force: SMatrix::zeros(),
            d_tip_d_tension: SMatrix::zeros(),
            d_tip_d_force: SMatrix::zeros(),
            d_base_d_tension: SMatrix::zeros(),
            sweeps: 0,
        }
    }
}

/// The tension, N, that bends `model`'s rod by about a radian through a tendon at the largest
/// offset of `tendons`.
pub(crate) fn tension_scale_n<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    tendons: &Tendons<T>,
) -> T {
    let radius = tendons.largest_offset_m();
    let radius = if radius > T::zero() {
        radius
    } else {
        model.length_m()
    };
    model.moment_scale_nm() / radius
}

/// The relative forward-difference step, `max(2 eps^(1/3), 1e-3)`: the solves' own error (their
/// tolerance, about `1e-11 L` in f64) over the step must stay small where the lengths see a direction
/// weakly (an axial tip force changes them a thousand times less than a lateral one); the truncation
/// error, about the step relative, only slows the Newton-type iterations that use it, by that factor
/// per iteration.
fn relative_step<T: Scalar>() -> T {
    (T::default_epsilon().powf(T::lit(1.0 / 3.0)) * T::lit(2.0)).max(T::lit(1e-3))
}

/// The sensitivity of `at` (a converged equilibrium of `tendons` on `model`, under `load`) to the
/// tensions and, when `with_force`, to the tip force.
pub(crate) fn sensitivity<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    tendons: &Tendons<T>,
    at: &TendonEquilibrium<T>,
    load: &TipLoad<T>,
    with_force: bool,
    settings: &ShootingSettings<T>,
) -> Result<Result<Sensitivity<T>, Termination>, ModelError> {
    let mut out = Sensitivity::zero();
    if traceable(tendons) && traced(model, tendons, at, load, with_force, &mut out) {
        return Ok(Ok(out));
    }
    // (The differences below write every column the traced sensitivity may have begun; its
    // sweeps stay counted.)
    let count = tendons.len();
    let tau_step = tension_scale_n(model, tendons) * relative_step::<T>();
    let force_step = model.moment_scale_nm() / model.length_m() * relative_step::<T>();
    let base_tip = at.equilibrium.tip_position_m;
    let columns = count + if with_force { 3 } else { 0 };
    for c in 0..columns {
        let mut tau = [T::zero(); MAX_TENDONS];
        for (t, a) in tau.iter_mut().zip(&at.tensions_n) {
            *t = *a;
        }
        let mut perturbed = *load;
        let h = if c < count {
            if let Some(t) = tau.get_mut(c) {
                *t += tau_step;
            }
            tau_step
        } else {
            perturbed.force_n += crate::ode::unit::<T, 3>(c - count) * force_step;
            force_step
        };
        let tau = tau.get(..count).unwrap_or(&[]);
        let moved = model.solve_tendons(tendons, tau, &perturbed, Some(at), settings)?;
        out.sweeps += u32::from(moved.equilibrium.report.sweeps);
        if !moved.is_success()
            || moved.unstretched_m.len() != count
            || at.unstretched_m.len() != count
        {
            return Ok(Err(moved.equilibrium.report.termination));
        }
        let d_tip = (moved.equilibrium.tip_position_m - base_tip) / h;
        let d_length = SVector::<T, MAX_TENDONS>::from_fn(|j, _| {
            match (moved.unstretched_m.get(j), at.unstretched_m.get(j)) {
                (Some(a), Some(b)) => (*a - *b) / h,
                _ => T::zero(),
            }
        });
        if c < count {
            out.d_base_d_tension
                .set_column(c, &((moved.base() - at.base()) / h));
            out.d_length_d_tension.set_column(c, &d_length);
            out.d_tip_d_tension.set_column(c, &d_tip);
        } else {
            out.d_length_d_force.set_column(c - count, &d_length);
            out.d_tip_d_force.set_column(c - count, &d_tip);
        }
    }
    Ok(Ok(out))
}

/// Whether the sensitivity of `tendons` can be traced ([`traced`]): without capstan friction (the
/// chords' tensions read the wrap angles, whose changes the tangents do not carry into the
/// stretch) and with at most six tendons (a sweep's tangent slots; seven to twelve take the
/// differences).
pub(crate) fn traceable<T: Scalar>(tendons: &Tendons<T>) -> bool {
    tendons.frictionless() && tendons.len() <= MAX_TANGENTS
}

/// The sensitivity of `at` from tangents (see the module's doc), frictionless, at most six tendons
/// (a sweep's slots), into `out`; `false` where a sweep is not finite or does not pass every
/// guide, or the result is not finite (`out` is then partly written). Out
/// of line, one parameter at a time on six-vectors: its records and sweeps stay out of the
/// displacement solve's frame, and the controller's flash takes no wider matrices.
#[inline(never)]
fn traced<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    tendons: &Tendons<T>,
    at: &TendonEquilibrium<T>,
    load: &TipLoad<T>,
    with_force: bool,
    out: &mut Sensitivity<T>,
) -> bool {
    let count = tendons.len();
    // More tensions than a sweep's slots: not [`traceable`], whoever calls.
    if count > MAX_TANGENTS {
        return false;
    }
    let guides = tendons.guide_s_m.len();
    // A tendon without tension pulls with none of its chords, and the guides' loads pass it by
    // (its chords' directions with it): it is traced at `eps^2` of the tension scale, a tension no
    // solve resolves, where its chords pull along their directions (the one-sided change from
    // zero, as a forward difference takes it).
    let eps = T::default_epsilon();
    let tiny = tension_scale_n(model, tendons) * eps * eps;
    let mut tau = [T::zero(); MAX_TENDONS];
    for (t, a) in tau.iter_mut().zip(&at.tensions_n) {
        *t = a.max(tiny);
    }
    let record = GuideRecord::new();
    let paths = PathChanges::new();
    let ode = TendonRod::new(model, tendons, &tau, load, T::one())
        .recording(&record)
        .tracing_paths(&paths);
    let x = ode.unknowns(&at.equilibrium.base_force_n, &at.equilibrium.base_moment_nm);
    // The unknowns' sweep: `J`, and the paths' and the tip's changes along the unknowns.
    let unknowns = sweep(&ode, &x, TangentSet::unknowns(false), None);
    let Some(d_path_dx) = paths
        .along(&record, &x, guides, 6)
        .filter(|_| unknowns.finite)
    else {
        return false;
    };
    let lu = unknowns.jacobian().lu();
    let d_tip_dx: [Vector3<T>; 6] =
        core::array::from_fn(|k| unknowns.d_position(Family::Unknown, k));
    out.sweeps = 1;
    // Whether every length entry written is finite: a nearly singular `J` (or f32's range) could
    // leave what no solve would, never to be taken for an answer. A non-finite `dx` reaches every
    // length entry (through the paths' changes along it); the tip's and the base's columns come
    // from the same `dx` and the sweep's finite tangents.
    let mut finite = true;
    // The tensions' tangents and the tip force's, in one sweep where they fit.
    let together = with_force && count + 3 <= MAX_TANGENTS;
    let runs = if with_force && !together { 2 } else { 1 };
    for run in 0..runs {
        let which = if run == 0 {
            TangentSet::parameters(together, count)
        } else {
            TangentSet::parameters(true, 0)
        };
        let swept = sweep(&ode, &x, which, None);
        out.sweeps += 1;
        let Some(d_path_dp) = paths
            .along(&record, &x, guides, which.count::<6>())
            .filter(|_| swept.finite)
        else {
            return false;
        };
        for p in 0..count + 3 {
            let (family, c) = if p < count {
                (Family::Tension, p)
            } else {
                (Family::TipForce, p - count)
            };
            let Some(slot) = which.slot::<6>(family, c) else {
                continue;
            };
            // The unknowns' change on the equilibrium per unit of the parameter, and the tip's.
            let Some(dx) = lu.solve(&(-swept.d_residual(family, c))) else {
                return false;
            };
            let d_tip = d_tip_dx
                .iter()
                .zip(dx.iter())
                .fold(swept.d_position(family, c), |a, (d, x)| a + d * *x);
            // Each tendon's needed unstretched length: its path's change (stretched at its own
            // tension), and its own tension's stretch of its feed and path.
            for j in 0..count {
                let (Some(t), Some(tension), Some(path_m)) = (
                    tendons.tendons().get(j),
                    at.tensions_n.get(j),
                    at.path_m.get(j),
                ) else {
                    return false;
                };
                let (Some(along_x), Some(held)) =
                    (d_path_dx.get(j), d_path_dp.get(j).and_then(|d| d.get(slot)))
                else {
                    return false;
                };
                let d_path = along_x
                    .iter()
                    .zip(dx.iter())
                    .fold(*held, |a, (d, x)| a + *d * *x);
                let own = if family == Family::Tension && c == j {
                    t.d_unstretched_d_tension(t.feed_length_m + *path_m, *tension)
                } else {
                    T::zero()
                };
                let entry = if family == Family::Tension {
                    out.d_length_d_tension.get_mut((j, c))
                } else {
                    out.d_length_d_force.get_mut((j, c))
                };
                if let Some(e) = entry {
                    *e = t.unstretched_m(d_path, *tension) + own;
                    finite = finite && e.is_finite();
                }
            }
            if family == Family::Tension {
                let (_, dn, dm) = ode.base(&dx);
                out.d_base_d_tension
                    .set_column(c, &crate::scalar::stacked(&dn, &dm));
                out.d_tip_d_tension.set_column(c, &d_tip);
            } else {
                out.d_tip_d_force.set_column(c, &d_tip);
            }
        }
    }
    finite
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tendon::Tendon;

    /// The traced sensitivity against differences of converged solves (central, and one-sided of
    /// second order for the tendon at zero tension): every needed length, the tip and the base, per
    /// tension and per tip force component, with elastic tendons and a feed (the stretch's own
    /// share), a tendon ending mid-way and one without tension; three tendons (their tensions and
    /// the tip force in one sweep) and four (in two).
    #[test]
    fn tendon_traced_sensitivity_matches_differences_of_solves() {
        let (model, [a, b]) = crate::ode::tendon::tests::scene();
        let elastic = |t: Tendon<f64>| Tendon {
            axial_stiffness_n: Some(2.0e3),
            feed_length_m: 0.2,
            ..t
        };
        let list = [
            elastic(a),
            elastic(b),
            elastic(Tendon::at_angle(4.0, 0.009, 0.225)),
            elastic(Tendon::at_angle(5.2, 0.007, 0.3)),
        ];
        for (count, sweeps) in [(3, 2), (4, 3)] {
            let tendons = Tendons::new(&model, &list[..count]).unwrap();
            let tau = &[2.0, 1.5, 0.0, 1.0][..count];
            matches_differences(&model, &tendons, tau, sweeps);
        }
    }

    /// Seven tendons do not fit a sweep's six slots: no traced sensitivity, the differences
    /// instead (a warm solve per tendon), every column written.
    #[test]
    fn tendon_sensitivity_of_seven_tendons_is_differenced() {
        let (model, _) = crate::ode::tendon::tests::scene();
        let list: [Tendon<f64>; 7] =
            core::array::from_fn(|k| Tendon::at_angle(0.9 * k as f64, 0.01, 0.3));
        let tendons = Tendons::new(&model, &list).unwrap();
        let tau = [1.0, 0.5, 0.0, 0.8, 0.3, 0.0, 0.6];
        let load = TipLoad::zero();
        let settings = ShootingSettings::default();
        let at = model
            .solve_tendons(&tendons, &tau, &load, None, &settings)
            .unwrap();
        assert!(at.is_success());
        let mut traced_out = Sensitivity::zero();
        assert!(!traced(
            &model,
            &tendons,
            &at,
            &load,
            false,
            &mut traced_out
        ));
        let differenced = sensitivity(&model, &tendons, &at, &load, false, &settings)
            .unwrap()
            .unwrap();
        assert!(differenced.sweeps >= 7, "{} sweeps", differenced.sweeps);
        for c in 0..7 {
            // Pulling a tendon shortens its own path.
            assert!(differenced.d_length_d_tension[(c, c)] < 0.0, "column {c}");
        }
    }

    fn matches_differences(model: &Model<f64>, tendons: &Tendons<f64>, tau: &[f64], sweeps: u32) {
        let count = tau.len();
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        let settings = ShootingSettings {
            tolerance: 1e-14,
            ..ShootingSettings::default()
        };
        let at = model
            .solve_tendons(tendons, tau, &load, None, &settings)
            .unwrap();
        assert!(at.is_success());
        let mut traced_out = Sensitivity::zero();
        assert!(traced(model, tendons, &at, &load, true, &mut traced_out));
        let traced = traced_out;
        assert_eq!(traced.sweeps, sweeps);
        let solve = |tau: &[f64], force: Vector3<f64>| {
            let eq = model
                .solve_tendons(tendons, tau, &TipLoad::force(force), Some(&at), &settings)
                .unwrap();
            assert!(eq.is_success());
            // Rows: the needed lengths, the tip, the base.
            let mut v = SVector::<f64, { MAX_TENDONS + 9 }>::zeros();
            for j in 0..count {
                v[j] = eq.unstretched_m[j];
            }
            v.fixed_rows_mut::<3>(count)
                .copy_from(&eq.equilibrium.tip_position_m);
            v.fixed_rows_mut::<6>(count + 3).copy_from(&eq.base());
            v
        };
        let h_tau = 1e-4 * tension_scale_n(model, tendons);
        let h_force = 1e-4 * model.moment_scale_nm() / model.length_m();
        for c in 0..count + 3 {
            let mut col = SVector::<f64, { MAX_TENDONS + 9 }>::zeros();
            let fd = if c < count {
                let moved = |k: f64| {
                    let mut t = tau.to_vec();
                    t[c] += k * h_tau;
                    solve(&t, load.force_n)
                };
                for j in 0..count {
                    col[j] = traced.d_length_d_tension[(j, c)];
                }
                col.fixed_rows_mut::<3>(count)
                    .copy_from(&traced.d_tip_d_tension.column(c));
                col.fixed_rows_mut::<6>(count + 3)
                    .copy_from(&traced.d_base_d_tension.column(c));
                if tau[c] == 0.0 {
                    (moved(1.0) * 4.0 - moved(2.0) - moved(0.0) * 3.0) / (2.0 * h_tau)
                } else {
                    (moved(1.0) - moved(-1.0)) / (2.0 * h_tau)
                }
            } else {
                let k = c - count;
                let moved = |s: f64| {
                    solve(
                        tau,
                        load.force_n + crate::ode::unit::<f64, 3>(k) * (s * h_force),
                    )
                };
                let fd = (moved(1.0) - moved(-1.0)) / (2.0 * h_force);
                for j in 0..count {
                    col[j] = traced.d_length_d_force[(j, k)];
                }
                col.fixed_rows_mut::<3>(count)
                    .copy_from(&traced.d_tip_d_force.column(k));
                // (The base's change per force is not kept: the sum of the loads.)
                col.fixed_rows_mut::<6>(count + 3)
                    .copy_from(&fd.fixed_rows::<6>(count + 3));
                fd
            };
            // Per block (lengths, tip, base), relative to the block's largest entry: 3e-8 at most
            // here (the differences' own error); without the tendon's own stretch 0.13, with the
            // tendon at zero tension traced at zero 0.84.
            for (start, len) in [(0, count), (count, 3), (count + 3, 6)] {
                let (f, t) = (fd.rows(start, len), col.rows(start, len));
                let scale = f.amax().max(1e-12);
                let off = f
                    .iter()
                    .zip(t.iter())
                    .fold(0.0f64, |a, (f, t)| a.max((f - t).abs()))
                    / scale;
                assert!(
                    off < 2e-7,
                    "{count} tendons, column {c}, rows {start}..: off by {off:e} of {scale:e}"
                );
            }
        }
    }
}
