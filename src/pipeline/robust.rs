//! The robust method: the paper's sections 3 to 5 in the same order, with
//! each rule that breaks on real cells replaced by one that holds there
//! (each stage module pairs the paper's rule with the robust one and says
//! why).
//!
//! - 3.2: the workpiece's dominant normal first ([`super::orientation`]),
//!   then plane points by the neighbour count of a plane *tilted* to it
//!   (Eq. 6 with the foreshortening it leaves out), off-normal faces
//!   rejected;
//! - 3.3: clustering on the pixel grid where there is one; background
//!   removal by depth along the normal, not by the largest bounding box;
//! - 3.4.1: edge points against the tilted plane's count (Eq. 15's rule);
//! - 3.4.2: RANSAC per plate, not over both at once;
//! - 4.1: the weld edges by the centroids (Eq. 16) and the edges' facing
//!   each other across the gap;
//! - 4.2: the edges resampled along the plate boundary and refitted along
//!   their principal direction with outliers trimmed (Eq. 17 to 25);
//! - 4.3: the normal from the two plates' planes, not the edges' ends
//!   (Eq. 33, 34), the weld per joint type (Eq. 32, 36) and the lap weld at
//!   the root (Eq. 38), over the stretch both edges were seen;
//! - 5.1: base-frame waypoints (Eq. 39 to 42).

use rayon::prelude::*;

use crate::cloud::is_valid_point;
use crate::config::Method;
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;

use super::background::{BackgroundError, CornerKind, Layout, PlaneCluster};
use super::boundary::{self, Boundary, BoundaryParams, CoarseEdge};
use super::context::{self, Context, EdgeFigures, MIN_CLUSTER_POINTS, PlannedWeld};
use super::edge_points::{EdgeCriterion, FullCount};
use super::fillet::Web;
use super::neighbours::NeighbourSearch;
use super::plane_points::PlanePoints;
use super::ransac::EdgeLine;
use super::refit::{self, SeamAxes};
use super::trace::TracedWeld;
use super::view_border;
use super::{Plan, PlanError, PlanStats, SeamAssessment, SeamCoverage, Stage, StageTimings, Unplanned};
use super::{
    background, clustering, groove, orientation, plane_points, quality, ransac, tee, web_face, weld_edges,
    weld_equation, workpieces,
};

/// How far, in degrees, a sampled local normal may lie from the most common
/// one and still be averaged into the dominant normal. Depth noise tilts
/// the normals of one plate by a degree or two; a bevel or side face lies
/// tens of degrees off, so five degrees keeps the plates and drops faces.
const DOMINANT_NORMAL_AGREEMENT_DEG: f64 = 5.0;

/// The shortest vector normalised as a direction: below it the sum of two
/// plate normals is taken as no direction at all (they point apart).
const MIN_DIRECTION_NORM: f64 = 1e-9;

/// The Euclidean clustering tolerance in point spacings, at least, for a
/// cloud whose spacing is measured: diagonal neighbours lie 1.4 spacings
/// apart, and the plane criterion leaves the odd hole.
const CLUSTER_SPACINGS: f64 = 2.5;

/// The tightest clustering tolerance in point spacings that still joins a
/// measured cloud's lattice: past its diagonal neighbours (1.41 spacings),
/// with a little room for a voxel grid's uneven rows. Clusters the loose
/// tolerance joins are split at it only into pieces each large enough to
/// be a plate ([`clustering::split_narrow_gaps`]).
const TIGHT_CLUSTER_SPACINGS: f64 = 1.6;

/// The shortest run of a weld edge's samples, as a share of them, that a
/// step between two lines is read across: shorter runs are a tack weld's
/// or a spatter's, and the share of samples beyond the line judges them.
const MIN_STEP_RUN_SHARE: f64 = 0.1;

