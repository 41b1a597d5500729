//! Throughput of the readers on a 1-hour, 12-channel, 40 Hz log (1.7 M rows).
//!
//! A bench binary (not a test: speed is measured, never asserted):
//! `cargo bench -p gsens-io --bench readers` (it allocates a few hundred MB).
//! (`prepare_session` on the same log: `gsens-session`'s `benches/prepare.rs`.)

use std::time::Instant;

use gsens_io::{ImuSeries, TrackingRow, TrackingWriter, read_imu, read_tracking, read_tracking_file};

const EPOCHS: usize = 3600 * 40;

/// Writes the log; `round` maps each value to what the log holds (full precision,
/// or a receiver's few decimals: `round(v, scale)`, scale = 10^decimals).
fn tracking_text(round: impl Fn(f64, f64) -> f64) -> Vec<u8> {
    let mut x: u64 = 0x2545_F491_4F6C_DD1D;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut w = TrackingWriter::new(Vec::with_capacity(200 << 20)).unwrap();
    for k in 0..EPOCHS {
        let t_s = 345_600.0 + k as f64 * 0.025;
        for ch in 0..12u32 {
            // Channel 11 drops out now and then.
            if ch == 11 && (k / 1000) % 7 == 3 {
                continue;
            }
            let row = TrackingRow {
                t_s,
                channel: ch,
                prn: ch * 2 + 1,
                cn0_dbhz: round(35.0 + ch as f64 + rnd(), 10.0),
                elev_deg: if ch == 5 { None } else { Some(round(10.0 + 70.0 * rnd(), 10.0)) },
                phase_err_rad: round(0.05 * (rnd() - 0.5), 1e6),
            };
            w.write_row(&row).unwrap();
        }
    }
    w.finish().unwrap()
}

fn time_tracking(label: &str, text: &[u8]) -> gsens_io::TrackingLog {
    let rows = text.iter().filter(|&&b| b == b'\n').count() - 1;
    // Baseline: splitting the text into records with the csv crate, nothing parsed.
    let t = Instant::now();
    let mut rdr = csv::ReaderBuilder::new().flexible(true).from_reader(text);
    let mut rec = csv::ByteRecord::new();
    let mut n = 0usize;
    while rdr.read_byte_record(&mut rec).unwrap() {
        n += rec.len();
    }
    let split_s = t.elapsed().as_secs_f64();
    assert_eq!(n, rows * 6);

    let t = Instant::now();
    let log = read_tracking(text, "tracking.csv").unwrap();
    let read_s = t.elapsed().as_secs_f64();
    assert_eq!(log.rows(), rows);
    eprintln!(
        "tracking ({label}): {rows} rows, {:.1} MB read in {read_s:.3} s ({:.0} MB/s; csv splitting alone {split_s:.3} s)",
        text.len() as f64 / 1e6,
        text.len() as f64 / 1e6 / read_s,
    );

    // The same bytes as a file: read_tracking_file's quote-free fast path, its chunks parsed at once
    // (median of 5 reads; the file is in the page cache after the first).
    let path = std::env::temp_dir().join(format!("gsens-bench-readers-{}.csv", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let mut times: Vec<f64> = (0..5)
        .map(|_| {
            let t = Instant::now();
            let from_file = read_tracking_file(&path).unwrap();
            let s = t.elapsed().as_secs_f64();
            // Not assert_eq!: its message would print 1.7 M rows (and NaN elevations differ).
            let same = |a: &gsens_io::ChannelTrack, b: &gsens_io::ChannelTrack| {
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                (a.channel, a.prn, &a.t_s, &a.phase_err_rad, &a.cn0_dbhz)
                    == (b.channel, b.prn, &b.t_s, &b.phase_err_rad, &b.cn0_dbhz)
                    && bits(&a.elev_deg) == bits(&b.elev_deg)
            };
            assert!(from_file.tracks().iter().zip(log.tracks()).all(|(a, b)| same(a, b)));
            assert!(from_file.tracks().len() == log.tracks().len() && from_file.epoch_line() == log.epoch_line());
            s
        })
        .collect();
    std::fs::remove_file(&path).unwrap();
    let median_s = gsens_core::stats::median_in_place(&mut times);
    eprintln!(
        "tracking ({label}) as a file (read_tracking_file): median {median_s:.3} s ({:.0} MB/s)",
        text.len() as f64 / 1e6 / median_s
    );
    log
}

fn main() {
    let full = tracking_text(|v, _| v);
    time_tracking("full f64 precision", &full);
    drop(full);
    let short = tracking_text(|v, scale| (v * scale).round() / scale);
    time_tracking("receiver-like decimals", &short);
    drop(short);

    let imu = ImuSeries {
        t_s: (0..EPOCHS).map(|k| 345_600.0 + k as f64 * 0.025).collect(),
        accel_mps2: (0..EPOCHS).map(|k| [(k as f64).sin(), (k as f64).cos(), 9.81 + 1e-3 * (k % 17) as f64]).collect(),
    };
    let mut imu_text = Vec::new();
    gsens_io::write_imu_csv(&mut imu_text, &imu).unwrap();
    let t = Instant::now();
    let imu_back = read_imu(imu_text.as_slice(), "imu.csv").unwrap();
    let imu_s = t.elapsed().as_secs_f64();
    assert_eq!(imu_back, imu);

    eprintln!("imu: {} rows in {imu_s:.3} s", imu_back.len());
}
