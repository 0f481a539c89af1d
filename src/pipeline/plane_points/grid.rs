//! The plane criterion's fast classification on a pixel grid: the counts
//! run eight pixels at a time over the full plane's ellipse; a point whose
//! count there already reaches what it needs is a plane point (the exact
//! count can only be larger), and only the others are counted over the
//! whole exact window. The result is the reference's, point for point.
//!
//! What a point needs comes from the criterion ([`Threshold::needed`]);
//! [`BlockThreshold`] lets a criterion answer for a block of eight pixels
//! at once, which the robust one does with the kernels' lane forms of its
//! depth range, normal test and memo keys ([`kernels::depth_range`],
//! [`kernels::normal_test`], [`kernels::tile_keys`]).

use rayon::prelude::*;

use super::{PaperThreshold, PlanePoints, RobustThreshold, Threshold};
use crate::geometry::vec3;
use crate::kernels::{self, LaneMasks, NormalTest};
use crate::pipeline::grid_search::{Grid, LANES, Span, SpanRuns};
use crate::pipeline::neighbours::{FullCountCache, KeyMemo, NeighbourSearch, PixelEllipse};

/// [`Threshold::needed`] for a block of pixels of one row.
pub(super) trait BlockThreshold: Threshold {
    /// [`Threshold::needed`] for the `LANES` pixels from `(col, row)`, all
    /// inside the row, in integers, into `needs` (all rejected on entry).
    /// Filled in place: a block returned by value was copied out whole
    /// right after its lanes were written one by one, which stalls.
    fn needed_block(&self, grid: &Grid, row: usize, col: usize, memos: &mut Memos, needs: &mut BlockNeeds) {
        let first = row * grid.width() + col;
        needs.set_each(LANES, |l| self.needed(first + l, &mut memos.full));
    }
}

impl BlockThreshold for PaperThreshold<'_> {}

impl BlockThreshold for RobustThreshold<'_> {
    /// The normal test of eight lanes at once on the coordinate planes,
    /// for the lanes that have all four neighbours at their step (once per
    /// step when the block straddles a step boundary); any other lane, and
    /// a block near the image border, is tested lane by lane. Compiled for
    /// AVX2 where that is the level, so that the kernels it calls inline
    /// into it and their lanes stay in registers.
    fn needed_block(&self, grid: &Grid, row: usize, col: usize, memos: &mut Memos, needs: &mut BlockNeeds) {
        kernels::vectorised(
            #[inline(always)]
            || self.needed_block_on_lanes(grid, row, col, memos, needs),
        );
    }
}

/// What the lanes of a block need, in integers: a count is whole, so
/// `count >= t` is `count >= ceil(t)`. Plain arrays rather than options
/// of float pairs: building those lane by lane and reading them back whole
/// stalled on every lane.
#[derive(Debug, Clone, Copy)]
pub(super) struct BlockNeeds {
    /// The least neighbour count that makes the lane a plane point, or
    /// [`BlockNeeds::SKIP`] when it was rejected before counting.
    count: [u32; LANES],
    /// The full-plane count, saturated, recorded for the edge stage.
    full: [u16; LANES],
}

impl BlockNeeds {
    /// A lane rejected before counting.
    const SKIP: u32 = u32::MAX;
    /// A count no window reaches: the need of a lane whose threshold is
    /// beyond any count (or not a number).
    const NEVER: u32 = u32::MAX - 1;
    const REJECTED: BlockNeeds = BlockNeeds { count: [Self::SKIP; LANES], full: [0; LANES] };

    /// Records `needed(l)` for each of the first `lanes` lanes.
    #[inline(always)]
    fn set_each(&mut self, lanes: usize, mut needed: impl FnMut(usize) -> Option<(f64, f64)>) {
        for l in 0..lanes {
            self.set(l, needed(l));
        }
    }

    /// Records [`Threshold::needed`]'s answer for lane `l`.
    #[inline(always)]
    fn set(&mut self, l: usize, needed: Option<(f64, f64)>) {
        self.set_lane(l, LaneNeed::of(needed));
    }

    #[inline(always)]
    fn set_lane(&mut self, l: usize, need: LaneNeed) {
        self.count[l] = need.count;
        self.full[l] = need.full;
    }

    #[inline(always)]
    fn counted(&self, l: usize) -> bool {
        self.count[l] != Self::SKIP
    }
}

/// One lane of [`BlockNeeds`].
#[derive(Debug, Clone, Copy, Default)]
struct LaneNeed {
    count: u32,
    full: u16,
}

