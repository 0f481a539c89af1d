//! Clouds in metres and in the robot base frame: the units guess on the
//! simulated suite in both units, base-frame clouds planned as their
//! camera-frame originals, and clouds no camera could have seen refused
//! with the reason.

use nalgebra::{Isometry3, Point3, Translation3};
use weldseam::cloud::{Point, PointCloud};
use weldseam::config::Config;
use weldseam::geometry::pose::RobotPose;
use weldseam::pipeline::input::guess_units;
use weldseam::pipeline::{CloudFrame, Plan, PlanRequest, Planner, Stage, Units};
use weldseam::sim::{Draw, eval_suite};

use crate::scenes;

fn mapped(cloud: &PointCloud, f: impl Fn(Point) -> Point) -> PointCloud {
    let points = cloud.points().iter().map(|&p| if p[0].is_finite() { f(p) } else { p }).collect();
    PointCloud::organized(cloud.width(), cloud.height(), points).expect("same size")
}

#[test]
fn units_are_guessed_right_on_the_suite_in_millimetres_and_in_metres() {
    let camera = weldseam::camera::CameraModel::default();
    for (name, spec) in eval_suite(Draw::Documented).into_iter().step_by(3) {
        let sim = scenes::rendered(&spec, &camera);
        let mm = guess_units(&sim.cloud);
        assert!(!mm.metres, "{name}: millimetres taken for metres (median {})", mm.median_distance);
        let metres = guess_units(&mapped(&sim.cloud, |p| p.map(|c| c * 1e-3)));
        assert!(metres.metres, "{name}: metres taken for millimetres (median {})", metres.median_distance);
    }
    // The ends of the working range: 100 mm to 3 m, in either unit.
    for depth_mm in [100.0f32, 3000.0] {
        let plane: Vec<Point> = (0..400).map(|i| [(i % 20) as f32 - 10.0, (i / 20) as f32 - 10.0, depth_mm]).collect();
        let mm = PointCloud::unorganized(plane.clone());
        let metres = PointCloud::unorganized(plane.iter().map(|p| p.map(|c| c * 1e-3)).collect());
        assert!(!guess_units(&mm).metres, "{depth_mm} mm");
        assert!(guess_units(&metres).metres, "{depth_mm} mm in metres");
    }
}

fn first_seam_ends(plan: &Plan) -> [nalgebra::Vector3<f64>; 2] {
    let seam = &plan.seams[0];
    [seam.waypoints[0].position, seam.waypoints[seam.waypoints.len() - 1].position]
}

#[test]
fn a_cloud_in_metres_plans_like_the_millimetre_one() {
    let (name, spec) = eval_suite(Draw::Documented).swap_remove(0);
    let config = Config::default();
    let sim = scenes::rendered(&spec, &config.camera);
    let planner = Planner::new(config);
    let request = PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose);
    let mm_plan = planner.plan(&sim.cloud, &request).expect("millimetres plan");
    let metres = mapped(&sim.cloud, |p| p.map(|c| c * 1e-3));
    let guessed = PlanRequest { units: Units::Auto, ..request.clone() };
    let explicit = PlanRequest { units: Units::Metres, ..request.clone() };
    for request in [guessed, explicit] {
        let plan = planner.plan(&metres, &request).unwrap_or_else(|e| panic!("{name}: {e}"));
        for (a, b) in first_seam_ends(&plan).iter().zip(first_seam_ends(&mm_plan)) {
            assert!((a - b).norm() < 0.05, "{name}: ends {a:?} vs {b:?}");
        }
    }
}

#[test]
fn a_base_frame_cloud_plans_the_seam_of_the_camera_frame_one() {
    let (name, spec) = eval_suite(Draw::Documented).swap_remove(1);
    let config = Config::default();
    let sim = scenes::rendered(&spec, &config.camera);
    // Coordinates on a 1/1024 mm lattice, a pose turned by right angles and
    // whole-millimetre offsets: the move to the base frame and back is then
    // exact in f32, so both clouds are the same points.
    let camera_cloud = mapped(&sim.cloud, |p| p.map(|c| (c * 1024.0).round() / 1024.0));
    let pose = RobotPose { xyz_mm: [300.0, -200.0, 400.0], angles_deg: [90.0, 0.0, 180.0] };
    let hand_eye = Isometry3::from_parts(Translation3::new(10.0, -20.0, 100.0), nalgebra::UnitQuaternion::identity());
    let base_from_camera = pose.to_isometry(config.euler) * hand_eye;
    let base_cloud = mapped(&camera_cloud, |p| {
        let q = base_from_camera * Point3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
        [q.x as f32, q.y as f32, q.z as f32]
    });
    let planner = Planner::new(config);
    let request = PlanRequest {
        hand_eye: Some(hand_eye),
        units: Units::Millimetres,
        ..PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), pose)
    };
    let in_camera = planner.plan(&camera_cloud, &request).unwrap_or_else(|e| panic!("{name}: {e}"));
    let base_request = PlanRequest { cloud_frame: CloudFrame::Base, units: Units::Auto, ..request.clone() };
    let in_base = planner.plan(&base_cloud, &base_request).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (a, b) = (&in_camera.seams[0].waypoints, &in_base.seams[0].waypoints);
    assert_eq!(a.len(), b.len(), "{name}");
    for (p, q) in a.iter().zip(b) {
        assert!((p.position - q.position).norm() < 1e-6, "{name}: {:?} vs {:?}", p.position, q.position);
    }
    // Planned as a camera-frame cloud, the base-frame one is refused:
    // every point lies outside any camera's view.
    let err = planner.plan(&base_cloud, &request).expect_err("a base-frame cloud is no camera view");
    assert_eq!((err.rule.id, err.stage), ("frame.no_valid_point", Stage::Input), "{err}");
}

