//! The boundary read on a pixel grid: each scan line walked outward
//! across the coarse edge while its pixels stay on the plate's plane, and
//! on past the coarse edge's ends to the plate's corners.
//!
//! Where the plate ends over a depth jump (a gap with the table seen
//! through it, a lap's upper plate over the lower one), a pixel whose
//! footprint straddles the edge returns a blend of both depths along its
//! own ray: a mixed pixel, off the plate and off the surface beyond. It
//! may be the plate's last pixel or the first one beyond, and nothing in
//! its depth says which, so the plate ends within it; two of them (both
//! pixels mixed) hold the edge between them. The rule "the plate ends
//! half a pixel past its last on-plane pixel" alone stops a pixel short
//! wherever the plate's own last pixel is mixed, which reads every gap
//! seen through too wide by about half a pixel on each side, and a
//! procedure's gap limit is crossed by that. The walk therefore steps
//! over a run of up to [`MAX_MIXED_PIXELS`] mixed pixels ([`Walker::mixed_run`])
//! and places the edge at the run's middle. A face beyond the edge (a
//! bevel, a wall) is no mixture: its pixels lie on the line through the
//! surface beyond, and the plate ends before them. Nor is the face that
//! joins the plate's edge to the surface beyond, where the camera sees it
//! (a lap's upper plate seen from its edge's side, a gap's wall turned
//! towards the camera): seen across one or two pixels it lies between
//! the two surfaces as a blend would, so the run is read only where that
//! face turns its back to the camera's rays and no pixel can lie on it.
//!
//! Near a corner whose end the scan lines cross obliquely, the last
//! lines walk out through the plate's end, short of the edge by up to
//! the band's width; [`turned_off_the_edge`] sets those samples apart by
//! the way the boundary runs through them.

use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, vec3};

use super::{Boundary, BoundaryParams, BoundarySample, CoarseEdge, ExtentRule};

struct Walker<'a> {
    cloud: &'a PointCloud,
    plane: &'a Plane,
    edge: &'a CoarseEdge,
    params: &'a BoundaryParams,
    /// Walk along columns (true) or rows, and in which sense.
    along_cols: bool,
    sense: isize,
}

/// The most pixels a mixed return spans at one edge: the plate's last
/// pixel and the first one beyond, each of whose footprints may straddle
/// the edge.
pub const MAX_MIXED_PIXELS: isize = 2;

/// A pixel in the plate's cross-section along a scan line: how far out
/// across the edge (`out`) and how far off the plate's plane (`height`),
/// mm.
#[derive(Debug, Clone, Copy)]
struct Profile {
    out: f64,
    height: f64,
}

