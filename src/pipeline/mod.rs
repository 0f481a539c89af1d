//! The seam pipeline: from a camera-frame point cloud and the robot pose
//! at capture to base-frame welding waypoints. One stage per module, run
//! in the paper's order (sections 3 to 5):
//!
//! 1. [`orientation`]: the workpiece's dominant normal (robust method only).
//! 2. [`plane_points`]: the plane point criterion (Eq. 14).
//! 3. [`clustering`]: Euclidean clustering (3.3).
//! 4. [`background`]: background removal, the two workpiece plates (3.3).
//! 5. [`edge_points`]: the plane edge criterion (Eq. 15).
//! 6. [`ransac`]: iterative RANSAC line segmentation (3.4.2).
//! 7. [`weld_edges`]: weld edges by centroid positioning (Eq. 16).
//! 8. [`boundary`] and [`refit`]: the edges' least-squares refit (4.2).
//! 9. [`weld_equation`]: the weld per joint type (Eq. 32 to 38).
//! 10. [`trajectory`]: sampling and the base frame (Eq. 42).
//!
//! The pipeline does no I/O. Its loops run on the current rayon pool, so
//! the caller chooses the threads (the daemon installs a dedicated pool).

pub mod background;
pub mod boundary;
pub mod clustering;
pub mod edge_points;
pub mod grid_search;
pub mod neighbours;
pub mod orientation;
pub mod plane_points;
pub mod ransac;
pub mod refit;
pub mod trajectory;
pub mod weld_edges;
pub mod weld_equation;

use std::borrow::Cow;
use std::fmt;

use rayon::prelude::*;
use std::time::Instant;

use nalgebra::Isometry3;

use crate::camera::{MeasurableVolume, Unmeasurable};
use crate::cloud::PointCloud;
use crate::config::{Config, Method};
use crate::geometry::pose::RobotPose;
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;

use background::{PlaneCluster, Workpiece};
use boundary::{Boundary, BoundaryParams, BoundarySample, CoarseEdge};
use clustering::UNCLUSTERED;
use edge_points::{EdgeCriterion, FullCount};
use neighbours::NeighbourSearch;
use ransac::{EdgeLine, RansacParams};
use refit::{CurveFit, Frame, SeamCurve};
pub use trajectory::Waypoint;

/// What the controller asks for.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    pub joint: JointType,
    /// Groove depth d of a V-butt joint, mm (Eq. 32). Required for V-butt.
    pub groove_depth_mm: Option<f64>,
    /// The robot flange pose when the frame was captured.
    pub pose: RobotPose,
    /// `End_T_Camera`, if not the configured one.
    pub hand_eye: Option<Isometry3<f64>>,
    pub step_mm: Option<f64>,
    pub work_angle_deg: Option<f64>,
    pub travel_angle_deg: Option<f64>,
    /// The waypoints start at the seam's end nearest this point (robot
    /// base frame, mm); else by [`trajectory::travel_order`]'s default.
    pub start_near: Option<Vec3>,
}

impl PlanRequest {
    /// A request with the configured defaults for everything optional.
    pub fn new(joint: JointType, groove_depth_mm: Option<f64>, pose: RobotPose) -> Self {
        PlanRequest {
            joint,
            groove_depth_mm,
            pose,
            hand_eye: None,
            step_mm: None,
            work_angle_deg: None,
            travel_angle_deg: None,
            start_near: None,
        }
    }
}

/// A pipeline stage, for timings and error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    Request,
    Orientation,
    PlanePoints,
    Clustering,
    Background,
    EdgePoints,
    Ransac,
    WeldEdges,
    Refit,
    WeldEquation,
    Trajectory,
}

