//! Step 3 of [`super`]'s module docs: the rotation search, a [`BoundingOracle`] of the shared branch
//! and bound over boxes of rotation vectors; what each box hands down to its octants (a tighter
//! minorant, or a smaller ellipsoid of translations); and the boxes inside the whitened ball, which
//! step 4 bounds.

use super::box_bound::{BoxBound, Cell, Ellipsoid, TranslationEllipsoid};
use super::lens::Slack;
use super::local_bound::{LocalModel, Whitening};
use super::minorant::{largest_eigenvalue, minkowski, ScaledMinorant};
use super::problem::{Problem, SearchStart};
use super::HALF_COST_FLOOR;
use crate::geometry::quaternion::exp_so3;
use crate::global::branch_and_bound::{
    branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Corner, Region, SubRegions,
};
use crate::interrupt::{stop_reason, StopReason};
use crate::pose::reprojection::Pose;
use nalgebra::{Matrix3, Vector3};
use std::rc::Rc;

/// A rotation cell that the search kept: the box `|ω − centre| ≤ half` (per axis) of rotation
/// vectors (`R = exp(ω) R̂`), and the ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` (`C`, `t*` the
/// minorant's Hessian and minimiser at the box's centre, for the box's depth bounds) that holds the
/// translation of every pose of the sublevel set whose rotation lies in the box.
/// A record of the test hook `testing::rotation_search` (hidden from the docs).
#[doc(hidden)]
#[derive(Debug, Clone)]
pub struct KeptCell {
    pub centre: Vector3<f64>,
    /// The half-widths of the box along the three axes.
    pub half: Vector3<f64>,
    pub t_star: Vector3<f64>,
    pub c: Matrix3<f64>,
    pub slack: f64,
    /// Whether the cell lies inside the whitened ball of the target radius (else it was left
    /// unsplit at the least half-width).
    pub inside_ball: bool,
    /// The depth bounds `Dᵢ` of the cell's minorant (handed down by its ancestors): the search
    /// claims `‖R Xᵢ + t‖ ≤ Dᵢ` for every pose of the sublevel set with its rotation in the box.
    pub depths: Vec<f64>,
    /// Whether the ellipsoid comes from a quadratic with the segments' terms (with depth bounds:
    /// where it reaches less far than the points' alone).
    pub with_segments: bool,
    /// For a cell inside the ball: the largest whitened length `‖(0, t − t*)‖_W` over its
    /// ellipsoid (`W = JᵀJ` at the centre), a part of the radius the search claims for the cell.
    pub extent: Option<f64>,
}

/// What the test hook [`super::testing::rotation_search`] records: the cells kept, the cells pruned, and the
/// half-width at which cells stop being split.
pub(super) struct RecordedCells {
    pub(super) min_half: f64,
    pub(super) cells: Vec<KeptCell>,
    pub(super) pruned: usize,
    pub(super) behind: Vec<KeptCell>,
}

impl RecordedCells {
    /// Nothing recorded yet; cells stop being split at `min_half`.
    pub(super) fn new(min_half: f64) -> Self {
        RecordedCells {
            min_half,
            cells: vec![],
            pruned: 0,
            behind: vec![],
        }
    }
}

/// Step 4's bound for the cells inside the ball: the local bound over the ball of the largest cell
/// radius met so far (it holds the cell, so the bound is valid for it), recomputed only when a cell
/// reaches farther; over the ball of the target radius where that cannot be computed.
pub(super) struct BallBound<'m> {
    pub(super) model: &'m LocalModel<'m>,
    /// The radius and raw bound last computed (`radius` 0 before the first cell).
    pub(super) radius: f64,
    pub(super) bound: f64,
    /// The raw bound over the ball of the target radius (every cell inside the ball lies in it).
    pub(super) at_target: f64,
}

impl BallBound<'_> {
    /// A valid lower bound of `f` over the whitened ball of `radius` (at most the target). Through a
    /// lens, the target's (it already closes the gap; a smaller ball's would cost its enclosures of
    /// the distortion's variation again).
    pub(super) fn at(&mut self, radius: f64) -> f64 {
        if self.model.lens.is_some() {
            return self.at_target;
        }
        if radius > self.radius {
            match self.model.raw_bound(radius, None) {
                Some(bound) => (self.radius, self.bound) = (radius, bound),
                None => return self.at_target,
            }
        }
        self.bound
    }
}

