//! Self-checks of the model that need neither std nor allocation, so the same checks run on the host
//! (in f64 and f32, `cargo test`) and on the emulated Cortex-M4 (in f32, the firmware's `selftest`
//! image). Every check compares with a number that would differ if the code were wrong: closed-form
//! beam solutions, the thesis's tables, the independent golden reference, round trips.
//!
//! Tolerances are stated per scalar type: f32 resolves positions on a 40 cm rod to about 1e-7 m and
//! moments to about 2e-5 of `E I / L`.

// The checks index fixed-size arrays with constants or bounded loop counters; none takes input.
#![allow(clippy::indexing_slicing)]

use nalgebra::{Vector1, Vector2, Vector3};

use crate::reference::{self, Exp2Mass};
use model_core::inverse::{
    Determination, Estimator, EstimatorSettings, InverseSettings, InverseStart, LoadBasis,
    ParamCount, Params, estimate,
};
use model_core::{
    Cable, CrossSection, GuideMass, Material, Model, ModelError, NoShapeLoad, PointLoad, Rod,
    Scalar, Section, ShapePoint, ShootingSettings, Stability, Start, Stiffness, Termination,
    TipLoad,
};

/// A failed check: what was measured against what limit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Failure {
    /// Which check inside the case.
    pub check: &'static str,
    /// The measured value (error, residual, or a flag as 0/1).
    pub value: f64,
    /// The limit it had to stay within.
    pub limit: f64,
}

/// The result of one case.
pub type Outcome = Result<(), Failure>;

/// A named self-check.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// What it checks.
    pub name: &'static str,
    /// Runs it.
    pub run: fn() -> Outcome,
}

fn within(check: &'static str, value: f64, limit: f64) -> Outcome {
    if value.is_finite() && value <= limit {
        Ok(())
    } else {
        Err(Failure {
            check,
            value,
            limit,
        })
    }
}

fn holds(check: &'static str, condition: bool) -> Outcome {
    if condition {
        Ok(())
    } else {
        Err(Failure {
            check,
            value: 0.0,
            limit: 1.0,
        })
    }
}

fn ok<V>(check: &'static str, result: Result<V, ModelError>) -> Result<V, Failure> {
    result.map_err(|_| Failure {
        check,
        value: 0.0,
        limit: 1.0,
    })
}

/// `f64_tol` in f64, `f32_tol` in f32.
fn tol<T: Scalar>(f64_tol: f64, f32_tol: f64) -> f64 {
    if T::default_epsilon().to_f64() < 1e-10 {
        f64_tol
    } else {
        f32_tol
    }
}

fn libm_sqrt(x: f64) -> f64 {
    <f64 as nalgebra::ComplexField>::sqrt(x)
}

fn f64s<T: Scalar>(v: &Vector3<T>) -> Vector3<f64> {
    v.map(Scalar::to_f64)
}

fn lit3<T: Scalar>(v: [f64; 3]) -> Vector3<T> {
    Vector3::new(T::lit(v[0]), T::lit(v[1]), T::lit(v[2]))
}

fn solved<T: Scalar>(
    model: &Model<T>,
    load: &TipLoad<T>,
) -> Result<model_core::Equilibrium<T>, Failure> {
    let eq = ok(
        "solve input",
        model.solve(load, Start::Cold, &ShootingSettings::default()),
    )?;
    holds("solve converged", eq.report.termination.is_success())?;
    Ok(eq)
}

const L: f64 = reference::FREE_LENGTH_M;

fn straight_rod<T: Scalar>(
    sections: usize,
    steps: u16,
    line_density: f64,
) -> Result<Rod<T>, Failure> {
    let mut rod = Rod::new();
    rod.gravity_m_s2 = Vector3::zeros();
    rod.guide_mass = GuideMass::Ignore;
    for _ in 0..sections {
        ok(
            "section",
            rod.push_section(Section {
                length_m: T::lit(L / sections as f64),
                stiffness: ok(
                    "stiffness",
                    reference::nitinol_stiffness(reference::YOUNGS_MODULUS_PA),
                )?,
                line_density_kg_per_m: T::lit(line_density),
                steps,
            }),
        )?;
    }
    Ok(rod)
}

fn stiffness_f64() -> Result<Stiffness<f64>, Failure> {
    ok(
        "stiffness",
        reference::nitinol_stiffness(reference::YOUNGS_MODULUS_PA),
    )
}

/// Small tip load: `P L^3 / 3 E I + P L / G A` (Timoshenko, shear coefficient 1).
pub fn cantilever_tip_load<T: Scalar>() -> Outcome {
    let k = stiffness_f64()?;
    let (ei, ga) = (k.bending_torsion_nm2.x, k.shear_axial_n.x);
    // P L^2 / EI = 1e-4 in f64 (geometric correction ~1e-8), 1e-2 in f32 (so the sag is far above f32 rounding).
    let ratio = tol::<T>(1e-4, 1e-2);
    let force = ratio * ei / (L * L);
    let model = ok("model", Model::<T>::new(straight_rod(1, 50, 0.0)?))?;
    let eq = solved(&model, &TipLoad::force(lit3([0.0, -force, 0.0])))?;
    let expected = -force * L * L * L / (3.0 * ei) - force * L / ga;
    within(
        "relative sag error",
        (eq.tip_position_m.y.to_f64() - expected).abs() / expected.abs(),
        tol::<T>(1e-6, 1e-3),
    )
}

