//! Several workpieces in one frame (issue 15): the plane clusters grouped
//! into workpieces before the background rule (`background::robust_select`)
//! picks each workpiece's two plates, so that plates of different
//! workpieces are never paired across the table.
//!
//! The table (or fixture) the workpieces rest on is the layer farthest
//! from the camera, seen around all of them. Without it, the clusters of
//! one workpiece lie close together along the plane: its plates are
//! separated only by what the joint puts between them (a butt joint's gap
//! or groove, a lap's step and the band of the lower plate its upper plate
//! hides, a tee's web standing on its flange), while two workpieces are
//! separated by the table seen between them. So adjacency is measured on
//! a coarse occupancy grid in the plane: each cluster's cells grow, a cell
//! at a time, over cells no cluster and no table point holds, and two
//! clusters whose growths meet within [`MAX_JOINT_OPENING_MM`] of each
//! other belong to one workpiece, unless they meet only at a corner: a
//! contact far weaker than both clusters' own joints
//! ([`MIN_CONTACT_SHARE`]), as where two workpieces set corner to corner
//! come within the reach across a shadow, the table not seen between
//! them. The cells are a few point spacings wide, so the measure follows
//! the cloud, not one camera.
//!
//! A frame splits into workpieces only where the table, taken away, leaves
//! at least two groups of two clusters or more; otherwise every cluster is
//! handed on together, exactly as a frame of one workpiece always was. A
//! lone cluster of a frame of several (a tee's flange beyond the band its
//! web hides, a plate whose partner is out of view) pairs with nothing and
//! joins no group.

use std::collections::BTreeMap;

use crate::cloud::PointCloud;
use crate::geometry::{Vec3, plane_axes, vec3};

use super::background::PlaneCluster;

/// The widest gap, mm along the plates, between two plate tops of one
/// joint: a V-groove's opening (about 18 mm for an 11 mm deep groove of 70
/// degrees), a lap's lower plate hidden beside its upper plate's edge (the
/// upper plate's thickness times the view's slant), each widened by the
/// rim the plane criterion trims. Workpieces nearer each other than the
/// table shows between them are one workpiece to this measure.
pub const MAX_JOINT_OPENING_MM: f64 = 25.0;

/// A grid cell in point spacings: wide enough that a plate's points leave
/// no cell of it empty, fine enough that a gap of a few spacings shows.
const CELL_SPACINGS: f64 = 4.0;

/// The most cells the grid may have; a coarser cell is taken beyond it,
/// so a wide, fine frame costs no more than this.
const MAX_CELLS: f64 = 4.0e6;

/// Every how many points the clusters' extent is taken.
const BOUNDS_STRIDE: usize = 8;

/// Every how many of a cluster's points marks its cell: a cell
/// [`CELL_SPACINGS`] wide holds about its square in points, so every
/// fourth leaves about four in each (a cell left empty inside a plate is
/// crossed in one step; a wall of table cells many cells thick is not).
const MARK_STRIDE: usize = 4;

/// How strong a contact between two clusters must be, as a share of the
/// strongest contact of either, to join them. Two clusters' growths meet
/// along the length of their contact, so a joint's plates meet hundreds of
/// times (746 to 1150 on fresh draw 2's multi-05, cells of 1.1 mm), while
/// a plate's corner that comes within the reach of another workpiece's
/// plate across a shadow meets it a dozen times (12 there). A contact weak
/// beside both clusters' own joints is not one: two workpieces set corner
/// to corner stay two. A joint's plates are each other's strongest
/// contact, or close to it, so no joint is cut by this. Where the corners
/// lie in a wide open shadow, their growths race along each other for
/// many steps and meet far more often: in a scene of two butt pairs with
/// 100 mm joints, corners 14 mm apart in an 18 mm square without table,
/// 122 times against each joint's 608 (1 mm cells), 32 against 152
/// (4 mm cells). Such corners still join.
const MIN_CONTACT_SHARE: f64 = 0.1;

/// The fewest clusters a frame of two workpieces shows: two plates each
/// and the table.
const MIN_CLUSTERS_FOR_SEVERAL: usize = 5;