impl Walker<'_> {
    fn index(&self, scanline: usize, k: isize) -> Option<usize> {
        let (w, h) = (self.cloud.width() as isize, self.cloud.height() as isize);
        let (col, row) = if self.along_cols { (k, scanline as isize) } else { (scanline as isize, k) };
        (col >= 0 && row >= 0 && col < w && row < h).then(|| (row * w + col) as usize)
    }

    fn outward_of(&self, p: &Vec3) -> f64 {
        (p - self.edge.point).dot(&self.edge.outward)
    }

    fn on_plate(&self, i: usize) -> Option<Vec3> {
        let p = self.cloud.points()[i];
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(&p);
        (self.plane.signed_distance(&v).abs() <= self.params.on_plane_mm
            && self.outward_of(&v).abs() <= self.params.band_mm)
            .then_some(v)
    }

    fn profile_at(&self, scanline: usize, k: isize) -> Option<Profile> {
        let p = self.cloud.points()[self.index(scanline, k)?];
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(&p);
        Some(Profile { out: self.outward_of(&v), height: self.plane.signed_distance(&v) })
    }

    /// How many pixels past `last` (the plate's last on-plane pixel, at
    /// `last_point`) are mixed returns: 0 where the next pixel is no
    /// mixture (a dropout, a face beyond, or the surface beyond itself). A
    /// run of `n` is mixed when the two pixels after it lie off the plate
    /// on one side of it and at least half the plate's pixel `step` apart
    /// across the edge (the surface beyond, seen rather than edge-on: a
    /// veil of mixed returns along one ray is no surface), and every pixel
    /// of the run lies between the plate and the line through those two,
    /// more than the on-plane tolerance from both: on neither surface, as
    /// a blend along a ray lies. The longest run that is mixed wins, so a
    /// second mixed pixel is not taken for the surface beyond. None is read
    /// where the camera sees the face joining the plate's edge to the
    /// surface beyond ([`Walker::joining_face_seen`]).
    fn mixed_run(&self, scanline: usize, last: isize, last_point: &Vec3, step: f64) -> isize {
        let tolerance = self.params.on_plane_mm;
        let at = |n: isize| self.profile_at(scanline, last + n * self.sense);
        (1..=MAX_MIXED_PIXELS)
            .rev()
            .find(|&n| {
                let (Some(b0), Some(b1)) = (at(n + 1), at(n + 2)) else { return false };
                let side = b0.height.signum();
                if b0.height.abs() <= tolerance
                    || b1.height * side <= tolerance
                    || b1.out - b0.out < step / 2.0
                    || self.joining_face_seen(last_point, side)
                {
                    return false;
                }
                let beyond = |out: f64| b0.height + (b1.height - b0.height) * (out - b0.out) / (b1.out - b0.out);
                (1..=n).all(|m| {
                    at(m).is_some_and(|p| {
                        let (height, surface) = (p.height * side, beyond(p.out) * side);
                        height > tolerance && height < surface - tolerance
                    })
                })
            })
            .unwrap_or(0)
    }

    /// Whether the camera (at the origin) sees the face that joins the
    /// plate's edge at `last` to a surface beyond on the `side` of the
    /// plate's plane (the sign of its signed distance). Behind the plate,
    /// that face is the plate's own, facing outward, seen where the ray
    /// runs inward; in front, it is the nearer surface's, facing back
    /// across the edge, seen where the ray runs outward.
    fn joining_face_seen(&self, last: &Vec3, side: f64) -> bool {
        let behind = side != self.plane.signed_distance(&Vec3::zeros()).signum();
        let ray_outward = last.dot(&self.edge.outward);
        if behind { ray_outward < 0.0 } else { ray_outward > 0.0 }
    }

    /// Walks outward from position `k` on `scanline` and returns the
    /// boundary sample, or `None` when the walk leaves the image or the
    /// band before the plate ends (no boundary there).
    fn walk(&self, scanline: usize, mut k: isize, mean_step: f64) -> Option<(isize, BoundarySample)> {
        let mut last = self.on_plate(self.index(scanline, k)?)?;
        let mut previous: Option<Vec3> = self.index(scanline, k - self.sense).and_then(|i| self.on_plate(i));
        loop {
            let next_k = k + self.sense;
            let next = self.index(scanline, next_k)?;
            match self.on_plate(next) {
                Some(v) => {
                    previous = Some(last);
                    last = v;
                    k = next_k;
                }
                None => {
                    let p = self.cloud.points()[next];
                    // Still on the plane but outside the band: no edge here.
                    if p[0].is_finite() && self.plane.signed_distance(&vec3(&p)).abs() <= self.params.on_plane_mm {
                        return None;
                    }
                    break;
                }
            }
        }
        let step =
            previous.map(|p| self.outward_of(&last) - self.outward_of(&p)).filter(|s| *s > 0.0).unwrap_or(mean_step);
        // The plate ends half a step past its last pixel, or within the
        // run of mixed pixels after it, at the run's middle.
        let steps_past_last = (self.mixed_run(scanline, k, &last, step) + 1) as f64 / 2.0;
        let position = self.plane.project(&last) + self.edge.outward * (step * steps_past_last);
        Some((k, BoundarySample { position, along: (position - self.edge.point).dot(&self.edge.direction) }))
    }
}

/// Samples the boundary of the plate whose member pixels are `members`
/// beside `edge`: all of them, or only those [`super::band_members`] keeps, which
/// give the same samples. Organized clouds only.
pub fn sample_boundary(
    cloud: &PointCloud,
    members: &[u32],
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
) -> Boundary {
    let points = cloud.points();
    let w = cloud.width();
    let near: Vec<usize> = members
        .iter()
        .map(|&i| i as usize)
        .filter(|&i| (vec3(&points[i]) - edge.point).dot(&edge.outward).abs() <= params.band_mm)
        .collect();
    if near.is_empty() {
        return Boundary::default();
    }
    // Walk along the image axis that crosses the edge most directly.
    let mean_axis_step = |dc: usize, dr: usize| -> f64 {
        let mut sum = 0.0;
        let mut n = 0usize;
        for &i in near.iter().step_by((near.len() / 500).max(1)) {
            let (col, row) = (i % w + dc, i / w + dr);
            if col < w && row < cloud.height() {
                let q = points[row * w + col];
                if q[0].is_finite() {
                    sum += (vec3(&q) - vec3(&points[i])).dot(&edge.outward);
                    n += 1;
                }
            }
        }
        if n == 0 { 0.0 } else { sum / n as f64 }
    };
    let (col_step, row_step) = (mean_axis_step(1, 0), mean_axis_step(0, 1));
    let along_cols = col_step.abs() >= row_step.abs();
    let axis_step = if along_cols { col_step } else { row_step };
    if axis_step == 0.0 {
        return Boundary::default();
    }
    let walker = Walker { cloud, plane, edge, params, along_cols, sense: if axis_step > 0.0 { 1 } else { -1 } };
    let mean_step = axis_step.abs();

    // The outermost member on each scan line starts that line's walk.
    let split = |i: usize| {
        if along_cols { (i / w, (i % w) as isize) } else { (i % w, (i / w) as isize) }
    };
    let mut start: std::collections::BTreeMap<usize, isize> = std::collections::BTreeMap::new();
    for &i in &near {
        let (line, k) = split(i);
        let entry = start.entry(line).or_insert(k);
        if (k - *entry) * walker.sense > 0 {
            *entry = k;
        }
    }
    let mut found: Vec<(usize, isize, BoundarySample)> = Vec::new();
    for (&line, &k) in &start {
        if let Some((end, s)) = walker.walk(line, k, mean_step) {
            found.push((line, end, s));
        }
    }
    extend_past_ends(&walker, &mut found, mean_step);
    found.sort_by_key(|(line, _, _)| *line);
    let line_spacing_mm = median_line_spacing(&found);
    let turned = turned_off_the_edge(&found, edge);
    let (mut samples, mut across_other_edge) = (Vec::new(), Vec::new());
    for ((_, _, sample), turned) in found.into_iter().zip(turned) {
        if turned { across_other_edge.push(sample) } else { samples.push(sample) }
    }
    Boundary { samples, across_other_edge, line_spacing_mm, extent_rule: ExtentRule::AllSamples }
}

