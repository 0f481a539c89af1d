//! Criterion benchmarks of the hot paths on the paper's 1920 x 1200 frame
//! (I-butt at 500 mm, the densest case): the whole pipeline, parsing the
//! frame's binary PCD, and decoding it from the camera link. Per-stage
//! figures come from `weldseam bench`, which reads the pipeline's own
//! stage clock.
//!
//! `cargo bench` runs them (`cargo bench -- --test` runs each once);
//! `cargo test` does not build them.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::joint::JointType;
use weldseam::mock::load::frame_message;
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::server::connection::MessageReader;
use weldseam::sim::scenarios::Scenario;
use weldseam_proto::frame::DEFAULT_MAX_FRAME_BYTES;

fn scenario() -> Scenario {
    Scenario::new(JointType::IButt, 500.0, CameraModel::default())
}

fn pipeline(c: &mut Criterion) {
    let scenario = scenario();
    let sim = scenario.simulate();
    let planner = Planner::new(Config { camera: scenario.camera, ..Config::default() });
    let request = PlanRequest::new(scenario.joint, sim.truth.groove_depth_mm, sim.pose);
    let mut group = c.benchmark_group("pipeline");
    group.sample_size(10);
    group.bench_function("plan 1920x1200 i_butt 500 mm", |b| {
        b.iter(|| planner.plan(black_box(&sim.cloud), &request).expect("the benchmark frame plans"))
    });
    group.finish();
}

fn frame_input(c: &mut Criterion) {
    let sim = scenario().simulate();
    let mut pcd = Vec::new();
    weldseam::cloud::pcd::write_binary(&sim.cloud, &mut pcd).expect("encode the PCD");
    let message = frame_message(&sim.cloud, 1, 0).expect("encode the frame message");
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().expect("a runtime");

    let mut group = c.benchmark_group("frame input");
    group.sample_size(20);
    group.bench_function("pcd::parse 27.6 MB binary", |b| {
        b.iter(|| weldseam::cloud::pcd::parse(black_box(&pcd), Path::new("frame.pcd")).expect("the PCD parses"))
    });
    group.bench_function("camera link reader, Frame 27.6 MB", |b| {
        b.iter(|| {
            let mut reader =
                MessageReader::new(black_box(&message[..]), std::time::Duration::from_secs(5), DEFAULT_MAX_FRAME_BYTES);
            rt.block_on(reader.read()).expect("the frame decodes").expect("a whole message")
        })
    });
    group.bench_function("proto frame::decode, Frame 27.6 MB", |b| {
        b.iter(|| {
            weldseam_proto::frame::decode(black_box(&message), DEFAULT_MAX_FRAME_BYTES).expect("the frame decodes")
        })
    });
    group.finish();
}

criterion_group!(benches, pipeline, frame_input);
criterion_main!(benches);
