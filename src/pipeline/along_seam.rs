//! The joint's figures along the seam: at every waypoint, the gap, the
//! high-low (mismatch), a V-groove's cross-section and a lap's step, read
//! from the points near it, each with its standard error.
//!
//! The seam is found and checked first; this module only reads. At each
//! station it takes a slab across the seam, [`slab_length_mm`] long, and
//! measures it with the per-seam measures' own code on the slab alone:
//!
//! - each weld edge's boundary samples in the slab are fitted as a line
//!   by [`refit::fit_trimmed`], the fit the whole edge gets; the gap is
//!   the two lines' distance across the seam at the station, the high-low
//!   (a butt's) or the step (a lap's, upper edge to the lower plate's edge
//!   at the root) their distance along the plate normal, as
//!   [`quality::measure`] reads them over the whole seam. Each edge's
//!   standard error is [`quality::edge_sigma`]; a distance between two
//!   edges has both, `√(σ1² + σ2²)`;
//! - a V-groove's bevels in the slab are probed by [`groove::probe`] between
//!   the slab's two edge lines; its gap is its opening where the bevels
//!   meet the plates' top (the plates' edges stop short of it, as the
//!   edge criterion walks onto a bevel's first millimetres), and its
//!   cross-section is the area between the
//!   bevels from the plates' top down to the depth the probe finds,
//!   `Σ (cᵢ d − d² tan αᵢ / 2)` over the two bevels (`cᵢ` where a bevel
//!   meets the top, `αᵢ` its angle from the normal; one bevel seen: twice
//!   its half). Its standard error is `d` times the bevels' tops' (a
//!   line's end: `2 rms / √n` each) and the root's width times the depth's,
//!   which is read at a point and so known to a spacing's `1 / √12`.
//!
//! A figure is `None` where the slab holds too few samples of an edge
//! ([`MIN_SLAB_SAMPLES`]) or no bevel shows the groove's root: the plan
//! says it does not know rather than carry the seam's mean.

use rayon::prelude::*;

use crate::cloud::PointCloud;
use crate::config::Config;
use crate::geometry::Vec3;
use crate::geometry::fit::Plane;
use crate::joint::JointType;

use super::background::Workpiece;
use super::boundary::Boundary;
use super::context::CameraGrid;
use super::groove::{self, GrooveProfile};
use super::quality;
use super::refit::{self, CurveFit, SeamAxes};

/// The shortest slab, mm: long enough that each edge's samples (one a scan
/// line or strip, 0.3 to 0.5 mm apart at a structured-light camera's
/// working distance) average their pixel steps over 16 to 25 of them, and
/// short enough to follow a gap that opens along a seam of a few hundred
/// mm.
pub const MIN_SLAB_LENGTH_MM: f64 = 8.0;

/// ... and never fewer than this many point spacings, on a coarse cloud.
pub const SLAB_SPACINGS: f64 = 16.0;

/// The fewest boundary samples of an edge a slab's line is fitted from:
/// a line and a spread beside it.
pub const MIN_SLAB_SAMPLES: usize = 6;

/// A figure and its standard error (one sigma), in the figure's unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    pub value: f64,
    pub sigma: f64,
}

/// The joint at one waypoint.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointFigures {
    /// Butt joints: the distance between the weld edges across the seam,
    /// mm (an I-butt's gap, a V-groove's opening at the top).
    pub gap_mm: Option<Measured>,
    /// Butt joints: the plates' height difference along the normal, mm.
    pub high_low_mm: Option<Measured>,
    /// V-butt joints: the groove's cross-section from the plates' top to
    /// its root, mm², with its angle (degrees) and depth (mm).
    pub groove_area_mm2: Option<Measured>,
    pub groove_angle_deg: Option<f64>,
    pub groove_depth_mm: Option<f64>,
    /// Lap joints: the step from the upper plate's edge down to the lower
    /// plate, mm (the upper plate's thickness at the root).
    pub lap_step_mm: Option<Measured>,
}

/// What the bevels of a V-groove are probed with, beside the cloud.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrooveSetting {
    pub depth_to_support_mm: Option<f64>,
    pub floor_between_plates: bool,
    /// The structured-light projector in the camera frame.
    pub projector: Vec3,
}