/// Plans one frame by the robust method.
pub(super) fn plan(mut ctx: Context) -> Result<Plan, PlanError> {
    let config = ctx.config;
    let cfg = &config.pipeline;
    let camera = &config.camera;
    // The scale: the camera's for its raw frames, else measured from the
    // cloud's own spacing (Eq. 4 to 14 hold for one camera only).
    let measured = ctx.measure_scale()?;
    let scale = ctx.scale;
    let cloud = ctx.cloud;
    let search = {
        let mut search = NeighbourSearch::new(cloud, camera, scale.radius_mm);
        if measured {
            let full = search.measure_full_counts().map(|m| m.cloud_full_count());
            tracing::debug!(cloud_full_count = full, radius_mm = scale.radius_mm, "full-plane counts measured");
        }
        search
    };
    ctx.clock.lap(Stage::NeighbourIndex)?;

    // Plates, table and fixture lie parallel: one normal describes them.
    let dominant = orientation::dominant_normal(cloud, &search, camera.fx(), DOMINANT_NORMAL_AGREEMENT_DEG)
        .ok_or_else(|| PlanError::at(Stage::Orientation, "no surface normal could be estimated"))?;
    ctx.trace.record(|t| t.dominant_normal = Some(dominant));
    ctx.clock.lap(Stage::Orientation)?;

    // 3.2: plane points against the count of a plane tilted to the
    // dominant normal (Eq. 6 and 14, foreshortened), facing it.
    let mut plane = plane_points::robust_criterion(
        &search,
        &plane_points::RobustPlaneCriterion {
            normal: dominant,
            min_ratio: cfg.plane_min_neighbour_ratio,
            max_angle_deg: cfg.plane_max_normal_angle_deg,
        },
    );
    ctx.stats.plane_points = plane.len();
    ctx.trace.record(|t| t.plane_points = plane.mask.clone());
    ctx.clock.lap(Stage::PlanePoints)?;
    if ctx.stats.plane_points == 0 {
        return Err(PlanError::at(Stage::PlanePoints, "no point passed the plane point criterion"));
    }

    // A point stands for a tilted pixel's area: what a cluster's area, and
    // so whether it is large enough to be a plate, is read with.
    let area_per_point = |c: &Vec3, n: &Vec3| search.area_per_point(c, n);

    // 3.3: clustering, on the pixel grid where the frame has one.
    let mut clusters = if cloud.is_organized() {
        clustering::grid(cloud, &plane.mask, cfg.cluster_tolerance_mm, MIN_CLUSTER_POINTS)
    } else {
        // A plate's points connect through neighbours about a spacing
        // apart, diagonals and the criterion's gaps included.
        let tolerance = scale.at_least_spacings(cfg.cluster_tolerance_mm, CLUSTER_SPACINGS);
        let loose = clustering::euclidean(cloud, &plane.mask, tolerance, MIN_CLUSTER_POINTS);
        // Plates a gap narrower than that apart (an I-butt's in a voxel
        // cloud) are told apart at the tightest tolerance that still
        // joins a lattice's neighbours.
        let tight_tolerance = scale.at_least_spacings(cfg.cluster_tolerance_mm, TIGHT_CLUSTER_SPACINGS);
        if tight_tolerance < tolerance {
            let tight = clustering::euclidean(cloud, &plane.mask, tight_tolerance, MIN_CLUSTER_POINTS);
            clustering::split_narrow_gaps(loose, &tight, |members| {
                !ctx.planes_of(vec![members.to_vec()], area_per_point).is_empty()
            })
        } else {
            loose
        }
    };
    // The edge criterion needs the counts, not the mask: free it early,
    // as the frame-sized arrays of the coming stages add up.
    plane.mask = Vec::new();
    ctx.clock.lap(Stage::Clustering)?;

    // 3.3: the plates are the nearest parallel planes (a lap: two layers a
    // plate thickness apart).
    let planes = ctx.planes_of(std::mem::take(&mut clusters.members), area_per_point);
    ctx.stats.clusters = planes.len();
    ctx.trace.record(|t| t.planes = planes.clone());

    // Several workpieces: the clusters grouped so that plates of different
    // workpieces are never paired across the table; a frame of one is one
    // group holding every cluster, as it always was.
    let middle = planes.iter().fold(Vec3::zeros(), |m, c| m + c.centroid) / planes.len().max(1) as f64;
    let grouping = workpieces::GroupSettings {
        normal: dominant,
        max_tilt_deg: cfg.plane_max_normal_angle_deg,
        coplanar_tolerance_mm: cfg.coplanar_tolerance_mm,
        point_spacing_mm: scale.spacing_at(camera, &middle),
    };
    let mut groups = workpieces::group(cloud, planes, &grouping);
    let front = Front { search: &search, plane: &plane, dominant };
    if groups.len() == 1 {
        let planes = groups.pop().map(|g| g.planes).unwrap_or_default();
        let (welds, unplanned) = plan_workpiece(&mut ctx, &front, &clusters.labels, planes)?;
        return ctx.finish_several(Method::Robust, welds, unplanned);
    }

    // Each workpiece side by side: its seams, or why not. They share the
    // frame's stages, read nothing another writes, and each has its own
    // context; the trace keeps the first workpiece's stages and the
    // counts are the first's too.
    ctx.clock.lap(Stage::Background)?;
    let outcomes: Vec<Outcome> = ctx
        .per_workpiece(groups.len())
        .into_par_iter()
        .zip(groups)
        .enumerate()
        .map(|(k, (mut piece, group))| {
            let _span = tracing::debug_span!("workpiece", number = k + 1).entered();
            piece.clock.restart();
            let result = plan_workpiece(&mut piece, &front, &clusters.labels, group.planes);
            if let Err(refusal) = &result {
                // The refusing stage's own work, up to the refusal.
                // The refusal stands; the time limit is the plan's to check.
                let _ = piece.clock.lap(refusal.stage);
            }
            Outcome {
                result,
                joint: piece.joint,
                near_camera: group.near_camera,
                stats: piece.stats,
                timings: piece.clock.into_timings(),
            }
        })
        .collect();
    ctx.clock.lap_beside(outcomes.iter().map(|o| &o.timings));
    if let Some(first) = outcomes.first() {
        ctx.stats = first.stats.clone();
    }
    // A workpiece stopped by the time limit says nothing about the frame:
    // the plan as a whole ran out of time.
    if let Some(stopped) = outcomes.iter().find_map(|o| o.result.as_ref().err().filter(|e| e.out_of_time)) {
        return Err(stopped.clone());
    }
    ctx.clock.deadline.check(Stage::Background)?;
    let (mut welds, mut unplanned) = (Vec::new(), Vec::new());
    for (k, outcome) in outcomes.into_iter().enumerate() {
        match outcome.result {
            Ok((planned, seen)) => {
                welds.extend(planned.into_iter().map(|weld| weld.traced(k == 0)));
                unplanned.extend(seen);
            }
            Err(reason) => {
                tracing::info!(workpiece = k + 1, near_camera = ?outcome.near_camera.as_slice(), "workpiece not planned: {reason}");
                // The joint requested is no workpiece's joint when it
                // does not match; otherwise the one planned or seen.
                let mismatch = reason.gate == Some(quality::Gate::JointMismatch);
                let joint = outcome.joint.filter(|j| !(mismatch && ctx.request.joint.given() == Some(*j)));
                unplanned.push(Unplanned { joint, near_camera: Some(outcome.near_camera), reason });
            }
        }
    }
    ctx.finish_several(Method::Robust, welds, unplanned)
}

/// What planning one workpiece of several gave, and what its context
/// recorded on the way.
struct Outcome {
    result: Result<(Vec<PlannedWeld>, Vec<Unplanned>), PlanError>,
    /// The joint planned or seen, for a workpiece refused.
    joint: Option<JointType>,
    near_camera: Vec3,
    stats: PlanStats,
    timings: StageTimings,
}

/// Refuses a workpiece found to be `joint` when the request does not admit
/// it (a set of types, [`crate::joint::RequestedJoint::OneOf`]), saying what was seen:
/// `seen`, the evidence that decided the type. `ctx.joint` names what was
/// seen, for the workpiece's entry among the unplanned.
fn admit(ctx: &mut Context, joint: JointType, stage: Stage, seen: &str) -> Result<(), PlanError> {
    ctx.joint = Some(joint);
    if ctx.request.joint.admits(joint) {
        return Ok(());
    }
    Err(joint_mismatch(ctx, &format!("a {joint} joint"), stage, seen))
}

/// The refusal of a workpiece that is `what` (found from `seen`) under a
/// request that does not admit it.
fn joint_mismatch(ctx: &Context, what: &str, stage: Stage, seen: &str) -> PlanError {
    let message = format!("{seen}: this looks like {what}, not one of the joints requested ({})", ctx.request.joint);
    PlanError { gate: Some(quality::Gate::JointMismatch), ..PlanError::at(stage, message) }
}

/// What the workpieces of a frame share from the frame's front stages.
struct Front<'f> {
    search: &'f NeighbourSearch<'f>,
    plane: &'f PlanePoints,
    dominant: Vec3,
}