/// Small uniform weight: `w L^4 / 8 E I + w L^2 / 2 G A`.
pub fn cantilever_uniform_weight<T: Scalar>() -> Outcome {
    let k = stiffness_f64()?;
    let (ei, ga) = (k.bending_torsion_nm2.x, k.shear_axial_n.x);
    let weight_per_m = tol::<T>(1e-4, 1e-2) * ei / (L * L * L);
    let mut rod = straight_rod::<T>(1, 50, weight_per_m / reference::GRAVITY_M_S2)?;
    rod.gravity_m_s2 = lit3([0.0, -reference::GRAVITY_M_S2, 0.0]);
    let model = ok("model", Model::<T>::new(rod))?;
    let eq = solved(&model, &TipLoad::zero())?;
    let expected = -weight_per_m * L * L * L * L / (8.0 * ei) - weight_per_m * L * L / (2.0 * ga);
    within(
        "relative sag error",
        (eq.tip_position_m.y.to_f64() - expected).abs() / expected.abs(),
        tol::<T>(1e-6, 1e-3),
    )
}

/// A tip moment bends the rod into a circle of radius `E I / M`; here three quarters of a turn.
pub fn pure_moment_circle<T: Scalar>() -> Outcome {
    let ei = stiffness_f64()?.bending_torsion_nm2.x;
    let angle = 1.5 * core::f64::consts::PI;
    let moment = angle * ei / L;
    let model = ok("model", Model::<T>::new(straight_rod(1, 200, 0.0)?))?;
    let eq = solved(&model, &TipLoad::moment(lit3([0.0, 0.0, moment])))?;
    let radius = ei / moment;
    let s: [T; 5] = core::array::from_fn(|i| T::lit(L * i as f64 / 4.0));
    let blank = ShapePoint::default();
    let mut out = [blank; 5];
    let written = ok("shape", model.shape(&eq, &s, &mut out))?;
    holds("all shape points written", written == s.len())?;
    let mut worst = 0.0f64;
    for p in &out {
        let phi = p.s_m.to_f64() / radius;
        let (sin, cos) = (
            <f64 as nalgebra::ComplexField>::sin(phi),
            <f64 as nalgebra::ComplexField>::cos(phi),
        );
        let arc = Vector3::new(radius * sin, radius * (1.0 - cos), 0.0);
        worst = worst.max((f64s(&p.position_m) - arc).norm());
    }
    within("distance from the arc, m", worst, tol::<T>(1e-9, 2e-5))
}

/// An axial tip force stretches the rod by `F L / E A` (exact: the force stays axial).
pub fn axial_extension<T: Scalar>() -> Outcome {
    let ea = stiffness_f64()?.shear_axial_n.z;
    let force = 50.0;
    let model = ok("model", Model::<T>::new(straight_rod(1, 20, 0.0)?))?;
    let eq = solved(&model, &TipLoad::force(lit3([force, 0.0, 0.0])))?;
    let stretch = eq.tip_position_m.x.to_f64() - L;
    within(
        "relative extension error",
        (stretch - force * L / ea).abs() / (force * L / ea),
        tol::<T>(1e-9, 1e-3),
    )
}

/// Two sections of the same material give the same answer as one, under a 3D load with gravity and
/// a hung mass at the transition.
pub fn two_sections_equal_one<T: Scalar>() -> Outcome {
    let build = |sections: usize| -> Result<Model<T>, Failure> {
        let mut rod = straight_rod::<T>(
            sections,
            60 / sections as u16,
            reference::bare_line_density_kg_m(),
        )?;
        rod.gravity_m_s2 = lit3([0.0, -reference::GRAVITY_M_S2, 0.0]);
        ok(
            "load",
            rod.push_load(PointLoad::mass(T::lit(L / 2.0), T::lit(0.01))),
        )?;
        ok("model", Model::new(rod))
    };
    let load = TipLoad::force(lit3([0.02, -0.1, 0.05]));
    let one = solved(&build(1)?, &load)?;
    let two = solved(&build(2)?, &load)?;
    within(
        "tip difference, m",
        f64s(&(one.tip_position_m - two.tip_position_m)).norm(),
        tol::<T>(1e-12, 1e-6),
    )
}

