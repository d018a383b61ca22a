//! Detector configuration: a loose input form (every field optional, as JS
//! passes it) validated once into [`Config`]. Errors name the field and value.

use serde::{Deserialize, Serialize};

use crate::filter::FilterNoise;
use crate::indicators::IndicatorSettings;
use crate::methods::Method;
use navguard_logs::decimal::Shortest;

pub use crate::error::ConfigError;

/// What users pass (JSON / JS object, camelCase). Unknown fields are rejected.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "camelCase")]
pub struct ConfigInput {
    /// Detection method (see [`crate::methods`]): "anfis" (default), "chi2",
    /// "nis", "gate", "mahalanobis", "rms", "knee", "adaptive".
    pub method: Option<String>,
    /// Training condition: retrain after this many new fault epochs.
    pub tc: Option<f64>,
    /// Length of each database D1, D2 (epochs).
    pub q: Option<f64>,
    /// Indicator window (GPS epochs).
    pub window: Option<f64>,
    /// F-indicator decision threshold.
    pub threshold: Option<f64>,
    /// Online retraining on/off.
    pub retrain: Option<bool>,
    /// GPS horizontal position noise, m.
    pub gps_pos_sigma: Option<f64>,
    /// GPS vertical position noise, m.
    pub gps_alt_sigma: Option<f64>,
    /// GPS velocity noise, m/s.
    pub gps_vel_sigma: Option<f64>,
    /// Barometer noise, m.
    pub baro_sigma: Option<f64>,
    /// Accelerometer noise for the INS prediction, m/s².
    pub accel_noise: Option<f64>,
    /// Acceleration noise of the constant-velocity model (GPS only), m/s².
    pub cv_accel_noise: Option<f64>,
    /// Time without a fix that counts as an outage, s (default: auto from the GPS rate).
    pub outage_timeout: Option<f64>,
    /// Longest coast on rejected GPS before re-anchoring the filter, s.
    pub max_coast: Option<f64>,
    /// A pause with no rows at all longer than this is a logging gap, s.
    pub data_gap: Option<f64>,
    /// A trained model (as written by `navguard-train` / `trainFromCsv`).
    pub model: Option<crate::model::Model>,
}

/// Checked configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// Detection method (see [`crate::methods`]).
    pub method: Method,
    /// Training condition TC: retrain after this many new fault epochs.
    pub tc: usize,
    /// Length q of each database D1, D2 (epochs).
    pub q: usize,
    /// Indicator window (GPS epochs).
    pub window: usize,
    /// F-indicator decision threshold.
    pub threshold: f64,
    /// Online retraining on/off.
    pub retrain: bool,
    /// Filter noise (σ of each sensor).
    pub noise: FilterNoiseCfg,
    /// Time without a fix that counts as an outage, s (`None`: from the GPS rate).
    pub outage_timeout: Option<f64>,
    /// Longest coast on rejected GPS before re-anchoring the filter, s.
    pub max_coast: f64,
    /// A pause with no rows longer than this is a logging gap, s.
    pub data_gap: f64,
    /// A trained model (`None`: the embedded default).
    #[serde(skip)]
    pub model: Option<crate::model::Model>,
}

/// Serializable mirror of the filter noise (for reports).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterNoiseCfg {
    /// GPS horizontal position noise, m.
    pub gps_pos_sigma: f64,
    /// GPS vertical position noise, m.
    pub gps_alt_sigma: f64,
    /// GPS velocity noise, m/s.
    pub gps_vel_sigma: f64,
    /// Barometer noise, m.
    pub baro_sigma: f64,
    /// Accelerometer noise for the INS prediction, m/s².
    pub accel_noise: f64,
    /// Acceleration noise of the constant-velocity model (GPS only), m/s².
    pub cv_accel_noise: f64,
}

impl Default for Config {
    fn default() -> Self {
        // Defaults cannot fail validation; a test checks that.
        let d = FilterNoise::default();
        Config {
            method: Method::Anfis,
            tc: 100,
            q: 500,
            window: 10,
            threshold: 0.5,
            retrain: true,
            noise: FilterNoiseCfg {
                gps_pos_sigma: d.gps_pos_h,
                gps_alt_sigma: d.gps_pos_v,
                gps_vel_sigma: d.gps_vel,
                baro_sigma: d.baro,
                accel_noise: d.accel,
                cv_accel_noise: d.cv_accel,
            },
            outage_timeout: None,
            max_coast: 20.0,
            data_gap: 1.0,
            model: None,
        }
    }
}

