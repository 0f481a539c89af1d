//! Conversions between the library's types and the wire protocol's, the
//! one place where they meet: [`to_proto`] for what leaves the library
//! (plan reports, plan requests, frames) and [`from_proto`] for what
//! arrives (requests, joints). Policy (limits, timeouts, which frame) stays
//! with the daemon; here a value only changes its form, and a wire value
//! the library cannot represent is an error naming the field.

/// Library values in the protocol's form.
pub mod to_proto {
    use std::collections::BTreeMap;

    use weldseam_proto::message::{self, Frame, FrameMeta, FrameSelect, Units};
    use weldseam_proto::plan as proto;

    use crate::cloud::PointCloud;
    use crate::geometry::pose::EulerConvention;
    use crate::joint::JointType;
    use crate::pipeline::{Plan, PlanRequest, Seam};

    pub fn joint(j: JointType) -> proto::Joint {
        match j {
            JointType::VButt => proto::Joint::VButt,
            JointType::IButt => proto::Joint::IButt,
            JointType::Lap => proto::Joint::Lap,
        }
    }

    fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
        [v.x, v.y, v.z]
    }

    fn seam(s: &Seam, euler: EulerConvention) -> proto::Seam {
        proto::Seam {
            joint: joint(s.joint),
            waypoints: s
                .waypoints
                .iter()
                .map(|w| proto::Waypoint { xyz: arr(&w.position), rpy_deg: euler.angles(&w.orientation) })
                .collect(),
            start_camera: arr(&s.start_camera),
            end_camera: arr(&s.end_camera),
            normal_camera: arr(&s.normal_camera),
            length_mm: s.length_mm,
            edge_fit_rms_mm: s.edge_fit_rms_mm,
            edge_samples: s.edge_samples.map(|n| n as u32),
            edge_samples_dropped: s.edge_samples_dropped.map(|n| n as u32),
        }
    }

    /// The report of `plan`, with orientations in `euler`'s angles.
    pub fn plan_result(plan: &Plan, euler: EulerConvention) -> proto::PlanResult {
        let mut timing_ms: BTreeMap<String, f64> =
            plan.timings.stages.iter().map(|(stage, ms)| (stage.name().to_string(), *ms)).collect();
        timing_ms.insert("total".into(), plan.timings.total_ms());
        let s = &plan.stats;
        proto::PlanResult {
            seams: plan.seams.iter().map(|x| seam(x, euler)).collect(),
            timing_ms,
            method: plan.method.name().into(),
            euler_convention: euler.name().into(),
            points: proto::PointCounts {
                valid: s.valid_points as u64,
                plane: s.plane_points as u64,
                clusters: s.clusters as u32,
                plates: s.plate_points.map(|n| n as u64),
                edges: s.edge_points.map(|n| n as u64),
                edge_lines: s.edge_lines as u32,
            },
        }
    }

    /// The controller's plan request `request_id` for `request`, planned
    /// from the frame `frame` selects, with the daemon's default timeout
    /// and any camera.
    pub fn plan_request(request_id: u64, request: &PlanRequest, frame: FrameSelect) -> message::PlanRequest {
        let [x, y, z] = request.pose.xyz_mm;
        let [rx, ry, rz] = request.pose.angles_deg;
        message::PlanRequest {
            request_id,
            joint: message::PlanRequest::joint_code(joint(request.joint)),
            groove_depth_mm: request.groove_depth_mm,
            pose: [x, y, z, rx, ry, rz],
            step_mm: request.step_mm,
            work_angle_deg: request.work_angle_deg,
            travel_angle_deg: request.travel_angle_deg,
            frame,
            timeout_ms: 0,
            camera: None,
            hand_eye: request.hand_eye.map(|m| {
                let h = m.to_homogeneous();
                std::array::from_fn(|k| h[(k / 4, k % 4)])
            }),
            start_near: request.start_near.map(|p| arr(&p)),
        }
    }

    /// The camera link's Frame message for `cloud` (millimetres), answering
    /// trigger `trigger_id` (0 when free-running).
    pub fn frame(cloud: &PointCloud, frame_id: u64, trigger_id: u64, capture_time_us: u64) -> Frame {
        let meta = FrameMeta {
            frame_id,
            trigger_id,
            capture_time_us,
            width: cloud.width() as u32,
            height: cloud.height() as u32,
            units: Units::Millimetres as u32,
        };
        Frame { meta, points: cloud.points().to_vec() }
    }
}

