//! Iterative RANSAC line segmentation of edge points (section 3.4.2,
//! Fig. 13): find the best-supported 3D line, remove its inliers, repeat
//! until too few points remain or a line has too little support.
//!
//! The generator is seeded, so the same frame always gives the same lines.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use crate::geometry::Vec3;
use crate::geometry::fit::Moments;
use crate::kernels;

/// A segmented edge line: a point on it, its unit direction and the
/// indices (into the input slice) of its inliers.
#[derive(Debug, Clone)]
pub struct EdgeLine {
    pub point: Vec3,
    pub direction: Vec3,
    pub inliers: Vec<usize>,
}

impl EdgeLine {
    /// Distance from `p` to the infinite line.
    pub fn distance(&self, p: &Vec3) -> f64 {
        (p - self.point).cross(&self.direction).norm()
    }
}

/// Settings of the iterative segmentation.
#[derive(Debug, Clone, Copy)]
pub struct RansacParams {
    pub distance_mm: f64,
    pub iterations: u32,
    pub min_line_points: usize,
    pub min_remaining_points: usize,
    pub max_lines: usize,
    pub seed: u64,
}

/// Segments `points` into lines, best supported first.
pub fn segment_lines(points: &[Vec3], params: &RansacParams) -> Vec<EdgeLine> {
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut remaining: Vec<usize> = (0..points.len()).collect();
    let mut lines = Vec::new();
    while lines.len() < params.max_lines && remaining.len() >= params.min_remaining_points.max(2) {
        let Some(line) = best_line(points, &remaining, params, &mut rng) else {
            break;
        };
        if line.inliers.len() < params.min_line_points {
            break;
        }
        let taken: std::collections::HashSet<usize> = line.inliers.iter().copied().collect();
        remaining.retain(|i| !taken.contains(i));
        lines.push(line);
    }
    lines
}

fn best_line(points: &[Vec3], remaining: &[usize], params: &RansacParams, rng: &mut ChaCha8Rng) -> Option<EdgeLine> {
    let n = remaining.len();
    // Scoring on a fixed subsample keeps a hypothesis cheap on long edges;
    // gathered once, since every hypothesis reads all of it.
    let sample_stride = (n / 2000).max(1);
    let sample: Vec<Vec3> = remaining.iter().step_by(sample_stride).map(|&i| points[i]).collect();
    let mut best: Option<(usize, Vec3, Vec3)> = None;
    for _ in 0..params.iterations {
        let a = points[remaining[(rng.next_u64() % n as u64) as usize]];
        let b = points[remaining[(rng.next_u64() % n as u64) as usize]];
        let d = b - a;
        let len = d.norm();
        // Two points closer than the inlier distance give no direction.
        if len < 2.0 * params.distance_mm {
            continue;
        }
        let dir = d / len;
        // Only a strictly better score replaces the best, as in a plain
        // scan, so a hypothesis that cannot get there is dropped early.
        let needed = best.as_ref().map_or(0, |(s, _, _)| s + 1);
        if let Some(score) = score_reaching(&sample, &a, &dir, params.distance_mm, needed) {
            best = Some((score, a, dir));
        }
    }
    let (_, a, dir) = best?;
    let inliers_of = |point: &Vec3, dir: &Vec3| -> Vec<usize> {
        remaining
            .iter()
            .copied()
            .filter(|&i| (points[i] - point).cross(dir).norm_squared() <= params.distance_mm * params.distance_mm)
            .collect()
    };
    let mut inliers = inliers_of(&a, &dir);
    let (mut point, mut direction) = (a, dir);
    // One least-squares polish of the hypothesis on its inliers.
    if let Some((c, d)) = inliers.iter().map(|&i| &points[i]).collect::<Moments>().line() {
        let polished = inliers_of(&c, &d);
        if polished.len() >= inliers.len() {
            (point, direction, inliers) = (c, d, polished);
        }
    }
    Some(EdgeLine { point, direction, inliers })
}

