//! The robust method's page for a tee joint (issue 15), taken once the
//! background stage has found a web standing on its flange: the paper has
//! no fillet, so past section 3.3 this page replaces its edge sections
//! (3.4 to 4.3) by the fillet stage ([`super::fillet`]), then checks each
//! root's figures against the gates and samples it as section 5.1 does.
//!
//! - the roots: each web side face fitted where the cloud shows it, the
//!   root where it meets the flange, clipped to where the face's foot and
//!   the flange up to it are both seen (timed as the refit stage);
//! - the gates ([`super::quality`]): the face's and the flange's fit
//!   residuals, the root's evidence along the stretch planned, the web
//!   square to the flange, the root's position uncertainty;
//! - 5.1: each root its own seam, the torch leaning from the flange towards
//!   the web ([`super::trajectory::fillet_torch_axis`]).
//!
//! A root not seen (the web hides its face or the flange beside it) or
//! refused by a gate is a joint seen but not planned ([`Unplanned`]),
//! beside the root that was; with no root planned the plan is refused.

use crate::geometry::Vec3;
use crate::joint::JointType;

use super::background::{PlaneCluster, Workpiece};
use super::context::{Context, EdgeFigures, PlannedWeld};
use super::fillet::{self, Root, RootEvidence, TeeView, Web};
use super::trace::TracedWeld;
use super::{PlanError, SeamAssessment, SeamCoverage, Stage, Unplanned, boundary, quality, trajectory};
use crate::rules::refit::TEE_NO_ROOT_SEEN;

/// Where the flange lies: either side of the web (a tee), or on one side
/// only (an inside corner, the web standing at the flange's end).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Flange {
    BothSides,
    OneSide,
}

/// A tee as the background stage found it: what is seen of its web, every
/// piece of its flange, and what lies behind the flange.
pub(super) struct SeenTee<'w> {
    pub web: Web<'w>,
    pub flange_pieces: Vec<&'w PlaneCluster>,
    pub flange_sides: Flange,
    pub depth_to_support_mm: Option<f64>,
    /// The web is a member with every side a root (a block standing on
    /// the flange, [`super::background::Selected::web_by_faces`]): its
    /// ends' roots are read beside the two along it.
    pub every_side: bool,
}