impl Stage {
    /// The stages that do the pipeline's work, in run order (the request
    /// check takes no measurable time and is not timed).
    pub const IN_ORDER: [Stage; 10] = [
        Stage::Orientation,
        Stage::PlanePoints,
        Stage::Clustering,
        Stage::Background,
        Stage::EdgePoints,
        Stage::Ransac,
        Stage::WeldEdges,
        Stage::Refit,
        Stage::WeldEquation,
        Stage::Trajectory,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Stage::Request => "request",
            Stage::Orientation => "orientation",
            Stage::PlanePoints => "plane_points",
            Stage::Clustering => "clustering",
            Stage::Background => "background",
            Stage::EdgePoints => "edge_points",
            Stage::Ransac => "ransac",
            Stage::WeldEdges => "weld_edges",
            Stage::Refit => "refit",
            Stage::WeldEquation => "weld_equation",
            Stage::Trajectory => "trajectory",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why no trajectory could be planned: the stage that failed and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{stage} stage failed: {reason}")]
pub struct PlanError {
    pub stage: Stage,
    pub reason: String,
}

impl PlanError {
    fn at(stage: Stage, reason: impl fmt::Display) -> Self {
        PlanError { stage, reason: reason.to_string() }
    }
}

/// Wall time per stage, in run order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimings {
    pub stages: Vec<(Stage, f64)>,
}

impl StageTimings {
    pub fn total_ms(&self) -> f64 {
        self.stages.iter().map(|(_, ms)| ms).sum()
    }

    pub fn get(&self, stage: Stage) -> Option<f64> {
        self.stages.iter().find(|(s, _)| *s == stage).map(|(_, ms)| *ms)
    }
}

struct Clock {
    timings: StageTimings,
    last: Instant,
}

impl Clock {
    fn start() -> Self {
        Clock { timings: StageTimings::default(), last: Instant::now() }
    }

    fn lap(&mut self, stage: Stage) {
        let now = Instant::now();
        self.timings.stages.push((stage, (now - self.last).as_secs_f64() * 1e3));
        self.last = now;
    }
}

/// Point counts through the pipeline, for logs and quality checks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlanStats {
    pub valid_points: usize,
    pub plane_points: usize,
    pub clusters: usize,
    pub plate_points: [usize; 2],
    pub edge_points: [usize; 2],
    pub edge_lines: usize,
}

/// One planned seam.
#[derive(Debug, Clone, PartialEq)]
pub struct Seam {
    pub joint: JointType,
    /// Base frame, ordered along the seam.
    pub waypoints: Vec<Waypoint>,
    /// The seam's ends in the camera frame.
    pub start_camera: Vec3,
    pub end_camera: Vec3,
    /// Plate normal in the camera frame, into the workpiece.
    pub normal_camera: Vec3,
    pub length_mm: f64,
    /// RMS residual of each weld edge's least-squares fit, mm.
    pub edge_fit_rms_mm: [f64; 2],
    /// Samples used by each edge's fit, and how many the trimming dropped.
    pub edge_samples: [usize; 2],
    pub edge_samples_dropped: [usize; 2],
}

/// The result of planning one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub method: Method,
    pub seams: Vec<Seam>,
    pub stats: PlanStats,
    pub timings: StageTimings,
}

/// Plans trajectories with one configuration.
#[derive(Debug, Clone)]
pub struct Planner {
    config: Config,
}

impl Planner {
    pub fn new(config: Config) -> Self {
        Planner { config }
    }

    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Checks a request's own values against the configured limits (pose
    /// within the robot's reach, sane angles, hand-eye, groove depth,
    /// step, torch angles) before any frame is fetched for it.
    pub fn check_request(&self, request: &PlanRequest) -> Result<(), PlanError> {
        validate(request, &self.config)
    }

    /// Runs the pipeline on `cloud` (camera frame, mm).
    pub fn plan(&self, cloud: &PointCloud, request: &PlanRequest) -> Result<Plan, PlanError> {
        Run::new(&self.config, cloud, request)?.execute()
    }
}

/// One pipeline run: the inputs and what the stages have found so far.
struct Run<'a> {
    config: &'a Config,
    /// The frame, once [`Run::execute`] has begun without the points the
    /// camera cannot measure.
    cloud: Cow<'a, PointCloud>,
    request: &'a PlanRequest,
    method: Method,
    clock: Clock,
    stats: PlanStats,
}

impl<'a> Run<'a> {
    fn new(config: &'a Config, cloud: &'a PointCloud, request: &'a PlanRequest) -> Result<Self, PlanError> {
        validate(request, config)?;
        Ok(Run {
            config,
            cloud: Cow::Borrowed(cloud),
            request,
            method: config.pipeline.method,
            clock: Clock::start(),
            stats: PlanStats::default(),
        })
    }