/// What the seam's stages found that the figures along it are read from:
/// its two weld edges' boundary samples on the seam's axes (a lap: the
/// upper plate's edge first), and for a V-groove the probe's setting.
#[derive(Debug, Clone, PartialEq)]
pub struct Evidence {
    pub joint: JointType,
    pub axes: SeamAxes,
    pub samples: [Vec<Vec3>; 2],
    pub planes: [Plane; 2],
    pub point_spacing_mm: f64,
    /// The edges' fits' trimming, `pipeline.fit_trim_sigma`.
    pub trim_sigma: f64,
    pub groove: Option<GrooveSetting>,
}

impl Evidence {
    /// The evidence of a butt joint's or a lap's seam: its plates, the
    /// joint decided, the seam's axes, its weld edges' boundary samples
    /// and the point spacing at the seam.
    pub(super) fn of_plates(
        config: &Config,
        workpiece: &Workpiece,
        joint: JointType,
        axes: SeamAxes,
        boundaries: &[Boundary; 2],
        point_spacing_mm: f64,
    ) -> Evidence {
        let groove = (joint == JointType::VButt).then(|| GrooveSetting {
            depth_to_support_mm: workpiece.depth_to_support_mm,
            floor_between_plates: workpiece.support_between_plates,
            projector: Vec3::new(config.camera.baseline_mm, 0.0, 0.0),
        });
        Evidence {
            joint,
            axes,
            samples: boundaries.each_ref().map(|b| b.samples.iter().map(|s| s.position).collect()),
            planes: workpiece.plates.each_ref().map(|p| p.plane),
            point_spacing_mm,
            trim_sigma: config.pipeline.fit_trim_sigma,
            groove,
        }
    }
}

/// How long a slab is on a cloud of `point_spacing_mm`.
pub fn slab_length_mm(point_spacing_mm: f64) -> f64 {
    MIN_SLAB_LENGTH_MM.max(SLAB_SPACINGS * point_spacing_mm)
}

/// The figures at each station, given as feature coordinates on the
/// evidence's axes. `grid` is the frame's pixel grid when it has the
/// camera's (the groove probe then reads only the pixels under its box).
pub(super) fn measure(
    evidence: &Evidence,
    cloud: &PointCloud,
    grid: Option<&CameraGrid>,
    stations: &[f64],
) -> Vec<JointFigures> {
    let length = slab_length_mm(evidence.point_spacing_mm);
    // A slab centred on a station near the seam's end would lie partly
    // past it, where the edges have no samples: it is slid along the seam
    // to lie within the stations' span (the figure is still read at the
    // station, on the lines fitted in the slab).
    let first = stations.iter().copied().fold(f64::INFINITY, f64::min);
    let last = stations.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let slab = |s: f64| {
        let from = (s - 0.5 * length).min(last - length).max(first);
        (from, from + length)
    };
    stations.par_iter().map(|&s| at_station(evidence, cloud, grid, s, slab(s))).collect()
}

