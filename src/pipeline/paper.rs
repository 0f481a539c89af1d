//! The paper's method, as written, from the sanitised frame to the
//! waypoints: section 3 (preprocessing), section 4 (the weld) and
//! section 5.1 (the trajectory), one stage after the other.
//!
//! - 3.2: plane points by the neighbour count of a frontal plane (Eq. 6,
//!   13, 14);
//! - 3.3: Euclidean clustering at `paper.cluster_tolerance_mm`, the cluster
//!   with the largest xy bounding box is the background;
//! - 3.4.1: edge points, at most `paper.edge_ratio` of the frontal count
//!   (Eq. 15);
//! - 3.4.2: iterative RANSAC over both plates' edge points at once;
//! - 4.1: the weld edges are the lines the two centroids lie on either
//!   side of (Eq. 16);
//! - 4.2: each edge refitted by least squares along camera x or y
//!   (Eq. 17 to 25) over its RANSAC inliers;
//! - 4.3: the normal from the edges' end points (Eq. 33, 34) and the weld
//!   per joint type (Eq. 32, 36, 38);
//! - 5.1: base-frame waypoints (Eq. 39 to 42).
//!
//! It stays reachable (`pipeline.method = "paper"`) as the reference the
//! robust method is measured against; [`super::robust`] says where and
//! why the robust method departs from it.

use crate::config::Method;

use super::context::{self, Context, EdgeFigures, MIN_CLUSTER_POINTS, PlannedWeld};
use super::edge_points::{EdgeCriterion, FullCount};
use super::neighbours::NeighbourSearch;
use super::refit::{self, CurveFit, SeamAxes, SeamCurve};
use super::trace::TracedWeld;
use super::{Plan, PlanError, SeamAssessment, Stage};
use super::{background, clustering, plane_points, ransac, weld_edges, weld_equation};
use crate::geometry::Vec3;
use crate::rules;

/// Plans one frame by the paper's method.
pub(super) fn plan(mut ctx: Context) -> Result<Plan, PlanError> {
    let config = ctx.config;
    let camera = &config.camera;
    let cloud = ctx.cloud;
    let search = NeighbourSearch::new(cloud, camera, config.pipeline.neighbour_radius_mm);
    ctx.clock.lap(Stage::NeighbourIndex)?;

    // 3.2: a point is a plane point when its neighbour count reaches the
    // least a frontal plane at its depth can have (Eq. 14).
    let mut plane = plane_points::paper_criterion(cloud, camera, &search);
    ctx.stats.plane_points = plane.len();
    ctx.trace.record(|t| t.plane_points = plane.mask.clone());
    ctx.clock.lap(Stage::PlanePoints)?;
    if ctx.stats.plane_points == 0 {
        return Err(PlanError::by(&rules::plane_points::NO_PLANE_POINT, "no point passed the plane point criterion"));
    }

    // 3.3: Euclidean clustering splits the plane points into planes.
    let mut clusters = clustering::euclidean(cloud, &plane.mask, config.paper.cluster_tolerance_mm, MIN_CLUSTER_POINTS);
    // The edge criterion needs the counts, not the mask: free it early,
    // as the frame-sized arrays of the coming stages add up.
    plane.mask = Vec::new();
    ctx.clock.lap(Stage::Clustering)?;

    // 3.3: the plane with the largest xy bounding box is the background;
    // a point stands for the area of a frontal plane's pixel (Eq. 4).
    let planes = ctx.planes_of(std::mem::take(&mut clusters.members), |c, _| 1.0 / camera.density(c.z));
    ctx.stats.clusters = planes.len();
    ctx.trace.record(|t| t.planes = planes.clone());
    let workpiece = background::paper_select(cloud, planes).map_err(|e| PlanError::by(e.rule(), e))?;
    ctx.stats.plate_points = workpiece.plates.each_ref().map(|p| p.members.len());
    ctx.trace.record(|t| t.plate_labels = Some(workpiece.plates.each_ref().map(|p| p.label)));
    ctx.clock.lap(Stage::Background)?;
    // The paper's method is always told the joint (the request's check).
    let joint = ctx.request.joint.given();
    ctx.check_groove_depth(joint, &workpiece)?;

    // 3.4.1: an edge point has at most `paper.edge_ratio` of a frontal
    // plane's neighbour count (Eq. 15).
    let criterion = EdgeCriterion { full: FullCount::Frontal, ratio: config.paper.edge_ratio };
    let edges = context::plate_edge_points(&clusters.labels, &workpiece, &search, &plane, &criterion);
    ctx.stats.edge_points = [edges[0].len(), edges[1].len()];
    ctx.trace.record(|t| t.edge_points = edges.clone());
    ctx.clock.lap(Stage::EdgePoints)?;

    // 3.4.2: iterative RANSAC over both plates' edge points together; a
    // line belongs to the plate most of its inliers come from.
    let mut all: Vec<Vec3> = ctx.points_of(&edges[0]);
    let split = all.len();
    all.extend(ctx.points_of(&edges[1]));
    let lines = ransac::segment_lines(&all, &ctx.ransac_params(0));
    ctx.stats.edge_lines = lines.len();
    ctx.clock.lap(Stage::Ransac)?;

    // 4.1: the weld edges are the lines with the two plate centroids on
    // either side (Eq. 16).
    let centroids = workpiece.plates.each_ref().map(|p| p.centroid);
    let owner =
        |l: &ransac::EdgeLine| (l.inliers.iter().filter(|&&i| i >= split).count() * 2 > l.inliers.len()) as usize;
    ctx.trace.record(|t| t.add_lines(&lines, &all, owner));
    let pick = weld_edges::paper_select(&lines, centroids, owner).map_err(|e| PlanError::by(e.rule(), e))?;
    ctx.trace.record(|t| t.pick_lines(|l| pick.contains(&l.rank)));
    ctx.clock.lap(Stage::WeldEdges)?;

    // 4.2: each edge's RANSAC inliers refitted by least squares, the
    // feature along camera x or y (Eq. 17 to 25).
    let inliers: [Vec<Vec3>; 2] = pick.map(|k| lines[k].inliers.iter().map(|&i| all[i]).collect());
    let union: Vec<Vec3> = inliers.iter().flatten().copied().collect();
    let axes = SeamAxes::paper(&union);
    let degree = config.pipeline.fit_degree as usize;
    let fits = fit_edges(&inliers, &axes, degree)?;
    ctx.trace.record(|t| (t.weld_edges, t.fit_samples) = (Some(fits.clone()), inliers.clone()));
    ctx.clock.lap(Stage::Refit)?;

    // 4.3: the normal from the edges' end points (Eq. 33, 34), then the
    // weld per joint type (Eq. 32, 36; Eq. 38 for a lap), over its own
    // feature range.
    let (e1, e2) = (&fits[0].curve, &fits[1].curve);
    let normal = plate_normal(e1, e2)?;
    let depth = ctx.request.groove_depth_mm.unwrap_or(0.0);
    let joint = context::decided(joint)?;
    let weld = context::weld(joint, e1, e2, &normal, depth, || Ok(weld_equation::lap_paper(e1, e2)))?;
    let span = (weld.s_min, weld.s_max);
    ctx.trace.record(|t| t.weld = Some(TracedWeld { curve: weld.clone(), span, normal }));
    ctx.clock.lap(Stage::WeldEquation)?;

    // 5.1: the waypoints in the robot's base frame.
    let weld = PlannedWeld::new(joint, weld, span, normal, EdgeFigures::of(&fits), SeamAssessment::default());
    ctx.finish(Method::Paper, weld)
}

