//! Robust pose from points and lines with outliers: LO-RANSAC (Chum, Matas & Kittler 2003) with MSAC
//! scoring (Torr & Zisserman 2000).
//!
//! Each iteration draws a minimal sample of three correspondences, points and lines together
//! (`sampler`), solves it with [`crate::pose::minimal::solve`] (P3P today; the mixed and line-only
//! solvers as they exist), and scores every pose it returns whose sample lies in front of the camera by
//! the truncated squared reprojection error (`scoring`: `½ Σ min(eᵢ², τᵢ²)`, points in pixels, lines
//! as the RMS of the two endpoint-to-projected-line distances in pixels, with separate thresholds).
//! Scoring stops early as soon as a hypothesis cannot beat the best one, or, once a best model exists,
//! as soon as Wald's sequential probability ratio test (SPRT, `sprt`: Matas & Chum, ICCV 2005) finds
//! it no better than a random pose: with many correspondences and few inliers a bad hypothesis is then
//! rejected after a few tens of errors instead of all of them.
//!
//! When a hypothesis beats every hypothesis scored before it (as solved from its sample: the loop's
//! record, see [`crate::consensus`]), *local optimisation* re-fits it by iterated least squares with a
//! shrinking threshold (the "LO+" of Lebeda, Matas & Chum, BMVC 2012): the inliers within
//! [`LO_THRESHOLD_MULTIPLIER`] times the thresholds are re-fitted by the trust region of the refinement
//! (at most [`RansacOptions::local_iterations`] iterations), then those within a smaller multiple at the
//! new pose, down to the thresholds themselves over [`LOCAL_ROUNDS`] rounds; every fit is scored with the
//! true thresholds and the best kept. A minimal sample's pose is off by several pixels at the far side of
//! the scene, so inliers selected at the thresholds alone can miss part of the true inlier set and
//! settle on a worse model nearby; the wider rounds bring the accuracy to that of the
//! maximum-likelihood fit on the true inliers (measured with `bench/compare_robust_pose.py`: the figures
//! are in docs/benchmarks.md, "Figures behind code comments"). The best model is the best-scoring
//! of all the local optimisations. The loop stops when the number of
//! samples reaches the adaptive bound of `sampler` for [`RansacOptions::confidence`], the cap of
//! [`RansacOptions::min_inlier_ratio`], the iteration cap, or the time budget. A best model with at
//! least [`RansacReport::required_inliers`] then settles on its final consensus (`guided`): the
//! correspondences within the threshold of their *prediction* uncertainty (a high-leverage inlier,
//! e.g. a point much nearer than the rest of the scene, can lie tens of pixels off a fit that left it
//! out) are re-fitted until the set is stable, a fit kept only when it scores better. The caller
//! ([`crate::pose::estimate_pose`]) then refines the best model on its inliers with the full
//! reprojection refinement.
//!
//! The loop itself (sampling, the best model, the adaptive bound and its cap, the budget and the stop)
//! is the sampling consensus shared with robust triangulation (`crate::consensus`); this module plugs
//! into it the mixed samples, the minimal solvers, the scoring with the SPRT and the local optimisation.
//!
//! **All-outlier data.** With no model in the data, no inlier fraction is ever found, so the adaptive
//! bound never comes down: before the SPRT and the `min_inlier_ratio` cap the loop ran to
//! `max_iterations` (100,000 samples), each hypothesis scored on nearly every correspondence (its
//! partial MSAC sum stays below the best's until the end). Now it draws about 9,800 samples (the cap of
//! the default 0.1: 9,206, a few % more for the SPRT's `α`) and rejects each hypothesis after about 30
//! errors (the times before and after, from `bench/robust_outliers.py`:
//! docs/benchmarks.md, "Figures behind code comments").
//!
//! **Inliers by chance.** A wrong pose still agrees with some outliers: each falls within the threshold
//! of its prediction with probability `p ≈ π τ² / (W H)` for observations spread over a `W × H` window
//! (1.6e-4 at 4 px in 640 x 480), so among `n` correspondences a wrong model has its 3 sample inliers
//! plus about `n p` chance ones (3.3 at `n = 20,000`), the best of tens of thousands of such models a
//! dozen, and a local optimisation fitted to them pulls in more (18 were reported after the final
//! refinement at 20,000 points). A fixed `min_inliers = 6` therefore separates real models from chance
//! only for small `n`: all-outlier data used to end `not_converged` with 6-18 "inliers". The best model
//! must also beat chance: [`RansacReport::required_inliers`] is `max(min_inliers, min(c + 1, ⌈ρ n⌉))`,
//! with `c` the most inliers that the best of the `M` hypotheses tried reaches by chance with
//! probability above [`CHANCE_SIGNIFICANCE`] (`sprt::chance_inliers`: the exact binomial tails of
//! the points and the lines, Bonferroni over `M`) and `ρ` = [`RansacOptions::min_inlier_ratio`]: a model with at least the
//! fraction of inliers the loop is designed to find is never refused, so a threshold wider than the
//! image (every correspondence an inlier of every pose) still gives an answer. With the defaults and
//! 4 px thresholds in a 640 x 480 image, `c + 1` is at most `min_inliers` = 6 up to about 150
//! correspondences even after the ~17,000 poses of an all-outlier run (up to about 500 after the few
//! hundred poses of a run that finds a model), 7 at 500, 9 at 2,000 and 18 at 20,000: a small fraction
//! of the inliers of any model the loop is designed to find (at least `⌈ρ n⌉` = 2,000 at 20,000).
//!
//! Conventions: `x_cam = R X + t` in the frame of the correspondences given (the pipeline passes its
//! centred, unit-scale frame); pixel errors do not depend on that frame.

