//! Conversions between the library's types and the wire protocol's, the
//! one place where they meet: [`to_proto`] for what leaves the library
//! (plan reports, plan requests, frames) and [`from_proto`] for what
//! arrives (requests, joints). Policy (limits, timeouts, which frame) stays
//! with the daemon; here a value only changes its form, and a wire value
//! the library cannot represent is an error naming the field.

/// Library values in the protocol's form.
pub mod to_proto {
    use std::collections::BTreeMap;

    use weldseam_proto::ErrorCode;
    use weldseam_proto::message::{self, Frame, FrameMeta, FrameSelect, Units};
    use weldseam_proto::plan as proto;
    use weldseam_proto::trace as proto_trace;

    use super::from_proto::FrameInput;
    use crate::cloud::PointCloud;
    use crate::geometry::pose::EulerConvention;
    use crate::joint::JointType;
    use crate::pipeline::quality::{Gate, GateFailure, SeamQuality, Spread};
    use crate::pipeline::refit::SeamCurve;
    use crate::pipeline::roi::Roi;
    use crate::pipeline::trace::TracedLine;
    use crate::pipeline::{CloudFrame, Plan, PlanError, PlanRequest, PlanTrace, Seam, Stage};

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
            coverage: s.coverage.map(|c| proto::SeamCoverage {
                edge: c.edge,
                joint: c.joint,
                visible_joint_mm: c.visible_joint_mm,
                beyond_mm: c.beyond_mm,
            }),
            quality: s.quality.as_ref().map(quality),
            warnings: s.warnings.iter().map(warning).collect(),
        }
    }

    fn spread(s: &Spread) -> proto::Spread {
        proto::Spread { min: s.min, mean: s.mean, max: s.max }
    }

    pub fn quality(q: &SeamQuality) -> proto::SeamQuality {
        proto::SeamQuality {
            point_spacing_mm: q.point_spacing_mm,
            gap_mm: q.gap_mm.as_ref().map(spread),
            misalignment_mm: q.misalignment_mm,
            lap_step_mm: q.lap_step_mm,
            depth_to_support_mm: q.depth_to_support_mm,
            plate_angle_deg: q.plate_angle_deg,
            uncertainty_across_mm: q.uncertainty_across_mm,
            uncertainty_normal_mm: q.uncertainty_normal_mm,
        }
    }

    pub fn warning(f: &GateFailure) -> proto::GateWarning {
        proto::GateWarning {
            gate: f.gate.name().to_string(),
            value: f.value,
            limit: f.limit,
            message: f.message.clone(),
        }
    }

    /// The error code a refused plan carries: the gate's own code for a
    /// seam a quality gate refused, `bad_request` for a request that does
    /// not fit the frame, `plan_failed` for every other stage.
    pub fn plan_error_code(e: &PlanError) -> ErrorCode {
        match (e.gate, e.stage) {
            (Some(gate), _) => gate_code(gate),
            (None, Stage::Request) => ErrorCode::BadRequest,
            (None, _) => ErrorCode::PlanFailed,
        }
    }

    pub fn gate_code(gate: Gate) -> ErrorCode {
        match gate {
            Gate::EdgeFitResidual => ErrorCode::EdgeFitResidual,
            Gate::EdgeCoverage => ErrorCode::EdgeCoverage,
            Gate::JointCoverage => ErrorCode::JointCoverage,
            Gate::Misalignment => ErrorCode::Misalignment,
            Gate::GapWidth => ErrorCode::GapWidth,
            Gate::PlateAngle => ErrorCode::PlateAngle,
            Gate::PositionUncertainty => ErrorCode::PositionUncertainty,
            Gate::JointMismatch => ErrorCode::JointMismatch,
        }
    }

    /// Why a plan was refused, as `plan --json` prints it.
    pub fn refusal(e: &PlanError) -> proto::Refusal {
        proto::Refusal {
            stage: e.stage.name().into(),
            code: plan_error_code(e).name().into(),
            gate: e.gate.map(|g| g.name().into()),
            message: e.reason.clone(),
        }
    }

    /// The figures of a plan's trace, with `report` (the plan as `plan
    /// --json` prints it) when there is one.
    pub fn plan_trace(trace: &PlanTrace, report: Option<proto::PlanResult>) -> proto_trace::PlanTrace {
        let count = |n: usize| n as u64;
        let plate_of = |label: u32| {
            trace.plate_labels.and_then(|labels| labels.iter().position(|&l| l == label)).map(|k| k as u8 + 1)
        };
        let ends = |curve: &SeamCurve, (s0, s1): (f64, f64)| [arr(&curve.at(s0)), arr(&curve.at(s1))];
        let line = |l: &TracedLine| proto_trace::TraceLine {
            plate: l.plate as u8 + 1,
            rank: l.rank as u32,
            inliers: count(l.inliers),
            ends: l.ends.each_ref().map(arr),
            picked: l.picked,
        };
        proto_trace::PlanTrace {
            joint: joint(trace.joint),
            groove_depth_mm: trace.groove_depth_mm,
            method: trace.method.name().into(),
            plan: report,
            error: trace.refusal.as_ref().map(refusal),
            points: proto_trace::TracePoints {
                valid: trace.cloud.as_ref().map_or(0, |c| count(c.valid_count())),
                plane: count(trace.plane_points.iter().filter(|&&p| p).count()),
                plates: trace
                    .plate_labels
                    .map(|_| [0, 1].map(|k| trace.plate(k).map_or(0, |p| count(p.members.len())))),
                edges: trace.edge_points.each_ref().map(|e| count(e.len())),
                fit_samples: trace.fit_samples.each_ref().map(|s| count(s.len())),
            },
            dominant_normal: trace.dominant_normal.as_ref().map(arr),
            planes: trace
                .planes
                .iter()
                .map(|p| proto_trace::TracePlane {
                    label: p.label,
                    points: count(p.members.len()),
                    area_mm2: p.area_mm2,
                    normal: arr(&p.plane.normal),
                    offset_mm: p.plane.offset,
                    centroid: arr(&p.centroid),
                    plate: plate_of(p.label),
                })
                .collect(),
            edge_lines: trace.edge_lines.iter().map(line).collect(),
            weld_edges: trace
                .weld_edges
                .iter()
                .flatten()
                .map(|f| proto_trace::TraceEdge {
                    rms_mm: f.rms_mm,
                    samples: count(f.points_used),
                    dropped: count(f.points_dropped),
                    ends: ends(&f.curve, (f.curve.s_min, f.curve.s_max)),
                })
                .collect(),
            weld: trace.weld.as_ref().map(|w| proto_trace::TraceWeld {
                ends: ends(&w.curve, w.span),
                normal: arr(&w.normal),
                length_mm: w.length_mm(),
            }),
            waypoints_camera: trace.waypoints_camera.iter().map(arr).collect(),
            quality: trace.quality.as_ref().map(quality),
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
            roi: request.roi.as_ref().map(roi),
        }
    }

    /// The camera link's Frame message for `cloud` (camera frame,
    /// millimetres), answering trigger `trigger_id` (0 when free-running).
    /// An unorganized cloud goes as a frame of height 1.
    pub fn frame(cloud: &PointCloud, frame_id: u64, trigger_id: u64, capture_time_us: u64) -> Frame {
        frame_in(cloud, FrameInput::default(), frame_id, trigger_id, capture_time_us)
    }

    /// As [`frame`], for a cloud in the units and frame `input` names.
    pub fn frame_in(
        cloud: &PointCloud,
        input: FrameInput,
        frame_id: u64,
        trigger_id: u64,
        capture_time_us: u64,
    ) -> Frame {
        let meta = FrameMeta {
            frame_id,
            trigger_id,
            capture_time_us,
            width: cloud.width() as u32,
            height: cloud.height() as u32,
            units: units(input.units) as u32,
            cloud_frame: cloud_frame(input.cloud_frame) as u32,
        };
        Frame { meta, points: cloud.points().to_vec() }
    }

    pub fn units(u: crate::pipeline::Units) -> Units {
        match u {
            crate::pipeline::Units::Millimetres => Units::Millimetres,
            crate::pipeline::Units::Metres => Units::Metres,
            crate::pipeline::Units::Auto => Units::Auto,
        }
    }

    pub fn cloud_frame(f: CloudFrame) -> message::CloudFrame {
        match f {
            CloudFrame::Camera => message::CloudFrame::Camera,
            CloudFrame::Base => message::CloudFrame::Base,
        }
    }

    /// A region of interest in the wire's form.
    pub fn roi(r: &Roi) -> message::Roi {
        message::Roi { min_mm: arr(&r.min()), max_mm: arr(&r.max()), frame: cloud_frame(r.frame()) as u32 }
    }
}

