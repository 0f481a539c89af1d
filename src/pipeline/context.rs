//! What the paper's method ([`super::paper`]) and the robust method
//! ([`super::robust`]) share while they plan one frame: the configuration
//! and request, the frame without the points the camera cannot measure, the
//! clock that times each stage and the point counts. Also the steps both
//! methods take the same way: the input check, the plane clusters' areas,
//! the plate labels, the weld per joint type and the trajectory at the end.

use std::sync::OnceLock;
use std::time::Instant;

use nalgebra::{Isometry3, Point3};

use rayon::prelude::*;

use crate::cloud::PointCloud;
use crate::config::{Config, Method, PointDensity};
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;

use super::along_seam;
use super::background::{self, PlaneCluster, Workpiece};
use super::edge_points::{self, EdgeCriterion};
use super::neighbours::NeighbourSearch;
use super::plane_points::PlanePoints;
use super::ransac::RansacParams;
use super::refit::{CurveFit, SeamCurve};
use super::scale::{self, Scale};
use super::seam_process;
use super::trace::Tracer;
use super::trajectory::{self, Waypoint};
use super::view_border::ViewBorder;
use super::weld_equation;
use crate::process::clearance::Obstacles;
use crate::rules;

use super::{Deadline, Plan, PlanError, PlanRequest, PlanStats, Seam, SeamAssessment, Stage, StageTimings, Unplanned};

mod camera_grid;
mod screen;

pub(super) use camera_grid::CameraGrid;
pub(super) use screen::sanitise;

/// A seam's two fitted features as it reports them: its weld edges' fits,
/// or a fillet root's web face and flange.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct EdgeFigures {
    pub rms_mm: [f64; 2],
    pub samples: [usize; 2],
    pub dropped: [usize; 2],
}

impl EdgeFigures {
    pub(super) fn of(fits: &[CurveFit; 2]) -> Self {
        EdgeFigures {
            rms_mm: fits.each_ref().map(|f| f.rms_mm),
            samples: fits.each_ref().map(|f| f.points_used),
            dropped: fits.each_ref().map(|f| f.points_dropped),
        }
    }
}

/// The fewest plane points a cluster may have. Clusters below a few dozen
/// points cannot reach the area limit (`pipeline.min_plane_area_mm2`) at any
/// working distance, so dropping them early only saves work.
pub(super) const MIN_CLUSTER_POINTS: usize = 30;

/// How much deeper than the measured plates a groove may be, mm: plane
/// offsets are fitted over thousands of points and agree to a tenth of a
/// millimetre, so this only absorbs fit noise.
const GROOVE_DEPTH_TOLERANCE_MM: f64 = 0.5;

/// The step at which a lap root is tested against the image border, mm
/// along the seam: a fiftieth of a millimetre is far below the waypoint
/// step, so the clipped ends are exact to well within the plan's accuracy.
const VIEW_CLIP_STEP_MM: f64 = 0.02;

/// Measures the wall time of each stage: every lap charges the time since
/// the previous one to the stage just finished (added up when a stage
/// runs again, for the next workpiece of a frame).
///
/// It also carries the plan's [`Deadline`]: every lap checks it, so a plan
/// past its time limit stops at the end of the stage it was in.
pub(super) struct Clock {
    timings: StageTimings,
    last: Instant,
    pub(super) deadline: Deadline,
}

impl Clock {
    pub(super) fn start(deadline: Deadline) -> Self {
        Clock { timings: StageTimings::default(), last: Instant::now(), deadline }
    }

    /// Charges the time since the last lap to `stage`; the refusal of a
    /// plan whose time limit has passed.
    pub(super) fn lap(&mut self, stage: Stage) -> Result<(), PlanError> {
        let now = Instant::now();
        self.charge(stage, (now - self.last).as_secs_f64() * 1e3);
        self.last = now;
        self.deadline.check(stage)
    }

    /// What each stage was charged.
    pub(super) fn into_timings(self) -> StageTimings {
        self.timings
    }

    /// Starts the next lap now: a workpiece's clock is made before its
    /// work is scheduled, and must not charge the wait to its first stage.
    pub(super) fn restart(&mut self) {
        self.last = Instant::now();
    }