pub(crate) mod guided;
pub(crate) mod pipeline;
pub(crate) mod sampler;
pub(crate) mod scoring;
pub(crate) mod sprt;

use super::correspondences::Correspondences;
use super::minimal::solve;
use super::reprojection::{Pose, ReprojectionCost};
use crate::camera::Intrinsics;
use crate::consensus::{self, Estimator, Stats, Stop};
use crate::error::{number, Error, Result};
use crate::interrupt::stop_reason;
use crate::optim::{trust_region, Subproblem, TrustRegionOptions};
use crate::rng::Rng;
use sampler::{solvable, Sampler};
use scoring::{subset, Prepared, Thresholds, Verdict};
use sprt::{chance_inliers, chance_probabilities, Sprt};
use std::time::{Duration, Instant};

/// Options of the robust estimator (`PoseOptions::ransac`). Every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct RansacOptions {
    /// Inlier threshold of a point: the reprojection distance in pixels. Default `4.0`.
    pub point_threshold: f64,
    /// Inlier threshold of a line: the RMS of the distances of its two observed segment endpoints to
    /// the projected 3-D line, pixels. Default `4.0`.
    pub line_threshold: f64,
    /// Probability of having drawn at least one all-inlier sample when the loop stops on its adaptive
    /// bound (see `sampler`). In `(0, 1)`. Default `0.9999`.
    pub confidence: f64,
    /// Cap on the number of samples drawn. ≥ 1. Default `100_000`.
    pub max_iterations: usize,
    /// Minimum number of samples drawn before the adaptive bound (or the `min_inlier_ratio` cap) may
    /// stop the loop. Default `0`.
    pub min_iterations: usize,
    /// `ρ`, the smallest inlier fraction the loop is designed to find. It stops after
    /// `⌈ln(1 − confidence) / ln(1 − ρ³ (1 − α))⌉` samples (see `sampler`) even when the best model so
    /// far has fewer inliers: by then a model with a fraction `ρ` of the points and of the lines as
    /// inliers would have been found with probability `confidence`. It is also the floor of the SPRT's
    /// `ε`, and a model with at least `⌈ρ n⌉` inliers always meets [`RansacReport::required_inliers`].
    /// In `[0, 1)`; 0 removes the cap and the chance requirement (only `max_iterations` bounds the
    /// loop). Default `0.1` (COLMAP's default): at most 9,206 samples at the default confidence; data
    /// with 90 % outliers or fewer are found with the requested confidence, sparser models only by luck.
    pub min_inlier_ratio: f64,
    /// Early rejection of bad hypotheses by the sequential probability ratio test (`sprt`); `false`
    /// scores every hypothesis until it cannot beat the best one. Default `true`.
    pub sprt: bool,
    /// Wall-time budget of the sampling loop (checked every iteration); `None`: no budget. Default
    /// `None` (the iteration cap bounds the loop).
    pub time_budget: Option<Duration>,
    /// Seed of the sampler ([`Rng`]): the same seed and data give the same result. Default `0`.
    pub seed: u64,
    /// Iteration cap of each trust-region run of the local optimisation. 0 disables it. Default `10`.
    pub local_iterations: usize,
    /// Fewest inliers a model needs to be accepted; with fewer the status is `TooFewInliers`. At least
    /// 3 (a sample's worth); fewer than this many correspondences in all is an error. Default `6`:
    /// random outliers support a wrong model of a 3-correspondence sample by at most one or two
    /// chance agreements when there are a few hundred correspondences (at 4 px in a 640 x 480 image
    /// each falls within threshold with probability about 1.6e-4). With more, the chance agreements
    /// grow with their number: the model must then also beat chance, see
    /// [`RansacReport::required_inliers`].
    pub min_inliers: usize,
}

