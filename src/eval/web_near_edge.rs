//! Each root of a tee whose web stands near the flange's edge
//! (`sim::web_near_edge`), judged as the tee suite judges roots.
//!
//! A plan's seams are matched to the tee's two roots as on the tee suite
//! ([`match_seams`]: within issue 15's fillet bar, 0.5 mm across and the
//! ends within 1 mm, of the whole root or of a stretch the camera sees).
//! Each root then gets one [`RootVerdict`]:
//!
//! - a root the camera sees along half its length or more is right when a
//!   `t_fillet` seam is found on it;
//! - a root it does not see (the web hides it, or the projector's light)
//!   is right when no seam lies on it and the plan names a joint it left
//!   unplanned (`tee.root_hidden_by_web` and its kin), or when a seam is
//!   found within the bar on the stretch of it that is seen;
//! - a root with no seam on it otherwise is refused: by the plan's
//!   refusal, or by the joint the plan names as not planned; where the
//!   plan goes through and names nothing, it is left unnamed;
//! - a root nearest a seam that meets the bar of no root, or found by a
//!   seam named another joint than `t_fillet`, is confident wrong.

use crate::camera::CameraModel;
use crate::eval::{SeamError, TrueSeam, match_seams};
use crate::geometry::Vec3;
use crate::joint::{JointType, RequestedJoint};
use crate::pipeline::{PlanRequest, Planner};
use crate::sim::{Simulation, WebNearEdge};

/// What became of one root.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum RootVerdict {
    /// Planned within the bar where seen; named not planned where hidden.
    Right,
    /// Not planned, and the plan says why: refused whole, or the joint
    /// named as not planned.
    Refused,
    /// Not planned, and the plan, which went through, says nothing of it.
    Unnamed,
    /// A seam on it off the bar, or named another joint.
    ConfidentWrong,
}

impl RootVerdict {
    pub const ALL: [RootVerdict; 4] =
        [RootVerdict::Right, RootVerdict::Refused, RootVerdict::Unnamed, RootVerdict::ConfidentWrong];

    pub fn label(self) -> &'static str {
        match self {
            RootVerdict::Right => "right",
            RootVerdict::Refused => "refused",
            RootVerdict::Unnamed => "not planned, not named",
            RootVerdict::ConfidentWrong => "confident wrong",
        }
    }
}

/// One root's outcome under one request.
#[derive(Debug, Clone, PartialEq)]
pub struct RootOutcome {
    /// On the flange's narrow side.
    pub narrow: bool,
    /// The share of the root the camera sees, and whether it is to be
    /// found (at least half).
    pub seen_share: f64,
    pub seen: bool,
    pub verdict: RootVerdict,
    /// The error of the seam that lies on it (found, or nearest it off the
    /// bar).
    pub error: Option<SeamError>,
    /// The rule that refused the plan, or that the plan names for a joint
    /// not planned; `-` for none.
    pub rule: &'static str,
}

/// Plans `scene` as `joint` with `planner` and judges each root, the −x
/// side's first.
pub fn plan_roots(
    scene: &WebNearEdge,
    planner: &Planner,
    camera: &CameraModel,
    joint: RequestedJoint,
) -> Vec<RootOutcome> {
    let sim = scene.simulate(camera);
    judge_plan(scene, &sim, planner, joint)
}

