//! Best-first branch and bound over an axis-aligned box (Josephson & Kahl 2008, section 4).
//!
//! The problem supplies a [`BoundingOracle`]: for a sub-box ([`Region`]) of the search space it returns
//! a lower bound of the objective over the admissible points of that region (a convex relaxation,
//! section 4.1), the relaxation's minimiser, and optionally a candidate solution whose cost is an
//! upper bound (the paper's local step, section 5). The box coordinates are the problem's choice —
//! the denominators of the fractions, line parameters (section 4.2), coordinates of a point, the
//! rotation vectors of the pose certificate ([`crate::pose::certificate`]) — and their number need
//! not be the number of views.
//!
//! The search always expands the open region with the least lower bound; its bound is the global
//! lower bound (every admissible point lies in an open region, in a pruned one whose bound is
//! recorded, or in a region proved empty). It stops when `(upper − lower) ≤ max_relative_gap · upper`
//! or after `max_nodes` bound computations, or when the call is stopped ([`crate::interrupt`], polled
//! before every split; [`BranchAndBoundResult::stopped`]). Splitting (section 4.2): the oracle picks the axis and
//! the position ([`BoundingOracle::split`]; by default the widest axis at the relaxed minimiser,
//! kept inside the middle half of the interval so that every split shrinks the region), or cuts
//! several axes at once ([`BoundingOracle::subdivide`]).
//!
//! A region may hand facts it proved down to the sub-regions it is split into
//! ([`BoundingOracle::Inherited`], [`BoundingOracle::bound_with`]): what holds on every admissible
//! point of a region holds on those of its sub-regions, and can tighten their bounds. The pose
//! certificate hands down depth bounds this way; the triangulation problems hand down nothing (`()`).

use crate::interrupt::{stop_reason, StopReason};
use smallvec::SmallVec;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// The coordinates of a corner: held inline up to four dimensions (the pose certificate's boxes of
/// rotations have three, and a search bounds thousands of them), on the heap beyond.
pub type Corner = SmallVec<[f64; 4]>;

/// The sub-regions a region is cut into: held inline up to eight (the octants of the pose
/// certificate's boxes), so that a split allocates nothing.
pub type SubRegions = SmallVec<[Region; 8]>;

/// An axis-aligned box `[lower, upper]` in `ℝᵈ`.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Lower corner.
    pub lower: Corner,
    /// Upper corner.
    pub upper: Corner,
}

impl Region {
    /// The box `[lower, upper]`.
    pub fn new(lower: impl Into<Corner>, upper: impl Into<Corner>) -> Region {
        Region {
            lower: lower.into(),
            upper: upper.into(),
        }
    }

    /// The dimension `d`.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// The width along axis `k`.
    pub fn width(&self, k: usize) -> f64 {
        self.upper[k] - self.lower[k]
    }

    /// The centre.
    pub fn centre(&self) -> Vec<f64> {
        self.lower.iter().zip(&self.upper).map(|(a, b)| 0.5 * (a + b)).collect()
    }

    /// The two halves of the box cut at `x_axis = at`.
    pub fn split(&self, axis: usize, at: f64) -> (Region, Region) {
        let mut left = self.clone();
        let mut right = self.clone();
        left.upper[axis] = at;
        right.lower[axis] = at;
        (left, right)
    }

    /// `at` moved into the middle half `[lo + w/4, hi − w/4]` of axis `k`.
    pub fn central(&self, k: usize, at: f64) -> f64 {
        let quarter = 0.25 * self.width(k);
        at.clamp(self.lower[k] + quarter, self.upper[k] - quarter)
    }
}

