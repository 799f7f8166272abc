//! The line and quadric batches (`triangulation::line::batch`, `triangulation::quadric::batch`): every
//! track's result equals the single call's on its visible views (bit for bit: the same function on the
//! same numbers), a bad track is an error naming it and never loses the others, and whole-call errors.

use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3};
use pluecker::geometry::quadric::{project_dual, Ellipse};
use pluecker::rng::Rng;
use pluecker::triangulation::tracks::TrackCameras;
use pluecker::triangulation::fitting::fit_conic;
use pluecker::triangulation::line::{
    lines_from_segments, triangulate_line, triangulate_line_segments, LineTriangulation,
};
use pluecker::triangulation::line::batch::{triangulate_lines, ImageLines, LineTracks};
use pluecker::triangulation::quadric::{triangulate_quadric, Matrix5, QuadricTriangulation};
use pluecker::triangulation::quadric::batch::{triangulate_quadrics, QuadricTracks};
use pluecker::triangulation::scenes::{arc_cameras, quadric_scene};
use pluecker::triangulation::{Method, Status, TriangulationOptions};
use pluecker::Error;
use std::sync::atomic::{AtomicUsize, Ordering};

fn opts(method: Method) -> TriangulationOptions {
    // A node cap keeps branch and bound short; equality with the single call holds at any cap.
    TriangulationOptions {
        method,
        max_nodes: 40,
        ..Default::default()
    }
}

/// A result with its wall time zeroed: the one field a batch and a single call may not share.
fn untimed_line(mut r: LineTriangulation) -> LineTriangulation {
    r.report.time_seconds = 0.0;
    r
}

fn untimed_quadric(mut r: QuadricTriangulation) -> QuadricTriangulation {
    r.report.time_seconds = 0.0;
    r
}

fn project(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> Vector2<f64> {
    let u = p * x.push(1.0);
    u.xy() / u.z
}

/// `n` random segments near the origin seen by `cameras`, with 1 px endpoint noise: the flat
/// `(n, v, 2, 2)` endpoints.
fn noisy_segments(cameras: &[Matrix3x4<f64>], n: usize, rng: &mut Rng) -> Vec<f64> {
    let mut out = Vec::with_capacity(4 * n * cameras.len());
    for _ in 0..n {
        let mid = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2;
        let half = rng.unit_vector3() * rng.uniform_in(0.4, 0.8);
        for p in cameras {
            for end in [mid + half, mid - half] {
                let u = project(p, &end);
                out.extend([u.x + rng.normal(), u.y + rng.normal()]);
            }
        }
    }
    out
}

/// The visible views of track `t` under a flat `(n, v)` mask.
fn seen(visible: &[bool], v: usize, t: usize) -> Vec<usize> {
    (0..v).filter(|&j| visible[t * v + j]).collect()
}

fn segment(endpoints: &[f64], v: usize, t: usize, j: usize) -> [Vector2<f64>; 2] {
    let s = &endpoints[4 * (t * v + j)..][..4];
    [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])]
}

/// A random visibility mask with at least `min` views per track.
fn mask(n: usize, v: usize, min: usize, rng: &mut Rng) -> Vec<bool> {
    let mut visible = vec![false; n * v];
    for t in 0..n {
        let count = min + rng.below(v - min + 1);
        for j in rng.sample_indices(v, count) {
            visible[t * v + j] = true;
        }
    }
    visible
}

