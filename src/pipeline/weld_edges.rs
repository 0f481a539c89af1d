//! Weld edge lines by centroid positioning (section 4.1, Eq. 16): the two
//! plate edges beside the weld are the lines that have the two plates'
//! centroids on opposite sides, `f_edge(C1) · f_edge(C2) < 0`.
//!
//! The paper tests the sign in the xoy projection over all lines. The
//! robust variant tests it in the plate's own plane (exact at any tilt),
//! takes one line from each plate, requires the two to be parallel, and
//! among the candidates keeps the pair facing each other most closely, so
//! a stray line through a hole or along the image border is not chosen.
//! Where the plates also face each other along another edge, turned from
//! that pair as a part's end is from its side, for a longer stretch, the
//! nearest pair is no answer: an object lying on a plate (a clamp over a
//! lap's upper plate) faces the plane under it along its end and along
//! its sides, a lap's upper plate may end on its lower plate, and the
//! longer stretch is as likely the joint as the nearer one. That is
//! refused. A lap's lower plate may show beside its upper plate's side
//! only as a sliver (barely in view) whose lines separate no centroids,
//! so no pair stands for the side: for a lap the stretch the lower plate
//! is seen beside each of the upper plate's edges is read from its points
//! ([`check_lap_edge`]) and refused the same way. It is refused too
//! where the lower plate runs beside an end of the upper plate along all
//! of it: a lap's upper plate reaches past its lower plate's edge, and a
//! plate lying on the table with its far edge out of view (butt plates
//! the cloud sees as one) shows the same two layers. Where the request
//! leaves a butt joint open, the upper plate must also be seen to end off
//! the plane under it somewhere besides the weld edge
//! ([`check_lap_ends_off_lower_plane`]): a step between two planes and
//! nothing else is a lap's, and a plate's lying on the table, alike.
//!
//! Each refusal is a rule of [`crate::rules::weld_edges`]
//! ([`WeldEdgeError::rule`]).

use crate::geometry::{Vec3, extent};
use crate::rules::{self, Rule};

use super::boundary::{CoarseEdge, SpannedEdge};
use super::ransac::EdgeLine;

/// Eq. 16's edge function in the xoy projection: the signed area of the
/// projected line and the point.
fn xoy_side(line: &EdgeLine, c: &Vec3) -> f64 {
    let d = line.direction;
    (c.x - line.point.x) * d.y - (c.y - line.point.y) * d.x
}

/// Eq. 16's edge function measured in the plane with normal `n`.
fn in_plane_side(line: &EdgeLine, n: &Vec3, c: &Vec3) -> f64 {
    (c - line.point).cross(&line.direction).dot(n)
}

/// Why the weld edges could not be chosen.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WeldEdgeError {
    /// Fewer than two lines separate the centroids.
    #[error("{found} of {lines} edge lines separate the two plates' centroids, need 2")]
    TooFewSeparating { found: usize, lines: usize },
    /// Separating lines exist but no pair of them is parallel.
    #[error("no separating edge line of one plate is within {max_angle_deg}° of one of the other plate")]
    NotParallel { max_angle_deg: f64 },
    /// The nearest facing pair shares a shorter stretch than another
    /// facing pair along another edge.
    #[error(
        "the two plates face each other along two edges {angle_deg:.0}° apart: the nearest pair for {nearest_mm:.0} \
         mm, the other for {longer_mm:.0} mm; an object lying on a plate (a clamp) faces the plane under it along \
         its end and its sides, and a lap's upper plate may end on its lower plate: which edge is the joint is not \
         clear"
    )]
    TwoFacingEdges { nearest_mm: f64, longer_mm: f64, angle_deg: f64 },
    /// A lap's lower plate is seen beside another edge of the upper
    /// plate, turned from the chosen one, for longer than beside it.
    #[error(
        "the lap's lower plate is seen beside the upper plate's chosen edge for {chosen_mm:.0} mm and beside \
         another of its edges, {angle_deg:.0}° from it, for {longer_mm:.0} mm: the upper plate may end on the lower \
         plate, or the lower plate may be seen only as a sliver along the joint; which edge is the joint is not clear"
    )]
    LowerPlateBesideOtherEdge { chosen_mm: f64, longer_mm: f64, angle_deg: f64 },
    /// A lap's lower plate is seen beside an end of the upper plate along
    /// all of it: the upper plate does not reach past the lower plate's
    /// edge anywhere in view, as a lap's upper plate does.
    #[error(
        "the lap's lower plate is seen beside the upper plate's end ({angle_deg:.0}° from the chosen edge) along \
         {seen_mm:.0} of its {end_mm:.0} mm: a lap's upper plate reaches past its lower plate's edge, and this one \
         does not anywhere in view; it may lie wholly on the plane under it (a part on the table, or butt plates \
         seen as one across a gap the cloud does not resolve); bring the upper plate's far edge into view"
    )]
    UpperPlateOnLowerPlane { seen_mm: f64, end_mm: f64, angle_deg: f64 },
    /// The plane under a lap's upper plate (its lower plate's layer) is
    /// seen beside the upper plate's far edge too: the upper plate lies on
    /// it whole.
    #[error(
        "the plane under the lap's upper plate is seen beside its far edge too, along {seen_mm:.0} of its \
         {far_mm:.0} mm, as beside the chosen edge: the upper plate lies on it whole, not on a lower plate that \
         ends under it (a part on the table or on spacers, such as butt plates seen as one across a gap the cloud \
         does not resolve, or a plate lapped on a larger one all round, whose weld edge the frame does not tell)"
    )]
    UpperPlateWithinLowerLayer { seen_mm: f64, far_mm: f64 },
    /// Under a request that leaves a butt joint open, a lap's upper plate
    /// seen to end off the plane under it nowhere but along the chosen
    /// edge: the frame shows one step between two planes, and what the
    /// lower one is does not show.
    #[error(
        "the joint type cannot be told: the lap's upper plate is seen to end off the plane under it only along the \
         chosen edge ({edges}), so the frame shows one step between two planes and nothing else; a lap's plates \
         show that, and so does a workpiece seen as one plane over what it rests on (a plate on the table, or butt \
         plates closer together than the cloud resolves); request lap to plan it as a lap, or bring an end or the \
         far edge of the upper plate into view"
    )]
    StepAlone { edges: String },
}