    /// Ends the lap of the workpieces planned side by side, whose own
    /// clocks timed `beside`: the wall time since the last lap is shared
    /// among their stages ([`share_wall_time`]).
    pub(super) fn lap_beside<'t>(&mut self, beside: impl IntoIterator<Item = &'t StageTimings>) {
        let now = Instant::now();
        let wall = (now - self.last).as_secs_f64() * 1e3;
        for (stage, ms) in share_wall_time(wall, beside).stages {
            self.charge(stage, ms);
        }
        self.last = now;
    }

    /// Adds `ms` to `stage`: a stage that runs once per workpiece is
    /// charged their sum.
    fn charge(&mut self, stage: Stage, ms: f64) {
        match self.timings.stages.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, total)) => *total += ms,
            None => self.timings.stages.push((stage, ms)),
        }
    }
}

/// `wall_ms` of work done side by side, shared among the stages of
/// `beside` in proportion to each stage's time summed over them: the
/// shares add up to the wall time, and each says where the cores' time
/// went. With no stage timed, the time is the background stage's, where
/// each workpiece's planning starts.
fn share_wall_time<'t>(wall_ms: f64, beside: impl IntoIterator<Item = &'t StageTimings>) -> StageTimings {
    let mut summed = StageTimings::default();
    for (stage, ms) in beside.into_iter().flat_map(|t| &t.stages) {
        match summed.stages.iter_mut().find(|(s, _)| s == stage) {
            Some((_, total)) => *total += ms,
            None => summed.stages.push((*stage, *ms)),
        }
    }
    let cpu_ms = summed.total_ms();
    if cpu_ms <= 0.0 {
        return StageTimings { stages: vec![(Stage::Background, wall_ms)] };
    }
    for (_, ms) in &mut summed.stages {
        *ms *= wall_ms / cpu_ms;
    }
    summed
}

/// One frame being planned: the inputs and what both methods record.
pub(super) struct Context<'a> {
    pub config: &'a Config,
    pub request: &'a PlanRequest,
    /// The frame without the points the camera cannot measure. Held
    /// outside the context (by the planner), so the stages' borrows of it
    /// leave the context free to record each workpiece's progress.
    pub cloud: &'a PointCloud,
    pub clock: Clock,
    pub stats: PlanStats,
    /// The radius and spacing the frame is planned at: the camera's until
    /// [`Context::measure_scale`] measures the cloud.
    pub scale: Scale,
    /// What each stage found, when the caller asked for it.
    pub trace: Tracer<'a>,
    /// The image's border as the cloud's rays show it, read the first time
    /// a stage asks ([`Context::view_border`]). Held by the planner, so
    /// every workpiece's context of one frame shares it.
    view_border: &'a OnceLock<Option<ViewBorder>>,
}

impl<'a> Context<'a> {
    /// The context of a frame [`sanitise`] passed, with `valid_points`
    /// valid points; the input stage ends here.
    pub(super) fn new(
        config: &'a Config,
        cloud: &'a PointCloud,
        request: &'a PlanRequest,
        clock: Clock,
        trace: Tracer<'a>,
        view_border: &'a OnceLock<Option<ViewBorder>>,
        valid_points: usize,
    ) -> Result<Self, PlanError> {
        let mut ctx = Context {
            config,
            request,
            cloud,
            clock,
            stats: PlanStats { valid_points, ..PlanStats::default() },
            scale: Scale::of_camera(config.pipeline.neighbour_radius_mm),
            trace,
            view_border,
        };
        ctx.clock.lap(Stage::Input)?;
        Ok(ctx)
    }

