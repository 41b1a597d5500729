//! IF sample generator throughput: 8 GPS L1 C/A satellites at 4 Msps,
//! `ibyte` output to a sink that discards it, one core. Throughput
//! "elements" are seconds of signal, so elem/s = signal seconds per wall
//! second (goal: ≥ 10, i.e. ten times real time).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gsens_sim::iq::{IqConfig, IqFormat, generate_iq};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::NullSink;

fn iq_8_satellites_4msps(c: &mut Criterion) {
    const SIGNAL_S: f64 = 2.0;
    let mut sc = Scenario::default();
    sc.session.duration_s = Some(SIGNAL_S);
    sc.satellites.max_channels = 8;
    sc.satellites.elevation_mask_deg = 0.0;
    let mut g = c.benchmark_group("iq");
    g.sample_size(10);
    g.throughput(Throughput::Elements(SIGNAL_S as u64));
    for format in [IqFormat::Ibyte, IqFormat::GrComplex] {
        let cfg = IqConfig::new(4.0e6, format, &sc);
        g.bench_function(format!("8sat_4msps_{}", format.gnss_sdr_item_type()), |b| {
            b.iter(|| {
                let t = generate_iq(&sc, 1, &cfg, std::io::sink(), &mut NullSink, |_| {}, |_| {}).unwrap();
                assert_eq!(t.satellites.len(), 8);
                black_box(t.samples)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, iq_8_satellites_4msps);
criterion_main!(benches);
