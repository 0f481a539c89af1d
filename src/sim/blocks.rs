//! Solid blocks standing on a plate, and blocks stacked on them
//! ([`blocks_suite`]): every foot of a block is a fillet root, the block's
//! face meeting the surface it stands on.
//!
//! Issue 49 met these on real scans (a cube standing on a plate with two
//! of its inside roots in view; cubes stacked) and refused them: the plane
//! nearest the camera, the block's top, was taken for the flange. Here the
//! same layout is drawn from seeds nothing in the planner was tuned on,
//! with its truth: every root, and how much of it the camera sees.
//!
//! A block is the scene model's tee whose web is as thick as the block is
//! wide: the web's length is the block's length, its height the block's,
//! and its top is the block's top; the flange is the plate. The tee's two
//! roots are the feet of the block's long faces; the feet of its end faces
//! run across the seam's direction, from one long face to the other, and
//! their truth is a straight line's ([`super::truth::line_truth`]). A
//! stacked scene puts a smaller block on the first one's top, its four feet
//! roots on that top. Each block is [`MIN_SIDE_MM`] to [`MAX_SIDE_MM`] a
//! side. The scenes take in turn, by their index, the classes the real
//! scans show:
//!
//! - the camera facing one long face of the block, or leaning over a
//!   corner of it so that two faces and their roots are in view (a box
//!   seen from above shows at most two of its side faces; the roots of
//!   the others may be in the image, hidden behind the block);
//! - a cube, or a box of three sides drawn apart;
//! - one block on the plate, or a smaller one stacked on it;
//! - the block's top edges along its length sharp, or rounded to
//!   [`MIN_EDGE_RADIUS_MM`] to [`MAX_EDGE_RADIUS_MM`] (the vertical edges
//!   and the top's end edges stay sharp: the scene model extrudes
//!   cross-sections along the seam);
//! - the plate running past the view ([`MIN_WIDE_MARGIN_MM`] to
//!   [`MAX_WIDE_MARGIN_MM`] round the block), ending in view
//!   ([`MIN_NARROW_MARGIN_MM`] to [`MAX_NARROW_MARGIN_MM`]), or the cloud
//!   cropped to [`MIN_KEPT_MM`] to [`MAX_KEPT_MM`] round the block;
//! - the table in view, or cropped away with everything lower than
//!   [`TABLE_CROP_UNDER_PLATE_MM`] under the plate's bottom.
//!
//! The camera stands 500 to 1000 mm off and tilts 0 to [`MAX_TILT_DEG`]
//! degrees, each stratum once over the 16 scenes. A scene is redrawn until
//! the camera sees one root at least along half its length.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::draw::Draw;
use super::scene::{ConvexSolid, PlateShape, Scene, SurfaceKind, build_scene_reshaped};
use super::suite::uniform;
use super::truth::{LineOfSight, LineTruth, MIN_SEEN_SHARE, line_truth};
use super::{
    CameraPlacement, JointGeometry, NoiseSpec, PlateExtent, SceneSpec, Simulation, default_base_from_workpiece,
    paper_hand_eye, simulate_scene,
};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::geometry::pose::EulerConvention;

/// Scenes of [`blocks_suite`], and how many of them (the last) are held
/// out: the documented seeds are the first [`BLOCKS_SCENES`] −
/// [`BLOCKS_HOLDOUT`].
pub const BLOCKS_SCENES: usize = 16;
pub const BLOCKS_HOLDOUT: usize = 4;
const BLOCKS_SEED: u64 = 0xb10c_2026;
const BLOCKS_HOLDOUT_SEED: u64 = 0xb10c_0ff5;

