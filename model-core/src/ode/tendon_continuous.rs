//! The rod pulled by continuously routed tendons (Rucker & Webster 2011; MODEL.md §6.8): each tendon
//! runs along the backbone at its constant body offset, pressing on it with a distributed load, and
//! pulls at its termination.
//!
//! The states are the composite force and moment `N`, `M` of the rod and its tendons cut together
//! (global), with the position and frame: `p' = R v`, `R' = R hat(u)`, `N' = -f`, `M' = -p' x N`,
//! the dead-load equations of `force_state.rs`, because the tendons' distributed load and their pull
//! at the terminations are internal to the composite. The tendons enter the constitutive law
//! (`crate::tendon` `distributed.rs`): `(v, u)` solve `D (v - e3) + sum tau g_i = R^T N`,
//! `C u + sum tau r_i x g_i = R^T M` at every stage, Newton in six unknowns. A termination is a node
//! where the routing changes, and `N`, `M` are continuous there; the rod's own force jumps by the
//! tendon's pull, `-tau R g`, which the composite already holds.
//!
//! Unknowns `x = (N(0) L / E I, M(0) / E I)`, residual `((N(L) - F) L, M(L) - M_tip)`, as in
//! `force_state.rs`: six unknowns, single shooting. Tangents: those of `force_state.rs` with
//! `(dv, du) = J^-1 (n_l x dtheta + R^T dN, m_l x dtheta + R^T dM)`, `J` the strain solve's Jacobian.
//!
//! The state also integrates each tendon's path, `l_i' = |v + u x r_i|` up to its termination: the
//! length of its curve `p + R r_i` from the base plate's hole.

use core::cell::Cell;

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::force_state::{self, ForceStateRod};
use super::{Pose, RodOde};
use crate::Scalar;
use crate::kinematics::Attitude;
use crate::loads::{NoShapeLoad, TipLoad};
use crate::model::{Grid, Model};
use crate::plan::{Interval, Node};
use crate::rod::StrainModel;
use crate::shape::ShapePoint;
use crate::tendon::distributed::{Routing, Section, Strains, chord_matrix, strains};
use crate::tendon::{MAX_TENDONS, Tendons};

static NO_SHAPE_LOAD: NoShapeLoad = NoShapeLoad;

