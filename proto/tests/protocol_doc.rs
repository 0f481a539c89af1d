//! PROTOCOL.md's hex examples are the encodings this crate produces: the
//! document cannot drift from the code.

use std::collections::BTreeMap;

use serde::de::{self, DeserializeOwned, Visitor};
use weldseam_proto::along_seam::{
    AlongSeam, CutStretch, JointFigures, Measured, Pass, PassKind, SeamProcess, WaypointProcess, Weave,
};
use weldseam_proto::frame::{encode, encode_in};
use weldseam_proto::message::{
    CloudFrame, DaemonLimits, ErrorCode, Frame, FrameAck, FrameMeta, FrameSelect, Hello, HelloAck, Message, PlanReply,
    PlanRequest, Roi, Role, Status, Trigger, Units, joint_code,
};
use weldseam_proto::plan::{
    GateWarning, Joint, PlanResult, PointCounts, Refusal, Seam, SeamCoverage, SeamQuality, UnplannedJoint, Waypoint,
};
use weldseam_proto::session::capability;
use weldseam_proto::{PROTOCOL_VERSION, Session};

fn hex_dump(bytes: &[u8]) -> String {
    bytes
        .chunks(16)
        .enumerate()
        .map(|(i, row)| {
            let hex: Vec<String> = row.iter().map(|b| format!("{b:02x}")).collect();
            format!("{:04x}  {}\n", i * 16, hex.join(" "))
        })
        .collect()
}

/// A lap seam of two waypoints with its quality figures and one warning,
/// beside a tee root left unplanned.
fn plan_reply() -> PlanReply {
    let seam = Seam {
        joint: Joint::Lap,
        joint_evidence: Some("lap".into()),
        waypoints: vec![
            Waypoint { xyz: [800.0, -100.0, 20.0], rpy_deg: [180.0, 0.0, 90.0] },
            Waypoint { xyz: [800.0, 100.0, 20.0], rpy_deg: [180.0, 0.0, 90.0] },
        ],
        start_camera: [-100.0, 0.0, 480.0],
        end_camera: [100.0, 0.0, 480.0],
        normal_camera: [0.0, 0.0, 1.0],
        length_mm: 200.0,
        edge_fit_rms_mm: [0.25, 0.5],
        edge_samples: [400, 380],
        edge_samples_dropped: [2, 4],
        coverage: Some(SeamCoverage { edge: [1.0, 0.75], joint: 1.0, visible_joint_mm: 200.0, beyond_mm: 0.0 }),
        quality: Some(SeamQuality {
            point_spacing_mm: 0.5,
            gap_mm: None,
            misalignment_mm: None,
            lap_step_mm: Some(5.0),
            depth_to_support_mm: None,
            plate_angle_deg: 0.5,
            uncertainty_across_mm: 0.625,
            uncertainty_normal_mm: 0.625,
            groove_angle_deg: None,
            groove_depth_mm: None,
        }),
        warnings: vec![GateWarning {
            gate: "position_uncertainty".into(),
            rule: Some("seam.position_uncertainty".into()),
            value: 0.625,
            limit: 0.5,
            message: "0.625 > 0.5 mm".into(),
        }],
        along_seam: None,
        process: None,
    };
    let unplanned = UnplannedJoint {
        joint: Some("t_fillet".into()),
        near_camera_mm: Some([0.0, 150.0, 500.0]),
        code: ErrorCode::PlanFailed.code(),
        refusal: Refusal {
            stage: "fillet".into(),
            code: "plan_failed".into(),
            rule: Some("tee.root_hidden_by_web".into()),
            gate: None,
            message: "the web hides the root".into(),
        },
    };
    PlanReply {
        request_id: 5,
        frame_id: 7,
        result: PlanResult {
            seams: vec![seam],
            unplanned: vec![unplanned],
            timing_ms: BTreeMap::from([("total".to_string(), 250.0)]),
            method: "robust".into(),
            euler_convention: "zyx".into(),
            points: PointCounts {
                valid: 100_000,
                plane: 60_000,
                clusters: 3,
                plates: [30_000, 25_000],
                edges: [400, 380],
                edge_lines: 2,
            },
        },
    }
}

