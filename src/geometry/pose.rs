//! Robot poses, Euler conventions and the hand-eye matrix: everything Eq. 42
//! needs to carry a camera-frame point into the robot base frame,
//! `Base_p = Base_T_End · End_T_Camera · Camera_p`.

use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};

/// How a controller's three angles `(rx, ry, rz)` in degrees become a
/// rotation. Controllers disagree, so the cell configures it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EulerConvention {
    /// `R = Rz(rz) · Ry(ry) · Rx(rx)`: roll-pitch-yaw about fixed axes, as
    /// the paper's poses and most controllers report them.
    #[default]
    Zyx,
    /// `R = Rx(rx) · Ry(ry) · Rz(rz)`.
    Xyz,
    /// `(rx, ry, rz)` is a rotation vector in degrees: axis times angle.
    RotationVector,
}

impl EulerConvention {
    /// The names accepted in config files and on the command line.
    pub const NAMES: &'static [&'static str] = &["zyx", "xyz", "rotation_vector"];

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "zyx" => Some(EulerConvention::Zyx),
            "xyz" => Some(EulerConvention::Xyz),
            "rotation_vector" => Some(EulerConvention::RotationVector),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            EulerConvention::Zyx => "zyx",
            EulerConvention::Xyz => "xyz",
            EulerConvention::RotationVector => "rotation_vector",
        }
    }

    /// The rotation for angles in degrees.
    pub fn rotation(self, angles_deg: [f64; 3]) -> Rotation3<f64> {
        let [a, b, c] = angles_deg.map(f64::to_radians);
        let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), a);
        let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), b);
        let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), c);
        match self {
            EulerConvention::Zyx => rz * ry * rx,
            EulerConvention::Xyz => rx * ry * rz,
            EulerConvention::RotationVector => Rotation3::new(Vector3::new(a, b, c)),
        }
    }

    /// The angles in degrees that give `rotation` (the inverse of
    /// [`EulerConvention::rotation`]), for reporting torch orientations.
    pub fn angles(self, rotation: &Rotation3<f64>) -> [f64; 3] {
        let m = rotation.matrix();
        let rad = match self {
            EulerConvention::Zyx => {
                let (roll, pitch, yaw) = rotation.euler_angles();
                [roll, pitch, yaw]
            }
            EulerConvention::Xyz => {
                // R = Rx(a) Ry(b) Rz(c): m02 = sin b, m12 = -sin a cos b,
                // m22 = cos a cos b, m01 = -cos b sin c, m00 = cos b cos c.
                let b = m[(0, 2)].clamp(-1.0, 1.0).asin();
                if m[(0, 2)].abs() < 1.0 - 1e-12 {
                    [(-m[(1, 2)]).atan2(m[(2, 2)]), b, (-m[(0, 1)]).atan2(m[(0, 0)])]
                } else {
                    // Gimbal lock: only a ± c is defined; put it all in a.
                    [m[(2, 1)].atan2(m[(1, 1)]), b, 0.0]
                }
            }
            EulerConvention::RotationVector => {
                let v = rotation.scaled_axis();
                [v.x, v.y, v.z]
            }
        };
        rad.map(f64::to_degrees)
    }
}

/// A robot flange pose as controllers report it: position in mm and three
/// angles in degrees, interpreted with an [`EulerConvention`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotPose {
    pub xyz_mm: [f64; 3],
    pub angles_deg: [f64; 3],
}

impl RobotPose {
    /// `Base_T_End` for this pose.
    pub fn to_isometry(&self, convention: EulerConvention) -> Isometry3<f64> {
        let rot = convention.rotation(self.angles_deg);
        Isometry3::from_parts(
            Translation3::new(self.xyz_mm[0], self.xyz_mm[1], self.xyz_mm[2]),
            UnitQuaternion::from_rotation_matrix(&rot),
        )
    }