    fn execute(mut self) -> Result<Plan, PlanError> {
        let cfg = &self.config.pipeline;
        let camera = &self.config.camera;
        // A point outside what the camera can measure is a corrupt frame's
        // or noise, and one such point far off the axis would widen every
        // window it is part of: it becomes invalid before any stage runs.
        let volume = camera.measurable_volume(self.cloud.width(), self.cloud.height(), self.cloud.is_organized());
        let counts = count_measurable(&self.cloud, &volume);
        if counts.unmeasurable() > 0 {
            tracing::warn!(
                near = counts.near,
                far = counts.far,
                off_view = counts.off_view,
                min_depth_mm = camera.min_depth_mm,
                max_depth_mm = camera.max_depth_mm,
                max_off_axis_deg = camera.max_off_axis_deg,
                camera_field_of_view = volume.fov_applies(),
                "ignoring {} invalid points the camera cannot measure",
                counts.unmeasurable()
            );
            self.cloud = Cow::Owned(without_unmeasurable(&self.cloud, &volume));
        }
        self.stats.valid_points = counts.valid - counts.unmeasurable();
        if self.stats.valid_points == 0 && counts.near > 0 && counts.near == counts.valid {
            return Err(PlanError::at(
                Stage::PlanePoints,
                format!(
                    "the frame has no valid point: all {} points lie nearer than camera.min_depth_mm ({} mm); \
                     is the cloud in millimetres and in the camera frame?",
                    counts.near, camera.min_depth_mm
                ),
            ));
        }
        if self.stats.valid_points == 0 && counts.unmeasurable() > 0 {
            return Err(PlanError::at(
                Stage::PlanePoints,
                format!(
                    "the frame has no valid point: of its {} points {} lie nearer than camera.min_depth_mm \
                     ({} mm), {} farther than camera.max_depth_mm ({} mm) and {} outside the view \
                     (camera.max_off_axis_deg {}°{}); is the cloud in millimetres and in the camera frame?",
                    counts.valid,
                    counts.near,
                    camera.min_depth_mm,
                    counts.far,
                    camera.max_depth_mm,
                    counts.off_view,
                    camera.max_off_axis_deg,
                    if volume.fov_applies() { ", or the camera's field of view" } else { "" }
                ),
            ));
        }
        if self.stats.valid_points == 0 {
            return Err(PlanError::at(Stage::PlanePoints, "the frame has no valid point"));
        }
        let cloud: &PointCloud = &self.cloud;
        let search = NeighbourSearch::new(cloud, camera, cfg.neighbour_radius_mm);
        let robust = self.method == Method::Robust;

        let dominant = if robust {
            let n = orientation::dominant_normal(cloud, &search, camera.fx(), 5.0)
                .ok_or_else(|| PlanError::at(Stage::Orientation, "no surface normal could be estimated"))?;
            self.clock.lap(Stage::Orientation);
            Some(n)
        } else {
            None
        };

        let plane = match dominant {
            Some(normal) => plane_points::robust_criterion(
                &search,
                &plane_points::RobustPlaneCriterion {
                    normal,
                    min_ratio: cfg.plane_min_neighbour_ratio,
                    max_angle_deg: cfg.plane_max_normal_angle_deg,
                },
            ),
            None => plane_points::paper_criterion(cloud, camera, &search),
        };
        self.stats.plane_points = plane.len();
        self.clock.lap(Stage::PlanePoints);
        if self.stats.plane_points == 0 {
            return Err(PlanError::at(Stage::PlanePoints, "no point passed the plane point criterion"));
        }

        // Clusters below a few dozen points cannot reach the area limit.
        const MIN_CLUSTER_POINTS: usize = 30;
        let mut plane = plane;
        let mut clusters = if robust && cloud.is_organized() {
            clustering::grid(cloud, &plane.mask, cfg.cluster_tolerance_mm, MIN_CLUSTER_POINTS)
        } else {
            let tol = if robust { cfg.cluster_tolerance_mm } else { self.config.paper.cluster_tolerance_mm };
            clustering::euclidean(cloud, &plane.mask, tol, MIN_CLUSTER_POINTS)
        };
        // The edge criterion needs the counts, not the mask: free it early,
        // as the frame-sized arrays of the coming stages add up.
        plane.mask = Vec::new();
        self.clock.lap(Stage::Clustering);

        let area_per_point = |c: &Vec3, n: &Vec3| -> f64 {
            if robust {
                1.0 / camera.plane_density_at([c.x, c.y, c.z], [n.x, n.y, n.z])
            } else {
                1.0 / camera.density(c.z)
            }
        };
        let planes: Vec<PlaneCluster> =
            background::describe(cloud, std::mem::take(&mut clusters.members), area_per_point)
                .into_iter()
                .filter(|c| c.area_mm2 >= cfg.min_plane_area_mm2)
                .collect();
        self.stats.clusters = planes.len();
        let workpiece = match dominant {
            Some(normal) => background::robust_select(
                planes,
                &background::Selection {
                    joint: self.request.joint,
                    normal,
                    coplanar_tolerance_mm: cfg.coplanar_tolerance_mm,
                    lap_step_min_mm: cfg.lap_step_min_mm,
                    lap_step_max_mm: cfg.lap_step_max_mm,
                    max_tilt_deg: cfg.plane_max_normal_angle_deg,
                },
            ),
            None => background::paper_select(cloud, planes),
        }
        .map_err(|e| PlanError::at(Stage::Background, e))?;
        self.stats.plate_points = workpiece.plates.each_ref().map(|p| p.members.len());
        self.clock.lap(Stage::Background);
        self.check_groove_depth(&workpiece)?;

        // The cluster labels, renumbered in place: plate k is label k.
        let mut labels = clusters.labels;
        let plate_labels = workpiece.plates.each_ref().map(|p| p.label);
        labels.par_iter_mut().for_each(|l| {
            *l = match plate_labels.iter().position(|p| p == l) {
                Some(k) => k as u32,
                None => UNCLUSTERED,
            }
        });
        let criterion = match dominant {
            Some(_) => EdgeCriterion { full: FullCount::Plane, ratio: cfg.edge_max_neighbour_ratio },
            None => EdgeCriterion { full: FullCount::Frontal, ratio: self.config.paper.edge_ratio },
        };
        let plates = std::array::from_fn(|k| edge_points::Plate {
            labels: &labels,
            label: k as u32,
            members: &workpiece.plates[k].members,
        });
        let edges = edge_points::edge_points_of_plates(&search, &plane, plates, &criterion);
        self.stats.edge_points = [edges[0].len(), edges[1].len()];
        self.clock.lap(Stage::EdgePoints);

        let seam = if robust {
            // The plates' least-squares planes fix the normal far better
            // than the sampled dominant one: the groove depth (Eq. 32) and
            // the lap step are shifted along it.
            let [a, b] = workpiece.plates.each_ref().map(|p| p.plane.normal);
            let normal = (a + b).try_normalize(1e-9).or(dominant).unwrap_or_else(Vec3::z);
            self.robust_seam(&workpiece, &edges, normal)?
        } else {
            self.paper_seam(&workpiece, &edges)?
        };
        Ok(Plan { method: self.method, seams: vec![seam], stats: self.stats, timings: self.clock.timings })
    }

