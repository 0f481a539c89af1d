//! The evaluation suite: a fixed, seeded set of scenes spread over the
//! camera's working range, and the framing measures that keep every scene
//! a fair test (enough seam and enough of both plates in view).
//!
//! Distances and tilts are stratified: each joint's scenes take every step
//! of 500..1000 mm and 0..30 degrees once, ends included. Everything else
//! is drawn at random, and a draw is kept only when the framing it asks
//! for (plates filling the view, the seam running off the image, plates
//! running off across the seam) is met.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::draw::Draw;
use super::faults::{self, Fault, FaultKind, PlateSide};
use super::render::CameraView;
use super::scene::{SurfaceKind, build_scene};
use super::truth::{observed_seam_range, visible_interval};
use super::{
    CameraPlacement, JointGeometry, NoiseSpec, PlateExtent, SceneSpec, default_base_from_workpiece, paper_hand_eye,
};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::geometry::pose::EulerConvention;
use crate::joint::JointType;

/// Scenes per joint type.
pub const SCENES_PER_JOINT: usize = 22;
/// The shortest observed seam a suite scene may have.
pub const MIN_OBSERVED_SEAM_MM: f64 = 80.0;
/// How much of each plate's top must be in view beside the seam.
pub const MIN_PLATE_IN_VIEW_MM: f64 = 40.0;

const SUITE_SEED: u64 = 0x5eed_2024;
const MAX_DRAWS: usize = 4000;
const MIN_DISTANCE_MM: f64 = 500.0;
const MAX_DISTANCE_MM: f64 = 1000.0;
const MAX_TILT_DEG: f64 = 30.0;
/// Pixel stride of the coarse ray grid that looks for the table.
const TABLE_PROBE_GRID: (usize, usize) = (48, 30);

/// How a scene sits in the image, as the suite's requirements need it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Framing {
    /// Length of the seam in view (both seam-side edges in the image).
    pub observed_seam_mm: f64,
    /// How much of each plate's top surface (A, B) is in view beside the
    /// seam, measured across it at the middle of the observed seam.
    pub plate_in_view_mm: [f64; 2],
    /// A plate's outer edge lies outside the image there.
    pub plate_runs_off_across: bool,
    /// The seam continues beyond the image at one end or both.
    pub seam_clipped: bool,
    /// Some of the table or a spacer is in line of sight, other than
    /// through the joint's gap.
    pub background_visible: bool,
}

/// Measures how `spec` is framed by `camera`.
pub fn framing(spec: &SceneSpec, camera: &CameraModel) -> Framing {
    framing_with(spec, camera, true)
}

/// [`framing`], skipping the ray casting for the background when
/// `probe_background` is false (it then reports the background visible).
fn framing_with(spec: &SceneSpec, camera: &CameraModel, probe_background: bool) -> Framing {
    let background = || !probe_background || background_visible(spec, camera);
    let physical = spec.seam_range();
    let Some([y0, y1]) = observed_seam_range(spec, camera) else {
        return Framing {
            observed_seam_mm: 0.0,
            plate_in_view_mm: [0.0, 0.0],
            plate_runs_off_across: true,
            seam_clipped: true,
            background_visible: background(),
        };
    };
    let middle = (y0 + y1) / 2.0;
    let in_view = plates_in_view(spec, camera, middle);
    let top_widths = plate_top_widths(spec);
    Framing {
        observed_seam_mm: y1 - y0,
        plate_in_view_mm: in_view,
        plate_runs_off_across: in_view[0] < top_widths[0] || in_view[1] < top_widths[1],
        seam_clipped: y0 > physical[0] || y1 < physical[1],
        background_visible: background(),
    }
}

/// Widths of the plates' top surfaces, from the seam-side edge outward.
fn plate_top_widths(spec: &SceneSpec) -> [f64; 2] {
    let edge = spec.joint.seam_edge_half_width();
    [spec.plate_a.width_mm - edge, spec.plate_b.width_mm - edge]
}

