//! The figures along the seam and the weld process over the binary link:
//! a controller granted `along_seam` gets, with a procedure configured,
//! each seam's figures at every waypoint and its process, exactly as the
//! library plans them; one that did not ask gets the same seams without
//! them.

use std::sync::Arc;

use weldseam::config::procedure::Procedure;
use weldseam::convert::{from_proto, to_proto};
use weldseam::joint::JointType;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::ControllerClient;
use weldseam::pipeline::Planner;
use weldseam::server::Stopped;
use weldseam_proto::message::FrameSelect;
use weldseam_proto::session::capability;

use super::{WAIT, config, sim_request, wait_for_camera};
use crate::scenes;
use crate::util::Cell;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_over_the_binary_link_carries_the_process_to_a_controller_that_asked() {
    let mut config = config();
    config.process.procedure = Some(Procedure::example());
    config.process.plate_thickness_mm = Some(6.0);
    let sim = scenes::demo(JointType::IButt);
    let cell = Cell::start(config.clone()).await;
    let (stop_cam, cam) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());

    let asked = capability::ALONG_SEAM;
    let mut granted = ControllerClient::connect_asking(&cell.controller, "along", asked).await.unwrap();
    assert_eq!(granted.capabilities, asked);
    wait_for_camera(&mut granted).await;
    let request = sim_request(1, JointType::IButt, sim, FrameSelect::Trigger);
    let reply = granted.plan(request.clone(), WAIT).await.unwrap();
    let seam = reply.result.seams.first().expect("a seam");
    let n = seam.waypoints.len();
    assert!(n >= 10, "{n} waypoints");

    // The figures: one per waypoint, the gap measured nearly everywhere,
    // each with its standard error.
    let figures = seam.along_seam.as_ref().expect("the figures along the seam");
    assert_eq!(figures.len(), n);
    let gaps: Vec<_> = figures.iter().filter_map(|f| f.gap_mm).collect();
    assert!(gaps.len() * 10 >= n * 9, "gap measured at {} of {n} waypoints", gaps.len());
    assert!(gaps.iter().all(|g| g.value > 0.0 && g.sigma > 0.0), "{gaps:?}");

    // The process: the procedure's name, a process per waypoint, the
    // welded ones with their passes' settings, each cut with its rule.
    let process = seam.process.as_ref().expect("the process, a procedure being configured");
    assert_eq!(process.procedure, Procedure::example().name);
    assert_eq!(process.waypoints.len(), n);
    let welded: Vec<_> = process.waypoints.iter().flatten().collect();
    assert!(welded.len() * 10 >= n * 9, "{} of {n} welded: {:?}", welded.len(), process.cut);
    for w in &welded {
        let pass = w.passes.first().expect("a pass");
        assert!(pass.travel_speed_mm_s > 0.0 && pass.wire_feed_m_min > 0.0 && pass.current_a > 0.0, "{pass:?}");
        assert!(pass.deposited_area_mm2 > 0.0 && pass.voltage_v > 0.0, "{pass:?}");
    }
    for cut in &process.cut {
        assert!(weldseam::rules::by_id(&cut.rule).is_some_and(|_| cut.rule.starts_with("process.")), "{cut:?}");
    }

    // Exactly what the library plans of the same frame and request.
    let library = Planner::new(config.clone())
        .plan(&sim.cloud, &from_proto::plan_request(&request, config.euler).unwrap())
        .expect("the library plans the frame");
    let mut expected = to_proto::plan_result(&library, config.euler);
    to_proto::add_along_seam(&mut expected, &library);
    assert_eq!(seam.along_seam, expected.seams[0].along_seam);
    assert_eq!(seam.process, expected.seams[0].process);

    // A controller that did not ask: the same seam, without them.
    let mut plain = ControllerClient::connect(&cell.controller, "plain").await.unwrap();
    let bare = plain.plan(sim_request(2, JointType::IButt, sim, FrameSelect::FrameId(reply.frame_id)), WAIT).await;
    let bare = bare.unwrap();
    let mut stripped = seam.clone();
    (stripped.along_seam, stripped.process) = (None, None);
    assert_eq!(bare.result.seams, vec![stripped]);

    let _ = stop_cam.send(());
    cam.await.unwrap();
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}
