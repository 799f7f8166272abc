//! The forms of input of the triangulation functions: every pairing of cameras (projections or views)
//! and observations (dense or rows tracks; lines or segments; conics or edge points) either gives the
//! answer of the equivalent form, bit for bit (but for `time_seconds`), or is refused as a whole call
//! naming the argument.

use crate::common::{outlines, segment_tracks};
use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3};
use pluecker::camera::{Camera, CameraModel};
use pluecker::rng::Rng;
use pluecker::triangulation::line::{triangulate_line, triangulate_lines, LineObservations, SparseLineTracks};
use pluecker::triangulation::point::{triangulate_points, DensePointTracks, SparsePointTracks};
use pluecker::triangulation::quadric::{triangulate_quadric, triangulate_quadrics, DenseQuadricTracks};
use pluecker::triangulation::scenes::{line_scene, quadric_scene};
use pluecker::triangulation::{Csr, Method, TrackCameras, TriangulationOptions, View};
use pluecker::{Error, Pose};

fn opts(method: Method) -> TriangulationOptions {
    let mut o = TriangulationOptions::default();
    o.method = method;
    o.certify.max_nodes = Some(200);
    o
}

/// `r` with its time zeroed (the only field that differs between equivalent calls).
fn untimed<T: std::fmt::Debug>(r: &T) -> String {
    let s = format!("{r:?}");
    let mut out = String::new();
    let mut rest = s.as_str();
    while let Some(i) = rest.find("time_seconds: ") {
        out.push_str(&rest[..i + 14]);
        rest = &rest[i + 14..];
        rest = &rest[rest.find([',', ' ', '}']).unwrap_or(rest.len())..];
    }
    out + rest
}

fn lens_views(v: usize) -> (Camera, Vec<View>) {
    let lens = Camera::new(CameraModel::SimpleRadial, &[800.0, 320.0, 240.0, -0.1]).unwrap();
    let views = (0..v)
        .map(|j| {
            let t = Vector3::new(-0.5 * j as f64, 0.1 * j as f64, 4.0);
            View::new(lens.clone(), Pose::new(Matrix3::identity(), t))
        })
        .collect();
    (lens, views)
}

#[test]
fn dense_point_tracks_through_views_are_the_rows_form_of_the_same_observations() {
    let (lens, views) = lens_views(3);
    let mut rng = Rng::new(3);
    let points: Vec<Vector3<f64>> = (0..4).map(|_| rng.unit_vector3() * 0.3).collect();
    let dense: Vec<f64> = points
        .iter()
        .flat_map(|x| {
            let pixels: Vec<f64> = views
                .iter()
                .flat_map(|v| {
                    let u = lens.project(&(v.pose.rotation * x + v.pose.translation));
                    [u.x + 0.3, u.y - 0.2]
                })
                .collect();
            pixels
        })
        .collect();
    let image: Vec<usize> = (0..4).flat_map(|_| 0..3).collect();
    let offsets: Vec<usize> = (0..=4).map(|t| 3 * t).collect();
    for method in Method::ALL {
        let tracks = DensePointTracks {
            observations: &dense,
            visible: None,
            covariances: None,
        };
        let rows = SparsePointTracks {
            csr: Csr {
                offsets: &offsets,
                image: &image,
            },
            observations: &dense,
            covariances: None,
        };
        let a = triangulate_points(&views, tracks, &opts(*method), None).unwrap();
        let b = triangulate_points(&views, rows, &opts(*method), None).unwrap();
        assert_eq!(untimed(&a), untimed(&b), "{method:?}");
        assert!(a.iter().all(|r| r.is_ok()));
    }
}

#[test]
fn segments_with_a_noise_through_views_are_segments_with_endpoint_covariances_sigma_squared() {
    let (lens, views) = lens_views(3);
    let (a, b) = (Vector3::new(-0.3, -0.4, 0.5), Vector3::new(0.4, 0.3, -0.2));
    let segments: Vec<[Vector2<f64>; 2]> = views
        .iter()
        .map(|v| {
            let image = |x: &Vector3<f64>| lens.project(&(v.pose.rotation * x + v.pose.translation));
            [image(&a), image(&b) + Vector2::new(0.3, 0.1)]
        })
        .collect();
    let sigma = 1.5;
    let covariances = vec![[Matrix2::identity() * (sigma * sigma); 2]; 3];
    for method in [Method::Linear, Method::Local] {
        let with_sigma = triangulate_line(&views, LineObservations::Segments(&segments, sigma), &opts(method));
        let with_covariances = triangulate_line(
            &views,
            LineObservations::SegmentEndpoints(&segments, Some(&covariances)),
            &opts(method),
        );
        assert_eq!(untimed(&with_sigma), untimed(&with_covariances));
        assert!(with_sigma.is_ok());
    }
    let bad = triangulate_line(
        &views,
        LineObservations::Segments(&segments, -1.0),
        &opts(Method::Local),
    );
    assert!(
        matches!(bad, Err(Error::InvalidOption { ref name, .. }) if name == "sigma"),
        "{bad:?}"
    );
}

