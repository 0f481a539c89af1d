//! A consumer depth camera (RealSense-class active stereo) and the seeded
//! suite of its scans as users hand them over: cropped to a strip around
//! the seam, voxel-downsampled at 1 mm and in metres.
//!
//! The camera is the kind a new user tries first: 1280 x 720 px over about
//! 87 x 58 degrees, good from 0.2 to 0.5 m, with depth noise growing with
//! the square of depth (about 0.12 % of depth at 0.3 m and 0.2 % at
//! 0.5 m) and more dropouts than an industrial structured-light camera.
//! The point of the suite is that the planner is run with its default
//! config, the paper's camera configured: the user configures nothing.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::draw::Draw;
use super::suite::framing;
use super::variants::{Step, Variant};
use super::{
    CameraPlacement, JointGeometry, NoiseSpec, PlateExtent, SceneSpec, default_base_from_workpiece, demo_scene,
    paper_hand_eye,
};
use crate::camera::CameraModel;
use crate::geometry::pose::EulerConvention;
use crate::joint::JointType;

/// Which camera the simulator renders with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CameraPreset {
    /// The paper's industrial structured-light camera (Table 1), the
    /// default everywhere.
    #[default]
    Industrial,
    /// A RealSense-class consumer depth camera ([`consumer_camera`]).
    Consumer,
}

impl CameraPreset {
    pub fn camera(self) -> CameraModel {
        match self {
            CameraPreset::Industrial => CameraModel::default(),
            CameraPreset::Consumer => consumer_camera(),
        }
    }

    pub fn noise(self) -> NoiseSpec {
        match self {
            CameraPreset::Industrial => NoiseSpec::default(),
            CameraPreset::Consumer => consumer_noise(),
        }
    }
}

/// Horizontal and vertical field of view of the consumer camera, degrees
/// (the depth stream of a RealSense D435-class unit at 1280 x 720).
pub const CONSUMER_FOV_DEG: [f64; 2] = [87.0, 58.0];
/// The distance the consumer camera's field of view and accuracy are
/// given at, mm: the far end of its good range.
const CONSUMER_REFERENCE_MM: f64 = 500.0;
/// Depth noise (one sigma along the ray) at [`CONSUMER_REFERENCE_MM`]:
/// 0.2 % of depth there, growing with the square of depth, so 0.36 mm
/// (0.12 %) at 300 mm.
const CONSUMER_SIGMA_AT_REFERENCE_MM: f64 = 1.0;
/// Distance between the stereo pair's cameras (and so the emitter's
/// offset for shadows), mm.
const CONSUMER_BASELINE_MM: f64 = 50.0;

/// The consumer depth camera: 1280 x 720 px, [`CONSUMER_FOV_DEG`], depth
/// sigma 1 mm at 500 mm growing with z squared ([`CameraModel::depth_sigma`]).
pub fn consumer_camera() -> CameraModel {
    let [h, v] = CONSUMER_FOV_DEG.map(|deg| 2.0 * CONSUMER_REFERENCE_MM * (deg / 2.0).to_radians().tan());
    CameraModel {
        width_px: 1280,
        height_px: 720,
        fov_width_mm: h,
        fov_height_mm: v,
        fov_distance_mm: CONSUMER_REFERENCE_MM,
        baseline_mm: CONSUMER_BASELINE_MM,
        nominal_accuracy_mm: CONSUMER_SIGMA_AT_REFERENCE_MM,
        ..CameraModel::default()
    }
}

/// How a consumer stereo camera degrades a frame: the depth noise of its
/// [`CameraModel`], three times the industrial camera's dropouts (stereo
/// matching fails on shiny, untextured steel), flying pixels at depth
/// edges, and returns lost at a less grazing angle.
pub fn consumer_noise() -> NoiseSpec {
    NoiseSpec { dropout_rate: 0.01, max_incidence_deg: 75.0, ..NoiseSpec::default() }
}

/// What a user of such a camera and a point-cloud library hands over: an
/// 80 mm strip around the seam (40 mm either side), voxel-downsampled at
/// 1 mm, in metres.
pub fn consumer_variant() -> Variant {
    Variant::from_steps(&[Step::Cropped { width_mm: 40.0 }, Step::Voxel { size_mm: 1.0 }, Step::Metres])
        .unwrap_or_else(|_| unreachable!("three different steps"))
}

