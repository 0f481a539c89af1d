//! The exact seam a simulated frame shows, for scoring the planner.
//!
//! The seam physically runs where both plates exist along it. A planner can
//! only be asked for the part the camera sees, so the truth is clipped to
//! the seam parameters at which both seam-side top edges (for a lap, the
//! upper plate's edge and the root line) project inside the image. Each
//! image border is a linear inequality along a 3D line, so the clipping is
//! exact, not sampled.
//!
//! A frame may show more seams than one: a tee's two fillet roots, and the
//! seams of several workpieces. [`seam_truths`] gives each its own truth
//! and how much of it the camera sees: the stretches that are in the image
//! and that neither the camera's view ray nor the projector's light ray
//! reaches through a solid ([`LineOfSight`]; a web hides the root behind
//! it, a neighbouring part may shade one), sampled along the seam.

use nalgebra::Isometry3;

use super::JointGeometry;
use super::scene::{ConvexSolid, build_scene};
use super::{SceneSpec, Workpiece};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::joint::JointType;

/// The seam a frame shows, in the camera and robot base frames.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    pub joint: JointType,
    pub groove_depth_mm: Option<f64>,
    /// The observed seam's ends: `start` at the smaller workpiece y.
    pub start_camera: Vec3,
    pub end_camera: Vec3,
    pub start_base: Vec3,
    pub end_base: Vec3,
    /// Unit normal of the top surface, pointing into the workpiece (away
    /// from the camera).
    pub plate_normal_camera: Vec3,
    pub plate_normal_base: Vec3,
    /// The seam continues beyond the image at its start.
    pub clipped_start: bool,
    /// The seam continues beyond the image at its end.
    pub clipped_end: bool,
    pub length_mm: f64,
}

/// Margin from the sensor's outer pixel centres within which a point
/// counts as in the image: half a pixel inside the outermost centres.
const IMAGE_MARGIN_PX: f64 = 0.5;
/// Points closer to the camera plane than this count as not imaged.
const MIN_DEPTH_MM: f64 = 1.0;

/// The pixel rectangle `[u_min, u_max, v_min, v_max]` a point must project
/// into to count as seen.
pub fn image_rect(camera: &CameraModel) -> [f64; 4] {
    [
        IMAGE_MARGIN_PX,
        camera.width_px as f64 - 1.0 - IMAGE_MARGIN_PX,
        IMAGE_MARGIN_PX,
        camera.height_px as f64 - 1.0 - IMAGE_MARGIN_PX,
    ]
}

/// True when a camera-frame point projects inside [`image_rect`].
pub fn in_image(camera: &CameraModel, p: &Vec3) -> bool {
    visible_interval(camera, p, &Vec3::zeros()).is_some()
}

/// The parameters `s` for which `origin + s along` (camera frame) is in
/// front of the camera and projects inside [`image_rect`]; `None` if none.
/// Bounds may be infinite.
pub fn visible_interval(camera: &CameraModel, origin: &Vec3, along: &Vec3) -> Option<[f64; 2]> {
    let [u0, u1, v0, v1] = image_rect(camera);
    let (fx, fy, cx, cy) = (camera.fx(), camera.fy(), camera.cx(), camera.cy());
    // u >= u0  <=>  fx X + (cx - u0) Z >= 0 for Z > 0; likewise the others.
    let borders = [
        Vec3::new(fx, 0.0, cx - u0),
        Vec3::new(-fx, 0.0, u1 - cx),
        Vec3::new(0.0, fy, cy - v0),
        Vec3::new(0.0, -fy, v1 - cy),
    ];
    let in_front = (origin.z - MIN_DEPTH_MM, along.z);
    let mut range = [f64::NEG_INFINITY, f64::INFINITY];
    let constraints = borders.iter().map(|w| (w.dot(origin), w.dot(along))).chain(std::iter::once(in_front));
    for (a, b) in constraints {
        // a + b s >= 0
        if b > 0.0 {
            range[0] = range[0].max(-a / b);
        } else if b < 0.0 {
            range[1] = range[1].min(-a / b);
        } else if a < 0.0 {
            return None;
        }
    }
    (range[0] <= range[1]).then_some(range)
}

