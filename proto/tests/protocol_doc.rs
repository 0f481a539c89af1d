//! PROTOCOL.md's hex examples are the encodings this crate produces: the
//! document cannot drift from the code.

use weldseam_proto::frame::encode;
use weldseam_proto::message::{
    CloudFrame, ErrorCode, Frame, FrameAck, FrameMeta, FrameSelect, Hello, Message, PlanRequest, Roi, Role, Status,
    Trigger, Units, joint_code,
};

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

fn examples() -> Vec<(&'static str, Message)> {
    vec![
        (
            "hello",
            Message::Hello(Hello {
                protocol_version: weldseam_proto::PROTOCOL_VERSION,
                role: Role::Camera,
                name: "cam-1".into(),
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
    for (name, message) in examples() {
        let dump = hex_dump(&encode(&message).unwrap());
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
    let version = format!("# The weldseam wire protocol, version {}", weldseam_proto::PROTOCOL_VERSION);
    assert!(doc.starts_with(&version), "PROTOCOL.md's title is not {version:?}");
}
