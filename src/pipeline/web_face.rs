//! A tee whose web's top is out of view (issue 15 with issue 11's crops):
//! a cloud cropped a few centimetres round a fillet root keeps the flange
//! and the web's side face up to the crop, but not the web's top, which is
//! what [`super::background`] finds a tee by. The face itself is the
//! evidence then: a steep plane standing on the flange.
//!
//! With `n` the flange's unit normal into the workpiece and `h(p) = d_f −
//! n·p` the height over the flange (as in [`super::fillet`]), the face is
//! searched among the points at `margin ≤ h ≤ web_height_max` over the
//! flange's footprint, by RANSAC over planes that are
//!
//! - steep: the face's normal `m` within [`MAX_FACE_LEAN_DEG`] of the
//!   flange's plane, `|m·n| ≤ sin(lean)` (a web leans a few degrees; the
//!   quality gate `quality.max_web_tilt_deg` judges the fitted face);
//! - seen: turned at least [`super::fillet::MIN_FACE_VIEW_DEG`] towards the
//!   camera's ray to them, so the veil of mixed returns a depth jump hangs
//!   along the rays is never taken for a face;
//!
//! then refitted by least squares with outliers trimmed (the fillet
//! stage's face fit). The face is taken only when it stands on the flange
//! (its foot within a few spacings of the flange's plane) and rises a
//! useful height above it; otherwise there is no tee to plan, and the
//! reason says which.
//!
//! Only one face of a web is ever seen (the faces are steep), so a web
//! found this way gives at most one root: the one on the face's side. A
//! block or a box section standing on the flange shows two of its faces:
//! [`find_all`] reads the member's faces one after the other, each from
//! the points the faces before it leave, keeping those that meet along
//! an edge.
//!
//! What rises over a lone plane also says what is in view when nothing can
//! be planned ([`valley`]): read on the largest facet of it, the valley it
//! makes with the plane tells a groove's two flanks from a web standing on
//! its flange.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, extent, plane_axes};

use super::background::PlaneCluster;
use super::fillet::{self, MIN_FACE_POINTS, MIN_FACE_VIEW_DEG, NotRead};
use crate::rules::background::{
    TEE_FACE_FOOT_ABOVE_FLANGE, TEE_NO_FACE_STANDS_ON_FLANGE, TEE_NOTHING_STANDS_ON_FLANGE, TEE_STANDING_FACE_TOO_LOW,
    TEE_STANDING_FACE_TOO_SPARSE,
};

/// How far a face may lean from standing square on the flange and still
/// be searched for, degrees: wide enough for any web the quality gate
/// could accept and a margin over it, so that the gate, not the search,
/// is what refuses a leaning one.
pub const MAX_FACE_LEAN_DEG: f64 = 30.0;

/// Planes tried. The face holds most of the points over the flange in a
/// crop round its root, so a few hundred draws find it with certainty.
const RANSAC_DRAWS: usize = 400;

/// Points scored per draw, at most: the face's share of the candidates is
/// what is compared, and a few thousand estimate it well.
const SCORED_POINTS: usize = 4_000;

/// Candidate points kept, at most (a regular stride over the rest): the
/// search's cost is bounded whatever the cloud holds over its flange.
const MAX_CANDIDATES: usize = 200_000;

/// A point lies on a candidate face within this many point spacings (or
/// the on-plane tolerance, if more).
const FACE_TOLERANCE_SPACINGS: f64 = 1.5;

/// The face's foot must come within this many spacings of the flange's
/// plane (above the margin that keeps the flange's own points out): a
/// face that stops higher stands over the flange, not on it.
const FOOT_REACH_SPACINGS: f64 = 4.0;

/// The least height a face must be seen to, in point spacings: a face a
/// few spacings tall is a plate's edge or a ridge of noise, and its tilt
/// (and so its root) is poorly fixed.
const MIN_FACE_HEIGHT_SPACINGS: f64 = 10.0;

/// The fewest points per square point spacing a face must hold over the
/// rectangle its points span (along the root by up the face): a face
/// turned the least angle seen ([`MIN_FACE_VIEW_DEG`]) to the rays is
/// sampled at about sin 5° ≈ 0.09 per spacing², and half of that allows
/// for dropouts. Stray returns that happen to lie on one plane over a
/// large flange are far sparser.
const MIN_FACE_FILL: f64 = 0.04;

