//! Each root of a block standing on a plate, or of blocks stacked
//! (`sim::blocks`), judged as the tee suite judges a tee's roots.
//!
//! A plan's seams are matched to the scene's roots as on the tee suite
//! ([`match_seams`]: within issue 15's fillet bar, 0.5 mm across and the
//! ends within 1 mm, of the whole root or of a stretch the camera sees;
//! each seam to the nearest root within the bar no earlier seam took).
//! Each root then gets one [`RootVerdict`]:
//!
//! - a root the camera sees along half its length or more is right when a
//!   `t_fillet` seam is found on it;
//! - a root it does not see (its face turned away, the block in front of
//!   it, out of the image, the projector's light cut off) is right when no
//!   seam lies on it and the plan says it did not plan it: refused whole,
//!   or a joint named as not planned; or when a seam lies within the bar
//!   on a stretch of it that is seen;
//! - a root seen with no seam on it is refused when the plan refused or
//!   named a joint it did not plan, and left unnamed when the plan went
//!   through and names nothing;
//! - a root is confident wrong when the seam found on it is named another
//!   joint than `t_fillet`, or when a seam that meets no root's bar lies
//!   nearest it (whether or not another seam found it).
//!
//! A scene with several roots seen is judged root by root: the planner may
//! plan one seam or several, each a right root where it lies on one; a
//! seen root it leaves is refused or unnamed, never wrong; a seam on no
//! root is one confident wrong root, the nearest.

use crate::camera::CameraModel;
use crate::eval::web_near_edge::RootVerdict;
use crate::eval::{SeamError, TrueSeam, match_seams};
use crate::geometry::Vec3;
use crate::joint::{JointType, RequestedJoint};
use crate::pipeline::{PlanRequest, Planner};
use crate::sim::blocks::{BlockCapture, BlockRoot};
use crate::sim::truth::MIN_SEEN_SHARE;
use crate::sim::{BlockScene, SceneSpec};

/// One root's outcome under one request.
#[derive(Debug, Clone, PartialEq)]
pub struct RootOutcome {
    pub root: BlockRoot,
    /// The share of the root the camera sees, and whether it is to be
    /// found (at least half).
    pub seen_share: f64,
    pub seen: bool,
    /// Some of it is in the image.
    pub in_image: bool,
    pub verdict: RootVerdict,
    /// The error of the seam that lies on it (found, or nearest it off the
    /// bar).
    pub error: Option<SeamError>,
    /// The rule that refused the plan, or that the plan names for a joint
    /// not planned; `-` for none.
    pub rule: &'static str,
}

/// Plans `scene` as `joint` with `planner` and judges each root, in
/// [`BlockScene::roots`]'s order.
pub fn plan_roots(
    scene: &BlockScene,
    planner: &Planner,
    camera: &CameraModel,
    joint: RequestedJoint,
) -> Vec<RootOutcome> {
    judge_plan(&scene.spec, &scene.simulate(camera), planner, joint)
}

/// The roots as the tee judging reads them, in the robot base frame.
fn true_seams(spec: &SceneSpec, capture: &BlockCapture) -> Vec<TrueSeam> {
    let base = spec.base_from_workpiece;
    let in_base = |p: &Vec3| base.transform_point(&(*p).into()).coords;
    capture
        .roots
        .iter()
        .map(|(root, truth)| TrueSeam {
            label: format!("block {} root {}", root.block + 1, root.face.name()),
            joint: JointType::TFillet,
            whole: truth.in_image_base.unwrap_or_else(|| root.ends.map(|e| in_base(&e))),
            seen: truth.seen_base.clone(),
            seen_share: truth.seen_share,
            seen_enough: truth.seen_share >= MIN_SEEN_SHARE,
        })
        .collect()
}