    /// The pose that gives `iso` under `convention`.
    pub fn from_isometry(iso: &Isometry3<f64>, convention: EulerConvention) -> Self {
        let t = iso.translation.vector;
        RobotPose { xyz_mm: [t.x, t.y, t.z], angles_deg: convention.angles(&iso.rotation.to_rotation_matrix()) }
    }

    /// True when all six numbers are finite.
    pub fn is_finite(&self) -> bool {
        self.xyz_mm.iter().chain(self.angles_deg.iter()).all(|v| v.is_finite())
    }
}

/// Why a hand-eye matrix was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HandEyeError {
    /// A coefficient is NaN or infinite.
    #[error("the hand-eye matrix has a non-finite entry at row {row}, column {col}")]
    NotFinite { row: usize, col: usize },
    /// The last row is not `0 0 0 1`, so it is not a rigid transform.
    #[error("the hand-eye matrix's last row must be 0, 0, 0, 1 (found {found:?})")]
    BadLastRow { found: [f64; 4] },
    /// `RᵀR` differs from the identity by more than the tolerance: the
    /// rotation is not orthonormal (a mistyped coefficient, typically).
    #[error(
        "the hand-eye rotation is not orthonormal: RᵀR differs from the identity by {deviation:.4} \
         at ({row}, {col}) (tolerance {tolerance}); check the coefficients for a typo"
    )]
    NotOrthonormal { deviation: f64, row: usize, col: usize, tolerance: f64 },
    /// `det R < 0`: a reflection, not a rotation.
    #[error("the hand-eye rotation is a reflection (determinant {det:.4}); a camera frame must be right-handed")]
    Reflection { det: f64 },
}

/// Tolerance on `RᵀR - I` for calibration matrices printed to four
/// decimals, as calibration tools commonly export them.
pub const ORTHONORMAL_TOLERANCE: f64 = 2e-3;

/// Validates a row-major 4x4 `End_T_Camera` and returns it as a rigid
/// transform. The rotation is re-orthonormalised (nearest rotation, by SVD)
/// so four-decimal rounding does not scale the trajectory.
pub fn hand_eye_from_rows(m: &[f64; 16]) -> Result<Isometry3<f64>, HandEyeError> {
    for (i, v) in m.iter().enumerate() {
        if !v.is_finite() {
            return Err(HandEyeError::NotFinite { row: i / 4, col: i % 4 });
        }
    }
    let last = [m[12], m[13], m[14], m[15]];
    if last != [0.0, 0.0, 0.0, 1.0] {
        return Err(HandEyeError::BadLastRow { found: last });
    }
    let mat = Matrix4::from_row_slice(m);
    let r: Matrix3<f64> = mat.fixed_view::<3, 3>(0, 0).into_owned();
    let gram = r.transpose() * r - Matrix3::identity();
    let (mut worst, mut at) = (0.0f64, (0, 0));
    for row in 0..3 {
        for col in 0..3 {
            if gram[(row, col)].abs() > worst {
                worst = gram[(row, col)].abs();
                at = (row, col);
            }
        }
    }
    if worst > ORTHONORMAL_TOLERANCE {
        return Err(HandEyeError::NotOrthonormal {
            deviation: worst,
            row: at.0,
            col: at.1,
            tolerance: ORTHONORMAL_TOLERANCE,
        });
    }
    let det = r.determinant();
    if det < 0.0 {
        return Err(HandEyeError::Reflection { det });
    }
    let svd = r.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        // SVD of a finite 3x3 always yields both factors when asked.
        return Err(HandEyeError::NotOrthonormal {
            deviation: f64::NAN,
            row: 0,
            col: 0,
            tolerance: ORTHONORMAL_TOLERANCE,
        });
    };
    let rot = Rotation3::from_matrix_unchecked(u * v_t);
    Ok(Isometry3::from_parts(Translation3::new(m[3], m[7], m[11]), UnitQuaternion::from_rotation_matrix(&rot)))
}

