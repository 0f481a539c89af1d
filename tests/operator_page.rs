//! The operator page in a real browser: headless Chromium driven through
//! chromedriver (WebDriver), against a daemon on 127.0.0.1 port 0 fed by
//! the mock camera and controller. The page shows a planned seam, then a
//! refusal with its rule id without being reloaded, and a plan opened with
//! the keyboard shows its pictures and waypoints. With a weld procedure
//! configured, a plan opens to its profile along the seam too, and to each
//! stretch not welded with the rule that cut it. A screenshot of each
//! state is kept under the test's target directory (`operator-page/`);
//! with `WELDSEAM_BLESS=1` the list's is also written to
//! docs/operator-page.png, the README's.
//!
//! The browser is Debian's `chromium` and `chromium-driver`: when either
//! is missing, the test runs tools/install-browser once and fails with
//! what it said if that does not bring them.

use std::net::{Ipv4Addr, SocketAddr, TcpListener};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::Duration;

use fantoccini::{Client, ClientBuilder, Locator};
use weldseam::config::procedure::EXAMPLE;
use weldseam::config::{Config, ProcessParams};
use weldseam::joint::JointType;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::{ControllerClient, request_for_simulation};
use weldseam::process::Procedure;
use weldseam::server::local::LocalDaemon;
use weldseam::sim::{Draw, ProcessCase, process_suite};
use weldseam::sim::{demo_scene, simulate};
use weldseam_proto::message::FrameSelect;
use weldseam_proto::session::capability;

use crate::daemon::{request, small_cloud};

const CHROMIUM: &str = "/usr/bin/chromium";
const CHROMEDRIVER: &str = "/usr/bin/chromedriver";

/// The longest the page may take to show a change (it polls every second).
const PAGE_WAIT: Duration = Duration::from_secs(30);
/// The longest the whole test may take: a hang fails it.
const TEST_WAIT: Duration = Duration::from_secs(300);

