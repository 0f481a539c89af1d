//! Simulated hand-eye calibration sets: robot poses around a target (a
//! board whose pose the camera reports, or calibration spheres on posts
//! over a table, seen as point clouds), with the true hand-eye alongside.
//!
//! Each capture's geometry is first the camera's view of the target
//! (`Camera_T_Target`): the camera `distance_mm` away, tilted 10 to 35
//! degrees off the target's normal in any direction, rolled up to 45
//! degrees about its axis, aimed within 30 mm of the target's origin. The
//! robot pose follows from it: for a camera on the flange `Base_T_End =
//! Base_T_Target · Camera_T_Target⁻¹ · End_T_Camera⁻¹`; for a camera fixed
//! in the cell (the target on the flange) `Base_T_End = Base_T_Camera ·
//! Camera_T_Target · End_T_Target⁻¹`.
//!
//! Noise: the pose the controller reports differs from the true one by a
//! random translation of RMS length [`ROBOT_TRANSLATION_SIGMA_MM`] and a
//! random rotation of RMS angle [`ROBOT_ROTATION_SIGMA_DEG`] (each axis a
//! third of the variance; a robot's repeatability as specified, ISO 9283's
//! three-sigma radius, is larger than this RMS error, so the set is no
//! easier than a real cell); a board's pose by
//! [`BOARD_TRANSLATION_SIGMA_MM`] and [`BOARD_ROTATION_SIGMA_DEG`] alike; a sphere cloud carries the simulator's
//! sensor noise ([`super::noise`]: depth noise along each ray, mixed
//! pixels at the spheres' rims against the table, dropouts, outliers).
//! Spheres are rendered only in windows of pixels around each sphere, so a
//! capture is about 10⁵ points rather than a whole frame.
//!
//! The tooling-ball rig ([`CalibrationSpec::rig`]) is what many cells
//! mount: three balls of one radius ([`TOOLING_BALL_RADIUS_MM`]) on posts
//! thinner than the balls above a table, rendered in one window around the
//! whole rig with the camera binned ([`RIG_BINNING`]), so each cloud holds
//! the balls' caps, the posts, a wide stretch of table, the sensor's noise,
//! and stray returns ([`RIG_STRAY_FRACTION`] of the points scattered in
//! the window's view, [`RIG_FLARE_CLUSTERS`] small clusters of flare).
//!
//! Three faults on request: one capture's observation taken at a pose the
//! controller did not report (a wrong pairing), rotations all about the
//! camera's axis (near-parallel rotation axes), and small rotations (tilts
//! of 3 to 8 degrees).

use std::collections::HashSet;

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::noise::{self, NoiseSpec};
use crate::calibration::Mount;
use crate::camera::{CameraModel, Intrinsics};
use crate::cloud::{INVALID_POINT, PointCloud};
use crate::geometry::Vec3;

/// The robot's pose noise: RMS length of the translation error.
pub const ROBOT_TRANSLATION_SIGMA_MM: f64 = 0.05;
/// See [`ROBOT_TRANSLATION_SIGMA_MM`].
pub const ROBOT_ROTATION_SIGMA_DEG: f64 = 0.01;
/// A board detector's pose noise: RMS length of the translation error.
pub const BOARD_TRANSLATION_SIGMA_MM: f64 = 0.05;
/// See [`BOARD_TRANSLATION_SIGMA_MM`].
pub const BOARD_ROTATION_SIGMA_DEG: f64 = 0.02;
/// The most captures a simulated set has.
pub const MAX_SIM_CAPTURES: usize = 200;

/// What the camera sees.
#[derive(Debug, Clone, PartialEq)]
pub enum CalibrationTarget {
    /// A board whose pose the camera reports.
    Board,
    /// Spheres of these radii (mm) on posts over a table.
    Spheres(Vec<f64>),
}

/// The spheres' default radii, mm: different, so they are named by size.
pub const DEFAULT_SPHERE_RADII_MM: [f64; 3] = [20.0, 15.0, 10.0];

