//! A uniform grid of cubic cells over a cloud's valid points, for clouds
//! without a pixel grid.
//!
//! With cells as wide as the search radius, every neighbour of a point lies
//! in its own cell or one of the 26 around it. The points' indices are
//! stored in cell order, so a cell's points are one contiguous run, and
//! each occupied cell keeps the list of its occupied neighbour cells, found
//! once when the index is built rather than once per query. A query
//! therefore costs a scan of at most 27 runs, stopping as soon as its
//! visitor has what it needs (a count up to a threshold, a bounded sample
//! for a normal); each cell also keeps the bounding box of its points, so a
//! dense clump just out of reach costs one box test, not a scan.
//!
//! Building sorts the points by cell, on rayon, and the order is fixed by
//! (cell, cloud index), so queries visit neighbours in the same order on
//! every run and every machine.
//!
//! The index reads the cloud's own coordinates through those indices and
//! keeps no copy of them: a copy in cell order, one array per axis, made a
//! point query's loads contiguous, but it was as large as the cloud itself,
//! and it was the largest part of the index. The queries that read every
//! point ([`CellIndex::query_by_cell`]) gather each cell's candidates into
//! such arrays once for the cell's points anyway ([`Neighbourhood`]).
//!
//! For a few thousand queries (the spacing measurement) no index of the
//! cloud pays: [`counts_around`] sorts the few thousand query points by
//! cell and reads the cloud once against them.

use std::ops::{ControlFlow, Range};

use rayon::prelude::*;

use crate::cloud::Point;
#[cfg(doc)]
use crate::kernels::within;
use crate::pipeline::Deadline;
use crate::pipeline::gather::{gather, split_into_parts};

mod neighbourhood;

pub(crate) use neighbourhood::{HOOD_LANES, Neighbourhood};

/// Cell coordinates are packed into 21 bits each. Sanitised clouds lie
/// within 3 m of the camera and 80° of its axis (17 m across at most), so
/// cells of a twentieth of a millimetre still fit; coordinates beyond are
/// clamped, which can only put far-apart points in one cell, never split a
/// neighbourhood.
const AXIS_BITS: u32 = 21;
const AXIS_HALF_RANGE: i64 = 1 << (AXIS_BITS - 1);

/// How much wider than the query radius a cell is.
const CELL_MARGIN: f64 = 1.0 + 1e-5;

/// A cell's points and the box around them.
#[derive(Debug, Clone, Copy)]
struct Cell {
    /// The cell's run in the cell-ordered point array.
    start: u32,
    end: u32,
    min: [f32; 3],
    max: [f32; 3],
}

/// The index: the points' indices in cell order, the occupied cells and
/// their neighbourhoods.
pub(crate) struct CellIndex<'a> {
    /// The cloud's points, as given.
    points: &'a [Point],
    /// Cell-ordered position → cloud point index.
    index_of: Vec<u32>,
    /// The occupied cells' packed keys, ascending: a point's cell is found
    /// by its key, which costs a few comparisons per query but no array
    /// the size of the cloud.
    keys: Vec<u64>,
    /// The inverse of the cells' width, which gives a point its key.
    inverse_cell_mm: f64,
    cells: Vec<Cell>,
    /// The occupied cells among each cell's 27 (itself first), as ranges
    /// of `neighbour_cells` given by `neighbour_start`.
    neighbour_start: Vec<u32>,
    neighbour_cells: Vec<u32>,
}

/// The largest value of one packed field.
const FIELD_MAX: u64 = (1 << AXIS_BITS) - 1;

fn pack(c: [i64; 3]) -> u64 {
    let field = |v: i64| (v.clamp(-AXIS_HALF_RANGE, AXIS_HALF_RANGE - 1) + AXIS_HALF_RANGE) as u64;
    (field(c[0]) << (2 * AXIS_BITS)) | (field(c[1]) << AXIS_BITS) | field(c[2])
}

/// The (x, y) offsets of a cell's nine columns of three, its own first.
const COLUMNS: [(i64, i64); 9] = [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1)];