impl WeldEdgeError {
    /// Whether the weld edges were chosen but the joint they make cannot be
    /// told from the frame (for `auto`, the `joint_unknown` gate).
    pub fn is_unknown(&self) -> bool {
        matches!(self, WeldEdgeError::StepAlone { .. })
    }

    /// The rule that refused.
    pub fn rule(&self) -> &'static Rule {
        match self {
            WeldEdgeError::TooFewSeparating { .. } => &rules::weld_edges::NO_LINE_BETWEEN_PLATES,
            WeldEdgeError::NotParallel { .. } => &rules::weld_edges::NO_PARALLEL_PAIR,
            WeldEdgeError::TwoFacingEdges { .. } => &rules::weld_edges::TWO_FACING_EDGES,
            WeldEdgeError::LowerPlateBesideOtherEdge { .. } => &rules::weld_edges::LOWER_PLATE_BESIDE_OTHER_EDGE,
            WeldEdgeError::UpperPlateOnLowerPlane { .. } => &rules::weld_edges::UPPER_PLATE_NOT_PAST_LOWER,
            WeldEdgeError::UpperPlateWithinLowerLayer { .. } => &rules::weld_edges::UPPER_PLATE_WITHIN_LOWER_LAYER,
            WeldEdgeError::StepAlone { .. } => &rules::weld_edges::UPPER_PLATE_ENDS_OFF_LOWER,
        }
    }
}

/// One of the upper plate's other edges (turned from the lap's weld edge,
/// an end of the plate, or parallel to it on the plate's far side), and
/// the stretch of it the lower plate is seen beside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtherEdge {
    /// The edge's line among the upper plate's.
    pub line: usize,
    /// How long the line's inliers reach along it, mm.
    pub length_mm: f64,
    /// How much of that the lower plate is seen beside, mm.
    pub seen_mm: f64,
}

/// One of a lap's upper plate's other edges, as
/// [`check_lap_ends_off_lower_plane`] reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeSeen {
    /// How long the line's inliers reach along it, mm.
    pub length_mm: f64,
    /// Where the line lies.
    pub lies: EdgeLies,
    /// How much of it the plane under the plate is seen beside, read from
    /// every point on that plane, mm.
    pub plane_beside_mm: f64,
}

/// What an edge line of a plate is: where the plate ends, or only where
/// it stops being seen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EdgeLies {
    /// The plate ends there, inside the view.
    InView,
    /// Along the view's border: the plate runs on out of the image.
    AlongBorder,
    /// With the plate seen again beyond it (a slit through the plate, such
    /// as a butt joint's gap the cloud resolves along part of it).
    WithinPlate,
}

/// The share of an end of a lap's upper plate beside which the lower
/// plate, seen there, shows the upper plate lying on it all the way
/// across. A lap's lower plate ends under its upper plate, so beside the
/// upper plate's end it is seen only as far as the two overlap: at most
/// 53 % of the end on the simulated laps (plates 60 to 250 mm wide,
/// overlapping by 20 to 60 mm, staggered along the seam in some scenes)
/// of the eval, fault, hard and consumer suites in organized frames, of
/// the eval, fault, hard, consumer-far and several-workpiece suites at
/// 1 mm voxels, and of the eval suite cropped. A plate lying on the
/// table with no far edge in view has the table seen beside 96 and 97 %
/// of its ends: bins at the corners, where an end's line has its last
/// inliers, keep a whole end from reading 100 %.
const LOWER_PLATE_ALONG_END_SHARE: f64 = 0.9;

