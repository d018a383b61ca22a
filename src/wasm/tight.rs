//! The tightly coupled GNSS/INS lab (Shen et al. 2022): `TightDetector`,
//! `tightSimulate`, `tightGanTrain`. Lab module.

use js_sys::{Object, Uint8Array};
use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::interop::{self as js_in, err, options, plain_of, to_js, MAX_BYTES, MAX_TEXT};
use crate::tight::fdi::Action;
use crate::tight::stream::{EpochOutput, Status, TightConfig};

#[wasm_bindgen(typescript_custom_section)]
const TS_TIGHT: &'static str = r#"
/** One epoch for the tightly coupled detector: IMU (rad/s, m/s^2) and pseudo-ranges (m); `pr: []` on IMU-only rows. */
export interface TightRow { t: number; gyro: [number, number, number]; accel: [number, number, number]; pr: { prn: number; pr: number }[] }
/** Fields that do not apply to a row are undefined, e.g. `faultyPrn` on a fault-free epoch or `ganScoreMax` for strategies other than `gan`. */
export interface TightOutput {
  t: number; status: "initializing" | "no-gnss" | "ok" | "fault"; faultyPrn?: number; statistic?: number;
  lambdaMax: number; rdpop?: number; action?: string; ganScoreMax?: number; nSats: number;
  positionNed: [number, number, number]; velocityNed: [number, number, number]; clockBiasM: number;
}
/** Tightly coupled detector configuration (see docs/tight.md); every field optional. */
export interface TightConfig { strategy?: string; [field: string]: unknown }
export interface TightSimulation { csv: string; config: TightConfig; faultyPrn: number; faultStart: number; faultEnd: number }
/** Options of `tightGanTrain` (all optional): fault-free training and calibration flights, GAN size. */
export interface GanTrainOptions { trainSeeds?: number[]; calibSeeds?: number[]; epochs?: number; hidden?: number; window?: number; alpha?: number }
export interface GanTrainProgress { epoch: number; epochs: number; dLoss: number; gLoss: number; dReal: number; dFake: number }
export interface GanTrainResult { model: Uint8Array; tau: number; m: number; lambda: number; t2: number; falseAlarm: number; trainWindows: number; calibWindows: number; parameters: number; table1: string }
"#;

/// One epoch's output as JS sees it (camelCase, like the rest of the API).
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct TightOutput<'a> {
    t: f64,
    status: &'a Status,
    faulty_prn: Option<u8>,
    statistic: Option<f64>,
    lambda_max: f64,
    rdpop: Option<f64>,
    action: Option<Action>,
    gan_score_max: Option<f64>,
    n_sats: usize,
    position_ned: [f64; 3],
    velocity_ned: [f64; 3],
    clock_bias_m: f64,
}

impl<'a> From<&'a EpochOutput> for TightOutput<'a> {
    fn from(o: &'a EpochOutput) -> Self {
        TightOutput {
            t: o.t,
            status: &o.status,
            faulty_prn: o.faulty_prn,
            statistic: o.statistic,
            lambda_max: o.lambda_max,
            rdpop: o.rdpop,
            action: o.action,
            gan_score_max: o.gan_score_max,
            n_sats: o.n_sats,
            position_ned: o.position_ned,
            velocity_ned: o.velocity_ned,
            clock_bias_m: o.clock_bias_m,
        }
    }
}