/// The occupied neighbours of every occupied cell (`keys`, sorted), the
/// cell itself first, as ranges of one array.
///
/// Keys are sorted x, then y, then z, so the three cells of a neighbouring
/// column are consecutive keys, and for a fixed column offset the wanted
/// keys grow with the cell's own: one cursor per column walks forward
/// through `keys` once for all cells, with no search per cell.
fn neighbourhoods(keys: &[u64]) -> (Vec<u32>, Vec<u32>) {
    // Two walks: the first counts each list so that the second fills one
    // array of exactly their length (a plate's cells have 9 to 27 occupied
    // neighbours; a guessed capacity doubled past its end).
    let mut starts = Vec::with_capacity(keys.len() + 1);
    starts.push(0u32);
    let total = std::cell::Cell::new(0u32);
    walk_neighbourhoods(keys, |_, _| total.set(total.get() + 1), |_| starts.push(total.get()));
    let mut list = Vec::with_capacity(total.get() as usize);
    walk_neighbourhoods(keys, |_, k| list.push(k), |_| {});
    (starts, list)
}

/// Calls `neighbour(c, k)` for each occupied cell `c` of `keys` and each
/// occupied cell `k` of its 27, `c` itself first, then `done(c)`.
fn walk_neighbourhoods(keys: &[u64], mut neighbour: impl FnMut(u32, u32), mut done: impl FnMut(u32)) {
    let mut cursors = [0usize; COLUMNS.len()];
    for (c, &key) in keys.iter().enumerate() {
        neighbour(c as u32, c as u32);
        for (cursor, range) in cursors.iter_mut().zip(column_ranges(key)) {
            let Some((lo, hi)) = range else { continue };
            while *cursor < keys.len() && keys[*cursor] < lo {
                *cursor += 1;
            }
            let mut k = *cursor;
            while k < keys.len() && keys[k] <= hi {
                if k != c {
                    neighbour(c as u32, k as u32);
                }
                k += 1;
            }
        }
        done(c as u32);
    }
}

/// The packed key of the cell holding `p` among cells `cell_mm` wide.
#[inline]
fn cell_key(p: &Point, inverse_cell_mm: f64) -> u64 {
    pack(std::array::from_fn(|a| cell_coordinate(f64::from(p[a]), inverse_cell_mm)))
}

/// The cell coordinate of `v` among cells `cell_mm` wide, clamped to what
/// a key packs (as [`pack`] clamps), so that distinct coordinates give
/// distinct keys.
#[inline]
fn cell_coordinate(v: f64, inverse_cell_mm: f64) -> i64 {
    (v * inverse_cell_mm).floor().clamp(-(AXIS_HALF_RANGE as f64), (AXIS_HALF_RANGE - 1) as f64) as i64
}

/// The inclusive key ranges of the nine columns of three cells around the
/// cell `key`, in [`COLUMNS`] order; `None` for a column outside the
/// packed range. Every key of the 27 cells lies in one of them.
#[inline]
fn column_ranges(key: u64) -> [Option<(u64, u64)>; COLUMNS.len()] {
    let (x, y, z) = (key >> (2 * AXIS_BITS), (key >> AXIS_BITS) & FIELD_MAX, key & FIELD_MAX);
    COLUMNS.map(|(dx, dy)| {
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        if !(0..=FIELD_MAX as i64).contains(&nx) || !(0..=FIELD_MAX as i64).contains(&ny) {
            return None;
        }
        let column = ((nx as u64) << (2 * AXIS_BITS)) | ((ny as u64) << AXIS_BITS);
        Some((column | z.saturating_sub(1), column | (z + 1).min(FIELD_MAX)))
    })
}

/// How much wider than the radius the cells of [`counts_around`] are, in
/// radii: more than two, so that a disc (the radius and a hair for
/// rounding) reaches at most two cells along each axis.
const SAMPLE_CELL_RADII: f64 = 2.5;

/// How far past the radius a sample's disc is taken to reach when its
/// cells are listed: the kernels' f32 predicate accepts points up to a
/// few parts in 10⁷ beyond the radius.
const SAMPLE_REACH_MARGIN: f64 = 1e-5;

/// The points of a parallel chunk of [`counts_around`]'s pass.
const COUNT_CHUNK: usize = 1 << 14;

