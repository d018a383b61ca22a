//! Head-to-head comparison of every `config.method` on the same flights: a
//! battery of simulated flights (every fault kind at two magnitudes, the
//! paper's outage scenario in both variants, clean aggressive and survey
//! flights; each over several seeds) plus any real logs handed in.
//!
//! Per method: accuracy, false-alarm rate FP/(TP+FP), misdetection rate
//! FN/(TP+FN) and F2 pooled over the labelled GPS epochs of the fault
//! flights; false alarms per flight hour on the clean flights (an alarm is
//! a run of flagged GPS epochs); per fault kind, how many injected faults
//! were caught and the median detection delay. On real logs (no labels): the
//! share of GPS epochs flagged.
//!
//! The randomised development battery of issue 14 ([`crate::battery`]:
//! other noise models, rates, IMU grades, trajectories, fault kinds and
//! durations, boot clocks) is the other set of flights on offer
//! ([`CompareRun::new_battery`]); its `eval` split was never used to tune
//! anything.
//!
//! Runs incrementally ([`CompareRun::step`]) so a front end shows progress.

use serde::Serialize;

use crate::battery::{self, Split};
use crate::config::Config;
use crate::detector::Detector;
use crate::logs::LogData;
use crate::methods::Method;
use crate::metrics::{self, Metrics};
use crate::sample::Sample;
use crate::sim::{self, FaultKind, OutageMode, Scenario, Trajectory};

/// One simulated flight of the battery.
#[derive(Clone, Debug)]
pub struct Case {
    /// Group it is reported under: a fault kind name, "outage" or "clean".
    pub group: String,
    /// Readable label, e.g. "step 5 m".
    pub label: String,
    /// The simulated flight.
    pub flight: CaseFlight,
}

/// Where a case's rows come from.
#[derive(Clone, Debug)]
pub enum CaseFlight {
    /// The paper-style simulator (`sim`).
    Scenario(Scenario),
    /// A flight of the randomised development battery (`battery`).
    Battery(Box<battery::Flight>),
}

impl CaseFlight {
    fn simulate(&self) -> Result<Vec<Sample>, String> {
        match self {
            CaseFlight::Scenario(sc) => sim::simulate(sc),
            CaseFlight::Battery(f) => Ok(battery::simulate(f)),
        }
    }

    /// Length of the flight, s.
    fn duration(&self) -> f64 {
        match self {
            CaseFlight::Scenario(sc) => sc.duration,
            CaseFlight::Battery(f) => f.path.duration,
        }
    }
}

/// `n` flights of the randomised battery's `split` (indices 0..n), each
/// reported under its first fault's kind (with its axis where it has one:
/// `step-h`, `drag-off-v`) or "clean".
pub fn battery_cases(split: Split, n: u64) -> Vec<Case> {
    (0..n)
        .map(|i| {
            let f = battery::Flight::draw(split, i);
            let group = f.faults.first().map_or_else(|| "clean".to_string(), battery::kind_key);
            Case { group, label: f.describe(), flight: CaseFlight::Battery(Box::new(f)) }
        })
        .collect()
}

/// Fault magnitudes of the core issue: (kind, magnitudes, unit).
const KINDS: [(FaultKind, [f64; 2], &str); 7] = [
    (FaultKind::Step, [5.0, 20.0], "m"),
    (FaultKind::Ramp, [0.1, 1.0], "m/s"),
    (FaultKind::Noise, [3.0, 8.0], "m"),
    (FaultKind::Frozen, [0.0, 0.0], ""),
    (FaultKind::ZeroVelocity, [0.0, 0.0], ""),
    (FaultKind::BaroStuck, [0.0, 0.0], ""),
    (FaultKind::AccelBias, [0.3, 1.0], "m/s²"),
];