    fn ransac_params(&self, seed_offset: u64) -> RansacParams {
        let cfg = &self.config.pipeline;
        RansacParams {
            distance_mm: cfg.ransac_distance_mm,
            iterations: cfg.ransac_iterations,
            min_line_points: cfg.ransac_min_line_points as usize,
            min_remaining_points: cfg.ransac_min_remaining_points as usize,
            max_lines: cfg.ransac_max_lines as usize,
            seed: cfg.ransac_seed.wrapping_add(seed_offset),
        }
    }

    fn points_of(&self, indices: &[u32]) -> Vec<Vec3> {
        indices.iter().map(|&i| vec3(&self.cloud.points()[i as usize])).collect()
    }

    /// Stages 6 to 10 as the paper has them.
    fn paper_seam(&mut self, workpiece: &Workpiece, edges: &[Vec<u32>; 2]) -> Result<Seam, PlanError> {
        let cfg = &self.config.pipeline;
        let mut all: Vec<Vec3> = self.points_of(&edges[0]);
        let split = all.len();
        all.extend(self.points_of(&edges[1]));
        let lines = ransac::segment_lines(&all, &self.ransac_params(0));
        self.stats.edge_lines = lines.len();
        self.clock.lap(Stage::Ransac);

        let centroids = workpiece.plates.each_ref().map(|p| p.centroid);
        let owner = |l: &EdgeLine| (l.inliers.iter().filter(|&&i| i >= split).count() * 2 > l.inliers.len()) as usize;
        let pick =
            weld_edges::paper_select(&lines, centroids, owner).map_err(|e| PlanError::at(Stage::WeldEdges, e))?;
        self.clock.lap(Stage::WeldEdges);

        let inliers: [Vec<Vec3>; 2] = pick.map(|k| lines[k].inliers.iter().map(|&i| all[i]).collect());
        let union: Vec<Vec3> = inliers.iter().flatten().copied().collect();
        let frame = Frame::paper(&union);
        let degree = cfg.fit_degree as usize;
        let fits: [CurveFit; 2] = [0, 1]
            .map(|k| refit::fit(&inliers[k], &frame, degree))
            .into_iter()
            .collect::<Option<Vec<_>>>()
            .and_then(|v| v.try_into().ok())
            .ok_or_else(|| PlanError::at(Stage::Refit, "a weld edge has too few points for a least-squares fit"))?;
        self.clock.lap(Stage::Refit);

        let (e1, e2) = (&fits[0].curve, &fits[1].curve);
        let normal = weld_equation::paper_normal(e1, e2)
            .ok_or_else(|| PlanError::at(Stage::WeldEquation, "the weld edges are collinear; no plate normal"))?;
        let weld = self.weld(e1, e2, &normal, || weld_equation::lap_paper(e1, e2))?;
        let (s0, s1) = (weld.s_min, weld.s_max);
        self.clock.lap(Stage::WeldEquation);
        self.finish(weld, s0, s1, normal, &fits)
    }

