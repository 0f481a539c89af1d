//! Background removal (section 3.3): which plane clusters are the two
//! workpiece plates and which are the table or other background.
//!
//! The paper deletes the cluster with the largest xy bounding box. That
//! fails when the plates run off the image (the table splits and a table
//! piece is kept as a plate) and when the plates fill the view (a plate is
//! deleted). The robust rule uses what a cell guarantees instead: the
//! plates are parallel planes nearer the camera than whatever they rest
//! on. Butt plates are the nearest layer holding two coplanar clusters; a
//! lap is the nearest pair of layers one plate thickness apart.

use crate::cloud::PointCloud;
use crate::geometry::fit::{Moments, Plane};
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;

/// A cluster of plane points with its fitted plane.
#[derive(Debug, Clone)]
pub struct PlaneCluster {
    /// The cluster's label in [`super::clustering::Clusters::labels`].
    pub label: u32,
    pub members: Vec<u32>,
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
        PlaneCluster { members: Vec::new(), ..*self }
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
    /// The other clusters of each plate's layer (robust method): pieces
    /// of a plate a streak or a dropout split off, or whatever else lies
    /// in its plane. The coverage report joins those beside the weld that
    /// continue the plate across a narrow break, so a seam that stops
    /// where one piece ends is not taken for the whole joint. Butt plates
    /// share one layer, and so these.
    pub layer_mates: [Vec<PlaneCluster>; 2],
}

/// Why no workpiece could be found among the plane clusters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BackgroundError {
    /// Fewer than two candidate planes remain.
    #[error("found {found} workpiece plane(s), need 2")]
    TooFewPlanes { found: usize },
    /// No two clusters lie in one plane nearer the camera than the rest.
    #[error(
        "found {found} planes but no two coplanar ones (offsets {offsets_mm:?} mm along the normal) for a butt joint"
    )]
    NoCoplanarPair { found: usize, offsets_mm: Vec<f64> },
    /// No two layers are one plate thickness apart.
    #[error(
        "found {found} planes but no two layers {min_mm} to {max_mm} mm apart (offsets {offsets_mm:?} mm) for a lap joint"
    )]
    NoLapStep { found: usize, offsets_mm: Vec<f64>, min_mm: f64, max_mm: f64 },
    /// A plane larger than either plate of the coplanar pair lies nearer
    /// the camera: the pair is more likely the table or a fixture seen on
    /// both sides of the workpiece, and the plane the two plates seen as
    /// one across a gap the cloud does not resolve.
    #[error(
        "a plane of {area_mm2:.0} mm² lies {above_mm:.1} mm nearer the camera than the only coplanar pair \
         (plates of {smaller_mm2:.0} mm² and more): the pair may be the table on both sides of a workpiece whose \
         plates are seen as one, across a gap narrower than the cloud resolves"
    )]
    PairUnderLargerPlane { area_mm2: f64, above_mm: f64, smaller_mm2: f64 },
    /// A butt joint was asked for, but the nearest plates lie in two
    /// layers one plate thickness apart, as a lap's do.
    #[error(
        "no two plates lie in one plane for a {joint} joint, but the nearest two lie {step_mm:.1} mm apart along \
         the normal, one over the other: this looks like a lap joint, not the {joint} joint requested"
    )]
    LooksLikeLap { joint: JointType, step_mm: f64 },
    /// A lap joint was asked for, but the upper layer holds two plates
    /// side by side, as butt plates lie.
    #[error(
        "the upper layer holds two plates side by side in one plane ({first_mm2:.0} and {second_mm2:.0} mm²), \
         coplanar within {tolerance_mm} mm: this looks like a butt joint, not the lap requested"
    )]
    LooksLikeButt { first_mm2: f64, second_mm2: f64, tolerance_mm: f64 },
    /// A nearer plane lies across the plane the plates were sought in,
    /// which is seen on both of its long sides: a tee's web on its flange,
    /// or an object lying on the workpiece; not a plate of a butt or lap
    /// joint. The layers alone cannot tell the two apart.
    #[error(
        "a long plane of {top_mm2:.0} mm², {above_mm:.1} mm nearer the camera, lies across the plane under it, \
         which is seen on both of its sides ({first_mm2:.0} and {second_mm2:.0} mm²): the web of a tee joint \
         standing on its flange (tee joints are not planned), or an object lying on the workpiece (a clamp or a \
         bar) over the joint; a lap's upper plate ends on its lower plate, and butt plates are not one plane cut \
         in two; for a clamp, clear the joint or set a region of interest beside it"
    )]
    LiesAcross { top_mm2: f64, above_mm: f64, first_mm2: f64, second_mm2: f64 },
    /// The joint type was left to the planner, and the nearest layer holds
    /// a plate and a piece too small to be a plate beside it, over a lower
    /// plane one plate thickness behind: butt plates, one barely seen, or a
    /// lap's upper plate that a gap in the cloud cut in two.
    #[error(
        "the nearest layer holds a plate of {first_mm2:.0} mm² and a piece of {second_mm2:.0} mm² beside it, \
         {step_mm:.1} mm over a lower plane: two butt plates, one barely in view, or a lap's upper plate cut in two \
         by a gap in the cloud; the joint type cannot be told: name it in the request"
    )]
    Ambiguous { first_mm2: f64, second_mm2: f64, step_mm: f64 },
    /// The joint type was left to the planner, and the layers fit neither
    /// layout.
    #[error("the joint type cannot be told from the plates: not a butt joint ({butt}); not a lap ({lap})")]
    Unrecognised { butt: Box<BackgroundError>, lap: Box<BackgroundError> },
}