/// Points of `sample` within `distance` of the line through `a` along
/// `dir`, when that count reaches `needed`; `None` as soon as it cannot.
/// A plain loop over chunks, which the compiler turns into four-lane
/// double registers where the kernels run AVX2: the same operations in the
/// same order, so the same inliers.
fn score_reaching(sample: &[Vec3], a: &Vec3, dir: &Vec3, distance: f64, needed: usize) -> Option<usize> {
    kernels::vectorised(
        #[inline(always)]
        || score_reaching_lanes(sample, a, dir, distance, needed),
    )
}

#[inline(always)]
fn score_reaching_lanes(sample: &[Vec3], a: &Vec3, dir: &Vec3, distance: f64, needed: usize) -> Option<usize> {
    // Chunks long enough to vectorise, short enough to give up early.
    const CHUNK: usize = 128;
    let limit = distance * distance;
    let mut score = 0;
    let mut left = sample.len();
    for chunk in sample.chunks(CHUNK) {
        if score + left < needed {
            return None;
        }
        left -= chunk.len();
        score += chunk.iter().map(|p| ((p - a).cross(dir).norm_squared() <= limit) as usize).sum::<usize>();
    }
    (score >= needed).then_some(score)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> RansacParams {
        RansacParams {
            distance_mm: 1.0,
            iterations: 200,
            min_line_points: 20,
            min_remaining_points: 20,
            max_lines: 8,
            seed: 7,
        }
    }

    /// The four edges of a 100 x 60 mm rectangle at z = 700, with jitter.
    fn rectangle() -> Vec<Vec3> {
        let mut pts = Vec::new();
        for i in 0..200 {
            let t = i as f64 * 0.5;
            let j = ((i * 37) % 11) as f64 * 0.03;
            pts.push(Vec3::new(t, j, 700.0));
            pts.push(Vec3::new(t, 60.0 + j, 700.0));
        }
        for i in 0..120 {
            let t = i as f64 * 0.5;
            pts.push(Vec3::new(0.0, t, 700.0));
            pts.push(Vec3::new(100.0, t, 700.0));
        }
        pts
    }

    #[test]
    fn finds_the_four_edges_of_a_rectangle() {
        let lines = segment_lines(&rectangle(), &params());
        assert_eq!(lines.len(), 4);
        let along_x = lines.iter().filter(|l| l.direction.x.abs() > 0.999).count();
        assert_eq!(along_x, 2);
        assert!(lines.iter().all(|l| l.inliers.len() >= 115));
    }

    #[test]
    fn same_seed_same_lines() {
        let a = segment_lines(&rectangle(), &params());
        let b = segment_lines(&rectangle(), &params());
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.inliers, y.inliers);
        }
    }

    #[test]
    fn early_scoring_counts_exactly_what_a_plain_scan_counts() {
        let pts = rectangle();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            let a = pts[(rng.next_u64() % pts.len() as u64) as usize];
            let b = pts[(rng.next_u64() % pts.len() as u64) as usize];
            let Some(dir) = (b - a).try_normalize(1e-9) else { continue };
            let plain = pts.iter().filter(|p| (*p - a).cross(&dir).norm_squared() <= 1.0).count();
            assert_eq!(score_reaching(&pts, &a, &dir, 1.0, 0), Some(plain));
            assert_eq!(score_reaching(&pts, &a, &dir, 1.0, plain), Some(plain));
            assert_eq!(score_reaching(&pts, &a, &dir, 1.0, plain + 1), None);
            assert_eq!(score_reaching_lanes(&pts, &a, &dir, 1.0, 0), Some(plain));
        }
    }

    #[test]
    fn too_few_points_give_no_line() {
        let pts: Vec<Vec3> = (0..10).map(|i| Vec3::new(i as f64, 0.0, 500.0)).collect();
        assert!(segment_lines(&pts, &params()).is_empty());
    }
}
