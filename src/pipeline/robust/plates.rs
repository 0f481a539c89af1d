//! The robust method's path for two plates side by side or one on the
//! other (a butt joint or a lap): from the plates' edge points to a weld
//! through the quality gates, section 3.4 to 4.3 in the paper's order.
//! [`plan_plates`] reads as that order: each step takes what it needs and
//! returns what it found.

use crate::geometry::Vec3;
use crate::joint::JointType;

use super::super::along_seam;
use super::super::background::{Layout, PlaneCluster, Workpiece};
use super::super::boundary::{self, Boundary, BoundaryParams, CoarseEdge};
use super::super::context::{self, Context, EdgeFigures, PlannedWeld};
use super::super::edge_points::{EdgeCriterion, FullCount};
use super::super::groove::{self, GrooveProfile, RootLine};
use super::super::quality::{self, GateFailure, SeamQuality};
use super::super::ransac::{self, EdgeLine};
use super::super::refit::{self, CurveFit, SeamAxes, SeamCurve};
use super::super::straightness::{RootBend, Samples, bend_of};
use super::super::trace::TracedWeld;
use super::super::{PlanError, SeamAssessment, SeamCoverage, Stage, weld_edges, weld_equation};
use super::lap_edge::check_lap_edge;
use super::root_weld;
use super::{Front, Refused, SeenAs, admit};
use crate::rules;

/// The shortest vector normalised as a direction: below it the sum of two
/// plate normals is taken as no direction at all (they point apart).
const MIN_DIRECTION_NORM: f64 = 1e-9;

/// The shortest run of a weld edge's samples, as a share of them, that a
/// step between two lines is read across: shorter runs are a tack weld's
/// or a spatter's, and the share of samples beyond the line judges them.
pub(super) const MIN_STEP_RUN_SHARE: f64 = 0.1;

/// A butt joint's or a lap's weld from its two plates: edge points through
/// the quality gates (3.4 to 4.3). `joint` is the joint known from the
/// layers: a lap, or a butt joint's type when the request names it; the
/// groove stage decides it for a butt pair under `auto`.
pub(super) fn plan_plates(
    ctx: &mut Context,
    front: &Front,
    labels: &[u32],
    workpiece: Workpiece,
    layout: Layout,
    layers: String,
    joint: Option<JointType>,
) -> Result<PlannedWeld, Refused> {
    ctx.check_groove_depth(joint, &workpiece).seen_as(joint)?;
    let edges = find_edge_points(ctx, front, labels, &workpiece).seen_as(joint)?;
    let normal = plates_normal(&workpiece, front.dominant);
    let (edge_points, lines) = segment_edge_lines(ctx, &edges).seen_as(joint)?;
    let pick = pick_weld_edges(ctx, &workpiece, layout, &edge_points, &lines, normal).seen_as(joint)?;
    let (refitted, beside) = refit_weld_edges(ctx, &workpiece, layout, &lines, pick, normal).seen_as(joint)?;
    let groove = judge_groove(ctx, &workpiece, layout, &refitted, layers, joint)?;
    let decided = Some(groove.joint);
    let placed = place_weld(ctx, &workpiece, layout, &refitted, beside.clone(), (&groove, None), normal);
    let checked = placed.and_then(|p| Ok((check_gates(ctx, &workpiece, &refitted, &groove, &p, None)?, p)));
    // Ragged top edges over clean flanks: the weld on the groove's root.
    // Along every stretch either edge was seen: a ragged edge's fit may
    // hold one run of it only.
    let [c0, c1] = refitted.fits.each_ref().map(|f| &f.curve);
    let either = (c0.s_min.min(c1.s_min), c0.s_max.max(c1.s_max));
    let reprobe = || probe_groove(ctx, &workpiece, &refitted, either);
    let root = root_weld::wanted(&checked, groove.joint, reprobe);
    let ((quality, warnings), placed) = match root {
        Some(root) => {
            let placed = place_weld(ctx, &workpiece, layout, &refitted, beside, (&groove, Some(&root)), normal);
            placed.and_then(|p| Ok((check_gates(ctx, &workpiece, &refitted, &groove, &p, Some(&root))?, p)))
        }
        None => checked,
    }
    .seen_as(decided)?;
    let (axes, boundaries, spacing) = (refitted.axes, &refitted.boundaries, refitted.seam_spacing);
    let along = along_seam::Evidence::of_plates(ctx.config, &workpiece, groove.joint, axes, boundaries, spacing);
    let PlacedWeld { weld, span: (s0, s1), coverage, .. } = placed;
    let (joint, joint_evidence, fits) = (groove.joint, groove.evidence, refitted.fits);
    // 5.1 follows once every workpiece is planned: the seams' order
    // decides where each one's waypoints start.
    let assessment =
        SeamAssessment { joint_evidence: Some(joint_evidence), coverage, quality: Some(quality), warnings };
    Ok(PlannedWeld::new(joint, weld, (s0, s1), normal, EdgeFigures::of(&fits), assessment).with_along(along))
}