/// Plans one workpiece from its plane clusters (and the table's) to its
/// checked welds: the plates and how they lie (3.3), then the path of
/// that layout: a butt joint's or a lap's edges through the quality gates,
/// or a tee's fillet roots (each root seen a weld, a root hidden named in
/// the second list). `labels` are the frame's cluster labels, which the
/// edge stage reads for this workpiece's plates.
fn plan_workpiece(
    ctx: &mut Context,
    front: &Front,
    labels: &[u32],
    planes: Vec<PlaneCluster>,
) -> Result<(Vec<PlannedWeld>, Vec<Unplanned>), PlanError> {
    let cfg = &ctx.config.pipeline;
    let selection = background::Selection {
        joint: ctx.request.joint.given(),
        normal: front.dominant,
        coplanar_tolerance_mm: cfg.coplanar_tolerance_mm,
        lap_step_min_mm: cfg.lap_step_min_mm,
        lap_step_max_mm: cfg.lap_step_max_mm,
        web_height_max_mm: cfg.tee_web_height_max_mm,
        web_thickness_max_mm: cfg.tee_web_thickness_max_mm,
        max_tilt_deg: cfg.plane_max_normal_angle_deg,
        neighbour_radius_mm: ctx.scale.radius_mm,
    };
    // A corner joint's plates pass for a butt pair, a lap or a tee. An
    // inside corner's fillet root is a tee's root with the flange on one
    // side: planned as one under `t_fillet` or `auto`. Any other corner,
    // or another request, is refused by name.
    if let Some(corner) = background::find_corner(&planes, &selection, ctx.cloud.points(), || ctx.view_border()) {
        let fillet = ctx.request.joint.admits(JointType::TFillet);
        if corner.kind == CornerKind::Inside && fillet {
            tracing::debug!(rule = corner.rule(fillet).id, "{}", corner.what);
            let (standing, flange) = (planes[corner.standing].clone(), planes[corner.flange].clone());
            let workpiece = background::Workpiece {
                plates: [standing, flange],
                depth_to_support_mm: None,
                support_between_plates: false,
                layer_mates: [Vec::new(), Vec::new()],
            };
            ctx.clock.lap(Stage::Background)?;
            let layers = format!("an inside corner: {}", corner.what);
            return tee::plan(ctx, tee::SeenTee::of(&workpiece, tee::Flange::OneSide), layers);
        }
        let refusal = corner.refusal();
        return Err(PlanError { gate: Some(quality::Gate::CornerJoint), ..PlanError::by(refusal.rule(), refusal) });
    }
    // A tee whose web's top is not found may have it out of view (a crop
    // round its root): its face standing on the nearest layer of planes,
    // planned under `t_fillet`; under `auto`, named when too few planes
    // are seen for any other joint.
    let face_may_stand = match selection.joint {
        Some(JointType::TFillet) => true,
        None => planes.iter().filter(|c| selection.faces_camera(c)).count() < 2,
        Some(_) => false,
    };
    let bare_flange = face_may_stand.then(|| background::nearest_layer(&planes, &selection)).flatten();
    let selected = match (background::robust_select(planes, &selection, ctx.cloud.points()), bare_flange) {
        (Err(e @ (BackgroundError::NoWeb { .. } | BackgroundError::TooFewPlanes { .. })), Some(flange)) => {
            return plan_topless_tee(ctx, flange, e);
        }
        (selected, _) => selected,
    };
    let background::Selected { workpiece, layout, evidence: layers } =
        selected.map_err(|e| background_refusal(&e, e.to_string()))?;
    if layout == Layout::Lap {
        ctx.joint = Some(JointType::Lap);
        ctx.trace.record(|t| t.joint = Some(JointType::Lap));
    }
    // A set of types requested: the layers decide a lap or a tee; a butt
    // pair is one of the two butt joints, which the groove probe tells.
    match layout {
        Layout::Lap => admit(ctx, JointType::Lap, Stage::Background, &layers)?,
        Layout::Tee => admit(ctx, JointType::TFillet, Stage::Background, &layers)?,
        Layout::Butt => {
            if ![JointType::VButt, JointType::IButt].into_iter().any(|j| ctx.request.joint.admits(j)) {
                return Err(joint_mismatch(ctx, "a butt joint", Stage::Background, &layers));
            }
        }
    }
    tracing::debug!(?layout, "{layers}");
    ctx.stats.plate_points = workpiece.plates.each_ref().map(|p| p.members.len());
    ctx.trace.record(|t| t.plate_labels = Some(workpiece.plates.each_ref().map(|p| p.label)));
    for (k, plate) in workpiece.plates.iter().enumerate() {
        tracing::debug!(
            plate = k + 1,
            points = plate.members.len(),
            area_mm2 = plate.area_mm2,
            normal = ?plate.plane.normal.as_slice(),
            offset_mm = plate.plane.offset,
            centroid = ?plate.centroid.as_slice(),
            "plate"
        );
    }
    ctx.clock.lap(Stage::Background)?;
    // One path per layout: each returns the workpiece's welds.
    match layout {
        Layout::Butt | Layout::Lap => {
            plan_plates(ctx, front, labels, workpiece, layout, layers).map(|weld| (vec![weld], Vec::new()))
        }
        // A web on its flange: its fillet roots, not two plates' edges.
        Layout::Tee => tee::plan(ctx, tee::SeenTee::of(&workpiece, tee::Flange::BothSides), layers),
    }
}