/// The paper's `End_T_Camera` (Eq. 41) with its one typo corrected: the
/// printed `-0.353` in row 2 must be `-0.0353` for the rotation to be
/// orthonormal.
pub const PAPER_HAND_EYE: [f64; 16] = [
    0.9943, 0.0364, -0.1003, 76.0178, //
    -0.0353, 0.9993, 0.0121, -84.3385, //
    0.1007, -0.0085, 0.9949, 100.3920, //
    0.0, 0.0, 0.0, 1.0,
];

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < tol)
    }

    #[test]
    fn zyx_is_rz_ry_rx() {
        let r = EulerConvention::Zyx.rotation([30.0, 0.0, 0.0]);
        let v = r * Vector3::new(0.0, 1.0, 0.0);
        let a = 30f64.to_radians();
        assert!((v - Vector3::new(0.0, a.cos(), a.sin())).norm() < 1e-12);
        let r = EulerConvention::Zyx.rotation([10.0, 20.0, 30.0]);
        let expected = EulerConvention::Zyx.rotation([0.0, 0.0, 30.0])
            * EulerConvention::Zyx.rotation([0.0, 20.0, 0.0])
            * EulerConvention::Zyx.rotation([10.0, 0.0, 0.0]);
        assert!((r.matrix() - expected.matrix()).norm() < 1e-12);
    }

    #[test]
    fn angles_invert_rotation_for_every_convention() {
        for conv in [EulerConvention::Zyx, EulerConvention::Xyz, EulerConvention::RotationVector] {
            for angles in [[178.28, 1.04, 107.12], [-176.89, 6.33, 105.7], [10.0, -40.0, 5.0]] {
                let r = conv.rotation(angles);
                let back = conv.rotation(conv.angles(&r));
                assert!((r.matrix() - back.matrix()).norm() < 1e-9, "{conv:?} {angles:?}");
            }
        }
        assert!(close(
            EulerConvention::Zyx.angles(&EulerConvention::Zyx.rotation([10.0, 20.0, 30.0])),
            [10.0, 20.0, 30.0],
            1e-9
        ));
    }

    #[test]
    fn paper_matrix_typo_is_refused_and_the_fix_accepted() {
        let mut typo = PAPER_HAND_EYE;
        typo[4] = -0.353;
        assert!(matches!(hand_eye_from_rows(&typo), Err(HandEyeError::NotOrthonormal { .. })));
        let iso = hand_eye_from_rows(&PAPER_HAND_EYE).unwrap();
        assert!((iso.translation.vector - Vector3::new(76.0178, -84.3385, 100.392)).norm() < 1e-9);
    }

    #[test]
    fn bad_matrices_name_the_problem() {
        let mut m = PAPER_HAND_EYE;
        m[5] = f64::NAN;
        assert_eq!(hand_eye_from_rows(&m), Err(HandEyeError::NotFinite { row: 1, col: 1 }));
        let mut m = PAPER_HAND_EYE;
        m[15] = 2.0;
        assert!(matches!(hand_eye_from_rows(&m), Err(HandEyeError::BadLastRow { .. })));
        let mut m = [0.0; 16];
        m[0] = -1.0;
        m[5] = 1.0;
        m[10] = 1.0;
        m[15] = 1.0;
        assert!(matches!(hand_eye_from_rows(&m), Err(HandEyeError::Reflection { .. })));
    }

    #[test]
    fn pose_round_trips_through_isometry() {
        let pose = RobotPose { xyz_mm: [-613.5, -284.81, 296.28], angles_deg: [178.28, 1.04, 107.12] };
        let iso = pose.to_isometry(EulerConvention::Zyx);
        let back = RobotPose::from_isometry(&iso, EulerConvention::Zyx);
        assert!(close(back.xyz_mm, pose.xyz_mm, 1e-9));
        assert!(close(back.angles_deg, pose.angles_deg, 1e-9));
    }
}
