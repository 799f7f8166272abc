//! Stopping long calls (`pluecker::interrupt`): batches reject the tracks they had not started and
//! keep the others, branch and bound ends with an honest bound and status `Interrupted`, the RANSAC
//! loop and the pose certificate stop at their next poll.

use crate::common;

use common::{noisy_segments, project, segment_tracks};
use nalgebra::{Matrix3x4, Vector2, Vector3};
use pluecker::interrupt::{with_stop, Stop, StopReason};
use pluecker::pose::{estimate_pose, CertifyOptions, PoseOptions, RansacOptions, RansacStop};
use pluecker::rng::Rng;
use pluecker::synthetic::{random_scene, SceneKind};
use pluecker::triangulation::line::triangulate_lines;
use pluecker::triangulation::line::{lines_from_segments, triangulate_line, LineObservations};
use pluecker::triangulation::point::{triangulate_points, DensePointTracks, LinearPoints};
use pluecker::triangulation::scenes::arc_cameras;
use pluecker::triangulation::{LineBound, Method, Status, TriangulationOptions};
use pluecker::Error;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Barrier};
use std::time::Duration;

/// `n` noisy segments (2 px) seen by 4 cameras: flat `(n, v, 2, 2)` endpoints.
fn segments(n: usize, seed: u64) -> (Vec<Matrix3x4<f64>>, Vec<f64>) {
    let mut rng = Rng::new(seed);
    let cameras = arc_cameras(4, 0.5, &mut rng);
    let endpoints = noisy_segments(&cameras, n, 2.0, &mut rng);
    (cameras, endpoints)
}

/// Branch and bound to a 1e-9 gap with the paper's relaxation: minutes per line, unless stopped (the
/// default Taylor bound closes this gap in milliseconds).
fn endless() -> TriangulationOptions {
    let mut options = TriangulationOptions::default();
    options.method = Method::Optimal;
    options.certify.max_relative_gap = 1e-9;
    options.certify.max_nodes = Some(usize::MAX);
    options.line_bound = LineBound::Relaxation;
    options
}

/// A stop that another thread requests once the first poll has been reached, and that thread: the
/// poll blocks on a barrier until the requester is there, so the request comes after that poll
/// (whose track or node goes ahead) whatever the timing.
fn requested_after_poll(k: usize) -> (Arc<Stop>, std::thread::JoinHandle<()>) {
    let barrier = Arc::new(Barrier::new(2));
    let polls = AtomicUsize::new(0);
    let at_poll = Arc::clone(&barrier);
    let stop = Arc::new(Stop::new().with_check(move || {
        if polls.fetch_add(1, Ordering::Relaxed) + 1 == k {
            at_poll.wait();
        }
        false
    }));
    let requester = Arc::clone(&stop);
    let thread = std::thread::spawn(move || {
        barrier.wait();
        requester.request();
    });
    (stop, thread)
}

#[test]
fn a_request_from_another_thread_stops_a_line_batch() {
    // One track more than rayon has threads: every track is endless, so at most one per thread can
    // have started when the request comes, and at least one cannot have.
    let threads = rayon::current_num_threads();
    let n = threads + 1;
    let (cameras, endpoints) = segments(n, 1);
    let tracks = segment_tracks(&endpoints, 1.0);
    // The first poll is the one before the first track: that track starts.
    let (stop, requester) = requested_after_poll(1);
    let batch = with_stop(stop, || triangulate_lines(&cameras, tracks, &endless(), None)).unwrap();
    requester.join().unwrap();
    let (mut started, mut skipped) = (0, 0);
    for result in &batch {
        match result {
            Ok(line) => {
                started += 1;
                let report = &line.report;
                assert_eq!(report.status, Status::Interrupted);
                assert!(!report.certified());
                assert!(report.certificate.is_none_or(|c| c.lower_bound <= report.cost) && report.cost.is_finite());
            }
            Err(Error::Interrupted {
                reason: StopReason::Requested,
            }) => skipped += 1,
            Err(e) => panic!("unexpected {e}"),
        }
    }
    assert_eq!(started + skipped, n);
    assert!(
        (1..=threads).contains(&started) && skipped >= 1,
        "{started} started, {skipped} skipped, {threads} threads"
    );
}