/// The lap seam's figures at its two waypoints (the step measured at the
/// first only) and its process: the first waypoint welded in one pass,
/// the second cut where the torch meets a clamp.
fn along_seam(mut reply: PlanReply) -> PlanReply {
    let seam = &mut reply.result.seams[0];
    let step = JointFigures { lap_step_mm: Some(Measured { value: 5.0, sigma: 0.25 }), ..JointFigures::default() };
    seam.along_seam = Some(vec![step, JointFigures::default()]);
    let pass = Pass {
        kind: PassKind::Single,
        layer: 0,
        bead: 0,
        lateral_mm: 0.0,
        height_mm: 0.0,
        work_angle_deg: 45.0,
        travel_speed_mm_s: 8.0,
        wire_feed_m_min: 6.0,
        voltage_v: 22.0,
        current_a: 180.0,
        target_area_mm2: 15.0,
        deposited_area_mm2: 15.0,
        weave: None,
    };
    let welded = WaypointProcess {
        thickness_mm: 5.0,
        joint_area_mm2: 12.5,
        crown_area_mm2: 2.5,
        work_angle_deg: 45.0,
        travel_angle_deg: 10.0,
        re_angled: false,
        passes: vec![pass],
    };
    seam.process = Some(SeamProcess {
        procedure: "gmaw".into(),
        waypoints: vec![Some(welded), None],
        cut: vec![CutStretch {
            first: 1,
            last: 1,
            rule: "process.torch_blocked".into(),
            reason: "clamp".into(),
            contact_camera_mm: Some([100.0, 12.0, 470.0]),
        }],
    });
    reply
}

/// The daemon's limits as its default configuration sets them.
fn default_limits() -> DaemonLimits {
    DaemonLimits {
        max_frame_bytes: 128 << 20,
        max_message_bytes: 4 << 20,
        plan_queue_depth: 4,
        max_requests_per_connection: 2,
        fresh_frame_timeout_ms: 5_000,
        max_request_timeout_ms: 30_000,
        capture_time_tolerance_ms: 200,
        frame_history: 8,
        frame_history_bytes: 128 << 20,
        stall_timeout_ms: 5_000,
    }
}