/// The number of valid points of `points` within `radius_mm` of each of
/// `samples` by the kernels' predicate ([`within`]), a sample itself
/// included if it is one of the points, read up to `cap`.
///
/// For a few thousand samples (the spacing measurement), in one pass over
/// the cloud and nothing the cloud's size: the samples are sorted by the
/// cell they lie in, and each point of the cloud is tested against the
/// samples of the block of two cells by two by two from the lowest cell
/// its disc reaches (a sample within the radius of a point lies there, as
/// the point lies within the sample's). The block's cells of one column
/// along z are neighbours in key order, so a block is four runs of the
/// sorted samples, looked up once for the points that share it. Sorting
/// the whole cloud into cells instead (as [`CellIndex`] does for a query
/// per point) cost several times the cloud's own memory for 4096 counts;
/// listing each sample under every cell its disc reaches cost up to eight
/// entries a sample, half a megabyte, more than a small cloud itself.
///
/// Its cost grows with the points times the samples near each, so a cloud
/// whose points crowd into a few cells costs far more than its size: each
/// chunk first checks `deadline`, and once it has passed the chunks left
/// count nothing (the caller checks the deadline before reading counts).
pub(crate) fn counts_around(
    points: &[Point],
    samples: &[Point],
    radius_mm: f64,
    cap: u32,
    deadline: Deadline,
) -> Vec<u32> {
    let inverse_cell_mm = 1.0 / (SAMPLE_CELL_RADII * radius_mm);
    let reach = radius_mm * (1.0 + SAMPLE_REACH_MARGIN);
    let mut homed: Vec<(u64, u32)> =
        samples.iter().enumerate().map(|(s, p)| (cell_key(p, inverse_cell_mm), s as u32)).collect();
    homed.sort_unstable();
    let run_between = |(first, last): (u64, u64)| {
        let start = homed.partition_point(|&(k, _)| k < first);
        start..start + homed[start..].iter().take_while(|&&(k, _)| k <= last).count()
    };
    let radius_sq = (radius_mm * radius_mm) as f32;
    let counts = points
        .par_chunks(COUNT_CHUNK)
        .map(|chunk| {
            let mut counts = vec![0u32; samples.len()];
            if deadline.passed() {
                return counts;
            }
            // Neighbouring points mostly share their block: its runs of
            // samples are looked up once for the stretch.
            let mut cached: Option<([i64; 3], [Range<usize>; 4])> = None;
            for q in chunk.iter().filter(|q| q[0].is_finite()) {
                let low = std::array::from_fn(|a| cell_coordinate(f64::from(q[a]) - reach, inverse_cell_mm));
                let runs = match &cached {
                    Some((cached_low, runs)) if *cached_low == low => runs,
                    _ => &cached.insert((low, block_columns(low).map(|column| column.map_or(0..0, run_between)))).1,
                };
                for run in runs {
                    for &(_, s) in &homed[run.clone()] {
                        counts[s as usize] += crate::kernels::within(&samples[s as usize], q, radius_sq) as u32;
                    }
                }
            }
            counts
        })
        .reduce(
            || vec![0u32; samples.len()],
            |mut total, part| {
                for (t, p) in total.iter_mut().zip(part) {
                    *t += p;
                }
                total
            },
        );
    counts.into_iter().map(|n| n.min(cap)).collect()
}

/// The four columns of the block of [`counts_around`] whose lowest cell is
/// `low`, each as the first and last key of its cells along z; `None` for a
/// column past the packed range (its cells would clamp onto the column
/// before it, and be counted twice).
fn block_columns(low: [i64; 3]) -> [Option<(u64, u64)>; 4] {
    let top = AXIS_HALF_RANGE - 1;
    std::array::from_fn(|c| {
        let (x, y) = (low[0] + (c & 1) as i64, low[1] + (c >> 1) as i64);
        (x <= top && y <= top).then(|| (pack([x, y, low[2]]), pack([x, y, (low[2] + 1).min(top)])))
    })
}

