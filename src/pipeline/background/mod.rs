//! Background removal (section 3.3): which plane clusters are the two
//! workpiece plates and which are the table or other background.
//!
//! The paper deletes the cluster with the largest xy bounding box. That
//! fails when the plates run off the image (the table splits and a table
//! piece is kept as a plate) and when the plates fill the view (a plate is
//! deleted). The robust rule uses what a cell guarantees instead: the
//! plates are parallel planes nearer the camera than whatever they rest
//! on. Butt plates are the nearest layer holding two coplanar clusters; a
//! lap is the nearest pair of layers one plate thickness apart; a tee is a
//! long narrow plane (the web's top) a web's height, more than any lap
//! step, over a layer it lies across, seen on both of its sides (the
//! flange), or a top of any width standing so with a face seen falling
//! from its edges to the layer under it (a block standing on a plate,
//! weighed under `auto` only where neither a butt nor a lap fits).
//!
//! The stage's files, by concern: [`error`] says why no workpiece was
//! found, each reason a rule of `crate::rules::background`;
//! [`placement`] reads where one plane cluster lies beside, across or
//! beyond others, and whether a face falls from one to a lower layer;
//! [`image_break`] tells a piece a break in the image (a streak, a
//! dropout) cut off a plate from a plate of its own, by whether the break
//! runs on across the surface behind them;
//! [`layers`] sorts the clusters into layers and finds the butt, lap or
//! tee layout in them; [`beside`] tells which plate of a
//! layer another plane stands beside; [`corner`] recognises a corner
//! joint by what the cloud shows beyond a plate's edge.

mod beside;
mod corner;
mod error;
mod image_break;
mod layers;
mod placement;
#[cfg(test)]
mod standing_tests;
#[cfg(test)]
mod tests;

use std::sync::Arc;

use crate::cloud::PointCloud;
use crate::geometry::fit::{Moments, Plane};
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;

pub use corner::{Corner, find_corner};
pub use error::{BackgroundError, CornerKind};
pub use layers::{nearest_layer, robust_select};

/// A cluster of plane points with its fitted plane.
#[derive(Debug, Clone)]
pub struct PlaneCluster {
    /// The cluster's label in [`crate::pipeline::clustering::Clusters::labels`].
    pub label: u32,
    /// The cluster's points, shared: a workpiece's planes are cloned to
    /// be read a second way (`auto`'s tee reading), not their points.
    pub members: Arc<Vec<u32>>,
    pub plane: Plane,
    pub centroid: Vec3,
    /// The area the points cover on their plane, mm².
    pub area_mm2: f64,
    /// The direction the points spread along most, and how many times
    /// further than across it: a bar lying on a plate is long and narrow.
    pub long_axis: Vec3,
    pub elongation: f64,
}

impl PlaneCluster {
    /// The cluster's plane, place and shape without its points.
    pub fn clone_shape(&self) -> PlaneCluster {
        PlaneCluster { members: Arc::default(), ..*self }
    }
}

#[cfg(test)]
impl PlaneCluster {
    /// The cluster of the points of `points` that `pick` keeps, each
    /// standing for a square millimetre: unit tests' planes.
    pub(crate) fn of_points(points: &[Vec3], pick: impl Fn(&Vec3) -> bool) -> PlaneCluster {
        use crate::geometry::fit::Moments;
        let members: Vec<u32> = (0..points.len() as u32).filter(|&i| pick(&points[i as usize])).collect();
        let moments: Moments = members.iter().map(|&i| &points[i as usize]).collect();
        let (long_axis, elongation) = moments.elongation().expect("two distinct points");
        PlaneCluster {
            label: 0,
            area_mm2: members.len() as f64,
            plane: moments.plane().expect("points spanning a plane"),
            centroid: moments.centroid().expect("points"),
            members: members.into(),
            long_axis,
            elongation,
        }
    }
}

/// The two workpiece plates. For a lap joint `plates[0]` is the upper
/// plate and `plates[1]` the lower one (robust method; the paper's method
/// sorts them later by the depth of their edges).
#[derive(Debug, Clone)]
pub struct Workpiece {
    pub plates: [PlaneCluster; 2],
    /// How far behind the plates (the butt plates' top, or the lower lap
    /// plate) the next parallel surface lies, mm along the normal: the
    /// table or fixture they rest on, when the camera sees it. The plates
    /// are no thicker than this, so neither is a groove (robust method).
    pub depth_to_support_mm: Option<f64>,
    /// Whether that surface is only a narrow strip between butt plates
    /// (robust method): the joint's own floor (a V-groove's apex in a
    /// noisy cloud, the table seen through a gap), whose depth measures
    /// the groove rather than bounding it. A requested groove
    /// depth is then judged by the groove-depth gate against the measured
    /// one, not refused against this depth.
    pub support_between_plates: bool,
    /// The other clusters of each plate's layer (robust method): pieces
    /// of a plate a streak or a dropout split off, or whatever else lies
    /// in its plane. The coverage report joins those beside the weld that
    /// continue the plate across a narrow break, so a seam that stops
    /// where one piece ends is not taken for the whole joint. Butt plates
    /// share one layer, and so these.
    pub layer_mates: [Vec<PlaneCluster>; 2],
}