/// A calibration set to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationSpec {
    pub target: CalibrationTarget,
    pub mount: Mount,
    pub captures: usize,
    pub seed: u64,
    /// The camera's distance to the target, mm.
    pub distance_mm: f64,
    /// This capture's observation is taken at an unreported pose.
    pub wrong_pairing: Option<usize>,
    /// Every rotation about the camera's axis.
    pub parallel_axes: bool,
    /// Tilts of 3 to 8 degrees and rolls within 8 degrees: the small
    /// rotations integrators complain of.
    pub small_rotations: bool,
    /// The true hand-eye: `End_T_Camera`, or `Base_T_Camera`.
    pub hand_eye: Isometry3<f64>,
    /// The tooling-ball rig: the target must be
    /// `Spheres([TOOLING_BALL_RADIUS_MM; 3])`.
    pub rig: bool,
}

impl CalibrationSpec {
    /// Fifteen captures at 500 mm, the camera on the flange with the
    /// paper's hand-eye.
    pub fn new(target: CalibrationTarget, mount: Mount, seed: u64) -> CalibrationSpec {
        let hand_eye = match mount {
            Mount::EyeInHand => super::paper_hand_eye(),
            Mount::EyeToHand => Isometry3::new(Vec3::new(900.0, -400.0, 800.0), Vec3::new(2.2, -0.4, 0.3)),
        };
        CalibrationSpec {
            target,
            mount,
            captures: 15,
            seed,
            distance_mm: 500.0,
            wrong_pairing: None,
            parallel_axes: false,
            small_rotations: false,
            hand_eye,
            rig: false,
        }
    }
}

/// What one simulated capture holds.
#[derive(Debug, Clone)]
pub enum SimObservation {
    TargetPose(Isometry3<f64>),
    Cloud(PointCloud),
}

/// One simulated capture: the pose the controller reports and what the
/// camera gave.
#[derive(Debug, Clone)]
pub struct SimCapture {
    pub base_t_end: Isometry3<f64>,
    pub observation: SimObservation,
}

/// A simulated set and its truth.
#[derive(Debug, Clone)]
pub struct CalibrationSet {
    pub captures: Vec<SimCapture>,
    /// The true hand-eye.
    pub hand_eye: Isometry3<f64>,
    /// Where the target is: `Base_T_Target`, or `End_T_Target` for a
    /// camera fixed in the cell.
    pub target_pose: Isometry3<f64>,
    /// The spheres' centres in the target frame.
    pub sphere_centres: Vec<Vec3>,
}

/// Why a set cannot be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationSimError {
    #[error("{0} captures: give 3 to {MAX_SIM_CAPTURES}")]
    Captures(usize),
    #[error("the wrong pairing names capture {index}, but the set has {count}")]
    WrongPairing { index: usize, count: usize },
    #[error("the distance {0} mm is outside 200 to 2000 mm")]
    Distance(f64),
    #[error("give 1 to {} sphere radii of 5 to 60 mm", crate::calibration::sphere::MAX_SPHERES)]
    Radii,
    #[error("the tooling-ball rig holds three spheres of {TOOLING_BALL_RADIUS_MM} mm, on the camera's side")]
    Rig,
}

impl CalibrationSpec {
    pub fn validate(&self) -> Result<(), CalibrationSimError> {
        if !(3..=MAX_SIM_CAPTURES).contains(&self.captures) {
            return Err(CalibrationSimError::Captures(self.captures));
        }
        if let Some(index) = self.wrong_pairing.filter(|i| *i >= self.captures) {
            return Err(CalibrationSimError::WrongPairing { index, count: self.captures });
        }
        if !(200.0..=2000.0).contains(&self.distance_mm) {
            return Err(CalibrationSimError::Distance(self.distance_mm));
        }
        if let CalibrationTarget::Spheres(radii) = &self.target
            && (radii.is_empty()
                || radii.len() > crate::calibration::sphere::MAX_SPHERES
                || radii.iter().any(|r| !(5.0..=60.0).contains(r)))
        {
            return Err(CalibrationSimError::Radii);
        }
        let rig_target = CalibrationTarget::Spheres(vec![TOOLING_BALL_RADIUS_MM; 3]);
        if self.rig && (self.target != rig_target || self.mount != Mount::EyeInHand) {
            return Err(CalibrationSimError::Rig);
        }
        Ok(())
    }
}

/// Seeded normal and uniform draws.
struct Draws(ChaCha8Rng);

