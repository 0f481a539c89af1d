//! The classic closed forms of `AX = XB`, each from every pair of
//! captures (not only consecutive ones, so the answer does not depend on
//! the order the captures were taken or listed in).
//!
//! For captures `i` and `j` with `A_i X B_i = Y` (the target fixed, see
//! the module above), `A = A_j⁻¹ A_i` and `B = B_j B_i⁻¹` satisfy
//! `A X = X B`. Both forms solve the rotation first, then the translation
//! from `(R_A - I) t_X = R_X t_B - t_A` by least squares.
//!
//! - Tsai and Lenz (1989): the rotations as modified Rodrigues vectors
//!   `P = 2 sin(θ/2) n`; `skew(P_A + P_B) P' = P_B - P_A` for each pair,
//!   `P_X = 2 P' / √(1 + |P'|²)`.
//! - Park and Martin (1994): the rotations' logarithms `α = log R_A`,
//!   `β = log R_B` satisfy `α = R_X β`; `R_X` is the orthogonal Procrustes
//!   solution of `Σ β αᵀ` (their `(MᵀM)^-½ Mᵀ`, with the determinant kept
//!   at +1).

use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Pairs whose hand rotation is smaller than this carry no rotation
/// information, only noise, and are left out of the closed forms.
pub const MIN_PAIR_ROTATION_DEG: f64 = 2.0;

/// The closed forms this module has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClosedForm {
    TsaiLenz,
    ParkMartin,
}

impl ClosedForm {
    pub const ALL: [ClosedForm; 2] = [ClosedForm::TsaiLenz, ClosedForm::ParkMartin];

    pub fn name(self) -> &'static str {
        match self {
            ClosedForm::TsaiLenz => "tsai-lenz",
            ClosedForm::ParkMartin => "park-martin",
        }
    }

    /// `X` from the relative motions, or `None` when they do not determine
    /// it (fewer than two motions with rotation, all about one axis).
    pub fn solve(self, motions: &[Motion]) -> Option<Isometry3<f64>> {
        let usable: Vec<&Motion> =
            motions.iter().filter(|m| m.a.rotation.angle().to_degrees() >= MIN_PAIR_ROTATION_DEG).collect();
        if usable.len() < 2 {
            return None;
        }
        let rotation = match self {
            ClosedForm::TsaiLenz => tsai_lenz_rotation(&usable)?,
            ClosedForm::ParkMartin => park_martin_rotation(&usable)?,
        };
        let translation = translation(&usable, &rotation)?;
        Some(Isometry3::from_parts(Translation3::from(translation), UnitQuaternion::from_rotation_matrix(&rotation)))
    }
}

/// One relative motion: `A X = X B`.
#[derive(Debug, Clone, Copy)]
pub struct Motion {
    pub a: Isometry3<f64>,
    pub b: Isometry3<f64>,
}

