//! What stands between a record's arrival and the screen: `LiveSession::push`
//! and `LiveSession::view` (the draw is the terminal's), on the default
//! session at 60 s with a batch estimate applied; and, for the worker thread,
//! one batch estimate of those 60 s.

use criterion::{Criterion, criterion_group, criterion_main};
use gsens_live::{Input, LiveConfig, LiveSession, read_session_dir};

fn session_at_60_s() -> (LiveSession, Vec<Input>) {
    let dir = std::env::temp_dir().join(format!("gsens-live-bench-{}", std::process::id()));
    gsens_sim::simulate_to_dir(&gsens_sim::scenario::Scenario::default(), 1, &dir, |_| {}).unwrap();
    let inputs = read_session_dir(&dir).unwrap();
    let settings = gsens_inputs::settings_of_simulated_session(&dir.join("truth.json")).unwrap();
    let mut live = LiveSession::new(LiveConfig::new(settings, 8e-4)).unwrap();
    let mut rest = Vec::new();
    for (k, x) in inputs.into_iter().enumerate() {
        if x.t_s() > 60.0 {
            rest.push(x);
            continue;
        }
        live.push("bench", k as u64, x);
        if let Some(job) = live.batch_due() {
            live.apply(job.run());
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    (live, rest)
}

fn bench(c: &mut Criterion) {
    let (live, rest) = session_at_60_s();
    let mut g = c.benchmark_group("live");
    g.bench_function("push 1000 records after 60 s", |b| {
        b.iter_batched(
            || live_clone(&live),
            |mut s| {
                for (k, x) in rest.iter().take(1000).enumerate() {
                    s.push("bench", k as u64, *x);
                }
                s
            },
            criterion::BatchSize::LargeInput,
        )
    });
    g.bench_function("view at 60 s", |b| b.iter(|| live.view()));
    g.sample_size(10);
    g.bench_function("batch estimate of 60 s (worker thread)", |b| b.iter(|| live.final_job().run()));
    g.finish();
}

fn live_clone(s: &LiveSession) -> LiveSession {
    s.clone()
}

criterion_group!(benches, bench);
criterion_main!(benches);