/// [`plan_roots`] of a scene already captured.
pub fn judge_plan(scene: &WebNearEdge, sim: &Simulation, planner: &Planner, joint: RequestedJoint) -> Vec<RootOutcome> {
    let truths: Vec<TrueSeam> = sim.seams.iter().map(|s| TrueSeam::of(&scene.spec, s)).collect();
    let request = PlanRequest::new(joint, None, sim.pose);
    let outcome = |root: usize, verdict, error, rule| RootOutcome {
        narrow: root == scene.narrow_root(),
        seen_share: truths[root].seen_share,
        seen: truths[root].seen_enough,
        verdict,
        error,
        rule,
    };
    let plan = match planner.plan(&sim.cloud, &request) {
        Ok(plan) => plan,
        Err(e) => return (0..truths.len()).map(|t| outcome(t, RootVerdict::Refused, None, e.rule.id)).collect(),
    };
    let returned: Vec<(Vec<Vec3>, JointType)> =
        plan.seams.iter().map(|s| (s.waypoints.iter().map(|w| w.position).collect(), s.joint)).collect();
    let matches = match_seams(&truths, &returned);
    let named = plan.unplanned.first().map(|u| u.reason.rule.id);
    (0..truths.len())
        .map(|t| {
            if let Some(found) = matches.found.iter().find(|m| m.truth == t) {
                let (path, seam_joint) = &returned[found.returned];
                let verdict =
                    if *seam_joint == JointType::TFillet { RootVerdict::Right } else { RootVerdict::ConfidentWrong };
                return outcome(t, verdict, truths[t].best_error(path), "-");
            }
            if let Some(extra) = matches.extra.iter().find(|x| x.nearest == Some(t)) {
                return outcome(t, RootVerdict::ConfidentWrong, extra.error, "-");
            }
            match (truths[t].seen_enough, named) {
                (false, Some(rule)) => outcome(t, RootVerdict::Right, None, rule),
                (true, Some(rule)) => outcome(t, RootVerdict::Refused, None, rule),
                (_, None) => outcome(t, RootVerdict::Unnamed, None, "-"),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::sim::draw::Draw;
    use crate::sim::web_near_edge::{WEB_NEAR_EDGE_HOLDOUT, WEB_NEAR_EDGE_SCENES};
    use crate::sim::web_near_edge_suite;

    /// The documented seeds, under `t_fillet` and `auto`: no root is
    /// confident wrong, and as many roots are right as were measured on
    /// the planner of the family's first commit; the outcomes printed
    /// (`cargo test --lib web_near_edge -- --nocapture`). When a change
    /// to the planner moves the count, the new count goes here with the
    /// scenes it moved in the change's message.
    #[test]
    fn no_root_is_confident_wrong_on_the_documented_seeds() {
        let planner = Planner::new(Config::default());
        let camera = CameraModel::default();
        let suite = web_near_edge_suite(Draw::Documented);
        let mut right = [0, 0];
        for scene in suite.iter().take(WEB_NEAR_EDGE_SCENES - WEB_NEAR_EDGE_HOLDOUT) {
            let sim = scene.simulate(&camera);
            for (r, joint) in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto].into_iter().enumerate() {
                let roots = judge_plan(scene, &sim, &planner, joint);
                for root in &roots {
                    let side = if root.narrow { "narrow" } else { "wide" };
                    eprintln!("{} {joint} {side} root: {:?} ({})", scene.name, root.verdict, root.rule);
                    assert_ne!(root.verdict, RootVerdict::ConfidentWrong, "{} {joint} {side} root", scene.name);
                    right[r] += usize::from(root.verdict == RootVerdict::Right);
                }
            }
        }
        assert_eq!(right, MEASURED_RIGHT, "roots right under t_fillet and auto");
    }

    /// Roots right on the documented seeds (of 24) under `t_fillet` and
    /// `auto`, as measured: under `t_fillet` both roots of 9 scenes (01,
    /// 03, 09 and 11 seen from the wide side, 00, 02, 06, 08 and 10 from
    /// the narrow one; 04, 05 and 07, the web's top cropped and its face
    /// seen at a grazing angle, refused); under `auto` those of 01, 03, 09
    /// and 10, the others refused by the layout rules
    /// (`tee.web_seen_on_one_side` among them: a web seen over its flange
    /// on one side only is planned when named).
    const MEASURED_RIGHT: [usize; 2] = [18, 8];

    /// The held-out seeds, run once when the planner is frozen: the
    /// outcomes are printed for the report, never tuned on.
    #[test]
    #[ignore = "held-out seeds: run once, at the end, and reported apart"]
    fn held_out_seeds() {
        let planner = Planner::new(Config::default());
        let camera = CameraModel::default();
        for scene in web_near_edge_suite(Draw::Documented).iter().skip(WEB_NEAR_EDGE_SCENES - WEB_NEAR_EDGE_HOLDOUT) {
            for joint in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto] {
                eprintln!("{} {joint}: {:?}", scene.name, plan_roots(scene, &planner, &camera, joint));
            }
        }
    }
}
