//! Native benchmarks: per-row cost of the detector and the whole paper
//! scenario with retraining (compare with benches/node-bench.mjs for wasm).
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use navguard::config::Config;
use navguard::detector::Detector;
use navguard::sim::{simulate, OutageMode, Scenario};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let rows = simulate(&Scenario::paper(OutageMode::Degraded, 1)).unwrap_or_default();
    let mut g = c.benchmark_group("detector");
    g.throughput(Throughput::Elements(rows.len() as u64));
    g.sample_size(20);
    g.bench_function("paper_scenario_tc100", |b| {
        b.iter(|| {
            let mut d = Detector::new(Config::default()).unwrap();
            for s in &rows {
                black_box(d.push_valid(s));
            }
        })
    });
    g.bench_function("paper_scenario_no_retrain", |b| {
        let cfg = Config { retrain: false, ..Config::default() };
        b.iter(|| {
            let mut d = Detector::new(cfg.clone()).unwrap();
            for s in &rows {
                black_box(d.push_valid(s));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
