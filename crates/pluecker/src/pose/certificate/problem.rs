//! The problem of the test, prepared once ([`super`]'s module docs): per point its whitened residual
//! map `Wᵢ K₂` and its part `AᵢᵀAᵢ` of step 2's minorant, per segment endpoint its `G_e`, the
//! bearings; and what the rotation search starts from: step 1's depth bounds `Dᵢ` (law of sines over
//! pairs of points), or, without them, the object's distance from the camera
//! ([`crate::pose::object_distance`]).
//!
//! **A rig's cameras** ([`Problem::of_rig`]): camera `k` sees `x_k = R_k x + c_k` of a point `x` in the
//! rig's frame (the frame of the pose), i.e. `x_k = R_k (x + e_k)` with the offset `e_k = R_kᵀ c_k`
//! (`−e_k` is the camera's centre in the rig's frame). A point's residual `Aᵢ x_k / x_{k,z}` is then
//! `(Aᵢ R_k) (x + e_k) / x_{k,z}` and `‖x_k‖ = ‖x + e_k‖`, so every step reads the rig as one camera
//! whose points each carry the map `Aᵢ R_k`, the bearing `R_kᵀ bᵢ` and the offset `e_k`; the depth
//! bounds of step 1 come from pairs of points, of one camera or of two with the distance between
//! their centres added ([`depth_bounds_each`]), and reach a point without a partner by the triangle
//! inequality ([`rig_depth_bounds`]). Step 4 runs on each camera's own observations at its own pose
//! ([`CameraPart`]).

use super::minorant::{largest_eigenvalue, Minorant, PointForm};
use crate::camera::Intrinsics;
use crate::optim::{Linearization, Objective};
use crate::pose::correspondences::Correspondences;
use crate::pose::object_distance::{distance_bound, Sight};
use crate::pose::reprojection::{Pose, ReprojectionCost};
use crate::rig::tangent_map;
use nalgebra::{Matrix2, Matrix3, SMatrix, Vector3};
use std::rc::Rc;

/// Why noise that carries a lens's Jacobians (the first-order noise of undistorted pixels) is not
/// certified: the cost is in the distorted pixels, which [`super::certify`] is given with the lens.
pub(super) const FIRST_ORDER_NOISE: &str = "not attempted: the noise is the first-order noise of undistorted pixels; \
    the certificate bounds the cost in the observed pixels, through the lens";

/// Partners per point for its depth bound (the widest-apart in the image of a small spread set).
pub(super) const DEPTH_PARTNERS: usize = 16;
/// At most this many segments, the longest in the image, enter the box bound
/// ([`Problem::lines_bound`]): each costs per box about as much as the rest of the bound, a few
/// already constrain the rotation where the points are few, and fewer terms only weaken the minorant.
/// (With all 50 segments of the 50-point + 50-segment benchmark rows, the searches that fail took
/// 2.5-3.3 times as long for one or two more certificates in 50.)
pub(super) const BOX_BOUND_SEGMENTS: usize = 8;
/// Boxes of rotations within this angle of the answer's are bounded with every segment where there
/// are no depth bounds ([`SearchStart::ObjectDistance`], [`Problem::segments_in`]): there the translation ellipsoid
/// decides whether a box lies inside the whitened ball of step 4. With depth bounds every box keeps
/// [`BOX_BOUND_SEGMENTS`]: every segment near the answer there saved nodes at f = 250-800 px but cost
/// 3.5 times as much per node at f = 15000 px (50 points + 50 segments, 20 scenes of
/// `bench/profile_pose.py`: median 10 → 17-22 ms for the same nodes), and the linearised bound
/// ([`Problem::linear_lines_bound`]) with the longest segments alone already did better than before
/// on every row.
pub(super) const NEAR_ANSWER: f64 = 0.5;
/// At most this many segments, the longest in the image, enter the bound of a box where there are no
/// depth bounds ([`SearchStart::ObjectDistance`]): there they are the bound, not an addition to it.
pub(super) const BALL_SEGMENTS: usize = 32;