/// [`demo_scene`] as the case has it: plates 420 mm long seen from
/// 375 mm (the middle of 300 to 450 mm) at 8 degrees, with the consumer
/// camera's noise; for V-butt a groove about 30 mm wide and 10 mm deep
/// between 12 mm plates, for I-butt a 3 mm gap.
pub fn consumer_demo_scene(joint: JointType) -> SceneSpec {
    let mut spec = demo_scene(joint);
    match joint {
        JointType::VButt => {
            spec.joint = JointGeometry::VButt {
                thickness_mm: 12.0,
                groove_angle_deg: 111.0,
                groove_depth_mm: 10.0,
                root_gap_mm: 1.0,
            }
        }
        // At 1 mm voxels a gap must span a few voxels to show.
        JointType::IButt => spec.joint = JointGeometry::IButt { thickness_mm: 6.0, gap_mm: 3.0 },
        JointType::Lap | JointType::TFillet => {}
    }
    let plate = PlateExtent { width_mm: 120.0, length_mm: 420.0, offset_mm: 0.0 };
    (spec.plate_a, spec.plate_b) = (plate, plate);
    spec.placement.distance_mm = 375.0;
    spec.placement.tilt_deg = 8.0;
    spec.noise = consumer_noise();
    spec
}

/// Scenes of each joint type in [`consumer_suite`], in order V-butt,
/// I-butt, lap.
pub const CONSUMER_SCENES: [(JointType, usize); 3] =
    [(JointType::VButt, 10), (JointType::IButt, 5), (JointType::Lap, 5)];
/// The last this many scenes of each joint type are held out: named
/// `-holdout`, drawn from their own seeds, and never used to choose any
/// parameter of the planner or of this suite.
pub const CONSUMER_HOLDOUT_PER_JOINT: usize = 2;
/// Camera standoffs of the suite, mm: the consumer camera's good range.
pub const CONSUMER_DISTANCE_MM: [f64; 2] = [200.0, 500.0];
/// Camera tilts of the suite, degrees.
pub const CONSUMER_TILT_DEG: [f64; 2] = [0.0, 30.0];
/// The shortest seam a consumer scene shows; the longest the field of
/// view allows is about 400 mm.
pub const CONSUMER_MIN_SEAM_MM: f64 = 150.0;
/// How much of each plate's top must be in view beside the seam: more
/// than the 40 mm crop leaves of it beside the groove.
pub const CONSUMER_MIN_PLATE_IN_VIEW_MM: f64 = 30.0;

const CONSUMER_SEED: u64 = 0xc0_05e7;
const CONSUMER_HOLDOUT_SEED: u64 = 0x401d_0075;
const MAX_DRAWS: usize = 2000;

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let unit = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    lo + (hi - lo) * unit
}

/// One joint's cross-section as consumer-camera users weld them: V-grooves
/// 24 to 32 mm wide and 8 to 10 mm deep, I-butt gaps of 2.5 to 4 mm (at
/// least two and a half voxels: narrower ones cannot show at 1 mm), lap
/// plates 4 to 10 mm thick.
fn draw_joint(joint: JointType, rng: &mut ChaCha8Rng) -> JointGeometry {
    match joint {
        JointType::VButt => {
            let thickness_mm = uniform(rng, 10.0, 14.0);
            let groove_depth_mm = uniform(rng, 8.0, 10.0f64.min(thickness_mm - 1.0));
            let root_gap_mm = uniform(rng, 0.0, 2.0);
            let top_width_mm = uniform(rng, 24.0, 32.0);
            let half_angle = ((top_width_mm - root_gap_mm) / 2.0 / groove_depth_mm).atan();
            JointGeometry::VButt {
                thickness_mm,
                groove_angle_deg: 2.0 * half_angle.to_degrees(),
                groove_depth_mm,
                root_gap_mm,
            }
        }
        JointType::IButt => {
            JointGeometry::IButt { thickness_mm: uniform(rng, 4.0, 10.0), gap_mm: uniform(rng, 2.5, 4.0) }
        }
        JointType::Lap => JointGeometry::Lap {
            lower_thickness_mm: uniform(rng, 4.0, 10.0),
            upper_thickness_mm: uniform(rng, 4.0, 10.0),
            overlap_mm: uniform(rng, 20.0, 60.0),
        },
        JointType::TFillet => super::suite::draw_tee(rng),
    }
}

