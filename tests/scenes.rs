//! Simulated frames for every suite of the test binary, each rendered
//! once: a full frame takes about a second to render, and many suites
//! plan the same scene (the demo lap above all), so the first test to ask
//! for a scene renders it and every later one, on any thread, shares it.
//!
//! Frames are keyed by everything that makes them: the scene's and the
//! camera's parameters (their `Debug` text, which spells every field and
//! prints each float exactly enough to read it back) and, for a variant,
//! the variant's name. A frame lives until the binary ends: the whole
//! binary's frames (about a hundred renders and fifty variants) held the
//! test process at about 4 GB resident at its peak, the price of
//! rendering each scene once.
//!
//! With `WELDSEAM_TEST_FRAMES=1` in the environment each request prints
//! how many frames were asked for and how many rendered so far; run with
//! `--nocapture` and read the last line for the whole run.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{LazyLock, Mutex, OnceLock, PoisonError};

use weldseam::camera::CameraModel;
use weldseam::joint::JointType;
use weldseam::sim::scenarios::Scenario;
use weldseam::sim::variants::{Variant, voxel_grid};
use weldseam::sim::{SceneSpec, Simulation, demo_scene, simulate};

/// One frame, rendered by the first test that asks for it; the others
/// asking meanwhile wait for it rather than render it again.
type Slot = OnceLock<Simulation>;

/// Every frame asked for so far, by key. A slot is leaked on purpose: it
/// lives as long as the binary, so the frame can be lent as `'static`.
static FRAMES: LazyLock<Mutex<HashMap<String, &'static Slot>>> = LazyLock::new(Default::default);

/// How many frames (renders and variants) were asked for, and how many
/// made, so far.
static ASKED: AtomicUsize = AtomicUsize::new(0);
static MADE: AtomicUsize = AtomicUsize::new(0);
/// How many of those asked and made were full renders of a scene.
static RENDERS_ASKED: AtomicUsize = AtomicUsize::new(0);
static RENDERS_MADE: AtomicUsize = AtomicUsize::new(0);

/// The frame under `key`, made by `make` if no test has made it yet.
fn shared(key: String, render: bool, make: impl FnOnce() -> Simulation) -> &'static Simulation {
    ASKED.fetch_add(1, Ordering::Relaxed);
    if render {
        RENDERS_ASKED.fetch_add(1, Ordering::Relaxed);
    }
    // The map is held only to find the slot: frames of different scenes
    // are made side by side, and a test that panicked while holding it
    // left the map whole.
    let slot: &'static Slot =
        FRAMES.lock().unwrap_or_else(PoisonError::into_inner).entry(key).or_insert_with(|| Box::leak(Box::default()));
    let frame = slot.get_or_init(|| {
        MADE.fetch_add(1, Ordering::Relaxed);
        if render {
            RENDERS_MADE.fetch_add(1, Ordering::Relaxed);
        }
        make()
    });
    if std::env::var_os("WELDSEAM_TEST_FRAMES").is_some() {
        eprintln!("{}", counts());
    }
    frame
}

/// The counts so far, as `WELDSEAM_TEST_FRAMES` prints them.
pub fn counts() -> String {
    format!(
        "frames: {} full renders asked for, {} made; {} frames in all (renders and variants) asked for, {} made",
        RENDERS_ASKED.load(Ordering::Relaxed),
        RENDERS_MADE.load(Ordering::Relaxed),
        ASKED.load(Ordering::Relaxed),
        MADE.load(Ordering::Relaxed),
    )
}

fn key(spec: &SceneSpec, camera: &CameraModel) -> String {
    format!("{spec:?} seen by {camera:?}")
}

/// `spec` as `camera` sees it: [`simulate`]'s frame, shared.
pub fn rendered(spec: &SceneSpec, camera: &CameraModel) -> &'static Simulation {
    shared(key(spec, camera), true, || simulate(spec, camera))
}

/// `spec` seen by the paper's camera.
pub fn by_default_camera(spec: &SceneSpec) -> &'static Simulation {
    rendered(spec, &CameraModel::default())
}

/// The documented several-workpiece scene whose name starts `prefix`,
/// with its name.
pub fn multi_scene(prefix: &str) -> (String, SceneSpec) {
    weldseam::sim::multi_suite(weldseam::sim::Draw::Documented)
        .into_iter()
        .find(|(n, _)| n.starts_with(prefix))
        .unwrap_or_else(|| panic!("no several-workpiece scene {prefix}"))
}

/// The demo scene of `joint` seen by the paper's camera (what
/// `simulate --joint` writes).
pub fn demo(joint: JointType) -> &'static Simulation {
    by_default_camera(&demo_scene(joint))
}

/// `spec` as `camera` sees it, made into `variant` as `eval --variant`
/// makes it (the scene's seed orders an unorganized cloud's shuffle); the
/// raw variant is the frame itself.
pub fn as_variant(spec: &SceneSpec, camera: &CameraModel, variant: &Variant) -> &'static Simulation {
    let frame = rendered(spec, camera);
    if variant.is_raw() {
        return frame;
    }
    shared(format!("{} as {variant}", key(spec, camera)), false, || variant.apply(frame, spec.seed))
}

/// [`as_variant`] by the variant's name (`voxel:1`, `cropped:25,metres`).
pub fn as_named_variant(spec: &SceneSpec, camera: &CameraModel, variant: &str) -> &'static Simulation {
    as_variant(spec, camera, &Variant::parse(variant).expect("a variant the simulator makes"))
}

/// [`Scenario::simulate`]'s frame, shared: the scenario's scene, then its
/// voxel grid if it has one.
pub fn scenario(scenario: &Scenario) -> &'static Simulation {
    let spec = scenario.spec();
    let frame = rendered(&spec, &scenario.camera);
    match scenario.voxel_mm {
        None => frame,
        Some(size_mm) => shared(format!("{} voxel {size_mm} mm", key(&spec, &scenario.camera)), false, || Simulation {
            cloud: voxel_grid(&frame.cloud, size_mm),
            ..frame.clone()
        }),
    }
}

#[test]
fn a_scene_asked_for_twice_is_rendered_once_and_shared() {
    let first = demo(JointType::Lap);
    let again = rendered(&demo_scene(JointType::Lap), &CameraModel::default());
    assert!(std::ptr::eq(first, again), "the same frame, not a second render");
    // Another camera is another frame.
    let small = CameraModel { width_px: 480, height_px: 300, ..CameraModel::default() };
    let other = rendered(&demo_scene(JointType::Lap), &small);
    assert!(!std::ptr::eq(first, other));
    assert_eq!(other.cloud.width(), 480);
    // A variant is made from the shared render, once.
    let voxels = as_named_variant(&demo_scene(JointType::Lap), &small, "voxel:2");
    assert!(std::ptr::eq(voxels, as_named_variant(&demo_scene(JointType::Lap), &small, "voxel:2")));
    assert!(voxels.cloud.len() < other.cloud.len());
}
