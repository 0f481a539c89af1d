//! A root from the web's side face: the points between the flange and the
//! web's top on one side of the web, fitted to a plane (outliers trimmed),
//! checked to be a side face seen (its foot along the web, turned towards
//! the camera), met with the flange, and the stretch along the root where
//! the face's foot and the flange up to it are both seen; with the face
//! fit's prediction error at the root's ends as its uncertainty.

use std::collections::HashMap;

use crate::geometry::fit::{Moments, Plane};
use crate::geometry::{MAD_PER_SIGMA, Vec3, vec3};

use super::super::refit::{SeamAxes, SeamCurve};
use super::super::straightness::{RootBend, Samples, bend_of};
use super::flange_at_root::HeightLine;
use super::frame::{WebFrame, height_margin, valid_points};
use super::stretch::{STATION_SPACINGS, ends_at_border, ends_past_cut_foot, joint_beyond_run, seen_run};
use super::{MIN_FACE_POINTS, NotRead, Root, RootEvidence, Side, TeeView, Web};
use crate::rules::Rule;
use crate::rules::refit::{
    TEE_ROOT_ENDS_AT_IMAGE_BORDER, TEE_ROOT_LONGEST_SEEN_RUN, TEE_ROOT_NOT_SEEN, TEE_ROOT_RUNS_PAST_CUT_FOOT,
    TEE_SIDE_FACE_ALONG_CAMERA_RAYS, TEE_SIDE_FACE_IS_WEB_END,
};

/// The face's foot: its points up to this many spacings above the lowest
/// face point of their station along the root.
const FOOT_BAND_SPACINGS: f64 = 10.0;

/// The flange seen up to the root: a flange point within this many
/// spacings outward of the root line.
pub(super) const FLANGE_REACH_SPACINGS: f64 = 6.0;

/// The least angle, degrees, between a face and the camera's ray to it: a
/// face turned further from the camera is not seen at all (or only as
/// noise), and points lying along the rays are the mixed returns a depth
/// jump leaves at the web's edge (a veil from its top down to whatever
/// lies behind), not a face.
pub const MIN_FACE_VIEW_DEG: f64 = 5.0;

/// The most a face's foot may turn from the web top's long axis, degrees,
/// and still be the web's side face. A side face runs along the top
/// (square or leaning, the two share the web's length); the web's end
/// face stands at 90° to it. The top's long axis, from the spread of a
/// top many times longer than wide, is good to a degree or two.
const MAX_ROOT_SKEW_DEG: f64 = 20.0;

/// Rounds of a trimmed fit's trimming at most ([`trimmed_fit`]): a face's
/// or a flange's kept set settles in a few.
const TRIM_ROUNDS: usize = 8;

/// The floor of a face's trimming limit, mm: a near-perfect fit does not
/// trim honest points.
const MIN_FACE_TRIM_MM: f64 = 0.05;