/// The seed of the search's generator: the same cloud always gives the
/// same face.
const SEED: u64 = 0x5eed_face;

/// The most faces [`find_all`] searches for on one flange: a member
/// shows two of its faces, and the search may first find another
/// member's; the bound keeps the search's cost fixed.
pub const MAX_STANDING_FACES: usize = 4;

/// The least two faces of one member are turned from each other where
/// they meet, degrees ([`meet`]): a box's or a block's faces meet at 90°,
/// a hexagonal bar's at 60°; two faces nearer parallel are no edge's.
const MIN_EDGE_TURN_DEG: f64 = 30.0;

/// How near the other face's plane a face's points are taken as lying at
/// the edge the two meet in, point spacings: past the tolerance a face's
/// points are set aside by ([`FACE_TOLERANCE_SPACINGS`]), within the
/// spread of an edge's returns.
const EDGE_REACH_SPACINGS: f64 = 4.0;

/// The fewest points of each face near the edge for the edge to count as
/// shown by both.
const MIN_EDGE_POINTS: usize = 10;

/// Two faces turned within this of parallel, degrees, and lying nearer
/// than [`FACES_APART_SPACINGS`] are one face seen twice ([`same_face`]).
const PARALLEL_FACE_DEG: f64 = 10.0;

/// How far apart two parallel faces must lie, in point spacings, to be
/// two: a face's returns spread a spacing or two off it, and a second
/// member's face stands further off than its own thickness of noise.
const FACES_APART_SPACINGS: f64 = 10.0;

/// The share of a further face's points lying within
/// [`FACES_APART_SPACINGS`] of a found face's plane above which it is
/// that face's leftover whatever its fit's turn ([`same_face`]): nearly
/// all, leaving room for the few returns of the flange or an edge's veil
/// a slab of leftovers takes in.
const LEFTOVER_SHARE: f64 = 0.9;

/// A web's side face seen standing on the flange, its top not in view.
#[derive(Debug, Clone, PartialEq)]
pub struct StandingFace {
    /// The face's plane, its normal out of the web towards the side it is
    /// seen from.
    pub plane: Plane,
    pub centroid: Vec3,
    /// The flange's plane, its normal into the workpiece.
    pub flange: Plane,
    /// The points on the face.
    pub points: usize,
    /// How high over the flange the face is seen, mm: the web stands at
    /// least this tall.
    pub seen_height_mm: f64,
}

/// The settings of the search.
#[derive(Debug, Clone, Copy)]
pub struct FaceSearch {
    /// The cloud's point spacing near the flange, mm.
    pub point_spacing_mm: f64,
    /// A point lies on a plane within this distance, mm.
    pub on_plane_mm: f64,
    /// How tall a web may stand, mm (`pipeline.tee_web_height_max_mm`).
    pub web_height_max_mm: f64,
    /// Face points further than this many residuals from the fit are
    /// dropped and the face refitted.
    pub trim_sigma: f64,
}

/// The web's side face standing on the flange made of `flange_pieces`, or
/// why none is seen (and the rule that decided it).
pub fn find(cloud: &PointCloud, flange_pieces: &[&PlaneCluster], s: &FaceSearch) -> Result<StandingFace, NotRead> {
    let over = OverFlange::of(cloud, flange_pieces, s)?;
    over.face_among(&over.candidates).map(|(face, _)| face)
}