/// The indices of the (at most) `count` longest observed segments, longest first.
pub(super) fn longest_segments(corr: &Correspondences, count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..corr.n_lines()).collect();
    let length = |i: usize| (corr.lines2d[i][1] - corr.lines2d[i][0]).norm();
    order.sort_by(|&i, &j| length(j).total_cmp(&length(i)));
    order.truncate(count);
    order
}

/// The data of the test, prepared once (conditioned frame, centred on the object).
pub(super) struct Problem<'c> {
    /// The correspondences (for a rig, every camera's points one camera after the other, in the order
    /// of [`Self::cameras`]; the noise is the cameras').
    pub(super) corr: &'c Correspondences,
    /// The cameras: one, whose pose is the pose (`sensor` `None`), or a rig's.
    pub(super) cameras: Vec<CameraPart<'c>>,
    /// Per point, its part `Aᵢᵀ Aᵢ` of step 2's minorant ([`PointForm`]; for a rig's camera `k`, of
    /// `Aᵢ R_k`).
    pub(super) forms: Vec<PointForm>,
    /// Per point, the offset `e_k = R_kᵀ c_k` of its camera (zero for one camera; module docs).
    pub(super) offsets: Vec<Vector3<f64>>,
    /// What the rotation search starts from: step 1's depth bounds, or the object's distance.
    pub(super) start: SearchStart,
    /// The parts of the box bound with segments ([`LineForm`]), longest segment first: the first
    /// `box_segments` enter every box's bound ([`BOX_BOUND_SEGMENTS`], or [`BALL_SEGMENTS`] without
    /// depth bounds), all of them the bounds of boxes near the answer without depth bounds.
    pub(super) lines: Vec<LineForm>,
    pub(super) box_segments: usize,
    /// Unit bearings of the points (for a rig's camera `k`, `R_kᵀ bᵢ`: in the rig's frame).
    pub(super) bearings: Vec<Vector3<f64>>,
    /// `‖Xᵢ‖` (object coordinates).
    pub(super) norms: Vec<f64>,
    /// A cone of the bearings: their normalised mean `a`, `δ = max ‖bᵢ − a‖` and `max (‖Xᵢ‖ + ‖eᵢ‖)`.
    /// Every `bᵢ · (R Xᵢ + t + eᵢ) ≥ a · t − δ ‖t‖ − max (‖Xᵢ‖ + ‖eᵢ‖)`: where that is positive no
    /// point is behind.
    pub(super) bearing_cone: (Vector3<f64>, f64, f64),
}

/// One camera's observations as the test reads them: its intrinsics, its correspondences, per point
/// its whitened residual map `W K₂` (`W` the whitening of its noise, the identity without covariances;
/// `K₂` the 2x2 block of `K`, which maps a normalised-plane error to the whitened residual), per
/// segment endpoint its `G_e`, and where the camera sits in the frame of the pose.
pub(super) struct CameraPart<'c> {
    pub(super) camera: Intrinsics,
    pub(super) corr: &'c Correspondences,
    pub(super) point_maps: Vec<Matrix2<f64>>,
    /// `K⁻¹` (normalised endpoints `ē = K⁻¹ ẽ`).
    pub(super) k_inv: Matrix3<f64>,
    /// Per segment endpoint, `G_e = Lᵀ G` and its norm: `G` is the upper-left 2x2 block of `K⁻ᵀ` (a
    /// line moment `m` projects to a pixel line whose normal is `G m_xy`) and `L Lᵀ` the endpoint's
    /// covariance (the identity without covariances), so that the endpoint's residual is
    /// `ēᵀ m / ‖G_e m_xy‖`.
    pub(super) endpoint_maps: Vec<[EndpointMap; 2]>,
    /// A rig's camera: its `sensor_from_rig` `(R_k, c_k)`, `x_k = R_k x + c_k` for `x` in the frame of
    /// the pose. `None`: the pose is the camera's own.
    pub(super) sensor: Option<Pose>,
}