/// Local-optimisation rounds per new best model (each: inliers → re-fit → re-score), the inlier
/// threshold shrinking geometrically from [`LO_THRESHOLD_MULTIPLIER`] × to 1 × the thresholds.
pub const LOCAL_ROUNDS: usize = 4;

/// Inlier thresholds of the first local-optimisation round, as a multiple of the scoring thresholds
/// (Lebeda et al. 2012 use 3 with 4 rounds).
pub const LO_THRESHOLD_MULTIPLIER: f64 = 3.0;

/// `ψ`: the probability, under the outlier model of `sprt::chance_probabilities`, that the best of
/// the hypotheses tried on all-outlier data meets the chance part of [`RansacReport::required_inliers`]
/// (the 5 % of PROSAC's non-randomness test, Chum & Matas, CVPR 2005, here for the best of `M`).
pub const CHANCE_SIGNIFICANCE: f64 = 0.05;

/// Seed offset of the second random stream (the verification order and start slots of
/// `scoring`), so that the samples drawn for a seed do not depend on the scoring.
const ORDER_STREAM: u64 = 0x5b7d_3c4e_a1f2_9e07;

impl Default for RansacOptions {
    fn default() -> Self {
        RansacOptions {
            point_threshold: 4.0,
            line_threshold: 4.0,
            confidence: 0.9999,
            max_iterations: 100_000,
            min_iterations: 0,
            min_inlier_ratio: 0.1,
            sprt: true,
            time_budget: None,
            seed: 0,
            local_iterations: 10,
            min_inliers: 6,
        }
    }
}

impl RansacOptions {
    /// Checks the ranges stated on each field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| {
            Err(Error::InvalidOption {
                name: name.into(),
                reason,
            })
        };
        for (name, value) in [
            ("point_threshold", self.point_threshold),
            ("line_threshold", self.line_threshold),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return bad(
                    name,
                    format!("must be a positive finite number of pixels, got {}", number(value)),
                );
            }
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return bad(
                "confidence",
                format!("must be in (0, 1), got {}", number(self.confidence)),
            );
        }
        if self.max_iterations < 1 {
            return bad("max_iterations", "must be at least 1".into());
        }
        if self.min_iterations > self.max_iterations {
            return bad("min_iterations", "must not exceed the iteration cap".into());
        }
        if !(self.min_inlier_ratio >= 0.0 && self.min_inlier_ratio < 1.0) {
            return bad(
                "min_inlier_ratio",
                format!("must be in [0, 1), got {}", number(self.min_inlier_ratio)),
            );
        }
        if self.min_inliers < 3 {
            return bad("min_inliers", format!("must be at least 3, got {}", self.min_inliers));
        }
        Ok(())
    }

    fn thresholds(&self) -> Thresholds {
        Thresholds {
            point2: self.point_threshold * self.point_threshold,
            line2: self.line_threshold * self.line_threshold,
        }
    }
}

