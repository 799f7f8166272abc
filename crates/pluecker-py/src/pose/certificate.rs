//! A test hook of the pose certificate, hidden from the API (`pluecker._core._pose_rotation_search`):
//! steps 1-3 of the proof around any pose and at any level, so that the pytest files can check the
//! region it proves against poses found independently (numpy).

use crate::camera::PyCamera;
use crate::convert::{pose_from_parts, Real};
use crate::errors::{guarded, invalid_argument};
use crate::pose::correspondences;
use numpy::{PyArray1, PyArrayMethods};
use pluecker::testing::pose_certificate::{rotation_search, KeptCell};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Runs the rotation search of the pose certificate around the pose `(R, t)` for the sublevel set
/// `{½ Σ r² ≤ level}` (px²) of the given correspondences (their frame as given; centre the object
/// for a small search). Boxes of rotation vectors are split until pruned, inside the whitened ball of
/// radius `target`, or of half-width `min_half` (rad). Returns a dict: `depths` (step 1's bounds), the
/// kept cells as `centres` (K, 3) (rotation vectors `ω`, `R' = exp(ω) R`), `halves` (K, 3) (half-widths
/// per axis), `t_star` (K, 3), `C` (K, 3, 3), `slack` (K,) (the translation ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack`), `inside_ball`
/// (K,), `radius`, `pruned`, `nodes`; and the cells pruned by cheirality as `behind_centres`,
/// `behind_halves`, `behind_t_star`, `behind_C`, `behind_slack` (the search claims that in each some
/// point has `b · (R' X + t) ≤ 0`, `b` its observed ray, over the whole box and ellipsoid). A refusal of the proof (`not proved: ...`) is a `ValueError`.
#[pyfunction]
#[pyo3(signature = (camera, R, t, level, points2d = None, points3d = None, lines2d = None, lines3d = None, *, target = Real::new(f64::INFINITY), min_half = Real::new(2e-3), max_nodes = 400_000))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn _pose_rotation_search<'py>(
    py: Python<'py>,
    camera: &Bound<'py, PyCamera>,
    R: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
    level: Real,
    points2d: Option<&Bound<'py, PyAny>>,
    points3d: Option<&Bound<'py, PyAny>>,
    lines2d: Option<&Bound<'py, PyAny>>,
    lines3d: Option<&Bound<'py, PyAny>>,
    target: Real,
    min_half: Real,
    max_nodes: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let camera = pinhole_only("camera", camera.get())?;
    let pose = pose_from_parts("R", R, "t", t)?;
    let corr = correspondences(points2d, points3d, lines2d, lines3d)?;
    let (level, target, min_half) = (level.get("level")?, target.get("target")?, min_half.get("min_half")?);
    let region = guarded(|| {
        Ok(rotation_search(
            &camera, &corr, &pose, level, target, min_half, max_nodes,
        ))
    })?
    .map_err(|why| invalid_argument("level", why))?;
    let out = PyDict::new(py);
    out.set_item("depths", PyArray1::from_vec(py, region.depths.clone()))?;
    set_cells(&out, "", &region.cells)?;
    set_cells(&out, "behind_", &region.behind)?;
    out.set_item(
        "inside_ball",
        PyArray1::from_vec(py, region.cells.iter().map(|c| c.inside_ball).collect()),
    )?;
    out.set_item("radius", region.radius)?;
    out.set_item("pruned", region.pruned)?;
    out.set_item("nodes", region.nodes)?;
    Ok(out)
}

/// The boxes and translation ellipsoids of `cells` as arrays `{prefix}centres` (K, 3),
/// `{prefix}halves` (K, 3), `{prefix}t_star` (K, 3), `{prefix}C` (K, 3, 3), `{prefix}slack` (K,).
fn set_cells(out: &Bound<'_, PyDict>, prefix: &str, cells: &[KeptCell]) -> PyResult<()> {
    let py = out.py();
    let n = cells.len();
    let flat = |f: &dyn Fn(&KeptCell) -> Vec<f64>| cells.iter().flat_map(f).collect::<Vec<f64>>();
    out.set_item(
        format!("{prefix}centres"),
        PyArray1::from_vec(py, flat(&|c| c.centre.as_slice().to_vec())).reshape([n, 3])?,
    )?;
    out.set_item(
        format!("{prefix}t_star"),
        PyArray1::from_vec(py, flat(&|c| c.t_star.as_slice().to_vec())).reshape([n, 3])?,
    )?;
    let c = flat(&|c| (0..9).map(|i| c.c[(i / 3, i % 3)]).collect());
    out.set_item(format!("{prefix}C"), PyArray1::from_vec(py, c).reshape([n, 3, 3])?)?;
    out.set_item(
        format!("{prefix}halves"),
        PyArray1::from_vec(py, flat(&|c| c.half.as_slice().to_vec())).reshape([n, 3])?,
    )?;
    out.set_item(
        format!("{prefix}slack"),
        PyArray1::from_vec(py, cells.iter().map(|c| c.slack).collect()),
    )?;
    Ok(())
}

/// The pinhole part `K` of the camera argument `name` of a function that works in undistorted pixels
/// only; an `InvalidOptionError` naming it when the camera distorts (its pixels would be taken as
/// undistorted: a wrong answer).
fn pinhole_only(name: &str, camera: &PyCamera) -> PyResult<pluecker::camera::Intrinsics> {
    if camera.inner.distorts() {
        return Err(invalid_argument(
            name,
            format!(
                "a {} camera distorts; this function takes pinhole pixels: give camera.pinhole_part and \
                 pixels undistorted by camera.undistort",
                camera.inner.model().as_str()
            ),
        ));
    }
    Ok(camera.inner.intrinsics())
}