impl Draws {
    fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    fn between(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    fn gaussian(&mut self) -> f64 {
        let radius = (-2.0 * (1.0 - self.uniform()).ln()).sqrt();
        radius * (std::f64::consts::TAU * self.uniform()).cos()
    }

    fn vector(&mut self, sigma: f64) -> Vec3 {
        Vec3::new(self.gaussian(), self.gaussian(), self.gaussian()) * sigma
    }

    /// `pose` moved by a random rigid motion whose translation and
    /// rotation have the given RMS length and angle.
    fn jitter(&mut self, pose: &Isometry3<f64>, rms_mm: f64, rms_deg: f64) -> Isometry3<f64> {
        let per_axis = 1.0 / 3f64.sqrt();
        let delta = Isometry3::new(self.vector(rms_mm * per_axis), self.vector(rms_deg.to_radians() * per_axis));
        Isometry3::from_parts(
            Translation3::from(pose.translation.vector + delta.translation.vector),
            delta.rotation * pose.rotation,
        )
    }
}

/// The spheres' centres in the target frame: on posts over the table
/// (`z = 0`), spread over about 160 mm, the distances between the first
/// three all different by 10 mm or more so that equal spheres can be told
/// apart by them.
fn sphere_layout(radii: &[f64]) -> Vec<Vec3> {
    const SPOTS: [[f64; 2]; 6] =
        [[-90.0, -50.0], [70.0, -50.0], [-30.0, 60.0], [60.0, 75.0], [0.0, -5.0], [-95.0, 20.0]];
    radii.iter().zip(SPOTS).enumerate().map(|(k, (r, [x, y]))| Vec3::new(x, y, r + 30.0 + 10.0 * k as f64)).collect()
}

/// The camera's view of the target for one capture.
fn view(draws: &mut Draws, spec: &CalibrationSpec, index: usize) -> Isometry3<f64> {
    let (tilt, azimuth, roll) = if spec.parallel_axes {
        // Only the roll about the camera's axis changes; the view
        // direction wobbles by a fraction of a degree.
        let roll = -60.0 + 120.0 * index as f64 / (spec.captures.max(2) - 1) as f64;
        (20.0 + draws.between(-0.3, 0.3), draws.between(-0.5, 0.5), roll + draws.between(-2.0, 2.0))
    } else if spec.small_rotations {
        (draws.between(3.0, 8.0), draws.between(0.0, 360.0), draws.between(-8.0, 8.0))
    } else {
        // A sphere looks the same from any side, so sphere sets tilt
        // further than a board can be detected at.
        let steepest = match spec.target {
            CalibrationTarget::Board => 45.0,
            CalibrationTarget::Spheres(_) => 60.0,
        };
        (draws.between(20.0, steepest), draws.between(0.0, 360.0), draws.between(-90.0, 90.0))
    };
    let distance = spec.distance_mm * draws.between(0.92, 1.08);
    let aim = Vec3::new(draws.between(-30.0, 30.0), draws.between(-30.0, 30.0), 0.0);
    let (t, a) = (tilt.to_radians(), azimuth.to_radians());
    let eye = aim + distance * Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos());
    // The optical axis from the eye to the aim point; the image's x axis
    // level with the target's x where it can be, then rolled.
    let z = (aim - eye).normalize();
    let x0 = Vec3::x().cross(&z).cross(&z) * -1.0;
    let x0 = if x0.norm() > 1e-6 { x0.normalize() } else { Vec3::y() };
    let y0 = z.cross(&x0);
    let level = Rotation3::from_basis_unchecked(&[x0, y0, z]);
    let rolled = level * Rotation3::from_axis_angle(&Vector3::z_axis(), roll.to_radians());
    let target_t_camera = Isometry3::from_parts(Translation3::from(eye), UnitQuaternion::from_rotation_matrix(&rolled));
    target_t_camera.inverse()
}

