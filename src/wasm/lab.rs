//! The lab module: simulators, the method comparison and model training.
//! Loaded by the package only when one of these is first used.

use wasm_bindgen::prelude::*;

use super::interop::{self as js_in, config_from, err, options, plain_of, to_js, MAX_BYTES, MAX_NAME};
use crate::logs;
use crate::sample::Sample;
use crate::sim;

#[wasm_bindgen(typescript_custom_section)]
const TS_LAB: &'static str = r#"
/** `battery`: run `flights` flights (default 48) of the randomised battery's split ("tune" or "eval") instead of the seeded one; `seeds` does not go with it. */
export interface CompareOptions { seeds?: number; methods?: string[]; battery?: "tune" | "eval"; flights?: number }
export interface CompareResult { comparison: object; markdown: string }
"#;

/// Simulate a built-in scenario by name (see `scenarioNames()`) into navlog CSV text.
#[wasm_bindgen]
pub fn simulate(#[wasm_bindgen(unchecked_param_type = "string")] name: &JsValue, #[wasm_bindgen(unchecked_param_type = "number")] seed: &JsValue) -> Result<String, JsError> {
    let seed = js_in::num(seed, "simulate: seed").map_err(err)?;
    let name = js_in::string(name, MAX_NAME, "simulate: name").map_err(err)?;
    if !(seed.is_finite() && seed >= 0.0 && seed.fract() == 0.0 && seed < 9.0e15) {
        return Err(err(format!("seed: must be a non-negative integer, got {seed}")));
    }
    let sc = sim::Scenario::preset(&name, seed as u64).map_err(err)?;
    let rows = sim::simulate(&sc).map_err(err)?;
    Ok(sim::to_csv(&sc, &rows))
}

/// Simulate a scenario given as an object (same fields as the `# scenario:` CSV comment).
#[wasm_bindgen(js_name = simulateScenario)]
pub fn simulate_scenario(#[wasm_bindgen(unchecked_param_type = "object")] scenario: JsValue) -> Result<String, JsError> {
    let sc: sim::Scenario = plain_of(&scenario, "scenario")?;
    let rows = sim::simulate(&sc).map_err(err)?;
    Ok(sim::to_csv(&sc, &rows))
}


fn js_clock() -> f64 {
    js_sys::Date::now() / 1000.0
}

/// Every `config.method` over a seeded battery of simulated flights (and any
/// real logs added), in steps for a progress bar: `new CompareRun({ seeds,
/// methods })`, `addLog(name, bytes)`, `step()` until it returns 1, then
/// `finish()` → `{ comparison, markdown }`.
#[wasm_bindgen]
pub struct CompareRun {
    run: Option<crate::compare::CompareRun>,
}

#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct CompareOptions {
    /// Number of seeds (1..=n), default 5.
    seeds: Option<f64>,
    methods: Option<Vec<String>>,
    /// The randomised battery's split instead of the seeded battery.
    battery: Option<String>,
    /// Flights of the randomised battery, default 48.
    flights: Option<f64>,
}

#[wasm_bindgen]
impl CompareRun {
    /// A comparison of `options.methods` (default: all) over `options.seeds`
    /// seeds of the seeded battery, or `options.flights` flights of the
    /// randomised battery's `options.battery` split.
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(js_name = options, unchecked_param_type = "CompareOptions | undefined")] opts: JsValue) -> Result<CompareRun, JsError> {
        let o: CompareOptions = options(&opts, "compare options")?;
        let methods = o
            .methods
            .unwrap_or_default()
            .iter()
            .map(|m| crate::methods::Method::parse(m).map_err(|e| e.to_string().replace("config.method", "compare options.methods")))
            .collect::<Result<Vec<_>, _>>()
            .map_err(err)?;
        if let Some(split) = &o.battery {
            let split = crate::battery::Split::parse(split).map_err(|e| err(format!("compare options.battery: {e}")))?;
            if o.seeds.is_some() {
                return Err(err("compare options.seeds: does not go with options.battery (use options.flights)"));
            }
            let n = o.flights.unwrap_or(48.0);
            if !(n.is_finite() && n.fract() == 0.0 && (1.0..=1000.0).contains(&n)) {
                return Err(err(format!("compare options.flights: must be an integer in 1..=1000, got {n}")));
            }
            let run = crate::compare::CompareRun::new_battery(split, n as u64, &methods, Some(js_clock)).map_err(err)?;
            return Ok(CompareRun { run: Some(run) });
        }
        if o.flights.is_some() {
            return Err(err("compare options.flights: goes with options.battery only"));
        }
        let n = o.seeds.unwrap_or(5.0);
        if !(n.is_finite() && n.fract() == 0.0 && (1.0..=100.0).contains(&n)) {
            return Err(err(format!("compare options.seeds: must be an integer in 1..=100, got {n}")));
        }
        let seeds: Vec<u64> = (1..=n as u64).collect();
        Ok(CompareRun { run: Some(crate::compare::CompareRun::new(&seeds, &methods, Some(js_clock)).map_err(err)?) })
    }

    /// Add a real log (any supported format) under `name`.
    #[wasm_bindgen(js_name = addLog)]
    pub fn add_log(&mut self, #[wasm_bindgen(unchecked_param_type = "string")] name: &JsValue, #[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue) -> Result<(), JsError> {
        let name = js_in::string(name, MAX_NAME, "CompareRun.addLog: name").map_err(err)?;
        let bytes = js_in::bytes(bytes, MAX_BYTES, "CompareRun.addLog: bytes").map_err(err)?;
        let log = logs::read_any(&bytes).map_err(|e| err(format!("{name}: {e}")))?;
        self.run.as_mut().ok_or_else(|| err("CompareRun: already finished"))?.add_log(&name, log);
        Ok(())
    }

    /// Run one (flight, method) pair; returns the fraction done.
    pub fn step(&mut self) -> Result<f64, JsError> {
        self.run.as_mut().ok_or_else(|| err("CompareRun: already finished"))?.step().map_err(err)
    }

    /// `{ comparison, markdown }` (runs what is left first).
    #[wasm_bindgen(unchecked_return_type = "CompareResult")]
    pub fn finish(&mut self) -> Result<JsValue, JsError> {
        let run = self.run.take().ok_or_else(|| err("CompareRun: already finished"))?;
        let c = run.finish().map_err(err)?;
        to_js(&CompareResult { markdown: crate::compare::markdown(&c), comparison: c })
    }
}

#[derive(serde::Serialize)]
struct CompareResult {
    comparison: crate::compare::Comparison,
    markdown: String,
}


/// Train a model from labelled navlog CSV files (an array of `Uint8Array`).
/// Pass the result as `config.model`.
#[wasm_bindgen(js_name = trainFromCsv, unchecked_return_type = "NavguardModel")]
pub fn train_from_csv(#[wasm_bindgen(unchecked_param_type = "Uint8Array[]")] files: JsValue, #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<JsValue, JsError> {
    let cfg = config_from(&config)?;
    let mut streams = vec![];
    for (i, f) in js_in::items(&files, 10_000, "trainFromCsv: files").map_err(err)?.iter().enumerate() {
        let bytes = js_in::bytes(f, MAX_BYTES, &format!("trainFromCsv: file {i}")).map_err(err)?;
        let log = logs::csv::read_csv(&bytes).map_err(|e| err(format!("trainFromCsv: file {i}: {e}")))?;
        streams.push(log.samples);
    }
    let refs: Vec<&[Sample]> = streams.iter().map(|s| s.as_slice()).collect();
    let model = crate::calibrate::train_model(&refs, &cfg, 42).map_err(err)?;
    to_js(&model)
}

