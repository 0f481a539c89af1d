//! `weldseam controller`: a mock robot controller. Sends one plan request
//! (or a ping) and prints the reply as a table or JSON; an error reply
//! exits non-zero with its code and message. With `--text --dialect`, it
//! plays a robot program on the text link instead, for commissioning: the
//! hello, a trigger (or plan) line, every waypoint pulled, each seam's
//! CHECK held against the lines pulled, and the reason of an error line,
//! each line printed as sent (`>`) and received (`<`); with `--process`,
//! the process lines too, and then each weld waypoint's travel speed and
//! weave as the robot received them.

use std::time::Duration;

use anyhow::Context;
use weldseam::convert::{to_proto, to_text};
use weldseam::geometry::pose::{EulerConvention, RobotPose};
use weldseam::joint::JointType;
use weldseam::mock::ClientError;
use weldseam::mock::controller::ControllerClient;
use weldseam::mock::text_robot::{PullError, PulledSeam, TextRobot};
use weldseam_proto::message::{FrameSelect, PlanRequest};
use weldseam_proto::session::capability;
use weldseam_proto::text::Dialect;

use super::args;

#[derive(Debug, clap::Args)]
pub struct ControllerArgs {
    /// The daemon's controller link, host:port (the text link's with
    /// --text); 127.0.0.1:7302 (7303 with --text) when absent.
    #[arg(long)]
    pub connect: Option<String>,
    /// Speak the text link, as a robot program does, and print the session.
    #[arg(long, requires = "dialect")]
    pub text: bool,
    /// With --text: ask for the weld process lines (`HELLO,<dialect>,PROCESS`)
    /// and print each weld waypoint's travel speed and weave after the
    /// session.
    #[arg(long, requires = "text")]
    pub process: bool,
    /// The robot language on the text link: ur, abb, kuka or fanuc. The
    /// --pose is converted into its convention and units.
    #[arg(long, value_parser = dialect)]
    pub dialect: Option<Dialect>,
    /// Joint type: v-butt, i-butt, lap or t-fillet (a tee joint's fillet
    /// roots).
    #[arg(long, required_unless_present = "ping")]
    pub joint: Option<JointType>,
    /// Robot pose at capture: x,y,z,rx,ry,rz (mm, degrees).
    #[arg(long, allow_hyphen_values = true, value_parser = args::pose, required_unless_present = "ping")]
    pub pose: Option<RobotPose>,
    #[command(flatten)]
    pub request: args::RequestArgs,
    #[command(flatten)]
    pub roi: args::RoiArgs,
    /// Which frame: trigger (a fresh capture), next (the next frame to
    /// arrive) or a frame id.
    #[arg(long, default_value = "trigger", value_parser = frame_select)]
    pub frame: FrameSelect,
    /// How long the daemon may wait for a fresh frame, ms (0: its default).
    #[arg(long, default_value_t = 0)]
    pub timeout_ms: u32,
    /// The camera (its Hello name) to trigger or take the frame from; any
    /// connected camera when absent.
    #[arg(long)]
    pub camera: Option<String>,
    /// Start the waypoints at the seam's end nearest this base-frame
    /// point: x,y,z (mm).
    #[arg(long, allow_hyphen_values = true, value_parser = args::point)]
    pub start_near: Option<[f64; 3]>,
    /// Ask for one seam only: the one nearest --start-near (the first of
    /// the documented order without it).
    #[arg(long)]
    pub one_seam: bool,
    /// The request id echoed in the reply.
    #[arg(long, default_value_t = 1)]
    pub request_id: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Only ping the daemon and print its status.
    #[arg(long)]
    pub ping: bool,
}

fn dialect(text: &str) -> Result<Dialect, String> {
    Dialect::from_name(text).ok_or_else(|| format!("expected ur, abb, kuka or fanuc, got {text:?}"))
}

fn frame_select(text: &str) -> Result<FrameSelect, String> {
    match text {
        "trigger" => Ok(FrameSelect::Trigger),
        "next" => Ok(FrameSelect::NextFrame),
        id => id
            .parse()
            .map(FrameSelect::FrameId)
            .map_err(|_| format!("expected trigger, next or a frame id, got {id:?}")),
    }
}

pub fn run(args: &ControllerArgs) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().context("cannot start")?;
    match (args.text, args.dialect) {
        (true, Some(dialect)) => runtime.block_on(text_session(args, dialect)),
        _ => runtime.block_on(exchange(args)),
    }
}

