//! A V-groove welded on its root when its top edges are ragged (rule
//! `groove.weld_on_bevel_midline`): the weld is first placed from the
//! weld edges and judged by their samples; where the edges fail the gates
//! that read a top edge's straightness (samples beyond its line, on two
//! lines, a residual of several spacings: a groove cut by hand or by a
//! torch) while both flanks are clean plane faces and a bevel shows the
//! root, the weld is placed again on the root the flanks place station by
//! station ([`super::super::groove::RootLine`]), along the stretch they
//! show it, and the same gates read the root's own samples in place of
//! the edges': how far they scatter about the root line, whether they
//! step between two runs, along how much of the seam both flanks are
//! seen, whether they bend.

use crate::joint::JointType;
use crate::rules::{self, Rule};

use super::super::PlanError;
use super::super::groove::{Between, GrooveProfile, RootLine};
use super::super::quality::{FittedEdges, SeamEvidence};
use super::super::refit::step_in;
use super::super::straightness::{Samples, bend_of};
use super::plates::MIN_STEP_RUN_SHARE;

/// The gates that judge a top edge's straightness: what a ragged edge
/// fails, and what the root's samples are judged by in its place.
/// A top edge cut back along part of the seam may also be picked as the
/// run on one line only, and then seen along part of the joint: the
/// joint's coverage and the plates seen beside it past the seam's ends.
const EDGE_STRAIGHTNESS: [&Rule; 5] = [
    &rules::quality::EDGE_SAMPLES_BEYOND_LINE,
    &rules::quality::EDGE_SAMPLES_ON_TWO_LINES,
    &rules::quality::EDGE_FIT_RESIDUAL,
    &rules::quality::JOINT_COVERAGE,
    &rules::quality::STOPS_SHORT_OF_JOINT,
];

/// The root to weld on instead of the edges' midline: for a V-groove
/// whose edge-placed weld `checked` was refused by a top edge's
/// straightness, when the groove `probe` reads along every stretch either
/// edge was seen still shows a V-groove and a root from both flanks.
pub(super) fn wanted<T>(
    checked: &Result<T, PlanError>,
    joint: JointType,
    probe: impl FnOnce() -> GrooveProfile,
) -> Option<RootLine> {
    let Err(refused) = checked else { return None };
    if joint != JointType::VButt || !EDGE_STRAIGHTNESS.iter().any(|r| r.id == refused.rule.id) {
        return None;
    }
    let profile = probe();
    tracing::debug!(verdict = ?profile.verdict(), "along either edge: {}", profile.describe());
    if profile.verdict() != Between::Groove {
        return None;
    }
    let root = profile.root()?;
    tracing::debug!(
        rule = rules::weld_equation::WELD_ON_BEVEL_MIDLINE.id,
        edges = refused.rule.id,
        stations = root.samples.len(),
        rms_mm = root.rms_mm,
        span = ?root.span,
        offset = ?root.offset,
        "ragged top edges: the V-groove's weld on the root its flanks place"
    );
    Some(root)
}

/// The gates' evidence with the root's samples in place of the top
/// edges': its residual, its largest step, the share of the seam where
/// both flanks show it, and its bend.
pub(super) fn evidence<'a>(edges: SeamEvidence<'a>, root: &RootLine, spacing_mm: f64) -> SeamEvidence<'a> {
    let residuals: Vec<(f64, f64)> = root.residuals().collect();
    SeamEvidence {
        edge_fit_rms_mm: [root.rms_mm; 2],
        edge_beyond: None,
        edge_steps: Some([step_in(residuals.clone(), MIN_STEP_RUN_SHARE), None]),
        edge_coverage: Some([root.station_share; 2]),
        fits: FittedEdges::GrooveRoot,
        root_bend: bend_of(residuals, Samples::PerStation, spacing_mm, "the groove's root"),
        ..edges
    }
}
