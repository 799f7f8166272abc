"""Line and quadric tracks given one observation per row (issue 12 §3): the same answers as the dense
batches, whatever the order of the rows, with bad tracks named and the others kept."""

from __future__ import annotations

import numpy as np
import pytest
from triangulation_scenes import NODES, cameras, ellipsoid, line_tracks, outlines, random_visibility

import pluecker


def rows_of(visible: np.ndarray, rng: np.random.Generator):
    """The (track, image) pairs of a visibility mask, in a random order."""
    track, image = np.nonzero(visible)
    order = rng.permutation(len(track))
    return track[order], image[order]


@pytest.mark.parametrize("method", ["local", "optimal"])
def test_sparse_lines_equal_the_dense_batch(method, seed):
    P, segments = line_tracks(seed)
    rng = np.random.default_rng(seed)
    visible = random_visibility(rng, len(segments), 4, 2)
    options = pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=NODES))
    dense = pluecker.triangulate_lines(P, np.where(visible[..., None, None], segments, np.nan), visible,
                                       sigma=1.5, options=options)
    # Rows in the dense order (by track, then image): each track's views in the same order, the same
    # numbers, the same answer to rounding.
    track, image = np.nonzero(visible)
    sparse = pluecker.triangulate_lines(P, segments[track, image], track=track, image=image, sigma=1.5, options=options)
    np.testing.assert_allclose(sparse.plucker, dense.plucker, atol=1e-12)
    np.testing.assert_array_equal(sparse.status, dense.status)
    np.testing.assert_array_equal(sparse.certified, dense.certified)
    np.testing.assert_allclose(sparse.cost, dense.cost, rtol=1e-12, atol=1e-15)
    # Rows in any order: a track's views come in another order, and the minimiser, which stops on a step
    # of 1e-10, lands within its tolerance (differences of 1e-9 were seen; 1e-6 allows 1000x that).
    track, image = rows_of(visible, rng)
    shuffled = pluecker.triangulate_lines(P, segments[track, image], track=track, image=image, sigma=1.5, options=options)
    np.testing.assert_allclose(shuffled.plucker, dense.plucker, atol=1e-6)
    np.testing.assert_array_equal(shuffled.status, dense.status)
    # Homogeneous lines with covariances, too.
    track, image = np.nonzero(visible)
    homogeneous = np.concatenate([segments, np.ones(segments.shape[:-1] + (1,))], axis=-1)
    lines = np.cross(homogeneous[..., 0, :], homogeneous[..., 1, :])
    cov = np.tile(np.diag([2.0, 0.5]), lines.shape[:2] + (1, 1))
    dense = pluecker.triangulate_lines(P, lines, visible, cov, options=pluecker.TriangulationOptions(method="local"))
    sparse = pluecker.triangulate_lines(P, lines[track, image], covariances=cov[track, image], track=track, image=image, options=pluecker.TriangulationOptions(method="local"))
    np.testing.assert_allclose(sparse.plucker, dense.plucker, atol=1e-12)


def test_sparse_quadrics_equal_the_dense_batch(seed):
    rng = np.random.default_rng(seed)
    n, views = 5, 5
    P = cameras(views, 60.0, rng)
    conics = np.stack([outlines(P, ellipsoid(rng)[3]) for _ in range(n)])
    conics += rng.normal(0.0, 1e-9, conics.shape) * np.abs(conics)
    visible = random_visibility(rng, n, views, 3)
    dense = pluecker.triangulate_quadrics(P, conics, visible, options=pluecker.TriangulationOptions(method="local"))
    track, image = rows_of(visible, rng)
    sparse = pluecker.triangulate_quadrics(P, conics[track, image], track=track, image=image, options=pluecker.TriangulationOptions(method="local"))
    np.testing.assert_allclose(sparse.Q, dense.Q, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(sparse.status, dense.status)


def test_bad_rows_stay_in_their_track(seed):
    P, segments = line_tracks(seed, n=6)
    visible = np.ones((6, 4), dtype=bool)
    track, image = np.nonzero(visible)
    rows = segments[track, image]
    image = image.copy()
    image[np.flatnonzero(track == 2)[0]] = 9  # beyond the 4 cameras
    rows[np.flatnonzero(track == 4)[1], 0, 0] = np.nan
    batch = pluecker.triangulate_lines(P, rows, track=track, image=image, options=pluecker.TriangulationOptions(method="local"), n_tracks=7)
    assert len(batch) == 7 and batch.status[6] == "too_few_views"  # a track id without rows
    assert batch.status[2] == "invalid_input" and "image[8]: expected an image index below 4" in batch.messages[2]
    assert batch.status[4] == "non_finite", batch.messages[4]
    assert all(batch.status[i] == "success" for i in (0, 1, 3, 5))
    with pytest.raises(pluecker.ShapeError, match="lines"):
        pluecker.triangulate_lines(P, rows[:, 0], track=track, image=image)
    with pytest.raises(pluecker.ShapeError, match="covariances"):
        pluecker.triangulate_lines(P, rows, covariances=np.ones((3, 2, 2)), track=track, image=image)
    with pytest.raises(pluecker.InvalidOptionError, match="n_tracks"):
        pluecker.triangulate_lines(P, rows, track=track, image=image, n_tracks=3)
    with pytest.raises(pluecker.InvalidOptionError, match="outlier_threshold"):
        pluecker.triangulate_quadrics(P, np.tile(np.eye(3), (len(track), 1, 1)), track=track, image=image, options=pluecker.TriangulationOptions(outlier_threshold=4.0))


@pytest.mark.parametrize("function", [pluecker.triangulate_points, pluecker.triangulate_lines,
                                      pluecker.triangulate_quadrics])
def test_the_rows_form_takes_track_and_image_together_and_no_mask(function):
    """One batch function per primitive takes both forms: ``track=`` and ``image=`` together select the rows
    form, whose rows list only what is seen; an argument of the other form is named, not ignored."""
    P = cameras(3, 10.0, np.random.default_rng(0))
    data = np.zeros((3, 2)) if function is pluecker.triangulate_points else np.zeros((3, 3, 3))
    rows = {"track": [0, 0, 0], "image": [0, 1, 2]}
    cases = [({"track": rows["track"]}, "image"), ({"image": rows["image"]}, "track"),
             ({**rows, "visible": np.ones((1, 3), bool)}, "visible"), ({"n_tracks": 1}, "n_tracks")]
    if function is not pluecker.triangulate_quadrics:
        # Views take the rows form: in the dense form they are named.
        views = [pluecker.View.from_projection(p) for p in P]
        with pytest.raises(pluecker.InvalidOptionError, match=r"^cameras: views take the rows form"):
            function(views, data)
    for kwargs, name in cases:
        with pytest.raises(pluecker.InvalidOptionError, match=rf"^{name}\b"):
            function(P, data, **kwargs)