/// Simulates a calibration set. Validate the spec first.
pub fn simulate_calibration(spec: &CalibrationSpec, camera: &CameraModel) -> CalibrationSet {
    let mut draws = Draws(ChaCha8Rng::seed_from_u64(spec.seed));
    let (target_pose, radii) = match (&spec.target, spec.mount) {
        (CalibrationTarget::Board, Mount::EyeInHand) => {
            (Isometry3::new(Vec3::new(700.0, 100.0, -200.0), Vec3::new(0.0, 0.0, 0.4)), Vec::new())
        }
        (CalibrationTarget::Spheres(r), Mount::EyeInHand) => {
            (Isometry3::new(Vec3::new(700.0, 100.0, -200.0), Vec3::new(0.0, 0.0, 0.4)), r.clone())
        }
        // On the flange: a board or a sphere tree 150 mm out along the tool axis.
        (CalibrationTarget::Board, Mount::EyeToHand) => {
            (Isometry3::new(Vec3::new(10.0, -5.0, 150.0), Vec3::new(0.0, 0.0, 0.2)), Vec::new())
        }
        (CalibrationTarget::Spheres(r), Mount::EyeToHand) => {
            (Isometry3::new(Vec3::new(10.0, -5.0, 150.0), Vec3::new(0.0, 0.0, 0.2)), r.clone())
        }
    };
    let sphere_centres =
        if spec.rig { RIG_BALLS.iter().map(|b| Vec3::from(*b)).collect() } else { sphere_layout(&radii) };
    // One view more than captures: the spare is the wrong pairing's.
    let views: Vec<Isometry3<f64>> = (0..=spec.captures).map(|i| view(&mut draws, spec, i)).collect();
    let true_hand = |camera_t_target: &Isometry3<f64>| match spec.mount {
        Mount::EyeInHand => target_pose * camera_t_target.inverse() * spec.hand_eye.inverse(),
        Mount::EyeToHand => spec.hand_eye * camera_t_target * target_pose.inverse(),
    };
    let captures = (0..spec.captures)
        .map(|i| {
            let seen = if spec.wrong_pairing == Some(i) { views[spec.captures] } else { views[i] };
            let reported = draws.jitter(&true_hand(&views[i]), ROBOT_TRANSLATION_SIGMA_MM, ROBOT_ROTATION_SIGMA_DEG);
            let observation = match &spec.target {
                CalibrationTarget::Board => SimObservation::TargetPose(draws.jitter(
                    &seen,
                    BOARD_TRANSLATION_SIGMA_MM,
                    BOARD_ROTATION_SIGMA_DEG,
                )),
                CalibrationTarget::Spheres(radii) => {
                    let seed = spec.seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
                    SimObservation::Cloud(if spec.rig {
                        render_rig(&seen, &sphere_centres, radii[0], camera, seed)
                    } else {
                        render_spheres(&seen, &sphere_centres, radii, camera, seed)
                    })
                }
            };
            SimCapture { base_t_end: reported, observation }
        })
        .collect();
    CalibrationSet { captures, hand_eye: spec.hand_eye, target_pose, sphere_centres }
}

/// The spheres' posts are this fraction of their radius thick.
const POST_RADIUS_FRACTION: f64 = 0.3;
/// Each sphere's window reaches this multiple of its radius around it,
/// so the table and the post show around the sphere.
const WINDOW_REACH: f64 = 1.4;

/// A surface of the sphere scene, in the camera frame.
enum Surface {
    Sphere {
        centre: Vec3,
        radius: f64,
    },
    /// A vertical post from the table (`base`) up to the sphere's centre.
    Post {
        base: Vec3,
        top: Vec3,
        radius: f64,
    },
    Table {
        point: Vec3,
        normal: Vec3,
    },
}

impl Surface {
    /// The nearest hit along the ray `t · ray` (t is the depth, ray.z = 1)
    /// and the surface normal there.
    fn hit(&self, ray: &Vec3) -> Option<(f64, Vec3)> {
        match self {
            Surface::Sphere { centre, radius } => {
                let (a, b, c) = (ray.norm_squared(), ray.dot(centre), centre.norm_squared() - radius * radius);
                let disc = b * b - a * c;
                (disc >= 0.0)
                    .then(|| (b - disc.sqrt()) / a)
                    .filter(|t| *t > 0.0)
                    .map(|t| (t, (ray * t - centre) / *radius))
            }
            Surface::Table { point, normal } => {
                let denom = normal.dot(ray);
                (denom.abs() > 1e-9).then(|| normal.dot(point) / denom).filter(|t| *t > 0.0).map(|t| (t, *normal))
            }
            Surface::Post { base, top, radius } => {
                let axis = (top - base).normalize();
                // |(t r - base) - ((t r - base)·axis) axis|² = radius²
                let d = ray - axis * ray.dot(&axis);
                let m = -base + axis * base.dot(&axis);
                let (a, b, c) = (d.norm_squared(), d.dot(&m), m.norm_squared() - radius * radius);
                let disc = b * b - a * c;
                if disc < 0.0 || a == 0.0 {
                    return None;
                }
                let t = (-b - disc.sqrt()) / a;
                let p = ray * t;
                let along = (p - base).dot(&axis);
                let within = t > 0.0 && along >= 0.0 && along <= (top - base).norm();
                within.then(|| {
                    let n = (p - base) - axis * along;
                    (t, n / n.norm())
                })
            }
        }
    }
}