/// The root where the web's side face, fitted to its points, meets the
/// flange, or why the face gives none.
pub(super) fn root_from_face(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, NotRead> {
    let spacing = view.point_spacing_mm;
    // The flange's own scatter sets both which points are the flange
    // beside the root and where the face's points begin: a flange that
    // strays past the on-plane tolerance has points standing that high
    // over its plane, and taken for the face's they would make a foot
    // where no face stands (on the bare flange past a web's end).
    let on_flange = frame.on_flange_mm(view.on_plane_mm);
    let margin = height_margin(on_flange, spacing);
    let ((inner, reach), h_hi) = frame.face_band(view, sign, margin);
    let face_points: Vec<Vec3> = valid_points(view.cloud)
        .filter(|p| {
            let h = frame.height_of(p);
            let off = sign * (frame.across(p) - frame.middle);
            (margin..=h_hi).contains(&h) && (inner..=reach).contains(&off)
        })
        .collect();
    let hidden = if side == Side::Far { ", hidden by the web" } else { "" };
    if face_points.len() < MIN_FACE_POINTS {
        return Err(NotRead::by(
            &TEE_ROOT_NOT_SEEN,
            format!(
                "the web's side face there is not seen{hidden} ({} points between the flange and the web's top, \
             fewer than {MIN_FACE_POINTS})",
                face_points.len()
            ),
        ));
    }
    let Some(face) = fit_face(&face_points, view.trim_sigma) else {
        return Err(NotRead::by(&TEE_ROOT_NOT_SEEN, "the points on the web's side face span no plane"));
    };
    // A side face runs the web's length. Where the side face is turned
    // edge-on and returns nothing, the points between the flange and the
    // web's top on this side can be the web's end face, standing across
    // the web: its "root" would be a few millimetres of the web's
    // thickness. (A face lying parallel to the flange is refused below.)
    let foot_line = frame.n.cross(&face.plane.normal).try_normalize(1e-6);
    if let (None, Some(foot_line)) = (frame.face_only, foot_line) {
        let skew_deg = foot_line.dot(&frame.e).abs().clamp(0.0, 1.0).acos().to_degrees();
        if skew_deg > MAX_ROOT_SKEW_DEG {
            return Err(NotRead::by(
                &TEE_SIDE_FACE_IS_WEB_END,
                format!(
                    "the {} points between the flange and the web's top stand across the web (their foot \
                 {skew_deg:.0}° from the top's long axis, over {MAX_ROOT_SKEW_DEG}°): the web's end, not its \
                 side face{hidden}",
                    face.inliers.len()
                ),
            ));
        }
    }
    // The face's normal out of the web, towards this side.
    let m = if face.plane.normal.dot(&frame.u) * sign >= 0.0 { face.plane.normal } else { -face.plane.normal };
    let d_m = m.dot(&face.centroid);
    let view_deg = m.dot(&(-face.centroid).normalize()).clamp(-1.0, 1.0).asin().to_degrees();
    if view_deg < MIN_FACE_VIEW_DEG {
        return Err(NotRead::by(
            &TEE_SIDE_FACE_ALONG_CAMERA_RAYS,
            format!(
                "the {} points between the flange and the web's top lie along the camera's rays ({view_deg:.1}° from \
             them, below {MIN_FACE_VIEW_DEG}°): mixed returns at the web's edge, not its side face{hidden}",
                face.inliers.len()
            ),
        ));
    }
    let face_plane = Plane { normal: m, offset: d_m };
    let whole_flange = Plane { normal: frame.n, offset: frame.flange_offset };
    let parallel = || {
        NotRead::by(&TEE_ROOT_NOT_SEEN, "the points between the flange and the web's top lie parallel to the flange")
    };
    // The root on the whole flange's plane first, then on the flange's
    // plane where the face stands on it (`super::flange_at_root`).
    let first = Meeting::of(&whole_flange, &face_plane, frame).ok_or_else(parallel)?;
    // The flange beside the root, seen as evidence of it: outward of the
    // face's own foot (which lies at the flange's height too, where the
    // web overhangs the flange's end) by the same margin that keeps the
    // flange out of the face, and a few spacings on.
    let flange_reach = margin + FLANGE_REACH_SPACINGS * spacing;
    // Its height is read as far on, past the face's own scatter across its
    // plane too (its inlier band, `trim_sigma` of its RMS): within it the
    // face's lowest points lie at the flange's height and over it, and a
    // depth camera blends the two surfaces into the inside corner. Read
    // there, pc0002's beam top stood 1 mm high all along its second root.
    let height_from = margin + view.trim_sigma * face.rms_mm;
    let height_band = (height_from, height_from + FLANGE_REACH_SPACINGS * spacing);
    let local = flange_beside(view, frame, &first, &face.inliers, height_band, on_flange);
    let flange_plane = local.map_or(whole_flange, |line| line.plane(&whole_flange, &first.p0, &first.r));
    let Meeting { r, p0, w } = Meeting::of(&flange_plane, &face_plane, frame).ok_or_else(parallel)?;
    let n = flange_plane.normal;
    // Up the face from the root.
    let up = {
        let v = r.cross(&m);
        if v.dot(&n) <= 0.0 { v } else { -v }
    };
    let web_angle_deg = up.dot(&w).clamp(-1.0, 1.0).acos().to_degrees();

    // The evidence along the root: the face's foot and the flange up to it.
    let along = |p: &Vec3| (p - p0).dot(&r);
    let foot_points = station_feet(&face.inliers, along, |p| frame.height_of(p), spacing);
    let foot: Vec<f64> = foot_points.iter().map(along).collect();
    // And the flange seen under where the web stands, inward of the root:
    // past the web's end.
    let web_width = 2.0 * frame.half_width;
    let mut beside: Vec<Vec3> = Vec::new();
    let mut under_web: Vec<f64> = Vec::new();
    for p in valid_points(view.cloud).filter(|p| flange_plane.signed_distance(p).abs() <= on_flange) {
        let out = (p - p0).dot(&w);
        if (margin..=flange_reach).contains(&out) {
            beside.push(p);
        } else if (-web_width..=-margin).contains(&out) {
            under_web.push(along(&p));
        }
    }
    if foot.is_empty() {
        return Err(NotRead::by(&TEE_ROOT_NOT_SEEN, "the web's side face is not seen down to the flange"));
    }
    if beside.is_empty() {
        return Err(NotRead::by(
            &TEE_ROOT_NOT_SEEN,
            format!(
                "the flange is not seen up to the web's face{}",
                if side == Side::Far { " (the web hides it)" } else { " (in the web's shadow)" }
            ),
        ));
    }
    let flange_along: Vec<f64> = beside.iter().map(along).collect();
    let Some(run) = seen_run(&foot, &flange_along, spacing) else {
        return Err(NotRead::by(
            &TEE_ROOT_NOT_SEEN,
            "the web's face and the flange up to it are not seen together anywhere along the root",
        ));
    };
    let mut ends_set_by: Vec<&'static Rule> = Vec::new();
    if run.cut {
        ends_set_by.push(&TEE_ROOT_LONGEST_SEEN_RUN);
    }
    let evidence_ends = (run.s0, run.s1);
    let run = match view.border {
        Some(border) => ends_at_border(border, &p0, &r, run, [&foot_points, &beside], spacing),
        None => run,
    };
    if (run.s0, run.s1) != evidence_ends {
        ends_set_by.push(&TEE_ROOT_ENDS_AT_IMAGE_BORDER);
    }
    let border_ends = (run.s0, run.s1);
    let run = ends_past_cut_foot(view, &p0, &r, run, &foot_points, &beside, &under_web, spacing);
    if (run.s0, run.s1) != border_ends {
        ends_set_by.push(&TEE_ROOT_RUNS_PAST_CUT_FOOT);
    }
    // With the web's top out of view nothing tells which way the web runs
    // (the skew test above needs the top's long axis), and a web's end
    // face stands on the flange as its side face does, only as long as the
    // web is thick. A face whose root runs no longer than the thickest web
    // may be that end, its "root" across the web.
    let run_mm = run.s1 - run.s0;
    if frame.face_only.is_some() && run_mm <= view.web_thickness_max_mm {
        return Err(NotRead::by(
            &TEE_SIDE_FACE_IS_WEB_END,
            format!(
                "the face standing on the flange is seen along {run_mm:.1} mm of its root, no longer than the \
                 thickest web ({:.0} mm), and the web's top is out of view: it may be a web's end, standing across \
                 the web{hidden}",
                view.web_thickness_max_mm
            ),
        ));
    }
    // Where the web's top stands over the root and the flange is seen up
    // to it beyond the stretch, the joint goes on though the face's foot
    // is not seen there (turned nearly edge-on, or covered): the quality
    // gate refuses a root stopping short of it.
    let joint_beyond_ends_mm = match view.web {
        Web::Top(top) => {
            let points = view.cloud.points();
            let top_along: Vec<f64> = top.members.iter().map(|&i| along(&vec3(&points[i as usize]))).collect();
            Some(joint_beyond_run(&top_along, &flange_along, (run.s0, run.s1), spacing))
        }
        Web::Face(_) => None,
    };
    // The flange near the root: its points beside the run, against its
    // plane there.
    let near_flange: Vec<&Vec3> = beside.iter().filter(|p| (run.s0..=run.s1).contains(&along(p))).collect();
    let flange_rms_mm = rms(near_flange.iter().map(|p| flange_plane.signed_distance(p)));

    // The face fit's prediction error at the root's ends (h = 0).
    let stats = FaceSpread::of(&face.inliers, |p| frame.height_of(p), along);
    let floor = spacing / 12f64.sqrt();
    let at_end = |t: f64| {
        let n = face.inliers.len() as f64;
        let lever = 1.0 / n + stats.mean_h.powi(2) / (n * stats.var_h) + (t - stats.mean_t).powi(2) / (n * stats.var_t);
        face.rms_mm * lever.sqrt()
    };
    let face_sigma = at_end(run.s0).max(at_end(run.s1));
    // The flange's height at the root's ends, read from its points beside
    // the root (nil where the whole flange's plane, of thousands of
    // points, is kept).
    let flange_sigma = local.map_or(0.0, |line| {
        let t = |s: f64| (p0 + r * s - first.p0).dot(&first.r);
        line.sigma_at(t(run.s0)).max(line.sigma_at(t(run.s1)))
    });
    // Across: the face's offset error, seen through the web's angle to the
    // flange; along the normal: the flange's height at the root's ends
    // and the face's share where the web is not square.
    let sin = web_angle_deg.to_radians().sin().max(0.1);
    let cos = web_angle_deg.to_radians().cos().abs();
    let uncertainty_across_mm = (face_sigma / sin).hypot(flange_sigma * cos / sin).hypot(floor);
    let uncertainty_normal_mm = (face_sigma * cos / sin).hypot(flange_sigma).hypot(floor);

    // Whether the root is straight: the face's foot across it and the
    // flange beside it along the normal, station by station over the run.
    let in_run = |p: &&Vec3| (run.s0..=run.s1).contains(&along(p));
    let bend = RootBend::worse(
        bend_of(
            foot_points.iter().filter(in_run).map(|p| (along(p), m.dot(p) - d_m)),
            Samples::Points,
            spacing,
            "the web's face",
        ),
        bend_of(
            near_flange.iter().map(|p| (along(p), flange_plane.signed_distance(p))),
            Samples::Points,
            spacing,
            "the flange",
        ),
    );

    let line = SeamCurve {
        axes: SeamAxes { origin: p0, e: r, a: w, b: n },
        coef_a: vec![0.0, 0.0],
        coef_b: vec![0.0, 0.0],
        s_min: run.s0,
        s_max: run.s1,
    };
    Ok(Root {
        side,
        evidence: RootEvidence::Face,
        sign,
        line,
        face: Plane { normal: m, offset: d_m },
        face_rms_mm: face.rms_mm,
        face_points: face.inliers.len(),
        face_dropped: face.dropped,
        flange: flange_plane,
        flange_rms_mm,
        flange_points: near_flange.len(),
        web_angle_deg,
        web_height_mm: frame.height,
        coverage: run.coverage,
        seen_share: run.share,
        seen_mm: run.seen_mm,
        joint_beyond_ends_mm,
        uncertainty_across_mm,
        uncertainty_normal_mm,
        bend,
        ends_set_by,
    })
}

/// Where the face meets a flange's plane: the root's direction `r` (along
/// the web), its point `p0` nearest the web's origin, and `w`, across the
/// root in the flange away from the web.
struct Meeting {
    r: Vec3,
    p0: Vec3,
    w: Vec3,
}

impl Meeting {
    /// `None` where the face lies parallel to the flange.
    fn of(flange: &Plane, face: &Plane, frame: &WebFrame) -> Option<Meeting> {
        let (n, m) = (flange.normal, face.normal);
        let r = n.cross(&m).try_normalize(1e-6)?;
        let r = if r.dot(&frame.e) >= 0.0 { r } else { -r };
        // The point on both planes nearest the web's origin (a 2 × 2 solve
        // in the span of n and m).
        let o = frame.origin;
        let nm = n.dot(&m);
        let det = 1.0 - nm * nm;
        let (rn, rm) = (flange.offset - n.dot(&o), face.offset - m.dot(&o));
        let p0 = o + n * ((rn - nm * rm) / det) + m * ((rm - nm * rn) / det);
        let w = r.cross(&n);
        let w = if w.dot(&m) >= 0.0 { w } else { -w };
        Some(Meeting { r, p0, w })
    }
}

/// The flange's height along the root where the face stands on it
/// ([`super::flange_at_root`]): its points `band` (mm, from, to) outward of the
/// root `at` on the whole flange's plane, within `on_flange` of that
/// plane, along the face's length (its `inliers`); `None` with fewer than
/// [`MIN_FACE_POINTS`] of them, the whole flange's plane then kept.
fn flange_beside(
    view: &TeeView,
    frame: &WebFrame,
    at: &Meeting,
    inliers: &[Vec3],
    band: (f64, f64),
    on_flange: f64,
) -> Option<HeightLine> {
    let along = |p: &Vec3| (p - at.p0).dot(&at.r);
    let (t0, t1) =
        inliers.iter().map(along).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| (lo.min(t), hi.max(t)));
    let samples: Vec<(f64, f64)> = valid_points(view.cloud)
        .filter_map(|p| {
            let h = frame.height_of(&p);
            let (out, t) = ((p - at.p0).dot(&at.w), along(&p));
            (h.abs() <= on_flange && (band.0..=band.1).contains(&out) && (t0..=t1).contains(&t)).then_some((t, h))
        })
        .collect();
    HeightLine::fit(&samples, view.trim_sigma, MIN_FACE_TRIM_MM, MIN_FACE_POINTS)
}