/// A block's side, mm (the real scans' cubes are some 50 to 100 mm).
pub const MIN_SIDE_MM: f64 = 30.0;
pub const MAX_SIDE_MM: f64 = 120.0;
/// The lower block of a stack is at least this wide, so that a block of
/// [`MIN_SIDE_MM`] fits on its top with [`STACK_MARGIN_MM`] round it.
pub const MIN_STACK_BASE_MM: f64 = 60.0;
/// The upper block stands at least this far in from the lower one's top
/// edges (besides their rounding): its feet lie on the flat of the top.
pub const STACK_MARGIN_MM: f64 = 5.0;
/// The plate's thickness, mm.
pub const MIN_PLATE_MM: f64 = 6.0;
pub const MAX_PLATE_MM: f64 = 20.0;
/// The radius of the block's rounded top edges, mm: a machined or
/// cast block's slightly broken edges.
pub const MIN_EDGE_RADIUS_MM: f64 = 1.0;
pub const MAX_EDGE_RADIUS_MM: f64 = 4.0;
/// Straight pieces a rounded edge is drawn with (as the near-edge tees'
/// flange edge).
pub const EDGE_ARC_SEGMENTS: usize = 8;
/// How far the plate reaches past the block on each side when it runs
/// past the view, and when it ends in view, mm.
pub const MIN_WIDE_MARGIN_MM: f64 = 250.0;
pub const MAX_WIDE_MARGIN_MM: f64 = 500.0;
pub const MIN_NARROW_MARGIN_MM: f64 = 15.0;
pub const MAX_NARROW_MARGIN_MM: f64 = 60.0;
/// A crop round the block keeps this much of the plate beyond its faces,
/// mm, as a region of interest round the roots does.
pub const MIN_KEPT_MM: f64 = 20.0;
pub const MAX_KEPT_MM: f64 = 60.0;
/// How far the table lies under the plate's bottom, mm.
pub const MIN_TABLE_DROP_MM: f64 = 20.0;
pub const MAX_TABLE_DROP_MM: f64 = 200.0;
/// A crop of the table drops every point lower than this under the
/// plate's bottom, mm.
pub const TABLE_CROP_UNDER_PLATE_MM: f64 = 5.0;
/// The standoffs and tilts the scenes take, each stratum once.
const DISTANCE_MM: [f64; 2] = [500.0, 1000.0];
pub const MAX_TILT_DEG: f64 = 40.0;
/// How far the camera's aim lies off the block's face, mm.
const MAX_AIM_OFF_FACE_MM: f64 = 40.0;
/// How far the camera's azimuth strays from square to the face it faces,
/// or from the diagonal of the corner it leans over, degrees.
const FACE_AZIMUTH_SPREAD_DEG: f64 = 20.0;
const CORNER_AZIMUTH_SPREAD_DEG: f64 = 15.0;
/// Draws of a scene until it is valid and a root is seen (the last draw
/// is kept after this many).
const MAX_DRAWS: u64 = 200;

/// Where the camera looks from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockView {
    /// Square to one long face of the block.
    Face,
    /// Over a corner: a long face and an end face in view.
    Corner,
}

impl BlockView {
    pub fn name(self) -> &'static str {
        match self {
            BlockView::Face => "face",
            BlockView::Corner => "corner",
        }
    }
}

/// How much of the plate the cloud holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlateReach {
    /// The plate runs past the view on every side.
    PastView,
    /// The plate ends in view, its edges and what lies beyond them seen.
    EndsInView,
    /// The cloud is cropped to this far (mm) round the block's foot.
    Cropped(f64),
}

/// The block stacked on the first one: its foot on the first one's top
/// (the first workpiece's frame), its height and its top edges' rounding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpperBlock {
    pub x_mm: [f64; 2],
    pub y_mm: [f64; 2],
    pub height_mm: f64,
}

/// Which face of a block a root is the foot of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    MinusX,
    PlusX,
    MinusY,
    PlusY,
}

impl Face {
    pub const ALL: [Face; 4] = [Face::MinusX, Face::PlusX, Face::MinusY, Face::PlusY];