/// The motions between every pair of the captures `(A_i, B_i)`.
pub fn motions(pairs: &[(Isometry3<f64>, Isometry3<f64>)]) -> Vec<Motion> {
    let mut out = Vec::with_capacity(pairs.len() * pairs.len().saturating_sub(1) / 2);
    for (j, (a_j, b_j)) in pairs.iter().enumerate() {
        for (a_i, b_i) in &pairs[..j] {
            out.push(Motion { a: a_j.inverse() * a_i, b: b_j * b_i.inverse() });
        }
    }
    out
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The modified Rodrigues vector `2 sin(θ/2) n` of a rotation.
fn rodrigues(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    // For a unit quaternion (cos θ/2, sin θ/2 n) the vector part is
    // sin(θ/2) n; w ≥ 0 keeps θ within π.
    let v = q.imag();
    if q.w < 0.0 { -2.0 * v } else { 2.0 * v }
}

/// Least squares `M x = y` for a tall system, by SVD.
fn solve_stacked(m: DMatrix<f64>, y: DVector<f64>) -> Option<DVector<f64>> {
    let svd = m.svd(true, true);
    let s = &svd.singular_values;
    let largest = s.iter().copied().fold(0.0, f64::max);
    // A near-null direction means the motions do not determine it.
    if largest == 0.0 || s.iter().copied().fold(f64::INFINITY, f64::min) < largest * 1e-9 {
        return None;
    }
    svd.solve(&y, 0.0).ok()
}

fn tsai_lenz_rotation(motions: &[&Motion]) -> Option<Rotation3<f64>> {
    let n = motions.len();
    let mut m = DMatrix::zeros(3 * n, 3);
    let mut y = DVector::zeros(3 * n);
    for (k, motion) in motions.iter().enumerate() {
        let pa = rodrigues(&motion.a.rotation);
        let pb = rodrigues(&motion.b.rotation);
        m.fixed_view_mut::<3, 3>(3 * k, 0).copy_from(&skew(&(pa + pb)));
        y.fixed_rows_mut::<3>(3 * k).copy_from(&(pb - pa));
    }
    let p_prime = solve_stacked(m, y)?;
    let p_prime = Vector3::new(p_prime[0], p_prime[1], p_prime[2]);
    let p = 2.0 * p_prime / (1.0 + p_prime.norm_squared()).sqrt();
    // |P| = 2 sin(θ/2).
    let angle = 2.0 * (p.norm() / 2.0).clamp(-1.0, 1.0).asin();
    Some(match nalgebra::Unit::try_new(p, 1e-15) {
        Some(axis) => Rotation3::from_axis_angle(&axis, angle),
        None => Rotation3::identity(),
    })
}

/// The rotation `R` maximising `Σ αᵀ R β`: Park and Martin's least
/// squares of `α = R β`, by the SVD of `Σ β αᵀ`.
fn park_martin_rotation(motions: &[&Motion]) -> Option<Rotation3<f64>> {
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> =
        motions.iter().map(|m| (m.a.rotation.scaled_axis(), m.b.rotation.scaled_axis())).collect();
    procrustes(&pairs)
}

/// The rotation `R` that best maps each `from` onto its `to` (`to ≈ R
/// from`), pairs `(to, from)`, or `None` when they span less than a
/// plane.
pub fn procrustes(pairs: &[(Vector3<f64>, Vector3<f64>)]) -> Option<Rotation3<f64>> {
    let h: Matrix3<f64> = pairs.iter().map(|(to, from)| from * to.transpose()).sum();
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let s = svd.singular_values;
    if s[1] <= s[0] * 1e-9 {
        return None;
    }
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    Some(Rotation3::from_matrix_unchecked(r))
}

fn translation(motions: &[&Motion], rotation: &Rotation3<f64>) -> Option<Vector3<f64>> {
    let n = motions.len();
    let mut m = DMatrix::zeros(3 * n, 3);
    let mut y = DVector::zeros(3 * n);
    for (k, motion) in motions.iter().enumerate() {
        let ra = motion.a.rotation.to_rotation_matrix().into_inner() - Matrix3::identity();
        m.fixed_view_mut::<3, 3>(3 * k, 0).copy_from(&ra);
        let rhs = rotation * motion.b.translation.vector - motion.a.translation.vector;
        y.fixed_rows_mut::<3>(3 * k).copy_from(&rhs);
    }
    let t = solve_stacked(m, y)?;
    Some(Vector3::new(t[0], t[1], t[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(t: [f64; 3], r: [f64; 3]) -> Isometry3<f64> {
        Isometry3::new(Vector3::from(t), Vector3::from(r.map(f64::to_radians)))
    }

    /// Exact captures of a target at `y` by a camera at `x` on the flange.
    fn exact_pairs(x: &Isometry3<f64>, y: &Isometry3<f64>) -> Vec<(Isometry3<f64>, Isometry3<f64>)> {
        let hands = [
            pose([400.0, 0.0, 600.0], [180.0, 0.0, 0.0]),
            pose([420.0, 30.0, 580.0], [160.0, 10.0, 20.0]),
            pose([380.0, -40.0, 610.0], [190.0, -15.0, -30.0]),
            pose([410.0, 50.0, 590.0], [170.0, 20.0, 45.0]),
            pose([395.0, -20.0, 620.0], [200.0, 5.0, 10.0]),
        ];
        hands.iter().map(|a| (*a, (a * x).inverse() * y)).collect()
    }

    #[test]
    fn both_forms_recover_an_exact_hand_eye() {
        let x = pose([40.0, -80.0, 100.0], [3.0, -5.0, 90.0]);
        let y = pose([450.0, 10.0, 0.0], [0.0, 0.0, 30.0]);
        let motions = motions(&exact_pairs(&x, &y));
        assert_eq!(motions.len(), 10);
        for form in ClosedForm::ALL {
            let found = form.solve(&motions).unwrap_or_else(|| panic!("{}", form.name()));
            assert!((found.translation.vector - x.translation.vector).norm() < 1e-6, "{}", form.name());
            assert!(found.rotation.angle_to(&x.rotation) < 1e-9, "{}", form.name());
        }
    }

    #[test]
    fn rotations_about_one_axis_do_not_determine_the_hand_eye() {
        let x = pose([40.0, -80.0, 100.0], [3.0, -5.0, 90.0]);
        let y = pose([450.0, 10.0, 0.0], [0.0, 0.0, 30.0]);
        let pairs: Vec<_> = [0.0, 20.0, 45.0, 70.0]
            .iter()
            .map(|angle| {
                let a = pose([400.0, 0.0, 600.0], [0.0, 0.0, *angle]);
                (a, (a * x).inverse() * y)
            })
            .collect();
        for form in ClosedForm::ALL {
            assert!(form.solve(&motions(&pairs)).is_none(), "{}", form.name());
        }
    }
}