/// A plane fitted to a face's points, refitted without its outliers.
#[derive(Debug, Clone)]
pub(in crate::pipeline) struct FaceFit {
    pub plane: Plane,
    pub centroid: Vec3,
    pub inliers: Vec<Vec3>,
    pub rms_mm: f64,
    pub dropped: usize,
}

/// Least squares (the scatter's least axis), then refits without the
/// points further than `trim_sigma` standard deviations from the plane,
/// until the kept set stops changing (at most [`TRIM_ROUNDS`]).
///
/// The residual scale is the median distance of all the points from the
/// plane, as a standard deviation ([`MAD_PER_SIGMA`]), as the weld edges'
/// fits take it ([`crate::pipeline::refit::fit_trimmed`]): the band a face
/// is read from also holds what stands beside it (a tube's rounded
/// corners curving away, other parts crossing the band past the face's
/// ends). Their distances inflate an RMS, so a limit of a few RMS keeps
/// most of them round after round: a tenth of a band in such clutter
/// turns the plane by tenths of a degree, a root 150 mm long by most of a
/// millimetre at one end. The median moves with clutter only in
/// proportion to its share.
pub(in crate::pipeline) fn fit_face(points: &[Vec3], trim_sigma: f64) -> Option<FaceFit> {
    let fit_of = |kept: Vec<Vec3>| -> Option<FaceFit> {
        let moments: Moments = kept.iter().collect();
        let plane = moments.plane()?;
        let centroid = moments.centroid()?;
        let rms_mm = rms(kept.iter().map(|p| plane.signed_distance(p)));
        Some(FaceFit { plane, centroid, dropped: points.len() - kept.len(), inliers: kept, rms_mm })
    };
    trimmed_fit(points, (trim_sigma, MIN_FACE_TRIM_MM), MIN_FACE_POINTS, fit_of, |fit, p| {
        fit.plane.signed_distance(p).abs()
    })
}