/// The share of the upper plate's far edge (parallel to the weld edge, on
/// the plate's other side) beside which the lower plate's layer, seen
/// there, shows the upper plate lying on it whole. A lap's lower plate
/// ends under its upper plate, so beyond the far edge lies whatever the
/// lower plate rests on: the layer is seen beside 0 % of the far edge on
/// every lap of the eval, fault, hard, consumer, consumer-far and
/// several-workpiece suites, organized and at 1 mm voxels, and of the
/// eval and fault suites' scenes of any joint planned under `auto` at
/// 1 mm voxels. Butt plates on spacers that the voxels join into one
/// plate show the table beside 81 % (i-butt-06) and 100 % (an I-butt of
/// fresh draw 7 of the fault suite requested as a lap) of it. Half is
/// the rule: a far edge the layer runs beside for most of its length.
const LOWER_LAYER_BESIDE_FAR_EDGE_SHARE: f64 = 0.5;

/// How far from the nearest pair another facing pair must turn to be
/// another edge of the plates rather than a stray line: a part's end
/// meets its side at a right angle, and a line through a corner of the
/// plate's outline, or along the image border where it cuts the plates,
/// runs at any angle (31° on the hard suite's lap-10, whose seam the
/// nearest pair is).
const OTHER_EDGE_MIN_ANGLE_DEG: f64 = 60.0;

/// The least stretch two weld edges must share along the seam, as a
/// fraction of the shorter one's: facing edges share most of theirs (a
/// streak or a clamp may cut one into pieces, each still beside the
/// other edge), edges meeting end to end share none.
const MIN_SHARED_SPAN: f64 = 0.25;

/// The paper's selection: of all lines, the two with the most inliers that
/// separate the centroids in the xoy plane. `owner(line)` tells which
/// plate (0 or 1) most of a line's inliers belong to; the result is
/// ordered by owner.
pub fn paper_select(
    lines: &[EdgeLine],
    centroids: [Vec3; 2],
    owner: impl Fn(&EdgeLine) -> usize,
) -> Result<[usize; 2], WeldEdgeError> {
    let mut separating: Vec<usize> = (0..lines.len())
        .filter(|&k| xoy_side(&lines[k], &centroids[0]) * xoy_side(&lines[k], &centroids[1]) < 0.0)
        .collect();
    if separating.len() < 2 {
        return Err(WeldEdgeError::TooFewSeparating { found: separating.len(), lines: lines.len() });
    }
    separating.sort_by(|&a, &b| lines[b].inliers.len().cmp(&lines[a].inliers.len()));
    let (a, b) = (separating[0], separating[1]);
    Ok(if owner(&lines[a]) <= owner(&lines[b]) { [a, b] } else { [b, a] })
}

/// The robust selection over each plate's own lines. Returns the index of
/// the chosen line in each plate's list.
pub fn robust_select(
    lines: [&[EdgeLine]; 2],
    points: [&[Vec3]; 2],
    centroids: [Vec3; 2],
    normal: &Vec3,
    max_angle_deg: f64,
) -> Result<[usize; 2], WeldEdgeError> {
    let separating = |plate: usize| -> Vec<usize> {
        (0..lines[plate].len())
            .filter(|&k| {
                let l = &lines[plate][k];
                in_plane_side(l, normal, &centroids[0]) * in_plane_side(l, normal, &centroids[1]) < 0.0
            })
            .collect()
    };
    let (sep_a, sep_b) = (separating(0), separating(1));
    let found = sep_a.len() + sep_b.len();
    if sep_a.is_empty() || sep_b.is_empty() {
        return Err(WeldEdgeError::TooFewSeparating { found, lines: lines[0].len() + lines[1].len() });
    }
    let cos_max = max_angle_deg.to_radians().cos();
    let mid = |plate: usize, k: usize| -> Vec3 {
        let l = &lines[plate][k];
        let sum: Vec3 = l.inliers.iter().map(|&i| points[plate][i]).sum();
        sum / l.inliers.len().max(1) as f64
    };
    // Where each line's inliers run along its direction, from its point.
    let span = |plate: usize, k: usize, along: &Vec3| -> (f64, f64) {
        let l = &lines[plate][k];
        l.inliers
            .iter()
            .map(|&i| along.dot(&(points[plate][i] - l.point)))
            .fold((f64::MAX, f64::MIN), |(lo, hi), t| (lo.min(t), hi.max(t)))
    };
    // Every facing pair: how far apart, which lines, the stretch shared.
    let mut facing: Vec<(f64, [usize; 2], f64)> = Vec::new();
    for &a in &sep_a {
        for &b in &sep_b {
            let (la, lb) = (&lines[0][a], &lines[1][b]);
            if la.direction.dot(&lb.direction).abs() < cos_max {
                continue;
            }
            // Weld edges face each other across the joint: their inliers
            // run side by side. Two plates' outer edges meeting end to
            // end at a corner (a lap's upper plate ending on the lower
            // plate's outline) are collinear, nearer than any facing
            // pair, and share no stretch.
            let (along, offset) = (la.direction, la.direction.dot(&(lb.point - la.point)));
            let ((a0, a1), (b0, b1)) = (span(0, a, &along), span(1, b, &along));
            let (b0, b1) = (b0.min(b1) + offset, b0.max(b1) + offset);
            let shared = a1.min(b1) - a0.max(b0);
            if shared < MIN_SHARED_SPAN * (a1 - a0).min(b1 - b0) {
                continue;
            }
            // How far apart the two edges run: the facing pair is closest.
            let gap = la.distance(&mid(1, b)) + lb.distance(&mid(0, a));
            facing.push((gap, [a, b], shared));
        }
    }
    let &(_, best, shared) =
        facing.iter().min_by(|x, y| x.0.total_cmp(&y.0)).ok_or(WeldEdgeError::NotParallel { max_angle_deg })?;
    let turned = turned_from(lines[0], best[0]);
    let other_edge = facing
        .iter()
        .filter(|(_, [a, _], other)| *other > shared && turned.contains(a))
        .max_by(|x, y| x.2.total_cmp(&y.2));
    if let Some(&(_, [a, _], longer_mm)) = other_edge {
        return Err(WeldEdgeError::TwoFacingEdges {
            nearest_mm: shared,
            longer_mm,
            angle_deg: turn_deg(&lines[0][a], &lines[0][best[0]]),
        });
    }
    Ok(best)
}