/// Thesis Table 4.5: the predicted change of the upper cable's length as the tip load grows,
/// for one mass model (the thesis's numbers are given to 0.001 cm).
fn table_4_5<T: Scalar>(mass: Exp2Mass, column: usize) -> Outcome {
    let model = ok(
        "model",
        Model::<T>::new(ok("bench", reference::exp2_bench(mass, 100, 1))?),
    )?;
    let mut reference_length = None;
    let mut worst = 0.0f64;
    for row in reference::csv_rows::<7>(reference::TABLE_4_5_CSV) {
        let row = ok("Table 4.5 row", row)?;
        let weight = row[0] * 1e-3 * reference::GRAVITY_M_S2;
        let eq = solved(&model, &TipLoad::force(lit3([0.0, -weight, 0.0])))?;
        let length = eq
            .cable_lengths_m
            .first()
            .copied()
            .map_or(f64::NAN, Scalar::to_f64);
        let base = *reference_length.get_or_insert(length);
        let delta_cm = (length - base) * 100.0;
        worst = worst.max((delta_cm - row[column]).abs());
    }
    within("worst cable-delta error, cm", worst, 0.01)
}

/// Table 4.5, average-mass model.
pub fn table_4_5_average<T: Scalar>() -> Outcome {
    table_4_5::<T>(Exp2Mass::Average, 4)
}

/// Table 4.5, accurate-mass model.
pub fn table_4_5_accurate<T: Scalar>() -> Outcome {
    table_4_5::<T>(Exp2Mass::Accurate, 6)
}

/// The bench of Table 4.1 with `mass_g` hung at the section transition (at the modulus the thesis's
/// predictions imply), 50 steps per section.
fn table_4_1_model<T: Scalar>(mass_g: f64) -> Result<Model<T>, Failure> {
    let mut rod = ok(
        "bench",
        reference::exp1_bench::<T>(reference::EXP1_YOUNGS_MODULUS_PA, 50),
    )?;
    ok(
        "load",
        rod.push_load(PointLoad::mass(
            T::lit(reference::EXP1_TRANSITION_M),
            T::lit(mass_g * 1e-3),
        )),
    )?;
    ok("model", Model::new(rod))
}

/// Thesis Table 4.1: the predicted tips of both sections, within 0.1 cm (at the modulus that the
/// thesis's predictions imply, see [`reference::EXP1_YOUNGS_MODULUS_PA`]).
pub fn table_4_1<T: Scalar>() -> Outcome {
    let mut worst = 0.0f64;
    for row in reference::csv_rows::<9>(reference::TABLE_4_1_CSV) {
        let row = ok("Table 4.1 row", row)?;
        let model = table_4_1_model::<T>(row[0])?;
        let eq = solved(&model, &TipLoad::zero())?;
        let blank = ShapePoint::default();
        let mut out = [blank; 2];
        let s = [T::lit(reference::EXP1_TRANSITION_M), T::lit(L)];
        ok("shape", model.shape(&eq, &s, &mut out))?;
        for (point, (x, y)) in out.iter().zip([(row[5], row[6]), (row[7], row[8])]) {
            let p = f64s(&point.position_m) * 100.0;
            worst = worst.max(libm_sqrt((p.x - x) * (p.x - x) + (p.y - y) * (p.y - y)));
        }
    }
    within(
        "worst section-tip error vs the thesis's prediction, cm",
        worst,
        0.1,
    )
}

/// Every row of Tables 4.1 and 4.3 converges from a cold start, to a stable equilibrium.
pub fn thesis_rows_converge_cold<T: Scalar>() -> Outcome {
    for row in reference::csv_rows::<9>(reference::TABLE_4_1_CSV) {
        let row = ok("Table 4.1 row", row)?;
        let eq = solved(&table_4_1_model::<T>(row[0])?, &TipLoad::zero())?;
        holds(
            "Table 4.1 row stable",
            eq.report.stability == Stability::Stable,
        )?;
    }
    for mass in [Exp2Mass::Average, Exp2Mass::Accurate] {
        let model = ok(
            "model",
            Model::<T>::new(ok("bench", reference::exp2_bench(mass, 100, 0))?),
        )?;
        for row in reference::csv_rows::<5>(reference::TABLE_4_3_CSV) {
            let row = ok("Table 4.3 row", row)?;
            let weight = row[0] * 1e-3 * reference::GRAVITY_M_S2;
            let eq = solved(&model, &TipLoad::force(lit3([0.0, -weight, 0.0])))?;
            holds(
                "Table 4.3 row stable",
                eq.report.stability == Stability::Stable,
            )?;
        }
    }
    Ok(())
}

