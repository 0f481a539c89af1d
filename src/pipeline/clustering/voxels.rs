//! Euclidean clustering of any cloud by voxels ([`euclidean`]): points are
//! hashed into voxels whose diagonal is the tolerance, so a voxel's points
//! are connected at once, and neighbouring voxels are joined when any pair
//! of their points is close enough. The straightforward form
//! ([`euclidean_reference`]) is the fallback for coordinates too far out to
//! pack and the reference the fast form is tested against.

use std::collections::HashMap;

use rayon::prelude::*;

use super::{Clusters, DisjointSets, close, collect, identity};
use crate::cloud::PointCloud;
use crate::pipeline::gather::try_gather;

/// Voxels two cells apart can still hold points within the tolerance
/// (a voxel's diagonal is the tolerance, so three apart cannot).
const VOXEL_REACH: i64 = 2;

/// Bits per axis of a packed voxel key.
const VOXEL_AXIS_BITS: u32 = 21;

/// The (dx, dy) columns of voxels that follow a voxel in key order within
/// reach, with the first dz of each: in its own column only the voxels
/// above it, in the others all five.
const LATER_COLUMNS: [(i64, i64, i64); 13] = [
    (0, 0, 1),
    (0, 1, -VOXEL_REACH),
    (0, 2, -VOXEL_REACH),
    (1, -2, -VOXEL_REACH),
    (1, -1, -VOXEL_REACH),
    (1, 0, -VOXEL_REACH),
    (1, 1, -VOXEL_REACH),
    (1, 2, -VOXEL_REACH),
    (2, -2, -VOXEL_REACH),
    (2, -1, -VOXEL_REACH),
    (2, 0, -VOXEL_REACH),
    (2, 1, -VOXEL_REACH),
    (2, 2, -VOXEL_REACH),
];

/// Voxels of a parallel job: enough to amortise its binary searches.
const VOXELS_PER_JOB: usize = 1024;

/// The connected pairs a job holds before it joins them (8 kB): a job's
/// thousand voxels find several thousand pairs, and held until the job's
/// end they were a tenth of a small cloud's own size per thread. The sets
/// do not depend on the order of the unions.
const PAIRS_PER_JOIN: usize = 1024;

/// Exact Euclidean clustering of the points selected by `mask`.
///
/// The same clusters as [`euclidean_reference`], which they are tested
/// against: the same voxels, every point of a voxel joined, and two voxels
/// within reach joined when any pair of their points is close. What
/// differs is how: keys are packed and sorted once on rayon, the voxels
/// within reach are found by walking the sorted keys column by column (no
/// hashing), and the pairs of voxels are tested in parallel jobs, each
/// joining the pairs it found as soon as it is done. Clusters depend only
/// on which points connect, not on the order of the unions.
///
/// Memory: each selected point's voxel key and index sorted together, in
/// one vector sized once: 8 bytes a point when the selection's voxels span
/// few enough to number in 32 bits (a workpiece's, at any tolerance above
/// a few hundredths of a millimetre), else 16; where each voxel starts (4
/// bytes a voxel); and the union-find (4 bytes a point of the cloud, which
/// becomes the labels). A job's joined pairs live only until it has
/// joined them, not in one list of every pair of the cloud.
pub(crate) fn euclidean(cloud: &PointCloud, mask: &[bool], tolerance_mm: f64, min_points: usize) -> Clusters {
    let points = cloud.points();
    let cell = tolerance_mm / 3f64.sqrt();
    // The reference's voxel coordinates (i32, as it computes them).
    let voxel_of = |i: usize| points[i].map(|v| (v as f64 / cell).floor() as i32 as i64);
    let none = || ([i64::MAX; 3], [i64::MIN; 3]);
    let (low, high) = (0..points.len())
        .into_par_iter()
        .filter(|&i| mask[i])
        .map(|i| (voxel_of(i), voxel_of(i)))
        .reduce(none, |(a0, a1), (b0, b1)| {
            (std::array::from_fn(|k| a0[k].min(b0[k])), std::array::from_fn(|k| a1[k].max(b1[k])))
        });
    // Each axis's field holds the coordinates offset to leave the reach
    // free on either side, so that no step to a neighbour leaves it.
    let bits: [u32; 3] = std::array::from_fn(|k| {
        let span = (high[k].saturating_sub(low[k])).max(0) as u64 + 2 * VOXEL_REACH as u64 + 1;
        u64::BITS - span.leading_zeros()
    });
    if bits.iter().sum::<u32>() <= u32::BITS {
        let layout = VoxelLayout { y_shift: bits[2], x_shift: bits[1] + bits[2] };
        let field = |k: usize, c: i64| (c - low[k] + VOXEL_REACH) as u64;
        let packed = try_gather(
            mask,
            |_, &m| m,
            |i, _| {
                let c = voxel_of(i);
                let key = (field(0, c[0]) << layout.x_shift) | (field(1, c[1]) << layout.y_shift) | field(2, c[2]);
                Some(PackedEntry((key << u32::BITS) | i as u64))
            },
        );
        if let Some(entries) = packed {
            return join_voxels(entries, points, mask, tolerance_mm, layout, min_points);
        }
    }
    // Wide fields: each coordinate offset by half its field, when every
    // one leaves room for the reach on either side.
    let half = 1i64 << (VOXEL_AXIS_BITS - 1);
    let layout = VoxelLayout { y_shift: VOXEL_AXIS_BITS, x_shift: 2 * VOXEL_AXIS_BITS };
    let wide = try_gather(
        mask,
        |_, &m| m,
        |i, _| {
            let mut key = 0u64;
            for c in voxel_of(i) {
                if c.abs() >= half - VOXEL_REACH {
                    return None;
                }
                key = (key << VOXEL_AXIS_BITS) | (c + half) as u64;
            }
            Some((key, i as u32))
        },
    );
    match wide {
        Some(entries) => join_voxels(entries, points, mask, tolerance_mm, layout, min_points),
        None => euclidean_reference(cloud, mask, tolerance_mm, min_points),
    }
}

