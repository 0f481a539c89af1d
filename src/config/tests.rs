//! Parsing and checking whole configuration files and single keys.

use super::*;

#[test]
fn empty_file_gives_the_defaults() {
    let c = Config::parse("", "empty").unwrap();
    assert_eq!(c.pipeline, PipelineParams::default());
    assert_eq!(c.camera, CameraModel::default());
    assert_eq!(c.euler, EulerConvention::Zyx);
}

#[test]
fn unknown_keys_are_refused_with_their_name() {
    let e = Config::parse("[pipeline]\nneighbour_radius = 1.0\n", "x.toml").unwrap_err().to_string();
    assert!(e.contains("neighbour_radius") && e.contains("x.toml"), "{e}");
}

#[test]
fn bad_values_name_their_key() {
    let cases = [
        ("[pipeline]\nneighbour_radius_mm = -1.0\n", "pipeline.neighbour_radius_mm"),
        ("[camera]\nmin_depth_mm = 0.0\n", "camera.min_depth_mm"),
        ("[pipeline]\nmethod = \"fast\"\n", "pipeline.method"),
        ("[trajectory]\nstep_mm = 0.0\n", "trajectory.step_mm"),
        ("[robot]\neuler_convention = \"zxz\"\n", "robot.euler_convention"),
        ("[robot]\nhand_eye = [1.0, 0.0]\n", "robot.hand_eye"),
        ("[pipeline]\nedge_max_neighbour_ratio = 0.9\n", "pipeline.edge_max_neighbour_ratio"),
        ("[server]\ncamera_listen = \"localhost\"\n", "server.camera_listen"),
        ("[server]\ncontroller_allow = [\"10.0.0.x\"]\n", "server.controller_allow"),
        ("[server]\nplan_queue_depth = 0\n", "server.plan_queue_depth"),
        ("[server]\nmax_frame_bytes = 12\n", "server.max_frame_bytes"),
        ("[server]\nstall_timeout_ms = 0\n", "server.stall_timeout_ms"),
        ("[server]\nframe_history_bytes = 1024\n", "server.frame_history_bytes"),
        ("[server]\ncapture_time_tolerance_ms = 60000\n", "server.capture_time_tolerance_ms"),
        ("[server]\nmax_request_timeout_ms = 4294967295\n", "server.max_request_timeout_ms"),
        ("[server]\nmax_request_timeout_ms = 100\n", "server.fresh_frame_timeout_ms"),
        ("[server]\nmax_requests_per_connection = 5\n", "server.max_requests_per_connection"),
        ("[server]\nidle_trim_ms = 100000000\n", "server.idle_trim_ms"),
        ("[server]\nhello_timeout_ms = 0\n", "server.hello_timeout_ms"),
        ("[server]\nhello_timeout_ms = 3600000\n", "server.hello_timeout_ms"),
        ("[server]\nmessage_timeout_ms = 4000000\n", "server.message_timeout_ms"),
        ("[server]\nmin_transfer_bytes_per_s = 10\n", "server.min_transfer_bytes_per_s"),
        ("[server]\nmax_pending_connections = 0\n", "server.max_pending_connections"),
        ("[server]\nmax_pending_connections = 100000\n", "server.max_pending_connections"),
        ("[server]\nmax_pending_per_address = 65\n", "server.max_pending_per_address"),
        ("[server]\nmetrics_listen = \"9100\"\n", "server.metrics_listen"),
        ("[server]\nmetrics_listen = \"0.0.0.0:9464\"\n", "server.http_token"),
        ("[server]\nhttp_token = \"short\"\n", "server.http_token"),
        ("[server]\nhttp_token = \"a token with spaces in it\"\n", "server.http_token"),
        ("[server]\npage_plans = 0\n", "server.page_plans"),
        ("[server]\npage_plans = 1000\n", "server.page_plans"),
        ("[records]\nmax_bytes = 1000\n", "records.max_bytes"),
        ("[records]\nmax_age_days = 0\n", "records.max_age_days"),
        ("[pipeline]\nroi = [1.0, 2.0]\n", "pipeline.roi"),
        ("[pipeline]\nroi = [0.0, 0.0, 600.0, 10.0, 10.0, 500.0]\n", "pipeline.roi"),
        ("[pipeline]\nroi_frame = \"tool\"\n", "roi_frame"),
        ("[debug]\nkeep_last = 0\n", "debug.keep_last"),
        ("[debug]\nkeep = 3\n", "keep"),
    ];
    // Beyond loopback with a token, and on loopback without one, the listener starts.
    let exposed = "[server]\nmetrics_listen = \"0.0.0.0:9464\"\nhttp_token = \"0123456789abcdef\"\n";
    assert_eq!(Config::parse(exposed, "c.toml").unwrap().server.http_token.as_deref(), Some("0123456789abcdef"));
    Config::parse("[server]\nmetrics_listen = \"127.0.0.1:9464\"\n", "c.toml").unwrap();
    for (text, key) in cases {
        let e = Config::parse(text, "c.toml").unwrap_err().to_string();
        assert!(e.contains(key), "{text:?} gave {e}");
    }
}

