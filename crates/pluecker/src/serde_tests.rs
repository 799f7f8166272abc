//! The `serde` feature: results, cameras and options round-trip through JSON (readable, names as the
//! crate spells them) and CBOR (floats bit for bit, NaN included); a camera is checked again when read.

use crate::camera::{Camera, CameraModel};
use crate::pose::{estimate_pose, PoseOptions, PoseResult};
use crate::triangulation::point::{triangulate_point, PointTriangulation};
use crate::triangulation::{Method, TriangulationOptions};
use crate::{synthetic, CertifyOptions, RansacOptions, Status};
use nalgebra::{Matrix3, Matrix3x4, Vector2, Vector3};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;
use std::time::Duration;

/// `value` written as JSON and read back; the JSON too.
fn through_json<T: Serialize + DeserializeOwned>(value: &T) -> (T, String) {
    let json = serde_json::to_string(value).unwrap();
    (serde_json::from_str(&json).unwrap(), json)
}

/// `value` written as CBOR and read back.
fn through_cbor<T: Serialize + DeserializeOwned>(value: &T) -> T {
    let mut bytes = Vec::new();
    ciborium::into_writer(value, &mut bytes).unwrap();
    ciborium::from_reader(bytes.as_slice()).unwrap()
}

/// Asserts that `value` comes back equal through JSON and through CBOR; returns the JSON.
fn round_trips<T: Serialize + DeserializeOwned + PartialEq + Debug>(value: &T) -> String {
    let (back, json) = through_json(value);
    assert_eq!(&back, value, "through JSON: {json}");
    assert_eq!(&through_cbor(value), value, "through CBOR");
    json
}

/// A NaN with a payload and its sign bit set: only an exact copy keeps both.
fn odd_nan(payload: u64) -> f64 {
    f64::from_bits(0xfff0_0000_0000_0000 | payload)
}

fn pose_result() -> PoseResult {
    let scene = synthetic::random_scene(synthetic::SceneKind::General, 20, 5, 42);
    let options = PoseOptions {
        certify: Some(CertifyOptions::default()),
        sigma_px: Some(1.0),
        ..PoseOptions::default()
    };
    estimate_pose(&scene.camera, &scene.correspondences, &options).unwrap()
}

