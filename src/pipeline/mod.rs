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
//!    A tee's web on its flange leaves the paper's order here for
//!    [`fillet`]: its side faces, the roots where they meet the flange
//!    and where each root is seen (`tee.rs`), then stages 11 and 12.
//! 9. [`groove`]: what lies between a butt joint's edges: a V-groove's
//!    bevels and depth, a square gap, or a plate standing there (robust
//!    method only; it decides V or I for `auto`).
//! 10. [`weld_equation`]: the weld per joint type (Eq. 32 to 38).
//! 11. [`quality`]: the seam's figures against the gates (robust only).
//! 12. [`trajectory`]: sampling and the base frame (Eq. 42).
//!
//! Two methods run these stages: `paper.rs` as the paper writes them and
//! `robust.rs` with the rules that hold in real cells, each one plan read
//! top to bottom over a shared context (`context.rs`: the sanitised frame,
//! the clock, the counts). [`Planner::plan`] checks the request and picks the
//! method once.
//!
//! The pipeline does no I/O. Its loops run on the current rayon pool, so
//! the caller chooses the threads (the daemon installs a dedicated pool).

pub mod along_seam;
pub mod background;
pub mod boundary;
pub mod clustering;
mod context;
pub mod deadline;
pub mod edge_points;
pub mod fillet;
mod gather;
#[cfg(test)]
mod grid_exactness;
pub mod grid_search;
pub mod groove;
pub mod input;
pub mod neighbours;
pub mod orientation;
mod paper;
pub mod passes;
pub mod plane_points;
pub mod quality;
pub mod ransac;
pub mod refit;
pub mod regrid;
mod robust;
pub mod roi;
mod scale;
pub mod seam_process;
pub mod straightness;
pub mod survey;
mod tee;
pub mod trace;
pub mod trajectory;
pub mod view_border;
pub mod web_face;
pub mod weld_edges;
pub mod weld_equation;
pub mod workpieces;

use std::borrow::Cow;
use std::fmt;
use std::sync::OnceLock;

use nalgebra::Isometry3;

use crate::cloud::PointCloud;
use crate::config::{Config, Method};
use crate::geometry::Vec3;
use crate::geometry::pose::RobotPose;
use crate::joint::{JointType, RequestedJoint};

use context::Context;
pub use deadline::Deadline;
pub use input::{CloudFrame, Units};
use roi::Roi;
pub use trace::PlanTrace;
use trace::Tracer;
pub use trajectory::Waypoint;

pub use crate::rules::Stage;
use crate::rules::{self, Rule};

/// What the controller asks for.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    /// The joint type, or `auto` to decide it from the frame (robust
    /// method only).
    pub joint: RequestedJoint,
    /// Groove depth d of a V-butt joint, mm (Eq. 32). The paper's method
    /// needs it; the robust method measures it where the groove's faces
    /// are seen and checks a given one against the measurement.
    pub groove_depth_mm: Option<f64>,
    /// The robot flange pose when the frame was captured.
    pub pose: RobotPose,
    /// `End_T_Camera`, if not the configured one.
    pub hand_eye: Option<Isometry3<f64>>,
    pub step_mm: Option<f64>,
    pub work_angle_deg: Option<f64>,
    pub travel_angle_deg: Option<f64>,
    /// The waypoints start at the seam's end nearest this point (robot
    /// base frame, mm); else by [`trajectory::travel_order`]'s default. On
    /// a frame of several seams, the seam nearest it comes first, then
    /// each next the nearest to where the last one ends
    /// ([`trajectory::seam_order`]).
    pub start_near: Option<Vec3>,
    /// Return one seam only: the first of the order, which is the seam
    /// nearest `start_near` when it is given. The frame's other workpieces
    /// are still planned (so a refused nearest one does not hide the next)
    /// and their seams dropped; the unplanned ones are still named.
    pub one_seam: bool,
    /// The cloud's units: millimetres unless the caller says otherwise.
    pub units: Units,
    /// The cloud's frame; the camera's by default.
    pub cloud_frame: CloudFrame,
    /// Only the points inside this box are planned; `pipeline.roi` of the
    /// config when None.
    pub roi: Option<Roi>,
}