    /// Stages 6 to 10 made robust.
    fn robust_seam(&mut self, workpiece: &Workpiece, edges: &[Vec<u32>; 2], normal: Vec3) -> Result<Seam, PlanError> {
        let cfg = &self.config.pipeline;
        let edge_points: [Vec<Vec3>; 2] = [self.points_of(&edges[0]), self.points_of(&edges[1])];
        // Each plate's lines are independent, and seeded per plate, so the
        // two run side by side with the same result.
        let (params_a, params_b) = (self.ransac_params(0), self.ransac_params(1));
        let (lines_a, lines_b) = rayon::join(
            || ransac::segment_lines(&edge_points[0], &params_a),
            || ransac::segment_lines(&edge_points[1], &params_b),
        );
        let lines: [Vec<EdgeLine>; 2] = [lines_a, lines_b];
        self.stats.edge_lines = lines[0].len() + lines[1].len();
        self.clock.lap(Stage::Ransac);

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
        self.clock.lap(Stage::WeldEdges);

        let boundary_of = |k: usize| {
            let line = &lines[k][pick[k]];
            let plane = &plates[k].plane;
            if !self.cloud.is_organized() {
                // Without a pixel grid the RANSAC inliers are the best samples.
                let samples = line
                    .inliers
                    .iter()
                    .map(|&i| {
                        let position = plane.project(&edge_points[k][i]);
                        BoundarySample { position, along: position.dot(&line.direction) }
                    })
                    .collect();
                return Boundary { samples, line_spacing_mm: 0.0 };
            }
            let direction = (line.direction - plane.normal * line.direction.dot(&plane.normal)).normalize();
            let mut outward = plane.normal.cross(&direction);
            if outward.dot(&(centroids[1 - k] - line.point)) < 0.0 {
                outward = -outward;
            }
            let edge = CoarseEdge { point: plane.project(&line.point), direction, outward };
            let params = BoundaryParams { band_mm: cfg.boundary_band_mm, on_plane_mm: cfg.on_plane_tolerance_mm };
            boundary::sample_boundary(&self.cloud, &plates[k].members, plane, &edge, &params)
        };
        let (boundary_a, boundary_b) = rayon::join(|| boundary_of(0), || boundary_of(1));
        let boundaries: [Boundary; 2] = [boundary_a, boundary_b];
        let samples: [Vec<Vec3>; 2] = boundaries.each_ref().map(|b| b.samples.iter().map(|s| s.position).collect());
        let union: Vec<Vec3> = samples.iter().flatten().copied().collect();
        let frame = Frame::principal(&union, &normal)
            .ok_or_else(|| PlanError::at(Stage::Refit, "the weld edge samples do not spread along a line"))?;
        let degree = cfg.fit_degree as usize;
        let fit_edge = |k: usize| {
            refit::fit_trimmed(&samples[k], &frame, degree, cfg.fit_trim_sigma).ok_or_else(|| {
                PlanError::at(
                    Stage::Refit,
                    format!("weld edge {} has {} boundary samples, too few to fit", k + 1, samples[k].len()),
                )
            })
        };
        let fits = [fit_edge(0)?, fit_edge(1)?];
        for (k, f) in fits.iter().enumerate() {
            tracing::debug!(
                edge = k + 1,
                samples = samples[k].len(),
                dropped = f.points_dropped,
                rms_mm = f.rms_mm,
                from_mm = f.curve.s_min,
                to_mm = f.curve.s_max,
                "weld edge refitted"
            );
        }
        self.clock.lap(Stage::Refit);

        let (e1, e2) = (&fits[0].curve, &fits[1].curve);
        let step = plates[1].plane.offset - plates[0].plane.offset;
        let weld = self.weld(e1, e2, &normal, || weld_equation::lap_root(e1, step, &normal))?;
        // The seam runs where both plates exist along it.
        let extent = |k: usize| {
            boundaries[k].extent(|s| frame.feature(&s.position)).ok_or_else(|| {
                PlanError::at(Stage::WeldEquation, format!("weld edge {} has no boundary sample", k + 1))
            })
        };
        let ((a0, a1), (b0, b1)) = (extent(0)?, extent(1)?);
        let (mut s0, mut s1) = (a0.max(b0), a1.min(b1));
        if self.request.joint == JointType::Lap {
            // The root lies a plate thickness below the edges the samples
            // saw; never plan a stretch of it the camera did not see.
            (s0, s1) = self.clip_to_view(&weld, s0, s1);
        }
        if s1 - s0 <= 0.0 {
            return Err(PlanError::at(Stage::WeldEquation, "the two weld edges do not overlap along the seam"));
        }
        self.clock.lap(Stage::WeldEquation);
        self.finish(weld, s0, s1, normal, &fits)
    }