fn point_triangulation() -> PointTriangulation {
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let camera = |cx: f64| k * Matrix3x4::new(1.0, 0.0, 0.0, -cx, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    let projections = [camera(0.0), camera(1.0), camera(2.0)];
    let x = Vector3::new(0.3, -0.2, 5.0);
    let pixels: Vec<Vector2<f64>> = projections
        .iter()
        .map(|p| {
            let h = p * x.push(1.0);
            Vector2::new(h.x / h.z + 0.3, h.y / h.z - 0.2)
        })
        .collect();
    triangulate_point(&projections, &pixels, None, &TriangulationOptions::default()).unwrap()
}

#[test]
fn a_pose_result_round_trips_with_its_names() {
    let result = pose_result();
    assert!(result.report.certificate.is_some() && result.details.residual_test.is_some());
    let json = round_trips(&result);
    assert!(json.contains(r#""status":"success""#), "{json}");
    assert!(json.contains(r#""method":"trust-region""#), "{json}");
    assert!(json.contains(r#""kind":"sublevel_set""#), "{json}");
}

#[test]
fn the_json_has_the_reports_fields_beside_the_results_and_matrices_as_rows() {
    let mut result = pose_result();
    result.report.cost = f64::NAN;
    let json: serde_json::Value = serde_json::from_str(&serde_json::to_string(&result).unwrap()).unwrap();
    assert!(json.get("report").is_none(), "{json}");
    assert_eq!(json["status"], "success");
    assert_eq!(json["success"], true);
    assert_eq!(json["certified"], result.report.certified());
    assert!(json["cost"].is_null(), "NaN is written as null");
    assert_eq!(json["residual_dof"], result.report.residual_dof);
    let r = &result.pose.rotation;
    for i in 0..3 {
        let row: Vec<f64> = (0..3)
            .map(|j| json["pose"]["rotation"][i][j].as_f64().unwrap())
            .collect();
        assert_eq!(row, [r[(i, 0)], r[(i, 1)], r[(i, 2)]], "row {i}");
    }
    let covariance = result.covariance.unwrap();
    assert_eq!(json["covariance"][1][4].as_f64(), Some(covariance[(1, 4)]));
    let point = point_triangulation();
    let json: serde_json::Value = serde_json::from_str(&serde_json::to_string(&point).unwrap()).unwrap();
    assert_eq!(json["method"], point.report.method.as_str());
    assert_eq!(json["covariance"][0][2].as_f64(), point.covariance.map(|c| c[(0, 2)]));
}

#[test]
fn nan_fields_keep_their_bits_through_cbor() {
    let mut result = pose_result();
    result.report.cost = odd_nan(1);
    result.pose.translation.x = odd_nan(0xdead_beef);
    result.details.behind_camera_cost = Some(f64::NAN);
    let back = through_cbor(&result);
    let bits = |r: &PoseResult| {
        let behind = r.details.behind_camera_cost.map(f64::to_bits);
        (r.report.cost.to_bits(), r.pose.translation.x.to_bits(), behind)
    };
    assert_eq!(bits(&back), bits(&result));
    // Every other field is equal: compared with the NaNs replaced by a number in both.
    let numbers = |mut r: PoseResult| {
        r.report.cost = 0.0;
        r.pose.translation.x = 0.0;
        r.details.behind_camera_cost = Some(0.0);
        r
    };
    assert_eq!(numbers(back), numbers(result));

    let mut point = point_triangulation();
    point.point.y = odd_nan(7);
    point.report.cost = f64::NAN;
    let back = through_cbor(&point);
    assert_eq!(back.point.y.to_bits(), point.point.y.to_bits());
    assert_eq!(back.report.cost.to_bits(), point.report.cost.to_bits());
}

#[test]
fn a_point_triangulation_round_trips() {
    let point = point_triangulation();
    assert!(point.covariance.is_some());
    let json = round_trips(&point);
    assert!(json.contains(r#""cost_kind":"#), "{json}");
}

#[test]
fn a_camera_is_its_model_and_parameters() {
    let params = [800.0, 790.0, 320.0, 240.0, -0.12, 0.03, 1e-3, -2e-3];
    let camera = Camera::new(CameraModel::OpenCv, &params).unwrap();
    let json = round_trips(&camera);
    assert_eq!(
        json,
        r#"{"model":"OPENCV","params":[800.0,790.0,320.0,240.0,-0.12,0.03,0.001,-0.002]}"#
    );
}

#[test]
fn an_invalid_camera_does_not_deserialise() {
    for (model, params) in [
        (CameraModel::Pinhole, vec![0.0, 800.0, 320.0, 240.0]),
        (CameraModel::SimpleRadial, vec![800.0, 320.0, 240.0]),
    ] {
        let core = Camera::new(model, &params).unwrap_err().to_string();
        let json = format!(r#"{{"model":"{}","params":{params:?}}}"#, model.as_str());
        let error = serde_json::from_str::<Camera>(&json).unwrap_err().to_string();
        assert!(error.contains(&core), "{error} does not say {core}");
    }
    let error = serde_json::from_str::<Camera>(r#"{"model":"PINHOLE_X","params":[]}"#).unwrap_err();
    assert!(error
        .to_string()
        .contains("unknown name 'PINHOLE_X'; expected one of SIMPLE_PINHOLE, PINHOLE"));
}

#[test]
fn options_round_trip() {
    let ransac = RansacOptions {
        time_budget: Some(Duration::from_millis(250)),
        seed: 7,
        ..RansacOptions::default()
    };
    let pose = PoseOptions {
        method: crate::pose::Method::LevenbergMarquardt,
        ransac: Some(ransac),
        certify: Some(CertifyOptions::default()),
        initial_pose: Some(crate::Pose {
            rotation: Matrix3::identity(),
            translation: Vector3::new(0.1, 0.2, 3.0),
        }),
        ..PoseOptions::default()
    };
    let json = round_trips(&pose);
    assert!(json.contains(r#""method":"levenberg-marquardt""#), "{json}");
    assert!(json.contains(r#""subproblem":"hebden""#), "{json}");

    let triangulation = TriangulationOptions {
        method: Method::ALL[Method::ALL.len() - 1],
        outlier_threshold: Some(2.5),
        ..TriangulationOptions::default()
    };
    round_trips(&triangulation);
}

#[test]
fn named_enums_are_their_names() {
    for status in <Status as strum::VariantArray>::VARIANTS {
        let (back, json) = through_json(status);
        assert_eq!(json, format!("\"{}\"", status.as_str()));
        assert_eq!(&back, status);
    }
    let error = serde_json::from_str::<Status>(r#""fine""#).unwrap_err().to_string();
    assert!(
        error.contains("unknown name 'fine'; expected one of success"),
        "{error}"
    );
}