/// The forward model against the independent golden reference: tip within 0.01 mm and cable
/// lengths within 1 um in f64 (0.05 mm and 10 um in f32).
pub fn golden_forward<T: Scalar>() -> Outcome {
    let model = ok(
        "model",
        Model::<T>::new(ok("bench", reference::golden_bench(200))?),
    )?;
    let (mut tip_err, mut cable_err, mut rows) = (0.0f64, 0.0f64, 0);
    for row in reference::golden_rows() {
        let row = ok("golden row", row)?;
        let eq = solved(&model, &TipLoad::force(lit3(row.force_n)))?;
        tip_err = tip_err.max((f64s(&eq.tip_position_m) - Vector3::from(row.tip_m)).norm());
        for (c, expected) in eq.cable_lengths_m.iter().zip(row.cables_m) {
            cable_err = cable_err.max((c.to_f64() - expected).abs());
        }
        rows += 1;
    }
    holds("golden rows present", rows >= 4)?;
    within("worst tip error, m", tip_err, tol::<T>(1e-5, 5e-5))?;
    within(
        "worst cable-length error, m",
        cable_err,
        tol::<T>(1e-6, 1e-5),
    )
}

/// The rod equations with the internal force and moment as states (the path of loads that read the
/// shape), without such loads, land on the fast path's equilibrium on the golden rows: tip within
/// 1e-10 m in f64 (50 um in f32), cable lengths within 1e-10 m (10 um).
pub fn force_state_matches_dead_load<T: Scalar>() -> Outcome {
    let model = ok(
        "model",
        Model::<T>::new(ok("bench", reference::golden_bench(100))?),
    )?;
    let (mut tip_gap, mut cable_gap) = (0.0f64, 0.0f64);
    for row in reference::golden_rows() {
        let row = ok("golden row", row)?;
        let load = TipLoad::force(lit3(row.force_n));
        let fast = solved(&model, &load)?;
        let state = ok(
            "solve input",
            model.solve_with(&NoShapeLoad, &load, None, &ShootingSettings::default()),
        )?;
        holds(
            "force-state solve converged",
            state.report.termination.is_success(),
        )?;
        tip_gap = tip_gap.max(f64s(&(fast.tip_position_m - state.tip_position_m)).norm());
        for (a, b) in fast
            .cable_lengths_m
            .iter()
            .zip(state.cable_lengths_m.iter())
        {
            cable_gap = cable_gap.max((a.to_f64() - b.to_f64()).abs());
        }
    }
    within("tip difference, m", tip_gap, tol::<T>(1e-10, 5e-5))?;
    within("cable difference, m", cable_gap, tol::<T>(1e-10, 1e-5))
}

/// The inverse on the golden reference: from the three cable lengths alone, the tip within 0.1 mm and
/// every force component within the standard deviation the estimate reports (for a 4096-count
/// encoder on a 5 mm spool: 7.7 um resolution).
pub fn golden_inverse<T: Scalar>() -> Outcome
where
    Params: ParamCount<T, 3>,
{
    let model = ok(
        "model",
        Model::<T>::new(ok("bench", reference::golden_bench(100))?),
    )?;
    let settings = InverseSettings::with_resolution(T::lit(7.7e-6));
    for row in reference::golden_rows() {
        let row = ok("golden row", row)?;
        let lengths = row.cables_m.map(T::lit);
        let est = ok(
            "estimate input",
            estimate(
                &model,
                &LoadBasis::tip_force(),
                &lengths,
                InverseStart::Params(Vector3::zeros()),
                &settings,
            ),
        )?;
        holds("estimate converged", est.report.termination.is_success())?;
        within(
            "tip error, m",
            (f64s(&est.tip_position_m) - Vector3::from(row.tip_m)).norm(),
            1e-4,
        )?;
        for i in 0..3 {
            let err = (est.params[i].to_f64() - row.force_n[i]).abs();
            within(
                "force error over its reported std",
                err / est.quality.force_std_n[i].to_f64(),
                1.0,
            )?;
        }
    }
    Ok(())
}

/// A 3D round trip: forward at a known tip force, then the warm-started estimator follows the force
/// along a short path from the cable lengths alone.
pub fn round_trip_tracking<T: Scalar>() -> Outcome
where
    Params: ParamCount<T, 3>,
{
    let model = ok(
        "model",
        Model::<T>::new(ok("bench", reference::golden_bench(40))?),
    )?;
    let path = |k: usize| {
        let t = k as f64 * 0.05;
        [
            0.03 * <f64 as nalgebra::ComplexField>::sin(0.7 * t),
            -0.15 + 0.1 * <f64 as nalgebra::ComplexField>::sin(1.3 * t),
            0.2 * <f64 as nalgebra::ComplexField>::cos(0.9 * t),
        ]
    };
    let lengths_at = |k: usize| -> Result<([T; 3], Vector3<T>), Failure> {
        let eq = solved(&model, &TipLoad::force(lit3(path(k))))?;
        let mut lengths = [T::zero(); 3];
        for (dst, src) in lengths.iter_mut().zip(eq.cable_lengths_m.iter()) {
            *dst = *src;
        }
        Ok((lengths, eq.tip_position_m))
    };
    let settings =
        EstimatorSettings::with_inverse(InverseSettings::with_resolution(T::lit(7.7e-6)));
    let (first, _) = lengths_at(0)?;
    let (mut estimator, _) = ok(
        "estimator input",
        Estimator::new(
            &model,
            LoadBasis::tip_force(),
            &first,
            Vector3::zeros(),
            settings,
        ),
    )?;
    for k in 1..12 {
        let (lengths, tip) = lengths_at(k)?;
        let est = ok("update input", estimator.update(&lengths))?;
        holds("update converged", est.report.termination.is_success())?;
        holds(
            "update within budget",
            est.report.sweeps <= u16::from(settings.max_sweeps),
        )?;
        within(
            "tip error, m",
            f64s(&(est.tip_position_m - tip)).norm(),
            tol::<T>(1e-6, 1e-4),
        )?;
        // The estimate is a posterior mode (a weak prior on the load): its bias must be a small fraction
        // of the uncertainty it reports.
        for i in 0..3 {
            let err = (est.params[i].to_f64() - path(k)[i]).abs();
            let sd = est.quality.force_std_n[i].to_f64();
            within(
                "force error over a tenth of its reported sd",
                err / (0.1 * sd),
                1.0,
            )?;
        }
    }
    Ok(())
}