/// The y range of the seam (workpiece frame) whose edges are all in view,
/// or `None` when the camera sees no part of it.
pub fn observed_seam_range(spec: &SceneSpec, camera: &CameraModel) -> Option<[f64; 2]> {
    let camera_from_workpiece = spec.workpiece_from_camera().inverse();
    range_in_view(camera, &camera_from_workpiece, spec.seam_range(), &spec.joint.seam_edges_xz())
}

/// The part of `range` (a workpiece's y) along which every line of
/// `edges_xz` (at its x and z, along y) is in view of `camera`, which sees
/// the workpiece through `camera_from_own`; `None` when some edge is not
/// in view along any of it.
fn range_in_view(
    camera: &CameraModel,
    camera_from_own: &Isometry3<f64>,
    range: [f64; 2],
    edges_xz: &[[f64; 2]],
) -> Option<[f64; 2]> {
    let along = camera_from_own.rotation * Vec3::y();
    let mut range = range;
    for &[x, z] in edges_xz {
        let origin = camera_from_own.transform_point(&Vec3::new(x, 0.0, z).into()).coords;
        let [lo, hi] = visible_interval(camera, &origin, &along)?;
        range = [range[0].max(lo), range[1].min(hi)];
    }
    (range[0] <= range[1]).then_some(range)
}

/// The ground truth of `spec` as `camera` sees it.
pub fn ground_truth(spec: &SceneSpec, camera: &CameraModel) -> GroundTruth {
    let workpiece_from_camera = spec.workpiece_from_camera();
    let camera_from_workpiece = workpiece_from_camera.inverse();
    let base_from_workpiece = spec.base_from_workpiece;
    let physical = spec.seam_range();
    let observed = observed_seam_range(spec, camera);
    let [y0, y1] = observed.unwrap_or_else(|| {
        let middle = (physical[0] + physical[1]) / 2.0;
        [middle, middle]
    });
    // The seam, or a tee's first root.
    let [seam_x, seam_z] = spec.joint.seam_lines_xz()[0];
    let start = Vec3::new(seam_x, y0, seam_z);
    let end = Vec3::new(seam_x, y1, seam_z);
    let in_camera = |p: &Vec3| camera_from_workpiece.transform_point(&(*p).into()).coords;
    let in_base = |p: &Vec3| base_from_workpiece.transform_point(&(*p).into()).coords;
    let into_workpiece = -Vec3::z();
    GroundTruth {
        joint: spec.joint.joint_type(),
        groove_depth_mm: spec.joint.groove_depth_mm(),
        start_camera: in_camera(&start),
        end_camera: in_camera(&end),
        start_base: in_base(&start),
        end_base: in_base(&end),
        plate_normal_camera: camera_from_workpiece.rotation * into_workpiece,
        plate_normal_base: base_from_workpiece.rotation * into_workpiece,
        clipped_start: observed.is_none() || y0 > physical[0],
        clipped_end: observed.is_none() || y1 < physical[1],
        length_mm: y1 - y0,
    }
}

/// A seam counts as seen when the camera sees at least this share of its
/// length (issue 15's bar for a root that must be found).
pub const MIN_SEEN_SHARE: f64 = 0.5;
/// Step along a seam at which its seen stretches are sampled.
const SEEN_STEP_MM: f64 = 0.25;
/// Seen stretches shorter than this do not count.
pub const MIN_SEEN_STRETCH_MM: f64 = 5.0;

/// One weld seam of a frame and how much of it the camera sees.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamTruth {
    /// Which workpiece (0: the first, the scene's own) and which of its
    /// seams (0; a tee's root on its +x side is 1).
    pub workpiece: usize,
    pub root: usize,
    /// The stretch of the seam whose line is in the image, as
    /// [`GroundTruth`] has it for a frame's one seam.
    pub truth: GroundTruth,
    /// The seam's whole length, where both plates exist, mm.
    pub physical_mm: f64,
    /// The stretches (the workpiece's own y, mm) the camera sees: in the
    /// image, and neither the view ray nor the projector's ray blocked.
    pub seen_mm: Vec<[f64; 2]>,
    /// The seen stretches' length over the physical length.
    pub seen_share: f64,
}

