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

use crate::config::Method;
use crate::geometry::Vec3;
use crate::joint::JointType;
use crate::rules::{self, Rule};

use super::background::{BackgroundError, CornerKind, Layout, PlaneCluster};
use super::context::{Context, MIN_CLUSTER_POINTS, PlannedWeld};
use super::neighbours::NeighbourSearch;
use super::plane_points::PlanePoints;
use super::{Plan, PlanError, PlanStats, Stage, StageTimings, Unplanned};
use super::{background, clustering, orientation, plane_points, quality, tee, web_face, workpieces};

/// How far, in degrees, a sampled local normal may lie from the most common
/// one and still be averaged into the dominant normal. Depth noise tilts
/// the normals of one plate by a degree or two; a bevel or side face lies
/// tens of degrees off, so five degrees keeps the plates and drops faces.
const DOMINANT_NORMAL_AGREEMENT_DEG: f64 = 5.0;

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

mod lap_edge;
mod plates;
mod root_weld;
mod standing_face;
mod tee_reading;

use plates::plan_plates;

/// Plans one frame by the robust method: the frame's stages up to its
/// plane clusters, then each workpiece's.
pub(super) fn plan(mut ctx: Context) -> Result<Plan, PlanError> {
    let search = index_neighbours(&mut ctx)?;
    let dominant = find_dominant_normal(&mut ctx, &search)?;
    let mut plane = find_plane_points(&mut ctx, &search, dominant)?;
    let (labels, planes) = cluster_planes(&mut ctx, &search, &mut plane)?;
    let groups = group_workpieces(&ctx, planes, dominant);
    let front = Front { search: &search, plane: &plane, dominant };
    plan_workpieces(ctx, &front, &labels, groups)
}

/// The neighbour index at the frame's scale: the camera's for its raw
/// frames, else measured from the cloud's own spacing.
fn index_neighbours<'a>(ctx: &mut Context<'a>) -> Result<NeighbourSearch<'a>, PlanError> {
    let camera = &ctx.config.camera;
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
    Ok(search)
}

/// The workpiece's dominant normal (robust method only).
fn find_dominant_normal(ctx: &mut Context, search: &NeighbourSearch) -> Result<Vec3, PlanError> {
    let (cloud, camera) = (ctx.cloud, &ctx.config.camera);
    // Plates, table and fixture lie parallel: one normal describes them.
    let dominant =
        orientation::dominant_normal(cloud, search, camera.fx(), DOMINANT_NORMAL_AGREEMENT_DEG).ok_or_else(|| {
            PlanError::by(&rules::orientation::NO_DOMINANT_NORMAL, "no surface normal could be estimated")
        })?;
    ctx.trace.record(|t| t.dominant_normal = Some(dominant));
    ctx.clock.lap(Stage::Orientation)?;
    Ok(dominant)
}

/// 3.2: the plane points.
fn find_plane_points(ctx: &mut Context, search: &NeighbourSearch, dominant: Vec3) -> Result<PlanePoints, PlanError> {
    let cfg = &ctx.config.pipeline;
    // 3.2: plane points against the count of a plane tilted to the
    // dominant normal (Eq. 6 and 14, foreshortened), facing it.
    let plane = plane_points::robust_criterion(
        search,
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
        return Err(PlanError::by(&rules::plane_points::NO_PLANE_POINT, "no point passed the plane point criterion"));
    }

    Ok(plane)
}

/// 3.3: the plane points clustered, and the clusters large enough to be
/// plates as planes; the frame's cluster labels, which the edge stage
/// reads. The plane points' mask is freed here.
fn cluster_planes(
    ctx: &mut Context,
    search: &NeighbourSearch,
    plane: &mut PlanePoints,
) -> Result<(Vec<u32>, Vec<PlaneCluster>), PlanError> {
    let cfg = &ctx.config.pipeline;
    let (cloud, scale) = (ctx.cloud, ctx.scale);
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
    Ok((clusters.labels, planes))
}

/// Several workpieces: the clusters grouped so that plates of different
/// workpieces are never paired across the table; a frame of one is one
/// group holding every cluster.
fn group_workpieces(ctx: &Context, planes: Vec<PlaneCluster>, dominant: Vec3) -> Vec<workpieces::WorkpieceGroup> {
    let cfg = &ctx.config.pipeline;
    let (cloud, camera, scale) = (ctx.cloud, &ctx.config.camera, ctx.scale);
    let middle = planes.iter().fold(Vec3::zeros(), |m, c| m + c.centroid) / planes.len().max(1) as f64;
    let grouping = workpieces::GroupSettings {
        normal: dominant,
        max_tilt_deg: cfg.plane_max_normal_angle_deg,
        coplanar_tolerance_mm: cfg.coplanar_tolerance_mm,
        point_spacing_mm: scale.spacing_at(camera, &middle),
    };
    workpieces::group(cloud, planes, &grouping)
}