/// How the frame is grouped.
#[derive(Debug, Clone, Copy)]
pub struct GroupSettings {
    /// The workpieces' dominant normal, away from the camera.
    pub normal: Vec3,
    /// Clusters whose normal is further than this from `normal` are not
    /// workpiece planes (as `background::Selection::max_tilt_deg`).
    pub max_tilt_deg: f64,
    /// Clusters whose offsets along the normal agree within this lie in
    /// one layer (`pipeline.coplanar_tolerance_mm`).
    pub coplanar_tolerance_mm: f64,
    /// The point spacing on the workpieces, mm.
    pub point_spacing_mm: f64,
}

/// One workpiece's clusters, with the table's beside them for the layer
/// rule (the table is the surface the plates rest on; on a frame of
/// several, without its points), and where it lies.
#[derive(Debug, Clone)]
pub struct WorkpieceGroup {
    pub planes: Vec<PlaneCluster>,
    /// The area-weighted middle of its own clusters (the table's left
    /// out), camera frame: how a person tells the workpieces apart.
    pub near_camera: Vec3,
}

/// The frame's clusters as workpieces: one group holding every cluster,
/// in the order given, unless the frame shows several (see the module's
/// documentation); then one group per workpiece, nearest the camera first.
pub fn group(cloud: &PointCloud, planes: Vec<PlaneCluster>, s: &GroupSettings) -> Vec<WorkpieceGroup> {
    match split(cloud, &planes, s) {
        None => {
            let near_camera = middle(planes.iter());
            vec![WorkpieceGroup { planes, near_camera }]
        }
        Some((groups, table)) => {
            let mut out: Vec<WorkpieceGroup> = groups
                .into_iter()
                .map(|members| {
                    let near_camera = middle(members.iter().map(|&k| &planes[k]));
                    // The layer rule reads the table's plane, place and
                    // area, not its points: a frame's largest cluster is
                    // not copied for every workpiece.
                    let table = table.iter().map(|&k| planes[k].clone_shape());
                    let planes = members.iter().map(|&k| planes[k].clone()).chain(table).collect();
                    WorkpieceGroup { planes, near_camera }
                })
                .collect();
            out.sort_by(|a, b| s.normal.dot(&a.near_camera).total_cmp(&s.normal.dot(&b.near_camera)));
            out
        }
    }
}

/// The area-weighted centroid of `clusters`.
fn middle<'c>(clusters: impl Iterator<Item = &'c PlaneCluster>) -> Vec3 {
    let (sum, area) =
        clusters.fold((Vec3::zeros(), 0.0), |(sum, area), c| (sum + c.centroid * c.area_mm2, area + c.area_mm2));
    if area > 0.0 { sum / area } else { sum }
}

/// The indices of each workpiece's clusters (two or more each, at least
/// two workpieces) and of the table's, or None for a frame of one.
fn split(cloud: &PointCloud, planes: &[PlaneCluster], s: &GroupSettings) -> Option<(Vec<Vec<usize>>, Vec<usize>)> {
    let cos_tilt = s.max_tilt_deg.to_radians().cos();
    let candidates: Vec<usize> =
        (0..planes.len()).filter(|&k| planes[k].plane.normal.dot(&s.normal) >= cos_tilt).collect();
    if candidates.len() < MIN_CLUSTERS_FOR_SEVERAL {
        return None;
    }
    let offset = |k: usize| s.normal.dot(&planes[k].centroid);
    let farthest = candidates.iter().map(|&k| offset(k)).fold(f64::NEG_INFINITY, f64::max);
    let (table, others): (Vec<usize>, Vec<usize>) =
        candidates.iter().partition(|&&k| offset(k) >= farthest - s.coplanar_tolerance_mm);
    if others.len() < 2 * 2 {
        return None;
    }
    let grid = OccupancyGrid::new(cloud, planes, &table, &others, s)?;
    let groups: Vec<Vec<usize>> = grid
        .components()
        .into_iter()
        .filter(|c| c.len() >= 2)
        .map(|c| c.into_iter().map(|k| others[k]).collect())
        .collect();
    tracing::debug!(
        table = ?table.iter().map(|&k| planes[k].label).collect::<Vec<_>>(),
        groups = ?groups.iter().map(|g| g.iter().map(|&k| planes[k].label).collect::<Vec<_>>()).collect::<Vec<_>>(),
        cell_mm = grid.cell_mm,
        "plane clusters grouped into workpieces"
    );
    (groups.len() >= 2).then_some((groups, table))
}