/// Every face of the member standing on the flange made of
/// `flange_pieces`, the one holding the most points first, or why none is
/// seen: a block standing on a plate shows two of its faces, each with a
/// root. After each face found, its points are set aside and the search
/// runs again on the rest, [`MAX_STANDING_FACES`] times at most, until it
/// finds no face or one a found face's leftover points make
/// ([`same_face`]). A face is kept when it passes every test the first one
/// does and meets a face kept along an edge both show ([`meet`]): the
/// same member's. A face standing apart is another member's, a second web
/// or a fixture's side, which a face alone does not tell apart; it is not
/// kept, as a lone face under a request for any joint is not planned.
pub fn find_all(
    cloud: &PointCloud,
    flange_pieces: &[&PlaneCluster],
    s: &FaceSearch,
) -> Result<Vec<StandingFace>, NotRead> {
    let mut over = OverFlange::of(cloud, flange_pieces, s)?;
    let first = over.face_among(&over.candidates)?;
    // The candidates are read from here on only as what is left.
    let mut left = std::mem::take(&mut over.candidates);
    let mut last_plane = first.0.plane;
    let mut kept = vec![first];
    for _ in 1..MAX_STANDING_FACES {
        left.retain(|p| last_plane.signed_distance(p).abs() > over.tolerance);
        if left.len() < MIN_FACE_POINTS {
            break;
        }
        let Ok(next) = over.face_among(&left) else { break };
        last_plane = next.0.plane;
        if kept.iter().any(|(face, _)| same_face(face, (&next.0, &next.1), s.point_spacing_mm)) {
            break;
        }
        let reach = EDGE_REACH_SPACINGS * s.point_spacing_mm;
        if kept.iter().any(|(face, points)| meet((&face.plane, points), (&next.0.plane, &next.1), reach)) {
            kept.push(next);
        }
    }
    Ok(kept.into_iter().map(|(face, _)| face).collect())
}

/// Whether two faces (each its plane and points) meet along an edge both
/// show, as two faces of one member do: turned at least
/// [`MIN_EDGE_TURN_DEG`] from each other, and where each face's points
/// come within `reach` of the other's plane, their stretches along the
/// line the planes meet in overlap.
fn meet(a: (&Plane, &[Vec3]), b: (&Plane, &[Vec3]), reach: f64) -> bool {
    let Some(edge) = a.0.normal.cross(&b.0.normal).try_normalize(1e-9) else { return false };
    if a.0.normal.dot(&b.0.normal).abs() > MIN_EDGE_TURN_DEG.to_radians().cos() {
        return false;
    }
    let along_edge = |points: &[Vec3], other: &Plane| {
        let near: Vec<f64> =
            points.iter().filter(|p| other.signed_distance(p).abs() <= reach).map(|p| edge.dot(p)).collect();
        (near.len() >= MIN_EDGE_POINTS).then(|| extent(near))
    };
    match (along_edge(a.1, b.0), along_edge(b.1, a.0)) {
        (Some((a0, a1)), Some((b0, b1))) => a0.max(b0) <= a1.min(b1),
        _ => false,
    }
}

/// Whether `b` (its face and points) is the leftover of `a`: the points
/// of a noisy face beyond the tolerance its own fit keeps, lying nearer
/// `a`'s plane than [`FACES_APART_SPACINGS`] point spacings, either
/// - as a face turned within [`PARALLEL_FACE_DEG`] of it, its centroid
///   that near; or
/// - at any turn, with [`LEFTOVER_SHARE`] of its points that near: a
///   plane fitted to a thin slab of leftovers turns as they lead it (near
///   a member's corner, or where the camera blends the face into what
///   meets it), but the slab stays within the face's own band.
///
/// A second member's face stands further off, or turned from the first
/// with its points reaching out of that band across its own width.
fn same_face(a: &StandingFace, b: (&StandingFace, &[Vec3]), spacing: f64) -> bool {
    let band_mm = FACES_APART_SPACINGS * spacing;
    let (face, points) = b;
    let parallel = a.plane.normal.dot(&face.plane.normal).abs() >= PARALLEL_FACE_DEG.to_radians().cos();
    if parallel && a.plane.signed_distance(&face.centroid).abs() < band_mm {
        return true;
    }
    let in_band = points.iter().filter(|p| a.plane.signed_distance(p).abs() < band_mm).count();
    !points.is_empty() && in_band as f64 >= LEFTOVER_SHARE * points.len() as f64
}

/// What stands over a flange: the flange's plane and the points over its
/// footprint that a face standing on it is searched among.
struct OverFlange<'s> {
    flange: Plane,
    candidates: Vec<Vec3>,
    /// A point lies on a face within this distance, mm.
    tolerance: f64,
    /// Points this high over the flange's plane and higher are candidates,
    /// mm: below it they are the flange's own.
    margin: f64,
    s: &'s FaceSearch,
}

