//! Sampling consensus: the one loop of RANSAC (Fischler & Bolles 1981), generic over an
//! [`Estimator`], used by the robust pose ([`crate::pose::robust`]: LO-RANSAC over mixed point/line
//! samples with the SPRT) and by robust triangulation ([`crate::triangulation::point::robust`],
//! [`crate::triangulation::line::robust`]: two-view samples).
//!
//! Each iteration draws a minimal sample ([`Estimator::sample`]), solves it for its models
//! ([`Estimator::models`]; none: a degenerate sample) and scores each model
//! ([`Estimator::score`], typically the MSAC cost `Σ min(eᵢ², τ²)` of Torr & Zisserman 2000, see
//! [`truncated`]). A model scoring strictly below every model scored before it *as solved from its
//! sample* (the record) is handed to the local optimisation ([`Estimator::refine`], applied to each
//! so-far-the-best sample, Chum, Matas & Kittler 2003), and the refined model becomes the best model
//! when its score is strictly below the best refined score so far: the answer is the best of all the
//! local optimisations. Comparing a raw sample's score with a refined one instead would refine almost
//! nothing after the first local optimisation (a fit to all the inliers scores far below any minimal
//! sample's model), so a sample in the basin of a better consensus, e.g. one holding a high-leverage
//! inlier that the first fit left out, would never be refined. The records of `k` samples number
//! about `ln k`, so this costs a few local optimisations more.
//!
//! **Stopping.** The loop stops, checked in this order before each sample:
//! 1. on the adaptive bound: with `P` the probability that a sample is all-inlier for the best model
//!    ([`Estimator::new_best`]), `N = ⌈ln(1 − confidence) / ln(1 − P (1 − α))⌉` samples
//!    (Hartley & Zisserman §4.7.1), counted as `Σᵢ kᵢ ln(1 − P (1 − αᵢ)) ≤ ln(1 − confidence)` over the
//!    `kᵢ` samples verified with a test that rejects a good model with probability at most `αᵢ`
//!    ([`Estimator::rejection_bound`]; Chum & Matas 2008, eq. 9) — or on the same bound at the
//!    probability [`Options::floor_probability`] of the smallest inlier fraction the loop is designed to
//!    find (COLMAP's `min_inlier_ratio`), whichever is smaller; never before
//!    [`Options::min_iterations`];
//! 2. after [`Options::max_iterations`] samples;
//! 3. when [`Options::time_budget`] has run out (measured by the caller's clock);
//! 4. when the call is stopped ([`crate::interrupt`]), if [`Options::interruptible`];
//! 5. when the estimator has no sample left (an exhaustive list of samples, or none drawable).
//!
//! The bound is recomputed only when the best model or `α` changes: the samples drawn in between are
//! then counted at the `α` assumed for them.

use crate::interrupt::{stop_reason, StopReason};
use std::time::Duration;

/// The part of one problem the loop does not know: how to sample, solve, score and refine.
pub(crate) trait Estimator {
    /// A minimal sample (indices of the data).
    type Sample;
    /// A model (a pose, a point, a line, ...).
    type Model;
    /// The score of a model, lower is better (the MSAC cost, or a tuple ranking on more than it).
    type Score: PartialOrd + Copy;

    /// The next minimal sample; `None` when there is none left.
    fn sample(&mut self) -> Option<Self::Sample>;

    /// The models `sample` determines; none when it is degenerate.
    fn models(&mut self, sample: &Self::Sample) -> Vec<Self::Model>;

    /// The score of `model` (solved from `sample`), or `None` when it cannot beat `record`, the best
    /// score of a sample's model so far (an early exit of the scoring, or a rejection by a sequential
    /// test once a record exists).
    fn score(
        &mut self,
        model: &Self::Model,
        sample: &Self::Sample,
        record: Option<Self::Score>,
        stats: &Stats,
    ) -> Option<Self::Score>;

    /// Local optimisation of a model that beats the record: returns a model scoring no worse (by
    /// default the model itself).
    fn refine(&mut self, model: Self::Model, score: Self::Score) -> (Self::Model, Self::Score) {
        (model, score)
    }