/// The rod under dead loads and continuously routed tendons.
#[derive(Debug)]
pub(crate) struct ContinuousTendonRod<'a, T: Scalar, A: Attitude<T>, const NODES: usize> {
    rod: ForceStateRod<'a, T, A, NoShapeLoad, NODES>,
    model: &'a Model<T, A, NODES>,
    tendons: &'a Tendons<T>,
    /// Full tensions, N.
    tensions_n: [T; MAX_TENDONS],
    /// Tensions at the load scale, N.
    scaled_n: [T; MAX_TENDONS],
    kirchhoff: bool,
    /// Where each sweep leaves its unknowns, load scale and the path lengths it integrated.
    record: Option<&'a PathRecord<T>>,
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Clone for ContinuousTendonRod<'_, T, A, NODES> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Copy for ContinuousTendonRod<'_, T, A, NODES> {}

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> ContinuousTendonRod<'a, T, A, NODES> {
    /// The equations of `model` under `load`, the scene's dead loads and the tendons at
    /// `tensions_n`, all scaled by `alpha`.
    pub(crate) fn new(
        model: &'a Model<T, A, NODES>,
        tendons: &'a Tendons<T>,
        tensions_n: &[T; MAX_TENDONS],
        load: &TipLoad<T>,
        alpha: T,
    ) -> Self {
        Self {
            rod: ForceStateRod::new(model, &NO_SHAPE_LOAD, load, alpha),
            model,
            tendons,
            tensions_n: *tensions_n,
            scaled_n: tensions_n.map(|t| t * alpha),
            kirchhoff: model.rod().strain_model == StrainModel::Kirchhoff,
            record: None,
        }
    }

    /// The same equations, leaving in `record` where each sweep ran and the path lengths it
    /// integrated to the tip.
    pub(crate) fn recording<'b>(
        &self,
        record: &'b PathRecord<T>,
    ) -> ContinuousTendonRod<'b, T, A, NODES>
    where
        'a: 'b,
    {
        let shorter: ContinuousTendonRod<'b, T, A, NODES> = *self;
        ContinuousTendonRod {
            record: Some(record),
            ..shorter
        }
    }

    fn tensions(&self) -> &[T] {
        self.scaled_n.get(..self.tendons.len()).unwrap_or(&[])
    }

    /// The first interval's section and routing: the base's.
    fn base_section(&self) -> Option<(Section<T>, Routing<T>)> {
        let first = self.model.plan().intervals.first()?;
        let comp = self.model.compliance(first.section)?;
        Some((
            Section::new(comp, self.kirchhoff),
            Routing::along(self.tendons, self.tensions(), first.s0_m),
        ))
    }

    /// The scaled unknowns of the rod's own base force (N) and moment (N m), global: the tendons'
    /// tensions along their tangents there are added (explicit: the strains follow from `n`, `m`).
    pub(crate) fn unknowns(&self, force_n: &Vector3<T>, moment_nm: &Vector3<T>) -> SVector<T, 6> {
        let r0 = self.model.rod().base_orientation;
        let Some((sec, routing)) = self.base_section() else {
            return SVector::repeat(T::lit(f64::NAN));
        };
        let n_l = r0.tr_mul(force_n);
        let v = if sec.kirchhoff {
            Vector3::z()
        } else {
            Vector3::z() + sec.d_inv.component_mul(&n_l)
        };
        let u = sec.c_inv.component_mul(&r0.tr_mul(moment_nm));
        let mut n = *force_n;
        let mut m = *moment_nm;
        for (_, r, tau) in routing.iter() {
            let g = (v + u.cross(r)).normalize();
            n += r0 * g * tau;
            m += r0 * r.cross(&g) * tau;
        }
        self.rod.unknowns(&n, &m)
    }

    /// The base strain and the rod's own base force and moment (global) of unknowns `x`.
    pub(crate) fn base(&self, x: &SVector<T, 6>) -> (Vector3<T>, Vector3<T>, Vector3<T>) {
        let (n, m) = self.rod.force_moment(x);
        let r0 = self.model.rod().base_orientation;
        let solved = self.base_section().and_then(|(sec, routing)| {
            let chord = chord_matrix(&sec, &routing)?;
            let s = strains(&sec, &routing, &chord, &r0.tr_mul(&n), &r0.tr_mul(&m), None)?;
            Some((s, sec))
        });
        match solved {
            Some((s, sec)) => (s.u, r0 * s.n_rod, r0 * sec.c.component_mul(&s.u)),
            None => {
                let nan = Vector3::repeat(T::lit(f64::NAN));
                (nan, nan, nan)
            }
        }
    }

    fn solve_strains(
        f: &Field<'a, T>,
        rot: &Matrix3<T>,
        y: &force_state::State<T, A>,
        jacobian_inverse: Option<&mut SMatrix<T, 6, 6>>,
    ) -> Strains<T> {
        strains(
            &f.section,
            &f.routing,
            &f.chord,
            &rot.tr_mul(&y.n),
            &rot.tr_mul(&y.m),
            jacobian_inverse,
        )
        .unwrap_or_else(Strains::failed)
    }
}

/// What the last sweep saw: its unknowns, its load scale and each tendon's path length at the tip.
/// A solve's converged sweep ran at its answer, so the solve's paths are read from it rather than
/// from one more sweep (when the record is that sweep's: same unknowns, full scale, reached the tip).
#[derive(Debug)]
pub(crate) struct PathRecord<T: Scalar> {
    x: Cell<SVector<T, 6>>,
    alpha: Cell<T>,
    /// Not a number until the sweep reaches the tip.
    paths: Cell<[T; MAX_TENDONS]>,
}

impl<T: Scalar> PathRecord<T> {
    /// An empty record.
    pub(crate) fn new() -> Self {
        Self {
            x: Cell::new(SVector::repeat(T::lit(f64::NAN))),
            alpha: Cell::new(T::zero()),
            paths: Cell::new([T::lit(f64::NAN); MAX_TENDONS]),
        }
    }

    /// The path lengths of the last sweep, if it ran at unknowns `x` at full load to the tip and
    /// they are finite.
    pub(crate) fn paths_at(&self, x: &SVector<T, 6>) -> Option<[T; MAX_TENDONS]> {
        let paths = self.paths.get();
        let held = self.x.get() == *x && self.alpha.get() == T::one();
        (held && paths.iter().all(|l| l.is_finite())).then_some(paths)
    }