impl<'c> CameraPart<'c> {
    /// The observations `corr` of `camera`, placed by `sensor` (module docs).
    pub(super) fn new(
        camera: &Intrinsics,
        corr: &'c Correspondences,
        sensor: Option<Pose>,
    ) -> std::result::Result<Self, String> {
        let k = camera.matrix();
        let k2 = Matrix2::new(camera.fx, camera.skew, 0.0, camera.fy);
        let k_inv = k.try_inverse().ok_or("singular camera")?;
        let g = k_inv.transpose().fixed_view::<2, 2>(0, 0).into_owned();
        let (point_maps, endpoint_maps) = match &corr.noise {
            None => {
                let g_norm = norm2x2(&g).1;
                (vec![k2; corr.n_points()], vec![[(g, g_norm); 2]; corr.n_lines()])
            }
            // Noise that carries a lens's Jacobians: the cost is in the distorted pixels.
            Some(noise) if !noise.absolute => return Err(FIRST_ORDER_NOISE.into()),
            Some(noise) => {
                let endpoint = |c: &Matrix2<f64>| -> std::result::Result<EndpointMap, String> {
                    // The residual's scale is √(l₁₂ᵀ C l₁₂): only the symmetric part of C enters.
                    let l = (0.5 * (c + c.transpose()))
                        .cholesky()
                        .ok_or("not attempted: a covariance is not positive definite")?
                        .l();
                    let map = l.transpose() * g;
                    Ok((map, norm2x2(&map).1))
                };
                (
                    noise.points.iter().map(|w| w * k2).collect(),
                    noise
                        .lines
                        .iter()
                        .map(|[c0, c1]| Ok([endpoint(c0)?, endpoint(c1)?]))
                        .collect::<std::result::Result<_, String>>()?,
                )
            }
        };
        Ok(CameraPart {
            camera: *camera,
            corr,
            point_maps,
            k_inv,
            endpoint_maps,
            sensor,
        })
    }

    /// The unit bearings of the points, in the camera's frame.
    fn bearings(&self) -> Vec<Vector3<f64>> {
        (self.corr.points2d.iter())
            .map(|u| (self.k_inv * Vector3::new(u.x, u.y, 1.0)).normalize())
            .collect()
    }

    /// The angle bound `αᵢ` of every point at the residual `eps0`: a whitened error `e` is a
    /// normalised-plane error of at least `e / sᵢ` (`sᵢ` the least singular value of `Wᵢ K₂`).
    fn alphas(&self, eps0: f64) -> Vec<f64> {
        self.point_maps.iter().map(|m| eps0 / norm2x2(m).0).collect()
    }

    /// Step 2's point forms in the camera's frame: a point's residual is
    /// `Wᵢ K₂ (π(x) − ūᵢ) = Aᵢ x / x_z` with `Aᵢ = Wᵢ K₂ Eᵢ`, `Eᵢ = [1 0 −ū₁; 0 1 −ū₂]` (`ūᵢ` the
    /// normalised observed point); for a rig's camera, of `Aᵢ R_k`, in the rig's frame.
    fn forms(&self) -> Vec<PointForm> {
        (self.point_maps.iter().zip(&self.corr.points2d))
            .map(|(map, u)| {
                let n = self.k_inv * Vector3::new(u.x, u.y, 1.0);
                let e = SMatrix::<f64, 2, 3>::new(1.0, 0.0, -n.x / n.z, 0.0, 1.0, -n.y / n.z);
                let a = match &self.sensor {
                    None => map * e,
                    Some(sensor) => map * e * sensor.rotation,
                };
                let h = a.transpose() * a;
                PointForm {
                    h,
                    norm2: largest_eigenvalue(&h),
                }
            })
            .collect()
    }