/// Protocol values in the library's form.
pub mod from_proto {
    use weldseam_proto::message;
    use weldseam_proto::plan as proto;

    use crate::geometry::Vec3;
    use crate::geometry::pose::{HandEyeError, RobotPose, hand_eye_from_rows};
    use crate::joint::JointType;
    use crate::pipeline::{CloudFrame, PlanRequest, Units};

    pub fn joint(j: proto::Joint) -> JointType {
        match j {
            proto::Joint::VButt => JointType::VButt,
            proto::Joint::IButt => JointType::IButt,
            proto::Joint::Lap => JointType::Lap,
        }
    }

    /// Why a wire plan request has no library form.
    #[derive(Debug, thiserror::Error)]
    pub enum RequestError {
        #[error("joint code {0} is unknown; expected 0 (v_butt), 1 (i_butt) or 2 (lap)")]
        UnknownJoint(u32),
        #[error("hand_eye (End_T_Camera): {0}")]
        HandEye(#[from] HandEyeError),
        #[error("start_near has a non-finite coordinate: {0:?}")]
        StartNear([f64; 3]),
    }

    /// The pipeline's request for a controller's: joint, pose, hand-eye and
    /// the optional overrides. The planner checks their ranges.
    pub fn plan_request(r: &message::PlanRequest) -> Result<PlanRequest, RequestError> {
        let joint = r.joint_type().ok_or(RequestError::UnknownJoint(r.joint))?;
        let [x, y, z, rx, ry, rz] = r.pose;
        let hand_eye = r.hand_eye.as_ref().map(hand_eye_from_rows).transpose()?;
        let start_near = match r.start_near {
            Some(p) if p.iter().all(|v| v.is_finite()) => Some(Vec3::from(p)),
            Some(p) => return Err(RequestError::StartNear(p)),
            None => None,
        };
        Ok(PlanRequest {
            joint: self::joint(joint),
            groove_depth_mm: r.groove_depth_mm,
            pose: RobotPose { xyz_mm: [x, y, z], angles_deg: [rx, ry, rz] },
            hand_eye,
            step_mm: r.step_mm,
            work_angle_deg: r.work_angle_deg,
            travel_angle_deg: r.travel_angle_deg,
            start_near,
            // Frames arrive in the camera frame and are scaled to
            // millimetres by their units code as they are decoded.
            units: Units::Millimetres,
            cloud_frame: CloudFrame::Camera,
        })
    }
}

#[cfg(test)]
mod tests {
    use weldseam_proto::message::FrameSelect;

    use super::{from_proto, to_proto};
    use crate::geometry::Vec3;
    use crate::geometry::pose::RobotPose;
    use crate::joint::JointType;
    use crate::pipeline::PlanRequest;

    #[test]
    fn a_plan_request_survives_the_wire_and_a_bad_one_names_its_field() {
        let pose = RobotPose { xyz_mm: [1.0, -2.0, 3.5], angles_deg: [10.0, -20.0, 30.0] };
        let mut request = PlanRequest::new(JointType::VButt, Some(4.0), pose);
        request.step_mm = Some(2.5);
        request.start_near = Some(Vec3::new(7.0, 8.0, 9.0));
        let wire = to_proto::plan_request(7, &request, FrameSelect::NextFrame);
        assert_eq!((wire.request_id, wire.frame), (7, FrameSelect::NextFrame));
        let back = from_proto::plan_request(&wire).unwrap();
        assert_eq!((back.joint, back.groove_depth_mm, back.step_mm), (JointType::VButt, Some(4.0), Some(2.5)));
        assert_eq!((back.pose.xyz_mm, back.pose.angles_deg), (pose.xyz_mm, pose.angles_deg));
        assert_eq!(back.start_near, request.start_near);

        let mut unknown = wire.clone();
        unknown.joint = 9;
        assert!(from_proto::plan_request(&unknown).unwrap_err().to_string().contains("joint code 9"));
        let mut far = wire;
        far.start_near = Some([f64::NAN, 0.0, 0.0]);
        assert!(from_proto::plan_request(&far).unwrap_err().to_string().contains("start_near"));
    }
}
