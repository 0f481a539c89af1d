//! Radius neighbour counts, the measurement behind the plane and edge
//! criteria (Eq. 14 and 15), and the count a full plane would give.
//!
//! Organized frames are searched on the pixel grid: every 3D neighbour
//! within R of a pixel's point lies inside a small image window around the
//! pixel ([`CameraModel::neighbour_window`]), so scanning that window gives
//! exactly the count a KD-tree query would. Unorganized clouds use cells as
//! wide as the radius ([`cells`]), whose queries stop as soon as the caller
//! has what it needs (a count up to its threshold, a bounded sample for a
//! normal), so no density makes a point cost more than that. A kiddo KD-tree that reads every neighbour
//! serves as the reference both paths are tested against.

pub(crate) mod cells;

use std::ops::ControlFlow;

#[cfg(test)]
use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::camera::CameraModel;
use crate::cloud::{Point, PointCloud};
use crate::geometry::{Vec3, ceil_i64, floor_i64};

use super::grid_search::{LANES, Span};
use super::scale::DensityMap;
use crate::kernels::{self, TileScales, within};
pub(crate) use cells::Neighbourhood;
use cells::{CellAnswers, CellIndex};

/// The most neighbours of one point a sampled visit reads: more than any
/// frame of the paper's camera gives within its field of view at its
/// nearest depth, far less than a cloud a thousand times denser.
pub(crate) const MAX_SAMPLED_NEIGHBOURS: usize = 4096;

/// Finds the neighbours of cloud points within a fixed radius.
// Public only because orientation's public functions take it.
pub struct NeighbourSearch<'a> {
    cloud: &'a PointCloud,
    camera: &'a CameraModel,
    radius: f32,
    radius_sq: f32,
    index: Index<'a>,
    /// The full-plane counts measured from the cloud itself, when they
    /// replace the camera's ([`super::scale`]).
    measured: Option<DensityMap>,
}

/// How the neighbours of a point are found.
enum Index<'a> {
    /// An organized cloud: its pixel window.
    Grid,
    /// An unorganized cloud: cells as wide as the radius, whose queries
    /// stop early.
    Cells(CellIndex<'a>),
    /// The kiddo KD-tree of the reference search.
    #[cfg(test)]
    KdTree(KdIndex),
}

#[cfg(test)]
struct KdIndex {
    tree: ImmutableKdTree<f32, 3>,
    /// Tree item → cloud point index.
    point_of_item: Vec<u32>,
}

impl<'a> NeighbourSearch<'a> {
    /// Prepares a search with radius `radius_mm`: the pixel grid of an
    /// organized cloud, else cells of its points.
    pub(crate) fn new(cloud: &'a PointCloud, camera: &'a CameraModel, radius_mm: f64) -> Self {
        let radius = radius_mm as f32;
        let index = if cloud.is_organized() {
            Index::Grid
        } else {
            Index::Cells(CellIndex::for_radius(cloud.points(), radius_mm))
        };
        NeighbourSearch { cloud, camera, radius, radius_sq: radius * radius, index, measured: None }
    }

    /// The full-plane counts of this search measured from its cloud rather
    /// than predicted from the camera.
    pub(crate) fn measure_full_counts(&mut self) -> Option<&DensityMap> {
        self.measured = DensityMap::measure(self);
        self.measured.as_ref()
    }

    /// The measured full-plane counts, if this search uses them.
    pub(crate) fn measured(&self) -> Option<&DensityMap> {
        self.measured.as_ref()
    }

    /// The surface a point at `p` with unit normal `n` stands for, mm²:
    /// measured, or one pixel's footprint on the tilted plane.
    pub(crate) fn area_per_point(&self, p: &Vec3, n: &Vec3) -> f64 {
        match &self.measured {
            Some(map) => map.area_per_point_at(&[p.x as f32, p.y as f32, p.z as f32]),
            None => 1.0 / self.camera.plane_density_at(p, n),
        }
    }

    /// A search that always queries a kiddo KD-tree for every neighbour,
    /// even on a pixel grid: the straightforward reference the grid and
    /// tree paths are tested against.
    #[cfg(test)]
    pub(crate) fn kdtree(cloud: &'a PointCloud, camera: &'a CameraModel, radius_mm: f64) -> Self {
        let radius = radius_mm as f32;
        let index = Index::KdTree(build_tree(cloud.points()));
        NeighbourSearch { cloud, camera, radius, radius_sq: radius * radius, index, measured: None }
    }