    /// The camera's pose and the whitening of its steps for the pose `pose` and the whitening `t`
    /// of the frame of the pose: for a rig's camera, `(R_k R, R_k t + c_k)` and `diag(R_k, R_k) T`
    /// (the rig's chart step `(ω, τ)` moves the camera by `(R_k ω, R_k τ)`).
    pub(super) fn own(&self, pose: &Pose, t: &SMatrix<f64, 6, 6>) -> (Pose, SMatrix<f64, 6, 6>) {
        match &self.sensor {
            None => (*pose, *t),
            Some(sensor) => (sensor.compose(pose), tangent_map(&sensor.rotation) * t),
        }
    }
}

/// What the rotation search starts from.
pub(super) enum SearchStart {
    /// Step 1's depth bounds, and the minorant for them (the search tightens them box by box:
    /// [`super::search::RotationSearch`]).
    DepthBounds(Rc<Minorant>),
    /// Without depth bounds (lines alone, or fewer than two points seen far enough apart): the
    /// pivot `c` (an object point) is at most `distance` from the camera on `S`
    /// ([`crate::pose::object_distance`]), so the translation of a pose of `S` whose rotation is within
    /// `θ` of `R_c` lies in the ball of centre `−R_c c` and radius `distance + θ ‖c‖`; every box is
    /// bounded from the residuals at its centre rotation ([`Problem::ball_bound`]) and hands its
    /// octants a smaller ellipsoid of translations ([`super::box_bound::TranslationEllipsoid`]).
    ObjectDistance { pivot: Vector3<f64>, distance: f64 },
}

/// A segment's part of the box bound with lines ([`Problem::lines_bound`]): its object endpoint `a`,
/// direction `d = b − a` and moment `a × d` (with norms), per observed endpoint `ē = K⁻¹ ẽ`, `‖ē‖` and
/// `‖G_e‖`, and its camera's offset `e_k` (for a rig's camera `k`, `ē` is turned into the rig's frame,
/// `R_kᵀ K⁻¹ ẽ`: the numerator `ēᵀ R_k ((R a + t + e_k) × R d)` is then the single camera's at the
/// translation `t + e_k`; zero offset for one camera).
pub(super) struct LineForm {
    pub(super) a: Vector3<f64>,
    pub(super) b: Vector3<f64>,
    pub(super) d: Vector3<f64>,
    pub(super) moment: Vector3<f64>,
    pub(super) norms: [f64; 4],
    pub(super) ends: [(Vector3<f64>, f64, f64); 2],
    pub(super) offset: Vector3<f64>,
}

impl LineForm {
    /// Segment `index` of `corr`, seen by a camera at the origin of the frame of the pose.
    pub(super) fn new(corr: &Correspondences, index: usize, maps: &[EndpointMap; 2], k_inv: &Matrix3<f64>) -> Self {
        let (a, b) = (corr.lines3d[index][0], corr.lines3d[index][1]);
        let seen = corr.lines2d[index];
        let d = b - a;
        let moment = a.cross(&d);
        LineForm {
            a,
            b,
            d,
            moment,
            norms: [a.norm(), b.norm(), d.norm(), moment.norm()],
            ends: std::array::from_fn(|k| {
                let e = k_inv * Vector3::new(seen[k].x, seen[k].y, 1.0);
                (e, e.norm(), maps[k].1)
            }),
            offset: Vector3::zeros(),
        }
    }

    /// Segment `index` of a rig's camera `part` ([`CameraPart::sensor`]).
    fn of_camera(part: &CameraPart, index: usize) -> Self {
        let mut form = LineForm::new(part.corr, index, &part.endpoint_maps[index], &part.k_inv);
        if let Some(sensor) = &part.sensor {
            for end in &mut form.ends {
                end.0 = sensor.rotation.transpose() * end.0;
            }
            form.offset = sensor.rotation.transpose() * sensor.translation;
        }
        form
    }
}

/// A segment endpoint's `G_e` and `‖G_e‖` ([`CameraPart::endpoint_maps`]).
pub(super) type EndpointMap = (Matrix2<f64>, f64);

pub(super) fn norm2x2(m: &Matrix2<f64>) -> (f64, f64) {
    let s = m.singular_values();
    (s.min(), s.max())
}