/// What the oracle learnt about one region.
#[derive(Debug, Clone)]
pub enum Bound<C> {
    /// The region holds no admissible point (proved): it is discarded.
    Empty {
        /// Conic-solver iterations spent.
        solver_iterations: usize,
    },
    /// A lower bound over the region's admissible points.
    Bounded {
        /// The bound (valid, not merely approximate: see [`crate::global::socp`]).
        lower: f64,
        /// The minimiser of the relaxation, a point of the region (a splitting hint), if the
        /// problem has one.
        relaxed_minimizer: Option<Vec<f64>>,
        /// A solution found from the relaxed minimiser, with its true cost (an upper bound).
        candidate: Option<(f64, C)>,
        /// Conic-solver iterations spent.
        solver_iterations: usize,
    },
    /// The bound could not be computed (a solver failure): the region keeps its parent's bound and
    /// is split further.
    Failed {
        /// Conic-solver iterations spent.
        solver_iterations: usize,
    },
}

/// The problem side of branch and bound.
pub trait BoundingOracle {
    /// A solution of the problem (e.g. a 3-D point).
    type Candidate: Clone;

    /// What the bound of a region hands down to the sub-regions it is split into: a fact proved for
    /// every admissible point of the region (so valid on each sub-region), e.g. the pose certificate's
    /// depth bounds. The root gets `Default::default()` (nothing proved yet); `()` for a problem that
    /// hands nothing down.
    type Inherited: Clone + Default;

    /// A lower bound of the objective over `region` (and a candidate when one is cheap to find).
    fn bound(&mut self, region: &Region) -> Bound<Self::Candidate>;

    /// [`Self::bound`] for a region whose parent handed down `inherited` (the default for the root),
    /// and what this region hands down to its sub-regions. The search passes each region exactly what its
    /// own parent handed down. Default: [`Self::bound`], handing `inherited` on unchanged.
    fn bound_with(
        &mut self,
        region: &Region,
        inherited: &Self::Inherited,
    ) -> (Bound<Self::Candidate>, Self::Inherited) {
        (self.bound(region), inherited.clone())
    }

    /// The search also stops when `upper − lower ≤ absolute_gap()` (for optima at the rounding
    /// level, where a relative gap cannot close). Default `0`.
    fn absolute_gap(&self) -> f64 {
        0.0
    }

    /// The axis to split and the position. Default: the widest axis, at the relaxed minimiser
    /// moved into the middle half of the interval (or the midpoint without a minimiser).
    fn split(&self, region: &Region, relaxed_minimizer: Option<&[f64]>) -> (usize, f64) {
        let axis = (0..region.dim())
            .max_by(|&a, &b| region.width(a).total_cmp(&region.width(b)))
            .unwrap_or(0);
        let at = relaxed_minimizer.map_or(0.5 * (region.lower[axis] + region.upper[axis]), |m| m[axis]);
        (axis, region.central(axis, at))
    }

    /// The sub-regions an open region is replaced by; together they must cover it. Default: the two
    /// halves of the cut [`Self::split`] picks. A problem may cut several axes at once: the pose
    /// certificate cuts a box of rotations into its eight octants, so that its boxes stay cubes and
    /// the work done on every split box is shared by eight children.
    fn subdivide(&self, region: &Region, relaxed_minimizer: Option<&[f64]>) -> SubRegions {
        let (axis, at) = self.split(region, relaxed_minimizer);
        let (left, right) = region.split(axis, at);
        SubRegions::from_iter([left, right])
    }
}

/// Options of [`branch_and_bound`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchAndBoundOptions {
    /// Stop when `upper − lower ≤ max_relative_gap · upper`. Default `1e-3`.
    pub max_relative_gap: f64,
    /// Stop after this many bound computations (the root included). Default 2000.
    pub max_nodes: usize,
    /// A bound known a priori for every point (e.g. `0` for a sum of squares); it replaces the
    /// bound of regions whose relaxation failed. Default `−∞`.
    pub trivial_lower_bound: f64,
}

impl Default for BranchAndBoundOptions {
    fn default() -> Self {
        BranchAndBoundOptions {
            max_relative_gap: 1e-3,
            max_nodes: 2000,
            trivial_lower_bound: f64::NEG_INFINITY,
        }
    }
}