    pub(crate) fn cloud(&self) -> &PointCloud {
        self.cloud
    }

    pub(crate) fn camera(&self) -> &CameraModel {
        self.camera
    }

    pub(crate) fn radius_mm(&self) -> f64 {
        self.radius as f64
    }

    /// Calls `visit(j)` for every valid point `j` within the radius of
    /// point `i` (including `i` itself). `i` must be valid.
    pub(crate) fn for_each(&self, i: usize, mut visit: impl FnMut(usize)) {
        self.visit_until(i, |j| {
            visit(j);
            ControlFlow::Continue(())
        });
    }

    /// [`NeighbourSearch::for_each`] until `visit` breaks. On a pixel grid
    /// the window bounds the work; in cells the break does, which is what
    /// keeps a cloud far denser than any camera's from costing the whole
    /// cloud per point.
    #[inline]
    pub(crate) fn visit_until(&self, i: usize, mut visit: impl FnMut(usize) -> ControlFlow<()>) {
        let points = self.cloud.points();
        let p = &points[i];
        match &self.index {
            Index::Grid => {
                let w = self.cloud.width();
                let (col, row) = (i % w, i / w);
                let (wx, wy) = self.camera.neighbour_window(*p, self.radius as f64);
                let (c0, c1) = (col.saturating_sub(wx), col.saturating_add(wx).min(w - 1));
                let (r0, r1) = (row.saturating_sub(wy), row.saturating_add(wy).min(self.cloud.height() - 1));
                for r in r0..=r1 {
                    let line = &points[r * w..(r + 1) * w];
                    for (c, q) in line.iter().enumerate().take(c1 + 1).skip(c0) {
                        // NaN compares false, so invalid pixels never count.
                        if within(p, q, self.radius_sq) && visit(r * w + c).is_break() {
                            return;
                        }
                    }
                }
            }
            Index::Cells(cells) => {
                // The cells give candidates; the shared predicate decides.
                cells.visit_within(p, self.radius_sq, self.radius_sq * (1.0 + 1e-5), visit);
            }
            #[cfg(test)]
            Index::KdTree(index) => {
                let reach = self.radius_sq * (1.0 + 1e-5);
                let found = index.tree.query(p).within::<SquaredEuclidean<f32>>(reach).unsorted().execute();
                for hit in found {
                    let j = index.point_of_item[hit.item as usize] as usize;
                    if within(p, &points[j], self.radius_sq) && visit(j).is_break() {
                        return;
                    }
                }
            }
        }
    }

    /// Number of valid points within the radius of point `i` for which
    /// `member(j)` holds.
    #[cfg(test)]
    pub(crate) fn count(&self, i: usize, member: impl Fn(usize) -> bool) -> u32 {
        let mut n = 0;
        self.for_each(i, |j| n += member(j) as u32);
        n
    }