/// Where a voxel key's x and y fields start (z fills the bits below y).
#[derive(Debug, Clone, Copy)]
struct VoxelLayout {
    x_shift: u32,
    y_shift: u32,
}

/// A selected point's voxel key and index, sorted by key, then index.
trait VoxelEntry: Copy + Ord + Send + Sync + Default {
    fn key(&self) -> u64;
    fn index(&self) -> u32;
}

/// A key of up to 64 bits beside the index: 16 bytes.
impl VoxelEntry for (u64, u32) {
    fn key(&self) -> u64 {
        self.0
    }
    fn index(&self) -> u32 {
        self.1
    }
}

/// A key of up to 32 bits above the index, in 8 bytes; ordered as the
/// pair would be.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
struct PackedEntry(u64);

impl VoxelEntry for PackedEntry {
    fn key(&self) -> u64 {
        self.0 >> u32::BITS
    }
    fn index(&self) -> u32 {
        self.0 as u32
    }
}

/// [`euclidean`] once the selected points are keyed: `keyed` sorted, the
/// voxels walked and joined.
fn join_voxels<E: VoxelEntry>(
    mut keyed: Vec<E>,
    points: &[[f32; 3]],
    mask: &[bool],
    tolerance_mm: f64,
    layout: VoxelLayout,
    min_points: usize,
) -> Clusters {
    let tol_sq = (tolerance_mm * tolerance_mm) as f32;
    keyed.par_sort_unstable();
    // Where each voxel's run of points starts in `keyed`, and its end.
    let voxels =
        if keyed.is_empty() { 0 } else { 1 + keyed.par_windows(2).filter(|w| w[0].key() != w[1].key()).count() };
    let mut starts: Vec<u32> = Vec::with_capacity(voxels + 1);
    for (position, entry) in keyed.iter().enumerate() {
        if position == 0 || keyed[position - 1].key() != entry.key() {
            starts.push(position as u32);
        }
    }
    starts.push(keyed.len() as u32);
    let key = |v: usize| keyed[starts[v] as usize].key();
    let run = |v: usize| &keyed[starts[v] as usize..starts[v + 1] as usize];

    let mut parent = identity(points.len());
    let mut sets = DisjointSets { parent: &mut parent, offset: 0 };
    for v in 0..voxels {
        let members = run(v);
        for b in &members[1..] {
            sets.union(members[0].index(), b.index());
        }
    }
    // Every pair of voxels within reach whose points connect, found in
    // parallel over jobs of consecutive voxels and joined job by job.
    let sets = std::sync::Mutex::new(sets);
    // A poisoned lock means a panic elsewhere, which unwinds the whole plan
    // anyway; the sets themselves are never left half-set.
    let join = |found: &mut Vec<(u32, u32)>| {
        let mut sets = sets.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        for (a, b) in found.drain(..) {
            sets.union(a, b);
        }
    };
    (0..voxels.div_ceil(VOXELS_PER_JOB)).into_par_iter().for_each(|job| {
        let range = job * VOXELS_PER_JOB..((job + 1) * VOXELS_PER_JOB).min(voxels);
        let mut found: Vec<(u32, u32)> = Vec::with_capacity(PAIRS_PER_JOIN);
        // One cursor per column: for consecutive voxels the wanted
        // keys of a column only grow, so each walks forward.
        let mut cursors = [usize::MAX; LATER_COLUMNS.len()];
        for v in range {
            let own = key(v);
            for (cursor, &(dx, dy, dz0)) in cursors.iter_mut().zip(&LATER_COLUMNS) {
                let shift = |k: u64, dx: i64, dy: i64, dz: i64| {
                    let delta = (dx << layout.x_shift) + (dy << layout.y_shift) + dz;
                    (k as i64 + delta) as u64
                };
                // Fields never overflow: every coordinate is at least
                // the reach away from the ends of its field.
                let (lo, hi) = (shift(own, dx, dy, dz0), shift(own, dx, dy, VOXEL_REACH));
                if *cursor == usize::MAX {
                    *cursor = starts[..voxels].partition_point(|&start| keyed[start as usize].key() < lo);
                }
                while *cursor < voxels && key(*cursor) < lo {
                    *cursor += 1;
                }
                let mut w = *cursor;
                while w < voxels && key(w) <= hi {
                    let connected = run(v).iter().any(|a| {
                        let p = &points[a.index() as usize];
                        run(w).iter().any(|b| close(p, &points[b.index() as usize], tol_sq))
                    });
                    if connected {
                        found.push((run(v)[0].index(), run(w)[0].index()));
                        if found.len() == PAIRS_PER_JOIN {
                            join(&mut found);
                        }
                    }
                    w += 1;
                }
            }
        }
        join(&mut found);
    });
    drop(keyed);
    drop(starts);
    collect(parent, |i| mask[i], min_points)
}