/// 4.2: each edge's inliers fitted by least squares along `axes`.
fn fit_edges(inliers: &[Vec<Vec3>; 2], axes: &SeamAxes, degree: usize) -> Result<[CurveFit; 2], PlanError> {
    let fit = |k: usize| {
        refit::fit(&inliers[k], axes, degree).ok_or_else(|| {
            PlanError::by(
                &rules::refit::EDGE_TOO_FEW_POINTS_TO_FIT,
                "a weld edge has too few points for a least-squares fit",
            )
        })
    };
    Ok([fit(0)?, fit(1)?])
}

/// 4.3: the plate normal from the edges' end points (Eq. 33, 34).
fn plate_normal(e1: &SeamCurve, e2: &SeamCurve) -> Result<Vec3, PlanError> {
    weld_equation::paper_normal(e1, e2).ok_or_else(|| {
        PlanError::by(&rules::weld_equation::EDGES_COLLINEAR, "the weld edges are collinear; no plate normal")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edge_of_too_few_points_or_collinear_edges_are_refused_by_rule() {
        let line = |y: f64, n: usize| (0..n).map(|k| Vec3::new(k as f64, y, 700.0)).collect::<Vec<_>>();
        let axes = SeamAxes::paper(&line(0.0, 10));
        // A line needs two points apart along it, and a residual a third.
        let short = fit_edges(&[line(-1.0, 10), line(1.0, 2)], &axes, 1).unwrap_err();
        assert_eq!((short.rule.id, short.stage), ("edge.too_few_points_to_fit", Stage::Refit), "{short}");
        let fits = fit_edges(&[line(-1.0, 10), line(1.0, 3)], &axes, 1).expect("two lines");
        let (e1, e2) = (&fits[0].curve, &fits[1].curve);
        assert!((plate_normal(e1, e2).expect("a plane") - Vec3::z()).norm() < 1e-9);
        // The same edge twice spans no plane.
        let collinear = plate_normal(e1, e1).unwrap_err();
        assert_eq!((collinear.rule.id, collinear.stage), ("seam.edges_collinear", Stage::WeldEquation), "{collinear}");
    }
}