/// The battery for `seeds`.
pub fn battery(seeds: &[u64]) -> Vec<Case> {
    let mut out = vec![];
    for &seed in seeds {
        for (kind, mags, unit) in KINDS {
            let mags: &[f64] = if mags[0] == mags[1] { &mags[..1] } else { &mags[..] };
            for &m in mags {
                // Ramps need time to grow; the rest get 30 s.
                let len = if kind == FaultKind::Ramp { 60.0 } else { 30.0 };
                let label = if unit.is_empty() { kind.name().to_string() } else { format!("{} {m} {unit}", kind.name()) };
                out.push(Case { group: kind.name().into(), label, flight: CaseFlight::Scenario(Scenario::with_fault(kind, m, 120.0, len, seed)) });
            }
        }
        out.push(Case { group: "outage".into(), label: "paper (degraded fix)".into(), flight: CaseFlight::Scenario(Scenario::paper(OutageMode::Degraded, seed)) });
        out.push(Case { group: "outage".into(), label: "paper (silent)".into(), flight: CaseFlight::Scenario(Scenario::paper(OutageMode::Silent, seed)) });
        out.push(Case { group: "clean".into(), label: "clean aggressive".into(), flight: CaseFlight::Scenario(Scenario::clean(Trajectory::Aggressive, seed, 300.0)) });
        out.push(Case { group: "clean".into(), label: "clean survey".into(), flight: CaseFlight::Scenario(Scenario::clean(Trajectory::Survey, seed, 300.0)) });
    }
    out
}

/// Detection of one fault group by one method.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct KindResult {
    /// The fault group (a fault kind name or "outage").
    pub group: String,
    /// Faults of this group in the battery.
    pub faults: u64,
    /// Of those, detected while active.
    pub detected: u64,
    /// Median delay over the detected faults, s (NaN if none).
    pub median_delay_s: f64,
}

/// A real log's flagged share for one method.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct LogResult {
    /// The log's file name.
    pub name: String,
    /// GPS epochs evaluated.
    pub gps_epochs: u64,
    /// Share of them flagged.
    pub flagged_fraction: f64,
}

/// Everything measured for one method.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct MethodResult {
    /// The method's `config.method` name.
    pub method: &'static str,
    /// Pooled over the fault flights' labelled epochs.
    pub metrics: Metrics,
    /// Hours of clean flight run.
    pub clean_hours: f64,
    /// Alarm episodes on the clean flights.
    pub clean_alarms: u64,
    /// `clean_alarms / clean_hours`.
    pub false_alarms_per_hour: f64,
    /// Share of clean flights' GPS epochs flagged.
    pub clean_flagged_fraction: f64,
    /// Detection per fault group.
    pub kinds: Vec<KindResult>,
    /// Flagged share per real log given.
    pub logs: Vec<LogResult>,
    /// Rows processed per second by this method (whole battery, this machine).
    pub rows_per_s: f64,
}

/// The comparison.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Comparison {
    /// Simulator seeds of the battery (empty for the randomised battery).
    pub seeds: Vec<u64>,
    /// The randomised battery's split ("tune" or "eval"), when it was run.
    pub split: Option<&'static str>,
    /// Flights per method.
    pub flights: usize,
    /// One result per method compared.
    pub methods: Vec<MethodResult>,
}

#[derive(Default)]
struct Acc {
    rows: Vec<(f64, f64, u8)>,
    clean_s: f64,
    clean_alarms: u64,
    clean_epochs: u64,
    clean_flagged: u64,
    kinds: Vec<(String, u64, u64, Vec<f64>)>,
    logs: Vec<LogResult>,
    rows_done: u64,
    seconds: f64,
}

/// A comparison in progress.
pub struct CompareRun {
    methods: Vec<Method>,
    cases: Vec<Case>,
    logs: Vec<(String, LogData)>,
    seeds: Vec<u64>,
    split: Option<Split>,
    /// Samples of the current case (simulated once, run by every method).
    current: Option<(usize, Vec<Sample>)>,
    next: usize,
    acc: Vec<Acc>,
    /// Clock for rows/s, supplied by the caller (no std::time on wasm).
    clock: fn() -> f64,
}

fn no_clock() -> f64 {
    f64::NAN
}

impl CompareRun {
    /// `methods` empty = all. `clock` returns seconds (e.g. `performance.now()/1e3`), or None.
    pub fn new(seeds: &[u64], methods: &[Method], clock: Option<fn() -> f64>) -> Result<Self, String> {
        if seeds.is_empty() {
            return Err("compare: seeds must not be empty".into());
        }
        Ok(Self::with_cases(battery(seeds), seeds.to_vec(), None, methods, clock))
    }

