//! Euclidean clustering of the plane points (section 3.3): points closer
//! than a tolerance, directly or through a chain of others, form one plane.
//!
//! Two exact implementations:
//! - [`euclidean`] clusters any cloud by hashing points into voxels whose
//!   diagonal is the tolerance (so a voxel's points are connected at once)
//!   and joining neighbouring voxels when any pair of their points is
//!   close enough. It is the paper's clustering without a KD-tree query per
//!   point.
//! - [`grid`] clusters an organized frame on its pixel grid: adjacent plane
//!   pixels join when their points are within the tolerance. A gap between
//!   plates always leaves a line of non-plane pixels, so plates separate
//!   even when their gap is far below the tolerance (the paper's 2 mm
//!   merges I-butt plates closer than about 1 mm). It joins whole runs of
//!   pixels at a time and gives exactly the clusters of `reference()`
//!   (kept beside it for the tests), which joins pixel by pixel.
//!
//! Without a grid nothing marks a gap but its width, so a cloud whose
//! tolerance is measured in point spacings is clustered twice, and
//! [`split_narrow_gaps`] splits the clusters of the looser pass that hold
//! two plates the tighter one tells apart.

use rayon::prelude::*;

use crate::cloud::PointCloud;
// Two points are close when within the tolerance by the kernels' one
// predicate, the neighbour counts' own.
use crate::kernels::within as close;

/// Marks a point that belongs to no cluster.
pub(crate) const UNCLUSTERED: u32 = u32::MAX;

mod voxels;

pub(crate) use voxels::euclidean;
#[cfg(test)]
use voxels::euclidean_reference;

/// Cluster labels per point and the member indices of each cluster,
/// largest first.
#[derive(Debug, Clone)]
pub(crate) struct Clusters {
    pub labels: Vec<u32>,
    pub members: Vec<Vec<u32>>,
}

/// Union-find over a slice of slots whose ids start at `offset`, so
/// disjoint parts of one parent array can be worked on in parallel.
struct DisjointSets<'a> {
    parent: &'a mut [u32],
    offset: u32,
}

impl DisjointSets<'_> {
    fn find(&mut self, mut x: u32) -> u32 {
        let o = self.offset;
        while self.parent[(x - o) as usize] != x {
            let grand = self.parent[(self.parent[(x - o) as usize] - o) as usize];
            self.parent[(x - o) as usize] = grand;
            x = grand;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        self.link(ra, rb);
    }

    /// Joins the sets of roots `ra` and `rb`; returns the joint root.
    fn link(&mut self, ra: u32, rb: u32) -> u32 {
        // Smaller root wins, so roots do not depend on visit order.
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[(hi - self.offset) as usize] = lo;
        lo
    }
}

fn identity(n: usize) -> Vec<u32> {
    (0..n as u32).collect()
}

/// Turns a union-find over `n` slots into labelled clusters of the slots
/// that are in the set, keeping clusters of at least `min_points`. Sets
/// must hold only such slots. The parent array becomes the label array,
/// so no frame-sized array is added.
fn collect(parent: Vec<u32>, in_set: impl Fn(usize) -> bool, min_points: usize) -> Clusters {
    let n = parent.len();
    let mut ids = parent;
    // A parent never has a larger index than its child (unions hang the
    // larger root under the smaller, halving only shortens paths), so in
    // one forward pass every parent is already numbered when its children
    // are reached: a root opens the next set number, the others take their
    // parent's. Sets are thus numbered by their smallest slot. Slots that
    // share a parent are in one set, and the grid's runs are such slots
    // side by side, so they are numbered together.
    let mut sizes: Vec<u32> = Vec::new();
    let mut i = 0;
    while i < n {
        if !in_set(i) {
            ids[i] = UNCLUSTERED;
            i += 1;
            continue;
        }
        let p = ids[i] as usize;
        debug_assert!(p <= i, "slot {i} hangs under the later slot {p}");
        let id = if p == i {
            sizes.push(0);
            sizes.len() as u32 - 1
        } else {
            ids[p]
        };
        let end = i + 1 + leading(&ids[i + 1..], p as u32);
        ids[i..end].fill(id);
        sizes[id as usize] += (end - i) as u32;
        i = end;
    }
    let mut kept: Vec<u32> = (0..sizes.len() as u32).filter(|&k| sizes[k as usize] as usize >= min_points).collect();
    // Largest first; ties by the smallest member, which numbered the set.
    kept.sort_by(|&a, &b| sizes[b as usize].cmp(&sizes[a as usize]).then(a.cmp(&b)));
    let mut members: Vec<Vec<u32>> = kept.iter().map(|&k| Vec::with_capacity(sizes[k as usize] as usize)).collect();
    // The size table becomes the set-to-label table.
    let mut label_of = sizes;
    label_of.fill(UNCLUSTERED);
    for (label, &k) in kept.iter().enumerate() {
        label_of[k as usize] = label as u32;
    }
    let mut labels = ids;
    let mut i = 0;
    while i < n {
        let id = labels[i];
        let end = i + 1 + leading(&labels[i + 1..], id);
        if id != UNCLUSTERED {
            let label = label_of[id as usize];
            labels[i..end].fill(label);
            if label != UNCLUSTERED {
                members[label as usize].extend(i as u32..end as u32);
            }
        }
        i = end;
    }
    Clusters { labels, members }
}