    /// `model` (refined) is the new best: the probability `P` that a sample is all-inlier for it (for
    /// the adaptive bound; by default 0, no adaptive bound).
    fn new_best(&mut self, _model: &Self::Model, _stats: &Stats) -> f64 {
        0.0
    }

    /// `α`, the probability that the scoring rejects a model of an all-inlier sample once a best
    /// model exists (`1 / A` of a sequential test, by default 0).
    fn rejection_bound(&self) -> f64 {
        0.0
    }
}

/// How long the loop runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Options {
    /// Probability of having drawn at least one all-inlier sample when the loop stops on its adaptive
    /// bound, in `(0, 1)`.
    pub confidence: f64,
    /// `P` at the smallest inlier fraction the loop is designed to find (`ρ^s` for samples of `s`):
    /// the adaptive bound at this probability caps the loop whatever the best model; 0: no cap.
    pub floor_probability: f64,
    /// Samples drawn at most.
    pub max_iterations: usize,
    /// Samples drawn before the adaptive bound may stop the loop.
    pub min_iterations: usize,
    /// Time budget of the loop, against the caller's clock.
    pub time_budget: Option<Duration>,
    /// Whether a stop of the call ([`crate::interrupt`]) ends the loop.
    pub interruptible: bool,
}

impl Options {
    /// Every sample the estimator gives, in order, without any adaptive stop (an exhaustive search).
    pub fn exhaustive() -> Options {
        Options {
            confidence: 0.5,
            floor_probability: 0.0,
            max_iterations: usize::MAX,
            min_iterations: 0,
            time_budget: None,
            interruptible: false,
        }
    }
}

/// Why the loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stop {
    /// The adaptive bound of the best model.
    Confidence,
    /// The adaptive bound at [`Options::floor_probability`].
    MinInlierRatio,
    /// [`Options::max_iterations`].
    IterationCap,
    /// [`Options::time_budget`], or the time budget of the call's stop.
    TimeBudget,
    /// The call was stopped.
    Interrupted,
    /// The estimator had no sample left.
    Exhausted,
}

/// What the loop counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Stats {
    /// Samples drawn.
    pub iterations: usize,
    /// Samples without a model.
    pub degenerate_samples: usize,
    /// Models scored (fully or until an early exit).
    pub models_scored: usize,
    /// Models that beat the record (each refined once).
    pub records: usize,
    /// Refined models that beat the best refined model.
    pub new_bests: usize,
}

/// The best model, its score, the counts and why the loop stopped.
#[derive(Debug, Clone)]
pub(crate) struct Outcome<M, S> {
    /// The best model and its score; `None` when no model was ever scored.
    pub best: Option<(M, S)>,
    /// What the loop counted.
    pub stats: Stats,
    /// Why it stopped.
    pub stop: Stop,
}

/// The MSAC term of one squared error `e`: `min(e, τ²)`, and `τ²` when `e` is not finite (a point
/// behind a camera, a model that does not determine the residual).
pub(crate) fn truncated(e: f64, tau2: f64) -> f64 {
    if e.is_finite() {
        e.min(tau2)
    } else {
        tau2
    }
}

/// The MSAC score `Σ min(eᵢ, τ²)` of the squared errors `eᵢ` ([`truncated`]), summed in order, and the
/// number of inliers `eᵢ ≤ τ²`.
pub(crate) fn msac(errors: impl IntoIterator<Item = f64>, tau2: f64) -> (f64, usize) {
    errors.into_iter().fold((0.0, 0), |(score, inliers), e| {
        (score + truncated(e, tau2), inliers + (e <= tau2) as usize)
    })
}