/// `fit` over all `samples`, then again without those further from the
/// last fit (`distance`) than `trim.0` standard deviations of the median
/// distance ([`MAD_PER_SIGMA`]) and never tighter than `trim.1` mm, until
/// the kept set stops changing (at most [`TRIM_ROUNDS`]); the last fit holding
/// at least `min_kept` samples. `None` where the first fit fails.
pub(super) fn trimmed_fit<S: Copy, F>(
    samples: &[S],
    trim: (f64, f64),
    min_kept: usize,
    fit: impl Fn(Vec<S>) -> Option<F>,
    distance: impl Fn(&F, &S) -> f64,
) -> Option<F> {
    let mut last = fit(samples.to_vec())?;
    let mut kept_before: Option<Vec<bool>> = None;
    for _ in 0..TRIM_ROUNDS {
        let distances: Vec<f64> = samples.iter().map(|s| distance(&last, s)).collect();
        let mut sorted = distances.clone();
        let middle = sorted.len() / 2;
        let (_, median, _) = sorted.select_nth_unstable_by(middle, f64::total_cmp);
        let limit = (trim.0 * *median / MAD_PER_SIGMA).max(trim.1);
        let keep: Vec<bool> = distances.iter().map(|&d| d <= limit).collect();
        if kept_before.as_ref() == Some(&keep) {
            break;
        }
        let kept: Vec<S> = samples.iter().zip(&keep).filter(|(_, k)| **k).map(|(s, _)| *s).collect();
        if kept.len() < min_kept {
            break;
        }
        let Some(refit) = fit(kept) else { break };
        last = refit;
        kept_before = Some(keep);
    }
    Some(last)
}

