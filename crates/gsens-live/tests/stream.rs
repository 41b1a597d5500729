//! The streamed estimate against the batch estimate on the same data.
//!
//! The default session (the paper's experiment) fed record by record: at the
//! end the stream, re-streamed under the batch's loop and time offset, gives
//! Γ̂ within 0.1σ of the batch pipeline's (measured: +0.065σ, 0.000σ,
//! 0.000σ), its σ within 5 % (+2.4 %). What differs is the averaging: the
//! stream averages its set of channels as the epochs arrive (the set changes
//! while the channels are acquired); the batch removes each track's
//! constant offset over the whole session and screens it first. Before the
//! batch's hand-back the stream runs under the stated loop and no IMU time
//! offset: on this session (a 2 ms IMU latency, found by the batch) that
//! puts it about 0.9σ off, which is why the stream is re-run under the
//! batch's loop and offset at every batch.

use gsens_calib::PipelineSettings;
use gsens_live::{LiveConfig, LiveSession, read_session_dir};

fn session(dir_name: &str) -> (tempfile::TempDir, PipelineSettings) {
    let scratch = tempfile::Builder::new().prefix(&format!("gsens-live-{dir_name}-")).tempdir().unwrap();
    let dir = scratch.path();
    gsens_sim::simulate_to_dir(&gsens_sim::scenario::Scenario::default(), 1, dir, |_| {}).unwrap();
    let mut settings = gsens_inputs::settings_of_simulated_session(&dir.join("truth.json")).unwrap();
    // The stream is the batch path's least squares through the loop model:
    // compared with the batch estimate through the loop model, not the loop-free one.
    settings.measurement = gsens_calib::MeasurementChoice::TrackingError;
    (scratch, settings)
}

#[test]
fn the_stream_ends_at_the_batch_estimate() {
    let (scratch, settings) = session("stream");
    let dir = scratch.path();
    let mut live = LiveSession::new(LiveConfig::new(settings, 1e-9)).unwrap();
    let mut before_batch = None;
    for (k, x) in read_session_dir(dir).unwrap().iter().enumerate() {
        live.push("replay", k as u64 + 1, *x);
        if before_batch.is_none() && live.data_t_s() >= 60.0 {
            // Before any batch: the stated loop, white-noise σ.
            before_batch = Some(live.view().axes);
        }
    }
    let streamed_stated = live.view().axes;
    let job = live.final_job();
    live.apply(job.run());
    let view = live.view();
    for (i, a) in view.axes.iter().enumerate() {
        let (g_batch, s_batch) = (a.gamma_hz_per_mps2.unwrap(), a.sigma_hz_per_mps2.unwrap());
        let (g_now, s_now) = (a.now_gamma_hz_per_mps2.unwrap(), a.now_sigma_hz_per_mps2.unwrap());
        let g_stated = streamed_stated[i].now_gamma_hz_per_mps2.unwrap();
        eprintln!(
            "axis {i}: batch {g_batch:+.6} ± {s_batch:.6}, stream {g_now:+.6} ± {s_now:.6} ({:+.3}σ), stated loop {g_stated:+.6} ({:+.3}σ)",
            (g_now - g_batch) / s_batch,
            (g_stated - g_batch) / s_batch
        );
        assert!((g_now - g_batch).abs() <= 0.1 * s_batch, "axis {i}");
        assert!((s_now / s_batch - 1.0).abs() < 0.05, "axis {i}: σ {s_now} vs {s_batch}");
    }
}