    /// Decides where the full-plane count comes from
    /// (`pipeline.point_density`) and, when it is the cloud itself,
    /// measures the cloud's spacing and derives the radius from it
    /// ([`super::scale`]). Returns whether the density is measured.
    pub(super) fn measure_scale(&mut self) -> Result<bool, PlanError> {
        let cfg = &self.config.pipeline;
        let measured = match cfg.point_density {
            PointDensity::Camera => false,
            PointDensity::Measured => true,
            PointDensity::Auto => !self.cloud.is_organized(),
        };
        if !measured {
            return Ok(false);
        }
        let spacing = scale::measure_spacing_until(self.cloud, cfg.neighbour_radius_mm, self.clock.deadline);
        // Counts cut short by the time limit mean nothing.
        self.clock.deadline.check(Stage::NeighbourIndex)?;
        let spacing = spacing.map_err(|e| {
            PlanError::by(
                &rules::neighbour_index::DENSITY_UNMEASURABLE,
                format!("{e}; the point density cannot be measured"),
            )
        })?;
        self.scale = Scale::of_spacing(spacing, cfg.neighbour_radius_mm);
        tracing::info!(
            spacing_mm = spacing.spacing_mm,
            measured_at_mm = spacing.measured_at_mm,
            median_neighbours = spacing.median_count,
            samples = spacing.samples,
            radius_mm = self.scale.radius_mm,
            configured_radius_mm = cfg.neighbour_radius_mm,
            organized = self.cloud.is_organized(),
            "point density measured from the cloud"
        );
        Ok(true)
    }

    /// The clusters as plane patches, those smaller than
    /// `pipeline.min_plane_area_mm2` left out; `area_per_point` is the
    /// surface one point stands for at a centroid with a normal.
    pub(super) fn planes_of(
        &self,
        members: Vec<Vec<u32>>,
        area_per_point: impl Fn(&Vec3, &Vec3) -> f64,
    ) -> Vec<PlaneCluster> {
        let min_area = self.config.pipeline.min_plane_area_mm2;
        background::describe(self.cloud, members, area_per_point)
            .into_iter()
            .filter(|c| c.area_mm2 >= min_area)
            .collect()
    }

    /// A groove cannot be deeper than the plates: where the surface they
    /// rest on is seen, the depth to it bounds the requested groove depth
    /// (which moves every waypoint along the normal, Eq. 32). A surface
    /// seen only between the plates is the joint's own floor, no bound:
    /// the groove-depth gate judges the request against the groove
    /// measured. `joint` is the joint known so far: the one requested, or
    /// the one the plates' layers showed.
    pub(super) fn check_groove_depth(&self, joint: Option<JointType>, workpiece: &Workpiece) -> Result<(), PlanError> {
        let (Some(JointType::VButt), Some(depth), Some(support), false) =
            (joint, self.request.groove_depth_mm, workpiece.depth_to_support_mm, workpiece.support_between_plates)
        else {
            return Ok(());
        };
        if depth > support + GROOVE_DEPTH_TOLERANCE_MM {
            return Err(PlanError::by(
                &rules::request::GROOVE_DEEPER_THAN_PLATES,
                format!(
                    "groove depth {depth} mm is deeper than the plates: their top lies {support:.1} mm above \
                     the surface they rest on"
                ),
            ));
        }
        Ok(())
    }

    /// The RANSAC parameters of the configuration, the seed moved by
    /// `seed_offset` so that runs meant to be independent are.
    pub(super) fn ransac_params(&self, seed_offset: u64) -> RansacParams {
        let cfg = &self.config.pipeline;
        RansacParams {
            // Edge points scatter across an edge by about a point spacing.
            distance_mm: self.scale.at_least_spacings(cfg.ransac_distance_mm, 1.0),
            iterations: cfg.ransac_iterations,
            min_line_points: cfg.ransac_min_line_points as usize,
            min_remaining_points: cfg.ransac_min_remaining_points as usize,
            max_lines: cfg.ransac_max_lines as usize,
            seed: cfg.ransac_seed.wrapping_add(seed_offset),
        }
    }

    /// The frame's points at `indices`.
    pub(super) fn points_of(&self, indices: &[u32]) -> Vec<Vec3> {
        indices.iter().map(|&i| vec3(&self.cloud.points()[i as usize])).collect()
    }

    /// Whether `p` lies inside the image: projected onto the configured
    /// camera's pixel grid when the frame is one, else within the border
    /// the cloud's rays span ([`ViewBorder`]) or at most `slack_mm` past
    /// it (what a downsampled cloud shows of its border lies up to half a
    /// voxel inside it). `None` for a frame of too few points to show a
    /// border.
    pub(super) fn in_view(&self, p: &Vec3, slack_mm: f64) -> Option<bool> {
        match self.camera_grid() {
            Some(grid) => Some(grid.in_view(p)),
            None => self.view_border().map(|border| border.outside_mm(p) <= slack_mm),
        }
    }

