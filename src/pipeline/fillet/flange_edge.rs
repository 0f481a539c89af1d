//! A root from the flange's edge against the web, for a side whose face is
//! turned too nearly edge-on to return points: at each station along the
//! web the innermost flange point and the outermost point of the web's
//! top, a line fitted to each; the root on the first, taken only where
//! the face the two edges imply is turned towards both the camera and the
//! projector (a flange ending at the web's shadow implies a face turned
//! from the shadowing eye by nothing), and only where the web's top
//! stands over it.

use std::collections::HashSet;

use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, extent};

use super::super::refit::{SeamAxes, SeamCurve};
use super::super::straightness::{RootBend, Samples, bend_of};
use super::super::view_border::BORDER_REACH_SPACINGS;
use super::face::{FLANGE_REACH_SPACINGS, rms};
use super::frame::{FACE_REACH_SPACINGS, WebFrame, frame_along, valid_points};
use super::stretch::{MAX_STATIONS, STATION_SPACINGS, SeenRun, covered_share, seen_run};
use super::{NotRead, Root, RootEvidence, Side, TeeView, Web};
use crate::rules::Rule;
use crate::rules::refit::{
    TEE_FLANGE_EDGE_AT_SHADOW, TEE_FLANGE_EDGE_ENDS_WITH_WEB_TOP, TEE_FLANGE_EDGE_PAST_WEB_TOP,
    TEE_FLANGE_EDGE_READ_ALONG_ITSELF, TEE_ROOT_LONGEST_SEEN_RUN, TEE_ROOT_NOT_SEEN,
};

/// A root read from the flange's edge: each edge's sampling may move the
/// face the edges imply by a spacing, both towards a face seen; the face
/// must be turned towards the camera and the projector by more than this
/// many spacings over the web's height to tell it from a shadow's edge.
const EDGE_VIEW_SPACINGS: f64 = 4.0;

/// A station's edge sample belongs to the edge's line within this many
/// spacings (or `trim_sigma` residuals, if more).
const EDGE_TOLERANCE_SPACINGS: f64 = 1.5;

/// The fewest stations that make an edge line.
const MIN_EDGE_STATIONS: usize = 8;

/// Refits of an edge's line after trimming its outliers; the loop stops
/// sooner once the kept samples settle.
const EDGE_LINE_REFITS: usize = 4;