/// On a straight rod without gravity the cables barely see an axial tip force (only through `E A`):
/// the estimate must say the axial component is poorly determined, not guess it confidently.
pub fn axial_force_is_weakly_determined<T: Scalar>() -> Outcome
where
    Params: ParamCount<T, 3>,
{
    let mut rod = ok("bench", reference::golden_bench::<T>(40))?;
    rod.gravity_m_s2 = Vector3::zeros();
    let model = ok("model", Model::new(rod))?;
    let eq = solved(&model, &TipLoad::zero())?;
    // The data alone (no prior), to compare with the closed form.
    let settings = InverseSettings {
        prior_std_scale: T::lit(f64::INFINITY),
        ..InverseSettings::with_resolution(T::lit(7.7e-6))
    };
    let est = ok(
        "estimate input",
        estimate(
            &model,
            &LoadBasis::tip_force(),
            &eq.cable_lengths_m,
            InverseStart::Params(Vector3::zeros()),
            &settings,
        ),
    )?;
    holds("estimate converged", est.report.termination.is_success())?;
    holds(
        "called weak",
        est.quality.determination == Determination::Weak,
    )?;
    // The weak direction is the rod's axis (global x), and its std is what three cables stretching
    // by F l / E A each imply: s E A / (sqrt(3) l), l the cable's span from the first guide.
    #[cfg(feature = "identifiability")]
    within(
        "weakest direction off the axis",
        1.0 - est.quality.weakest_direction.x.to_f64().abs(),
        1e-3,
    )?;
    let ea = stiffness_f64()?.shear_axial_n.z;
    let span = L - reference::GUIDE_FIRST_CENTRE_M;
    let expected = 7.7e-6 / libm_sqrt(12.0) * ea / (libm_sqrt(3.0) * span);
    within(
        "axial std vs s EA / (sqrt 3 l), relative",
        (est.quality.force_std_n.x.to_f64() - expected).abs() / expected,
        0.05,
    )
}

/// One cable cannot determine three force components: the estimate says so.
pub fn one_cable_three_unknowns_is_undetermined<T: Scalar>() -> Outcome
where
    Params: ParamCount<T, 3>,
{
    let model = ok(
        "model",
        Model::<T>::new(ok(
            "bench",
            reference::exp2_bench(Exp2Mass::Average, 40, 1),
        )?),
    )?;
    let eq = solved(&model, &TipLoad::force(lit3([0.0, -0.1, 0.0])))?;
    let settings = InverseSettings::with_resolution(T::lit(7.7e-6));
    let est = ok(
        "estimate input",
        estimate(
            &model,
            &LoadBasis::tip_force(),
            &eq.cable_lengths_m,
            InverseStart::Params(Vector3::zeros()),
            &settings,
        ),
    )?;
    holds(
        "called undetermined",
        est.quality.determination == Determination::Undetermined,
    )
}

/// The thesis bench with its single cable and a hung mass of unknown size: 17.2 g is recovered,
/// and the saturating 83.2 g comes with a wider uncertainty than 17.2 g.
pub fn one_cable_hung_mass<T: Scalar>() -> Outcome
where
    Params: ParamCount<T, 1>,
{
    let model = ok(
        "model",
        Model::<T>::new(ok(
            "bench",
            reference::exp2_bench(Exp2Mass::Average, 60, 1),
        )?),
    )?;
    let basis = ok("basis", LoadBasis::force_along(&lit3([0.0, -1.0, 0.0])))?;
    // The data alone (no prior): exact lengths must give back the exact weight.
    let settings = InverseSettings {
        prior_std_scale: T::lit(f64::INFINITY),
        ..InverseSettings::with_resolution(T::lit(1e-3))
    };
    let mut std = [0.0f64; 2];
    for (i, grams) in [17.2, 83.2].into_iter().enumerate() {
        let weight = grams * 1e-3 * reference::GRAVITY_M_S2;
        let eq = solved(&model, &TipLoad::force(lit3([0.0, -weight, 0.0])))?;
        let est = ok(
            "estimate input",
            estimate(
                &model,
                &basis,
                &eq.cable_lengths_m,
                InverseStart::Params(Vector1::new(T::zero())),
                &settings,
            ),
        )?;
        holds("estimate converged", est.report.termination.is_success())?;
        // The solve stops at 1e-4 sd of fit; f32 rounds the length to ~1e-7 m, and near saturation
        // the length moves only ~1e-3 m per N.
        within(
            "weight error, N",
            (est.params[0].to_f64() - weight).abs(),
            tol::<T>(1e-6, 5e-4),
        )?;
        std[i] = est.quality.param_std[0].to_f64();
    }
    holds("saturation widens the uncertainty", std[1] > 3.0 * std[0])
}

