//! The integration plan: the fixed grid of nodes and steps the integrator walks.
//!
//! Every discontinuity is a node (section ends, guide centres and, in the accurate-mass model, guide
//! edges, point loads, cable terminations), so no fixed step straddles one. Between nodes the line
//! density and the distal point forces are constant, so the internal force is affine in `s`:
//! `n(s) = F_tip + N_k + g lambda_k (s_{k+1} - s)`, with `N_k` summed once here from the tip down.
//! The plan is built once per scene; its step count is the cost of one sweep, known ahead.

use heapless::Vec;
use nalgebra::Vector3;

use crate::error::ModelError;
use crate::mass::{guide_is_segment, line_density_kg_per_m};
use crate::rod::Rod;
use crate::{MAX_CABLES, MAX_GUIDES, MAX_POINT_LOADS, MAX_SECTIONS, Scalar};

/// Most nodes a plan can hold by default: base, tip, section ends, three per guide, one per load and
/// cable end. It is the default of [`crate::Model`]'s `NODES` parameter; a controller that knows its
/// scene picks a smaller capacity there (the plan is most of a model's memory), and
/// [`crate::Model::new`] refuses a scene that needs more with [`ModelError::Capacity`].
pub const MAX_NODES: usize = 2 + MAX_SECTIONS + 3 * MAX_GUIDES + MAX_POINT_LOADS + MAX_CABLES;

/// No guide at this node.
pub(crate) const NO_GUIDE: u8 = u8::MAX;

/// A node of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node<T> {
    pub s_m: T,
    /// Index of the guide centred here, or `NO_GUIDE`.
    pub guide: u8,
    /// Bit `c` set when cable `c` terminates here.
    pub cable_ends: u8,
    /// Sum of point moments here (global), N m; at the tip, added to the tip moment.
    pub moment_nm: Vector3<T>,
    /// Sum of point forces and hung weights here (global), N. The closed-form internal force has
    /// them in each interval's distal force already; the internal-force-as-state equations apply them
    /// as jumps of `n` at the node.
    pub force_n: Vector3<T>,
}

/// The open interval between node `k` and node `k + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Interval<T> {
    pub s0_m: T,
    pub s1_m: T,
    pub steps: u16,
    pub section: u8,
    pub line_density_kg_per_m: T,
    /// Force distal of `s1` (gravity on the distal mass and distal point loads), excluding the tip load, N.
    pub distal_force_n: Vector3<T>,
}

/// The grid of one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan<T, const NODES: usize = MAX_NODES> {
    gravity_m_s2: Vector3<T>,
    pub(crate) nodes: Vec<Node<T>, NODES>,
    pub(crate) intervals: Vec<Interval<T>, NODES>,
    total_steps: u32,
}