impl PlanRequest {
    /// A request with the configured defaults for everything optional.
    pub fn new(joint: impl Into<RequestedJoint>, groove_depth_mm: Option<f64>, pose: RobotPose) -> Self {
        PlanRequest {
            joint: joint.into(),
            groove_depth_mm,
            pose,
            hand_eye: None,
            step_mm: None,
            work_angle_deg: None,
            travel_angle_deg: None,
            start_near: None,
            one_seam: false,
            units: Units::Millimetres,
            cloud_frame: CloudFrame::Camera,
            roi: None,
        }
    }
}

/// Why no trajectory could be planned: the rule that refused, its stage,
/// and the reason with the figures it read; for a seam the planner found
/// but will not trust, the quality gate (the refusal's class the protocol
/// carries); or that the plan's time limit ran out ([`Deadline`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{stage} stage failed: {reason}")]
pub struct PlanError {
    pub stage: Stage,
    /// The decision that refused, from [`crate::rules`].
    pub rule: &'static Rule,
    pub reason: String,
    pub gate: Option<quality::Gate>,
    /// The plan was stopped at its [`Deadline`]: no finding about the
    /// frame, which may plan within a longer limit.
    pub out_of_time: bool,
}

impl PlanError {
    /// A refusal by `rule`, at its stage, of its gate class.
    pub fn by(rule: &'static Rule, reason: impl fmt::Display) -> Self {
        PlanError { stage: rule.stage, rule, reason: reason.to_string(), gate: rule.gate, out_of_time: false }
    }

    /// A refusal by `rule` found in `stage`, for the one rule checked at
    /// every stage's end, the plan's time limit
    /// ([`crate::rules::request::TIME_LIMIT`]): the rule is the same
    /// wherever the plan stops, and the stage says where that was.
    pub fn by_in(rule: &'static Rule, stage: Stage, reason: impl fmt::Display) -> Self {
        PlanError { stage, ..PlanError::by(rule, reason) }
    }

    /// A refusal by a quality gate.
    fn refused(failure: &quality::GateFailure) -> Self {
        PlanError { gate: Some(failure.gate), ..PlanError::by(failure.rule, &failure.message) }
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
    /// The joint planned: the one requested, or the one `auto` found.
    pub joint: JointType,
    /// What the robust method saw that makes it this joint: the plates'
    /// layers and, for a butt joint, what lies between the edges.
    pub joint_evidence: Option<String>,
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
    /// How much of the joint the trajectory covers and on what evidence;
    /// the robust method measures it, the paper's has no such figure.
    pub coverage: Option<SeamCoverage>,
    /// The seam's quality figures (robust method).
    pub quality: Option<quality::SeamQuality>,
    /// The gates the seam failed that `quality.warn_only` makes warnings.
    pub warnings: Vec<quality::GateFailure>,
    /// The joint's figures at each waypoint, in their order (robust
    /// method, butt joints and laps; empty otherwise).
    pub along_seam: Vec<along_seam::JointFigures>,
    /// The weld process at each waypoint, where `process.procedure` is
    /// configured.
    pub process: Option<seam_process::SeamProcess>,
}

/// How much of the visible joint a seam spans, and how much of the seam
/// its weld edges were seen along (issue 11: "report its coverage").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeamCoverage {
    /// The fraction of the seam's length within a scan line (or strip) of
    /// a boundary sample of each weld edge ([`boundary::coverage`]).
    pub edge: [f64; 2],
    /// The fraction of the visible joint the seam spans: the stretch along
    /// the seam where both plates are seen beside it (each plate's points
    /// inside its weld edge, widened by the rim the plane criterion trims;
    /// for a lap, where the root is in view). A seam that stops short of
    /// where both plates' evidence ends scores below 1.
    pub joint: f64,
    /// The visible joint's length, mm.
    pub visible_joint_mm: f64,
    /// How much of the seam runs beyond the visible joint, mm: beyond
    /// where both plates are seen, no weld has evidence.
    pub beyond_mm: f64,
}

