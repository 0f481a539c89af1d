//! The same simulated capture as real cameras and real tools hand it
//! over: without its pixel grid, voxel-downsampled, in metres, in the robot
//! base frame, cropped around the seam (dropping the pixel grid, or
//! keeping it with the pixels outside the box left invalid), written as
//! PCL's tools write PCD (`DATA binary_compressed`), or several of these
//! at once.
//!
//! Each variant is a pure transform of a simulated frame. None of them
//! moves the seam out of the cloud, so the ground truth stays what it was:
//! in the camera frame, in millimetres (and in the base frame), where the
//! plan is scored. A [`Variant`] is written as on the command line:
//! `unorganized`, `voxel:1.0`, `metres`, `base`, `cropped:25`, `masked:25`,
//! `compressed`, or a comma-separated combination such as
//! `cropped:25,voxel:1,metres`. The steps always run in one order,
//! whatever order they are written in: crop (in the camera frame, where
//! the truth is), drop the grid, voxel downsampling, the base frame,
//! metres, the order a tool chain would take them in, and last the file
//! it writes.

use std::collections::HashMap;
use std::fmt;

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use crate::cloud::{INVALID_POINT, Point, PointCloud, is_valid_point, pcd};
use crate::geometry::Vec3;
use crate::sim::{GroundTruth, Simulation};

/// Voxel edge limits, mm: finer than a camera's pixel spacing is pointless,
/// and coarser than this leaves no plate to find.
pub const VOXEL_MM: [f64; 2] = [0.05, 50.0];
/// Crop width limits, mm of plate either side of the seam.
pub const CROP_WIDTH_MM: [f64; 2] = [2.0, 1000.0];

/// One step of a variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// Only the points inside a box around the seam: `width_mm` of plate
    /// either side of it and beyond its ends, and as much above and below
    /// the plate's top surface.
    Cropped { width_mm: f64 },
    /// The same box, the pixel grid kept: every pixel whose point lies
    /// outside it left invalid, as a camera driver's region of interest or
    /// PCL's `CropBox` keeping the cloud organized writes it. What lies
    /// beyond the box is then neither seen nor empty: no return.
    Masked { width_mm: f64 },
    /// The valid points only, same coordinates, in an order shuffled from
    /// the scene's seed, so nothing can rely on pixel order.
    Unorganized,
    /// Voxel-grid downsampling as PCL's `VoxelGrid` does it: the centroid
    /// of the points in each occupied cube of edge `size_mm`.
    Voxel { size_mm: f64 },
    /// Points in the robot base frame, through the pose and hand-eye.
    Base,
    /// Coordinates in metres.
    Metres,
    /// Written as PCD `DATA binary_compressed` (LZF, field by field, as
    /// PCL's tools write it) and read back by the reader `plan` loads
    /// files with: lossless, so the cloud plans as it did, through the
    /// codec a real file goes through.
    Compressed,
}

impl Step {
    /// The position of the step in the order every variant applies them.
    fn rank(&self) -> usize {
        match self {
            Step::Cropped { .. } | Step::Masked { .. } => 0,
            Step::Unorganized => 1,
            Step::Voxel { .. } => 2,
            Step::Base => 3,
            Step::Metres => 4,
            Step::Compressed => 5,
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Step::Cropped { .. } => "cropped",
            Step::Masked { .. } => "masked",
            Step::Unorganized => "unorganized",
            Step::Voxel { .. } => "voxel",
            Step::Base => "base",
            Step::Metres => "metres",
            Step::Compressed => "compressed",
        }
    }
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Step::Cropped { width_mm } => write!(f, "cropped:{width_mm}"),
            Step::Masked { width_mm } => write!(f, "masked:{width_mm}"),
            Step::Voxel { size_mm } => write!(f, "voxel:{size_mm}"),
            other => f.write_str(other.name()),
        }
    }
}

/// A variant: its steps in the order they apply. No steps is the raw
/// organized frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Variant {
    steps: Vec<Step>,
}