/// How many slots at the start of `slots` hold `value`.
fn leading<T: Copy + PartialEq>(slots: &[T], value: T) -> usize {
    // Whole blocks first, compared without branching so they vectorise.
    const BLOCK: usize = 16;
    let mut n = 0;
    for block in slots.chunks_exact(BLOCK) {
        if !block.iter().fold(true, |all, &s| all & (s == value)) {
            break;
        }
        n += BLOCK;
    }
    n + slots[n..].iter().take_while(|&&s| s == value).count()
}

/// Clusters the points of an organized frame selected by `mask`, joining
/// 8-adjacent pixels whose points are within `tolerance_mm`.
///
/// Each row is cut into runs of selected pixels whose horizontal
/// neighbours are within the tolerance; a run is one union-find node (its
/// first pixel), and its other pixels point at it. Rows are then joined
/// run against run: two touching runs need one close pixel pair, and none
/// when they are already joined, so plates cost a check per run and not
/// three per pixel. Horizontal strips are labelled in parallel, each in
/// its own part of the parent array, then joined across the rows where
/// strips meet.
pub(crate) fn grid(cloud: &PointCloud, mask: &[bool], tolerance_mm: f64, min_points: usize) -> Clusters {
    let (w, h) = (cloud.width(), cloud.height());
    let points = cloud.points();
    let tol_sq = (tolerance_mm * tolerance_mm) as f32;
    if w == 0 || h == 0 {
        return collect(Vec::new(), |_| false, min_points);
    }
    // Every slot is written below; zeroed memory costs no pass of its own.
    let mut parent = vec![0u32; points.len()];
    let strip_rows = h.div_ceil(rayon::current_num_threads().max(1)).max(1);
    parent.par_chunks_mut(strip_rows * w).enumerate().for_each(|(k, chunk)| {
        let first_row = k * strip_rows;
        let mut sets = DisjointSets { parent: chunk, offset: (first_row * w) as u32 };
        let (mut above, mut runs, mut links) = (Vec::new(), Vec::new(), Vec::new());
        for r in 0..sets.parent.len() / w {
            let base = (first_row + r) * w;
            row_runs(&points[base..base + w], &mask[base..base + w], tol_sq, &mut links, &mut runs);
            point_at_runs(&mut sets.parent[r * w..(r + 1) * w], base as u32, &runs);
            if r > 0 {
                link_rows(&mut sets, points, base - w, w, &above, &runs, tol_sq);
            }
            std::mem::swap(&mut above, &mut runs);
        }
    });
    let mut sets = DisjointSets { parent: &mut parent, offset: 0 };
    let (mut above, mut below, mut links) = (Vec::new(), Vec::new(), Vec::new());
    for seam_row in (strip_rows..h).step_by(strip_rows) {
        let (a, b) = ((seam_row - 1) * w, seam_row * w);
        row_runs(&points[a..b], &mask[a..b], tol_sq, &mut links, &mut above);
        row_runs(&points[b..b + w], &mask[b..b + w], tol_sq, &mut links, &mut below);
        link_rows(&mut sets, points, a, w, &above, &below, tol_sq);
    }
    collect(parent, |i| mask[i], min_points)
}