/// The depth bound of every point for its angle bound `αᵢ` (`None` when some point has no partner
/// seen far enough apart).
pub(super) fn depth_bounds(corr: &Correspondences, bearings: &[Vector3<f64>], alphas: &[f64]) -> Option<Vec<f64>> {
    let offsets = vec![Vector3::zeros(); corr.n_points()];
    depth_bounds_each(&corr.points3d, bearings, &offsets, alphas)
        .into_iter()
        .collect()
}

/// Step 1's depth bound of each point for its angle bound `αᵢ`, with a partner `j` seen far enough
/// apart (`None` for a point without one): on `S` the point `yᵢ = R Xᵢ + t` is at the distance `λᵢ`
/// from its camera's centre `−eᵢ` along a direction `bᵢ'` within `αᵢ` of its bearing `bᵢ` (both in
/// the frame of the pose: [`Problem::bearings`], [`Problem::offsets`]), so
/// `λᵢ bᵢ' − λⱼ bⱼ' = yᵢ − yⱼ + eᵢ − eⱼ` has a norm of at most `dᵢⱼ + ‖eᵢ − eⱼ‖`, and of at least
/// `λᵢ sin γ'` (the distance of `λᵢ bᵢ'` from the line along `bⱼ'`), `γ' ∈ [γ − αᵢ − αⱼ, γ + αᵢ + αⱼ]`
/// the angle between `bᵢ'` and `bⱼ'`: `λᵢ ≤ (dᵢⱼ + ‖eᵢ − eⱼ‖) / min(sin(γ ∓ (αᵢ + αⱼ)))`. For two
/// points of one camera (`eᵢ = eⱼ`) this is the law of sines of the module docs.
pub(super) fn depth_bounds_each(
    points: &[Vector3<f64>],
    bearings: &[Vector3<f64>],
    offsets: &[Vector3<f64>],
    alphas: &[f64],
) -> Vec<Option<f64>> {
    let n = bearings.len();
    // Partners: an even spread of the points.
    let step = (n / DEPTH_PARTNERS).max(1);
    let partners: Vec<usize> = (0..n).step_by(step).take(DEPTH_PARTNERS).collect();
    let pair = |i: usize, j: usize| -> f64 {
        let gamma = bearings[i].angle(&bearings[j]);
        let (lo, hi) = (gamma - alphas[i] - alphas[j], gamma + alphas[i] + alphas[j]);
        if i == j || lo <= 0.0 || hi >= std::f64::consts::PI {
            return f64::INFINITY;
        }
        ((points[i] - points[j]).norm() + (offsets[i] - offsets[j]).norm()) / lo.sin().min(hi.sin())
    };
    (0..n)
        .map(|i| {
            let mut best = partners.iter().map(|&j| pair(i, j)).fold(f64::INFINITY, f64::min);
            // Every point as a partner when the spread set did not give a bound.
            if !best.is_finite() {
                best = (0..n).map(|j| pair(i, j)).fold(f64::INFINITY, f64::min);
            }
            best.is_finite().then_some(best)
        })
        .collect()
}

/// Every segment of a rig's `cameras` as a [`LineForm`], the longest in the image first (pixels of
/// every camera alike).
fn rig_segments(cameras: &[CameraPart]) -> Vec<LineForm> {
    let mut lines: Vec<(f64, LineForm)> = (cameras.iter())
        .flat_map(|part| {
            (0..part.corr.n_lines()).map(move |j| {
                let seen = part.corr.lines2d[j];
                ((seen[1] - seen[0]).norm(), LineForm::of_camera(part, j))
            })
        })
        .collect();
    lines.sort_by(|a, b| b.0.total_cmp(&a.0));
    lines.into_iter().map(|(_, form)| form).collect()
}

