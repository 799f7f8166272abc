//! Tests of [`super::p3p`]: noise-free random instances (the truth among the solutions, to a tolerance
//! set by the conditioning of eq. 4), an independent multistart search, and the degenerate cases.

use super::*;
use crate::camera::Intrinsics;
use crate::rng::Rng;
use nalgebra::Vector2;

/// Machine epsilon.
const EPS: f64 = f64::EPSILON;

/// Accuracy required of the recovered pose: `‖R − R*‖_F` and `‖t − t*‖ / scene scale`.
const POSE_TOLERANCE: f64 = 1e-8;

/// Conditioning up to which every instance must meet [`POSE_TOLERANCE`]. The returned depths solve
/// eq. 4 to rounding, so their relative error is about `κ ε` times a modest constant (the rounding of
/// `a`, `b` and of the residuals), where `κ` is the condition number of eq. 4's Jacobian at the true
/// depths. `κ ≤ 1e5` keeps `κ ε ≤ 2.2e-11`, 450 times under the tolerance, room for that constant
/// and for the pose construction. Beyond it (next to the danger cylinder) the error may legitimately
/// exceed 1e-8, and is then required to stay below [`CONDITIONED_ERROR`]` κ ε`.
const KAPPA_LIMIT: f64 = 1e5;

/// The constant of the conditioning bound `error ≤ C κ ε` required of every instance. The largest
/// ratio seen over 4·10⁵ random instances of several fields of view is 76.
const CONDITIONED_ERROR: f64 = 1e3;

/// A noise-free P3P instance: three camera-frame points and their world coordinates under a pose.
struct Instance {
    cam: [Vector3<f64>; 3],
    points: [Vector3<f64>; 3],
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
}

impl Instance {
    fn new(cam: [Vector3<f64>; 3], rotation: Matrix3<f64>, translation: Vector3<f64>) -> Instance {
        let points = cam.map(|c| rotation.transpose() * (c - translation));
        Instance {
            cam,
            points,
            rotation,
            translation,
        }
    }

    /// A random pose and three points with depth in [1, 6] in the frustum `|x|, |y| ≤ half_width z`.
    fn random(rng: &mut Rng, half_width: f64) -> Instance {
        let cam = std::array::from_fn(|_| {
            let z = rng.uniform_in(1.0, 6.0);
            let mut lateral = || z * rng.uniform_in(-half_width, half_width);
            Vector3::new(lateral(), lateral(), z)
        });
        let translation = rng.unit_vector3() * rng.uniform_in(0.0, 4.0);
        Instance::new(cam, rng.rotation(), translation)
    }

    fn bearings(&self) -> [Vector3<f64>; 3] {
        self.cam.map(|c| c.normalize())
    }

    /// The scene scale of translation errors: the largest distance of a point from either origin.
    fn scale(&self) -> f64 {
        self.cam
            .iter()
            .chain(&self.points)
            .map(|v| v.norm())
            .fold(0.0, f64::max)
    }

    /// The larger of `‖R − R*‖_F` and `‖t − t*‖ / scale` for the closest returned pose.
    fn error(&self, poses: &[Pose]) -> f64 {
        let scale = self.scale();
        let error = |Pose {
                         rotation: r,
                         translation: t,
                     }: &Pose| {
            let rotation_error = (r - self.rotation).norm();
            rotation_error.max((t - self.translation).norm() / scale)
        };
        poses.iter().map(error).fold(f64::INFINITY, f64::min)
    }

    /// `κ`: the condition number of the Jacobian of eq. 4 at the true depths.
    fn conditioning(&self) -> f64 {
        let problem = Problem::new(&self.bearings(), &self.points).expect("a valid instance");
        let depth = |x: &Vector3<f64>| (self.rotation * x + self.translation).norm() / problem.scale;
        let lambda = Vector3::from_fn(|i, _| depth(&problem.x[i]));
        let singular = problem.jacobian(&lambda).singular_values();
        singular.max() / singular.min()
    }
}