#[test]
fn line_batch_equals_single_calls_for_every_input_form() {
    let mut rng = Rng::new(11);
    let (n, v) = (6, 5);
    let cameras = arc_cameras(v, 0.8, &mut rng);
    let endpoints = noisy_segments(&cameras, n, &mut rng);
    let visible = mask(n, v, 2, &mut rng);
    let segments_of = |t: usize| -> Vec<[Vector2<f64>; 2]> {
        seen(&visible, v, t)
            .iter()
            .map(|&j| segment(&endpoints, v, t, j))
            .collect()
    };
    let cams_of = |t: usize| -> Vec<Matrix3x4<f64>> { seen(&visible, v, t).iter().map(|&j| cameras[j]).collect() };

    // Segments with endpoint noise, every method.
    for method in Method::ALL {
        let tracks = LineTracks {
            lines: ImageLines::Segments {
                endpoints: &endpoints,
                sigma: 1.5,
            },
            visible: Some(&visible),
            covariances: None,
        };
        let batch = triangulate_lines(TrackCameras::Shared(&cameras), &tracks, &opts(method), None).unwrap();
        assert_eq!(batch.len(), n);
        for (t, r) in batch.into_iter().enumerate() {
            let single = triangulate_line_segments(&cams_of(t), &segments_of(t), 1.5, &opts(method)).unwrap();
            assert_eq!(
                untimed_line(r.unwrap()),
                untimed_line(single),
                "{} track {t}",
                method.as_str()
            );
        }
    }

    // Homogeneous lines with covariances (a skewed one per observation), and segments whose
    // covariances are given: both replace the endpoint noise.
    let mut lines = Vec::new();
    let mut covariances = Vec::new();
    for k in 0..n * v {
        let s = segment(&endpoints, v, k / v, k % v);
        lines.extend(s[0].push(1.0).cross(&s[1].push(1.0)).iter());
        let a = Matrix2::new(1.0 + rng.uniform(), rng.normal(), 0.0, 1.0 + rng.uniform());
        covariances.extend((a * a.transpose()).transpose().iter());
    }
    let covs_of = |t: usize| -> Vec<Matrix2<f64>> {
        seen(&visible, v, t)
            .iter()
            .map(|&j| Matrix2::from_row_slice(&covariances[4 * (t * v + j)..][..4]))
            .collect()
    };
    let homogeneous = LineTracks {
        lines: ImageLines::Homogeneous(&lines),
        visible: Some(&visible),
        covariances: Some(&covariances),
    };
    let with_covariances = LineTracks {
        lines: ImageLines::Segments {
            endpoints: &endpoints,
            sigma: 1.0,
        },
        ..homogeneous
    };
    for tracks in [homogeneous, with_covariances] {
        let batch = triangulate_lines(TrackCameras::Shared(&cameras), &tracks, &opts(Method::Local), None).unwrap();
        for (t, r) in batch.into_iter().enumerate() {
            let (image, _) = lines_from_segments(&segments_of(t), 1.0).unwrap();
            let single = triangulate_line(&cams_of(t), &image, Some(&covs_of(t)), &opts(Method::Local)).unwrap();
            let r = untimed_line(r.unwrap());
            // The homogeneous lines are the segments' lines up to scale and sign, which the residual
            // ignores (section 3.1 normalises each line): the same line to rounding (Plücker
            // coordinates are homogeneous: up to sign), and the same cost (about 1 per observation; 0
            // to rounding for a track in two views, which fit any line exactly).
            let distance = (r.plucker.coordinates() - single.plucker.coordinates())
                .norm()
                .min((r.plucker.coordinates() + single.plucker.coordinates()).norm());
            assert!(distance < 1e-9, "track {t}: {distance}");
            let tolerance = 1e-9 * single.report.cost + 1e-12;
            assert!((r.report.cost - single.report.cost).abs() <= tolerance, "track {t}");
        }
    }
}

