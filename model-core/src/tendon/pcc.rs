//! Piecewise constant curvature (MODEL.md §6.9): the cheapest tendon variant, closed form, no solve.
//!
//! The backbone is cut at the section ends and the tendons' terminations; on each piece the rod
//! carries only the moment of the tendons routed along it, taken along the tangent, so its strains
//! are constant:
//!
//! ```text
//! C u = sum_i tau_i e3 x r_i,      v = e3 - D^-1 e3 sum_i tau_i    (Kirchhoff: v = e3)
//! ```
//!
//! and the piece is a circular arc (Webster & Jones 2010's constant-curvature kinematics, with the
//! stretch of the rod's strain model). Gravity, point loads and the tip load are not part of it: they
//! are accepted and ignored, and their effect is this variant's error (measured in
//! `tests/tendon_variants.rs`). Without them it is exact: with no external load the composite force
//! and moment vanish (`distributed.rs`), every `g_i = e3` solves the strain equations, and the
//! continuous-routing model is this arc, piece by piece.
//!
//! A piece of reference length `l` with strains `u`, `v` moves the frame by
//! `R+ = R exp(hat(u l))`, `p+ = p + R G(u l) v l`,
//! `G(phi) = I + (1 - cos t) / t^2 hat(phi) + (t - sin t) / t^3 hat(phi)^2`, `t = |phi|`; a tendon
//! routed along it lengthens by `l |v + u x r_i|`.

use heapless::Vec;
use nalgebra::{Matrix3, Vector3};

use super::distributed::Routing;
use super::{MAX_TENDONS, TendonEquilibrium, Tendons};
use crate::error::{ModelError, finite_vec};
use crate::kinematics::{Attitude, exp_so3};
use crate::loads::TipLoad;
use crate::model::Model;
use crate::plan::section_at;
use crate::report::{SolveReport, Termination};
use crate::rod::StrainModel;
use crate::shape::{ShapePoint, check_queries};
use crate::shooting::Equilibrium;
use crate::stability::Stability;
use crate::{MAX_CABLES, MAX_SECTIONS, Scalar};

/// Most pieces: one per section and one per termination.
const MAX_PIECES: usize = MAX_SECTIONS + MAX_TENDONS + 1;

/// A backbone point and frame.
type Frame<T> = (Vector3<T>, Matrix3<T>);

/// One arc of constant strain.
#[derive(Clone, Copy, Debug)]
struct Piece<T> {
    s0_m: T,
    s1_m: T,
    u: Vector3<T>,
    v: Vector3<T>,
    /// Each tendon's length per unit reference length here (zero when not routed here).
    speed: [T; MAX_TENDONS],
}

/// The pieces' start poses and strains.
#[derive(Clone, Debug)]
struct Arcs<T> {
    pieces: Vec<Piece<T>, MAX_PIECES>,
    /// The pose at each piece's start.
    starts: Vec<Frame<T>, MAX_PIECES>,
    tip: Frame<T>,
}

/// `G(phi)`: the integral of `exp(hat(phi) x)` over `x` in `[0, 1]`.
fn arc_matrix<T: Scalar>(phi: &Vector3<T>) -> Matrix3<T> {
    let t2 = phi.norm_squared();
    let (a, b) = if t2 < T::lit(1e-4) {
        // (1 - cos t)/t^2 and (t - sin t)/t^3 to O(t^6).
        (
            T::lit(0.5) - t2 / T::lit(24.0) * (T::one() - t2 / T::lit(30.0)),
            (T::one() - t2 / T::lit(20.0) * (T::one() - t2 / T::lit(42.0))) / T::lit(6.0),
        )
    } else {
        let t = t2.sqrt();
        let (s, c) = t.sin_cos();
        ((T::one() - c) / t2, (t - s) / (t2 * t))
    };
    let k = phi.cross_matrix();
    Matrix3::identity() + k * a + k * k * b
}

/// The pose a distance `len` along a piece from `(p, r)`.
fn along<T: Scalar>(piece: &Piece<T>, p: &Vector3<T>, r: &Matrix3<T>, len: T) -> Frame<T> {
    let phi = piece.u * len;
    (
        p + r * (arc_matrix(&phi) * piece.v * len),
        r * exp_so3(&phi),
    )
}