/// What the robust method adds to a seam beyond its geometry: coverage,
/// quality figures and the warnings of gates that only warn.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct SeamAssessment {
    pub joint_evidence: Option<String>,
    pub coverage: Option<SeamCoverage>,
    pub quality: Option<quality::SeamQuality>,
    pub warnings: Vec<quality::GateFailure>,
}

/// A joint seen in the frame for which no seam is returned, and why: the
/// root of a tee the web hides, or one workpiece of several whose seam
/// failed a stage or a gate while the others planned. A frame of one
/// joint that cannot be planned is a [`PlanError`], not a plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Unplanned {
    /// The joint, where the planner could tell it.
    pub joint: Option<JointType>,
    /// Where in the camera frame the joint lies (its plates' middle), so
    /// a person can tell which one is meant.
    pub near_camera: Option<Vec3>,
    /// The stage, the reason and the gate, as a refusal would give them.
    pub reason: PlanError,
}

/// The result of planning one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub method: Method,
    pub seams: Vec<Seam>,
    /// The joints seen but not planned, each with its reason.
    pub unplanned: Vec<Unplanned>,
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

    /// Runs the pipeline on `cloud`, in the units and frame the request
    /// names (camera frame and millimetres by default).
    ///
    /// First, timed as the input stage with the screening that follows,
    /// `input::prepare` brings the cloud into the camera frame in
    /// millimetres, `roi::crop` drops the points outside the region of
    /// interest (the request's, else the config's), then `regrid::prepare`
    /// puts a raw export that lost its grid back on the camera's and takes
    /// an organized frame's own intrinsics for another camera's frame.
    /// Each step that changes the cloud makes a copy of it, which the
    /// caller's cloud is held beside; [`Planner::plan_owned`] does not.
    ///
    /// The method is chosen here, once: `paper.rs` and `robust.rs` each
    /// run the whole way through.
    pub fn plan(&self, cloud: &PointCloud, request: &PlanRequest) -> Result<Plan, PlanError> {
        self.run(Cow::Borrowed(cloud), request, Tracer::off(), Deadline::NONE)
    }

    /// [`Planner::plan`] (of a borrowed cloud) or [`Planner::plan_owned`]
    /// (of an owned one), stopped and refused once `deadline` passes
    /// ([`PlanError::out_of_time`]). A plan that ends in time is the same,
    /// byte for byte.
    pub fn plan_until(
        &self,
        cloud: Cow<'_, PointCloud>,
        request: &PlanRequest,
        deadline: Deadline,
    ) -> Result<Plan, PlanError> {
        self.run(cloud, request, Tracer::off(), deadline)
    }

    /// [`Planner::plan`] of a cloud the caller no longer needs: it is
    /// converted (units, frame, the points the camera cannot measure) in
    /// place, and dropped once re-gridded, so a large frame is not held
    /// twice (issue 11's memory bound: a 2.3 MP frame in metres peaked at
    /// 3.7 times its raw size with its copy). The plan is the same, byte
    /// for byte.
    pub fn plan_owned(&self, cloud: PointCloud, request: &PlanRequest) -> Result<Plan, PlanError> {
        self.run(Cow::Owned(cloud), request, Tracer::off(), Deadline::NONE)
    }

    /// [`Planner::plan`], recording what each stage found ([`PlanTrace`]),
    /// and on a refusal the stage and reason beside everything gathered
    /// up to it.
    pub fn plan_traced(&self, cloud: &PointCloud, request: &PlanRequest) -> (Result<Plan, PlanError>, PlanTrace) {
        self.plan_traced_until(cloud, request, Deadline::NONE)
    }

    /// [`Planner::plan_traced`] within `deadline`, as [`Planner::plan_until`].
    pub fn plan_traced_until(
        &self,
        cloud: &PointCloud,
        request: &PlanRequest,
        deadline: Deadline,
    ) -> (Result<Plan, PlanError>, PlanTrace) {
        let mut trace = PlanTrace::new(request.joint.given(), request.groove_depth_mm, self.config.pipeline.method);
        let result = self.run(Cow::Borrowed(cloud), request, Tracer::on(&mut trace), deadline);
        trace.refusal = result.as_ref().err().cloned();
        (result, trace)
    }

    fn run(
        &self,
        cloud: Cow<'_, PointCloud>,
        request: &PlanRequest,
        tracer: Tracer,
        deadline: Deadline,
    ) -> Result<Plan, PlanError> {
        validate(request, &self.config)?;
        let clock = context::Clock::start(deadline);
        let converted = input::prepare(cloud, request, &self.config)?;
        deadline.check(Stage::Input)?;
        let cropped = match self.region_of_interest(request)? {
            Some(roi) => {
                let kept = roi::crop(&converted, &roi, self.box_from_camera(request, &roi).as_ref())
                    .map_err(|e| PlanError::by(&rules::input::TOO_FEW_POINTS_IN_REGION, e))?;
                // The whole cloud is not needed past here.
                drop(converted);
                Cow::Owned(kept)
            }
            None => converted,
        };
        let input = regrid::prepare(&self.config.camera, cropped);
        deadline.check(Stage::Input)?;
        let other_camera;
        let config = match input.camera {
            Some(camera) => {
                other_camera = Config { camera, ..self.config.clone() };
                &other_camera
            }
            None => &self.config,
        };
        let mut tracer = tracer;
        let (frame, valid_points) = context::sanitise(config, input.cloud, request, &mut tracer)?;
        let view_border = OnceLock::new();
        let ctx = Context::new(config, &frame, request, clock, tracer, &view_border, valid_points)?;
        match self.config.pipeline.method {
            Method::Paper => paper::plan(ctx),
            Method::Robust => robust::plan(ctx),
        }
    }
}

