//! The weld process along a planned seam, when a procedure is configured
//! (`process.procedure`): at every waypoint, the passes and the arc's
//! settings [`weld_station`] gives for the joint measured there
//! ([`super::along_seam`]), the weave, and the torch's angles cleared
//! against the frame's cloud ([`crate::process::clearance`]).
//!
//! The joint's cross-section at a waypoint, from its figures and the
//! plates' thickness `t` (`process.plate_thickness_mm`, or where it is 0,
//! the joint's own: a V-groove's depth, a lap's step):
//!
//! - square butt: `t` and the gap;
//! - V-groove: its angle, its depth `d`, the root gap
//!   `W − 2 d tan(α/2)` from its opening `W`, and a root face `t − d`;
//! - lap: the procedure's fillet on the upper plate `t` (its step);
//! - tee: the procedure's fillet, where `t` is configured.
//!
//! The torch is the entry's ([`Procedure::torch_for`]: the procedure's,
//! or the entry's own nozzle, contact tip and stand-off), checked for
//! every pass at the waypoint: the pass the
//! waypoints trace (a single pass, or a V-groove's root) aimed at the
//! waypoint along the seam's torch axis, each other pass at its own aim
//! point, every one tilted by its work angle and the entry's travel angle
//! in the frame [`Station`] defines. The obstacles are the frame's points
//! and the space behind them as the camera saw it. Where the torch leans
//! to clear, every pass leans as much and the waypoint's orientation
//! follows the angles the traced pass cleared at.
//!
//! Three rules cut stretches from the welded seam, each a run of
//! consecutive waypoints with its reason: figures not measured
//! ([`rules::process::FIGURES_UNMEASURED`]), a joint outside the
//! procedure ([`rules::process::OUTSIDE_PROCEDURE`]) and a torch no angle
//! clears ([`rules::process::TORCH_BLOCKED`]). The waypoints stay in the
//! seam; a cut waypoint carries no parameters.

use crate::cloud::PointCloud;
use crate::config::procedure::Torch;
use crate::geometry::Vec3;
use crate::joint::JointType;
use crate::process::clearance::{Aim, Clearance, Contact, Obstacles, Station, clear_station};
use crate::process::{JointSection, Layout, PassKind, Procedure, VGroove, fillet_section, weld_station};
use crate::rules::{self, Rule};

use nalgebra::Isometry3;

use super::along_seam::JointFigures;
use super::refit::SeamCurve;
use super::trajectory::{self, Waypoint};

/// What one waypoint is welded with.
#[derive(Debug, Clone, PartialEq)]
pub struct WaypointProcess {
    /// The plates' thickness the entry was picked by, mm.
    pub thickness_mm: f64,
    /// The passes and their settings at this waypoint.
    pub layout: Layout,
    /// The torch angles of the pass the waypoints trace, in the
    /// clearance's frame ([`Station::axis`]), degrees.
    pub work_angle_deg: f64,
    pub travel_angle_deg: f64,
    /// Whether they were moved from the procedure's to clear the cloud.
    pub re_angled: bool,
    /// The torch's axis, from the waypoint towards the torch, camera frame.
    pub torch_axis_camera: Vec3,
    /// The seam's frame at the waypoint (camera frame): the pass offsets
    /// and work angles of [`Layout`] are across and up from it.
    pub station: Station,
}

/// A run of waypoints cut from the welded seam, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct CutStretch {
    /// The first and last waypoint cut, indices into the seam's waypoints.
    pub first: usize,
    pub last: usize,
    pub rule: &'static Rule,
    /// The figure and the limit, or what is missing, at the first waypoint.
    pub reason: String,
    /// Where the torch touches the cloud (camera frame, mm), for a torch
    /// blocked.
    pub contact_camera: Option<Vec3>,
}

/// The process along one seam.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamProcess {
    /// The procedure's name.
    pub procedure: String,
    /// Per waypoint, in order; None where the waypoint is cut.
    pub waypoints: Vec<Option<WaypointProcess>>,
    pub cut: Vec<CutStretch>,
    /// `Base_T_Camera` of the frame: the stations' frames in the base.
    pub base_from_camera: Isometry3<f64>,
}

/// Where one waypoint lies, camera frame: the aim point, the direction of
/// travel and the torch's axis into the workpiece before any angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Place {
    pub point: Vec3,
    pub travel: Vec3,
    pub into: Vec3,
}