/// The root where the flange's edge meets the web, for a side whose face
/// is turned too nearly edge-on to return points.
///
/// Along the web, at each station, the innermost flange point on this side
/// and the outermost point of the web's top are read; a line is fitted to
/// each across its stations (trimmed). The flange's edge is the root only
/// if nothing hides the flange there: the face the two edges imply (from
/// the root up to the top's edge) must be turned towards the camera and
/// the projector. Where the flange instead ends at the edge of the web's
/// shadow (from the camera, or from the projector), that implied face
/// holds the ray that grazes the top's edge, so it is turned from the
/// shadowing eye by nothing; sampling moves each edge by up to a spacing,
/// both towards calling the face seen, so the margin must exceed
/// [`EDGE_VIEW_SPACINGS`] spacings over the web's height. A root turned
/// less than that is refused, not guessed.
pub(super) fn root_from_flange_edge(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, NotRead> {
    let root = flange_edge_root(view, frame, sign, side)?;
    // The web's axis from its top's spread lies off the web where the
    // image's border cuts the top obliquely: the edge, looked for outward
    // of the web's middle line along that axis, then runs into the
    // search's bound before the web ends. Read again along the edge's own
    // direction.
    let Web::Top(top) = view.web else {
        return Ok(root);
    };
    let along_edge = root.line.axes.e;
    if along_edge.dot(&frame.e).abs() >= MAX_AXIS_TURN_DEG.to_radians().cos() {
        return Ok(root);
    }
    match frame_along(view.cloud, top, frame, &along_edge) {
        Some(turned) => match flange_edge_root(view, &turned, sign, side) {
            Ok(mut along_itself) => {
                tracing::debug!(rule = TEE_FLANGE_EDGE_READ_ALONG_ITSELF.id, "the flange's edge read along itself");
                along_itself.ends_set_by.push(&TEE_FLANGE_EDGE_READ_ALONG_ITSELF);
                Ok(along_itself)
            }
            Err(_) => Ok(root),
        },
        None => Ok(root),
    }
}

/// How far, degrees, the flange's edge may run from the web's axis before
/// the edge is read again along its own direction: a degree moves the edge
/// by a spacing every 20 to 60 mm along a root (spacings of 0.3 to 1 mm).
const MAX_AXIS_TURN_DEG: f64 = 1.0;

/// The root from the flange's edge in the web's frame `frame`
/// ([`root_from_flange_edge`]).
fn flange_edge_root(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, NotRead> {
    let not_seen = |why: String| NotRead::by(&TEE_ROOT_NOT_SEEN, why);
    let Web::Top(web_top) = view.web else {
        return Err(not_seen("the web's top is out of view, so its edge cannot stand in for the face".into()));
    };
    let spacing = view.point_spacing_mm;
    let top_edge = frame.half_width + view.rim_mm;
    // A web leaning 45° puts its root a web height outward of its top.
    let outermost = top_edge + frame.height;
    let top_reach = top_edge + FACE_REACH_SPACINGS * spacing;
    let mut flange: Vec<EdgeSample> = Vec::new();
    let mut top: Vec<EdgeSample> = Vec::new();
    for p in valid_points(view.cloud) {
        let off = sign * (frame.across(&p) - frame.middle);
        if !(0.0..=outermost).contains(&off) {
            continue;
        }
        let (t, h) = ((p - frame.origin).dot(&frame.e), frame.height_of(&p));
        if h.abs() <= view.on_plane_mm {
            flange.push(EdgeSample { t, off, h });
        } else if off <= top_reach && web_top.plane.signed_distance(&p).abs() <= view.on_plane_mm {
            top.push(EdgeSample { t, off, h });
        }
    }
    let stations = Stations::over(flange.iter().chain(&top).map(|s| s.t), spacing)
        .ok_or_else(|| not_seen("no flange point lies beside the web".to_string()))?;
    let flange_edge = stations.extremes(&flange, |a, b| a.off < b.off);
    let top_edge_samples = stations.extremes(&top, |a, b| a.off > b.off);
    let tolerance = |rms: f64| (view.trim_sigma * rms).max(EDGE_TOLERANCE_SPACINGS * spacing);
    let root_line = EdgeLine::fit(&flange_edge, tolerance).ok_or_else(|| {
        not_seen(format!("the flange's edge is seen at {} stations along the web, too few", flange_edge.len()))
    })?;
    let top_line = EdgeLine::fit(&top_edge_samples, tolerance).ok_or_else(|| {
        not_seen(format!("the web top's edge is seen at {} stations along the web, too few", top_edge_samples.len()))
    })?;

    // The implied face across the middle of the root's stations.
    let t_mid = 0.5 * (root_line.t_range.0 + root_line.t_range.1);
    let lean = top_line.at(t_mid) - root_line.at(t_mid);
    let slant = lean.hypot(frame.height);
    let (n, e, outward) = (frame.n, frame.e, frame.u * sign);
    let root_at = |t: f64| frame.origin + e * t + frame.u * (frame.middle + sign * root_line.at(t)) + n * frame.height;
    let root_mid = root_at(t_mid);
    let m = ((outward * frame.height + n * lean) / slant).normalize();
    let turned_deg = |eye: Vec3| {
        let to_eye = eye - root_mid;
        (m.dot(&to_eye) / to_eye.norm()).clamp(-1.0, 1.0).asin().to_degrees()
    };
    let view_margin_deg = turned_deg(Vec3::zeros()).min(turned_deg(view.projector));
    let least_margin_deg = (EDGE_VIEW_SPACINGS * spacing / frame.height).atan().to_degrees();
    if view_margin_deg < least_margin_deg {
        return Err(NotRead::by(
            &TEE_FLANGE_EDGE_AT_SHADOW,
            format!(
                "the face from the flange's edge up to the web top's edge is turned {view_margin_deg:.1}° towards the \
             camera or the projector, below {least_margin_deg:.1}° ({EDGE_VIEW_SPACINGS} point spacings of \
             {spacing:.2} mm over the web's {:.0} mm): the flange may end at the web's shadow, not at the root",
                frame.height
            ),
        ));
    }

    // The root line and its frame: `r` along it, `w` outward in the flange.
    let p0 = root_at(0.0);
    let r = (root_at(1.0) - p0).normalize();
    let w = {
        let w = r.cross(&n);
        if w.dot(&outward) >= 0.0 { w } else { -w }
    };
    let stretch = (root_at(1.0) - p0).norm();
    let along = |t: f64| t * stretch;
    // The evidence of the root: every flange point at the edge's line (not
    // only each station's innermost, whose place along a station would
    // round the root's ends off by up to a station), in the stations whose
    // innermost point lies on the line (where the flange runs on under the
    // web, past its end, a station's innermost point leaves the line) and
    // the stations next to them. The station holding the web's end holds
    // the flange past it too, so its innermost point leaves the line; its
    // points at the line still show the root up to the web's end, and the
    // web top's extent (below) ends the root there, not a station short.
    let at_edge = tolerance(root_line.rms_mm);
    let on_line: HashSet<usize> = root_line.kept.iter().map(|s| stations.index(s.t)).collect();
    let beside_line =
        |k: usize| [k.checked_sub(1), Some(k), k.checked_add(1)].into_iter().flatten().any(|j| on_line.contains(&j));
    let edge: Vec<f64> = flange
        .iter()
        .filter(|s| (s.off - root_line.at(s.t)).abs() <= at_edge && beside_line(stations.index(s.t)))
        .map(|s| along(s.t))
        .collect();
    // The root runs where the flange's edge does: the web's top, nearer
    // the camera, may leave the image before the root does; it need only
    // be seen above enough of the root to be judged by the coverage gate.
    let run = seen_run(&edge, &edge, spacing)
        .ok_or_else(|| not_seen("the flange's edge is not seen along the web anywhere".to_string()))?;
    // Only where the web stands: past the web's end the flange's edge runs
    // on nearly straight (the web's end hides the flange behind it a little
    // more at each step), so the root ends where the web's top does, unless
    // the image's border cut the top there (the top, nearer the camera,
    // leaves the image before the root does); with no grid to tell, it
    // ends there too.
    // The top's edge from every point at its line, like the flange's
    // evidence above: a station's outermost point would round its extent
    // off, and, one to a station at a place of its own along it, would
    // leave every third or so of the coverage gate's stations empty.
    let top_on_line: HashSet<usize> = top_line.kept.iter().map(|s| stations.index(s.t)).collect();
    let top_at_line: Vec<f64> = top
        .iter()
        .filter(|s| {
            (s.off - top_line.at(s.t)).abs() <= tolerance(top_line.rms_mm) && top_on_line.contains(&stations.index(s.t))
        })
        .map(|s| s.t)
        .collect();
    let (top_lo, top_hi) = extent(top_at_line.iter().copied());
    let top_at = |t: f64| frame.origin + e * t + frame.u * (frame.middle + sign * top_line.at(t));
    let step = STATION_SPACINGS * spacing / stretch;
    // Past the top's end: off the configured camera's grid, or where no
    // ray of the cloud reaches (within the sampling's reach of its border).
    let reach = BORDER_REACH_SPACINGS * spacing;
    let cut_by_border = |t: f64| match (view.in_view, view.border) {
        (Some(in_view), _) => !in_view(&top_at(t)),
        (None, Some(border)) => border.outside_mm(&top_at(t)) > -reach,
        (None, None) => false,
    };
    let s0 = if cut_by_border(top_lo - step) { run.s0 } else { run.s0.max(along(top_lo)) };
    let s1 = if cut_by_border(top_hi + step) { run.s1 } else { run.s1.min(along(top_hi)) };
    if view.in_view.is_none() && view.border.is_none() {
        let past = (s0 - run.s0).max(run.s1 - s1);
        if past > view.max_beyond_mm {
            return Err(NotRead::by(
                &TEE_FLANGE_EDGE_PAST_WEB_TOP,
                format!(
                    "the flange's edge runs on {past:.1} mm past where the web's top is seen, more than {:.1} mm \
                 (quality.max_joint_beyond_seam_mm): the web may end there, or the image cut its top (neither \
                 the camera's grid nor the cloud's rays show where the image ends)",
                    view.max_beyond_mm
                ),
            ));
        }
    }
    if s1 <= s0 {
        return Err(not_seen("the flange's edge is not seen where the web's top is".to_string()));
    }
    let mut ends_set_by: Vec<&'static Rule> = Vec::new();
    if run.cut {
        ends_set_by.push(&TEE_ROOT_LONGEST_SEEN_RUN);
    }
    if (s0, s1) != (run.s0, run.s1) {
        ends_set_by.push(&TEE_FLANGE_EDGE_ENDS_WITH_WEB_TOP);
    }
    let run = SeenRun { s0, s1, share: ((s1 - s0) / run.seen_mm).min(1.0), ..run };
    let top_seen: Vec<f64> = top_at_line.iter().map(|&t| along(t)).collect();
    let coverage = [covered_share(&top_seen, run.s0, run.s1, spacing), run.coverage[1]];
    let web_angle_deg = frame.height.atan2(lean).to_degrees();

    // The flange beside the root, over the run.
    let flange_reach = FLANGE_REACH_SPACINGS * spacing;
    let beside: Vec<f64> = flange
        .iter()
        .filter(|s| {
            let out = s.off - root_line.at(s.t);
            (0.0..=flange_reach).contains(&out) && (run.s0..=run.s1).contains(&along(s.t))
        })
        .map(|s| s.h)
        .collect();
    // Whether the root is straight: the flange's edge across it and the
    // flange beside it along the normal, station by station over the run.
    let bend = RootBend::worse(
        bend_of(
            root_line
                .kept
                .iter()
                .filter(|s| (run.s0..=run.s1).contains(&along(s.t)))
                .map(|s| (along(s.t), s.off - root_line.at(s.t))),
            Samples::PerStation,
            spacing,
            "the flange's edge against the web",
        ),
        bend_of(
            flange
                .iter()
                .filter(|s| {
                    let out = s.off - root_line.at(s.t);
                    (0.0..=flange_reach).contains(&out) && (run.s0..=run.s1).contains(&along(s.t))
                })
                .map(|s| (along(s.t), s.h)),
            Samples::Points,
            spacing,
            "the flange",
        ),
    );
    let floor = spacing / 12f64.sqrt();
    let in_run = root_line.kept.iter().filter(|s| (run.s0..=run.s1).contains(&along(s.t))).count().max(1);
    Ok(Root {
        side,
        evidence: RootEvidence::FlangeEdge { view_margin_deg, least_margin_deg },
        sign,
        line: SeamCurve {
            axes: SeamAxes { origin: p0, e: r, a: w, b: n },
            coef_a: vec![0.0, 0.0],
            coef_b: vec![0.0, 0.0],
            s_min: run.s0,
            s_max: run.s1,
        },
        face: Plane { normal: m, offset: m.dot(&root_mid) },
        face_rms_mm: root_line.rms_mm,
        face_points: root_line.kept.len(),
        face_dropped: root_line.dropped,
        flange: Plane { normal: n, offset: frame.flange_offset },
        flange_rms_mm: rms(beside.iter().copied()),
        flange_points: beside.len(),
        web_angle_deg,
        web_height_mm: frame.height,
        coverage,
        seen_share: run.share,
        seen_mm: run.seen_mm,
        // Clipped to where the web's top is seen, above.
        joint_beyond_ends_mm: None,
        // The edge's line across its stations, and the sampling: the root
        // lies within a spacing inward of the flange's last point.
        uncertainty_across_mm: (root_line.rms_mm / (in_run as f64).sqrt()).hypot(floor),
        uncertainty_normal_mm: floor,
        bend,
        ends_set_by,
    })
}

/// A point beside the web: along it from the web top's centroid, outward
/// from the web's middle, and its height over the flange, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
struct EdgeSample {
    t: f64,
    off: f64,
    h: f64,
}

/// Stations along the web, [`STATION_SPACINGS`] long (at most
/// [`MAX_STATIONS`] of them).
struct Stations {
    start: f64,
    width: f64,
    count: usize,
}

impl Stations {
    fn over(ts: impl Iterator<Item = f64>, spacing: f64) -> Option<Stations> {
        let (lo, hi) = extent(ts);
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let width = (STATION_SPACINGS * spacing).max((hi - lo) / MAX_STATIONS as f64).max(f64::MIN_POSITIVE);
        let count = (((hi - lo) / width).floor() as usize + 1).min(MAX_STATIONS);
        Some(Stations { start: lo, width, count })
    }

    fn index(&self, t: f64) -> usize {
        (((t - self.start) / self.width).floor().max(0.0) as usize).min(self.count - 1)
    }

    /// Each station's sample that `beyond` puts first: the innermost of the
    /// flange, the outermost of the web's top.
    fn extremes(&self, samples: &[EdgeSample], beyond: impl Fn(&EdgeSample, &EdgeSample) -> bool) -> Vec<EdgeSample> {
        let mut best: Vec<Option<EdgeSample>> = vec![None; self.count];
        for s in samples {
            let k = self.index(s.t);
            if best[k].is_none_or(|b| beyond(s, &b)) {
                best[k] = Some(*s);
            }
        }
        best.into_iter().flatten().collect()
    }
}

/// A straight edge across its stations, `off = a + b·t`: least squares,
/// started from the median offset and refitted without the stations
/// further than `tolerance(rms)` from it (a dropout that cuts the flange
/// short, or the flange running on past the web's end).
#[derive(Debug, Clone, PartialEq)]
struct EdgeLine {
    a: f64,
    b: f64,
    rms_mm: f64,
    kept: Vec<EdgeSample>,
    dropped: usize,
    t_range: (f64, f64),
}

impl EdgeLine {
    fn at(&self, t: f64) -> f64 {
        self.a + self.b * t
    }

    fn fit(samples: &[EdgeSample], tolerance: impl Fn(f64) -> f64) -> Option<EdgeLine> {
        if samples.len() < MIN_EDGE_STATIONS {
            return None;
        }
        let mut offs: Vec<f64> = samples.iter().map(|s| s.off).collect();
        offs.sort_by(f64::total_cmp);
        let mut line = EdgeLine {
            a: offs[offs.len() / 2],
            b: 0.0,
            rms_mm: 0.0,
            kept: Vec::new(),
            dropped: 0,
            t_range: (0.0, 0.0),
        };
        for _ in 0..=EDGE_LINE_REFITS {
            let limit = tolerance(line.rms_mm);
            let kept: Vec<EdgeSample> =
                samples.iter().filter(|s| (s.off - line.at(s.t)).abs() <= limit).copied().collect();
            if kept.len() < MIN_EDGE_STATIONS {
                return None;
            }
            let n = kept.len() as f64;
            let (mt, mo) = (kept.iter().map(|s| s.t).sum::<f64>() / n, kept.iter().map(|s| s.off).sum::<f64>() / n);
            let (stt, sto) =
                kept.iter().fold((0.0, 0.0), |(tt, to), s| (tt + (s.t - mt).powi(2), to + (s.t - mt) * (s.off - mo)));
            let b = if stt > 0.0 { sto / stt } else { 0.0 };
            let settled = kept == line.kept;
            line = EdgeLine {
                a: mo - b * mt,
                b,
                rms_mm: 0.0,
                t_range: extent(kept.iter().map(|s| s.t)),
                dropped: samples.len() - kept.len(),
                kept,
            };
            line.rms_mm = rms(line.kept.iter().map(|s| s.off - line.at(s.t)));
            if settled {
                break;
            }
        }
        Some(line)
    }
}
