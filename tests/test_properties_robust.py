"""The robust pose on clean data, property-tested (hypothesis): any inlier threshold that the noise
stays within gives ``success`` after a few samples, however wide the threshold.

Clean data: ``n`` points uniform in a box in front of a camera at a random pose, projected with
Gaussian noise of ``σ`` px, no outliers. A threshold ``τ ≥ 4 σ`` holds every point at the true pose
but with probability ``e⁻⁸ ≈ 3e-4`` (the squared radius of 2-D Gaussian noise is ``σ² χ²₂``), so the
best model has essentially every point as an inlier, the probability that a sample is all-inlier is
about 1, and the loop's adaptive bound (confidence 0.9999) stops it within a few samples. Thresholds
range from ``4 σ`` to ``1e300`` px, i.e. past the window of the image (every random pixel then agrees
with any pose, and the sequential test has nothing to go on) and past the square root of the largest
double. A threshold of 100 px used to run 100,000 samples to the iteration cap (``not_converged``).
"""

from __future__ import annotations

import numpy as np
import pluecker
from hypothesis import given, note
from hypothesis import strategies as st
from test_properties_certificates import rotation

#: Samples the loop may draw on clean data: the adaptive bound at an inlier fraction of 0.9 and the
#: default confidence, ⌈ln(1e-4) / ln(1 − 0.9³)⌉ = 8, with the sequential test's α (≤ 0.1: 9) and one
#: degenerate sample.
FEW_SAMPLES = 10


@st.composite
def clean_problems(draw):
    n = draw(st.integers(8, 200))
    sigma = draw(st.floats(0.05, 3.0))
    tau = sigma * 4.0 * 10.0 ** draw(st.floats(0.0, 6.0))
    tau = draw(st.sampled_from([tau, tau, tau, 1e6, 1e154, 1e300]))
    f = draw(st.floats(200.0, 1500.0))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    X_cam = np.c_[rng.uniform(-1, 1, (n, 2)), rng.uniform(4, 6, n)]
    R = rotation(rng.normal(size=4))
    t = rng.normal(size=3)
    X = (X_cam - t) @ R  # x_cam = R X + t
    u = X_cam[:, :2] / X_cam[:, 2:] * f + [320, 240] + rng.normal(0, sigma, (n, 2))
    return pluecker.Camera.pinhole(f, f, 320, 240), f, u, X, sigma, tau


@given(clean_problems(), st.sampled_from(["point", "line"]), st.integers(0, 2**32 - 1))
def test_clean_data_succeeds_within_a_few_samples_for_any_threshold_above_the_noise(problem, which, seed):
    camera, f, u, X, sigma, tau = problem
    # The threshold of the points, or a line threshold as wide (there are no lines) beside the
    # default point threshold (4 px, or 4 σ if that is more).
    thresholds = {"point_threshold": tau} if which == "point" else \
        {"point_threshold": max(4.0, 4 * sigma), "line_threshold": tau}
    ransac = pluecker.RansacOptions(seed=seed, **thresholds)
    r = pluecker.estimate_pose(camera, u, X, options=pluecker.PoseOptions(ransac=ransac))
    report = r.details.ransac
    note(f"n {len(u)}, σ {sigma:.3g} px, {which} threshold {tau:.3g} px: {r.status}, {report.stop}, "
         f"{report.iterations} samples, {report.inliers} inliers")
    assert r.status == "success"
    assert report.stop == "confidence" and report.iterations <= FEW_SAMPLES
    # The pose: every point within 6 σ of its prediction (the estimate's own error is a fraction of σ
    # with at least 8 points), whatever the threshold was.
    x = X @ r.pose.rotation.T + r.pose.translation
    errors = np.linalg.norm(x[:, :2] / x[:, 2:] * f + [320, 240] - u, axis=1)
    assert np.all(x[:, 2] > 0) and np.max(errors) <= 6 * sigma