/// Every pose is finite, a rotation to rounding, and puts each point in front of the camera within
/// `angle` radians of its bearing.
fn assert_valid(poses: &[Pose], bearings: &[Vector3<f64>; 3], points: &[Vector3<f64>; 3], angle: f64, what: &str) {
    assert!(poses.len() <= 4, "{what}: {} solutions", poses.len());
    for Pose {
        rotation: r,
        translation: t,
    } in poses
    {
        assert!(
            r.iter().chain(t.iter()).all(|v| v.is_finite()),
            "{what}: non-finite pose"
        );
        // The triads are orthonormal to rounding: a few ε per entry.
        let orthogonality = (r.transpose() * r - Matrix3::identity()).amax();
        assert!(
            orthogonality < 1e-14 && (r.determinant() - 1.0).abs() < 1e-14,
            "{what}: R not a rotation"
        );
        for (x, y) in points.iter().zip(bearings) {
            let c = r * x + t;
            let y = y.normalize();
            assert!(c.dot(&y) > 0.0, "{what}: a point behind the camera");
            let miss = c.normalize().cross(&y).norm();
            assert!(miss <= angle, "{what}: a point {miss:e} rad off its bearing");
        }
    }
}

/// What [`check_random_draws`] saw: draws within [`POSE_TOLERANCE`], draws with `κ > KAPPA_LIMIT`,
/// and how many draws had 0, 1, 2, 3, 4 solutions.
struct DrawSummary {
    found: usize,
    ill_conditioned: usize,
    counts: [usize; 5],
}

/// Solves `draws` random instances whose points lie within `x, y ∈ ±half_width · z`, asserting that
/// every returned pose is a genuine solution and that the truth is among them to `C κ ε`, and to
/// [`POSE_TOLERANCE`] when `κ ≤ KAPPA_LIMIT`.
fn check_random_draws(seed: u64, draws: usize, half_width: f64) -> DrawSummary {
    let mut rng = Rng::new(seed);
    let mut summary = DrawSummary {
        found: 0,
        ill_conditioned: 0,
        counts: [0; 5],
    };
    for draw in 0..draws {
        let inst = Instance::random(&mut rng, half_width);
        let poses = p3p(&inst.bearings(), &inst.points);
        let what = format!("seed {seed}, draw {draw}");
        // Genuine solutions put each point on its ray to the rounding of the refined depths (about
        // 1e-11 rad at worst over 3·10⁵ draws); a spurious one would miss by more than 1e-4.
        assert_valid(&poses, &inst.bearings(), &inst.points, 1e-9, &what);
        summary.counts[poses.len()] += 1;
        let (error, kappa) = (inst.error(&poses), inst.conditioning());
        if error <= POSE_TOLERANCE {
            summary.found += 1;
        }
        if kappa > KAPPA_LIMIT {
            summary.ill_conditioned += 1;
        } else {
            assert!(error <= POSE_TOLERANCE, "{what}: error {error:e} with κ = {kappa:e}");
        }
        assert!(
            error <= CONDITIONED_ERROR * kappa * EPS,
            "{what}: error {error:e} with κ = {kappa:e}"
        );
    }
    println!(
        "p3p, field of view ±{half_width}: true pose within {POSE_TOLERANCE:e} in {}/{draws} draws; {} with \
         κ > {KAPPA_LIMIT:e}; draws with 0..4 solutions: {:?}",
        summary.found, summary.ill_conditioned, summary.counts
    );
    summary
}

#[test]
fn random_instances_recover_the_true_pose() {
    let summary = check_random_draws(3_001, 1000, 2.0);
    // κ > 1e5 occurred in 13 of 10⁵ draws of this distribution: 5 of 1000 would be a 30-fold excess.
    assert!(
        summary.ill_conditioned <= 5,
        "{} ill-conditioned draws",
        summary.ill_conditioned
    );
    assert!(summary.counts[0] == 0, "every instance has its true solution");
    assert!(
        summary.counts[3] + summary.counts[4] > 0,
        "some instances have more than two solutions"
    );
}

#[test]
fn narrow_field_of_view_is_as_accurate_as_its_conditioning() {
    // A 6° field of view (markers seen from afar, the paper's motivating case): short sides and
    // nearly equal bearings, and a larger share of ill-conditioned instances.
    let summary = check_random_draws(3_008, 500, 0.05);
    // κ > 1e5 occurred in 904 of 10⁵ draws here (0.9%, about 4.5 expected of 500).
    assert!(
        summary.ill_conditioned <= 15,
        "{} ill-conditioned draws",
        summary.ill_conditioned
    );
}