    /// `count` (the tests' reference) when it is below `cap`, else `cap`: a
    /// criterion comparing the count with a threshold needs no more, and
    /// stops there.
    #[inline]
    pub(crate) fn count_up_to(&self, i: usize, member: impl Fn(usize) -> bool, cap: u32) -> u32 {
        let mut n = 0;
        if cap == 0 {
            return 0;
        }
        self.visit_until(i, |j| {
            n += member(j) as u32;
            if n >= cap { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        n
    }

    /// The most neighbours point `p` can have in a frame of the configured
    /// camera: one per pixel of its window, which holds every pixel whose
    /// ray passes within the radius of `p`. A denser cloud is not this
    /// camera's frame; its neighbourhoods are sampled rather than read
    /// whole (see [`NeighbourSearch::for_each_sampled`]).
    pub(crate) fn frame_neighbours_at_most(&self, p: &Point) -> usize {
        let (wx, wy) = self.camera.neighbour_window(*p, self.radius as f64);
        let side = |w: usize| w.saturating_mul(2).saturating_add(1);
        side(wx).saturating_mul(side(wy)).min(MAX_SAMPLED_NEIGHBOURS)
    }

    /// Calls `visit(j)` for the neighbours of point `i`, up to `at_most` of
    /// them and never more than [`NeighbourSearch::frame_neighbours_at_most`]:
    /// a bounded sample of the neighbours of a point however dense the
    /// cloud.
    pub(crate) fn for_each_sampled(&self, i: usize, at_most: usize, mut visit: impl FnMut(usize)) {
        let cap = self.frame_neighbours_at_most(&self.cloud.points()[i]).min(at_most);
        let mut n = 0;
        self.visit_until(i, |j| {
            visit(j);
            n += 1;
            if n >= cap { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
    }
}

impl NeighbourSearch<'_> {
    /// For a cloud without a pixel grid, `query(state, i, neighbours)` of
    /// every valid point `i` for which `wanted(i)` holds (after
    /// `prepare(state, candidates)` of its cell), with its
    /// neighbours read from candidates gathered once per cell
    /// ([`CellIndex::query_by_cell`]): the same neighbours in the same
    /// order as [`NeighbourSearch::visit_until`], for less work when every
    /// point is queried. The answers come in the cells' order, each point's
    /// index found again as they are read ([`CellAnswers::into_points`]);
    /// `None` on a pixel grid, which is searched by window.
    pub(crate) fn query_by_cell<S, T: Send + Clone + Default, W: Fn(usize) -> bool + Sync>(
        &self,
        init: impl Fn() -> S + Sync,
        wanted: W,
        prepare: impl Fn(&mut S, &Neighbourhood) + Sync,
        query: impl Fn(&mut S, usize, &PointNeighbours) -> T + Sync,
    ) -> Option<CellAnswers<'_, T, W>> {
        let Index::Cells(cells) = &self.index else { return None };
        let points = self.cloud.points();
        Some(cells.query_by_cell(init, wanted, prepare, |state, hood, i| {
            query(state, i, &PointNeighbours { hood, p: points[i], radius_sq: self.radius_sq })
        }))
    }
}

/// How the neighbours of one point are read: through the search, or from
/// its cell's gathered candidates. Both give the same neighbours in the
/// same order.
pub(crate) trait VisitNeighbours {
    /// Calls `visit(j)` for every neighbour `j` of the point, in the
    /// search's order, until it breaks.
    fn visit_until(&self, visit: impl FnMut(usize) -> ControlFlow<()>);

    /// The number of neighbours `j` with `member(j)`, read up to `cap`:
    /// [`NeighbourSearch::count_up_to`].
    fn count_up_to(&self, member: impl Fn(usize) -> bool, cap: u32) -> u32;

    /// The first neighbours, in order, into `sample` (as many as it
    /// holds, less [`SAMPLE_SLACK`]), reading until `stop` of them are
    /// seen; returns how many were seen, at least `stop` when the visit
    /// stopped there. The slots past the sample's may hold anything.
    #[inline(always)]
    fn sample_until(&self, sample: &mut [u32], stop: usize) -> usize {
        let room = sample.len().saturating_sub(SAMPLE_SLACK);
        let mut seen = 0usize;
        if stop > 0 {
            self.visit_until(|j| {
                if seen < room {
                    sample[seen] = j as u32;
                }
                seen += 1;
                if seen >= stop { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            });
        }
        seen
    }
}

/// Slots a sample buffer of [`VisitNeighbours::sample_until`] needs past
/// the sample itself: a block of candidates is stored whole.
pub(crate) const SAMPLE_SLACK: usize = cells::HOOD_LANES;

/// Point `i` of a search: its neighbours as the search finds them.
pub(crate) struct SearchedPoint<'s, 'a>(pub &'s NeighbourSearch<'a>, pub usize);

impl VisitNeighbours for SearchedPoint<'_, '_> {
    #[inline(always)]
    fn visit_until(&self, visit: impl FnMut(usize) -> ControlFlow<()>) {
        self.0.visit_until(self.1, visit);
    }

    #[inline(always)]
    fn count_up_to(&self, member: impl Fn(usize) -> bool, cap: u32) -> u32 {
        self.0.count_up_to(self.1, member, cap)
    }
}

/// A point's neighbours read from its cell's candidates
/// ([`NeighbourSearch::query_by_cell`]).
pub(crate) struct PointNeighbours<'h> {
    hood: &'h Neighbourhood,
    p: Point,
    radius_sq: f32,
}

impl PointNeighbours<'_> {
    /// The number of neighbours whose candidate bit is set in `flags`
    /// (made by [`Neighbourhood::flags_into`] from this point's cell's
    /// candidates), read up to `cap`.
    #[inline(always)]
    pub(crate) fn count_flagged_up_to(&self, flags: &[u32], cap: u32) -> u32 {
        self.hood.count_flagged_up_to(&self.p, self.radius_sq, flags, cap)
    }
}

impl VisitNeighbours for PointNeighbours<'_> {
    #[inline(always)]
    fn visit_until(&self, visit: impl FnMut(usize) -> ControlFlow<()>) {
        self.hood.visit_within(&self.p, self.radius_sq, visit);
    }

    #[inline(always)]
    fn count_up_to(&self, member: impl Fn(usize) -> bool, cap: u32) -> u32 {
        self.hood.count_up_to(&self.p, self.radius_sq, member, cap)
    }

    #[inline(always)]
    fn sample_until(&self, sample: &mut [u32], stop: usize) -> usize {
        self.hood.sample_until(&self.p, self.radius_sq, sample, stop)
    }
}

/// Side of the image tiles over which the full-plane count is shared.
pub(crate) const FULL_COUNT_TILE_PX: usize = 32;
/// Depth step over which the full-plane count is shared, mm.
pub(crate) const FULL_COUNT_DEPTH_STEP_MM: f64 = 0.5;

/// Full-plane counts for one plane orientation.
///
/// On a grid the count for a point is the lattice count of the plane's
/// ellipse at the centre of the point's 32 x 32 pixel tile (binned by its
/// viewing direction, so a cropped frame gets the counts of the full one)
/// and at its depth rounded to 0.5 mm. Across a tile and half a millimetre
/// the ellipse changes by about a thousandth, so this is the pixel's own
/// lattice count give or take one lattice point; in exchange it is computed
/// once per tile and depth step instead of once per pixel. Without a grid
/// it is `π R² D` with the exact pinhole density. When the search measured
/// its full counts from the cloud ([`super::scale::DensityMap`]), those
/// replace the camera's: on a grid, the measured count at the tile's
/// centre and depth step.
pub(crate) struct FullCounts<'a> {
    cloud: &'a PointCloud,
    camera: &'a CameraModel,
    measured: Option<&'a DensityMap>,
    normal: Vec3,
    radius: f64,
    /// Tiles per unit of `x / z` and of `y / z`, depth steps per mm.
    scales: TileScales,
    /// A tile's extent in `x / z` and `y / z`.
    tile_x: f64,
    tile_y: f64,
}

/// Memo slots: a row of a tilted 1920-pixel frame crosses some 60 tiles
/// and two to four depth steps in each, and the rows of a tile reuse the
/// same keys, so a few hundred live keys must fit without evicting each
/// other.
const CACHE_SLOTS: usize = 1024;

/// A per-thread memo of values keyed by full-count memo key (tile and
/// depth step, see [`FullCounts::keys_of_lanes`]); a collision only costs
/// a recomputation.
pub(crate) struct KeyMemo<V> {
    slots: Box<[(u64, V); CACHE_SLOTS]>,
}

impl<V: Copy + Default> Default for KeyMemo<V> {
    fn default() -> Self {
        // No key is all ones: that would take a depth step of -1.
        KeyMemo { slots: Box::new([(u64::MAX, V::default()); CACHE_SLOTS]) }
    }
}

impl<V: Copy> KeyMemo<V> {
    /// The value of `key`, from the memo or from `compute`.
    #[inline(always)]
    pub(crate) fn get_or_insert_with(&mut self, key: u64, compute: impl FnOnce() -> V) -> V {
        let slot = (key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (64 - CACHE_SLOTS.trailing_zeros())) as usize;
        let (held, value) = self.slots[slot];
        if held == key {
            return value;
        }
        let value = compute();
        self.slots[slot] = (key, value);
        value
    }
}

/// The memo of full-plane counts.
pub(crate) type FullCountCache = KeyMemo<f64>;

impl<'a> FullCounts<'a> {
    pub(crate) fn new(search: &'a NeighbourSearch<'a>, normal: &Vec3) -> Self {
        let tile = FULL_COUNT_TILE_PX as f64;
        FullCounts {
            cloud: search.cloud,
            camera: search.camera,
            measured: search.measured.as_ref(),
            normal: *normal,
            radius: search.radius as f64,
            scales: TileScales {
                tiles_per_x: (search.camera.fx() / tile) as f32,
                tiles_per_y: (search.camera.fy() / tile) as f32,
                steps_per_mm: 1.0 / FULL_COUNT_DEPTH_STEP_MM as f32,
            },
            tile_x: tile / search.camera.fx(),
            tile_y: tile / search.camera.fy(),
        }
    }