/// The thesis's heavier exp-2 loads have an upside-down equilibrium next to the right one (at 150 g
/// here, with the base strain about +1.4 /m). Started there, the solver converges to it and must
/// report it as unstable, never as success; a cold start finds the hanging rod.
pub fn wrong_branch_is_reported<T: Scalar>() -> Outcome {
    let model = ok(
        "model",
        Model::<T>::new(ok(
            "bench",
            reference::exp2_bench(Exp2Mass::Average, 100, 0),
        )?),
    )?;
    let weight = 0.150 * reference::GRAVITY_M_S2;
    let load = TipLoad::force(lit3([0.0, -weight, 0.0]));
    let settings = ShootingSettings {
        cold_fallback: false,
        ..ShootingSettings::default()
    };
    let eq = ok(
        "solve input",
        model.solve(&load, Start::Warm(lit3([0.0, 1.42, 0.0])), &settings),
    )?;
    holds(
        "upside-down root reached",
        eq.tip_position_m.y.to_f64() > 0.1,
    )?;
    holds(
        "reported unstable",
        eq.report.termination == Termination::Unstable,
    )?;
    let cold = solved(&model, &load)?;
    holds(
        "cold start hangs down",
        cold.tip_position_m.y.to_f64() < -0.3,
    )?;
    holds(
        "cold start stable",
        cold.report.stability == Stability::Stable,
    )
}

/// A weightless rod pushed back along itself, 10 degrees off its axis, at 26 times its buckling load
/// (1.23 N): the nearly straight equilibrium next to the unloaded rod is unstable in the plane and
/// across it at the same arc lengths, two conjugate points at once that `det H` cannot see. Started
/// at the straight rod, the solver converges to it and must report it as unstable; a cold start must
/// not return it (the stable rod is bent right over, its tip behind the base).
pub fn pushed_back_past_buckling<T: Scalar>() -> Outcome {
    let model = ok("model", Model::<T>::new(straight_rod(1, 20, 0.0)?))?;
    let load = TipLoad::force(lit3([-1.2077, -0.2130, 0.0]));
    let settings = ShootingSettings {
        cold_fallback: false,
        ..ShootingSettings::default()
    };
    let straight = ok(
        "solve input",
        model.solve(&load, Start::Warm(Vector3::zeros()), &settings),
    )?;
    holds(
        "nearly straight root reached",
        straight.tip_position_m.x.to_f64() > 0.3,
    )?;
    holds(
        "reported unstable",
        straight.report.termination == Termination::Unstable,
    )?;
    let cold = ok(
        "solve input",
        model.solve(&load, Start::Cold, &ShootingSettings::default()),
    )?;
    holds(
        "cold start not on the straight branch",
        !cold.report.termination.is_success() || cold.tip_position_m.x.to_f64() < 0.0,
    )
}

/// Ten times the thesis's heaviest load: a cold start still reaches the stable, hanging branch.
pub fn ten_times_heaviest_load<T: Scalar>() -> Outcome {
    let model = ok(
        "model",
        Model::<T>::new(ok(
            "bench",
            reference::exp2_bench(Exp2Mass::Average, 100, 0),
        )?),
    )?;
    let weight = 0.832 * reference::GRAVITY_M_S2;
    let eq = solved(&model, &TipLoad::force(lit3([0.0, -weight, 0.0])))?;
    holds("stable", eq.report.stability == Stability::Stable)?;
    // Nearly vertical at the tip: the tangent points down.
    within(
        "tip tangent off vertical",
        eq.tip_tangent().y.to_f64() + 1.0,
        0.05,
    )
}