#[test]
fn line_batch_with_cameras_per_track_and_progress() {
    let mut rng = Rng::new(12);
    let (n, v) = (4, 3);
    let mut cameras = Vec::new();
    let mut endpoints = Vec::new();
    for _ in 0..n {
        let own = arc_cameras(v, 0.6, &mut rng);
        endpoints.extend(noisy_segments(&own, 1, &mut rng));
        cameras.extend(own);
    }
    let tracks = LineTracks {
        lines: ImageLines::Segments {
            endpoints: &endpoints,
            sigma: 1.0,
        },
        visible: None,
        covariances: None,
    };
    let done = AtomicUsize::new(0);
    let per_track = TrackCameras::PerTrack {
        cameras: &cameras,
        views: v,
    };
    let batch = triangulate_lines(per_track, &tracks, &opts(Method::Local), Some(&done)).unwrap();
    assert_eq!(done.load(Ordering::Relaxed), n);
    for (t, r) in batch.into_iter().enumerate() {
        let segments: Vec<[Vector2<f64>; 2]> = (0..v).map(|j| segment(&endpoints, v, t, j)).collect();
        let single =
            triangulate_line_segments(&cameras[t * v..(t + 1) * v], &segments, 1.0, &opts(Method::Local)).unwrap();
        assert_eq!(untimed_line(r.unwrap()), untimed_line(single), "track {t}");
    }
    // A singular camera of one track is that track's error, named by track and view.
    let mut bad = cameras.clone();
    bad[2 * v + 1] = Matrix3x4::zeros();
    let per_track = TrackCameras::PerTrack {
        cameras: &bad,
        views: v,
    };
    let batch = triangulate_lines(per_track, &tracks, &opts(Method::Linear), None).unwrap();
    assert!(matches!(&batch[2], Err(Error::SingularCamera { what }) if what.starts_with("cameras[2][1]")));
    assert!(batch.iter().enumerate().all(|(t, r)| r.is_ok() == (t != 2)));
}

#[test]
fn a_bad_line_track_is_its_own_error_and_never_loses_the_others() {
    let mut rng = Rng::new(13);
    let (n, v) = (8, 4);
    let cameras = arc_cameras(v, 0.8, &mut rng);
    let endpoints = noisy_segments(&cameras, n, &mut rng);
    let mut lines: Vec<f64> = (0..n * v)
        .flat_map(|k| {
            let s = segment(&endpoints, v, k / v, k % v);
            s[0].push(1.0)
                .cross(&s[1].push(1.0))
                .iter()
                .copied()
                .collect::<Vec<_>>()
        })
        .collect();
    let mut visible = vec![true; n * v];
    let mut covariances: Vec<f64> = (0..n * v).flat_map(|_| [1.0, 0.0, 0.0, 1.0]).collect();
    // Track 1: NaN in visible view 2. Track 2: NaN in a view it is not seen in (fine).
    lines[3 * (v + 2)] = f64::NAN;
    lines[3 * (2 * v + 3) + 1] = f64::NAN;
    visible[2 * v + 3] = false;
    // Track 3: one visible view.
    for j in 1..v {
        visible[3 * v + j] = false;
    }
    // Track 4: the line at infinity (zero normal) in view 1.
    lines[3 * (4 * v + 1)..3 * (4 * v + 1) + 3].copy_from_slice(&[0.0, 0.0, 1.0]);
    // Track 5: a covariance that is not positive definite in view 3.
    covariances[4 * (5 * v + 3)..4 * (5 * v + 3) + 4].copy_from_slice(&[1.0, 2.0, 2.0, 1.0]);
    // Track 6: seen by views 0 and 1 only, the 3-D line parallel to their baseline: it lies in an
    // epipolar plane of the pair, both back-projected planes are that plane.
    let (c0, c1) = (centre(&cameras[0]), centre(&cameras[1]));
    let a = (c0 + c1) / 2.0 + (c1 - c0).cross(&Vector3::y()).normalize() * 4.0;
    let b = a + (c1 - c0);
    for j in 0..v {
        visible[6 * v + j] = j < 2;
        let l = (cameras[j] * a.push(1.0)).cross(&(cameras[j] * b.push(1.0)));
        lines[3 * (6 * v + j)..3 * (6 * v + j) + 3].copy_from_slice(l.as_slice());
    }
    let tracks = LineTracks {
        lines: ImageLines::Homogeneous(&lines),
        visible: Some(&visible),
        covariances: Some(&covariances),
    };
    let batch = triangulate_lines(TrackCameras::Shared(&cameras), &tracks, &opts(Method::Local), None).unwrap();
    assert!(matches!(&batch[1], Err(Error::NonFinite { what, index: 2 }) if what == "lines[1]"));
    assert!(matches!(&batch[3], Err(Error::TooFewCorrespondences { actual, .. }) if actual == "track 3: 1 view(s)"));
    assert!(matches!(&batch[4], Err(Error::Degenerate { what }) if what.starts_with("lines[4][1] has a zero normal")));
    assert!(
        matches!(&batch[5], Err(Error::Degenerate { what }) if what == "covariances[5][3] is not positive definite")
    );
    assert!(
        matches!(&batch[6], Err(Error::Degenerate { what }) if what.starts_with("lines[6]: the back-projected planes coincide")),
        "{:?}",
        batch[6]
    );
    for t in [0, 2, 7] {
        let r = batch[t].as_ref().unwrap();
        assert_eq!(r.report.status, Status::Success, "track {t}");
        let views = seen(&visible, v, t);
        let cams: Vec<Matrix3x4<f64>> = views.iter().map(|&j| cameras[j]).collect();
        let image: Vec<Vector3<f64>> = views
            .iter()
            .map(|&j| Vector3::from_row_slice(&lines[3 * (t * v + j)..][..3]))
            .collect();
        let covs = vec![Matrix2::identity(); views.len()];
        let single = triangulate_line(&cams, &image, Some(&covs), &opts(Method::Local)).unwrap();
        assert_eq!(untimed_line(r.clone()), untimed_line(single), "track {t}");
    }

    // Segments: NaN and a zero-length segment name the segment.
    let mut endpoints = endpoints.clone();
    endpoints[4 * (2 * v + 1) + 3] = f64::INFINITY;
    let p = &endpoints[4 * 5 * v..][..2].to_vec();
    endpoints[4 * 5 * v + 2..4 * 5 * v + 4].copy_from_slice(p);
    let tracks = LineTracks {
        lines: ImageLines::Segments {
            endpoints: &endpoints,
            sigma: 1.0,
        },
        visible: None,
        covariances: None,
    };
    let batch = triangulate_lines(TrackCameras::Shared(&cameras), &tracks, &opts(Method::Linear), None).unwrap();
    assert!(matches!(&batch[2], Err(Error::NonFinite { what, index: 1 }) if what == "segments[2]"));
    assert!(matches!(&batch[5], Err(Error::Degenerate { what }) if what == "segments[5][0] has zero length"));
    assert_eq!(batch.iter().filter(|r| r.is_ok()).count(), n - 2);
}