/// The places of a seam's waypoints, as [`trajectory::waypoints`] samples
/// them from `start` to `end` along `curve` with the torch's axis `into`
/// (camera frame).
pub fn places(curve: &SeamCurve, start: f64, end: f64, step_mm: f64, into: &Vec3) -> Vec<Place> {
    let forward = if end >= start { 1.0 } else { -1.0 };
    trajectory::sample_features(curve, start, end, step_mm)
        .into_iter()
        .map(|s| Place { point: curve.at(s), travel: curve.tangent(s) * forward, into: *into })
        .collect()
}

/// Turns each welded waypoint's torch to the angles the process set (and
/// cleared) there; a cut waypoint keeps the trajectory's.
pub fn orient(waypoints: &mut [Waypoint], places: &[Place], process: &SeamProcess, base_from_camera: &Isometry3<f64>) {
    for ((w, place), p) in waypoints.iter_mut().zip(places).zip(&process.waypoints) {
        if let Some(p) = p {
            let rotation = base_from_camera.rotation;
            w.orientation =
                trajectory::torch_orientation(&(rotation * place.travel), &(rotation * -p.torch_axis_camera), 0.0, 0.0);
        }
    }
}

/// The frame's points, indexed for the torch with the space behind them
/// the camera could not see: built once per frame, for every seam of it
/// (the torch reaches 100 mm and more round a seam, most of a frame). An
/// organized frame is read through its own pixel grid, the hidden space
/// laid only where the torch asks; any other cloud is binned by its rays.
pub fn obstacles_of<'a>(cloud: &'a PointCloud, torch: &Torch) -> Obstacles<'a> {
    let started = std::time::Instant::now();
    let obstacles = if cloud.is_organized() {
        Obstacles::seen_in_organized_frame(cloud.points(), cloud.width(), torch)
    } else {
        Obstacles::seen_in_frame(cloud.points(), torch)
    };
    tracing::debug!(
        ms = started.elapsed().as_secs_f64() * 1e3,
        organized = cloud.is_organized(),
        "the frame indexed for the torch"
    );
    obstacles
}

