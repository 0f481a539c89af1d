//! The measuring code of `weldseam bench` at its smallest: one run of the
//! smallest frame, checked for shape (every stage has its row, every
//! measurement produced a figure), never for speed.

use weldseam::bench::{self, FRAME_SIZES, Scenario, camera_with_size};
use weldseam::joint::JointType;
use weldseam::pipeline::Stage;

use crate::util::write_temp;

fn smallest() -> Scenario {
    let (w, h) = FRAME_SIZES[0];
    Scenario::new(JointType::IButt, 500.0, camera_with_size(w, h))
}

#[test]
fn the_stage_and_scaling_tables_have_every_row() {
    let scenario = smallest();
    let sim = scenario.simulate();
    let timings = bench::time_plans(&scenario, &sim, 1);
    assert_eq!(timings.error, None);
    assert_eq!(timings.totals.len(), 1);
    assert!(timings.valid_points > 0);

    let table = bench::stage_table("per stage", std::slice::from_ref(&timings));
    assert_eq!(table.headers, ["stage", "i_butt ms"]);
    for stage in Stage::IN_ORDER {
        let row = table.row(stage.name()).unwrap_or_else(|| panic!("no {stage} row in\n{}", table.to_text()));
        assert_ne!(row[1], "-", "{stage}");
    }
    for name in ["total", "cpu time, all threads", "valid points", "Mpoints/s"] {
        assert!(table.row(name).is_some_and(|r| r[1] != "-"), "no {name} row in\n{}", table.to_text());
    }
    let markdown = table.to_markdown();
    assert!(Stage::IN_ORDER.iter().all(|s| markdown.contains(&format!("| {} |", s.name()))), "{markdown}");

    let scaling = bench::scaling_table("scaling", &[timings]);
    let row = scaling.row("896 x 560").expect("a row for the frame size");
    assert!(row.iter().all(|c| c != "-"), "{row:?}");
}

#[test]
fn loading_decoding_and_the_daemon_give_one_figure_each() {
    let scenario = smallest();
    let sim = scenario.simulate();

    let mut pcd = Vec::new();
    weldseam::cloud::pcd::write_binary(&sim.cloud, &mut pcd).unwrap();
    let (_dir, path) = write_temp("frame.pcd", &pcd);
    assert_eq!(bench::time_load(&path, 1).unwrap().len(), 1);

    let message = bench::frame_message(&sim.cloud, 1, 0).unwrap();
    let decode = bench::time_frame_decode(&message, 1).unwrap();
    assert_eq!((decode.link_reader.len(), decode.link_to_cloud.len(), decode.in_memory.len()), (1, 1, 1));
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let Ok(weldseam_proto::Message::Frame(frame)) = rt.block_on(bench::read_like_the_link(&message)) else {
        panic!("the link's reader did not decode the frame");
    };
    assert_eq!(frame.points.len(), sim.cloud.len());

    let latency = bench::daemon_latency(&scenario, &sim, 1).unwrap();
    assert_eq!(latency.len(), 1);
    // Not a speed target: a bound that only a lost or stuck reply (or a
    // sample in the wrong unit) breaks, since the pipeline's own time on
    // this frame is a fraction of it.
    assert!(latency[0] > 0.0 && latency[0] < 120_000.0, "{latency:?} ms");
}

#[test]
fn the_load_measurement_answers_requests_in_order() {
    let scenario = smallest();
    let sim = scenario.simulate();
    let load =
        bench::Load { duration: std::time::Duration::from_secs(2), controllers: 2, camera_hz: 10.0, queue_depth: 2 };
    let figures = bench::daemon_under_load(&scenario, &sim, load).unwrap();
    assert!(!figures.replies.is_empty(), "no request was answered: {:?}", figures.errors);
    // A reply time runs from the request written to the reply read, so it
    // holds the pipeline's time for that plan; a mixed-up sample breaks it.
    for r in &figures.replies {
        assert!(r.plan_ms > 0.0 && r.reply_ms >= r.plan_ms, "{r:?}");
    }
    let frames: Vec<u64> = figures.replies.iter().map(|r| r.frame_id).collect();
    assert!(frames.iter().all(|&id| id > 0), "every plan names the camera's frame: {frames:?}");
}