/// A rig's depth bounds: each point's own (`depths`, from its partners: [`depth_bounds_each`]), and for
/// a point without one the least over the points `j` with one of `Dⱼ + ‖Xᵢ − Xⱼ‖ + ‖eᵢ − eⱼ‖`: its
/// distance `‖R Xᵢ + t + eᵢ‖` from its camera's centre is at most point `j`'s from its own, plus the
/// object's distance between the points, plus the distance between the two centres `−eᵢ`, `−eⱼ`
/// (triangle inequality). `None` when no point has a bound of its own.
pub(super) fn rig_depth_bounds(
    depths: &[Option<f64>],
    points: &[Vector3<f64>],
    offsets: &[Vector3<f64>],
) -> Option<Vec<f64>> {
    let bounded: Vec<usize> = (0..depths.len()).filter(|&j| depths[j].is_some()).collect();
    depths
        .iter()
        .enumerate()
        .map(|(i, own)| {
            own.or_else(|| {
                (bounded.iter())
                    .map(|&j| {
                        depths[j].unwrap_or(f64::INFINITY)
                            + (points[i] - points[j]).norm()
                            + (offsets[i] - offsets[j]).norm()
                    })
                    .min_by(f64::total_cmp)
            })
        })
        .collect()
}

impl<'c> Problem<'c> {
    pub(super) fn new(camera: &Intrinsics, corr: &'c Correspondences, f_hat: f64) -> std::result::Result<Self, String> {
        Self::build(camera, corr, f_hat, true)
    }

    /// The data of the test without depth bounds ([`SearchStart::ObjectDistance`]) even where the points give them.
    pub(super) fn without_depths(
        camera: &Intrinsics,
        corr: &'c Correspondences,
        f_hat: f64,
    ) -> std::result::Result<Self, String> {
        Self::build(camera, corr, f_hat, false)
    }

    /// The data of the test, with step 1's depth bounds where `use_depths` and the points give them.
    pub(super) fn build(
        camera: &Intrinsics,
        corr: &'c Correspondences,
        f_hat: f64,
        use_depths: bool,
    ) -> std::result::Result<Self, String> {
        let part = CameraPart::new(camera, corr, None)?;
        let eps0 = (2.0 * f_hat).sqrt();
        let alphas = part.alphas(eps0);
        let bearings = part.bearings();
        let depths = if !use_depths {
            Err("the search without depth bounds was asked for".to_string())
        } else if corr.n_points() < 2 {
            Err("the depth bounds need at least two points".to_string())
        } else if !alphas.iter().all(|alpha| *alpha < 0.25) {
            Err(format!("residuals too large ({eps0:.3e} px) for the angle bounds"))
        } else {
            depth_bounds(corr, &bearings, &alphas)
                .ok_or_else(|| "no two points are seen far enough apart to bound the depths".to_string())
        };
        let forms = part.forms();
        let offsets = vec![Vector3::zeros(); corr.n_points()];
        let (start, segments) = match depths {
            Ok(depths) => (
                SearchStart::DepthBounds(Rc::new(Minorant::build(
                    &corr.points3d,
                    &bearings,
                    &forms,
                    &offsets,
                    depths,
                ))),
                BOX_BOUND_SEGMENTS,
            ),
            Err(why) => {
                let (pivot, distance) =
                    object_distance(corr, &bearings, &alphas, &part.endpoint_maps, &part.k_inv, eps0).ok_or_else(
                        || format!("not proved: {why}, and the observations do not bound the object's distance"),
                    )?;
                (SearchStart::ObjectDistance { pivot, distance }, BALL_SEGMENTS)
            }
        };
        Ok(Problem {
            corr,
            forms,
            lines: longest_segments(corr, corr.n_lines())
                .into_iter()
                .map(|i| LineForm::new(corr, i, &part.endpoint_maps[i], &part.k_inv))
                .collect(),
            box_segments: segments,
            bearing_cone: bearing_cone(&bearings, &corr.points3d, &offsets),
            offsets,
            bearings,
            norms: corr.points3d.iter().map(|x| x.norm()).collect(),
            start,
            cameras: vec![part],
        })
    }