/// The figures in the slab `span` round station `s`.
fn at_station(
    evidence: &Evidence,
    cloud: &PointCloud,
    grid: Option<&CameraGrid>,
    s: f64,
    span: (f64, f64),
) -> JointFigures {
    let axes = &evidence.axes;
    let fit_edge = |k: usize| -> Option<CurveFit> {
        let inside: Vec<Vec3> =
            evidence.samples[k].iter().filter(|p| (span.0..=span.1).contains(&axes.feature(p))).copied().collect();
        if inside.len() < MIN_SLAB_SAMPLES {
            return None;
        }
        refit::fit_trimmed(&inside, axes, 1, evidence.trim_sigma, evidence.point_spacing_mm)
    };
    let (Some(first), Some(second)) = (fit_edge(0), fit_edge(1)) else {
        return JointFigures::default();
    };
    let spacing = evidence.point_spacing_mm;
    let edge_sigmas = [&first, &second].map(|fit| quality::edge_sigma(fit, 1, spacing));
    let sigma = edge_sigmas[0].hypot(edge_sigmas[1]);
    let offset = second.curve.at(s) - first.curve.at(s);
    let across = Measured { value: offset.dot(&axes.a).abs(), sigma };
    let along_normal = Measured { value: offset.dot(&axes.b).abs(), sigma };
    match evidence.joint {
        JointType::Lap => JointFigures { lap_step_mm: Some(along_normal), ..JointFigures::default() },
        JointType::IButt => {
            JointFigures { gap_mm: Some(across), high_low_mm: Some(along_normal), ..JointFigures::default() }
        }
        JointType::VButt => {
            let profile = evidence.groove.map(|setting| {
                groove::probe(
                    cloud,
                    &groove::ProbeSetting {
                        edges: [&first.curve, &second.curve],
                        span,
                        point_spacing_mm: spacing,
                        depth_to_support_mm: setting.depth_to_support_mm,
                        floor_between_plates: setting.floor_between_plates,
                        grid,
                        projector: setting.projector,
                    },
                )
            });
            let area = profile.as_ref().and_then(|p| groove_area(p, s));
            // The plates' edges stop short of a bevel's top (the edge
            // criterion walks onto its first millimetres); the bevels
            // seen, carried up to the top, place the opening.
            let edges = EdgesAcross { apart_mm: across.value, sigma_mm: edge_sigmas };
            let opening = profile.as_ref().and_then(|p| bevel_opening(p, s, &edges)).unwrap_or(across);
            JointFigures {
                gap_mm: Some(opening),
                high_low_mm: Some(along_normal),
                groove_area_mm2: area,
                groove_angle_deg: profile.as_ref().and_then(GrooveProfile::groove_angle_deg),
                groove_depth_mm: profile.as_ref().and_then(GrooveProfile::depth_mm),
                ..JointFigures::default()
            }
        }
        JointType::TFillet => JointFigures::default(),
    }
}

/// Where a butt joint's two weld edges lie across the seam at a station:
/// how far apart, and each one's standard error (the first edge's first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgesAcross {
    pub apart_mm: f64,
    pub sigma_mm: [f64; 2],
}

/// A V-groove's opening at the plates' top at `s`: each side's bevel's
/// fitted line where it meets the top, known to a line's end
/// (`2 rms / √n`); a side whose bevel is not seen, by its weld edge
/// (`edges`, on the probe's midline between them). The camera sees a
/// bevel that faces away from it, or lies in the projector's shadow, not
/// at all: the plate's top then ends at the bevel's edge as at a square
/// gap's, where the edge criterion places it, while on a bevel it sees
/// the criterion walks onto the bevel's first millimetres and the edge
/// lies short of the top by 0.2 to 0.5 mm across. `None` without a bevel.
pub fn bevel_opening(profile: &GrooveProfile, s: f64, edges: &EdgesAcross) -> Option<Measured> {
    let bevels = [-1, 1].map(|side| profile.bevels().find(|f| f.side == side));
    if bevels.iter().all(Option::is_none) {
        return None;
    }
    // The bevels' tops are read as |t| from the edges' midline; an edge
    // lies half their distance from it.
    let [(first, first_sigma), (second, second_sigma)] = [0, 1].map(|k| {
        bevels[k].map_or((0.5 * edges.apart_mm, edges.sigma_mm[k]), |f| {
            (f.top.at(s), 2.0 * f.rms_mm / (f.points.max(1) as f64).sqrt())
        })
    });
    Some(Measured { value: first + second, sigma: first_sigma.hypot(second_sigma) })
}