    /// The memo key of a valid grid point: its tile and depth step
    /// ([`kernels::tile_key`], with which every path computes it).
    #[inline(always)]
    fn key(&self, p: &Point) -> u64 {
        kernels::tile_key(p, &self.scales)
    }

    /// The full-plane count of the points with memo key `key` (from
    /// [`FullCounts::keys_of_lanes`]), from the memo or computed.
    #[inline]
    pub(crate) fn value_of(&self, key: u64, cache: &mut FullCountCache) -> f64 {
        cache.get_or_insert_with(key, || self.count_of_key(key))
    }

    /// The full-plane count of memo key `key`, computed: the lattice count
    /// at the centre of its tile and depth step.
    fn count_of_key(&self, key: u64) -> f64 {
        let tile_row = (key >> 48) as u16 as i16 as f64;
        let tile_col = (key >> 32) as u16 as i16 as f64;
        let depth_step = key as u32 as i32 as f64;
        let ray = Vec3::new((tile_col + 0.5) * self.tile_x, (tile_row + 0.5) * self.tile_y, 1.0);
        let centre = ray * (depth_step * FULL_COUNT_DEPTH_STEP_MM);
        match self.measured {
            Some(map) => map.full_count_at(&[centre.x as f32, centre.y as f32, centre.z as f32]),
            None => lattice_count_in_ellipse(self.camera, &centre, &self.normal, self.radius),
        }
    }

