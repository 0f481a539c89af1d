//! Input preparation, the step before the frame is sanitised: the cloud's
//! units (millimetres, metres, or guessed from its distances) and its frame
//! (the camera's, or the robot base's brought into the camera's with the
//! capture pose and the hand-eye), and the check that what results can be
//! a camera's view at all ([`check_camera_view`], on counts that the
//! sanitising step takes in its one pass over the frame). Every later
//! stage sees camera-frame millimetres.

use std::borrow::Cow;

use nalgebra::{Isometry3, Point3};
use rayon::prelude::*;

use crate::cloud::{INVALID_POINT, Point, PointCloud};
use crate::config::Config;
pub use crate::geometry::region::CloudFrame;

use super::{PlanError, PlanRequest};
use crate::rules;

/// The units a cloud's coordinates are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Units {
    /// The library's default: a camera's frames are in millimetres, and a
    /// corrupt frame near the optical centre must not pass for one in
    /// metres. The command line guesses unless told.
    #[default]
    Millimetres,
    Metres,
    /// Guessed from the cloud's distances by [`guess_units`].
    Auto,
}

/// A cloud whose valid points lie at a median distance from the origin
/// below this (in its own units) is taken to be in metres. Structured-light
/// and depth cameras measure from about 100 mm to a few metres, so a
/// millimetre cloud has a median of 100 or more and a metre cloud one of a
/// few at most; 20 sits a factor of 5 or more from both.
pub const METRES_BELOW_MEDIAN_DISTANCE: f64 = 20.0;

/// The valid points the units guess looks at, evenly spread over the
/// cloud: the median of a few thousand is as telling as that of millions.
const UNITS_SAMPLE_POINTS: usize = 4096;

/// No camera sees farther off its optical axis than this (the widest
/// depth cameras see about 60° to each side).
pub const MAX_PLAUSIBLE_OFF_AXIS_DEG: f64 = 80.0;

/// A cloud more than this fraction of whose valid points lie behind the
/// camera or beyond any camera's view cannot be a camera-frame view.
const MAX_IMPLAUSIBLE_FRACTION: f64 = 0.5;

/// The least share of a frame's sampled valid points that must be
/// distinct points. A camera measures each pixel on its own ray, so its
/// frames (and the voxel grids and crops made of them) repeat a point
/// hardly ever; a frame most of whose points are one and the same is a
/// stuck sensor's or a corrupt transfer's. Such a frame is refused at
/// once: the density measure of a cloud without a grid compares every
/// point with every sampled point near it, which on 2.3 million copies of
/// one point took 20 s, for a frame that shows no surface at all.
pub const MIN_DISTINCT_SHARE: f64 = 0.5;

/// The least extent of a frame's sampled valid points, mm, along the axis
/// they spread most. Any joint's two plates span several millimetres
/// each; points that all lie within a box this wide show no surface a
/// seam could be planned on (and make the same worst case of the density
/// measure as repeated points do).
pub const MIN_VIEW_EXTENT_MM: f64 = 5.0;

/// The valid points [`check_spread`] looks at, evenly spread over the
/// frame: enough to tell a share to a few percent, a millisecond to read.
const SPREAD_SAMPLE_POINTS: usize = 4096;

/// No depth camera sees wider than this across either axis of its image,
/// degrees: the widest (wide-angle time-of-flight modes) see 120° by 120°,
/// structured-light and stereo ones 90° or less. A cloud whose points,
/// seen from the camera's origin, spread wider than this across x or y
/// was not captured from there: it is in another frame (most often the
/// robot's base, where a workpiece beside the robot is seen from its foot
/// over 140° and more) or its pose is not the capture's.
pub const MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG: f64 = 120.0;

/// The share of the sampled points left out at each end when the angular
/// extent is read: a few stray returns (a reflection, a flying pixel at
/// an edge) must not widen it.
const EXTENT_TRIMMED_SHARE: f64 = 0.01;