/// How far each plate's top is in view outward from its seam-side edge at
/// seam parameter `y`, up to the plate's outer edge.
pub(super) fn plates_in_view(spec: &SceneSpec, camera: &CameraModel, y: f64) -> [f64; 2] {
    let camera_from_workpiece = spec.workpiece_from_camera().inverse();
    let edges = spec.joint.seam_edges_xz();
    let top_widths = plate_top_widths(spec);
    let mut widths = [0.0; 2];
    for (side, (([x, z], outward), top_width)) in edges.iter().zip([-1.0, 1.0]).zip(top_widths).enumerate() {
        let origin = camera_from_workpiece.transform_point(&Vec3::new(*x, y, *z).into()).coords;
        let along = camera_from_workpiece.rotation * Vec3::new(outward, 0.0, 0.0);
        widths[side] = match visible_interval(camera, &origin, &along) {
            Some([lo, hi]) if lo <= 0.0 && hi >= 0.0 => hi.min(top_width),
            _ => 0.0,
        };
    }
    widths
}

/// Casts a coarse grid of rays and reports whether any reaches the table
/// or a spacer without passing through the joint's gap.
fn background_visible(spec: &SceneSpec, camera: &CameraModel) -> bool {
    let workpiece_from_camera = spec.workpiece_from_camera();
    let scene = build_scene(spec).transformed(&workpiece_from_camera.inverse());
    let view = CameraView::new(scene, camera, 90.0);
    let through_gap = gap_half_width(&spec.joint) + 1.0;
    let (nu, nv) = TABLE_PROBE_GRID;
    let (w, h) = (camera.width_px as f64 - 1.0, camera.height_px as f64 - 1.0);
    (0..nv).any(|j| {
        (0..nu).any(|i| {
            let (u, v) = (w * i as f64 / (nu - 1) as f64, h * j as f64 / (nv - 1) as f64);
            let Some(hit) = view.first_surface(u, v) else {
                return true;
            };
            if view.solids()[hit.solid].kind == SurfaceKind::Plate {
                return false;
            }
            let ray = workpiece_from_camera.rotation * Vec3::from(camera.ray(u, v));
            let origin = workpiece_from_camera.translation.vector;
            let at_plate_bottom = origin + ray * (-origin.z / ray.z);
            at_plate_bottom.x.abs() > through_gap
        })
    })
}

/// Half the width of the opening through the plates, if any.
fn gap_half_width(joint: &JointGeometry) -> f64 {
    match *joint {
        JointGeometry::IButt { gap_mm, .. } => gap_mm / 2.0,
        JointGeometry::VButt { root_gap_mm, .. } => root_gap_mm / 2.0,
        JointGeometry::Lap { .. } | JointGeometry::Tee { .. } | JointGeometry::Corner { .. } => 0.0,
    }
}

/// What a suite scene must show beyond the common requirements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Goal {
    /// Plates fill the whole view: no table in sight.
    FillView,
    /// The seam runs off the image, so the truth is clipped.
    SeamOffImage,
    /// A plate runs off the image across the seam.
    PlateOffAcross,
    /// No constraint beyond the common ones.
    Free,
}

impl Goal {
    fn for_index(k: usize) -> Goal {
        match k {
            0..=3 => Goal::FillView,
            4..=8 => Goal::SeamOffImage,
            9..=13 => Goal::PlateOffAcross,
            _ => Goal::Free,
        }
    }

    fn tag(self) -> &'static str {
        match self {
            Goal::FillView => "-fill",
            Goal::SeamOffImage => "-clipped",
            Goal::PlateOffAcross => "-wide",
            Goal::Free => "",
        }
    }

    fn met_by(self, f: &Framing) -> bool {
        let common =
            f.observed_seam_mm >= MIN_OBSERVED_SEAM_MM && f.plate_in_view_mm.iter().all(|w| *w >= MIN_PLATE_IN_VIEW_MM);
        common
            && match self {
                Goal::FillView => !f.background_visible,
                Goal::SeamOffImage => f.seam_clipped,
                Goal::PlateOffAcross => f.plate_runs_off_across,
                Goal::Free => true,
            }
    }
}

/// For lap joints: which plate the camera looks from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LapSide {
    Upper,
    Lower,
}

/// The fixed part of one suite scene; the rest is drawn.
#[derive(Debug, Clone, Copy)]
pub(super) struct ScenePlan {
    joint: JointType,
    index: usize,
    distance_mm: f64,
    tilt_deg: f64,
    goal: Goal,
    lap_side: Option<LapSide>,
    narrow_gap: bool,
    staggered: bool,
}