    /// Narrows `[s0, s1]` to where `curve` lies inside the image
    /// ([`Self::in_view`], `slack_mm` past a border read from the cloud); a
    /// frame that shows no border is left as it is.
    pub(super) fn clip_to_view(&self, curve: &SeamCurve, s0: f64, s1: f64, slack_mm: f64) -> (f64, f64) {
        if self.in_view(&curve.at(s0), slack_mm).is_none() {
            return (s0, s1);
        }
        let inside = |s: f64| self.in_view(&curve.at(s), slack_mm) == Some(true);
        let steps = ((s1 - s0) / VIEW_CLIP_STEP_MM).ceil().max(1.0) as usize;
        let ss: Vec<f64> = (0..=steps).map(|k| s0 + (s1 - s0) * k as f64 / steps as f64).collect();
        match (ss.iter().position(|&s| inside(s)), ss.iter().rposition(|&s| inside(s))) {
            (Some(first), Some(last)) => (ss[first], ss[last]),
            _ => (s0, s0),
        }
    }

    /// The point spacing near `p`, mm: measured from the cloud, or the
    /// camera's pixel footprint there.
    pub(super) fn spacing_at(&self, p: &Vec3) -> f64 {
        self.scale.spacing_at(&self.config.camera, p)
    }

    /// One context per workpiece of the frame, for planning them side by
    /// side: each starts from the frame's counts and the joint requested,
    /// with a clock of its own. The first records into the frame's trace,
    /// which keeps the first workpiece's stages; the others record nothing.
    pub(super) fn per_workpiece(&mut self, count: usize) -> Vec<Context<'_>> {
        let mut first_trace = Some(self.trace.reborrow());
        (0..count)
            .map(|_| Context {
                config: self.config,
                request: self.request,
                cloud: self.cloud,
                clock: Clock::start(self.clock.deadline),
                stats: self.stats.clone(),
                scale: self.scale,
                trace: first_trace.take().unwrap_or_else(Tracer::off),
                view_border: self.view_border,
            })
            .collect()
    }

    /// The same frame read under `request` instead of the one asked: under
    /// `auto`, the reading a tee's request makes, weighed for what its
    /// refusal says ([`super::robust`]'s tee reading). It records nothing in
    /// the frame's trace, starts from this context's counts and scale, and
    /// its clock keeps the plan's deadline.
    pub(super) fn under_request<'b>(&'b self, request: &'b PlanRequest) -> Context<'b> {
        Context {
            config: self.config,
            request,
            cloud: self.cloud,
            clock: Clock::start(self.clock.deadline),
            stats: self.stats.clone(),
            scale: self.scale,
            trace: Tracer::off(),
            view_border: self.view_border,
        }
    }

    /// The image's border the frame's points span, read once per frame
    /// however many workpieces ask; `None` for a frame of too few points.
    pub(super) fn view_border(&self) -> Option<&ViewBorder> {
        self.view_border.get_or_init(|| ViewBorder::of_cloud(self.cloud)).as_ref()
    }

    /// The configured camera's pixel grid, when the frame lies on it (a raw
    /// organized frame, or one re-gridded onto it).
    pub(super) fn camera_grid(&self) -> Option<CameraGrid<'_>> {
        let camera = &self.config.camera;
        let (width, height) = (camera.width_px as usize, camera.height_px as usize);
        (self.cloud.is_organized() && (self.cloud.width(), self.cloud.height()) == (width, height))
            .then(|| CameraGrid::for_camera(camera))
    }

    /// Section 5.1 for the paper's method: the one weld sampled into
    /// base-frame waypoints (Eq. 42), checked against the robot's reach,
    /// and the plan.
    pub(super) fn finish(self, method: Method, weld: PlannedWeld) -> Result<Plan, PlanError> {
        self.finish_several(method, vec![weld], Vec::new())
    }

    /// Section 5.1 for every weld of the frame, in the order
    /// [`trajectory::seam_order`] gives (one weld: the end
    /// [`trajectory::travel_order`] picks first, as always): each sampled
    /// into base-frame waypoints (Eq. 42) and checked against the robot's
    /// reach. With several, a seam beyond the reach joins `unplanned`, and
    /// `request.one_seam` keeps the first seam only. A frame whose every
    /// workpiece was refused is an error naming each.
    pub(super) fn finish_several(
        mut self,
        method: Method,
        welds: Vec<PlannedWeld>,
        mut unplanned: Vec<Unplanned>,
    ) -> Result<Plan, PlanError> {
        let base_from_camera = self.base_from_camera();
        let request = self.request;
        let order: Vec<(usize, bool)> = if welds.len() == 1 {
            let w = &welds[0];
            let (start, _) =
                trajectory::travel_order(&w.curve, w.span.0, w.span.1, &base_from_camera, request.start_near);
            vec![(0, start == w.span.0)]
        } else {
            let ends: Vec<[Vec3; 2]> = welds
                .iter()
                .map(|w| [w.span.0, w.span.1].map(|s| (base_from_camera * Point3::from(w.curve.at(s))).coords))
                .collect();
            trajectory::seam_order(&ends, request.start_near)
        };
        let several = welds.len() + unplanned.len() > 1;
        // The torch's obstacles: the whole frame, indexed once for all its
        // seams, and only when a procedure asks for them.
        let obstacles = std::cell::OnceCell::new();
        let mut seams = Vec::with_capacity(welds.len());
        for (k, forward) in order {
            let weld = &welds[k];
            let (s0, s1) = weld.span;
            let ends = if forward { (s0, s1) } else { (s1, s0) };
            match self.seam(weld, ends, &base_from_camera, &obstacles) {
                Ok(seam) => seams.push(seam),
                Err(reason) if several => unplanned.push(Unplanned {
                    joint: Some(weld.joint),
                    near_camera: Some(weld.curve.at(0.5 * (s0 + s1))),
                    reason,
                }),
                Err(reason) => return Err(reason),
            }
            if request.one_seam && !seams.is_empty() {
                break;
            }
        }
        self.clock.lap(Stage::Trajectory)?;
        if seams.is_empty() {
            return Err(none_planned(&unplanned));
        }
        Ok(Plan { method, seams, unplanned, stats: self.stats, timings: self.clock.timings })
    }

    /// `Base_T_End · End_T_Camera` at capture (Eq. 42).
    fn base_from_camera(&self) -> Isometry3<f64> {
        let hand_eye = self.request.hand_eye.unwrap_or(self.config.hand_eye);
        self.request.pose.to_isometry(self.config.euler) * hand_eye
    }

    /// One weld sampled from `start` to `end` into base-frame waypoints,
    /// checked against the robot's reach: the seam.
    fn seam(
        &mut self,
        weld: &PlannedWeld,
        (start, end): (f64, f64),
        base_from_camera: &Isometry3<f64>,
        obstacles: &std::cell::OnceCell<Obstacles<'a>>,
    ) -> Result<Seam, PlanError> {
        let t = &self.config.trajectory;
        let params = trajectory::TrajectoryParams {
            step_mm: self.request.step_mm.unwrap_or(t.step_mm),
            work_angle_deg: self.request.work_angle_deg.unwrap_or(t.work_angle_deg),
            travel_angle_deg: self.request.travel_angle_deg.unwrap_or(t.travel_angle_deg),
            fillet_work_angle_deg: t.fillet_work_angle_deg,
        };
        let mut waypoints = trajectory::waypoints(&weld.curve, start, end, &weld.torch_axis, base_from_camera, &params);
        if weld.traced {
            self.trace.record(|t| {
                let to_camera = |w: &Waypoint| base_from_camera.inverse_transform_point(&w.position.into()).coords;
                (t.waypoints_camera, t.base_from_camera) =
                    (waypoints.iter().map(to_camera).collect(), Some(*base_from_camera));
            });
        }
        self.check_reach(&waypoints)?;
        // The joint's figures at each waypoint, read on the weld edges'
        // axes (the weld lies along the normal from them, at the same
        // feature coordinate).
        let along_seam = match &weld.along {
            Some(evidence) => {
                let stations: Vec<f64> = trajectory::sample_features(&weld.curve, start, end, params.step_mm)
                    .into_iter()
                    .map(|s| evidence.axes.feature(&weld.curve.at(s)))
                    .collect();
                let grid = self.camera_grid();
                along_seam::measure(evidence, self.cloud, grid.as_ref(), &stations)
            }
            None => Vec::new(),
        };
        let process = self.config.process.procedure.as_ref().map(|procedure| {
            let places = seam_process::places(&weld.curve, start, end, params.step_mm, &weld.torch_axis);
            let obstacles = obstacles.get_or_init(|| seam_process::obstacles_of(self.cloud, &procedure.torch));
            let thickness = self.config.process.plate_thickness_mm;
            let process = seam_process::along(
                procedure,
                weld.joint,
                thickness,
                &places,
                &along_seam,
                obstacles,
                base_from_camera,
            );
            seam_process::orient(&mut waypoints, &places, &process, base_from_camera);
            process
        });
        let length_mm = waypoints.windows(2).map(|w| (w[1].position - w[0].position).norm()).sum();
        let assessment = weld.assessment.clone();
        Ok(Seam {
            joint: weld.joint,
            joint_evidence: assessment.joint_evidence,
            start_camera: weld.curve.at(start),
            end_camera: weld.curve.at(end),
            normal_camera: weld.normal,
            length_mm,
            waypoints,
            edge_fit_rms_mm: weld.edges.rms_mm,
            edge_samples: weld.edges.samples,
            edge_samples_dropped: weld.edges.dropped,
            coverage: assessment.coverage,
            quality: assessment.quality,
            warnings: assessment.warnings,
            along_seam,
            process,
        })
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
            Some(k) => Err(PlanError::by(
                &rules::trajectory::WAYPOINT_BEYOND_ROBOT,
                format!(
                    "waypoint {k} lies {:.0} mm from the base origin, beyond robot.max_reach_mm ({reach} mm); \
                     check the pose, robot.hand_eye and the cloud's units",
                    waypoints[k].position.norm()
                ),
            )),
        }
    }
}