fn examples() -> Vec<(&'static str, Vec<u8>)> {
    let v7 = |m: &Message| encode_in(Session::V7, m).unwrap();
    let rule_ids = Session { version: PROTOCOL_VERSION, capabilities: capability::RULE_IDS };
    let reply = Message::PlanReply(plan_reply());
    let plain_reply = encode(&reply).unwrap();
    let reply_with_rules = encode_in(rule_ids, &reply).unwrap();
    assert_eq!(&reply_with_rules[16..plain_reply.len()], &plain_reply[16..], "rule_ids only appends");
    let along = Session { version: PROTOCOL_VERSION, capabilities: capability::ALONG_SEAM };
    let with_along = Message::PlanReply(along_seam(plan_reply()));
    assert_eq!(encode(&with_along).unwrap(), plain_reply, "ungranted, the seam's figures are not sent");
    let reply_with_along = encode_in(along, &with_along).unwrap();
    assert_eq!(&reply_with_along[16..plain_reply.len()], &plain_reply[16..], "along_seam only appends");
    let mut examples: Vec<(&'static str, Vec<u8>)> =
        messages().into_iter().map(|(n, m)| (n, encode(&m).unwrap())).collect();
    examples.extend([
        (
            "hello_v7",
            v7(&Message::Hello(Hello {
                protocol_version: 7,
                role: Role::Camera,
                name: "cam-1".into(),
                capabilities: 0,
            })),
        ),
        (
            "hello_ack_v7",
            v7(&Message::HelloAck(HelloAck {
                protocol_version: 7,
                server: "weldseam 0.1.0".into(),
                capabilities: 0,
                limits: None,
            })),
        ),
        ("plan_reply_rules", reply_with_rules[plain_reply.len()..].to_vec()),
        ("plan_reply_along_seam", reply_with_along[plain_reply.len()..].to_vec()),
        (
            "error_rule",
            encode_in(
                rule_ids,
                &Message::refusal(
                    ErrorCode::PlanFailed,
                    Some(5),
                    "frame 7: input stage failed: no valid point",
                    "frame.no_valid_point",
                ),
            )
            .unwrap(),
        ),
    ]);
    examples
}

fn messages() -> Vec<(&'static str, Message)> {
    vec![
        ("hello", Message::Hello(Hello::new(Role::Camera, "cam-1", capability::LIMITS))),
        (
            "hello_ack",
            Message::HelloAck(HelloAck {
                protocol_version: PROTOCOL_VERSION,
                server: "weldseam 0.1.0".into(),
                capabilities: capability::LIMITS,
                limits: Some(default_limits()),
            }),
        ),
        (
            "frame",
            Message::Frame(Frame {
                meta: FrameMeta {
                    frame_id: 7,
                    trigger_id: 3,
                    capture_time_us: 1_700_000_000_000_000,
                    width: 2,
                    height: 1,
                    units: Units::Millimetres as u32,
                    cloud_frame: CloudFrame::Camera as u32,
                },
                points: vec![[1.0, -2.0, 700.0], [f32::NAN, f32::NAN, f32::NAN]],
            }),
        ),
        (
            "frame_ack",
            Message::FrameAck(FrameAck { frame_id: 7, trigger_id: 3, code: 0, requests: 1, message: String::new() }),
        ),
        ("trigger", Message::Trigger(Trigger { trigger_id: 3 })),
        ("ping", Message::Ping),
        (
            "status",
            Message::Status(Status {
                uptime_ms: 60_000,
                frames_received: 12,
                plans_done: 4,
                queue_length: 1,
                camera_connected: true,
                cameras: 1,
                latest_frame_id: Some(7),
                latest_capture_time_us: Some(1_700_000_000_000_000),
            }),
        ),
        (
            "plan_request",
            Message::PlanRequest(PlanRequest {
                request_id: 5,
                joint: joint_code::LAP,
                groove_depth_mm: None,
                pose: [800.0, 0.0, 500.0, 180.0, 0.0, 0.0],
                step_mm: Some(2.0),
                work_angle_deg: None,
                travel_angle_deg: None,
                frame: FrameSelect::Trigger,
                timeout_ms: 0,
                camera: Some("cam-1".into()),
                hand_eye: None,
                start_near: Some([700.0, -100.0, 0.0]),
                roi: None,
                pose_in: None,
                one_seam: false,
            }),
        ),
        (
            "plan_request_roi",
            Message::PlanRequest(PlanRequest {
                request_id: 6,
                joint: joint_code::I_BUTT,
                groove_depth_mm: None,
                pose: [800.0, 0.0, 500.0, 180.0, 0.0, 0.0],
                step_mm: None,
                work_angle_deg: None,
                travel_angle_deg: None,
                frame: FrameSelect::NextFrame,
                timeout_ms: 0,
                camera: None,
                hand_eye: None,
                start_near: None,
                roi: Some(Roi {
                    min_mm: [-60.0, -40.0, 400.0],
                    max_mm: [60.0, 40.0, 600.0],
                    frame: CloudFrame::Camera as u32,
                }),
                pose_in: None,
                one_seam: false,
            }),
        ),
        ("plan_reply", Message::PlanReply(plan_reply())),
        ("error", Message::error(ErrorCode::Busy, Some(5), "busy")),
    ]
}

/// The text of the ```text block that follows `<!-- hex:NAME -->`.
fn block<'a>(doc: &'a str, name: &str) -> Option<&'a str> {
    let marker = format!("<!-- hex:{name} -->");
    let after = &doc[doc.find(&marker)? + marker.len()..];
    let body = &after[after.find("```text\n")? + "```text\n".len()..];
    Some(&body[..body.find("```")?])
}

