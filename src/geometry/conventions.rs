//! How robot controllers write a pose: the rotation conventions (Euler
//! orders intrinsic and extrinsic, KUKA's A B C, FANUC's W P R, UR's
//! rotation vector, quaternions with w first or last) and the units (mm
//! or m, degrees or radians). A [`PoseConvention`] turns a controller's
//! numbers into `Base_T_End` (millimetres) and back, so the daemon can
//! read a pose and write a waypoint in the robot's own language.
//!
//! The config's `robot.euler_convention` ([`EulerConvention`]) is one of
//! these, in mm and degrees: `zyx` is extrinsic x-y-z (FANUC's W P R),
//! `xyz` intrinsic x-y-z, `rotation_vector` the rotation vector.

use std::fmt;
use std::str::FromStr;

use nalgebra::{Isometry3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};

use super::pose::{EulerConvention, RobotPose};

/// A coordinate axis of an Euler sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    fn unit(self) -> Unit<Vector3<f64>> {
        match self {
            Axis::X => Vector3::x_axis(),
            Axis::Y => Vector3::y_axis(),
            Axis::Z => Vector3::z_axis(),
        }
    }

    fn letter(self) -> char {
        match self {
            Axis::X => 'x',
            Axis::Y => 'y',
            Axis::Z => 'z',
        }
    }

    fn from_letter(c: char) -> Option<Axis> {
        match c {
            'x' => Some(Axis::X),
            'y' => Some(Axis::Y),
            'z' => Some(Axis::Z),
            _ => None,
        }
    }
}

/// Whether each Euler rotation is about the moved axes or the fixed ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EulerFrame {
    /// Each rotation about the axes as the previous ones left them:
    /// angles `(a, b, c)` about `(i, j, k)` give `R = Ri(a) · Rj(b) · Rk(c)`.
    Intrinsic,
    /// Each rotation about the fixed base axes: angles `(a, b, c)` about
    /// `(i, j, k)` give `R = Rk(c) · Rj(b) · Ri(a)`.
    Extrinsic,
}

/// How the rotation part of a pose is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RotationForm {
    /// Three angles about `axes` in the order written, three different
    /// axes (the Tait-Bryan orders robots use: `xyz`, `zyx`, ...; proper
    /// Euler orders such as `zyz` are not read).
    Euler { axes: [Axis; 3], frame: EulerFrame },
    /// Axis times angle (UR's `rx, ry, rz`).
    RotationVector,
    /// A unit quaternion `w, x, y, z` (ABB's `q1..q4`).
    QuaternionWFirst,
    /// A unit quaternion `x, y, z, w` (ROS, Eigen's storage).
    QuaternionWLast,
}

/// The unit of a pose's position.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LengthUnit {
    Millimetres,
    Metres,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn mm(self) -> f64 {
        match self {
            LengthUnit::Millimetres => 1.0,
            LengthUnit::Metres => 1000.0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Millimetres => "mm",
            LengthUnit::Metres => "m",
        }
    }

    /// The unit [`LengthUnit::name`] calls `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [LengthUnit::Millimetres, LengthUnit::Metres].into_iter().find(|u| u.name() == name)
    }
}

/// The unit of a pose's angles (quaternions have none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AngleUnit {
    Degrees,
    Radians,
}

impl AngleUnit {
    fn radians_of(self, v: f64) -> f64 {
        match self {
            AngleUnit::Degrees => v.to_radians(),
            AngleUnit::Radians => v,
        }
    }

    fn of_radians(self, v: f64) -> f64 {
        match self {
            AngleUnit::Degrees => v.to_degrees(),
            AngleUnit::Radians => v,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            AngleUnit::Degrees => "deg",
            AngleUnit::Radians => "rad",
        }
    }

    /// The unit [`AngleUnit::name`] calls `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [AngleUnit::Degrees, AngleUnit::Radians].into_iter().find(|u| u.name() == name)
    }
}

/// A pose's numbers as a controller writes them: the position `x, y, z`,
/// then the rotation's three or four numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PoseConvention {
    pub rotation: RotationForm,
    pub length: LengthUnit,
    pub angle: AngleUnit,
}