/// Each workpiece's welds, or why not, and the frame's plan: one
/// workpiece in the frame's own context, several side by side.
fn plan_workpieces(
    mut ctx: Context,
    front: &Front,
    labels: &[u32],
    mut groups: Vec<workpieces::WorkpieceGroup>,
) -> Result<Plan, PlanError> {
    if groups.len() == 1 {
        let planes = groups.pop().map(|g| g.planes).unwrap_or_default();
        let (welds, unplanned) = plan_workpiece(&mut ctx, front, labels, planes).map_err(|r| r.reason)?;
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
            let result = plan_workpiece(&mut piece, front, labels, group.planes);
            if let Err(refused) = &result {
                // The refusing stage's own work, up to the refusal.
                // The refusal stands; the time limit is the plan's to check.
                let _ = piece.clock.lap(refused.reason.stage);
            }
            Outcome { result, near_camera: group.near_camera, stats: piece.stats, timings: piece.clock.into_timings() }
        })
        .collect();
    ctx.clock.lap_beside(outcomes.iter().map(|o| &o.timings));
    if let Some(first) = outcomes.first() {
        ctx.stats = first.stats.clone();
    }
    // A workpiece stopped by the time limit says nothing about the frame:
    // the plan as a whole ran out of time.
    if let Some(stopped) =
        outcomes.iter().find_map(|o| o.result.as_ref().err().map(|r| &r.reason).filter(|e| e.out_of_time))
    {
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
            Err(Refused { reason, seen }) => {
                tracing::info!(workpiece = k + 1, near_camera = ?outcome.near_camera.as_slice(), "workpiece not planned: {reason}");
                // The joint requested is no workpiece's joint when it
                // does not match; otherwise the one seen.
                let mismatch = reason.gate == Some(quality::Gate::JointMismatch);
                let joint = seen.filter(|j| !(mismatch && ctx.request.joint.given() == Some(*j)));
                unplanned.push(Unplanned { joint, near_camera: Some(outcome.near_camera), reason });
            }
        }
    }
    ctx.finish_several(Method::Robust, welds, unplanned)
}

/// A workpiece's welds, and the joints seen in it but not planned.
type Welds = (Vec<PlannedWeld>, Vec<Unplanned>);

/// What planning one workpiece of several gave, and what its context
/// recorded on the way.
struct Outcome {
    result: Result<Welds, Refused>,
    near_camera: Vec3,
    stats: PlanStats,
    timings: StageTimings,
}

/// A workpiece refused: why, and the joint it was seen to be by then (the
/// one requested, or the one its layers or its groove showed), which names
/// it among a frame's unplanned.
struct Refused {
    reason: PlanError,
    seen: Option<JointType>,
}

/// A stage's refusal, of a workpiece seen to be `joint` so far.
trait SeenAs<T> {
    fn seen_as(self, joint: Option<JointType>) -> Result<T, Refused>;
}

impl<T> SeenAs<T> for Result<T, PlanError> {
    fn seen_as(self, seen: Option<JointType>) -> Result<T, Refused> {
        self.map_err(|reason| Refused { reason, seen })
    }
}

/// Refuses a workpiece found to be `joint` when the request does not admit
/// it (a set of types, [`crate::joint::RequestedJoint::OneOf`]), saying what was seen:
/// `seen`, the evidence that decided the type, by `rule` (the plates'
/// layers, [`rules::background::JOINT_NOT_REQUESTED`], or the groove,
/// [`rules::groove::BUTT_NOT_REQUESTED`]). The refusal names `joint` as
/// what was seen, for the workpiece's entry among the unplanned.
fn admit(ctx: &Context, joint: JointType, rule: &'static Rule, seen: &str) -> Result<(), Refused> {
    if ctx.request.joint.admits(joint) {
        return Ok(());
    }
    Err(joint_mismatch(ctx, &format!("a {joint} joint"), rule, seen)).seen_as(Some(joint))
}