impl ScenePlan {
    pub(super) fn new(joint: JointType, joint_index: usize, k: usize, max_tilt_deg: f64) -> ScenePlan {
        let steps = (SCENES_PER_JOINT - 1) as f64;
        let goal = Goal::for_index(k);
        // The plates can only fill the view from close by, so those scenes
        // take the nearest distances; the others are permuted over the rest.
        let fill_count = 4;
        let distance_step = if goal == Goal::FillView {
            k
        } else {
            let rest = SCENES_PER_JOINT - fill_count;
            fill_count + ((k - fill_count) * 7 + joint_index * 3) % rest
        };
        let tilt_step = (k * 5 + joint_index * 7) % SCENES_PER_JOINT;
        ScenePlan {
            joint,
            index: k,
            distance_mm: MIN_DISTANCE_MM + (MAX_DISTANCE_MM - MIN_DISTANCE_MM) * distance_step as f64 / steps,
            tilt_deg: max_tilt_deg * tilt_step as f64 / steps,
            goal,
            lap_side: (joint == JointType::Lap).then_some(if k.is_multiple_of(2) {
                LapSide::Upper
            } else {
                LapSide::Lower
            }),
            narrow_gap: joint == JointType::IButt && k.is_multiple_of(3),
            staggered: k % 3 == 1,
        }
    }

    pub(super) fn name(&self) -> String {
        let joint = self.joint.dashed_name();
        let side = match self.lap_side {
            Some(LapSide::Upper) => "-upper-side",
            Some(LapSide::Lower) => "-lower-side",
            None => "",
        };
        format!("{joint}-{:02}-d{:.0}-t{:.0}{}{side}", self.index, self.distance_mm, self.tilt_deg, self.goal.tag())
    }

    pub(super) fn draw_joint(&self, rng: &mut ChaCha8Rng) -> JointGeometry {
        match self.joint {
            JointType::VButt => {
                let t = uniform(rng, 6.0, 12.0);
                JointGeometry::VButt {
                    thickness_mm: t,
                    groove_angle_deg: uniform(rng, 40.0, 70.0),
                    groove_depth_mm: uniform(rng, 3.0, t - 1.0),
                    root_gap_mm: uniform(rng, 0.0, 2.0),
                }
            }
            JointType::IButt => JointGeometry::IButt {
                thickness_mm: uniform(rng, 3.0, 12.0),
                gap_mm: if self.narrow_gap { uniform(rng, 0.5, 0.8) } else { uniform(rng, 0.8, 3.0) },
            },
            JointType::Lap => JointGeometry::Lap {
                lower_thickness_mm: uniform(rng, 3.0, 10.0),
                upper_thickness_mm: uniform(rng, 3.0, 10.0),
                overlap_mm: uniform(rng, 20.0, 60.0),
            },
            JointType::TFillet => draw_tee(rng),
        }
    }

    fn draw_plates(&self, rng: &mut ChaCha8Rng) -> [PlateExtent; 2] {
        let width_range = match self.goal {
            Goal::FillView => (200.0, 250.0),
            Goal::PlateOffAcross => (150.0, 250.0),
            _ => (60.0, 250.0),
        };
        let length_range = match self.goal {
            Goal::FillView | Goal::SeamOffImage => (300.0, 400.0),
            _ => (120.0, 400.0),
        };
        let a = PlateExtent {
            width_mm: uniform(rng, width_range.0, width_range.1),
            length_mm: uniform(rng, length_range.0, length_range.1),
            offset_mm: 0.0,
        };
        let b = if self.staggered {
            let shift = uniform(rng, 10.0, 60.0) * if rng.next_u32().is_multiple_of(2) { 1.0 } else { -1.0 };
            PlateExtent {
                width_mm: uniform(rng, width_range.0, width_range.1),
                length_mm: uniform(rng, length_range.0, length_range.1),
                offset_mm: shift,
            }
        } else {
            PlateExtent { width_mm: uniform(rng, width_range.0, width_range.1), ..a }
        };
        [a, b]
    }

