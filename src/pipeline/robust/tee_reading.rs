//! Under `auto`, a workpiece every proposed reading refused is read once
//! more as a tee's request (`t_fillet`) reads it: planned where the refused
//! reading itself found a web standing along the seam, else for what its
//! refusal says.
//!
//! Without a request the layers take a web's top only where it stands
//! higher than a lap's upper plate is thick and over its flange on both of
//! its sides: a short web, or one whose far side hides its flange, stands
//! as a clamp or a bar lying across a butt or lap joint does, and only the
//! joint's name tells them apart (`stands_as_web` in
//! src/pipeline/background/layers.rs, `tee.web_seen_on_one_side`). Two
//! classes of workpiece were refused for it with a reason that is not what
//! the cloud shows:
//! - a short web standing on its flange: the flange's halves either side
//!   of it read as a butt pair, whose groove probe then finds a plate
//!   standing between the edges along the seam and refuses it as a tee
//!   (`butt.plate_standing_in_gap`), which `auto` did not plan;
//! - a member standing on a curved part (a round tube on a cylinder, its
//!   top a strip a few tens of millimetres over the cylinder's nearest
//!   facet): read as a lap, refused for the edge between two plates a lap
//!   has and a tee does not, where the tee's reading finds the member's
//!   root and refuses it as bending.
//!
//! So, once every reading `auto` proposes is refused (the layers', and the
//! face standing beside them where one is weighed), the tee's is made:
//! - passing every gate where the refused reading was a butt pair with a
//!   plate standing between its edges along the seam, it is the joint: the
//!   groove probe saw a web standing along the seam, which a clamp lying
//!   across the joint, standing over a stretch of it, does not show;
//! - passing every gate otherwise, the workpiece is still refused by the
//!   reading `auto` made, which now says that a tee's request would plan
//!   its root: a short web and a clamp are not told apart without the
//!   name, and a clamp's foot welded is the confident wrong answer the
//!   planner does not give;
//! - refused at a later stage than the reading `auto` made (it got further
//!   into the cloud), its refusal is the workpiece's, the other's after it;
//! - refused no further, the reading `auto` made keeps its refusal.
//!
//! Every refusal keeps its own rule, and the plan's evidence names the rule
//! that read the web: no rule decides here, only which of two readings,
//! each by its rules, says more of the cloud.

use crate::joint::{JointType, RequestedJoint};
use crate::pipeline::context::Context;
use crate::pipeline::quality::Gate;
use crate::pipeline::{PlanError, PlanRequest};
use crate::rules;

use super::{Refused, Welds};

/// Whether the request leaves the joint to the planner and admits a tee:
/// the tee's reading is then one the planner may weigh.
pub(super) fn may_weigh(ctx: &Context) -> bool {
    ctx.request.joint.given().is_none() && ctx.request.joint.admits(JointType::TFillet)
}

/// Whether `refused` leaves the tee's reading something to say: not a
/// plan out of time (which says nothing of the cloud), not a tee already
/// (the layers' web, or the face standing beside them), not a lone plane
/// (`auto` weighed the face standing on it already, and the valley a
/// groove's two flanks make with it, which a tee's request does not ask),
/// not a joint the request does not admit, unless that joint is the tee
/// the butt pair's groove probe found standing between its edges.
pub(super) fn worth_weighing(refused: &Refused) -> bool {
    let lone_plane = [&rules::background::TOO_FEW_PLANES, &rules::background::WEB_FACE_WITHOUT_TOP]
        .into_iter()
        .any(|rule| std::ptr::eq(refused.reason.rule, rule));
    let read_otherwise =
        refused.seen != Some(JointType::TFillet) && refused.reason.gate != Some(Gate::JointMismatch) && !lone_plane;
    !refused.reason.out_of_time && (read_otherwise || web_in_gap(refused))
}

/// Whether the butt pair's groove probe refused it for a plate standing
/// between its edges along the seam: a web the layers did not read.
fn web_in_gap(refused: &Refused) -> bool {
    std::ptr::eq(refused.reason.rule, &rules::groove::PLATE_STANDING_IN_GAP)
}

