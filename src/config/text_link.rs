//! The `[text_link]` section: the text controller link that robot programs
//! speak directly (see ROBOTS.md), its address, who may connect, the
//! dialect a session starts in, and the bounds on a line and a session.

use std::net::{IpAddr, SocketAddr};
use std::time::Duration;

use weldseam_proto::text::Dialect;

use super::server::{ip_list, socket_addr};
use super::{ConfigError, check, count_in, file, in_range};

/// The text controller link's settings, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct TextLinkConfig {
    /// Where robot programs connect; None leaves the link off.
    pub listen: Option<SocketAddr>,
    /// Peers allowed; empty allows any.
    pub allow: Vec<IpAddr>,
    /// Sessions served at once; a further connection is told busy.
    pub max_connections: usize,
    /// The dialect of a session that does not name one; None makes the
    /// robot's first line a `HELLO`.
    pub dialect: Option<Dialect>,
    /// The longest request line, terminator included.
    pub max_line_bytes: usize,
    /// A line begun must end within this time.
    pub line_timeout: Duration,
    /// A session without a whole line for this long is closed; zero never.
    pub idle_timeout: Duration,
    /// How far the approach and retract points lie from the seam's first
    /// and last waypoints, back along the torch axis, mm.
    pub approach_offset_mm: f64,
}

/// The defaults, stated once: [`file::TextLinkSection::default`] writes
/// them the file's way.
impl Default for TextLinkConfig {
    fn default() -> Self {
        TextLinkConfig {
            listen: Some(SocketAddr::from(([127, 0, 0, 1], 7303))),
            allow: Vec::new(),
            max_connections: 8,
            dialect: None,
            max_line_bytes: 256,
            line_timeout: Duration::from_millis(5_000),
            idle_timeout: Duration::from_millis(600_000),
            approach_offset_mm: 50.0,
        }
    }
}

/// The shortest line limit: a plan line of a quaternion pose and a groove
/// depth written with a few decimals.
pub const MIN_LINE_BYTES: u64 = 80;
/// The longest: far above any robot string, small enough to hold per session.
pub const MAX_LINE_BYTES: u64 = 4096;

impl file::TextLinkSection {
    /// Checks the `[text_link]` section and builds its typed values.
    pub fn validate(&self) -> Result<TextLinkConfig, ConfigError> {
        let t = self;
        let listen = match t.listen.as_str() {
            "" => None,
            text => Some(socket_addr("text_link.listen", text)?),
        };
        count_in("text_link.max_connections", t.max_connections.into(), 1, 1024)?;
        let dialect = match t.dialect.as_str() {
            "" => None,
            name => Some(Dialect::from_name(name).ok_or_else(|| ConfigError::Invalid {
                key: "text_link.dialect",
                message: format!(
                    "unknown dialect {name:?}; expected \"\" (the robot names it), ur, abb, kuka or fanuc"
                ),
            })?),
        };
        count_in("text_link.max_line_bytes", t.max_line_bytes, MIN_LINE_BYTES, MAX_LINE_BYTES)?;
        count_in("text_link.line_timeout_ms", t.line_timeout_ms, 10, 3_600_000)?;
        check("text_link.idle_timeout_ms", t.idle_timeout_ms <= 86_400_000, || {
            format!("must lie in [0 (never), 86400000] ms, got {}", t.idle_timeout_ms)
        })?;
        in_range("text_link.approach_offset_mm", t.approach_offset_mm, 0.0, 1_000.0)?;
        Ok(TextLinkConfig {
            listen,
            allow: ip_list("text_link.allow", &t.allow)?,
            max_connections: t.max_connections as usize,
            dialect,
            max_line_bytes: t.max_line_bytes as usize,
            line_timeout: Duration::from_millis(t.line_timeout_ms),
            idle_timeout: Duration::from_millis(t.idle_timeout_ms),
            approach_offset_mm: t.approach_offset_mm,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::config::Config;

    #[test]
    fn bad_values_name_their_key() {
        for (text, key) in [
            ("[text_link]\nlisten = \"7303\"\n", "text_link.listen"),
            ("[text_link]\ndialect = \"staubli\"\n", "text_link.dialect"),
            ("[text_link]\nmax_line_bytes = 10\n", "text_link.max_line_bytes"),
            ("[text_link]\napproach_offset_mm = -1.0\n", "text_link.approach_offset_mm"),
            ("[text_link]\nallow = [\"robot\"]\n", "text_link.allow"),
            ("[text_link]\nmax_connections = 0\n", "text_link.max_connections"),
        ] {
            let e = Config::parse(text, "c.toml").unwrap_err().to_string();
            assert!(e.contains(key), "{text:?} gave {e}");
        }
        let c = Config::parse("[text_link]\nlisten = \"\"\ndialect = \"ABB\"\n", "c.toml").unwrap();
        assert_eq!((c.text_link.listen, c.text_link.dialect), (None, Some(weldseam_proto::text::Dialect::Abb)));
    }
}