    /// A groove cannot be deeper than the plates: where the surface they
    /// rest on is seen, the depth to it bounds the requested groove depth
    /// (which moves every waypoint along the normal, Eq. 32).
    fn check_groove_depth(&self, workpiece: &Workpiece) -> Result<(), PlanError> {
        let (JointType::VButt, Some(depth), Some(support)) =
            (self.request.joint, self.request.groove_depth_mm, workpiece.depth_to_support_mm)
        else {
            return Ok(());
        };
        if depth > support + GROOVE_DEPTH_TOLERANCE_MM {
            return Err(PlanError::at(
                Stage::Request,
                format!(
                    "groove depth {depth} mm is deeper than the plates: their top lies {support:.1} mm above \
                     the surface they rest on"
                ),
            ));
        }
        Ok(())
    }

    /// Every waypoint must be a place the robot can go: finite and within
    /// its reach. A waypoint beyond it means the pose, the hand-eye matrix
    /// or the cloud's units are wrong, and no trajectory is safer than one
    /// built on them.
    fn check_reach(&self, waypoints: &[Waypoint]) -> Result<(), PlanError> {
        let reach = self.config.robot_limits.max_reach_mm;
        let beyond =
            waypoints.iter().position(|w| !(w.position.iter().all(|c| c.is_finite()) && w.position.norm() <= reach));
        match beyond {
            None => Ok(()),
            Some(k) => Err(PlanError::at(
                Stage::Trajectory,
                format!(
                    "waypoint {k} lies {:.0} mm from the base origin, beyond robot.max_reach_mm ({reach} mm); \
                     check the pose, robot.hand_eye and the cloud's units",
                    waypoints[k].position.norm()
                ),
            )),
        }
    }

    /// The weld of the requested joint from its two edges (Eq. 32, 36);
    /// `lap` gives the lap weld, where the methods differ.
    fn weld(
        &self,
        e1: &SeamCurve,
        e2: &SeamCurve,
        normal: &Vec3,
        lap: impl FnOnce() -> SeamCurve,
    ) -> Result<SeamCurve, PlanError> {
        match self.request.joint {
            JointType::VButt => weld_equation::v_butt(e1, e2, self.request.groove_depth_mm.unwrap_or(0.0), normal),
            JointType::IButt => weld_equation::i_butt(e1, e2),
            JointType::Lap => Some(lap()),
        }
        .ok_or_else(|| PlanError::at(Stage::WeldEquation, "the weld edges were fitted in different frames"))
    }