/// The tight config (parsed in one place for the constructor and `withGanModel`).
fn tight_config(v: &JsValue) -> Result<TightConfig, JsError> {
    options(v, "tight config")
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct TightSimulation {
    csv: String,
    config: TightConfig,
    faulty_prn: u8,
    fault_start: f64,
    fault_end: f64,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct GanTrainProgress {
    epoch: usize,
    epochs: usize,
    d_loss: f64,
    g_loss: f64,
    d_real: f64,
    d_fake: f64,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct GanTrainResult {
    #[serde(skip)]
    model: Vec<u8>,
    tau: f64,
    m: f64,
    lambda: f64,
    t2: f64,
    false_alarm: f64,
    train_windows: usize,
    calib_windows: usize,
    parameters: usize,
    table1: String,
}

/// The tightly coupled GNSS/INS detector of Shen et al. 2022 (see
/// `docs/tight.md`): one row per epoch `{ t, gyro: [x,y,z], accel: [x,y,z],
/// pr: [{ prn, pr }] }` (IMU-only rows have `pr: []`); each output names the
/// faulty satellite, if any.
#[wasm_bindgen(js_name = TightDetector)]
pub struct TightDetectorJs {
    inner: crate::tight::stream::TightDetector,
}

#[wasm_bindgen(js_class = TightDetector)]
impl TightDetectorJs {
    /// `new TightDetector(config)`: every field optional (see `docs/tight.md`).
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "TightConfig | undefined")] config: JsValue) -> Result<TightDetectorJs, JsError> {
        let cfg = tight_config(&config)?;
        Ok(TightDetectorJs { inner: crate::tight::stream::TightDetector::new(cfg).map_err(err)? })
    }

    /// One epoch row; returns `{ t, status, faultyPrn, statistic, lambdaMax, rdpop, action, nSats, positionNed, ... }`.
    #[wasm_bindgen(unchecked_return_type = "TightOutput")]
    pub fn push(&mut self, #[wasm_bindgen(unchecked_param_type = "TightRow")] row: JsValue) -> Result<JsValue, JsError> {
        let row: crate::tight::stream::EpochRow = plain_of(&row, "tight row")?;
        let out = self.inner.push(&row).map_err(err)?;
        to_js(&TightOutput::from(&out))
    }

    /// GAN-FDSR with a model from `tightGanTrain` (its `model` bytes) instead
    /// of the embedded one; `config` as for the constructor.
    #[wasm_bindgen(js_name = withGanModel)]
    pub fn with_gan_model(#[wasm_bindgen(unchecked_param_type = "TightConfig | undefined")] config: JsValue, #[wasm_bindgen(unchecked_param_type = "Uint8Array")] model: &JsValue) -> Result<TightDetectorJs, JsError> {
        let model = js_in::bytes(model, MAX_BYTES, "withGanModel: model").map_err(err)?;
        let cfg = tight_config(&config)?;
        let model = crate::tight::gan_fdsr::GanDetectorModel::from_bytes(&model).map_err(err)?;
        Ok(TightDetectorJs { inner: crate::tight::stream::TightDetector::with_gan(cfg, model).map_err(err)? })
    }

    /// Every row of a pseudo-range CSV (`pr_<prn>` or `sat_id` layout); an array of outputs.
    #[wasm_bindgen(js_name = pushCsv, unchecked_return_type = "TightOutput[]")]
    pub fn push_csv(&mut self, #[wasm_bindgen(unchecked_param_type = "string")] text: &JsValue) -> Result<JsValue, JsError> {
        let text = js_in::string(text, MAX_TEXT, "pushCsv: text").map_err(err)?;
        let rows = crate::tight::stream::parse_csv(&text).map_err(err)?;
        let out = self.inner.run(&rows).map_err(err)?;
        to_js(&out.iter().map(TightOutput::from).collect::<Vec<_>>())
    }
}

/// A simulated tightly coupled flight: environment `env` (1–5, the paper's
/// Table 3 plus Env 5), fault type 1–5 (Table 4; 0 = none), seed. Returns
/// `{ csv, config, faultyPrn, faultStart, faultEnd }`: feed `csv` to a
/// `new TightDetector(config)`.
#[wasm_bindgen(js_name = tightSimulate, unchecked_return_type = "TightSimulation")]
pub fn tight_simulate(
    #[wasm_bindgen(unchecked_param_type = "number")] env: &JsValue,
    #[wasm_bindgen(unchecked_param_type = "number", js_name = faultType)] fault_type: &JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] seed: &JsValue,
) -> Result<JsValue, JsError> {
    let small = |v: &JsValue, what: &str| -> Result<u32, JsError> {
        let x = js_in::num(v, what).map_err(err)?;
        Ok(if x.fract() == 0.0 && (0.0..=1e6).contains(&x) { x as u32 } else { u32::MAX })
    };
    let (env, fault_type) = (small(env, "tightSimulate: env")?, small(fault_type, "tightSimulate: faultType")?);
    let seed = js_in::num(seed, "tightSimulate: seed").map_err(err)?;
    use crate::tight::fdi::{FdsrConfig, Strategy};
    use crate::tight::scenario::{environments, run_with_rows, FaultSpec, FaultType, RunSpec, SimConfig, World};
    let cfg = SimConfig::default();
    let world = World::new(&cfg).map_err(err)?;
    let envs = environments(&world, &cfg).map_err(err)?;
    let e = envs.get((env as usize).wrapping_sub(1)).ok_or_else(|| err(format!("tightSimulate: env must be 1..={}, got {env}", envs.len())))?;
    let kind = match fault_type {
        0 => None,
        1 => Some(FaultType::Step20),
        2 => Some(FaultType::Step10),
        3 => Some(FaultType::Ramp1),
        4 => Some(FaultType::Ramp05),
        5 => Some(FaultType::Ramp03),
        k => return Err(err(format!("tightSimulate: fault type must be 0..=5, got {k}"))),
    };
    if !(seed.is_finite() && seed >= 0.0) {
        return Err(err(format!("tightSimulate: seed must be a non-negative number, got {seed}")));
    }
    let fault = kind.map(|kind| FaultSpec { prn: e.faulty_prn, kind, start: e.fault_start, end: e.fault_end });
    let spec = RunSpec {
        world: &world,
        cfg: &cfg,
        prns: &e.prns,
        watch_prn: e.faulty_prn,
        fault,
        fdsr: FdsrConfig { strategy: Strategy::Fdi, alpha: 0.001, eta: 0.035 },
        seed: seed as u64,
        gan: None,
    };
    let (_, rows, init) = run_with_rows(&spec).map_err(err)?;
    let tc = crate::tight::stream::TightConfig { t0: world.t0, strategy: Strategy::Fdi, initial: Some(init), ..Default::default() };
    to_js(&TightSimulation { csv: crate::tight::stream::to_csv(&rows), config: tc, faulty_prn: e.faulty_prn, fault_start: e.fault_start, fault_end: e.fault_end })
}

