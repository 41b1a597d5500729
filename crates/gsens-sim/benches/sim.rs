//! Simulation throughput.
//!
//! - `channel_update`: one loop update of a correlator-level channel
//!   (phase ramp, sinc, sin/cos, two Gaussian draws, atan discriminator, the
//!   core's loop filter, lock/C/N0 bookkeeping), 8 channels interleaved as in a
//!   session. Throughput in channel updates per second (goal: ≥ 20 M/s on one
//!   core, i.e. ≤ 50 ns per update).
//! - `default_scenario`: the whole default session (130 s, ~7 channels at
//!   1 ms, oscillator, motion, IMU, satellites), logs dropped. Throughput
//!   "elements" are simulated seconds, so elem/s = simulated s per wall s.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gsens_core::LoopSpec;
use gsens_sim::channel::{Channel, ChannelConfig, ChannelStart, Discriminator};
use gsens_sim::rng::substream;
use gsens_sim::scenario::Scenario;
use gsens_sim::session::{NullSink, simulate};

fn channel_update(c: &mut Criterion) {
    const CHANNELS: usize = 8;
    const STEPS: usize = 10_000;
    let cfg = ChannelConfig::new(LoopSpec::PAPER.coeffs().unwrap(), 0.001, Discriminator::Costas);
    let start = |i: usize| ChannelStart {
        cn0_dbhz: 38.0 + i as f64,
        preload_freq_hz: 1000.0 * i as f64,
        preload_rate_hz_per_s: 0.0,
        initial_phase_err_rad: 0.0,
        bit_offset: i as u32,
    };
    let mut chans: Vec<Channel> =
        (0..CHANNELS).map(|i| Channel::new(&cfg, &start(i), substream(1, i as u64))).collect();
    let mut g = c.benchmark_group("sim");
    g.throughput(Throughput::Elements((CHANNELS * STEPS) as u64));
    g.bench_function("channel_update", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for k in 0..STEPS {
                let df = 0.3 * ((k & 255) as f64 * 0.0245).sin();
                for (i, ch) in chans.iter_mut().enumerate() {
                    acc += ch.step(1000.0 * i as f64, black_box(df)).discriminator_rad;
                }
            }
            black_box(acc)
        })
    });
    let sc = Scenario::default();
    g.throughput(Throughput::Elements(sc.duration_s() as u64));
    g.sample_size(10);
    g.bench_function("default_scenario", |b| b.iter(|| simulate(black_box(&sc), 1, &mut NullSink, |_| {}).unwrap()));
    g.finish();
}

criterion_group!(benches, channel_update);
criterion_main!(benches);
