//! # pluecker
//!
//! Geometric vision from points, lines and conics: the camera pose from known 3-D structure and the
//! 3-D structure from known cameras, with statistically optimal answers.
//!
//! ## Conventions (used everywhere)
//! The same statement as the README's "Conventions" section, which Python and JSON users read.
//! - World to camera: `x_cam = R X_world + t`; the camera looks down `+z`; a point is in front when `z > 0`.
//! - Pixels: `u = K x_cam / z` with `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`; `fx`, `fy` may be
//!   negative (a mirrored axis, as in Phong & Horaud's camera), never zero.
//! - Angles in radians; lengths in the unit of the 3-D data; image quantities in pixels.
//! - Image segments are pairs of pixel endpoints; 3-D segments pairs of world endpoints (only the 3-D
//!   line through them is used).
//! - Row-major data, one correspondence or track per row: points `(N, 2)` / `(N, 3)` (the batch slices of
//!   [`triangulation`] and the numpy arrays of the Python package).
//! - Known cameras (triangulation) are 3x4 matrices `P = K [R | t]` (any positive scale) mapping world
//!   points to pixels, `λ (u, v, 1)ᵀ = P (X, 1)ᵀ`; a point is in front when `λ = (P X̃)₃ > 0`.
//!
//! ## Examples
//! The pose of a camera from points and lines:
//! ```
//! use pluecker::{pose::{estimate_pose, PoseOptions}, synthetic};
//! let scene = synthetic::random_scene(synthetic::SceneKind::General, 20, 5, 42);
//! let result = estimate_pose(&scene.camera, &scene.correspondences, &PoseOptions::default()).unwrap();
//! assert!((result.pose.rotation - scene.rotation).norm() < 1e-6);
//! assert!((result.pose.translation - scene.translation).norm() < 1e-6);
//! ```
//!
//! A point triangulated from two known cameras, with its certificate of global optimality (the same
//! call takes `&views`, [`triangulation::View`]s of COLMAP cameras, with the images' raw pixels):
//! ```
//! use pluecker::nalgebra::{Matrix3, Matrix3x4, Vector2, Vector3};
//! use pluecker::triangulation::{point::triangulate_point, TriangulationOptions};
//! let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
//! let camera = |cx: f64| k * Matrix3x4::new(1.0, 0.0, 0.0, -cx, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0);
//! let projections = [camera(0.0), camera(1.0)];
//! let x = Vector3::new(0.3, -0.2, 5.0);
//! let pixels: Vec<Vector2<f64>> = projections
//!     .iter()
//!     .map(|p| { let h = p * x.push(1.0); Vector2::new(h.x / h.z + 0.3, h.y / h.z - 0.2) })
//!     .collect();
//! let result = triangulate_point(&projections, &pixels, None, &TriangulationOptions::default()).unwrap();
//! assert!(result.report.certified());
//! assert!((result.point - x).norm() < 0.05);
//! ```
//!
//! A 3-D line from its image segments (endpoints with 1 px of noise per coordinate):
//! ```
//! use pluecker::triangulation::line::{triangulate_line, LineObservations};
//! use pluecker::triangulation::{scenes::line_scene, TriangulationOptions};
//! let scene = line_scene(3, 0.8, 7);
//! let observed = LineObservations::Segments(&scene.segments, 1.0);
//! let line = triangulate_line(&scene.cameras, observed, &TriangulationOptions::default()).unwrap();
//! let along = (scene.endpoints[1] - scene.endpoints[0]).normalize();
//! assert!(line.direction.cross(&along).norm() < 1e-6);
//! assert!(line.report.certified());
//! ```
//!
//! An ellipsoid from its outline conics in three views:
//! ```
//! use pluecker::nalgebra::Matrix3;
//! use pluecker::triangulation::quadric::triangulate_quadric;
//! use pluecker::triangulation::{scenes::quadric_scene, TriangulationOptions};
//! let scene = quadric_scene(3, 0.8, 7);
//! let conics: Vec<Matrix3<f64>> = scene.outlines.iter().map(|e| e.primal()).collect();
//! let quadric = triangulate_quadric(&scene.cameras, &conics, &TriangulationOptions::default()).unwrap();
//! assert!((quadric.centre - scene.ellipsoid.centre).norm() < 1e-6);
//! assert!(quadric.report.success());
//! ```
//!
//! Many tracks at once, as COLMAP stores them, one observation per row (the batch functions also take
//! dense `(n, v)` tracks with a visibility mask): image ids index the cameras, a point track may see
//! one image twice (two keypoints, as COLMAP's track merging leaves them), and a bad track is its own
//! error, never the batch's:
//! ```
//! use pluecker::nalgebra::{Matrix3, Matrix3x4, Vector3};
//! use pluecker::triangulation::{point::{triangulate_points, SparsePointTracks}, Csr, TriangulationOptions};
//! let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
//! let projections: Vec<Matrix3x4<f64>> = (0..4)
//!     .map(|j| k * Matrix3x4::new(1.0, 0.0, 0.0, -(j as f64), 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0))
//!     .collect();
//! let pixel = |x: &Vector3<f64>, j: usize| { let h = projections[j] * x.push(1.0); [h.x / h.z, h.y / h.z] };
//! let (a, b) = (Vector3::new(0.3, -0.2, 6.0), Vector3::new(-0.5, 0.4, 7.0));
//! // Track 0 is seen in images 0, 2, 3; track 1 in image 1 twice and image 3; track 2 names image 7.
//! let image = [0, 2, 3, 1, 1, 3, 0, 7];
//! let points = [&a, &a, &a, &b, &b, &b, &a, &a];
//! let observations: Vec<f64> = image.iter().zip(points).flat_map(|(&j, x)| pixel(x, j.min(3))).collect();
//! let tracks = SparsePointTracks {
//!     csr: Csr { offsets: &[0, 3, 6, 8], image: &image },
//!     observations: &observations,
//!     covariances: None,
//! };
//! let results = triangulate_points(&projections, tracks, &TriangulationOptions::default(), None).unwrap();
//! assert!((results[0].as_ref().unwrap().point - a).norm() < 1e-6);
//! assert!((results[1].as_ref().unwrap().point - b).norm() < 1e-6);
//! assert!(results[2].is_err()); // image[7]: an image index below 4 (the cameras)
//! ```
//!
//! The pose of a camera rig, `x_rig = R X_world + t`, from points seen by any of its cameras (each
//! observation names its camera; [`pose::generalized`]):
//! ```
//! use pluecker::nalgebra::{Matrix3, Vector2, Vector3};
//! use pluecker::{estimate_rig_pose, Camera, Correspondences, ObservingCameras, Pose, PoseOptions, Rig};
//! // Two cameras on a bar, 0.5 apart, the second turned a quarter of a turn about y.
//! let turn = Matrix3::new(0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0);
//! let rig = Rig::new(
//!     vec![Camera::pinhole(600.0, 600.0, 320.0, 240.0, 0.0).unwrap(); 2],
//!     vec![Pose::identity(), Pose::new(turn, Vector3::new(0.5, 0.0, 0.0))],
//! )
//! .unwrap();
//! let truth = Pose::new(Matrix3::identity(), Vector3::new(0.1, -0.2, 0.3));
//! let (mut corr, mut cameras) = (Correspondences::default(), ObservingCameras::default());
//! for i in 0..12 {
//!     let k = i % 2;
//!     let x_cam = Vector3::new(0.1 * i as f64 - 0.6, 0.3 * (i as f64).sin(), 4.0 + 0.3 * i as f64);
//!     let world = rig.sensor_from_world(k, &truth).inverse().transform(&x_cam);
//!     corr.points2d.push(Vector2::new(600.0 * x_cam.x / x_cam.z + 320.0, 600.0 * x_cam.y / x_cam.z + 240.0));
//!     corr.points3d.push(world);
//!     cameras.point_cameras.push(k);
//! }
//! let result = estimate_rig_pose(&rig, &corr, &cameras, &PoseOptions::default()).unwrap();
//! assert!(result.report.success());
//! assert!((result.pose.translation - truth.translation).norm() < 1e-8);
//! ```
//!
//! ## Features
//! - `serde`: `serde::Serialize` and `serde::Deserialize` on the results, the options, [`Pose`],
//!   [`camera::Intrinsics`] and [`Camera`]. Enums are written by their names (`as_str`), a camera as
//!   `{"model": "OPENCV", "params": [...]}` and read back through [`Camera::new`], so its checks apply;
//!   a matrix as its rows (`[[r00, r01, r02], …]`, as a row-major numpy array), a vector as one list.
//!
//! ## References
//! - T. Q. Phong, R. Horaud, A. Yassine, P. D. Tao, *Object pose from 2-D to 3-D point and line
//!   correspondences*, IJCV 15(3), 1995. Equation numbers in doc comments refer to this paper.

