//! The candidates of one cell's points gathered once ([`Neighbourhood`]):
//! the queries that read every point of a cloud ([`CellIndex::query_by_cell`])
//! test each point of a cell against the same arrays, laid out for vector
//! lanes, rather than walking the cell index once per point.

use std::ops::ControlFlow;

use crate::cloud::Point;

use super::{CellIndex, within_mask};

/// The candidate neighbours of the points of one cell: the points of its
/// occupied neighbour cells, concatenated in the order
/// [`CellIndex::visit_within`] reads them (the cell itself first, then its
/// neighbourhood list, each cell's points in cell order), one array per
/// axis, ending in padding no point is ever near. Every neighbour of a
/// point of the cell is among them, and filtering them by [`within`](crate::kernels::within)
/// gives the point's neighbours in `visit_within`'s order: that visit
/// only skips whole cells holding no neighbour.
#[derive(Default)]
pub(crate) struct Neighbourhood {
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    index_of: Vec<u32>,
}

impl Neighbourhood {
    /// Fills this with the candidates of the points of cell `c`.
    pub(super) fn gather(&mut self, index: &CellIndex, c: usize) {
        let (xs, ys, zs, index_of) = (&mut self.xs, &mut self.ys, &mut self.zs, &mut self.index_of);
        index_of.clear();
        let around = index.neighbour_start[c] as usize..index.neighbour_start[c + 1] as usize;
        for &n in &index.neighbour_cells[around] {
            let cell = &index.cells[n as usize];
            index_of.extend_from_slice(&index.index_of[cell.start as usize..cell.end as usize]);
        }
        // Whole blocks: the padding's distance from any finite point is
        // infinite, so never within a radius.
        let padded = index_of.len().next_multiple_of(HOOD_LANES);
        for v in [&mut *xs, &mut *ys, &mut *zs] {
            v.clear();
            v.resize(padded, f32::INFINITY);
        }
        for (((x, y), z), &j) in xs.iter_mut().zip(ys.iter_mut()).zip(zs.iter_mut()).zip(index_of.iter()) {
            [*x, *y, *z] = index.points[j as usize];
        }
        index_of.resize(padded, 0);
    }

    /// One bit per candidate, `flag(j)` of candidate `j`, as
    /// [`Neighbourhood::count_flagged_up_to`] reads them, into `bits`.
    pub(crate) fn flags_into(&self, bits: &mut Vec<u32>, flag: impl Fn(usize) -> bool) {
        bits.clear();
        bits.extend(
            self.index_of.chunks(HOOD_LANES).map(|block| {
                block.iter().enumerate().fold(0u32, |b, (lane, &j)| b | ((flag(j as usize) as u32) << lane))
            }),
        );
    }

    /// [`Neighbourhood::count_up_to`] of the candidates whose bit is set
    /// in `flags` ([`Neighbourhood::flags_into`]).
    #[inline(always)]
    pub(crate) fn count_flagged_up_to(&self, p: &Point, radius_sq: f32, flags: &[u32], cap: u32) -> u32 {
        if cap == 0 {
            return 0;
        }
        let mut n = 0;
        for ((_, inside), &flagged) in self.masks(p, radius_sq).zip(flags) {
            n += (inside & flagged).count_ones();
            if n >= cap {
                return cap;
            }
        }
        n
    }

    /// The blocks of candidates, each with the mask of its lanes within
    /// `radius_sq` of `p` by the kernels' predicate ([`within`](crate::kernels::within)).
    #[inline(always)]
    fn masks<'s>(&'s self, p: &'s Point, radius_sq: f32) -> impl Iterator<Item = (usize, u32)> + 's {
        let blocks = |axis: &'s [f32]| axis.as_chunks::<HOOD_LANES>().0;
        let (xs, ys, zs) = (blocks(&self.xs), blocks(&self.ys), blocks(&self.zs));
        xs.iter()
            .zip(ys)
            .zip(zs)
            .enumerate()
            .map(move |(b, ((x, y), z))| (b * HOOD_LANES, within_mask(p, x, y, z, radius_sq)))
    }

    /// Calls `visit(j)` for every candidate `j` within `radius_sq` of `p`
    /// by the kernels' predicate ([`within`](crate::kernels::within)), in order, until it breaks:
    /// for a point of the cell, [`CellIndex::visit_within`]'s visits.
    #[inline(always)]
    pub(crate) fn visit_within(&self, p: &Point, radius_sq: f32, mut visit: impl FnMut(usize) -> ControlFlow<()>) {
        for (first, mut inside) in self.masks(p, radius_sq) {
            while inside != 0 {
                let lane = inside.trailing_zeros() as usize;
                inside &= inside - 1;
                if visit(self.index_of[first + lane] as usize).is_break() {
                    return;
                }
            }
        }
    }

    /// [`crate::pipeline::neighbours::VisitNeighbours::sample_until`] of `p`'s neighbours: each
    /// block's lanes within `radius_sq` stored in order without a branch
    /// per lane (a block is stored whole, hence the slack), the rest only
    /// counted.
    #[inline(always)]
    pub(crate) fn sample_until(&self, p: &Point, radius_sq: f32, sample: &mut [u32], stop: usize) -> usize {
        let room = sample.len().saturating_sub(HOOD_LANES);
        let mut seen = 0usize;
        if stop == 0 {
            return 0;
        }
        for (first, inside) in self.masks(p, radius_sq) {
            if inside == 0 {
                continue;
            }
            if seen < room {
                let slots = &mut sample[seen..seen + HOOD_LANES];
                let mut at = 0;
                for (lane, &j) in self.index_of[first..first + HOOD_LANES].iter().enumerate() {
                    slots[at] = j;
                    at += ((inside >> lane) & 1) as usize;
                }
            }
            seen += inside.count_ones() as usize;
            if seen >= stop {
                return seen;
            }
        }
        seen
    }

    /// The number of candidates within `radius_sq` of `p` for which
    /// `member` holds, read up to `cap` (as
    /// [`crate::pipeline::neighbours::NeighbourSearch::count_up_to`] reads it): the count does
    /// not depend on the order, so a block is counted whole before the cap
    /// is checked.
    #[inline(always)]
    pub(crate) fn count_up_to(&self, p: &Point, radius_sq: f32, member: impl Fn(usize) -> bool, cap: u32) -> u32 {
        if cap == 0 {
            return 0;
        }
        let mut n = 0;
        for (first, mut inside) in self.masks(p, radius_sq) {
            while inside != 0 {
                let lane = inside.trailing_zeros() as usize;
                inside &= inside - 1;
                n += member(self.index_of[first + lane] as usize) as u32;
            }
            if n >= cap {
                return cap;
            }
        }
        n
    }
}

/// Candidates of a [`Neighbourhood`] tested together: a fixed block the
/// compiler lays out in vector lanes.
pub(crate) const HOOD_LANES: usize = 16;