/// The joint being planned, once it is known: `joint`, the one the request
/// names, or for `auto` the one the layers or the groove decided.
pub(super) fn decided(joint: Option<JointType>) -> Result<JointType, PlanError> {
    joint.ok_or_else(|| PlanError::by(&rules::request::JOINT_UNDECIDED, "the joint type was neither given nor decided"))
}

/// The weld of `joint` from its two edges: the midline shifted by the
/// groove depth `groove_depth_mm` for a V-butt joint (Eq. 32), the midline
/// for an I-butt joint (Eq. 36); `lap` gives the lap weld (Eq. 38), where
/// the methods differ.
pub(super) fn weld(
    joint: JointType,
    e1: &SeamCurve,
    e2: &SeamCurve,
    normal: &Vec3,
    groove_depth_mm: f64,
    lap: impl FnOnce() -> Result<SeamCurve, PlanError>,
) -> Result<SeamCurve, PlanError> {
    match joint {
        JointType::VButt => weld_equation::v_butt(e1, e2, groove_depth_mm, normal),
        JointType::IButt => weld_equation::i_butt(e1, e2),
        JointType::Lap => return lap(),
        // A tee's roots are the fillet stage's, not two edges' weld.
        JointType::TFillet => {
            return Err(PlanError::by(
                &rules::weld_equation::FILLET_NOT_FROM_EDGES,
                "a tee's fillet roots are not planned from two edges",
            ));
        }
    }
    .ok_or_else(|| {
        PlanError::by(&rules::weld_equation::EDGES_IN_DIFFERENT_AXES, "the weld edges were fitted in different axes")
    })
}