fn centre(p: &Matrix3x4<f64>) -> Vector3<f64> {
    let m = p.fixed_view::<3, 3>(0, 0).into_owned();
    -(m.try_inverse().unwrap() * p.column(3))
}

#[test]
fn line_batch_whole_call_errors() {
    let mut rng = Rng::new(14);
    let cameras = arc_cameras(3, 0.8, &mut rng);
    let endpoints = noisy_segments(&cameras, 2, &mut rng);
    let shared = TrackCameras::Shared(&cameras);
    let o = opts(Method::Linear);
    let run = |tracks: &LineTracks, o: &TriangulationOptions| triangulate_lines(shared, tracks, o, None).unwrap_err();
    let tracks = |sigma| LineTracks {
        lines: ImageLines::Segments {
            endpoints: &endpoints,
            sigma,
        },
        visible: None,
        covariances: None,
    };
    assert!(matches!(run(&tracks(0.0), &o), Error::InvalidOption { name, .. } if name == "sigma"));
    assert!(matches!(run(&tracks(f64::NAN), &o), Error::InvalidOption { name, .. } if name == "sigma"));
    let bad = TriangulationOptions {
        max_nodes: 0,
        ..o.clone()
    };
    assert!(matches!(run(&tracks(1.0), &bad), Error::InvalidOption { name, .. } if name == "max_nodes"));
    let short = LineTracks {
        lines: ImageLines::Homogeneous(&endpoints[..8]),
        ..tracks(1.0)
    };
    assert!(matches!(run(&short, &o), Error::Shape { what, .. } if what == "lines"));
    let flags = [true; 5];
    let masked = LineTracks {
        visible: Some(&flags),
        ..tracks(1.0)
    };
    assert!(matches!(run(&masked, &o), Error::Shape { what, .. } if what == "visible"));
    let covs = [1.0; 8];
    let covariances = LineTracks {
        covariances: Some(&covs),
        ..tracks(1.0)
    };
    assert!(matches!(run(&covariances, &o), Error::Shape { what, .. } if what == "covariances"));
    let mut singular = cameras.clone();
    singular[1][(0, 0)] = f64::NAN;
    assert!(matches!(
        triangulate_lines(TrackCameras::Shared(&singular), &tracks(1.0), &o, None),
        Err(Error::NonFinite { what, index: 1 }) if what == "cameras"
    ));
    let per_track = TrackCameras::PerTrack {
        cameras: &cameras,
        views: 3,
    };
    assert!(matches!(
        triangulate_lines(per_track, &tracks(1.0), &o, None),
        Err(Error::Shape { what, .. }) if what == "cameras"
    ));
    let empty = LineTracks {
        lines: ImageLines::Homogeneous(&[]),
        ..tracks(1.0)
    };
    assert!(triangulate_lines(shared, &empty, &o, None).unwrap().is_empty());
}