/// The spheres' cloud for the camera at `camera_t_target`: each sphere's
/// pixel window rendered (spheres, posts, table), degraded by the
/// simulator's noise, and joined as one unorganized cloud.
fn render_spheres(
    camera_t_target: &Isometry3<f64>,
    centres: &[Vec3],
    radii: &[f64],
    camera: &CameraModel,
    seed: u64,
) -> PointCloud {
    let up = camera_t_target.rotation * Vec3::z();
    let mut surfaces: Vec<Surface> = Vec::new();
    for (c, r) in centres.iter().zip(radii) {
        let centre = (camera_t_target * Point3::from(*c)).coords;
        let base = (camera_t_target * Point3::new(c.x, c.y, 0.0)).coords;
        surfaces.push(Surface::Sphere { centre, radius: *r });
        surfaces.push(Surface::Post { base, top: centre, radius: r * POST_RADIUS_FRACTION });
    }
    surfaces.push(Surface::Table { point: camera_t_target.translation.vector, normal: up });
    let spec = NoiseSpec::default();
    let min_cos = spec.max_incidence_deg.to_radians().cos();
    let projector = Vec3::new(camera.baseline_mm, 0.0, 0.0);
    let mut done: HashSet<(i64, i64)> = HashSet::new();
    let mut points = Vec::new();
    for (k, (c, r)) in centres.iter().zip(radii).enumerate() {
        let centre = (camera_t_target * Point3::from(*c)).coords;
        let Some(window) = pixel_window(camera, &centre, r * WINDOW_REACH) else { continue };
        let [u0, v0, w, h] = window;
        let sub = camera.with_pinhole(
            w as u32,
            h as u32,
            Intrinsics { fx: camera.fx(), fy: camera.fy(), cx: camera.cx() - u0 as f64, cy: camera.cy() - v0 as f64 },
        );
        let mut exact = vec![f64::NAN; (w * h) as usize];
        for row in 0..h {
            for col in 0..w {
                if done.contains(&(u0 + col, v0 + row)) {
                    continue;
                }
                let ray = Vec3::from(sub.ray(col as f64, row as f64));
                let nearest = surfaces.iter().filter_map(|s| s.hit(&ray)).min_by(|a, b| a.0.total_cmp(&b.0));
                if let Some((depth, normal)) = nearest {
                    let p = ray * depth;
                    let to_camera = (-p).normalize();
                    let to_projector = (projector - p).normalize();
                    let facing = normal.dot(&to_camera).abs() >= min_cos && normal.dot(&to_projector).abs() >= min_cos;
                    if facing {
                        exact[(row * w + col) as usize] = depth;
                    }
                }
            }
        }
        let depths = noise::degrade(&exact, &sub, &spec, seed.wrapping_add(k as u64 * 7919));
        for row in 0..h {
            for col in 0..w {
                let z = depths[(row * w + col) as usize];
                if z.is_finite() && done.insert((u0 + col, v0 + row)) {
                    let ray = sub.ray(col as f64, row as f64);
                    points.push([(ray[0] * z) as f32, (ray[1] * z) as f32, z as f32]);
                }
            }
        }
    }
    if points.is_empty() {
        points.push(INVALID_POINT);
    }
    PointCloud::unorganized(points)
}