/// A workpiece's weld, checked, before its waypoints: the seams of a frame
/// are ordered first, and the order decides where each one starts.
#[derive(Debug, Clone)]
pub(super) struct PlannedWeld {
    joint: JointType,
    curve: SeamCurve,
    span: (f64, f64),
    /// The plate normal the seam reports (a fillet's: the flange's).
    normal: Vec3,
    /// Tool z before the work and travel angles: the plate normal, or a
    /// fillet's axis between web and flange.
    torch_axis: Vec3,
    edges: EdgeFigures,
    assessment: SeamAssessment,
    /// Whether the trace records this weld's waypoints (the trace holds
    /// one workpiece's stages).
    traced: bool,
    /// What the joint's figures along the seam are read from, where the
    /// seam's path measures them (a butt joint's or a lap's edges).
    along: Option<Box<along_seam::Evidence>>,
}

impl PlannedWeld {
    pub(super) fn new(
        joint: JointType,
        curve: SeamCurve,
        span: (f64, f64),
        normal: Vec3,
        edges: EdgeFigures,
        assessment: SeamAssessment,
    ) -> Self {
        PlannedWeld { joint, curve, span, normal, torch_axis: normal, edges, assessment, traced: true, along: None }
    }

    /// This weld with the torch along `axis` instead of the plate normal
    /// (a fillet's, between the web and the flange).
    pub(super) fn with_torch_axis(self, torch_axis: Vec3) -> Self {
        PlannedWeld { torch_axis, ..self }
    }