    fn draw_placement(&self, seam_length: f64, rng: &mut ChaCha8Rng) -> CameraPlacement {
        let (azimuth, across) = match self.lap_side {
            Some(LapSide::Upper) => (uniform(rng, 120.0, 240.0), uniform(rng, -60.0, -5.0)),
            Some(LapSide::Lower) => (uniform(rng, -60.0, 60.0), uniform(rng, 5.0, 60.0)),
            None if self.goal == Goal::FillView => (uniform(rng, 0.0, 360.0), uniform(rng, -20.0, 20.0)),
            None => (uniform(rng, 0.0, 360.0), uniform(rng, -60.0, 60.0)),
        };
        let along_reach = if self.goal == Goal::SeamOffImage { 0.45 } else { 0.25 };
        CameraPlacement {
            distance_mm: self.distance_mm,
            tilt_deg: self.tilt_deg,
            tilt_azimuth_deg: azimuth,
            roll_deg: uniform(rng, 0.0, 360.0),
            target_offset_mm: [across, uniform(rng, -along_reach, along_reach) * seam_length],
        }
    }

    pub(super) fn draw(&self, seed: u64, rng: &mut ChaCha8Rng) -> SceneSpec {
        let joint = self.draw_joint(rng);
        let [plate_a, plate_b] = self.draw_plates(rng);
        let spacer_height_mm = uniform(rng, 20.0, 60.0);
        let mut spec = SceneSpec {
            joint,
            plate_a,
            plate_b,
            spacer_height_mm,
            placement: CameraPlacement::straight(self.distance_mm, self.tilt_deg),
            noise: NoiseSpec::default(),
            base_from_workpiece: default_base_from_workpiece(),
            hand_eye: paper_hand_eye(),
            euler: EulerConvention::Zyx,
            seed,
            faults: Vec::new(),
            others: Vec::new(),
        };
        let [y0, y1] = spec.seam_range();
        spec.placement = self.draw_placement(y1 - y0, rng);
        spec
    }
}

impl ScenePlan {
    /// Draws from stream `stream` of `base_seed` until the scene is valid
    /// and framed as its goal asks (the last draw after [`MAX_DRAWS`]).
    pub(super) fn draw_framed(&self, base_seed: u64, stream: u64, camera: &CameraModel) -> SceneSpec {
        self.draw_framed_reshaped(base_seed, stream, camera, |_, _| {})
    }

    /// [`ScenePlan::draw_framed`] with each draw reshaped by `reshape`
    /// (another cross-section, say) before its framing is judged; `reshape`
    /// draws from the same stream after the plan's own draw.
    pub(super) fn draw_framed_reshaped(
        &self,
        base_seed: u64,
        stream: u64,
        camera: &CameraModel,
        reshape: impl Fn(&mut SceneSpec, &mut ChaCha8Rng),
    ) -> SceneSpec {
        let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
        rng.set_stream(stream);
        let seed = base_seed.wrapping_add(stream);
        let draw = |rng: &mut ChaCha8Rng| {
            let mut spec = self.draw(seed, rng);
            reshape(&mut spec, rng);
            spec
        };
        let mut spec = draw(&mut rng);
        for _ in 1..MAX_DRAWS {
            let probe_background = self.goal == Goal::FillView;
            let framed = framing_with(&spec, camera, probe_background);
            if spec.validate().is_ok() && self.goal.met_by(&framed) {
                break;
            }
            spec = draw(&mut rng);
        }
        spec
    }

    /// Whether the plan asks for plates filling the view (no table seen).
    pub(super) fn fills_view(&self) -> bool {
        self.goal == Goal::FillView
    }
}

/// A tee's cross-section as issue 15 states its range: a web 4 to 12 mm
/// thick and 40 to 100 mm tall on a flange 6 to 16 mm thick.
pub(super) fn draw_tee(rng: &mut ChaCha8Rng) -> JointGeometry {
    JointGeometry::Tee {
        flange_thickness_mm: uniform(rng, 6.0, 16.0),
        web_thickness_mm: uniform(rng, 4.0, 12.0),
        web_height_mm: uniform(rng, 40.0, 100.0),
    }
}

pub(super) fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let unit = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    lo + (hi - lo) * unit
}