/// Why a pose's numbers do not make a pose.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PoseError {
    #[error("a {convention} pose has {expected} numbers, got {got}")]
    Count { convention: String, expected: usize, got: usize },
    #[error("pose number {index} is not finite ({value})")]
    NotFinite { index: usize, value: f64 },
    /// A quaternion far from unit length is a wrong field or a typo, not a
    /// rotation to normalise silently.
    #[error("the quaternion's length is {norm:.4}, not 1 (within {QUATERNION_NORM_TOLERANCE})")]
    QuaternionNorm { norm: f64 },
}

/// How far a quaternion's length may be from 1: a quaternion printed to
/// four decimals is within about 2e-4 of unit length.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// The most numbers a pose takes (position and a quaternion).
pub const MAX_POSE_NUMBERS: usize = 7;

/// Why a convention name was not understood.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown pose convention {0:?}; expected extrinsic_ or intrinsic_ and the three axes in some order (e.g. \
     intrinsic_zyx), \
     kuka_abc, fanuc_wpr, rotation_vector, quaternion_wxyz, quaternion_xyzw, zyx or xyz"
)]
pub struct UnknownConvention(pub String);

impl RotationForm {
    /// KUKA's A, B, C: `R = Rz(A) · Ry(B) · Rx(C)`, written A, B, C.
    pub const KUKA_ABC: RotationForm =
        RotationForm::Euler { axes: [Axis::Z, Axis::Y, Axis::X], frame: EulerFrame::Intrinsic };
    /// FANUC's W, P, R: `R = Rz(R) · Ry(P) · Rx(W)`, written W, P, R.
    pub const FANUC_WPR: RotationForm =
        RotationForm::Euler { axes: [Axis::X, Axis::Y, Axis::Z], frame: EulerFrame::Extrinsic };

    /// How many numbers the rotation takes.
    pub fn numbers_len(self) -> usize {
        match self {
            RotationForm::QuaternionWFirst | RotationForm::QuaternionWLast => 4,
            _ => 3,
        }
    }

    /// The rotation the numbers `r` stand for (angles in radians).
    fn rotation(self, r: &[f64]) -> Result<Rotation3<f64>, PoseError> {
        Ok(match self {
            RotationForm::Euler { axes, frame } => euler_rotation(axes, frame, r),
            RotationForm::RotationVector => Rotation3::new(Vector3::new(r[0], r[1], r[2])),
            RotationForm::QuaternionWFirst | RotationForm::QuaternionWLast => {
                let (w, v) = match self {
                    RotationForm::QuaternionWFirst => (r[0], Vector3::new(r[1], r[2], r[3])),
                    _ => (r[3], Vector3::new(r[0], r[1], r[2])),
                };
                let q = nalgebra::Quaternion::from_parts(w, v);
                let norm = q.norm();
                if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
                    return Err(PoseError::QuaternionNorm { norm });
                }
                UnitQuaternion::from_quaternion(q).to_rotation_matrix()
            }
        })
    }

    /// The numbers that give `rotation` (angles in radians): Euler angles
    /// each within ±π, the middle one within ±π/2; a rotation vector of
    /// angle at most π; a quaternion with w ≥ 0.
    fn numbers(self, rotation: &Rotation3<f64>) -> [f64; 4] {
        match self {
            RotationForm::Euler { axes, frame } => {
                let [a, b, c] = euler_angles(rotation, axes, frame);
                [a, b, c, 0.0]
            }
            RotationForm::RotationVector => {
                let v = rotation.scaled_axis();
                [v.x, v.y, v.z, 0.0]
            }
            RotationForm::QuaternionWFirst | RotationForm::QuaternionWLast => {
                let q = UnitQuaternion::from_rotation_matrix(rotation);
                // q and -q are the same rotation; w ≥ 0 is the one written.
                let q = if q.w < 0.0 { -q.into_inner() } else { q.into_inner() };
                match self {
                    RotationForm::QuaternionWFirst => [q.w, q.i, q.j, q.k],
                    _ => [q.i, q.j, q.k, q.w],
                }
            }
        }
    }

    /// The name [`FromStr`] reads.
    pub fn name(self) -> String {
        match self {
            RotationForm::Euler { axes, frame } => {
                let prefix = match frame {
                    EulerFrame::Intrinsic => "intrinsic_",
                    EulerFrame::Extrinsic => "extrinsic_",
                };
                format!("{prefix}{}", axes.iter().map(|a| a.letter()).collect::<String>())
            }
            RotationForm::RotationVector => "rotation_vector".into(),
            RotationForm::QuaternionWFirst => "quaternion_wxyz".into(),
            RotationForm::QuaternionWLast => "quaternion_xyzw".into(),
        }
    }
}