/// A lap's weld edge checked against the upper plate's other edges
/// (`lines`, fitted to `edge_points`; `chosen` the weld edge's): the
/// lower plate, with the pieces of its layer, must not be seen beside one
/// turned from it for longer, nor beside all of one (the upper plate's
/// end), nor beside most of the edge across the plate from it (the upper
/// plate lying on the layer whole; [`weld_edges::check_lap_edge`]), and
/// under a request that leaves a butt joint open the upper plate must be
/// seen to end off the plane under it somewhere besides that edge
/// ([`weld_edges::check_lap_ends_off_lower_plane`]). The lower plate's
/// points begin past the upper plate's edge points by up to two neighbour
/// radii (the rims the plane criterion trims off both plates) and what
/// the upper plate's thickness, a lap step, hides or shades.
fn check_lap_edge(
    ctx: &Context,
    workpiece: &background::Workpiece,
    lines: &[EdgeLine],
    edge_points: &[Vec3],
    chosen: usize,
) -> Result<(), PlanError> {
    let turned = weld_edges::turned_from(lines, chosen);
    let [upper, lower] = &workpiece.plates;
    // The chosen edge, the turned ones (the plate's ends), then the lines
    // parallel to it that face away from it: across the plate.
    let candidates: Vec<usize> = std::iter::once(chosen)
        .chain(turned.iter().copied())
        .chain((0..lines.len()).filter(|k| *k != chosen && !turned.contains(k)))
        .collect();
    let spanned = weld_edges::plate_edges(lines, &candidates, edge_points, &upper.centroid, &upper.plane.normal);
    let (measured, edges): (Vec<usize>, Vec<boundary::SpannedEdge>) = candidates
        .iter()
        .zip(&spanned)
        .enumerate()
        .filter(|(k, (_, e))| *k <= turned.len() || e.edge.outward.dot(&spanned[0].edge.outward) < -FAR_EDGE_MIN_COS)
        .map(|(_, (&line, &e))| (line, e))
        .unzip();
    let step_mm = upper.plane.normal.dot(&(lower.centroid - upper.centroid)).abs();
    let band_mm = step_mm + 2.0 * ctx.scale.radius_mm + ctx.scale.band(ctx.config.pipeline.boundary_band_mm);
    let spacing_mm = ctx.scale.spacing_at(&ctx.config.camera, &upper.centroid);
    let bin_mm = (2.0 * spacing_mm).max(LAP_EDGE_BIN_MIN_MM);
    let beside: Vec<&[u32]> =
        std::iter::once(lower).chain(&workpiece.layer_mates[1]).map(|c| c.members.as_slice()).collect();
    // The refusal rules judge the other edges against the chosen one: with
    // none, they have nothing to read.
    if measured.len() > 1 {
        let seen_mm = boundary::stretch_seen_beside(ctx.cloud, &beside, &edges, [band_mm, bin_mm, spacing_mm]);
        tracing::debug!(?measured, ?seen_mm, band_mm, "lower plate beside the upper plate's edges");
        let other = |k: usize| weld_edges::OtherEdge {
            line: measured[k],
            length_mm: edges[k].span[1] - edges[k].span[0],
            seen_mm: seen_mm[k],
        };
        let ends: Vec<weld_edges::OtherEdge> = (1..=turned.len()).map(other).collect();
        let far: Vec<weld_edges::OtherEdge> = (1 + turned.len()..measured.len()).map(other).collect();
        weld_edges::check_lap_edge(lines, chosen, seen_mm[0], &ends, &far)
            .map_err(|e| PlanError::at(Stage::WeldEdges, e))?;
    }
    // A lap request says what the plane under the upper plate is; one that
    // leaves a butt joint open asks the frame.
    if ![JointType::VButt, JointType::IButt].into_iter().any(|j| ctx.request.joint.admits(j)) {
        return Ok(());
    }
    let (measured, edges) = (&measured[1..], &edges[1..]);
    let lies = edges_lie(ctx, upper, lines, measured, edge_points, edges, [band_mm, bin_mm, spacing_mm]);
    let plane_beside_mm = lower_plane_beside(ctx, lower, &beside, edges, [band_mm, bin_mm, spacing_mm]);
    tracing::debug!(?lies, ?plane_beside_mm, "where the upper plate's other edges lie");
    let seen: Vec<weld_edges::EdgeSeen> = edges
        .iter()
        .zip(lies)
        .zip(plane_beside_mm)
        .map(|((e, lies), plane_beside_mm)| weld_edges::EdgeSeen {
            length_mm: e.span[1] - e.span[0],
            lies,
            plane_beside_mm,
        })
        .collect();
    weld_edges::check_lap_ends_off_lower_plane(&seen).map_err(|e| PlanError {
        gate: e.is_unknown().then_some(quality::Gate::JointUnknown),
        ..PlanError::at(Stage::WeldEdges, e)
    })
}

/// How long a stretch of each of `edges` the plane of `lower` is seen
/// beside, read from the layer's clusters (`clusters`) and every other
/// point within `pipeline.on_plane_tolerance_mm` of that plane: returns
/// too few to make a cluster (a corner of the table between the image's
/// border and a plate) count too. The cloud is read one point in as many
/// as the bins need ([`boundary::read_stride`]), so a frame of millions
/// of points costs a tenth of a pass or less.
fn lower_plane_beside(
    ctx: &Context,
    lower: &PlaneCluster,
    clusters: &[&[u32]],
    edges: &[boundary::SpannedEdge],
    figures: [f64; 3],
) -> Vec<f64> {
    let tolerance_mm = ctx.config.pipeline.on_plane_tolerance_mm;
    let stride = boundary::read_stride(figures);
    let points = ctx.cloud.points();
    let mut on_plane: Vec<u32> = (0..points.len())
        .into_par_iter()
        .step_by(stride)
        .filter(|&i| {
            let p = &points[i];
            is_valid_point(p) && lower.plane.signed_distance(&vec3(p)).abs() <= tolerance_mm
        })
        .map(|i| i as u32)
        .collect();
    on_plane.extend(clusters.iter().flat_map(|members| members.iter().step_by(stride)));
    boundary::stretch_seen_beside_reading(ctx.cloud, &[&on_plane], edges, figures, 1)
}

/// Where each of a plate's `edges` lies (line `measured[k]` of `lines`,
/// fitted to `edge_points`): along the view's border where most of the
/// line's inliers lie within the plate's rim (a neighbour radius) and two
/// spacings of it ([`view_border::ViewBorder::runs_along`]); within the
/// plate where the plate's own points are seen past the line's scatter
/// (two spacings) and within `band_mm` beyond it along most of its span;
/// else in view, where the plate ends.
fn edges_lie(
    ctx: &Context,
    plate: &PlaneCluster,
    lines: &[EdgeLine],
    measured: &[usize],
    edge_points: &[Vec3],
    edges: &[boundary::SpannedEdge],
    [band_mm, bin_mm, spacing_mm]: [f64; 3],
) -> Vec<weld_edges::EdgeLies> {
    use weld_edges::EdgeLies;
    let scatter_mm = 2.0 * spacing_mm;
    let past_scatter: Vec<boundary::SpannedEdge> = edges
        .iter()
        .map(|e| {
            let mut past = *e;
            past.edge.point += e.edge.outward * scatter_mm;
            past
        })
        .collect();
    let plate_beyond = boundary::stretch_seen_beside(
        ctx.cloud,
        &[&plate.members],
        &past_scatter,
        [band_mm - scatter_mm, bin_mm, spacing_mm],
    );
    let reach_mm = ctx.scale.radius_mm + 2.0 * spacing_mm;
    measured
        .iter()
        .zip(edges)
        .zip(plate_beyond)
        .map(|((&line, e), beyond_mm)| {
            let inliers: Vec<Vec3> = lines[line].inliers.iter().map(|&i| edge_points[i]).collect();
            if ctx.view_border().is_some_and(|border| border.runs_along(&inliers, reach_mm)) {
                EdgeLies::AlongBorder
            } else if beyond_mm > PLATE_BEYOND_SLIT_SHARE * (e.span[1] - e.span[0]) {
                EdgeLies::WithinPlate
            } else {
                EdgeLies::InView
            }
        })
        .collect()
}

/// The share of an edge line's span beyond which a plate's own points are
/// seen for the line to be a slit through the plate rather than its end:
/// beyond a plate's end nothing of it lies, and beyond one side of a slit
/// (a butt joint's gap the cloud resolves along part of its length, in a
/// workpiece it otherwise sees as one) the other side runs all along.
const PLATE_BEYOND_SLIT_SHARE: f64 = 0.5;

/// Of an upper plate's edges not turned from the lap's weld edge (under
/// 60°, [`weld_edges::turned_from`]), one lies across the plate from it
/// when their outward directions are within about 25° of opposite (a
/// cosine of 0.9); nearer alike, it is another line along the weld edge's
/// own side.
const FAR_EDGE_MIN_COS: f64 = 0.9;