/// A tooling ball's radius, mm: the 1.5-inch ball fixture makers sell.
pub const TOOLING_BALL_RADIUS_MM: f64 = 19.05;
/// The rig's posts' radius, mm: half-inch posts, thinner than the balls.
pub const RIG_POST_RADIUS_MM: f64 = 6.35;
/// The rig's ball centres in the target frame (the table at `z = 0`), mm:
/// posts 85 to 135 mm tall, the three distances 157.7, 127.8 and 143.4 mm
/// (all different, so balls of one radius are named by them).
pub const RIG_BALLS: [[f64; 3]; 3] = [[-75.0, -40.0, 110.0], [80.0, -25.0, 85.0], [-15.0, 70.0, 135.0]];
/// The rig is rendered this far around its balls and posts, mm: table
/// all around.
pub const RIG_MARGIN_MM: f64 = 60.0;
/// The rig's camera is binned this many pixels a side (a capture of
/// about 10⁵ points rather than a whole frame's).
pub const RIG_BINNING: f64 = 3.0;
/// Stray returns (interreflections, dust) scattered uniformly over the
/// window's pixels, 150 mm before to 50 mm behind the table, as a
/// fraction of the points.
pub const RIG_STRAY_FRACTION: f64 = 0.01;
/// Small clusters of flare: each [`RIG_FLARE_POINTS`] points within 4 mm.
pub const RIG_FLARE_CLUSTERS: usize = 6;
/// See [`RIG_FLARE_CLUSTERS`].
pub const RIG_FLARE_POINTS: usize = 150;

/// The tooling-ball rig's cloud for the camera at `camera_t_target`: one
/// window around every ball and post (the table all around), the balls,
/// posts and table rendered and degraded by the simulator's noise, then
/// stray returns and flare added.
fn render_rig(
    camera_t_target: &Isometry3<f64>,
    centres: &[Vec3],
    radius: f64,
    camera: &CameraModel,
    seed: u64,
) -> PointCloud {
    let up = camera_t_target.rotation * Vec3::z();
    let mut surfaces: Vec<Surface> = Vec::new();
    let mut corners = Vec::new();
    for c in centres {
        let centre = (camera_t_target * Point3::from(*c)).coords;
        let base = (camera_t_target * Point3::new(c.x, c.y, 0.0)).coords;
        surfaces.push(Surface::Sphere { centre, radius });
        surfaces.push(Surface::Post { base, top: centre, radius: RIG_POST_RADIUS_MM });
        corners.push(centre);
        corners.push(base);
    }
    surfaces.push(Surface::Table { point: camera_t_target.translation.vector, normal: up });
    let binned = camera.with_pinhole(
        (camera.width_px as f64 / RIG_BINNING) as u32,
        (camera.height_px as f64 / RIG_BINNING) as u32,
        Intrinsics {
            fx: camera.fx() / RIG_BINNING,
            fy: camera.fy() / RIG_BINNING,
            cx: camera.cx() / RIG_BINNING,
            cy: camera.cy() / RIG_BINNING,
        },
    );
    let windows: Vec<[i64; 4]> =
        corners.iter().filter_map(|p| pixel_window(&binned, p, radius + RIG_MARGIN_MM)).collect();
    if windows.is_empty() {
        return PointCloud::unorganized(vec![INVALID_POINT]);
    }
    let u0 = windows.iter().map(|w| w[0]).min().unwrap_or(0);
    let v0 = windows.iter().map(|w| w[1]).min().unwrap_or(0);
    let u1 = windows.iter().map(|w| w[0] + w[2]).max().unwrap_or(0);
    let v1 = windows.iter().map(|w| w[1] + w[3]).max().unwrap_or(0);
    let (w, h) = (u1 - u0, v1 - v0);
    let sub = binned.with_pinhole(
        w as u32,
        h as u32,
        Intrinsics { fx: binned.fx(), fy: binned.fy(), cx: binned.cx() - u0 as f64, cy: binned.cy() - v0 as f64 },
    );
    let spec = NoiseSpec::default();
    let min_cos = spec.max_incidence_deg.to_radians().cos();
    let projector = Vec3::new(camera.baseline_mm, 0.0, 0.0);
    let mut exact = vec![f64::NAN; (w * h) as usize];
    for row in 0..h {
        for col in 0..w {
            let ray = Vec3::from(sub.ray(col as f64, row as f64));
            let nearest = surfaces.iter().filter_map(|s| s.hit(&ray)).min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((depth, normal)) = nearest {
                let p = ray * depth;
                let facing = normal.dot(&(-p).normalize()).abs() >= min_cos
                    && normal.dot(&(projector - p).normalize()).abs() >= min_cos;
                if facing {
                    exact[(row * w + col) as usize] = depth;
                }
            }
        }
    }
    let depths = noise::degrade(&exact, &sub, &spec, seed);
    let mut points = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let z = depths[(row * w + col) as usize];
            if z.is_finite() {
                let ray = sub.ray(col as f64, row as f64);
                points.push([(ray[0] * z) as f32, (ray[1] * z) as f32, z as f32]);
            }
        }
    }
    let mut draws = Draws(ChaCha8Rng::seed_from_u64(seed ^ 0x005e_ed0f_57a7));
    let table_depth = camera_t_target.translation.vector.z;
    let stray = (points.len() as f64 * RIG_STRAY_FRACTION) as usize;
    for _ in 0..stray {
        let ray = sub.ray(draws.between(0.0, w as f64), draws.between(0.0, h as f64));
        let z = draws.between(table_depth - 150.0, table_depth + 50.0);
        points.push([(ray[0] * z) as f32, (ray[1] * z) as f32, z as f32]);
    }
    for _ in 0..RIG_FLARE_CLUSTERS {
        let ray = sub.ray(draws.between(0.0, w as f64), draws.between(0.0, h as f64));
        let centre = Vec3::from(ray) * draws.between(table_depth - 150.0, table_depth);
        for _ in 0..RIG_FLARE_POINTS {
            let p = centre + draws.vector(4.0 / 3f64.sqrt());
            points.push([p.x as f32, p.y as f32, p.z as f32]);
        }
    }
    PointCloud::unorganized(points)
}

