//! Per-epoch cost of the core: average 8 channels, advance the triad, update
//! the estimator (the path a receiver runs at its log rate).

use criterion::{Criterion, criterion_group, criterion_main};
use gsens_core::LoopSpec;
use gsens_core::{BatchLeastSquares, GradientObserver, RecursiveLeastSquares};
use gsens_core::{Calibrator, GammaEstimator};
use gsens_core::{LoggedPhase, RegressorModel};
use std::hint::black_box;

fn bench_epoch<E: GammaEstimator>(c: &mut Criterion, name: &str, estimator: E, loop_interval_s: f64) {
    let coeffs = LoopSpec::PAPER.coeffs().unwrap();
    let model = RegressorModel::new(coeffs, loop_interval_s, 0.025, LoggedPhase::Last).unwrap();
    let mut cal = Calibrator::new(model, estimator, 0, 0.05, 0.025);
    let weights = [1.0; 8];
    let mut k = 0u64;
    c.bench_function(name, |b| {
        b.iter(|| {
            k += 1;
            let t = k as f64 * 0.025;
            let a = [3.0 * (5.6 * t).sin(), 0.1, 9.8];
            let mut phases = [0.01 * (5.6 * t).cos(); 8];
            phases[(k % 8) as usize] = f64::NAN;
            black_box(cal.feed_channels(black_box(&a), black_box(&phases), &weights))
        })
    });
}

fn benches(c: &mut Criterion) {
    bench_epoch(c, "epoch_8ch_batch", BatchLeastSquares::new(), 0.025);
    bench_epoch(c, "epoch_8ch_rls", RecursiveLeastSquares::new(1.0, 1e8), 0.025);
    bench_epoch(c, "epoch_8ch_gradient", GradientObserver::new(0.5, 0.025), 0.025);
    bench_epoch(c, "epoch_8ch_batch_1ms_loop", BatchLeastSquares::new(), 0.001);
}

criterion_group!(core, benches);
criterion_main!(core);