impl LaneNeed {
    /// [`Threshold::needed`]'s answer in integers.
    #[inline(always)]
    fn of(needed: Option<(f64, f64)>) -> LaneNeed {
        let Some((t, full)) = needed else { return LaneNeed { count: BlockNeeds::SKIP, full: 0 } };
        let count = if t <= 0.0 {
            0
        } else if t < BlockNeeds::NEVER as f64 {
            crate::geometry::ceil_i64(t) as u32
        } else {
            BlockNeeds::NEVER
        };
        LaneNeed { count, full: full.clamp(0.0, u16::MAX as f64) as u16 }
    }
}

impl RobustThreshold<'_> {
    /// The normal test of the criterion, as the kernels take it.
    #[inline(always)]
    fn normal_test(&self) -> NormalTest {
        let n = self.criterion.normal;
        NormalTest { reference: [n.x as f32, n.y as f32, n.z as f32], cos_sq: (self.cos_limit * self.cos_limit) as f32 }
    }

    /// [`BlockThreshold::needed_block`]'s body.
    #[inline(always)]
    fn needed_block_on_lanes(&self, grid: &Grid, row: usize, col: usize, memos: &mut Memos, needs: &mut BlockNeeds) {
        let (w, h) = (grid.width(), grid.height());
        let first = row * w + col;
        let centre = grid.lanes(first);
        let pz = &centre[2];
        // The step only falls as depth grows, so the nearest and farthest
        // lanes bound every valid lane's step; at most two steps occur
        // where a step boundary crosses the block.
        let (z_near, z_far) = kernels::depth_range(pz);
        let (step_near, step_far) = (self.steps.step(z_near), self.steps.step(z_far));
        let fits = col >= step_near && col + LANES - 1 + step_near < w && row >= step_near && row + step_near < h;
        // Only positive depths have a step table entry; all-invalid blocks
        // have no finite nearest depth.
        let positive = z_near > 0.0 && z_near.is_finite();
        if !(fits && positive) {
            needs.set_each(LANES, |l| self.needed_on_grid(grid, first + l, &mut memos.full));
            return;
        }
        // A block across a step boundary is rare: its second normal test
        // is kept out of line, off the common path.
        let test = self.normal_test();
        let mut facts = kernels::normal_test(grid.planes(), w, first, step_far, &test);
        if step_near != step_far {
            let near_lanes = lane_bits(|l| pz[l] < self.steps.depth_limit(step_near));
            Self::straddle(grid, first, step_near, near_lanes, &test, &mut facts);
        }
        // An invalid lane's step is 1 whatever its neighbours: it reads as
        // incomplete either way and takes the scalar path below.
        let LaneMasks { complete, facing } = facts;
        let mut incomplete = !complete & ((1 << LANES) - 1);
        while incomplete != 0 {
            // A missing neighbour: the one-sided rule, lane by lane.
            let l = incomplete.trailing_zeros() as usize;
            needs.set(l, self.needed_on_grid(grid, first + l, &mut memos.full));
            incomplete &= incomplete - 1;
        }
        let need_of = |key: u64, memos: &mut Memos| {
            memos.need.get_or_insert_with(key, || {
                LaneNeed::of(self.need_of_full(self.full_counts.value_of(key, &mut memos.full)))
            })
        };
        let mut open = complete & facing;
        if open == 0 {
            return;
        }
        let keys = self.full_counts.keys_of_lanes(&centre);
        if open == (1 << LANES) - 1 {
            // Inside a plate: a look-up per lane, whose hits are certain
            // enough to predict, where a loop over distinct keys was not.
            for (l, &key) in keys.iter().enumerate() {
                needs.set_lane(l, need_of(key, memos));
            }
            return;
        }
        // Neighbouring pixels mostly share a memo key, and so what they
        // need: one look-up per distinct key serves every lane that has it.
        while open != 0 {
            let key = keys[open.trailing_zeros() as usize];
            let need = need_of(key, memos);
            let take = lane_bits(|l| keys[l] == key) & open;
            for l in 0..LANES {
                if take >> l & 1 != 0 {
                    needs.set_lane(l, need);
                }
            }
            open &= !take;
        }
    }
}

/// Bit `l` set where `test(l)` holds, for the lanes of a block.
#[inline(always)]
fn lane_bits(test: impl Fn(usize) -> bool) -> u32 {
    (0..LANES).fold(0, |bits, l| bits | (test(l) as u32) << l)
}