impl<'w> SeenTee<'w> {
    /// The tee in `workpiece`: the web's top and the largest flange piece,
    /// the flange's other pieces its layer mates.
    pub fn of(workpiece: &'w Workpiece, flange_sides: Flange) -> SeenTee<'w> {
        let [web_top, flange] = &workpiece.plates;
        SeenTee {
            web: Web::Top(web_top),
            flange_pieces: std::iter::once(flange).chain(&workpiece.layer_mates[1]).collect(),
            flange_sides,
            depth_to_support_mm: workpiece.depth_to_support_mm,
            every_side: false,
        }
    }
}

/// Plans the seen roots of `tee` as welds, and names the roots not
/// planned; `layers` says in words what the background stage saw.
pub(super) fn plan(
    ctx: &mut Context,
    tee: SeenTee,
    layers: String,
) -> Result<(Vec<PlannedWeld>, Vec<Unplanned>), PlanError> {
    let config = ctx.config;
    let cfg = &config.pipeline;
    ctx.trace.record(|t| t.joint = Some(JointType::TFillet));
    let spacing = ctx.spacing_at(&tee.web.centroid());
    let grid = ctx.camera_grid();
    let in_view = grid.as_ref().map(|g| move |p: &Vec3| g.in_view(p));
    let view = TeeView {
        cloud: ctx.cloud,
        web: tee.web,
        flange_pieces: &tee.flange_pieces,
        point_spacing_mm: spacing,
        rim_mm: boundary::rim_trim_radii(cfg.plane_min_neighbour_ratio) * ctx.scale.radius_mm,
        on_plane_mm: cfg.on_plane_tolerance_mm,
        trim_sigma: cfg.fit_trim_sigma,
        projector: Vec3::new(config.camera.baseline_mm, 0.0, 0.0),
        in_view: in_view.as_ref().map(|f| f as &dyn Fn(&Vec3) -> bool),
        border: ctx.view_border(),
        max_beyond_mm: config.quality.max_joint_beyond_seam_mm,
        every_side: tee.every_side,
        web_thickness_max_mm: cfg.tee_web_thickness_max_mm,
    };
    let mut roots = Vec::from(fillet::find_roots(&view));
    if tee.every_side {
        roots.extend(fillet::find_end_roots(&view));
    }
    if tee.flange_sides == Flange::OneSide {
        // An inside corner: the side with no flange has no root at all.
        roots.retain(|root| root.as_ref().map_or_else(|not| not.flange_seen, |_| true));
    }
    for root in &roots {
        match root {
            Ok(r) => {
                for rule in &r.ends_set_by {
                    tracing::debug!(rule = rule.id, side = ?r.side, "the fillet root's ends moved or cut");
                }
                tracing::debug!(
                side = ?r.side,
                face_points = r.face_points,
                face_rms_mm = r.face_rms_mm,
                bend = ?r.bend,
                web_angle_deg = r.web_angle_deg,
                from_mm = r.line.s_min,
                to_mm = r.line.s_max,
                "fillet root"
                )
            }
            Err(not) => tracing::debug!(rule = not.rule.id, side = ?not.side, "{}", not.reason),
        }
    }
    ctx.clock.lap(Stage::Refit)?;

    // Each root's figures against the gates; a root refused or not seen
    // is named beside the ones planned.
    let mut planned: Vec<(Root, SeamAssessment)> = Vec::new();
    let mut unplanned: Vec<Unplanned> = Vec::new();
    for root in roots {
        let root = match root {
            Ok(root) => root,
            Err(not) => {
                unplanned.push(Unplanned {
                    joint: Some(JointType::TFillet),
                    near_camera: Some(not.near_camera),
                    reason: PlanError::by(not.rule, not.reason),
                });
                continue;
            }
        };
        let near_camera = root.line.at(0.5 * (root.line.s_min + root.line.s_max));
        let quality = quality::measure_fillet(&root, spacing, tee.depth_to_support_mm);
        let coverage = SeamCoverage {
            edge: root.coverage,
            joint: root.seen_share,
            visible_joint_mm: root.seen_mm,
            beyond_mm: 0.0,
        };
        let evidence = quality::SeamEvidence {
            joint: JointType::TFillet,
            quality: &quality,
            edge_fit_rms_mm: [root.face_rms_mm, root.flange_rms_mm],
            edge_beyond: None,
            edge_steps: None,
            edge_coverage: Some(root.coverage),
            coverage: Some(&coverage),
            // The web's top and the flange up to the root seen beyond
            // the root's ends: the joint goes on where its face is not seen.
            joint_beyond_ends_mm: root.joint_beyond_ends_mm,
            length_mm: root.line.s_max - root.line.s_min,
            given_groove_depth_mm: None,
            fits: match root.evidence {
                RootEvidence::Face => quality::FittedEdges::WebFace,
                RootEvidence::FlangeEdge { .. } => quality::FittedEdges::FlangeEdge,
            },
            root_bend: root.bend,
        };
        let (warnings, refusals): (Vec<_>, Vec<_>) =
            quality::check(&evidence, &config.quality).into_iter().partition(|f| config.quality.warns_only(f.gate));
        if let Some(first) = refusals.first() {
            let mut reason = PlanError::refused(first);
            reason.reason = format!("{}: {}", root.side.root_name(root.sign), reason.reason);
            unplanned.push(Unplanned { joint: Some(JointType::TFillet), near_camera: Some(near_camera), reason });
            continue;
        }
        for failure in &warnings {
            tracing::warn!(gate = %failure.gate, value = failure.value, limit = failure.limit, "{}", failure.message);
        }
        let joint_evidence = format!("{layers}; {}: {}", root.side.root_name(root.sign), root.describe());
        let assessment = SeamAssessment {
            joint_evidence: Some(joint_evidence),
            coverage: Some(coverage),
            quality: Some(quality),
            warnings,
        };
        planned.push((root, assessment));
    }
    ctx.clock.lap(Stage::Quality)?;
    if planned.is_empty() {
        // Nothing to weld: the gate that refused a root seen, else why
        // neither was seen.
        let gated = unplanned.iter().find(|u| u.reason.gate.is_some()).map(|u| u.reason.clone());
        return Err(gated.unwrap_or_else(|| {
            let why: Vec<&str> = unplanned.iter().map(|u| u.reason.reason.as_str()).collect();
            PlanError::by(&TEE_NO_ROOT_SEEN, format!("no fillet root of the tee joint is seen: {}", why.join("; ")))
        }));
    }

    // 5.1 (sampled with the frame's other welds): each root its own seam,
    // the torch between the flange and the web.
    ctx.trace.record(|t| {
        let (root, _) = &planned[0];
        let normal = root.flange.normal;
        t.weld = Some(TracedWeld { curve: root.line.clone(), span: root.span(), normal });
    });
    let welds = planned
        .into_iter()
        .map(|(root, assessment)| {
            let normal = root.flange.normal;
            let axis =
                trajectory::fillet_torch_axis(&normal, &root.away_from_web(), config.trajectory.fillet_work_angle_deg);
            let edges = EdgeFigures {
                rms_mm: [root.face_rms_mm, root.flange_rms_mm],
                samples: [root.face_points, root.flange_points],
                dropped: [root.face_dropped, 0],
            };
            PlannedWeld::new(JointType::TFillet, root.line.clone(), root.span(), normal, edges, assessment)
                .with_torch_axis(axis)
        })
        .collect();
    Ok((welds, unplanned))
}