    /// This weld with the evidence its figures along the seam are read
    /// from.
    pub(super) fn with_along(self, evidence: along_seam::Evidence) -> Self {
        PlannedWeld { along: Some(Box::new(evidence)), ..self }
    }

    /// This weld, its waypoints traced or not.
    pub(super) fn traced(self, traced: bool) -> Self {
        PlannedWeld { traced, ..self }
    }
}

/// The refusal of a frame none of whose workpieces could be planned: the
/// first one's stage and gate, and every workpiece's reason.
fn none_planned(unplanned: &[Unplanned]) -> PlanError {
    let Some(first) = unplanned.first() else {
        return PlanError::by(&rules::background::NO_WORKPIECE_IN_VIEW, "no workpiece was found in the frame");
    };
    let each: Vec<String> = unplanned
        .iter()
        .enumerate()
        .map(|(k, u)| {
            let place =
                u.near_camera.map_or(String::new(), |p| format!(" near ({:.0}, {:.0}, {:.0}) mm", p.x, p.y, p.z));
            let joint = u.joint.map_or(String::new(), |j| format!(" ({j})"));
            format!("workpiece {}{joint}{place}: {}", k + 1, u.reason)
        })
        .collect();
    PlanError {
        stage: first.reason.stage,
        rule: first.reason.rule,
        reason: format!("none of the {} workpieces in view could be planned: {}", unplanned.len(), each.join("; ")),
        gate: first.reason.gate,
        out_of_time: first.reason.out_of_time,
    }
}

/// The edge points of both plates (Eq. 15 by `criterion`): each plate's
/// members classified against its neighbours of its own cluster label.
/// The frame's labels are read, not renumbered, so every workpiece of a
/// frame reads the same ones. Both methods take this step alike; only the
/// criterion differs.
pub(super) fn plate_edge_points(
    labels: &[u32],
    workpiece: &Workpiece,
    search: &NeighbourSearch,
    plane: &PlanePoints,
    criterion: &EdgeCriterion,
) -> [Vec<u32>; 2] {
    let plates = std::array::from_fn(|k| edge_points::Plate {
        labels,
        label: workpiece.plates[k].label,
        members: &workpiece.plates[k].members,
    });
    let mut edges = edge_points::edge_points_of_plates(search, plane, plates, criterion);
    if search.measured().is_some() {
        for (k, edge) in edges.iter_mut().enumerate() {
            let before = edge.len();
            let plate = &workpiece.plates[k];
            keep_one_sided(edge, labels, plate.label, &plate.plane.normal, search);
            tracing::debug!(plate = k + 1, before, after = edge.len(), "edge points one-sided");
        }
    }
    edges
}