/// What [`branch_and_bound`] found.
#[derive(Debug, Clone)]
pub struct BranchAndBoundResult<C> {
    /// The best solution and its cost (the incumbent passed in, or a better candidate).
    pub best: Option<(f64, C)>,
    /// A valid lower bound of the objective over the whole box, and the incumbent's cost (the
    /// optimum is at most that): `min(bound over the box, incumbent)`.
    pub lower_bound: f64,
    /// A valid lower bound over the admissible points of the box alone (`+∞` when every region
    /// was proved empty: the box holds no admissible point).
    pub box_lower_bound: f64,
    /// True when the gap closed.
    pub converged: bool,
    /// Why the search was stopped before the gap closed or `max_nodes` was reached, if it was.
    pub stopped: Option<StopReason>,
    /// Bound computations (root included).
    pub nodes: usize,
    /// Regions whose bound computation failed (counted; read by the unit tests only).
    #[allow(dead_code)]
    pub failed_nodes: usize,
    /// Conic-solver iterations, summed.
    pub solver_iterations: usize,
}

/// An open region: its box, its splitting hint, and what its bound hands down to its sub-regions.
struct Open<I> {
    region: Region,
    hint: Option<Vec<f64>>,
    handed_down: I,
}

/// An open region in the queue: its bound and the slot of its [`Open`] data (the heap moves these
/// sixteen bytes, not the regions).
struct Queued {
    lower: f64,
    slot: usize,
}

impl PartialEq for Queued {
    fn eq(&self, other: &Self) -> bool {
        self.lower.total_cmp(&other.lower) == Ordering::Equal
    }
}
impl Eq for Queued {}
impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Queued {
    // A max-heap on the reversed order: the least lower bound first.
    fn cmp(&self, other: &Self) -> Ordering {
        other.lower.total_cmp(&self.lower)
    }
}

/// The open regions, least bound first.
struct Queue<I> {
    heap: BinaryHeap<Queued>,
    /// The data of the queued regions, by slot; `None` in the free slots.
    slots: Vec<Option<Open<I>>>,
    free: Vec<usize>,
}

impl<I> Queue<I> {
    fn push(&mut self, lower: f64, open: Open<I>) {
        let slot = match self.free.pop() {
            Some(slot) => {
                self.slots[slot] = Some(open);
                slot
            }
            None => {
                self.slots.push(Some(open));
                self.slots.len() - 1
            }
        };
        self.heap.push(Queued { lower, slot });
    }

    /// The least bound in the queue.
    fn least(&self) -> Option<f64> {
        self.heap.peek().map(|top| top.lower)
    }

    /// Removes the region with the least bound.
    fn pop(&mut self) -> Option<(f64, Open<I>)> {
        let Queued { lower, slot } = self.heap.pop()?;
        self.free.push(slot);
        let open = self.slots[slot].take().expect("a queued slot holds its region");
        Some((lower, open))
    }
}

/// The state of one search.
struct Search<C, I> {
    queue: Queue<I>,
    best: Option<(f64, C)>,
    /// Least bound of the regions discarded because they could not improve the incumbent by more
    /// than the gap: they still count in the global lower bound.
    pruned_floor: f64,
    nodes: usize,
    failed_nodes: usize,
    solver_iterations: usize,
    gap: f64,
    absolute_gap: f64,
}

impl<C, I> Search<C, I> {
    fn closed(&self, upper: f64, lower: f64) -> bool {
        upper - lower <= (self.gap * upper.abs()).max(self.absolute_gap)
    }

    fn upper(&self) -> f64 {
        self.best.as_ref().map_or(f64::INFINITY, |b| b.0)
    }