#[inline]
fn num(field: &str, v: Option<f64>, lo: f64, hi: f64, default: f64) -> Result<f64, ConfigError> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(x),
        Some(x) => Err(ConfigError::new(field, format!("must be a number in [{}, {}], got {}", Shortest(lo), Shortest(hi), Shortest(x)))),
    }
}

#[inline]
fn int(field: &str, v: Option<f64>, lo: usize, hi: usize, default: usize) -> Result<usize, ConfigError> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 => Ok(x as usize),
        Some(x) => Err(ConfigError::new(field, format!("must be an integer in {lo}..={hi}, got {}", Shortest(x)))),
    }
}

impl ConfigInput {
    /// Field names as users spell them (camelCase).
    pub const FIELDS: [&'static str; 16] = [
        "method", "tc", "q", "window", "threshold", "retrain", "gpsPosSigma", "gpsAltSigma", "gpsVelSigma",
        "baroSigma", "accelNoise", "cvAccelNoise", "outageTimeout", "maxCoast", "dataGap", "model",
    ];

    /// Reject a field name that is not a config field (for front ends that
    /// deserialize field by field and so never see unknown keys).
    #[inline]
    pub fn check_field_name(name: &str) -> Result<(), ConfigError> {
        if Self::FIELDS.contains(&name) {
            Ok(())
        } else {
            Err(ConfigError::new(name, format!("unknown field (known: {})", Self::FIELDS.join(", "))))
        }
    }

    /// Validate into a [`Config`].
    #[inline]
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn check(&self) -> Result<Config, ConfigError> {
        let d = Config::default();
        let method = match &self.method {
            Some(m) => Method::parse(m)?,
            None => d.method,
        };
        let n = &d.noise;
        let outage_timeout = match self.outage_timeout {
            None => None,
            Some(x) => Some(num("outageTimeout", Some(x), 0.01, 3600.0, 0.0)?),
        };
        if let Some(m) = &self.model {
            m.check().map_err(|e| ConfigError::new("model", e))?;
        }
        Ok(Config {
            method,
            tc: int("tc", self.tc, 1, 1_000_000, d.tc)?,
            q: int("q", self.q, 10, 100_000, d.q)?,
            window: int("window", self.window, 2, 1000, d.window)?,
            threshold: num("threshold", self.threshold, -10.0, 10.0, d.threshold)?,
            retrain: self.retrain.unwrap_or(d.retrain),
            noise: FilterNoiseCfg {
                gps_pos_sigma: num("gpsPosSigma", self.gps_pos_sigma, 1e-3, 1000.0, n.gps_pos_sigma)?,
                gps_alt_sigma: num("gpsAltSigma", self.gps_alt_sigma, 1e-3, 1000.0, n.gps_alt_sigma)?,
                gps_vel_sigma: num("gpsVelSigma", self.gps_vel_sigma, 1e-4, 100.0, n.gps_vel_sigma)?,
                baro_sigma: num("baroSigma", self.baro_sigma, 1e-3, 1000.0, n.baro_sigma)?,
                accel_noise: num("accelNoise", self.accel_noise, 1e-4, 100.0, n.accel_noise)?,
                cv_accel_noise: num("cvAccelNoise", self.cv_accel_noise, 1e-3, 1000.0, n.cv_accel_noise)?,
            },
            outage_timeout,
            max_coast: num("maxCoast", self.max_coast, 0.1, 3600.0, d.max_coast)?,
            data_gap: num("dataGap", self.data_gap, 0.05, 3600.0, d.data_gap)?,
            model: self.model.clone(),
        })
    }

