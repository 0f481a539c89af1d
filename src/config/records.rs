//! The `[records]` section: where the daemon keeps a record of every plan
//! (the frame, the request, the configuration and the answer) and how
//! much of them, for `weldseam records` and `weldseam replay`.

use std::path::Path;

use serde::Deserialize;

use super::{ConfigError, check, count_in};

/// The plan records' store. An empty `dir` keeps none.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordsParams {
    pub dir: String,
    /// The most bytes the records may take; the oldest go first.
    pub max_bytes: u64,
    /// Records older than this go, whatever room is left.
    pub max_age_days: u32,
}

/// `records.max_bytes` unless configured: a day of a busy cell's full
/// 1920 x 1200 frames (27.6 MB each) is about 2000 plans.
pub const DEFAULT_RECORDS_MAX_BYTES: u64 = 64 << 30;

/// `records.max_age_days` unless configured: long enough for a quality
/// engineer to ask about last month's parts.
pub const DEFAULT_RECORDS_MAX_AGE_DAYS: u32 = 30;

/// The least `records.max_bytes`: room for one frame of the largest kind.
pub const MIN_RECORDS_MAX_BYTES: u64 = 64 << 20;

/// The most `records.max_bytes` may ask for: 16 TiB.
pub const MAX_RECORDS_MAX_BYTES: u64 = 16 << 40;

/// The longest `records.max_age_days`: ten years.
pub const MAX_RECORDS_AGE_DAYS: u32 = 3650;

impl Default for RecordsParams {
    fn default() -> Self {
        RecordsParams {
            dir: String::new(),
            max_bytes: DEFAULT_RECORDS_MAX_BYTES,
            max_age_days: DEFAULT_RECORDS_MAX_AGE_DAYS,
        }
    }
}

impl RecordsParams {
    /// Where the records go, when the daemon keeps them.
    pub fn directory(&self) -> Option<&Path> {
        (!self.dir.is_empty()).then(|| Path::new(&self.dir))
    }

    /// The limit on age.
    pub fn max_age(&self) -> std::time::Duration {
        std::time::Duration::from_secs(u64::from(self.max_age_days) * 86_400)
    }

    /// Checks the `[records]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        count_in("records.max_bytes", self.max_bytes, MIN_RECORDS_MAX_BYTES, MAX_RECORDS_MAX_BYTES)?;
        count_in("records.max_age_days", self.max_age_days.into(), 1, MAX_RECORDS_AGE_DAYS.into())?;
        check("records.dir", !self.dir.contains('\0'), || "must not contain a NUL character".into())
    }
}