/// The rotation of Euler angles `r` (radians) about `axes`.
fn euler_rotation(axes: [Axis; 3], frame: EulerFrame, r: &[f64]) -> Rotation3<f64> {
    let [a, b, c] = [0, 1, 2].map(|k| Rotation3::from_axis_angle(&axes[k].unit(), r[k]));
    match frame {
        EulerFrame::Intrinsic => a * b * c,
        EulerFrame::Extrinsic => c * b * a,
    }
}

/// How far the rotation of the angles found may lie from the one they were
/// read from, as the norm of the matrices' difference (about the angle in
/// radians; an angle near 0 is not resolved below 1e-8 by its arc cosine).
const EULER_REBUILD_TOLERANCE: f64 = 1e-9;

/// The Euler angles (radians) of `rotation` about `axes`, by nalgebra's
/// general extraction (Shuster and Markley). At gimbal lock (the middle
/// angle at ±90°) only the sum or difference of the outer two is defined,
/// and nalgebra's answer there can be NaN or wrong (its extrinsic case
/// turns the wrong way), so every answer is checked by rebuilding the
/// rotation; one that fails is replaced by the locked solution: the first
/// angle 0, the middle ±90° and the last what remains.
fn euler_angles(rotation: &Rotation3<f64>, axes: [Axis; 3], frame: EulerFrame) -> [f64; 3] {
    let error = |angles: &[f64; 3]| match angles.iter().all(|a| a.is_finite()) {
        true => (euler_rotation(axes, frame, angles).matrix() - rotation.matrix()).norm(),
        false => f64::INFINITY,
    };
    let (angles, _) = rotation.euler_angles_ordered(axes.map(Axis::unit), frame == EulerFrame::Extrinsic);
    if error(&angles) <= EULER_REBUILD_TOLERANCE {
        return angles;
    }
    let locked = [std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2].map(|middle| {
        let turn = Rotation3::from_axis_angle(&axes[1].unit(), middle).inverse();
        let rest = match frame {
            EulerFrame::Intrinsic => turn * rotation,
            EulerFrame::Extrinsic => rotation * turn,
        };
        [0.0, middle, rest.scaled_axis().dot(&axes[2].unit())]
    });
    std::iter::once(angles).chain(locked).min_by(|a, b| error(a).total_cmp(&error(b))).unwrap_or(angles)
}

impl FromStr for RotationForm {
    type Err = UnknownConvention;

    /// `extrinsic_xyz`, `intrinsic_zyx` (any order of the three axes), `kuka_abc`, `fanuc_wpr`, `rotation_vector`,
    /// `quaternion_wxyz`, `quaternion_xyzw`, and the config's `zyx`
    /// (extrinsic x-y-z) and `xyz` (intrinsic x-y-z); any case, `-` for `_`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key = s.trim().to_ascii_lowercase().replace('-', "_");
        let unknown = || UnknownConvention(s.to_string());
        let euler = |frame, letters: &str| -> Option<RotationForm> {
            let axes: Vec<Axis> = letters.chars().map(Axis::from_letter).collect::<Option<_>>()?;
            let axes: [Axis; 3] = axes.try_into().ok()?;
            // Three different axes: nalgebra's extraction of the angles
            // takes only Tait-Bryan orders.
            (axes[0] != axes[1] && axes[1] != axes[2] && axes[0] != axes[2])
                .then_some(RotationForm::Euler { axes, frame })
        };
        match key.as_str() {
            "kuka_abc" | "abc" => Ok(RotationForm::KUKA_ABC),
            "fanuc_wpr" | "wpr" => Ok(RotationForm::FANUC_WPR),
            "rotation_vector" | "rotvec" => Ok(RotationForm::RotationVector),
            "quaternion_wxyz" => Ok(RotationForm::QuaternionWFirst),
            "quaternion_xyzw" => Ok(RotationForm::QuaternionWLast),
            other => {
                let parsed = if let Some(letters) = other.strip_prefix("extrinsic_") {
                    euler(EulerFrame::Extrinsic, letters)
                } else if let Some(letters) = other.strip_prefix("intrinsic_") {
                    euler(EulerFrame::Intrinsic, letters)
                } else {
                    EulerConvention::from_name(other).map(|e| PoseConvention::config(e).rotation)
                };
                parsed.ok_or_else(unknown)
            }
        }
    }
}

