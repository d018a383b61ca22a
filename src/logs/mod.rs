//! Flight-log readers. Each turns a file into fused [`Sample`] rows (one row
//! per sensor message, sorted by boot time), plus metadata and warnings.

use crate::sample::Sample;

pub mod csv;
pub mod dataflash;
pub mod ulog;

/// What a reader made of a log.
#[derive(Clone, Debug, Default)]
pub struct LogData {
    /// "csv", "ulog" or "dataflash".
    pub format: &'static str,
    /// Fused samples, sorted by `t` (s, the log's own boot clock).
    pub samples: Vec<Sample>,
    /// Vehicle and log metadata (key, value), e.g. ("sys_name", "PX4").
    pub meta: Vec<(String, String)>,
    /// Things the reader coped with: truncation, dropouts, unknown columns.
    pub warnings: Vec<String>,
    /// Detector inputs the log lacks: any of "gps", "imu", "attitude", "baro".
    pub missing: Vec<String>,
    /// Message counts per topic or message type (ULog: "topic" or "topic/multi_id").
    pub topic_counts: Vec<(String, u64)>,
}

/// Read any supported log, recognised by content (not by file name).
pub fn read_any(bytes: &[u8]) -> Result<LogData, String> {
    if ulog::is_ulog(bytes) {
        return ulog::read_ulog(bytes);
    }
    if dataflash::is_dataflash(bytes) {
        return dataflash::read_dataflash(bytes);
    }
    csv::read_csv(bytes).map_err(|e| format!("not a ULog or DataFlash log, and not a navlog CSV: {e}"))
}
