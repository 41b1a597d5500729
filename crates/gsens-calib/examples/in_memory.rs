//! The calibration pipeline on logs already in memory: the median wall time of
//! `calibrate_logs` plus the result document over several runs, the CSV
//! parsing left out. The Python binding's overhead is measured against it
//! (`python/benchmarks/binding_overhead.py`, BENCHMARKS.md).
//!
//! ```sh
//! cargo run --release -p gsens-calib --example in_memory -- DIR RUNS ['{"bn_hz": 3, ...}']
//! ```
//!
//! DIR holds `imu.csv` and `tracking.csv`; the optional JSON object holds
//! `CalibrationOptions` by name (what `gsens.estimate` takes as keywords).

use gsens_calib::{CalibrationOptions, calibrate_logs};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: in_memory DIR RUNS [OPTIONS_JSON]";
    let dir = std::path::PathBuf::from(args.get(1).ok_or(usage)?);
    let runs: usize = args.get(2).ok_or(usage)?.parse()?;
    let options: CalibrationOptions = serde_json::from_str(args.get(3).map_or("{}", String::as_str))?;
    let settings = options.pipeline_settings()?;
    let imu_path = dir.join("imu.csv");
    let imu = gsens_io::read_imu_file(&imu_path)?;
    let tracking = gsens_io::read_tracking_file(dir.join("tracking.csv"))?;
    let imu_name = imu_path.display().to_string();
    let mut wall_s = Vec::with_capacity(runs);
    let mut gamma = [None; 3];
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        let outcome = calibrate_logs(&tracking, &imu, &imu_name, &settings)?;
        let doc = outcome.document(None);
        wall_s.push(start.elapsed().as_secs_f64());
        gamma = doc.calibration.gamma_hz_per_mps2;
    }
    let median_s = gsens_core::stats::median_in_place(&mut wall_s);
    println!(
        "calibrate_logs + document: median {:.1} ms over {} runs (min {:.1}, max {:.1}); Γ̂ = {:?}",
        median_s * 1e3,
        wall_s.len(),
        wall_s[0] * 1e3,
        wall_s[wall_s.len() - 1] * 1e3,
        gamma
    );
    Ok(())
}