impl RobustThreshold<'_> {
    /// Takes the normal test of the lanes in `near_lanes`, those of a block
    /// nearer than a step boundary, at their step `step_near`.
    #[cold]
    #[inline(never)]
    fn straddle(
        grid: &Grid,
        first: usize,
        step_near: usize,
        near_lanes: u32,
        test: &NormalTest,
        facts: &mut LaneMasks,
    ) {
        let near = kernels::normal_test(grid.planes(), grid.width(), first, step_near, test);
        facts.complete = (near.complete & near_lanes) | (facts.complete & !near_lanes);
        facts.facing = (near.facing & near_lanes) | (facts.facing & !near_lanes);
    }
}

/// Classifies every point of the cloud by `threshold`: on a pixel grid
/// block by block, elsewhere point by point with counts that stop at what
/// the point needs.
pub(super) fn classify<T: BlockThreshold>(search: &NeighbourSearch, threshold: &T) -> PlanePoints {
    let cloud = search.cloud();
    let n = cloud.len();
    let mut mask = vec![false; n];
    let mut counts = vec![0u16; n];
    let mut full = vec![0u16; n];
    let saturate = |v: f64| v.clamp(0.0, u16::MAX as f64) as u16;
    // Counting stops at the threshold: however dense the cloud, a point
    // costs at most that many neighbours, and the count kept is a lower
    // bound, as on the grid.
    let cap_of = |t: f64| LaneNeed::of(Some((t, 0.0))).count;
    // A point's mask, kept count and full count from what it needs and
    // its count.
    let decide = |answer: Option<(f64, f64, u32)>| match answer {
        Some((t, full_count, count)) => {
            let plane = count as f64 >= t;
            (plane, if plane { saturate(count as f64) } else { 0 }, saturate(full_count))
        }
        None => (false, 0, 0),
    };
    // Cells: each cell's candidates gathered once for all its points.
    let by_cell = search.query_by_cell(
        FullCountCache::default,
        |_| true,
        |_, _| {},
        |cache, i, neighbours| decide(threshold.needed_and_count_of(search, i, neighbours, cache, &cap_of)),
    );
    if let Some(answers) = by_cell {
        for (i, (m, c, f)) in answers.into_points() {
            (mask[i], counts[i], full[i]) = (m, c, f);
        }
        return PlanePoints { mask, counts, full };
    }
    if !cloud.is_organized() {
        // The tests' KD-tree: point by point.
        mask.par_iter_mut()
            .zip(counts.par_iter_mut())
            .zip(full.par_iter_mut())
            .enumerate()
            .for_each_init(FullCountCache::default, |cache, (i, ((m, c), f))| {
                (*m, *c, *f) = decide(threshold.needed_and_count(search, i, cache, &cap_of))
            });
        return PlanePoints { mask, counts, full };
    }
    let grid = Grid::new(cloud);
    let w = cloud.width();
    // One scratch per rayon job, not per row: the full-count memo then
    // serves the 32 rows of a tile instead of starting cold on each.
    mask.par_chunks_mut(w).zip(counts.par_chunks_mut(w)).zip(full.par_chunks_mut(w)).enumerate().for_each_init(
        Scratch::new,
        |scratch, (row, ((mask_row, count_row), full_row))| {
            scratch.spans_for = None;
            for col in (0..w).step_by(LANES) {
                let out =
                    BlockOut { mask: &mut mask_row[col..], counts: &mut count_row[col..], full: &mut full_row[col..] };
                classify_block(search, &grid, threshold, row, col, scratch, out);
            }
        },
    );
    PlanePoints { mask, counts, full }
}

/// Scratch space reused across the blocks of a row.
struct Scratch {
    /// The spans of the ellipse counted first, as runs on the grid.
    runs: SpanRuns,
    /// The union of a block's exact windows.
    window: Vec<Span>,
    /// Depth and column of the point the spans were made for.
    spans_for: Option<(f32, usize)>,
    memos: Memos,
    needs: BlockNeeds,
}

/// The memos of a rayon job: full-plane counts, and what a lane of each
/// memo key needs, which the block path reads without converting.
#[derive(Default)]
pub(super) struct Memos {
    full: FullCountCache,
    need: KeyMemo<LaneNeed>,
}

impl Scratch {
    fn new() -> Self {
        Scratch {
            runs: SpanRuns::default(),
            window: Vec::new(),
            spans_for: None,
            memos: Memos::default(),
            needs: BlockNeeds::REJECTED,
        }
    }

