//! The `rule_ids` capability's fields: the planner's rule that made each
//! refusal and warning, by its stable id (`family.decision`). A capability
//! appends its fields after every field a message had, so a peer that did
//! not ask reads exactly the bytes it read before:
//!
//! - an Error ends with `rule` (`Option<String>`): the rule that refused
//!   the request it answers, absent where no rule did (a request refused
//!   before planning, a frame that never came);
//! - a PlanReply ends with `warning_rules` (per seam, in order: a `u64`
//!   count, then each warning's rule id) and `unplanned_rules` (a `u64`
//!   count, then each unplanned joint's rule id), as many as the result
//!   has seams, warnings and unplanned joints.

use crate::frame::{DecodeError, EncodeError, decode_prefix, encode_struct, whole};
use crate::message::{ErrorCode, ErrorReply, PlanReply, Tag};
use crate::session::{Session, capability};

/// An Error's fields before the capability's.
type ErrorFields = (ErrorCode, Option<u64>, String);

pub(crate) fn encode_error(session: Session, m: &ErrorReply, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    encode_struct(Tag::Error, &(m.code, m.request_id, &m.message), out)?;
    if session.has(capability::RULE_IDS) {
        encode_struct(Tag::Error, &m.rule, out)?;
    }
    Ok(())
}

pub(crate) fn decode_error(session: Session, payload: &[u8]) -> Result<ErrorReply, DecodeError> {
    let tag = Tag::Error;
    let ((code, request_id, message), mut used) = decode_prefix::<ErrorFields>(tag, payload)?;
    let mut rule = None;
    if session.has(capability::RULE_IDS) {
        let (r, n) = decode_prefix::<Option<String>>(tag, &payload[used..])?;
        (rule, used) = (r, used + n);
    }
    whole(tag, payload, used)?;
    Ok(ErrorReply { code, request_id, message, rule })
}

pub(crate) fn encode_plan_reply(session: Session, m: &PlanReply, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    encode_struct(Tag::PlanReply, m, out)?;
    if session.has(capability::RULE_IDS) {
        encode_struct(Tag::PlanReply, &(m.result.warning_rules(), m.result.unplanned_rules()), out)?;
    }
    crate::along_seam::encode(session, m, out)
}

pub(crate) fn decode_plan_reply(session: Session, payload: &[u8]) -> Result<PlanReply, DecodeError> {
    let tag = Tag::PlanReply;
    let (mut reply, mut used) = decode_prefix::<PlanReply>(tag, payload)?;
    if session.has(capability::RULE_IDS) {
        let ((warnings, unplanned), n) = decode_prefix::<(Vec<Vec<String>>, Vec<String>)>(tag, &payload[used..])?;
        used += n;
        if !reply.result.set_rules(warnings, unplanned) {
            let reason = "the rule ids do not match the reply's seams, warnings and unplanned joints".into();
            return Err(DecodeError::Malformed { tag: tag.name(), reason });
        }
    }
    used += crate::along_seam::decode(session, &payload[used..], &mut reply)?;
    whole(tag, payload, used)?;
    Ok(reply)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::frame::{decode_body_in, encode_body_in};
    use crate::message::Message;
    use crate::plan::{GateWarning, PlanResult, PointCounts, Refusal, UnplannedJoint};

    fn granted() -> Session {
        Session { version: 8, capabilities: capability::RULE_IDS }
    }

    fn reply() -> PlanReply {
        let refusal = Refusal {
            stage: "groove".into(),
            code: "plan_failed".into(),
            rule: Some("groove.root_hidden".into()),
            gate: None,
            message: "no root".into(),
        };
        PlanReply {
            request_id: 3,
            frame_id: 4,
            result: PlanResult {
                seams: vec![],
                unplanned: vec![UnplannedJoint { joint: None, near_camera_mm: None, code: 46, refusal }],
                timing_ms: BTreeMap::new(),
                method: "robust".into(),
                euler_convention: "zyx".into(),
                points: PointCounts::default(),
            },
        }
    }

    fn round_trip(session: Session, m: &Message) -> Message {
        let body = encode_body_in(session, m).unwrap();
        decode_body_in(session, m.tag() as u16, &body).unwrap()
    }

    #[test]
    fn an_error_carries_its_rule_only_when_granted() {
        let refusal = Message::refusal(ErrorCode::PlanFailed, Some(9), "no seam", "seam.too_short_for_fit");
        let plain = encode_body_in(Session::NEWEST, &refusal).unwrap();
        let without = Message::error(ErrorCode::PlanFailed, Some(9), "no seam");
        assert_eq!(plain, encode_body_in(Session::NEWEST, &without).unwrap(), "ungranted: today's bytes");
        assert_eq!(plain, encode_body_in(Session::V7, &refusal).unwrap());
        assert_eq!(round_trip(Session::NEWEST, &refusal), without);
        let granted_bytes = encode_body_in(granted(), &refusal).unwrap();
        assert_eq!(&granted_bytes[..plain.len()], &plain[..], "appended after every field");
        assert_eq!(granted_bytes[plain.len()], 1);
        assert_eq!(round_trip(granted(), &refusal), refusal);
        // An error no rule made ends with an absent rule.
        let busy = Message::error(ErrorCode::Busy, None, "busy");
        assert_eq!(encode_body_in(granted(), &busy).unwrap().last(), Some(&0));
        assert_eq!(round_trip(granted(), &busy), busy);
    }

    #[test]
    fn a_plan_reply_carries_its_rules_only_when_granted() {
        let mut with_warning = reply();
        let mut seam = crate::plan::Seam {
            joint: crate::plan::Joint::Lap,
            joint_evidence: None,
            waypoints: vec![],
            start_camera: [0.0; 3],
            end_camera: [0.0; 3],
            normal_camera: [0.0, 0.0, 1.0],
            length_mm: 1.0,
            edge_fit_rms_mm: [0.0; 2],
            edge_samples: [1; 2],
            edge_samples_dropped: [0; 2],
            coverage: None,
            quality: None,
            warnings: vec![],
            along_seam: None,
            process: None,
        };
        seam.warnings.push(GateWarning {
            gate: "joint_coverage".into(),
            rule: Some("seam.spans_visible_joint".into()),
            value: 0.5,
            limit: 0.8,
            message: "short".into(),
        });
        with_warning.result.seams.push(seam);
        let m = Message::PlanReply(with_warning.clone());
        let plain = encode_body_in(Session::NEWEST, &m).unwrap();
        let Message::PlanReply(read) = round_trip(Session::NEWEST, &m) else { panic!() };
        assert_eq!(read.result.seams[0].warnings[0].rule, None);
        assert_eq!(read.result.unplanned[0].refusal.rule, None);
        let granted_bytes = encode_body_in(granted(), &m).unwrap();
        assert_eq!(&granted_bytes[..plain.len()], &plain[..], "appended after every field");
        assert_eq!(round_trip(granted(), &m), m);
        // Rules that do not match the reply are malformed.
        let mut short = plain.clone();
        crate::frame::encode_struct(Tag::PlanReply, &(Vec::<Vec<String>>::new(), vec!["a.b".to_string()]), &mut short)
            .unwrap();
        assert!(matches!(decode_body_in(granted(), Tag::PlanReply as u16, &short), Err(DecodeError::Malformed { .. })));
    }
}