    /// Parse and check a JSON config text (`{}` or empty for defaults).
    pub fn from_json(text: &str) -> Result<Config, ConfigError> {
        if text.trim().is_empty() {
            return Ok(Config::default());
        }
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| ConfigError::new("", format!("not JSON: {e}")))?;
        Self::from_value(v)
    }

    /// Check a config given as serde_json data: the same reader as
    /// [`ConfigInput::from_data`], over the same data.
    pub fn from_value(v: serde_json::Value) -> Result<Config, ConfigError> {
        Self::from_data(Data::from(v))
    }

    /// Check a config given as plain data (the wasm facade copies a JS
    /// object into this form first, reading every field once). Each field
    /// is read by hand ([`input_of`]), not by serde's derive, and from
    /// [`Data`], not serde_json's `Value`: the core wasm module then carries
    /// neither a deserializer nor serde_json's value type and map (about
    /// 14 KB); the messages are serde's. An object's fields are taken in
    /// key order, as serde_json's map holds them.
    #[inline]
    pub fn from_data(v: Data) -> Result<Config, ConfigError> {
        let Data::Obj(mut fields) = v else {
            return Err(ConfigError::new("", "must be a JSON object"));
        };
        by_key(&mut fields);
        input_of(&fields)?.check()
    }
}

/// JSON-like data, as the config reader takes it: what JSON text or a JS
/// object holds. Numbers keep serde_json's three classes, which its
/// messages name ("integer `5`", "floating point `5.5`").
#[derive(Clone, Debug, PartialEq)]
pub enum Data {
    /// `null`.
    Null,
    /// `true` / `false`.
    Bool(bool),
    /// A non-negative integer.
    U(u64),
    /// A negative integer.
    I(i64),
    /// Any other (finite) number.
    F(f64),
    /// A string.
    Str(String),
    /// An array.
    Arr(Vec<Data>),
    /// An object's fields (a name at most once).
    Obj(Vec<(String, Data)>),
}

impl Data {
    #[inline]
    fn as_f64(&self) -> Option<f64> {
        match *self {
            Data::U(u) => Some(u as f64),
            Data::I(i) => Some(i as f64),
            Data::F(x) => Some(x),
            _ => None,
        }
    }