/// How many sampled lines away, each side, a sample's neighbours are
/// that tell which way the boundary runs through it.
pub const TURN_LINES: usize = 2;

/// Which samples' walks left the plate across another of its edges than
/// the one sampled. Where the scan lines cross a plate's end obliquely,
/// the last lines before the corner walk out through the end, up to the
/// band's width short of the edge, and their samples run along the end,
/// across the coarse edge, more than along it. A sample is taken off
/// the edge when the boundary turns more than 45° from the coarse edge on
/// both sides of it, [`TURN_LINES`] sampled lines away (on the one side
/// there is at the samples' ends): a run of walks through a plate's end,
/// and a lone walk cut short (a dropout on its line), which the fit would
/// trim; a sample beside a lone short one turns on one side only and
/// stays. `found` is sorted by line.
fn turned_off_the_edge(found: &[(usize, isize, BoundarySample)], edge: &CoarseEdge) -> Vec<bool> {
    let turns = |a: usize, b: usize| {
        let d = found[b].2.position - found[a].2.position;
        d.dot(&edge.outward).abs() > d.dot(&edge.direction).abs()
    };
    let n = found.len();
    (0..n)
        .map(|i| {
            let before = i.checked_sub(TURN_LINES).map(|a| turns(a, i));
            let after = (i + TURN_LINES < n).then(|| turns(i, i + TURN_LINES));
            match (before, after) {
                (Some(b), Some(a)) => b && a,
                (Some(one), None) | (None, Some(one)) => one,
                (None, None) => false,
            }
        })
        .collect()
}

/// The median distance along the edge from one scan line's sample to the
/// next line's, per line. `found` is sorted by line.
fn median_line_spacing(found: &[(usize, isize, BoundarySample)]) -> f64 {
    let mut steps: Vec<f64> = found
        .windows(2)
        .filter(|w| w[1].0 > w[0].0)
        .map(|w| (w[1].2.along - w[0].2.along).abs() / (w[1].0 - w[0].0) as f64)
        .collect();
    if steps.is_empty() {
        return 0.0;
    }
    let mid = steps.len() / 2;
    *steps.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Continues sampling on the scan lines beyond the first and last sampled
/// ones, each walk starting a few pixels inside the previous line's
/// boundary pixel, for as long as the plate is there. The plane criterion
/// trims about R off a plate's corners, so without this the seam would
/// stop short of the plate ends. `found` holds (line, boundary pixel,
/// sample).
fn extend_past_ends(walker: &Walker, found: &mut Vec<(usize, isize, BoundarySample)>, mean_step: f64) {
    if found.is_empty() {
        return;
    }
    found.sort_by_key(|(line, _, _)| *line);
    let lines = if walker.along_cols { walker.cloud.height() } else { walker.cloud.width() };
    // Both ends are fixed before extending: extension appends to `found`.
    let ends =
        [(-1isize, found[0].0 as isize, found[0].1), (1, found[found.len() - 1].0 as isize, found[found.len() - 1].1)];
    const MAX_EXTENSION_LINES: usize = 40;
    for (direction, mut line, mut boundary) in ends {
        for _ in 0..MAX_EXTENSION_LINES {
            line += direction;
            if line < 0 || line as usize >= lines {
                break;
            }
            let walked =
                (1..8).find_map(|inset| walker.walk(line as usize, boundary - inset * walker.sense, mean_step));
            match walked {
                Some((end, s)) => {
                    found.push((line as usize, end, s));
                    boundary = end;
                }
                None => break,
            }
        }
    }
}