/// Why the sampling loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum RansacStop {
    /// The adaptive bound for the requested confidence was reached.
    Confidence,
    /// [`RansacOptions::max_iterations`] samples were drawn first.
    IterationCap,
    /// The cap of [`RansacOptions::min_inlier_ratio`] was reached first: the best model has a smaller
    /// inlier fraction than that, or there is none.
    MinInlierRatio,
    /// [`RansacOptions::time_budget`], or the time budget of the call's stop ([`crate::interrupt`]),
    /// ran out first.
    TimeBudget,
    /// The call was stopped ([`crate::interrupt`]: Ctrl-C seen by a binding, the caller's request).
    Interrupted,
    /// No sample can be drawn: no mix of the data's points and lines has a minimal solver (e.g. lines
    /// only while the three-line solver is missing).
    NoSolvableSample,
}

impl From<Stop> for RansacStop {
    fn from(stop: Stop) -> RansacStop {
        match stop {
            Stop::Confidence => RansacStop::Confidence,
            Stop::MinInlierRatio => RansacStop::MinInlierRatio,
            Stop::IterationCap => RansacStop::IterationCap,
            Stop::TimeBudget => RansacStop::TimeBudget,
            Stop::Interrupted => RansacStop::Interrupted,
            Stop::Exhausted => RansacStop::NoSolvableSample,
        }
    }
}

impl RansacStop {
    /// snake_case name for reports, JSON and Python.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }
}

/// What the robust loop did.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RansacReport {
    /// Samples drawn.
    pub iterations: usize,
    /// Samples for which the minimal solver returned no pose (degenerate: collinear points, parallel
    /// lines, ...), or whose every pose put the sample behind the camera.
    pub degenerate_samples: usize,
    /// Poses scored (a sample may give up to four), fully or until an early exit.
    pub models_scored: usize,
    /// Poses rejected by the sequential test ([`RansacOptions::sprt`]).
    pub sprt_rejections: usize,
    /// Reprojection errors evaluated while scoring the poses (early exits included; not those of the
    /// local optimisation or of the inlier masks): the work of the scoring.
    pub errors_evaluated: usize,
    /// Local optimisations run (one per sample whose pose beat every sample's before it, each up to
    /// `LOCAL_ROUNDS` rounds).
    pub local_optimizations: usize,
    /// Inliers (points + lines) of the best model before the final refinement.
    pub inliers: usize,
    /// Fewest inliers the best model needs (before and after the final refinement), else the status is
    /// `TooFewInliers`: `max(min_inliers, min(c + 1, ⌈ρ n⌉))` with `c` the most inliers a wrong model
    /// plausibly gets by chance (see the module documentation) and `ρ` = `min_inlier_ratio`.
    pub required_inliers: usize,
    /// MSAC score `Σ min(eᵢ², τᵢ²)` of the best model, px² (the result's cost convention).
    pub score: f64,
    /// Why the loop stopped.
    pub stop: RansacStop,
    /// Wall time of the loop including local optimisation, seconds.
    pub time_seconds: f64,
}

/// The best model of [`ransac`] (frame of the correspondences) and the report.
#[derive(Debug, Clone)]
pub struct RansacOutcome {
    /// The best pose, or `None` if no hypothesis was ever scored.
    pub pose: Option<Pose>,
    /// Point inlier mask of the best pose (all false without one).
    pub inliers_points: Vec<bool>,
    /// Line inlier mask of the best pose (all false without one).
    pub inliers_lines: Vec<bool>,
    /// What the loop did.
    pub report: RansacReport,
    /// The prepared data, for the inlier tests of the final refinement.
    pub(crate) data: Prepared,
    /// The thresholds used.
    pub(crate) thresholds: Thresholds,
}