/// Why a variant's text was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VariantError {
    #[error(
        "no variant given: name one of raw, unorganized, voxel:MM, metres, base, cropped:MM, masked:MM, compressed"
    )]
    Empty,
    #[error(
        "unknown variant {0:?}: the variants are raw, unorganized, voxel:MM, metres, base, cropped:MM, masked:MM, \
         compressed"
    )]
    Unknown(String),
    #[error("{name} needs a size in mm, as in {name}:{example}")]
    MissingSize { name: &'static str, example: &'static str },
    #[error("{name} takes no value, but got {value:?}")]
    UnexpectedValue { name: &'static str, value: String },
    #[error("{name}:{value} is not a number of millimetres")]
    NotANumber { name: &'static str, value: String },
    #[error("{name}:{value} is outside {min} to {max} mm")]
    OutOfRange { name: &'static str, value: f64, min: f64, max: f64 },
    #[error("{0} is given twice")]
    Repeated(&'static str),
    #[error("{0} and {1} both crop the cloud: give one")]
    TwoCrops(&'static str, &'static str),
}

impl Variant {
    /// The raw organized frame, unchanged.
    pub fn raw() -> Variant {
        Variant::default()
    }

    /// The steps, in the order they apply.
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    pub fn is_raw(&self) -> bool {
        self.steps.is_empty()
    }

    /// True when the cloud comes out in metres.
    pub fn in_metres(&self) -> bool {
        self.steps.contains(&Step::Metres)
    }

    /// True when the cloud comes out as PCD `DATA binary_compressed`.
    pub fn is_compressed(&self) -> bool {
        self.steps.contains(&Step::Compressed)
    }

    /// True when the cloud comes out in the robot base frame.
    pub fn in_base_frame(&self) -> bool {
        self.steps.contains(&Step::Base)
    }

    /// Parses `cropped:25,voxel:1,metres` (any order; `raw` alone is the
    /// unchanged frame).
    pub fn parse(text: &str) -> Result<Variant, VariantError> {
        let text = text.trim();
        if text.is_empty() {
            return Err(VariantError::Empty);
        }
        if text == "raw" {
            return Ok(Variant::raw());
        }
        let steps = text.split(',').map(|part| parse_step(part.trim())).collect::<Result<Vec<Step>, _>>()?;
        Variant::from_steps(&steps)
    }

    /// The variant of these steps (any order; each kind at most once).
    pub fn from_steps(steps: &[Step]) -> Result<Variant, VariantError> {
        let mut sorted: Vec<Step> = Vec::with_capacity(steps.len());
        for step in steps {
            if let Some(same) = sorted.iter().find(|s| s.rank() == step.rank()) {
                return Err(match same.name() == step.name() {
                    true => VariantError::Repeated(step.name()),
                    false => VariantError::TwoCrops(same.name(), step.name()),
                });
            }
            sorted.push(*step);
        }
        sorted.sort_by_key(Step::rank);
        Ok(Variant { steps: sorted })
    }

    /// The simulated capture as this variant: the transformed cloud, with
    /// the same truth, pose and transforms. `seed` orders the shuffle of
    /// [`Step::Unorganized`] (the scene's seed keeps each scene's order
    /// fixed from run to run).
    pub fn apply(&self, sim: &Simulation, seed: u64) -> Simulation {
        let mut cloud = sim.cloud.clone();
        for step in &self.steps {
            cloud = match *step {
                Step::Cropped { width_mm } => crop_around_seam(&cloud, &sim.truth, width_mm),
                Step::Masked { width_mm } => mask_around_seam(&cloud, &sim.truth, width_mm),
                Step::Unorganized => unorganized(&cloud, seed),
                Step::Voxel { size_mm } => voxel_grid(&cloud, size_mm),
                Step::Base => transformed(&cloud, |p| sim.base_from_camera * p),
                Step::Metres => to_metres(&cloud),
                Step::Compressed => through_compressed_pcd(&cloud),
            };
        }
        Simulation { cloud, ..sim.clone() }
    }
}

impl fmt::Display for Variant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.steps.is_empty() {
            return f.write_str("raw");
        }
        let names: Vec<String> = self.steps.iter().map(Step::to_string).collect();
        f.write_str(&names.join(","))
    }
}

impl std::str::FromStr for Variant {
    type Err = VariantError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Variant::parse(s)
    }
}