    pub fn name(self) -> &'static str {
        match self {
            Face::MinusX => "-x",
            Face::PlusX => "+x",
            Face::MinusY => "-y",
            Face::PlusY => "+y",
        }
    }
}

/// One root of the scene: the foot of one face of one block (0: the block
/// on the plate; 1: the block stacked on it), a straight line between two
/// ends in the first workpiece's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockRoot {
    pub block: usize,
    pub face: Face,
    pub ends: [Vec3; 2],
}

/// One scene of the family.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockScene {
    pub name: String,
    /// The block on the plate as a tee: the web is the block.
    pub spec: SceneSpec,
    pub view: BlockView,
    pub cube: bool,
    pub upper: Option<UpperBlock>,
    /// The block's (and the upper block's) top edges along its length
    /// rounded to this radius, mm.
    pub edge_radius_mm: Option<f64>,
    pub plate: PlateReach,
    /// The table (and the spacers) cropped away.
    pub table_cropped: bool,
}

/// A scene captured: the frame, and each root's truth in the order of
/// [`BlockScene::roots`].
pub struct BlockCapture {
    pub sim: Simulation,
    pub roots: Vec<(BlockRoot, LineTruth)>,
}

/// The family's scenes, named like
/// `blocks-03-d812-t14-corner-box-stacked-r2.5-platecrop-tablecrop`
/// (index, standoff, tilt, view, shape and what is added or cropped); the
/// last [`BLOCKS_HOLDOUT`] are `-holdout`, drawn from their own seed, not
/// to be run until the planner is frozen.
pub fn blocks_suite(draw: Draw) -> Vec<BlockScene> {
    let camera = CameraModel::default();
    (0..BLOCKS_SCENES)
        .map(|k| {
            let holdout = k >= BLOCKS_SCENES - BLOCKS_HOLDOUT;
            let base_seed = draw.seed(if holdout { BLOCKS_HOLDOUT_SEED } else { BLOCKS_SEED });
            let mut scene = draw_scene(k, base_seed, 0);
            for attempt in 1..MAX_DRAWS {
                if scene.is_fair(&camera) {
                    break;
                }
                scene = draw_scene(k, base_seed, attempt);
            }
            scene.name.push_str(&draw.suffix(holdout));
            scene
        })
        .collect()
}