#[test]
fn refinement_brings_the_depths_to_rounding_level() {
    // On a narrow field of view the closed form alone leaves residuals of eq. 4 up to about 30 ε
    // times the largest λᵢ² (1.5e6 ε in absolute terms over 10⁵ draws); the Gauss-Newton steps
    // must bring every well-conditioned solution to the rounding of evaluating the residuals, which
    // is a few ε times the largest λᵢ² (at most 1.2 seen).
    let mut rng = Rng::new(3_009);
    let (mut worst_before, mut worst_after) = (0.0f64, 0.0f64);
    for draw in 0..1000 {
        let inst = Instance::random(&mut rng, 0.05);
        let problem = Problem::new(&inst.bearings(), &inst.points).expect("a valid instance");
        for candidate in problem.candidate_depths() {
            let Some(lambda) = problem.refine(candidate) else {
                continue;
            };
            let singular = problem.jacobian(&lambda).singular_values();
            if singular.max() / singular.min() > KAPPA_LIMIT {
                continue;
            }
            let rounding = EPS * lambda.amax().powi(2).max(1.0);
            let (before, after) = (problem.residuals(&candidate).amax(), problem.residuals(&lambda).amax());
            assert!(
                after <= 8.0 * rounding,
                "draw {draw}: residual {after:e} = {} ε λ²",
                after / rounding
            );
            (worst_before, worst_after) = (worst_before.max(before / rounding), worst_after.max(after / rounding));
        }
    }
    println!("eq. 4 residuals / (ε max λ²): {worst_before:.3e} before refinement, {worst_after:.3} after");
}

#[test]
fn every_solution_found_by_multistart_newton_is_returned() {
    // An independent search: plain Newton on eq. 4 from 50 random positive starts per instance.
    let mut rng = Rng::new(3_002);
    let (mut checked, mut skipped) = (0, 0);
    for draw in 0..200 {
        let inst = Instance::random(&mut rng, 2.0);
        let bearings = inst.bearings();
        let poses = p3p(&bearings, &inst.points);
        let problem = Problem::new(&bearings, &inst.points).expect("a valid instance");
        let mut seen: Vec<Vector3<f64>> = Vec::new();
        for _ in 0..50 {
            let mut lambda = Vector3::from_fn(|_, _| rng.uniform_in(0.05f64.ln(), 20f64.ln()).exp());
            for _ in 0..100 {
                let Some(inverse) = problem.jacobian(&lambda).try_inverse() else {
                    break;
                };
                lambda -= inverse * problem.residuals(&lambda);
            }
            let converged = problem.residuals(&lambda).amax() <= 1e-14 && lambda.iter().all(|&l| l > 0.0);
            if !converged || seen.iter().any(|s| (s - lambda).amax() <= 1e-8 * s.amax()) {
                continue;
            }
            seen.push(lambda);
            let singular = problem.jacobian(&lambda).singular_values();
            if singular.max() / singular.min() > KAPPA_LIMIT {
                skipped += 1;
                continue;
            }
            let Pose {
                rotation: r,
                translation: t,
            } = problem.pose(&lambda).expect("a pose");
            let truth = Instance {
                rotation: r,
                translation: t,
                ..inst
            };
            let error = truth.error(&poses);
            assert!(
                error <= POSE_TOLERANCE,
                "draw {draw}: Newton found a solution p3p missed ({error:e})"
            );
            checked += 1;
        }
    }
    println!("multistart Newton: {checked} solutions checked, {skipped} ill-conditioned skipped");
    // Every instance has at least its true solution, and Newton finds more than that on average.
    assert!(checked > 200, "{checked}");
}

