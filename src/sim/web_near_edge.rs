//! Tees whose web stands near the flange's edge ([`web_near_edge_suite`]):
//! a tube or a plate standing on a box beam or a narrow flange, so that on
//! one side of the web the flange shows only a sliver, 6 to 30 mm from the
//! web's face to the flange's outer edge, with a drop of 100 to 300 mm to
//! the table beyond it, while on the other side the flange is wide.
//!
//! Issue 49 met this on a real scan: the sliver beside the web was read as
//! a plate's edge flush with a larger plane and a drop beyond, an outside
//! corner, and the tee refused. Here the same layout is drawn from seeds
//! nothing in the planner was tuned on, with its truth: both fillet roots,
//! and how much of each the camera sees ([`super::truth::seam_truths`]).
//!
//! Each scene is a tee of [`super::tee_suite`]'s plate ranges (web 4 to
//! 12 mm thick and 40 to 100 mm tall, flange 6 to 16 mm thick), its flange
//! reaching [`MIN_NARROW_MM`] to [`MAX_NARROW_MM`] beyond the web's face on
//! the narrow side (the tee's plate A or B width, whichever side is
//! narrow: the scene model's flange already has a reach per side) and
//! [`MIN_WIDE_MM`] to [`MAX_WIDE_MM`] on the other. The scenes take in
//! turn, by their index, the classes the real scans show:
//!
//! - the camera leaning over the narrow side or over the wide side;
//! - the flange's outer edge on the narrow side square, or rounded to a
//!   radius of [`MIN_EDGE_RADIUS_MM`] to [`MAX_EDGE_RADIUS_MM`] as a
//!   rolled section's is (the flange's cross-section with that corner an
//!   arc of [`EDGE_ARC_SEGMENTS`] straight pieces);
//! - the web's top in view, or cropped away: the cloud keeps only
//!   [`MIN_WEB_KEPT_MM`] to [`MAX_WEB_KEPT_MM`] of the web above the
//!   flange, as a region of interest round the root leaves it;
//! - the table in view, or cropped away with everything lower than
//!   [`TABLE_CROP_UNDER_FLANGE_MM`] under the flange's bottom.
//!
//! The camera stands 500 to 1000 mm off and tilts 0 to 30 degrees, each
//! stratum once over the 16 scenes, as the tee suite's do. A scene is
//! redrawn until the camera sees one root at least along half its length
//! and [`MIN_OBSERVED_SEAM_MM`] of it in the image. The rounding and the
//! crops change what is captured, not the roots: the truth is the tee's,
//! and its line of sight is the square-edged tee's (a rounded corner takes
//! away flange the roots' rays do not cross).

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::draw::Draw;
use super::scene::{PlateShape, build_scene_reshaped};
use super::suite::{MIN_OBSERVED_SEAM_MM, draw_tee, uniform};
use super::truth::seam_truths;
use super::{
    CameraPlacement, JointGeometry, NoiseSpec, PlateExtent, SceneSpec, Simulation, default_base_from_workpiece,
    paper_hand_eye, simulate_scene,
};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::geometry::pose::EulerConvention;

/// Scenes of [`web_near_edge_suite`], and how many of them (the last) are
/// held out: the documented seeds are the first [`WEB_NEAR_EDGE_SCENES`]
/// − [`WEB_NEAR_EDGE_HOLDOUT`].
pub const WEB_NEAR_EDGE_SCENES: usize = 16;
pub const WEB_NEAR_EDGE_HOLDOUT: usize = 4;
const WEB_NEAR_EDGE_SEED: u64 = 0xed9e_2026;
const WEB_NEAR_EDGE_HOLDOUT_SEED: u64 = 0xed9e_0ff5;

