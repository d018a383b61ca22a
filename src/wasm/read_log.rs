//! `readLog`: a log (navlog CSV, PX4 ULog, ArduPilot DataFlash) read into
//! columns. Core module, with the detector: `new Detector()` plus `readLog`
//! is what a page or a script needs first.

use js_sys::{Float64Array, Object};
use wasm_bindgen::prelude::*;

use super::interop::{self as js_in, array_of, err, set, string_pairs, strings, Obj, MAX_BYTES};
use crate::detector::column_of_rows;
use crate::logs;
use crate::sample::COLUMNS;

#[wasm_bindgen(typescript_custom_section)]
const TS_READ_LOG: &'static str = r#"
export interface LogColumns { format: string; rows: number; columns: Partial<Record<keyof NavSample, Float64Array>>; warnings: string[]; missing: string[]; meta: [string, string][]; topicCounts: [string, number][] }
"#;

/// Parse a log into columns (for plotting): `{ format, columns: {name: Float64Array}, warnings, missing, meta }`.
#[wasm_bindgen(js_name = readLog, unchecked_return_type = "LogColumns")]
pub fn read_log(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue) -> Result<JsValue, JsError> {
    let bytes = js_in::bytes(bytes, MAX_BYTES, "readLog: bytes").map_err(err)?;
    let log = logs::read_any(&bytes)?;
    let cols = Object::new();
    let mut buf = Vec::new();
    for (i, name) in COLUMNS.iter().enumerate() {
        if column_of_rows(&log.samples, i, &mut buf) {
            set(&cols, name, &Float64Array::from(&buf[..]).into());
        }
    }
    let topics = array_of(&log.topic_counts, |(k, n)| js_sys::Array::of2(&JsValue::from_str(k), &JsValue::from_f64(*n as f64)).into());
    Ok(Obj::new()
        .s("format", log.format)
        .n("rows", log.samples.len() as f64)
        .v("warnings", &strings(&log.warnings))
        .v("missing", &strings(&log.missing))
        .v("meta", &string_pairs(&log.meta))
        .v("topicCounts", &topics)
        .v("columns", &cols.into())
        .done())
}