/// The evaluation scenes, named like `lap-07-d612-t18-lower-side`: joint,
/// index, distance, tilt, the framing asked for and, for laps, the side
/// the camera looks from. The same list on every call.
pub fn eval_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    let mut suite = Vec::with_capacity(3 * SCENES_PER_JOINT);
    for (j, joint) in JointType::ALL.into_iter().enumerate() {
        for k in 0..SCENES_PER_JOINT {
            let plan = ScenePlan::new(joint, j, k, MAX_TILT_DEG);
            let stream = (j * SCENES_PER_JOINT + k) as u64;
            let name = format!("{}{}", plan.name(), draw.suffix(false));
            suite.push((name, plan.draw_framed(draw.seed(SUITE_SEED), stream, &camera)));
        }
    }
    suite
}

/// Scenes per joint type of [`hard_suite`] drawn from their own seed and
/// named `-holdout` (the last of each joint's, free framing).
pub const HARD_HOLDOUT_PER_JOINT: usize = 4;
/// The hard suite's steepest tilt, degrees.
pub const HARD_MAX_TILT_DEG: f64 = 45.0;
/// The hard suite's depth sigma at the standoff, mm: stratified over this.
pub const HARD_DEPTH_SIGMA_MM: [f64; 2] = [0.05, 0.15];
/// The hard suite's dropout rates: stratified over this.
pub const HARD_DROPOUT_RATE: [f64; 2] = [0.003, 0.05];
const HARD_SEED: u64 = 0x4a2d_2026;
const HARD_HOLDOUT_SEED: u64 = 0x4a2d_0ff5;

/// The evaluation suite made hard, as issue 12 states its target: the same
/// strata and framings as [`eval_suite`] (22 scenes per joint), the
/// camera tilted 0 to 45 degrees, the depth sigma at the standoff 0.05 to
/// 0.15 mm and 0.3 to 5 % of the returns dropped, each stratified so its
/// ends are in the suite. Named `hard-` and the eval suite's name, with
/// the sigma (`-s0.15`) and the dropout percentage (`-dr5.0`). The last
/// [`HARD_HOLDOUT_PER_JOINT`] of each joint are drawn from their own seed
/// and named `-holdout`: nothing in the planner or its gates is to be
/// chosen by looking at them.
pub fn hard_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    let steps = (SCENES_PER_JOINT - 1) as f64;
    let mut suite = Vec::with_capacity(3 * SCENES_PER_JOINT);
    for (j, joint) in JointType::ALL.into_iter().enumerate() {
        for k in 0..SCENES_PER_JOINT {
            let plan = ScenePlan::new(joint, j, k, HARD_MAX_TILT_DEG);
            let holdout = k >= SCENES_PER_JOINT - HARD_HOLDOUT_PER_JOINT;
            let base_seed = draw.seed(if holdout { HARD_HOLDOUT_SEED } else { HARD_SEED });
            let mut spec = plan.draw_framed(base_seed, (j * SCENES_PER_JOINT + k) as u64, &camera);
            // Steps coprime with 22 visit every stratum once.
            let sigma_step = ((k * 3 + j * 5) % SCENES_PER_JOINT) as f64 / steps;
            let dropout_step = ((k * 13 + j * 7) % SCENES_PER_JOINT) as f64 / steps;
            let [s0, s1] = HARD_DEPTH_SIGMA_MM;
            let sigma = s0 + (s1 - s0) * sigma_step;
            let [d0, d1] = HARD_DROPOUT_RATE;
            spec.noise.dropout_rate = d0 + (d1 - d0) * dropout_step;
            spec.noise.depth_noise_scale = sigma / camera.depth_sigma(plan.distance_mm);
            let name = format!(
                "hard-{}-s{sigma:.2}-dr{:.1}{}",
                plan.name(),
                spec.noise.dropout_rate * 100.0,
                draw.suffix(holdout)
            );
            suite.push((name, spec));
        }
    }
    suite
}

/// Scenes of [`fault_suite`] per fault and joint type, and how many of
/// them (the last) are held out.
pub const FAULT_SCENES_PER_JOINT: usize = 4;
pub const FAULT_HOLDOUT_PER_JOINT: usize = 1;
const FAULT_SEED: u64 = 0xfa17_2026;
const FAULT_HOLDOUT_SEED: u64 = 0xfa17_0ff5;

