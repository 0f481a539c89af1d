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
/// (or `auto`, or a list of types joined by `+`, where a request may leave
/// the type to the planner).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown joint type {0:?} (expected v-butt, i-butt, lap, t-fillet, auto, or types joined by + such as v-butt+lap)"
)]
pub struct UnknownJoint(pub String);

/// A set of joint types: the types a fixture holds, of which the planner
/// decides each workpiece's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct JointSet(u8);

impl JointSet {
    /// One bit per type, by its place in the declaration (which
    /// [`JointType::NAMED`] follows).
    fn bit(joint: JointType) -> u8 {
        1 << joint as u8
    }

    /// The set with `joint` added.
    pub fn with(self, joint: JointType) -> JointSet {
        JointSet(self.0 | JointSet::bit(joint))
    }

    pub fn contains(self, joint: JointType) -> bool {
        self.0 & JointSet::bit(joint) != 0
    }

    /// The types in the set, in [`JointType::NAMED`]'s order.
    pub fn iter(self) -> impl Iterator<Item = JointType> {
        JointType::NAMED.into_iter().filter(move |&j| self.contains(j))
    }

    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

impl FromIterator<JointType> for JointSet {
    fn from_iter<I: IntoIterator<Item = JointType>>(joints: I) -> Self {
        joints.into_iter().fold(JointSet::default(), JointSet::with)
    }
}

impl fmt::Display for JointSet {
    /// The canonical names joined by `+`: `v_butt+lap`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(JointType::name).collect();
        f.write_str(&names.join("+"))
    }
}

/// The joint a plan request names: one type; `auto`, to have the planner
/// decide it from the geometry (the plates' layers, then the groove faces
/// between the weld edges) and say on what evidence; or a set of types,
/// decided as with `auto`, where a workpiece of a type outside the set is
/// refused as a joint that does not match.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RequestedJoint {
    Auto,
    Type(JointType),
    /// Two or more types (a set of one is that type's request).
    OneOf(JointSet),
}

impl RequestedJoint {
    /// The type requested, or None when the planner decides it (`auto` or
    /// a set of types).
    pub fn given(self) -> Option<JointType> {
        match self {
            RequestedJoint::Auto | RequestedJoint::OneOf(_) => None,
            RequestedJoint::Type(joint) => Some(joint),
        }
    }

    /// Whether a workpiece found to be `joint` answers the request.
    pub fn admits(self, joint: JointType) -> bool {
        match self {
            RequestedJoint::Auto => true,
            RequestedJoint::Type(requested) => requested == joint,
            RequestedJoint::OneOf(set) => set.contains(joint),
        }
    }

    /// The request for the types of `set`: a set of one is that type's.
    pub fn one_of(set: JointSet) -> Option<RequestedJoint> {
        match set.len() {
            0 => None,
            1 => set.iter().next().map(RequestedJoint::Type),
            _ => Some(RequestedJoint::OneOf(set)),
        }
    }

    /// The canonical name: a type's, `auto`, or a set's (`v_butt+lap`).
    pub fn name(self) -> std::borrow::Cow<'static, str> {
        match self {
            RequestedJoint::Auto => "auto".into(),
            RequestedJoint::Type(joint) => joint.name().into(),
            RequestedJoint::OneOf(set) => set.to_string().into(),
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
        f.write_str(&self.name())
    }
}

impl FromStr for RequestedJoint {
    type Err = UnknownJoint;

    /// A joint type's name, `auto` in any case, or types' names joined by
    /// `+` (`v-butt+lap`; `+` because the text link's fields are separated
    /// by commas).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(RequestedJoint::Auto);
        }
        if !s.contains('+') {
            return s.parse().map(RequestedJoint::Type);
        }
        let set = s.split('+').map(str::parse).collect::<Result<JointSet, _>>().map_err(|_| UnknownJoint(s.into()))?;
        RequestedJoint::one_of(set).ok_or_else(|| UnknownJoint(s.into()))
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

    #[test]
    fn a_request_may_name_the_types_a_fixture_holds() {
        let set: JointSet = [JointType::Lap, JointType::VButt].into_iter().collect();
        assert_eq!("v-butt+lap".parse(), Ok(RequestedJoint::OneOf(set)));
        assert_eq!(" LAP + v_butt ".parse(), Ok(RequestedJoint::OneOf(set)));
        assert_eq!(RequestedJoint::OneOf(set).name(), "v_butt+lap");
        assert_eq!(RequestedJoint::OneOf(set).name().parse(), Ok(RequestedJoint::OneOf(set)));
        // A set of one is that type's request; a repeated type counts once.
        assert_eq!("lap+lap".parse(), Ok(RequestedJoint::Type(JointType::Lap)));
        for bad in ["v-butt+", "+lap", "lap+auto", "lap+tee", "+"] {
            assert_eq!(bad.parse::<RequestedJoint>(), Err(UnknownJoint(bad.into())), "{bad}");
        }
        let request = RequestedJoint::OneOf(set);
        assert!(request.admits(JointType::Lap) && request.admits(JointType::VButt));
        assert!(!request.admits(JointType::IButt) && !request.admits(JointType::TFillet));
        assert_eq!(request.given(), None);
        assert!(RequestedJoint::Auto.admits(JointType::TFillet));
        assert!(!RequestedJoint::Type(JointType::Lap).admits(JointType::VButt));
        let all: JointSet = JointType::NAMED.into_iter().collect();
        assert_eq!(all.len(), 4);
        assert_eq!(all.iter().collect::<Vec<_>>(), JointType::NAMED);
    }
}
