//! The plane point criterion (section 3.2): which points lie inside a
//! plane, as opposed to on edges, side faces, holes or outliers.
//!
//! The paper's criterion (Eq. 14) keeps a point when its neighbour count
//! within R reaches `N'min` of Eq. 13, a frontal plane's count at the
//! point's depth less the accuracy margin. It misjudges tilted plates
//! (their density is about `cos θ` of the frontal one) and ignores that a
//! pixel grid's count differs from `π R² D` by up to 15 %. The robust
//! criterion compares the count with what a complete plane of the
//! workpiece's orientation gives at that very pixel, and also requires the
//! local normal to agree with the workpiece's, which no count can check.
//!
//! Either criterion needs, for a point, its neighbour count within R and
//! the count it must reach, derived from the count a complete plane would
//! give there ([`Threshold::needed`]); how the counts are taken fast is
//! [`grid`]'s business. [`reference`] counts every point.

#[cfg(test)]
use rayon::prelude::*;

mod grid;

use crate::camera::CameraModel;
use crate::cloud::PointCloud;
use crate::geometry::Vec3;

use super::neighbours::{FullCountCache, FullCounts, NeighbourSearch, SearchedPoint, VisitNeighbours};
use super::orientation::{
    GridPoints, StepTable, grid_normal_agrees, local_normal, normal_step, scatter_facing_and_count_of,
};

/// The plane points and, for each, a lower bound of its neighbour count
/// and the full-plane count it was measured against (the edge criterion
/// reuses both to skip points that cannot be edges).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PlanePoints {
    pub mask: Vec<bool>,
    pub counts: Vec<u16>,
    /// The full-plane count of the robust criterion; 0 for the paper's.
    pub full: Vec<u16>,
}

impl PlanePoints {
    pub(crate) fn len(&self) -> usize {
        self.mask.iter().filter(|&&b| b).count()
    }
}

/// What decides a point: the neighbour count it needs, or `None` when it
/// is rejected before counting.
trait Threshold: Sync {
    /// The count point `i` needs, and the full count it derives from (0
    /// when the criterion has none).
    fn needed(&self, i: usize, cache: &mut FullCountCache) -> Option<(f64, f64)>;

    /// The orientation of the plane the full count assumes: the fast
    /// classification counts over its ellipse first.
    fn plane_normal(&self) -> Vec3;

    /// [`Threshold::needed`] of point `i` of a cloud without a pixel grid
    /// and, when it is counted, its neighbour count read up to
    /// `cap_of(needed count)`: what the classification takes per point
    /// there. The robust criterion reads its normal and its count in one
    /// visit of the neighbours.
    fn needed_and_count(
        &self,
        search: &NeighbourSearch,
        i: usize,
        cache: &mut FullCountCache,
        cap_of: &dyn Fn(f64) -> u32,
    ) -> Option<(f64, f64, u32)>
    where
        Self: Sized,
    {
        self.needed_and_count_of(search, i, &SearchedPoint(search, i), cache, cap_of)
    }

    /// [`Threshold::needed_and_count`] with point `i`'s neighbours read
    /// through `neighbours`, which gives them as `search` would.
    fn needed_and_count_of(
        &self,
        search: &NeighbourSearch,
        i: usize,
        neighbours: &impl VisitNeighbours,
        cache: &mut FullCountCache,
        cap_of: &dyn Fn(f64) -> u32,
    ) -> Option<(f64, f64, u32)>
    where
        Self: Sized,
    {
        let _ = search;
        let (t, full) = self.needed(i, cache)?;
        Some((t, full, neighbours.count_up_to(|_| true, cap_of(t))))
    }
}

/// Eq. 14: `N_r >= N'min(L)` with `L` the point's depth (Eq. 13).
struct PaperThreshold<'a> {
    cloud: &'a PointCloud,
    camera: &'a CameraModel,
    radius: f64,
}

impl Threshold for PaperThreshold<'_> {
    fn needed(&self, i: usize, _: &mut FullCountCache) -> Option<(f64, f64)> {
        let p = self.cloud.points()[i];
        p[0].is_finite().then(|| (self.camera.min_plane_neighbours(self.radius, p[2] as f64), 0.0))
    }

    fn plane_normal(&self) -> Vec3 {
        Vec3::z()
    }
}