// `!(x > 0.0)` is true for NaN: the NaN guard used throughout (a NaN input or bound must take the
// failing branch), which the comparison's partial_cmp spelling would hide.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Every public item is documented (`make lint` turns this into an error).
#![warn(missing_docs)]
// Every type a public signature names is itself reachable (re-exported) from a public path.
#![warn(unnameable_types)]

pub mod camera;
pub(crate) mod camera_pose;
pub(crate) mod certificate;
pub mod chi_square;
pub(crate) mod consensus;
pub(crate) mod cost_kind;
pub(crate) mod covariance;
pub(crate) mod error;
pub mod geometry;
pub(crate) mod global;
pub mod interrupt;
#[cfg(feature = "serde")]
pub(crate) mod matrix_rows;
pub(crate) mod names;
pub mod optim;
pub mod pose;
pub(crate) mod report;
pub(crate) mod rig;
pub mod rng;
pub(crate) mod status;
pub mod synthetic;
pub mod triangulation;

#[cfg(all(test, feature = "serde"))]
mod serde_tests;

pub use camera::Camera;
pub use error::{Error, Result};
// The crate root holds no two things of one name: each primitive's `Method` and result stay in their
// module (`pose::Method`, `triangulation::Method`), as `io::Error` and `fmt::Error` do in std.
pub use camera_pose::{Pose, ROTATION_TOLERANCE};
pub use certificate::{Certificate, CertificateKind, CertifyOptions, Primitive};
pub use cost_kind::CostKind;
pub use pose::{
    estimate_pose, estimate_rig_pose, Correspondences, CovarianceSource, ObservingCameras, PoseDetails, PoseOptions,
    PoseResult, RansacOptions, RansacReport, RansacStop,
};
pub use report::Report;
pub use rig::Rig;
pub use status::Status;

/// The linear-algebra crate whose types the API takes and returns (`Vector3`, `Matrix3x4`, ...),
/// re-exported so that a project uses the same version: `use pluecker::nalgebra::Vector3;` needs no
/// `nalgebra` entry of its own in `Cargo.toml` (a second, other version would make its types
/// different types).
pub use nalgebra;

/// Items the Python bindings and the integration tests use that are not part of the user-facing API.
#[doc(hidden)]
pub mod testing {
    pub use crate::error::number;
    /// The pose certificate's steps one by one, for the tests of the proof (the test hooks of the
    /// module `pose::certificate`, whose costs are `½ Σ r²`).
    pub use crate::pose::certificate::testing as pose_certificate;
}