    /// Bounds `region` (given what its parent handed down) and queues it unless it is empty or
    /// cannot improve on the incumbent.
    fn evaluate<O: BoundingOracle<Candidate = C, Inherited = I>>(
        &mut self,
        oracle: &mut O,
        region: Region,
        parent_lower: f64,
        inherited: &I,
    ) {
        self.nodes += 1;
        let (bound, handed_down) = oracle.bound_with(&region, inherited);
        let (lower, hint) = match bound {
            Bound::Empty { solver_iterations } => {
                self.solver_iterations += solver_iterations;
                return;
            }
            Bound::Failed { solver_iterations } => {
                self.solver_iterations += solver_iterations;
                self.failed_nodes += 1;
                (parent_lower, None)
            }
            Bound::Bounded {
                lower,
                relaxed_minimizer,
                candidate,
                solver_iterations,
            } => {
                self.solver_iterations += solver_iterations;
                if let Some((cost, c)) = candidate {
                    if cost < self.upper() {
                        self.best = Some((cost, c));
                    }
                }
                // The region lies inside its parent, whose bound holds for it too.
                (lower.max(parent_lower), relaxed_minimizer)
            }
        };
        let upper = self.upper();
        if lower >= upper {
            self.pruned_floor = self.pruned_floor.min(lower);
            return;
        }
        if self.closed(upper, lower) {
            self.pruned_floor = self.pruned_floor.min(lower);
            return;
        }
        self.queue.push(
            lower,
            Open {
                region,
                hint,
                handed_down,
            },
        );
    }

    fn finish(self, lower_bound: f64, converged: bool, stopped: Option<StopReason>) -> BranchAndBoundResult<C> {
        let open = self.queue.least().unwrap_or(f64::INFINITY);
        BranchAndBoundResult {
            box_lower_bound: open.min(self.pruned_floor),
            best: self.best,
            lower_bound,
            converged,
            stopped,
            nodes: self.nodes,
            failed_nodes: self.failed_nodes,
            solver_iterations: self.solver_iterations,
        }
    }
}