/// The least bin, mm, in which the lower plate is looked for beside an
/// upper plate's edge; two point spacings where they are wider, so a bin
/// that falls between two points' places is not read as a break.
const LAP_EDGE_BIN_MIN_MM: f64 = 2.0;

/// The refusal of a workpiece the background rule found no joint in,
/// saying `reason`, under the gate `e` falls under (a joint other than the
/// one requested, or none that `auto` can name; else no gate).
fn background_refusal(e: &BackgroundError, reason: String) -> PlanError {
    let gate = if e.is_joint_mismatch() {
        Some(quality::Gate::JointMismatch)
    } else if e.is_unrecognised() {
        Some(quality::Gate::JointUnknown)
    } else {
        None
    };
    PlanError { gate, ..PlanError::by(e.rule(), reason) }
}

/// A tee's root from its web's one face seen standing on `flange` (the
/// nearest layer of planes), the web's top out of view; refused with
/// `not_found` (why no web's top was found) and why no face was either.
/// Under `auto` the face is named, not planned: a face alone does not
/// tell a tee's web from an inside corner's plate or a fixture's side.
fn plan_topless_tee(
    ctx: &mut Context,
    flange: Vec<PlaneCluster>,
    not_found: BackgroundError,
) -> Result<(Vec<PlannedWeld>, Vec<Unplanned>), PlanError> {
    let cfg = &ctx.config.pipeline;
    let pieces: Vec<&PlaneCluster> = flange.iter().collect();
    let search = web_face::FaceSearch {
        point_spacing_mm: ctx.spacing_at(&flange[0].centroid),
        on_plane_mm: cfg.on_plane_tolerance_mm,
        web_height_max_mm: cfg.tee_web_height_max_mm,
        trim_sigma: cfg.fit_trim_sigma,
    };
    let fillet_asked = ctx.request.joint.given() == Some(JointType::TFillet);
    let face = web_face::find(ctx.cloud, &pieces, &search).map_err(|why| {
        // Under `auto` the search was a guess at a cropped tee: its failure
        // says nothing about the joint the cloud holds.
        let reason = if fillet_asked {
            format!("{not_found}; nor does a web's side face stand on the nearest plane: {why}")
        } else {
            not_found.to_string()
        };
        background_refusal(&not_found, reason)
    })?;
    let layers = format!(
        "no web's top is in view; a side face of {} points stands on the nearest plane ({:.0} mm² in {} piece(s)), \
         seen {:.0} mm tall",
        face.points,
        flange.iter().map(|c| c.area_mm2).sum::<f64>(),
        flange.len(),
        face.seen_height_mm
    );
    tracing::debug!("{layers}");
    if !fillet_asked {
        let reason = format!(
            "{not_found}; {layers}: this may be a tee's web (or an inside corner's standing plate) cropped below its \
             top; request t_fillet to plan its root"
        );
        return Err(PlanError { gate: Some(quality::Gate::JointUnknown), ..PlanError::at(Stage::Background, reason) });
    }
    ctx.clock.lap(Stage::Background)?;
    let tee = tee::SeenTee {
        web: Web::Face(&face),
        flange_pieces: pieces,
        flange_sides: tee::Flange::BothSides,
        depth_to_support_mm: None,
    };
    tee::plan(ctx, tee, layers)
}