/// How far the flange reaches beyond the web's face on the narrow side,
/// mm: the real scan's sliver is 14 to 25 mm wide; a narrow flange's or a
/// box beam's edge may stand closer or further.
pub const MIN_NARROW_MM: f64 = 6.0;
pub const MAX_NARROW_MM: f64 = 30.0;
/// How far it reaches beyond the web's other face, mm.
pub const MIN_WIDE_MM: f64 = 80.0;
pub const MAX_WIDE_MM: f64 = 250.0;
/// The radius of a rolled section's rounded outer edge, mm.
pub const MIN_EDGE_RADIUS_MM: f64 = 1.0;
pub const MAX_EDGE_RADIUS_MM: f64 = 5.0;
/// Straight pieces the rounded edge is drawn with: a 5 mm arc's chords
/// then stray at most 0.1 mm from it, less than the camera's pixel there.
pub const EDGE_ARC_SEGMENTS: usize = 8;
/// How far the table lies under the flange's top, mm (the real scan's
/// floor is 200 mm and more below the beam's top).
pub const MIN_TABLE_DROP_MM: f64 = 100.0;
pub const MAX_TABLE_DROP_MM: f64 = 300.0;
/// How much of the web above the flange's top a crop of its top keeps, mm.
pub const MIN_WEB_KEPT_MM: f64 = 15.0;
pub const MAX_WEB_KEPT_MM: f64 = 35.0;
/// A crop of the table drops every point lower than this under the
/// flange's bottom, mm: the flange's edge face stays, the spacers and the
/// table go.
pub const TABLE_CROP_UNDER_FLANGE_MM: f64 = 5.0;
/// The standoffs and tilts the scenes take, each stratum once (the tee
/// suite's range).
const DISTANCE_MM: [f64; 2] = [500.0, 1000.0];
const MAX_TILT_DEG: f64 = 30.0;
/// Draws of a scene until it is valid and a root is seen (the last draw
/// is kept after this many).
const MAX_DRAWS: u64 = 200;

/// Which side of the web the camera leans over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewSide {
    /// Over the sliver of flange and the drop beyond it.
    Narrow,
    /// Over the wide flange.
    Wide,
}

impl ViewSide {
    pub fn name(self) -> &'static str {
        match self {
            ViewSide::Narrow => "narrow",
            ViewSide::Wide => "wide",
        }
    }
}

/// One scene of the family: the tee, and what is done to it and its cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct WebNearEdge {
    pub name: String,
    pub spec: SceneSpec,
    /// The side of the web (−1: −x, plate A's; +1: +x, plate B's) where
    /// the flange is narrow.
    pub narrow_sign: f64,
    /// How far the flange reaches beyond the web's face there, mm.
    pub narrow_mm: f64,
    pub view: ViewSide,
    /// The narrow side's outer top edge rounded to this radius, mm.
    pub edge_radius_mm: Option<f64>,
    /// The web's top cropped away above this height over the flange's
    /// top, mm.
    pub web_kept_mm: Option<f64>,
    /// The table (and the spacers) cropped away.
    pub table_cropped: bool,
}