/// Keeps the edge points whose same-plate neighbours do not surround them
/// ([`scale::surrounded`]).
///
/// A measured cloud's density is not smooth: noise and resampling leave
/// the odd patch of a plate with a fifth fewer points than its
/// surroundings, and the count criterion (Eq. 15) takes it for an edge. An
/// edge is where the plate ends, so its points have an empty side; such a
/// patch has neighbours all around.
fn keep_one_sided(edge: &mut Vec<u32>, labels: &[u32], label: u32, normal: &Vec3, search: &NeighbourSearch) {
    // A parallel filter keeps the order, so the edge points stay sorted.
    *edge = edge
        .par_iter()
        .copied()
        .filter(|&i| !scale::surrounded_by(search, i as usize, normal, |j| labels[j] == label))
        .collect();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_weld_waits_for_its_joint_type_and_no_workpiece_is_a_refusal() {
        let pose = crate::geometry::pose::RobotPose { xyz_mm: [0.0; 3], angles_deg: [0.0; 3] };
        let request = PlanRequest::new(crate::joint::RequestedJoint::Auto, None, pose);
        // `auto` before the layers and the groove decided it.
        let undecided = decided(request.joint.given()).unwrap_err();
        assert_eq!((undecided.rule.id, undecided.stage), ("joint.undecided", Stage::Request), "{undecided}");
        let none = none_planned(&[]);
        assert_eq!((none.rule.id, none.stage), ("workpiece.none_in_view", Stage::Background), "{none}");
        // Several refused: the first one's rule, each one's reason.
        let refusal = |rule| Unplanned { joint: None, near_camera: None, reason: PlanError::by(rule, "seen") };
        let both =
            none_planned(&[refusal(&rules::background::JOINT_NOT_REQUESTED), refusal(&rules::input::NO_VALID_POINT)]);
        assert_eq!((both.rule.id, both.gate), ("joint.not_requested", Some(crate::rules::Gate::JointMismatch)));
        assert!(both.reason.contains("none of the 2 workpieces"), "{both}");
    }

    #[test]
    fn a_weld_is_placed_from_two_edges_of_one_seam_only() {
        use super::super::refit::{self, SeamAxes};
        // One edge along camera x, the other along camera y: each fitted
        // in the axes its own points span.
        let line = |along: Vec3| (0..20).map(|k| Vec3::new(0.0, 0.0, 700.0) + along * k as f64).collect::<Vec<_>>();
        let fit = |points: Vec<Vec3>| refit::fit(&points, &SeamAxes::paper(&points), 1).expect("a line").curve;
        let (e1, e2) = (fit(line(Vec3::x())), fit(line(Vec3::y())));
        let normal = Vec3::z();
        let weld = |joint: JointType| super::weld(joint, &e1, &e2, &normal, 1.0, || Ok(e1.clone())).map(|_| ());
        let across = weld(JointType::IButt).unwrap_err();
        assert_eq!((across.rule.id, across.stage), ("seam.edges_in_different_axes", Stage::WeldEquation));
        assert_eq!(weld(JointType::VButt).unwrap_err().rule.id, "seam.edges_in_different_axes");
        let tee = weld(JointType::TFillet).unwrap_err();
        assert_eq!((tee.rule.id, tee.stage), ("joint.fillet_not_from_edges", Stage::WeldEquation), "{tee}");
        // A lap's weld is its own equation's (Eq. 38), not the midline.
        assert_eq!(weld(JointType::Lap), Ok(()));
    }

    #[test]
    fn side_by_side_wall_time_is_shared_by_each_stage_s_summed_time() {
        let timings = |stages: &[(Stage, f64)]| StageTimings { stages: stages.to_vec() };
        let beside = [
            timings(&[(Stage::Background, 1.0), (Stage::EdgePoints, 3.0)]),
            timings(&[(Stage::Background, 2.0), (Stage::EdgePoints, 1.0), (Stage::Refit, 3.0)]),
        ];
        // 10 ms of the cores' time done in 5 ms of wall time: each stage
        // charged half its summed time, in the order the stages first ran.
        let shared = share_wall_time(5.0, &beside);
        assert_eq!(shared.stages, [(Stage::Background, 1.5), (Stage::EdgePoints, 2.0), (Stage::Refit, 1.5)]);
        assert!((shared.total_ms() - 5.0).abs() < 1e-12);
        // Workpieces refused before any stage timed: the wait is the
        // background stage's.
        assert_eq!(share_wall_time(2.0, &[StageTimings::default()]).stages, [(Stage::Background, 2.0)]);
    }
}