    /// The data of the test for a rig's `cameras` (each with its `sensor`; module docs), whose points
    /// `corr` holds one camera after the other in their order, at the level `f_hat`. The search needs
    /// step 1's depth bounds: without them (no camera sees two of its points far enough apart, or the
    /// residuals are too large for the angle bounds) there is no certificate.
    pub(super) fn of_rig(
        cameras: Vec<CameraPart<'c>>,
        corr: &'c Correspondences,
        f_hat: f64,
    ) -> std::result::Result<Self, String> {
        let eps0 = (2.0 * f_hat).sqrt();
        let n = corr.n_points();
        let (mut forms, mut bearings, mut offsets, mut alphas) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for part in &cameras {
            let (rotation, offset) = part.sensor.map_or((Matrix3::identity(), Vector3::zeros()), |s| {
                (s.rotation, s.rotation.transpose() * s.translation)
            });
            alphas.extend(part.alphas(eps0));
            bearings.extend(part.bearings().iter().map(|b| rotation.transpose() * b));
            forms.extend(part.forms());
            offsets.extend(std::iter::repeat(offset).take(part.corr.n_points()));
        }
        if bearings.len() != n {
            return Err("not attempted: the cameras' points are not the problem's".into());
        }
        if !alphas.iter().all(|alpha| *alpha < 0.25) {
            return Err(format!(
                "not proved: residuals too large ({eps0:.3e} px) for the angle bounds"
            ));
        }
        let depths = depth_bounds_each(&corr.points3d, &bearings, &offsets, &alphas);
        let depths = rig_depth_bounds(&depths, &corr.points3d, &offsets)
            .ok_or("not proved: no two points of the rig are seen far enough apart to bound the depths")?;
        Ok(Problem {
            corr,
            start: SearchStart::DepthBounds(Rc::new(Minorant::build(
                &corr.points3d,
                &bearings,
                &forms,
                &offsets,
                depths,
            ))),
            forms,
            lines: rig_segments(&cameras),
            // More segments than one camera's search takes ([`BOX_BOUND_SEGMENTS`]): a rig has no
            // search without depth bounds to follow a failed one. 40 scenes of 50 points + 50 segments
            // (the rig tests' ring, f = 800 px), 2 / 4 cameras: 8 segments certified 35 / 39 at a median
            // 3.8 / 1.9 ms, 16 segments 37 / 40 at 3.8 / 2.4 ms, 32 segments 39 / 40 at 4.2 / 2.4 ms.
            box_segments: BALL_SEGMENTS,
            bearing_cone: bearing_cone(&bearings, &corr.points3d, &offsets),
            offsets,
            bearings,
            norms: corr.points3d.iter().map(|x| x.norm()).collect(),
            cameras,
        })
    }

    /// The cost `½ Σ r²` of every camera at `pose`, linearised in the chart of the pose: one
    /// camera's own, or the sum over a rig's cameras of theirs at their poses, each step mapped by
    /// `diag(R_k, R_k)` (as the rig's cost, [`crate::pose::generalized`]).
    pub(super) fn linearize(&self, pose: &Pose) -> Linearization<6> {
        match self.cameras.as_slice() {
            [one] if one.sensor.is_none() => ReprojectionCost::of(&one.camera, one.corr).linearize(pose),
            cameras => {
                let mut total = Linearization::zero();
                for part in cameras {
                    let (own, b) = part.own(pose, &SMatrix::identity());
                    total.add_mapped(&ReprojectionCost::of(&part.camera, part.corr).linearize(&own), &b);
                }
                total
            }
        }
    }

    /// Whether the cameras are a rig's ([`Self::of_rig`]).
    pub(super) fn is_rig(&self) -> bool {
        self.cameras.iter().any(|c| c.sensor.is_some())
    }

    /// Step 1's minorant (`None` without depth bounds).
    pub(super) fn root(&self) -> Option<&Rc<Minorant>> {
        match &self.start {
            SearchStart::DepthBounds(root) => Some(root),
            SearchStart::ObjectDistance { .. } => None,
        }
    }