impl PoseConvention {
    /// Universal Robots: metres, rotation vector in radians.
    pub const UR: PoseConvention = PoseConvention {
        rotation: RotationForm::RotationVector,
        length: LengthUnit::Metres,
        angle: AngleUnit::Radians,
    };
    /// ABB RAPID: millimetres, quaternion q1..q4 = w, x, y, z.
    pub const ABB: PoseConvention = PoseConvention {
        rotation: RotationForm::QuaternionWFirst,
        length: LengthUnit::Millimetres,
        angle: AngleUnit::Degrees,
    };
    /// KUKA KRL: millimetres, A, B, C in degrees.
    pub const KUKA: PoseConvention =
        PoseConvention { rotation: RotationForm::KUKA_ABC, length: LengthUnit::Millimetres, angle: AngleUnit::Degrees };
    /// FANUC: millimetres, W, P, R in degrees.
    pub const FANUC: PoseConvention = PoseConvention {
        rotation: RotationForm::FANUC_WPR,
        length: LengthUnit::Millimetres,
        angle: AngleUnit::Degrees,
    };

    /// The convention `robot.euler_convention` names, in mm and degrees.
    pub fn config(euler: EulerConvention) -> PoseConvention {
        let rotation = match euler {
            EulerConvention::Zyx => {
                RotationForm::Euler { axes: [Axis::X, Axis::Y, Axis::Z], frame: EulerFrame::Extrinsic }
            }
            EulerConvention::Xyz => {
                RotationForm::Euler { axes: [Axis::X, Axis::Y, Axis::Z], frame: EulerFrame::Intrinsic }
            }
            EulerConvention::RotationVector => RotationForm::RotationVector,
        };
        PoseConvention { rotation, length: LengthUnit::Millimetres, angle: AngleUnit::Degrees }
    }

    /// How many numbers a pose takes: 6, or 7 with a quaternion.
    pub fn numbers_len(&self) -> usize {
        3 + self.rotation.numbers_len()
    }

    /// A name for messages: the rotation, the length and the angle unit.
    pub fn describe(&self) -> String {
        match self.rotation {
            RotationForm::QuaternionWFirst | RotationForm::QuaternionWLast => {
                format!("{} ({})", self.rotation.name(), self.length.name())
            }
            _ => format!("{} ({}, {})", self.rotation.name(), self.length.name(), self.angle.name()),
        }
    }

    /// `Base_T_End` in millimetres for a pose's numbers.
    pub fn to_isometry(&self, values: &[f64]) -> Result<Isometry3<f64>, PoseError> {
        if values.len() != self.numbers_len() {
            return Err(PoseError::Count {
                convention: self.describe(),
                expected: self.numbers_len(),
                got: values.len(),
            });
        }
        if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(PoseError::NotFinite { index, value });
        }
        let scale = self.length.mm();
        let mut rotation = [0.0; MAX_POSE_NUMBERS - 3];
        for (r, v) in rotation.iter_mut().zip(&values[3..]) {
            *r = match self.rotation {
                RotationForm::QuaternionWFirst | RotationForm::QuaternionWLast => *v,
                _ => self.angle.radians_of(*v),
            };
        }
        let rotation = self.rotation.rotation(&rotation[..self.rotation.numbers_len()])?;
        Ok(Isometry3::from_parts(
            Translation3::new(values[0] * scale, values[1] * scale, values[2] * scale),
            UnitQuaternion::from_rotation_matrix(&rotation),
        ))
    }

    /// The pose's numbers for `Base_T_End` (or a waypoint) in millimetres:
    /// the first [`PoseConvention::numbers_len`] entries of the array.
    pub fn numbers(&self, pose: &Isometry3<f64>) -> [f64; MAX_POSE_NUMBERS] {
        let t = pose.translation.vector / self.length.mm();
        let r = self.rotation.numbers(&pose.rotation.to_rotation_matrix());
        let angle = |v: f64| match self.rotation {
            RotationForm::QuaternionWFirst | RotationForm::QuaternionWLast => v,
            _ => self.angle.of_radians(v),
        };
        [t.x, t.y, t.z, angle(r[0]), angle(r[1]), angle(r[2]), angle(r[3])]
    }

    /// The pose's numbers as the daemon's configured convention reads
    /// them (mm, degrees, `euler`), for a pose written in this one.
    pub fn to_robot_pose(&self, values: &[f64], euler: EulerConvention) -> Result<RobotPose, PoseError> {
        Ok(RobotPose::from_isometry(&self.to_isometry(values)?, euler))
    }
}