fn parse_step(part: &str) -> Result<Step, VariantError> {
    let (name, value) = match part.split_once(':') {
        Some((n, v)) => (n.trim(), Some(v.trim())),
        None => (part, None),
    };
    let plain = |step: Step| match value {
        None => Ok(step),
        Some(v) => Err(VariantError::UnexpectedValue { name: step.name(), value: v.to_string() }),
    };
    let sized = |name: &'static str, example: &'static str, [min, max]: [f64; 2]| {
        let value = value.ok_or(VariantError::MissingSize { name, example })?;
        let mm: f64 = value.parse().map_err(|_| VariantError::NotANumber { name, value: value.to_string() })?;
        if !(min..=max).contains(&mm) {
            return Err(VariantError::OutOfRange { name, value: mm, min, max });
        }
        Ok(mm)
    };
    match name {
        "unorganized" | "unorganised" => plain(Step::Unorganized),
        "metres" | "meters" => plain(Step::Metres),
        "base" => plain(Step::Base),
        "compressed" => plain(Step::Compressed),
        "voxel" => Ok(Step::Voxel { size_mm: sized("voxel", "1.0", VOXEL_MM)? }),
        "cropped" => Ok(Step::Cropped { width_mm: sized("cropped", "25", CROP_WIDTH_MM)? }),
        "masked" => Ok(Step::Masked { width_mm: sized("masked", "25", CROP_WIDTH_MM)? }),
        "" => Err(VariantError::Empty),
        other => Err(VariantError::Unknown(other.to_string())),
    }
}

/// The valid points in an order shuffled by `seed` (Fisher-Yates).
pub fn unorganized(cloud: &PointCloud, seed: u64) -> PointCloud {
    let mut points: Vec<Point> = cloud.points().iter().copied().filter(is_valid_point).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in (1..points.len()).rev() {
        // Uniform below i + 1, without the bias of a plain modulo worth
        // speaking of: i is at most a few million, next_u64 has 64 bits.
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        points.swap(i, j);
    }
    PointCloud::unorganized(points)
}

/// The voxel of `p` on a grid of edge `size` anchored at `origin`.
fn voxel_of(p: &Point, origin: &[f64; 3], size: f64) -> [i64; 3] {
    std::array::from_fn(|k| ((p[k] as f64 - origin[k]) / size).floor() as i64)
}

/// The lower corner of the valid points' bounding box; `None` if none.
fn lower_corner(points: &[Point]) -> Option<[f64; 3]> {
    let mut valid = points.iter().filter(|p| is_valid_point(p));
    let first = valid.next()?;
    let mut low: [f64; 3] = first.map(f64::from);
    for p in valid {
        for k in 0..3 {
            low[k] = low[k].min(p[k] as f64);
        }
    }
    Some(low)
}

/// Voxel-grid downsampling as PCL's `VoxelGrid` does it: a grid of cubes
/// of edge `size_mm` anchored at the cloud's lower bounding-box corner,
/// one point per occupied cube at the centroid of its points, in the order
/// of the cubes' indices. The output is unorganized.
pub fn voxel_grid(cloud: &PointCloud, size_mm: f64) -> PointCloud {
    let Some(origin) = lower_corner(cloud.points()) else {
        return PointCloud::unorganized(Vec::new());
    };
    let mut sums: HashMap<[i64; 3], ([f64; 3], u32)> = HashMap::new();
    for p in cloud.points().iter().filter(|p| is_valid_point(p)) {
        let entry = sums.entry(voxel_of(p, &origin, size_mm)).or_insert(([0.0; 3], 0));
        for (sum, c) in entry.0.iter_mut().zip(p) {
            *sum += *c as f64;
        }
        entry.1 += 1;
    }
    let mut voxels: Vec<([i64; 3], [f64; 3], u32)> = sums.into_iter().map(|(key, (sum, n))| (key, sum, n)).collect();
    voxels.sort_unstable_by_key(|(key, _, _)| [key[2], key[1], key[0]]);
    let points = voxels.iter().map(|(_, sum, n)| std::array::from_fn(|k| (sum[k] / *n as f64) as f32)).collect();
    PointCloud::unorganized(points)
}

