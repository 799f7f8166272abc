//! Seeded synthetic scenes for line and quadric triangulation (tests, examples, benchmarks).
//!
//! Cameras `K [R | t]` (f = 800 px, 640 x 480 images, principal point at the centre) sit on an arc of
//! radius 5 around the world origin, spread over `spread` radians, each looking at a point near the
//! origin; the primitive lies within about one unit of the origin and is seen inside every image.

use crate::geometry::plucker;
use crate::geometry::quadric::{project_dual, Ellipse, Ellipsoid};
use crate::rng::Rng;
use nalgebra::{Matrix3, Matrix3x4, Vector2, Vector3, Vector6};

/// Image width and height, pixels.
pub(crate) const IMAGE_SIZE: (f64, f64) = (640.0, 480.0);

/// A segment seen by several cameras, with its truth.
#[derive(Debug, Clone)]
pub struct LineScene {
    /// 3x4 cameras mapping world points to pixels.
    pub cameras: Vec<Matrix3x4<f64>>,
    /// The true 3-D segment endpoints (world).
    pub endpoints: [Vector3<f64>; 2],
    /// Its image segments, noise-free pixel endpoints, one per camera.
    pub segments: Vec<[Vector2<f64>; 2]>,
}

impl LineScene {
    /// The true line (Plücker coordinates, eq. 3, unit norm).
    pub fn plucker(&self) -> Vector6<f64> {
        plucker::from_points(&self.endpoints[0], &self.endpoints[1]).normalize()
    }

    /// The image segments with i.i.d. Gaussian noise of `sigma` px on every endpoint coordinate.
    pub fn noisy_segments(&self, sigma: f64, rng: &mut Rng) -> Vec<[Vector2<f64>; 2]> {
        let mut noise = || Vector2::new(rng.normal(), rng.normal()) * sigma;
        self.segments.iter().map(|s| [s[0] + noise(), s[1] + noise()]).collect()
    }
}

/// An ellipsoid seen by several cameras, with its truth.
#[derive(Debug, Clone)]
pub struct QuadricScene {
    /// 3x4 cameras mapping world points to pixels.
    pub cameras: Vec<Matrix3x4<f64>>,
    /// The true ellipsoid.
    pub ellipsoid: Ellipsoid,
    /// Its outlines (eqs. 12-13), one image ellipse per camera.
    pub outlines: Vec<Ellipse>,
}

impl QuadricScene {
    /// `n` points of each outline with i.i.d. Gaussian noise of `sigma` px per coordinate (random phase).
    pub fn noisy_outline_points(&self, n: usize, sigma: f64, rng: &mut Rng) -> Vec<Vec<Vector2<f64>>> {
        self.outlines
            .iter()
            .map(|e| {
                let phase = rng.uniform_in(0.0, std::f64::consts::TAU);
                e.sample(n, phase)
                    .into_iter()
                    .map(|p| p + Vector2::new(rng.normal(), rng.normal()) * sigma)
                    .collect()
            })
            .collect()
    }
}

/// `views` cameras on the arc (module docs).
pub fn arc_cameras(views: usize, spread: f64, rng: &mut Rng) -> Vec<Matrix3x4<f64>> {
    let k = Matrix3::new(
        800.0,
        0.0,
        IMAGE_SIZE.0 / 2.0,
        0.0,
        800.0,
        IMAGE_SIZE.1 / 2.0,
        0.0,
        0.0,
        1.0,
    );
    (0..views)
        .map(|i| {
            let angle = spread * (i as f64 / (views.max(2) - 1) as f64 - 0.5);
            let centre = Vector3::new(5.0 * angle.sin(), 0.5 * rng.normal(), -5.0 * angle.cos());
            let target = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.1;
            let z = (target - centre).normalize();
            let up = Vector3::new(0.2 * rng.normal(), 1.0, 0.0);
            let x = up.cross(&z).normalize();
            let y = z.cross(&x);
            let r = Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
            let mut rt = Matrix3x4::zeros();
            rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
            rt.set_column(3, &(-r * centre));
            k * rt
        })
        .collect()
}

fn project(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> Option<Vector2<f64>> {
    let u = p * x.push(1.0);
    (u.z > 0.0).then(|| u.xy() / u.z)
}

fn inside(u: &Vector2<f64>) -> bool {
    (20.0..IMAGE_SIZE.0 - 20.0).contains(&u.x) && (20.0..IMAGE_SIZE.1 - 20.0).contains(&u.y)
}

/// A random segment of length 0.8-1.6 near the origin, seen inside every image at least 60 px long.
pub fn line_scene(views: usize, spread: f64, seed: u64) -> LineScene {
    let mut rng = Rng::new(seed);
    let cameras = arc_cameras(views, spread, &mut rng);
    loop {
        let mid = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2;
        let half = rng.unit_vector3() * rng.uniform_in(0.4, 0.8);
        let endpoints = [mid + half, mid - half];
        let segments: Option<Vec<[Vector2<f64>; 2]>> = cameras
            .iter()
            .map(|p| Some([project(p, &endpoints[0])?, project(p, &endpoints[1])?]))
            .collect();
        if let Some(segments) = segments {
            if segments
                .iter()
                .all(|s| inside(&s[0]) && inside(&s[1]) && (s[0] - s[1]).norm() > 60.0)
            {
                return LineScene {
                    cameras,
                    endpoints,
                    segments,
                };
            }
        }
    }
}

/// A random ellipsoid near the origin with semi-axes 0.15-0.5, every outline inside every image.
pub fn quadric_scene(views: usize, spread: f64, seed: u64) -> QuadricScene {
    let mut rng = Rng::new(seed);
    let cameras = arc_cameras(views, spread, &mut rng);
    loop {
        let mut axes = rng.rotation();
        if axes.determinant() < 0.0 {
            axes.column_mut(2).neg_mut();
        }
        let mut s = [
            rng.uniform_in(0.15, 0.5),
            rng.uniform_in(0.15, 0.5),
            rng.uniform_in(0.15, 0.5),
        ];
        s.sort_by(|a, b| b.total_cmp(a));
        let ellipsoid = Ellipsoid {
            centre: Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2,
            axes,
            semi_axes: Vector3::from(s),
        };
        let outlines: Option<Vec<Ellipse>> = cameras
            .iter()
            .map(|p| Ellipse::from_primal(&project_dual(p, &ellipsoid.dual()).try_inverse()?))
            .collect();
        if let Some(outlines) = outlines {
            let fits = outlines
                .iter()
                .all(|e| e.sample(16, 0.0).iter().all(inside) && e.semi_axes.y > 15.0);
            if fits {
                return QuadricScene {
                    cameras,
                    ellipsoid,
                    outlines,
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_project_inside_the_images() {
        for seed in 0..5 {
            let scene = line_scene(4, 0.8, seed);
            for (p, s) in scene.cameras.iter().zip(&scene.segments) {
                let l = plucker::project(p, &scene.plucker());
                for u in s {
                    assert!(inside(u));
                    assert!((l.xy().dot(u) + l.z).abs() < 1e-9 * l.xy().norm() * (1.0 + u.norm()));
                }
            }
            let scene = quadric_scene(3, 0.8, seed);
            assert_eq!(scene.outlines.len(), 3);
        }
    }
}