impl<T: Scalar> Arcs<T> {
    fn new<A: Attitude<T>, const NODES: usize>(
        model: &Model<T, A, NODES>,
        tendons: &Tendons<T>,
        tensions_n: &[T],
    ) -> Result<Self, ModelError> {
        let rod = model.rod();
        let length = model.length_m();
        let tol = length * T::lit(1e-6);
        let mut cuts: Vec<T, { MAX_PIECES + 1 }> = Vec::new();
        let mut push = |s: T| cuts.push(s).map_err(|_| ModelError::Capacity("PCC pieces"));
        push(T::zero())?;
        let mut end = T::zero();
        for section in &rod.sections {
            end += section.length_m;
            push(end)?;
        }
        for r in &tendons.routed {
            if let Some(s) = tendons.guide_s_m.get(r.end_guide) {
                push(*s)?;
            }
        }
        crate::scalar::insertion_sort(&mut cuts, |a, b| a < b);
        let kirchhoff = rod.strain_model == StrainModel::Kirchhoff;
        let mut out = Self {
            pieces: Vec::new(),
            starts: Vec::new(),
            tip: (rod.base_position_m, rod.base_orientation),
        };
        let (mut p, mut r) = out.tip;
        let mut s0 = T::zero();
        for &s1 in cuts.iter().skip(1) {
            let s1 = s1.min(length);
            if s1 - s0 <= tol {
                continue;
            }
            let mid = (s0 + s1) * T::lit(0.5);
            let (section, _) = section_at(rod, mid);
            let comp = u8::try_from(section)
                .ok()
                .and_then(|k| model.compliance(k))
                .ok_or(ModelError::OutOfRange("section"))?;
            let routing = Routing::along(tendons, tensions_n, mid);
            let u = -comp.c_inv.component_mul(&routing.straight_moment_nm());
            let v = if kirchhoff {
                Vector3::z()
            } else {
                Vector3::z() - comp.d_inv.component_mul(&Vector3::z()) * routing.total_tension_n()
            };
            let mut speed = [T::zero(); MAX_TENDONS];
            for (i, offset, _) in routing.iter() {
                if let Some(sp) = speed.get_mut(i) {
                    let w = v + u.cross(offset);
                    // A tendon running backwards: the arc curls inside its offset.
                    *sp = if w.z > T::zero() {
                        w.norm()
                    } else {
                        T::lit(f64::NAN)
                    };
                }
            }
            let piece = Piece {
                s0_m: s0,
                s1_m: s1,
                u,
                v,
                speed,
            };
            out.starts
                .push((p, r))
                .map_err(|_| ModelError::Capacity("PCC pieces"))?;
            out.pieces
                .push(piece)
                .map_err(|_| ModelError::Capacity("PCC pieces"))?;
            (p, r) = along(&piece, &p, &r, s1 - s0);
            s0 = s1;
        }
        out.tip = (p, r);
        Ok(out)
    }

    /// The piece containing `s` (the distal one at a cut), its start pose.
    fn piece_at(&self, s: T) -> Option<(&Piece<T>, &Frame<T>)> {
        let k = self
            .pieces
            .iter()
            .position(|piece| s < piece.s1_m)
            .unwrap_or(self.pieces.len().saturating_sub(1));
        Some((self.pieces.get(k)?, self.starts.get(k)?))
    }

    fn point(&self, s: T) -> Option<ShapePoint<T>> {
        let (piece, (p, r)) = self.piece_at(s)?;
        let (position_m, rotation) = along(piece, p, r, s - piece.s0_m);
        Some(ShapePoint {
            s_m: s,
            position_m,
            rotation,
            strain_per_m: piece.u,
        })
    }

    /// Each tendon's path: its length per unit reference length summed over the pieces.
    fn paths(&self) -> [T; MAX_TENDONS] {
        let mut out = [T::zero(); MAX_TENDONS];
        for piece in &self.pieces {
            for (l, sp) in out.iter_mut().zip(&piece.speed) {
                *l += *sp * (piece.s1_m - piece.s0_m);
            }
        }
        out
    }
}

/// The rod's measuring cables (`crate::rod::Cable`) on the arcs: chords from the first guide through
/// each guide up to the termination, as the sweep traces them.
fn cable_lengths<T: Scalar, A: Attitude<T>, const NODES: usize>(
    model: &Model<T, A, NODES>,
    arcs: &Arcs<T>,
) -> Option<Vec<T, MAX_CABLES>> {
    let rod = model.rod();
    let tol = model.length_m() * T::lit(1e-6);
    let mut out = Vec::new();
    for cable in &rod.cables {
        let offset = cable.offset_local_m();
        let hole = |s: T| arcs.point(s).map(|pt| pt.position_m + pt.rotation * offset);
        let mut prev: Option<Vector3<T>> = None;
        let mut sum = T::zero();
        let guides = rod
            .guides
            .iter()
            .map(|g| g.s_m)
            .filter(|s| *s <= cable.end_m + tol);
        for s in guides.chain(core::iter::once(cable.end_m)) {
            let here = hole(s)?;
            if let Some(prev) = prev {
                sum += (here - prev).norm();
            }
            prev = Some(here);
        }
        out.push(sum).ok()?;
    }
    Some(out)
}