#[test]
fn solutions_do_not_depend_on_the_order_of_the_correspondences() {
    let mut rng = Rng::new(3_003);
    for draw in 0..100 {
        let inst = Instance::random(&mut rng, 2.0);
        if inst.conditioning() > KAPPA_LIMIT {
            continue;
        }
        let poses = p3p(&inst.bearings(), &inst.points);
        for order in [[0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
            let permuted = Instance::new(order.map(|i| inst.cam[i]), inst.rotation, inst.translation);
            let other = p3p(&permuted.bearings(), &permuted.points);
            assert_eq!(other.len(), poses.len(), "draw {draw}, order {order:?}");
            for Pose {
                rotation: r,
                translation: t,
            } in &other
            {
                let same = Instance {
                    rotation: *r,
                    translation: *t,
                    ..inst
                };
                assert!(same.error(&poses) <= POSE_TOLERANCE, "draw {draw}, order {order:?}");
            }
        }
    }
}

#[test]
fn bearings_from_pixels_of_a_mirrored_camera() {
    // The paper's camera (Phong & Horaud 1995, Table 1): fx < 0. Bearings from pixels as documented.
    let cam = Intrinsics::new(-1730.3, 1220.7, 243.8, 241.2, 0.0).unwrap();
    let mut rng = Rng::new(3_004);
    for draw in 0..200 {
        let inst = Instance::random(&mut rng, 2.0);
        let bearings = inst.cam.map(|c| {
            let n = cam.pixel_to_normalized(&cam.project(&c));
            Vector3::new(n.x, n.y, 1.0).normalize()
        });
        assert!(bearings
            .iter()
            .zip(&inst.bearings())
            .all(|(b, y)| (b - y).norm() < 1e-12));
        if inst.conditioning() <= KAPPA_LIMIT {
            let error = inst.error(&p3p(&bearings, &inst.points));
            assert!(error <= POSE_TOLERANCE, "draw {draw}: {error:e}");
        }
    }
    assert_eq!(cam.pixel_to_normalized(&Vector2::new(243.8, 241.2)), Vector2::zeros());
}

/// Reprojection bound for near-degenerate instances: accepted depths satisfy eq. 4 to
/// [`RESIDUAL_TOLERANCE`] of the longest squared side, so the camera-frame triangle's sides match
/// the world's to that order, and the apex of a flat triangle, fixed by its sides only to the square
/// root of their error, moves by at most `√RESIDUAL_TOLERANCE` of the longest side; divided by the
/// smallest depth, an angle.
fn flat_reprojection_bound(inst: &Instance) -> f64 {
    let p = &inst.points;
    let side = [(0, 1), (0, 2), (1, 2)]
        .map(|(i, j)| (p[i] - p[j]).norm())
        .into_iter()
        .fold(0.0, f64::max);
    let depth = inst.cam.iter().map(|c| c.norm()).fold(f64::INFINITY, f64::min);
    RESIDUAL_TOLERANCE.sqrt() * side / depth
}

/// Two random camera-frame points in front of the camera, depth 2-5.
fn two_points(rng: &mut Rng) -> (Vector3<f64>, Vector3<f64>) {
    let mut point = || {
        Vector3::new(
            rng.uniform_in(-1.0, 1.0),
            rng.uniform_in(-1.0, 1.0),
            rng.uniform_in(2.0, 5.0),
        )
    };
    (point(), point())
}

#[test]
fn nearly_collinear_world_points_give_finite_valid_poses() {
    // The third point lies off the segment 12 by `offset` times its length. The rotation about the
    // line is then fixed only through that offset: besides eq. 4's κ, the error is amplified by
    // 1/h with h = |(x₂ − x₁) × (x₃ − x₁)| / (longest side)², the triangle's relative height.
    let mut rng = Rng::new(3_005);
    for offset in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 0.0] {
        let mut returned = 0;
        for draw in 0..100 {
            let (c1, c2) = two_points(&mut rng);
            let c3 = c1 + (c2 - c1) * rng.uniform_in(0.2, 0.8) + rng.unit_vector3().cross(&(c2 - c1)) * offset;
            let inst = Instance::new([c1, c2, c3], rng.rotation(), rng.unit_vector3() * 2.0);
            let poses = p3p(&inst.bearings(), &inst.points);
            let what = format!("offset {offset:e}, draw {draw}");
            assert_valid(
                &poses,
                &inst.bearings(),
                &inst.points,
                flat_reprojection_bound(&inst),
                &what,
            );
            returned += poses.len();
            let p = &inst.points;
            let longest = [(0, 1), (0, 2), (1, 2)].map(|(i, j)| (p[i] - p[j]).norm_squared());
            let height = (p[1] - p[0]).cross(&(p[2] - p[0])).norm() / longest.into_iter().fold(0.0, f64::max);
            if height > 0.0 && !poses.is_empty() {
                let (error, kappa) = (inst.error(&poses), inst.conditioning());
                assert!(
                    error <= CONDITIONED_ERROR * kappa * EPS / height,
                    "{what}: error {error:e}, κ {kappa:e}"
                );
            }
        }
        // Each instance has its true solution; near collinearity it pairs with a mirror solution.
        assert!(returned >= 100, "offset {offset:e}: {returned} poses");
    }
}