/// The refusal by `rule` of a workpiece that is `what` (found from
/// `seen`) under a request that does not admit it.
fn joint_mismatch(ctx: &Context, what: &str, rule: &'static Rule, seen: &str) -> PlanError {
    let message = format!("{seen}: this looks like {what}, not one of the joints requested ({})", ctx.request.joint);
    PlanError::by(rule, message)
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
/// edge stage reads for this workpiece's plates. The joint passes from
/// stage to stage: the one requested, then the one the layers show, then
/// (for a butt pair) the one its groove shows. Under `auto`, a workpiece
/// every reading refused is read once more as a tee's request would read
/// it, for what that refusal says ([`tee_reading`]).
fn plan_workpiece(
    ctx: &mut Context,
    front: &Front,
    labels: &[u32],
    planes: Vec<PlaneCluster>,
) -> Result<Welds, Refused> {
    if !tee_reading::may_weigh(ctx) {
        return read_workpiece(ctx, front, labels, planes);
    }
    let kept = planes.clone();
    match read_workpiece(ctx, front, labels, planes) {
        Err(refused) if tee_reading::worth_weighing(&refused) => {
            Err(tee_reading::weigh(ctx, refused, |as_tee| read_workpiece(as_tee, front, labels, kept)))
        }
        read => read,
    }
}

/// [`plan_workpiece`] under the request as asked.
fn read_workpiece(
    ctx: &mut Context,
    front: &Front,
    labels: &[u32],
    planes: Vec<PlaneCluster>,
) -> Result<Welds, Refused> {
    let cfg = &ctx.config.pipeline;
    let requested = ctx.request.joint.given();
    let selection = background::Selection {
        joint: requested,
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
            ctx.clock.lap(Stage::Background).seen_as(requested)?;
            let layers = format!("an inside corner: {}", corner.what);
            let tee = tee::SeenTee::of(&workpiece, tee::Flange::OneSide);
            return tee::plan(ctx, tee, layers).seen_as(Some(JointType::TFillet));
        }
        let refusal = corner.refusal();
        return Err(PlanError::by(refusal.rule(), refusal)).seen_as(requested);
    }
    // A tee whose web's top is not found may have it out of view (a crop
    // round its root): its face standing on the nearest layer of planes,
    // planned under `t_fillet`; under `auto`, when too few planes are
    // seen for any other joint, planned where it stands taller than a
    // lap's upper plate.
    // Under any other request, a lone plane is refused with what is seen
    // beside it.
    let lone_plane = planes.iter().filter(|c| selection.faces_camera(c)).count() < 2;
    let face_may_stand = match selection.joint {
        Some(JointType::TFillet) => true,
        None => lone_plane,
        Some(_) => false,
    };
    // Under `auto` with planes enough for a butt pair or a lap, a face
    // standing on the nearest layer is the other layout they allow: it is
    // weighed against the layers' reading once that reading is refused
    // ([`standing_face::instead_of_layers`]).
    let face_beside_layers = selection.joint.is_none() && !lone_plane && ctx.request.joint.admits(JointType::TFillet);
    let nearest = (face_may_stand || lone_plane || face_beside_layers)
        .then(|| background::nearest_layer(&planes, &selection))
        .flatten();
    let (selected, standing_on) = match (background::robust_select(planes, &selection, ctx.cloud.points()), nearest) {
        (Err(e @ (BackgroundError::NoWeb { .. } | BackgroundError::TooFewPlanes { .. })), Some(flange))
            if face_may_stand =>
        {
            return plan_topless_tee(ctx, flange, e);
        }
        (Err(e @ BackgroundError::TooFewPlanes { .. }), Some(lone)) => {
            return Err(in_view_refusal(ctx, &lone, &e)).seen_as(requested);
        }
        (selected, nearest) => (selected, nearest.filter(|_| face_beside_layers)),
    };
    let background::Selected { workpiece, layout, evidence: layers, web_by_faces } =
        selected.map_err(|e| PlanError::by(e.rule(), &e)).seen_as(requested)?;
    if layout == Layout::Lap {
        ctx.trace.record(|t| t.joint = Some(JointType::Lap));
    }
    // A set of types requested: the layers decide a lap or a tee; a butt
    // pair is one of the two butt joints, which the groove probe tells.
    let joint = match layout {
        Layout::Lap => Some(JointType::Lap),
        Layout::Tee => Some(JointType::TFillet),
        Layout::Butt => requested,
    };
    match layout {
        Layout::Lap => admit(ctx, JointType::Lap, &rules::background::JOINT_NOT_REQUESTED, &layers)?,
        Layout::Tee => admit(ctx, JointType::TFillet, &rules::background::JOINT_NOT_REQUESTED, &layers)?,
        Layout::Butt => {
            if ![JointType::VButt, JointType::IButt].into_iter().any(|j| ctx.request.joint.admits(j)) {
                let mismatch = joint_mismatch(ctx, "a butt joint", &rules::background::JOINT_NOT_REQUESTED, &layers);
                return Err(mismatch).seen_as(joint);
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
    ctx.clock.lap(Stage::Background).seen_as(joint)?;
    // One path per layout: each returns the workpiece's welds.
    match layout {
        Layout::Butt | Layout::Lap => {
            let read = plan_plates(ctx, front, labels, workpiece, layout, layers, joint);
            match (read, standing_on) {
                (Err(refused), Some(flange)) if !refused.reason.out_of_time => {
                    standing_face::instead_of_layers(ctx, flange, layout, refused)
                }
                (read, _) => read.map(|weld| (vec![weld], Vec::new())),
            }
        }
        // A web on its flange: its fillet roots, not two plates' edges.
        Layout::Tee => {
            let tee = tee::SeenTee { every_side: web_by_faces, ..tee::SeenTee::of(&workpiece, tee::Flange::BothSides) };
            tee::plan(ctx, tee, layers).seen_as(joint)
        }
    }
}

/// A tee's root from its web's one face seen standing on `flange` (the
/// nearest layer of planes), the web's top out of view; refused with
/// `not_found` (why no web's top was found) and why no face was either.
/// Under `auto` (a lone plane in view) the faces are planned as beside a
/// refused reading of the layers, where they stand taller than a lap's
/// upper plate ([`standing_face::on_lone_plane`]); a request that admits
/// no tee has the largest named, not planned. With more planes in view
/// they are weighed against the layers' reading instead
/// ([`standing_face::instead_of_layers`]).
fn plan_topless_tee(
    ctx: &mut Context,
    flange: Vec<PlaneCluster>,
    not_found: BackgroundError,
) -> Result<Welds, Refused> {
    let requested = ctx.request.joint.given();
    let pieces: Vec<&PlaneCluster> = flange.iter().collect();
    let search = face_search(ctx, &flange);
    let fillet_asked = ctx.request.joint.given() == Some(JointType::TFillet);
    // Under `auto`, two faces meeting in a valley no web makes with its
    // flange (a groove's flanks, their plate tops out of view) are named,
    // and no tee is suggested.
    if !fillet_asked && web_face::valley(ctx.cloud, &pieces, &search).is_some_and(|v| v.is_groove()) {
        return Err(in_view_refusal(ctx, &flange, &not_found)).seen_as(requested);
    }
    // Every face of the member standing on the flange is a web's (a
    // block shows two): under `t_fillet` each is planned; under `auto`
    // each standing taller than a lap's upper plate, where a tee may be
    // planned at all; else the largest is named.
    let tee_admitted = ctx.request.joint.admits(JointType::TFillet);
    let faces = if tee_admitted {
        web_face::find_all(ctx.cloud, &pieces, &search)
    } else {
        web_face::find(ctx.cloud, &pieces, &search).map(|face| vec![face])
    };
    let faces = faces.map_err(|why| {
        // Under `auto` the search was a guess at a cropped tee: its failure
        // says nothing about the joint the cloud holds.
        if !fillet_asked {
            return PlanError::by(not_found.rule(), &not_found);
        }
        // Under `t_fillet` the face search is the last reading of the
        // frame: its rule refused, in the class the top's search gave.
        let reason = format!("{not_found}; nor does a web's side face stand on the nearest plane: {why}");
        PlanError { gate: not_found.rule().gate, ..PlanError::by(why.rule(), reason) }
    });
    let faces = faces.seen_as(requested)?;
    if !fillet_asked && tee_admitted {
        ctx.clock.lap(Stage::Background).seen_as(requested)?;
        return standing_face::on_lone_plane(ctx, &flange, faces, &not_found);
    }
    let layers = standing_face::face_evidence(&faces[0], &flange);
    tracing::debug!("{layers}");
    if !fillet_asked {
        let reason = format!(
            "{not_found}; {layers}: this may be a tee's web (or an inside corner's standing plate) cropped below its \
             top; request t_fillet to plan its root"
        );
        return Err(PlanError::by(&rules::background::WEB_FACE_WITHOUT_TOP, reason)).seen_as(requested);
    }
    ctx.clock.lap(Stage::Background).seen_as(requested)?;
    standing_face::plan_faces(ctx, &faces, &flange).seen_as(Some(JointType::TFillet))
}

/// The settings of the search for what stands on `flange` (the nearest
/// layer of planes).
fn face_search(ctx: &Context, flange: &[PlaneCluster]) -> web_face::FaceSearch {
    let cfg = &ctx.config.pipeline;
    web_face::FaceSearch {
        point_spacing_mm: flange.first().map_or(ctx.scale.radius_mm, |c| ctx.spacing_at(&c.centroid)),
        on_plane_mm: cfg.on_plane_tolerance_mm,
        web_height_max_mm: cfg.tee_web_height_max_mm,
        trim_sigma: cfg.fit_trim_sigma,
    }
}

/// The refusal `not_found` (too few workpiece planes, or no web's top)
/// with what is in view beside the lone plane `flange`: the valley it
/// makes with the face rising over it, where one does ([`web_face::valley`]).
fn in_view_refusal(ctx: &Context, flange: &[PlaneCluster], not_found: &BackgroundError) -> PlanError {
    let pieces: Vec<&PlaneCluster> = flange.iter().collect();
    match web_face::valley(ctx.cloud, &pieces, &face_search(ctx, flange)) {
        Some(valley) => PlanError::by(not_found.rule(), format!("{not_found}: {}", valley.describe())),
        None => PlanError::by(not_found.rule(), not_found),
    }
}