impl<'s> OverFlange<'s> {
    /// The flange of `flange_pieces` and what stands over it, or why
    /// nothing can stand on it.
    fn of(cloud: &PointCloud, flange_pieces: &[&PlaneCluster], s: &'s FaceSearch) -> Result<Self, NotRead> {
        let (flange, flange_points) = fillet::flange_plane(cloud, flange_pieces)
            .ok_or_else(|| NotRead::by(&TEE_NO_FACE_STANDS_ON_FLANGE, "the flange's points span no plane"))?;
        let n = flange.normal;
        let height = |p: &Vec3| flange.offset - n.dot(p);
        let spacing = s.point_spacing_mm;
        let margin = fillet::height_margin(s.on_plane_mm, spacing);
        let over_flange = Footprint::of(&flange_points, &n, FOOT_REACH_SPACINGS * spacing);
        let mut candidates: Vec<Vec3> = fillet::valid_points(cloud)
            .filter(|p| (margin..=s.web_height_max_mm).contains(&height(p)) && over_flange.holds(p))
            .collect();
        if candidates.len() > MAX_CANDIDATES {
            let stride = candidates.len().div_ceil(MAX_CANDIDATES);
            candidates = candidates.into_iter().step_by(stride).collect();
        }
        if candidates.len() < MIN_FACE_POINTS {
            return Err(NotRead::by(
                &TEE_NOTHING_STANDS_ON_FLANGE,
                format!(
                    "nothing in view stands on the flange: {} points lie {margin:.1} to {:.0} mm over it, fewer than \
                 {MIN_FACE_POINTS} (a web's face turned edge-on to the camera returns none, and with the web's top out \
                 of view nothing else shows where its root is)",
                    candidates.len(),
                    s.web_height_max_mm
                ),
            ));
        }
        let tolerance = s.on_plane_mm.max(FACE_TOLERANCE_SPACINGS * spacing);
        Ok(OverFlange { flange, candidates, tolerance, margin, s })
    }

    /// The face standing on the flange among `candidates` and the points
    /// on it, or why none is seen there.
    fn face_among(&self, candidates: &[Vec3]) -> Result<(StandingFace, Vec<Vec3>), NotRead> {
        let (flange, s, tolerance, margin) = (self.flange, self.s, self.tolerance, self.margin);
        let n = flange.normal;
        let height = |p: &Vec3| flange.offset - n.dot(p);
        let spacing = s.point_spacing_mm;
        let plane = best_steep_plane(candidates, &n, tolerance).ok_or_else(|| {
            NotRead::by(
                &TEE_NO_FACE_STANDS_ON_FLANGE,
                format!(
                    "the {} points over the flange lie on no face standing within {MAX_FACE_LEAN_DEG}° of square on it \
                 and turned {MIN_FACE_VIEW_DEG}° or more towards the camera",
                    candidates.len()
                ),
            )
        })?;
        let on_face: Vec<Vec3> =
            candidates.iter().copied().filter(|p| plane.signed_distance(p).abs() <= tolerance).collect();
        let fit = fillet::fit_face(&on_face, s.trim_sigma).ok_or_else(|| {
            NotRead::by(&TEE_NO_FACE_STANDS_ON_FLANGE, "the points on the face standing on the flange span no plane")
        })?;
        // Out of the web: towards the camera, which sees this face.
        let normal = if fit.plane.normal.dot(&fit.centroid) <= 0.0 { fit.plane.normal } else { -fit.plane.normal };
        let face = Plane { normal, offset: normal.dot(&fit.centroid) };
        // The draws were turned towards the camera; the refit may still settle
        // on the veil of mixed returns if that is most of what stands there.
        let view_deg = normal.dot(&(-fit.centroid).normalize()).clamp(-1.0, 1.0).asin().to_degrees();
        if view_deg < MIN_FACE_VIEW_DEG {
            return Err(NotRead::by(
                &TEE_NO_FACE_STANDS_ON_FLANGE,
                format!(
                    "the {} points standing on the flange lie along the camera's rays ({view_deg:.1}° from them, below \
                 {MIN_FACE_VIEW_DEG}°): mixed returns at a depth jump, not a web's face",
                    fit.inliers.len()
                ),
            ));
        }
        let (lowest, highest) = extent(fit.inliers.iter().map(height));
        let foot_reach = margin + FOOT_REACH_SPACINGS * spacing;
        if lowest > foot_reach {
            return Err(NotRead::by(
                &TEE_FACE_FOOT_ABOVE_FLANGE,
                format!(
                    "the face over the flange ({} points) is seen no lower than {lowest:.1} mm over it, above {foot_reach:.1} \
                 mm: it stands over the flange, not on it",
                    fit.inliers.len()
                ),
            ));
        }
        let along_root = n.cross(&normal);
        let (first, last) = extent(fit.inliers.iter().map(|p| along_root.dot(p)));
        let spanned_mm2 = (last - first) * (highest - lowest);
        let fill = fit.inliers.len() as f64 * spacing * spacing / spanned_mm2.max(f64::MIN_POSITIVE);
        if fill < MIN_FACE_FILL {
            return Err(NotRead::by(
                &TEE_STANDING_FACE_TOO_SPARSE,
                format!(
                    "the {} points on a plane standing on the flange are strewn over {spanned_mm2:.0} mm² ({fill:.3} per \
                 square point spacing, below {MIN_FACE_FILL}): stray returns, not a face",
                    fit.inliers.len()
                ),
            ));
        }
        let least_height = MIN_FACE_HEIGHT_SPACINGS * spacing;
        if highest < least_height {
            return Err(NotRead::by(
                &TEE_STANDING_FACE_TOO_LOW,
                format!(
                    "the face on the flange ({} points) is seen only {highest:.1} mm tall, below {least_height:.1} mm \
                 ({MIN_FACE_HEIGHT_SPACINGS} point spacings of {spacing:.2} mm): a plate's edge or noise, not a web",
                    fit.inliers.len()
                ),
            ));
        }
        let found = StandingFace {
            plane: face,
            centroid: fit.centroid,
            flange,
            points: fit.inliers.len(),
            seen_height_mm: highest,
        };
        Ok((found, fit.inliers))
    }
}