/// The valid points [`AngularExtent::of`] looks at, evenly spread over the
/// frame: enough for its trimmed ends to a fraction of a degree.
const EXTENT_SAMPLE_POINTS: usize = 4096;

/// The fewest sampled points an angular extent is read from: with fewer,
/// a trimmed end is one stray point.
const MIN_EXTENT_SAMPLE_POINTS: usize = 200;

/// What the units guess saw and concluded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitsGuess {
    pub metres: bool,
    /// The median distance of the sampled valid points from the origin,
    /// in the cloud's own units.
    pub median_distance: f64,
    pub sampled_points: usize,
}

/// Guesses whether `cloud` is in metres from its valid points' median
/// distance to the origin (see [`METRES_BELOW_MEDIAN_DISTANCE`]). A cloud
/// without a valid point is taken as millimetres.
pub fn guess_units(cloud: &PointCloud) -> UnitsGuess {
    let valid = || cloud.points().iter().filter(|p| p[0].is_finite());
    let stride = (cloud.valid_count() / UNITS_SAMPLE_POINTS).max(1);
    let mut distances: Vec<f64> =
        valid().step_by(stride).map(|p| p.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt()).collect();
    let median_distance = if distances.is_empty() {
        f64::NAN
    } else {
        let middle = distances.len() / 2;
        *distances.select_nth_unstable_by(middle, f64::total_cmp).1
    };
    UnitsGuess {
        metres: median_distance < METRES_BELOW_MEDIAN_DISTANCE,
        median_distance,
        sampled_points: distances.len(),
    }
}

/// True when `cloud` is in metres: as `units` says, or as guessed (and
/// logged with the figures behind the guess) when it says [`Units::Auto`].
pub fn is_in_metres(cloud: &PointCloud, units: Units) -> bool {
    match units {
        Units::Millimetres => false,
        Units::Metres => true,
        Units::Auto => {
            let guess = guess_units(cloud);
            tracing::info!(
                median_distance = guess.median_distance,
                sampled_points = guess.sampled_points,
                metres_below = METRES_BELOW_MEDIAN_DISTANCE,
                "units guessed from the cloud: {}",
                if guess.metres { "metres" } else { "millimetres" }
            );
            guess.metres
        }
    }
}

/// A cloud in metres in millimetres, its organization kept.
pub fn metres_to_millimetres(cloud: &PointCloud) -> PointCloud {
    transformed(Cow::Borrowed(cloud), 1000.0, &Isometry3::identity())
}

/// Brings `cloud` into camera-frame millimetres as `request` says it is
/// given. A cloud already in camera-frame millimetres is returned as it
/// is, uncopied; one the caller handed over (`Cow::Owned`) is converted
/// in place, so a frame is never held twice. Whether the result can be a
/// camera's view is checked when the frame is sanitised, on the counts of
/// its one pass over the points ([`check_camera_view`]).
pub(super) fn prepare<'a>(
    cloud: Cow<'a, PointCloud>,
    request: &PlanRequest,
    config: &Config,
) -> Result<Cow<'a, PointCloud>, PlanError> {
    let metres = is_in_metres(&cloud, request.units);
    let scale = if metres { 1000.0 } else { 1.0 };
    let prepared = match request.cloud_frame {
        CloudFrame::Camera if !metres => cloud,
        CloudFrame::Camera => Cow::Owned(transformed(cloud, scale, &Isometry3::identity())),
        CloudFrame::Base => {
            // p_cam = (Base_T_End * End_T_Camera)^-1 p_base
            let hand_eye = request.hand_eye.unwrap_or(config.hand_eye);
            let base_from_camera = request.pose.to_isometry(config.euler) * hand_eye;
            Cow::Owned(transformed(cloud, scale, &base_from_camera.inverse()))
        }
    };
    Ok(prepared)
}