#[test]
fn nearly_equal_bearings_give_accurate_poses() {
    // Points 1 and 3 on nearly one ray (the third point `offset` off the ray of the first, farther
    // away): eq. 4 stays well conditioned; 1 − b₁₃ is evaluated as ‖y₁ − y₃‖²/2.
    let mut rng = Rng::new(3_006);
    for offset in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 0.0] {
        for draw in 0..100 {
            let (c1, c2) = two_points(&mut rng);
            let c3 = c1 * rng.uniform_in(1.2, 2.0) + rng.unit_vector3().cross(&c1).normalize() * offset;
            let inst = Instance::new([c1, c2, c3], rng.rotation(), rng.unit_vector3() * 2.0);
            let poses = p3p(&inst.bearings(), &inst.points);
            let what = format!("offset {offset:e}, draw {draw}");
            assert_valid(&poses, &inst.bearings(), &inst.points, 1e-9, &what);
            let (error, kappa) = (inst.error(&poses), inst.conditioning());
            assert!(
                error <= CONDITIONED_ERROR * kappa * EPS,
                "{what}: error {error:e}, κ {kappa:e}"
            );
            if kappa <= KAPPA_LIMIT {
                assert!(error <= POSE_TOLERANCE, "{what}: error {error:e}, κ {kappa:e}");
            }
        }
    }
}

#[test]
fn collinear_coincident_and_invalid_inputs_return_no_pose_or_valid_ones() {
    let bearings = [
        Vector3::new(0.1, 0.0, 1.0),
        Vector3::new(0.0, 0.2, 1.0),
        Vector3::new(-0.1, -0.1, 1.0),
    ];
    let points = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
    ];
    assert!(!p3p(&bearings, &points).is_empty(), "the reference input has solutions");
    // Exactly collinear (on an axis, so the triangle's height is exactly zero): no pose.
    let on_axis = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(3.0, 0.0, 0.0),
    ];
    assert!(p3p(&bearings, &on_axis).is_empty());
    // Collinear up to rounding, seen from a real camera: no pose or valid ones, never a panic.
    let mut rng = Rng::new(3_007);
    for draw in 0..100 {
        let (c1, c2) = two_points(&mut rng);
        let inst = Instance::new([c1, c2, (c1 + c2) * 0.5], rng.rotation(), rng.unit_vector3());
        let poses = p3p(&inst.bearings(), &inst.points);
        let bound = flat_reprojection_bound(&inst);
        assert_valid(
            &poses,
            &inst.bearings(),
            &inst.points,
            bound,
            &format!("collinear draw {draw}"),
        );
    }
    // Coincident points: no pose.
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let mut coincident = points;
        coincident[j] = coincident[i];
        assert!(p3p(&bearings, &coincident).is_empty(), "points {i} and {j} coincide");
    }
    // Non-finite values and zero bearings: no pose.
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for i in 0..3 {
            let (mut b, mut p) = (bearings, points);
            b[i].y = bad;
            p[i].z = bad;
            assert!(
                p3p(&b, &points).is_empty() && p3p(&bearings, &p).is_empty(),
                "{bad} at {i}"
            );
        }
    }
    let mut zero = bearings;
    zero[1] = Vector3::zeros();
    assert!(p3p(&zero, &points).is_empty());
    // Three equal bearings (all points on one ray is impossible for a triangle): no panic, valid poses.
    let same = [bearings[0]; 3];
    assert_valid(&p3p(&same, &points), &same, &points, 1e-9, "equal bearings");
    // Huge and tiny scenes: the conditioning by the longest side makes the solver scale-invariant.
    for scale in [1e-150, 1e150] {
        let scaled = points.map(|p| p * scale);
        let poses = p3p(&bearings, &scaled);
        assert_eq!(poses.len(), p3p(&bearings, &points).len(), "scale {scale:e}");
        assert_valid(&poses, &bearings, &scaled, 1e-9, &format!("scale {scale:e}"));
    }
}

#[test]
fn collinear_world_points_never_give_a_matrix_that_is_not_a_rotation() {
    // Found from Python (tests/test_pose_minimal.py): the points 0, 0.3 (1, 1, 1), 0.6 (1, 1, 1) on a line
    // seen from a random pose gave a rank-one "rotation", the product of a camera-side triad built from
    // rounding noise. Every returned R must be a rotation.
    let bearings = [
        Vector3::new(-0.07526772324075112, -0.01967980950306423, 0.9969691444252811),
        Vector3::new(-0.02218546740365586, -0.08926486036048183, 0.9957608095024152),
        Vector3::new(0.03175390807588196, -0.1590491898256914, 0.9867598717710908),
    ];
    let points = [
        Vector3::zeros(),
        Vector3::new(0.3, 0.3, 0.3),
        Vector3::new(0.6, 0.6, 0.6),
    ];
    for pose in p3p(&bearings, &points) {
        let r = pose.rotation;
        assert!(
            (r * r.transpose() - nalgebra::Matrix3::identity()).amax() < 1e-9 && r.determinant() > 0.0,
            "{r}"
        );
    }
}