impl BackgroundError {
    /// Whether the error says the joint seen is not the joint requested.
    pub fn is_joint_mismatch(&self) -> bool {
        matches!(self, BackgroundError::LooksLikeLap { .. } | BackgroundError::LooksLikeButt { .. })
    }

    /// Whether the joint type was left to the planner and could not be told.
    pub fn is_unrecognised(&self) -> bool {
        matches!(self, BackgroundError::Unrecognised { .. } | BackgroundError::Ambiguous { .. })
    }
}

/// How large the second plate of a layer must be, against the first, to
/// count as a plate beside it rather than a piece of fixture or a clamp.
const SIDE_BY_SIDE_AREA_RATIO: f64 = 0.25;

/// A plane at least this many times longer than wide is a bar that can lie
/// across another plane, cutting it in two.
const BAR_ELONGATION: f64 = 2.0;

/// Whether `top`, nearer the camera, lies across the plane that `a` and
/// `b` are pieces of: `top` is long and narrow, and the two lie on
/// opposite sides of its long axis. A lap's upper plate ends on its lower
/// plate, so the lower one is seen on one side of it only; two butt
/// plates have nothing lying along the gap between them.
fn lies_across(top: &PlaneCluster, a: &PlaneCluster, b: &PlaneCluster, normal: &Vec3) -> bool {
    if top.elongation < BAR_ELONGATION {
        return false;
    }
    let across = normal.cross(&top.long_axis);
    let side = |c: &PlaneCluster| across.dot(&(c.centroid - top.centroid));
    side(a) * side(b) < 0.0
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
            let moments: Moments =
                m.iter().step_by(stride).map(|&i| vec3(&points[i as usize])).collect::<Vec<_>>().iter().collect();
            let plane = moments.plane()?;
            let centroid = moments.centroid()?;
            let area_mm2 = m.len() as f64 * area_per_point(&centroid, &plane.normal);
            let (long_axis, elongation) = moments.elongation()?;
            Some(PlaneCluster { label: label as u32, members: m, plane, centroid, area_mm2, long_axis, elongation })
        })
        .collect()
}