/// Lines `which` of a plate as edges of the plate: laid in its plane
/// (`normal`), the outward side away from the plate's `centroid`, the
/// span the reach of the line's inliers (in `points`) along it.
pub fn plate_edges(
    lines: &[EdgeLine],
    which: &[usize],
    points: &[Vec3],
    centroid: &Vec3,
    normal: &Vec3,
) -> Vec<SpannedEdge> {
    which
        .iter()
        .map(|&k| {
            let l = &lines[k];
            let direction =
                (l.direction - normal * normal.dot(&l.direction)).try_normalize(f64::EPSILON).unwrap_or(l.direction);
            let mut outward = normal.cross(&direction);
            if outward.dot(&(centroid - l.point)) > 0.0 {
                outward = -outward;
            }
            let (lo, hi) = extent(l.inliers.iter().map(|&i| direction.dot(&(points[i] - l.point))));
            SpannedEdge { edge: CoarseEdge { point: l.point, direction, outward }, span: [lo, hi] }
        })
        .collect()
}

/// The angle between two lines, 0 to 90°.
fn turn_deg(a: &EdgeLine, b: &EdgeLine) -> f64 {
    a.direction.dot(&b.direction).abs().min(1.0).acos().to_degrees()
}

/// The lines of a plate turned from line `chosen` as a part's end is from
/// its side ([`OTHER_EDGE_MIN_ANGLE_DEG`] or more).
pub fn turned_from(lines: &[EdgeLine], chosen: usize) -> Vec<usize> {
    let cos_other = OTHER_EDGE_MIN_ANGLE_DEG.to_radians().cos();
    let direction = lines[chosen].direction;
    (0..lines.len()).filter(|&k| lines[k].direction.dot(&direction).abs() <= cos_other).collect()
}

/// A lap's weld edge against the upper plate's other edges: the lower
/// plate is seen beside line `chosen` for `chosen_mm`, and beside each
/// of the `turned` edges ([`turned_from`] `chosen`, the plate's ends) and
/// the `far` ones (parallel to it, across the plate) for the stretch
/// given. A lap's upper plate may end on its lower plate,
/// which is then seen beside its end as well as its side; where the
/// lower plate shows only as a sliver along the side (barely in view),
/// the side's lines do not separate the centroids and the end's pair is
/// the only candidate. Where the lower plate runs beside a turned edge
/// for longer than beside the chosen one, which is the joint is not
/// clear: refused, as two facing edges are. Where it runs beside an end
/// along all of it ([`LOWER_PLATE_ALONG_END_SHARE`]), the upper plate
/// nowhere reaches past the lower plate's edge: a plate lying on the
/// table, its far edge out of view, shows the same layers as a lap, and
/// is refused. Where the lower plate's layer runs beside the far edge
/// too ([`LOWER_LAYER_BESIDE_FAR_EDGE_SHARE`]), the plate lies on it
/// whole, with its far edge in view: refused.
pub fn check_lap_edge(
    lines: &[EdgeLine],
    chosen: usize,
    chosen_mm: f64,
    turned: &[OtherEdge],
    far: &[OtherEdge],
) -> Result<(), WeldEdgeError> {
    let angle_deg = |e: &OtherEdge| turn_deg(&lines[e.line], &lines[chosen]);
    if let Some(longer) = turned.iter().filter(|e| e.seen_mm > chosen_mm).max_by(|a, b| a.seen_mm.total_cmp(&b.seen_mm))
    {
        return Err(WeldEdgeError::LowerPlateBesideOtherEdge {
            chosen_mm,
            longer_mm: longer.seen_mm,
            angle_deg: angle_deg(longer),
        });
    }
    if let Some(end) =
        turned.iter().find(|e| e.length_mm > 0.0 && e.seen_mm >= LOWER_PLATE_ALONG_END_SHARE * e.length_mm)
    {
        return Err(WeldEdgeError::UpperPlateOnLowerPlane {
            seen_mm: end.seen_mm,
            end_mm: end.length_mm,
            angle_deg: angle_deg(end),
        });
    }
    match far.iter().find(|e| e.length_mm > 0.0 && e.seen_mm >= LOWER_LAYER_BESIDE_FAR_EDGE_SHARE * e.length_mm) {
        Some(edge) => Err(WeldEdgeError::UpperPlateWithinLowerLayer { seen_mm: edge.seen_mm, far_mm: edge.length_mm }),
        None => Ok(()),
    }
}