/// A V-groove's cross-section at `s` from its profile: between the bevels,
/// from the plates' top down to the depth the profile finds (see the
/// module's documentation), or `None` without a bevel or a depth.
pub fn groove_area(profile: &GrooveProfile, s: f64) -> Option<Measured> {
    let depth = profile.depth_mm()?;
    let bevels: Vec<_> = profile.bevels().collect();
    // One bevel seen: the groove taken as symmetric about its midline.
    let weight = match bevels.len() {
        1 => 2.0,
        2 => 1.0,
        _ => return None,
    };
    let mut area = 0.0;
    let mut bottom = 0.0;
    let mut tops_variance = 0.0;
    for face in &bevels {
        let top = face.top.at(s);
        let run = depth * face.angle_deg.to_radians().tan();
        area += weight * (top * depth - 0.5 * depth * run);
        bottom += weight * (top - run);
        tops_variance += weight * (2.0 * face.rms_mm / (face.points.max(1) as f64).sqrt()).powi(2);
    }
    let depth_variance = profile.point_spacing_mm.powi(2) / 12.0;
    let sigma = (depth * depth * tops_variance + bottom.max(0.0).powi(2) * depth_variance).sqrt();
    (area > 0.0).then_some(Measured { value: area, sigma })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axes() -> SeamAxes {
        SeamAxes { origin: Vec3::new(0.0, 0.0, 600.0), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() }
    }

    /// Two edges along y, 0.5 mm apart in samples, whose distance across
    /// opens linearly from `gap0` to `gap1` over y = 0..100 and whose
    /// second edge stands `high_low` lower along the normal.
    fn opening_edges(gap0: f64, gap1: f64, high_low: f64) -> [Vec<Vec3>; 2] {
        let gap = |y: f64| gap0 + (gap1 - gap0) * y / 100.0;
        let ys: Vec<f64> = (0..=200).map(|k| k as f64 * 0.5).collect();
        // A pixel-sized staircase of ±0.1 mm, as edge samples have.
        let wobble = |k: usize| 0.1 * ((k % 3) as f64 - 1.0);
        [
            ys.iter().enumerate().map(|(k, &y)| Vec3::new(-gap(y) / 2.0 + wobble(k), y, 600.0)).collect(),
            ys.iter().enumerate().map(|(k, &y)| Vec3::new(gap(y) / 2.0 - wobble(k), y, 600.0 + high_low)).collect(),
        ]
    }

    fn evidence(joint: JointType, samples: [Vec<Vec3>; 2]) -> Evidence {
        let plane = Plane { normal: Vec3::z(), offset: 600.0 };
        Evidence {
            joint,
            axes: axes(),
            samples,
            planes: [plane, plane],
            point_spacing_mm: 0.5,
            trim_sigma: 3.0,
            groove: None,
        }
    }

    #[test]
    fn a_gap_that_opens_along_the_seam_is_followed_station_by_station() {
        let e = evidence(JointType::IButt, opening_edges(0.5, 3.0, 0.8));
        let cloud = PointCloud::unorganized(Vec::new());
        let stations: Vec<f64> = (1..10).map(|k| k as f64 * 10.0).collect();
        let figures = measure(&e, &cloud, None, &stations);
        for (s, f) in stations.iter().zip(&figures) {
            let gap = f.gap_mm.expect("both edges are seen");
            let truth = 0.5 + 2.5 * s / 100.0;
            assert!((gap.value - truth).abs() < 0.05, "at {s}: {gap:?} for {truth}");
            // Each edge known to its samples' scatter and a spacing's
            // 1/√12 at least: the gap to √2 of that.
            let floor = 2f64.sqrt() * 0.5 / 12f64.sqrt();
            assert!(gap.sigma >= floor - 1e-12 && gap.sigma < 0.3, "{gap:?}");
            let high_low = f.high_low_mm.expect("a butt's high-low");
            assert!((high_low.value - 0.8).abs() < 0.05, "{high_low:?}");
            assert_eq!((f.lap_step_mm, f.groove_area_mm2), (None, None));
        }
        // The seam's mean would be 1.75 mm everywhere: the stations at 10
        // and 90 mm are 2 mm apart in truth, and so in the figures.
        let spread = figures[8].gap_mm.unwrap().value - figures[0].gap_mm.unwrap().value;
        assert!((spread - 2.0).abs() < 0.1, "{spread}");
    }

    /// The demo I-butt captured, then its second plate (and the table
    /// beside it) sheared away from the first in the cloud so that the gap
    /// opens from 1.5 mm at one end of the seam to 3.5 mm at the other:
    /// every waypoint's gap follows the gap under it, not the seam's mean.
    #[test]
    fn a_simulated_gap_that_opens_along_the_seam_is_followed_at_every_waypoint() {
        use crate::camera::CameraModel;
        use crate::pipeline::{PlanRequest, Planner};
        use crate::sim::{demo_scene, simulate};
        use nalgebra::Point3;

        let spec = demo_scene(JointType::IButt);
        let [y0, y1] = spec.seam_range();
        // The gap's growth per mm along the seam (workpiece y).
        let opening = 2.0 / (y1 - y0);
        let truth = |y: f64| 1.5 + opening * (y.clamp(y0, y1) - y0);
        let mut sim = simulate(&spec, &CameraModel::default());
        sim.reshape_in_workpiece_frame(&spec, |w| {
            // The second plate (workpiece x > 0) pulled away from the first.
            let mut w = *w;
            if w.x > 0.0 {
                w.x += opening * (w.y - y0);
            }
            Some(w)
        });

        let planner = Planner::new(Config::default());
        let request = PlanRequest::new(JointType::IButt, None, sim.pose);
        let plan = planner.plan(&sim.cloud, &request).expect("the sheared butt plans");
        let seam = &plan.seams[0];
        assert_eq!(seam.along_seam.len(), seam.waypoints.len());
        let workpiece_from_base = spec.base_from_workpiece.inverse();
        let mut errors = Vec::new();
        for (w, f) in seam.waypoints.iter().zip(&seam.along_seam) {
            let y = (workpiece_from_base * Point3::from(w.position)).y;
            let Some(gap) = f.gap_mm else { continue };
            errors.push((y, gap.value, truth(y)));
        }
        eprintln!("(y, measured, true) gap: {errors:.2?}");
        assert!(errors.len() * 10 >= seam.waypoints.len() * 9, "{} of {}", errors.len(), seam.waypoints.len());
        for &(y, measured, true_gap) in &errors {
            assert!((measured - true_gap).abs() < 0.5, "at y = {y:.1}: {measured:.3} for {true_gap:.3}");
        }
        let mut sorted: Vec<f64> = errors.iter().map(|(_, m, t)| (m - t).abs()).collect();
        sorted.sort_by(f64::total_cmp);
        assert!(sorted[sorted.len() / 2] < 0.2, "median error {:.3}", sorted[sorted.len() / 2]);
        // The seam's ends are 2 mm apart in truth, and so in the plan.
        let (first, last) = (errors[0], errors[errors.len() - 1]);
        assert!(((last.1 - first.1) - (last.2 - first.2)).abs() < 0.5, "{first:?} .. {last:?}");
        assert!((last.2 - first.2).abs() > 1.5, "the waypoints span most of the seam: {first:?} .. {last:?}");
    }

    #[test]
    fn a_slab_with_too_few_samples_of_an_edge_has_no_figure() {
        let [first, second] = opening_edges(1.0, 1.0, 0.0);
        // The second edge unseen from y = 40 to 60.
        let second = second.into_iter().filter(|p| !(40.0..=60.0).contains(&p.y)).collect();
        let e = evidence(JointType::IButt, [first, second]);
        let cloud = PointCloud::unorganized(Vec::new());
        let figures = measure(&e, &cloud, None, &[20.0, 50.0, 80.0]);
        assert!(figures[0].gap_mm.is_some() && figures[2].gap_mm.is_some());
        assert_eq!(figures[1], JointFigures::default());
    }

    /// The demo scenes planned: every waypoint of a butt joint and a lap
    /// carries its figures, near the scene's geometry (an I-butt's 1.5 mm
    /// gap, a V-groove 1 mm at the root, 60 degrees and 6 mm deep, a lap's
    /// 5 mm upper plate; the plates level).
    #[test]
    fn the_demo_scenes_figures_along_the_seam_follow_their_geometry() {
        use crate::camera::CameraModel;
        use crate::config::Config;
        use crate::pipeline::{PlanRequest, Planner};
        use crate::sim::{demo_scene, simulate};
        let planner = Planner::new(Config::default());
        let opening = 1.0 + 12.0 * 30f64.to_radians().tan();
        let cases = [
            (JointType::IButt, 1.5, 0.0),
            (JointType::VButt, opening, 6.0 * (opening + 1.0) / 2.0),
            (JointType::Lap, 5.0, 0.0),
        ];
        for (joint, truth, area) in cases {
            let sim = simulate(&demo_scene(joint), &CameraModel::default());
            let plan = planner.plan(&sim.cloud, &PlanRequest::new(joint, None, sim.pose)).expect("the demo plans");
            let seam = &plan.seams[0];
            assert_eq!(seam.along_seam.len(), seam.waypoints.len());
            let read = |f: &JointFigures| if joint == JointType::Lap { f.lap_step_mm } else { f.gap_mm };
            let errors: Vec<f64> = seam.along_seam.iter().filter_map(read).map(|m| (m.value - truth).abs()).collect();
            let high_low: Vec<f64> = seam.along_seam.iter().filter_map(|f| f.high_low_mm).map(|m| m.value).collect();
            let areas: Vec<f64> = seam
                .along_seam
                .iter()
                .filter_map(|f| f.groove_area_mm2)
                .map(|m| (m.value - area).abs() / area)
                .collect();
            eprintln!(
                "{joint}: {} waypoints, {} measured, errors {errors:.3?}, high-low {high_low:.3?}, areas {areas:.3?}",
                seam.waypoints.len(),
                errors.len()
            );
            assert!(
                errors.len() * 10 >= seam.waypoints.len() * 9,
                "{joint}: {} of {}",
                errors.len(),
                seam.waypoints.len()
            );
            let largest = errors.iter().copied().fold(0.0, f64::max);
            assert!(largest < 0.5, "{joint}: {errors:?}");
            assert!(high_low.iter().all(|v| *v < 0.5), "{joint}: {high_low:?}");
            assert!(areas.iter().all(|e| *e < 0.10), "{joint}: {areas:?}");
        }
    }

    /// A bevel of a 60 degree groove on `side` whose top lies `top_mm`
    /// from the probe's midline, fitted to 400 points with a 0.1 mm RMS.
    fn bevel(side: i8, top_mm: f64) -> groove::Face {
        groove::Face {
            side,
            points: 400,
            angle_deg: 30.0,
            rms_mm: 0.1,
            station_rms_mm: 0.1,
            depth_mm: 8.0,
            foot_mm: 0.5,
            station_share: 1.0,
            along_rays: false,
            foot_hidden: false,
            foot_at_probe_bottom: false,
            foot_on_floor: false,
            top: groove::LineAlong { middle_s: 50.0, at_middle_mm: top_mm, per_mm: 0.0 },
            stations: std::array::from_fn(|_| None),
        }
    }

    fn profile_of(faces: Vec<groove::Face>) -> GrooveProfile {
        GrooveProfile {
            point_spacing_mm: 0.3,
            opening_mm: 9.6,
            points_below: 400,
            faces,
            standing: None,
            span: (0.0, 100.0),
        }
    }

    #[test]
    fn a_grooves_opening_is_read_at_its_bevels_tops_and_where_one_is_unseen_at_that_sides_edge() {
        // The edges 9.6 mm apart, each found 0.2 mm down the bevel it
        // stands on: the bevels' tops lie 5.0 mm either side.
        let edges = EdgesAcross { apart_mm: 9.6, sigma_mm: [0.08, 0.09] };
        let both = bevel_opening(&profile_of(vec![bevel(-1, 5.0), bevel(1, 5.0)]), 50.0, &edges).unwrap();
        assert!((both.value - 10.0).abs() < 1e-9, "{both:?}");
        assert!((both.sigma - 2f64.sqrt() * 0.01).abs() < 1e-9, "{both:?}");
        // The first bevel unseen (facing away from the camera): its plate's
        // edge, half the edges' distance from their midline, stands for it,
        // and its standard error comes with it.
        let one = bevel_opening(&profile_of(vec![bevel(1, 5.0)]), 50.0, &edges).unwrap();
        assert!((one.value - 9.8).abs() < 1e-9, "{one:?}");
        assert!((one.sigma - 0.08f64.hypot(0.01)).abs() < 1e-9, "{one:?}");
        // A face too steep to be a bevel is no bevel's top.
        let wall = groove::Face { angle_deg: 2.0, ..bevel(1, 5.0) };
        assert_eq!(bevel_opening(&profile_of(vec![wall]), 50.0, &edges), None);
        assert_eq!(bevel_opening(&profile_of(Vec::new()), 50.0, &edges), None);
    }

    #[test]
    fn a_laps_step_is_the_edges_distance_along_the_normal() {
        let e = evidence(JointType::Lap, opening_edges(0.0, 0.0, 4.0));
        let cloud = PointCloud::unorganized(Vec::new());
        let f = measure(&e, &cloud, None, &[50.0])[0];
        assert!((f.lap_step_mm.unwrap().value - 4.0).abs() < 1e-6, "{f:?}");
        assert_eq!((f.gap_mm, f.high_low_mm), (None, None));
    }
}