/// Every numeric key of the shipped file, with its section.
fn numeric_keys() -> Vec<(String, String, toml::Value)> {
    let text = include_str!("../../config/weldseam.toml");
    let doc: toml::Table = toml::from_str(text).unwrap();
    let mut keys = Vec::new();
    for (section, table) in &doc {
        for (key, value) in table.as_table().unwrap() {
            if value.is_integer() || value.is_float() {
                keys.push((section.clone(), key.clone(), value.clone()));
            }
        }
    }
    keys
}

#[test]
fn every_number_has_a_ceiling_named_in_its_error() {
    // The seed may be any number; every other value has a limit, so a
    // unit mix-up or a typo cannot hang or silently break the planner.
    let keys = numeric_keys();
    assert!(keys.len() > 40, "found {} numeric keys", keys.len());
    for (section, key, value) in keys.into_iter().filter(|(_, k, _)| k != "ransac_seed") {
        // The largest u32 for counts; for 64-bit keys whose ceiling lies
        // above that (a frame of over 4 GB), the largest TOML integer.
        let huge: &[&str] = if value.is_integer() { &["4294967295", "9223372036854775807"] } else { &["1e300"] };
        let refused = huge.iter().find_map(|h| {
            let text = format!("[{section}]\n{key} = {h}\n");
            // A huge value may first break a rule between two keys (a
            // frame larger than the history); the next one must meet
            // the key's own ceiling.
            match Config::parse(&text, "c.toml") {
                Err(ConfigError::Invalid { key: named, message }) if named == format!("{section}.{key}") => {
                    Some((text, message))
                }
                _ => None,
            }
        });
        let (text, message) = refused.unwrap_or_else(|| panic!("{section}.{key} has no ceiling"));
        assert!(message.contains("must"), "{text:?} gave {message}");
    }
}

#[test]
fn tolerances_of_nothing_are_refused() {
    for key in ["cluster_tolerance_mm", "coplanar_tolerance_mm", "ransac_distance_mm", "on_plane_tolerance_mm"] {
        let text = format!("[pipeline]\n{key} = 1e-30\n");
        let e = Config::parse(&text, "c.toml").unwrap_err().to_string();
        assert!(e.contains(&format!("pipeline.{key}")) && e.contains("must lie in"), "{e}");
    }
}

#[test]
fn a_hand_eye_with_a_camera_a_kilometre_away_is_refused() {
    let mut rows = crate::geometry::pose::PAPER_HAND_EYE;
    rows[3] = 1e6;
    let text = format!("[robot]\nhand_eye = {rows:?}\n");
    let e = Config::parse(&text, "c.toml").unwrap_err().to_string();
    assert!(e.contains("robot.hand_eye") && e.contains("max_hand_eye_translation_mm (1000 mm)"), "{e}");
}

#[test]
fn camera_values_out_of_range_name_their_key_and_limit() {
    let cases = [
        ("width_px = 0", "camera.width_px", "[1, 32768]"),
        ("height_px = 100000", "camera.height_px", "[1, 32768]"),
        ("fov_width_mm = 1e300", "camera.fov_width_mm", "100000"),
        ("nominal_accuracy_mm = 0.0", "camera.nominal_accuracy_mm", "[0.000001, 100]"),
        ("max_depth_mm = 500.0", "camera.max_depth_mm", "[1000, 100000]"),
        ("max_depth_mm = inf", "camera.max_depth_mm", "[1000, 100000]"),
        ("max_off_axis_deg = 90.0", "camera.max_off_axis_deg", "[1, 89]"),
        ("fov_margin_px = -1.0", "camera.fov_margin_px", "[0, 32768]"),
        ("fov_margin_px = nan", "camera.fov_margin_px", "[0, 32768]"),
    ];
    for (line, key, limit) in cases {
        let e = Config::parse(&format!("[camera]\n{line}\n"), "c.toml").unwrap_err().to_string();
        assert!(e.contains(key) && e.contains(limit), "{line:?} gave {e}");
    }
    let c = Config::parse("[camera]\nmax_depth_mm = 2000.0\nfov_margin_px = 0.0\n", "c.toml").unwrap();
    assert_eq!((c.camera.max_depth_mm, c.camera.fov_margin_px), (2000.0, 0.0));
}

#[test]
fn the_papers_printed_hand_eye_typo_is_refused() {
    let mut rows = crate::geometry::pose::PAPER_HAND_EYE;
    rows[4] = -0.353;
    let text = format!("[robot]\nhand_eye = {rows:?}\n");
    let e = Config::parse(&text, "c.toml").unwrap_err().to_string();
    assert!(e.contains("robot.hand_eye") && e.contains("orthonormal"), "{e}");
}