impl fmt::Display for PoseConvention {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe())
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    const ALL_AXES: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// Every Euler order (the 6 orders of three axes, each intrinsic and
    /// extrinsic), the rotation vector and both quaternion orders.
    fn every_rotation_form() -> Vec<RotationForm> {
        let mut forms =
            vec![RotationForm::RotationVector, RotationForm::QuaternionWFirst, RotationForm::QuaternionWLast];
        for a in ALL_AXES {
            for b in ALL_AXES {
                for c in ALL_AXES {
                    if a != b && b != c && a != c {
                        for frame in [EulerFrame::Intrinsic, EulerFrame::Extrinsic] {
                            forms.push(RotationForm::Euler { axes: [a, b, c], frame });
                        }
                    }
                }
            }
        }
        forms
    }

    fn every_convention() -> Vec<PoseConvention> {
        let mut all = Vec::new();
        for rotation in every_rotation_form() {
            for length in [LengthUnit::Millimetres, LengthUnit::Metres] {
                for angle in [AngleUnit::Degrees, AngleUnit::Radians] {
                    all.push(PoseConvention { rotation, length, angle });
                }
            }
        }
        all
    }

    fn same_pose(a: &Isometry3<f64>, b: &Isometry3<f64>) -> bool {
        let turn = a.rotation.to_rotation_matrix().matrix() - b.rotation.to_rotation_matrix().matrix();
        (a.translation.vector - b.translation.vector).norm() < 1e-9 && turn.norm() < 1e-9
    }

    fn rz(deg: f64) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::z_axis(), deg.to_radians())
    }
    fn ry(deg: f64) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::y_axis(), deg.to_radians())
    }
    fn rx(deg: f64) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::x_axis(), deg.to_radians())
    }

    #[test]
    fn the_vendor_conventions_are_their_manuals_products() {
        // KUKA: R = Rz(A) Ry(B) Rx(C), written A, B, C.
        let kuka = PoseConvention::KUKA.to_isometry(&[1.0, 2.0, 3.0, 30.0, -20.0, 10.0]).unwrap();
        let expected = rz(30.0) * ry(-20.0) * rx(10.0);
        assert!((kuka.rotation.to_rotation_matrix().matrix() - expected.matrix()).norm() < 1e-12);
        // FANUC: R = Rz(R) Ry(P) Rx(W), written W, P, R.
        let fanuc = PoseConvention::FANUC.to_isometry(&[1.0, 2.0, 3.0, 10.0, -20.0, 30.0]).unwrap();
        assert!(same_pose(&fanuc, &kuka));
        // FANUC's W P R is the config's default zyx.
        let zyx = RobotPose { xyz_mm: [1.0, 2.0, 3.0], angles_deg: [10.0, -20.0, 30.0] };
        assert!(same_pose(&fanuc, &zyx.to_isometry(EulerConvention::Zyx)));
        // UR: metres and radians, axis times angle.
        let ur = PoseConvention::UR.to_isometry(&[0.001, 0.002, 0.003, 0.0, 0.0, std::f64::consts::FRAC_PI_2]).unwrap();
        assert!((ur.translation.vector - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-12);
        assert!((ur.rotation.to_rotation_matrix().matrix() - rz(90.0).matrix()).norm() < 1e-12);
        // ABB: q1..q4 = w, x, y, z; a half turn about x.
        let abb = PoseConvention::ABB.to_isometry(&[1.0, 2.0, 3.0, 0.0, 1.0, 0.0, 0.0]).unwrap();
        assert!((abb.rotation.to_rotation_matrix().matrix() - rx(180.0).matrix()).norm() < 1e-12);
        assert_eq!(PoseConvention::ABB.numbers(&abb)[3..7], [0.0, 1.0, 0.0, 0.0]);
    }

    #[test]
    fn intrinsic_and_extrinsic_orders_are_each_others_reverse() {
        let intrinsic: RotationForm = "intrinsic_zyx".parse().unwrap();
        let extrinsic: RotationForm = "extrinsic_xyz".parse().unwrap();
        let angles = [0.3, -0.2, 0.1];
        let a = intrinsic.rotation(&angles).unwrap();
        let b = extrinsic.rotation(&[angles[2], angles[1], angles[0]]).unwrap();
        assert!((a.matrix() - b.matrix()).norm() < 1e-12);
    }

    #[test]
    fn names_parse_and_print_back() {
        for form in every_rotation_form() {
            assert_eq!(form.name().parse::<RotationForm>(), Ok(form));
        }
        assert_eq!("KUKA-ABC".parse::<RotationForm>(), Ok(RotationForm::KUKA_ABC));
        assert_eq!("zyx".parse::<RotationForm>(), Ok(RotationForm::FANUC_WPR));
        for bad in ["intrinsic_xxy", "extrinsic_xy", "intrinsic_zxz", "zxz", "euler", ""] {
            assert!(bad.parse::<RotationForm>().is_err(), "{bad}");
        }
    }

    #[test]
    fn the_config_conventions_read_as_before() {
        let angles = [178.28, 1.04, 107.12];
        for euler in [EulerConvention::Zyx, EulerConvention::Xyz, EulerConvention::RotationVector] {
            let pose = RobotPose { xyz_mm: [-613.5, -284.81, 296.28], angles_deg: angles };
            let mut values = pose.xyz_mm.to_vec();
            values.extend(angles);
            let here = PoseConvention::config(euler).to_isometry(&values).unwrap();
            assert!(same_pose(&here, &pose.to_isometry(euler)), "{euler:?}");
        }
    }

    #[test]
    fn bad_numbers_are_refused_by_name() {
        let c = PoseConvention::KUKA;
        assert!(matches!(c.to_isometry(&[0.0; 5]), Err(PoseError::Count { expected: 6, got: 5, .. })));
        assert!(matches!(
            c.to_isometry(&[0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0]),
            Err(PoseError::NotFinite { index: 2, .. })
        ));
        let q = PoseConvention::ABB;
        assert!(matches!(q.to_isometry(&[0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0]), Err(PoseError::QuaternionNorm { .. })));
    }

    #[test]
    fn gimbal_lock_gives_finite_angles_that_rebuild_the_rotation() {
        for form in every_rotation_form() {
            let RotationForm::Euler { axes, .. } = form else { continue };
            // The middle angle at its lock.
            for lock in [90.0f64, -90.0] {
                let r = Rotation3::from_axis_angle(&axes[1].unit(), lock.to_radians())
                    * Rotation3::from_axis_angle(&axes[0].unit(), 0.4);
                let angles = form.numbers(&r);
                assert!(angles.iter().all(|a| a.is_finite()), "{form:?} {lock}");
                let back = form.rotation(&angles[..3]).unwrap();
                let off = (back.matrix() - r.matrix()).norm();
                assert!(off < 1e-9, "{form:?} {lock}: {off}");
            }
        }
    }

    fn any_pose() -> impl Strategy<Value = Isometry3<f64>> {
        let coordinate = -3000.0..3000.0f64;
        let angle = -std::f64::consts::PI..std::f64::consts::PI;
        (coordinate.clone(), coordinate.clone(), coordinate, angle.clone(), angle.clone(), angle).prop_map(
            |(x, y, z, a, b, c)| {
                Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_euler_angles(a, b, c))
            },
        )
    }

    proptest! {
        /// Any pose written in any convention reads back as itself.
        #[test]
        fn every_convention_round_trips(pose in any_pose()) {
            for convention in every_convention() {
                let numbers = convention.numbers(&pose);
                let back = convention.to_isometry(&numbers[..convention.numbers_len()]).unwrap();
                prop_assert!(same_pose(&back, &pose), "{convention}: {pose:?} -> {numbers:?} -> {back:?}");
            }
        }

        /// Numbers written by one convention and read as the config's give
        /// the same flange pose.
        #[test]
        fn a_pose_moves_between_conventions(pose in any_pose()) {
            for convention in [PoseConvention::UR, PoseConvention::ABB, PoseConvention::KUKA, PoseConvention::FANUC] {
                let numbers = convention.numbers(&pose);
                for euler in [EulerConvention::Zyx, EulerConvention::Xyz, EulerConvention::RotationVector] {
                    let robot = convention.to_robot_pose(&numbers[..convention.numbers_len()], euler).unwrap();
                    prop_assert!(same_pose(&robot.to_isometry(euler), &pose), "{convention} as {euler:?}");
                }
            }
        }
    }
}