/// Draw `attempt` of scene `k`: its classes from its index, the rest from
/// its own stream of `base_seed`.
fn draw_scene(k: usize, base_seed: u64, attempt: u64) -> BlockScene {
    let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
    rng.set_stream(k as u64 + attempt * BLOCKS_SCENES as u64);
    let view = if k.is_multiple_of(2) { BlockView::Face } else { BlockView::Corner };
    let cube = (k / 4).is_multiple_of(2);
    let stacked = k % 3 == 2;
    let rounded = matches!(k % 4, 1 | 2);
    let table_cropped = k % 5 == 4;
    let reach_class = (k / 2) % 3;
    // Strides coprime with 16 visit every stratum once.
    let last = (BLOCKS_SCENES - 1) as f64;
    let [d0, d1] = DISTANCE_MM;
    let distance_mm = d0 + (d1 - d0) * ((k * 7) % BLOCKS_SCENES) as f64 / last;
    let tilt_deg = MAX_TILT_DEG * ((k * 5) % BLOCKS_SCENES) as f64 / last;

    let smallest = if stacked { MIN_STACK_BASE_MM } else { MIN_SIDE_MM };
    let mut side = || uniform(&mut rng, smallest, MAX_SIDE_MM);
    let [width, length, height] = if cube {
        let s = side();
        [s; 3]
    } else {
        [side(), side(), side()]
    };
    let plate_mm = uniform(&mut rng, MIN_PLATE_MM, MAX_PLATE_MM);
    let edge_radius_mm = rounded.then(|| uniform(&mut rng, MIN_EDGE_RADIUS_MM, MAX_EDGE_RADIUS_MM));
    let (plate, margin_range) = match reach_class {
        0 => (PlateReach::PastView, [MIN_WIDE_MARGIN_MM, MAX_WIDE_MARGIN_MM]),
        1 => (PlateReach::EndsInView, [MIN_NARROW_MARGIN_MM, MAX_NARROW_MARGIN_MM]),
        _ => (PlateReach::Cropped(uniform(&mut rng, MIN_KEPT_MM, MAX_KEPT_MM)), [MAX_KEPT_MM, MAX_WIDE_MARGIN_MM]),
    };
    let mut margin = || uniform(&mut rng, margin_range[0], margin_range[1]);
    let [minus_x, plus_x, minus_y, plus_y] = [margin(), margin(), margin(), margin()];
    let plate_a = PlateExtent { width_mm: width / 2.0 + minus_x, length_mm: length, offset_mm: 0.0 };
    let plate_b =
        PlateExtent { width_mm: width / 2.0 + plus_x, length_mm: length + minus_y + plus_y, offset_mm: -minus_y };
    let table_drop_mm = uniform(&mut rng, MIN_TABLE_DROP_MM, MAX_TABLE_DROP_MM);

    let upper = stacked.then(|| {
        let inset = STACK_MARGIN_MM + edge_radius_mm.unwrap_or(0.0);
        let mut side_on = |room: f64| uniform(&mut rng, MIN_SIDE_MM, room - 2.0 * inset);
        let [w, l, h] = if cube {
            let s = side_on(width.min(length));
            [s; 3]
        } else {
            [side_on(width), side_on(length), uniform(&mut rng, MIN_SIDE_MM, MAX_SIDE_MM)]
        };
        let x0 = uniform(&mut rng, -width / 2.0 + inset, width / 2.0 - inset - w);
        let y0 = uniform(&mut rng, inset, length - inset - l);
        UpperBlock { x_mm: [x0, x0 + w], y_mm: [y0, y0 + l], height_mm: h }
    });

    // The camera sits on the side of the face it faces, or over the corner
    // it leans over, and aims at the plate beside the block.
    let x_sign = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
    let y_sign: f64 = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
    let off_face = |rng: &mut ChaCha8Rng| uniform(rng, 0.0, MAX_AIM_OFF_FACE_MM);
    let across_mm = x_sign * (width / 2.0 + off_face(&mut rng));
    let (azimuth_deg, along_mm) = match view {
        BlockView::Face => {
            let square = if x_sign > 0.0 { 0.0 } else { 180.0 };
            let spread = FACE_AZIMUTH_SPREAD_DEG;
            (square + uniform(&mut rng, -spread, spread), uniform(&mut rng, -0.25, 0.25) * length)
        }
        BlockView::Corner => {
            let diagonal = y_sign.atan2(x_sign).to_degrees();
            let spread = CORNER_AZIMUTH_SPREAD_DEG;
            (diagonal + uniform(&mut rng, -spread, spread), y_sign * (length / 2.0 + off_face(&mut rng)))
        }
    };
    let spec = SceneSpec {
        joint: JointGeometry::Tee { flange_thickness_mm: plate_mm, web_thickness_mm: width, web_height_mm: height },
        plate_a,
        plate_b,
        spacer_height_mm: table_drop_mm,
        placement: CameraPlacement {
            distance_mm,
            tilt_deg,
            tilt_azimuth_deg: azimuth_deg,
            roll_deg: uniform(&mut rng, 0.0, 360.0),
            target_offset_mm: [across_mm, along_mm],
        },
        noise: NoiseSpec::default(),
        base_from_workpiece: default_base_from_workpiece(),
        hand_eye: paper_hand_eye(),
        euler: EulerConvention::Zyx,
        seed: base_seed.wrapping_add(k as u64),
        faults: Vec::new(),
        others: Vec::new(),
    };
    let shape = if cube { "cube" } else { "box" };
    let mut name = format!("blocks-{k:02}-d{distance_mm:.0}-t{tilt_deg:.0}-{}-{shape}{width:.0}", view.name());
    if upper.is_some() {
        name.push_str("-stacked");
    }
    if let Some(r) = edge_radius_mm {
        name.push_str(&format!("-r{r:.1}"));
    }
    name.push_str(match plate {
        PlateReach::PastView => "",
        PlateReach::EndsInView => "-plateedge",
        PlateReach::Cropped(_) => "-platecrop",
    });
    if table_cropped {
        name.push_str("-tablecrop");
    }
    BlockScene { name, spec, view, cube, upper, edge_radius_mm, plate, table_cropped }
}