    /// True when the spans were made for a point close enough to `(z, col)`
    /// to serve it: the spans only choose where counting starts, so a
    /// slightly different ellipse costs at most a fallback count.
    fn spans_serve(&self, z: f32, col: usize) -> bool {
        self.spans_for.is_some_and(|(z0, c0)| (z - z0).abs() <= 0.02 * z0 && col < c0 + 512)
    }
}

/// Where a block's results go: slices starting at the block's first pixel.
struct BlockOut<'a> {
    mask: &'a mut [bool],
    counts: &'a mut [u16],
    full: &'a mut [u16],
}

/// Classifies up to `LANES` pixels of one row starting at `col`.
fn classify_block<T: BlockThreshold>(
    search: &NeighbourSearch,
    grid: &Grid,
    threshold: &T,
    row: usize,
    col: usize,
    scratch: &mut Scratch,
    out: BlockOut,
) {
    let w = grid.width();
    let lanes = LANES.min(w - col);
    let first = row * w + col;
    // The predicate's radius, squared in single precision as the KD-tree
    // path squares it.
    let radius_sq = (search.radius_mm() * search.radius_mm()) as f32;
    // Lane `l`'s exact window, where all its neighbours lie.
    let window_of = |l: usize| search.camera().neighbour_window(grid.point(first + l), search.radius_mm());
    scratch.needs = BlockNeeds::REJECTED;
    if lanes == LANES {
        threshold.needed_block(grid, row, col, &mut scratch.memos, &mut scratch.needs);
    } else {
        let cache = &mut scratch.memos.full;
        scratch.needs.set_each(lanes, |l| threshold.needed(first + l, cache));
    }
    let needs = &scratch.needs;
    let Some(anchor) = (0..lanes).find(|&l| needs.counted(l)) else { return };
    // The block's partial counts over the ellipse of its first candidate:
    // lower bounds for every lane. An interior point finds nearly all its
    // neighbours there; widening the ellipse for the few that noise moves
    // outside it cost a third more distances than the recounts it saved.
    let mut partial = [0u32; LANES];
    if lanes == LANES {
        let point = grid.point(first + anchor);
        if !scratch.spans_serve(point[2], col) {
            // An ellipse wider or taller than the image (a point far off
            // the axis, or a plane seen nearly edge-on) could never be
            // counted in it: its spans would only cost time and memory in
            // proportion to its size, which one corrupt point makes
            // unbounded. It gets no runs, as one seen edge-on gets none,
            // and so no partial count: the lanes are counted exactly.
            let ellipse =
                PixelEllipse::new(search.camera(), &vec3(&point), &threshold.plane_normal(), search.radius_mm())
                    .filter(|e| e.fits_grid(w, grid.height()));
            scratch.runs.prepare(w, |spans| ellipse.iter().for_each(|e| e.spans_into(spans)));
            scratch.spans_for = Some((point[2], col));
        }
        if let Some(counts) = grid.count_runs(col, row, &scratch.runs, radius_sq) {
            partial = counts;
        }
    }
    // A lane short of its threshold on the ellipse is counted again over
    // its whole exact window; the whole block at once when it can be.
    let short = (0..lanes).any(|l| needs.counted(l) && partial[l] < needs.count[l]);
    let mut exact: Option<[u32; LANES]> = None;
    if short && lanes == LANES {
        let windows = (0..lanes).filter(|&l| needs.counted(l)).map(window_of);
        let (wx, wy) = windows.fold((0, 0), |(a, b), (x, y)| (a.max(x), b.max(y)));
        let (wx, wy) = (wx as isize, wy as isize);
        // The union of the lanes' exact windows: counting over more pixels
        // than a lane's window still gives its exact count.
        // Rows beyond the top or bottom hold no neighbours, so leaving
        // them out keeps the count exact along those borders.
        let rows = (-wy).max(-(row as isize))..=wy.min((grid.height() - 1 - row) as isize);
        scratch.window.clear();
        scratch.window.extend(rows.map(|dv| Span { dv, du_lo: -wx, du_hi: wx }));
        if grid.spans_fit(col, row, &scratch.window) {
            exact = Some(grid.count_block(col, row, &scratch.window, radius_sq));
        }
    }
    for l in 0..lanes {
        if !needs.counted(l) {
            continue;
        }
        let need = needs.count[l];
        let count = match exact {
            _ if partial[l] >= need => partial[l],
            Some(counts) => counts[l],
            None => grid.count_window(first + l, window_of(l), radius_sq),
        };
        out.full[l] = needs.full[l];
        if count >= need {
            out.mask[l] = true;
            out.counts[l] = count.min(u16::MAX as u32) as u16;
        }
    }
}