/// One scene at a fixed standoff and tilt, the rest drawn: plates 420 to
/// 480 mm long (a 400 mm strip where the field of view allows), the
/// camera over the seam's middle, leaning and rolled at random.
fn draw_scene(joint: JointType, distance_mm: f64, tilt_deg: f64, seed: u64, rng: &mut ChaCha8Rng) -> SceneSpec {
    let length_mm = uniform(rng, 420.0, 480.0);
    let plate = |rng: &mut ChaCha8Rng| PlateExtent { width_mm: uniform(rng, 80.0, 150.0), length_mm, offset_mm: 0.0 };
    let (plate_a, plate_b) = (plate(rng), plate(rng));
    SceneSpec {
        joint: draw_joint(joint, rng),
        plate_a,
        plate_b,
        spacer_height_mm: uniform(rng, 20.0, 60.0),
        placement: CameraPlacement {
            distance_mm,
            tilt_deg,
            tilt_azimuth_deg: uniform(rng, 0.0, 360.0),
            roll_deg: uniform(rng, 0.0, 360.0),
            target_offset_mm: [uniform(rng, -10.0, 10.0), uniform(rng, -0.1, 0.1) * length_mm],
        },
        noise: consumer_noise(),
        base_from_workpiece: default_base_from_workpiece(),
        hand_eye: paper_hand_eye(),
        euler: EulerConvention::Zyx,
        seed,
        faults: Vec::new(),
        others: Vec::new(),
    }
}

/// The consumer camera's evaluation scenes, named like
/// `consumer-v-butt-03-d300-t10` (`-holdout` on the held-out ones): per
/// joint type, standoffs and tilts stratified over [`CONSUMER_DISTANCE_MM`]
/// and [`CONSUMER_TILT_DEG`], each scene showing at least
/// [`CONSUMER_MIN_SEAM_MM`] of seam and [`CONSUMER_MIN_PLATE_IN_VIEW_MM`]
/// of both plates. The same list on every call.
pub fn consumer_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    stratified_suite(
        draw,
        &Strata {
            prefix: "consumer",
            scenes: CONSUMER_SCENES,
            distance_mm: CONSUMER_DISTANCE_MM,
            seed: CONSUMER_SEED,
            holdout_seed: CONSUMER_HOLDOUT_SEED,
        },
    )
}

/// Scenes of each joint type in [`consumer_far_suite`].
pub const CONSUMER_FAR_SCENES: [(JointType, usize); 3] =
    [(JointType::VButt, 10), (JointType::IButt, 6), (JointType::Lap, 8)];
/// Standoffs of [`consumer_far_suite`], mm: the far end of the consumer
/// camera's good range, where its depth noise (0.74 to 1 mm) is as large
/// as the 1 mm voxels the scans are handed over in.
pub const CONSUMER_FAR_DISTANCE_MM: [f64; 2] = [430.0, 500.0];
const CONSUMER_FAR_SEED: u64 = 0xfa_12_c0;
const CONSUMER_FAR_HOLDOUT_SEED: u64 = 0xfa12_401d;

/// The consumer camera at the far end of its range, named like
/// `consumer-far-lap-03-d460-t10`: drawn as [`consumer_suite`] is, from
/// seeds of its own, at standoffs over [`CONSUMER_FAR_DISTANCE_MM`]. The
/// consumer suite's tuning scenes stop at 433 mm and its held-out ones
/// are the two farthest of each joint type, so without this suite the
/// noisiest scans were seen only held out. The last two of each joint
/// type are held out here too.
pub fn consumer_far_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    stratified_suite(
        draw,
        &Strata {
            prefix: "consumer-far",
            scenes: CONSUMER_FAR_SCENES,
            distance_mm: CONSUMER_FAR_DISTANCE_MM,
            seed: CONSUMER_FAR_SEED,
            holdout_seed: CONSUMER_FAR_HOLDOUT_SEED,
        },
    )
}

/// What a stratified consumer suite is drawn from.
struct Strata {
    prefix: &'static str,
    scenes: [(JointType, usize); 3],
    distance_mm: [f64; 2],
    seed: u64,
    holdout_seed: u64,
}