    /// Step 2's minorant for the depth bounds `depths`.
    pub(super) fn minorant(&self, depths: Vec<f64>) -> Minorant {
        Minorant::build(&self.corr.points3d, &self.bearings, &self.forms, &self.offsets, depths)
    }
}

/// A bound on the sine of the angle between the ray of an observed segment endpoint `ē = K⁻¹ ẽ` and
/// the interpretation plane (normal `m`) of every pose where the endpoint's residual
/// `ēᵀ m / ‖G_e m_xy‖` is at most `residual` in magnitude: `|ēᵀ m| ≤ residual ‖G_e‖ ‖m‖`, so the sine
/// `|ēᵀ m| / (‖ē‖ ‖m‖)` is at most `residual ‖G_e‖ / ‖ē‖` (`g_norm = ‖G_e‖`), and at most 1.
pub(super) fn endpoint_sine(residual: f64, g_norm: f64, e: &Vector3<f64>) -> f64 {
    (residual * g_norm / e.norm()).min(1.0)
}

/// The pivot of the object (the mean of its points and segment midpoints) and the bound on its
/// distance from the camera on `S` ([`crate::pose::object_distance`]; `None` without one). A point is
/// within its angle bound `αᵢ` of its observed ray (step 1). A segment endpoint `ē` whose residual
/// `ēᵀ m / ‖G_e m_xy‖` is at most `ε₀` is within the angle whose sine is `ε₀ ‖G_e‖ / ‖ē‖` of the
/// interpretation plane (normal `m`), as `‖G_e m_xy‖ ≤ ‖G_e‖ ‖m‖`.
pub(super) fn object_distance(
    corr: &Correspondences,
    bearings: &[Vector3<f64>],
    alphas: &[f64],
    endpoint_maps: &[[EndpointMap; 2]],
    k_inv: &Matrix3<f64>,
    eps0: f64,
) -> Option<(Vector3<f64>, f64)> {
    let count = corr.n_points() + corr.n_lines();
    if count == 0 {
        return None;
    }
    let pivot = (corr.points3d.iter().sum::<Vector3<f64>>()
        + corr.lines3d.iter().map(|[a, b]| (a + b) * 0.5).sum::<Vector3<f64>>())
        / count as f64;
    let rays = (corr.points3d.iter().zip(bearings).zip(alphas))
        .filter(|(_, alpha)| **alpha < std::f64::consts::FRAC_PI_2)
        .map(|((x, b), alpha)| Sight::Ray {
            direction: *b,
            tolerance: *alpha,
            offset: (x - pivot).norm(),
        });
    let planes = (corr.lines3d.iter().zip(&corr.lines2d).zip(endpoint_maps))
        .filter(|(([a, b], _), _)| (b - a).norm() > 0.0)
        .map(|(([a, b], seen), maps)| {
            let d = b - a;
            let ends = [0, 1].map(|k| k_inv * Vector3::new(seen[k].x, seen[k].y, 1.0));
            Sight::Plane {
                ends,
                sines: [0, 1].map(|k| endpoint_sine(eps0, maps[k].1, &ends[k])),
                offset: (a - pivot).cross(&d).norm() / d.norm(),
            }
        });
    let sights: Vec<Sight> = rays.chain(planes).collect();
    distance_bound(&sights).map(|distance| (pivot, distance))
}

/// [`Problem::bearing_cone`] (an empty cone, `δ = ∞`, without points or where the bearings' mean
/// vanishes).
pub(super) fn bearing_cone(
    bearings: &[Vector3<f64>],
    points: &[Vector3<f64>],
    offsets: &[Vector3<f64>],
) -> (Vector3<f64>, f64, f64) {
    let Some(axis) = bearings.iter().sum::<Vector3<f64>>().try_normalize(1e-12) else {
        return (Vector3::z(), f64::INFINITY, 0.0);
    };
    let reach = bearings.iter().map(|b| (b - axis).norm()).fold(0.0, f64::max);
    let largest = (points.iter().zip(offsets))
        .map(|(x, e)| x.norm() + e.norm())
        .fold(0.0, f64::max);
    (axis, reach, largest)
}
