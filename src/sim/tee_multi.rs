//! Issue 15's suites: tee joints ([`tee_suite`]) and several workpieces in
//! one frame ([`multi_suite`]), seeded and fixed like the eval suite, with
//! `-holdout` scenes drawn from their own seed that nothing in the planner
//! is to be tuned on. Their truth is every seam in the frame and how much
//! of each the camera sees ([`super::truth::seam_truths`]).

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use super::draw::Draw;
use super::suite::{MIN_OBSERVED_SEAM_MM, ScenePlan, draw_tee, framing, uniform};
use super::truth::{SeamTruth, seam_truths};
use super::{
    CameraPlacement, CornerKind, JointGeometry, NoiseSpec, PlateExtent, SceneSpec, Workpiece,
    default_base_from_workpiece, paper_hand_eye,
};
use crate::camera::CameraModel;
use crate::geometry::pose::EulerConvention;
use crate::joint::JointType;

/// Scenes of [`tee_suite`], and how many of them (the last) are held out.
pub const TEE_SCENES: usize = 22;
pub const TEE_HOLDOUT: usize = 6;
const TEE_SEED: u64 = 0x7ee_2026;
const TEE_HOLDOUT_SEED: u64 = 0x7ee_0ff5;
/// The tee suite's steepest tilt, degrees (issue 15: up to 30).
const TEE_MAX_TILT_DEG: f64 = 30.0;
/// Redraws of a tee scene until the camera sees at least one root.
const MAX_TEE_REDRAWS: u64 = 50;

/// Scenes of [`multi_suite`], and how many of them (the last) are held out.
pub const MULTI_SCENES: usize = 12;
pub const MULTI_HOLDOUT: usize = 3;
const MULTI_SEED: u64 = 0x3a17_2026;
const MULTI_HOLDOUT_SEED: u64 = 0x3a17_0ff5;
/// Standoffs of the several-workpiece scenes: far enough that two or three
/// parts fit the view (525 by 330 mm at 750 mm).
const MULTI_DISTANCE_MM: [f64; 2] = [750.0, 1000.0];
const MULTI_MAX_TILT_DEG: f64 = 30.0;
/// The joints the workpieces of a multi scene take in turn.
const MULTI_JOINTS: [JointType; 4] = [JointType::VButt, JointType::IButt, JointType::Lap, JointType::TFillet];
/// The least share of every seam that must lie in the image.
const MULTI_MIN_IN_IMAGE_SHARE: f64 = 0.8;
const MULTI_MAX_DRAWS: usize = 4000;

/// Tee joints over the working range: 22 scenes, the camera at 500 to
/// 1000 mm and tilted 0 to 30 degrees (each stratum once), webs 4 to 12 mm
/// thick and 40 to 100 mm tall on flanges 6 to 16 mm thick, framed as the
/// eval suite's scenes are (both roots at least 80 mm in the image, 40 mm
/// of the flange in view either side), and at least one root seen along
/// half its length (the other may be hidden behind the web). Named like
/// `t-fillet-07-d738-t10-wide`; the last [`TEE_HOLDOUT`] are `-holdout`.
/// One view sees one root at most: the web's side faces are vertical, so
/// the camera (and the projector beside it) sees the root on its own side
/// and the web hides the other.
pub fn tee_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    (0..TEE_SCENES)
        .map(|k| {
            let plan = ScenePlan::new(JointType::TFillet, 3, k, TEE_MAX_TILT_DEG);
            let holdout = k >= TEE_SCENES - TEE_HOLDOUT;
            let base_seed = draw.seed(if holdout { TEE_HOLDOUT_SEED } else { TEE_SEED });
            let mut spec = plan.draw_framed(base_seed, k as u64, &camera);
            for attempt in 1..MAX_TEE_REDRAWS {
                if seam_truths(&spec, &camera).iter().any(SeamTruth::is_seen) {
                    break;
                }
                spec = plan.draw_framed(base_seed, k as u64 + attempt * TEE_SCENES as u64, &camera);
            }
            (format!("{}{}", plan.name(), draw.suffix(holdout)), spec)
        })
        .collect()
}

/// Scenes of [`corner_suite`], and how many of them (the last) are held
/// out.
pub const CORNER_SCENES: usize = 20;
pub const CORNER_HOLDOUT: usize = 6;
const CORNER_SEED: u64 = 0xc0_2026;
const CORNER_HOLDOUT_SEED: u64 = 0xc0_0ff5;
/// How far an outside corner's web may rise above the flange's top, mm.
const CORNER_MAX_PROUD_MM: f64 = 4.0;