/// `cloud` scaled by `scale`, then moved by `camera_from_cloud`, in f64.
fn transformed(cloud: Cow<'_, PointCloud>, scale: f64, camera_from_cloud: &Isometry3<f64>) -> PointCloud {
    map_points(cloud, |p| {
        if !p[0].is_finite() {
            return INVALID_POINT;
        }
        let q = camera_from_cloud * Point3::new(p[0].into(), p[1].into(), p[2].into()).map(|c: f64| c * scale);
        [q.x as f32, q.y as f32, q.z as f32]
    })
}

/// `cloud` with every point replaced by `f` of it, its organization kept
/// (and, as the cloud's constructors do, any point `f` makes invalid
/// marked NaN in a grid, dropped from a bag of points). A borrowed cloud
/// is copied; an owned one is changed in place, in its own buffer.
pub(super) fn map_points(cloud: Cow<'_, PointCloud>, f: impl Fn(&Point) -> Point + Sync + Send) -> PointCloud {
    let (width, height, organized) = (cloud.width(), cloud.height(), cloud.is_organized());
    let points = match cloud {
        Cow::Borrowed(cloud) => cloud.points().par_iter().map(&f).collect(),
        Cow::Owned(cloud) => {
            let mut points = cloud.into_points();
            points.par_iter_mut().for_each(|p| *p = f(p));
            points
        }
    };
    if organized {
        PointCloud::organized(width, height, points).unwrap_or_else(|| PointCloud::unorganized(Vec::new()))
    } else {
        PointCloud::unorganized(points)
    }
}

/// Where a cloud's valid points lie against any camera's view.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ViewCounts {
    pub valid: usize,
    /// Behind the camera: z <= 0.
    pub behind: usize,
    /// In front of it but more than [`MAX_PLAUSIBLE_OFF_AXIS_DEG`] off its
    /// axis.
    pub beyond_any_view: usize,
}

/// [`MAX_PLAUSIBLE_OFF_AXIS_DEG`] as the per-point test takes it: the
/// squared tangent, so that no point needs a square root (`hypot` alone
/// cost a raw frame 4 ms).
#[derive(Debug, Clone, Copy)]
pub(super) struct ViewLimit {
    max_tan_sq: f32,
}

impl ViewLimit {
    pub(super) fn new() -> ViewLimit {
        let max_tan = MAX_PLAUSIBLE_OFF_AXIS_DEG.to_radians().tan();
        ViewLimit { max_tan_sq: (max_tan * max_tan) as f32 }
    }
}

/// Whether a cloud can be a camera-frame view, from its [`ViewCounts`]
/// and its [`AngularExtent`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// At least half its valid points lie where a camera can see, and they
    /// spread no wider than a camera sees.
    Camera,
    /// More than half lie behind the camera.
    MostlyBehind,
    /// More than half lie behind it or beyond any camera's field of view.
    MostlyBeyondView,
    /// Seen from the camera's origin, they spread wider across one axis
    /// than any camera sees ([`MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG`]).
    WiderThanAnyCamera,
}

/// How wide a cloud's valid points spread as seen from the camera's
/// origin: the angle between the rays to its outermost points across each
/// axis of the image (the angle of `x` against `z`, and of `y` against
/// `z`), the [`EXTENT_TRIMMED_SHARE`] at each end left out. A camera's
/// view spreads at most its field of view across each axis, whatever it
/// looks at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngularExtent {
    /// Across the image's x axis, degrees.
    pub across_x_deg: f64,
    /// Across the image's y axis, degrees.
    pub across_y_deg: f64,
    pub sampled_points: usize,
}