#[test]
fn clouds_no_camera_could_see_are_refused_with_the_reason() {
    let (_, spec) = eval_suite(Draw::Documented).swap_remove(0);
    let config = Config::default();
    let sim = scenes::rendered(&spec, &config.camera);
    let planner = Planner::new(config);
    let request = PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose);
    let behind = mapped(&sim.cloud, |[x, y, z]| [x, y, -z]);
    let err = planner.plan(&behind, &request).expect_err("behind the camera");
    assert_eq!((err.rule.id, err.stage), ("frame.not_in_camera_frame", Stage::Input), "{err}");
    assert!(err.reason.contains("lie behind the camera (z <= 0)"), "{err}");
    assert!(err.reason.contains("--cloud-frame base"), "{err}");
    let sideways = mapped(&sim.cloud, |[x, y, z]| [x + 20.0 * z, y, z]);
    let err = planner.plan(&sideways, &request).expect_err("beyond any field of view");
    assert_eq!((err.rule.id, err.stage), ("frame.not_in_camera_frame", Stage::Input), "{err}");
    // The figure the rule read: points off the axis, not behind.
    assert!(err.reason.contains("off its axis, beyond any camera's field of view"), "{err}");
}

/// A simulated frame moved along the optical axis until its plates lie a
/// sixth of its width from the origin, as a robot's base frame holds a
/// workpiece on a table beside the robot: no point lies behind the camera
/// or off any view's cone, but seen from the origin the points spread
/// wider across than any camera sees, and the refusal says so with the
/// figure. The frame where it was is a camera's view and plans.
#[test]
fn a_cloud_spread_wider_than_any_camera_sees_is_refused_as_no_camera_view() {
    use weldseam::pipeline::input::{AngularExtent, MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG};
    let (_, spec) = eval_suite(Draw::Documented).swap_remove(0);
    let config = Config::default();
    let sim = scenes::rendered(&spec, &config.camera);
    let valid: Vec<Point> = sim.cloud.points().iter().copied().filter(|p| p[0].is_finite()).collect();
    let (low, high) = valid.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    let mut depths: Vec<f32> = valid.iter().map(|p| p[2]).collect();
    depths.sort_unstable_by(f32::total_cmp);
    let shift = depths[depths.len() / 2] - (high - low) / 6.0;
    let close = mapped(&sim.cloud, |[x, y, z]| [x, y, z - shift]);

    let seen = AngularExtent::of(&sim.cloud).expect("a frame's spread");
    assert!(!seen.wider_than_any_camera(), "{seen:?}");
    let wide = AngularExtent::of(&close).expect("a frame's spread");
    assert!(wide.across_x_deg > MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG, "{wide:?}");

    let planner = Planner::new(config);
    let request = PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose);
    assert!(planner.plan(&sim.cloud, &request).is_ok(), "the frame where it was plans");
    let err = planner.plan(&close, &request).expect_err("wider than any camera sees");
    assert_eq!((err.rule.id, err.stage), ("frame.not_in_camera_frame", Stage::Input), "{err}");
    assert!(err.reason.contains("across x") && err.reason.contains("any depth camera sees"), "{err}");
    assert!(err.reason.contains("--cloud-frame base"), "{err}");
}

/// A cloud handed over by value (`Planner::plan_owned`, as `weldseam plan`
/// and the daemon plan the frames they no longer need) is converted in
/// place instead of copied, and plans as the same cloud lent does: the
/// same seams, counts and refusals on every variant of the bench's table
/// and on their mixes, the points the camera cannot measure included.
#[test]
fn a_cloud_planned_by_value_plans_as_the_same_cloud_borrowed() {
    use weldseam::sim::scenarios::{Scenario, VARIANT_JOINT, VARIANTS, camera_with_size};
    use weldseam::sim::variants::Variant;
    let scenario = Scenario::new(VARIANT_JOINT, 500.0, camera_with_size(896, 560));
    let frame = scenes::scenario(&scenario);
    let planner = Planner::new(Config { camera: scenario.camera, ..Config::default() });
    let untimed = |plan: Result<Plan, _>| plan.map(|plan| Plan { timings: Default::default(), ..plan });
    let mut planned = 0;
    for text in VARIANTS.into_iter().chain(["unorganized,metres,base", "cropped:25,metres"]) {
        let variant = Variant::parse(text).unwrap();
        let sim = variant.apply(frame, scenario.seed());
        let mut request = PlanRequest::new(scenario.joint, sim.truth.groove_depth_mm, sim.pose);
        request.units = Units::Auto;
        if variant.in_base_frame() {
            request.cloud_frame = CloudFrame::Base;
        }
        let borrowed = untimed(planner.plan(&sim.cloud, &request));
        let owned = untimed(planner.plan_owned(sim.cloud.clone(), &request));
        assert_eq!(owned, borrowed, "{text}");
        planned += borrowed.is_ok() as usize;
    }
    assert!(planned >= 5, "most variants plan: {planned}");
    // A frame with points the camera cannot measure loses them in place.
    let mut points = frame.cloud.points().to_vec();
    for p in points.iter_mut().step_by(97).filter(|p| p[0].is_finite()) {
        p[2] *= 50.0;
    }
    let far = PointCloud::organized(frame.cloud.width(), frame.cloud.height(), points).expect("same size");
    let request = PlanRequest::new(scenario.joint, frame.truth.groove_depth_mm, frame.pose);
    let borrowed = untimed(planner.plan(&far, &request));
    assert_eq!(untimed(planner.plan_owned(far, &request)), borrowed);
    assert!(borrowed.is_ok(), "{borrowed:?}");
}
