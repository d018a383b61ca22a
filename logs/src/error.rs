//! [`LogError`]: a log no reader can read. Here, at the bottom of the
//! layers, because both the readers and navguard's streaming audit raise it
//! (navguard re-exports it as `navguard::error::LogError`).

/// Where in a log a [`LogError`] was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogPos {
    /// The file as a whole (a binary log's errors say how many bytes or
    /// messages were read in their message).
    File,
    /// The header row of a navlog CSV.
    Header,
    /// A line of a navlog CSV, counted from 1 (comments and blank lines
    /// count).
    Line(u64),
}

/// A log that cannot be read: which reader gave up, where, on which column,
/// and why. Raised only when nothing usable can be read (a reader copes with
/// everything else and says so in its warnings). Displays as today's
/// one-line messages: `line 3, column 'lat': cannot parse "abc" as a
/// number`, `header: column 'lat' appears twice`, `ULog header truncated (7
/// of 16 bytes)`, with `not a ULog or DataFlash log, and not a navlog CSV: `
/// in front when the file was read as a CSV only because it is neither
/// binary format.
#[derive(Clone, Debug, PartialEq)]
pub struct LogError {
    /// The reader: `"csv"`, `"ulog"` or `"dataflash"` (as `LogData::format`).
    pub format: &'static str,
    /// Where in the file.
    pub pos: LogPos,
    /// The CSV column concerned, as named in the header (e.g. `"lat"`).
    pub column: Option<String>,
    /// What was wrong, including the offending value or the byte counts.
    pub message: String,
    /// True when the file is not recognised as any format: it was read as a
    /// CSV because it is neither a ULog nor a DataFlash log.
    pub unrecognised: bool,
}

impl LogError {
    /// An error about the file as a whole.
    pub fn file(format: &'static str, message: impl Into<String>) -> Self {
        LogError { format, pos: LogPos::File, column: None, message: message.into(), unrecognised: false }
    }

    /// An error at `pos` of a navlog CSV, on `column` if one is named.
    pub fn csv(pos: LogPos, column: Option<&str>, message: impl Into<String>) -> Self {
        LogError { format: "csv", pos, column: column.map(str::to_string), message: message.into(), unrecognised: false }
    }

    /// The same error, for a file that no reader recognised.
    pub fn unrecognised(self) -> Self {
        LogError { unrecognised: true, ..self }
    }

    /// The CSV line, if the error is on one.
    pub fn line(&self) -> Option<u64> {
        match self.pos {
            LogPos::Line(n) => Some(n),
            _ => None,
        }
    }
}

impl core::fmt::Display for LogError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.unrecognised {
            f.write_str("not a ULog or DataFlash log, and not a navlog CSV: ")?;
        }
        match (self.pos, &self.column) {
            (LogPos::File, _) => write!(f, "{}", self.message),
            (LogPos::Header, Some(c)) => write!(f, "header: column '{c}' {}", self.message),
            (LogPos::Header, None) => write!(f, "header: {}", self.message),
            (LogPos::Line(n), Some(c)) => write!(f, "line {n}, column '{c}': {}", self.message),
            (LogPos::Line(n), None) => write!(f, "line {n}: {}", self.message),
        }
    }
}

impl std::error::Error for LogError {}

/// Callers that carry errors as text (the streaming audit) take a log
/// error with `?`, message unchanged.
impl From<LogError> for String {
    fn from(e: LogError) -> String {
        e.to_string()
    }
}
