//! A rig's problem as its search sees it: the data in the conditioned frame, every correspondence as
//! a minimal solver's feature, the samples, and the assembly of the result ([`finish`]).

use super::cost::{RigObservations, RigReprojectionCost};
use super::linear::{rays, Ray};
use super::ObservingCameras;
use crate::camera_pose::Pose;
use crate::error::Result;
use crate::optim::Objective;
use crate::pose::candidates::samples_by;
use crate::pose::certificate::{certify_rig, RigCamera, Verdict};
use crate::pose::correspondences::Conditioning;
use crate::pose::minimal::{solve_generalized, RigFeature};
use crate::pose::result::{assemble_at, is_finite, PipelineOutcome};
use crate::pose::{CertifyOptions, Correspondences, PoseOptions, PoseResult};
use crate::rig::Rig;
use nalgebra::Vector3;
use std::time::Instant;

/// The data of a search over several cameras, in the conditioned frame: the object centred at its
/// centroid and divided by its RMS radius, the rig's translations divided by the same.
pub(super) struct Conditioned {
    pub cond: Conditioning,
    pub rig: Rig,
    pub corr: Correspondences,
    /// The ray of every point ([`rays`]).
    pub rays: Vec<Ray>,
    /// Every correspondence as a minimal solver's feature (points first, then segments); `None` for a
    /// segment whose endpoints its lens cannot unproject (it is not sampled).
    pub features: Vec<Option<RigFeature>>,
    /// The camera of each feature.
    pub feature_cameras: Vec<usize>,
}

impl Conditioned {
    pub fn new(rig: &Rig, corr: &Correspondences, cameras: &ObservingCameras) -> Result<Conditioned> {
        let cond = Conditioning::of(corr);
        let rig = rig.scaled(1.0 / cond.scale);
        let corr = cond.correspondences(corr);
        let rays = rays(&rig, &corr, cameras)?;
        let centres = rig.centres();
        let points = rays.iter().zip(&corr.points3d).map(|(ray, point)| {
            Some(RigFeature::Point {
                ray: *ray,
                point: *point,
            })
        });
        // A segment's interpretation plane: through its camera's centre, normal to both endpoints'
        // bearings (unprojected through the lens), turned into the rig's frame.
        let lines = corr
            .lines2d
            .iter()
            .zip(&corr.lines3d)
            .enumerate()
            .map(|(j, (seen, object))| {
                let k = cameras.line(j);
                let camera = &rig.cameras()[k];
                let bearing = |u: &nalgebra::Vector2<f64>| camera.unproject(u, j).ok().map(|n| n.push(1.0));
                let normal = bearing(&seen[0])?.cross(&bearing(&seen[1])?);
                Some(RigFeature::Line {
                    normal: rig.sensor_from_rig()[k].rotation.transpose() * normal,
                    centre: centres[k],
                    endpoints: *object,
                })
            });
        let features = points.chain(lines).collect();
        let feature_cameras = (0..corr.n_points())
            .map(|i| cameras.point(i))
            .chain((0..corr.n_lines()).map(|j| cameras.line(j)))
            .collect();
        Ok(Conditioned {
            cond,
            rig,
            corr,
            rays,
            features,
            feature_cameras,
        })
    }

    pub fn to_world(&self, p: &Pose) -> Pose {
        Pose::new(p.rotation, self.cond.pose_to_world(&p.rotation, &p.translation))
    }

    pub fn conditioned(&self, p: &Pose) -> Pose {
        Pose::new(p.rotation, self.cond.pose_from_world(&p.rotation, &p.translation))
    }

    /// The poses the minimal solver of its mix finds for the features of `triple` (conditioned frame;
    /// [`solve_generalized`]); none when one of them cannot be sampled.
    pub fn solve(&self, triple: &[usize; 3]) -> Vec<Pose> {
        match triple.map(|i| self.features[i]) {
            [Some(a), Some(b), Some(c)] => solve_generalized(&[a, b, c]),
            _ => Vec::new(),
        }
    }

    /// A feature's place on the object for the spread of a sample: a point, or a segment's midpoint.
    fn position(&self, i: usize) -> Vector3<f64> {
        let np = self.corr.n_points();
        if i < np {
            self.corr.points3d[i]
        } else {
            let s = &self.corr.lines3d[i - np];
            0.5 * (s[0] + s[1])
        }
    }

    /// The samples for the minimal solvers: wide object triangles first, over more cameras first.
    pub fn samples(&self) -> Vec<[usize; 3]> {
        samples_by(self.features.len(), |&[i, j, k]| {
            let (a, b, c) = (self.position(i), self.position(j), self.position(k));
            let area = (b - a).cross(&(c - a)).norm();
            let [p, q, r] = [i, j, k].map(|f| self.feature_cameras[f]);
            let distinct = 1 + usize::from(p != q) + usize::from(r != p && r != q);
            distinct as f64 * area
        })
    }
}

/// The result of a rig's pipeline: [`assemble_at`] with `cost`, the rig's cost of `parts.used` (world
/// frame), linearised at the pose.
pub(super) fn finish(
    cost: &RigReprojectionCost<'_>,
    opts: &PoseOptions,
    started: Instant,
    parts: PipelineOutcome<'_>,
) -> PoseResult {
    let linearization = is_finite(&parts.pose).then(|| cost.linearize(&parts.pose));
    assemble_at(linearization, opts, started, parts)
}

/// The certificate of `pose` (`rig_from_world`, conditioned frame), a local minimum of the cost
/// `cost` (`½ Σ r²`) of `observations` (conditioned frame) seen by `rig` (scaled as they are):
/// [`certify_rig`] over the cameras that saw them.
pub(super) fn certify(
    rig: &Rig,
    observations: &RigObservations,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
) -> Verdict {
    let cameras: Vec<RigCamera> = (observations.shares.iter())
        .map(|share| RigCamera {
            index: share.camera,
            camera: &rig.cameras()[share.camera],
            sensor_from_rig: rig.sensor_from_rig()[share.camera],
            corr: &share.corr,
        })
        .collect();
    certify_rig(&cameras, pose, cost, options)
}