/// Every fault of [`FaultKind::ALL`] on every joint type,
/// [`FAULT_SCENES_PER_JOINT`] scenes each: clean scenes drawn as the eval
/// suite's free ones (the whole of both plates' seam-side tops in view,
/// at least 80 mm of seam), the camera at 500 to 1000 mm and tilted 0 to
/// 30 degrees (spread so each fault and joint sees near and far, square and
/// tilted), with the fault drawn onto the seam in view. Named like
/// `fault-clamp-lap-02-d833-t10` (`-as-i-butt` for the joint a wrong
/// request names). The last [`FAULT_HOLDOUT_PER_JOINT`] of each fault and
/// joint are drawn from their own seed and named `-holdout`: nothing in
/// the planner or its gates is to be chosen by looking at them.
pub fn fault_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    let mut suite = Vec::new();
    for (f, kind) in FaultKind::ALL.into_iter().enumerate() {
        for (j, joint) in JointType::ALL.into_iter().enumerate() {
            for s in 0..FAULT_SCENES_PER_JOINT {
                let holdout = s >= FAULT_SCENES_PER_JOINT - FAULT_HOLDOUT_PER_JOINT;
                let base_seed = draw.seed(if holdout { FAULT_HOLDOUT_SEED } else { FAULT_SEED });
                let stream = ((f * 3 + j) * FAULT_SCENES_PER_JOINT + s) as u64;
                let last = (FAULT_SCENES_PER_JOINT - 1) as f64;
                let mut plan = ScenePlan::new(joint, j, SCENES_PER_JOINT - 1 - s, MAX_TILT_DEG);
                plan.goal = Goal::Free;
                let distance_step = ((s + f + 2 * j) % FAULT_SCENES_PER_JOINT) as f64 / last;
                let tilt_step = ((3 * s + f + j) % FAULT_SCENES_PER_JOINT) as f64 / last;
                plan.distance_mm = MIN_DISTANCE_MM + (MAX_DISTANCE_MM - MIN_DISTANCE_MM) * distance_step;
                plan.tilt_deg = MAX_TILT_DEG * tilt_step;
                let spec = draw_faulted(&plan, kind, s, base_seed, stream, &camera);
                let requested = match spec.requested_joint() {
                    r if r != joint => format!("-as-{}", r.dashed_name()),
                    _ => String::new(),
                };
                let name = format!(
                    "fault-{kind}-{}-{s:02}-d{:.0}-t{:.0}{requested}{}",
                    joint.dashed_name(),
                    plan.distance_mm,
                    plan.tilt_deg,
                    draw.suffix(holdout)
                );
                suite.push((name, spec));
            }
        }
    }
    suite
}

/// Draws a clean scene for `plan` with a `kind` fault on it until both are
/// valid and the scene is framed as the fault needs.
fn draw_faulted(
    plan: &ScenePlan,
    kind: FaultKind,
    index: usize,
    base_seed: u64,
    stream: u64,
    camera: &CameraModel,
) -> SceneSpec {
    let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
    rng.set_stream(stream);
    let seed = base_seed.wrapping_add(stream);
    let mut spec = plan.draw(seed, &mut rng);
    for _ in 0..MAX_DRAWS {
        spec = plan.draw(seed, &mut rng);
        if kind == FaultKind::TouchingPart {
            // The touched plate's outer edge must be in view.
            let narrow = uniform(&mut rng, 60.0, 110.0);
            if index.is_multiple_of(2) { spec.plate_b.width_mm = narrow } else { spec.plate_a.width_mm = narrow }
        }
        let Some(observed) = observed_seam_range(&spec, camera) else { continue };
        spec.faults = vec![draw_fault(kind, &spec, observed, index, &mut rng)];
        if kind == FaultKind::BarelyInView && faults::frame_barely_in_view(&mut spec, camera).is_err() {
            continue;
        }
        if spec.validate().is_ok() && fault_framing_ok(&spec, camera) {
            break;
        }
    }
    spec
}