/// The plane through three of `points` that holds the most of them within
/// `tolerance`, among the planes steep to the flange (normal `n`) and
/// turned towards the camera; None when no draw gives one.
fn best_steep_plane(points: &[Vec3], n: &Vec3, tolerance: f64) -> Option<Plane> {
    let max_cos_to_flange_normal = MAX_FACE_LEAN_DEG.to_radians().sin();
    let min_sin_to_ray = MIN_FACE_VIEW_DEG.to_radians().sin();
    best_plane(points, tolerance, |normal, ray| {
        normal.dot(n).abs() <= max_cos_to_flange_normal && normal.dot(ray).abs() >= min_sin_to_ray
    })
}

/// The plane through three of `points` that holds the most of them within
/// `tolerance`, among those `admits` (given the plane's unit normal and
/// the unit ray from the camera to the three points' middle); None when
/// no draw gives one. The draws are seeded ([`SEED`]): the same points
/// always give the same plane.
fn best_plane(points: &[Vec3], tolerance: f64, admits: impl Fn(&Vec3, &Vec3) -> bool) -> Option<Plane> {
    let stride = points.len().div_ceil(SCORED_POINTS).max(1);
    let scored: Vec<&Vec3> = points.iter().step_by(stride).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut best: Option<(usize, Plane)> = None;
    for _ in 0..RANSAC_DRAWS {
        let [a, b, c] = [0; 3].map(|_| &points[(rng.next_u64() % points.len() as u64) as usize]);
        let Some(normal) = (b - a).cross(&(c - a)).try_normalize(1e-9) else {
            continue;
        };
        let middle = (a + b + c) / 3.0;
        if !admits(&normal, &middle.normalize()) {
            continue;
        }
        let plane = Plane { normal, offset: normal.dot(&middle) };
        let support = scored.iter().filter(|p| plane.signed_distance(p).abs() <= tolerance).count();
        if best.as_ref().is_none_or(|(most, _)| support > *most) {
            best = Some((support, plane));
        }
    }
    best.map(|(_, plane)| plane)
}

/// The most the two faces of a valley may differ in how far each is turned
/// from the camera's line of sight, degrees, for the camera to be looking
/// into it down its middle, as it looks into a groove. A tee is seen from
/// above its flange: the flange turned less than
/// `pipeline.plane_max_normal_angle_deg` (20°) from the rays, its web 50°
/// and more.
pub const VALLEY_MIDDLE_SLANT_DEG: f64 = 15.0;

