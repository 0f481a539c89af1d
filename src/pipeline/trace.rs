//! An opt-in record of what one plan found at each stage, for the pictures
//! and figures a person reads to see why a seam is where it is, or why it
//! was refused (`plan --debug`, the daemon's `[debug]` section).
//!
//! It costs nothing when off: [`super::Planner::plan`] runs with a
//! [`Tracer`] that holds no trace, and each stage's hook is a closure that
//! only a tracer holding one runs. [`super::Planner::plan_traced`] fills a
//! [`PlanTrace`] and, when the plan is refused, keeps everything gathered
//! up to the refusal beside the stage and reason. Indices refer to
//! [`PlanTrace::cloud`], the frame as the stages saw it.

use nalgebra::Isometry3;

use crate::camera::CameraModel;
use crate::cloud::PointCloud;
use crate::config::Method;
use crate::geometry::{Vec3, extent};
use crate::joint::JointType;

use super::PlanError;
use super::background::PlaneCluster;
use super::quality::{GateFailure, SeamQuality};
use super::ransac::EdgeLine;
use super::refit::{CurveFit, SeamCurve};

/// What one plan found, stage by stage; a stage that did not run leaves
/// its fields empty.
#[derive(Debug, Clone)]
pub struct PlanTrace {
    /// The joint planned: the one requested, or for `auto` the one found
    /// (None until it is); and the groove depth requested.
    pub joint: Option<JointType>,
    pub groove_depth_mm: Option<f64>,
    pub method: Method,
    /// The camera the frame was planned with (the configured one, or the
    /// organized frame's own pinhole standing in for it).
    pub camera: Option<CameraModel>,
    /// The frame as the stages saw it: camera frame, millimetres, the
    /// region of interest applied, unmeasurable points invalid.
    pub cloud: Option<PointCloud>,
    /// The workpiece's dominant normal (robust method).
    pub dominant_normal: Option<Vec3>,
    /// Which points passed the plane point criterion (Eq. 14), by index.
    pub plane_points: Vec<bool>,
    /// The plane clusters large enough to be a plate (3.3).
    pub planes: Vec<PlaneCluster>,
    /// The labels of the two planes chosen as the plates, in the
    /// pipeline's order (a lap's upper plate first).
    pub plate_labels: Option<[u32; 2]>,
    /// Each plate's edge points (Eq. 15), by index.
    pub edge_points: [Vec<u32>; 2],
    /// The RANSAC edge lines (3.4.2).
    pub edge_lines: Vec<TracedLine>,
    /// The samples each weld edge was fitted to: the robust method's
    /// plate boundary samples (4.2), the paper's RANSAC inliers.
    pub fit_samples: [Vec<Vec3>; 2],
    /// The two refitted weld edges (Eq. 17 to 25).
    pub weld_edges: Option<[CurveFit; 2]>,
    /// The weld (Eq. 32 to 38) and the stretch of it planned.
    pub weld: Option<TracedWeld>,
    pub quality: Option<SeamQuality>,
    /// The gates the seam failed that only warn.
    pub warnings: Vec<GateFailure>,
    /// The waypoints in the camera frame, in travel order.
    pub waypoints_camera: Vec<Vec3>,
    /// Camera frame to robot base frame at capture (Eq. 42).
    pub base_from_camera: Option<Isometry3<f64>>,
    /// Why the plan was refused, when it was.
    pub refusal: Option<PlanError>,
}

/// One RANSAC edge line as a segment over its inliers.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedLine {
    /// The plate (0 or 1) whose edge points it was found among.
    pub plate: usize,
    /// Its place in the order RANSAC found the lines of its run.
    pub rank: usize,
    /// The ends of its inliers along it.
    pub ends: [Vec3; 2],
    pub inliers: usize,
    /// Chosen as a weld edge (Eq. 16).
    pub picked: bool,
}

/// The weld curve, the stretch of it planned and the plate normal.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedWeld {
    pub curve: SeamCurve,
    /// The planned stretch along the curve's feature axis, mm.
    pub span: (f64, f64),
    /// The plate normal, into the workpiece.
    pub normal: Vec3,
}

impl PlanTrace {
    /// An empty trace of a plan of `joint` by `method`.
    pub fn new(joint: Option<JointType>, groove_depth_mm: Option<f64>, method: Method) -> Self {
        PlanTrace {
            joint,
            groove_depth_mm,
            method,
            camera: None,
            cloud: None,
            dominant_normal: None,
            plane_points: Vec::new(),
            planes: Vec::new(),
            plate_labels: None,
            edge_points: [Vec::new(), Vec::new()],
            edge_lines: Vec::new(),
            fit_samples: [Vec::new(), Vec::new()],
            weld_edges: None,
            weld: None,
            quality: None,
            warnings: Vec::new(),
            waypoints_camera: Vec::new(),
            base_from_camera: None,
            refusal: None,
        }
    }

    /// The plane cluster chosen as plate `k`, once the plates are chosen.
    pub fn plate(&self, k: usize) -> Option<&PlaneCluster> {
        let label = self.plate_labels?[k];
        self.planes.iter().find(|p| p.label == label)
    }

    /// Appends RANSAC lines found among `points`, each on the plate `plate`
    /// says.
    pub(super) fn add_lines(&mut self, lines: &[EdgeLine], points: &[Vec3], plate: impl Fn(&EdgeLine) -> usize) {
        self.edge_lines.extend(lines.iter().enumerate().map(|(rank, line)| {
            let along = |&i: &usize| (points[i] - line.point).dot(&line.direction);
            let (lo, hi) = extent(line.inliers.iter().map(along));
            let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 0.0) };
            TracedLine {
                plate: plate(line),
                rank,
                ends: [line.point + line.direction * lo, line.point + line.direction * hi],
                inliers: line.inliers.len(),
                picked: false,
            }
        }));
    }

    /// Marks the lines chosen as weld edges.
    pub(super) fn pick_lines(&mut self, picked: impl Fn(&TracedLine) -> bool) {
        for line in &mut self.edge_lines {
            line.picked = picked(line);
        }
    }
}

impl TracedWeld {
    /// The planned stretch's length along the curve, mm.
    pub fn length_mm(&self) -> f64 {
        // A straight seam needs two points; a few dozen follow any curve
        // the fit degrees allow to far below a micrometre.
        const SEGMENTS: usize = 64;
        let (s0, s1) = self.span;
        let at = |k: usize| self.curve.at(s0 + (s1 - s0) * k as f64 / SEGMENTS as f64);
        (1..=SEGMENTS).map(|k| (at(k) - at(k - 1)).norm()).sum()
    }
}

/// The hook the stages record through: holds the trace when tracing, and
/// nothing (so no hook runs) otherwise.
pub(super) struct Tracer<'a>(Option<&'a mut PlanTrace>);

impl<'a> Tracer<'a> {
    pub(super) fn off() -> Self {
        Tracer(None)
    }

    pub(super) fn on(trace: &'a mut PlanTrace) -> Self {
        Tracer(Some(trace))
    }

    /// The same trace, lent for a shorter while: to the first workpiece of
    /// a frame, whose stages it keeps.
    pub(super) fn reborrow(&mut self) -> Tracer<'_> {
        Tracer(self.0.as_deref_mut())
    }

    /// Runs `record` on the trace, if there is one.
    pub(super) fn record(&mut self, record: impl FnOnce(&mut PlanTrace)) {
        if let Some(trace) = self.0.as_deref_mut() {
            record(trace);
        }
    }
}