/// The planar reduction of the thesis bench (every load in the vertical plane) gives the 3D answer:
/// tip and cable lengths, on the same grid; and a load out of the plane is not reduced.
pub fn planar_reduction_matches_3d<T: Scalar>() -> Outcome {
    let model = ok(
        "model",
        Model::<T>::new(ok(
            "bench",
            reference::exp2_bench(Exp2Mass::Accurate, 60, 3),
        )?),
    )?;
    let settings = ShootingSettings::default();
    for grams in [0.0, 40.2, 83.2] {
        let load = TipLoad::force(lit3([0.0, -grams * 1e-3 * reference::GRAVITY_M_S2, 0.0]));
        let full = solved(&model, &load)?;
        let planar = model_core::planar::PlanarModel::new(&model, &load).ok_or(Failure {
            check: "scene is planar",
            value: 0.0,
            limit: 1.0,
        })?;
        let reduced = ok("planar solve input", planar.solve(&load, &settings))?;
        holds(
            "planar solve converged",
            reduced.report.termination.is_success(),
        )?;
        within(
            "tip difference, m",
            f64s(&(full.tip_position_m - reduced.tip_position_m)).norm(),
            tol::<T>(1e-8, 2e-6),
        )?;
        for (a, b) in full
            .cable_lengths_m
            .iter()
            .zip(reduced.cable_lengths_m.iter())
        {
            within(
                "cable difference, m",
                (a.to_f64() - b.to_f64()).abs(),
                tol::<T>(1e-8, 2e-6),
            )?;
        }
    }
    let sideways = TipLoad::force(lit3([0.0, -0.1, 0.05]));
    holds(
        "out-of-plane load not reduced",
        model_core::planar::PlanarModel::new(&model, &sideways).is_none(),
    )
}

/// The model picker: for the in-plane thesis bench it takes the planar reduction, its measured error
/// meets the requested tolerance, it costs no more than the full model, and a tighter tolerance
/// never gets a cheaper pick.
pub fn reduction_meets_tolerance<T: Scalar>() -> Outcome {
    let rod = ok(
        "bench",
        reference::exp2_bench::<T>(Exp2Mass::Accurate, 100, 3),
    )?;
    let load = TipLoad::force(lit3([0.0, -0.0402 * reference::GRAVITY_M_S2, 0.0]));
    let settings = ShootingSettings::default();
    let mut previous_cost = 0;
    for tolerance in [1e-3, 1e-5] {
        let choice = ok(
            "choice",
            model_core::reduction::choose(&rod, &load, T::lit(tolerance), &settings),
        )?;
        holds("planar picked for an in-plane scene", choice.variant.planar)?;
        within(
            "measured error over the tolerance",
            choice.error_m.to_f64() / tolerance,
            1.0,
        )?;
        holds(
            "no dearer than the full model",
            choice.cost <= choice.full_cost,
        )?;
        holds(
            "a tighter tolerance costs at least as much",
            choice.cost >= previous_cost,
        )?;
        previous_cost = choice.cost;
    }
    Ok(())
}

/// Invalid inputs come back as typed errors, never a panic or a wrong answer.
pub fn invalid_inputs_are_refused<T: Scalar>() -> Outcome
where
    Params: ParamCount<T, 3>,
{
    let bench = || ok("bench", reference::golden_bench::<T>(20));
    let nan = T::lit(f64::NAN);
    let model = ok("model", Model::new(bench()?))?;
    let settings = ShootingSettings::default();
    holds(
        "NaN tip force",
        model.solve(
            &TipLoad::force(Vector3::new(nan, T::zero(), T::zero())),
            Start::Cold,
            &settings,
        ) == Err(ModelError::NonFinite("tip force")),
    )?;
    let mut rod = bench()?;
    if let Some(s) = rod.sections.first_mut() {
        s.length_m = T::zero();
    }
    holds(
        "zero section length",
        Model::<T>::new(rod).err() == Some(ModelError::NotPositive("section length")),
    )?;
    let mut rod = bench()?;
    if let Some(s) = rod.sections.first_mut() {
        s.steps = 0;
    }
    holds(
        "zero steps",
        Model::<T>::new(rod).err() == Some(ModelError::NotPositive("section steps")),
    )?;
    let mut rod = bench()?;
    let mut refused = false;
    for _ in 0..model_core::MAX_GUIDES + 1 {
        refused |= rod
            .push_guide(model_core::Guide {
                s_m: T::lit(0.1),
                thickness_m: T::zero(),
                mass_kg: T::zero(),
            })
            .is_err();
    }
    holds("too many guides", refused)?;
    let mut rod = bench()?;
    if let Some(g) = rod.guides.get_mut(1) {
        g.s_m = T::lit(0.001);
    }
    holds(
        "unordered guides",
        Model::<T>::new(rod).err() == Some(ModelError::Unordered("guides")),
    )?;
    let mut rod = bench()?;
    ok(
        "cable",
        rod.push_cable(Cable {
            hole_m: Vector2::new(T::lit(0.01), T::zero()),
            end_m: T::lit(1.0),
        }),
    )?;
    holds(
        "cable ending beyond the tip",
        Model::<T>::new(rod).err() == Some(ModelError::OutOfRange("cable termination")),
    )?;
    let settings = InverseSettings::default();
    let basis = LoadBasis::tip_force();
    let start = InverseStart::Params(Vector3::zeros());
    let too_long = [T::lit(0.39), T::lit(0.39), T::lit(5.0)];
    holds(
        "cable longer than possible",
        estimate(&model, &basis, &too_long, start, &settings).is_err(),
    )?;
    let negative = [T::lit(0.39), T::lit(-0.39), T::lit(0.39)];
    holds(
        "negative cable length",
        estimate(&model, &basis, &negative, start, &settings).is_err(),
    )?;
    let missing = [T::lit(0.39), T::lit(0.39)];
    holds(
        "wrong number of cable lengths",
        estimate(&model, &basis, &missing, start, &settings).is_err(),
    )?;
    let material = Material::isotropic(T::lit(62e9), T::lit(0.7));
    holds("Poisson's ratio above 0.5", material.is_err())?;
    holds(
        "negative diameter",
        CrossSection::solid_circle(T::lit(-1.0)).is_err(),
    )?;
    let blank = ShapePoint::default();
    let mut out = [blank; 2];
    let eq = solved(&model, &TipLoad::zero())?;
    holds(
        "unsorted shape queries",
        model
            .shape(&eq, &[T::lit(0.2), T::lit(0.1)], &mut out)
            .is_err(),
    )?;
    holds(
        "shape query beyond the tip",
        model.shape(&eq, &[T::lit(0.5)], &mut out).is_err(),
    )?;
    holds(
        "shape buffer too small",
        model
            .shape(&eq, &[T::zero(), T::lit(0.1), T::lit(0.2)], &mut out)
            .is_err(),
    )
}