/// A butt joint's or a lap's weld from its two plates: edge points through
/// the quality gates (3.4 to 4.3).
fn plan_plates(
    ctx: &mut Context,
    front: &Front,
    labels: &[u32],
    workpiece: background::Workpiece,
    layout: Layout,
    layers: String,
) -> Result<PlannedWeld, PlanError> {
    let config = ctx.config;
    let cfg = &config.pipeline;
    let camera = &config.camera;
    let scale = ctx.scale;
    let cloud = ctx.cloud;
    let (search, plane, dominant) = (front.search, front.plane, front.dominant);
    ctx.check_groove_depth(&workpiece)?;

    // 3.4.1: edge points, at most `pipeline.edge_max_neighbour_ratio` of a
    // tilted plane's count (Eq. 15's rule).
    let criterion = EdgeCriterion { full: FullCount::Plane, ratio: cfg.edge_max_neighbour_ratio };
    let edges = context::plate_edge_points(labels, &workpiece, search, plane, &criterion);
    ctx.stats.edge_points = [edges[0].len(), edges[1].len()];
    ctx.trace.record(|t| t.edge_points = edges.clone());
    ctx.clock.lap(Stage::EdgePoints)?;

    // The plates' least-squares planes fix the normal far better than the
    // sampled dominant one: the groove depth (Eq. 32) and the lap step are
    // shifted along it.
    let [normal_a, normal_b] = workpiece.plates.each_ref().map(|p| p.plane.normal);
    let normal = (normal_a + normal_b).try_normalize(MIN_DIRECTION_NORM).unwrap_or(dominant);

    // 3.4.2: RANSAC per plate. The plates' lines are independent and
    // seeded per plate, so the two run side by side with the same result.
    let edge_points: [Vec<Vec3>; 2] = [ctx.points_of(&edges[0]), ctx.points_of(&edges[1])];
    let (params_a, params_b) = (ctx.ransac_params(0), ctx.ransac_params(1));
    let (lines_a, lines_b) = rayon::join(
        || ransac::segment_lines(&edge_points[0], &params_a),
        || ransac::segment_lines(&edge_points[1], &params_b),
    );
    let lines: [Vec<EdgeLine>; 2] = [lines_a, lines_b];
    ctx.stats.edge_lines = lines[0].len() + lines[1].len();
    ctx.trace.record(|t| (0..2).for_each(|k| t.add_lines(&lines[k], &edge_points[k], |_| k)));
    for (k, plate_lines) in lines.iter().enumerate() {
        for line in plate_lines {
            tracing::debug!(
                plate = k + 1,
                point = ?line.point.as_slice(),
                direction = ?line.direction.as_slice(),
                inliers = line.inliers.len(),
                "edge line"
            );
        }
    }
    ctx.clock.lap(Stage::Ransac)?;

    // 4.1: one line per plate, the centroids on either side (Eq. 16) and
    // the two lines facing each other across the gap.
    let plates = &workpiece.plates;
    let centroids = plates.each_ref().map(|p| p.centroid);
    let pick = weld_edges::robust_select(
        [&lines[0], &lines[1]],
        [&edge_points[0], &edge_points[1]],
        centroids,
        &normal,
        cfg.max_edge_angle_deg,
    )
    .map_err(|e| PlanError::at(Stage::WeldEdges, e))?;
    ctx.trace.record(|t| t.pick_lines(|l| l.rank == pick[l.plate]));
    if layout == Layout::Lap {
        check_lap_edge(ctx, &workpiece, &lines[0], &edge_points[0], pick[0])?;
    }
    ctx.clock.lap(Stage::WeldEdges)?;

    // 4.2: each weld edge resampled along its plate's boundary, then
    // refitted along the samples' principal direction with outliers
    // trimmed (Eq. 17 to 25).
    // The point spacing near `p`: measured, or the camera's pixel footprint.
    let spacing_at = |p: &Vec3| scale.spacing_at(camera, p);
    let params = BoundaryParams { band_mm: scale.band(cfg.boundary_band_mm), on_plane_mm: cfg.on_plane_tolerance_mm };
    // The edge through `point` along `direction`, laid in plate k's plane,
    // its outward side towards the other plate.
    let edge_across = |k: usize, point: &Vec3, direction: &Vec3| {
        let plane = &plates[k].plane;
        let direction = (direction - plane.normal * direction.dot(&plane.normal)).normalize();
        let mut outward = plane.normal.cross(&direction);
        if outward.dot(&(centroids[1 - k] - point)) < 0.0 {
            outward = -outward;
        }
        CoarseEdge { point: plane.project(point), direction, outward }
    };
    let boundary_of = |k: usize| {
        let line = &lines[k][pick[k]];
        let plane = &plates[k].plane;
        let edge = edge_across(k, &line.point, &line.direction);
        // Where the plate is seen beside the weld, for the coverage report.
        let along = |members: &[u32]| boundary::members_along(cloud, members, &edge, params.band_mm);
        let mates = workpiece.layer_mates[k].iter().filter_map(|c| along(&c.members)).collect::<Vec<_>>();
        // Both read only the plate's members near the edge.
        let near = boundary::band_members(cloud, &plates[k].members, &edge, params.band_mm);
        let seen_beside = (along(&near), mates);
        if cloud.is_organized() {
            return (boundary::sample_boundary(cloud, &near, plane, &edge, &params), seen_beside);
        }
        // Without a pixel grid: strips a few spacings wide, each ending
        // where its points stop, read from the whole cloud (both plates'
        // boundaries are read at once, so what one no longer needs is
        // freed first). Where the plate's noise exceeds the on-plane
        // tolerance, the strips' ends are moved out by what it thins.
        drop(near);
        let spacing = spacing_at(&edge.point);
        let scatter = boundary::plane_scatter(cloud, plane, &edge, &params, spacing);
        tracing::debug!(plate = k + 1, scatter_mm = ?scatter, "plate noise");
        (boundary::sample_scattered(cloud, plane, &edge, &params, spacing, scatter), seen_beside)
    };
    let ((boundary_a, beside_a), (boundary_b, beside_b)) = rayon::join(|| boundary_of(0), || boundary_of(1));
    let boundaries: [Boundary; 2] = [boundary_a, boundary_b];
    let samples: [Vec<Vec3>; 2] = boundaries.each_ref().map(|b| b.samples.iter().map(|s| s.position).collect());
    ctx.trace.record(|t| t.fit_samples = samples.clone());
    let union: Vec<Vec3> = samples.iter().flatten().copied().collect();
    let axes = SeamAxes::principal(&union, &normal)
        .ok_or_else(|| PlanError::at(Stage::Refit, "the weld edge samples do not spread along a line"))?;
    let degree = cfg.fit_degree as usize;
    let seam_spacing = spacing_at(&axes.origin);
    let fit_edge = |k: usize| {
        refit::fit_trimmed(&samples[k], &axes, degree, cfg.fit_trim_sigma, seam_spacing).ok_or_else(|| {
            PlanError::at(
                Stage::Refit,
                format!("weld edge {} has {} boundary samples, too few to fit", k + 1, samples[k].len()),
            )
        })
    };
    // The least-median start tries a thousand lines an edge: both at once.
    let (fit_a, fit_b) = rayon::join(|| fit_edge(0), || fit_edge(1));
    let fits = [fit_a?, fit_b?];
    ctx.trace.record(|t| t.weld_edges = Some(fits.clone()));
    // A plate's points stop at its edge: a share of the samples beyond the
    // fitted line, towards the other plate, is the edge itself where a
    // dropout or a shadow cut the rest of it short (the `edge_cut_short`
    // gate reads it). The side is the one the other plate's centroid lies
    // on, which a lap's nearly coincident edges would not tell. The limit
    // is the trimming's, three RMS of the fit, or a spacing at least.
    let limits_mm = fits.each_ref().map(|f| (cfg.fit_trim_sigma * f.rms_mm).max(seam_spacing));
    let outward = [0, 1].map(|k| axes.a * (centroids[1 - k] - centroids[k]).dot(&axes.a).signum());
    let beyond = [0, 1].map(|k| refit::beyond_curve(&samples[k], &fits[k].curve, &outward[k], limits_mm[k]));
    // Where the samples run on two lines, each along a tenth of the edge
    // at least, the fit may run between them (a band over half the seam)
    // or follow one with the other's tenth just inside the share above.
    // Samples trimmed inside the line are a receded run left out, not
    // one of the two. Read on the edges that place the weld: a lap's root
    // is under the upper plate's edge (Eq. 38), and of the lower plate only
    // its plane counts.
    let places_weld = |k: usize| layout == Layout::Butt || k == 0;
    let steps = [0, 1].map(|k| {
        let range = [limits_mm[k], f64::INFINITY];
        places_weld(k)
            .then(|| refit::largest_step(&samples[k], &fits[k].curve, &outward[k], range, MIN_STEP_RUN_SHARE))
            .flatten()
    });
    for (k, f) in fits.iter().enumerate() {
        tracing::debug!(
            edge = k + 1,
            samples = samples[k].len(),
            dropped = f.points_dropped,
            beyond = beyond[k].share(),
            step_mm = steps[k].map(|s| s.size_mm),
            step_share = steps[k].map(|s| s.shorter_share),
            rms_mm = f.rms_mm,
            from_mm = f.curve.s_min,
            to_mm = f.curve.s_max,
            "weld edge refitted"
        );
    }
    ctx.clock.lap(Stage::Refit)?;

    // Between a butt joint's edges: a V-groove's bevels (and how deep it
    // is), a square gap, or a plate standing there. It decides V or I for
    // `auto`, checks the type requested, and measures the depth of Eq. 32.
    let (profile, groove_depth_mm) = if layout == Layout::Butt {
        let span = (fits[0].curve.s_min.max(fits[1].curve.s_min), fits[0].curve.s_max.min(fits[1].curve.s_max));
        let grid = ctx.camera_grid();
        let profile = groove::probe(
            cloud,
            &groove::ProbeSetting {
                edges: [&fits[0].curve, &fits[1].curve],
                span,
                point_spacing_mm: seam_spacing,
                depth_to_support_mm: workpiece.depth_to_support_mm,
                grid: grid.as_ref(),
                projector: Vec3::new(camera.baseline_mm, 0.0, 0.0),
            },
        );
        tracing::debug!(verdict = ?profile.verdict(), "{}", profile.describe());
        let judged = groove::judge(ctx.joint, &profile);
        if let Err(groove::GrooveError::LooksLikeTee { .. }) = judged {
            // What was seen, for a workpiece of several named unplanned.
            ctx.joint = Some(JointType::TFillet);
        }
        let joint = judged.map_err(|e| {
            let gate = if e.is_unknown() { quality::Gate::JointUnknown } else { quality::Gate::JointMismatch };
            PlanError { gate: Some(gate), ..PlanError::at(Stage::Groove, e) }
        })?;
        ctx.trace.record(|t| t.joint = Some(joint));
        admit(ctx, joint, Stage::Groove, &profile.describe())?;
        let depth = match (joint, ctx.request.groove_depth_mm, profile.depth_mm()) {
            (JointType::VButt, Some(given), _) => given,
            (JointType::VButt, None, Some(measured)) => measured,
            (JointType::VButt, None, None) => {
                return Err(PlanError::at(
                    Stage::Groove,
                    format!(
                        "no groove depth was given and none could be measured: no bevel face is seen down to the \
                         groove's root ({}); give the depth",
                        profile.describe()
                    ),
                ));
            }
            _ => 0.0,
        };
        if joint == JointType::VButt {
            profile.check_opening(depth).map_err(|e| PlanError::at(Stage::Groove, e))?;
        }
        (Some(profile), depth)
    } else {
        (None, 0.0)
    };
    let joint = ctx.joint()?;
    let joint_evidence = match &profile {
        Some(p) => format!("{layers}; between the edges: {}", p.verdict_sentence()),
        None => layers,
    };
    ctx.clock.lap(Stage::Groove)?;

    // 4.3: the weld per joint type (Eq. 32, 36), a lap weld at the root a
    // plate step below the upper edge (Eq. 38), planned only where both
    // plates were seen and, for a lap, where the root is in view.
    let (e1, e2) = (&fits[0].curve, &fits[1].curve);
    let middle = 0.5 * (e1.s_min.max(e2.s_min) + e1.s_max.min(e2.s_max));
    let lap_step = weld_equation::lap_step(e1, &plates[1].plane, &normal, middle);
    let weld = ctx.weld(e1, e2, &normal, groove_depth_mm, || {
        let step = lap_step.ok_or_else(|| {
            PlanError::at(Stage::WeldEquation, "the lower plate's plane runs along the plate normal: no lap step")
        })?;
        Ok(weld_equation::lap_root(e1, step, &normal))
    })?;
    // A V-groove's midline between its edges as its two bevels place them,
    // not as far as the strips walked onto each bevel.
    let bevels_offset = profile.as_ref().and_then(|p| p.bevel_midline_offset());
    let weld = match (ctx.joint, bevels_offset) {
        (Some(JointType::VButt), Some(offset)) => {
            tracing::debug!(?offset, "the V-groove's midline from its bevels");
            weld_equation::moved_towards(&weld, e1, e2, &offset)
        }
        _ => weld,
    };
    let extent = |k: usize| {
        boundaries[k]
            .extent(|s| axes.feature(&s.position))
            .ok_or_else(|| PlanError::at(Stage::WeldEquation, format!("weld edge {} has no boundary sample", k + 1)))
    };
    let mut extents = [extent(0)?, extent(1)?];
    // Each weld edge as its fit gives it, at the middle of its span.
    let fitted_edge = |k: usize| {
        let curve = &fits[k].curve;
        let middle = 0.5 * (curve.s_min + curve.s_max);
        edge_across(k, &curve.at(middle), &curve.tangent(middle))
    };
    if !cloud.is_organized() && degree == 1 {
        // Without a grid the strips read each end to a strip's width, and
        // miss or mistake the ends where the cloud's border cuts a plate:
        // the plate's last rows inside the fitted edge say where it ends.
        let spacing = seam_spacing;
        let refine = |k: usize| {
            let along = |p: &Vec3| axes.feature(p);
            let (edge, rms) = (fitted_edge(k), fits[k].rms_mm);
            boundary::rim_refined_extent(cloud, &plates[k].plane, &edge, &params, spacing, rms, along, extents[k])
        };
        let refined = [refine(0), refine(1)];
        tracing::debug!(strips = ?extents, rims = ?refined, "weld edge ends refined along the plates' rims");
        extents = refined;
    }
    if let Some(grid) = ctx.camera_grid() {
        // On the camera's grid the boundary samples stop a trimmed rim
        // short of the image border; where the plate runs on to it, so
        // does the edge.
        let reach = |k: usize| {
            let edge = fitted_edge(k);
            let spacing = spacing_at(&edge.point);
            boundary::reach_image_border(
                cloud,
                &grid,
                &fits[k].curve,
                &plates[k].plane,
                &-edge.outward,
                spacing,
                extents[k],
            )
        };
        let reached = [reach(0), reach(1)];
        tracing::debug!(samples = ?extents, borders = ?reached, "weld edge ends carried to the image border");
        extents = reached;
    }
    if ctx.camera_grid().is_none()
        && let Some(border) = ctx.view_border()
    {
        // Without a grid to carry each edge to the image's border, an edge
        // the border crosses obliquely stops short of it, the strips' last
        // one cut part way; where the plate's rim runs on to the border,
        // so does the edge.
        let spacing = seam_spacing;
        let along = |p: &Vec3| axes.feature(p);
        let near = view_border::END_EVIDENCE_SPACINGS * spacing;
        let reach = |k: usize| {
            let edge = fitted_edge(k);
            let rim =
                boundary::rim_points_at_ends(cloud, &plates[k].plane, &edge, &params, spacing, along, extents[k], near);
            border.edge_extent_at_border(&fits[k].curve, extents[k], &rim, along, spacing)
        };
        let reached = [reach(0), reach(1)];
        tracing::debug!(edges = ?extents, at_border = ?reached, "weld edge ends carried to the image's border");
        extents = reached;
    }
    let [(a0, a1), (b0, b1)] = extents;
    tracing::debug!(edge_1_mm = ?[a0, a1], edge_2_mm = ?[b0, b1], "weld edges seen along the seam");
    let (mut s0, mut s1) = (a0.max(b0), a1.min(b1));
    if layout == Layout::Lap {
        // The root lies a plate thickness below the edges the samples
        // saw; never plan a stretch of it the camera did not see (where
        // the image's border cuts the edges obliquely, the root leaves the
        // image before they do).
        (s0, s1) = ctx.clip_to_view(&weld, s0, s1);
    }
    // The visible joint: where both plates are seen beside the weld, their
    // members widened by the rim the plane criterion trimmed (for a lap,
    // where the root is also in view). The seam should span all of it.
    let trim = boundary::rim_trim_radii(cfg.plane_min_neighbour_ratio) * scale.radius_mm;
    // Each plate's edge may run either way along the seam's axis.
    let interval = |ends: [Vec3; 2]| {
        let [p, q] = ends.map(|e| axes.feature(&e));
        (p.min(q) - trim, p.max(q) + trim)
    };
    // Pieces of a plate in its plane beyond a narrow break (a streak cut
    // it) show the joint going on; beyond a wide one (a clamp), another
    // stretch of it.
    let max_break = boundary::JOINT_BREAK_SPACINGS * seam_spacing;
    let beside = [beside_a, beside_b].map(|(own, mates)| {
        let mates: Vec<(f64, f64)> = mates.into_iter().map(interval).collect();
        own.map(|ends| boundary::joined_extent(interval(ends), &mates, max_break))
    });
    let visible_joint = match beside {
        [Some((a0, a1)), Some((b0, b1))] => {
            let (v0, v1) = (a0.max(b0), a1.min(b1));
            Some(if layout == Layout::Lap { ctx.clip_to_view(&weld, v0, v1) } else { (v0, v1) })
        }
        _ => None,
    };
    // A lap's lower edge can run on along the foot of the upper plate's
    // side face past where the lower plate ends (the face's lowest pixels
    // lie in the lower plate's plane). Where the cloud, in view beside that
    // stretch, shows no lower plate inside its edge, the plate has ended,
    // and the seam ends where the plate was last seen.
    if layout == Layout::Lap
        && let (Some(grid), Some((v0, v1))) = (ctx.camera_grid(), visible_joint)
    {
        let unseen = |from: f64, to: f64| {
            let inward = -fitted_edge(1).outward;
            boundary::plate_unseen_beside(
                cloud,
                &grid,
                &fits[1].curve,
                &plates[1].plane,
                inward,
                seam_spacing,
                (from, to),
            )
        };
        let start = if s0 < v0 && unseen(v0, s0) { v0 } else { s0 };
        let end = if s1 > v1 && unseen(v1, s1) { v1 } else { s1 };
        if (start, end) != (s0, s1) {
            tracing::debug!(seam = ?(s0, s1), lower_plate_seen = ?(v0, v1), "the lap's seam ends where its lower plate ends");
            (s0, s1) = (start, end);
        }
    }
    ctx.trace.record(|t| t.weld = Some(TracedWeld { curve: weld.clone(), span: (s0, s1), normal }));
    if s1 - s0 <= 0.0 {
        return Err(PlanError::at(Stage::WeldEquation, "the two weld edges do not overlap along the seam"));
    }
    // Both edges must have been seen along the seam, not glimpsed here and
    // there: a gap the cloud cannot resolve still leaves the odd chance
    // hole, and a seam through those is a guess (the edge coverage gate).
    let edge_coverage = boundaries.each_ref().map(|b| boundary::coverage(b, |s| axes.feature(&s.position), s0, s1));
    tracing::debug!(coverage = ?edge_coverage, length_mm = s1 - s0, "weld edge coverage");
    let coverage = visible_joint.map(|(v0, v1)| {
        let visible_joint_mm = (v1 - v0).max(0.0);
        let spanned = (s1.min(v1) - s0.max(v0)).max(0.0);
        let joint = if visible_joint_mm > 0.0 { spanned / visible_joint_mm } else { 0.0 };
        let beyond_mm = (s1 - s0) - spanned;
        tracing::debug!(joint_coverage = joint, visible_joint_mm, beyond_mm, "seam coverage");
        SeamCoverage { edge: edge_coverage, joint, visible_joint_mm, beyond_mm }
    });
    // Where the plates go on side by side beyond the seam's ends, the
    // joint does too: an edge lost under a streak, not a plate's end.
    let followed_beyond = ctx.camera_grid().map(|grid| {
        let [before, after] = boundary::surfaces_beyond(
            cloud,
            &grid,
            [&fits[0].curve, &fits[1].curve],
            [&plates[0].plane, &plates[1].plane],
            [0, 1].map(|k| -fitted_edge(k).outward),
            seam_spacing,
            (s0, s1),
        );
        if layout == Layout::Lap {
            // A lap's joint goes on only as far as its root is in view.
            let (v0, v1) = ctx.clip_to_view(&weld, s0 - before, s1 + after);
            [(s0 - v0).max(0.0), (v1 - s1).max(0.0)]
        } else {
            [before, after]
        }
    });
    // Without a grid, the plates' members themselves (not widened by the
    // rim the criterion trimmed, which is an estimate) lying beside each
    // other beyond an end: an edge lost there while both plates go on.
    let members_beyond = || visible_joint.map(|(v0, v1)| [(s0 - v0 - trim).max(0.0), (v1 - trim - s1).max(0.0)]);
    let joint_beyond_ends_mm = followed_beyond.or_else(members_beyond);
    tracing::debug!(?joint_beyond_ends_mm, "plates seen beside the joint beyond the seam's ends");
    ctx.clock.lap(Stage::WeldEquation)?;

    // What the fits say about the seam, against the configured gates: a
    // seam that fails one is refused, unless the gate only warns.
    let quality = quality::measure(&quality::SeamFits {
        joint,
        fits: &fits,
        degree,
        planes: [&plates[0].plane, &plates[1].plane],
        span: (s0, s1),
        point_spacing_mm: seam_spacing,
        depth_to_support_mm: workpiece.depth_to_support_mm,
        lap_step_mm: lap_step.filter(|_| joint == JointType::Lap),
        groove: profile.as_ref(),
    });
    tracing::debug!(?quality, "seam quality");
    let evidence = quality::SeamEvidence {
        joint,
        quality: &quality,
        edge_fit_rms_mm: fits.each_ref().map(|f| f.rms_mm),
        edge_beyond: Some(beyond),
        edge_steps: Some(steps),
        edge_coverage: Some(edge_coverage),
        coverage: coverage.as_ref(),
        joint_beyond_ends_mm,
        length_mm: s1 - s0,
        given_groove_depth_mm: ctx.request.groove_depth_mm.filter(|_| joint == JointType::VButt),
        fits: quality::FittedEdges::WeldEdges,
    };
    let (warnings, refusals): (Vec<_>, Vec<_>) =
        quality::check(&evidence, &config.quality).into_iter().partition(|f| config.quality.warns_only(f.gate));
    ctx.trace.record(|t| (t.quality, t.warnings) = (Some(quality), warnings.clone()));
    for failure in &warnings {
        tracing::warn!(gate = %failure.gate, value = failure.value, limit = failure.limit, "{}", failure.message);
    }
    if let Some(first) = refusals.first() {
        return Err(PlanError::refused(first));
    }
    ctx.clock.lap(Stage::Quality)?;

    // 5.1 follows once every workpiece is planned: the seams' order
    // decides where each one's waypoints start.
    let assessment =
        SeamAssessment { joint_evidence: Some(joint_evidence), coverage, quality: Some(quality), warnings };
    Ok(PlannedWeld::new(joint, weld, (s0, s1), normal, EdgeFigures::of(&fits), assessment))
}