/// The fault's parameters, drawn for the seam `observed` in view.
fn draw_fault(kind: FaultKind, spec: &SceneSpec, observed: [f64; 2], index: usize, rng: &mut ChaCha8Rng) -> Fault {
    let [y0, y1] = observed;
    let side = if index.is_multiple_of(2) { PlateSide::B } else { PlateSide::A };
    match kind {
        FaultKind::WrongJoint => {
            let others: Vec<JointType> = JointType::ALL.into_iter().filter(|j| *j != spec.joint.joint_type()).collect();
            Fault::WrongJoint { requested: others[index % others.len()] }
        }
        FaultKind::SeamDropout => {
            let length = uniform(rng, 15.0, 50.0);
            let start = uniform(rng, y0 + 10.0, (y1 - 10.0 - length).max(y0 + 10.0));
            Fault::SeamDropout { along_mm: [start, start + length], margin_mm: uniform(rng, 0.5, 4.0) }
        }
        FaultKind::Clamp => {
            let width = uniform(rng, 15.0, 40.0);
            Fault::Clamp {
                centre_mm: uniform(rng, y0 + 0.3 * (y1 - y0), y1 - 0.3 * (y1 - y0)),
                width_mm: width,
                height_mm: uniform(rng, 10.0, 40.0),
                half_reach_mm: uniform(rng, 40.0, 120.0),
            }
        }
        FaultKind::TackWelds => {
            let pitch = uniform(rng, 30.0, 80.0);
            Fault::TackWelds {
                first_mm: y0 + uniform(rng, 5.0, pitch),
                pitch_mm: pitch,
                length_mm: uniform(rng, 4.0, 10.0),
                crown_mm: uniform(rng, 0.5, 2.0),
                spread_mm: uniform(rng, 1.0, 3.0),
            }
        }
        FaultKind::Spatter => Fault::Spatter {
            seed: rng.next_u64(),
            count: 20 + (rng.next_u32() % 60) as usize,
            radius_mm: uniform(rng, 0.4, 1.2),
            spread_mm: spec.joint.seam_edge_half_width() + uniform(rng, 5.0, 30.0),
        },
        FaultKind::SpecularStreaks => Fault::SpecularStreaks {
            seed: rng.next_u64(),
            count: 1 + (rng.next_u32() % 4) as usize,
            length_mm: uniform(rng, 20.0, 120.0),
            width_px: uniform(rng, 1.0, 4.0),
            offset_mm: uniform(rng, 2.0, 15.0),
        },
        FaultKind::BarelyInView => Fault::BarelyInView { plate: side, in_view_mm: uniform(rng, 6.0, 25.0) },
        FaultKind::TouchingPart => {
            Fault::TouchingPart { plate: side, width_mm: uniform(rng, 40.0, 150.0), step_mm: uniform(rng, -2.0, 2.0) }
        }
        FaultKind::EdgeGlare => {
            let shortest = uniform(rng, 3.0, 10.0);
            Fault::EdgeGlare {
                seed: rng.next_u64(),
                band_mm: uniform(rng, 0.5, 2.5),
                run_mm: [shortest, shortest + uniform(rng, 5.0, 30.0)],
                share: uniform(rng, 0.15, 0.5),
            }
        }
    }
}

/// What a fault scene must show: at least [`MIN_OBSERVED_SEAM_MM`] of seam
/// and [`MIN_PLATE_IN_VIEW_MM`] of each plate, but for a plate barely in
/// view (within a millimetre of what the fault asks) and, for a touching
/// part, the touched plate's whole top (its outer edge, where the part
/// abuts, in view).
pub(super) fn fault_framing_ok(spec: &SceneSpec, camera: &CameraModel) -> bool {
    let f = framing_with(spec, camera, false);
    let index = |plate: PlateSide| usize::from(plate == PlateSide::B);
    let widths = plate_top_widths(spec);
    f.observed_seam_mm >= MIN_OBSERVED_SEAM_MM
        && (0..2).all(|side| match spec.faults.first() {
            Some(Fault::BarelyInView { plate, in_view_mm }) if index(*plate) == side => {
                (f.plate_in_view_mm[side] - in_view_mm).abs() < 1.0
            }
            Some(Fault::TouchingPart { plate, .. }) if index(*plate) == side => {
                f.plate_in_view_mm[side] >= widths[side] - 1e-6
            }
            _ => f.plate_in_view_mm[side] >= MIN_PLATE_IN_VIEW_MM,
        })
}

#[cfg(test)]
#[path = "suite_tests.rs"]
mod tests;