#[test]
fn intrinsics_replace_or_agree_with_the_field_of_view() {
    let paper = CameraModel::default();
    let only = "[camera]\nfx = 2000.0\nfy = 2010.0\ncx = 950.25\ncy = 601.75\n";
    let c = Config::parse(only, "c.toml").unwrap().camera;
    assert_eq!((c.fx(), c.fy(), c.cx(), c.cy()), (2000.0, 2010.0, 950.25, 601.75));
    assert!((c.fov_width_mm - 1920.0 * 1000.0 / 2000.0).abs() < 1e-9, "the fov they imply: {c:?}");
    // Both forms, agreeing: the paper's camera with its principal point moved.
    let both = format!(
        "[camera]\nfov_width_mm = 700.0\nfov_height_mm = 440.0\nfx = {}\nfy = {}\ncx = 958.0\ncy = 600.0\n",
        paper.fx(),
        paper.fy()
    );
    let c = Config::parse(&both, "c.toml").unwrap().camera;
    assert_eq!((c.fx(), c.cx()), (paper.fx(), 958.0));
    let cases = [
        ("fov_width_mm = 700.0\nfx = 2000.0\nfy = 2727.0\ncx = 959.5\ncy = 599.5", "camera.fx", "not both"),
        ("fx = 2000.0\nfy = 2000.0", "camera.cx", "fx, fy given but not cx, cy"),
        ("fx = 1.0\nfy = 2000.0\ncx = 959.5\ncy = 599.5", "camera.fx", "must lie in"),
        ("k1 = 50.0", "camera.k1", "[-10, 10]"),
    ];
    for (lines, key, text) in cases {
        let e = Config::parse(&format!("[camera]\n{lines}\n"), "c.toml").unwrap_err().to_string();
        assert!(e.contains(key) && e.contains(text), "{lines:?} gave {e}");
    }
    let c = Config::parse("[camera]\nk1 = -0.1\np2 = 0.001\n", "c.toml").unwrap().camera;
    assert_eq!((c.distortion.k1, c.distortion.p2, c.fx()), (-0.1, 0.001, paper.fx()));
}

#[test]
fn shipped_config_file_is_valid_and_equals_the_defaults() {
    let text = include_str!("../../config/weldseam.toml");
    Config::parse(text, "config/weldseam.toml").unwrap();
    // The whole file, section by section: [robot]'s convention and
    // hand-eye and [paper] included, not only what a built config holds.
    let file: ConfigFile = toml::from_str(text).unwrap();
    assert_eq!(file, ConfigFile::default());
}

#[test]
fn a_request_and_the_config_share_the_step_and_angle_limits() {
    use crate::geometry::pose::RobotPose;
    use crate::joint::JointType;
    use crate::pipeline::{PlanRequest, Planner};
    let planner = Planner::new(Config::default());
    let pose = RobotPose { xyz_mm: [500.0, 0.0, 500.0], angles_deg: [180.0, 0.0, 0.0] };
    let request = |step: f64, angle: f64| PlanRequest {
        step_mm: Some(step),
        travel_angle_deg: Some(angle),
        ..PlanRequest::new(JointType::IButt, None, pose)
    };
    let config = |step: f64, angle: f64| {
        Config::parse(&format!("[trajectory]\nstep_mm = {step}\ntravel_angle_deg = {angle}\n"), "c.toml")
    };
    // At the limits both accept; just beyond, both refuse.
    for (step, angle) in [(MIN_STEP_MM, -MAX_TORCH_ANGLE_DEG), (MAX_STEP_MM, MAX_TORCH_ANGLE_DEG)] {
        assert!(planner.check_request(&request(step, angle)).is_ok(), "request {step} {angle}");
        assert!(config(step, angle).is_ok(), "config {step} {angle}");
    }
    for (step, angle) in [(MIN_STEP_MM * 0.99, 0.0), (MAX_STEP_MM * 1.01, 0.0), (5.0, MAX_TORCH_ANGLE_DEG + 0.1)] {
        assert!(planner.check_request(&request(step, angle)).is_err(), "request {step} {angle}");
        assert!(config(step, angle).is_err(), "config {step} {angle}");
    }
}

#[test]
fn the_planning_hash_counts_the_weld_process_where_one_is_set() {
    use crate::process::Procedure;
    let plain = Config::default();
    // Without a process, the fingerprint the records made before the
    // process was counted carry.
    assert_eq!(plain.planning_hash(), PLAIN_PLANNING_HASH);
    let with = |procedure: Procedure, thickness: Option<f64>| Config {
        process: ProcessParams { procedure: Some(procedure), plate_thickness_mm: thickness },
        ..Config::default()
    };
    let example = with(Procedure::example(), Some(8.0));
    assert_ne!(example.planning_hash(), plain.planning_hash());
    assert_ne!(example.planning_hash(), with(Procedure::example(), Some(10.0)).planning_hash());
    let mut wider_margin = Procedure::example();
    wider_margin.torch.margin_mm += 0.5;
    assert_ne!(example.planning_hash(), with(wider_margin, Some(8.0)).planning_hash());
    assert_eq!(example.planning_hash(), with(Procedure::example(), Some(8.0)).planning_hash());
}

/// [`Config::default`]'s planning hash.
const PLAIN_PLANNING_HASH: &str = "f81686f82aaebb4a";