/// Train a GAN-FDSR model in the page (small models: a few flights and
/// epochs), as `navguard-gan train` does natively. `onProgress` is called
/// after every epoch with `{ epoch, epochs, dLoss, gLoss, dReal, dFake }`;
/// returning `false` cancels. The `model` bytes go to
/// `TightDetector.withGanModel`.
#[wasm_bindgen(js_name = tightGanTrain, unchecked_return_type = "GanTrainResult")]
pub fn tight_gan_train(
    #[wasm_bindgen(unchecked_param_type = "GanTrainOptions | undefined")] options: JsValue,
    #[wasm_bindgen(js_name = onProgress, unchecked_param_type = "((p: GanTrainProgress) => boolean | void) | undefined")] on_progress: JsValue,
) -> Result<JsValue, JsError> {
    use crate::tight::gan_fdsr_train::{train_detector, GanTrainOptions};
    use crate::tight::scenario::{environments, SimConfig, World};
    let mut opts = GanTrainOptions::default();
    // Small by default: the page trains in seconds, not minutes.
    opts.train_seeds = vec![101, 102];
    opts.calib_seeds = vec![201, 202];
    opts.gan.epochs = 5;
    if let Some(options) = js_in::given(&options) {
        let o: serde_json::Map<String, serde_json::Value> = plain_of(options, "tightGanTrain options")?;
        const KNOWN: [&str; 6] = ["trainSeeds", "calibSeeds", "epochs", "hidden", "window", "alpha"];
        if let Some(k) = o.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(err(format!("tightGanTrain options.{k}: unknown field (known: {})", KNOWN.join(", "))));
        }
        let seeds = |k: &str| -> Result<Option<Vec<u64>>, JsError> {
            let Some(v) = o.get(k) else { return Ok(None) };
            let arr: Vec<f64> = serde_json::from_value(v.clone()).map_err(|e| err(format!("tightGanTrain: {k}: {e}")))?;
            if arr.is_empty() || arr.iter().any(|x| !(x.is_finite() && *x >= 0.0 && x.fract() == 0.0)) {
                return Err(err(format!("tightGanTrain: {k} must be a non-empty array of non-negative integers, got {arr:?}")));
            }
            Ok(Some(arr.into_iter().map(|x| x as u64).collect()))
        };
        if let Some(s) = seeds("trainSeeds")? {
            opts.train_seeds = s;
        }
        if let Some(s) = seeds("calibSeeds")? {
            opts.calib_seeds = s;
        }
        for (k, slot, lo, hi) in [("epochs", &mut opts.gan.epochs, 1usize, 1000usize), ("hidden", &mut opts.gan.hidden, 1, 128), ("window", &mut opts.gan.window, 2, 200)] {
            let Some(v) = o.get(k) else { continue };
            match v.as_f64() {
                Some(x) if x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 => *slot = x as usize,
                _ => return Err(err(format!("tightGanTrain: {k} must be an integer in {lo}..={hi}, got {v}"))),
            }
        }
        if let Some(a) = o.get("alpha") {
            opts.alpha = a.as_f64().filter(|x| *x > 0.0 && *x < 1.0).ok_or_else(|| err(format!("tightGanTrain: alpha must be in (0, 1), got {a}")))?;
        }
    }
    let cb = on_progress.dyn_ref::<js_sys::Function>().cloned();
    let sim = SimConfig::default();
    let world = World::new(&sim).map_err(err)?;
    let envs = environments(&world, &sim).map_err(err)?;
    let prns = envs.first().ok_or_else(|| err("tightGanTrain: no environment"))?.prns.clone();
    let (model, report) = train_detector(&world, &sim, &prns, &opts, &mut |p| {
        let Some(f) = cb.as_ref() else { return true };
        let progress = GanTrainProgress { epoch: p.epoch, epochs: p.epochs, d_loss: p.d_loss, g_loss: p.g_loss, d_real: p.d_real, d_fake: p.d_fake };
        // A progress report that cannot be made, a throwing or a
        // `false`-returning callback cancels training.
        let Ok(o) = to_js(&progress) else { return false };
        match f.call1(&JsValue::NULL, &o) {
            Ok(v) => v.as_bool() != Some(false),
            Err(_) => false,
        }
    })
    .map_err(err)?;
    let bytes = model.to_bytes().map_err(err)?;
    let result = GanTrainResult {
        model: bytes,
        tau: report.tau as f64,
        m: report.m as f64,
        lambda: model.gan.lambda(),
        t2: model.gan.t2(),
        false_alarm: report.threshold.false_alarm,
        train_windows: report.train_windows,
        calib_windows: report.calib_windows,
        parameters: model.gan.param_count(),
        table1: crate::tight::chaos::table1_markdown(&report.chaos),
    };
    let out = to_js(&result)?;
    // Bytes as a Uint8Array (serde would make an array of numbers).
    js_in::set(out.unchecked_ref::<Object>(), "model", &Uint8Array::from(result.model.as_slice()).into());
    Ok(out)
}