    /// Field `key` of an object (`None` for an absent field or a non-object).
    #[inline]
    fn get(&self, key: &str) -> Option<&Data> {
        let Data::Obj(fields) = self else { return None };
        fields.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// serde_json's data as [`Data`] (its map is already in key order).
impl From<serde_json::Value> for Data {
    fn from(v: serde_json::Value) -> Data {
        use serde_json::Value;
        match v {
            Value::Null => Data::Null,
            Value::Bool(b) => Data::Bool(b),
            Value::Number(n) => match (n.as_u64(), n.as_i64()) {
                (Some(u), _) => Data::U(u),
                (_, Some(i)) => Data::I(i),
                _ => Data::F(n.as_f64().unwrap_or(f64::NAN)),
            },
            Value::String(s) => Data::Str(s),
            Value::Array(a) => Data::Arr(a.into_iter().map(Data::from).collect()),
            Value::Object(m) => Data::Obj(m.into_iter().map(|(k, v)| (k, Data::from(v))).collect()),
        }
    }
}

/// Sort an object's fields by name, as serde_json's map iterates them. An
/// insertion sort: a config has at most 16 known fields (the first unknown
/// one is an error), and input already in order (serde_json's) costs one
/// pass; std's sort would add its code to the core module for that.
#[inline]
fn by_key(fields: &mut [(String, Data)]) {
    for i in 1..fields.len() {
        let mut j = i;
        while j > 0 && fields[j - 1].0 > fields[j].0 {
            fields.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// The [`ConfigInput`] that `fields` (in key order) spell: each field `null`
/// or absent for the default, else of its type. Fields are taken in order,
/// each name checked then its value, so with several bad fields the first
/// reported is the one serde reported; a type error names its field, with
/// serde_json's message for it.
#[inline]
fn input_of(fields: &[(String, Data)]) -> Result<ConfigInput, ConfigError> {
    use plain::*;
    let mut input = ConfigInput::default();
    let i = &mut input;
    for (k, v) in fields {
        ConfigInput::check_field_name(k)?;
        if matches!(v, Data::Null) {
            continue;
        }
        let e = |m| ConfigError::new(k.as_str(), m);
        let slot = match k.as_str() {
            "method" => {
                i.method = Some(string_of(v).map_err(e)?);
                continue;
            }
            "retrain" => {
                i.retrain = Some(bool_of(v).map_err(e)?);
                continue;
            }
            "model" => {
                i.model = Some(model_of(v).map_err(e)?);
                continue;
            }
            "tc" => &mut i.tc,
            "q" => &mut i.q,
            "window" => &mut i.window,
            "threshold" => &mut i.threshold,
            "gpsPosSigma" => &mut i.gps_pos_sigma,
            "gpsAltSigma" => &mut i.gps_alt_sigma,
            "gpsVelSigma" => &mut i.gps_vel_sigma,
            "baroSigma" => &mut i.baro_sigma,
            "accelNoise" => &mut i.accel_noise,
            "cvAccelNoise" => &mut i.cv_accel_noise,
            "outageTimeout" => &mut i.outage_timeout,
            "maxCoast" => &mut i.max_coast,
            "dataGap" => &mut i.data_gap,
            // check_field_name let only FIELDS through.
            _ => continue,
        };
        *slot = Some(f64_of(v).map_err(e)?);
    }
    Ok(input)
}

/// Plain data read into the config's types by hand, with the messages
/// serde_json gives for the same data (a test holds them to serde's).
mod plain {
    use super::Data;
    use crate::anfis::Anfis;
    use crate::model::Model;

    /// How serde_json names a value it did not expect.
    #[inline]
    fn unexpected(v: &Data) -> String {
        match v {
            Data::Null => "null".into(),
            Data::Bool(b) => format!("boolean `{b}`"),
            Data::U(u) => format!("integer `{u}`"),
            Data::I(i) => format!("integer `{i}`"),
            Data::F(x) => format!("floating point `{}`", float_text(*x)),
            // serde_json writes `{s:?}`; `quoted` is the same below U+0100
            // without std's Unicode tables (see `navguard_logs::text`).
            Data::Str(s) => format!("string {}", navguard_logs::text::quoted(s)),
            Data::Arr(_) => "sequence".into(),
            Data::Obj(_) => "map".into(),
        }
    }
    /// A float as serde_json writes it in messages: the shortest digits,
    /// fixed for decimal exponents -5..=15 (`1000.0`, `0.00001`), else
    /// `1.5e+16`, `1e-7`. Built from bytes: str slicing's panic path would
    /// bring std's Unicode tables into the core module.
    #[inline]
    fn float_text(x: f64) -> String {
        // `{:e}` of |x|: the shortest digits, a dot after the first, `e`,
        // the exponent.
        let sci = navguard_logs::decimal::Sci(x.abs()).to_string();
        let mut digits = Vec::new();
        let mut exp = 0i32;
        let mut bytes = sci.bytes();
        for b in bytes.by_ref() {
            match b {
                b'0'..=b'9' => digits.push(b),
                b'e' => break,
                _ => {}
            }
        }
        let mut negative_exp = false;
        for b in bytes {
            match b {
                b'0'..=b'9' => exp = exp * 10 + i32::from(b - b'0'),
                _ => negative_exp = true,
            }
        }
        if negative_exp {
            exp = -exp;
        }
        let n = digits.len() as i32;
        let mut out = String::new();
        if x.is_sign_negative() {
            out.push('-');
        }
        let zeros = |out: &mut String, k: i32| (0..k).for_each(|_| out.push('0'));
        let push = |out: &mut String, d: &[u8]| d.iter().for_each(|&b| out.push(b as char));
        if (-5..=15).contains(&exp) {
            if n - 1 <= exp {
                push(&mut out, &digits);
                zeros(&mut out, exp - (n - 1));
                out.push_str(".0");
            } else if exp >= 0 {
                let (a, b) = digits.split_at(exp as usize + 1);
                push(&mut out, a);
                out.push('.');
                push(&mut out, b);
            } else {
                out.push_str("0.");
                zeros(&mut out, -exp - 1);
                push(&mut out, &digits);
            }
        } else {
            push(&mut out, &digits[..1]);
            if n > 1 {
                out.push('.');
                push(&mut out, &digits[1..]);
            }
            out.push_str(if exp >= 0 { "e+" } else { "e-" });
            out.push_str(&exp.abs().to_string());
        }
        out
    }

    #[inline]
    fn invalid(v: &Data, expected: &str) -> String {
        format!("invalid type: {}, expected {expected}", unexpected(v))
    }

    #[inline]
    pub fn f64_of(v: &Data) -> Result<f64, String> {
        v.as_f64().ok_or_else(|| invalid(v, "f64"))
    }

    #[inline]
    pub fn string_of(v: &Data) -> Result<String, String> {
        match v {
            Data::Str(s) => Ok(s.clone()),
            _ => Err(invalid(v, "a string")),
        }
    }

    #[inline]
    pub fn bool_of(v: &Data) -> Result<bool, String> {
        match *v {
            Data::Bool(b) => Ok(b),
            _ => Err(invalid(v, "a boolean")),
        }
    }

    /// `[f64; N]`: elements first, then the length (as serde reads them).
    #[inline]
    fn array_of<const N: usize>(v: &Data) -> Result<[f64; N], String> {
        let Data::Arr(a) = v else { return Err(invalid(v, &format!("an array of length {N}"))) };
        let mut out = [0.0; N];
        for (i, o) in out.iter_mut().enumerate() {
            *o = f64_of(a.get(i).ok_or_else(|| format!("invalid length {i}, expected an array of length {N}"))?)?;
        }
        if a.len() > N {
            return Err(format!("invalid length {}, expected fewer elements in array", a.len()));
        }
        Ok(out)
    }

    /// `[[f64; N]; K]`.
    #[inline]
    fn rows_of<const N: usize, const K: usize>(v: &Data) -> Result<[[f64; N]; K], String> {
        let Data::Arr(a) = v else { return Err(invalid(v, &format!("an array of length {K}"))) };
        let mut out = [[0.0; N]; K];
        for (i, o) in out.iter_mut().enumerate() {
            *o = array_of(a.get(i).ok_or_else(|| format!("invalid length {i}, expected an array of length {K}"))?)?;
        }
        if a.len() > K {
            return Err(format!("invalid length {}, expected fewer elements in array", a.len()));
        }
        Ok(out)
    }

    #[inline]
    fn pairs_of(v: &Data) -> Result<Vec<[f64; 2]>, String> {
        let Data::Arr(a) = v else { return Err(invalid(v, "a sequence")) };
        a.iter().map(array_of).collect()
    }

    /// A struct's fields: those present read in key order (serde_json's
    /// map order), then the first missing one in declaration order.
    #[inline]
    fn required<T>(v: Option<T>, name: &str) -> Result<T, String> {
        v.ok_or_else(|| format!("missing field `{name}`"))
    }

    #[inline]
    fn anfis_of(v: &Data) -> Result<Anfis, String> {
        let Data::Obj(_) = v else { return Err(invalid(v, "struct Anfis")) };
        // Key order: centre, conseq, sigma.
        let centre = v.get("centre").map(rows_of).transpose()?;
        let conseq = v.get("conseq").map(rows_of).transpose()?;
        let sigma = v.get("sigma").map(rows_of).transpose()?;
        Ok(Anfis { centre: required(centre, "centre")?, sigma: required(sigma, "sigma")?, conseq: required(conseq, "conseq")? })
    }

    #[inline]
    pub fn model_of(v: &Data) -> Result<Model, String> {
        let Data::Obj(_) = v else { return Err(invalid(v, "struct Model")) };
        // Key order: anfis, d1, d2, provenance (declaration order too).
        let anfis = v.get("anfis").map(anfis_of).transpose()?;
        let d1 = v.get("d1").map(pairs_of).transpose()?;
        let d2 = v.get("d2").map(pairs_of).transpose()?;
        let provenance = v.get("provenance").map(string_of).transpose()?.unwrap_or_default();
        Ok(Model { anfis: required(anfis, "anfis")?, d1: required(d1, "d1")?, d2: required(d2, "d2")?, provenance })
    }
}

impl Config {
    /// The input form that checks to this config (model aside): used to
    /// re-validate a config read back from a snapshot.
    #[inline]
    pub fn to_input(&self) -> ConfigInput {
        let n = &self.noise;
        ConfigInput {
            method: Some(self.method.name().to_string()),
            tc: Some(self.tc as f64),
            q: Some(self.q as f64),
            window: Some(self.window as f64),
            threshold: Some(self.threshold),
            retrain: Some(self.retrain),
            gps_pos_sigma: Some(n.gps_pos_sigma),
            gps_alt_sigma: Some(n.gps_alt_sigma),
            gps_vel_sigma: Some(n.gps_vel_sigma),
            baro_sigma: Some(n.baro_sigma),
            accel_noise: Some(n.accel_noise),
            cv_accel_noise: Some(n.cv_accel_noise),
            outage_timeout: self.outage_timeout,
            max_coast: Some(self.max_coast),
            data_gap: Some(self.data_gap),
            model: None,
        }
    }

    /// The filter noise in the filter's own form.
    pub fn filter_noise(&self) -> FilterNoise {
        let n = &self.noise;
        FilterNoise {
            accel: n.accel_noise,
            cv_accel: n.cv_accel_noise,
            gps_pos_h: n.gps_pos_sigma,
            gps_pos_v: n.gps_alt_sigma,
            gps_vel: n.gps_vel_sigma,
            baro: n.baro_sigma,
            ..FilterNoise::default()
        }
    }

    /// The indicator settings this config implies (its window).
    pub fn indicator_settings(&self) -> IndicatorSettings {
        IndicatorSettings { window: self.window, ..IndicatorSettings::default() }
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate() {
        assert_eq!(ConfigInput::default().check().unwrap(), Config::default());
        assert_eq!(ConfigInput::from_json("{}").unwrap(), Config::default());
    }

    /// The hand-written reader gives what serde's derive of `ConfigInput`
    /// gave (the reader before it): the same config, or the same message,
    /// for every field's wrong types and a model broken every way.
    #[test]
    fn hand_reader_matches_serde() {
        use serde_json::{json, Value};
        let model: Value = serde_json::from_str(include_str!("default_model.json")).unwrap();
        let with = |path: &[&str], v: Value| {
            let mut m = model.clone();
            let mut at = &mut m;
            for k in &path[..path.len() - 1] {
                at = match k.parse::<usize>() {
                    Ok(i) => &mut at[i],
                    Err(_) => &mut at[*k],
                };
            }
            let last = path[path.len() - 1];
            match (last.parse::<usize>(), at) {
                (Ok(i), Value::Array(a)) => a[i] = v,
                (_, Value::Object(o)) if v.is_null() && last.starts_with('-') => {
                    o.remove(&last[1..]);
                }
                (_, Value::Object(o)) => {
                    o.insert(last.to_string(), v);
                }
                _ => panic!("bad path {path:?}"),
            }
            m
        };
        let bad_values = [json!(5), json!(-5), json!(5.5), json!(1e300), json!(-1.5e16), json!(1.25e15), json!(0.00001), json!(1.5e-7), json!(-0.000123), json!(true), json!("x\"y"), json!([1]), json!({"a": 1}), json!(null)];
        let mut cases = vec![];
        for f in ConfigInput::FIELDS {
            // One deliberate difference: serde also read a struct from an
            // array of its fields in order; the hand reader wants the
            // object (`invalid type: sequence, expected struct Model`).
            for v in bad_values.iter().filter(|v| !(f == "model" && v.is_array())) {
                cases.push(json!({ f: v }));
            }
        }
        // Several bad fields: the first in key order, names checked as met
        // (as the serde path did).
        let first = |t: &str| ConfigInput::from_json(t).unwrap_err().field;
        assert_eq!(first(r#"{"tc": "x", "retrain": 5}"#), "retrain");
        assert_eq!(first(r#"{"aaa": 1, "tc": "x"}"#), "aaa");
        assert_eq!(first(r#"{"method": 5, "zzz": 1}"#), "method");
        assert_eq!(
            ConfigInput::from_json(r#"{"model": [1]}"#).unwrap_err().to_string(),
            "config.model: invalid type: sequence, expected struct Model"
        );
        for v in [
            with(&["anfis", "centre", "0"], json!([1, 2])),
            with(&["anfis", "centre", "0"], json!([1, 2, 3, 4])),
            with(&["anfis", "centre", "1", "2"], json!("x")),
            with(&["anfis", "sigma"], json!([[1, 2, 3]])),
            with(&["anfis", "sigma"], json!([[1, 2, 3], [1, 2, 3], [1, 2, 3]])),
            with(&["anfis", "-conseq"], json!(null)),
            with(&["anfis", "-centre"], json!(null)),
            with(&["anfis", "conseq"], json!(7)),
            with(&["anfis", "-centre"], json!(null)),
            with(&["d1", "3"], json!([1, 2, 3])),
            with(&["d1", "3"], json!([1])),
            with(&["d1", "3"], json!({})),
            with(&["d2"], json!({})),
            with(&["-d2"], json!(null)),
            with(&["-anfis"], json!(null)),
            with(&["-provenance"], json!(null)),
            with(&["provenance"], json!(null)),
            with(&["provenance"], json!(5)),
            with(&["extra"], json!([1, 2])),
            with(&["d1"], json!([])),
            model.clone(),
        ] {
            cases.push(json!({ "model": v, "tc": 3 }));
        }
        cases.push(json!({ "method": "chi2", "tc": 7, "q": 20, "retrain": false, "outageTimeout": 2.5, "model": null }));
        for case in cases {
            let ours = ConfigInput::from_value(case.clone());
            let serde = serde_json::from_value::<ConfigInput>(case.clone()).map_err(|e| e.to_string());
            match (&ours, serde) {
                (Ok(c), Ok(input)) => assert_eq!(Ok(c.clone()), input.check(), "{case}"),
                (Err(e), Err(m)) => assert_eq!(e.message, m, "{case}"),
                (Err(e), Ok(input)) => assert_eq!(Err(e.clone()), input.check(), "{case}"),
                (Ok(_), Err(m)) => panic!("{case}: serde refused it ({m}), the hand reader did not"),
            }
        }
    }

    #[test]
    fn errors_name_field_and_value() {
        let e = ConfigInput::from_json(r#"{"tc": 0}"#).unwrap_err();
        assert_eq!(e, ConfigError::new("tc", "must be an integer in 1..=1000000, got 0"));
        assert_eq!(e.to_string(), "config.tc: must be an integer in 1..=1000000, got 0");
        let e = e.to_string();
        assert!(e.contains("config.tc") && e.contains("got 0"), "{e}");
        let e = ConfigInput::from_json(r#"{"window": 2.5}"#).unwrap_err().to_string();
        assert!(e.contains("config.window") && e.contains("2.5"), "{e}");
        assert!(ConfigInput::check_field_name("bogus").unwrap_err().to_string().contains("config.bogus"));
        assert!(ConfigInput::FIELDS.iter().all(|f| ConfigInput::check_field_name(f).is_ok()));
        // Every declared field round-trips through serde (FIELDS matches the struct).
        for f in ConfigInput::FIELDS {
            let v = match f { "method" => "\"anfis\"", "retrain" => "true", "model" => "null", _ => "1" };
            let r = ConfigInput::from_json(&format!("{{\"{f}\": {v}}}"));
            assert!(!r.as_ref().is_err_and(|e| e.message.contains("unknown field")), "{f}: {r:?}");
        }
        let e = ConfigInput::from_json(r#"{"bogus": 1}"#).unwrap_err().to_string();
        assert!(e.contains("bogus"), "{e}");
        let e = ConfigInput::from_json(r#"{"method": "magic"}"#).unwrap_err().to_string();
        assert!(e.contains("config.method") && e.contains("magic"), "{e}");
        let e = ConfigInput::from_json(r#"{"gpsPosSigma": -1}"#).unwrap_err().to_string();
        assert!(e.contains("config.gpsPosSigma") && e.contains("-1"), "{e}");
        // Whole-config errors have no field.
        assert_eq!(ConfigInput::from_json("[1]").unwrap_err().to_string(), "config: must be a JSON object");
        assert!(ConfigInput::from_json("{").unwrap_err().to_string().starts_with("config: not JSON: "));
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Config { method, tc, q, window, threshold, retrain, noise, outage_timeout, max_coast, data_gap } skip { model });
    impl_codec!(FilterNoiseCfg { gps_pos_sigma, gps_alt_sigma, gps_vel_sigma, baro_sigma, accel_noise, cv_accel_noise });
}
