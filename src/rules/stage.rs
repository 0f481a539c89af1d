//! The pipeline's stages, named once: a rule belongs to one, a refusal
//! names one, and the timings are kept per stage.

use std::fmt;

/// A pipeline stage, for timings, rules and error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    Request,
    Input,
    NeighbourIndex,
    Orientation,
    PlanePoints,
    Clustering,
    Background,
    EdgePoints,
    Ransac,
    WeldEdges,
    Refit,
    /// The groove probe: what lies between a butt joint's weld edges
    /// (groove faces, a square gap, or a plate standing there).
    Groove,
    WeldEquation,
    /// The seam's quality figures against the configured gates.
    Quality,
    Trajectory,
}

impl Stage {
    /// The stages that do the pipeline's work, in run order (the request
    /// check takes no measurable time and is not timed). Each is charged
    /// the same work in both methods: [`Stage::Input`] the frame's check
    /// against what the camera can measure, [`Stage::NeighbourIndex`] the
    /// neighbour search's index (a point tree, or nothing to build on a
    /// pixel grid); the paper's method has no [`Stage::Orientation`],
    /// [`Stage::Groove`] or [`Stage::Quality`].
    pub const IN_ORDER: [Stage; 14] = [
        Stage::Input,
        Stage::NeighbourIndex,
        Stage::Orientation,
        Stage::PlanePoints,
        Stage::Clustering,
        Stage::Background,
        Stage::EdgePoints,
        Stage::Ransac,
        Stage::WeldEdges,
        Stage::Refit,
        Stage::Groove,
        Stage::WeldEquation,
        Stage::Quality,
        Stage::Trajectory,
    ];

    /// Every stage, the request check first.
    pub const ALL: [Stage; 15] = {
        let mut all = [Stage::Request; 15];
        let mut k = 0;
        while k < Stage::IN_ORDER.len() {
            all[k + 1] = Stage::IN_ORDER[k];
            k += 1;
        }
        all
    };

    pub fn name(self) -> &'static str {
        match self {
            Stage::Request => "request",
            Stage::Input => "input",
            Stage::NeighbourIndex => "neighbour_index",
            Stage::Orientation => "orientation",
            Stage::PlanePoints => "plane_points",
            Stage::Clustering => "clustering",
            Stage::Background => "background",
            Stage::EdgePoints => "edge_points",
            Stage::Ransac => "ransac",
            Stage::WeldEdges => "weld_edges",
            Stage::Refit => "refit",
            Stage::Groove => "groove",
            Stage::WeldEquation => "weld_equation",
            Stage::Quality => "quality",
            Stage::Trajectory => "trajectory",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