    /// The full-plane count of point `i`, which must be valid.
    pub(crate) fn get(&self, i: usize, cache: &mut FullCountCache) -> f64 {
        self.get_point(&self.cloud.points()[i], cache)
    }

    /// [`FullCounts::get`] of a valid point of this cloud, given by value.
    #[inline]
    pub(crate) fn get_point(&self, p: &Point, cache: &mut FullCountCache) -> f64 {
        let p = *p;
        if !self.cloud.is_organized() {
            if let Some(map) = self.measured {
                return map.full_count_at(&p);
            }
            let n = &self.normal;
            let density = self.camera.plane_density_at(&Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64), n);
            return std::f64::consts::PI * self.radius * self.radius * density;
        }
        self.value_of(self.key(&p), cache)
    }

    /// The memo keys of `LANES` valid grid points given as coordinate
    /// lanes ([`kernels::tile_keys`]).
    #[inline(always)]
    pub(crate) fn keys_of_lanes(&self, lanes: &[[f32; LANES]; 3]) -> [u64; LANES] {
        kernels::tile_keys(lanes, &self.scales)
    }

    /// The tile and depth scales of the memo keys, for tests that compute
    /// keys through the kernels directly.
    #[cfg(test)]
    pub(crate) fn scales(&self) -> TileScales {
        self.scales
    }
}

#[cfg(test)]
fn build_tree(points: &[Point]) -> KdIndex {
    let mut coords = Vec::with_capacity(points.len());
    let mut point_of_item = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        if p[0].is_finite() {
            coords.push(*p);
            point_of_item.push(i as u32);
        }
    }
    let tree = ImmutableKdTree::new_from_slice(&coords).unwrap_or_else(|_| {
        // Only an empty slice fails; an empty tree answers every query with nothing.
        ImmutableKdTree::new_from_slice(&[[f32::MAX; 3]]).expect("a one-point tree always builds")
    });
    KdIndex { tree, point_of_item }
}

/// The most rows either side of its centre an ellipse is counted over
/// lattice point by lattice point: some three hundred times the rows a
/// 1 mm disc covers at 100 mm with the paper's camera, and more than a
/// sensor has.
pub(crate) const MAX_LATTICE_ROWS: i64 = 1 << 13;

/// The image, in pixel offsets, of the disc of radius R around a point on
/// a plane: near `p` the plane maps pixel offsets linearly to 3D
/// displacements, `d ≈ J (du, dv)`, so the offsets within the radius are
/// the lattice points inside the ellipse `(du, dv)ᵀ JᵀJ (du, dv) <= R²`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PixelEllipse {
    a: f64,
    b: f64,
    c: f64,
    det: f64,
    radius_sq: f64,
}