impl BlockScene {
    /// The block on the plate's height, and the plate's thickness.
    fn heights(&self) -> (f64, f64) {
        match self.spec.joint {
            JointGeometry::Tee { flange_thickness_mm: f, web_height_mm: h, .. } => (f, h),
            _ => unreachable!("a block scene's joint is a tee"),
        }
    }

    /// The block on the plate's foot: its x and y ranges.
    fn foot(&self) -> ([f64; 2], [f64; 2]) {
        let w = self.spec.joint.seam_edge_half_width();
        let a = &self.spec.plate_a;
        ([-w, w], [a.offset_mm, a.offset_mm + a.length_mm])
    }

    /// Every root: the block on the plate's four, then the stacked one's
    /// four, each in [`Face::ALL`]'s order, its ends ordered along +x or +y.
    pub fn roots(&self) -> Vec<BlockRoot> {
        let (f, h) = self.heights();
        let (x, y) = self.foot();
        let mut feet = vec![(0, x, y, f)];
        if let Some(u) = &self.upper {
            feet.push((1, u.x_mm, u.y_mm, f + h));
        }
        feet.into_iter()
            .flat_map(|(block, [x0, x1], [y0, y1], z)| {
                Face::ALL.map(|face| {
                    let ends = match face {
                        Face::MinusX => [Vec3::new(x0, y0, z), Vec3::new(x0, y1, z)],
                        Face::PlusX => [Vec3::new(x1, y0, z), Vec3::new(x1, y1, z)],
                        Face::MinusY => [Vec3::new(x0, y0, z), Vec3::new(x1, y0, z)],
                        Face::PlusY => [Vec3::new(x0, y1, z), Vec3::new(x1, y1, z)],
                    };
                    BlockRoot { block, face, ends }
                })
            })
            .collect()
    }

    /// The scene's solids in the first workpiece's frame: the tee's, its
    /// web's top edges rounded where the scene rounds them, and the
    /// stacked block.
    fn solids(&self) -> Scene {
        let (f, h) = self.heights();
        let (x, _) = self.foot();
        let mut scene = build_scene_reshaped(&self.spec, |k, shapes| {
            if k == 0 {
                shapes[0] = self.rounded(&shapes[0], x, f + h);
            }
        });
        if let Some(u) = &self.upper {
            let bottom = f + h;
            let top = bottom + u.height_mm;
            let profile = vec![[u.x_mm[0], bottom], [u.x_mm[1], bottom], [u.x_mm[1], top], [u.x_mm[0], top]];
            let shape = self.rounded(&PlateShape { profile_xz: profile, y_range: u.y_mm }, u.x_mm, top);
            scene.solids.extend(ConvexSolid::extruded(SurfaceKind::Plate, &shape.profile_xz, shape.y_range));
        }
        scene
    }

    /// A block's cross-section (spanning `x` across, its top at `top`)
    /// with both top edges rounded, where the scene rounds them.
    fn rounded(&self, shape: &PlateShape, x: [f64; 2], top: f64) -> PlateShape {
        let Some(radius_mm) = self.edge_radius_mm else { return shape.clone() };
        shape.with_rounded_corner([x[0], top], radius_mm, EDGE_ARC_SEGMENTS).with_rounded_corner(
            [x[1], top],
            radius_mm,
            EDGE_ARC_SEGMENTS,
        )
    }