/// One robot session on the text link, printed line by line.
async fn text_session(args: &ControllerArgs, dialect: Dialect) -> anyhow::Result<()> {
    // A text plan line carries the joint, the pose and the groove depth;
    // the rest is the daemon's configuration.
    let r = &args.request;
    let unsent = [
        ("--step", r.step.is_some()),
        ("--work-angle", r.work_angle.is_some()),
        ("--travel-angle", r.travel_angle.is_some()),
        ("--hand-eye", r.hand_eye.is_some()),
        ("--roi", args.roi.roi.is_some()),
        ("--camera", args.camera.is_some()),
        ("--start-near", args.start_near.is_some()),
        ("--json", args.json),
    ];
    if let Some((flag, _)) = unsent.iter().find(|(_, given)| *given) {
        anyhow::bail!(
            "{flag} has no field on the text link; its plan lines carry the joint, the pose and the groove depth"
        );
    }
    let addr = args.connect.clone().unwrap_or_else(|| "127.0.0.1:7303".into());
    let wait = Duration::from_millis(u64::from(args.timeout_ms).max(10_000)) + Duration::from_secs(120);
    let mut robot = TextRobot::connect(&addr, wait).await.map_err(explain)?;
    let hello =
        if args.process { format!("HELLO,{},PROCESS", dialect.name()) } else { format!("HELLO,{}", dialect.name()) };
    let hello = ask_printed(&mut robot, &hello).await?;
    let failed = |reply: &str| reply.trim_start_matches('(').starts_with('-');
    if failed(&hello) {
        ask_printed(&mut robot, "WHY").await?;
        anyhow::bail!("the daemon refused the hello");
    }
    if args.ping {
        ask_printed(&mut robot, "PING").await?;
        return Ok(());
    }
    let (Some(joint), Some(pose)) = (args.joint, args.pose) else {
        anyhow::bail!("--joint and --pose are required for a plan request");
    };
    let convention = to_text::convention(dialect);
    let numbers = convention.numbers(&pose.to_isometry(EulerConvention::default()));
    let (position, rotation) = dialect.decimals();
    let mut fields: Vec<String> = numbers[..convention.numbers_len()]
        .iter()
        .enumerate()
        .map(|(k, v)| format!("{v:.*}", if k < 3 { position } else { rotation }))
        .collect();
    if let Some(depth) = args.request.groove_depth {
        fields.push(format!("{:.*}", position, depth / convention.length.mm()));
    }
    let verb = match args.frame {
        FrameSelect::Trigger => "TRIGGER",
        FrameSelect::NextFrame => "PLAN",
        FrameSelect::FrameId(_) => anyhow::bail!("the text link plans a triggered or the next frame, not a frame id"),
    };
    let status = ask_printed(&mut robot, &format!("{verb},{},{}", joint.name(), fields.join(","))).await?;
    if failed(&status) {
        ask_printed(&mut robot, "WHY").await?;
        anyhow::bail!("the daemon answered an error line");
    }
    // The ok line's third number: the lines to pull.
    let lines: u64 = status
        .trim()
        .trim_matches(['(', ')'])
        .split(',')
        .nth(2)
        .and_then(|n| n.parse().ok())
        .context("the ok line has no waypoint count")?;
    // Store every line and check each seam against the daemon's CHECK, as
    // a robot program does before it moves.
    let pulled = robot
        .pull_plan_logged(dialect, lines, args.process, |sent, reply| {
            println!("> {sent}");
            print!("< {reply}");
        })
        .await;
    let seams = match pulled {
        Ok(seams) => seams,
        Err(PullError::Refused(line)) => {
            let why = ask_printed(&mut robot, "WHY").await?;
            anyhow::bail!("the daemon answered an error line to NEXT: {line} ({})", why.trim_end());
        }
        Err(e) => return Err(e.into()),
    };
    if args.process {
        print_process(&seams, dialect);
    }
    Ok(())
}

/// Sends `line`, prints it and its reply as the session print-out does.
async fn ask_printed(robot: &mut TextRobot, line: &str) -> anyhow::Result<String> {
    println!("> {line}");
    let reply = robot.ask(line).await.map_err(explain)?;
    print!("< {reply}");
    Ok(reply)
}