/// Every point mapped by `f` (computed in f64), the grid kept.
fn transformed(cloud: &PointCloud, f: impl Fn(nalgebra::Point3<f64>) -> nalgebra::Point3<f64>) -> PointCloud {
    let points: Vec<Point> = cloud
        .points()
        .iter()
        .map(|p| {
            if !is_valid_point(p) {
                return *p;
            }
            let q = f(nalgebra::Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
            [q.x as f32, q.y as f32, q.z as f32]
        })
        .collect();
    rebuild_like(cloud, points)
}

/// The same cloud, coordinates divided by 1000.
pub fn to_metres(cloud: &PointCloud) -> PointCloud {
    transformed(cloud, |p| p / 1000.0)
}

/// `cloud` written as PCD `DATA binary_compressed` and read back by
/// [`pcd::parse`], as `plan` reads a file a PCL tool wrote.
pub fn through_compressed_pcd(cloud: &PointCloud) -> PointCloud {
    let mut bytes = Vec::new();
    pcd::write_binary_compressed(cloud, &mut bytes)
        .unwrap_or_else(|e| unreachable!("writing a cloud into memory does not fail: {e}"));
    pcd::parse(&bytes, std::path::Path::new("compressed.pcd"))
        .unwrap_or_else(|e| unreachable!("the PCD reader reads what its writer wrote: {e}"))
}

/// `points` with `like`'s layout: organized of its size, or unorganized.
fn rebuild_like(like: &PointCloud, points: Vec<Point>) -> PointCloud {
    if like.is_organized() {
        PointCloud::organized(like.width(), like.height(), points)
            .unwrap_or_else(|| unreachable!("a map keeps the point count"))
    } else {
        PointCloud::unorganized(points)
    }
}

/// The seam's box: an origin at the seam's start and unit axes along the
/// seam, across it in the plate and along the plate normal, camera frame.
struct SeamBox {
    origin: Vec3,
    along: Vec3,
    across: Vec3,
    normal: Vec3,
    length_mm: f64,
    width_mm: f64,
}

impl SeamBox {
    fn new(truth: &GroundTruth, width_mm: f64) -> SeamBox {
        let seam = truth.end_camera - truth.start_camera;
        let along = seam.normalize();
        let normal = truth.plate_normal_camera.normalize();
        let across = normal.cross(&along).normalize();
        SeamBox { origin: truth.start_camera, along, across, normal, length_mm: seam.norm(), width_mm }
    }

    /// Inside: within `width_mm` of the seam across it and along the
    /// normal, and from `width_mm` before its start to as far past its end.
    fn contains(&self, p: &Vec3) -> bool {
        let d = p - self.origin;
        let (s, t, h) = (d.dot(&self.along), d.dot(&self.across), d.dot(&self.normal));
        (-self.width_mm..=self.length_mm + self.width_mm).contains(&s)
            && t.abs() <= self.width_mm
            && h.abs() <= self.width_mm
    }
}

/// The points inside a box around the seam (camera frame, mm), as a
/// cropping tool writes them: unorganized, in their original order.
pub fn crop_around_seam(cloud: &PointCloud, truth: &GroundTruth, width_mm: f64) -> PointCloud {
    let seam_box = SeamBox::new(truth, width_mm);
    let points = cloud
        .points()
        .iter()
        .copied()
        .filter(|p| is_valid_point(p) && seam_box.contains(&Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
        .collect();
    PointCloud::unorganized(points)
}

/// The points inside the same box as [`crop_around_seam`]'s, on the
/// frame's pixel grid: each point outside it made invalid, in place. An
/// unorganized cloud has no grid to keep and loses them.
pub fn mask_around_seam(cloud: &PointCloud, truth: &GroundTruth, width_mm: f64) -> PointCloud {
    if !cloud.is_organized() {
        return crop_around_seam(cloud, truth, width_mm);
    }
    let seam_box = SeamBox::new(truth, width_mm);
    let points = cloud
        .points()
        .iter()
        .map(|p| match is_valid_point(p) && seam_box.contains(&Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)) {
            true => *p,
            false => INVALID_POINT,
        })
        .collect();
    // The same width and height as the frame, so the grid is accepted.
    PointCloud::organized(cloud.width(), cloud.height(), points)
        .unwrap_or_else(|| crop_around_seam(cloud, truth, width_mm))
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use proptest::prelude::*;

    use super::*;
    use crate::joint::JointType;
    use crate::sim::scenarios::{FRAME_SIZES, Scenario, camera_with_size};

    fn small_sim(joint: JointType) -> Simulation {
        let (w, h) = FRAME_SIZES[0];
        Scenario::new(joint, 500.0, camera_with_size(w, h)).simulate()
    }

    fn sorted(points: &[Point]) -> Vec<[u32; 3]> {
        let mut bits: Vec<[u32; 3]> =
            points.iter().filter(|p| is_valid_point(p)).map(|p| p.map(f32::to_bits)).collect();
        bits.sort_unstable();
        bits
    }

    fn bounds(points: &[Point]) -> ([f32; 3], [f32; 3]) {
        let mut low = [f32::INFINITY; 3];
        let mut high = [f32::NEG_INFINITY; 3];
        for p in points.iter().filter(|p| is_valid_point(p)) {
            for k in 0..3 {
                low[k] = low[k].min(p[k]);
                high[k] = high[k].max(p[k]);
            }
        }
        (low, high)
    }

    #[test]
    fn variants_parse_in_any_order_and_apply_in_one() {
        let v = Variant::parse("metres, voxel:1, cropped:25").unwrap();
        assert_eq!(v.steps(), [Step::Cropped { width_mm: 25.0 }, Step::Voxel { size_mm: 1.0 }, Step::Metres]);
        assert_eq!(v.to_string(), "cropped:25,voxel:1,metres");
        assert_eq!(Variant::parse(&v.to_string()), Ok(v));
        assert_eq!("raw".parse::<Variant>(), Ok(Variant::raw()));
        assert!(Variant::parse("base").unwrap().in_base_frame());
        assert!(Variant::parse("unorganized,metres").unwrap().in_metres());
    }

    #[test]
    fn bad_variants_are_refused_with_what_is_wrong() {
        let err = |t: &str| Variant::parse(t).unwrap_err().to_string();
        assert!(err("voxels:1").contains("unknown variant \"voxels\""), "{}", err("voxels:1"));
        assert!(err("voxel").contains("voxel:1.0"), "{}", err("voxel"));
        assert!(err("voxel:0").contains("outside 0.05 to 50 mm"), "{}", err("voxel:0"));
        assert!(err("cropped:wide").contains("not a number"), "{}", err("cropped:wide"));
        assert!(err("metres:2").contains("takes no value"), "{}", err("metres:2"));
        assert!(err("base,base").contains("twice"), "{}", err("base,base"));
        assert!(
            err("masked:25,cropped:30").contains("masked and cropped both crop the cloud"),
            "{}",
            err("masked:25,cropped:30")
        );
        assert!(err("voxel:1,").contains("no variant"), "{}", err("voxel:1,"));
        assert!(err("").contains("no variant"));
    }

    #[test]
    fn unorganized_keeps_every_valid_point_in_a_seeded_order() {
        let sim = small_sim(JointType::IButt);
        let a = unorganized(&sim.cloud, 7);
        assert!(!a.is_organized());
        assert_eq!(a.len(), sim.cloud.valid_count());
        assert_eq!(sorted(a.points()), sorted(sim.cloud.points()), "the same points");
        assert_eq!(a, unorganized(&sim.cloud, 7), "one seed, one order");
        assert_ne!(a.points(), unorganized(&sim.cloud, 8).points(), "another seed, another order");
        let in_pixel_order: Vec<Point> = sim.cloud.points().iter().copied().filter(is_valid_point).collect();
        assert_ne!(a.points(), &in_pixel_order[..], "not in pixel order");
    }

    #[test]
    fn a_compressed_pcd_gives_back_every_point_and_the_grid() {
        let sim = small_sim(JointType::VButt);
        for text in ["compressed", "voxel:1,metres,compressed"] {
            let variant = Variant::parse(text).unwrap();
            assert!(variant.is_compressed());
            let plain = Variant::from_steps(&variant.steps()[..variant.steps().len() - 1]).unwrap().apply(&sim, 3);
            let read = variant.apply(&sim, 3);
            assert_eq!(
                (read.cloud.width(), read.cloud.height()),
                (plain.cloud.width(), plain.cloud.height()),
                "{text}"
            );
            assert_eq!(read.cloud.is_organized(), plain.cloud.is_organized(), "{text}");
            for (r, p) in read.cloud.points().iter().zip(plain.cloud.points()) {
                assert_eq!(is_valid_point(r), is_valid_point(p), "{text}");
                if is_valid_point(p) {
                    assert_eq!(r.map(f32::to_bits), p.map(f32::to_bits), "{text}: every bit of every point");
                }
            }
        }
        assert_eq!(Variant::parse("compressed,cropped:25").unwrap().to_string(), "cropped:25,compressed");
    }

    #[test]
    fn base_frame_points_come_back_to_the_camera_frame() {
        let sim = small_sim(JointType::Lap);
        let base = Variant::parse("base").unwrap().apply(&sim, 1);
        assert_eq!((base.cloud.width(), base.cloud.height()), (sim.cloud.width(), sim.cloud.height()));
        let back = sim.base_from_camera.inverse();
        let mut moved = 0.0f64;
        for (b, c) in base.cloud.points().iter().zip(sim.cloud.points()) {
            assert_eq!(is_valid_point(b), is_valid_point(c));
            if !is_valid_point(c) {
                continue;
            }
            let q = back * nalgebra::Point3::new(b[0] as f64, b[1] as f64, b[2] as f64);
            let error = (q - nalgebra::Point3::new(c[0] as f64, c[1] as f64, c[2] as f64)).norm();
            assert!(error < 1e-3, "{b:?} comes back {error} mm from {c:?}");
            moved = moved.max((b[2] - c[2]).abs() as f64);
        }
        assert!(moved > 10.0, "the base frame is another frame");
        assert_eq!(base.truth, sim.truth, "the truth stays in the camera frame, mm");
    }

    #[test]
    fn a_crop_keeps_the_plate_beside_the_seam_and_nothing_far() {
        let sim = small_sim(JointType::VButt);
        let width = 25.0;
        let cropped = crop_around_seam(&sim.cloud, &sim.truth, width);
        assert!(cropped.len() > 1000 && cropped.len() < sim.cloud.valid_count() / 2, "{} points", cropped.len());
        let seam_box = SeamBox::new(&sim.truth, width);
        let inner = SeamBox::new(&sim.truth, width - 1.0);
        let as_vec = |p: &Point| Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        assert!(cropped.points().iter().all(|p| seam_box.contains(&as_vec(p))));
        let kept: HashSet<[u32; 3]> = cropped.points().iter().map(|p| p.map(f32::to_bits)).collect();
        for p in sim.cloud.points().iter().filter(|p| is_valid_point(p) && inner.contains(&as_vec(p))) {
            assert!(kept.contains(&p.map(f32::to_bits)), "{p:?} is well inside the box but was dropped");
        }
        // Plate on both sides of the seam is left.
        let sides = cropped.points().iter().map(|p| (as_vec(p) - seam_box.origin).dot(&seam_box.across));
        let (min, max) = sides.fold((0.0f64, 0.0f64), |(lo, hi), t| (lo.min(t), hi.max(t)));
        assert!(min < -width + 2.0 && max > width - 2.0, "{min} to {max} mm across the seam");
    }

    #[test]
    fn a_mask_keeps_the_crops_points_on_the_frames_grid() {
        let sim = small_sim(JointType::Lap);
        let masked = Variant::parse("masked:40").unwrap().apply(&sim, 3).cloud;
        assert!(masked.is_organized());
        assert_eq!((masked.width(), masked.height()), (sim.cloud.width(), sim.cloud.height()));
        let cropped = crop_around_seam(&sim.cloud, &sim.truth, 40.0);
        assert!(cropped.len() < sim.cloud.valid_count(), "the box leaves points out");
        // Every kept point sits at its own pixel; the rest are invalid.
        let kept: HashSet<[u32; 3]> = cropped.points().iter().map(|p| p.map(f32::to_bits)).collect();
        for (m, p) in masked.points().iter().zip(sim.cloud.points()) {
            match is_valid_point(m) {
                true => assert_eq!(m, p),
                false => assert!(!is_valid_point(p) || !kept.contains(&p.map(f32::to_bits)), "{p:?} dropped"),
            }
        }
        assert_eq!(masked.valid_count(), cropped.len());
        // Without a grid it is the crop.
        let bag = unorganized(&sim.cloud, 3);
        assert_eq!(
            mask_around_seam(&bag, &sim.truth, 40.0).points(),
            crop_around_seam(&bag, &sim.truth, 40.0).points()
        );
    }

    #[test]
    fn a_combined_variant_is_cropped_downsampled_and_in_metres() {
        let sim = small_sim(JointType::IButt);
        let v = Variant::parse("cropped:25,voxel:1,metres").unwrap().apply(&sim, 3);
        let mm = voxel_grid(&crop_around_seam(&sim.cloud, &sim.truth, 25.0), 1.0);
        assert_eq!(v.cloud.len(), mm.len());
        for (m, p) in v.cloud.points().iter().zip(mm.points()) {
            for k in 0..3 {
                assert!((m[k] * 1000.0 - p[k]).abs() <= p[k].abs() * 1e-6, "{m:?} m against {p:?} mm");
            }
        }
        let (low, high) = bounds(v.cloud.points());
        assert!(low[2] > 0.3 && high[2] < 0.7, "depths {low:?} to {high:?} are in metres");
    }

    fn point() -> impl Strategy<Value = Point> {
        prop::array::uniform3(-500.0f32..500.0)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        #[test]
        fn voxels_hold_one_point_each_inside_the_input_box(
            points in prop::collection::vec(point(), 1..400),
            size in 0.05f64..200.0,
        ) {
            let input = PointCloud::unorganized(points);
            let output = voxel_grid(&input, size);
            let origin = lower_corner(input.points()).unwrap();
            let occupied: HashSet<[i64; 3]> = input.points().iter().map(|p| voxel_of(p, &origin, size)).collect();
            prop_assert_eq!(output.len(), occupied.len());
            let (low, high) = bounds(input.points());
            let mut seen = HashSet::new();
            for p in output.points() {
                prop_assert!((0..3).all(|k| low[k] <= p[k] && p[k] <= high[k]), "{:?} outside {:?} {:?}", p, low, high);
                prop_assert!(seen.insert(voxel_of(p, &origin, size)), "two points in the voxel of {:?}", p);
            }
        }

        #[test]
        fn metres_times_a_thousand_is_the_input(points in prop::collection::vec(point(), 1..200)) {
            let input = PointCloud::unorganized(points);
            let metres = to_metres(&input);
            prop_assert_eq!(metres.len(), input.len());
            for (m, p) in metres.points().iter().zip(input.points()) {
                for k in 0..3 {
                    let back = m[k] as f64 * 1000.0;
                    prop_assert!((back - p[k] as f64).abs() <= (p[k].abs() as f64) * 1e-6 + 1e-9, "{:?} -> {:?}", p, m);
                }
            }
        }
    }
}