/// What a cell of the grid holds.
const EMPTY: u32 = u32::MAX;
const TABLE: u32 = u32::MAX - 1;

/// The clusters' points on a grid in the plane, each cell the cluster that
/// holds it, the table, or empty.
struct OccupancyGrid {
    cells: Vec<u32>,
    width: usize,
    height: usize,
    cell_mm: f64,
    /// How many clusters (not the table) the grid holds.
    clusters: usize,
    /// How many cells a growth may cross.
    reach: u32,
}

impl OccupancyGrid {
    /// `others` rasterised over `table` (a cell the table shares with a
    /// cluster is the cluster's), on a grid spanning the clusters widened
    /// by the reach. None when the clusters have no extent.
    fn new(
        cloud: &PointCloud,
        planes: &[PlaneCluster],
        table: &[usize],
        others: &[usize],
        s: &GroupSettings,
    ) -> Option<Self> {
        let [u_axis, v_axis] = plane_axes(&s.normal)?;
        let points = cloud.points();
        let project = |i: u32| {
            let p = vec3(&points[i as usize]);
            (p.dot(&u_axis), p.dot(&v_axis))
        };
        // The clusters' extent along the plane, from every few points: the
        // margin around it is far wider than what the sample misses.
        let bounds = others.iter().flat_map(|&k| planes[k].members.iter().step_by(BOUNDS_STRIDE)).fold(
            [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY],
            |b, &i| {
                let (u, v) = project(i);
                [b[0].min(u), b[1].min(v), b[2].max(u), b[3].max(v)]
            },
        );
        let margin = MAX_JOINT_OPENING_MM;
        let [u0, v0, u1, v1] = [bounds[0] - margin, bounds[1] - margin, bounds[2] + margin, bounds[3] + margin];
        if !(u1 > u0 && v1 > v0) {
            return None;
        }
        let fine = (CELL_SPACINGS * s.point_spacing_mm).max(f64::EPSILON);
        let cell_mm = fine.max(((u1 - u0) * (v1 - v0) / MAX_CELLS).sqrt());
        let (width, height) = (((u1 - u0) / cell_mm).ceil() as usize + 1, ((v1 - v0) / cell_mm).ceil() as usize + 1);
        let cell_of = |i: u32| {
            let (u, v) = project(i);
            let (cu, cv) = ((u - u0) / cell_mm, (v - v0) / cell_mm);
            ((0.0..width as f64).contains(&cu) && (0.0..height as f64).contains(&cv))
                .then(|| cv as usize * width + cu as usize)
        };
        // One pass over each cluster's points, each marking its cell: the
        // table first, so a cell it shares with a cluster is the cluster's.
        let mut grid = vec![EMPTY; width * height];
        let owners = table.iter().map(|&k| (k, TABLE)).chain(others.iter().enumerate().map(|(n, &k)| (k, n as u32)));
        for (k, owner) in owners {
            for &i in planes[k].members.iter().step_by(MARK_STRIDE) {
                if let Some(c) = cell_of(i) {
                    grid[c] = owner;
                }
            }
        }
        let reach = (MAX_JOINT_OPENING_MM / cell_mm).ceil() as u32;
        Some(OccupancyGrid { cells: grid, width, height, cell_mm, clusters: others.len(), reach })
    }

