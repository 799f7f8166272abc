"""Outlier observations in point and line tracks (issue 12 §4): ``TriangulationOptions(outlier_threshold=...)``
on the single call, the dense batch and the sparse one, with the inlier masks laid out as the input was."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import pluecker
from triangulation_scenes import cameras, project

ROBUST = pluecker.TriangulationOptions(outlier_threshold=4.0)


def tracks(n: int, views: int, seed: int):
    """n points near the origin seen by all views with 1 px noise, one 40 px outlier per track."""
    rng = np.random.default_rng(seed)
    P = cameras(views, 40.0, rng)
    X = rng.normal(scale=0.5, size=(n, 3))
    x = np.stack([project(P, p) for p in X]) + rng.normal(size=(n, views, 2))
    outlier = rng.integers(0, views, size=n)
    angle = rng.uniform(0, 2 * np.pi, size=n)
    x[np.arange(n), outlier] += 40 * np.column_stack([np.cos(angle), np.sin(angle)])
    return P, X, x, outlier


def test_single_call_rejects_the_outlier_and_certifies_the_rest():
    P, X, x, outlier = tracks(30, 8, 1)
    for k in range(30):
        r = pluecker.triangulate_point(P, x[k], options=ROBUST)
        assert r.status == "success" and r.certified
        assert r.inliers.shape == (8,) and not r.inliers[outlier[k]]
        kept = r.inliers
        alone = pluecker.triangulate_point(P[kept], x[k][kept])
        np.testing.assert_allclose(r.point, alone.point, atol=1e-9)
    assert pluecker.triangulate_point(P, x[0]).inliers is None


def test_dense_batch_masks_are_per_view_and_false_where_not_visible():
    P, X, x, outlier = tracks(40, 8, 2)
    visible = np.ones((40, 8), dtype=bool)
    visible[::5, 3] = False  # some tracks miss view 3
    r = pluecker.triangulate_points(P, x, visible=visible, options=ROBUST)
    assert r.inliers.shape == (40, 8) and r.inliers.dtype == bool
    assert not r.inliers[~visible].any()
    rejected = ~r.inliers[np.arange(40), outlier] | ~visible[np.arange(40), outlier]
    assert rejected.all()
    error = np.linalg.norm(r.point - X, axis=1)
    plain = np.linalg.norm(pluecker.triangulate_points(P, x, visible=visible).point - X, axis=1)
    assert np.sqrt(np.mean(error**2)) < 0.3 * np.sqrt(np.mean(plain**2))
    assert pluecker.triangulate_points(P, x).inliers is None
    again = pickle.loads(pickle.dumps(r))
    np.testing.assert_array_equal(again.inliers, r.inliers)
    assert r.to_dict()["inliers"] == r.inliers.tolist()


def test_sparse_batch_masks_follow_the_rows_as_given():
    P, X, x, outlier = tracks(25, 6, 3)
    track, image = np.meshgrid(np.arange(25), np.arange(6), indexing="ij")
    rows = np.random.default_rng(4).permutation(25 * 6)  # rows in any order
    t, i, px = track.ravel()[rows], image.ravel()[rows], x.reshape(-1, 2)[rows]
    r = pluecker.triangulate_points(P, px, track=t, image=i, options=ROBUST)
    assert r.inliers.shape == (150,)
    is_outlier = i == outlier[t]
    assert not r.inliers[is_outlier].any()
    dense = pluecker.triangulate_points(P, x, options=ROBUST)
    np.testing.assert_array_equal(r.inliers, dense.inliers[t, i])
    np.testing.assert_allclose(r.point, dense.point, atol=1e-9)


def test_threshold_is_checked_and_refused_for_quadrics():
    with pytest.raises(pluecker.InvalidOptionError, match="outlier_threshold"):
        pluecker.TriangulationOptions(outlier_threshold=-1.0)
    rng = np.random.default_rng(5)
    P = cameras(3, 30.0, rng)
    conics = np.tile(np.diag([1.0, 1.0, -100.0]), (3, 1, 1))
    with pytest.raises(pluecker.InvalidOptionError, match="points and lines"):
        pluecker.triangulate_quadric(P, conics, options=ROBUST)


def line_tracks_with_outliers(n: int, views: int, seed: int):
    """n segments near the origin seen by all views with 1 px endpoint noise; one view per track moved
    40 px across the segment."""
    rng = np.random.default_rng(seed)
    P = cameras(views, 40.0, rng)
    ends = rng.normal(scale=0.5, size=(n, 2, 3))
    segments = np.stack([np.stack([project(P, A), project(P, B)], axis=1) for A, B in ends])  # (n, v, 2, 2)
    segments = segments + rng.normal(size=segments.shape)
    outlier = rng.integers(0, views, size=n)
    for k in range(n):
        a, b = segments[k, outlier[k]]
        d = (b - a) / np.linalg.norm(b - a)
        segments[k, outlier[k]] += 40.0 * np.array([-d[1], d[0]])
    return P, ends, segments, outlier


def test_robust_lines_reject_the_outlier_views():
    P, ends, segments, outlier = line_tracks_with_outliers(20, 7, 8)
    options = pluecker.TriangulationOptions(outlier_threshold=4.0, method="local")
    batch = pluecker.triangulate_lines(P, segments, options=options)
    assert batch.inliers.shape == (20, 7)
    assert not batch.inliers[np.arange(20), outlier].any()
    single = pluecker.triangulate_line(P, segments[3], options=options)
    np.testing.assert_array_equal(single.inliers, batch.inliers[3])
    kept = single.inliers
    np.testing.assert_allclose(single.plucker, pluecker.triangulate_line(P[kept], segments[3][kept],
                                                                         options=pluecker.TriangulationOptions(method="local")).plucker, atol=1e-9)
    # Sparse rows in any order: the mask follows the rows as given.
    track, image = np.nonzero(np.ones((20, 7), dtype=bool))
    order = np.random.default_rng(9).permutation(len(track))
    track, image = track[order], image[order]
    sparse = pluecker.triangulate_lines(P, segments[track, image], track=track, image=image, options=options)
    np.testing.assert_array_equal(sparse.inliers, batch.inliers[track, image])
    assert pluecker.triangulate_lines(P, segments, options=pluecker.TriangulationOptions(method="local")).inliers is None


def test_too_few_inliers_is_a_status():
    # Two views whose rays meet behind both cameras: no pair gives a point in front, so no two
    # observations agree on one.
    rng = np.random.default_rng(6)
    P = cameras(2, 30.0, rng)
    centres = [-np.linalg.solve(p[:, :3], p[:, 3]) for p in P]
    behind = centres[0] + centres[1]  # beyond both cameras, seen from the origin
    x = np.array([p[:2] / p[2] for p in (P @ np.append(behind, 1.0))])
    r = pluecker.triangulate_point(P, x, options=ROBUST)
    assert r.status == "too_few_inliers" and not r.certified
    assert np.isnan(r.point).all() and not r.inliers.any()


def test_every_result_says_which_domain_its_certificate_covers():
    """Issue 13 §1: a point certificate covers every point in front of the cameras; a line or quadric
    one from branch and bound only its search domain, and the result says so."""
    rng = np.random.default_rng(11)
    P = cameras(3, 30.0, rng)
    x = project(P, np.zeros(3)) + rng.normal(size=(3, 2))
    point = pluecker.triangulate_point(P, x)
    assert point.certified and point.certificate.domain == "every point in front of every camera"
    assert pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method="local")).certificate is None
    P4, _, segments, _ = line_tracks_with_outliers(1, 4, 12)
    expected = {"none": "none", "convexity_test": "every line (a cost at the zero bound)",
                "taylor_branch_and_bound": "every line at least 1/100 of the estimate's distance from each camera "
                                           "centre, in front of the cameras or not"}
    for views in (2, 4):  # two views: the zero-cost certificate; four: the Taylor branch and bound
        line = pluecker.triangulate_line(P4[:views], segments[0][:views])
        domain = expected.get(line.certificate.kind)
        if line.certificate.kind == "branch_and_bound":
            assert "eq. 27 strip widths" in line.certificate.domain and "100 times" in line.certificate.domain
        else:
            assert line.certificate.domain == domain, (views, line.certificate.kind)
        assert line.to_dict()["certificate"]["domain"] == line.certificate.domain
    assert pluecker.triangulate_line(P4[:2], segments[0][:2]).certificate.kind == "convexity_test"
    assert pluecker.triangulate_line(P4, segments[0]).certificate.kind == "taylor_branch_and_bound"
    paper = pluecker.TriangulationOptions(line_bound="relaxation")
    line = pluecker.triangulate_line(P4, segments[0], options=paper)
    assert line.certificate.kind == "branch_and_bound" and "eq. 27 strip widths" in line.certificate.domain