/// The paper's rule: delete the cluster with the largest xy bounding box,
/// keep the two largest of the rest.
pub fn paper_select(cloud: &PointCloud, mut planes: Vec<PlaneCluster>) -> Result<Workpiece, BackgroundError> {
    let points = cloud.points();
    let bbox_area = |c: &PlaneCluster| {
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for &i in &c.members {
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
        (Some(a), Some(b)) => {
            Ok(Workpiece { plates: [a, b], depth_to_support_mm: None, layer_mates: Default::default() })
        }
        _ => Err(BackgroundError::TooFewPlanes { found }),
    }
}

/// How the two plates of a joint lie: side by side in one plane (butt
/// joints, V or I), or one on the other a plate thickness apart (lap).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Butt,
    Lap,
}

impl Layout {
    pub fn of(joint: JointType) -> Layout {
        match joint {
            // A tee's flange shows either side of the web in one plane
            // (a tee request itself is refused before any stage runs).
            JointType::VButt | JointType::IButt | JointType::TFillet => Layout::Butt,
            JointType::Lap => Layout::Lap,
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
    /// Clusters whose normal is further than this from `normal` are not
    /// workpiece planes.
    pub max_tilt_deg: f64,
}

/// The two plates the robust rule chose, how they lie, and in words why.
#[derive(Debug, Clone)]
pub struct Selected {
    pub workpiece: Workpiece,
    pub layout: Layout,
    /// What the layers showed: the plates' offsets and areas, and for an
    /// automatic choice why the other layout was not it.
    pub evidence: String,
}

/// The clusters sorted into layers along the normal, nearest the camera
/// first, each layer's clusters largest first.
struct Layers {
    layers: Vec<Vec<PlaneCluster>>,
    normal: Vec3,
    found: usize,
    offsets_mm: Vec<f64>,
}

impl Layers {
    fn offset(&self, c: &PlaneCluster) -> f64 {
        self.normal.dot(&c.centroid)
    }

    /// The offset of layer `k`'s largest cluster.
    fn depth(&self, k: usize) -> f64 {
        self.offset(&self.layers[k][0])
    }

    /// How far behind layer `k` the next layer lies, if there is one.
    fn depth_behind(&self, k: usize) -> Option<f64> {
        (k + 1 < self.layers.len()).then(|| self.depth(k + 1) - self.depth(k))
    }
}

/// Where a butt joint's plates are: the layer holding them.
fn find_butt(l: &Layers, s: &Selection, joint: JointType) -> Result<usize, BackgroundError> {
    let Some(pos) = l.layers.iter().position(|layer| layer.len() >= 2) else {
        // Say what the layers look like when they look like a lap.
        if l.layers.len() >= 2 {
            let step_mm = l.depth(1) - l.depth(0);
            if (s.lap_step_min_mm..=s.lap_step_max_mm).contains(&step_mm) {
                return Err(BackgroundError::LooksLikeLap { joint, step_mm });
            }
        }
        return Err(BackgroundError::NoCoplanarPair { found: l.found, offsets_mm: l.offsets_mm.clone() });
    };
    // The plates are the workpiece's top: a nearer plane may be a clamp,
    // but not one larger than a plate. One lying across the pair (a clamp,
    // or a tee's web on its flange) stands between the pair's edges, where
    // the groove probe sees it and says which.
    let smaller_mm2 = l.layers[pos][1].area_mm2;
    if let Some(cover) = l.layers[..pos].iter().map(|layer| &layer[0]).find(|c| c.area_mm2 > smaller_mm2) {
        return Err(BackgroundError::PairUnderLargerPlane {
            area_mm2: cover.area_mm2,
            above_mm: l.depth(pos) - l.offset(cover),
            smaller_mm2,
        });
    }
    Ok(pos)
}

/// Where a lap's plates are: the upper and the lower layer.
fn find_lap(l: &Layers, s: &Selection) -> Result<(usize, usize), BackgroundError> {
    for upper in 0..l.layers.len() {
        for lower in upper + 1..l.layers.len() {
            let step = l.depth(lower) - l.depth(upper);
            if step > s.lap_step_max_mm {
                break;
            }
            if step >= s.lap_step_min_mm {
                // Two plates side by side on top are a butt joint's.
                if let [first, second, ..] = l.layers[upper].as_slice()
                    && second.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * first.area_mm2
                {
                    return Err(BackgroundError::LooksLikeButt {
                        first_mm2: first.area_mm2,
                        second_mm2: second.area_mm2,
                        tolerance_mm: s.coplanar_tolerance_mm,
                    });
                }
                // The lower plate seen on both sides of the upper one: the
                // upper one lies across it.
                let (top, under) = (&l.layers[upper][0], &l.layers[lower]);
                if let Some(piece) = under[1..].iter().find(|c| {
                    c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * under[0].area_mm2
                        && lies_across(top, &under[0], c, &l.normal)
                }) {
                    return Err(BackgroundError::LiesAcross {
                        top_mm2: top.area_mm2,
                        above_mm: step,
                        first_mm2: under[0].area_mm2,
                        second_mm2: piece.area_mm2,
                    });
                }
                return Ok((upper, lower));
            }
        }
    }
    Err(BackgroundError::NoLapStep {
        found: l.found,
        offsets_mm: l.offsets_mm.clone(),
        min_mm: s.lap_step_min_mm,
        max_mm: s.lap_step_max_mm,
    })
}

/// The robust rule: plates are the nearest parallel layers that fit the
/// joint type; with no type given, the layers decide: two plates side by
/// side in the nearest such layer make a butt joint, two layers a plate
/// thickness apart with one plate on top a lap, and where both fit, the
/// one whose top plate is nearer the camera (the workpiece's top) unless
/// that top is too small beside the butt plates to be a plate (a clamp).
pub fn robust_select(planes: Vec<PlaneCluster>, s: &Selection) -> Result<Selected, BackgroundError> {
    let cos_tilt = s.max_tilt_deg.to_radians().cos();
    let mut planes: Vec<PlaneCluster> =
        planes.into_iter().filter(|c| c.plane.normal.dot(&s.normal) >= cos_tilt).collect();
    let found = planes.len();
    if found < 2 {
        return Err(BackgroundError::TooFewPlanes { found });
    }
    let offset = |c: &PlaneCluster| s.normal.dot(&c.centroid);
    planes.sort_by(|a, b| offset(a).total_cmp(&offset(b)));
    let offsets_mm: Vec<f64> = planes.iter().map(|c| (offset(c) * 10.0).round() / 10.0).collect();

    // Layers: runs of clusters whose offsets agree, nearest the camera first.
    let mut layers: Vec<Vec<PlaneCluster>> = Vec::new();
    for c in planes {
        match layers.last_mut() {
            Some(layer) if offset(&c) - offset(&layer[0]) <= s.coplanar_tolerance_mm => layer.push(c),
            _ => layers.push(vec![c]),
        }
    }
    for layer in &mut layers {
        layer.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    }
    let l = Layers { layers, normal: s.normal, found, offsets_mm };

    let butt = |l: &Layers, pos: usize, why: String| {
        let [a, b] = [&l.layers[pos][0], &l.layers[pos][1]];
        let evidence = format!(
            "two plates side by side ({:.0} and {:.0} mm², {:.1} mm apart along the normal){why}",
            a.area_mm2,
            b.area_mm2,
            (l.offset(b) - l.offset(a)).abs()
        );
        (Layout::Butt, [(pos, 0), (pos, 1)], l.depth_behind(pos), evidence)
    };
    let lap = |l: &Layers, (upper, lower): (usize, usize), why: String| {
        let evidence = format!(
            "an upper plate of {:.0} mm² {:.1} mm over a lower one of {:.0} mm²{why}",
            l.layers[upper][0].area_mm2,
            l.depth(lower) - l.depth(upper),
            l.layers[lower][0].area_mm2
        );
        (Layout::Lap, [(upper, 0), (lower, 0)], l.depth_behind(lower), evidence)
    };
    let (layout, picks, depth_to_support_mm, evidence) = match s.joint {
        Some(joint) if Layout::of(joint) == Layout::Butt => butt(&l, find_butt(&l, s, joint)?, String::new()),
        Some(_) => lap(&l, find_lap(&l, s)?, String::new()),
        None => match (find_butt(&l, s, JointType::IButt), find_lap(&l, s)) {
            // A plate over the pair, not a clamp: as large as a plate beside
            // it, and over a lower plate of its own, not lying across the
            // pair (a clamp or a fixture over a butt joint's gap).
            (Ok(pos), Ok(lap_layers))
                if lap_layers.0 < pos
                    && lap_layers.1 != pos
                    && l.layers[lap_layers.0][0].area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * l.layers[pos][1].area_mm2 =>
            {
                lap(&l, lap_layers, " nearer the camera than the nearest coplanar pair".into())
            }
            // The lap's upper layer is the pair's, and the lap found no
            // second plate beside the first there: a plate and a piece.
            (Ok(pos), Ok((upper, lower))) if upper == pos => {
                return Err(BackgroundError::Ambiguous {
                    first_mm2: l.layers[pos][0].area_mm2,
                    second_mm2: l.layers[pos][1].area_mm2,
                    step_mm: l.depth(lower) - l.depth(upper),
                });
            }
            (Ok(pos), _) => butt(&l, pos, String::new()),
            (Err(BackgroundError::LooksLikeLap { .. }), Ok(lap_layers)) => {
                lap(&l, lap_layers, ", and no two plates side by side in one plane".into())
            }
            (Err(butt_error), Ok(lap_layers)) => lap(&l, lap_layers, format!("; not a butt joint: {butt_error}")),
            (Err(butt), Err(lap)) => {
                return Err(BackgroundError::Unrecognised { butt: Box::new(butt), lap: Box::new(lap) });
            }
        },
    };
    // Take the two plates out of their layers, the later pick first so the
    // earlier one's place does not move.
    let mut layers = l.layers;
    let mut take = |(layer, k): (usize, usize)| layers[layer].swap_remove(k);
    let (second, first) = (take(picks[1]), take(picks[0]));
    let layer_mates = [layers[picks[0].0].clone(), std::mem::take(&mut layers[picks[1].0])];
    let workpiece = Workpiece { plates: [first, second], depth_to_support_mm, layer_mates };
    Ok(Selected { workpiece, layout, evidence })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plate as long along y as it is wide across x.
    fn cluster(offset: f64, area: f64, centre_x: f64) -> PlaneCluster {
        PlaneCluster {
            label: 0,
            members: vec![0; area as usize],
            plane: Plane { normal: Vec3::z(), offset },
            centroid: Vec3::new(centre_x, 0.0, offset),
            area_mm2: area,
            long_axis: Vec3::y(),
            elongation: 1.0,
        }
    }

    /// A bar along y, five times longer than wide.
    fn bar(offset: f64, area: f64, centre_x: f64) -> PlaneCluster {
        PlaneCluster { elongation: 5.0, ..cluster(offset, area, centre_x) }
    }

    fn selection(joint: JointType) -> Selection {
        Selection { joint: Some(joint), ..auto() }
    }

    fn auto() -> Selection {
        Selection {
            joint: None,
            normal: Vec3::z(),
            coplanar_tolerance_mm: 3.0,
            lap_step_min_mm: 1.0,
            lap_step_max_mm: 30.0,
            max_tilt_deg: 10.0,
        }
    }

    #[test]
    fn a_split_table_is_not_taken_for_a_plate() {
        // Two table pieces, larger than the plates, 40 mm further away.
        let planes = vec![
            cluster(740.0, 90_000.0, -300.0),
            cluster(700.0, 20_000.0, -50.0),
            cluster(740.0, 80_000.0, 300.0),
            cluster(700.5, 25_000.0, 50.0),
        ];
        let w = robust_select(planes, &selection(JointType::IButt)).unwrap().workpiece;
        assert!(w.plates.iter().all(|p| p.plane.offset < 701.0));
    }

    #[test]
    fn table_pieces_under_plates_seen_as_one_are_refused() {
        // The plates merged across an unresolved gap (one plane), the table
        // 34 mm below split in two by the workpiece: no seam lies between
        // the table pieces, whatever their edges look like.
        let planes =
            vec![cluster(905.0, 160_000.0, 0.0), cluster(939.0, 40_000.0, -250.0), cluster(939.3, 30_000.0, 250.0)];
        let err = robust_select(planes, &selection(JointType::IButt)).unwrap_err();
        assert!(matches!(err, BackgroundError::PairUnderLargerPlane { .. }), "{err}");
        assert!(err.to_string().contains("34.0 mm nearer the camera"), "{err}");
        // A clamp on the plates is smaller than either plate and is passed over.
        let planes =
            vec![cluster(880.0, 2_000.0, 0.0), cluster(905.0, 60_000.0, -100.0), cluster(905.2, 50_000.0, 100.0)];
        let w = robust_select(planes, &selection(JointType::IButt)).unwrap().workpiece;
        assert!(w.plates.iter().all(|p| p.plane.offset > 904.0));
    }

    #[test]
    fn plates_filling_the_view_are_both_kept() {
        let planes = vec![cluster(700.0, 70_000.0, -100.0), cluster(700.2, 60_000.0, 100.0)];
        assert!(robust_select(planes, &selection(JointType::VButt)).is_ok());
    }

    #[test]
    fn lap_takes_the_nearest_layers_one_thickness_apart_upper_first() {
        let planes =
            vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
        let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
        assert_eq!(w.plates[0].plane.offset, 700.0);
        assert_eq!(w.plates[1].plane.offset, 706.0);
    }

    #[test]
    fn a_bar_lying_across_a_plate_is_no_lap() {
        // A clamp 15 mm over one plate, which is seen on both of its sides;
        // the other plate lies 7 mm lower, the table further.
        let planes = || {
            vec![
                bar(685.0, 8_000.0, 0.0),
                cluster(700.0, 9_000.0, -40.0),
                cluster(700.0, 8_500.0, 40.0),
                cluster(707.0, 14_000.0, 80.0),
                cluster(760.0, 90_000.0, 0.0),
            ]
        };
        let lap = robust_select(planes(), &selection(JointType::Lap)).unwrap_err();
        assert!(matches!(lap, BackgroundError::LiesAcross { .. }), "{lap}");
        assert!(lap.to_string().contains("clamp"), "{lap}");
        // As butt plates, the two sides are a pair, and what lies between
        // their edges is the groove probe's to name.
        let butt = robust_select(planes(), &selection(JointType::IButt)).unwrap();
        assert_eq!(butt.workpiece.plates.each_ref().map(|p| p.plane.offset), [700.0, 700.0]);
        assert_eq!(robust_select(planes(), &auto()).unwrap().layout, Layout::Butt);
    }

    #[test]
    fn a_lap_whose_lower_plate_is_seen_on_one_side_only_is_kept() {
        // The lower plate split in two along the seam (a streak), both
        // pieces beside the upper plate on the same side of it.
        let mut planes = vec![
            bar(700.0, 20_000.0, 0.0),
            cluster(706.0, 15_000.0, 60.0),
            cluster(706.0, 12_000.0, 60.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        planes[1].centroid.y = -80.0;
        planes[2].centroid.y = 80.0;
        let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
        assert_eq!(w.plates[0].plane.offset, 700.0);
        assert_eq!(w.plates[1].area_mm2, 15_000.0);
    }

    #[test]
    fn the_wrong_joint_requested_is_named_for_what_it_looks_like() {
        // A lap: the upper plate 6 mm over the lower one, the table behind.
        let lap = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
        for joint in [JointType::IButt, JointType::VButt] {
            let err = robust_select(lap.clone(), &selection(joint)).unwrap_err();
            assert!(err.is_joint_mismatch(), "{err}");
            assert!(err.to_string().contains("6.0 mm apart") && err.to_string().contains("looks like a lap"), "{err}");
        }
        // Butt plates side by side, the table 20 mm behind them (within a
        // lap's step range).
        let butt = vec![cluster(700.0, 30_000.0, -60.0), cluster(700.3, 25_000.0, 60.0), cluster(720.0, 90_000.0, 0.0)];
        let err = robust_select(butt.clone(), &selection(JointType::Lap)).unwrap_err();
        assert!(err.is_joint_mismatch() && err.to_string().contains("looks like a butt joint"), "{err}");
        assert!(robust_select(butt, &selection(JointType::IButt)).is_ok());
        // A clamp beside a lap's upper plate is not a second plate.
        let clamped = vec![
            cluster(700.0, 30_000.0, -60.0),
            cluster(700.5, 2_000.0, 60.0),
            cluster(706.0, 20_000.0, 50.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        assert!(robust_select(clamped, &selection(JointType::Lap)).is_ok());
    }

    #[test]
    fn with_no_type_given_the_layers_decide() {
        let lap = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
        let chosen = robust_select(lap, &auto()).unwrap();
        assert_eq!(chosen.layout, Layout::Lap);
        assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.plane.offset), [700.0, 706.0]);
        assert!(chosen.evidence.contains("6.0 mm over"), "{}", chosen.evidence);
        let butt = vec![cluster(700.0, 30_000.0, -60.0), cluster(700.3, 25_000.0, 60.0), cluster(720.0, 90_000.0, 0.0)];
        let chosen = robust_select(butt, &auto()).unwrap();
        assert_eq!(chosen.layout, Layout::Butt);
        assert_eq!(chosen.workpiece.depth_to_support_mm, Some(20.0));
        // A plate over a lower plate of its own, nearer than a coplanar
        // pair further on: the nearer top decides.
        let over = vec![
            cluster(694.0, 8_000.0, 0.0),
            cluster(700.0, 30_000.0, -60.0),
            cluster(710.0, 25_000.0, 60.0),
            cluster(710.3, 25_000.0, 160.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        assert_eq!(robust_select(over.clone(), &auto()).unwrap().layout, Layout::Lap);
        // A plate lying across a coplanar pair (a clamp or a fixture) is
        // not a lap's upper plate, however large.
        let across = vec![
            cluster(694.0, 20_000.0, 0.0),
            cluster(700.0, 30_000.0, -60.0),
            cluster(700.3, 25_000.0, 60.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        assert_eq!(robust_select(across, &auto()).unwrap().layout, Layout::Butt);
        // A plate with a small piece beside it, 4 mm over a lower plane: a
        // butt pair barely in view, or a lap's upper plate cut by a streak.
        let piece = vec![
            cluster(700.0, 20_000.0, 0.0),
            cluster(700.0, 1_600.0, -70.0),
            cluster(704.0, 40_000.0, -120.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        let err = robust_select(piece.clone(), &auto()).unwrap_err();
        assert!(matches!(err, BackgroundError::Ambiguous { .. }) && err.is_unrecognised(), "{err}");
        assert_eq!(robust_select(piece, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
        // Two planes 60 mm apart are neither.
        let apart = vec![cluster(700.0, 1000.0, 0.0), cluster(760.0, 1000.0, 0.0)];
        let err = robust_select(apart, &auto()).unwrap_err();
        assert!(err.is_unrecognised() && !err.is_joint_mismatch(), "{err}");
        assert!(err.to_string().contains("no two coplanar") && err.to_string().contains("no two layers"), "{err}");
    }

    #[test]
    fn failures_say_what_was_found() {
        let one = vec![cluster(700.0, 1000.0, 0.0)];
        assert_eq!(
            robust_select(one, &selection(JointType::IButt)).unwrap_err().to_string(),
            "found 1 workpiece plane(s), need 2"
        );
        let apart = vec![cluster(700.0, 1000.0, 0.0), cluster(760.0, 1000.0, 0.0)];
        assert!(matches!(
            robust_select(apart.clone(), &selection(JointType::IButt)),
            Err(BackgroundError::NoCoplanarPair { .. })
        ));
        assert!(matches!(robust_select(apart, &selection(JointType::Lap)), Err(BackgroundError::NoLapStep { .. })));
    }
}
