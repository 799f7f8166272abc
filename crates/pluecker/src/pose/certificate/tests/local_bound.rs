//! Step 4: the curvature bound along whitened rays and the whitened spread of a box
//! ([`super::super::local_bound`]).

use super::*;

/// `RayCurvature` bounds the second derivative of the residual vector along random whitened
/// rays (central differences), on wide and narrow fields of view, with points and lines, at the
/// pose and at a perturbed one.
#[test]
fn ray_curvature_bounds_the_second_derivative() {
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for (f, np, nl, planar) in [
        (250.0, 10, 0, false),
        (800.0, 20, 20, false),
        (4000.0, 30, 10, true),
        (15000.0, 10, 5, false),
    ] {
        for seed in 0..4 {
            let scene = visible_scene(f, np, nl, planar, seed);
            let mut rng = Rng::new(70 + seed);
            let corr = scene.noisy(1.0, true, &mut rng);
            let cost = ReprojectionCost::of(&scene.camera.intrinsics(), &corr);
            let truth = Pose::new(scene.rotation, scene.translation);
            let nudged = Pose::new(
                exp_so3(&Vector3::new(2e-3, -1e-3, 1e-3)) * truth.rotation,
                truth.translation + Vector3::new(1e-3, 2e-3, -3e-3),
            );
            for pose in [truth, nudged] {
                let f_hat = cost.cost(&pose);
                let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
                let lin = cost.linearize(&pose);
                let whitening = Whitening::new(&lin.gauss_newton).unwrap();
                let mu = (whitening.t.transpose() * lin.gauss_newton * whitening.t)
                    .symmetric_eigenvalues()
                    .max()
                    .sqrt();
                let radius = 3.0 * ((2.0 * f_hat).sqrt() + 0.1);
                let Some(k) = RayCurvature::new(&problem, &whitening, &pose, mu).and_then(|c| c.bound(radius)) else {
                    continue;
                };
                for _ in 0..20 {
                    let v = SVector::<f64, 6>::from_fn(|_, _| rng.normal()).normalize();
                    let a = whitening.t * v;
                    let at = |s: f64| -> Vec<f64> {
                        let omega = Vector3::new(a[0], a[1], a[2]) * s;
                        let tau = Vector3::new(a[3], a[4], a[5]) * s;
                        cost.residuals(&Pose::new(exp_so3(&omega) * pose.rotation, pose.translation + tau))
                    };
                    let h = 1e-2 * radius;
                    for i in 1..10 {
                        let s = radius * i as f64 / 10.0;
                        let (lo, mid, hi) = (at(s - h), at(s), at(s + h));
                        let second: f64 = lo
                            .iter()
                            .zip(&mid)
                            .zip(&hi)
                            .map(|((l, m), u)| ((l - 2.0 * m + u) / (h * h)).powi(2))
                            .sum::<f64>()
                            .sqrt();
                        // Central differences: error O(h² r'''), far below K here.
                        assert!(
                            second <= k * 1.01 + 1e-9,
                            "f={f} {np}p {nl}l seed {seed}: ‖r''‖ = {second} > K = {k}"
                        );
                        checked += 1;
                        worst = worst.max(second / k);
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "only {checked} samples");
    // Not vacuous: the bound is within two orders of magnitude of what the rays reach.
    assert!(
        worst > 1e-2,
        "K is {:.0}x the largest sampled second derivative",
        1.0 / worst
    );
}

/// `Whitening::box_spread` claims the largest whitened length `√(sᵀ W_ωω s)` of a rotation step `s` in
/// the box `|s_k| ≤ half_k`, which step 4 adds to a box centre's length to get its whitened radius.
/// Checked against an oracle written out here: the quadratic form summed entry by entry at all eight
/// vertices (the length is convex, so its largest value on the box is at one) and at uniform points of
/// the box and of its faces, none above the spread, and the spread the largest vertex (up to the
/// rounding of nine products, ~1e-15 relative: the largest vertex's form is at least a third of
/// `Σ|sᵢ W_ij s_j|`, since the vertices' mean is `Σ hᵢ² W_ii`). The metrics: random ones whose rotation
/// block couples the axes strongly (each of the four vertex pairs `±s` is the largest on some of them,
/// so a spread that left one out fails), and `JᵀJ` of real scenes at the truth.
#[test]
fn the_whitened_spread_of_a_rotation_box_is_its_largest_vertex() {
    let mut rng = Rng::new(61);
    let mut metrics: Vec<SMatrix<f64, 6, 6>> = (0..3000)
        .map(|_| {
            let scales = SVector::<f64, 6>::from_fn(|_, _| 10f64.powf(rng.uniform_in(-1.5, 1.5)));
            let a = SMatrix::<f64, 6, 6>::from_fn(|_, _| rng.normal()) * SMatrix::from_diagonal(&scales);
            a.transpose() * a
        })
        .collect();
    for (f, np, nl, seed) in [(250.0, 10, 0, 1), (800.0, 20, 20, 2), (4000.0, 30, 10, 3)] {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut Rng::new(seed));
        let truth = Pose::new(scene.rotation, scene.translation);
        metrics.push(
            ReprojectionCost::of(&scene.camera.intrinsics(), &corr)
                .linearize(&truth)
                .gauss_newton,
        );
    }
    let mut winners = [0usize; 4];
    let mut checked = 0;
    for w in &metrics {
        let whitening = Whitening::new(w).expect("a positive definite metric");
        for _ in 0..4 {
            let half = Vector3::from_fn(|_, _| 10f64.powf(rng.uniform_in(-4.0, 0.0)));
            let spread = whitening.box_spread(&half);
            let length = |s: &[f64; 3]| {
                let mut q = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        q += s[i] * w[(i, j)] * s[j];
                    }
                }
                q.max(0.0).sqrt()
            };
            let (mut largest, mut arg) = (0.0f64, 0);
            for vertex in 0..8 {
                let s: [f64; 3] = std::array::from_fn(|k| if vertex >> k & 1 == 1 { half[k] } else { -half[k] });
                let l = length(&s);
                if l > largest {
                    (largest, arg) = (l, vertex);
                }
            }
            // The pair ±s of the largest vertex: the signs of s₂ and s₃ relative to s₁.
            let relative = |k: usize| usize::from((arg >> k & 1) != (arg & 1));
            winners[relative(1) + 2 * relative(2)] += 1;
            assert!(
                (spread - largest).abs() <= 1e-12 * largest,
                "spread {spread} is not the largest vertex's length {largest} (half {half:?})"
            );
            for k in 0..40 {
                let mut s: [f64; 3] = std::array::from_fn(|i| rng.uniform_in(-half[i], half[i]));
                if k % 2 == 0 {
                    // On a face.
                    let i = k / 2 % 3;
                    s[i] = if k % 4 == 0 { half[i] } else { -half[i] };
                }
                assert!(
                    length(&s) <= spread * (1.0 + 1e-12),
                    "a step {s:?} of the box is longer, {}, than the spread {spread}",
                    length(&s)
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100_000, "{checked} points");
    assert!(
        winners.iter().all(|&n| n >= 500),
        "each vertex pair must be the largest on some boxes: {winners:?}"
    );
}
