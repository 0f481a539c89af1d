//! Under `auto`, a workpiece every proposed reading refused is read once
//! more as a tee's request (`t_fillet`) reads it: for what that refusal
//! says, never for a plan.
//!
//! Without a request the layers take a web's top only where it stands
//! higher than a lap's upper plate is thick and over its flange on both of
//! its sides: a short web, or one whose far side hides its flange, stands
//! as a clamp or a bar lying across a butt or lap joint does, and only the
//! joint's name tells them apart (`stands_as_web` in
//! src/pipeline/background/layers.rs, `tee.web_seen_on_one_side`). Two
//! classes of workpiece were refused for it with a reason that is not what
//! the cloud shows:
//! - a member standing on a curved part (a round tube on a cylinder, its
//!   top a strip a few tens of millimetres over the cylinder's nearest
//!   facet): read as a lap, refused for the edge between two plates a lap
//!   has and a tee does not, where the tee's reading finds the member's
//!   root and refuses it as bending;
//! - a short web standing on its flange: the flange's halves either side
//!   of it read as a butt pair, whose groove probe then finds a plate
//!   standing between the edges along the seam (`butt.plate_standing_in_gap`)
//!   and says nothing of whether a tee's request would plan it.
//!
//! So, once every reading `auto` proposes is refused (the layers', and the
//! face standing beside them where one is weighed), the tee's is made:
//! - refused at a later stage than the reading `auto` made (it got further
//!   into the cloud), its refusal is the workpiece's, the other's after it;
//! - refused no further, the reading `auto` made keeps its refusal;
//! - passing every gate, the workpiece is still refused by the reading
//!   `auto` made, which now says that a tee's request would plan its root.
//!   It is not planned: a clamp standing along the seam over a lap or a
//!   butt joint passes a tee's gates as a short web does (the fault
//!   suite's clamp over a lap at 1 mm voxels, 33 mm wide and 35 mm tall,
//!   seen along the whole seam, would be welded at its foot), and a
//!   clamp's foot welded is the confident wrong answer the planner does
//!   not give. Only the joint's name tells the two apart.
//!
//! Every refusal keeps its own rule: no rule decides here, only which of
//! two refusals, each by its rule, says more of the cloud.

use crate::joint::{JointType, RequestedJoint};
use crate::pipeline::context::Context;
use crate::pipeline::quality::Gate;
use crate::pipeline::{PlanError, PlanRequest};
use crate::rules;

use super::{Refused, Welds, standing_face};

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

/// The workpiece's refusal once `read` (the workpiece's reading under the
/// request it is given) has read it as a tee's request does, `auto`'s own
/// reading having been `refused`.
pub(super) fn weigh(
    ctx: &Context,
    refused: Refused,
    read: impl FnOnce(&mut Context) -> Result<Welds, Refused>,
) -> Refused {
    let request = PlanRequest { joint: RequestedJoint::Type(JointType::TFillet), ..ctx.request.clone() };
    let mut as_tee = ctx.under_request(&request);
    match read(&mut as_tee) {
        Ok((welds, _)) => {
            let reason = format!(
                "{}; read as a tee's request reads it, {} fillet root(s) pass every gate: a web standing short, \
                 or over its flange on one side only, or a clamp or a bar standing there, which only the joint's \
                 name tells apart; if it is a web, request t_fillet to plan its root",
                refused.reason.reason,
                welds.len()
            );
            tracing::debug!(rule = refused.reason.rule.id, "{reason}");
            Refused { reason: PlanError { reason, ..refused.reason }, seen: refused.seen }
        }
        Err(tee) => {
            let read_as = match refused.seen {
                Some(JointType::Lap) => "read as a lap",
                Some(JointType::VButt | JointType::IButt) => "read as a butt pair",
                _ => "as the layers read it",
            };
            standing_face::further(refused, tee.reason, read_as)
        }
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
        // seen as a tee already, yet the tee's reading says whether a tee's
        // request would plan it.
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