/// Each weld waypoint's travel speed and weave as the process lines gave
/// them, a row per waypoint (`seam.waypoint`, from 1), in mm whatever the
/// dialect's length unit, so a commissioning engineer reads them against
/// the procedure.
fn print_process(seams: &[PulledSeam], dialect: Dialect) {
    let mm = to_text::convention(dialect).length.mm();
    println!("process: travel speed into each weld waypoint, and its weave (half-swing each side, cycles per second)");
    for (s, seam) in (1..).zip(seams) {
        for (w, (_, process)) in (1..).zip(&seam.weld) {
            match process {
                Some([speed, amplitude, frequency]) => println!(
                    "  {s}.{w}  speed {:.3} mm/s  weave {:.3} mm at {frequency:.3} Hz",
                    speed * mm,
                    amplitude * mm
                ),
                None => println!("  {s}.{w}  no process line"),
            }
        }
    }
}

async fn exchange(args: &ControllerArgs) -> anyhow::Result<()> {
    let addr = args.connect.clone().unwrap_or_else(|| "127.0.0.1:7302".into());
    // The rule ids let a commissioning engineer look a refusal up
    // (`weldseam rules ID`), and the figures along the seam and the
    // process show what the daemon measured and would weld with; a
    // daemon without them answers as before.
    let asked = capability::RULE_IDS | capability::ALONG_SEAM;
    let mut client = ControllerClient::connect_asking(&addr, "weldseam-controller", asked).await.map_err(explain)?;
    if args.ping {
        let s = client.ping(Duration::from_secs(10)).await.map_err(explain)?;
        if args.json {
            println!(
                "{}",
                serde_json::json!({
                    "server": client.server, "uptime_ms": s.uptime_ms, "frames_received": s.frames_received,
                    "plans_done": s.plans_done, "queue_length": s.queue_length, "camera_connected": s.camera_connected,
                    "cameras": s.cameras, "latest_frame_id": s.latest_frame_id,
                    "latest_capture_time_us": s.latest_capture_time_us,
                })
            );
        } else {
            println!("server            {}", client.server);
            println!("uptime            {:.1} s", s.uptime_ms as f64 / 1e3);
            println!("frames received   {}", s.frames_received);
            println!("plans done        {}", s.plans_done);
            println!("queue length      {}", s.queue_length);
            println!("cameras connected {}", s.cameras);
            match (s.latest_frame_id, s.latest_capture_time_us) {
                (Some(id), Some(t)) => println!("latest frame      {id}, captured at {t} µs"),
                _ => println!("latest frame      none held"),
            }
        }
        return Ok(());
    }
    let (Some(joint), Some(pose)) = (args.joint, args.pose) else {
        anyhow::bail!("--joint and --pose are required for a plan request");
    };
    let [x, y, z] = pose.xyz_mm;
    let [rx, ry, rz] = pose.angles_deg;
    let request = PlanRequest {
        request_id: args.request_id,
        joint: PlanRequest::joint_code(to_proto::joint(joint)),
        groove_depth_mm: args.request.groove_depth,
        pose: [x, y, z, rx, ry, rz],
        step_mm: args.request.step,
        work_angle_deg: args.request.work_angle,
        travel_angle_deg: args.request.travel_angle,
        frame: args.frame,
        timeout_ms: args.timeout_ms,
        camera: args.camera.clone(),
        hand_eye: args.request.hand_eye,
        start_near: args.start_near,
        roi: args.roi.to_library()?.as_ref().map(to_proto::roi),
        pose_in: None,
        one_seam: args.one_seam,
    };
    // The daemon bounds the frame wait; allow for it and a slow plan.
    let wait = Duration::from_millis(u64::from(args.timeout_ms).max(10_000)) + Duration::from_secs(120);
    let reply = client.plan(request, wait).await.map_err(explain)?;
    if args.json {
        let out = serde_json::json!({
            "request_id": reply.request_id,
            "frame_id": reply.frame_id,
            "result": super::plan_json::plan_json(&reply.result),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    let r = &reply.result;
    println!(
        "request {}  frame {}  method {}  euler {}",
        reply.request_id, reply.frame_id, r.method, r.euler_convention
    );
    for (k, seam) in r.seams.iter().enumerate() {
        println!(
            "seam {}: {:?}, {:.1} mm, {} waypoints, edge fit rms {:.3} / {:.3} mm",
            k + 1,
            seam.joint,
            seam.length_mm,
            seam.waypoints.len(),
            seam.edge_fit_rms_mm[0],
            seam.edge_fit_rms_mm[1]
        );
        for w in &seam.warnings {
            let rule = w.rule.as_deref().map_or(String::new(), |r| format!(", rule {r}"));
            println!("  warning ({}{rule}): {}", w.gate, w.message);
        }
        print_waypoints(seam);
    }
    for u in &r.unplanned {
        let joint = u.joint.as_deref().unwrap_or("joint");
        let place = u
            .near_camera_mm
            .map_or(String::new(), |p| format!(" near ({:.0}, {:.0}, {:.0}) mm in the camera frame", p[0], p[1], p[2]));
        let rule = u.refusal.rule.as_deref().map_or(String::new(), |r| format!(", rule {r}"));
        println!("not planned: {joint}{place}: error {} ({}{rule}): {}", u.code, u.refusal.code, u.refusal.message);
    }
    if let Some(total) = r.timing_ms.get("total") {
        println!("pipeline {total:.0} ms");
    }
    Ok(())
}

/// A seam's waypoints, and beside each, where the daemon sent them (the
/// `along_seam` capability), its gap or lap step and high-low, and with a
/// procedure its passes, the first pass's travel speed and weave and
/// whether the torch was re-angled; then the stretches cut from the weld
/// with their rule and reason, so a stretch left unwelded says why.
fn print_waypoints(seam: &weldseam_proto::plan::Seam) {
    let figures = seam.along_seam.as_deref().unwrap_or_default();
    let process = seam.process.as_ref();
    if let Some(p) = process {
        println!("  procedure {}", p.procedure);
    }
    let mut head =
        format!("  {:>4}  {:>10} {:>10} {:>10}  {:>9} {:>9} {:>9}", "#", "x mm", "y mm", "z mm", "rx°", "ry°", "rz°");
    if !figures.is_empty() {
        head += &format!("  {:>13} {:>8}", "gap|step mm", "hi-lo mm");
    }
    if process.is_some() {
        head += &format!("  {:>6} {:>10} {:>15}", "passes", "speed mm/s", "weave mm @ Hz");
    }
    println!("{head}");
    let measured =
        |m: Option<weldseam_proto::along_seam::Measured>| m.map_or("-".to_string(), |m| format!("{:.2}", m.value));
    for (i, w) in seam.waypoints.iter().enumerate() {
        let mut row = format!(
            "  {:>4}  {:>10.3} {:>10.3} {:>10.3}  {:>9.3} {:>9.3} {:>9.3}",
            i, w.xyz[0], w.xyz[1], w.xyz[2], w.rpy_deg[0], w.rpy_deg[1], w.rpy_deg[2]
        );
        if let Some(f) = figures.get(i) {
            row += &format!("  {:>13} {:>8}", measured(f.gap_mm.or(f.lap_step_mm)), measured(f.high_low_mm));
        }
        if let Some(p) = process {
            match p.waypoints.get(i).and_then(Option::as_ref) {
                Some(at) => {
                    let first = at.passes.first();
                    let speed = first.map_or("-".to_string(), |p| format!("{:.2}", p.travel_speed_mm_s));
                    let weave = first
                        .and_then(|p| p.weave)
                        .map_or("-".to_string(), |w| format!("{:.2} @ {:.2}", w.amplitude_mm, w.frequency_hz));
                    let turned = if at.re_angled { " re-angled" } else { "" };
                    row += &format!("  {:>6} {speed:>10} {weave:>15}{turned}", at.passes.len());
                }
                None => row += &format!("  {:>6}", "cut"),
            }
        }
        println!("{row}");
    }
    for c in process.map(|p| p.cut.as_slice()).unwrap_or_default() {
        let contact = c.contact_camera_mm.map_or(String::new(), |p| {
            format!(", contact at ({:.1}, {:.1}, {:.1}) mm in the camera frame", p[0], p[1], p[2])
        });
        println!("  cut: waypoints {} to {} (rule {}): {}{contact}", c.first, c.last, c.rule, c.reason);
    }
}

/// Error replies become "error CODE (name): message" for the exit report,
/// with ", rule ID" after the code when a rule of the planner refused.
fn explain(e: ClientError) -> anyhow::Error {
    match e {
        ClientError::Refused(r) => match &r.rule {
            Some(rule) => anyhow::anyhow!("error {}, rule {rule}: {}", r.code, r.message),
            None => anyhow::anyhow!("error {}: {}", r.code, r.message),
        },
        other => other.into(),
    }
}