/// Every case, in a fixed order.
pub fn cases<T: Scalar>() -> [Case; 22]
where
    Params: ParamCount<T, 1> + ParamCount<T, 3>,
{
    [
        Case {
            name: "cantilever tip load: P L^3/3EI + P L/GA",
            run: cantilever_tip_load::<T>,
        },
        Case {
            name: "uniform weight: w L^4/8EI + w L^2/2GA",
            run: cantilever_uniform_weight::<T>,
        },
        Case {
            name: "pure tip moment: circle of radius EI/M",
            run: pure_moment_circle::<T>,
        },
        Case {
            name: "axial load: extension F L/EA",
            run: axial_extension::<T>,
        },
        Case {
            name: "two sections of one material = one section",
            run: two_sections_equal_one::<T>,
        },
        Case {
            name: "thesis Table 4.5, average mass",
            run: table_4_5_average::<T>,
        },
        Case {
            name: "thesis Table 4.5, accurate mass",
            run: table_4_5_accurate::<T>,
        },
        Case {
            name: "thesis Table 4.1 predicted section tips",
            run: table_4_1::<T>,
        },
        Case {
            name: "thesis Tables 4.1 and 4.3 converge cold",
            run: thesis_rows_converge_cold::<T>,
        },
        Case {
            name: "golden 3D forward: tips and cable lengths",
            run: golden_forward::<T>,
        },
        Case {
            name: "force as state = dead-load path (golden rows)",
            run: force_state_matches_dead_load::<T>,
        },
        Case {
            name: "golden 3D inverse from cable lengths",
            run: golden_inverse::<T>,
        },
        Case {
            name: "pushed back past buckling: two conjugate points at once",
            run: pushed_back_past_buckling::<T>,
        },
        Case {
            name: "round trip: warm estimator tracks a 3D force",
            run: round_trip_tracking::<T>,
        },
        Case {
            name: "axial tip force reported weakly determined",
            run: axial_force_is_weakly_determined::<T>,
        },
        Case {
            name: "one cable, three unknowns: undetermined",
            run: one_cable_three_unknowns_is_undetermined::<T>,
        },
        Case {
            name: "one cable, hung mass; saturation widens std",
            run: one_cable_hung_mass::<T>,
        },
        Case {
            name: "upside-down equilibrium reported unstable",
            run: wrong_branch_is_reported::<T>,
        },
        Case {
            name: "10x heaviest thesis load stays on branch",
            run: ten_times_heaviest_load::<T>,
        },
        Case {
            name: "planar reduction matches 3D",
            run: planar_reduction_matches_3d::<T>,
        },
        Case {
            name: "model picker meets the tolerance",
            run: reduction_meets_tolerance::<T>,
        },
        Case {
            name: "invalid inputs refused with typed errors",
            run: invalid_inputs_are_refused::<T>,
        },
    ]
}

/// Runs every case; returns how many passed and failed, calling `report` with each result.
pub fn run_all<T: Scalar>(mut report: impl FnMut(&'static str, &Outcome)) -> (usize, usize)
where
    Params: ParamCount<T, 1> + ParamCount<T, 3>,
{
    let (mut passed, mut failed) = (0, 0);
    for case in cases::<T>() {
        let outcome = (case.run)();
        if outcome.is_ok() {
            passed += 1;
        } else {
            failed += 1;
        }
        report(case.name, &outcome);
    }
    (passed, failed)
}