#[test]
fn line_inputs_that_the_cameras_cannot_see_are_refused_naming_the_argument() {
    let scene = line_scene(3, 0.8, 2);
    let (_, views) = lens_views(3);
    let lines: Vec<Vector3<f64>> = scene
        .segments
        .iter()
        .map(|s| Vector3::new(s[0].x, s[0].y, 1.0).cross(&Vector3::new(s[1].x, s[1].y, 1.0)))
        .collect();
    let o = opts(Method::Local);
    let refused = triangulate_line(&views, &lines, &o);
    assert!(
        matches!(refused, Err(Error::InvalidOption { ref name, .. }) if name == "lines"),
        "{refused:?}"
    );
    let refused = triangulate_line(
        &scene.cameras,
        LineObservations::SegmentEndpoints(&scene.segments, None),
        &o,
    );
    assert!(
        matches!(refused, Err(Error::InvalidOption { ref name, .. }) if name == "covariances"),
        "{refused:?}"
    );
    // Batches: views see rows of segments only; rows index shared cameras.
    let endpoints: Vec<f64> = scene
        .segments
        .iter()
        .flat_map(|s| [s[0].x, s[0].y, s[1].x, s[1].y])
        .collect();
    let refused = triangulate_lines(&views, segment_tracks(&endpoints, 1.0), &o, None);
    assert!(
        matches!(refused, Err(Error::InvalidOption { ref name, .. }) if name == "cameras"),
        "{refused:?}"
    );
    let rows = SparseLineTracks {
        csr: Csr {
            offsets: &[0, 3],
            image: &[0, 1, 2],
        },
        lines: pluecker::triangulation::line::ImageLines::Segments {
            endpoints: &endpoints,
            sigma: 1.0,
        },
        covariances: None,
    };
    let per_track = TrackCameras::PerTrack {
        projections: &scene.cameras,
        views: 3,
    };
    let refused = triangulate_lines(per_track, rows, &o, None);
    assert!(
        matches!(refused, Err(Error::InvalidOption { ref name, .. }) if name == "cameras"),
        "{refused:?}"
    );
    // The same rows with shared projections are solved.
    let solved = triangulate_lines(&scene.cameras, rows, &o, None).unwrap();
    assert!(solved[0].is_ok());
}

#[test]
fn a_quadric_batch_through_pinhole_views_is_the_batch_of_their_projections() {
    let scene = quadric_scene(3, 0.8, 5);
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0).unwrap();
    let views: Vec<View> = (0..3)
        .map(|j| {
            View::new(
                camera.clone(),
                Pose::new(Matrix3::identity(), Vector3::new(-0.5 * j as f64, 0.0, 4.0)),
            )
        })
        .collect();
    let projections: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect();
    let conics = outlines(&projections, &scene.ellipsoid);
    let flat: Vec<f64> = conics.iter().flat_map(|c| c.transpose().as_slice().to_vec()).collect();
    let tracks = DenseQuadricTracks {
        conics: &flat,
        visible: None,
        covariances: None,
    };
    let o = opts(Method::Local);
    let a = triangulate_quadrics(&views, tracks, &o, None).unwrap();
    let b = triangulate_quadrics(&projections, tracks, &o, None).unwrap();
    assert_eq!(untimed(&a), untimed(&b));
    let single = triangulate_quadric(&views, &conics, &o).unwrap();
    assert_eq!(untimed(&a[0].as_ref().unwrap()), untimed(&single));
    // A distorting lens is refused for the whole batch, naming the camera.
    let (_, lenses) = lens_views(3);
    let refused = triangulate_quadrics(&lenses, tracks, &o, None);
    assert!(
        matches!(refused, Err(Error::InvalidOption { ref name, .. }) if name == "cameras"),
        "{refused:?}"
    );
}