    /// Narrows `[s0, s1]` to where `curve` projects inside the image, when
    /// the frame is the configured camera's pixel grid.
    fn clip_to_view(&self, curve: &SeamCurve, s0: f64, s1: f64) -> (f64, f64) {
        let camera = &self.config.camera;
        let grid = (camera.width_px as usize, camera.height_px as usize);
        if !self.cloud.is_organized() || (self.cloud.width(), self.cloud.height()) != grid {
            return (s0, s1);
        }
        // Half a pixel inside the outermost pixel centres.
        let (u_max, v_max) = (grid.0 as f64 - 1.5, grid.1 as f64 - 1.5);
        let inside = |s: f64| {
            let p = curve.at(s);
            camera
                .project([p.x, p.y, p.z])
                .is_some_and(|(u, v)| (0.5..=u_max).contains(&u) && (0.5..=v_max).contains(&v))
        };
        const STEP_MM: f64 = 0.02;
        let steps = ((s1 - s0) / STEP_MM).ceil().max(1.0) as usize;
        let ss: Vec<f64> = (0..=steps).map(|k| s0 + (s1 - s0) * k as f64 / steps as f64).collect();
        match (ss.iter().position(|&s| inside(s)), ss.iter().rposition(|&s| inside(s))) {
            (Some(first), Some(last)) => (ss[first], ss[last]),
            _ => (s0, s0),
        }
    }

    fn finish(
        &mut self,
        weld: SeamCurve,
        s0: f64,
        s1: f64,
        normal: Vec3,
        fits: &[CurveFit; 2],
    ) -> Result<Seam, PlanError> {
        let hand_eye = self.request.hand_eye.unwrap_or(self.config.hand_eye);
        let base_from_camera = self.request.pose.to_isometry(self.config.euler) * hand_eye;
        let t = &self.config.trajectory;
        let params = trajectory::TrajectoryParams {
            step_mm: self.request.step_mm.unwrap_or(t.step_mm),
            work_angle_deg: self.request.work_angle_deg.unwrap_or(t.work_angle_deg),
            travel_angle_deg: self.request.travel_angle_deg.unwrap_or(t.travel_angle_deg),
        };
        let (start, end) = trajectory::travel_order(&weld, s0, s1, &base_from_camera, self.request.start_near);
        let waypoints = trajectory::waypoints(&weld, start, end, &normal, &base_from_camera, &params);
        self.check_reach(&waypoints)?;
        let length_mm = waypoints.windows(2).map(|w| (w[1].position - w[0].position).norm()).sum();
        self.clock.lap(Stage::Trajectory);
        Ok(Seam {
            joint: self.request.joint,
            start_camera: weld.at(start),
            end_camera: weld.at(end),
            normal_camera: normal,
            length_mm,
            waypoints,
            edge_fit_rms_mm: [fits[0].rms_mm, fits[1].rms_mm],
            edge_samples: [fits[0].points_used, fits[1].points_used],
            edge_samples_dropped: [fits[0].points_dropped, fits[1].points_dropped],
        })
    }
}

/// The valid points of a frame and, among them, those the camera cannot
/// measure, by reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct MeasurableCounts {
    valid: usize,
    near: usize,
    far: usize,
    off_view: usize,
}

impl MeasurableCounts {
    fn unmeasurable(&self) -> usize {
        self.near + self.far + self.off_view
    }

    fn add(self, other: MeasurableCounts) -> MeasurableCounts {
        MeasurableCounts {
            valid: self.valid + other.valid,
            near: self.near + other.near,
            far: self.far + other.far,
            off_view: self.off_view + other.off_view,
        }
    }
}

/// Counts the valid points and those outside `volume`, in one pass.
fn count_measurable(cloud: &PointCloud, volume: &MeasurableVolume) -> MeasurableCounts {
    // Plain loops over chunks: as a per-point filter, map and reduce the
    // fold's state went through the stack each point and stalled on it,
    // 15 ms a frame in some builds instead of under one.
    cloud
        .points()
        .par_chunks(1 << 14)
        .map(|chunk| {
            let mut counts = MeasurableCounts::default();
            for p in chunk.iter().filter(|p| p[0].is_finite()) {
                counts.valid += 1;
                match volume.reject(p) {
                    None => {}
                    Some(Unmeasurable::Near) => counts.near += 1,
                    Some(Unmeasurable::Far) => counts.far += 1,
                    Some(Unmeasurable::OffView) => counts.off_view += 1,
                }
            }
            counts
        })
        .reduce(MeasurableCounts::default, MeasurableCounts::add)
}