impl PlaneCluster {
    /// How wide a long narrow cluster is, mm: a rectangle L by W covers
    /// L W and spreads L / W times further along than across.
    pub fn width_mm(&self) -> f64 {
        (self.area_mm2 / self.elongation.max(1.0)).sqrt()
    }
}

/// Fits a plane to each cluster and estimates its area from the sampling
/// density the camera gives on that plane.
pub fn describe(
    cloud: &PointCloud,
    members: Vec<Vec<u32>>,
    area_per_point: impl Fn(&Vec3, &Vec3) -> f64,
) -> Vec<PlaneCluster> {
    let points = cloud.points();
    members
        .into_iter()
        .enumerate()
        .filter_map(|(label, m)| {
            // A fixed stride keeps the fit cheap on million-point plates.
            let stride = (m.len() / 50_000).max(1);
            let moments: Moments = m.iter().step_by(stride).map(|&i| vec3(&points[i as usize])).collect();
            let plane = moments.plane()?;
            let centroid = moments.centroid()?;
            let area_mm2 = m.len() as f64 * area_per_point(&centroid, &plane.normal);
            let (long_axis, elongation) = moments.elongation()?;
            Some(PlaneCluster {
                label: label as u32,
                members: m.into(),
                plane,
                centroid,
                area_mm2,
                long_axis,
                elongation,
            })
        })
        .collect()
}

/// The paper's rule: delete the cluster with the largest xy bounding box,
/// keep the two largest of the rest.
pub fn paper_select(cloud: &PointCloud, mut planes: Vec<PlaneCluster>) -> Result<Workpiece, BackgroundError> {
    let points = cloud.points();
    let bbox_area = |c: &PlaneCluster| {
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for &i in c.members.iter() {
            let p = points[i as usize];
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        ((hi[0] - lo[0]) * (hi[1] - lo[1])) as f64
    };
    if let Some(background) = (0..planes.len()).max_by(|&a, &b| bbox_area(&planes[a]).total_cmp(&bbox_area(&planes[b])))
    {
        planes.remove(background);
    }
    planes.sort_by_key(|c| std::cmp::Reverse(c.members.len()));
    take_two(planes)
}

fn take_two(planes: Vec<PlaneCluster>) -> Result<Workpiece, BackgroundError> {
    let found = planes.len();
    let mut it = planes.into_iter();
    match (it.next(), it.next()) {
        (Some(a), Some(b)) => Ok(Workpiece {
            plates: [a, b],
            depth_to_support_mm: None,
            support_between_plates: false,
            layer_mates: Default::default(),
        }),
        _ => Err(BackgroundError::TooFewPlanes { found }),
    }
}

/// How the two plates of a joint lie: side by side in one plane (butt
/// joints, V or I), one on the other a plate thickness apart (lap), or a
/// web standing on a flange (tee: `plates[0]` is the web's top,
/// `plates[1]` the largest flange piece and `layer_mates[1]` the others).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Butt,
    Lap,
    Tee,
}

impl Layout {
    pub fn of(joint: JointType) -> Layout {
        match joint {
            JointType::VButt | JointType::IButt => Layout::Butt,
            JointType::Lap => Layout::Lap,
            JointType::TFillet => Layout::Tee,
        }
    }
}

/// Settings of the robust selection.
#[derive(Debug, Clone, Copy)]
pub struct Selection {
    /// The joint requested; None to decide the layout from the layers.
    pub joint: Option<JointType>,
    /// The workpiece's dominant normal, away from the camera.
    pub normal: Vec3,
    pub coplanar_tolerance_mm: f64,
    pub lap_step_min_mm: f64,
    pub lap_step_max_mm: f64,
    /// A web's top lies more than `lap_step_max_mm` (or, a short web under
    /// a tee's request, [`layers::WEB_MIN_HEIGHT_PER_WIDTH`] times its
    /// width) and at most this far over its flange, and is at most
    /// `web_thickness_max_mm` wide.
    pub web_height_max_mm: f64,
    pub web_thickness_max_mm: f64,
    /// Clusters whose normal is further than this from `normal` are not
    /// workpiece planes.
    pub max_tilt_deg: f64,
    /// The plane criterion's neighbour radius (Eq. 6): a plate's points
    /// within it of the plate's edge may fail the criterion (their disc
    /// reaches past the edge), so a cluster can end up to this far inside
    /// its plate, and what lies beyond a plate is read past that rim.
    pub neighbour_radius_mm: f64,
}

impl Selection {
    /// Whether `c` faces the camera as the workpiece does: within
    /// `max_tilt_deg` of its dominant normal. Other clusters are no
    /// workpiece planes.
    pub fn faces_camera(&self, c: &PlaneCluster) -> bool {
        c.plane.normal.dot(&self.normal) >= self.max_tilt_deg.to_radians().cos()
    }
}

/// The two plates the robust rule chose, how they lie, and in words why.
#[derive(Debug, Clone)]
pub struct Selected {
    pub workpiece: Workpiece,
    pub layout: Layout,
    /// What the layers showed: the plates' offsets and areas, and for an
    /// automatic choice why the other layout was not it.
    pub evidence: String,
    /// A tee whose web's top was found by the faces falling from it to the
    /// flange, not by its shape: a member wider than a web is thick (a
    /// block) standing on the flange, each of whose sides has a root.
    pub web_by_faces: bool,
}