impl PixelEllipse {
    /// The ellipse of the plane through `p` with unit normal `n`; `None`
    /// when the plane is seen edge-on.
    pub(crate) fn new(camera: &CameraModel, p: &Vec3, n: &Vec3, radius: f64) -> Option<PixelEllipse> {
        let z = p.z;
        let ray = Vec3::new(p.x / z, p.y / z, 1.0);
        let n_dot_ray = n.dot(&ray);
        if n_dot_ray.abs() < 1e-6 {
            return None;
        }
        // ∂q/∂u and ∂q/∂v of q(u, v) = (n·p)/(n·r(u, v)) r(u, v) at p.
        let eu = Vec3::new(1.0 / camera.fx(), 0.0, 0.0);
        let ev = Vec3::new(0.0, 1.0 / camera.fy(), 0.0);
        let ju = (eu - ray * (n.dot(&eu) / n_dot_ray)) * z;
        let jv = (ev - ray * (n.dot(&ev) / n_dot_ray)) * z;
        let (a, b, c) = (ju.dot(&ju), ju.dot(&jv), jv.dot(&jv));
        let det = a * c - b * b;
        (det > 0.0).then_some(PixelEllipse { a, b, c, det, radius_sq: radius * radius })
    }

    /// The largest row offset inside the ellipse. Huge (saturated) for a
    /// plane seen nearly edge-on, where the ellipse is a needle.
    fn dv_max(&self) -> i64 {
        (self.radius_sq * self.a / self.det).sqrt().floor() as i64
    }

    /// The largest column offset inside the ellipse.
    fn du_max(&self) -> i64 {
        (self.radius_sq * self.c / self.det).sqrt().floor() as i64
    }

    /// True when the ellipse's offsets stay within `width x height`
    /// pixels of its centre, so some pixel of such a grid could have all
    /// of them in the image: spans of a larger ellipse could never be
    /// counted on it.
    pub(crate) fn fits_grid(&self, width: usize, height: usize) -> bool {
        let below = |extent: i64, size: usize| extent >= 0 && (extent as u64) < size as u64;
        below(self.dv_max(), height) && below(self.du_max(), width)
    }

    /// The real `du` interval of row `dv` inside the ellipse.
    fn row(&self, dv: i64) -> Option<(f64, f64)> {
        let dv = dv as f64;
        let disc = self.b * self.b * dv * dv - self.a * (self.c * dv * dv - self.radius_sq);
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        Some(((-self.b * dv - s) / self.a, (-self.b * dv + s) / self.a))
    }

    /// The number of pixel offsets inside the ellipse: what a pixel grid
    /// really gives, where `π R² D` can be 15 % off.
    ///
    /// An ellipse taller than [`MAX_LATTICE_ROWS`] (a plane seen within a
    /// fraction of a degree of edge-on, or a point far outside any field
    /// of view) is counted by its area, `π R² / sqrt(det)`, instead: no
    /// camera's frame holds such an ellipse, and counting it row by row
    /// would take time in proportion to its length, which has no bound.
    pub(crate) fn lattice_count(&self) -> f64 {
        // The ellipse is centred: row -dv holds the mirror image of row dv,
        // so the same number of lattice points.
        let dv_max = self.dv_max();
        if !(0..=MAX_LATTICE_ROWS).contains(&dv_max) {
            return std::f64::consts::PI * self.radius_sq / self.det.sqrt();
        }
        let mut count = 0i64;
        for dv in 0..=dv_max {
            if let Some((lo, hi)) = self.row(dv) {
                let row = (floor_i64(hi) - ceil_i64(lo) + 1).max(0);
                count += if dv == 0 { row } else { 2 * row };
            }
        }
        count as f64
    }

    /// Fills `out` with the row spans of the lattice points inside the
    /// ellipse: where most of a plane point's neighbours lie. Noise moves a
    /// few across the rim either way, so a count over the spans is only a
    /// lower bound of the exact one.
    pub(crate) fn spans_into(&self, out: &mut Vec<Span>) {
        out.clear();
        let dv_max = self.dv_max() as isize;
        for dv in -dv_max..=dv_max {
            if let Some((lo, hi)) = self.row(dv as i64) {
                let (du_lo, du_hi) = (ceil_i64(lo) as isize, floor_i64(hi) as isize);
                if du_lo <= du_hi {
                    out.push(Span { dv, du_lo, du_hi });
                }
            }
        }
    }
}