/// The best model so far.
pub(crate) struct Best {
    pub pose: Pose,
    pub score: f64,
}

/// The pose's part of the sampling loop ([`crate::consensus`]): mixed point/line samples
/// (`sampler`), the minimal solvers, the MSAC scoring with the SPRT (`scoring`, `sprt`) and the local
/// optimisation; it counts what [`RansacReport`] reports beyond the loop's own counts.
struct PoseEstimator<'a> {
    camera: &'a Intrinsics,
    corr: &'a Correspondences,
    data: &'a Prepared,
    tau: Thresholds,
    sampler: Sampler,
    /// The samples' stream.
    rng: Rng,
    /// The verification order's stream (start slots of `scoring`).
    order_rng: Rng,
    /// The trust region of the local optimisation.
    lo: TrustRegionOptions,
    local_iterations: usize,
    sprt: Option<Sprt>,
    errors_evaluated: usize,
    sprt_rejections: usize,
    local_optimizations: usize,
    /// Inliers of the best model, and its masks (points, lines).
    inliers: usize,
    best_inliers: Option<(Vec<bool>, Vec<bool>)>,
}

impl Estimator for PoseEstimator<'_> {
    type Sample = [usize; 3];
    type Model = Pose;
    type Score = f64;

    fn sample(&mut self) -> Option<[usize; 3]> {
        self.sampler.can_draw().then(|| self.sampler.draw(&mut self.rng))
    }

    /// The poses of the sample that put its correspondences in front of the camera.
    fn models(&mut self, sample: &[usize; 3]) -> Vec<Pose> {
        let features = sample.map(|k| self.data.feature(k));
        let mut poses = solve(&features);
        poses.retain(|pose| self.data.sample_in_front(pose, sample));
        poses
    }

    fn score(&mut self, pose: &Pose, sample: &[usize; 3], record: Option<f64>, stats: &Stats) -> Option<f64> {
        let bound = record.unwrap_or(f64::INFINITY);
        // The first model is scored in full; the test needs a model to compare with.
        let test = self.sprt.as_ref().filter(|_| record.is_some()).map(|s| *s.test());
        let (np, nl) = (self.data.n_points(), self.data.n_lines());
        let start = [
            scoring::below(&mut self.order_rng, np),
            scoring::below(&mut self.order_rng, nl),
        ];
        let (verdict, work) = self
            .data
            .evaluate(pose, &self.tau, bound, test.as_ref(), Some(sample), start);
        self.errors_evaluated += work;
        match verdict {
            Verdict::Score(score) if score < bound => Some(score),
            Verdict::Rejected { evaluated, consistent } => {
                self.sprt_rejections += 1;
                if let Some(s) = self.sprt.as_mut() {
                    s.rejected(evaluated, consistent, models_per_sample(stats));
                }
                None
            }
            _ => None,
        }
    }

    /// The local optimisation of a record sample, unless every inlier of its pose is an inlier of the
    /// best model: its fits would then start from a subset of the best model's inliers, in the basin
    /// the best model has settled in (with no outliers, every record after the first).
    fn refine(&mut self, pose: Pose, score: f64) -> (Pose, f64) {
        if self.local_iterations == 0 {
            return (pose, score);
        }
        if let Some((best_points, best_lines)) = &self.best_inliers {
            let (points, lines) = self.data.inliers(&pose, &self.tau);
            let within = |mask: &[bool], best: &[bool]| mask.iter().zip(best).all(|(&m, &b)| !m || b);
            if within(&points, best_points) && within(&lines, best_lines) {
                return (pose, score);
            }
        }
        self.local_optimizations += 1;
        let best = local_optimization(
            self.camera,
            self.corr,
            self.data,
            &self.tau,
            &self.lo,
            Best { pose, score },
        );
        (best.pose, best.score)
    }

    /// `P` of the best model's inlier fractions (points, lines); the SPRT is told of them.
    fn new_best(&mut self, pose: &Pose, stats: &Stats) -> f64 {
        let (points, lines) = self.data.inliers(pose, &self.tau);
        let count = |m: &[bool]| m.iter().filter(|&&v| v).count();
        let (ip, il) = (count(&points), count(&lines));
        self.inliers = ip + il;
        let (np, nl) = (points.len(), lines.len());
        self.best_inliers = Some((points, lines));
        let fraction = |i: usize, n: usize| if n == 0 { 0.0 } else { i as f64 / n as f64 };
        let f = [fraction(ip, np), fraction(il, nl)];
        if let Some(s) = self.sprt.as_mut() {
            s.new_best(f, models_per_sample(stats));
        }
        self.sampler.all_inlier_probability(f[0], f[1])
    }

    fn rejection_bound(&self) -> f64 {
        self.sprt.as_ref().map_or(0.0, Sprt::rejection_bound)
    }
}