impl<T: Scalar, A: Attitude<T>, const NODES: usize> Model<T, A, NODES> {
    /// The piecewise-constant-curvature shape under tendon tensions `tensions_n` (N, one per tendon,
    /// none negative), and each tendon's path length along its arcs. Closed form: no sweep, no
    /// solve, `Converged` (or `NonFinite` if a tendon would fold back on itself).
    ///
    /// This variant knows only the tendons' moments: a scene with gravity, point loads or a tip load
    /// is refused (`OutOfRange`), since its answer would not be that scene's equilibrium. To take
    /// its error knowingly (the model picker measures it), call
    /// [`Model::solve_tendons_pcc_ignoring_loads`].
    pub fn solve_tendons_pcc(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        load: &TipLoad<T>,
    ) -> Result<TendonEquilibrium<T>, ModelError> {
        let rod = self.rod();
        let zero = nalgebra::Vector3::zeros();
        let loaded = rod.gravity_m_s2 != zero
            || rod
                .loads
                .iter()
                .any(|l| l.force_n != zero || l.moment_nm != zero)
            || load.force_n != zero
            || load.moment_nm != zero;
        if loaded {
            return Err(ModelError::OutOfRange(
                "gravity or loads (piecewise constant curvature ignores them; \
                 solve_tendons_pcc_ignoring_loads takes that error knowingly)",
            ));
        }
        self.solve_tendons_pcc_ignoring_loads(tendons, tensions_n, load)
    }

    /// [`Model::solve_tendons_pcc`] with gravity, point loads and `load` recorded but not acting:
    /// their effect is this variant's error (MODEL.md §6.9), which the caller takes knowingly. The
    /// answer reports `Converged` as the closed form of the unloaded arcs, not as the scene's
    /// equilibrium.
    pub fn solve_tendons_pcc_ignoring_loads(
        &self,
        tendons: &Tendons<T>,
        tensions_n: &[T],
        load: &TipLoad<T>,
    ) -> Result<TendonEquilibrium<T>, ModelError> {
        tendons.check_model(self)?;
        let tau = tendons.check_tensions(tensions_n)?;
        let tau = tau.get(..tendons.len()).unwrap_or(&[]);
        load.validate()?;
        let arcs = Arcs::new(self, tendons, tau)?;
        let rod = self.rod();
        let r0 = rod.base_orientation;
        let first = arcs.pieces.first().ok_or(ModelError::Empty("sections"))?;
        let comp = self
            .base_compliance()
            .ok_or(ModelError::Empty("sections"))?;
        let total = Routing::along(tendons, tau, T::zero()).total_tension_n();
        let paths = arcs.paths();
        let cables = cable_lengths(self, &arcs);
        let finite = crate::scalar::all_finite(&arcs.tip.0)
            && paths
                .iter()
                .take(tendons.len())
                .all(|l| l.is_finite() && *l > T::zero())
            && arcs
                .pieces
                .iter()
                .all(|p| p.speed.iter().all(|s| s.is_finite()) && crate::scalar::all_finite(&p.u))
            && cables.is_some();
        let mut tensions = Vec::new();
        for t in tensions_n {
            // Cannot overflow: checked against MAX_TENDONS.
            let _ = tensions.push(*t);
        }
        let mut path_m = Vec::new();
        if finite {
            for l in paths.iter().take(tendons.len()) {
                let _ = path_m.push(*l);
            }
        }
        let equilibrium = Equilibrium {
            base_strain_per_m: first.u,
            // The tendons' pull, along the tangent, is all the rod carries at its base.
            base_force_n: -r0.column(2) * total,
            base_moment_nm: r0 * comp.c.component_mul(&first.u),
            load: *load,
            tip_position_m: arcs.tip.0,
            tip_rotation: arcs.tip.1,
            cable_lengths_m: cables.unwrap_or_default(),
            jacobian_nm2: None,
            report: SolveReport {
                termination: if finite {
                    Termination::Converged
                } else {
                    Termination::NonFinite
                },
                iterations: 0,
                sweeps: 0,
                residual: T::zero(),
                load_steps: 0,
                stability: Stability::Unchecked,
                phase_per_step_rad: T::zero(),
            },
        };
        let unstretched_m = super::paths::uniform_unstretched(tendons, &tensions, &path_m);
        Ok(TendonEquilibrium {
            equilibrium,
            tensions_n: tensions,
            path_m,
            unstretched_m,
        })
    }

    /// The backbone of a piecewise-constant-curvature shape at the arc lengths `s_m` (see
    /// [`Model::shape`]); the strain is the piece's (the distal one's at a cut).
    pub fn shape_tendons_pcc(
        &self,
        tendons: &Tendons<T>,
        solved: &TendonEquilibrium<T>,
        s_m: &[T],
        out: &mut [ShapePoint<T>],
    ) -> Result<usize, ModelError> {
        tendons.check_model(self)?;
        let tau = tendons.check_tensions(&solved.tensions_n)?;
        let tau = tau.get(..tendons.len()).unwrap_or(&[]);
        check_queries(s_m, out.len(), self.length_m())?;
        let arcs = Arcs::new(self, tendons, tau)?;
        let mut written = 0;
        for (s, o) in s_m.iter().zip(out.iter_mut()) {
            let point = arcs.point(*s).ok_or(ModelError::Empty("sections"))?;
            finite_vec(&point.position_m, "PCC shape")?;
            *o = point;
            written += 1;
        }
        Ok(written)
    }
}