/// A copy of `cloud` with the points outside `volume` made invalid.
fn without_unmeasurable(cloud: &PointCloud, volume: &MeasurableVolume) -> PointCloud {
    let points = cloud
        .points()
        .par_iter()
        .map(|p| if volume.reject(p).is_none() { *p } else { crate::cloud::INVALID_POINT })
        .collect();
    if cloud.is_organized() {
        PointCloud::organized(cloud.width(), cloud.height(), points)
            .unwrap_or_else(|| PointCloud::unorganized(Vec::new()))
    } else {
        PointCloud::unorganized(points)
    }
}

/// The deepest groove a request may name, mm. Plates for single-sided
/// V-butt welds are rarely thicker than 50 mm; twice that is nonsense.
pub const MAX_GROOVE_DEPTH_MM: f64 = 100.0;

/// How much deeper than the measured plates a groove may be, mm: plane
/// offsets are fitted over thousands of points and agree to a tenth of a
/// millimetre, so this only absorbs fit noise.
const GROOVE_DEPTH_TOLERANCE_MM: f64 = 0.5;

fn validate(r: &PlanRequest, config: &Config) -> Result<(), PlanError> {
    use crate::config::{MAX_POSE_ANGLE_DEG, MAX_STEP_MM, MAX_TORCH_ANGLE_DEG, MIN_STEP_MM};
    let bad = |reason: String| Err(PlanError::at(Stage::Request, reason));
    let limits = &config.robot_limits;
    if !r.pose.is_finite() {
        return bad(format!("the robot pose has a non-finite value: {:?} {:?}", r.pose.xyz_mm, r.pose.angles_deg));
    }
    let [x, y, z] = r.pose.xyz_mm;
    let reach = (x * x + y * y + z * z).sqrt();
    if reach > limits.max_reach_mm {
        return bad(format!(
            "the robot pose lies {reach:.0} mm from the base origin, beyond robot.max_reach_mm ({} mm); \
             is it in millimetres?",
            limits.max_reach_mm
        ));
    }
    if let Some(a) = r.pose.angles_deg.iter().find(|a| a.abs() > MAX_POSE_ANGLE_DEG) {
        return bad(format!("the robot pose angle {a}° is beyond ±{MAX_POSE_ANGLE_DEG}°; are the angles in degrees?"));
    }
    if let Some(hand_eye) = &r.hand_eye {
        let offset = hand_eye.translation.vector.norm();
        if offset > limits.max_hand_eye_translation_mm {
            return bad(format!(
                "the hand-eye translation is {offset:.1} mm long, beyond robot.max_hand_eye_translation_mm ({} mm)",
                limits.max_hand_eye_translation_mm
            ));
        }
    }
    if let Some(p) = &r.start_near
        && !(p.iter().all(|c| c.is_finite()) && p.norm() <= limits.max_reach_mm)
    {
        return bad(format!(
            "start_near ({:.0}, {:.0}, {:.0}) mm lies beyond robot.max_reach_mm ({} mm)",
            p.x, p.y, p.z, limits.max_reach_mm
        ));
    }
    match (r.joint, r.groove_depth_mm) {
        (JointType::VButt, None) => return bad("a V-butt joint needs its groove depth".into()),
        (_, Some(d)) if !(d.is_finite() && (0.0..=MAX_GROOVE_DEPTH_MM).contains(&d)) => {
            return bad(format!("groove depth {d} mm is outside 0 to {MAX_GROOVE_DEPTH_MM} mm"));
        }
        _ => {}
    }
    if let Some(step) = r.step_mm
        && !(step.is_finite() && (MIN_STEP_MM..=MAX_STEP_MM).contains(&step))
    {
        return bad(format!("step {step} mm is outside {MIN_STEP_MM} to {MAX_STEP_MM} mm"));
    }
    for (name, v) in [("work angle", r.work_angle_deg), ("travel angle", r.travel_angle_deg)] {
        if let Some(a) = v
            && !(a.is_finite() && (-MAX_TORCH_ANGLE_DEG..=MAX_TORCH_ANGLE_DEG).contains(&a))
        {
            return bad(format!("{name} {a}° is outside ±{MAX_TORCH_ANGLE_DEG}°"));
        }
    }
    Ok(())
}