impl AngularExtent {
    /// The extent of `cloud`'s valid points, read on points sampled evenly
    /// over it (by index, so a raw frame costs a few thousand reads), or
    /// None when too few valid points are sampled to read it.
    pub fn of(cloud: &PointCloud) -> Option<AngularExtent> {
        let points = cloud.points();
        let stride = (points.len() / EXTENT_SAMPLE_POINTS).max(1);
        let mut sample: Vec<&Point> = points.iter().step_by(stride).filter(|p| p[0].is_finite()).collect();
        if sample.len() < MIN_EXTENT_SAMPLE_POINTS {
            // A frame mostly invalid: sample its valid points themselves.
            let valid = points.iter().filter(|p| p[0].is_finite()).count();
            let stride = (valid / EXTENT_SAMPLE_POINTS).max(1);
            sample = points.iter().filter(|p| p[0].is_finite()).step_by(stride).collect();
        }
        if sample.len() < MIN_EXTENT_SAMPLE_POINTS {
            return None;
        }
        let across = |axis: usize| {
            let mut angles: Vec<f64> =
                sample.iter().map(|p| f64::from(p[axis]).atan2(f64::from(p[2])).to_degrees()).collect();
            angles.sort_unstable_by(f64::total_cmp);
            let trimmed = (angles.len() as f64 * EXTENT_TRIMMED_SHARE) as usize;
            angles[angles.len() - 1 - trimmed] - angles[trimmed]
        };
        Some(AngularExtent { across_x_deg: across(0), across_y_deg: across(1), sampled_points: sample.len() })
    }

    /// The wider of the two extents, with the axis it is across.
    pub fn widest(&self) -> (&'static str, f64) {
        if self.across_x_deg >= self.across_y_deg { ("x", self.across_x_deg) } else { ("y", self.across_y_deg) }
    }

    /// Whether no camera could see this wide ([`MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG`]).
    pub fn wider_than_any_camera(&self) -> bool {
        self.widest().1 > MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG
    }
}

/// Whether points with these `counts` and this `extent` can be a
/// camera-frame view: the counts first (points behind the camera or off
/// any view's cone say the most), then the spread.
pub fn view_of(counts: &ViewCounts, extent: Option<&AngularExtent>) -> View {
    match counts.view() {
        View::Camera if extent.is_some_and(AngularExtent::wider_than_any_camera) => View::WiderThanAnyCamera,
        view => view,
    }
}

/// Folds every valid point of `cloud` into a `C`, in parallel over chunks
/// of the frame that are then merged: the one shape of the input step's
/// passes over a raw frame. Plain loops over chunks: a per-point filter,
/// map and reduce kept its counts on the stack and stalled on them, 12 to
/// 15 ms a raw frame in some builds.
pub(super) fn fold_valid_points<C: Default + Send>(
    cloud: &PointCloud,
    add: impl Fn(&mut C, &Point) + Sync,
    merge: impl Fn(C, C) -> C + Sync + Send,
) -> C {
    cloud
        .points()
        .par_chunks(1 << 14)
        .map(|chunk| {
            let mut counts = C::default();
            for p in chunk.iter().filter(|p| p[0].is_finite()) {
                add(&mut counts, p);
            }
            counts
        })
        .reduce(C::default, merge)
}

impl ViewCounts {
    /// Counts `cloud`'s valid points by where they lie.
    pub fn of(cloud: &PointCloud) -> ViewCounts {
        let limit = ViewLimit::new();
        fold_valid_points(cloud, |counts: &mut ViewCounts, p| counts.add(p, &limit), ViewCounts::merge)
    }

    /// Counts the valid point `p`.
    #[inline(always)]
    pub(super) fn add(&mut self, p: &Point, limit: &ViewLimit) {
        self.valid += 1;
        if p[2] <= 0.0 {
            self.behind += 1;
        } else if p[0] * p[0] + p[1] * p[1] > p[2] * p[2] * limit.max_tan_sq {
            self.beyond_any_view += 1;
        }
    }

    pub(super) fn merge(self, other: ViewCounts) -> ViewCounts {
        ViewCounts {
            valid: self.valid + other.valid,
            behind: self.behind + other.behind,
            beyond_any_view: self.beyond_any_view + other.beyond_any_view,
        }
    }