/// Selected pixels of one row, columns `start..=end`, each within the
/// tolerance of the next.
#[derive(Debug, Clone, Copy)]
struct PixelRun {
    start: u32,
    end: u32,
}

/// The runs of one row, left to right; `links` is scratch space.
fn row_runs(points: &[[f32; 3]], mask: &[bool], tol_sq: f32, links: &mut Vec<bool>, runs: &mut Vec<PixelRun>) {
    let w = mask.len();
    // Whether each pixel joins its right neighbour, for the whole row at
    // once: without an exit in the loop it vectorises.
    links.clear();
    links.resize(w.saturating_sub(1), false);
    for (((link, p), q), m) in links.iter_mut().zip(points).zip(&points[1..]).zip(mask.windows(2)) {
        *link = m[0] & m[1] & close(p, q, tol_sq);
    }
    runs.clear();
    let mut col = 0;
    while col < w {
        if !mask[col] {
            col += 1;
            continue;
        }
        let end = col + leading(&links[col.min(links.len())..], true);
        runs.push(PixelRun { start: col as u32, end: end as u32 });
        col = end + 1;
    }
}

/// Points the pixels of each run at its first pixel and leaves the others
/// as roots of their own; `base` is the row's first pixel index.
fn point_at_runs(parent_row: &mut [u32], base: u32, runs: &[PixelRun]) {
    let mut col = 0;
    for run in runs {
        let (s, e) = (run.start as usize, run.end as usize);
        for (c, slot) in parent_row[col..s].iter_mut().enumerate() {
            *slot = base + (col + c) as u32;
        }
        parent_row[s..=e].fill(base + run.start);
        col = e + 1;
    }
    for (c, slot) in parent_row[col..].iter_mut().enumerate() {
        *slot = base + (col + c) as u32;
    }
}

/// Joins the runs of the row starting at pixel `base` to the 8-adjacent
/// runs of the row below.
fn link_rows(
    sets: &mut DisjointSets,
    points: &[[f32; 3]],
    base: usize,
    w: usize,
    above: &[PixelRun],
    below: &[PixelRun],
    tol_sq: f32,
) {
    let (top, bottom) = (&points[base..base + w], &points[base + w..base + 2 * w]);
    // Below runs ending left of a run's down-left neighbour cannot touch
    // it or any run to its right.
    let mut first = 0;
    for a in above {
        while first < below.len() && below[first].end + 1 < a.start {
            first += 1;
        }
        let mut ra = sets.find(base as u32 + a.start);
        for b in below[first..].iter().take_while(|b| b.start <= a.end + 1) {
            let rb = sets.find((base + w) as u32 + b.start);
            if ra != rb && touch(top, bottom, *a, *b, tol_sq) {
                ra = sets.link(ra, rb);
            }
        }
    }
}

/// Whether some pixel of run `a` in row `top` is within the tolerance of
/// an 8-adjacent pixel of run `b` in the row below.
fn touch(top: &[[f32; 3]], bottom: &[[f32; 3]], a: PixelRun, b: PixelRun, tol_sq: f32) -> bool {
    let (b0, b1) = (b.start as usize, b.end as usize);
    let cols = (a.start as usize).max(b0.saturating_sub(1))..=(a.end as usize).min(b1 + 1);
    cols.into_iter().any(|c| {
        let p = &top[c];
        (c.saturating_sub(1).max(b0)..=(c + 1).min(b1)).any(|d| close(p, &bottom[d], tol_sq))
    })
}

/// The least share of a cluster's points its plate-sized pieces must hold
/// for [`split_narrow_gaps`] to split it. Plates a narrow gap separates
/// hold all of it but a rim or a sliver (0.99 and more at 1 mm voxels). A
/// surface sparser than the tight tolerance (a consumer camera's table
/// twice as far as its plates) crumbles into dozens of pieces, the
/// plate-sized ones holding 0.62 to 0.89 of it: one surface, not plates.
pub(crate) const MIN_SPLIT_SHARE: f64 = 0.95;