/// Poses scored per sample drawn so far.
fn models_per_sample(stats: &Stats) -> f64 {
    stats.models_scored as f64 / stats.iterations as f64
}

/// The trust region of the local optimisation: `refinement` with Hebden steps, capped at
/// [`RansacOptions::local_iterations`] (a rig's loop uses it too).
pub(crate) fn local_optimization_options(refinement: &TrustRegionOptions, opts: &RansacOptions) -> TrustRegionOptions {
    let mut lo = *refinement;
    lo.subproblem = Subproblem::Hebden;
    lo.stopping.max_iterations = opts.local_iterations;
    lo
}

/// LO-RANSAC on validated correspondences (finite, no zero-length segment), in their frame.
/// `refinement` sets the trust region of the local optimisation (its cap is replaced by
/// [`RansacOptions::local_iterations`]).
pub fn ransac(
    camera: &Intrinsics,
    corr: &Correspondences,
    opts: &RansacOptions,
    refinement: &TrustRegionOptions,
) -> Result<RansacOutcome> {
    let started = Instant::now();
    let mut order_rng = Rng::new(opts.seed ^ ORDER_STREAM);
    let data = Prepared::new(camera, corr, &mut order_rng)?;
    let tau = opts.thresholds();
    let (np, nl) = (data.n_points(), data.n_lines());
    let sampler = Sampler::new(np, nl, solvable());
    let lo = local_optimization_options(refinement, opts);
    let chance = chance_probabilities(data.window, opts.point_threshold, opts.line_threshold);
    let rho = opts.min_inlier_ratio;
    let loop_opts = consensus::Options {
        confidence: opts.confidence,
        floor_probability: if rho > 0.0 {
            sampler.all_inlier_probability(rho, rho)
        } else {
            0.0
        },
        max_iterations: opts.max_iterations,
        min_iterations: opts.min_iterations,
        time_budget: opts.time_budget,
        interruptible: true,
    };
    let can_draw = sampler.can_draw();
    let mut estimator = PoseEstimator {
        camera,
        corr,
        data: &data,
        tau,
        sampler,
        rng: Rng::new(opts.seed),
        order_rng,
        lo,
        local_iterations: opts.local_iterations,
        sprt: opts
            .sprt
            .then(|| Sprt::new([np, nl], chance, opts.min_inlier_ratio, 1.0)),
        errors_evaluated: 0,
        sprt_rejections: 0,
        local_optimizations: 0,
        inliers: 0,
        best_inliers: None,
    };
    let outcome = if can_draw {
        consensus::run(&mut estimator, &loop_opts, || started.elapsed())
    } else {
        consensus::Outcome {
            best: None,
            stats: Stats::default(),
            stop: Stop::Exhausted,
        }
    };
    let stats = outcome.stats;
    let mut report = RansacReport {
        iterations: stats.iterations,
        degenerate_samples: stats.degenerate_samples,
        models_scored: stats.models_scored,
        sprt_rejections: estimator.sprt_rejections,
        errors_evaluated: estimator.errors_evaluated,
        local_optimizations: estimator.local_optimizations,
        inliers: estimator.inliers,
        required_inliers: opts.min_inliers,
        score: data.all_outlier_score(&tau),
        stop: outcome.stop.into(),
        time_seconds: 0.0,
    };
    report.required_inliers = required_inliers(opts, &report, chance, np, nl);
    let mut best = outcome.best.map(|(pose, score)| Best { pose, score });
    // The final consensus (`guided`), for a model that will be accepted, unless the call is stopping.
    let stopping = matches!(outcome.stop, Stop::Interrupted | Stop::TimeBudget);
    if opts.local_iterations > 0 && !stopping && report.inliers >= report.required_inliers {
        best = best.map(|b| guided::settle(camera, corr, &data, &tau, &lo, b));
    }
    let (inliers_points, inliers_lines) = match &best {
        Some(b) => data.inliers(&b.pose, &tau),
        None => (vec![false; np], vec![false; nl]),
    };
    if let Some(b) = &best {
        report.score = b.score;
        report.inliers = [&inliers_points, &inliers_lines]
            .iter()
            .map(|m| m.iter().filter(|&&v| v).count())
            .sum();
    }
    report.time_seconds = started.elapsed().as_secs_f64();
    Ok(RansacOutcome {
        pose: best.map(|b| b.pose),
        inliers_points,
        inliers_lines,
        report,
        data,
        thresholds: tau,
    })
}