    /// The clusters (indices into `others`) joined by growths that meet
    /// within the reach without crossing the table, along a contact not
    /// weak beside both clusters' strongest ([`MIN_CONTACT_SHARE`]), as
    /// connected groups.
    fn components(&self) -> Vec<Vec<usize>> {
        let mut owner = self.cells.clone();
        let mut steps = vec![0u32; self.cells.len()];
        let mut front: Vec<usize> = (0..owner.len()).filter(|&c| owner[c] < TABLE).collect();
        // How many times each pair's growths meet: their contact's length.
        let mut contacts: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        let (w, h) = (self.width as isize, self.height as isize);
        for step in 0..=self.reach {
            let mut next = Vec::new();
            for &c in &front {
                let (x, y) = ((c % self.width) as isize, (c / self.width) as isize);
                let me = owner[c];
                for (dx, dy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w || ny >= h {
                        continue;
                    }
                    let n = ny as usize * self.width + nx as usize;
                    match owner[n] {
                        TABLE => {}
                        EMPTY if step < self.reach => {
                            owner[n] = me;
                            steps[n] = step + 1;
                            next.push(n);
                        }
                        EMPTY => {}
                        other if other != me && steps[n] + step < self.reach => {
                            *contacts.entry((me.min(other), me.max(other))).or_default() += 1;
                        }
                        _ => {}
                    }
                }
            }
            front = next;
        }
        let mut strongest = vec![0u32; self.clusters];
        for (&(a, b), &n) in &contacts {
            strongest[a as usize] = strongest[a as usize].max(n);
            strongest[b as usize] = strongest[b as usize].max(n);
        }
        let joined: Vec<(u32, u32)> = contacts
            .into_iter()
            .filter(|&((a, b), n)| {
                let weaker_strongest = strongest[a as usize].min(strongest[b as usize]);
                n as f64 >= MIN_CONTACT_SHARE * weaker_strongest as f64
            })
            .map(|(pair, _)| pair)
            .collect();
        // Connected groups of the joined pairs.
        let mut group_of: Vec<Option<usize>> = vec![None; self.clusters];
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for start in 0..self.clusters {
            if group_of[start].is_some() {
                continue;
            }
            let id = groups.len();
            let mut members = vec![start];
            group_of[start] = Some(id);
            let mut k = 0;
            while k < members.len() {
                let m = members[k] as u32;
                for &(a, b) in &joined {
                    let other = if a == m {
                        b
                    } else if b == m {
                        a
                    } else {
                        continue;
                    };
                    if group_of[other as usize].is_none() {
                        group_of[other as usize] = Some(id);
                        members.push(other as usize);
                    }
                }
                k += 1;
            }
            members.sort_unstable();
            groups.push(members);
        }
        groups
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::fit::Plane;

    /// A rectangle of points `z` deep, from (x0, y0) to (x1, y1), one
    /// point a millimetre, as a cluster of `cloud`'s points.
    struct Scene {
        points: Vec<[f32; 3]>,
        planes: Vec<PlaneCluster>,
    }

    impl Scene {
        fn new() -> Self {
            Scene { points: Vec::new(), planes: Vec::new() }
        }

        fn rect(mut self, [x0, y0, x1, y1]: [f64; 4], z: f64) -> Self {
            let start = self.points.len() as u32;
            let mut y = y0;
            while y <= y1 {
                let mut x = x0;
                while x <= x1 {
                    self.points.push([x as f32, y as f32, z as f32]);
                    x += 1.0;
                }
                y += 1.0;
            }
            let members: Vec<u32> = (start..self.points.len() as u32).collect();
            let area_mm2 = members.len() as f64;
            let centroid = Vec3::new((x0 + x1) / 2.0, (y0 + y1) / 2.0, z);
            self.planes.push(PlaneCluster {
                label: self.planes.len() as u32,
                members: members.into(),
                plane: Plane { normal: Vec3::z(), offset: z },
                centroid,
                area_mm2,
                long_axis: Vec3::y(),
                elongation: 1.0,
            });
            self
        }

        /// The table around the parts, seen everywhere but where a part's
        /// box `[x0, y0, x1, y1]` (widened by a millimetre) covers it.
        fn table_around(mut self, parts: &[[f64; 4]], z: f64) -> Self {
            let start = self.points.len() as u32;
            let covered = |x: f64, y: f64| {
                parts.iter().any(|p| (p[0] - 1.0..=p[2] + 1.0).contains(&x) && (p[1] - 1.0..=p[3] + 1.0).contains(&y))
            };
            for y in -160..=160 {
                for x in -220..=220 {
                    let (x, y) = (x as f64, y as f64);
                    if !covered(x, y) {
                        self.points.push([x as f32, y as f32, z as f32]);
                    }
                }
            }
            let members: Vec<u32> = (start..self.points.len() as u32).collect();
            self.planes.push(PlaneCluster {
                label: self.planes.len() as u32,
                area_mm2: members.len() as f64,
                members: members.into(),
                plane: Plane { normal: Vec3::z(), offset: z },
                centroid: Vec3::new(0.0, 0.0, z),
                long_axis: Vec3::x(),
                elongation: 1.3,
            });
            self
        }

        fn group(self) -> Vec<Vec<u32>> {
            let cloud = PointCloud::unorganized(self.points);
            let settings = GroupSettings {
                normal: Vec3::z(),
                max_tilt_deg: 10.0,
                coplanar_tolerance_mm: 3.0,
                point_spacing_mm: 1.0,
            };
            group(&cloud, self.planes, &settings)
                .into_iter()
                .map(|g| g.planes.iter().map(|p| p.label).collect())
                .collect()
        }
    }

    #[test]
    fn two_butt_workpieces_side_by_side_on_a_table_are_two() {
        // Two butt pairs (gaps of 2 and 12 mm, a V-groove's opening), 40
        // mm apart with the table between them, 50 mm over it.
        let groups = Scene::new()
            .rect([-150.0, -100.0, -91.0, 100.0], 700.0)
            .rect([-89.0, -100.0, -30.0, 100.0], 700.0)
            .rect([10.0, -100.0, 64.0, 100.0], 701.0)
            .rect([76.0, -100.0, 130.0, 100.0], 701.0)
            .table_around(&[[-150.0, -100.0, -30.0, 100.0], [10.0, -100.0, 130.0, 100.0]], 750.0)
            .group();
        assert_eq!(groups.len(), 2, "{groups:?}");
        assert_eq!(&groups[0][..2], &[0, 1]);
        assert_eq!(&groups[1][..2], &[2, 3]);
        // Each group carries the table for the layer rule.
        assert!(groups.iter().all(|g| g[2..] == [4]), "{groups:?}");
    }

    #[test]
    fn a_lap_beside_a_butt_joint_is_two_workpieces() {
        // A lap (upper plate 6 mm over the lower, the band beside its edge
        // hidden) and a butt pair with a 3 mm gap, 30 mm apart.
        let groups = Scene::new()
            .rect([-150.0, -100.0, -90.0, 100.0], 694.0)
            .rect([-84.0, -100.0, -30.0, 100.0], 700.0)
            .rect([0.0, -100.0, 60.0, 100.0], 700.0)
            .rect([63.0, -100.0, 120.0, 100.0], 700.0)
            .table_around(&[[-150.0, -100.0, -30.0, 100.0], [0.0, -100.0, 120.0, 100.0]], 740.0)
            .group();
        assert_eq!(groups.len(), 2, "{groups:?}");
        let own: Vec<Vec<u32>> = groups.iter().map(|g| g.iter().copied().filter(|&l| l < 4).collect()).collect();
        assert!(own.contains(&vec![0, 1]) && own.contains(&vec![2, 3]), "{own:?}");
    }

    #[test]
    fn plates_of_two_workpieces_near_each_other_are_not_a_joint() {
        // Two butt pairs whose nearest plates lie 12 mm apart (as near as
        // a V-groove's edges) with the table seen between them: two
        // workpieces, never a pair across the table.
        let parts = [[-130.0, -100.0, -7.0, 100.0], [5.0, -100.0, 130.0, 100.0]];
        let groups = Scene::new()
            .rect([-130.0, -100.0, -70.0, 100.0], 700.0)
            .rect([-67.0, -100.0, -7.0, 100.0], 700.0)
            .rect([5.0, -100.0, 66.0, 100.0], 700.0)
            .rect([69.0, -100.0, 130.0, 100.0], 700.0)
            .table_around(&parts, 740.0)
            .group();
        let own: Vec<Vec<u32>> = groups.iter().map(|g| g.iter().copied().filter(|&l| l < 4).collect()).collect();
        assert_eq!(own, vec![vec![0, 1], vec![2, 3]], "{groups:?}");
    }

    #[test]
    fn one_workpiece_is_handed_on_whole_and_in_order() {
        // A butt pair, a clamp lying over it and a piece a streak cut off
        // one plate, the table around: every cluster goes on together, as
        // before there were groups.
        let scene = Scene::new()
            .rect([-100.0, -100.0, -2.0, 60.0], 700.0)
            .rect([1.0, -100.0, 100.0, 100.0], 700.0)
            .rect([-20.0, -10.0, 20.0, 10.0], 680.0)
            .rect([-100.0, 63.0, -2.0, 100.0], 700.0)
            .table_around(&[[-100.0, -100.0, 100.0, 100.0]], 740.0);
        let labels: Vec<u32> = scene.planes.iter().map(|p| p.label).collect();
        assert_eq!(scene.group(), vec![labels]);
    }
}