/// Conics fitted to 63 outline points with 1 px noise, and their covariances, of an ellipsoid seen by
/// `cameras`: the flat `(v, 3, 3)` and `(v, 5, 5)` entries of one track.
fn fitted_outlines(cameras: &[Matrix3x4<f64>], dual: &nalgebra::Matrix4<f64>, rng: &mut Rng) -> (Vec<f64>, Vec<f64>) {
    let (mut conics, mut covariances) = (Vec::new(), Vec::new());
    for p in cameras {
        let outline = Ellipse::from_primal(&project_dual(p, dual).try_inverse().unwrap()).unwrap();
        let points: Vec<Vector2<f64>> = outline
            .sample(63, rng.uniform_in(0.0, 6.3))
            .into_iter()
            .map(|x| x + Vector2::new(rng.normal(), rng.normal()))
            .collect();
        let fit = fit_conic(&points, 1.0).unwrap();
        conics.extend(fit.conic.transpose().iter());
        covariances.extend(fit.covariance.transpose().iter());
    }
    (conics, covariances)
}

#[test]
fn quadric_batch_equals_single_calls_with_shared_and_per_track_cameras() {
    let mut rng = Rng::new(15);
    let (n, v) = (4, 5);
    let cameras = quadric_scene(v, 0.8, 1).cameras;
    let (mut conics, mut covariances) = (Vec::new(), Vec::new());
    for k in 0..n {
        let e = quadric_scene(v, 0.8, 20 + k as u64).ellipsoid;
        let (c, s) = fitted_outlines(&cameras, &e.dual(), &mut rng);
        conics.extend(c);
        covariances.extend(s);
    }
    let visible = mask(n, v, 3, &mut rng);
    let single = |cams: &[Matrix3x4<f64>], t: usize, views: &[usize], method| {
        let c: Vec<Matrix3<f64>> = views
            .iter()
            .map(|&j| Matrix3::from_row_slice(&conics[9 * (t * v + j)..][..9]))
            .collect();
        let s: Vec<Matrix5> = views
            .iter()
            .map(|&j| Matrix5::from_row_slice(&covariances[25 * (t * v + j)..][..25]))
            .collect();
        triangulate_quadric(cams, &c, Some(&s), &opts(method)).unwrap()
    };
    for method in Method::ALL {
        let tracks = QuadricTracks {
            conics: &conics,
            visible: Some(&visible),
            covariances: Some(&covariances),
        };
        let batch = triangulate_quadrics(TrackCameras::Shared(&cameras), &tracks, &opts(method), None).unwrap();
        for (t, r) in batch.into_iter().enumerate() {
            let views = seen(&visible, v, t);
            let cams: Vec<Matrix3x4<f64>> = views.iter().map(|&j| cameras[j]).collect();
            let expected = untimed_quadric(single(&cams, t, &views, method));
            assert_eq!(untimed_quadric(r.unwrap()), expected, "{} track {t}", method.as_str());
        }
    }
    // The same conics with every track's cameras given per track (here the shared ones, repeated,
    // with track 1's scaled: a camera's scale does not matter).
    let mut per_track: Vec<Matrix3x4<f64>> = (0..n).flat_map(|_| cameras.iter().copied()).collect();
    for p in &mut per_track[v..2 * v] {
        *p *= -3.0;
    }
    let tracks = QuadricTracks {
        conics: &conics,
        visible: None,
        covariances: Some(&covariances),
    };
    let done = AtomicUsize::new(0);
    let cams = TrackCameras::PerTrack {
        cameras: &per_track,
        views: v,
    };
    let batch = triangulate_quadrics(cams, &tracks, &opts(Method::Local), Some(&done)).unwrap();
    assert_eq!(done.load(Ordering::Relaxed), n);
    let all: Vec<usize> = (0..v).collect();
    for (t, r) in batch.into_iter().enumerate() {
        let expected = untimed_quadric(single(&per_track[t * v..(t + 1) * v], t, &all, Method::Local));
        assert_eq!(untimed_quadric(r.unwrap()), expected, "track {t}");
    }
}

