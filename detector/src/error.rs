//! Error types shared across modules, kept at the bottom of the layers so
//! both the modules that raise them and those that check with them can use
//! them without importing each other. Each domain's own error sits with its
//! domain: [`crate::detector::InputError`] (a bad row),
//! [`crate::filter::FilterError`] (the filter refused an update),
//! [`crate::snapshot::SnapshotError`] and `navguard::tight::TightError` (the lab).
//! [`LogError`] (a log no reader can read) is the log readers' own
//! (crate `navguard-logs`), re-exported here because the streaming audit
//! raises it too.

/// A config that does not check: names the field (as users spell it,
/// camelCase; empty for the config as a whole) and what was wrong with the
/// value. Displays as `config.<field>: <message>` (or `config: <message>`).
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError {
    /// The field, e.g. `"tc"`, `"gpsPosSigma"`; empty for the whole config.
    pub field: String,
    /// What was wrong, including the offending value.
    pub message: String,
}

impl ConfigError {
    /// An error on `field` (empty: the whole config).
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigError { field: field.into(), message: message.into() }
    }
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.field.is_empty() {
            write!(f, "config: {}", self.message)
        } else {
            write!(f, "config.{}: {}", self.field, self.message)
        }
    }
}

impl std::error::Error for ConfigError {}

/// Callers that still carry errors as text (the detector's own checks)
/// take a config error with `?`, message unchanged.
impl From<ConfigError> for String {
    fn from(e: ConfigError) -> String {
        e.to_string()
    }
}

pub use navguard_logs::error::{LogError, LogPos};