/// The clusters `loose` holds, each split where it is two plates or more
/// joined only across a gap narrower than its tolerance. `tight` clusters
/// the same points at a tolerance that still joins a lattice's
/// neighbours; a loose cluster that holds two tight clusters or more that
/// pass `is_plate` (each large enough to be a plate on its own) becomes
/// those, and its other points (a rim, a sliver the tight tolerance cut
/// off) join no cluster. A loose cluster holding one such piece stays
/// whole, so a plate whose thin rim or tip the tight tolerance would cut
/// off keeps it; so does one whose plate-sized pieces hold less than
/// [`MIN_SPLIT_SHARE`] of its points. Largest first, as [`euclidean`]
/// gives them.
///
/// Why both: a voxel cloud's plates lie a spacing or two apart across an
/// I-butt gap, within the tolerance that keeps a plate's own sparse rims
/// joined (diagonal neighbours and the plane criterion's odd holes).
pub(crate) fn split_narrow_gaps(loose: Clusters, tight: &Clusters, is_plate: impl Fn(&[u32]) -> bool) -> Clusters {
    // Each tight cluster lies within one loose cluster: points joined at the
    // tight tolerance are joined at the loose one.
    let mut pieces: Vec<Vec<usize>> = vec![Vec::new(); loose.members.len()];
    for (t, members) in tight.members.iter().enumerate() {
        let Some(&first) = members.first() else { continue };
        if let Some(owner) = pieces.get_mut(loose.labels[first as usize] as usize) {
            owner.push(t);
        }
    }
    // Plate-sized pieces are looked for only in clusters of two or more,
    // and taken only where they hold next to all of it.
    let plates: Vec<Vec<usize>> = pieces
        .into_iter()
        .zip(&loose.members)
        .map(|(ts, whole)| {
            if ts.len() < 2 {
                return Vec::new();
            }
            let plates: Vec<usize> = ts.into_iter().filter(|&t| is_plate(&tight.members[t])).collect();
            let held: usize = plates.iter().map(|&t| tight.members[t].len()).sum();
            if (held as f64) < MIN_SPLIT_SHARE * whole.len() as f64 { Vec::new() } else { plates }
        })
        .collect();
    if plates.iter().all(|ts| ts.len() < 2) {
        return loose;
    }
    let Clusters { mut labels, members: loose_members } = loose;
    let mut members: Vec<Vec<u32>> = Vec::with_capacity(loose_members.len());
    for (whole, ts) in loose_members.into_iter().zip(plates) {
        if ts.len() < 2 {
            members.push(whole);
            continue;
        }
        for &i in &whole {
            labels[i as usize] = UNCLUSTERED;
        }
        members.extend(ts.into_iter().map(|t| tight.members[t].clone()));
    }
    // Largest first; ties by the smallest member, as `collect` orders them.
    members.sort_by(|a, b| b.len().cmp(&a.len()).then(a.first().cmp(&b.first())));
    for (label, m) in members.iter().enumerate() {
        for &i in m {
            labels[i as usize] = label as u32;
        }
    }
    Clusters { labels, members }
}