impl<'a> CellIndex<'a> {
    /// Indexes the valid (finite) points of `cloud_points` for queries
    /// within `radius_mm`: cells a hair wider than the radius, so that a
    /// neighbour exactly at the radius never falls two cells away through
    /// rounding.
    pub(crate) fn for_radius(cloud_points: &'a [Point], radius_mm: f64) -> CellIndex<'a> {
        let inverse = 1.0 / (radius_mm * CELL_MARGIN);
        let mut keyed: Vec<(u64, u32)> =
            gather(cloud_points, |_, p| p[0].is_finite(), |i, p| (cell_key(p, inverse), i as u32));
        keyed.par_sort_unstable();

        let index_of: Vec<u32> = keyed.par_iter().map(|&(_, i)| i).collect();
        // Sized once: the cells are counted before they are listed.
        let occupied = if keyed.is_empty() { 0 } else { 1 + keyed.par_windows(2).filter(|w| w[0].0 != w[1].0).count() };
        let mut keys: Vec<u64> = Vec::with_capacity(occupied);
        let mut cells: Vec<Cell> = Vec::with_capacity(occupied);
        for (position, &(key, i)) in keyed.iter().enumerate() {
            if keys.last() != Some(&key) {
                keys.push(key);
                cells.push(Cell {
                    start: position as u32,
                    end: position as u32,
                    min: [f32::INFINITY; 3],
                    max: [f32::NEG_INFINITY; 3],
                });
            }
            let cell = cells.last_mut().expect("a cell was just pushed");
            cell.end = position as u32 + 1;
            for ((lo, hi), &v) in cell.min.iter_mut().zip(cell.max.iter_mut()).zip(&cloud_points[i as usize]) {
                *lo = lo.min(v);
                *hi = hi.max(v);
            }
        }
        drop(keyed);

        let (neighbour_start, neighbour_cells) = neighbourhoods(&keys);
        CellIndex {
            points: cloud_points,
            index_of,
            keys,
            inverse_cell_mm: inverse,
            cells,
            neighbour_start,
            neighbour_cells,
        }
    }

    /// The cell of `p`, one of the indexed points; `None` for an invalid
    /// point, which has no cell.
    #[inline]
    fn cell_of(&self, p: &Point) -> Option<usize> {
        if !p[0].is_finite() {
            return None;
        }
        self.keys.binary_search(&cell_key(p, self.inverse_cell_mm)).ok()
    }

    /// The runs of the cell-ordered arrays of the cells around `p`, one of
    /// the indexed points, whose boxes come within `reach_sq` of it, its
    /// own cell first; none for an invalid point.
    #[inline]
    fn runs_in_reach<'s>(&'s self, p: &'s Point, reach_sq: f32) -> impl Iterator<Item = Range<usize>> + 's {
        let around = match self.cell_of(p) {
            Some(cell) => self.neighbour_start[cell] as usize..self.neighbour_start[cell + 1] as usize,
            None => 0..0,
        };
        self.neighbour_cells[around]
            .iter()
            .map(|&c| &self.cells[c as usize])
            .filter(move |cell| box_distance_sq(cell, p) <= reach_sq as f64)
            .map(|cell| cell.start as usize..cell.end as usize)
    }

    /// Calls `visit(j, q)` for candidates `q` (cloud index `j`) of every
    /// point within `reach_sq` of `p`, one of the indexed points, nearest
    /// cells first, until it breaks. Candidates are a superset of the points
    /// within the reach: the caller applies its own predicate. An invalid
    /// point has no cell and no neighbours. The reference of
    /// [`CellIndex::visit_within`]'s order.
    #[cfg(test)]
    pub(crate) fn visit_near(&self, p: &Point, reach_sq: f32, mut visit: impl FnMut(usize, &Point) -> ControlFlow<()>) {
        for run in self.runs_in_reach(p, reach_sq) {
            for &j in &self.index_of[run] {
                if visit(j as usize, &self.points[j as usize]).is_break() {
                    return;
                }
            }
        }
    }

    /// Calls `visit(j)` for every point `j` within `radius_sq` of `p`, one
    /// of the indexed points (a point elsewhere may lie in no cell, and then
    /// has no neighbours), by the kernels' predicate ([`within`]), nearest
    /// cells first, until it breaks: the same visits as `visit_near` (the
    /// tests' candidates) with that predicate in the visitor, with the
    /// distances of a cell's points computed [`LANES_PER_TEST`] at a time.
    /// Cells farther than `reach_sq` are skipped whole, as there.
    #[inline]
    pub(crate) fn visit_within(
        &self,
        p: &Point,
        radius_sq: f32,
        reach_sq: f32,
        mut visit: impl FnMut(usize) -> ControlFlow<()>,
    ) {
        for run in self.runs_in_reach(p, reach_sq) {
            let (start, end) = (run.start, run.end);
            let mut block = start;
            while block < end {
                let stop = (block + LANES_PER_TEST).min(end);
                let mut inside = within_mask_of(p, &self.index_of[block..stop], self.points, radius_sq);
                while inside != 0 {
                    let lane = inside.trailing_zeros() as usize;
                    inside &= inside - 1;
                    if visit(self.index_of[block + lane] as usize).is_break() {
                        return;
                    }
                }
                block = stop;
            }
        }
    }
}

impl CellIndex<'_> {
    /// Runs `query(state, hood, i)` for every point `i` of the index for
    /// which `wanted(i)` holds, cell by cell on rayon, `hood` holding the
    /// candidates of the cell's points ([`Neighbourhood`]), after
    /// `prepare(state, hood)` has seen them once; returns the answers. A
    /// query per point then reads one contiguous run of candidates instead
    /// of up to 27 cells, and the run is gathered once for the cell's
    /// points. Cells without a wanted point are skipped.
    ///
    /// The answers go straight into one vector of exactly their number,
    /// each cell's into its own part, in cell order: collected from rayon's
    /// per-job pieces, they took twice their size at the plane criterion,
    /// and each answer carried its point's index (four bytes beside the
    /// edge criterion's one-byte answer), which the cell order gives again
    /// ([`CellAnswers::into_points`]).
    pub(crate) fn query_by_cell<S, T: Send + Clone + Default, W: Fn(usize) -> bool + Sync>(
        &self,
        init: impl Fn() -> S + Sync,
        wanted: W,
        prepare: impl Fn(&mut S, &Neighbourhood) + Sync,
        query: impl Fn(&mut S, &Neighbourhood, usize) -> T + Sync,
    ) -> CellAnswers<'_, T, W> {
        let members = |cell: &Cell| &self.index_of[cell.start as usize..cell.end as usize];
        let wanted_in: Vec<u32> = self
            .cells
            .par_iter()
            .map(|cell| members(cell).iter().filter(|&&i| wanted(i as usize)).count() as u32)
            .collect();
        let mut answers = vec![T::default(); wanted_in.iter().map(|&n| n as usize).sum()];
        let parts = split_into_parts(&mut answers, wanted_in.iter().map(|&n| n as usize));
        self.cells.par_iter().zip(parts).enumerate().for_each_init(
            || (init(), Neighbourhood::default()),
            |(state, hood), (c, (cell, part))| {
                if part.is_empty() {
                    return;
                }
                hood.gather(self, c);
                prepare(state, hood);
                let cell_wanted = members(cell).iter().filter(|&&i| wanted(i as usize));
                for (slot, &i) in part.iter_mut().zip(cell_wanted) {
                    *slot = query(state, hood, i as usize);
                }
            },
        );
        CellAnswers { index: self, wanted, answers }
    }
}

