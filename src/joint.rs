//! The weld joint types the planner knows (the paper's section 2.2).

use std::fmt;
use std::str::FromStr;

/// A plane weld joint type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JointType {
    /// Plane V-type butt joint: two coplanar plates with bevelled edges.
    VButt,
    /// Plane I-type (square) butt joint: two coplanar plates, a narrow gap.
    IButt,
    /// Plane lap joint: one plate lying on another.
    Lap,
}

impl JointType {
    pub const ALL: [JointType; 3] = [JointType::VButt, JointType::IButt, JointType::Lap];

    /// The canonical name, as written in JSON output and on the wire.
    pub fn name(self) -> &'static str {
        match self {
            JointType::VButt => "v_butt",
            JointType::IButt => "i_butt",
            JointType::Lap => "lap",
        }
    }
}

impl fmt::Display for JointType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The joint name was not one of `v-butt`, `i-butt`, `lap`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown joint type {0:?} (expected v-butt, i-butt or lap)")]
pub struct UnknownJoint(pub String);

impl FromStr for JointType {
    type Err = UnknownJoint;

    /// Accepts `v-butt`, `v_butt`, `vbutt` and the like, any case.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key: String = s.chars().filter(|c| !matches!(c, '-' | '_' | ' ')).collect::<String>().to_ascii_lowercase();
        match key.as_str() {
            "vbutt" | "v" => Ok(JointType::VButt),
            "ibutt" | "i" => Ok(JointType::IButt),
            "lap" => Ok(JointType::Lap),
            _ => Err(UnknownJoint(s.to_string())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_with_dashes_or_underscores() {
        assert_eq!("v-butt".parse(), Ok(JointType::VButt));
        assert_eq!("V_BUTT".parse(), Ok(JointType::VButt));
        assert_eq!("i_butt".parse(), Ok(JointType::IButt));
        assert_eq!("lap".parse(), Ok(JointType::Lap));
        assert!("fillet".parse::<JointType>().is_err());
        for j in JointType::ALL {
            assert_eq!(j.name().parse(), Ok(j));
        }
    }
}