    fn start(&self, x: &SVector<T, 6>, alpha: T) {
        self.x.set(*x);
        self.alpha.set(alpha);
        self.paths.set([T::lit(f64::NAN); MAX_TENDONS]);
    }
}

/// The rod's state and each tendon's path length so far.
#[derive(Clone, Copy, Debug)]
pub(crate) struct State<T: Scalar, A> {
    rod: force_state::State<T, A>,
    path_m: [T; MAX_TENDONS],
}

/// The rod's rates and each tendon's length per unit reference length.
#[derive(Clone, Copy)]
pub(crate) struct Rates<T: Scalar, A: Attitude<T>> {
    rod: force_state::Rates<T, A>,
    speed: [T; MAX_TENDONS],
}

/// What a tangent's rate needs from one stage.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stage<T> {
    rot: Matrix3<T>,
    /// Composite force, global.
    n: Vector3<T>,
    /// Composite force and moment, body frame.
    n_local: Vector3<T>,
    m_local: Vector3<T>,
    v: Vector3<T>,
    u: Vector3<T>,
    p_rate: Vector3<T>,
    /// `d(v, u) / d(n_l, m_l)`.
    jacobian_inverse: SMatrix<T, 6, 6>,
}

/// One interval's coefficients: the rod's, its section's stiffnesses and the tendons routed along it.
#[derive(Debug)]
pub(crate) struct Field<'a, T> {
    rod: force_state::Field<'a, T>,
    section: Section<T>,
    routing: Routing<T>,
    /// The strain solve's chord matrix.
    chord: SMatrix<T, 6, 6>,
    /// The section's index in the rod.
    section_index: u8,
}

type Inner<'a, T, A, const NODES: usize> = ForceStateRod<'a, T, A, NoShapeLoad, NODES>;