/// The answers of [`CellIndex::query_by_cell`], one per wanted point, in
/// the index's cell order.
pub(crate) struct CellAnswers<'i, T, W> {
    index: &'i CellIndex<'i>,
    wanted: W,
    answers: Vec<T>,
}

impl<'i, T: 'i, W: Fn(usize) -> bool + 'i> CellAnswers<'i, T, W> {
    /// Each wanted point's cloud index with its answer, in cell order: the
    /// wanted points found again by walking the cells as the query did.
    pub(crate) fn into_points(self) -> impl Iterator<Item = (usize, T)> + 'i {
        let CellAnswers { index, wanted, answers } = self;
        index.index_of.iter().map(|&i| i as usize).filter(move |&i| wanted(i)).zip(answers)
    }
}

/// Points of a cell whose distances [`CellIndex::visit_within`] computes
/// together.
const LANES_PER_TEST: usize = 16;

/// [`within_mask`] of the points `indices` of `points`: bit `l` set when
/// point `indices[l]` is within `radius_sq` of `p`, by the same arithmetic.
#[inline(always)]
fn within_mask_of(p: &Point, indices: &[u32], points: &[Point], radius_sq: f32) -> u32 {
    let mut mask = 0u32;
    for (lane, &j) in indices.iter().enumerate() {
        let q = &points[j as usize];
        let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
        mask |= ((dx * dx + dy * dy + dz * dz <= radius_sq) as u32) << lane;
    }
    mask
}

/// Bit `l` set when point `l` of the coordinate slices is within
/// `radius_sq` of `p`, by [`within`]'s arithmetic term for term (so the
/// same answer), written as a loop the compiler runs in vector lanes.
#[inline(always)]
fn within_mask(p: &Point, xs: &[f32], ys: &[f32], zs: &[f32], radius_sq: f32) -> u32 {
    let mut mask = 0u32;
    for (lane, ((&x, &y), &z)) in xs.iter().zip(ys).zip(zs).enumerate() {
        let (dx, dy, dz) = (p[0] - x, p[1] - y, p[2] - z);
        mask |= ((dx * dx + dy * dy + dz * dz <= radius_sq) as u32) << lane;
    }
    mask
}