#[test]
fn protocol_md_hex_examples_match_the_encoder() {
    let doc = include_str!("../PROTOCOL.md");
    let mut wrong = String::new();
    for (name, bytes) in examples() {
        let dump = hex_dump(&bytes);
        if block(doc, name) != Some(dump.as_str()) {
            wrong.push_str(&format!("<!-- hex:{name} -->\n```text\n{dump}```\n"));
        }
    }
    assert!(wrong.is_empty(), "PROTOCOL.md is out of date; the examples should read:\n{wrong}");
}

#[test]
fn protocol_md_lists_every_error_code_and_the_frame_header_size() {
    let doc = include_str!("../PROTOCOL.md");
    for code in ErrorCode::ALL {
        let row = format!("| {} | {} |", code.code(), code.name());
        assert!(doc.contains(&row), "PROTOCOL.md's error table lacks {row}");
    }
    let header = format!("a {}-byte frame header", weldseam_proto::message::FRAME_META_BYTES);
    assert!(doc.contains(&header), "PROTOCOL.md does not say {header:?}");
    let version = format!("# The weldseam wire protocol, version {PROTOCOL_VERSION}");
    assert!(doc.starts_with(&version), "PROTOCOL.md's title is not {version:?}");
}

#[test]
fn protocol_md_lists_every_capability_by_bit_and_name() {
    let doc = include_str!("../PROTOCOL.md");
    for (bit, name) in capability::ALL {
        let row = format!("| {} | `{name}` |", bit.trailing_zeros());
        assert!(doc.contains(&row), "PROTOCOL.md's capability table lacks {row}");
    }
}

/// The name and fields of struct `T`, as serde's derive lists them: a
/// deserializer that records what `T` asks for and stops there.
fn struct_fields<T: DeserializeOwned>() -> (&'static str, &'static [&'static str]) {
    struct Probe<'a>(&'a mut Option<(&'static str, &'static [&'static str])>);
    impl<'de> de::Deserializer<'de> for Probe<'_> {
        type Error = de::value::Error;
        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(de::Error::custom("not a struct"))
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            name: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Self::Error> {
            *self.0 = Some((name, fields));
            Err(de::Error::custom("probed"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf option unit
            unit_struct newtype_struct seq tuple tuple_struct map enum identifier ignored_any
        }
    }
    let mut found = None;
    let _ = T::deserialize(Probe(&mut found));
    found.expect("a struct")
}

/// Every field the `along_seam` capability carries is a row of its
/// struct's table, in order: "NAME (fields in order)" and then a table
/// whose first column is the fields.
#[test]
fn protocol_md_documents_every_field_along_the_seam_in_order() {
    let doc = include_str!("../PROTOCOL.md");
    let structs = [
        struct_fields::<AlongSeam>(),
        struct_fields::<JointFigures>(),
        struct_fields::<Measured>(),
        struct_fields::<SeamProcess>(),
        struct_fields::<WaypointProcess>(),
        struct_fields::<Pass>(),
        struct_fields::<Weave>(),
        struct_fields::<CutStretch>(),
    ];
    for (name, fields) in structs {
        let heading = format!("\n{name} (fields in order)");
        let at = doc.find(&heading).unwrap_or_else(|| panic!("PROTOCOL.md has no {heading:?}"));
        let rows: Vec<&str> = doc[at..]
            .lines()
            .skip_while(|l| !l.starts_with("| field |"))
            .skip(2)
            .take_while(|l| l.starts_with('|'))
            .filter_map(|l| l.split('|').nth(1).map(str::trim))
            .collect();
        assert_eq!(rows, fields, "PROTOCOL.md's table of {name}");
    }
}