/// A lap's upper plate must be seen to end off the plane under it
/// somewhere besides its weld edge, where the request leaves a butt joint
/// open (as `auto` does). Each of `others` (the plate's ends and far
/// edges) comes with where it lies and the stretch of it beside which
/// the lower plane is seen, read from every point on that plane, not from
/// its clusters alone: the evidence must stand against the most the
/// cloud shows of that plane. An edge in view beside which the plane
/// runs along half of it or more ([`LOWER_PLANE_OFF_EDGE_SHARE`]) is the
/// plate lying on it there. Where no edge is left, the frame shows one
/// step between two planes and nothing else: a lap's plates, or a plate
/// or a workpiece seen as one lying on the table with its other edges
/// out of view. That is refused as not told; a request for a lap says
/// what the lower plane is, and does not ask this.
pub fn check_lap_ends_off_lower_plane(others: &[EdgeSeen]) -> Result<(), WeldEdgeError> {
    let off_plane = |e: &EdgeSeen| {
        e.lies == EdgeLies::InView && e.length_mm > 0.0 && e.plane_beside_mm < LOWER_PLANE_OFF_EDGE_SHARE * e.length_mm
    };
    if others.iter().any(off_plane) {
        return Ok(());
    }
    let told: Vec<String> = [
        (EdgeLies::AlongBorder, "along the image's border"),
        (EdgeLies::WithinPlate, "with the plate seen beyond"),
        (EdgeLies::InView, "in view with the plane under it beside"),
    ]
    .into_iter()
    .filter_map(|(lies, what)| {
        let count = others.iter().filter(|e| e.lies == lies && e.length_mm > 0.0).count();
        (count > 0).then(|| format!("{count} {what}"))
    })
    .collect();
    let edges = match told.as_slice() {
        [] => "no other edge of it is in view".to_string(),
        _ => format!("its other edges: {}", told.join(", ")),
    };
    Err(WeldEdgeError::StepAlone { edges })
}