    /// Whether these points can be a camera-frame view, by their counts
    /// alone (see [`view_of`] for the spread as well).
    pub fn view(&self) -> View {
        let limit = (self.valid as f64 * MAX_IMPLAUSIBLE_FRACTION) as usize;
        if self.behind > limit {
            View::MostlyBehind
        } else if self.behind + self.beyond_any_view > limit {
            View::MostlyBeyondView
        } else {
            View::Camera
        }
    }
}

/// Refuses a frame of `valid_points` valid points that are nearly all one
/// point ([`MIN_DISTINCT_SHARE`]) or all lie within a few millimetres
/// ([`MIN_VIEW_EXTENT_MM`]), judged on points sampled evenly over it: no
/// camera's view of a workpiece looks like that, and planning it would
/// only spend the planner's time.
pub(super) fn check_spread(cloud: &PointCloud, valid_points: usize) -> Result<(), PlanError> {
    let stride = (valid_points / SPREAD_SAMPLE_POINTS).max(1);
    let mut sample: Vec<[u32; 3]> =
        cloud.points().iter().filter(|p| p[0].is_finite()).step_by(stride).map(|p| p.map(f32::to_bits)).collect();
    let sampled = sample.len();
    if sampled == 0 {
        return Ok(());
    }
    let (mut low, mut high) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &sample {
        for a in 0..3 {
            let c = f32::from_bits(p[a]);
            (low[a], high[a]) = (low[a].min(c), high[a].max(c));
        }
    }
    let extent_mm = (0..3).map(|a| f64::from(high[a]) - f64::from(low[a])).fold(0.0, f64::max);
    sample.sort_unstable();
    sample.dedup();
    let distinct = sample.len();
    if (distinct as f64) < MIN_DISTINCT_SHARE * sampled as f64 && sampled > 1 {
        return Err(PlanError::by(
            &rules::input::ONE_POINT_REPEATED,
            format!(
                "the frame is not a camera's view: of {sampled} points sampled evenly over its {valid_points} \
                 valid points only {distinct} are distinct ({:.1} %, under the {:.0} % a frame needs); \
                 a stuck sensor or a corrupt transfer repeats one point",
                100.0 * distinct as f64 / sampled as f64,
                100.0 * MIN_DISTINCT_SHARE
            ),
        ));
    }
    if extent_mm < MIN_VIEW_EXTENT_MM {
        return Err(PlanError::by(
            &rules::input::SMALLER_THAN_A_JOINT,
            format!(
                "the frame is not a camera's view: its {valid_points} valid points all lie within \
                 {extent_mm:.3} mm of each other along every axis (of {sampled} sampled), under the \
                 {MIN_VIEW_EXTENT_MM} mm any joint's plates span"
            ),
        ));
    }
    Ok(())
}