/// The valley two faces open above which they are told as one surface
/// with a crease, not a groove's two flanks, degrees: each face within 5°
/// of one plane. The grooves a cell welds open 40 to 130° (the suites'
/// V-grooves 40 to 70°, a hand-cut real one 126°); a flank 5° off the
/// plates' plane would make a groove 30 mm wide only 1.3 mm deep. What
/// is in view is then one plate, or a butt's plates seen as one across a
/// gap narrower than the cloud resolves, with a slight turn or noise
/// parting its points (an I-butt 0.5 mm open at 1 mm voxels reads 179°).
pub const ONE_SURFACE_MIN_OPENING_DEG: f64 = 170.0;

/// What rises over a lone plane in view towards the camera, when no web's
/// top is seen: the plane fitted to those points and the valley it makes
/// with the lone plane. Read to say what is in view when a joint cannot
/// be planned, never to plan one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Valley {
    /// The angle the two faces open across the valley, degrees: 180 for
    /// one plane, 90 for a web standing square on its flange.
    pub opening_deg: f64,
    /// How far each face is turned from the camera's line of sight to it,
    /// degrees (0: seen squarely): the lone plane's, then the face rising
    /// over it.
    pub slants_deg: [f64; 2],
    /// The points on the face rising over the lone plane.
    pub points: usize,
}

impl Valley {
    /// Whether the valley opens wider than any web standing on its flange
    /// ([`MAX_FACE_LEAN_DEG`] from square at most).
    pub fn wider_than_a_web_stands(&self) -> bool {
        self.opening_deg > 90.0 + MAX_FACE_LEAN_DEG
    }

    /// Whether the two faces are a groove's flanks rather than a web and
    /// its flange: the valley opens wider than a web stands, or opens
    /// obtuse with the camera looking into it down its middle (both faces
    /// turned about as far from the rays, [`VALLEY_MIDDLE_SLANT_DEG`]),
    /// where a tee is seen from above its flange.
    pub fn is_groove(&self) -> bool {
        let middle = (self.slants_deg[0] - self.slants_deg[1]).abs() <= VALLEY_MIDDLE_SLANT_DEG;
        self.wider_than_a_web_stands() || (middle && self.opening_deg > 90.0)
    }

    /// What the valley is, in words, for a refusal.
    pub fn describe(&self) -> String {
        let [lone, rising] = self.slants_deg;
        let turned = format!("turned {lone:.0}° and {rising:.0}° from the camera's line of sight");
        if self.opening_deg >= ONE_SURFACE_MIN_OPENING_DEG {
            return format!(
                "only one surface is in view, its two parts within {:.0}° of one plane ({turned}): one plate, or a \
                 butt's plates seen as one across a gap narrower than the cloud resolves",
                (180.0 - self.opening_deg).round().max(1.0)
            );
        }
        let seen =
            format!("only two faces are in view, meeting in a valley that opens {:.0}° ({turned})", self.opening_deg);
        if self.is_groove() {
            format!(
                "{seen}: a groove's two flanks with no plate top beside them, so neither the groove's edges nor its \
                 depth can be read (a tee's web stands on its flange at about 90°, seen from above the flange)"
            )
        } else {
            seen
        }
    }
}