    /// The same over `flights` flights (1..=1000) of the randomised
    /// battery's `split`.
    pub fn new_battery(split: Split, flights: u64, methods: &[Method], clock: Option<fn() -> f64>) -> Result<Self, String> {
        if !(1..=1000).contains(&flights) {
            return Err(format!("compare: flights must be in 1..=1000, got {flights}"));
        }
        Ok(Self::with_cases(battery_cases(split, flights), vec![], Some(split), methods, clock))
    }

    fn with_cases(cases: Vec<Case>, seeds: Vec<u64>, split: Option<Split>, methods: &[Method], clock: Option<fn() -> f64>) -> Self {
        let methods = if methods.is_empty() { Method::ALL.to_vec() } else { methods.to_vec() };
        CompareRun {
            acc: methods.iter().map(|_| Acc::default()).collect(),
            methods,
            cases,
            logs: vec![],
            seeds,
            split,
            current: None,
            next: 0,
            clock: clock.unwrap_or(no_clock),
        }
    }

    /// Add a real log (run by every method, reported by name).
    pub fn add_log(&mut self, name: &str, log: LogData) {
        self.logs.push((name.to_string(), log));
    }

    fn units(&self) -> usize {
        (self.cases.len() + self.logs.len()) * self.methods.len()
    }

    /// Fraction done, in [0, 1].
    pub fn progress(&self) -> f64 {
        let n = self.units();
        if n == 0 { 1.0 } else { self.next as f64 / n as f64 }
    }

    /// Whether every unit of work has run.
    pub fn done(&self) -> bool {
        self.next >= self.units()
    }

    /// Run one (flight, method) pair. Returns the fraction done.
    pub fn step(&mut self) -> Result<f64, String> {
        if self.done() {
            return Ok(1.0);
        }
        let nm = self.methods.len();
        let (item, mi) = (self.next / nm, self.next % nm);
        let method = self.methods[mi];
        let cfg = Config { method, ..Config::default() };
        if item < self.cases.len() {
            if self.current.as_ref().is_none_or(|(i, _)| *i != item) {
                let rows = self.cases[item].flight.simulate()?;
                self.current = Some((item, rows));
            }
            let rows = match &self.current {
                Some((_, r)) => r,
                None => return Err("compare: internal: no current flight".into()),
            };
            let t0 = (self.clock)();
            let out = run(cfg, rows)?;
            let dt = (self.clock)() - t0;
            let acc = &mut self.acc[mi];
            acc.rows_done += rows.len() as u64;
            acc.seconds += dt;
            let case = &self.cases[item];
            if case.group == "clean" {
                // The randomised battery's rates are pooled over every
                // flight, clean ones included (its own definition,
                // `docs/battery.md`): a method's alarms on healthy flights
                // count against its false-alarm rate and F2.
                if self.split.is_some() {
                    acc.rows.extend(rows.iter().zip(&out).filter(|(s, _)| !s.label.is_nan()).map(|(s, o)| (s.t, s.label, *o)));
                }
                acc.clean_s += case.flight.duration();
                let mut prev = 0u8;
                for (s, o) in rows.iter().zip(&out) {
                    if !s.label.is_nan() {
                        acc.clean_epochs += 1;
                        acc.clean_flagged += *o as u64;
                        acc.clean_alarms += (*o == 1 && prev == 0) as u64;
                        prev = *o;
                    }
                }
            } else {
                let mut delay = f64::NAN;
                let t: Vec<f64> = rows.iter().map(|s| s.t).collect();
                let label: Vec<f64> = rows.iter().map(|s| s.label).collect();
                let m = metrics::compute(&t, &label, &out);
                for (s, o) in rows.iter().zip(&out) {
                    if !s.label.is_nan() {
                        acc.rows.push((s.t, s.label, *o));
                    }
                }
                if m.detected_intervals > 0 {
                    delay = m.mean_detection_delay;
                }
                let k = match acc.kinds.iter().position(|k| k.0 == case.group) {
                    Some(k) => k,
                    None => {
                        acc.kinds.push((case.group.clone(), 0, 0, vec![]));
                        acc.kinds.len() - 1
                    }
                };
                let e = &mut acc.kinds[k];
                e.1 += m.fault_intervals;
                e.2 += m.detected_intervals;
                if delay.is_finite() {
                    e.3.push(delay);
                }
            }
        } else {
            let (name, log) = &self.logs[item - self.cases.len()];
            let out = run(cfg, &log.samples)?;
            let (mut epochs, mut flagged) = (0u64, 0u64);
            for (s, o) in log.samples.iter().zip(&out) {
                if s.has_fix() {
                    epochs += 1;
                    flagged += *o as u64;
                }
            }
            self.acc[mi].logs.push(LogResult {
                name: name.clone(),
                gps_epochs: epochs,
                flagged_fraction: if epochs > 0 { flagged as f64 / epochs as f64 } else { 0.0 },
            });
        }
        self.next += 1;
        Ok(self.progress())
    }

