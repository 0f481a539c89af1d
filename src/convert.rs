//! Conversions between the library's types and the wire protocol's, the
//! one place where they meet: [`to_proto`] for what leaves the library
//! (plan reports, plan requests, frames, the text link's waypoint lines)
//! and [`from_proto`] for what arrives (requests, joints, the text link's
//! plan lines). Policy (limits, timeouts, which frame) stays
//! with the daemon; here a value only changes its form, and a wire value
//! the library cannot represent is an error naming the field.

pub mod along_seam;
pub mod calibration;
pub mod woven;

/// Library values in the protocol's form.
pub mod to_proto {
    use std::collections::BTreeMap;

    use weldseam_proto::ErrorCode;
    use weldseam_proto::message::{self, Frame, FrameMeta, FrameSelect, Units};
    use weldseam_proto::plan as proto;
    use weldseam_proto::trace as proto_trace;

    pub use super::along_seam::add_along_seam;
    use super::from_proto::FrameInput;
    use crate::cloud::PointCloud;
    use crate::geometry::pose::EulerConvention;
    use crate::joint::{JointType, RequestedJoint};
    use crate::pipeline::quality::{Gate, GateFailure, SeamQuality, Spread};
    use crate::pipeline::refit::SeamCurve;
    use crate::pipeline::roi::Roi;
    use crate::pipeline::trace::TracedLine;
    use crate::pipeline::{CloudFrame, Plan, PlanError, PlanRequest, PlanTrace, Seam, Stage, Unplanned};

    /// The daemon's limits as a HelloAck carries them (capability
    /// `limits`). A count or time past the wire field's range is sent as
    /// the field's largest value, which no client can exceed anyway.
    pub fn limits(s: &crate::config::ServerConfig) -> message::DaemonLimits {
        let ms = |d: std::time::Duration| u64::try_from(d.as_millis()).unwrap_or(u64::MAX);
        let count = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
        message::DaemonLimits {
            max_frame_bytes: s.max_frame_bytes,
            max_message_bytes: weldseam_proto::MAX_CONTROL_MESSAGE_BYTES as u64,
            plan_queue_depth: count(s.plan_queue_depth),
            max_requests_per_connection: count(s.max_requests_per_connection),
            fresh_frame_timeout_ms: ms(s.fresh_frame_timeout),
            max_request_timeout_ms: ms(s.max_request_timeout),
            capture_time_tolerance_ms: ms(s.capture_time_tolerance),
            frame_history: count(s.frame_history),
            frame_history_bytes: s.frame_history_bytes,
            stall_timeout_ms: ms(s.stall_timeout),
        }
    }

    pub fn joint(j: JointType) -> proto::Joint {
        match j {
            JointType::VButt => proto::Joint::VButt,
            JointType::IButt => proto::Joint::IButt,
            JointType::Lap => proto::Joint::Lap,
            JointType::TFillet => proto::Joint::TFillet,
        }
    }

    fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
        [v.x, v.y, v.z]
    }

    fn seam(s: &Seam, euler: EulerConvention) -> proto::Seam {
        proto::Seam {
            joint: joint(s.joint),
            joint_evidence: s.joint_evidence.clone(),
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
            // Set by `add_along_seam` where the report carries them.
            along_seam: None,
            process: None,
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
            groove_angle_deg: q.groove_angle_deg,
            groove_depth_mm: q.groove_depth_mm,
        }
    }

    pub fn warning(f: &GateFailure) -> proto::GateWarning {
        proto::GateWarning {
            gate: f.gate.name().to_string(),
            rule: Some(f.rule.id.into()),
            value: f.value,
            limit: f.limit,
            message: f.message.clone(),
        }
    }

    /// The error code a refused plan carries: the gate's own code for a
    /// seam a quality gate refused, `bad_request` for a request that does
    /// not fit the frame, `plan_failed` for every other stage.
    pub fn plan_error_code(e: &PlanError) -> ErrorCode {
        if e.out_of_time {
            return ErrorCode::PlanTimeout;
        }
        match (e.gate, e.stage) {
            (Some(gate), _) => gate_code(gate),
            (None, Stage::Request) => ErrorCode::BadRequest,
            (None, _) => ErrorCode::PlanFailed,
        }
    }

    pub fn gate_code(gate: Gate) -> ErrorCode {
        match gate {
            Gate::EdgeCutShort => ErrorCode::EdgeCutShort,
            Gate::EdgeFitResidual => ErrorCode::EdgeFitResidual,
            Gate::EdgeCoverage => ErrorCode::EdgeCoverage,
            Gate::JointCoverage => ErrorCode::JointCoverage,
            Gate::Misalignment => ErrorCode::Misalignment,
            Gate::GapWidth => ErrorCode::GapWidth,
            Gate::GapUnresolved => ErrorCode::GapUnresolved,
            Gate::PlateAngle => ErrorCode::PlateAngle,
            Gate::PositionUncertainty => ErrorCode::PositionUncertainty,
            Gate::GrooveDepth => ErrorCode::GrooveDepth,
            Gate::JointMismatch => ErrorCode::JointMismatch,
            Gate::JointUnknown => ErrorCode::JointUnknown,
            Gate::CornerJoint => ErrorCode::CornerJoint,
        }
    }

    /// A joint seen but not planned, with the code and refusal a plan of
    /// it alone would have given.
    pub fn unplanned(u: &Unplanned) -> proto::UnplannedJoint {
        proto::UnplannedJoint {
            joint: u.joint.map(|j| j.name().into()),
            near_camera_mm: u.near_camera.as_ref().map(arr),
            code: plan_error_code(&u.reason).into(),
            refusal: refusal(&u.reason),
        }
    }

    /// Why a plan was refused, as `plan --json` prints it.
    pub fn refusal(e: &PlanError) -> proto::Refusal {
        proto::Refusal {
            stage: e.stage.name().into(),
            code: plan_error_code(e).name().into(),
            rule: Some(e.rule.id.into()),
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
            joint: trace.joint.map(joint),
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
            unplanned: plan.unplanned.iter().map(unplanned).collect(),
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
            joint: match request.joint {
                RequestedJoint::Auto => message::joint_code::AUTO,
                RequestedJoint::Type(j) => message::PlanRequest::joint_code(joint(j)),
                RequestedJoint::OneOf(set) => {
                    message::PlanRequest::joint_set_code(&set.iter().map(joint).collect::<Vec<_>>())
                }
            },
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
            pose_in: None,
            one_seam: request.one_seam,
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

/// The text link's forms of library values: poses in a robot dialect's
/// convention, and a plan as the waypoint lines a robot pulls.
pub mod to_text {
    use weldseam_proto::text::{Dialect, PointKind, Reply};

    use crate::geometry::Isometry3;
    use crate::geometry::conventions::PoseConvention;
    use crate::pipeline::Plan;
    use crate::pipeline::passes::{self, Motion};
    use crate::pipeline::trajectory::{Waypoint, backed_off};

    pub use super::woven::WeaveLaidBy;
    use super::woven::{PiecePoint, woven};

    /// How `dialect` writes a pose.
    pub fn convention(dialect: Dialect) -> PoseConvention {
        match dialect {
            Dialect::Ur => PoseConvention::UR,
            Dialect::Abb => PoseConvention::ABB,
            Dialect::Kuka => PoseConvention::KUKA,
            Dialect::Fanuc => PoseConvention::FANUC,
        }
    }

    /// A waypoint's numbers in `dialect`'s convention and units.
    pub fn pose(w: &Waypoint, dialect: Dialect) -> Vec<f64> {
        let convention = convention(dialect);
        let iso = Isometry3::from_parts(w.position.into(), w.orientation.into());
        convention.numbers(&iso)[..convention.numbers_len()].to_vec()
    }

    /// Every line a robot pulls for `plan`, seam by seam: each seam's
    /// approach point (`approach_offset_mm` back from its first waypoint
    /// along the torch axis), its waypoints, its retract point; each line
    /// counting the lines left after it. A seam without waypoints has no
    /// lines. With a process (a procedure configured), each piece of each
    /// pass the robot welds ([`passes::seam_pieces`]) is a seam of its own
    /// on the link, root first; with `process_lines`, each weld waypoint
    /// line is followed by its process line (travel speed and weave, zeros
    /// where the plan has none). Where the dialect's program has no weave
    /// function ([`weave_laid_by`]), a weaving piece's lines are its woven
    /// path ([`super::woven`]), each process line with the speed along
    /// it and no weave.
    pub fn waypoint_lines(plan: &Plan, dialect: Dialect, approach_offset_mm: f64, process_lines: bool) -> Vec<Reply> {
        let pieces: Vec<Vec<(Waypoint, Option<Motion>)>> =
            plan.seams.iter().flat_map(|seam| link_pieces(seam, dialect, process_lines)).collect();
        let mut lines: Vec<(u32, Line)> = Vec::new();
        for (piece, number) in pieces.iter().zip(1u32..) {
            let (Some(first), Some(last)) = (piece.first(), piece.last()) else { continue };
            lines.push((number, Line::Pose(PointKind::Approach, backed_off(&first.0, approach_offset_mm))));
            for (w, motion) in piece {
                lines.push((number, Line::Pose(PointKind::Weld, *w)));
                if process_lines {
                    lines.push((number, Line::Motion(*motion)));
                }
            }
            lines.push((number, Line::Pose(PointKind::Retract, backed_off(&last.0, approach_offset_mm))));
        }
        let total = lines.len() as u64;
        // The dialect's length unit: UR's metres.
        let scale = if dialect == Dialect::Ur { 0.001 } else { 1.0 };
        lines
            .into_iter()
            .zip(1u64..)
            .map(|((seam, line), pulled)| {
                let remaining = total - pulled;
                match line {
                    Line::Pose(kind, w) => Reply::Waypoint { kind, seam, remaining, pose: pose(&w, dialect) },
                    Line::Motion(motion) => {
                        let m = motion.unwrap_or(Motion {
                            travel_speed_mm_s: 0.0,
                            weave_amplitude_mm: 0.0,
                            weave_frequency_hz: 0.0,
                        });
                        let motion = [m.travel_speed_mm_s * scale, m.weave_amplitude_mm * scale, m.weave_frequency_hz];
                        Reply::Process { seam, remaining, motion }
                    }
                }
            })
            .collect()
    }

    /// Who lays the weave for `dialect`'s shipped program: the one place
    /// this is decided. ABB's ArcWare and FANUC's ArcTool weave from the
    /// process line's half-swing and frequency; the KUKA and UR programs
    /// switch the arc with an output and have no weave function, so the
    /// daemon writes the weave into their path.
    pub fn weave_laid_by(dialect: Dialect) -> WeaveLaidBy {
        match dialect {
            Dialect::Abb | Dialect::Fanuc => WeaveLaidBy::Controller,
            Dialect::Kuka | Dialect::Ur => WeaveLaidBy::Path,
        }
    }

    /// The pieces a link sends for `seam` ([`passes::seam_pieces`]), each
    /// woven into its path where `dialect`'s program does not weave. Only
    /// with process lines: the woven path's speeds come on them, and
    /// without them a program would weld the longer woven path at its own
    /// speed, slower along the seam than planned.
    pub fn link_pieces(
        seam: &crate::pipeline::Seam,
        dialect: Dialect,
        process_lines: bool,
    ) -> Vec<Vec<(Waypoint, Option<Motion>)>> {
        let woven_here = process_lines && weave_laid_by(dialect) == WeaveLaidBy::Path;
        let Some(passes) = passes::pass_trajectories(seam).filter(|_| woven_here) else {
            return passes::seam_pieces(seam);
        };
        passes
            .pieces
            .iter()
            .map(|pass| {
                let points: Vec<PiecePoint> = pass
                    .points
                    .iter()
                    .map(|p| PiecePoint { pose: p.pose, motion: Some(passes::motion(p)), weave: p.weave })
                    .collect();
                woven(&points)
            })
            .collect()
    }

    /// One line of a pull before it is numbered.
    enum Line {
        Pose(PointKind, Waypoint),
        Motion(Option<Motion>),
    }
}

/// Protocol values in the library's form.
pub mod from_proto {
    use weldseam_proto::message;
    use weldseam_proto::plan as proto;

    use crate::cloud::PointCloud;
    use crate::geometry::Vec3;
    use crate::geometry::conventions::{
        AngleUnit, LengthUnit, PoseConvention, PoseError, RotationForm, UnknownConvention,
    };
    use crate::geometry::pose::{EulerConvention, HandEyeError, RobotPose, hand_eye_from_rows};
    use crate::joint::{JointType, RequestedJoint};
    use crate::pipeline::roi::{Roi, RoiError};
    use crate::pipeline::{CloudFrame, PlanRequest, Units};

    pub fn joint(j: proto::Joint) -> JointType {
        match j {
            proto::Joint::VButt => JointType::VButt,
            proto::Joint::IButt => JointType::IButt,
            proto::Joint::Lap => JointType::Lap,
            proto::Joint::TFillet => JointType::TFillet,
        }
    }

    /// Why a wire plan request has no library form.
    #[derive(Debug, thiserror::Error)]
    pub enum RequestError {
        #[error("joint code {0} is unknown; expected 0 (v_butt), 1 (i_butt), 2 (lap), 3 (auto) or 4 (t_fillet)")]
        UnknownJoint(u32),
        #[error("hand_eye (End_T_Camera): {0}")]
        HandEye(#[from] HandEyeError),
        #[error("start_near has a non-finite coordinate: {0:?}")]
        StartNear([f64; 3]),
        #[error("roi.frame code {0} is unknown; expected 0 (camera) or 1 (base)")]
        RoiFrame(u32),
        #[error("roi: {0}")]
        Roi(#[from] RoiError),
        #[error("pose_in.convention: {0}")]
        PoseConvention(#[from] UnknownConvention),
        #[error("pose_in.{field} code {code} is unknown; expected 0 ({}) or 1 ({})", .names[0], .names[1])]
        PoseUnit { field: &'static str, code: u32, names: [&'static str; 2] },
        #[error("pose_in: {0}")]
        Pose(#[from] PoseError),
    }

    /// The convention a wire pose names.
    pub fn pose_convention(p: &message::PoseIn) -> Result<PoseConvention, RequestError> {
        let rotation: RotationForm = p.convention.parse()?;
        let length = match message::LengthUnit::from_u32(p.length_unit) {
            Some(message::LengthUnit::Millimetres) => LengthUnit::Millimetres,
            Some(message::LengthUnit::Metres) => LengthUnit::Metres,
            None => {
                return Err(RequestError::PoseUnit { field: "length_unit", code: p.length_unit, names: ["mm", "m"] });
            }
        };
        let angle = match message::AngleUnit::from_u32(p.angle_unit) {
            Some(message::AngleUnit::Degrees) => AngleUnit::Degrees,
            Some(message::AngleUnit::Radians) => AngleUnit::Radians,
            None => {
                return Err(RequestError::PoseUnit { field: "angle_unit", code: p.angle_unit, names: ["deg", "rad"] });
            }
        };
        Ok(PoseConvention { rotation, length, angle })
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

    /// Why a text link plan line has no library form.
    #[derive(Debug, thiserror::Error)]
    pub enum TextRequestError {
        #[error(transparent)]
        Joint(#[from] crate::joint::UnknownJoint),
        #[error("pose: {0}")]
        Pose(#[from] crate::geometry::conventions::PoseError),
    }

    /// The pipeline's request for a text link plan line in `dialect`: the
    /// joint by the library's names (`auto` too), the pose read in the dialect's
    /// convention and carried into the daemon's (`euler`), the groove
    /// depth from the dialect's length unit into mm.
    pub fn text_plan_request(
        line: &weldseam_proto::text::PlanLine,
        dialect: weldseam_proto::text::Dialect,
        euler: crate::geometry::pose::EulerConvention,
    ) -> Result<PlanRequest, TextRequestError> {
        let joint: RequestedJoint = line.joint.parse()?;
        let convention = super::to_text::convention(dialect);
        let pose = convention.to_robot_pose(&line.pose, euler)?;
        let groove_depth_mm = line.groove_depth.map(|d| d * convention.length.mm());
        Ok(PlanRequest::new(joint, groove_depth_mm, pose))
    }

    /// The pipeline's request for a controller's: joint, pose, hand-eye and
    /// the optional overrides. A pose in a convention of its own
    /// (`pose_in`) is carried into the daemon's, `euler`. The planner
    /// checks the ranges.
    pub fn plan_request(r: &message::PlanRequest, euler: EulerConvention) -> Result<PlanRequest, RequestError> {
        let joint = match r.joint_type() {
            Some(joint) => RequestedJoint::Type(self::joint(joint)),
            None if r.is_auto_joint() => RequestedJoint::Auto,
            None => r
                .joint_set()
                .and_then(|joints| RequestedJoint::one_of(joints.into_iter().map(self::joint).collect()))
                .ok_or(RequestError::UnknownJoint(r.joint))?,
        };
        let pose = match &r.pose_in {
            Some(p) => pose_convention(p)?.to_robot_pose(&p.values, euler)?,
            None => {
                let [x, y, z, rx, ry, rz] = r.pose;
                RobotPose { xyz_mm: [x, y, z], angles_deg: [rx, ry, rz] }
            }
        };
        let hand_eye = r.hand_eye.as_ref().map(hand_eye_from_rows).transpose()?;
        let start_near = match r.start_near {
            Some(p) if p.iter().all(|v| v.is_finite()) => Some(Vec3::from(p)),
            Some(p) => return Err(RequestError::StartNear(p)),
            None => None,
        };
        let roi = r.roi.as_ref().map(roi).transpose()?;
        Ok(PlanRequest {
            joint,
            groove_depth_mm: r.groove_depth_mm,
            pose,
            hand_eye,
            step_mm: r.step_mm,
            work_angle_deg: r.work_angle_deg,
            travel_angle_deg: r.travel_angle_deg,
            start_near,
            one_seam: r.one_seam,
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
    use weldseam_proto::message::{FrameSelect, PoseIn};

    use super::{from_proto, to_proto};
    use crate::geometry::Vec3;
    use crate::geometry::conventions::PoseConvention;
    use crate::geometry::pose::{EulerConvention, RobotPose};
    use crate::joint::{JointType, RequestedJoint};
    use crate::pipeline::PlanRequest;

    #[test]
    fn a_plan_request_survives_the_wire_and_a_bad_one_names_its_field() {
        let pose = RobotPose { xyz_mm: [1.0, -2.0, 3.5], angles_deg: [10.0, -20.0, 30.0] };
        let mut request = PlanRequest::new(JointType::VButt, Some(4.0), pose);
        request.step_mm = Some(2.5);
        request.start_near = Some(Vec3::new(7.0, 8.0, 9.0));
        let wire = to_proto::plan_request(7, &request, FrameSelect::NextFrame);
        assert_eq!((wire.request_id, wire.frame), (7, FrameSelect::NextFrame));
        let back = from_proto::plan_request(&wire, EulerConvention::Zyx).unwrap();
        assert_eq!((back.joint, back.groove_depth_mm, back.step_mm), (JointType::VButt.into(), Some(4.0), Some(2.5)));
        assert_eq!((back.pose.xyz_mm, back.pose.angles_deg), (pose.xyz_mm, pose.angles_deg));
        assert_eq!(back.start_near, request.start_near);

        // `auto` has its own code and comes back as `auto`.
        let auto = PlanRequest { joint: RequestedJoint::Auto, groove_depth_mm: None, ..request.clone() };
        let auto_wire = to_proto::plan_request(8, &auto, FrameSelect::NextFrame);
        assert_eq!(auto_wire.joint, weldseam_proto::message::joint_code::AUTO);
        assert_eq!(from_proto::plan_request(&auto_wire, EulerConvention::Zyx).unwrap().joint, RequestedJoint::Auto);

        // A tee is named on the wire (code 4) and on the text link, and
        // comes back as itself for the planner.
        let tee = PlanRequest { joint: JointType::TFillet.into(), groove_depth_mm: None, ..request.clone() };
        let tee_wire = to_proto::plan_request(9, &tee, FrameSelect::NextFrame);
        assert_eq!(tee_wire.joint, weldseam_proto::message::joint_code::T_FILLET);
        assert_eq!(from_proto::plan_request(&tee_wire, EulerConvention::Zyx).unwrap().joint, tee.joint);
        let line = weldseam_proto::text::PlanLine { joint: "t-fillet".into(), pose: vec![0.0; 6], groove_depth: None };
        let from_text =
            from_proto::text_plan_request(&line, weldseam_proto::text::Dialect::Kuka, EulerConvention::Zyx).unwrap();
        assert_eq!(from_text.joint, tee.joint);

        // A set of types: SET plus a bit per type's code, on the wire and
        // as `+`-joined names on the text link.
        let set: RequestedJoint = "lap+v-butt".parse().unwrap();
        let set_request = PlanRequest { joint: set, groove_depth_mm: None, ..request.clone() };
        let set_wire = to_proto::plan_request(10, &set_request, FrameSelect::NextFrame);
        assert_eq!(set_wire.joint, 0x105);
        assert_eq!(from_proto::plan_request(&set_wire, EulerConvention::Zyx).unwrap().joint, set);
        let line =
            weldseam_proto::text::PlanLine { joint: "v_butt+lap".into(), pose: vec![0.0; 6], groove_depth: None };
        let from_text =
            from_proto::text_plan_request(&line, weldseam_proto::text::Dialect::Kuka, EulerConvention::Zyx).unwrap();
        assert_eq!(from_text.joint, set);
        // A set of one type is that type's request; a set naming no type,
        // `auto`'s code or bits beyond the types is an unknown joint.
        let mut one = set_wire.clone();
        one.joint = 0x100 | 1 << 4;
        assert_eq!(from_proto::plan_request(&one, EulerConvention::Zyx).unwrap().joint, JointType::TFillet.into());
        for code in [0x100, 0x100 | 1 << 3, 0x100 | 1 << 5, 0x300 | 1, 0xff] {
            one.joint = code;
            let error = from_proto::plan_request(&one, EulerConvention::Zyx).unwrap_err().to_string();
            assert!(error.contains(&format!("joint code {code}")), "{code:#x}: {error}");
        }

        let mut unknown = wire.clone();
        unknown.joint = 9;
        assert!(
            from_proto::plan_request(&unknown, EulerConvention::Zyx).unwrap_err().to_string().contains("joint code 9")
        );
        let mut far = wire;
        far.start_near = Some([f64::NAN, 0.0, 0.0]);
        assert!(from_proto::plan_request(&far, EulerConvention::Zyx).unwrap_err().to_string().contains("start_near"));
    }

    #[test]
    fn a_pose_in_any_convention_reads_as_the_daemons() {
        let pose = RobotPose { xyz_mm: [800.0, -35.0, 556.0], angles_deg: [174.68, 2.24, 18.09] };
        let mut wire = to_proto::plan_request(1, &PlanRequest::new(JointType::Lap, None, pose), FrameSelect::Trigger);
        let iso = pose.to_isometry(EulerConvention::Zyx);
        for (name, length_unit, angle_unit, convention) in [
            ("kuka_abc", 0, 0, PoseConvention::KUKA),
            ("rotation_vector", 1, 1, PoseConvention::UR),
            ("quaternion_wxyz", 0, 0, PoseConvention::ABB),
        ] {
            let values = convention.numbers(&iso)[..convention.numbers_len()].to_vec();
            wire.pose = [0.0; 6];
            wire.pose_in = Some(PoseIn { convention: name.into(), length_unit, angle_unit, values });
            // Read into the daemon's convention, whichever it is.
            for euler in [EulerConvention::Zyx, EulerConvention::Xyz] {
                let back = from_proto::plan_request(&wire, euler).unwrap().pose.to_isometry(euler);
                assert!((back.to_homogeneous() - iso.to_homogeneous()).norm() < 1e-9, "{name} as {euler:?}");
            }
        }
        let bad = |convention: &str, length_unit: u32, values: Vec<f64>| {
            let mut w = wire.clone();
            w.pose_in = Some(PoseIn { convention: convention.into(), length_unit, angle_unit: 0, values });
            from_proto::plan_request(&w, EulerConvention::Zyx).unwrap_err().to_string()
        };
        assert!(bad("zyz", 0, vec![0.0; 6]).contains("pose_in.convention"));
        assert!(bad("kuka_abc", 7, vec![0.0; 6]).contains("pose_in.length_unit code 7"));
        assert!(bad("kuka_abc", 0, vec![0.0; 5]).contains("6 numbers, got 5"));
        assert!(bad("kuka_abc", 0, vec![0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0]).contains("not finite"));
    }
}