/// The sensor pixels `[u0, v0, width, height]` within `reach` of a
/// camera-frame point, clipped to the sensor; `None` when none are.
fn pixel_window(camera: &CameraModel, centre: &Vec3, reach: f64) -> Option<[i64; 4]> {
    let near = centre.z - reach;
    if near <= camera.min_depth_mm {
        return None;
    }
    let (u, v) = camera.project(centre)?;
    let half_u = (reach * camera.fx() / near).ceil();
    let half_v = (reach * camera.fy() / near).ceil();
    let u0 = ((u - half_u).floor() as i64).max(0);
    let v0 = ((v - half_v).floor() as i64).max(0);
    let u1 = ((u + half_u).ceil() as i64).min(camera.width_px as i64 - 1);
    let v1 = ((v + half_v).ceil() as i64).min(camera.height_px as i64 - 1);
    (u1 > u0 && v1 > v0).then_some([u0, v0, u1 - u0 + 1, v1 - v0 + 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_board_set_is_consistent_with_its_truth() {
        let spec = CalibrationSpec::new(CalibrationTarget::Board, Mount::EyeInHand, 3);
        let set = simulate_calibration(&spec, &CameraModel::default());
        assert_eq!(set.captures.len(), 15);
        for c in &set.captures {
            let SimObservation::TargetPose(b) = &c.observation else { panic!("board") };
            let target = c.base_t_end * set.hand_eye * b;
            // Robot and board noise only: well under a millimetre.
            assert!((target.translation.vector - set.target_pose.translation.vector).norm() < 1.0);
            assert!((b.translation.vector.norm() - 500.0).abs() < 60.0);
        }
    }

    #[test]
    fn a_sphere_cloud_shows_every_sphere_around_its_true_centre() {
        let spec =
            CalibrationSpec::new(CalibrationTarget::Spheres(DEFAULT_SPHERE_RADII_MM.to_vec()), Mount::EyeInHand, 5);
        let set = simulate_calibration(&CalibrationSpec { captures: 3, ..spec }, &CameraModel::default());
        let SimObservation::Cloud(cloud) = &set.captures[0].observation else { panic!("cloud") };
        assert!(cloud.len() > 20_000, "{}", cloud.len());
        let camera_t_target = (set.captures[0].base_t_end * set.hand_eye).inverse() * set.target_pose;
        for (c, r) in set.sphere_centres.iter().zip(DEFAULT_SPHERE_RADII_MM) {
            let centre = (camera_t_target * Point3::from(*c)).coords;
            let on_sphere =
                cloud.points().iter().filter(|p| (crate::geometry::vec3(p) - centre).norm() - r < 1.5).count();
            assert!(on_sphere > 1000, "{on_sphere} points on the sphere of radius {r}");
        }
    }
}