/// The lattice count of a complete plane with normal `n` through `p`
/// within `radius` (see [`PixelEllipse`]); 0 for a plane seen edge-on.
pub(crate) fn lattice_count_in_ellipse(camera: &CameraModel, p: &Vec3, n: &Vec3, radius: f64) -> f64 {
    PixelEllipse::new(camera, p, n, radius).map_or(0.0, |e| e.lattice_count())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frontal plane at depth z sampled by the camera, with an optional
    /// hole of invalid pixels for columns >= `cut`.
    fn plane_cloud(camera: &CameraModel, w: usize, h: usize, z: f64, n: Vec3, cut: usize) -> PointCloud {
        let mut pts = Vec::with_capacity(w * h);
        let (u0, v0) = (camera.cx() - w as f64 / 2.0, camera.cy() - h as f64 / 2.0);
        let anchor = Vec3::new(0.0, 0.0, z);
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(u0 + col as f64, v0 + row as f64);
                let r = Vec3::new(r[0], r[1], r[2]);
                let t = n.dot(&anchor) / n.dot(&r);
                let q = r * t;
                pts.push(if col >= cut { [f32::NAN; 3] } else { [q.x as f32, q.y as f32, q.z as f32] });
            }
        }
        PointCloud::organized(w, h, pts).unwrap()
    }

    #[test]
    fn grid_counts_equal_kdtree_counts() {
        let camera = CameraModel::default();
        let n = Vec3::new(0.3, 0.2, 1.0).normalize();
        let cloud = plane_cloud(&camera, 40, 30, 520.0, n, 31);
        let flat = PointCloud::unorganized(cloud.points().to_vec());
        let grid = NeighbourSearch::new(&cloud, &camera, 1.0);
        let tree = NeighbourSearch::new(&flat, &camera, 1.0);
        // The flat cloud dropped invalid points; map indices through valid order.
        let valid: Vec<usize> = (0..cloud.len()).filter(|&i| cloud.points()[i][0].is_finite()).collect();
        for (k, &i) in valid.iter().enumerate() {
            assert_eq!(grid.count(i, |_| true), tree.count(k, |_| true), "point {i}");
        }
    }

    #[test]
    fn lattice_count_predicts_interior_counts_exactly() {
        let camera = CameraModel::default();
        for (z, n) in [
            (500.0, Vec3::z()),
            (900.0, Vec3::new(0.5, 0.0, 1.0).normalize()),
            (700.0, Vec3::new(-0.2, 0.4, 1.0).normalize()),
        ] {
            let cloud = plane_cloud(&camera, 41, 41, z, n, usize::MAX);
            let search = NeighbourSearch::new(&cloud, &camera, 1.0);
            let centre = 20 * 41 + 20;
            let actual = search.count(centre, |_| true) as f64;
            let expected = lattice_count_in_ellipse(&camera, &vec3(&cloud.points()[centre]), &n, 1.0);
            assert!((actual - expected).abs() <= 1.0, "z {z}: actual {actual}, lattice {expected}");
            let shared = full_plane_count(&search, centre, &n);
            assert!((shared - expected).abs() <= 1.0, "z {z}: tile count {shared}, pixel's own {expected}");
        }
    }

    /// The full-plane count of point `i` through its tile's memo entry.
    fn full_plane_count(search: &NeighbourSearch, i: usize, n: &Vec3) -> f64 {
        FullCounts::new(search, n).get(i, &mut FullCountCache::default())
    }

    fn vec3(p: &Point) -> Vec3 {
        Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    }

    #[test]
    fn edge_points_see_about_half_the_plane() {
        let camera = CameraModel::default();
        let cloud = plane_cloud(&camera, 41, 41, 600.0, Vec3::z(), 21);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let edge = 20 * 41 + 20;
        let ratio = search.count(edge, |_| true) as f64 / full_plane_count(&search, edge, &Vec3::z());
        assert!((0.45..0.65).contains(&ratio), "{ratio}");
    }

    #[test]
    fn members_filter_the_count() {
        let camera = CameraModel::default();
        let cloud = plane_cloud(&camera, 21, 21, 600.0, Vec3::z(), usize::MAX);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let all = search.count(220, |_| true);
        let left = search.count(220, |j| j % 21 <= 10);
        assert!(left < all && left > all / 3);
    }
}