/// Corner joints over the tee suite's range (issue 15 item 2): 20 scenes,
/// inside and outside corners in turn, the camera at 500 to 1000 mm and
/// tilted 0 to 30 degrees (each stratum once), webs 4 to 12 mm thick and
/// 40 to 100 mm tall on flanges 6 to 16 mm thick, an outside corner's web
/// standing on the table (the spacers as tall as its part under the
/// flange) and flush with the flange's top or up to 4 mm proud of it.
/// Each is framed as a tee of the same plates would be, then redrawn until
/// the camera sees the corner's weld along half its length. Named like
/// `corner-inside-03-d612-t14`; the last [`CORNER_HOLDOUT`] are `-holdout`.
pub fn corner_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    (0..CORNER_SCENES)
        .map(|k| {
            let kind = if k % 2 == 0 { CornerKind::Inside } else { CornerKind::Outside };
            let plan = ScenePlan::new(JointType::TFillet, 3, k, TEE_MAX_TILT_DEG);
            let holdout = k >= CORNER_SCENES - CORNER_HOLDOUT;
            let base_seed = draw.seed(if holdout { CORNER_HOLDOUT_SEED } else { CORNER_SEED });
            let attempt_at = |attempt: u64| {
                let stream = k as u64 + attempt * CORNER_SCENES as u64;
                let mut spec = plan.draw_framed(base_seed, stream, &camera);
                let mut rng = ChaCha8Rng::seed_from_u64(base_seed ^ stream);
                let proud_mm = match kind {
                    CornerKind::Inside => 0.0,
                    CornerKind::Outside => uniform(&mut rng, 0.0, CORNER_MAX_PROUD_MM),
                };
                as_corner(&mut spec, kind, proud_mm);
                spec
            };
            let mut spec = attempt_at(0);
            for attempt in 1..MAX_TEE_REDRAWS {
                if spec.validate().is_ok() && seam_truths(&spec, &camera).iter().any(SeamTruth::is_seen) {
                    break;
                }
                spec = attempt_at(attempt);
            }
            let placement = &spec.placement;
            let name = format!(
                "corner-{}-{k:02}-d{:.0}-t{:.0}{}",
                kind.name(),
                placement.distance_mm,
                placement.tilt_deg,
                draw.suffix(holdout)
            );
            (name, spec)
        })
        .collect()
}

/// Makes a tee scene's plates a corner of `kind`: the same flange and web
/// sizes, the web moved to the flange's end (whose reach on the web's side
/// the tee's plate A gave); an outside corner's spacers are made as tall
/// as the web's part under the flange, so the web stands on the table.
fn as_corner(spec: &mut SceneSpec, kind: CornerKind, proud_mm: f64) {
    let JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h } = spec.joint else {
        return;
    };
    spec.joint =
        JointGeometry::Corner { kind, flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h, proud_mm };
    if kind == CornerKind::Outside {
        spec.spacer_height_mm = h - f - proud_mm;
    }
}

/// Several workpieces per frame: 12 scenes of two or three parts (in
/// turn), each with its own joint (V-butt, I-butt, lap and tee in turn),
/// yaw and place on the table, none within 10 mm of another, the camera
/// at 750 to 1000 mm tilted 0 to 30 degrees over their middle, every seam
/// at least 80 % in the image and at least one seam of every part seen
/// along half its length. Named like `multi-04-3-lap+t-fillet+v-butt-d841-t8`;
/// the last [`MULTI_HOLDOUT`] are `-holdout`.
pub fn multi_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    let last = (MULTI_SCENES - 1) as f64;
    (0..MULTI_SCENES)
        .map(|k| {
            let holdout = k >= MULTI_SCENES - MULTI_HOLDOUT;
            let base_seed = draw.seed(if holdout { MULTI_HOLDOUT_SEED } else { MULTI_SEED });
            let count = 2 + k % 2;
            let joints: Vec<JointType> = (0..count).map(|w| MULTI_JOINTS[(k + w) % MULTI_JOINTS.len()]).collect();
            let [d0, d1] = MULTI_DISTANCE_MM;
            let distance = d0 + (d1 - d0) * ((k * 5) % MULTI_SCENES) as f64 / last;
            let tilt = MULTI_MAX_TILT_DEG * ((k * 7) % MULTI_SCENES) as f64 / last;
            let spec = draw_multi(&joints, distance, tilt, base_seed, k as u64, &camera);
            let names: Vec<&str> = joints.iter().map(|j| j.dashed_name()).collect();
            let name =
                format!("multi-{k:02}-{count}-{}-d{distance:.0}-t{tilt:.0}{}", names.join("+"), draw.suffix(holdout));
            (name, spec)
        })
        .collect()
}