/// 3.4.1: each plate's edge points.
fn find_edge_points(
    ctx: &mut Context,
    front: &Front,
    labels: &[u32],
    workpiece: &Workpiece,
) -> Result<[Vec<u32>; 2], PlanError> {
    let cfg = &ctx.config.pipeline;
    let (search, plane) = (front.search, front.plane);
    // 3.4.1: edge points, at most `pipeline.edge_max_neighbour_ratio` of a
    // tilted plane's count (Eq. 15's rule).
    let criterion = EdgeCriterion { full: FullCount::Plane, ratio: cfg.edge_max_neighbour_ratio };
    let edges = context::plate_edge_points(labels, workpiece, search, plane, &criterion);
    ctx.stats.edge_points = [edges[0].len(), edges[1].len()];
    ctx.trace.record(|t| t.edge_points = edges.clone());
    ctx.clock.lap(Stage::EdgePoints)?;

    Ok(edges)
}

/// The normal of the plates' own planes, or `dominant` where they point
/// apart.
fn plates_normal(workpiece: &Workpiece, dominant: Vec3) -> Vec3 {
    // The plates' least-squares planes fix the normal far better than the
    // sampled dominant one: the groove depth (Eq. 32) and the lap step are
    // shifted along it.
    let [normal_a, normal_b] = workpiece.plates.each_ref().map(|p| p.plane.normal);
    (normal_a + normal_b).try_normalize(MIN_DIRECTION_NORM).unwrap_or(dominant)
}

/// Each plate's edge points, and the lines RANSAC found among them.
type EdgeLines = ([Vec<Vec3>; 2], [Vec<EdgeLine>; 2]);

/// 3.4.2: each plate's edge points as points, and the lines RANSAC finds
/// among them.
fn segment_edge_lines(ctx: &mut Context, edges: &[Vec<u32>; 2]) -> Result<EdgeLines, PlanError> {
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

    Ok((edge_points, lines))
}

/// 4.1: the weld edge among each plate's lines, checked against a lap's
/// upper plate's other edges.
fn pick_weld_edges(
    ctx: &mut Context,
    workpiece: &Workpiece,
    layout: Layout,
    edge_points: &[Vec<Vec3>; 2],
    lines: &[Vec<EdgeLine>; 2],
    normal: Vec3,
) -> Result<[usize; 2], PlanError> {
    let cfg = &ctx.config.pipeline;
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
    .map_err(|e| PlanError::by(e.rule(), e))?;
    ctx.trace.record(|t| t.pick_lines(|l| l.rank == pick[l.plate]));
    if layout == Layout::Lap {
        check_lap_edge(ctx, workpiece, &lines[0], &edge_points[0], pick[0])?;
    }
    ctx.clock.lap(Stage::WeldEdges)?;

    Ok(pick)
}

/// What the weld edges' refit found (4.2): the boundary samples, the axes
/// and the fits, and where the samples leave the fitted lines.
struct Refitted {
    params: BoundaryParams,
    boundaries: [Boundary; 2],
    axes: SeamAxes,
    degree: usize,
    seam_spacing: f64,
    fits: [CurveFit; 2],
    beyond: [refit::Beyond; 2],
    steps: [Option<refit::Step>; 2],
    /// How far the edges that place the weld bend from their fitted
    /// curves, station by station (the worse edge).
    bend: Option<RootBend>,
}