/// The family's scenes, named like
/// `web-edge-03-d812-t14-narrow-n17-r2.5-webcrop-tablecrop` (index,
/// standoff, tilt, the side the camera leans over, the sliver's width, the
/// edge's radius and the crops where there are any); the last
/// [`WEB_NEAR_EDGE_HOLDOUT`] are `-holdout`, drawn from their own seed, not
/// to be run until the planner is frozen.
pub fn web_near_edge_suite(draw: Draw) -> Vec<WebNearEdge> {
    let camera = CameraModel::default();
    (0..WEB_NEAR_EDGE_SCENES)
        .map(|k| {
            let holdout = k >= WEB_NEAR_EDGE_SCENES - WEB_NEAR_EDGE_HOLDOUT;
            let base_seed = draw.seed(if holdout { WEB_NEAR_EDGE_HOLDOUT_SEED } else { WEB_NEAR_EDGE_SEED });
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
fn draw_scene(k: usize, base_seed: u64, attempt: u64) -> WebNearEdge {
    let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
    rng.set_stream(k as u64 + attempt * WEB_NEAR_EDGE_SCENES as u64);
    let view = if k.is_multiple_of(2) { ViewSide::Narrow } else { ViewSide::Wide };
    let rounded = (k / 2) % 2 == 1;
    let web_top_cropped = (k / 4) % 2 == 1;
    let table_cropped = k % 3 == 2;
    // Strides coprime with 16 visit every stratum once.
    let last = (WEB_NEAR_EDGE_SCENES - 1) as f64;
    let [d0, d1] = DISTANCE_MM;
    let distance_mm = d0 + (d1 - d0) * ((k * 7) % WEB_NEAR_EDGE_SCENES) as f64 / last;
    let tilt_deg = MAX_TILT_DEG * ((k * 5) % WEB_NEAR_EDGE_SCENES) as f64 / last;

    let joint = draw_tee(&mut rng);
    let JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, .. } = joint else {
        unreachable!("draw_tee draws a tee")
    };
    let narrow_sign = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
    let narrow_mm = uniform(&mut rng, MIN_NARROW_MM, MAX_NARROW_MM);
    let wide_mm = uniform(&mut rng, MIN_WIDE_MM, MAX_WIDE_MM);
    let length_mm = uniform(&mut rng, 120.0, 400.0);
    // The flange is as long as the web or longer (a beam under a tube).
    let flange_length_mm = length_mm + uniform(&mut rng, 0.0, 100.0);
    let reach = |beyond: f64| w / 2.0 + beyond;
    let (a_reach, b_reach) =
        if narrow_sign < 0.0 { (reach(narrow_mm), reach(wide_mm)) } else { (reach(wide_mm), reach(narrow_mm)) };
    let plate_a = PlateExtent { width_mm: a_reach, length_mm, offset_mm: 0.0 };
    let plate_b = PlateExtent {
        width_mm: b_reach,
        length_mm: flange_length_mm,
        offset_mm: -uniform(&mut rng, 0.0, flange_length_mm - length_mm),
    };
    let table_drop_mm = uniform(&mut rng, MIN_TABLE_DROP_MM, MAX_TABLE_DROP_MM);
    let edge_radius_mm = rounded.then(|| uniform(&mut rng, MIN_EDGE_RADIUS_MM, MAX_EDGE_RADIUS_MM));
    let web_kept_mm = web_top_cropped.then(|| uniform(&mut rng, MIN_WEB_KEPT_MM, MAX_WEB_KEPT_MM));

    // The camera sits on the side it leans over and aims at that side's
    // flange beside the web.
    let view_sign = match view {
        ViewSide::Narrow => narrow_sign,
        ViewSide::Wide => -narrow_sign,
    };
    let azimuth_deg = if view_sign > 0.0 { 0.0 } else { 180.0 } + uniform(&mut rng, -60.0, 60.0);
    let beyond = match view {
        ViewSide::Narrow => uniform(&mut rng, 0.0, narrow_mm),
        ViewSide::Wide => uniform(&mut rng, 0.0, 40.0),
    };
    let across_mm = view_sign * (w / 2.0 + beyond);
    let along_mm = uniform(&mut rng, -0.25, 0.25) * length_mm;
    let spec = SceneSpec {
        joint,
        plate_a,
        plate_b,
        spacer_height_mm: table_drop_mm - f,
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
    let mut name = format!("web-edge-{k:02}-d{distance_mm:.0}-t{tilt_deg:.0}-{}-n{narrow_mm:.0}", view.name());
    if let Some(r) = edge_radius_mm {
        name.push_str(&format!("-r{r:.1}"));
    }
    if web_top_cropped {
        name.push_str("-webcrop");
    }
    if table_cropped {
        name.push_str("-tablecrop");
    }
    WebNearEdge { name, spec, narrow_sign, narrow_mm, view, edge_radius_mm, web_kept_mm, table_cropped }
}

impl WebNearEdge {
    /// A fair scene: valid, one root at least seen along half its length,
    /// and [`MIN_OBSERVED_SEAM_MM`] of that root in the image.
    fn is_fair(&self, camera: &CameraModel) -> bool {
        self.spec.validate().is_ok()
            && seam_truths(&self.spec, camera).iter().any(|s| s.is_seen() && s.truth.length_mm >= MIN_OBSERVED_SEAM_MM)
    }

    /// The index of the narrow side's root among the tee's two
    /// ([`JointGeometry::seam_lines_xz`]: the −x side's first).
    pub fn narrow_root(&self) -> usize {
        usize::from(self.narrow_sign > 0.0)
    }

    /// The flange's cross-section with the narrow side's outer top edge
    /// rounded, where the scene rounds it.
    fn reshape(&self, shapes: &mut [PlateShape; 2]) {
        let Some(radius_mm) = self.edge_radius_mm else { return };
        let JointGeometry::Tee { flange_thickness_mm: f, .. } = self.spec.joint else { return };
        let edge_x = if self.narrow_sign < 0.0 { -self.spec.plate_a.width_mm } else { self.spec.plate_b.width_mm };
        shapes[1] = shapes[1].with_rounded_corner([edge_x, f], radius_mm, EDGE_ARC_SEGMENTS);
    }

    /// Whether a point of the workpiece's frame is kept by the scene's
    /// crops.
    fn kept(&self, p: &Vec3) -> bool {
        let JointGeometry::Tee { flange_thickness_mm: f, .. } = self.spec.joint else { return true };
        let under_table_crop = self.table_cropped && p.z < -TABLE_CROP_UNDER_FLANGE_MM;
        let over_web_crop = self.web_kept_mm.is_some_and(|kept| p.z > f + kept);
        !(under_table_crop || over_web_crop)
    }

    /// The scene captured: rendered with its rounded edge, its crops
    /// applied to the cloud; the truth the tee's.
    pub fn simulate(&self, camera: &CameraModel) -> Simulation {
        let scene = build_scene_reshaped(&self.spec, |k, shapes| {
            if k == 0 {
                self.reshape(shapes);
            }
        });
        let mut sim = simulate_scene(&self.spec, camera, scene);
        if self.table_cropped || self.web_kept_mm.is_some() {
            sim.reshape_in_workpiece_frame(&self.spec, |p| self.kept(p).then_some(*p));
        }
        sim
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scene::SurfaceKind;

    #[test]
    fn the_suite_is_fixed_and_spans_its_classes() {
        let suite = web_near_edge_suite(Draw::Documented);
        assert_eq!(suite.len(), WEB_NEAR_EDGE_SCENES);
        assert_eq!(suite, web_near_edge_suite(Draw::Documented), "the suite is the same on every call");
        let names: std::collections::HashSet<_> = suite.iter().map(|s| &s.name).collect();
        assert_eq!(names.len(), suite.len());
        assert_eq!(suite.iter().filter(|s| s.name.ends_with("-holdout")).count(), WEB_NEAR_EDGE_HOLDOUT);
        let cam = CameraModel::default();
        for s in &suite {
            assert!(s.is_fair(&cam), "{}", s.name);
            let JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, .. } = s.spec.joint else {
                panic!("{} is no tee", s.name);
            };
            let (a, b) = (s.spec.plate_a.width_mm, s.spec.plate_b.width_mm);
            let (narrow, wide) = if s.narrow_sign < 0.0 { (a, b) } else { (b, a) };
            assert!((narrow - w / 2.0 - s.narrow_mm).abs() < 1e-9, "{}", s.name);
            assert!((MIN_NARROW_MM..=MAX_NARROW_MM).contains(&s.narrow_mm), "{}", s.name);
            assert!((MIN_WIDE_MM..=MAX_WIDE_MM).contains(&(wide - w / 2.0)), "{}", s.name);
            let drop = s.spec.spacer_height_mm + f;
            assert!((MIN_TABLE_DROP_MM..=MAX_TABLE_DROP_MM).contains(&drop), "{}", s.name);
            assert!((500.0..=1000.0).contains(&s.spec.placement.distance_mm), "{}", s.name);
            assert!((0.0..=MAX_TILT_DEG).contains(&s.spec.placement.tilt_deg), "{}", s.name);
        }
        let documented = &suite[..WEB_NEAR_EDGE_SCENES - WEB_NEAR_EDGE_HOLDOUT];
        let count = |pick: &dyn Fn(&WebNearEdge) -> bool| documented.iter().filter(|s| pick(s)).count();
        assert_eq!(count(&|s| s.view == ViewSide::Narrow), 6);
        assert_eq!(count(&|s| s.edge_radius_mm.is_some()), 6);
        assert_eq!(count(&|s| s.web_kept_mm.is_some()), 4);
        assert_eq!(count(&|s| s.table_cropped), 4);
        let tilts: Vec<f64> = suite.iter().map(|s| s.spec.placement.tilt_deg).collect();
        assert!(tilts.contains(&0.0) && tilts.contains(&MAX_TILT_DEG));
    }

    #[test]
    fn the_narrow_edge_is_rounded_and_the_crops_drop_the_table_and_the_web_top() {
        let suite = web_near_edge_suite(Draw::Documented);
        let scene = suite.iter().find(|s| s.edge_radius_mm.is_some()).expect("a rounded scene");
        let JointGeometry::Tee { flange_thickness_mm: f, .. } = scene.spec.joint else { panic!("no tee") };
        let solids = build_scene_reshaped(&scene.spec, |k, shapes| {
            if k == 0 {
                scene.reshape(shapes);
            }
        })
        .solids;
        let flange = solids.iter().filter(|s| s.kind == SurfaceKind::Plate).nth(1).expect("the flange");
        let edge_x = scene.narrow_sign * (scene.narrow_mm + scene.spec.joint.seam_edge_half_width());
        let y = 0.5 * (scene.spec.seam_range()[0] + scene.spec.seam_range()[1]);
        // The square corner is gone, the top a radius in from the edge stays.
        assert!(flange.excess(&Vec3::new(edge_x, y, f)) > 0.2);
        let in_from_edge = edge_x - scene.narrow_sign * scene.edge_radius_mm.unwrap();
        assert!(flange.excess(&Vec3::new(in_from_edge, y, f)).abs() < 1e-9);

        let cropped = WebNearEdge { web_kept_mm: Some(20.0), table_cropped: true, ..scene.clone() };
        assert!(!cropped.kept(&Vec3::new(0.0, y, f + 21.0)) && cropped.kept(&Vec3::new(0.0, y, f + 19.0)));
        assert!(!cropped.kept(&Vec3::new(edge_x, y, -scene.spec.spacer_height_mm)));
        assert!(cropped.kept(&Vec3::new(edge_x, y, 0.0)));
        assert!(scene.web_kept_mm.is_some() || scene.kept(&Vec3::new(0.0, y, f + 100.0)));
    }
}