/// The face points' spread in height and along the root.
struct FaceSpread {
    mean_h: f64,
    var_h: f64,
    mean_t: f64,
    var_t: f64,
}

impl FaceSpread {
    fn of(points: &[Vec3], height: impl Fn(&Vec3) -> f64, along: impl Fn(&Vec3) -> f64) -> FaceSpread {
        let n = points.len().max(1) as f64;
        let (hs, ts): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (height(p), along(p))).unzip();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
        let var = |v: &[f64], m: f64| (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).max(f64::MIN_POSITIVE);
        let (mean_h, mean_t) = (mean(&hs), mean(&ts));
        FaceSpread { mean_h, var_h: var(&hs, mean_h), mean_t, var_t: var(&ts, mean_t) }
    }
}

/// The face's foot at each station along the root (`along`, stations of
/// [`STATION_SPACINGS`]): the face points up to [`FOOT_BAND_SPACINGS`]
/// above the lowest face point of their own station. A face turned nearly
/// edge-on to the camera or the projector returns points only where it is
/// turned a little less, above a line slanting along the root (the angle
/// of incidence changes along it): under the face's single lowest point
/// the foot would hold part of the root only.
fn station_feet(
    points: &[Vec3],
    along: impl Fn(&Vec3) -> f64,
    height: impl Fn(&Vec3) -> f64,
    spacing: f64,
) -> Vec<Vec3> {
    let width = STATION_SPACINGS * spacing;
    let station = |p: &Vec3| (along(p) / width).floor() as i64;
    let mut lowest: HashMap<i64, f64> = HashMap::new();
    for p in points {
        let h = height(p);
        lowest.entry(station(p)).and_modify(|low| *low = low.min(h)).or_insert(h);
    }
    let band = FOOT_BAND_SPACINGS * spacing;
    points.iter().copied().filter(|p| lowest.get(&station(p)).is_some_and(|&low| height(p) <= low + band)).collect()
}

pub(super) fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}