    /// Each root's truth, as the camera sees the scene.
    fn root_truths(&self, camera: &CameraModel, scene: &Scene) -> Vec<(BlockRoot, LineTruth)> {
        let camera_from_first = self.spec.workpiece_from_camera().inverse();
        let sight = LineOfSight::new(scene.transformed(&camera_from_first).solids, camera);
        self.roots().into_iter().map(|root| (root, line_truth(&self.spec, camera, &sight, root.ends))).collect()
    }

    /// A fair scene: valid, and one root at least seen along half its
    /// length.
    fn is_fair(&self, camera: &CameraModel) -> bool {
        self.spec.validate().is_ok()
            && self.root_truths(camera, &self.solids()).iter().any(|(_, t)| t.seen_share >= MIN_SEEN_SHARE)
    }

    /// Whether a point of the workpiece's frame is kept by the scene's
    /// crops.
    fn kept(&self, p: &Vec3) -> bool {
        let under_table_crop = self.table_cropped && p.z < -TABLE_CROP_UNDER_PLATE_MM;
        let outside_plate_crop = match self.plate {
            PlateReach::Cropped(kept) => {
                let ([x0, x1], [y0, y1]) = self.foot();
                p.x < x0 - kept || p.x > x1 + kept || p.y < y0 - kept || p.y > y1 + kept
            }
            _ => false,
        };
        !(under_table_crop || outside_plate_crop)
    }

