//! How well a set of robot poses determines the hand-eye: `AX = XB`
//! fixes `X`'s rotation only through rotations of the hand about at least
//! two different axes, and its translation only through rotations (a
//! translation along a rotation axis is invisible). So the set is judged
//! by the hand's rotations between every pair of captures: how large the
//! largest is, and how the rotation axes spread, from the eigenvalues of
//! `Σ θ² n nᵀ` over the pairs (the rotation information each axis
//! carries). A set whose axes are nearly parallel has its second
//! eigenvalue small against the first.

use nalgebra::{Isometry3, Matrix3, SymmetricEigen, Vector3};

/// A pose set whose largest rotation between two captures is below this
/// is too little rotation for `AX = XB`: the noise of the rotations
/// becomes comparable to the rotations themselves.
pub const MIN_ROTATION_SPREAD_DEG: f64 = 15.0;

/// Rotation axes whose spread (the angle `atan √(λ₂ / λ₁)` of the
/// information matrix's two largest eigenvalues) is below this are nearly
/// parallel.
pub const MIN_AXIS_SPREAD_DEG: f64 = 8.0;

/// The rotation each suggested pose should add about the missing axis.
pub const SUGGESTED_TURN_DEG: f64 = 30.0;

/// What the pose set's rotations are like.
#[derive(Debug, Clone, PartialEq)]
pub struct Conditioning {
    /// The largest rotation of the hand between two captures, degrees.
    pub largest_rotation_deg: f64,
    /// `atan √(λ₂ / λ₁)`: 0 when every rotation is about one axis, 45°
    /// when two axes carry equal information, degrees.
    pub axis_spread_deg: f64,
    /// `atan √(λ₃ / λ₁)`, the third axis likewise, degrees.
    pub third_axis_spread_deg: f64,
    /// The flange-frame axis the rotations turn least about (the
    /// eigenvector of the smallest eigenvalue): where poses are missing.
    pub weakest_axis: Vector3<f64>,
    /// The axis they turn most about.
    pub strongest_axis: Vector3<f64>,
}

impl Conditioning {
    /// The conditioning of the hand poses `A_i` (flange-frame relative
    /// rotations `A_j⁻¹ A_i`).
    pub fn of(hands: &[Isometry3<f64>]) -> Conditioning {
        let mut info = Matrix3::zeros();
        let mut largest = 0.0f64;
        for (j, a_j) in hands.iter().enumerate() {
            for a_i in &hands[..j] {
                let rotation = (a_j.inverse() * a_i).rotation;
                let omega = rotation.scaled_axis();
                largest = largest.max(omega.norm());
                info += omega * omega.transpose();
            }
        }
        let eigen = SymmetricEigen::new(info);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        let [l1, l2, l3] = order.map(|k| eigen.eigenvalues[k].max(0.0));
        let spread = |l: f64| if l1 > 0.0 { (l / l1).sqrt().atan().to_degrees() } else { 0.0 };
        Conditioning {
            largest_rotation_deg: largest.to_degrees(),
            axis_spread_deg: spread(l2),
            third_axis_spread_deg: spread(l3),
            weakest_axis: eigen.eigenvectors.column(order[2]).into_owned(),
            strongest_axis: eigen.eigenvectors.column(order[0]).into_owned(),
        }
    }

    /// The warnings a person should act on, each with the poses to add.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.largest_rotation_deg < MIN_ROTATION_SPREAD_DEG {
            out.push(format!(
                "too little rotation between captures: the largest is {:.1} degrees (at least {MIN_ROTATION_SPREAD_DEG} \
                 needed, 30 to 60 is good), so AX = XB is ill-posed; add poses that tilt the flange by \
                 {SUGGESTED_TURN_DEG} degrees or more about two different axes while the camera still sees the target",
                self.largest_rotation_deg
            ));
        } else if self.axis_spread_deg < MIN_AXIS_SPREAD_DEG {
            let a = self.strongest_axis;
            let w = self.weakest_axis;
            out.push(format!(
                "the rotation axes between captures are nearly parallel (all near ({:.2}, {:.2}, {:.2}) in the flange \
                 frame; spread {:.1} degrees, at least {MIN_AXIS_SPREAD_DEG} needed), so AX = XB is ill-posed: the \
                 hand-eye's rotation about that axis and its translation along it are not determined; add poses that \
                 turn the flange by about {SUGGESTED_TURN_DEG} degrees about an axis across it, such as ({:.2}, {:.2}, \
                 {:.2})",
                a.x, a.y, a.z, self.axis_spread_deg, w.x, w.y, w.z
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hand(r_deg: [f64; 3]) -> Isometry3<f64> {
        Isometry3::new(Vector3::new(400.0, 0.0, 500.0), Vector3::from(r_deg.map(f64::to_radians)))
    }

    #[test]
    fn rotations_about_several_axes_are_well_posed() {
        let hands = [hand([0.0, 0.0, 0.0]), hand([25.0, 0.0, 0.0]), hand([0.0, 25.0, 0.0]), hand([0.0, 0.0, 40.0])];
        let c = Conditioning::of(&hands);
        assert!(c.largest_rotation_deg > 35.0 && c.axis_spread_deg > 30.0, "{c:?}");
        assert!(c.warnings().is_empty());
    }

    #[test]
    fn rotations_about_one_axis_are_warned_with_the_axis_to_add() {
        let hands = [hand([0.0, 0.0, 0.0]), hand([0.5, 0.0, 30.0]), hand([0.0, 0.5, -30.0]), hand([0.0, 0.0, 60.0])];
        let c = Conditioning::of(&hands);
        assert!(c.axis_spread_deg < 2.0, "{c:?}");
        let w = c.warnings();
        assert!(w.len() == 1 && w[0].contains("nearly parallel"), "{w:?}");
        assert!(c.weakest_axis.z.abs() < 0.1 && c.strongest_axis.z.abs() > 0.99, "{c:?}");
    }

    #[test]
    fn small_rotations_are_warned() {
        let hands = [hand([0.0, 0.0, 0.0]), hand([3.0, 0.0, 0.0]), hand([0.0, 4.0, 0.0]), hand([0.0, 0.0, 5.0])];
        let w = Conditioning::of(&hands).warnings();
        assert!(w.len() == 1 && w[0].contains("too little rotation"), "{w:?}");
    }
}