/// The straightforward form of [`euclidean`]: voxels in a hash map, each
/// unordered pair of voxels within reach looked up and joined in turn. It
/// is the fallback for coordinates too far out to pack into a key, and the
/// reference the fast form is tested against.
pub(super) fn euclidean_reference(cloud: &PointCloud, mask: &[bool], tolerance_mm: f64, min_points: usize) -> Clusters {
    let points = cloud.points();
    let tol_sq = (tolerance_mm * tolerance_mm) as f32;
    // Voxels with a diagonal of the tolerance: any two points in one voxel
    // are within it, so a voxel is connected without looking.
    let cell = tolerance_mm / 3f64.sqrt();
    let key_of = |p: &[f32; 3]| -> (i32, i32, i32) {
        let k = |v: f32| (v as f64 / cell).floor() as i32;
        (k(p[0]), k(p[1]), k(p[2]))
    };
    let mut order: Vec<u32> = (0..points.len() as u32).filter(|&i| mask[i as usize]).collect();
    order.sort_unstable_by_key(|&i| key_of(&points[i as usize]));
    let mut voxels: HashMap<(i32, i32, i32), (usize, usize)> = HashMap::new();
    let mut start = 0;
    while start < order.len() {
        let key = key_of(&points[order[start] as usize]);
        let mut end = start + 1;
        while end < order.len() && key_of(&points[order[end] as usize]) == key {
            end += 1;
        }
        voxels.insert(key, (start, end));
        start = end;
    }

    let mut parent = identity(points.len());
    let mut sets = DisjointSets { parent: &mut parent, offset: 0 };
    for &(s, e) in voxels.values() {
        for k in s + 1..e {
            sets.union(order[s], order[k]);
        }
    }
    // Voxels two cells apart can still hold points within the tolerance.
    let reach = 2i32;
    let mut keys: Vec<_> = voxels.keys().copied().collect();
    keys.sort_unstable();
    for key in &keys {
        let (s, e) = voxels[key];
        for dx in -reach..=reach {
            for dy in -reach..=reach {
                for dz in -reach..=reach {
                    let other = (key.0 + dx, key.1 + dy, key.2 + dz);
                    // Visit each unordered pair of voxels once.
                    if other <= *key {
                        continue;
                    }
                    let Some(&(s2, e2)) = voxels.get(&other) else {
                        continue;
                    };
                    if sets.find(order[s]) == sets.find(order[s2]) {
                        continue;
                    }
                    'pairs: for &a in &order[s..e] {
                        for &b in &order[s2..e2] {
                            if close(&points[a as usize], &points[b as usize], tol_sq) {
                                sets.union(a, b);
                                break 'pairs;
                            }
                        }
                    }
                }
            }
        }
    }
    collect(parent, |i| mask[i], min_points)
}