/// [`plan_roots`] of a scene already captured.
pub fn judge_plan(
    spec: &SceneSpec,
    capture: &BlockCapture,
    planner: &Planner,
    joint: RequestedJoint,
) -> Vec<RootOutcome> {
    let truths = true_seams(spec, capture);
    let outcome = |t: usize, verdict, error, rule| RootOutcome {
        root: capture.roots[t].0,
        seen_share: truths[t].seen_share,
        seen: truths[t].seen_enough,
        in_image: capture.roots[t].1.in_image_base.is_some(),
        verdict,
        error,
        rule,
    };
    let request = PlanRequest::new(joint, None, capture.sim.pose);
    let plan = match planner.plan(&capture.sim.cloud, &request) {
        Ok(plan) => plan,
        Err(e) => {
            return (0..truths.len())
                .map(|t| {
                    let verdict = if truths[t].seen_enough { RootVerdict::Refused } else { RootVerdict::Right };
                    outcome(t, verdict, None, e.rule.id)
                })
                .collect();
        }
    };
    let returned: Vec<(Vec<Vec3>, JointType)> =
        plan.seams.iter().map(|s| (s.waypoints.iter().map(|w| w.position).collect(), s.joint)).collect();
    let matches = match_seams(&truths, &returned);
    let named = plan.unplanned.first().map(|u| u.reason.rule.id);
    (0..truths.len())
        .map(|t| {
            // A seam off every root's bar, nearest this one: a seam where
            // no root is (a seam within the bar of a root another seam
            // took is the same root planned twice, not a wrong one).
            let stray = matches.extra.iter().find(|x| {
                x.nearest == Some(t)
                    && !truths[t].best_error(&returned[x.returned].0).is_some_and(|e| e.passes_fillet())
            });
            if let Some(stray) = stray {
                return outcome(t, RootVerdict::ConfidentWrong, stray.error, "-");
            }
            if let Some(found) = matches.found.iter().find(|m| m.truth == t) {
                let (path, seam_joint) = &returned[found.returned];
                let verdict =
                    if *seam_joint == JointType::TFillet { RootVerdict::Right } else { RootVerdict::ConfidentWrong };
                return outcome(t, verdict, truths[t].best_error(path), "-");
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
    use crate::sim::blocks::{BLOCKS_HOLDOUT, BLOCKS_SCENES};
    use crate::sim::blocks_suite;
    use crate::sim::draw::Draw;

    /// The documented seeds, under `t_fillet` and `auto`: no root is
    /// confident wrong, and as many roots are right, seen and hidden, as
    /// were measured on the planner of the family's first commit; the
    /// outcomes printed (`cargo test --lib eval::blocks -- --nocapture`).
    /// When a change to the planner moves a count, the new count goes here
    /// with the scenes it moved in the change's message.
    #[test]
    fn no_root_is_confident_wrong_on_the_documented_seeds() {
        let planner = Planner::new(Config::default());
        let camera = CameraModel::default();
        let suite = blocks_suite(Draw::Documented);
        let mut right = [[0; 2]; 2];
        let mut seen_roots = 0;
        for scene in suite.iter().take(BLOCKS_SCENES - BLOCKS_HOLDOUT) {
            let capture = scene.simulate(&camera);
            for (r, joint) in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto].into_iter().enumerate() {
                for root in judge_plan(&scene.spec, &capture, &planner, joint) {
                    let name = format!("block {} root {}", root.root.block + 1, root.root.face.name());
                    let seen = if root.seen { "seen" } else { "hidden" };
                    eprintln!("{} {joint} {name} ({seen}): {:?} ({})", scene.name, root.verdict, root.rule);
                    assert_ne!(root.verdict, RootVerdict::ConfidentWrong, "{} {joint} {name}", scene.name);
                    right[r][usize::from(root.seen)] += usize::from(root.verdict == RootVerdict::Right);
                    seen_roots += usize::from(r == 0 && root.seen);
                }
            }
        }
        assert_eq!(seen_roots, SEEN_ROOTS, "roots seen along half their length");
        assert_eq!(right, MEASURED_RIGHT, "roots right under t_fillet and auto, [hidden, seen]");
    }

    /// Roots the camera sees along half their length on the documented
    /// seeds: 30 of their 64 (22 of 48 on the plate, 8 of 16 stacked).
    const SEEN_ROOTS: usize = 30;

    /// Roots right on the documented seeds under `t_fillet` and `auto`,
    /// each as `[hidden, seen]`, as measured. A block's top is a web's by
    /// the face falling from it to the plate seen on both of its sides
    /// (`tee.no_web_top`), and each of its sides a root read from its
    /// face where the camera sees that face from outside it: 8 of the 30
    /// seen roots are planned under both requests (blocks-01, -02 the
    /// stacked block's, -03 two, -04, -08 the lower block's, -09 two).
    /// Every hidden root is right: named by the rule that left it, none
    /// planned. The seen roots left are refused: no face seen falling
    /// from the top at small tilts, or the plane under it seen on one side
    /// only (`tee.nothing_stands_on_flange`, `joint.no_layout_fits`), a
    /// face seen along the camera's rays, the other block of a stacked
    /// scene (one member is planned per frame), and the fit and coverage
    /// gates.
    const MEASURED_RIGHT: [[usize; 2]; 2] = [[34, 8], [34, 8]];

    /// The held-out seeds, run once when the planner is frozen: the
    /// outcomes are printed for the report, never tuned on.
    #[test]
    #[ignore = "held-out seeds: run once, at the end, and reported apart"]
    fn held_out_seeds() {
        let planner = Planner::new(Config::default());
        let camera = CameraModel::default();
        for scene in blocks_suite(Draw::Documented).iter().skip(BLOCKS_SCENES - BLOCKS_HOLDOUT) {
            for joint in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto] {
                eprintln!("{} {joint}: {:?}", scene.name, plan_roots(scene, &planner, &camera, joint));
            }
        }
    }
}
