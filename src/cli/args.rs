//! Parsers for the comma-separated numeric flags shared by subcommands.

use weldseam::geometry::pose::RobotPose;

/// Parses exactly `N` comma-separated numbers, naming the flag in errors.
pub fn numbers<const N: usize>(flag: &str, text: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!("{flag} needs {N} comma-separated numbers, got {}: {text:?}", parts.len()));
    }
    let mut out = [0.0; N];
    for (k, part) in parts.iter().enumerate() {
        let v: f64 = part.parse().map_err(|_| format!("{flag}: value {} ({part:?}) is not a number", k + 1))?;
        if !v.is_finite() {
            return Err(format!("{flag}: value {} is not finite", k + 1));
        }
        out[k] = v;
    }
    Ok(out)
}

/// `x,y,z,rx,ry,rz` in mm and degrees.
pub fn pose(text: &str) -> Result<RobotPose, String> {
    let v = numbers::<6>("--pose", text)?;
    Ok(RobotPose { xyz_mm: [v[0], v[1], v[2]], angles_deg: [v[3], v[4], v[5]] })
}

/// Sixteen numbers, a row-major 4x4 matrix.
pub fn matrix(text: &str) -> Result<[f64; 16], String> {
    numbers::<16>("--hand-eye", text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_accepts_negative_values_and_spaces() {
        let p = pose("-613.5, -284.81,296.28,178.28,1.04,-107.12").unwrap();
        assert_eq!(p.xyz_mm, [-613.5, -284.81, 296.28]);
        assert_eq!(p.angles_deg[2], -107.12);
    }

    #[test]
    fn bad_poses_say_what_is_wrong() {
        assert!(pose("1,2,3").unwrap_err().contains("needs 6"));
        assert!(pose("1,2,3,4,5,x").unwrap_err().contains("value 6"));
        assert!(pose("1,2,3,4,5,nan").unwrap_err().contains("not finite"));
    }
}
