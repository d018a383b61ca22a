//! Detector configuration: a loose input form (every field optional, as JS
//! passes it) validated once into [`Config`]. Errors name the field and value.

use serde::{Deserialize, Serialize};

use crate::filter::FilterNoise;
use crate::indicators::IndicatorSettings;
use crate::methods::Method;

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

fn num(field: &str, v: Option<f64>, lo: f64, hi: f64, default: f64) -> Result<f64, ConfigError> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(x),
        Some(x) => Err(ConfigError::new(field, format!("must be a number in [{lo}, {hi}], got {x}"))),
    }
}

fn int(field: &str, v: Option<f64>, lo: usize, hi: usize, default: usize) -> Result<usize, ConfigError> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 => Ok(x as usize),
        Some(x) => Err(ConfigError::new(field, format!("must be an integer in {lo}..={hi}, got {x}"))),
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
    pub fn check_field_name(name: &str) -> Result<(), ConfigError> {
        if Self::FIELDS.contains(&name) {
            Ok(())
        } else {
            Err(ConfigError::new(name, format!("unknown field (known: {})", Self::FIELDS.join(", "))))
        }
    }

    /// Validate into a [`Config`].
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

    /// Check a config given as JSON data (the wasm facade copies a JS
    /// object into this form first, reading every field once).
    pub fn from_value(v: serde_json::Value) -> Result<Config, ConfigError> {
        let serde_json::Value::Object(map) = v else {
            return Err(ConfigError::new("", "must be a JSON object"));
        };
        // Field by field first, so a type error names its field.
        for (k, val) in &map {
            Self::check_field_name(k)?;
            let one = serde_json::Value::Object([(k.clone(), val.clone())].into_iter().collect());
            serde_json::from_value::<ConfigInput>(one).map_err(|e| ConfigError::new(k.as_str(), e.to_string()))?;
        }
        let input: ConfigInput = serde_json::from_value(serde_json::Value::Object(map)).map_err(|e| ConfigError::new("", e.to_string()))?;
        input.check()
    }
}

impl Config {
    /// The input form that checks to this config (model aside): used to
    /// re-validate a config read back from a snapshot.
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
