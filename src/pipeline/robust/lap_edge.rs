//! A lap's weld edge checked against the upper plate's other edges (4.1
//! for a lap): where the lower plate is seen beside them tells the upper
//! plate's edge over the lower one from its ends and its far side, and,
//! under a request that leaves a butt joint open, that the upper plate
//! ends off the plane under it somewhere.

use rayon::prelude::*;

use crate::cloud::is_valid_point;
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;

use super::super::background::{self, PlaneCluster};
use super::super::boundary;
use super::super::context::Context;
use super::super::ransac::EdgeLine;
use super::super::{PlanError, weld_edges};

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
pub(super) fn check_lap_edge(
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
    let beside: Vec<&[u32]> = std::iter::once(lower).chain(&workpiece.layer_mates[1]).map(|c| &c.members[..]).collect();
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
        weld_edges::check_lap_edge(lines, chosen, seen_mm[0], &ends, &far).map_err(|e| PlanError::by(e.rule(), e))?;
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
    weld_edges::check_lap_ends_off_lower_plane(&seen).map_err(|e| PlanError::by(e.rule(), e))
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
/// spacings of it ([`crate::pipeline::view_border::ViewBorder::runs_along`]); within the
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