/// A small workpiece of `joint` for a frame shared with others: plates 50
/// to 90 mm wide either side of the seam and 120 to 200 mm long.
fn draw_part(joint: JointType, rng: &mut ChaCha8Rng) -> (JointGeometry, [PlateExtent; 2]) {
    let geometry = match joint {
        JointType::TFillet => draw_tee(rng),
        // The eval suite's ranges (index 1: an I-butt's gap of any width).
        other => ScenePlan::new(other, 0, 1, 0.0).draw_joint(rng),
    };
    let length_mm = uniform(rng, 120.0, 200.0);
    let plate = |rng: &mut ChaCha8Rng| PlateExtent { width_mm: uniform(rng, 50.0, 90.0), length_mm, offset_mm: 0.0 };
    (geometry, [plate(rng), plate(rng)])
}

/// Draws a scene of `joints` until it is valid and framed as
/// [`multi_suite`] says (the last draw after [`MULTI_MAX_DRAWS`]).
fn draw_multi(
    joints: &[JointType],
    distance_mm: f64,
    tilt_deg: f64,
    base_seed: u64,
    stream: u64,
    camera: &CameraModel,
) -> SceneSpec {
    let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
    rng.set_stream(stream);
    let seed = base_seed.wrapping_add(stream);
    let mut spec = draw_multi_once(joints, distance_mm, tilt_deg, seed, &mut rng);
    for _ in 1..MULTI_MAX_DRAWS {
        if spec.validate().is_ok() && multi_framing_ok(&spec, camera) {
            break;
        }
        spec = draw_multi_once(joints, distance_mm, tilt_deg, seed, &mut rng);
    }
    spec
}

fn draw_multi_once(
    joints: &[JointType],
    distance_mm: f64,
    tilt_deg: f64,
    seed: u64,
    rng: &mut ChaCha8Rng,
) -> SceneSpec {
    let parts: Vec<Workpiece> = joints
        .iter()
        .enumerate()
        .map(|(k, joint)| {
            let (geometry, [plate_a, plate_b]) = draw_part(*joint, rng);
            // The first part sits at the origin unturned: the scene's frame.
            let (at_mm, yaw_deg) = if k == 0 {
                ([0.0, 0.0], 0.0)
            } else {
                ([uniform(rng, -220.0, 220.0), uniform(rng, -150.0, 250.0)], uniform(rng, -90.0, 90.0))
            };
            Workpiece { joint: geometry, plate_a, plate_b, at_mm, yaw_deg }
        })
        .collect();
    // Aim at the middle of the parts' seams.
    let centres: Vec<[f64; 2]> = parts
        .iter()
        .map(|w| {
            let [y0, y1] = w.seam_range();
            let c = w.pose().transform_point(&crate::geometry::Vec3::new(0.0, (y0 + y1) / 2.0, 0.0).into());
            [c.x, c.y]
        })
        .collect();
    let n = centres.len() as f64;
    let middle = centres.iter().fold([0.0, 0.0], |m, c| [m[0] + c[0] / n, m[1] + c[1] / n]);
    let [first_y0, first_y1] = parts[0].seam_range();
    let first = parts[0];
    SceneSpec {
        joint: first.joint,
        plate_a: first.plate_a,
        plate_b: first.plate_b,
        spacer_height_mm: uniform(rng, 20.0, 60.0),
        placement: CameraPlacement {
            distance_mm,
            tilt_deg,
            tilt_azimuth_deg: uniform(rng, 0.0, 360.0),
            roll_deg: uniform(rng, 0.0, 360.0),
            target_offset_mm: [middle[0], middle[1] - (first_y0 + first_y1) / 2.0],
        },
        noise: NoiseSpec::default(),
        base_from_workpiece: default_base_from_workpiece(),
        hand_eye: paper_hand_eye(),
        euler: EulerConvention::Zyx,
        seed,
        faults: Vec::new(),
        others: parts[1..].to_vec(),
    }
}

