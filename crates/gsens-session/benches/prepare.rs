//! Time of `prepare_session` on a 1-hour, 12-channel, 40 Hz log (1.7 M rows),
//! with and without the screening (the readers' throughput on the same log:
//! `gsens-io`'s `benches/readers.rs`).
//!
//! A bench binary (not a test: speed is measured, never asserted):
//! `cargo bench -p gsens-session --bench prepare` (it allocates a few hundred MB).

use std::time::Instant;

use gsens_io::{ImuSeries, TrackingLog, TrackingRow};
use gsens_session::{ScreeningConfig, SelectionConfig, prepare_session};

const EPOCHS: usize = 3600 * 40;

/// The log of `gsens-io`'s perf test, in memory.
fn tracking_log() -> TrackingLog {
    let mut x: u64 = 0x2545_F491_4F6C_DD1D;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut rows = Vec::with_capacity(EPOCHS * 12);
    for k in 0..EPOCHS {
        let t_s = 345_600.0 + k as f64 * 0.025;
        for ch in 0..12u32 {
            // Channel 11 drops out now and then.
            if ch == 11 && (k / 1000) % 7 == 3 {
                continue;
            }
            rows.push(TrackingRow {
                t_s,
                channel: ch,
                prn: ch * 2 + 1,
                cn0_dbhz: 35.0 + ch as f64 + rnd(),
                elev_deg: if ch == 5 { None } else { Some(10.0 + 70.0 * rnd()) },
                phase_err_rad: 0.05 * (rnd() - 0.5),
            });
        }
    }
    TrackingLog::from_rows("tracking.csv", &rows).unwrap()
}

fn main() {
    let log = tracking_log();
    let imu = ImuSeries {
        t_s: (0..EPOCHS).map(|k| 345_600.0 + k as f64 * 0.025).collect(),
        accel_mps2: (0..EPOCHS).map(|k| [(k as f64).sin(), (k as f64).cos(), 9.81 + 1e-3 * (k % 17) as f64]).collect(),
    };

    let t = Instant::now();
    let cfg = SelectionConfig { max_channels: None, ..SelectionConfig::default() };
    let s = prepare_session(&log, &imu, "imu.csv", &cfg, 0.0).unwrap();
    let prep_s = t.elapsed().as_secs_f64();
    assert_eq!(s.len(), EPOCHS);
    eprintln!("prepare_session (12 channels, offsets): {prep_s:.3} s");
    for (label, screening) in [("screening off", ScreeningConfig::off()), ("screening on", Default::default())] {
        for max_channels in [Some(4), None] {
            let cfg = SelectionConfig { max_channels, screening: screening.clone(), ..SelectionConfig::default() };
            let t = Instant::now();
            let s = prepare_session(&log, &imu, "imu.csv", &cfg, 0.0).unwrap();
            let prep_s = t.elapsed().as_secs_f64();
            assert_eq!(s.len(), EPOCHS);
            eprintln!("prepare_session, {label}, max_channels {max_channels:?}: {prep_s:.3} s");
        }
    }
}