    /// The scene captured, its crops applied to the cloud, with every
    /// root's truth.
    pub fn simulate(&self, camera: &CameraModel) -> BlockCapture {
        let scene = self.solids();
        let roots = self.root_truths(camera, &scene);
        let mut sim = simulate_scene(&self.spec, camera, scene);
        if self.table_cropped || matches!(self.plate, PlateReach::Cropped(_)) {
            sim.reshape_in_workpiece_frame(&self.spec, |p| self.kept(p).then_some(*p));
        }
        BlockCapture { sim, roots }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_suite_is_fixed_and_spans_its_classes() {
        let suite = blocks_suite(Draw::Documented);
        assert_eq!(suite.len(), BLOCKS_SCENES);
        assert_eq!(suite, blocks_suite(Draw::Documented), "the suite is the same on every call");
        let names: std::collections::HashSet<_> = suite.iter().map(|s| &s.name).collect();
        assert_eq!(names.len(), suite.len());
        assert_eq!(suite.iter().filter(|s| s.name.ends_with("-holdout")).count(), BLOCKS_HOLDOUT);
        let cam = CameraModel::default();
        for s in &suite {
            assert!(s.is_fair(&cam), "{}", s.name);
            let JointGeometry::Tee { web_thickness_mm: w, web_height_mm: h, .. } = s.spec.joint else {
                panic!("{} is no tee", s.name);
            };
            let l = s.spec.plate_a.length_mm;
            for side in [w, l, h] {
                assert!((MIN_SIDE_MM..=MAX_SIDE_MM).contains(&side), "{}", s.name);
            }
            if s.cube {
                assert!(w == l && l == h, "{}", s.name);
            }
            // The plate reaches past the block's foot on every side.
            let b = &s.spec.plate_b;
            assert!(s.spec.plate_a.width_mm > w / 2.0 && b.width_mm > w / 2.0, "{}", s.name);
            assert!(b.offset_mm < 0.0 && b.offset_mm + b.length_mm > l, "{}", s.name);
            if let Some(u) = &s.upper {
                assert!(u.x_mm[0] > -w / 2.0 && u.x_mm[1] < w / 2.0 && u.y_mm[0] > 0.0 && u.y_mm[1] < l, "{}", s.name);
                assert!(u.x_mm[1] - u.x_mm[0] >= MIN_SIDE_MM && u.y_mm[1] - u.y_mm[0] >= MIN_SIDE_MM, "{}", s.name);
            }
            assert_eq!(s.roots().len(), if s.upper.is_some() { 8 } else { 4 });
            assert!((500.0..=1000.0).contains(&s.spec.placement.distance_mm), "{}", s.name);
            assert!((0.0..=MAX_TILT_DEG).contains(&s.spec.placement.tilt_deg), "{}", s.name);
        }
        let documented = &suite[..BLOCKS_SCENES - BLOCKS_HOLDOUT];
        let count = |pick: &dyn Fn(&BlockScene) -> bool| documented.iter().filter(|s| pick(s)).count();
        assert_eq!(count(&|s| s.view == BlockView::Corner), 6);
        assert_eq!(count(&|s| s.cube), 8);
        assert_eq!(count(&|s| s.upper.is_some()), 4);
        assert_eq!(count(&|s| s.edge_radius_mm.is_some()), 6);
        assert_eq!(count(&|s| matches!(s.plate, PlateReach::Cropped(_))), 4);
        assert_eq!(count(&|s| s.plate == PlateReach::EndsInView), 4);
        assert_eq!(count(&|s| s.table_cropped), 2);
    }

    #[test]
    fn the_roots_are_the_feet_of_the_blocks_faces() {
        let suite = blocks_suite(Draw::Documented);
        let scene = suite.iter().find(|s| s.upper.is_some() && s.edge_radius_mm.is_some()).expect("a rounded stack");
        let solids = scene.solids().solids;
        let blocks: Vec<&ConvexSolid> = solids.iter().filter(|s| s.kind == SurfaceKind::Plate).collect();
        // The plate, the block on it and the block on that.
        assert_eq!(blocks.len(), 3);
        for root in scene.roots() {
            let middle = (root.ends[0] + root.ends[1]) / 2.0;
            // On the face of its block and the top of what it stands on.
            let (stands_on, block) = if root.block == 0 { (blocks[1], blocks[0]) } else { (blocks[0], blocks[2]) };
            assert!(block.excess(&middle).abs() < 1e-9, "{:?}", root);
            assert!(stands_on.excess(&middle).abs() < 1e-9, "{:?}", root);
        }
        // The rounded top edge: its sharp corner is cut away.
        let (f, h) = scene.heights();
        let w = scene.spec.joint.seam_edge_half_width();
        let y = scene.spec.plate_a.length_mm - 1.0;
        assert!(blocks[0].excess(&Vec3::new(w, y, f + h)) > 0.2);
        assert!(blocks[0].excess(&Vec3::new(0.0, y, f + h)).abs() < 1e-9);
    }

    #[test]
    fn a_corner_view_sees_two_roots_and_the_block_hides_the_others() {
        let camera = CameraModel::default();
        let suite = blocks_suite(Draw::Documented);
        let scene = suite.iter().find(|s| s.view == BlockView::Corner && s.upper.is_none()).expect("a corner view");
        let truths = scene.root_truths(&camera, &scene.solids());
        let seen: Vec<Face> =
            truths.iter().filter(|(_, t)| t.seen_share >= MIN_SEEN_SHARE).map(|(r, _)| r.face).collect();
        let azimuth = scene.spec.placement.tilt_azimuth_deg.to_radians();
        let facing_x = if azimuth.cos() > 0.0 { Face::PlusX } else { Face::MinusX };
        let facing_y = if azimuth.sin() > 0.0 { Face::PlusY } else { Face::MinusY };
        for (root, truth) in &truths {
            if ![facing_x, facing_y].contains(&root.face) {
                assert!(truth.seen_share < MIN_SEEN_SHARE, "{}: {:?} {truth:?}", scene.name, root.face);
            }
        }
        assert!(!seen.is_empty(), "{}", scene.name);
    }
}