/// Settings of the robust criterion.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RobustPlaneCriterion {
    /// The workpiece's dominant unit normal, facing away from the camera.
    pub normal: Vec3,
    /// Least fraction of the full-plane neighbour count.
    pub min_ratio: f64,
    /// Largest angle between the local and the dominant normal, degrees.
    pub max_angle_deg: f64,
}

struct RobustThreshold<'a> {
    search: &'a NeighbourSearch<'a>,
    full_counts: FullCounts<'a>,
    criterion: RobustPlaneCriterion,
    cos_limit: f64,
    steps: StepTable,
}

impl<'a> RobustThreshold<'a> {
    fn new(search: &'a NeighbourSearch<'a>, criterion: &RobustPlaneCriterion) -> Self {
        RobustThreshold {
            search,
            full_counts: FullCounts::new(search, &criterion.normal),
            criterion: *criterion,
            cos_limit: criterion.max_angle_deg.to_radians().cos(),
            steps: StepTable::new(search.camera().fx(), search.radius_mm()),
        }
    }
}

impl RobustThreshold<'_> {
    /// [`Threshold::needed`] of point `i` of an organized cloud, read from
    /// `grid`: the cloud itself, or its coordinate planes, which the fast
    /// path has in cache where the cloud's rows above and below are not.
    #[inline]
    fn needed_on_grid<G: GridPoints>(&self, grid: &G, i: usize, cache: &mut FullCountCache) -> Option<(f64, f64)> {
        let p = grid.point(i);
        if !p[0].is_finite() {
            return None;
        }
        let step = self.steps.step(p[2]);
        if !grid_normal_agrees(grid, i, step, &self.criterion.normal, self.cos_limit) {
            return None;
        }
        self.need_of_full(self.full_counts.get_point(&p, cache))
    }

    /// The count a facing point needs given its full-plane count, and
    /// that count; `None` for a plane seen edge-on.
    #[inline(always)]
    fn need_of_full(&self, full: f64) -> Option<(f64, f64)> {
        (full > 0.0).then_some((self.criterion.min_ratio * full, full))
    }
}

impl Threshold for RobustThreshold<'_> {
    fn needed(&self, i: usize, cache: &mut FullCountCache) -> Option<(f64, f64)> {
        let cloud = self.search.cloud();
        if cloud.is_organized() {
            return self.needed_on_grid(cloud, i, cache);
        }
        let p = cloud.points()[i];
        if !p[0].is_finite() {
            return None;
        }
        let step = normal_step(self.search.camera().fx(), p[2] as f64, self.search.radius_mm());
        let facing =
            local_normal(cloud, self.search, i, step).is_some_and(|n| n.dot(&self.criterion.normal) >= self.cos_limit);
        if !facing {
            return None;
        }
        self.need_of_full(self.full_counts.get(i, cache))
    }

    fn plane_normal(&self) -> Vec3 {
        self.criterion.normal
    }

    /// The full count first (a lookup), then the normal and the count it
    /// sets the cap of from one visit of the neighbours. The same answer
    /// as `needed` then a count: `needed` is `None` when the point does
    /// not face the workpiece or its full count is not positive, in either
    /// order.
    fn needed_and_count_of(
        &self,
        search: &NeighbourSearch,
        i: usize,
        neighbours: &impl VisitNeighbours,
        cache: &mut FullCountCache,
        cap_of: &dyn Fn(f64) -> u32,
    ) -> Option<(f64, f64, u32)>
    where
        Self: Sized,
    {
        let cloud = self.search.cloud();
        // The one visit serves the criterion's own search of a cloud
        // without a grid; anything else is counted as the default does.
        if cloud.is_organized() || !std::ptr::eq(search, self.search) {
            let (t, full) = self.needed(i, cache)?;
            return Some((t, full, neighbours.count_up_to(|_| true, cap_of(t))));
        }
        if !cloud.points()[i][0].is_finite() {
            return None;
        }
        let (t, full) = self.need_of_full(self.full_counts.get(i, cache))?;
        let (facing, count) =
            scatter_facing_and_count_of(search, i, neighbours, cap_of(t), &self.criterion.normal, self.cos_limit);
        facing.then_some((t, full, count))
    }
}