    /// Run what is left and summarise.
    pub fn finish(mut self) -> Result<Comparison, String> {
        while !self.done() {
            self.step()?;
        }
        let methods = self
            .methods
            .iter()
            .zip(self.acc)
            .map(|(m, a)| {
                let mut acc = metrics::Accumulator::default();
                for (t, l, s) in &a.rows {
                    acc.push(*t, *l, *s);
                }
                let hours = a.clean_s / 3600.0;
                MethodResult {
                    method: m.name(),
                    metrics: acc.metrics(),
                    clean_hours: hours,
                    clean_alarms: a.clean_alarms,
                    false_alarms_per_hour: if hours > 0.0 { a.clean_alarms as f64 / hours } else { f64::NAN },
                    clean_flagged_fraction: if a.clean_epochs > 0 { a.clean_flagged as f64 / a.clean_epochs as f64 } else { 0.0 },
                    kinds: a
                        .kinds
                        .into_iter()
                        .map(|(group, faults, detected, mut delays)| KindResult { group, faults, detected, median_delay_s: median(&mut delays) })
                        .collect(),
                    logs: a.logs,
                    rows_per_s: a.rows_done as f64 / a.seconds,
                }
            })
            .collect();
        Ok(Comparison { seeds: self.seeds, split: self.split.map(Split::name), flights: self.cases.len(), methods })
    }
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Statuses of one method over a stream (bad rows count as status 0).
fn run(cfg: Config, rows: &[Sample]) -> Result<Vec<u8>, String> {
    let mut det = Detector::new(cfg)?;
    Ok(rows.iter().map(|s| det.push(s).map_or(0, |o| o.status)).collect())
}

fn f(x: f64, d: usize) -> String {
    if x.is_finite() { format!("{x:.d$}") } else { "–".into() }
}

/// A table header with one column per method.
fn method_header(s: &mut String, first: &str, c: &Comparison) {
    s.push_str(&format!("| {first} |"));
    for m in &c.methods {
        s.push_str(&format!(" {} |", m.method));
    }
    s.push_str("\n|---|");
    for _ in &c.methods {
        s.push_str("---|");
    }
    s.push('\n');
}

/// The comparison as Markdown tables (what the README shows).
pub fn markdown(c: &Comparison) -> String {
    let mut s = String::new();
    match c.split {
        Some(split) => s.push_str(&format!(
            "{} flights of the randomised battery's {split} split (`src/battery.rs`); rates pooled over the labelled GPS epochs of every flight, clean ones included (as `docs/battery.md` defines them); false alarms per hour on the clean flights.\n\n",
            c.flights
        )),
        None => s.push_str(&format!(
            "{} simulated flights ({} seeds: {:?}); fault-flight rates pooled over labelled GPS epochs; false alarms per hour on the clean flights.\n\n",
            c.flights,
            c.seeds.len(),
            c.seeds
        )),
    }
    s.push_str("| method | accuracy | false alarm | misdetection | F2 | false alarms / h (clean) | clean epochs flagged |\n|---|---|---|---|---|---|---|\n");
    let best = c.methods.iter().map(|m| m.metrics.f2).fold(f64::NEG_INFINITY, f64::max);
    for m in &c.methods {
        let name = if m.metrics.f2 == best { format!("**{}**", m.method) } else { m.method.to_string() };
        s.push_str(&format!(
            "| {name} | {} | {} | {} | {} | {} | {}% |\n",
            f(m.metrics.accuracy, 4),
            f(m.metrics.false_alarm_rate, 4),
            f(m.metrics.misdetection_rate, 4),
            f(m.metrics.f2, 4),
            f(m.false_alarms_per_hour, 1),
            f(100.0 * m.clean_flagged_fraction, 2)
        ));
    }
    s.push_str("\nFaults caught (of injected) and median detection delay, s, per fault kind:\n\n");
    method_header(&mut s, "kind", c);
    if let Some(first) = c.methods.first() {
        for (k, kr) in first.kinds.iter().enumerate() {
            s.push_str(&format!("| {} |", kr.group));
            for m in &c.methods {
                match m.kinds.get(k) {
                    Some(r) => s.push_str(&format!(" {}/{} · {} |", r.detected, r.faults, f(r.median_delay_s, 1))),
                    None => s.push_str(" – |"),
                }
            }
            s.push('\n');
        }
        if !first.logs.is_empty() {
            s.push_str("\nReal logs (no labels): share of GPS epochs flagged:\n\n");
            method_header(&mut s, "log", c);
            for (k, lr) in first.logs.iter().enumerate() {
                s.push_str(&format!("| {} ({} epochs) |", lr.name, lr.gps_epochs));
                for m in &c.methods {
                    match m.logs.get(k) {
                        // No GPS epoch: nothing judged, never shown as a clean 0.00 %.
                        Some(_) if lr.gps_epochs == 0 => s.push_str(" no verdict |"),
                        Some(r) => s.push_str(&format!(" {}% |", f(100.0 * r.flagged_fraction, 2))),
                        None => s.push_str(" – |"),
                    }
                }
                s.push('\n');
            }
        }
    }
    s
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn battery_covers_every_kind_outages_and_clean_flights() {
        let b = battery(&[1, 2]);
        // 7 kinds: 4 with two magnitudes, 3 without → 11, + 2 outage + 2 clean = 15 per seed.
        assert_eq!(b.len(), 30);
        for g in ["step", "ramp", "noise", "frozen", "zero-velocity", "baro-stuck", "accel-bias", "outage", "clean"] {
            assert!(b.iter().any(|c| c.group == g), "{g}");
        }
    }

    /// A real log with no GPS epoch is "no verdict" in the table, never a
    /// clean 0.00 % (issue 16).
    #[test]
    fn a_log_without_gps_is_no_verdict() {
        let mut csv = String::from("t,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,baro\n");
        for i in 0..500 {
            csv.push_str(&format!("{:.2},0,0,-9.81,0,0,0,1,0,0,0,10\n", f64::from(i) / 50.0));
        }
        let log = crate::logs::csv::read_csv(csv.as_bytes()).unwrap();
        let mut run = CompareRun::new(&[1], &[Method::Chi2], None).unwrap();
        run.add_log("imu.csv", log);
        let md = markdown(&run.finish().unwrap());
        assert!(md.contains("| imu.csv (0 epochs) | no verdict |"), "{md}");
    }

    /// The randomised battery's flights, reported under their first
    /// fault's kind, run by each method; the split is named in the result
    /// and the Markdown.
    #[test]
    fn the_randomised_battery_runs_every_method_on_the_same_flights() {
        let cases = battery_cases(Split::Eval, 6);
        let groups: Vec<&str> = cases.iter().map(|c| c.group.as_str()).collect();
        // Eval flights 0-5 as the generator draws them (their first faults).
        assert_eq!(groups, ["outage", "drag-off-v", "degraded", "ramp-h", "baro-drift", "step-v"]);
        assert!(CompareRun::new_battery(Split::Eval, 0, &[], None).is_err());
        let c = CompareRun::new_battery(Split::Eval, 2, &[Method::Anfis, Method::Gate], None).unwrap().finish().unwrap();
        assert_eq!((c.flights, c.split, c.methods.len()), (2, Some("eval"), 2));
        // Same flights, same labels: the two methods' epoch counts agree.
        let n = |m: &MethodResult| m.metrics.tp + m.metrics.fp + m.metrics.tn + m.metrics.r#fn;
        assert_eq!(n(&c.methods[0]), n(&c.methods[1]));
        assert!(n(&c.methods[0]) > 100);
        assert!(markdown(&c).starts_with("2 flights of the randomised battery's eval split"));
    }

    #[test]
    fn median_even_and_odd() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&mut []).is_nan());
    }
}
