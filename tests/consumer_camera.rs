//! A consumer depth camera's scan as its user hands it over (an 80 mm
//! strip around the seam, voxel-downsampled at 1 mm, in metres), planned
//! end to end through `Planner::plan` with the default config: the paper's
//! camera configured, units guessed, nothing set for the other camera.
//! Each seam must lie within 1 mm of the truth and cover the visible joint
//! to within 2 mm at both ends.

use weldseam::config::Config;
use weldseam::eval::seam_error;
use weldseam::joint::JointType;
use weldseam::pipeline::input::Units;
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::sim::consumer::{consumer_camera, consumer_demo_scene, consumer_variant};
use weldseam::sim::{SceneSpec, consumer_suite, simulate};

/// Simulates `spec` with the consumer camera, makes the strip and plans it
/// at the default config; panics with the stage and reason if refused.
fn plan_strip(name: &str, spec: &SceneSpec) {
    let sim = consumer_variant().apply(&simulate(spec, &consumer_camera()), spec.seed);
    assert!(!sim.cloud.is_organized(), "{name}: the strip is unorganized");
    assert!(sim.cloud.points().iter().all(|p| p[2] < 1.0), "{name}: the strip is in metres");
    let planner = Planner::new(Config::default());
    let mut request = PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose);
    request.units = Units::Auto;
    let plan = planner.plan(&sim.cloud, &request).unwrap_or_else(|e| panic!("{name}: refused: {e}"));
    let err = seam_error(&sim.truth, &plan.seams[0]).expect("waypoints");
    assert!(err.max_mm < 1.0, "{name}: max error {:.3} mm", err.max_mm);
    assert!(
        err.start_mm < 2.0 && err.end_mm < 2.0,
        "{name}: ends {:.2} and {:.2} mm from the visible seam's ({:.0} mm long)",
        err.start_mm,
        err.end_mm,
        sim.truth.length_mm
    );
}

fn suite_scene(name: &str) -> SceneSpec {
    consumer_suite().into_iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no consumer scene {name}")).1
}

#[test]
fn the_issues_v_groove_strip_plans_at_the_default_settings() {
    // 30 mm wide, 10 mm deep, 420 mm long, seen from 375 mm: 409 mm of the
    // seam are in view, and the plan must span them to within 2 mm.
    let spec = consumer_demo_scene(JointType::VButt);
    plan_strip("the issue's V-groove", &spec);
}

#[test]
fn close_and_steep_v_groove_strips_plan_at_the_default_settings() {
    plan_strip("200 mm, square on", &suite_scene("consumer-v-butt-00-d200-t0"));
    plan_strip("300 mm, tilted 30 degrees", &suite_scene("consumer-v-butt-03-d300-t30"));
}