/// The share of an upper plate's edge in view beside which the plane
/// under it, read from every point on it, shows the plate lying on it
/// there rather than ending off it. A lap's lower plate ends under its
/// upper plate: beyond the far edge it is not seen, and beside an end
/// only where the two overlap. Every lap of the eval, fault, hard,
/// consumer-far and several-workpiece suites, organized and at 1 mm
/// voxels, of the consumer suite organized, of the eval and fault suites
/// at 0.5 mm voxels and of the eval suite cropped has an edge in view
/// reading 34 % or less (an end where the plates overlap over much of it
/// reads up to 54 %, on laps with another edge that counts). A plane
/// lying on the table whole, its corner in view, has the table beside
/// about 80 % of that corner's edge, the rest cut by the image's border.
const LOWER_PLANE_OFF_EDGE_SHARE: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;

    fn line(x: f64, along_y: bool, n: usize) -> EdgeLine {
        let direction = if along_y { Vec3::y() } else { Vec3::x() };
        EdgeLine { point: Vec3::new(x, 0.0, 600.0), direction, inliers: (0..n).collect() }
    }

    #[test]
    fn centroid_test_picks_the_facing_edges() {
        // Plate A spans x in [-100, -1], plate B x in [1, 100]; edges along y.
        let a_lines = vec![line(-100.0, true, 50), line(-1.0, true, 40), line(-50.0, false, 60)];
        let b_lines = vec![line(100.0, true, 50), line(1.0, true, 40)];
        let pts: Vec<Vec3> = (0..60).map(|i| Vec3::new(0.0, i as f64, 600.0)).collect();
        let a_pts: Vec<Vec3> = pts.iter().map(|p| p + Vec3::new(-1.0, 0.0, 0.0)).collect();
        let b_pts: Vec<Vec3> = pts.iter().map(|p| p + Vec3::new(1.0, 0.0, 0.0)).collect();
        let centroids = [Vec3::new(-50.0, 30.0, 600.0), Vec3::new(50.0, 30.0, 600.0)];
        let pick = robust_select([&a_lines, &b_lines], [&a_pts, &b_pts], centroids, &Vec3::z(), 10.0).unwrap();
        assert_eq!(pick, [1, 1]);
    }

    #[test]
    fn edges_meeting_end_to_end_are_not_a_facing_pair() {
        // Plate A's edge along y at x = -1 (y 0 to 100) faces plate B's at
        // x = +1; A also has an edge at x = +1 further down (y -100 to -5),
        // collinear with B's: nearer than any facing pair, sharing nothing.
        let run = |x: f64, y0: f64| (0..50).map(|i| Vec3::new(x, y0 + 2.0 * i as f64, 600.0)).collect::<Vec<_>>();
        let a_pts: Vec<Vec3> = [run(-1.0, 0.0), run(1.0, -100.0)].concat();
        let b_pts = run(1.0, 0.0);
        let along_y = |x: f64, inliers: std::ops::Range<usize>| EdgeLine {
            point: Vec3::new(x, 0.0, 600.0),
            direction: Vec3::y(),
            inliers: inliers.collect(),
        };
        let a_lines = vec![along_y(1.0, 50..100), along_y(-1.0, 0..50)];
        let b_lines = vec![along_y(1.0, 0..50)];
        let centroids = [Vec3::new(-50.0, 0.0, 600.0), Vec3::new(50.0, 50.0, 600.0)];
        let pick = robust_select([&a_lines, &b_lines], [&a_pts, &b_pts], centroids, &Vec3::z(), 10.0).unwrap();
        assert_eq!(pick, [1, 0]);
    }

    #[test]
    fn a_longer_facing_stretch_along_another_edge_is_refused() {
        // Plate A's end runs along x at y = 0 (x 0 to 30) and its side
        // along y at x = 30 (y 0 to 60); plate B faces the end 1 mm off
        // and the side 2 mm off, along as much of each: the end pair is
        // nearer, the side pair twice as long.
        let along = |from: Vec3, step: Vec3| (0..31).map(|i| from + step * i as f64).collect::<Vec<_>>();
        let a_pts = [along(Vec3::new(0.0, 0.0, 600.0), Vec3::x()), along(Vec3::new(30.0, 0.0, 600.0), Vec3::y() * 2.0)]
            .concat();
        let b_pts =
            [along(Vec3::new(0.0, -1.0, 600.0), Vec3::x()), along(Vec3::new(32.0, 0.0, 600.0), Vec3::y() * 2.0)]
                .concat();
        let line = |point: Vec3, direction: Vec3, inliers: std::ops::Range<usize>| EdgeLine {
            point,
            direction,
            inliers: inliers.collect(),
        };
        let a_lines = vec![
            line(Vec3::new(0.0, 0.0, 600.0), Vec3::x(), 0..31),
            line(Vec3::new(30.0, 0.0, 600.0), Vec3::y(), 31..62),
        ];
        let b_lines = vec![
            line(Vec3::new(0.0, -1.0, 600.0), Vec3::x(), 0..31),
            line(Vec3::new(32.0, 0.0, 600.0), Vec3::y(), 31..62),
        ];
        let centroids = [Vec3::new(15.0, 30.0, 600.0), Vec3::new(45.0, -30.0, 600.0)];
        let err = robust_select([&a_lines, &b_lines], [&a_pts, &b_pts], centroids, &Vec3::z(), 10.0).unwrap_err();
        assert_eq!(err.rule().id, "edge.two_facing_edges");
        let WeldEdgeError::TwoFacingEdges { nearest_mm, longer_mm, angle_deg } = err else { panic!("{err}") };
        assert!((nearest_mm - 30.0).abs() < 1e-9 && (longer_mm - 60.0).abs() < 1e-9, "{err}");
        assert!((angle_deg - 90.0).abs() < 1e-6, "{err}");
        // With the side as short as the end, the nearer pair is the answer.
        let short_side: Vec<EdgeLine> = vec![a_lines[0].clone(), line(a_lines[1].point, Vec3::y(), 31..46)];
        let short_b: Vec<EdgeLine> = vec![b_lines[0].clone(), line(b_lines[1].point, Vec3::y(), 31..46)];
        let pick = robust_select([&short_side, &short_b], [&a_pts, &b_pts], centroids, &Vec3::z(), 10.0).unwrap();
        assert_eq!(pick, [0, 0]);
    }

    #[test]
    fn a_lap_s_lower_plate_seen_longer_beside_another_edge_is_refused() {
        // An upper plate's side along y, its end along x, and a line 27°
        // off the side (where the image border cuts the plate).
        let side = EdgeLine { point: Vec3::new(0.0, 0.0, 600.0), direction: Vec3::y(), inliers: vec![] };
        let end = EdgeLine { direction: Vec3::x(), ..side.clone() };
        let askew = EdgeLine { direction: Vec3::new(1.0, 2.0, 0.0).normalize(), ..side.clone() };
        let lines = [side, end, askew];
        assert_eq!(turned_from(&lines, 0), vec![1]);
        let beside_end = |seen_mm: f64| [OtherEdge { line: 1, length_mm: 200.0, seen_mm }];
        // Beside the end for longer than beside the chosen side: refused.
        let err = check_lap_edge(&lines, 0, 40.0, &beside_end(90.0), &[]).unwrap_err();
        assert_eq!(err, WeldEdgeError::LowerPlateBesideOtherEdge { chosen_mm: 40.0, longer_mm: 90.0, angle_deg: 90.0 });
        assert_eq!(err.rule().id, "lap.lower_plate_beside_other_edge");
        // Shorter beside the end: kept.
        assert!(check_lap_edge(&lines, 0, 90.0, &beside_end(40.0), &[]).is_ok());
    }

    #[test]
    fn a_lap_s_upper_plate_must_reach_past_its_lower_plate_somewhere() {
        let side = EdgeLine { point: Vec3::new(0.0, 0.0, 600.0), direction: Vec3::y(), inliers: vec![] };
        let end = EdgeLine { direction: Vec3::x(), ..side.clone() };
        let lines = [side, end];
        let beside_end = |seen_mm: f64| [OtherEdge { line: 1, length_mm: 300.0, seen_mm }];
        // The lower plate beside the end as far as the plates overlap: a lap.
        assert!(check_lap_edge(&lines, 0, 330.0, &beside_end(60.0), &[]).is_ok());
        assert!(check_lap_edge(&lines, 0, 330.0, &beside_end(260.0), &[]).is_ok());
        // Beside all of it: the upper plate lies on the plane under it.
        let err = check_lap_edge(&lines, 0, 330.0, &beside_end(290.0), &[]).unwrap_err();
        assert_eq!(err, WeldEdgeError::UpperPlateOnLowerPlane { seen_mm: 290.0, end_mm: 300.0, angle_deg: 90.0 });
        assert_eq!(err.rule().id, "lap.upper_plate_not_past_lower");
        assert!(err.to_string().contains("far edge into view") && !err.to_string().contains("  "), "{err}");
        // An end of no length (a line of one inlier) says nothing.
        let point = [OtherEdge { line: 1, length_mm: 0.0, seen_mm: 0.0 }];
        assert!(check_lap_edge(&lines, 0, 330.0, &point, &[]).is_ok());
    }

    #[test]
    fn a_lap_s_upper_plate_must_not_lie_within_the_plane_under_it() {
        let side = EdgeLine { point: Vec3::new(0.0, 0.0, 600.0), direction: Vec3::y(), inliers: vec![] };
        let far_side = EdgeLine { point: Vec3::new(200.0, 0.0, 600.0), ..side.clone() };
        let lines = [side, far_side];
        let beside_far = |seen_mm: f64| [OtherEdge { line: 1, length_mm: 260.0, seen_mm }];
        // Beyond the far edge lies what the lower plate rests on: a lap.
        assert!(check_lap_edge(&lines, 0, 250.0, &[], &beside_far(0.0)).is_ok());
        assert!(check_lap_edge(&lines, 0, 250.0, &[], &beside_far(120.0)).is_ok());
        // The lower plate's layer beside most of the far edge too: the
        // upper plate lies on it whole.
        let err = check_lap_edge(&lines, 0, 250.0, &[], &beside_far(210.0)).unwrap_err();
        assert_eq!(err, WeldEdgeError::UpperPlateWithinLowerLayer { seen_mm: 210.0, far_mm: 260.0 });
        assert_eq!(err.rule().id, "lap.upper_plate_within_lower_layer");
        assert!(err.to_string().contains("210 of its 260 mm") && !err.to_string().contains("  "), "{err}");
    }

    #[test]
    fn a_lap_s_upper_plate_must_be_seen_to_end_off_the_plane_under_it() {
        use EdgeLies::{AlongBorder, InView, WithinPlate};
        let edge = |length_mm: f64, lies: EdgeLies, plane_beside_mm: f64| EdgeSeen { length_mm, lies, plane_beside_mm };
        // Ends and far side along the image's border, or no other edge:
        // a step and nothing else.
        let border = [edge(200.0, AlongBorder, 0.0), edge(200.0, AlongBorder, 0.0), edge(300.0, AlongBorder, 0.0)];
        for others in [&border[..], &[]] {
            let err = check_lap_ends_off_lower_plane(others).unwrap_err();
            assert!(err.is_unknown(), "{err}");
            assert_eq!(err.rule().id, "lap.upper_plate_ends_off_lower");
            assert_eq!(err.rule().gate, Some(crate::rules::Gate::JointUnknown));
        }
        // One end in view with the table beyond it, off the lower plane.
        let one_end = [edge(200.0, InView, 0.0), edge(200.0, AlongBorder, 0.0)];
        assert!(check_lap_ends_off_lower_plane(&one_end).is_ok());
        // An end in view beside the lower plate where they overlap, less
        // than half of it: the rest reaches past the lower plate.
        assert!(check_lap_ends_off_lower_plane(&[edge(100.0, InView, 45.0)]).is_ok());
        // A corner in view with the plane under it beside most of it, a
        // slit's side, an end of no length: none is where the plate ends
        // off that plane.
        let none = [edge(28.0, InView, 20.0), edge(320.0, WithinPlate, 0.0), edge(0.0, InView, 0.0)];
        let err = check_lap_ends_off_lower_plane(&none).unwrap_err();
        assert_eq!(
            err,
            WeldEdgeError::StepAlone {
                edges: "its other edges: 1 with the plate seen beyond, 1 in view with the plane under it beside".into()
            }
        );
        assert!(err.to_string().contains("request lap") && !err.to_string().contains("  "), "{err}");
    }

    #[test]
    fn a_plate_s_edges_face_away_from_it_over_their_inliers_reach() {
        // A plate round the origin; a line along its edge at x = 50,
        // inliers from y = -20 to 30.
        let points: Vec<Vec3> = (-20..=30).map(|y| Vec3::new(50.0, y as f64, 600.0)).collect();
        let line = EdgeLine { point: Vec3::new(50.0, 0.0, 600.0), direction: -Vec3::y(), inliers: (0..51).collect() };
        let [edge] = plate_edges(&[line], &[0], &points, &Vec3::new(0.0, 0.0, 600.0), &Vec3::z())[..] else { panic!() };
        assert!((edge.edge.outward - Vec3::x()).norm() < 1e-12);
        assert_eq!(edge.span, [-30.0, 20.0]);
    }

    #[test]
    fn paper_selection_needs_two_separating_lines() {
        let lines = vec![line(-100.0, true, 50), line(0.0, true, 40)];
        let centroids = [Vec3::new(-50.0, 30.0, 600.0), Vec3::new(50.0, 30.0, 600.0)];
        let err = paper_select(&lines, centroids, |_| 0).unwrap_err();
        assert_eq!(err, WeldEdgeError::TooFewSeparating { found: 1, lines: 2 });
        assert_eq!(err.rule().id, "edge.no_line_between_plates");
    }

    #[test]
    fn separating_lines_at_right_angles_are_no_pair() {
        // Plate A's edge along y at x = -1 and plate B's along x at
        // y = 1: each separates the centroids (A's at (-50, -50), B's at
        // (50, 50)), but they meet at a right angle.
        let a_lines = vec![line(-1.0, true, 40)];
        let b_lines =
            vec![EdgeLine { point: Vec3::new(0.0, 1.0, 600.0), direction: Vec3::x(), inliers: (0..40).collect() }];
        let a_pts: Vec<Vec3> = (0..40).map(|i| Vec3::new(-1.0, i as f64, 600.0)).collect();
        let b_pts: Vec<Vec3> = (0..40).map(|i| Vec3::new(i as f64, 1.0, 600.0)).collect();
        let centroids = [Vec3::new(-50.0, -50.0, 600.0), Vec3::new(50.0, 50.0, 600.0)];
        let err = robust_select([&a_lines, &b_lines], [&a_pts, &b_pts], centroids, &Vec3::z(), 10.0).unwrap_err();
        assert_eq!(err, WeldEdgeError::NotParallel { max_angle_deg: 10.0 });
        assert_eq!(err.rule().id, "edge.no_parallel_pair");
        // Turned to within the limit of each other, they are a pair.
        let turned = EdgeLine { direction: Vec3::new(0.1, 1.0, 0.0).normalize(), ..a_lines[0].clone() };
        let b_along_y =
            vec![EdgeLine { point: Vec3::new(1.0, 0.0, 600.0), direction: Vec3::y(), inliers: (0..40).collect() }];
        let b_pts: Vec<Vec3> = (0..40).map(|i| Vec3::new(1.0, i as f64, 600.0)).collect();
        let centroids = [Vec3::new(-50.0, 20.0, 600.0), Vec3::new(50.0, 20.0, 600.0)];
        assert_eq!(robust_select([&[turned], &b_along_y], [&a_pts, &b_pts], centroids, &Vec3::z(), 10.0), Ok([0, 0]));
    }
}