/// Every seam at least [`MULTI_MIN_IN_IMAGE_SHARE`] in the image and 80
/// mm long there, and at least one seam of every workpiece seen along
/// half its length.
pub(super) fn multi_framing_ok(spec: &SceneSpec, camera: &CameraModel) -> bool {
    // The cheap test first: the first part's seam in view at all.
    if framing(spec, camera).observed_seam_mm <= 0.0 {
        return false;
    }
    let seams = seam_truths(spec, camera);
    let in_image = seams.iter().all(|s| {
        s.truth.length_mm >= MULTI_MIN_IN_IMAGE_SHARE * s.physical_mm && s.truth.length_mm >= MIN_OBSERVED_SEAM_MM
    });
    in_image && (0..=spec.others.len()).all(|w| seams.iter().any(|s| s.workpiece == w && s.is_seen()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::suite::MIN_PLATE_IN_VIEW_MM;

    #[test]
    fn the_corner_suite_alternates_inside_and_outside_corners_each_seen() {
        let suite = corner_suite(Draw::Documented);
        assert_eq!(suite.len(), CORNER_SCENES);
        assert_eq!(suite, corner_suite(Draw::Documented), "the suite is the same on every call");
        assert_eq!(suite.iter().filter(|(n, _)| n.ends_with("-holdout")).count(), CORNER_HOLDOUT);
        let cam = CameraModel::default();
        for (k, (name, spec)) in suite.iter().enumerate() {
            assert_eq!(spec.validate(), Ok(()), "{name}");
            let JointGeometry::Corner { kind, flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h, proud_mm } =
                spec.joint
            else {
                panic!("{name} is no corner");
            };
            assert_eq!(kind, if k % 2 == 0 { CornerKind::Inside } else { CornerKind::Outside }, "{name}");
            assert!(name.starts_with(&format!("corner-{}-", kind.name())), "{name}");
            assert!((6.0..=16.0).contains(&f) && (4.0..=12.0).contains(&w) && (40.0..=100.0).contains(&h), "{name}");
            assert!((0.0..=CORNER_MAX_PROUD_MM).contains(&proud_mm), "{name}");
            if kind == CornerKind::Outside {
                // The web stands on the table.
                assert!((spec.spacer_height_mm - (h - f - proud_mm)).abs() < 1e-9, "{name}");
            }
            assert!((500.0..=1000.0).contains(&spec.placement.distance_mm), "{name}");
            assert!((0.0..=30.0).contains(&spec.placement.tilt_deg), "{name}");
            let seams = seam_truths(spec, &cam);
            assert_eq!(seams.len(), 1, "{name}: a corner has one weld");
            assert!(seams[0].is_seen(), "{name}");
        }
    }

    #[test]
    fn the_tee_suite_is_stratified_framed_and_fixed() {
        let suite = tee_suite(Draw::Documented);
        assert_eq!(suite.len(), TEE_SCENES);
        assert_eq!(suite, tee_suite(Draw::Documented), "the suite is the same on every call");
        let names: std::collections::HashSet<_> = suite.iter().map(|(n, _)| n).collect();
        assert_eq!(names.len(), suite.len());
        assert_eq!(suite.iter().filter(|(n, _)| n.ends_with("-holdout")).count(), TEE_HOLDOUT);
        let cam = CameraModel::default();
        let mut seen_roots = [0, 0];
        for (name, spec) in &suite {
            assert_eq!(spec.validate(), Ok(()), "{name}");
            let JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h } = spec.joint
            else {
                panic!("{name} is no tee");
            };
            assert!((6.0..=16.0).contains(&f) && (4.0..=12.0).contains(&w) && (40.0..=100.0).contains(&h), "{name}");
            assert!((500.0..=1000.0).contains(&spec.placement.distance_mm), "{name}");
            assert!((0.0..=30.0).contains(&spec.placement.tilt_deg), "{name}");
            let f = framing(spec, &cam);
            assert!(f.observed_seam_mm >= MIN_OBSERVED_SEAM_MM, "{name}: {f:?}");
            assert!(f.plate_in_view_mm.iter().all(|w| *w >= MIN_PLATE_IN_VIEW_MM), "{name}: {f:?}");
            let seen: Vec<usize> = seam_truths(spec, &cam).iter().filter(|s| s.is_seen()).map(|s| s.root).collect();
            // A camera sees one side face of a web at most: the other root
            // lies behind the web.
            let [root] = seen[..] else { panic!("{name}: roots seen {seen:?}") };
            seen_roots[root] += 1;
        }
        assert!(seen_roots.iter().all(|n| *n >= 5), "roots seen on each side: {seen_roots:?}");
        let tilts: Vec<f64> = suite.iter().map(|(_, s)| s.placement.tilt_deg).collect();
        assert!(tilts.contains(&0.0) && tilts.contains(&30.0));
    }

    #[test]
    fn the_multi_suite_has_two_or_three_parts_apart_and_in_view() {
        let suite = multi_suite(Draw::Documented);
        assert_eq!(suite.len(), MULTI_SCENES);
        assert_eq!(suite, multi_suite(Draw::Documented), "the suite is the same on every call");
        assert_eq!(suite.iter().filter(|(n, _)| n.ends_with("-holdout")).count(), MULTI_HOLDOUT);
        let cam = CameraModel::default();
        let mut joints = std::collections::HashSet::new();
        for (name, spec) in &suite {
            assert_eq!(spec.validate(), Ok(()), "{name}");
            assert!((1..=2).contains(&spec.others.len()), "{name}");
            assert!(multi_framing_ok(spec, &cam), "{name}");
            for w in spec.workpieces() {
                joints.insert(w.joint.joint_type());
            }
            let seams = seam_truths(spec, &cam);
            let tees = spec.workpieces().iter().filter(|w| matches!(w.joint, JointGeometry::Tee { .. })).count();
            assert_eq!(seams.len(), spec.others.len() + 1 + tees, "{name}: one seam a part, two a tee");
        }
        assert_eq!(joints.len(), 4, "every joint type appears: {joints:?}");
    }
}