/// What becomes of a cell inside the whitened ball of the target radius.
pub(super) enum InsideBall<'m> {
    /// The certificate: the cell's bound is step 4's over the ball ([`BallBound`]).
    Bound(BallBound<'m>),
    /// The test hook: the cell is recorded and closed at the level `f̂` (no bound is claimed, and the
    /// hook reports none). So are cells split down to the hook's `min_half`.
    Record(&'m mut RecordedCells),
}

/// Steps 1-3 of the module documentation as a [`BoundingOracle`] of the shared branch and bound,
/// over boxes of rotation vectors `ω` (`R = exp(ω) R̂`) inside `[−π, π]³`. The incumbent is the local
/// answer `(R̂, t̂)` of cost `f̂`; there are no other candidates.
///
/// The bound of a box with half-diagonal `θ`, centre rotation `R_c` and minorant `Q` at `R_c` (for
/// the box's depth bounds `Dᵢ`, valid where `‖xᵢ‖ ≤ Dᵢ`, i.e. on `S`): a pose of `S` in the box has
/// `√(2f) ≥ √Q_{R}(t) ≥ √q_min − θ η` (Minkowski, `q_min = min_t Q`), so `f ≥ ½ (√q_min − θ η)₊²` on
/// the poses of `S` in the box, and every other pose has `f > f̂`. That bound is handed to the search
/// unclamped: a box with bound `≥ f̂` holds no pose of `S` and is pruned, and the least bound over
/// the leaves (at most `f̂`, the cost of the box holding the answer) is the certificate's raw bound.
/// A box where some point is behind the camera for every `t` of the translation ellipsoid
/// `Q(t) ≤ (√(2f̂) + θ η)²` (which holds the translation of every pose of `S` in the box) is empty of
/// `S`; so is a box wholly outside the ball `‖ω‖ ≤ π`, whose rotations are met elsewhere. A box inside
/// the whitened ball of radius `target` is bounded by step 4 as well ([`InsideBall`]).
///
/// What a box hands down to its octants ([`BoundingOracle::Inherited`]) are its depth bounds: the
/// largest distance each point reaches over its poses of `S`,
/// `‖R X + t + e‖ ≤ ‖R_c X + t* + e‖ + θ ‖X‖ + ‖t − t*‖` with `t` in the ellipsoid (`e` the offset of the
/// point's camera, zero for one camera: [`Problem::offsets`]), capped by its own `Dᵢ`.
/// They hold on every pose of `S` in the box, so in each octant, and tighten the octants' minorants
/// ([`ScaledMinorant`]).
pub(super) struct RotationSearch<'a, 'c> {
    pub(super) problem: &'a Problem<'c>,
    pub(super) whitening: &'a Whitening,
    pub(super) pose: &'a Pose,
    pub(super) f_hat: f64,
    pub(super) target: f64,
    pub(super) max_relative_gap: f64,
    /// The slack of a lens's surrogate (`lens`): the boxes are bounded, and `f_hat` is a level, of
    /// the surrogate; step 4's bounds, of the cost, enter through [`Slack::to_surrogate`].
    pub(super) slack: Slack,
    pub(super) inside_ball: InsideBall<'a>,
    /// Whether the box bound with segments tries the rotation's linearisation
    /// ([`Problem::linear_lines_bound`]) where its Minkowski bound falls short. Not through a lens:
    /// there it cost more than it saved on every 50-point + 50-segment row of `bench/profile_pose.py`
    /// (the strong OPENCV lens at f = 800 / 4000 / 15000 px: median 25 / 5.4 / 10 ms → 31 / 8.4 /
    /// 20 ms for about the same nodes), where without a lens it halves the time at f = 250-800 px.
    pub(super) linearise_lines: bool,
    /// The largest whitened radius `‖(ω, t − t̂)‖_W` of the boxes found inside the ball.
    pub(super) radius: f64,
}

impl BoundingOracle for RotationSearch<'_, '_> {
    type Candidate = ();
    /// The minorant for the depth bounds of the box's poses of `S`, or the ball of their translations
    /// (`None`: the root's).
    type Inherited = Option<HandedDown>;

    fn bound(&mut self, region: &Region) -> Bound<()> {
        self.bound_with(region, &None).0
    }

    fn absolute_gap(&self) -> f64 {
        self.max_relative_gap * HALF_COST_FLOOR
    }

    /// The eight octants of the box (every axis cut at its midpoint): boxes stay cubes.
    fn subdivide(&self, region: &Region, _relaxed_minimizer: Option<&[f64]>) -> SubRegions {
        let (lo, hi) = (&region.lower, &region.upper);
        let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
        // Corners built in place (a clone of the parent's would cost more than the bound of a box).
        let corner = |pick: [f64; 3]| Corner::from_buf_and_len([pick[0], pick[1], pick[2], 0.0], 3);
        (0..8)
            .map(|octant: usize| {
                let upper_half = |k: usize| octant >> k & 1 == 1;
                let lower = std::array::from_fn(|k| if upper_half(k) { mid[k] } else { lo[k] });
                let upper = std::array::from_fn(|k| if upper_half(k) { hi[k] } else { mid[k] });
                Region {
                    lower: corner(lower),
                    upper: corner(upper),
                }
            })
            .collect()
    }

    fn bound_with(&mut self, region: &Region, inherited: &Option<HandedDown>) -> (Bound<()>, Option<HandedDown>) {
        let cell = Cell::of(region);
        // The box's nearest point to the origin: boxes wholly outside the ball ‖ω‖ ≤ π repeat rotations.
        let nearest = cell.centre.zip_map(&cell.half, |c, h| (c.abs() - h).max(0.0)).norm();
        if nearest > std::f64::consts::PI {
            return (Bound::Empty { solver_iterations: 0 }, None);
        }
        let r_c = exp_so3(&cell.centre) * self.pose.rotation;
        match (&self.problem.start, inherited) {
            (SearchStart::DepthBounds(_), Some(HandedDown::Minorant(scaled))) => self.points_box(&cell, &r_c, scaled),
            (SearchStart::DepthBounds(root), _) => {
                let root = ScaledMinorant {
                    minorant: Rc::clone(root),
                    scale: 1.0,
                };
                self.points_box(&cell, &r_c, &root)
            }
            (SearchStart::ObjectDistance { pivot, distance }, inherited) => {
                // The translations of the box's poses of S: t = P − R c with ‖P‖ ≤ distance, and those
                // of the parent's ball; the smaller ball is kept.
                let from_pivot =
                    TranslationEllipsoid::round(-(r_c * pivot), distance + cell.half.norm() * pivot.norm());
                let ball = match inherited {
                    Some(HandedDown::Translations(ball)) if ball.shape.trace() <= from_pivot.shape.trace() => {
                        ball.clone()
                    }
                    _ => from_pivot,
                };
                self.ball_box(&cell, &r_c, ball)
            }
        }
    }
}

/// What a box hands down to its octants ([`BoundingOracle::Inherited`]).
#[derive(Clone)]
pub(super) enum HandedDown {
    /// The minorant for the depth bounds of the box's poses of `S` ([`SearchStart::DepthBounds`]).
    Minorant(ScaledMinorant),
    /// An ellipsoid that holds the translations of the box's poses of `S` ([`SearchStart::ObjectDistance`]).
    Translations(TranslationEllipsoid),
}

#[cfg(test)]
impl HandedDown {
    /// The minorant handed down (the unit tests of the search with depth bounds).
    pub(super) fn minorant(&self) -> &ScaledMinorant {
        match self {
            HandedDown::Minorant(scaled) => scaled,
            HandedDown::Translations(_) => panic!("translations, not a minorant"),
        }
    }
}

/// A box's bound, with no candidate.
pub(super) fn bounded(lower: f64) -> Bound<()> {
    Bound::Bounded {
        lower,
        relaxed_minimizer: None,
        candidate: None,
        solver_iterations: 0,
    }
}

impl RotationSearch<'_, '_> {
    /// The box's bound `lower` when it proves the box empty of `S` (`lower ≥ f̂`): the search prunes it.
    pub(super) fn pruned(&mut self, lower: f64) -> Option<Bound<()>> {
        if lower < self.f_hat {
            return None;
        }
        if let InsideBall::Record(r) = &mut self.inside_ball {
            r.pruned += 1;
        }
        Some(bounded(lower))
    }

    /// The bound of a box that is not split further: one inside the whitened ball of the target
    /// radius (step 4's bound joins `lower`), or, for the test hook, one at its least half-width.
    /// The box's poses of `S` have their translations within `extent` (in the local metric) of `t_star`
    /// (computed only for boxes near the answer). `None`: the box is split.
    pub(super) fn settled(
        &mut self,
        cell: &Cell,
        lower: f64,
        t_star: &Vector3<f64>,
        extent: impl FnOnce() -> Option<f64>,
        kept: impl Fn(bool) -> KeptCell,
    ) -> Option<Bound<()>> {
        // Whitened radius of the box: centre, rotation spread and translation ellipsoid (triangle
        // inequality over the three parts of the step).
        if cell.centre.norm() + cell.half.norm() <= 1.0 {
            if let Some(extent) = extent() {
                let radius = self.whitening.length(&cell.centre, &(t_star - self.pose.translation))
                    + self.whitening.box_spread(&cell.half)
                    + extent;
                if radius <= self.target {
                    self.radius = self.radius.max(radius);
                    let lower = match &mut self.inside_ball {
                        InsideBall::Bound(ball) => lower.max(self.slack.to_surrogate(ball.at(radius))),
                        InsideBall::Record(r) => {
                            r.cells.push(KeptCell {
                                extent: Some(extent),
                                ..kept(true)
                            });
                            self.f_hat
                        }
                    };
                    return Some(bounded(lower));
                }
            }
        }
        if let InsideBall::Record(r) = &mut self.inside_ball {
            if cell.half.max() <= r.min_half {
                r.cells.push(kept(false));
                return Some(bounded(self.f_hat));
            }
        }
        None
    }

    /// The bound of a box with step 1's depth bounds ([`SearchStart::DepthBounds`]; [`RotationSearch`]).
    pub(super) fn points_box(
        &mut self,
        cell: &Cell,
        r_c: &Matrix3<f64>,
        scaled: &ScaledMinorant,
    ) -> (Bound<()>, Option<HandedDown>) {
        let problem = self.problem;
        let (minorant, scale) = (&scaled.minorant, scaled.scale);
        let theta = cell.half.norm();
        let Some((t_star, q_min, eta)) = scaled.at(r_c) else {
            return (
                Bound::Failed { solver_iterations: 0 },
                Some(HandedDown::Minorant(scaled.clone())),
            );
        };
        // The Minkowski bound, and the linearised one where the first falls short of f̂ and the
        // second could close the box.
        let by_minkowski = minkowski(q_min, theta * eta);
        let lower = if by_minkowski < self.f_hat {
            let wanted = self.f_hat * (1.0 - self.max_relative_gap);
            by_minkowski.max(scaled.linear_bound(r_c, theta, q_min, wanted))
        } else {
            by_minkowski
        };
        // The ellipsoid Q(t) ≤ β² holds the translations of the box's poses of S (slack ≥ 0 where
        // lower < f̂, up to rounding): they are within `spread` of t*.
        let beta = (2.0 * self.f_hat).sqrt() + theta * eta;
        let slack = (beta * beta - q_min).max(0.0);
        let slack_per_scale = slack / scale;
        let spread = (slack_per_scale * minorant.c_inv_max).max(0.0).sqrt();
        // The segments' residuals added to the minorant, where the points' alone fall short.
        let with_lines = if lower < self.f_hat && problem.box_segments > 0 && !problem.lines.is_empty() {
            let wanted = self
                .linearise_lines
                .then_some(self.f_hat * (1.0 - self.max_relative_gap));
            problem.lines_bound(
                scaled,
                r_c,
                theta,
                (&t_star, q_min),
                spread,
                problem.box_segments,
                wanted,
            )
        } else {
            None
        };
        let lower = with_lines.as_ref().map_or(lower, |l| lower.max(l.lower));
        // The translations of the box's poses of S lie in the points' ellipsoid and in the one with
        // the segments: the one with the lesser reach is kept.
        let points_ellipsoid = Ellipsoid {
            centre: t_star,
            c: minorant.c * scale,
            slack,
            spread,
            with_segments: false,
        };
        let ellipsoid = match &with_lines {
            Some(l) => match l.ellipsoid(self.f_hat, theta) {
                (slack, spread) if spread < points_ellipsoid.spread => Ellipsoid {
                    centre: l.t_star,
                    c: l.c,
                    slack,
                    spread,
                    with_segments: true,
                },
                _ => points_ellipsoid,
            },
            None => points_ellipsoid,
        };
        if !lower.is_finite() {
            return (
                Bound::Failed { solver_iterations: 0 },
                Some(HandedDown::Minorant(scaled.clone())),
            );
        }
        if let Some(pruned) = self.pruned(lower) {
            return (pruned, None);
        }
        let kept = |inside_ball: bool, ellipsoid: &Ellipsoid| KeptCell {
            centre: cell.centre,
            half: cell.half,
            t_star: ellipsoid.centre,
            c: ellipsoid.c,
            slack: ellipsoid.slack,
            inside_ball,
            depths: scaled.depths().collect(),
            with_segments: ellipsoid.with_segments,
            extent: None,
        };
        // Cheirality: a point behind the camera for every rotation of the box and t of the ellipsoid.
        // (Only a point with `b · (R_c x + t* + e) ≤ −θ ‖x‖` can be: the ellipsoid's term is not negative.)
        let (axis, reach, largest) = problem.bearing_cone;
        let surely_in_front = axis.dot(&t_star) - reach * t_star.norm() > largest;
        let behind = !surely_in_front
            && (problem
                .corr
                .points3d
                .iter()
                .zip(&problem.bearings)
                .zip(&problem.offsets))
            .zip(problem.norms.iter().zip(&minorant.bearing_spread))
            .any(|(((x, b), e), (norm, spread))| {
                let depth = b.dot(&(r_c * x + t_star + e));
                depth <= -theta * norm && depth + (slack_per_scale * spread).max(0.0).sqrt() <= -theta * norm
            });
        if behind {
            if let InsideBall::Record(r) = &mut self.inside_ball {
                r.pruned += 1;
                // The test above is on the points' ellipsoid.
                r.behind.push(kept(false, &points_ellipsoid));
            }
            return (Bound::Empty { solver_iterations: 0 }, None);
        }
        let extent = || {
            if ellipsoid.with_segments {
                self.whitening.ellipsoid_factor(&ellipsoid.c)
            } else {
                // The points' C is the minorant's times `scale`: its factor once per minorant.
                let factor = minorant
                    .extent
                    .get_or_init(|| self.whitening.ellipsoid_factor(&minorant.c));
                factor.map(|lambda| lambda / scale)
            }
            .map(|lambda| (ellipsoid.slack * lambda).max(0.0).sqrt())
        };
        if let Some(bound) = self.settled(cell, lower, &ellipsoid.centre, extent, |inside| {
            kept(inside, &ellipsoid)
        }) {
            return (bound, None);
        }
        // The depth bounds the octants inherit, and the minorant for them (else the octants share
        // this box's).
        let reach = (problem.corr.points3d.iter().zip(&problem.norms).zip(&problem.offsets))
            .map(|((x, norm), e)| (r_c * x + ellipsoid.centre + e).norm() + theta * norm + ellipsoid.spread);
        let handed_down = scaled.tightened(|depths| problem.minorant(depths), reach, r_c, 0.5 * theta);
        (bounded(lower), Some(HandedDown::Minorant(handed_down)))
    }

    /// The bound of a box without depth bounds ([`SearchStart::ObjectDistance`]) whose poses of `S` have their
    /// translations in `ball`: `Q` the minorant at `R_c` ([`Problem::ball_bound`]), a pose of `S`
    /// in the box has `√(2f) ≥ √q_min − θ η` (Minkowski, as with depth bounds), and its translation
    /// lies in the ellipsoid `Q(t) ≤ (√(2f̂) + θ η)²`, whose bounding ball the octants inherit where it
    /// is smaller than `ball`.
    pub(super) fn ball_box(
        &mut self,
        cell: &Cell,
        r_c: &Matrix3<f64>,
        ball: TranslationEllipsoid,
    ) -> (Bound<()>, Option<HandedDown>) {
        let theta = cell.half.norm();
        let segments = self.problem.segments_in(cell);
        let Some(BoxBound {
            lower,
            t_star,
            c,
            c_inv,
            slack,
            depths,
            ..
        }) = self.problem.ball_bound(segments, r_c, theta, &ball, self.f_hat)
        else {
            // The terms do not fix the translation: no bound, the octants are bounded again.
            return (bounded(0.0), Some(HandedDown::Translations(ball)));
        };
        if !lower.is_finite() {
            return (
                Bound::Failed { solver_iterations: 0 },
                Some(HandedDown::Translations(ball)),
            );
        }
        if let Some(pruned) = self.pruned(lower) {
            return (pruned, None);
        }
        let kept = |inside_ball: bool| KeptCell {
            centre: cell.centre,
            half: cell.half,
            t_star,
            c,
            slack,
            inside_ball,
            depths: depths.clone(),
            with_segments: true,
            extent: None,
        };
        let extent = || {
            self.whitening
                .ellipsoid_factor(&c)
                .map(|lambda| (slack * lambda).max(0.0).sqrt())
        };
        // Cheirality: an object point or segment endpoint behind the camera (z ≤ 0) for every rotation
        // of the box and translation of the ellipsoid, whose largest t_z is t*_z + √(slack (C⁻¹)_zz).
        let t_z = t_star.z + (slack * c_inv[(2, 2)]).max(0.0).sqrt();
        let behind = (self.problem.corr.points3d.iter())
            .chain(self.problem.corr.lines3d.iter().flatten())
            .any(|x| (r_c * x).z + theta * x.norm() + t_z <= 0.0);
        if behind {
            if let InsideBall::Record(r) = &mut self.inside_ball {
                r.pruned += 1;
                r.behind.push(kept(false));
            }
            return (Bound::Empty { solver_iterations: 0 }, None);
        }
        if let Some(bound) = self.settled(cell, lower, &t_star, extent, kept) {
            return (bound, None);
        }
        // Of two ellipsoids that hold the translations, the one of least trace.
        let shape = c_inv * slack;
        let handed_down = if shape.trace() < ball.shape.trace() {
            TranslationEllipsoid {
                centre: t_star,
                radius: largest_eigenvalue(&shape).max(0.0).sqrt(),
                shape,
            }
        } else {
            ball
        };
        (bounded(lower), Some(HandedDown::Translations(handed_down)))
    }
}

/// What the rotation search proved.
pub(super) struct Localised {
    /// The least bound over the leaves of the search (unclamped; `+∞` when every box was proved
    /// empty of `S`).
    pub(super) raw_lower_bound: f64,
    /// The largest whitened radius of the boxes inside the ball (0 when there is none).
    pub(super) radius: f64,
    pub(super) nodes: usize,
}

/// Runs `search` on the shared branch and bound from the root box `[−π, π]³` with the incumbent
/// `f̂`, until the gap closes (`Err` when it reaches `max_nodes` or is stopped).
/// Runs the rotation search; `Err` says why nothing is proved and how many boxes it bounded.
pub(super) fn localise(
    search: &mut RotationSearch,
    max_nodes: usize,
) -> std::result::Result<Localised, (String, usize)> {
    let pi = std::f64::consts::PI;
    let root = Region::new(vec![-pi; 3], vec![pi; 3]);
    let opts = BranchAndBoundOptions {
        max_relative_gap: search.max_relative_gap,
        max_nodes,
        // f = ½ Σ r² ≥ 0.
        trivial_lower_bound: 0.0,
    };
    // A stop requested before the search ends it before its first box (the search polls it before
    // every split; exact data can close the gap at the root).
    let stopped = |reason: StopReason| format!("not proved: {} during the rotation search", reason.describe());
    if let Some(reason) = stop_reason() {
        return Err((stopped(reason), 0));
    }
    let result = branch_and_bound(search, root, Some((search.f_hat, ())), &opts);
    if let Some(reason) = result.stopped {
        return Err((stopped(reason), result.nodes));
    }
    if !result.converged {
        return Err((
            format!("not proved: the rotation search reached max_nodes = {max_nodes}"),
            result.nodes,
        ));
    }
    Ok(Localised {
        raw_lower_bound: result.box_lower_bound,
        radius: search.radius,
        nodes: result.nodes,
    })
}
