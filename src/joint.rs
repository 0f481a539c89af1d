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
    /// Tee joint with fillet welds: a web plate standing on a flange plate,
    /// welded along the two lines where the web's side faces meet the
    /// flange's top (the fillet roots). The robust method plans each root
    /// it sees (the paper has no fillet, so its method refuses it).
    TFillet,
}

impl JointType {
    /// The paper's three joint types, which both methods plan (the suites
    /// and tests that go through them one by one).
    pub const ALL: [JointType; 3] = [JointType::VButt, JointType::IButt, JointType::Lap];
    /// Every joint type with a name, planned or not.
    pub const NAMED: [JointType; 4] = [JointType::VButt, JointType::IButt, JointType::Lap, JointType::TFillet];

    /// The canonical name, as written in JSON output and on the wire.
    pub fn name(self) -> &'static str {
        match self {
            JointType::VButt => "v_butt",
            JointType::IButt => "i_butt",
            JointType::Lap => "lap",
            JointType::TFillet => "t_fillet",
        }
    }

    /// The name as the command line and scene names spell it: `v-butt`,
    /// `i-butt`, `lap`, `t-fillet`.
    pub fn dashed_name(self) -> &'static str {
        match self {
            JointType::VButt => "v-butt",
            JointType::IButt => "i-butt",
            JointType::Lap => "lap",
            JointType::TFillet => "t-fillet",
        }
    }

    /// Whether the paper's method plans this joint (see [`JointType::ALL`]);
    /// the robust method plans every named type.
    pub fn is_planned_by_the_paper(self) -> bool {
        JointType::ALL.contains(&self)
    }
}

impl fmt::Display for JointType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The joint name was not one of `v-butt`, `i-butt`, `lap`, `t-fillet`
/// (or `auto` where a request may leave the type to the planner).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown joint type {0:?} (expected v-butt, i-butt, lap, t-fillet or auto)")]
pub struct UnknownJoint(pub String);

/// The joint a plan request names: one type, or `auto` to have the planner
/// decide it from the geometry (the plates' layers, then the groove faces
/// between the weld edges) and say on what evidence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RequestedJoint {
    Auto,
    Type(JointType),
}

impl RequestedJoint {
    /// The type requested, or None for `auto`.
    pub fn given(self) -> Option<JointType> {
        match self {
            RequestedJoint::Auto => None,
            RequestedJoint::Type(joint) => Some(joint),
        }
    }

    /// The canonical name: a type's, or `auto`.
    pub fn name(self) -> &'static str {
        match self {
            RequestedJoint::Auto => "auto",
            RequestedJoint::Type(joint) => joint.name(),
        }
    }
}

impl From<JointType> for RequestedJoint {
    fn from(joint: JointType) -> Self {
        RequestedJoint::Type(joint)
    }
}

impl fmt::Display for RequestedJoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RequestedJoint {
    type Err = UnknownJoint;

    /// A joint type's name, or `auto` in any case.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(RequestedJoint::Auto);
        }
        s.parse().map(RequestedJoint::Type)
    }
}

impl FromStr for JointType {
    type Err = UnknownJoint;

    /// Accepts `v-butt`, `v_butt`, `vbutt`, `t-fillet` and the like, any
    /// case.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key: String = s.chars().filter(|c| !matches!(c, '-' | '_' | ' ')).collect::<String>().to_ascii_lowercase();
        match key.as_str() {
            "vbutt" | "v" => Ok(JointType::VButt),
            "ibutt" | "i" => Ok(JointType::IButt),
            "lap" => Ok(JointType::Lap),
            "tfillet" => Ok(JointType::TFillet),
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
        assert_eq!("t-fillet".parse(), Ok(JointType::TFillet));
        assert_eq!("T_FILLET".parse(), Ok(RequestedJoint::Type(JointType::TFillet)));
        assert!("fillet".parse::<JointType>().is_err());
        assert!("auto".parse::<JointType>().is_err());
        assert!(!JointType::TFillet.is_planned_by_the_paper());
        assert!(JointType::ALL.iter().all(|j| j.is_planned_by_the_paper()));
        for j in JointType::NAMED {
            assert_eq!(j.name().parse(), Ok(j));
            assert_eq!(j.dashed_name().parse(), Ok(j));
            assert_eq!(j.name().parse(), Ok(RequestedJoint::Type(j)));
        }
    }

    #[test]
    fn a_request_may_leave_the_type_to_the_planner() {
        assert_eq!("auto".parse(), Ok(RequestedJoint::Auto));
        assert_eq!("AUTO".parse(), Ok(RequestedJoint::Auto));
        assert_eq!("lap".parse(), Ok(RequestedJoint::Type(JointType::Lap)));
        assert!("tee".parse::<RequestedJoint>().is_err());
        assert_eq!(RequestedJoint::Auto.name().parse(), Ok(RequestedJoint::Auto));
    }
}