/// Minimises over `root` by best-first branch and bound, starting from the optional `incumbent`.
pub fn branch_and_bound<O: BoundingOracle>(
    oracle: &mut O,
    root: Region,
    incumbent: Option<(f64, O::Candidate)>,
    opts: &BranchAndBoundOptions,
) -> BranchAndBoundResult<O::Candidate> {
    let mut search = Search {
        queue: Queue {
            heap: BinaryHeap::new(),
            slots: vec![],
            free: vec![],
        },
        best: incumbent,
        pruned_floor: f64::INFINITY,
        nodes: 0,
        failed_nodes: 0,
        solver_iterations: 0,
        gap: opts.max_relative_gap,
        absolute_gap: oracle.absolute_gap(),
    };
    search.evaluate(oracle, root, opts.trivial_lower_bound, &O::Inherited::default());
    loop {
        let upper = search.upper();
        // Drop regions the incumbent has overtaken since they were queued.
        while let Some(least) = search.queue.least().filter(|&least| least >= upper) {
            search.pruned_floor = search.pruned_floor.min(least);
            search.queue.pop();
        }
        let open_lower = search.queue.least().unwrap_or(f64::INFINITY);
        let lower = open_lower.min(search.pruned_floor).min(upper);
        if search.queue.heap.is_empty() || search.closed(upper, lower) {
            return search.finish(lower, true, None);
        }
        if search.nodes >= opts.max_nodes {
            return search.finish(lower, false, None);
        }
        if let Some(reason) = stop_reason() {
            return search.finish(lower, false, Some(reason));
        }
        let (open_lower, open) = search.queue.pop().expect("the queue is not empty");
        for child in oracle.subdivide(&open.region, open.hint.as_deref()) {
            search.evaluate(oracle, child, open_lower, &open.handed_down);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f(x) = Σ (x_k² − 1)² + τ_k x_k` with `τ = (0.1, 0.2, 0.3)`: eight local minima near the sign
    /// patterns of ±1, the global one near `(−1, −1, −1)`; bounded by interval arithmetic.
    struct DoubleWell {
        calls: usize,
    }

    const TILT: [f64; 3] = [0.1, 0.2, 0.3];

    fn double_well(x: &[f64]) -> f64 {
        x.iter().zip(TILT).map(|(v, t)| (v * v - 1.0).powi(2) + t * v).sum()
    }

    impl BoundingOracle for DoubleWell {
        type Candidate = Vec<f64>;
        type Inherited = ();
        fn bound(&mut self, region: &Region) -> Bound<Vec<f64>> {
            self.calls += 1;
            let mut lower = 0.0;
            for (k, tilt) in TILT.iter().enumerate().take(region.dim()) {
                let (a, b) = (region.lower[k], region.upper[k]);
                let sq_lo = if a <= 0.0 && b >= 0.0 { 0.0 } else { (a * a).min(b * b) };
                let sq_hi = (a * a).max(b * b);
                let (g_lo, g_hi) = (sq_lo - 1.0, sq_hi - 1.0);
                lower += if g_lo <= 0.0 && g_hi >= 0.0 {
                    0.0
                } else {
                    (g_lo * g_lo).min(g_hi * g_hi)
                };
                lower += tilt * a;
            }
            let centre = region.centre();
            let cost = double_well(&centre);
            Bound::Bounded {
                lower,
                relaxed_minimizer: Some(centre.clone()),
                candidate: Some((cost, centre)),
                solver_iterations: 1,
            }
        }
    }

    #[test]
    fn finds_the_global_minimum_of_a_tilted_double_well_with_a_valid_bound() {
        let mut oracle = DoubleWell { calls: 0 };
        let root = Region::new(vec![-2.0, -2.0, -2.0], vec![2.5, 2.5, 2.5]);
        let opts = BranchAndBoundOptions {
            max_relative_gap: 1e-3,
            max_nodes: 200_000,
            ..Default::default()
        };
        let result = branch_and_bound(&mut oracle, root, None, &opts);
        let (cost, x) = result.best.clone().unwrap();
        assert!(result.converged, "{} nodes", result.nodes);
        let truth = double_well_minimum(TILT.len());
        assert!(result.lower_bound <= truth + 1e-12, "{} > {truth}", result.lower_bound);
        assert!(cost >= truth && cost - result.lower_bound <= 1e-3 * cost.abs() + 1e-12);
        assert!(x.iter().all(|v| (v + 1.0).abs() < 0.1), "{x:?}");
        assert_eq!(result.nodes, oracle.calls);
    }

    #[test]
    fn node_cap_returns_an_honest_bound() {
        let mut oracle = DoubleWell { calls: 0 };
        let root = Region::new(vec![-2.0; 3], vec![2.5; 3]);
        let opts = BranchAndBoundOptions {
            max_relative_gap: 1e-9,
            max_nodes: 15,
            ..Default::default()
        };
        let result = branch_and_bound(&mut oracle, root, None, &opts);
        assert!(!result.converged && result.nodes <= 16);
        assert!(result.lower_bound <= result.best.unwrap().0);
    }

    #[test]
    fn a_stop_ends_the_search_with_an_honest_bound() {
        use crate::interrupt::{with_stop, Stop};
        use std::sync::Arc;
        let mut oracle = DoubleWell { calls: 0 };
        let root = Region::new(vec![-2.0; 3], vec![2.5; 3]);
        let opts = BranchAndBoundOptions {
            max_relative_gap: 1e-9,
            max_nodes: 200_000,
            ..Default::default()
        };
        let stop = Arc::new(Stop::new());
        stop.request();
        let result = with_stop(stop, || branch_and_bound(&mut oracle, root, None, &opts));
        // Only the root is bounded: the stop is polled before the first split.
        assert_eq!(result.nodes, 1);
        assert_eq!(result.stopped, Some(StopReason::Requested));
        assert!(!result.converged);
        assert!(result.lower_bound <= result.best.unwrap().0);
    }

    /// The double well, each region handing down itself: the search must give every region exactly
    /// what its own parent handed down (the root the default), never a sibling's or a grandparent's.
    struct Lineage {
        inner: DoubleWell,
        /// Regions that did not receive their parent's hand-down, and regions checked.
        wrong: Vec<String>,
        checked: usize,
    }

    /// Whether `child` is one of the two halves of `parent`: equal on every axis but one, where it
    /// keeps one end of the parent's interval and cuts the other strictly inside.
    fn is_half_of(child: &Region, parent: &Region) -> bool {
        let differing: Vec<usize> = (0..parent.dim())
            .filter(|&k| child.lower[k] != parent.lower[k] || child.upper[k] != parent.upper[k])
            .collect();
        let [k] = differing[..] else {
            return false;
        };
        let inside = |v: f64| v > parent.lower[k] && v < parent.upper[k];
        (child.lower[k] == parent.lower[k] && inside(child.upper[k]))
            || (child.upper[k] == parent.upper[k] && inside(child.lower[k]))
    }

    impl BoundingOracle for Lineage {
        type Candidate = Vec<f64>;
        type Inherited = Option<Region>;
        fn bound(&mut self, region: &Region) -> Bound<Vec<f64>> {
            self.inner.bound(region)
        }
        fn bound_with(&mut self, region: &Region, inherited: &Option<Region>) -> (Bound<Vec<f64>>, Option<Region>) {
            self.checked += 1;
            let root = self.checked == 1;
            let right = match inherited {
                None => root,
                Some(parent) => !root && is_half_of(region, parent),
            };
            if !right {
                self.wrong.push(format!("{region:?} received {inherited:?}"));
            }
            (self.inner.bound(region), Some(region.clone()))
        }
    }

    /// What a region hands down reaches exactly its halves (a hand-down is a fact proved on the
    /// parent: on a sibling or a cousin it need not hold).
    #[test]
    fn each_region_receives_what_its_parent_handed_down() {
        let mut oracle = Lineage {
            inner: DoubleWell { calls: 0 },
            wrong: vec![],
            checked: 0,
        };
        let root = Region::new(vec![-2.0; 3], vec![2.5; 3]);
        let opts = BranchAndBoundOptions {
            max_relative_gap: 1e-6,
            max_nodes: 3000,
            ..Default::default()
        };
        let result = branch_and_bound(&mut oracle, root, None, &opts);
        assert_eq!(oracle.checked, result.nodes);
        assert!(result.nodes > 100, "only {} regions", result.nodes);
        assert!(
            oracle.wrong.is_empty(),
            "{} of {}: {:?}",
            oracle.wrong.len(),
            oracle.checked,
            &oracle.wrong[..3.min(oracle.wrong.len())]
        );
    }

    /// The minimum of the tilted double well: each `x_k` solves `4x(x²−1) + τ_k = 0` near −1, by
    /// Newton's method (an oracle of its own: no branch and bound involved).
    fn double_well_minimum(dim: usize) -> f64 {
        TILT[..dim]
            .iter()
            .map(|&t| {
                let mut v: f64 = -1.0;
                for _ in 0..50 {
                    v -= (4.0 * v * (v * v - 1.0) + t) / (12.0 * v * v - 4.0);
                }
                (v * v - 1.0).powi(2) + t * v
            })
            .sum()
    }

    /// The double well whose oracle fails (no bound, no candidate) on every region that contains the
    /// global minimiser's neighbourhood (near `(−1, −1)`) and is wider than `fail_above`, and on every
    /// third call.
    struct Failing {
        inner: DoubleWell,
        fail_above: f64,
        calls: usize,
    }

    impl BoundingOracle for Failing {
        type Candidate = Vec<f64>;
        type Inherited = ();
        fn bound(&mut self, region: &Region) -> Bound<Vec<f64>> {
            self.calls += 1;
            let holds_minimiser = (0..region.dim()).all(|k| region.lower[k] <= -0.95 && region.upper[k] >= -1.05);
            let wide = (0..region.dim()).any(|k| region.width(k) > self.fail_above);
            if (holds_minimiser && wide) || self.calls % 3 == 0 {
                return Bound::Failed { solver_iterations: 1 };
            }
            self.inner.bound(region)
        }
    }

    /// Failure injection: regions whose bound could not be computed keep their parent's bound and
    /// are split further, so the global bound stays at or below the known minimum and the search
    /// still finds it. Dropping failed regions (as if empty) loses the minimiser's region: the bound
    /// then rises above the minimum.
    #[test]
    fn failed_regions_keep_their_parents_bound() {
        let truth = double_well_minimum(2);
        for (fail_above, max_nodes) in [(1.0, 200_000), (0.3, 200_000), (0.3, 40), (0.05, 3000)] {
            let mut oracle = Failing {
                inner: DoubleWell { calls: 0 },
                fail_above,
                calls: 0,
            };
            let root = Region::new(vec![-2.0; 2], vec![2.5; 2]);
            let opts = BranchAndBoundOptions {
                max_relative_gap: 1e-3,
                max_nodes,
                trivial_lower_bound: f64::NEG_INFINITY,
            };
            // The incumbent of a local search that stopped in the wrong well, near (1, 1).
            let incumbent = vec![0.97, 0.95];
            let result = branch_and_bound(&mut oracle, root, Some((double_well(&incumbent), incumbent)), &opts);
            assert!(result.failed_nodes > 0);
            assert!(
                result.lower_bound <= truth && result.box_lower_bound <= truth,
                "fail above {fail_above}, {max_nodes} nodes: bound {} / {} above the minimum {truth}",
                result.lower_bound,
                result.box_lower_bound
            );
            if result.converged {
                let (cost, _) = result.best.unwrap();
                assert!(cost - truth <= 1e-3 * cost.abs() + 1e-12, "{cost} vs {truth}");
            }
        }
    }

    /// The double well bounded exactly on each region's centre cell but without candidates: the
    /// incumbent passed in is all the search knows as an upper bound.
    struct NoCandidates(DoubleWell);

    impl BoundingOracle for NoCandidates {
        type Candidate = Vec<f64>;
        type Inherited = ();
        fn bound(&mut self, region: &Region) -> Bound<Vec<f64>> {
            match self.0.bound(region) {
                Bound::Bounded {
                    lower,
                    relaxed_minimizer,
                    solver_iterations,
                    ..
                } => Bound::Bounded {
                    lower,
                    relaxed_minimizer,
                    candidate: None,
                    solver_iterations,
                },
                other => other,
            }
        }
    }

    /// The floor of regions discarded within the gap: with an incumbent a little above the minimum
    /// (inside the gap tolerance) and no better candidate, the region of the minimiser is discarded
    /// because it cannot improve the incumbent by more than the gap, not because its bound is high:
    /// its bound (below the minimum) must stay in the result. Forgetting it reports the incumbent's
    /// cost, above the minimum, as the bound.
    #[test]
    fn regions_discarded_within_the_gap_keep_their_bound_in_the_result() {
        let truth = double_well_minimum(2);
        for (excess, gap) in [(5e-4, 1e-3), (9e-4, 1e-3), (1e-2, 2e-2)] {
            let incumbent_cost = truth + excess * truth.abs();
            let mut oracle = NoCandidates(DoubleWell { calls: 0 });
            let root = Region::new(vec![-2.0; 2], vec![2.5; 2]);
            let opts = BranchAndBoundOptions {
                max_relative_gap: gap,
                max_nodes: 200_000,
                trivial_lower_bound: f64::NEG_INFINITY,
            };
            let result = branch_and_bound(&mut oracle, root, Some((incumbent_cost, vec![-1.0; 2])), &opts);
            assert!(result.converged);
            assert!(
                result.lower_bound <= truth && result.box_lower_bound <= truth,
                "excess {excess}: bound {} / {} above the minimum {truth}",
                result.lower_bound,
                result.box_lower_bound
            );
            // The true gap, recomputed from the incumbent and the bound, closed.
            assert!(incumbent_cost - result.lower_bound <= gap * incumbent_cost.abs() * (1.0 + 1e-12));
        }
    }
}