impl<T: Scalar, const NODES: usize> Plan<T, NODES> {
    /// Builds the grid. The rod must already be validated.
    pub(crate) fn new(rod: &Rod<T>) -> Result<Self, ModelError> {
        let length = rod.length_m();
        let tol = length * T::lit(1e-6);

        // 1. Breakpoints.
        let mut points: Vec<T, MAX_NODES> = Vec::new();
        let mut push = |s: T| {
            points
                .push(s)
                .map_err(|_| ModelError::Capacity("breakpoints"))
        };
        push(T::zero())?;
        let mut end = T::zero();
        for section in &rod.sections {
            end += section.length_m;
            push(end)?;
        }
        // Without gravity the mass distribution plays no part: guide edges are not breakpoints.
        let weighted = rod.gravity_m_s2 != Vector3::zeros();
        for guide in &rod.guides {
            push(guide.s_m)?;
            if weighted && guide_is_segment(rod, guide) {
                let half = guide.thickness_m * T::lit(0.5);
                push(guide.s_m - half)?;
                push(guide.s_m + half)?;
            }
        }
        for load in &rod.loads {
            push(load.s_m)?;
        }
        for cable in &rod.cables {
            push(cable.end_m)?;
        }
        crate::scalar::insertion_sort(&mut points, |a, b| a < b);

        // 2. Nodes, merging points closer than `tol`; the first and last are pinned to 0 and L.
        let mut nodes: Vec<Node<T>, NODES> = Vec::new();
        for &s in &points {
            let s = s.max(T::zero()).min(length);
            let merged = nodes.last().is_some_and(|n| (s - n.s_m).abs() <= tol);
            if !merged {
                let node = Node {
                    s_m: s,
                    guide: NO_GUIDE,
                    cable_ends: 0,
                    moment_nm: Vector3::zeros(),
                    force_n: Vector3::zeros(),
                };
                nodes
                    .push(node)
                    .map_err(|_| ModelError::Capacity("nodes"))?;
            }
        }
        if let Some(last) = nodes.last_mut()
            && (last.s_m - length).abs() <= tol
        {
            last.s_m = length;
        }
        let at =
            |nodes: &Vec<Node<T>, NODES>, s: T| nodes.iter().position(|n| (n.s_m - s).abs() <= tol);
        for (g, guide) in rod.guides.iter().enumerate() {
            if let Some(i) = at(&nodes, guide.s_m)
                && let Some(node) = nodes.get_mut(i)
            {
                node.guide = u8::try_from(g).unwrap_or(NO_GUIDE);
            }
        }
        for (c, cable) in rod.cables.iter().enumerate() {
            if let Some(i) = at(&nodes, cable.end_m)
                && let Some(node) = nodes.get_mut(i)
            {
                node.cable_ends |= 1u8 << c;
            }
        }
        for load in &rod.loads {
            if let Some(i) = at(&nodes, load.s_m)
                && let Some(node) = nodes.get_mut(i)
                && i > 0
            {
                node.moment_nm += load.moment_nm;
                node.force_n += load.force_n + rod.gravity_m_s2 * load.mass_kg;
            }
        }

        // 3. Intervals: section, density and steps.
        let mut intervals: Vec<Interval<T>, NODES> = Vec::new();
        let mut total_steps: u32 = 0;
        for pair in nodes.windows(2) {
            let [a, b] = pair else { continue };
            let mid = (a.s_m + b.s_m) * T::lit(0.5);
            let (section, section_start) = section_at(rod, mid);
            let sec = rod
                .sections
                .get(section)
                .ok_or(ModelError::OutOfRange("section"))?;
            let h_target = sec.length_m / T::lit(f64::from(sec.steps));
            let ratio = ((b.s_m - a.s_m) / h_target - T::lit(1e-3)).ceil().to_f64();
            let steps = if ratio >= f64::from(u16::MAX) {
                u16::MAX
            } else if ratio >= 1.0 {
                ratio as u16
            } else {
                1
            };
            total_steps = total_steps.saturating_add(u32::from(steps));
            let interval = Interval {
                s0_m: a.s_m,
                s1_m: b.s_m,
                steps,
                section: u8::try_from(section).unwrap_or(u8::MAX),
                line_density_kg_per_m: line_density_kg_per_m(rod, section, section_start, mid),
                distal_force_n: Vector3::zeros(),
            };
            intervals
                .push(interval)
                .map_err(|_| ModelError::Capacity("intervals"))?;
        }

        // 4. Distal forces, from the tip down: N_{k-1} = N_k + g lambda_k (s_{k+1} - s_k) + loads at s_k.
        let g = rod.gravity_m_s2;
        let load_force = |s: T| {
            rod.loads
                .iter()
                .filter(|l| (l.s_m - s).abs() <= tol)
                .fold(Vector3::zeros(), |acc, l| acc + l.force_n + g * l.mass_kg)
        };
        let mut distal = load_force(length);
        for interval in intervals.iter_mut().rev() {
            interval.distal_force_n = distal;
            distal += g * (interval.line_density_kg_per_m * (interval.s1_m - interval.s0_m));
            if interval.s0_m > tol {
                distal += load_force(interval.s0_m);
            }
        }

        Ok(Self {
            gravity_m_s2: g,
            nodes,
            intervals,
            total_steps,
        })
    }

    /// RK4 steps in one sweep (each costs four evaluations of the right-hand side).
    pub fn total_steps(&self) -> u32 {
        self.total_steps
    }

    /// Number of intervals between breakpoints.
    pub fn interval_count(&self) -> usize {
        self.intervals.len()
    }

    /// Force the backbone carries at the base from everything but the tip load, N:
    /// the weight of all distal mass plus the point forces (the clamp reacts with its negative).
    pub fn base_force_n(&self) -> Vector3<T> {
        self.intervals.first().map_or(Vector3::zeros(), |i| {
            i.distal_force_n + self.gravity_m_s2 * (i.line_density_kg_per_m * (i.s1_m - i.s0_m))
        })
    }
}

/// The section containing `s` and the arc length where it starts.
pub(crate) fn section_at<T: Scalar>(rod: &Rod<T>, s: T) -> (usize, T) {
    let mut start = T::zero();
    let last = rod.sections.len().saturating_sub(1);
    for (i, section) in rod.sections.iter().enumerate() {
        if s < start + section.length_m || i == last {
            return (i, start);
        }
        start += section.length_m;
    }
    (last, start)
}