/// The squared distance from `p` to a cell's box, in double precision:
/// every single-precision squared distance of a point inside the box is at
/// least this, less rounding, which the caller's reach leaves room for.
#[inline]
fn box_distance_sq(cell: &Cell, p: &Point) -> f64 {
    (0..3)
        .map(|axis| {
            let v = p[axis] as f64;
            let gap = (cell.min[axis] as f64 - v).max(v - cell.max[axis] as f64).max(0.0);
            gap * gap
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scattered(n: usize) -> Vec<Point> {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(
                |i| {
                    if i % 11 == 3 { [f32::NAN; 3] } else { [next() * 10.0 - 5.0, next() * 10.0, 500.0 + next() * 3.0] }
                },
            )
            .collect()
    }

    fn brute_force(points: &[Point], p: &Point, r_sq: f32) -> Vec<usize> {
        (0..points.len())
            .filter(|&j| {
                let q = points[j];
                let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r_sq
            })
            .collect()
    }

    #[test]
    fn queries_find_exactly_the_points_a_scan_finds() {
        for n in [0, 1, 2, 15, 100, 3000] {
            let points = scattered(n);
            for radius in [0.3f32, 0.8, 2.5] {
                let index = CellIndex::for_radius(&points, radius as f64);
                for p in points.iter().filter(|p| p[0].is_finite()).take(200) {
                    let r_sq = radius * radius;
                    let mut found = Vec::new();
                    index.visit_near(p, r_sq * (1.0 + 1e-5), |j, q| {
                        assert_eq!(*q, points[j]);
                        let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r_sq {
                            found.push(j);
                        }
                        ControlFlow::Continue(())
                    });
                    let mut within_order = Vec::new();
                    index.visit_within(p, r_sq, r_sq * (1.0 + 1e-5), |j| {
                        within_order.push(j);
                        ControlFlow::Continue(())
                    });
                    assert_eq!(within_order, found, "the same points in the same order");
                    found.sort_unstable();
                    assert_eq!(found, brute_force(&points, p, r_sq), "{n} points, radius {radius}");
                }
            }
        }
    }

    #[test]
    fn a_cells_candidates_give_each_point_the_visit_of_the_index() {
        for n in [0, 1, 2, 15, 100, 3000] {
            let points = scattered(n);
            for radius in [0.3f32, 0.8, 2.5] {
                let index = CellIndex::for_radius(&points, radius as f64);
                let r_sq = radius * radius;
                let reach = r_sq * (1.0 + 1e-5);
                let flag = |j: usize| j % 3 != 1;
                let answers = index.query_by_cell(
                    Vec::new,
                    |i| i % 5 != 2,
                    |flags, hood| hood.flags_into(flags, flag),
                    |flags, hood, i| {
                        let p = &points[i];
                        let mut order = Vec::new();
                        hood.visit_within(p, r_sq, |j| {
                            order.push(j);
                            ControlFlow::Continue(())
                        });
                        let caps = [0, 1, 5, 17, 40, u32::MAX];
                        let counts = caps.map(|cap| hood.count_up_to(p, r_sq, |j| j % 2 == 0, cap));
                        let flagged = caps.map(|cap| hood.count_flagged_up_to(p, r_sq, flags, cap));
                        let samples = [0, 1, 3, 16, 33, 70, 500].map(|stop| {
                            let mut sample = vec![u32::MAX; 20 + HOOD_LANES];
                            let seen = hood.sample_until(p, r_sq, &mut sample, stop);
                            sample.truncate(seen.min(20));
                            (seen, sample)
                        });
                        (order, counts, flagged, samples)
                    },
                );
                let answers: Vec<_> = answers.into_points().collect();
                let mut answered: Vec<usize> = answers.iter().map(|(i, _)| *i).collect();
                answered.sort_unstable();
                let wanted: Vec<usize> = (0..n).filter(|&i| i % 5 != 2 && points[i][0].is_finite()).collect();
                assert_eq!(answered, wanted, "every wanted valid point once");
                for (i, (order, counts, flagged, samples)) in answers {
                    let p = &points[i];
                    let mut expected = Vec::new();
                    index.visit_within(p, r_sq, reach, |j| {
                        expected.push(j);
                        ControlFlow::Continue(())
                    });
                    assert_eq!(order, expected, "point {i} of {n}, radius {radius}");
                    let caps = [0, 1, 5, 17, 40, u32::MAX];
                    let count_of =
                        |member: &dyn Fn(usize) -> bool| expected.iter().filter(|&&j| member(j)).count() as u32;
                    assert_eq!(counts, caps.map(|cap| count_of(&|j| j % 2 == 0).min(cap)), "counts");
                    assert_eq!(flagged, caps.map(|cap| count_of(&flag).min(cap)), "flagged counts");
                    for (stop, (seen, sample)) in [0, 1, 3, 16, 33, 70, 500].into_iter().zip(samples) {
                        let all = expected.len();
                        if stop == 0 {
                            assert_eq!(seen, 0);
                            continue;
                        }
                        assert!(seen >= stop.min(all) && seen <= all, "seen {seen} of {all}, stop {stop}");
                        let first: Vec<u32> = expected.iter().take(seen.min(20)).map(|&j| j as u32).collect();
                        assert_eq!(sample, first, "the sample is the visit's first, stop {stop}");
                    }
                }
            }
        }
    }

    #[test]
    fn counts_around_samples_are_exactly_what_a_scan_counts() {
        for n in [0, 1, 2, 15, 100, 3000] {
            let points = scattered(n);
            let samples: Vec<Point> = points.iter().filter(|p| p[0].is_finite()).take(300).copied().collect();
            for radius in [0.3f32, 0.8, 2.5] {
                let r_sq = radius * radius;
                let all: Vec<u32> = samples.iter().map(|p| brute_force(&points, p, r_sq).len() as u32).collect();
                assert_eq!(
                    counts_around(&points, &samples, radius as f64, u32::MAX, Deadline::NONE),
                    all,
                    "{n} points, {radius}"
                );
                for cap in [1, 3, 10] {
                    let capped: Vec<u32> = all.iter().map(|&c| c.min(cap)).collect();
                    assert_eq!(
                        counts_around(&points, &samples, radius as f64, cap, Deadline::NONE),
                        capped,
                        "cap {cap}"
                    );
                }
            }
        }
        // A sample off the cloud's points counts its neighbours, not
        // itself; far coordinates are clamped, not wrapped.
        let far = vec![[1.0e9f32, 0.0, 500.0], [-1.0e9, 0.0, 500.0], [0.0, 0.0, 500.0], [0.04, 0.0, 500.0]];
        assert_eq!(counts_around(&far, &[far[2], [0.0, 0.02, 500.0]], 0.05, u32::MAX, Deadline::NONE), vec![2, 2]);
        assert_eq!(counts_around(&far, &[far[0]], 0.05, u32::MAX, Deadline::NONE), vec![1], "clamped, not wrapped");
    }

    #[test]
    fn a_query_starts_in_its_own_cell_and_stops_when_told() {
        let mut points = vec![[0.1f32, 0.1, 500.1]; 20_000];
        points.push([0.9, 0.1, 500.1]);
        let index = CellIndex::for_radius(&points, 1.0);
        let mut visited = Vec::new();
        index.visit_near(&points[0], 1.0, |j, _| {
            visited.push(j);
            if visited.len() == 10 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        assert_eq!(visited, (0..10).collect::<Vec<_>>());
    }

    #[test]
    fn a_clump_out_of_reach_costs_one_box_test() {
        // 20,000 points 1.5 mm from a lone point, in the next cell.
        let mut points = vec![[1.9f32, 0.5, 500.5]; 20_000];
        points.push([0.4, 0.5, 500.5]);
        let index = CellIndex::for_radius(&points, 1.0);
        let mut candidates = 0;
        index.visit_near(&points[20_000], 1.0, |_, _| {
            candidates += 1;
            ControlFlow::Continue(())
        });
        assert_eq!(candidates, 1, "only the point itself");
        assert_eq!(index.cells.len(), 2);
    }

    #[test]
    fn far_coordinates_are_clamped_not_wrapped() {
        let points = vec![[1.0e9f32, 0.0, 500.0], [-1.0e9, 0.0, 500.0], [0.0, 0.0, 500.0]];
        let index = CellIndex::for_radius(&points, 0.05);
        let mut seen = 0;
        index.visit_near(&points[2], 0.0025, |_, _| {
            seen += 1;
            ControlFlow::Continue(())
        });
        assert_eq!(seen, 1);
    }
}
