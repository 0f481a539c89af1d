//! Where a butt or lap weld runs along its seam: each weld edge's extent
//! read again where the frame lost its grid, carried to the image's border
//! where its plate runs on to it (`seam.end_at_image_border`), never past
//! where the edge's own line leaves the view, and the stretch both edges
//! show, a lap's lower edge leaving the image excepted.

use crate::geometry::Vec3;
use crate::rules;

use super::super::super::background::{Layout, PlaneCluster};
use super::super::super::boundary::{self, CoarseEdge};
use super::super::super::context::Context;
use super::super::super::view_border;
use super::Refitted;

/// The weld's stretch along the seam's feature axis from the two weld
/// edges' `extents` as their boundary samples give them, or a V-groove's
/// root span for both (`by_root`: not read again from the plates, only
/// clipped to where the edges are in view). `fitted_edge(k)` is edge `k`
/// as its fit places it.
pub(super) fn seam_span(
    ctx: &Context,
    plates: &[PlaneCluster; 2],
    refitted: &Refitted,
    fitted_edge: &impl Fn(usize) -> CoarseEdge,
    layout: Layout,
    mut extents: [(f64, f64); 2],
    by_root: bool,
) -> (f64, f64) {
    let Refitted { params, axes, degree, seam_spacing, fits, .. } = refitted;
    let (params, degree, seam_spacing) = (*params, *degree, *seam_spacing);
    let cloud = ctx.cloud;
    if !cloud.is_organized() && degree == 1 && !by_root {
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
    if let Some(grid) = ctx.camera_grid().filter(|_| !by_root) {
        // On the camera's grid the boundary samples stop a trimmed rim
        // short of the image border; where the plate runs on to it, so
        // does the edge.
        let reach = |k: usize| {
            let edge = fitted_edge(k);
            let spacing = ctx.spacing_at(&edge.point);
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
        if reached != extents {
            tracing::debug!(rule = rules::refit::SEAM_END_AT_IMAGE_BORDER.id, "a weld edge's end moved to the border");
        }
        extents = reached;
    }
    if ctx.camera_grid().is_none()
        && !by_root
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
        if reached != extents {
            tracing::debug!(rule = rules::refit::SEAM_END_AT_IMAGE_BORDER.id, "a weld edge's end moved to the border");
        }
        extents = reached;
    }
    // No edge runs on past where its own line leaves the image: a plate's
    // rows read inside its edge, or its rim, cross an oblique border before
    // or after the edge itself does, and a V-groove's root, read where its
    // flanks show it, is the joint's only where both edges are in view.
    // A border read from the cloud, and an edge fitted to a coarse cloud's
    // points, each lie up to about half a voxel inside the true ones: the
    // edge may run on as far past it as evidence reaches the border.
    let reach = view_border::BORDER_REACH_SPACINGS * seam_spacing;
    for (k, extent) in extents.iter_mut().enumerate() {
        let clipped = ctx.clip_to_view(&fits[k].curve, extent.0, extent.1, reach);
        if clipped.1 > clipped.0 {
            *extent = clipped;
        }
    }
    tracing::debug!(edge_1_mm = ?extents[0], edge_2_mm = ?extents[1], "weld edges seen along the seam");
    // A lap's lower edge stands in for its root: where it leaves the image
    // (the image's border a reach past its end) the root may still be in
    // view: the caller clips it to the view.
    let leaves_view = |at: f64, outward: f64| ctx.in_view(&fits[1].curve.at(at + outward * reach), 0.0) == Some(false);
    let lower_leaves = if layout == Layout::Lap {
        [leaves_view(extents[1].0, -1.0), leaves_view(extents[1].1, 1.0)]
    } else {
        [false; 2]
    };
    let span = boundary::seam_span(extents, [[false; 2], lower_leaves]);
    let [(a0, a1), (b0, b1)] = extents;
    if span != (a0.max(b0), a1.min(b1)) {
        tracing::debug!(
            rule = rules::refit::SEAM_END_AT_IMAGE_BORDER.id,
            ?lower_leaves,
            ?span,
            "the lap's root runs on past where its lower edge leaves the image"
        );
    }
    span
}