impl Planner {
    /// The request's region of interest, else the config's, if any.
    fn region_of_interest(&self, request: &PlanRequest) -> Result<Option<Roi>, PlanError> {
        match request.roi {
            Some(roi) => Ok(Some(roi)),
            None => self
                .config
                .pipeline
                .region_of_interest()
                .map_err(|e| PlanError::by(&rules::request::REGION_OF_INTEREST_INVALID, e)),
        }
    }

    /// The transform from the camera frame into `roi`'s: none for a
    /// camera-frame box, `Base_T_End · End_T_Camera` at capture (Eq. 42)
    /// for a base-frame one.
    fn box_from_camera(&self, request: &PlanRequest, roi: &Roi) -> Option<Isometry3<f64>> {
        match roi.frame() {
            CloudFrame::Camera => None,
            CloudFrame::Base => {
                Some(request.pose.to_isometry(self.config.euler) * request.hand_eye.unwrap_or(self.config.hand_eye))
            }
        }
    }
}

/// The deepest groove a request may name, mm. Plates for single-sided
/// V-butt welds are rarely thicker than 50 mm; twice that is nonsense.
pub const MAX_GROOVE_DEPTH_MM: f64 = 100.0;

fn validate(r: &PlanRequest, config: &Config) -> Result<(), PlanError> {
    use crate::config::{MAX_POSE_ANGLE_DEG, MAX_STEP_MM, MAX_TORCH_ANGLE_DEG, MIN_STEP_MM};
    use rules::request::{
        GROOVE_DEPTH_NOT_GIVEN, GROOVE_DEPTH_OUT_OF_RANGE, HAND_EYE_BEYOND_LIMIT, JOINT_BEYOND_METHOD,
        POSE_BEYOND_ROBOT, START_BEYOND_ROBOT, STEP_OUT_OF_RANGE, TORCH_ANGLE_OUT_OF_RANGE,
    };
    let bad = |rule: &'static Rule, reason: String| Err(PlanError::by(rule, reason));
    let limits = &config.robot_limits;
    if !r.pose.is_finite() {
        return bad(
            &POSE_BEYOND_ROBOT,
            format!("the robot pose has a non-finite value: {:?} {:?}", r.pose.xyz_mm, r.pose.angles_deg),
        );
    }
    let [x, y, z] = r.pose.xyz_mm;
    let reach = (x * x + y * y + z * z).sqrt();
    if reach > limits.max_reach_mm {
        return bad(
            &POSE_BEYOND_ROBOT,
            format!(
                "the robot pose lies {reach:.0} mm from the base origin, beyond robot.max_reach_mm ({} mm); \
             is it in millimetres?",
                limits.max_reach_mm
            ),
        );
    }
    if let Some(a) = r.pose.angles_deg.iter().find(|a| a.abs() > MAX_POSE_ANGLE_DEG) {
        return bad(
            &POSE_BEYOND_ROBOT,
            format!("the robot pose angle {a}° is beyond ±{MAX_POSE_ANGLE_DEG}°; are the angles in degrees?"),
        );
    }
    if let Some(hand_eye) = &r.hand_eye {
        let offset = hand_eye.translation.vector.norm();
        if offset > limits.max_hand_eye_translation_mm {
            return bad(
                &HAND_EYE_BEYOND_LIMIT,
                format!(
                    "the hand-eye translation is {offset:.1} mm long, beyond robot.max_hand_eye_translation_mm ({} mm)",
                    limits.max_hand_eye_translation_mm
                ),
            );
        }
    }
    if let Some(p) = &r.start_near
        && !(p.iter().all(|c| c.is_finite()) && p.norm() <= limits.max_reach_mm)
    {
        return bad(
            &START_BEYOND_ROBOT,
            format!(
                "start_near ({:.0}, {:.0}, {:.0}) mm lies beyond robot.max_reach_mm ({} mm)",
                p.x, p.y, p.z, limits.max_reach_mm
            ),
        );
    }
    let paper = config.pipeline.method == crate::config::Method::Paper;
    match (r.joint, r.groove_depth_mm) {
        (RequestedJoint::Type(joint), _) if paper && !joint.is_planned_by_the_paper() => {
            return bad(
                &JOINT_BEYOND_METHOD,
                format!(
                    "the paper's method plans butt and lap joints only, not {joint} (it has no fillet); tee joints \
                 need pipeline.method = \"robust\""
                ),
            );
        }
        (RequestedJoint::Auto | RequestedJoint::OneOf(_), _) if paper => {
            return bad(
                &JOINT_BEYOND_METHOD,
                format!(
                    "the paper's method plans the joint type it is given; `{}` needs pipeline.method = \"robust\"",
                    r.joint
                ),
            );
        }
        (RequestedJoint::Type(JointType::VButt), None) if paper => {
            return bad(
                &GROOVE_DEPTH_NOT_GIVEN,
                "the paper's method needs a V-butt joint's groove depth (the robust method measures it)".into(),
            );
        }
        (_, Some(d)) if !(d.is_finite() && (0.0..=MAX_GROOVE_DEPTH_MM).contains(&d)) => {
            return bad(
                &GROOVE_DEPTH_OUT_OF_RANGE,
                format!("groove depth {d} mm is outside 0 to {MAX_GROOVE_DEPTH_MM} mm"),
            );
        }
        _ => {}
    }
    if let Some(step) = r.step_mm
        && !(step.is_finite() && (MIN_STEP_MM..=MAX_STEP_MM).contains(&step))
    {
        return bad(&STEP_OUT_OF_RANGE, format!("step {step} mm is outside {MIN_STEP_MM} to {MAX_STEP_MM} mm"));
    }
    for (name, v) in [("work angle", r.work_angle_deg), ("travel angle", r.travel_angle_deg)] {
        if let Some(a) = v
            && !(a.is_finite() && (-MAX_TORCH_ANGLE_DEG..=MAX_TORCH_ANGLE_DEG).contains(&a))
        {
            return bad(&TORCH_ANGLE_OUT_OF_RANGE, format!("{name} {a}° is outside ±{MAX_TORCH_ANGLE_DEG}°"));
        }
    }
    Ok(())
}