/// One waypoint's outcome: welded, or cut by a rule with its reason.
type Outcome = Result<WaypointProcess, (&'static Rule, String, Option<Vec3>)>;

/// The process at every waypoint of a seam of `joint`, in a frame taken
/// at `base_from_camera`.
pub fn along(
    procedure: &Procedure,
    joint: JointType,
    thickness_mm: Option<f64>,
    places: &[Place],
    figures: &[JointFigures],
    obstacles: &Obstacles,
    base_from_camera: &Isometry3<f64>,
) -> SeamProcess {
    use rayon::prelude::*;
    let outcomes: Vec<Outcome> = places
        .par_iter()
        .enumerate()
        .map(|(k, place)| at_waypoint(procedure, joint, thickness_mm, place, figures.get(k), obstacles))
        .collect();
    let mut cut: Vec<CutStretch> = Vec::new();
    for (k, outcome) in outcomes.iter().enumerate() {
        let Err((rule, reason, contact)) = outcome else { continue };
        let (rule, contact) = (*rule, *contact);
        match cut.last_mut() {
            Some(last) if last.last + 1 == k && std::ptr::eq(last.rule, rule) => last.last = k,
            _ => cut.push(CutStretch { first: k, last: k, rule, reason: reason.clone(), contact_camera: contact }),
        }
    }
    SeamProcess {
        procedure: procedure.name.clone(),
        waypoints: outcomes.into_iter().map(Result::ok).collect(),
        cut,
        base_from_camera: *base_from_camera,
    }
}

/// The section of the joint at a waypoint and the thickness its entry is
/// picked by, or what is missing.
fn section(
    procedure: &Procedure,
    joint: JointType,
    configured_mm: Option<f64>,
    f: &JointFigures,
) -> Result<(f64, JointSection), String> {
    let missing = |what: &str| format!("no {what} is measured at this waypoint");
    let thickness = |what: &str| {
        configured_mm
            .ok_or_else(|| format!("a {what}'s plate thickness is not measured: set process.plate_thickness_mm"))
    };
    match joint {
        JointType::IButt => {
            let t = thickness("square butt")?;
            let gap = f.gap_mm.ok_or_else(|| missing("gap"))?.value;
            Ok((t, JointSection::SquareButt { thickness_mm: t, gap_mm: gap }))
        }
        JointType::VButt => {
            let angle = f.groove_angle_deg.ok_or_else(|| missing("groove angle"))?;
            let depth = f.groove_depth_mm.ok_or_else(|| missing("groove depth"))?;
            let opening = f.gap_mm.ok_or_else(|| missing("groove opening"))?.value;
            let t = configured_mm.unwrap_or(depth).max(depth);
            let root_gap = (opening - 2.0 * depth * (angle.to_radians() / 2.0).tan()).max(0.0);
            let groove =
                VGroove { thickness_mm: t, included_angle_deg: angle, root_gap_mm: root_gap, root_face_mm: t - depth };
            Ok((t, JointSection::VGroove(groove)))
        }
        JointType::Lap | JointType::TFillet => {
            let t = match (joint, configured_mm) {
                (_, Some(t)) => t,
                (JointType::Lap, None) => f.lap_step_mm.ok_or_else(|| missing("lap step"))?.value,
                _ => thickness("tee")?,
            };
            // Without an entry for the thickness, weld_station names the
            // ranges there are before it reads the section.
            let section =
                fillet_section(procedure, joint, t, 0.0).unwrap_or(JointSection::Fillet { leg_mm: 0.0, gap_mm: 0.0 });
            Ok((t, section))
        }
    }
}

/// The passes and settings the procedure gives a joint measured as `f`,
/// the torch aside: what a waypoint cut only for its torch would be
/// welded with where the torch could reach it (the eval scores a groove's
/// layout there), or why there are none.
pub fn layout_for(
    procedure: &Procedure,
    joint: JointType,
    configured_mm: Option<f64>,
    f: &JointFigures,
) -> Result<Layout, String> {
    let (thickness_mm, section) = section(procedure, joint, configured_mm, f)?;
    weld_station(procedure, joint, thickness_mm, &section).map_err(|e| e.to_string())
}

fn at_waypoint(
    procedure: &Procedure,
    joint: JointType,
    configured_mm: Option<f64>,
    place: &Place,
    figures: Option<&JointFigures>,
    obstacles: &Obstacles,
) -> Outcome {
    let unmeasured = |reason: String| (&rules::process::FIGURES_UNMEASURED, reason, None);
    let figures = figures.copied().unwrap_or_default();
    let (thickness_mm, section) = section(procedure, joint, configured_mm, &figures).map_err(unmeasured)?;
    let layout = weld_station(procedure, joint, thickness_mm, &section)
        .map_err(|e| (&rules::process::OUTSIDE_PROCEDURE, e.to_string(), None))?;
    let entry = procedure.entry(joint, thickness_mm).expect("weld_station found the entry");
    // The traced pass first, at the waypoint itself; then every other
    // pass at its aim point.
    let traced = layout.passes.iter().position(|p| matches!(p.kind, PassKind::Single | PassKind::Root));
    let traced_work = traced.map_or(entry.work_angle_deg, |k| layout.passes[k].work_angle_deg);
    let mut aims = vec![Aim::at_point(traced_work)];
    let others = layout.passes.iter().enumerate().filter(|(k, _)| Some(*k) != traced);
    let mut names = vec![traced.map_or_else(|| "pass".to_owned(), |k| pass_name(&layout.passes[k]))];
    for (_, pass) in others {
        aims.push(Aim { across_mm: pass.lateral_mm, up_mm: pass.height_mm, work_angle_deg: pass.work_angle_deg });
        names.push(pass_name(pass));
    }
    let station = Station { point: place.point, along: place.travel, bisector: -place.into };
    let torch = procedure.torch_for(entry);
    match clear_station(&torch, obstacles, &station, &aims, entry.travel_angle_deg) {
        Clearance::Clear { lean_deg, travel_angle_deg, moved } => Ok(WaypointProcess {
            thickness_mm,
            layout,
            work_angle_deg: traced_work + lean_deg,
            travel_angle_deg,
            re_angled: moved,
            torch_axis_camera: station.axis(traced_work + lean_deg, travel_angle_deg),
            station,
        }),
        Clearance::Blocked { pass, contact } => {
            let p = contact.point();
            let what = match contact {
                Contact::Seen(_) => "touches the cloud",
                Contact::Hidden(_) => "reaches behind a surface the camera saw, where it could not see,",
            };
            Err((
                &rules::process::TORCH_BLOCKED,
                format!(
                    "the torch of the {} {what} at ({:.1}, {:.1}, {:.1}) mm at every angle within the procedure's \
                     limits (work ±{}°, travel {:?}°)",
                    names.get(pass).map_or("pass", String::as_str),
                    p.x,
                    p.y,
                    p.z,
                    torch.work_deviation_deg,
                    torch.travel_angle_range_deg
                ),
                Some(p),
            ))
        }
    }
}

/// A pass's name in a reason, its layer and bead counted from 1.
fn pass_name(pass: &crate::process::Pass) -> String {
    match pass.kind {
        PassKind::Root => "root pass".to_owned(),
        PassKind::Single => "pass".to_owned(),
        PassKind::Fill => format!("fill pass of layer {}, bead {}", pass.layer, pass.bead + 1),
        PassKind::Cap => format!("cap pass, bead {}", pass.bead + 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::along_seam::Measured;

    fn places(n: usize) -> Vec<Place> {
        (0..n)
            .map(|k| Place { point: Vec3::new(0.0, k as f64 * 5.0, 600.0), travel: Vec3::y(), into: Vec3::z() })
            .collect()
    }

    fn gap(value: f64) -> JointFigures {
        let m = Measured { value, sigma: 0.05 };
        JointFigures { gap_mm: Some(m), high_low_mm: Some(Measured { value: 0.0, sigma: 0.05 }), ..Default::default() }
    }

    /// Flat plates in z = 600 on both sides of the seam (x = 0), with a
    /// gap between them.
    fn plates() -> Vec<Vec3> {
        let mut points = Vec::new();
        for i in -60..=60 {
            for j in -20..=120 {
                let x = i as f64;
                if x.abs() >= 2.0 {
                    points.push(Vec3::new(x, j as f64, 600.0));
                }
            }
        }
        points
    }

    #[test]
    fn a_gap_that_opens_along_the_seam_sets_the_arc_at_every_waypoint() {
        let p = Procedure::example();
        let n = 21;
        let figures: Vec<JointFigures> = (0..n).map(|k| gap(0.5 + 2.5 * k as f64 / (n - 1) as f64)).collect();
        let obstacles = Obstacles::new(plates());
        let process = along(&p, JointType::IButt, Some(3.0), &places(n), &figures, &obstacles, &Isometry3::identity());
        assert!(process.cut.is_empty(), "{:?}", process.cut);
        let mut feeds = Vec::new();
        for (w, f) in process.waypoints.iter().zip(&figures) {
            let w = w.as_ref().expect("every waypoint welded");
            let wanted = w.layout.joint_area_mm2 + w.layout.crown_area_mm2;
            let got = w.layout.deposited_area_mm2();
            assert!((got - wanted).abs() / wanted < 0.10, "gap {:?}: {got} for {wanted}", f.gap_mm);
            assert!(!w.re_angled);
            feeds.push(w.layout.passes[0].settings.wire_feed_m_min);
        }
        // More metal for a wider gap: the wire feeds faster (or the torch
        // slows once the feed is at its top).
        assert!(feeds.last() > feeds.first(), "{feeds:?}");
    }

    #[test]
    fn stretches_the_procedure_cannot_weld_are_cut_and_named() {
        let p = Procedure::example();
        let n = 12;
        // Waypoints 0-3 measured, 4-5 not, 6-7 a gap beyond the square
        // butt's limit, 8-11 measured again but under a clamp from 9 on.
        let mut figures: Vec<JointFigures> = (0..n).map(|_| gap(1.0)).collect();
        figures[4] = JointFigures::default();
        figures[5] = JointFigures::default();
        figures[6] = gap(9.0);
        figures[7] = gap(9.0);
        let mut points = plates();
        // A clamp's jaw 20 mm above the seam from y = 45 on: the nozzle
        // reaches it at every angle the procedure allows.
        for i in -30..=30 {
            for j in 45..=80 {
                points.push(Vec3::new(i as f64, j as f64, 580.0));
            }
        }
        let obstacles = Obstacles::new(points);
        let process = along(&p, JointType::IButt, Some(3.0), &places(n), &figures, &obstacles, &Isometry3::identity());
        let cut: Vec<(usize, usize, &str)> = process.cut.iter().map(|c| (c.first, c.last, c.rule.id)).collect();
        assert_eq!(cut.len(), 3, "{:?}", process.cut);
        assert_eq!(&cut[..2], &[(4, 5, "process.figures_unmeasured"), (6, 7, "process.outside_procedure")]);
        // The jaw starts at waypoint 9; the torch's nozzle, 10 mm round
        // its axis, reaches it from waypoint 8 unless a lean clears it.
        let (first, last, rule) = cut[2];
        assert!((8..=9).contains(&first) && last == 11 && rule == "process.torch_blocked", "{:?}", process.cut);
        assert!(process.cut[1].reason.contains("9.00 mm"), "{}", process.cut[1].reason);
        let contact = process.cut[2].contact_camera.expect("the point of contact");
        assert!((contact.z - 580.0).abs() < 1e-3, "on the jaw: {contact:?}");
        assert!(process.waypoints[..4].iter().all(Option::is_some));
        assert!(process.waypoints[4..8].iter().chain(&process.waypoints[9..]).all(Option::is_none));
        // A square butt with no thickness configured is not measured.
        let unknown = along(&p, JointType::IButt, None, &places(2), &figures[..2], &obstacles, &Isometry3::identity());
        assert_eq!(unknown.cut[0].rule.id, "process.figures_unmeasured");
        assert!(unknown.cut[0].reason.contains("process.plate_thickness_mm"), "{}", unknown.cut[0].reason);
    }

    /// The demo scenes planned with the example procedure: the waypoints
    /// stand where they stand without it, each carries the passes for the
    /// joint measured under it, and the metal they lay fills the joint and
    /// its crown within 10 %.
    #[test]
    fn the_demo_scenes_are_welded_waypoint_by_waypoint_where_they_were_planned() {
        use crate::camera::CameraModel;
        use crate::config::{Config, ProcessParams};
        use crate::pipeline::{PlanRequest, Planner};
        use crate::sim::{demo_scene, simulate};
        // The demo's plates: a 6 mm I-butt, a 10 mm V-groove, a lap's
        // upper plate taken from its step.
        for (joint, thickness) in
            [(JointType::IButt, Some(6.0)), (JointType::VButt, Some(10.0)), (JointType::Lap, None)]
        {
            let sim = simulate(&demo_scene(joint), &CameraModel::default());
            let request = PlanRequest::new(joint, None, sim.pose);
            let bare = Planner::new(Config::default()).plan(&sim.cloud, &request).expect("the demo plans");
            let process = ProcessParams { procedure: Some(Procedure::example()), plate_thickness_mm: thickness };
            let config = Config { process, ..Config::default() };
            let plan = Planner::new(config).plan(&sim.cloud, &request).expect("the demo plans with a procedure");
            let (seam, bare) = (&plan.seams[0], &bare.seams[0]);
            assert!(bare.process.is_none());
            let positions = |s: &crate::pipeline::Seam| s.waypoints.iter().map(|w| w.position).collect::<Vec<_>>();
            assert_eq!(positions(seam), positions(bare), "{joint}: the procedure moves no waypoint");
            let process = seam.process.as_ref().expect("a procedure is configured");
            assert_eq!(process.waypoints.len(), seam.waypoints.len());
            let welded: Vec<&WaypointProcess> = process.waypoints.iter().flatten().collect();
            eprintln!("{joint}: {} of {} welded, cut {:?}", welded.len(), seam.waypoints.len(), process.cut);
            assert!(welded.len() * 10 >= seam.waypoints.len() * 9, "{joint}: {:?}", process.cut);
            for w in &welded {
                let wanted = w.layout.joint_area_mm2 + w.layout.crown_area_mm2;
                let got = w.layout.deposited_area_mm2();
                assert!((got - wanted).abs() / wanted < 0.10, "{joint}: {got:.2} mm² for {wanted:.2}");
            }
            if joint == JointType::VButt {
                // The demo's groove: 60 degrees, 6 mm deep, a 1 mm root gap
                // through a 4 mm root face, 30.8 mm² and a 1.2 mm crown
                // over its 7.9 mm opening 8.7 mm² more: 39.5 mm², half a
                // percent under the 40 mm² the entry lays in one pass. Where
                // the section measured there is over it, the groove is laid
                // out as root, fill and cap; one bead everywhere else.
                let opening = 1.0 + 12.0 * 30f64.to_radians().tan();
                let area = 6.0 * (opening + 1.0) / 2.0 + 4.0;
                let one_bead = Procedure::example()
                    .entries
                    .iter()
                    .find(|e| e.joint == JointType::VButt)
                    .map(|e| e.bead_area_mm2[1])
                    .expect("the example welds V-grooves");
                for w in &welded {
                    let error = (w.layout.joint_area_mm2 - area).abs() / area;
                    assert!(error < 0.10, "{:.2} mm² for {area:.2}", w.layout.joint_area_mm2);
                    let section = w.layout.joint_area_mm2 + w.layout.crown_area_mm2;
                    let passes = w.layout.passes.len();
                    assert_eq!(passes == 1, section <= one_bead, "{passes} passes for {section:.2} mm²");
                }
            }
        }
    }
}