/// Protocol values in the library's form.
pub mod from_proto {
    use weldseam_proto::message;
    use weldseam_proto::plan as proto;

    use crate::cloud::PointCloud;
    use crate::geometry::Vec3;
    use crate::geometry::pose::{HandEyeError, RobotPose, hand_eye_from_rows};
    use crate::joint::JointType;
    use crate::pipeline::roi::{Roi, RoiError};
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
        #[error("roi.frame code {0} is unknown; expected 0 (camera) or 1 (base)")]
        RoiFrame(u32),
        #[error("roi: {0}")]
        Roi(#[from] RoiError),
    }

    pub fn cloud_frame(f: message::CloudFrame) -> CloudFrame {
        match f {
            message::CloudFrame::Camera => CloudFrame::Camera,
            message::CloudFrame::Base => CloudFrame::Base,
        }
    }

    /// A wire region of interest as the library's, checked as a box.
    pub fn roi(r: &message::Roi) -> Result<Roi, RequestError> {
        let frame = message::CloudFrame::from_u32(r.frame).ok_or(RequestError::RoiFrame(r.frame))?;
        Ok(Roi::new(r.min_mm, r.max_mm, cloud_frame(frame))?)
    }

    /// How a frame's points are to be read: the units and frame to tell
    /// the planner once they have been decoded.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct FrameInput {
        pub units: Units,
        pub cloud_frame: CloudFrame,
    }

    /// The library's cloud for a decoded Frame and how to read it. A frame
    /// of height 1 is unorganized, its invalid points dropped, as a PCD or
    /// PLY file of height 1 is read; taller frames keep their grid. Metres
    /// were scaled to millimetres as the points were decoded, so only a
    /// frame whose units are to be guessed leaves a choice to the planner.
    /// None when the points are not width x height.
    pub fn frame(frame: message::Frame) -> Option<(PointCloud, FrameInput)> {
        let meta = frame.meta;
        let units = match message::Units::from_u32(meta.units)? {
            message::Units::Millimetres | message::Units::Metres => Units::Millimetres,
            message::Units::Auto => Units::Auto,
        };
        let cloud_frame = cloud_frame(message::CloudFrame::from_u32(meta.cloud_frame)?);
        let cloud = if meta.height == 1 {
            (frame.points.len() == meta.width as usize).then(|| PointCloud::unorganized(frame.points))?
        } else {
            PointCloud::organized(meta.width as usize, meta.height as usize, frame.points)?
        };
        Some((cloud, FrameInput { units, cloud_frame }))
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
        let roi = r.roi.as_ref().map(roi).transpose()?;
        Ok(PlanRequest {
            joint: self::joint(joint),
            groove_depth_mm: r.groove_depth_mm,
            pose: RobotPose { xyz_mm: [x, y, z], angles_deg: [rx, ry, rz] },
            hand_eye,
            step_mm: r.step_mm,
            work_angle_deg: r.work_angle_deg,
            travel_angle_deg: r.travel_angle_deg,
            start_near,
            // The frame tells its units and frame when it comes (see
            // [`frame`]); until then, the library's defaults.
            units: Units::Millimetres,
            cloud_frame: CloudFrame::Camera,
            roi,
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