/// Refuses a cloud most of whose valid points lie behind the camera or
/// beyond any camera's field of view, by its `counts`, or whose points
/// spread wider than any camera sees, by its `extent`: planned, it would
/// give a seam of nonsense, so the reason and the likely cause are named
/// instead.
pub(super) fn check_camera_view(
    counts: &ViewCounts,
    extent: Option<&AngularExtent>,
    request: &PlanRequest,
) -> Result<(), PlanError> {
    let &ViewCounts { valid, behind, beyond_any_view } = counts;
    let hint = match request.cloud_frame {
        CloudFrame::Camera => "is the cloud in the robot base frame (cloud frame base, --cloud-frame base)?",
        CloudFrame::Base => "are the pose and the hand-eye those of the capture, and is the cloud in the base frame?",
    };
    match (view_of(counts, extent), extent) {
        (View::Camera, _) | (View::WiderThanAnyCamera, None) => Ok(()),
        (View::WiderThanAnyCamera, Some(extent)) => {
            let (axis, _) = extent.widest();
            Err(PlanError::by(
                &rules::input::NOT_IN_CAMERA_FRAME,
                format!(
                    "the cloud is not a camera-frame view: seen from the camera's origin its points spread over \
                     {:.1}° across x and {:.1}° across y (the outermost {:.0} % of {} sampled points left out at \
                     each side), wider across {axis} than the {MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG}° any depth camera \
                     sees; {hint}",
                    extent.across_x_deg,
                    extent.across_y_deg,
                    100.0 * EXTENT_TRIMMED_SHARE,
                    extent.sampled_points
                ),
            ))
        }
        (View::MostlyBehind, _) => Err(PlanError::by(
            &rules::input::NOT_IN_CAMERA_FRAME,
            format!(
                "the cloud is not a camera-frame view: {behind} of its {valid} valid points lie behind the \
                 camera (z <= 0); {hint}"
            ),
        )),
        (View::MostlyBeyondView, _) => Err(PlanError::by(
            &rules::input::NOT_IN_CAMERA_FRAME,
            format!(
                "the cloud is not a camera-frame view: {} of its {valid} valid points lie behind the camera or \
                 more than {MAX_PLAUSIBLE_OFF_AXIS_DEG}° off its axis, beyond any camera's field of view; {hint} \
                 Are its units right (--units mm|m)?",
                behind + beyond_any_view
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat surface facing the camera at `depth_mm`, `half_width_mm` to
    /// each side across x and half that across y, on a 5 mm grid.
    fn facing_surface(depth_mm: f32, half_width_mm: f32) -> Vec<Point> {
        let steps = (half_width_mm / 5.0) as i32;
        (-steps..=steps)
            .flat_map(|i| (-steps / 2..=steps / 2).map(move |j| [i as f32 * 5.0, j as f32 * 5.0, depth_mm]))
            .collect()
    }

    #[test]
    fn the_spread_seen_from_the_origin_tells_a_camera_view_from_a_cloud_held_close_and_wide() {
        // A table 700 mm wide seen from 600 mm: 60 degrees across x.
        let seen = AngularExtent::of(&PointCloud::unorganized(facing_surface(600.0, 350.0))).unwrap();
        let expected = 2.0 * (350.0f64 / 600.0).atan().to_degrees();
        assert!((seen.across_x_deg - expected).abs() < 1.0, "{seen:?} against {expected}");
        assert!(seen.across_y_deg < seen.across_x_deg && !seen.wider_than_any_camera(), "{seen:?}");
        assert_eq!(view_of(&ViewCounts { valid: 1, ..ViewCounts::default() }, Some(&seen)), View::Camera);

        // The same table 150 mm from the origin, as a robot's base frame
        // holds a workpiece beside the robot: 133 degrees across x.
        let mut close = facing_surface(150.0, 350.0);
        let wide = AngularExtent::of(&PointCloud::unorganized(close.clone())).unwrap();
        assert!(wide.wider_than_any_camera() && wide.widest().0 == "x", "{wide:?}");
        let counts = ViewCounts::of(&PointCloud::unorganized(close.clone()));
        assert_eq!(counts.view(), View::Camera, "no point lies behind the camera or off any cone");
        assert_eq!(view_of(&counts, Some(&wide)), View::WiderThanAnyCamera);

        // A few stray returns far off the axis do not widen a camera's view,
        // and behind the camera the counts speak first.
        let mut strays = facing_surface(600.0, 350.0);
        let n = strays.len() / 200;
        strays.extend((0..n).map(|i| [if i % 2 == 0 { 3000.0 } else { -3000.0 }, 0.0, 100.0]));
        let strayed = AngularExtent::of(&PointCloud::unorganized(strays)).unwrap();
        assert!((strayed.across_x_deg - expected).abs() < 2.0, "{strayed:?}");
        close.iter_mut().for_each(|p| p[2] = -p[2]);
        let behind = PointCloud::unorganized(close);
        assert_eq!(view_of(&ViewCounts::of(&behind), AngularExtent::of(&behind).as_ref()), View::MostlyBehind);

        // Too few points to read a spread from: none is judged.
        assert_eq!(AngularExtent::of(&PointCloud::unorganized(facing_surface(150.0, 20.0))), None);
    }
}