impl SeamTruth {
    /// Whether a planner is to find it: at least [`MIN_SEEN_SHARE`] seen.
    pub fn is_seen(&self) -> bool {
        self.seen_share >= MIN_SEEN_SHARE
    }

    /// A name for tables: `workpiece 2 lap`, `tee root -x`.
    pub fn label(&self) -> String {
        let root = match (self.truth.joint, self.root) {
            (JointType::TFillet, 0) => " root -x",
            (JointType::TFillet, _) => " root +x",
            _ => "",
        };
        format!("workpiece {} {}{root}", self.workpiece + 1, self.truth.joint.dashed_name())
    }

    /// The ends of the seen stretches in the robot base frame.
    pub fn seen_base(&self, spec: &SceneSpec) -> Vec<[Vec3; 2]> {
        let Some(workpiece) = spec.workpieces().get(self.workpiece).copied() else { return Vec::new() };
        let Some([x, z]) = workpiece.joint.seam_lines_xz().get(self.root).copied() else { return Vec::new() };
        let base_from_own = spec.base_from_workpiece * workpiece.pose();
        let at = |y: f64| base_from_own.transform_point(&Vec3::new(x, y, z).into()).coords;
        self.seen_mm.iter().map(|[a, b]| [at(*a), at(*b)]).collect()
    }
}

/// What hides a point from the camera or leaves it unlit: the scene's
/// solids in the camera frame, the camera at the origin and the projector
/// `camera.baseline_mm` along +x.
pub struct LineOfSight {
    solids: Vec<ConvexSolid>,
    projector: Vec3,
}

impl LineOfSight {
    /// `solids` in the camera frame.
    pub fn new(solids: Vec<ConvexSolid>, camera: &CameraModel) -> Self {
        LineOfSight { solids, projector: Vec3::new(camera.baseline_mm, 0.0, 0.0) }
    }

    /// Whether a camera-frame point is hidden from the camera or shaded
    /// from the projector.
    pub fn hides(&self, p: &Vec3) -> bool {
        [Vec3::zeros(), self.projector].iter().any(|from| self.solids.iter().any(|s| s.blocks(from, &(p - from))))
    }
}