/// The workpiece's welds or refusal once `read` (the workpiece's reading
/// under the request it is given) has read it as a tee's request does,
/// `auto`'s own reading having been `refused`.
pub(super) fn weigh(
    ctx: &Context,
    refused: Refused,
    read: impl FnOnce(&mut Context) -> Result<Welds, Refused>,
) -> Result<Welds, Refused> {
    let request = PlanRequest { joint: RequestedJoint::Type(JointType::TFillet), ..ctx.request.clone() };
    let mut as_tee = ctx.under_request(&request);
    match read(&mut as_tee) {
        Ok((welds, hidden)) if web_in_gap(&refused) => {
            let why = format!(
                "read as a butt pair, refused by {}: a plate stands between its edges along the seam, a web the \
                 layers did not read (no taller than a lap's upper plate is thick); read as a tee",
                refused.reason.rule.id
            );
            tracing::debug!(rule = refused.reason.rule.id, "{why}");
            Ok((welds.into_iter().map(|weld| weld.with_evidence_before(&why)).collect(), hidden))
        }
        Ok((welds, _)) => {
            let reason = format!(
                "{}; read as a tee's request reads it, {} fillet root(s) pass every gate: a web standing short, \
                 or over its flange on one side only, or a clamp or a bar standing there, which only the joint's \
                 name tells apart; if it is a web, request t_fillet to plan its root",
                refused.reason.reason,
                welds.len()
            );
            tracing::debug!(rule = refused.reason.rule.id, "{reason}");
            Err(Refused { reason: PlanError { reason, ..refused.reason }, seen: refused.seen })
        }
        Err(tee) if tee.reason.out_of_time => Err(tee),
        Err(tee) if tee.reason.stage > refused.reason.stage => {
            let read_as = match refused.seen {
                Some(JointType::Lap) => "read as a lap",
                Some(JointType::VButt | JointType::IButt) => "read as a butt pair",
                _ => "as the layers read it",
            };
            let reason = format!("{}; {read_as}: {}", tee.reason.reason, refused.reason.reason);
            tracing::debug!(rule = tee.reason.rule.id, "the tee's reading got further: {reason}");
            Err(Refused { reason: PlanError { reason, ..tee.reason }, seen: Some(JointType::TFillet) })
        }
        Err(_) => Err(refused),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::Rule;

    fn refused(rule: &'static Rule, seen: Option<JointType>) -> Refused {
        Refused { reason: PlanError::by(rule, "refused"), seen }
    }

    #[test]
    fn the_tee_s_reading_is_weighed_after_a_butt_or_lap_reading_and_a_web_in_the_gap_only() {
        // A lap's or a butt pair's reading refused: the tee's says more.
        assert!(worth_weighing(&refused(&rules::weld_edges::NO_LINE_BETWEEN_PLATES, Some(JointType::Lap))));
        assert!(worth_weighing(&refused(&rules::background::TEE_WEB_SEEN_ON_ONE_SIDE, None)));
        // The groove probe's web standing in the gap: a joint mismatch, and
        // seen as a tee already, yet the one the tee's reading plans.
        let web = refused(&rules::groove::PLATE_STANDING_IN_GAP, Some(JointType::TFillet));
        assert_eq!(web.reason.gate, Some(Gate::JointMismatch));
        assert!(worth_weighing(&web));
        // A lone plane: `auto` weighed its face and its valley already (a
        // groove's two flanks are not read again as a tee).
        assert!(!worth_weighing(&refused(&rules::background::TOO_FEW_PLANES, None)));
        assert!(!worth_weighing(&refused(&rules::background::WEB_FACE_WITHOUT_TOP, None)));
        // A tee read already, a joint the request does not admit, a plan out
        // of time: nothing more to say.
        assert!(!worth_weighing(&refused(&rules::weld_edges::NO_LINE_BETWEEN_PLATES, Some(JointType::TFillet))));
        assert!(!worth_weighing(&refused(&rules::groove::BUTT_NOT_REQUESTED, Some(JointType::VButt))));
        let mut late = refused(&rules::weld_edges::NO_LINE_BETWEEN_PLATES, Some(JointType::Lap));
        late.reason.out_of_time = true;
        assert!(!worth_weighing(&late));
    }
}