#[test]
fn a_bad_quadric_track_is_its_own_error_and_never_loses_the_others() {
    let mut rng = Rng::new(16);
    let (n, v) = (6, 4);
    let cameras = quadric_scene(v, 0.8, 2).cameras;
    let (mut conics, mut covariances) = (Vec::new(), Vec::new());
    for k in 0..n {
        let e = quadric_scene(v, 0.8, 40 + k as u64).ellipsoid;
        let (c, s) = fitted_outlines(&cameras, &e.dual(), &mut rng);
        conics.extend(c);
        covariances.extend(s);
    }
    let mut visible = vec![true; n * v];
    // Track 1: NaN in visible view 3. Track 2: two visible views. Track 3: a hyperbola in view 0.
    // Track 4: a covariance that is not positive definite in view 2.
    conics[9 * (v + 3) + 4] = f64::NAN;
    visible[2 * v] = false;
    visible[2 * v + 1] = false;
    conics[9 * 3 * v..9 * 3 * v + 9].copy_from_slice(&[1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -100.0]);
    covariances[25 * (4 * v + 2) + 24] = -1.0;
    let tracks = QuadricTracks {
        conics: &conics,
        visible: Some(&visible),
        covariances: Some(&covariances),
    };
    let batch = triangulate_quadrics(TrackCameras::Shared(&cameras), &tracks, &opts(Method::Local), None).unwrap();
    assert!(matches!(&batch[1], Err(Error::NonFinite { what, index: 3 }) if what == "conics[1]"));
    assert!(
        matches!(&batch[2], Err(Error::TooFewCorrespondences { required, actual, .. }) if required.starts_with('3') && actual == "track 2: 2 view(s)")
    );
    assert!(matches!(&batch[3], Err(Error::Degenerate { what }) if what == "conics[3][0] is not a real ellipse"));
    assert!(matches!(&batch[4], Err(Error::Degenerate { what }) if what.starts_with("covariances[4][2]")));
    for t in [0, 5] {
        let r = batch[t].as_ref().unwrap();
        assert_eq!(r.report.status, Status::Success, "track {t}");
    }
    // Whole-call errors: lengths that do not fit.
    let short = QuadricTracks {
        conics: &conics[..10],
        visible: None,
        covariances: None,
    };
    let o = opts(Method::Linear);
    assert!(matches!(
        triangulate_quadrics(TrackCameras::Shared(&cameras), &short, &o, None),
        Err(Error::Shape { what, .. }) if what == "conics"
    ));
    let covs = QuadricTracks {
        covariances: Some(&covariances[..25]),
        ..tracks
    };
    assert!(matches!(
        triangulate_quadrics(TrackCameras::Shared(&cameras), &covs, &o, None),
        Err(Error::Shape { what, .. }) if what == "covariances"
    ));
    assert!(matches!(
        triangulate_quadrics(TrackCameras::Shared(&[]), &tracks, &o, None),
        Err(Error::Shape { what, .. }) if what == "cameras"
    ));
}