/// The stretches of `range` (sampled every [`SEEN_STEP_MM`]) where
/// `hidden` is false, each at least `min_length_mm` long.
pub fn unhidden_stretches(range: [f64; 2], hidden: impl Fn(f64) -> bool, min_length_mm: f64) -> Vec<[f64; 2]> {
    let [y0, y1] = range;
    let steps = ((y1 - y0) / SEEN_STEP_MM).ceil().max(1.0) as usize;
    let mut pieces = Vec::new();
    let mut open: Option<f64> = None;
    for k in 0..=steps {
        let y = y0 + (y1 - y0) * k as f64 / steps as f64;
        match (hidden(y), open) {
            (false, None) => open = Some(y),
            (true, Some(start)) => {
                pieces.push([start, y - (y1 - y0) / steps as f64]);
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        pieces.push([start, y1]);
    }
    pieces.retain(|[a, b]| b - a >= min_length_mm);
    pieces
}

/// Every seam of every workpiece in the frame (a tee's two roots), the
/// first workpiece's first, with what the camera sees of each.
pub fn seam_truths(spec: &SceneSpec, camera: &CameraModel) -> Vec<SeamTruth> {
    let camera_from_first = spec.workpiece_from_camera().inverse();
    let sight = LineOfSight::new(build_scene(spec).transformed(&camera_from_first).solids, camera);
    let mut seams = Vec::new();
    for (k, workpiece) in spec.workpieces().iter().enumerate() {
        for (root, line) in workpiece.joint.seam_lines_xz().into_iter().enumerate() {
            seams.push(seam_truth(spec, camera, &sight, &camera_from_first, k, workpiece, root, line));
        }
    }
    seams
}

/// One seam's truth: the line `line_xz` of `workpiece` along its y.
#[allow(clippy::too_many_arguments)]
fn seam_truth(
    spec: &SceneSpec,
    camera: &CameraModel,
    sight: &LineOfSight,
    camera_from_first: &Isometry3<f64>,
    index: usize,
    workpiece: &Workpiece,
    root: usize,
    line_xz: [f64; 2],
) -> SeamTruth {
    let [x, z] = line_xz;
    let camera_from_own = camera_from_first * workpiece.pose();
    let base_from_own = spec.base_from_workpiece * workpiece.pose();
    let point = |y: f64| Vec3::new(x, y, z);
    let in_camera = |y: f64| camera_from_own.transform_point(&point(y).into()).coords;
    let in_base = |y: f64| base_from_own.transform_point(&point(y).into()).coords;
    let physical = workpiece.seam_range();
    // Clipped as a frame's one seam is (`observed_seam_range`): to where
    // every seam-side edge is in the image, so that a butt joint whose
    // plates the image border cuts slantwise ends where the plate cut
    // first still shows its edge, not where the seam's own line leaves the
    // image (a V-groove 14 mm open, cut at 45°, 7 mm further). A tee's
    // root is its own edge.
    let edges = match workpiece.joint {
        JointGeometry::Tee { .. } => vec![line_xz],
        joint => joint.seam_edges_xz().to_vec(),
    };
    let observed = range_in_view(camera, &camera_from_own, physical, &edges);
    let [y0, y1] = observed.unwrap_or_else(|| [(physical[0] + physical[1]) / 2.0; 2]);
    let seen_mm = match observed {
        Some(range) => unhidden_stretches(range, |y| sight.hides(&in_camera(y)), MIN_SEEN_STRETCH_MM),
        None => Vec::new(),
    };
    let physical_mm = physical[1] - physical[0];
    let seen_share = seen_mm.iter().fold(0.0, |sum, [a, b]| sum + (b - a)) / physical_mm;
    let into_workpiece = -Vec3::z();
    let truth = GroundTruth {
        joint: workpiece.joint.joint_type(),
        groove_depth_mm: workpiece.joint.groove_depth_mm(),
        start_camera: in_camera(y0),
        end_camera: in_camera(y1),
        start_base: in_base(y0),
        end_base: in_base(y1),
        plate_normal_camera: camera_from_own.rotation * into_workpiece,
        plate_normal_base: base_from_own.rotation * into_workpiece,
        clipped_start: observed.is_none() || y0 > physical[0],
        clipped_end: observed.is_none() || y1 < physical[1],
        length_mm: y1 - y0,
    };
    SeamTruth { workpiece: index, root, truth, physical_mm, seen_mm, seen_share }
}

/// What the camera sees of a straight root that need not run along its
/// workpiece's y: a block's foot along its end face runs along x
/// ([`line_truth`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LineTruth {
    /// The stretch of the root in the image, robot base frame, ordered as
    /// the root's ends are; `None` when no part of it is in the image.
    pub in_image_base: Option<[Vec3; 2]>,
    /// The stretches (robot base frame) the camera sees: in the image, and
    /// neither the view ray nor the projector's ray blocked.
    pub seen_base: Vec<[Vec3; 2]>,
    /// The root's whole length, mm.
    pub physical_mm: f64,
    /// The seen stretches' length over the whole length.
    pub seen_share: f64,
}

/// The truth of the straight root from `ends[0]` to `ends[1]` (the first
/// workpiece's frame), clipped to the image and sampled for what hides it
/// as [`seam_truths`] does a seam along y: `sight` holds the scene's
/// solids in the camera frame.
pub fn line_truth(spec: &SceneSpec, camera: &CameraModel, sight: &LineOfSight, ends: [Vec3; 2]) -> LineTruth {
    let camera_from_first = spec.workpiece_from_camera().inverse();
    let base_from_first = spec.base_from_workpiece;
    let physical_mm = (ends[1] - ends[0]).norm();
    let along = (ends[1] - ends[0]) / physical_mm;
    let point = |s: f64| ends[0] + along * s;
    let in_camera = |s: f64| camera_from_first.transform_point(&point(s).into()).coords;
    let in_base = |s: f64| base_from_first.transform_point(&point(s).into()).coords;
    let observed = visible_interval(camera, &in_camera(0.0), &(camera_from_first.rotation * along))
        .map(|[lo, hi]| [lo.max(0.0), hi.min(physical_mm)])
        .filter(|[lo, hi]| lo <= hi);
    let seen: Vec<[f64; 2]> = match observed {
        Some(range) => unhidden_stretches(range, |s| sight.hides(&in_camera(s)), MIN_SEEN_STRETCH_MM),
        None => Vec::new(),
    };
    let seen_share = seen.iter().fold(0.0, |sum, [a, b]| sum + (b - a)) / physical_mm;
    LineTruth {
        in_image_base: observed.map(|[a, b]| [in_base(a), in_base(b)]),
        seen_base: seen.iter().map(|[a, b]| [in_base(*a), in_base(*b)]).collect(),
        physical_mm,
        seen_share,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{CameraPlacement, NoiseSpec, PlateExtent, demo_scene};

    fn frontal_i_butt() -> SceneSpec {
        let mut spec = demo_scene(JointType::IButt);
        spec.plate_a = PlateExtent { width_mm: 120.0, length_mm: 200.0, offset_mm: 0.0 };
        spec.plate_b = PlateExtent { width_mm: 100.0, length_mm: 220.0, offset_mm: 30.0 };
        spec.placement = CameraPlacement::straight(800.0, 0.0);
        spec.noise = NoiseSpec::none();
        spec
    }

    #[test]
    fn a_fully_visible_seam_is_where_both_plates_exist() {
        let spec = frontal_i_butt();
        let truth = ground_truth(&spec, &CameraModel::default());
        assert!(!truth.clipped_start && !truth.clipped_end);
        assert!((truth.length_mm - 170.0).abs() < 1e-9);
        let t = 6.0;
        let b = spec.base_from_workpiece;
        let start = b.transform_point(&Vec3::new(0.0, 30.0, t).into()).coords;
        let end = b.transform_point(&Vec3::new(0.0, 200.0, t).into()).coords;
        assert!((truth.start_base - start).norm() < 1e-9);
        assert!((truth.end_base - end).norm() < 1e-9);
        // Frontal: the seam is straight ahead at 800 mm, normal along +z.
        let mid = (truth.start_camera + truth.end_camera) / 2.0;
        assert!((mid - Vec3::new(0.0, 0.0, 800.0)).norm() < 1e-9);
        assert!((truth.plate_normal_camera - Vec3::z()).norm() < 1e-12);
        assert!((truth.plate_normal_base - b.rotation * -Vec3::z()).norm() < 1e-12);
    }

    #[test]
    fn a_seam_longer_than_the_view_is_clipped_at_the_image_border() {
        let mut spec = frontal_i_butt();
        spec.plate_a.length_mm = 400.0;
        spec.plate_b = PlateExtent { length_mm: 400.0, offset_mm: 0.0, ..spec.plate_b };
        spec.placement.distance_mm = 500.0;
        let cam = CameraModel::default();
        let truth = ground_truth(&spec, &cam);
        assert!(truth.clipped_start && truth.clipped_end);
        // The seam runs along the image's v axis: its ends sit on the
        // clipping rows, and it is the view's height long, 220 mm at
        // 500 mm less the margins.
        let [_, _, v0, v1] = image_rect(&cam);
        let v_of = |p: &Vec3| cam.project(p).unwrap().1;
        let (va, vb) = (v_of(&truth.start_camera), v_of(&truth.end_camera));
        assert!(((va - v1).abs() < 1e-6 && (vb - v0).abs() < 1e-6), "{va} {vb}");
        let expected = (v1 - v0) / cam.fy() * (500.0 - 6.0 + 6.0);
        assert!((truth.length_mm - expected).abs() < 1e-6, "{}", truth.length_mm);
    }

    /// The demo tee seen from 600 mm, tilted 20 degrees towards `azimuth`.
    fn tee_from(azimuth_deg: f64) -> SceneSpec {
        let mut spec = demo_scene(JointType::TFillet);
        spec.placement = CameraPlacement { tilt_azimuth_deg: azimuth_deg, ..CameraPlacement::straight(600.0, 20.0) };
        spec.noise = NoiseSpec::none();
        spec
    }

    #[test]
    fn a_tee_shows_the_root_on_the_cameras_side_and_hides_the_other() {
        let cam = CameraModel::default();
        for (azimuth, seen_root) in [(0.0, 1), (180.0, 0)] {
            let spec = tee_from(azimuth);
            let seams = seam_truths(&spec, &cam);
            assert_eq!(seams.len(), 2);
            for seam in &seams {
                assert_eq!((seam.workpiece, seam.truth.joint), (0, JointType::TFillet));
                assert!((seam.physical_mm - 240.0).abs() < 1e-9 && (seam.truth.length_mm - 240.0).abs() < 1e-9);
                if seam.root == seen_root {
                    assert!(seam.is_seen() && seam.seen_share > 0.99, "{azimuth}: {seam:?}");
                    assert_eq!(seam.seen_mm.len(), 1);
                } else {
                    assert!(seam.seen_mm.is_empty() && seam.seen_share == 0.0, "{azimuth}: {seam:?}");
                }
            }
            // The roots lie where the web's side faces meet the flange's
            // top: 8 mm apart, on the flange's top (10 mm), in the base frame.
            let [x, z] = spec.joint.seam_lines_xz()[seen_root];
            assert!((x.abs() - 4.0).abs() < 1e-12 && (z - 10.0).abs() < 1e-12);
            let expected = spec.base_from_workpiece.transform_point(&Vec3::new(x, 0.0, z).into()).coords;
            assert!((seams[seen_root].truth.start_base - expected).norm() < 1e-9);
            let apart = seams[0].truth.start_base - seams[1].truth.start_base;
            assert!((apart.norm() - 8.0).abs() < 1e-9);
        }
        // Straight down over the web: each root is seen by one of camera
        // and projector at most, so neither counts as seen.
        let mut over = tee_from(0.0);
        over.placement = CameraPlacement::straight(600.0, 0.0);
        assert!(seam_truths(&over, &cam).iter().all(|s| !s.is_seen()));
    }

    #[test]
    fn a_line_s_truth_is_a_seam_s_along_the_same_root() {
        let cam = CameraModel::default();
        let spec = tee_from(0.0);
        let sight =
            LineOfSight::new(build_scene(&spec).transformed(&spec.workpiece_from_camera().inverse()).solids, &cam);
        let [y0, y1] = spec.seam_range();
        for (seam, [x, z]) in seam_truths(&spec, &cam).iter().zip(spec.joint.seam_lines_xz()) {
            // Along the root either way: the same share seen, the same stretch in the image.
            let ends = [Vec3::new(x, y0, z), Vec3::new(x, y1, z)];
            for (ends, forward) in [(ends, true), ([ends[1], ends[0]], false)] {
                let line = line_truth(&spec, &cam, &sight, ends);
                assert!((line.seen_share - seam.seen_share).abs() < 0.01, "{line:?} {seam:?}");
                assert!((line.physical_mm - seam.physical_mm).abs() < 1e-9);
                let [a, b] = line.in_image_base.expect("the root is in the image");
                let [a, b] = if forward { [a, b] } else { [b, a] };
                assert!((a - seam.truth.start_base).norm() < 1e-6 && (b - seam.truth.end_base).norm() < 1e-6);
            }
        }
    }

    #[test]
    fn every_workpiece_has_its_seams_where_its_pose_puts_them() {
        let cam = CameraModel::default();
        let mut spec = frontal_i_butt();
        spec.placement.distance_mm = 1000.0;
        let mut lap = crate::sim::demo_scene(JointType::Lap).first_workpiece();
        lap.plate_a = PlateExtent { width_mm: 60.0, length_mm: 150.0, offset_mm: 0.0 };
        lap.plate_b = lap.plate_a;
        // Turned so that its lower plate faces the camera, whose view at
        // 1000 mm spans 700 by 440 mm around the first seam's middle.
        lap.at_mm = [250.0, 150.0];
        lap.yaw_deg = 210.0;
        spec.others.push(lap);
        assert_eq!(spec.validate(), Ok(()));
        let seams = seam_truths(&spec, &cam);
        assert_eq!(
            seams.iter().map(|s| (s.workpiece, s.truth.joint)).collect::<Vec<_>>(),
            [(0, JointType::IButt), (1, JointType::Lap)]
        );
        // The lap's root (x = 0 on its 6 mm lower plate, y 0 to 150) turned
        // 210 degrees and moved to (250, 150) on the table.
        let (yaw, root_z) = (210f64.to_radians(), 6.0);
        let start = Vec3::new(250.0, 150.0, root_z);
        let end = Vec3::new(250.0 - yaw.sin() * 150.0, 150.0 + yaw.cos() * 150.0, root_z);
        let b = spec.base_from_workpiece;
        let lap_seam = &seams[1].truth;
        assert!((lap_seam.start_base - b.transform_point(&start.into()).coords).norm() < 1e-9);
        assert!((lap_seam.end_base - b.transform_point(&end.into()).coords).norm() < 1e-9);
        assert!(seams.iter().all(|s| s.is_seen()), "{seams:?}");
        // The first workpiece's truth is unchanged by the second.
        assert_eq!(seams[0].truth, ground_truth(&frontal_i_butt_at(1000.0), &cam));
        // Moved onto the first one, the second is refused.
        spec.others[0].at_mm = [120.0, 150.0];
        assert!(spec.validate().unwrap_err().to_string().contains("closer than 10 mm"));
    }

    #[test]
    fn a_seam_whose_plates_the_border_cuts_slantwise_ends_where_an_edge_leaves_the_image() {
        // The demo's V-groove, 400 mm long, seen from 500 mm rolled 40
        // degrees: each image border crosses the groove's two top edges
        // at different places along it.
        let mut spec = demo_scene(JointType::VButt);
        spec.plate_a = PlateExtent { width_mm: 120.0, length_mm: 400.0, offset_mm: 0.0 };
        spec.plate_b = spec.plate_a;
        spec.placement = CameraPlacement { roll_deg: 40.0, ..CameraPlacement::straight(500.0, 0.0) };
        spec.noise = NoiseSpec::none();
        let cam = CameraModel::default();
        let one = ground_truth(&spec, &cam);
        assert!(one.clipped_start && one.clipped_end);
        // A frame's seams are clipped as its one seam is.
        assert_eq!(seam_truths(&spec, &cam)[0].truth, one);
        // The groove's centre line runs on into the image past where an
        // edge has left it: that is no seam a planner can be asked for.
        let camera_from_workpiece = spec.workpiece_from_camera().inverse();
        let [x, z] = spec.joint.seam_lines_xz()[0];
        let on_line = camera_from_workpiece.transform_point(&Vec3::new(x, 0.0, z).into()).coords;
        let [lo, hi] = visible_interval(&cam, &on_line, &(camera_from_workpiece.rotation * Vec3::y())).unwrap();
        assert!(hi - lo > one.length_mm + 2.0, "{} against {}", hi - lo, one.length_mm);
    }

    fn frontal_i_butt_at(distance_mm: f64) -> SceneSpec {
        let mut spec = frontal_i_butt();
        spec.placement.distance_mm = distance_mm;
        spec
    }

    #[test]
    fn the_interval_matches_point_tests() {
        let cam = CameraModel::default();
        let origin = Vec3::new(-100.0, 20.0, 600.0);
        let along = Vec3::new(0.6, 0.3, 0.2).normalize();
        let [lo, hi] = visible_interval(&cam, &origin, &along).unwrap();
        for s in [lo + 1e-6, (lo + hi) / 2.0, hi - 1e-6] {
            assert!(in_image(&cam, &(origin + along * s)));
        }
        for s in [lo - 1e-3, hi + 1e-3] {
            assert!(!in_image(&cam, &(origin + along * s)));
        }
    }
}