#[test]
fn a_request_from_another_thread_stops_a_single_line() {
    let (cameras, endpoints) = segments(1, 2);
    let segments: Vec<[Vector2<f64>; 2]> = endpoints
        .chunks_exact(4)
        .map(|e| [Vector2::new(e[0], e[1]), Vector2::new(e[2], e[3])])
        .collect();
    let (lines, covariances) = lines_from_segments(&segments, 1.0).unwrap();
    // A conic solve polls before it starts and at each iteration: the request follows the third poll,
    // after the first iteration of the root's first solve, whenever it comes.
    let (stop, requester) = requested_after_poll(3);
    let line = with_stop(stop, || {
        triangulate_line(
            &cameras,
            LineObservations::Lines(&lines, Some(&covariances)),
            &endless(),
        )
    })
    .unwrap();
    requester.join().unwrap();
    let report = &line.report;
    assert_eq!(report.status, Status::Interrupted);
    assert!(!report.certified() && report.cost.is_finite());
    let c = report.certificate.expect("the search ran");
    assert!(c.nodes >= 1 && c.solver_iterations >= 1, "{c:?}");
    assert!(c.lower_bound <= report.cost);
}

#[test]
fn an_expired_budget_solves_nothing_in_every_point_path() {
    let mut rng = Rng::new(3);
    let cameras = arc_cameras(3, 0.5, &mut rng);
    let observations: Vec<f64> = (0..50)
        .flat_map(|_| {
            let x = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
            cameras.iter().flat_map(move |p| {
                let u = project(p, &x);
                [u.x, u.y]
            })
        })
        .collect();
    let tracks = DensePointTracks {
        observations: &observations,
        visible: None,
        covariances: None,
    };
    let expired = || Arc::new(Stop::with_time_budget(Some(Duration::ZERO)));
    let budget = Error::Interrupted {
        reason: StopReason::TimeBudget,
    };
    for method in [Method::Local, Method::Optimal] {
        let mut opts = TriangulationOptions::default();
        opts.method = method;
        let batch = with_stop(expired(), || triangulate_points(&cameras, tracks, &opts, None)).unwrap();
        assert!(batch.iter().all(|r| r.as_ref().err() == Some(&budget)));
    }
    let linear = with_stop(expired(), || LinearPoints::from_tracks(&cameras, &tracks)).unwrap();
    assert!(linear.outcomes.iter().all(|r| *r == Err(budget.clone())));
    assert!(linear.points.iter().all(|x| x.is_nan()));
    // Without a stop the same batch solves every track.
    let free = LinearPoints::from_tracks(&cameras, &tracks).unwrap();
    assert!(free.outcomes.iter().all(|r| *r == Ok(Status::Success)));
}

#[test]
fn ransac_and_the_certificate_stop_at_their_next_poll() {
    let scene = random_scene(SceneKind::General, 30, 0, 5);
    let requested = || {
        let stop = Arc::new(Stop::new());
        stop.request();
        stop
    };
    let mut ransac = RansacOptions::default();
    ransac.max_iterations = usize::MAX;
    ransac.min_inlier_ratio = 0.0;
    let mut robust = PoseOptions::default();
    robust.ransac = Some(ransac);
    let r = with_stop(requested(), || {
        estimate_pose(&scene.camera, &scene.correspondences, &robust)
    })
    .unwrap();
    let report = r.details.ransac.unwrap();
    assert_eq!((report.stop, report.iterations), (RansacStop::Interrupted, 0));

    let mut certify = PoseOptions::default();
    certify.certify = Some(CertifyOptions::default());
    let plain = estimate_pose(&scene.camera, &scene.correspondences, &certify).unwrap();
    assert!(
        plain.report.certificate.is_some_and(|c| c.certified),
        "{:?}",
        plain.details.uncertified_reason
    );
    let stopped = with_stop(requested(), || {
        estimate_pose(&scene.camera, &scene.correspondences, &certify)
    })
    .unwrap();
    assert!(stopped.report.certificate.is_none_or(|c| !c.certified));
    assert_eq!(stopped.report.status, pluecker::Status::Interrupted);
    let why = stopped.details.uncertified_reason.unwrap_or_default();
    assert!(why.contains("interrupted"), "{why}");
    // The pose itself does not depend on the stop.
    assert_eq!(stopped.pose.rotation, plain.pose.rotation);
}