/// Where each plate is seen beside its weld edge: its own points' ends
/// along the edge, and those of the pieces of its layer.
type Beside = (Option<[Vec3; 2]>, Vec<[Vec3; 2]>);

/// The edge through `point` along `direction`, laid in plate k's plane,
/// its outward side towards the other plate.
fn edge_in_plate(plates: &[PlaneCluster; 2], k: usize, point: &Vec3, direction: &Vec3) -> CoarseEdge {
    let centroids = plates.each_ref().map(|p| p.centroid);
    let plane = &plates[k].plane;
    let direction = (direction - plane.normal * direction.dot(&plane.normal)).normalize();
    let mut outward = plane.normal.cross(&direction);
    if outward.dot(&(centroids[1 - k] - point)) < 0.0 {
        outward = -outward;
    }
    CoarseEdge { point: plane.project(point), direction, outward }
}

/// 4.2: each weld edge resampled along its plate's boundary and refitted.
fn refit_weld_edges(
    ctx: &mut Context,
    workpiece: &Workpiece,
    layout: Layout,
    lines: &[Vec<EdgeLine>; 2],
    pick: [usize; 2],
    normal: Vec3,
) -> Result<(Refitted, [Beside; 2]), PlanError> {
    let config = ctx.config;
    let cfg = &config.pipeline;
    let camera = &config.camera;
    let scale = ctx.scale;
    let cloud = ctx.cloud;
    let plates = &workpiece.plates;
    let centroids = plates.each_ref().map(|p| p.centroid);
    // The point spacing near `p`: measured, or the camera's pixel footprint.
    // 4.2: each weld edge resampled along its plate's boundary, then
    // refitted along the samples' principal direction with outliers
    // trimmed (Eq. 17 to 25).
    let spacing_at = |p: &Vec3| scale.spacing_at(camera, p);
    let params = BoundaryParams { band_mm: scale.band(cfg.boundary_band_mm), on_plane_mm: cfg.on_plane_tolerance_mm };
    // The edge through `point` along `direction`, laid in plate k's plane,
    // its outward side towards the other plate.
    let edge_across = |k: usize, point: &Vec3, direction: &Vec3| edge_in_plate(plates, k, point, direction);
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
    let axes = seam_axes(&samples, &normal)?;
    let degree = cfg.fit_degree as usize;
    let seam_spacing = spacing_at(&axes.origin);
    let fit_edge = |k: usize| {
        refit::fit_trimmed(&samples[k], &axes, degree, cfg.fit_trim_sigma, seam_spacing).ok_or_else(|| {
            PlanError::by(
                &rules::refit::EDGE_TOO_FEW_POINTS_TO_FIT,
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

    // Whether the edges that place the weld follow their fitted curves
    // along the seam or bend off them (a plate bent along the joint, a
    // curved member): their samples within the trimming's limit, station
    // by station, across the seam and along the normal.
    let bend = [0, 1].into_iter().filter(|&k| places_weld(k)).fold(None, |worst, k| {
        let curve = &fits[k].curve;
        let kept: Vec<(f64, Vec3)> = samples[k]
            .iter()
            .filter(|p| curve.residual(p) <= limits_mm[k])
            .map(|p| {
                let s = axes.feature(p);
                (s, p - curve.at(s))
            })
            .collect();
        let evidence = if k == 0 { "weld edge 1" } else { "weld edge 2" };
        let across =
            bend_of(kept.iter().map(|(s, d)| (*s, d.dot(&axes.a))), Samples::PerStation, seam_spacing, evidence);
        let normal =
            bend_of(kept.iter().map(|(s, d)| (*s, d.dot(&axes.b))), Samples::PerStation, seam_spacing, evidence);
        RootBend::worse(worst, RootBend::worse(across, normal))
    });
    tracing::debug!(?bend, "weld edges' bend");
    let refitted = Refitted { params, boundaries, axes, degree, seam_spacing, fits, beyond, steps, bend };
    Ok((refitted, [beside_a, beside_b]))
}

/// What lies between a butt joint's edges, and the joint decided.
struct Groove {
    profile: Option<GrooveProfile>,
    depth_mm: f64,
    joint: JointType,
    /// What makes it this joint: the plates' layers and the groove.
    evidence: String,
}

/// The groove stage: a butt joint's groove probed and judged, and the joint
/// decided: `joint`, the one known so far, or the one the groove shows.
fn judge_groove(
    ctx: &mut Context,
    workpiece: &Workpiece,
    layout: Layout,
    refitted: &Refitted,
    layers: String,
    joint: Option<JointType>,
) -> Result<Groove, Refused> {
    let fits = &refitted.fits;
    // Between a butt joint's edges: a V-groove's bevels (and how deep it
    // is), a square gap, or a plate standing there. It decides V or I for
    // `auto`, checks the type requested, and measures the depth of Eq. 32.
    let (profile, groove_depth_mm, joint) = if layout == Layout::Butt {
        let span = (fits[0].curve.s_min.max(fits[1].curve.s_min), fits[0].curve.s_max.min(fits[1].curve.s_max));
        let profile = probe_groove(ctx, workpiece, refitted, span);
        tracing::debug!(verdict = ?profile.verdict(), "{}", profile.describe());
        let judged = groove::judge(joint, &profile);
        // What was seen, for a workpiece of several named unplanned.
        let seen = match &judged {
            Err(groove::GrooveError::LooksLikeTee { .. }) => Some(JointType::TFillet),
            _ => joint,
        };
        let joint = judged.map_err(|e| PlanError::by(e.rule(), e)).seen_as(seen)?;
        ctx.trace.record(|t| t.joint = Some(joint));
        admit(ctx, joint, &rules::groove::BUTT_NOT_REQUESTED, &profile.describe())?;
        let depth = match (joint, ctx.request.groove_depth_mm, profile.depth_mm()) {
            (JointType::VButt, Some(given), _) => given,
            (JointType::VButt, None, Some(measured)) => measured,
            (JointType::VButt, None, None) => {
                return Err(PlanError::by(
                    &rules::groove::GROOVE_DEPTH_UNMEASURED,
                    format!(
                        "no groove depth was given and none could be measured: no bevel face is seen down to the \
                         groove's root ({}); give the depth",
                        profile.describe()
                    ),
                ))
                .seen_as(Some(joint));
            }
            _ => 0.0,
        };
        if joint == JointType::VButt {
            profile.check_opening(depth).map_err(|e| PlanError::by(e.rule(), e)).seen_as(Some(joint))?;
        }
        (Some(profile), depth, Some(joint))
    } else {
        (None, 0.0, joint)
    };
    let joint = context::decided(joint).seen_as(joint)?;
    let joint_evidence = match &profile {
        Some(p) => format!("{layers}; between the edges: {}", p.verdict_sentence()),
        None => layers,
    };
    ctx.clock.lap(Stage::Groove).seen_as(Some(joint))?;

    Ok(Groove { profile, depth_mm: groove_depth_mm, joint, evidence: joint_evidence })
}

/// The groove between the weld edges probed along `span` of the seam's
/// feature axis.
fn probe_groove(ctx: &Context, workpiece: &Workpiece, refitted: &Refitted, span: (f64, f64)) -> GrooveProfile {
    let fits = &refitted.fits;
    groove::probe(
        ctx.cloud,
        &groove::ProbeSetting {
            edges: [&fits[0].curve, &fits[1].curve],
            span,
            point_spacing_mm: refitted.seam_spacing,
            depth_to_support_mm: workpiece.depth_to_support_mm,
            floor_between_plates: workpiece.support_between_plates,
            grid: ctx.camera_grid().as_ref(),
            projector: Vec3::new(ctx.config.camera.baseline_mm, 0.0, 0.0),
        },
    )
}

/// The weld placed (4.3), its span along the seam, and how much of the
/// joint it covers.
struct PlacedWeld {
    weld: SeamCurve,
    span: (f64, f64),
    lap_step: Option<f64>,
    edge_coverage: [f64; 2],
    coverage: Option<SeamCoverage>,
    joint_beyond_ends_mm: Option<[f64; 2]>,
}

/// 4.3: the weld per joint type over the stretch both edges were seen.
fn place_weld(
    ctx: &mut Context,
    workpiece: &Workpiece,
    layout: Layout,
    refitted: &Refitted,
    [beside_a, beside_b]: [Beside; 2],
    (groove, root): (&Groove, Option<&RootLine>),
    normal: Vec3,
) -> Result<PlacedWeld, PlanError> {
    let config = ctx.config;
    let cfg = &config.pipeline;
    let scale = ctx.scale;
    let cloud = ctx.cloud;
    let plates = &workpiece.plates;
    let edge_across = |k: usize, point: &Vec3, direction: &Vec3| edge_in_plate(plates, k, point, direction);
    let Refitted { boundaries, axes, seam_spacing, fits, .. } = refitted;
    let seam_spacing = *seam_spacing;
    let (profile, groove_depth_mm) = (&groove.profile, groove.depth_mm);
    // 4.3: the weld per joint type (Eq. 32, 36), a lap weld at the root a
    // plate step below the upper edge (Eq. 38), planned only where both
    // plates were seen and, for a lap, where the root is in view.
    let (e1, e2) = (&fits[0].curve, &fits[1].curve);
    let middle = 0.5 * (e1.s_min.max(e2.s_min) + e1.s_max.min(e2.s_max));
    let lap_step = weld_equation::lap_step(e1, &plates[1].plane, &normal, middle);
    let weld = context::weld(groove.joint, e1, e2, &normal, groove_depth_mm, || lap_root(e1, lap_step, &normal))?;
    // A V-groove's midline between its edges as its two bevels place them,
    // not as far as the strips walked onto each bevel.
    let bevels_offset = match root {
        Some(root) => Some(root.offset),
        None => profile.as_ref().and_then(|p| p.bevel_midline_offset()),
    };
    let weld = match (groove.joint, bevels_offset) {
        (JointType::VButt, Some(offset)) => {
            tracing::debug!(
                rule = rules::weld_equation::WELD_ON_BEVEL_MIDLINE.id,
                ?offset,
                "the V-groove's midline from its bevels"
            );
            weld_equation::moved_towards(&weld, e1, e2, &offset)
        }
        _ => weld,
    };
    let extent = |k: usize| {
        boundaries[k].extent(|s| axes.feature(&s.position)).ok_or_else(|| {
            PlanError::by(
                &rules::refit::EDGE_TOO_FEW_POINTS_TO_FIT,
                format!("weld edge {} has no boundary sample", k + 1),
            )
        })
    };
    let extents = match root {
        // Where both flanks show the root, whatever the top edges did.
        Some(root) => [root.span; 2],
        None => [extent(0)?, extent(1)?],
    };
    // Each weld edge as its fit gives it, at the middle of its span.
    let fitted_edge = |k: usize| {
        let curve = &fits[k].curve;
        let middle = 0.5 * (curve.s_min + curve.s_max);
        edge_across(k, &curve.at(middle), &curve.tangent(middle))
    };
    let (mut s0, mut s1) = edge_ends::seam_span(ctx, plates, refitted, &fitted_edge, layout, extents, root.is_some());
    if layout == Layout::Lap {
        // The root lies a plate thickness below the edges the samples
        // saw; never plan a stretch of it the camera did not see (where
        // the image's border cuts the edges obliquely, the root leaves the
        // image before they do).
        (s0, s1) = ctx.clip_to_view(&weld, s0, s1, 0.0);
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
            Some(if layout == Layout::Lap { ctx.clip_to_view(&weld, v0, v1, 0.0) } else { (v0, v1) })
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
            tracing::debug!(
                rule = rules::weld_equation::LAP_SEAM_ENDS_WHERE_LOWER_PLATE_ENDS.id,
                seam = ?(s0, s1),
                lower_plate_seen = ?(v0, v1),
                "the lap's seam ends where its lower plate ends"
            );
            (s0, s1) = (start, end);
        }
    }
    ctx.trace.record(|t| t.weld = Some(TracedWeld { curve: weld.clone(), span: (s0, s1), normal }));
    check_overlap(s0, s1)?;
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
            let (v0, v1) = ctx.clip_to_view(&weld, s0 - before, s1 + after, 0.0);
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

    Ok(PlacedWeld { weld, span: (s0, s1), lap_step, edge_coverage, coverage, joint_beyond_ends_mm })
}

/// The seam's axes (4.2): along the line both weld edges' boundary
/// samples spread, laid across the plates' `normal`.
fn seam_axes(samples: &[Vec<Vec3>; 2], normal: &Vec3) -> Result<SeamAxes, PlanError> {
    let union: Vec<Vec3> = samples.iter().flatten().copied().collect();
    SeamAxes::principal(&union, normal).ok_or_else(|| {
        PlanError::by(&rules::refit::SEAM_SAMPLES_NOT_ALONG_A_LINE, "the weld edge samples do not spread along a line")
    })
}

/// A lap's root (Eq. 38): the upper plate's edge `upper_edge` moved down
/// `step`, the lower plate's depth below it along `normal`, if the lower
/// plate faces along the normal enough for one to be read.
fn lap_root(upper_edge: &SeamCurve, step: Option<f64>, normal: &Vec3) -> Result<SeamCurve, PlanError> {
    let step = step.ok_or_else(|| {
        PlanError::by(
            &rules::weld_equation::LAP_NO_STEP_ALONG_NORMAL,
            "the lower plate's plane runs along the plate normal: no lap step",
        )
    })?;
    Ok(weld_equation::lap_root(upper_edge, step, normal))
}

/// The stretch `[s0, s1]` both weld edges were seen along holds some seam.
fn check_overlap(s0: f64, s1: f64) -> Result<(), PlanError> {
    if s1 - s0 <= 0.0 {
        return Err(PlanError::by(
            &rules::weld_equation::EDGES_DO_NOT_OVERLAP,
            "the two weld edges do not overlap along the seam",
        ));
    }
    Ok(())
}

/// The quality stage: the seam's figures against the configured gates;
/// the first that refuses refuses the seam, those that only warn are
/// returned with the figures.
fn check_gates(
    ctx: &mut Context,
    workpiece: &Workpiece,
    refitted: &Refitted,
    groove: &Groove,
    placed: &PlacedWeld,
    root: Option<&RootLine>,
) -> Result<(SeamQuality, Vec<GateFailure>), PlanError> {
    let config = ctx.config;
    let plates = &workpiece.plates;
    let (degree, seam_spacing, beyond, steps) =
        (refitted.degree, refitted.seam_spacing, refitted.beyond, refitted.steps);
    let fits = &refitted.fits;
    let (joint, profile) = (groove.joint, &groove.profile);
    let PlacedWeld { span: (s0, s1), lap_step, edge_coverage, coverage, joint_beyond_ends_mm, .. } = *placed;
    // What the fits say about the seam, against the configured gates: a
    // seam that fails one is refused, unless the gate only warns.
    let quality = quality::measure(&quality::SeamFits {
        joint,
        fits,
        degree,
        planes: [&plates[0].plane, &plates[1].plane],
        span: (s0, s1),
        point_spacing_mm: seam_spacing,
        depth_to_support_mm: workpiece.depth_to_support_mm,
        lap_step_mm: lap_step.filter(|_| joint == JointType::Lap),
        groove: profile.as_ref(),
    });
    tracing::debug!(?quality, "seam quality");
    let edges = quality::SeamEvidence {
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
        root_bend: refitted.bend,
    };
    let evidence = root.map_or(edges, |root| root_weld::evidence(edges, root, seam_spacing));
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

    Ok((quality, warnings))
}

mod edge_ends;
#[cfg(test)]
mod tests;