/// The valley the lone plane made of `flange_pieces` makes with the face
/// rising over it towards the camera, or None when nothing rises over it
/// or the face does not come down to it.
///
/// The points `margin` to `web_height_max_mm` over the lone plane,
/// anywhere beside it, may lie on several facets: a block standing on a
/// plate shows two of its faces, a groove's far flank a second plate's
/// edge beside it. One plane fitted through them all would be none of
/// them (through a block's two faces it lies near the plate's own plane,
/// and the valley would read as one surface). So the face is the facet
/// holding the most of them, found by drawing planes as the web's face
/// is found ([`best_plane`]) but at any tilt, since a groove's flank
/// leans further than a web may, then refitted with outliers trimmed.
/// Where no facet holds a face's worth of points, what rises is the lone
/// plane's own unevenness (two plates read as one across an unresolved
/// gap, slightly turned), and the plane through most of it describes it.
pub fn valley(cloud: &PointCloud, flange_pieces: &[&PlaneCluster], s: &FaceSearch) -> Option<Valley> {
    let (flange, flange_points) = fillet::flange_plane(cloud, flange_pieces)?;
    let n = flange.normal;
    let height = |p: &Vec3| flange.offset - n.dot(p);
    let spacing = s.point_spacing_mm;
    let margin = fillet::height_margin(s.on_plane_mm, spacing);
    let mut rising: Vec<Vec3> =
        fillet::valid_points(cloud).filter(|p| (margin..=s.web_height_max_mm).contains(&height(p))).collect();
    if rising.len() > MAX_CANDIDATES {
        let stride = rising.len().div_ceil(MAX_CANDIDATES);
        rising = rising.into_iter().step_by(stride).collect();
    }
    if rising.len() < MIN_FACE_POINTS {
        return None;
    }
    // A valley's two faces meet: a surface that stops over the plane (a
    // second plate's top, a ledge) makes none with it.
    let foot_reach = margin + FOOT_REACH_SPACINGS * spacing;
    let comes_down = |fit: &fillet::FaceFit| fit.inliers.iter().map(height).fold(f64::INFINITY, f64::min) <= foot_reach;
    // Where no facet holds a face's worth of points, what rises is the
    // lone plane's own unevenness (two plates read as one, slightly
    // turned), described by the plane through most of it.
    let fit = rising_facet(&rising, s)
        .filter(comes_down)
        .or_else(|| fillet::fit_face(&rising, s.trim_sigma).filter(|fit| 2 * fit.inliers.len() >= rising.len()))
        .filter(comes_down)?;
    // Both normals into the workpiece, away from the camera.
    let m = if fit.plane.normal.dot(&fit.centroid) >= 0.0 { fit.plane.normal } else { -fit.plane.normal };
    let opening_deg = 180.0 - n.dot(&m).clamp(-1.0, 1.0).acos().to_degrees();
    let flange_centroid = flange_points.iter().sum::<Vec3>() / flange_points.len().max(1) as f64;
    let slant = |normal: &Vec3, at: &Vec3| normal.dot(&at.normalize()).abs().clamp(0.0, 1.0).acos().to_degrees();
    Some(Valley {
        opening_deg,
        slants_deg: [slant(&n, &flange_centroid), slant(&m, &fit.centroid)],
        points: fit.inliers.len(),
    })
}

/// The facet holding the most of `rising` (points over a lone plane),
/// refitted with outliers trimmed, where it holds a face's worth of
/// points.
fn rising_facet(rising: &[Vec3], s: &FaceSearch) -> Option<fillet::FaceFit> {
    let tolerance = s.on_plane_mm.max(FACE_TOLERANCE_SPACINGS * s.point_spacing_mm);
    let min_sin_to_ray = MIN_FACE_VIEW_DEG.to_radians().sin();
    let facet = best_plane(rising, tolerance, |normal, ray| normal.dot(ray).abs() >= min_sin_to_ray)?;
    let on_facet: Vec<Vec3> = rising.iter().copied().filter(|p| facet.signed_distance(p).abs() <= tolerance).collect();
    if on_facet.len() < MIN_FACE_POINTS {
        return None;
    }
    fillet::fit_face(&on_facet, s.trim_sigma)
}

/// A rectangle in the flange's plane round its points, widened by a
/// margin: where a web standing on the flange may stand.
struct Footprint {
    axes: [Vec3; 2],
    low: [f64; 2],
    high: [f64; 2],
}

impl Footprint {
    fn of(points: &[Vec3], n: &Vec3, margin: f64) -> Footprint {
        // Any two directions across the normal span the plane.
        let axes = plane_axes(n).unwrap_or([Vec3::x(), Vec3::y()]);
        let spans = axes.map(|axis| extent(points.iter().map(|p| axis.dot(p))));
        Footprint { axes, low: spans.map(|(lo, _)| lo - margin), high: spans.map(|(_, hi)| hi + margin) }
    }

    /// Whether `p`, seen along the flange's normal, lies over the rectangle.
    fn holds(&self, p: &Vec3) -> bool {
        (0..2).all(|k| (self.low[k]..=self.high[k]).contains(&self.axes[k].dot(p)))
    }
}

#[cfg(test)]
#[path = "web_face_tests.rs"]
mod tests;