/// The straightforward form of [`grid`]: one pass over the frame joining
/// each selected pixel to its right and three lower neighbours, one pixel
/// pair at a time, then members grouped by their root in a map. Kept as
/// the reference.
#[cfg(test)]
pub(crate) fn reference(cloud: &PointCloud, mask: &[bool], tolerance_mm: f64, min_points: usize) -> Clusters {
    let (w, h) = (cloud.width(), cloud.height());
    let points = cloud.points();
    let tol_sq = (tolerance_mm * tolerance_mm) as f32;
    let mut parent = identity(points.len());
    let mut sets = DisjointSets { parent: &mut parent, offset: 0 };
    for row in 0..h {
        for col in 0..w {
            let i = row * w + col;
            if !mask[i] {
                continue;
            }
            let right = (col + 1 < w).then_some(i + 1);
            let below =
                (row + 1 < h).then(|| (col.saturating_sub(1)..=(col + 1).min(w - 1)).map(move |c| i + w - col + c));
            for j in right.into_iter().chain(below.into_iter().flatten()) {
                if mask[j] && close(&points[i], &points[j], tol_sq) {
                    sets.union(i as u32, j as u32);
                }
            }
        }
    }
    let mut groups: std::collections::BTreeMap<u32, Vec<u32>> = std::collections::BTreeMap::new();
    for i in (0..points.len()).filter(|&i| mask[i]) {
        groups.entry(sets.find(i as u32)).or_default().push(i as u32);
    }
    let mut members: Vec<Vec<u32>> = groups.into_values().filter(|m| m.len() >= min_points).collect();
    members.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
    let mut labels = vec![UNCLUSTERED; points.len()];
    for (label, m) in members.iter().enumerate() {
        for &i in m {
            labels[i as usize] = label as u32;
        }
    }
    Clusters { labels, members }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two 20 x 10 point patches on a 0.2 mm grid, `gap` mm apart in x, with
    /// a column of invalid pixels between them on the image grid.
    fn two_patches(gap: f32) -> (PointCloud, Vec<bool>) {
        let (w, h) = (41, 10);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let p = match col {
                    0..20 => [col as f32 * 0.2, row as f32 * 0.2, 600.0],
                    20 => [f32::NAN; 3],
                    _ => [19.0 * 0.2 + gap + (col - 21) as f32 * 0.2, row as f32 * 0.2, 600.0],
                };
                pts.push(p);
            }
        }
        let cloud = PointCloud::organized(w, h, pts).unwrap();
        let mask = cloud.points().iter().map(|p| p[0].is_finite()).collect();
        (cloud, mask)
    }

    #[test]
    fn grid_clustering_separates_a_half_millimetre_gap() {
        let (cloud, mask) = two_patches(0.5);
        let c = grid(&cloud, &mask, 2.0, 1);
        assert_eq!(c.members.len(), 2);
        assert_eq!(c.members[0].len(), 200);
    }

    #[test]
    fn euclidean_clustering_merges_what_the_tolerance_bridges() {
        let (cloud, mask) = two_patches(0.5);
        assert_eq!(euclidean(&cloud, &mask, 2.0, 1).members.len(), 1, "the paper's 2 mm merges a 0.5 mm gap");
        assert_eq!(euclidean(&cloud, &mask, 0.4, 1).members.len(), 2);
    }

    #[test]
    fn euclidean_matches_brute_force_on_scattered_points() {
        // Points on a coarse lattice with random-ish jitter; compare with O(n²).
        let mut pts = Vec::new();
        for i in 0..300u32 {
            let h = i.wrapping_mul(2654435761);
            let jitter = |s: u32| ((h >> s) & 0xff) as f32 / 255.0;
            pts.push([(i % 17) as f32 * 1.3 + jitter(0), (i / 17) as f32 * 1.1 + jitter(8), 500.0 + jitter(16) * 3.0]);
        }
        let cloud = PointCloud::unorganized(pts.clone());
        let mask = vec![true; pts.len()];
        let got = euclidean(&cloud, &mask, 1.2, 1);
        let mut parent = identity(pts.len());
        let mut sets = DisjointSets { parent: &mut parent, offset: 0 };
        for a in 0..pts.len() {
            for b in a + 1..pts.len() {
                if close(&pts[a], &pts[b], 1.44) {
                    sets.union(a as u32, b as u32);
                }
            }
        }
        let expected = collect(parent, |_| true, 1);
        let mut g: Vec<usize> = got.members.iter().map(Vec::len).collect();
        let mut e: Vec<usize> = expected.members.iter().map(Vec::len).collect();
        g.sort();
        e.sort();
        assert_eq!(g, e);
    }

    #[test]
    fn euclidean_gives_exactly_the_reference_clusters() {
        // Plates, stray points and clumps at several densities, with points
        // left out of the mask; and one point too far out to pack, which
        // sends the whole cloud down the reference path.
        let mut rng = Mix(17);
        for (n, spread, tolerance) in [(4000, 60.0f32, 2.4), (20_000, 120.0, 1.2), (3000, 15.0, 0.7), (0, 1.0, 1.0)] {
            let mut pts: Vec<[f32; 3]> = (0..n)
                .map(|k| {
                    let (x, y) = (rng.unit() * spread - spread / 2.0, rng.unit() * spread - spread / 2.0);
                    let z = if k % 5 == 0 { 480.0 + rng.unit() * 40.0 } else { 500.0 + 0.2 * x + rng.unit() * 0.3 };
                    [x, y, z]
                })
                .collect();
            let mask: Vec<bool> = (0..n).map(|_| rng.chance(0.9)).collect();
            let cloud = PointCloud::unorganized(pts.clone());
            let fast = euclidean(&cloud, &mask, tolerance, 3);
            let slow = euclidean_reference(&cloud, &mask, tolerance, 3);
            assert_eq!(fast.labels, slow.labels, "{n} points, tolerance {tolerance}");
            assert_eq!(fast.members, slow.members);
            pts.push([5.0e6, 0.0, 500.0]);
            let far = PointCloud::unorganized(pts);
            let mut far_mask = mask.clone();
            far_mask.push(true);
            let fast = euclidean(&far, &far_mask, tolerance, 1);
            assert_eq!(fast.labels, euclidean_reference(&far, &far_mask, tolerance, 1).labels);
        }
        // Voxels too many to number in 32 bits (a fine tolerance over a
        // 200 mm span: 14 + 14 + 12 bits) take the 16-byte keys.
        let mut pts: Vec<[f32; 3]> = (0..3000)
            .map(|_| [rng.unit() * 1.5, rng.unit() * 1.5, 500.0 + rng.unit() * 0.05])
            .chain([[-100.0, -100.0, 480.0], [100.0, 100.0, 520.0]])
            .collect();
        pts.extend((0..200).map(|k| [k as f32 * 0.02 - 2.0, 0.5, 500.0]));
        let mut mask: Vec<bool> = (0..pts.len()).map(|_| rng.chance(0.9)).collect();
        mask[3000..3002].fill(true);
        let cloud = PointCloud::unorganized(pts);
        let (fast, slow) = (euclidean(&cloud, &mask, 0.03, 2), euclidean_reference(&cloud, &mask, 0.03, 2));
        assert_eq!((fast.labels, fast.members), (slow.labels, slow.members));
    }

    #[test]
    fn strips_join_into_the_same_clusters_as_one_pass() {
        // A diagonal band and a block, on a grid tall enough for many strips.
        let (w, h) = (40usize, 97usize);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let on_band = row < 60 && (col as isize - (row as isize) / 3).abs() < 3;
                let on_block = col > 30 && row % 40 < 30;
                pts.push(if on_band || on_block { [col as f32 * 0.3, row as f32 * 0.3, 600.0] } else { [f32::NAN; 3] });
            }
        }
        let cloud = PointCloud::organized(w, h, pts).unwrap();
        let mask: Vec<bool> = cloud.points().iter().map(|p| p[0].is_finite()).collect();
        let sizes = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| grid(&cloud, &mask, 0.5, 1)).members.iter().map(Vec::len).collect::<Vec<_>>()
        };
        let one = sizes(1);
        assert_eq!(one, sizes(3));
        assert_eq!(one, sizes(7));
        assert_eq!(one.len(), 4, "the band and three blocks");
    }

    /// A small deterministic generator, so failures reproduce.
    struct Mix(u64);

    impl Mix {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }

        /// Uniform in [0, 1).
        fn unit(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }

        fn chance(&mut self, p: f32) -> bool {
            self.unit() < p
        }
    }

    /// A `w x h` frame of a few tilted plates with depth steps, noise,
    /// dropouts (NaN points, some of them still selected), isolated pixels
    /// and pixels pushed just past the tolerance. `mask_p` is the chance
    /// that a valid pixel is selected.
    fn noisy_frame(seed: u64, w: usize, h: usize, mask_p: f32) -> (PointCloud, Vec<bool>) {
        let mut rng = Mix(seed);
        let step = 0.4f32;
        let mut pts = Vec::with_capacity(w * h);
        let mut mask = Vec::with_capacity(w * h);
        for row in 0..h {
            for col in 0..w {
                let (x, y) = (col as f32 * step, row as f32 * step);
                // Plates split by a diagonal, a vertical and a horizontal
                // step, one of them smaller than the tolerance.
                let mut z = 600.0 + 0.05 * x;
                if col + row / 2 > w {
                    z += 3.0;
                }
                if col > w / 3 && row > h / 2 {
                    z += 0.3;
                }
                if row > 2 * h / 3 {
                    z -= 5.0;
                }
                z += (rng.unit() - 0.5) * 0.2;
                if rng.chance(0.03) {
                    // Just beyond reach of every neighbour.
                    z += 1.2;
                }
                let valid = !rng.chance(0.04);
                let p = if valid { [x, y, z] } else { [f32::NAN; 3] };
                pts.push(p);
                mask.push(if valid { rng.chance(mask_p) } else { rng.chance(0.1) });
            }
        }
        let cloud = PointCloud::organized(w, h, pts).unwrap();
        (cloud, mask)
    }

    fn assert_same(got: &Clusters, expected: &Clusters, what: &str) {
        if let Some(i) = (0..expected.labels.len()).find(|&i| got.labels.get(i) != expected.labels.get(i)) {
            panic!("{what}: pixel {i} labelled {:?}, expected {}", got.labels.get(i), expected.labels[i]);
        }
        assert_eq!(got.labels.len(), expected.labels.len(), "{what}: labels");
        assert_eq!(got.members, expected.members, "{what}: members");
    }

    #[test]
    fn grid_matches_the_reference_on_noisy_frames() {
        let pools: Vec<_> =
            [1, 2, 3, 7].map(|n| (n, rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap())).into();
        let mut seed = 1;
        for (w, h) in [(1, 9), (9, 1), (2, 2), (5, 17), (31, 23), (64, 50), (17, 101), (150, 12)] {
            for mask_p in [1.0, 0.97, 0.8, 0.5] {
                for tol in [0.5, 0.62, 1.0] {
                    seed += 1;
                    let (cloud, mask) = noisy_frame(seed, w, h, mask_p);
                    for min_points in [1, 3] {
                        let expected = reference(&cloud, &mask, tol, min_points);
                        for (n, pool) in &pools {
                            let got = pool.install(|| grid(&cloud, &mask, tol, min_points));
                            let what = format!("{w} x {h}, seed {seed}, {mask_p} selected, {tol} mm, {n} threads");
                            assert_same(&got, &expected, &what);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn grid_matches_the_reference_on_patterns() {
        // Checkerboards join only diagonally, stripes only along their
        // direction; a lone pixel at each corner; seams cut through all.
        let (w, h) = (24usize, 40usize);
        let patterns: [fn(usize, usize) -> bool; 5] = [
            |r, c| (r + c) % 2 == 0,
            |r, _| r % 2 == 0,
            |_, c| c % 3 != 1,
            |r, c| (r / 3 + c / 3) % 2 == 0,
            |r, c| (r == 0 || r == 39) && (c == 0 || c == 23) || (r % 5 == 2 && c % 4 == 1),
        ];
        for (k, selected) in patterns.iter().enumerate() {
            let pts = (0..h * w).map(|i| [(i % w) as f32 * 0.3, (i / w) as f32 * 0.3, 600.0]).collect();
            let cloud = PointCloud::organized(w, h, pts).unwrap();
            let mask: Vec<bool> = (0..h * w).map(|i| selected(i / w, i % w)).collect();
            // 0.35 mm reaches straight neighbours only, 0.45 mm diagonals too.
            for tol in [0.35, 0.45] {
                let expected = reference(&cloud, &mask, tol, 1);
                for n in [1, 2, 5] {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
                    let got = pool.install(|| grid(&cloud, &mask, tol, 1));
                    assert_same(&got, &expected, &format!("pattern {k}, {tol} mm, {n} threads"));
                }
            }
        }
    }

    #[test]
    fn small_clusters_are_dropped() {
        let (cloud, mask) = two_patches(0.5);
        let c = grid(&cloud, &mask, 2.0, 201);
        assert!(c.members.is_empty());
        assert!(c.labels.iter().all(|&l| l == UNCLUSTERED));
    }

    /// A 1 mm lattice of rectangles `[x0, x1) x [0, rows)`, each a list of
    /// columns, as an unorganized cloud with every point selected.
    fn lattice(columns: &[std::ops::Range<i32>], rows: i32) -> (PointCloud, Vec<bool>) {
        let pts: Vec<[f32; 3]> = columns
            .iter()
            .flat_map(|cols| cols.clone().flat_map(move |x| (0..rows).map(move |y| [x as f32, y as f32, 700.0])))
            .collect();
        let mask = vec![true; pts.len()];
        (PointCloud::unorganized(pts), mask)
    }

    /// Each cluster's label is its place in the list, and no other point
    /// has one.
    fn assert_labels_match_members(c: &Clusters) {
        let labelled = c.labels.iter().filter(|&&l| l != UNCLUSTERED).count();
        assert_eq!(labelled, c.members.iter().map(Vec::len).sum::<usize>());
        for (label, m) in c.members.iter().enumerate() {
            assert!(m.iter().all(|&i| c.labels[i as usize] == label as u32), "cluster {label}");
        }
        assert!(c.members.windows(2).all(|w| w[0].len() >= w[1].len()), "largest first");
    }

    #[test]
    fn plates_a_gap_narrower_than_the_loose_tolerance_joins_are_split() {
        // Two plates of a 1 mm lattice, 2 mm apart: the 2.5 mm tolerance
        // joins them, 1.6 mm does not.
        let (cloud, mask) = lattice(&[0..40, 41..70], 20);
        let loose = euclidean(&cloud, &mask, 2.5, 1);
        let tight = euclidean(&cloud, &mask, 1.6, 1);
        assert_eq!((loose.members.len(), tight.members.len()), (1, 2));
        let split = split_narrow_gaps(loose, &tight, |m| m.len() >= 100);
        assert_eq!(split.members.iter().map(Vec::len).collect::<Vec<_>>(), vec![800, 580]);
        assert_labels_match_members(&split);
    }

    #[test]
    fn a_plate_keeps_a_tip_the_tight_tolerance_cuts_off() {
        // A plate and a tip of 2 columns beyond a 2 mm break: one plate.
        let (cloud, mask) = lattice(&[0..40, 41..43], 20);
        let loose = euclidean(&cloud, &mask, 2.5, 1);
        let tight = euclidean(&cloud, &mask, 1.6, 1);
        assert_eq!(tight.members.len(), 2);
        let split = split_narrow_gaps(loose.clone(), &tight, |m| m.len() >= 100);
        assert_eq!(split.members, loose.members);
        assert_eq!(split.labels, loose.labels);
    }

    #[test]
    fn a_surface_that_crumbles_at_the_tight_tolerance_stays_whole() {
        // Two plate-sized pieces and five slivers, each 2 mm from the next:
        // the pieces hold 600 of 800 points, under the share a gap leaves.
        let slivers = [32..34, 35..37, 38..40, 41..43, 44..46];
        let columns: Vec<_> = [0..15, 16..31].into_iter().chain(slivers).collect();
        let (cloud, mask) = lattice(&columns, 20);
        let loose = euclidean(&cloud, &mask, 2.5, 1);
        let tight = euclidean(&cloud, &mask, 1.6, 1);
        assert_eq!((loose.members.len(), tight.members.len()), (1, 7));
        let split = split_narrow_gaps(loose.clone(), &tight, |m| m.len() >= 300);
        assert_eq!(split.members, loose.members);
    }

    #[test]
    fn pieces_too_small_for_a_plate_join_no_cluster_where_the_plates_split() {
        // Two plates with a sliver between them, each 2 mm from the next,
        // and a separate patch far off that needs no split.
        let (cloud, mask) = lattice(&[0..40, 41..43, 44..80, 200..230], 20);
        let loose = euclidean(&cloud, &mask, 2.5, 1);
        let tight = euclidean(&cloud, &mask, 1.6, 1);
        assert_eq!((loose.members.len(), tight.members.len()), (2, 4));
        let split = split_narrow_gaps(loose, &tight, |m| m.len() >= 100);
        assert_eq!(split.members.iter().map(Vec::len).collect::<Vec<_>>(), vec![800, 720, 600]);
        assert_labels_match_members(&split);
        // The sliver's 40 points are no cluster's.
        let unclustered = split.labels.iter().filter(|&&l| l == UNCLUSTERED).count();
        assert_eq!(unclustered, 40);
    }
}