impl<'a, T: Scalar, A: Attitude<T>, const NODES: usize> RodOde<T, 6>
    for ContinuousTendonRod<'a, T, A, NODES>
{
    type State = State<T, A>;
    type Rate = Rates<T, A>;
    type Stage = Stage<T>;
    type Tangent = force_state::Tangent<T>;
    type Seed = Vector3<T>;
    type Field = Field<'a, T>;
    type Track = ();

    fn grid(&self) -> Grid<'_, T> {
        self.rod.grid()
    }

    fn length_m(&self) -> T {
        self.rod.length_m()
    }

    fn at_scale(&self, load_scale: T) -> Self {
        Self {
            rod: self.rod.at_scale(load_scale),
            scaled_n: self.tensions_n.map(|t| t * load_scale),
            ..*self
        }
    }

    /// The dead loads' guess: on the straight rod the tendons' pull at their terminations and their
    /// tensions at the base cancel in the composite, which carries the dead loads alone.
    fn guess(&self) -> SVector<T, 6> {
        self.rod.guess()
    }

    fn start(&self, x: &SVector<T, 6>) -> State<T, A> {
        if let Some(record) = self.record {
            record.start(x, self.rod.alpha());
        }
        State {
            rod: self.rod.start(x),
            path_m: [T::zero(); MAX_TENDONS],
        }
    }

    /// The tensions' tangents are not traced along continuous routing: a sweep asked for one is
    /// not finite (never a zero derivative that reads as exact).
    fn seed(&self, family: super::Family, j: usize) -> (force_state::Tangent<T>, Vector3<T>) {
        let (mut tangent, seed) = self.rod.seed(family, j);
        if family == super::Family::Tension {
            tangent.n = Vector3::repeat(T::lit(f64::NAN));
        }
        (tangent, seed)
    }

    fn no_seed(&self) -> Vector3<T> {
        Vector3::zeros()
    }

    fn blank_stage(&self) -> Stage<T> {
        Stage {
            rot: Matrix3::zeros(),
            n: Vector3::zeros(),
            n_local: Vector3::zeros(),
            m_local: Vector3::zeros(),
            v: Vector3::zeros(),
            u: Vector3::zeros(),
            p_rate: Vector3::zeros(),
            jacobian_inverse: SMatrix::zeros(),
        }
    }

    fn field(&self, interval: &Interval<T>) -> Option<Field<'a, T>> {
        self.next_field(None, interval)
    }

    /// Within a section and a set of tendons, the chord matrix is the previous interval's.
    fn next_field(
        &self,
        previous: Option<&Field<'a, T>>,
        interval: &Interval<T>,
    ) -> Option<Field<'a, T>> {
        let model: &'a Model<T, A, NODES> = self.model;
        let comp = model.compliance(interval.section)?;
        let mid = (interval.s0_m + interval.s1_m) * T::lit(0.5);
        let section = Section::new(comp, self.kirchhoff);
        let routing = Routing::along(self.tendons, self.tensions(), mid);
        let chord = match previous {
            Some(p) if p.section_index == interval.section && routing.same_tendons(&p.routing) => {
                p.chord
            }
            _ => chord_matrix(&section, &routing)?,
        };
        Some(Field {
            rod: self.rod.field(interval)?,
            chord,
            section,
            routing,
            section_index: interval.section,
        })
    }

    /// The composite force's: the tendons' compression of the rod is balanced along it by their
    /// distributed load (a continuously routed tendon does not buckle the rod), so the bending
    /// phase follows the external loads that `N` carries.
    #[inline]
    fn bending_load(&self, f: &Field<'a, T>, s: T, y: &State<T, A>) -> T {
        self.rod.bending_load(&f.rod, s, &y.rod)
    }

    #[inline]
    fn stage_bending_load(&self, f: &Field<'a, T>, stage: &Stage<T>) -> T {
        super::local_bending_load(&stage.n_local, f.rod.compliance_squared)
    }

    fn rate(
        &self,
        f: &Field<'a, T>,
        _s: T,
        y: &State<T, A>,
        record: Option<&mut Stage<T>>,
    ) -> Rates<T, A> {
        let rot = y.rod.att.matrix();
        let (strains, record) = match record {
            Some(stage) => {
                let s = Self::solve_strains(f, &rot, &y.rod, Some(&mut stage.jacobian_inverse));
                (s, Some(stage))
            }
            None => (Self::solve_strains(f, &rot, &y.rod, None), None),
        };
        let p_rate = rot * strains.v;
        if let Some(stage) = record {
            stage.rot = rot;
            stage.n = y.rod.n;
            stage.n_local = rot.tr_mul(&y.rod.n);
            stage.m_local = rot.tr_mul(&y.rod.m);
            stage.v = strains.v;
            stage.u = strains.u;
            stage.p_rate = p_rate;
        }
        Rates {
            rod: force_state::Rates {
                p: p_rate,
                att: y.rod.att.rate(&rot, &strains.u),
                n: -f.rod.f,
                m: -p_rate.cross(&y.rod.n),
            },
            speed: strains.speed,
        }
    }

    #[inline]
    fn advance(y: &State<T, A>, k: &Rates<T, A>, h: T) -> State<T, A> {
        State {
            rod: Inner::<T, A, NODES>::advance(&y.rod, &k.rod, h),
            path_m: y.path_m,
        }
    }

    #[inline]
    fn combine(y: &State<T, A>, k: [&Rates<T, A>; 4], h: T) -> State<T, A> {
        let [k1, k2, k3, k4] = k;
        let (w1, w2) = (h / T::lit(6.0), h / T::lit(3.0));
        let mut path_m = y.path_m;
        for (j, l) in path_m.iter_mut().enumerate() {
            let rate = |k: &Rates<T, A>| k.speed.get(j).copied().unwrap_or_else(T::zero);
            *l += (rate(k1) + rate(k4)) * w1 + (rate(k2) + rate(k3)) * w2;
        }
        State {
            rod: Inner::<T, A, NODES>::combine(&y.rod, [&k1.rod, &k2.rod, &k3.rod, &k4.rod], h),
            path_m,
        }
    }

    #[inline]
    fn tangent_rate(
        &self,
        _f: &Field<'a, T>,
        st: &Stage<T>,
        _seed: &Vector3<T>,
        t: &force_state::Tangent<T>,
    ) -> force_state::Tangent<T> {
        let dnl = st.n_local.cross(&t.th) + st.rot.tr_mul(&t.n);
        let dml = st.m_local.cross(&t.th) + st.rot.tr_mul(&t.m);
        let mut d = SVector::<T, 6>::zeros();
        d.fixed_rows_mut::<3>(0).copy_from(&dnl);
        d.fixed_rows_mut::<3>(3).copy_from(&dml);
        let dvu = st.jacobian_inverse * d;
        let dv = dvu.fixed_rows::<3>(0).into_owned();
        let du = dvu.fixed_rows::<3>(3).into_owned();
        let dp = st.rot * (t.th.cross(&st.v) + dv);
        force_state::Tangent {
            p: dp,
            th: du - st.u.cross(&t.th),
            n: Vector3::zeros(),
            m: -(dp.cross(&st.n) + st.p_rate.cross(&t.n)),
        }
    }

    /// The dead point loads; the composite is continuous at a termination.
    fn node(
        &self,
        node: &Node<T>,
        proximal: &Field<'a, T>,
        distal: &Field<'a, T>,
        y: &mut State<T, A>,
        tangents: &mut [force_state::Tangent<T>],
    ) {
        self.rod
            .node(node, &proximal.rod, &distal.rod, &mut y.rod, tangents);
    }

    /// `((N(L) - F) L, M(L) - M)`: the composite's tip condition, the rod's and the tendons'
    /// terminating there together. Hands out the path lengths when asked.
    fn tip(
        &self,
        node: Option<&Node<T>>,
        last: &Field<'a, T>,
        y: &State<T, A>,
        tangents: &[force_state::Tangent<T>],
        seeds: &[Vector3<T>],
        d: &mut [SVector<T, 6>],
    ) -> SVector<T, 6> {
        if let Some(record) = self.record {
            record.paths.set(y.path_m);
        }
        self.rod.tip(node, &last.rod, &y.rod, tangents, seeds, d)
    }

    fn pose(&self, y: &State<T, A>) -> Pose<T> {
        self.rod.pose(&y.rod)
    }

    fn tangent_pose(
        &self,
        y: &State<T, A>,
        t: &force_state::Tangent<T>,
    ) -> (Vector3<T>, Vector3<T>) {
        self.rod.tangent_pose(&y.rod, t)
    }

    /// The rod's own strain `u` (one strain solve).
    fn shape_point(&self, s: T, y: &State<T, A>, f: &Field<'a, T>) -> ShapePoint<T> {
        let rotation = y.rod.att.matrix();
        ShapePoint {
            s_m: s,
            position_m: y.rod.p + y.rod.p_lo,
            rotation,
            strain_per_m: Self::solve_strains(f, &rotation, &y.rod, None).u,
        }
    }

    fn finite(&self, y: &State<T, A>, tangents: &[force_state::Tangent<T>]) -> bool {
        self.rod.finite(&y.rod, tangents) && y.path_m.iter().all(|l| l.is_finite())
    }

    /// No energy test with tendons yet: a cold solve follows the branch from the slack rod by load
    /// continuation, and the answer's stability is reported unchecked.
    fn has_stability_test(&self) -> bool {
        false
    }

    fn conservative(&self) -> bool {
        true
    }

    fn track(&self) {}

    fn crosses(
        &self,
        _track: &mut (),
        _y: &State<T, A>,
        _tangents: &[force_state::Tangent<T>],
        _f: &Field<'a, T>,
        _step_m: T,
    ) -> bool {
        false
    }

    fn jacobi_rotation(&self, _d_rotation: &Vector3<T>) -> SVector<T, 6> {
        SVector::zeros()
    }

    fn residual_size(&self, r: &SVector<T, 6>) -> T {
        self.rod.residual_size(r)
    }

    /// The rod's own base moment's rotation: the composite's less the tendons' moment about the
    /// base while they run along the tangent (a tendon-bent rod with no load has `M(0) = 0`).
    fn rotation_rad(&self, x: &SVector<T, 6>) -> T {
        let r0 = self.model.rod().base_orientation;
        let tendons = self
            .base_section()
            .map_or(Vector3::zeros(), |(_, routing)| {
                r0 * routing.straight_moment_nm()
            });
        let scale = self.rod.unknowns(&Vector3::zeros(), &tendons);
        (x - scale).fixed_rows::<3>(3).norm() * self.model.length_m()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::{TangentSet, sweep};
    use crate::tendon::Tendon;
    use crate::{CrossSection, Guide, GuideMass, Material, Rod, Section as RodSection, Stiffness};

    /// Two sections with gravity, three tendons ending at different guides.
    fn scene(strain_model: StrainModel) -> (Model<f64>, [Tendon<f64>; 3]) {
        let mut rod = Rod::new();
        rod.gravity_m_s2 = Vector3::new(0.0, -9.81, 0.0);
        rod.guide_mass = GuideMass::Ignore;
        rod.strain_model = strain_model;
        for (length, d) in [(0.15, 1.5e-3), (0.1, 1.2e-3)] {
            let material = Material::isotropic(60e9, 0.3).unwrap();
            rod.push_section(RodSection {
                length_m: length,
                stiffness: Stiffness::from_material(
                    &material,
                    &CrossSection::solid_circle(d).unwrap(),
                )
                .unwrap(),
                line_density_kg_per_m: 0.03,
                steps: 30,
            })
            .unwrap();
        }
        for k in 1..=5 {
            rod.push_guide(Guide {
                s_m: 0.05 * f64::from(k),
                thickness_m: 0.0,
                mass_kg: 0.0,
            })
            .unwrap();
        }
        let model = Model::new(rod).unwrap();
        (
            model,
            [
                Tendon::at_angle(0.3, 0.01, 0.25),
                Tendon::at_angle(2.0, 0.008, 0.15),
                Tendon::at_angle(4.0, 0.009, 0.2),
            ],
        )
    }

    /// The sweep's Jacobian (tangents through the strain solves) against central differences.
    #[test]
    fn tendon_continuous_jacobian_matches_finite_differences() {
        for strain_model in [StrainModel::Cosserat, StrainModel::Kirchhoff] {
            let (model, tendons) = scene(strain_model);
            let tendons = Tendons::new(&model, &tendons).unwrap();
            let mut tau = [0.0; MAX_TENDONS];
            tau[0] = 2.0;
            tau[1] = 1.5;
            tau[2] = 0.8;
            let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
            let ode = ContinuousTendonRod::new(&model, &tendons, &tau, &load, 1.0);
            let x = ode.guess() * 0.7 + SVector::<f64, 6>::from_fn(|i, _| 0.1 * i as f64);
            let sw = sweep(&ode, &x, TangentSet::unknowns(false), None);
            assert!(sw.finite);
            let j = sw.jacobian();
            let h = 1e-6;
            let mut worst: f64 = 0.0;
            for c in 0..6 {
                let mut dx = SVector::<f64, 6>::zeros();
                dx[c] = h;
                let plus = sweep(&ode, &(x + dx), TangentSet::NONE, None);
                let minus = sweep(&ode, &(x - dx), TangentSet::NONE, None);
                let fd = (plus.residual - minus.residual) / (2.0 * h);
                let err = (fd - j.column(c)).norm() / j.norm();
                worst = worst.max(err);
                // The tip position's tangent too.
                let fd_tip = (plus.tip_position_m - minus.tip_position_m) / (2.0 * h);
                let d_tip = sw.d_position(super::super::Family::Unknown, c);
                assert!(
                    (fd_tip - d_tip).norm() <= 1e-6 * d_tip.norm().max(1e-3),
                    "{strain_model:?} column {c}: tip {fd_tip:?} {d_tip:?}"
                );
            }
            assert!(
                worst < 1e-7,
                "{strain_model:?}: Jacobian off by {worst:e} (relative)"
            );
        }
    }

    /// A record hands out the path lengths of the sweep it recorded, only at that sweep's unknowns
    /// and at full load: a sweep with tangents integrates the same paths as one without (bit for
    /// bit), and a solve's paths (read from its converged sweep) are a plain sweep's at its answer.
    #[test]
    fn tendon_continuous_record_keeps_its_sweeps_paths() {
        let (model, tendons) = scene(StrainModel::Cosserat);
        let set = Tendons::new(&model, &tendons).unwrap();
        let mut tau = [0.0; MAX_TENDONS];
        tau[..3].copy_from_slice(&[2.0, 1.5, 0.8]);
        let load = TipLoad::force(Vector3::new(0.1, -0.2, 0.05));
        let record = PathRecord::new();
        let ode = ContinuousTendonRod::new(&model, &set, &tau, &load, 1.0);
        let recording = ode.recording(&record);
        let x = ode.guess() * 0.7 + SVector::<f64, 6>::from_fn(|i, _| 0.1 * i as f64);
        assert!(sweep(&recording, &x, TangentSet::unknowns(false), None).finite);
        let with_tangents = record.paths_at(&x).unwrap();
        let mut nearby = x;
        nearby[2] += 1e-12;
        assert!(record.paths_at(&nearby).is_none());
        assert!(sweep(&recording, &x, TangentSet::NONE, None).finite);
        let plain = record.paths_at(&x).unwrap();
        for j in 0..3 {
            // Lengths of curves about as long as the tendons' terminations' arc lengths.
            assert!(plain[j] > 0.1 && plain[j] < 0.3, "{plain:?}");
            // The same strain solves, whether the stage records a tangent map or not.
            assert_eq!(with_tangents[j], plain[j], "tendon {j}");
        }
        assert!(sweep(&recording.at_scale(0.5), &x, TangentSet::NONE, None).finite);
        assert!(record.paths_at(&x).is_none());

        let solved = model
            .solve_tendons_continuous(&set, &tau[..3], &load, None, &Default::default())
            .unwrap();
        assert!(solved.is_success(), "{:?}", solved.equilibrium.report);
        let eq = &solved.equilibrium;
        let answer = ode.unknowns(&eq.base_force_n, &eq.base_moment_nm);
        // The unknowns rebuilt from the base force and moment, not bit for bit the solve's.
        assert!(sweep(&recording, &answer, TangentSet::NONE, None).finite);
        let swept = record.paths_at(&answer).unwrap();
        for (j, (path, swept)) in solved.path_m.iter().zip(&swept).enumerate() {
            let gap = (path - swept).abs();
            assert!(gap < 1e-13, "tendon {j}: {gap:e} m");
        }
    }

    /// A sweep's coefficients carried from interval to interval (`next_field`) are those built
    /// afresh (`field`) on every interval, across a change of section that no tendon ends at too.
    #[test]
    fn tendon_continuous_next_field_is_field() {
        let (model, _) = scene(StrainModel::Cosserat);
        // Every tendon runs to the tip, past the change of section (stiffer to softer) at 0.15 m.
        let tendons = [
            Tendon::at_angle(0.3, 0.01, 0.25),
            Tendon::at_angle(2.0, 0.008, 0.25),
            Tendon::at_angle(4.0, 0.009, 0.25),
        ];
        let set = Tendons::new(&model, &tendons).unwrap();
        let mut tau = [0.0; MAX_TENDONS];
        tau[..3].copy_from_slice(&[2.0, 1.5, 0.8]);
        let ode = ContinuousTendonRod::new(&model, &set, &tau, &TipLoad::zero(), 1.0);
        let intervals = &model.plan().intervals;
        let mut previous = ode.field(&intervals[0]).unwrap();
        let mut section_changes = 0;
        for interval in &intervals[1..] {
            let carried = ode.next_field(Some(&previous), interval).unwrap();
            let fresh = ode.field(interval).unwrap();
            assert_eq!(carried.chord, fresh.chord);
            assert_eq!(carried.section.c, fresh.section.c);
            assert_eq!(carried.section.d, fresh.section.d);
            assert!(carried.routing.same_tendons(&fresh.routing));
            assert_eq!(carried.rod.f, fresh.rod.f);
            assert_eq!(carried.rod.compliance_squared, fresh.rod.compliance_squared);
            if carried.section_index != previous.section_index {
                section_changes += 1;
                assert!(carried.routing.same_tendons(&previous.routing));
                assert_ne!(carried.chord, previous.chord);
            }
            previous = carried;
        }
        assert_eq!(section_changes, 1);
    }

    /// Warm-start unknowns from the rod's own base force and moment invert `base`.
    #[test]
    fn tendon_continuous_base_round_trip() {
        let (model, tendons) = scene(StrainModel::Cosserat);
        let tendons = Tendons::new(&model, &tendons).unwrap();
        let mut tau = [0.0; MAX_TENDONS];
        tau[0] = 2.0;
        tau[2] = 0.5;
        let ode = ContinuousTendonRod::new(&model, &tendons, &tau, &TipLoad::zero(), 1.0);
        let x = SVector::<f64, 6>::new(0.3, -0.1, 2.0, 0.4, -0.7, 0.1);
        let (_, n, m) = ode.base(&x);
        let back = ode.unknowns(&n, &m);
        assert!((back - x).norm() < 1e-12, "{back:?}");
    }
}