/// The stride that permutes `count` tilts: 3 (the consumer suite's), or
/// the next odd number sharing no factor with `count`, so that every tilt
/// of the range is drawn once.
fn tilt_stride(count: usize) -> usize {
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    (3..).step_by(2).find(|&stride| gcd(stride, count) == 1).unwrap_or(1)
}

fn stratified_suite(draw: Draw, strata: &Strata) -> Vec<(String, SceneSpec)> {
    let camera = consumer_camera();
    let mut suite = Vec::new();
    for (j, (joint, count)) in strata.scenes.into_iter().enumerate() {
        let steps = (count - 1).max(1) as f64;
        for k in 0..count {
            // Distances in order, tilts permuted, so each joint spans both.
            let distance_mm =
                strata.distance_mm[0] + (strata.distance_mm[1] - strata.distance_mm[0]) * k as f64 / steps;
            let tilt_step = (k * tilt_stride(count) + j) % count;
            let tilt_deg = CONSUMER_TILT_DEG[1] * tilt_step as f64 / steps;
            let holdout = k >= count - CONSUMER_HOLDOUT_PER_JOINT;
            let stream = (j * 100 + k) as u64;
            let base_seed = draw.seed(if holdout { strata.holdout_seed } else { strata.seed });
            let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
            rng.set_stream(stream);
            let seed = base_seed.wrapping_add(stream);
            let mut spec = draw_scene(joint, distance_mm, tilt_deg, seed, &mut rng);
            for _ in 1..MAX_DRAWS {
                let f = framing(&spec, &camera);
                let framed = f.observed_seam_mm >= CONSUMER_MIN_SEAM_MM
                    && f.plate_in_view_mm.iter().all(|w| *w >= CONSUMER_MIN_PLATE_IN_VIEW_MM);
                if spec.validate().is_ok() && framed {
                    break;
                }
                spec = draw_scene(joint, distance_mm, tilt_deg, seed, &mut rng);
            }
            let name = format!(
                "{}-{}-{k:02}-d{distance_mm:.0}-t{tilt_deg:.0}{}",
                strata.prefix,
                joint.dashed_name(),
                draw.suffix(holdout)
            );
            suite.push((name, spec));
        }
    }
    suite
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{simulate, truth};

    #[test]
    fn the_consumer_camera_has_its_field_of_view_and_noise() {
        let cam = consumer_camera();
        let hfov = 2.0 * (cam.width_px as f64 / 2.0 / cam.fx()).atan().to_degrees();
        let vfov = 2.0 * (cam.height_px as f64 / 2.0 / cam.fy()).atan().to_degrees();
        assert!((hfov - 87.0).abs() < 0.2 && (vfov - 58.0).abs() < 0.2, "{hfov} x {vfov}");
        for (z, percent) in [(300.0, 0.12), (500.0, 0.2)] {
            let relative = cam.depth_sigma(z) / z * 100.0;
            assert!((relative - percent).abs() < 0.005, "{relative} % at {z}");
        }
        assert_eq!(CameraPreset::default().camera(), CameraModel::default());
        assert_eq!(CameraPreset::Industrial.noise(), NoiseSpec::default());
        assert_eq!(consumer_variant().to_string(), "cropped:40,voxel:1,metres");
    }

    #[test]
    fn the_consumer_suites_are_fixed_stratified_and_framed() {
        for (suite, scenes, [near, far]) in [
            (consumer_suite(Draw::Documented), CONSUMER_SCENES, CONSUMER_DISTANCE_MM),
            (consumer_far_suite(Draw::Documented), CONSUMER_FAR_SCENES, CONSUMER_FAR_DISTANCE_MM),
        ] {
            a_consumer_suite_is_fixed_stratified_and_framed(
                &suite,
                scenes,
                [near, far],
                Some(CONSUMER_HOLDOUT_PER_JOINT),
            );
        }
        assert_eq!(consumer_suite(Draw::Documented), consumer_suite(Draw::Documented));
        assert_eq!(consumer_far_suite(Draw::Documented), consumer_far_suite(Draw::Documented));
        let far_names: Vec<String> = consumer_far_suite(Draw::Documented).into_iter().map(|(n, _)| n).collect();
        assert!(
            consumer_suite(Draw::Documented).iter().all(|(n, _)| !far_names.contains(n)),
            "the suites share no name"
        );
    }

    fn a_consumer_suite_is_fixed_stratified_and_framed(
        suite: &[(String, SceneSpec)],
        scenes: [(JointType, usize); 3],
        [near, far]: [f64; 2],
        unseen_per_joint: Option<usize>,
    ) {
        let expected: usize = scenes.iter().map(|(_, n)| n).sum();
        assert_eq!(suite.len(), expected);
        let cam = consumer_camera();
        for (joint, count) in scenes {
            let scenes: Vec<_> = suite.iter().filter(|(_, s)| s.joint.joint_type() == joint).collect();
            assert_eq!(scenes.len(), count);
            let holdouts = scenes.iter().filter(|(n, _)| crate::sim::draw::is_unseen(n)).count();
            assert_eq!(holdouts, unseen_per_joint.unwrap_or(count), "{joint}");
            let distances: Vec<f64> = scenes.iter().map(|(_, s)| s.placement.distance_mm).collect();
            assert!(distances.contains(&near) && distances.contains(&far), "{joint}: {distances:?}");
            let mut tilts: Vec<f64> = scenes.iter().map(|(_, s)| s.placement.tilt_deg).collect();
            tilts.sort_by(f64::total_cmp);
            tilts.dedup();
            assert_eq!(tilts.len(), count, "{joint}: every tilt once, {tilts:?}");
            assert!(tilts.contains(&0.0) && tilts.contains(&30.0), "{joint}: {tilts:?}");
        }
        for (name, spec) in suite {
            assert_eq!(spec.validate(), Ok(()), "{name}");
            let f = framing(spec, &cam);
            assert!(f.observed_seam_mm >= CONSUMER_MIN_SEAM_MM, "{name}: {f:?}");
            assert!(f.plate_in_view_mm.iter().all(|w| *w >= CONSUMER_MIN_PLATE_IN_VIEW_MM), "{name}: {f:?}");
            if let JointGeometry::VButt { .. } = spec.joint {
                let width = 2.0 * spec.joint.seam_edge_half_width();
                assert!((23.9..=32.1).contains(&width), "{name}: groove {width} mm wide");
            }
        }
    }

    #[test]
    fn a_fresh_draw_keeps_the_strata_and_framing_and_redraws_every_scene() {
        let documented = consumer_far_suite(Draw::Documented);
        let fresh = consumer_far_suite(Draw::Fresh(1));
        // Every scene of a fresh draw is unseen.
        a_consumer_suite_is_fixed_stratified_and_framed(&fresh, CONSUMER_FAR_SCENES, CONSUMER_FAR_DISTANCE_MM, None);
        assert_eq!(fresh, consumer_far_suite(Draw::Fresh(1)), "a fresh draw is the same on every call");
        assert_ne!(fresh, consumer_far_suite(Draw::Fresh(2)));
        for ((name, spec), (documented_name, documented_spec)) in fresh.iter().zip(&documented) {
            let stem = documented_name.trim_end_matches("-holdout");
            assert_eq!(name, &format!("{stem}-fresh1"));
            assert_eq!(spec.joint.joint_type(), documented_spec.joint.joint_type(), "{name}");
            assert_eq!(spec.placement.distance_mm, documented_spec.placement.distance_mm, "{name}");
            assert_eq!(spec.placement.tilt_deg, documented_spec.placement.tilt_deg, "{name}");
            assert_ne!(spec.seed, documented_spec.seed, "{name}: the noise is redrawn");
            assert_ne!(spec.joint, documented_spec.joint, "{name}: so is the joint");
        }
    }

    #[test]
    fn the_demo_v_groove_shows_a_long_seam_in_the_consumer_frame() {
        let spec = consumer_demo_scene(JointType::VButt);
        assert_eq!(spec.validate(), Ok(()));
        let width = 2.0 * spec.joint.seam_edge_half_width();
        assert!((width - 30.0).abs() < 0.5, "{width}");
        let cam = consumer_camera();
        let truth = truth::ground_truth(&spec, &cam);
        assert!(truth.length_mm > 380.0, "{} mm of seam in view", truth.length_mm);
        let sim = simulate(&spec, &cam);
        assert_eq!((sim.cloud.width(), sim.cloud.height()), (1280, 720));
        let strip = consumer_variant().apply(&sim, spec.seed);
        assert!(!strip.cloud.is_organized());
        assert!(strip.cloud.points().iter().all(|p| p[2] > 0.2 && p[2] < 0.5), "metres, 0.2 to 0.5 m");
    }
}