/// [`RansacReport::required_inliers`]: `max(min_inliers, min(c + 1, ⌈ρ n⌉))` (see the module
/// documentation), `c` from the hypotheses scored and refitted so far.
pub(crate) fn required_inliers(
    opts: &RansacOptions,
    report: &RansacReport,
    chance: [f64; 2],
    np: usize,
    nl: usize,
) -> usize {
    let n = np + nl;
    let floor = (opts.min_inlier_ratio * n as f64).ceil() as usize;
    if floor == 0 {
        return opts.min_inliers;
    }
    let models = report.models_scored + LOCAL_ROUNDS * report.local_optimizations;
    let by_chance = chance_inliers([np, nl], chance, models, CHANCE_SIGNIFICANCE);
    opts.min_inliers.max((by_chance + 1).min(floor))
}

/// Re-fits `best` by iterated least squares on the inliers of a shrinking threshold (see the module
/// documentation), returning the best-scoring fit (or `best` itself).
fn local_optimization(
    camera: &Intrinsics,
    corr: &Correspondences,
    data: &Prepared,
    tau: &Thresholds,
    lo: &TrustRegionOptions,
    mut best: Best,
) -> Best {
    let mut current = best.pose;
    let mut fitted: Option<(Vec<bool>, Vec<bool>)> = None;
    for round in 0..LOCAL_ROUNDS {
        // A round re-fits all the inliers (tens of milliseconds at 10⁵): a stopped call ends here,
        // with the best fit so far, rather than at the loop's next sample.
        if round > 0 && stop_reason().is_some() {
            break;
        }
        let exponent = (LOCAL_ROUNDS - 1 - round) as f64 / (LOCAL_ROUNDS - 1) as f64;
        let m2 = LO_THRESHOLD_MULTIPLIER.powf(2.0 * exponent);
        let wide = Thresholds {
            point2: m2 * tau.point2,
            line2: m2 * tau.line2,
        };
        let masks = data.inliers(&current, &wide);
        if fitted.as_ref() == Some(&masks) {
            continue; // the same inliers again: the last re-fit already minimised their error
        }
        let inliers = subset(corr, &masks.0, &masks.1);
        fitted = Some(masks);
        if inliers.n_points() + inliers.n_lines() < 3 {
            break;
        }
        let cost = ReprojectionCost::of(camera, &inliers);
        let (pose, _) = trust_region::minimize(&cost, current, lo);
        current = pose;
        if let Some(score) = data.score(&pose, tau, best.score) {
            if score < best.score {
                best = Best { pose, score };
            }
        }
    }
    best
}

#[cfg(test)]
mod tests;