/// Eq. 14, the paper's criterion.
pub(crate) fn paper_criterion(cloud: &PointCloud, camera: &CameraModel, search: &NeighbourSearch) -> PlanePoints {
    grid::classify(search, &PaperThreshold { cloud, camera, radius: search.radius_mm() })
}

/// The robust criterion: `N_r >= ratio · N_plane(p)`, where `N_plane` is
/// the lattice count of a complete plane with the dominant normal through
/// `p`, and the local normal within the angle limit.
pub(crate) fn robust_criterion(search: &NeighbourSearch, criterion: &RobustPlaneCriterion) -> PlanePoints {
    grid::classify(search, &RobustThreshold::new(search, criterion))
}

/// The straightforward form of either criterion: one radius count per
/// point through `search` (a KD-tree in the tests). Kept as the reference.
#[cfg(test)]
pub(crate) fn reference(search: &NeighbourSearch, paper: bool, criterion: &RobustPlaneCriterion) -> Vec<bool> {
    let cloud = search.cloud();
    let paper_t = PaperThreshold { cloud, camera: search.camera(), radius: search.radius_mm() };
    let robust_t = RobustThreshold::new(search, criterion);
    let threshold: &dyn Threshold = if paper { &paper_t } else { &robust_t };
    (0..cloud.len())
        .into_par_iter()
        .map_init(FullCountCache::default, |cache, i| {
            threshold.needed(i, cache).is_some_and(|(t, _)| search.count(i, |_| true) as f64 >= t)
        })
        .collect()
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A plate at depth `z` tilted by `tilt_deg` about the image y axis, on
    /// columns below `plate_cols`, and a steep bevel after it.
    pub(super) fn scene(z: f64, tilt_deg: f64, plate_cols: usize) -> (PointCloud, Vec3) {
        let camera = CameraModel::default();
        let (w, h) = (60, 40);
        let t = tilt_deg.to_radians();
        let n = Vec3::new(t.sin(), 0.0, t.cos());
        let bevel = Vec3::new((t - 1.0).sin(), 0.0, (t - 1.0).cos());
        let anchor = Vec3::new(0.0, 0.0, z);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(camera.cx() - 30.0 + col as f64, camera.cy() - 20.0 + row as f64);
                let r = Vec3::new(r[0], r[1], r[2]);
                let m = if col < plate_cols { n } else { bevel };
                let q = r * (m.dot(&anchor) / m.dot(&r));
                pts.push([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        (PointCloud::organized(w, h, pts).unwrap(), n)
    }

    #[test]
    fn paper_criterion_loses_a_tilted_plate_that_the_robust_one_keeps() {
        let camera = CameraModel::default();
        let (cloud, n) = scene(900.0, 35.0, 60);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let centre = 20 * 60 + 30;
        let paper = paper_criterion(&cloud, &camera, &search);
        assert!(!paper.mask[centre], "foreshortening drops the paper's count below N'min");
        let robust = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
        assert!(robust_criterion(&search, &robust).mask[centre]);
    }

    #[test]
    fn robust_criterion_rejects_a_bevel_face_and_keeps_the_plate() {
        let camera = CameraModel::default();
        let (cloud, n) = scene(600.0, 10.0, 30);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let robust = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
        let mask = robust_criterion(&search, &robust).mask;
        assert!(mask[20 * 60 + 10], "plate interior");
        assert!(!mask[20 * 60 + 50], "bevel interior");
    }

    #[test]
    fn invalid_points_are_never_plane_points() {
        let camera = CameraModel::default();
        let cloud = PointCloud::organized(3, 3, vec![[f32::NAN; 3]; 9]).unwrap();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        assert_eq!(paper_criterion(&cloud, &camera, &search).len(), 0);
    }

    #[test]
    fn one_visit_for_normal_and_count_answers_as_the_separate_calls() {
        let camera = CameraModel::default();
        for (z, tilt, cols) in [(520.0, 0.0, 33), (800.0, 25.0, 41), (600.0, 10.0, 30)] {
            let (grid, n) = scene(z, tilt, cols);
            let cloud = PointCloud::unorganized(grid.points().to_vec());
            for (radius, measured) in [(1.0, false), (0.6, true), (2.5, true)] {
                let mut search = NeighbourSearch::new(&cloud, &camera, radius);
                if measured {
                    search.measure_full_counts();
                }
                let c = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
                let threshold = RobustThreshold::new(&search, &c);
                let mut cache = FullCountCache::default();
                for i in 0..cloud.len() {
                    for cap in [0, 1, 7, 40, 64, 65, 500, u32::MAX] {
                        let separate = threshold
                            .needed(i, &mut cache)
                            .map(|(t, full)| (t, full, search.count_up_to(i, |_| true, cap)));
                        let fused = threshold.needed_and_count(&search, i, &mut cache, &|_| cap);
                        assert_eq!(fused, separate, "point {i}, cap {cap}, radius {radius} at {z} mm");
                    }
                }
                let tree = NeighbourSearch::kdtree(&cloud, &camera, radius);
                if !measured {
                    assert_eq!(robust_criterion(&search, &c).mask, reference(&tree, false, &c), "{z} mm");
                }
            }
        }
    }

    /// [`grid::classify`] of a cloud without a grid, point by point
    /// through the search: what the by-cell classification must give.
    fn point_by_point(search: &NeighbourSearch, threshold: &impl Threshold) -> PlanePoints {
        let n = search.cloud().len();
        let mut out = PlanePoints { mask: vec![false; n], counts: vec![0; n], full: vec![0; n] };
        let mut cache = FullCountCache::default();
        let cap_of = |t: f64| if t <= 0.0 { 0 } else { t.ceil().min(u32::MAX as f64 - 1.0) as u32 };
        for i in 0..n {
            if let Some((t, full, count)) = threshold.needed_and_count(search, i, &mut cache, &cap_of) {
                out.mask[i] = count as f64 >= t;
                out.counts[i] = if out.mask[i] { count.min(u16::MAX as u32) as u16 } else { 0 };
                out.full[i] = full.clamp(0.0, u16::MAX as f64) as u16;
            }
        }
        out
    }

    #[test]
    fn by_cell_classification_answers_as_point_by_point() {
        let camera = CameraModel::default();
        for (z, tilt, cols) in [(520.0, 0.0, 33), (800.0, 25.0, 41), (600.0, 10.0, 30)] {
            let (grid, n) = scene(z, tilt, cols);
            // Jittered, so that cells and distances are not a lattice's.
            let jittered: Vec<_> = grid
                .points()
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    let h = (k as u32).wrapping_mul(2_654_435_761);
                    let d = |s: u32| ((h >> s) & 0xff) as f32 / 255.0 * 0.04 - 0.02;
                    [p[0] + d(0), p[1] + d(8), p[2] + d(16)]
                })
                .collect();
            for cloud in [PointCloud::unorganized(grid.points().to_vec()), PointCloud::unorganized(jittered)] {
                for (radius, measured) in [(1.0, false), (0.6, true), (2.5, true), (0.3, false)] {
                    let mut search = NeighbourSearch::new(&cloud, &camera, radius);
                    if measured {
                        search.measure_full_counts();
                    }
                    let c = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
                    let robust = RobustThreshold::new(&search, &c);
                    assert_eq!(robust_criterion(&search, &c), point_by_point(&search, &robust), "robust, {z} mm");
                    let paper = PaperThreshold { cloud: &cloud, camera: &camera, radius };
                    assert_eq!(
                        paper_criterion(&cloud, &camera, &search),
                        point_by_point(&search, &paper),
                        "paper, {z} mm"
                    );
                }
            }
        }
    }

    #[test]
    fn grid_fast_path_classifies_exactly_as_the_kdtree_reference() {
        let camera = CameraModel::default();
        for (z, tilt, cols) in [(520.0, 0.0, 33), (800.0, 25.0, 41), (980.0, 12.0, 60)] {
            let (cloud, n) = scene(z, tilt, cols);
            let grid = NeighbourSearch::new(&cloud, &camera, 1.0);
            let tree = NeighbourSearch::kdtree(&cloud, &camera, 1.0);
            let c = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
            assert_eq!(robust_criterion(&grid, &c).mask, reference(&tree, false, &c), "robust at {z} mm");
            assert_eq!(paper_criterion(&cloud, &camera, &grid).mask, reference(&tree, true, &c), "paper at {z} mm");
        }
    }
}
