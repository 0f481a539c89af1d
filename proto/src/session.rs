//! Version and capability negotiation: which protocol version a
//! connection speaks and which optional features its peer asked for and
//! was granted. The peer's Hello states the newest version it speaks and
//! (from version 8) the capabilities it wants; the daemon answers in its
//! HelloAck with the version both speak (the lower of the peer's and its
//! own newest) and the capabilities it grants. Every later message of the
//! connection is laid out as that version and those capabilities say, so
//! a peer gets exactly the bytes of the version it was written for.

use crate::message::{ErrorCode, Hello};

/// The newest protocol version this crate speaks. Version 8 added the
/// capabilities to the Hello and HelloAck; see PROTOCOL.md for each
/// version's changes.
pub const PROTOCOL_VERSION: u16 = 8;

/// The oldest version the daemon still serves: a peer stating this
/// version or a later one is answered in the newest version both speak.
/// PROTOCOL.md's policy says how long an old version is served.
pub const OLDEST_SERVED_VERSION: u16 = 7;

/// The first version whose Hello and HelloAck carry capabilities.
pub const CAPABILITIES_SINCE: u16 = 8;

/// The optional features a peer may ask for in its Hello, one bit each.
/// A bit the daemon does not know is never granted; a granted feature
/// changes only what the daemon sends, and only as PROTOCOL.md says.
pub mod capability {
    /// The HelloAck carries the daemon's limits (`DaemonLimits`), so a
    /// client can size its frames, requests and timeouts to them.
    pub const LIMITS: u64 = 1 << 0;

    /// Every refusal and warning names the planner's rule that made it
    /// (its stable id, `family.decision`): an Error ends with the rule of
    /// the refusal it reports, and a PlanReply with the rules of its
    /// seams' warnings and of its unplanned joints.
    pub const RULE_IDS: u64 = 1 << 1;

    /// Every seam carries the joint's figures at each of its waypoints
    /// and, with a weld procedure configured, its process: a PlanReply
    /// ends with them ([`crate::along_seam`]).
    pub const ALONG_SEAM: u64 = 1 << 2;

    /// Every capability this crate knows, with its name in PROTOCOL.md.
    pub const ALL: [(u64, &str); 3] = [(LIMITS, "limits"), (RULE_IDS, "rule_ids"), (ALONG_SEAM, "along_seam")];

    /// The bits of [`ALL`].
    pub const KNOWN: u64 = LIMITS | RULE_IDS | ALONG_SEAM;
}

/// What a connection speaks: its version and its granted capabilities.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Session {
    pub version: u16,
    /// Bits of [`capability`]; always 0 below [`CAPABILITIES_SINCE`].
    pub capabilities: u64,
}

impl Session {
    /// This crate's newest version, without capabilities: how a peer
    /// speaks before its Hello is answered.
    pub const NEWEST: Session = Session { version: PROTOCOL_VERSION, capabilities: 0 };

    /// A version 7 connection (which has no capabilities).
    pub const V7: Session = Session { version: 7, capabilities: 0 };

    /// A session of `version` without capabilities.
    pub const fn of(version: u16) -> Session {
        Session { version, capabilities: 0 }
    }

    pub fn has(&self, capability: u64) -> bool {
        self.capabilities & capability == capability
    }
}

/// Why a Hello cannot be answered with a HelloAck.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NegotiationError {
    /// The peer speaks only versions older than [`OLDEST_SERVED_VERSION`].
    #[error(
        "protocol version {0} is not supported; this daemon speaks version {PROTOCOL_VERSION} and serves peers of \
         version {OLDEST_SERVED_VERSION} and later (see \"Versions and capabilities\" in PROTOCOL.md)"
    )]
    TooOld(u16),
    /// The Hello's header and its `protocol_version` disagree.
    #[error("the Hello's header says version {header} but its protocol_version says {hello}; they must be equal")]
    Disagree { header: u16, hello: u16 },
}

impl NegotiationError {
    pub fn code(&self) -> ErrorCode {
        ErrorCode::UnsupportedVersion
    }
}

/// The session a daemon of this crate grants the peer of `hello`, which
/// came in a header of `header_version`: the lower of the peer's version
/// and [`PROTOCOL_VERSION`], and the capabilities asked that this crate
/// knows.
pub fn negotiate(hello: &Hello, header_version: u16) -> Result<Session, NegotiationError> {
    if hello.protocol_version != header_version {
        return Err(NegotiationError::Disagree { header: header_version, hello: hello.protocol_version });
    }
    if hello.protocol_version < OLDEST_SERVED_VERSION {
        return Err(NegotiationError::TooOld(hello.protocol_version));
    }
    let version = hello.protocol_version.min(PROTOCOL_VERSION);
    let capabilities = if version >= CAPABILITIES_SINCE { hello.capabilities & capability::KNOWN } else { 0 };
    Ok(Session { version, capabilities })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::Role;

    fn hello(version: u16, capabilities: u64) -> Hello {
        Hello { protocol_version: version, role: Role::Camera, name: "cam".into(), capabilities }
    }

    #[test]
    fn the_version_is_the_newest_both_speak_and_only_known_capabilities_are_granted() {
        assert_eq!(negotiate(&hello(7, 0), 7), Ok(Session::V7));
        assert_eq!(negotiate(&hello(8, 0), 8), Ok(Session::NEWEST));
        let both = capability::LIMITS | capability::RULE_IDS;
        assert_eq!(negotiate(&hello(8, both | 1 << 40), 8), Ok(Session { version: 8, capabilities: both }));
        let all = both | capability::ALONG_SEAM;
        assert_eq!(negotiate(&hello(8, all | 1 << 40), 8), Ok(Session { version: 8, capabilities: all }));
        assert_eq!(negotiate(&hello(7, both), 7), Ok(Session::V7), "version 7 has no capabilities");
        let asked = capability::LIMITS | 1 << 40;
        assert_eq!(negotiate(&hello(8, asked), 8), Ok(Session { version: 8, capabilities: capability::LIMITS }));
        // A newer peer is answered in this crate's newest version.
        assert_eq!(negotiate(&hello(12, asked), 12), Ok(Session { version: 8, capabilities: capability::LIMITS }));
        for old in 1..OLDEST_SERVED_VERSION {
            let refused = negotiate(&hello(old, 0), old).unwrap_err();
            assert_eq!(refused.code(), ErrorCode::UnsupportedVersion);
            assert!(refused.to_string().contains(&format!("version {old} is not supported")), "{refused}");
        }
        assert!(matches!(negotiate(&hello(8, 0), 7), Err(NegotiationError::Disagree { header: 7, hello: 8 })));
    }
}