/// Installs the browser with the project's script when it is missing.
fn browser() -> Result<(), String> {
    let present = || Path::new(CHROMIUM).exists() && Path::new(CHROMEDRIVER).exists();
    if present() {
        return Ok(());
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/install-browser");
    let output = Command::new(&script)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
    if output.status.success() && present() {
        return Ok(());
    }
    Err(format!(
        "the operator page's browser test needs {CHROMIUM} and {CHROMEDRIVER}; tools/install-browser did not \
         install them ({}):\n{}{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    ))
}

/// chromedriver on a loopback port; killed when dropped.
struct Driver {
    child: Child,
    url: String,
}

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Driver {
    async fn start() -> Driver {
        // A port the system just gave out and took back: free for the driver.
        let port = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap().local_addr().unwrap().port();
        let child = Command::new(CHROMEDRIVER)
            .arg(format!("--port={port}"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("cannot start chromedriver");
        let driver = Driver { child, url: format!("http://127.0.0.1:{port}") };
        let addr = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
        for _ in 0..200 {
            if tokio::net::TcpStream::connect(addr).await.is_ok() {
                return driver;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
        panic!("chromedriver did not listen on {addr} within 20 s");
    }

    async fn browse(&self) -> Client {
        let mut capabilities = serde_json::Map::new();
        capabilities.insert(
            "goog:chromeOptions".into(),
            serde_json::json!({
                "binary": CHROMIUM,
                "args": ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                         "--window-size=1400,1000", "--hide-scrollbars"],
            }),
        );
        let connector = hyper_util::client::legacy::connect::HttpConnector::new();
        ClientBuilder::new(connector).capabilities(capabilities).connect(&self.url).await.expect("no browser session")
    }
}

/// Where the screenshots go.
fn artefacts() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("operator-page");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

async fn screenshot(client: &Client, name: &str) -> Vec<u8> {
    let png = client.screenshot().await.unwrap();
    std::fs::write(artefacts().join(name), &png).unwrap();
    png
}

async fn wait_for(client: &Client, css: &str) -> fantoccini::elements::Element {
    match client.wait().at_most(PAGE_WAIT).for_element(Locator::Css(css)).await {
        Ok(element) => element,
        Err(e) => {
            let _ = screenshot(client, "failed.png").await;
            panic!("the page did not show {css:?} within {} s: {e}", PAGE_WAIT.as_secs());
        }
    }
}

/// Runs `drive` once the browser is found, within [`TEST_WAIT`].
fn in_browser(drive: impl std::future::Future<Output = ()>) {
    if let Err(e) = browser() {
        panic!("{e}");
    }
    let runtime = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    runtime.block_on(async {
        tokio::time::timeout(TEST_WAIT, drive).await.expect("the browser test took over 5 minutes");
    });
}

#[test]
fn the_page_shows_a_plan_and_a_refusal_as_they_happen() {
    in_browser(drive());
}

async fn drive() {
    let mut config = Config::default();
    config.server.pipeline_threads = 2;
    config.server.fresh_frame_timeout = Duration::from_secs(20);
    let lap = simulate(&demo_scene(JointType::Lap), &config.camera);
    let daemon = LocalDaemon::start_with_metrics(config).await.unwrap();
    let page = format!("http://{}/", daemon.metrics_addr.unwrap());
    let frames = vec![Arc::new(lap.cloud.clone()), Arc::new(small_cloud())];
    let (stop_camera, camera_stopped) = tokio::sync::oneshot::channel::<()>();
    let camera =
        weldseam::mock::camera::MockCamera::new(daemon.camera_addr.to_string(), frames, CameraOptions::default());
    let camera = tokio::spawn(camera.run(camera_stopped));
    let mut controller = ControllerClient::connect(&daemon.controller_addr.to_string(), "page-test").await.unwrap();
    controller.wait_for_camera(PAGE_WAIT).await.unwrap();

    let driver = Driver::start().await;
    let client = driver.browse().await;
    client.goto(&page).await.unwrap();
    wait_for(&client, "#status:not(.down)").await;

    // A planned seam appears by itself.
    let reply = controller.plan(request_for_simulation(1, JointType::Lap, &lap, FrameSelect::Trigger), PAGE_WAIT).await;
    assert_eq!(reply.unwrap().result.seams.len(), 1);
    let planned = wait_for(&client, r#"#plans button[data-outcome="planned"]"#).await;
    assert!(planned.text().await.unwrap().contains("PLANNED"));
    screenshot(&client, "1-planned.png").await;

    // A refusal appears by itself, with the rule that refused.
    let refusal = controller.plan(request(2, FrameSelect::Trigger), PAGE_WAIT).await;
    assert!(refusal.is_err(), "a flat plate has no lap joint to plan");
    let refused = wait_for(&client, r#"#plans button:not([data-outcome="planned"]) .rule"#).await;
    let rule = refused.text().await.unwrap();
    assert!(weldseam::rules::by_id(&rule).is_some(), "the page shows {rule:?}, not a rule of the catalogue");
    let plans = client.find_all(Locator::Css("#plans button")).await.unwrap();
    assert_eq!(plans.len(), 2, "the newest first: the refusal, then the plan");
    let list = screenshot(&client, "2-refused.png").await;
    if std::env::var_os("WELDSEAM_BLESS").is_some() {
        std::fs::write(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/operator-page.png"), &list).unwrap();
    }

    // The keyboard opens the plan: its pictures, figures and waypoints.
    let planned = wait_for(&client, r#"#plans button[data-outcome="planned"]"#).await;
    planned.send_keys(&fantoccini::key::Key::Enter.to_string()).await.unwrap();
    wait_for(&client, "#detail:not([hidden]) #camera-figure:not([hidden]) #camera-view").await;
    let drawn = client
        .wait()
        .at_most(PAGE_WAIT)
        .for_element(Locator::Css("#waypoints tbody tr"))
        .await
        .expect("the plan shows no waypoint");
    assert_eq!(drawn.find_all(Locator::Css("td")).await.unwrap().len(), 8);
    let loaded =
        client.execute("return document.getElementById('camera-view').naturalWidth;", Vec::new()).await.unwrap();
    assert!(loaded.as_u64().unwrap_or(0) > 0, "the camera view did not load");
    screenshot(&client, "3-plan.png").await;

    client.close().await.unwrap();
    drop(driver);
    let _ = stop_camera.send(());
    let _ = camera.await;
    daemon.stop().await.unwrap();
}

#[test]
fn a_plan_with_a_procedure_opens_to_its_profile_and_why_a_stretch_was_not_welded() {
    in_browser(drive_process());
}

/// A 20 mm plate's V-groove welded with the example procedure's own torch
/// (its thick V entry's, the tip extended past the nozzle, left out),
/// which cannot reach the groove's root: its plan carries stretches cut
/// by a rule.
async fn drive_process() {
    let scene = process_suite(Draw::Documented)
        .into_iter()
        .find(|s| s.case == ProcessCase::ThickVGroove)
        .expect("the process family has thick grooves");
    let mut config = Config::default();
    config.server.pipeline_threads = 2;
    config.server.fresh_frame_timeout = Duration::from_secs(20);
    // The torch's clearance along a deep groove, in a debug build on a
    // shared machine: past the default limit, which is for release builds.
    config.server.plan_timeout = Duration::from_secs(120);
    let own_torch =
        "torch = { contact_tip_to_work_mm = 12.7, nozzle_to_work_mm = 19.1, contact_tip_diameter_mm = 8.0 }";
    assert!(EXAMPLE.contains(own_torch), "the example's thick V entry has its own torch");
    let procedure = Procedure::from_toml(&EXAMPLE.replace(own_torch, "")).expect("valid without it");
    config.process = ProcessParams { procedure: Some(procedure), plate_thickness_mm: Some(scene.plate_thickness_mm()) };
    let sim = scene.simulate(&config.camera);
    let daemon = LocalDaemon::start_with_metrics(config).await.unwrap();
    let page = format!("http://{}/", daemon.metrics_addr.unwrap());
    let (stop_camera, camera_stopped) = tokio::sync::oneshot::channel::<()>();
    let camera = weldseam::mock::camera::MockCamera::new(
        daemon.camera_addr.to_string(),
        vec![Arc::new(sim.cloud.clone())],
        CameraOptions::default(),
    );
    let camera = tokio::spawn(camera.run(camera_stopped));
    let addr = daemon.controller_addr.to_string();
    let mut controller = ControllerClient::connect_asking(&addr, "page-test", capability::ALONG_SEAM).await.unwrap();
    controller.wait_for_camera(PAGE_WAIT).await.unwrap();

    let driver = Driver::start().await;
    let client = driver.browse().await;
    client.goto(&page).await.unwrap();
    wait_for(&client, "#status:not(.down)").await;

    let mut request = request_for_simulation(1, scene.case.joint(), &sim, FrameSelect::Trigger);
    // The groove's depth measured, as `weldseam eval --suite process` plans it.
    request.groove_depth_mm = None;
    let reply = controller.plan(request, PAGE_WAIT).await.expect("the groove is planned");
    let process = reply.result.seams[0].process.clone().expect("a procedure is configured");
    assert!(!process.cut.is_empty(), "the scene has a stretch the procedure cuts");

    let planned = wait_for(&client, r#"#plans button[data-outcome="planned"]"#).await;
    planned.send_keys(&fantoccini::key::Key::Enter.to_string()).await.unwrap();
    wait_for(&client, "#detail:not([hidden]) #profile-figure:not([hidden]) #profile").await;
    wait_for(&client, "#process:not([hidden]) .cut .rule").await;
    let mut shown = Vec::new();
    for rule in client.find_all(Locator::Css("#process .cut .rule")).await.unwrap() {
        shown.push(rule.text().await.unwrap());
    }
    let cut: Vec<String> = process.cut.iter().map(|c| c.rule.clone()).collect();
    assert_eq!(shown, cut, "each stretch not welded, with the rule that cut it");
    for rule in &shown {
        assert!(weldseam::rules::by_id(rule).is_some(), "the page shows {rule:?}, not a rule of the catalogue");
    }
    let reason = client.find(Locator::Css("#process .cut")).await.unwrap().text().await.unwrap();
    assert!(reason.contains(&process.cut[0].reason), "{reason}");
    let mut loaded = 0;
    for _ in 0..100 {
        let width =
            client.execute("return document.getElementById('profile').naturalWidth;", Vec::new()).await.unwrap();
        loaded = width.as_u64().unwrap_or(0);
        if loaded > 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(loaded > 0, "the profile picture did not load");
    // The picture kept shows the profile and the process below it.
    client.execute("document.getElementById('profile-figure').scrollIntoView();", Vec::new()).await.unwrap();
    screenshot(&client, "4-process.png").await;

    client.close().await.unwrap();
    drop(driver);
    let _ = stop_camera.send(());
    let _ = camera.await;
    daemon.stop().await.unwrap();
}