/// The number of samples after which `Σᵢ kᵢ ln(1 − P (1 − αᵢ)) ≤ ln(1 − confidence)` (module docs),
/// given the samples drawn so far as runs `(αᵢ, kᵢ)` in `history` and `rejection` = `α` of those still
/// to come; at least the samples drawn (and at least 1). `usize::MAX` if never (`P (1 − α) = 0`).
pub(crate) fn required_samples(p: f64, confidence: f64, history: &[(f64, usize)], rejection: f64) -> usize {
    let log_miss = |alpha: f64| (-(p * (1.0 - alpha.clamp(0.0, 1.0)))).ln_1p();
    let target = (1.0 - confidence).ln();
    let drawn: usize = history.iter().map(|h| h.1).sum();
    let so_far: f64 = history.iter().map(|&(alpha, k)| k as f64 * log_miss(alpha)).sum();
    if so_far <= target {
        return drawn.max(1);
    }
    let step = log_miss(rejection);
    if step == f64::NEG_INFINITY {
        return drawn + 1;
    }
    let n = (target - so_far) / step;
    if n.is_finite() && n < (usize::MAX - drawn) as f64 {
        drawn + (n.ceil() as usize).max(1)
    } else {
        usize::MAX
    }
}

/// Runs the loop (module docs) on `estimator`; `elapsed` is the clock of [`Options::time_budget`].
pub(crate) fn run<E: Estimator>(
    estimator: &mut E,
    opts: &Options,
    mut elapsed: impl FnMut() -> Duration,
) -> Outcome<E::Model, E::Score> {
    let mut stats = Stats::default();
    // The best refined model, and the best score of a model as solved from its sample.
    let mut best: Option<(E::Model, E::Score)> = None;
    let mut record: Option<E::Score> = None;
    // `P` of the best model.
    let mut probability: Option<f64> = None;
    // The samples drawn, counted per `α` of the test their models were verified with (0 without).
    let mut history: Vec<(f64, usize)> = Vec::new();
    // The stopping bound, its reason, and the `α` assumed for the samples to come; recomputed when
    // the best model or `α` changes.
    let mut limit: Option<(usize, Stop, f64)> = None;
    let stop = loop {
        let alpha_next = if best.is_some() {
            estimator.rejection_bound()
        } else {
            0.0
        };
        if limit.is_some_and(|l| l.2 != alpha_next) {
            limit = None;
        }
        let (bound, reason, _) = *limit.get_or_insert_with(|| {
            let needed = |p: f64| required_samples(p, opts.confidence, &history, alpha_next);
            let required = probability.map_or(usize::MAX, needed);
            let cap = if opts.floor_probability > 0.0 {
                needed(opts.floor_probability)
            } else {
                usize::MAX
            };
            if required <= cap {
                (required, Stop::Confidence, alpha_next)
            } else {
                (cap, Stop::MinInlierRatio, alpha_next)
            }
        });
        if stats.iterations >= bound.max(opts.min_iterations) {
            break reason;
        }
        if stats.iterations >= opts.max_iterations {
            break Stop::IterationCap;
        }
        if opts.time_budget.is_some_and(|budget| elapsed() >= budget) {
            break Stop::TimeBudget;
        }
        if opts.interruptible {
            if let Some(reason) = stop_reason() {
                break match reason {
                    StopReason::Requested => Stop::Interrupted,
                    StopReason::TimeBudget => Stop::TimeBudget,
                };
            }
        }
        let Some(sample) = estimator.sample() else {
            break Stop::Exhausted;
        };
        stats.iterations += 1;
        let models = estimator.models(&sample);
        if models.is_empty() {
            stats.degenerate_samples += 1;
        }
        let mut alpha = 0.0f64;
        for model in models {
            stats.models_scored += 1;
            if best.is_some() {
                alpha = alpha.max(estimator.rejection_bound());
            }
            let Some(score) = estimator.score(&model, &sample, record, &stats) else {
                continue;
            };
            if record.is_some_and(|b| !(score < b)) {
                continue;
            }
            record = Some(score);
            stats.records += 1;
            let (model, score) = estimator.refine(model, score);
            if best.as_ref().is_some_and(|b| !(score < b.1)) {
                continue;
            }
            stats.new_bests += 1;
            probability = Some(estimator.new_best(&model, &stats));
            limit = None;
            best = Some((model, score));
        }
        match history.iter_mut().find(|h| h.0 == alpha) {
            Some(h) => h.1 += 1,
            None => history.push((alpha, 1)),
        }
    };
    Outcome { best, stats, stop }
}

#[cfg(test)]
mod tests;
