//! The loop-free estimate on real GNSS-SDR 0.0.17 dumps (the fixtures: a
//! gsens IF file tracked by GNSS-SDR with its 2nd- and 3rd-order loops):
//! the replica's phase rebuilt from the records' NCO frequencies plus the
//! discriminator output is the phase each loop was fed, so Γ̂ follows with
//! no loop model, whichever loop GNSS-SDR ran. Measured: order 2 (2
//! tracks) z = +0.1, −2.0, +1.2 against the truth with σ 0.43–0.62 %;
//! order 3 (1 track covers the segment) z = +0.7, −1.4, +0.7, σ 0.9–1.1 %.

use std::path::{Path, PathBuf};

use gsens_calib::{LoopFreeEstimate, LoopFreeSettings, estimate_loop_free_from};
use gsens_gnss_sdr::{ImportSettings, gnss_sdr_input_phases, import_dir};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn truth() -> [f64; 3] {
    let text = std::fs::read_to_string(fixtures().join("truth.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    [0, 1, 2].map(|i| v["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap())
}

fn loop_free(name: &str) -> LoopFreeEstimate {
    let dir = fixtures().join(name);
    let settings = ImportSettings::from_conf(Some(&dir.join("gnss-sdr.conf")), None).unwrap();
    let imported = import_dir(&dir, &settings).unwrap();
    let phases = gnss_sdr_input_phases(&imported, imported.interval_s, core::f64::consts::FRAC_PI_4);
    let imu = gsens_io::read_imu_file(fixtures().join("imu.csv")).unwrap();
    let loop_free = LoopFreeSettings::new(imported.interval_s, gsens_core::LoggedPhase::Last);
    estimate_loop_free_from(&phases, &imu, &loop_free).unwrap()
}

#[test]
fn loop_free_estimates_from_both_loop_orders_are_within_their_sigma() {
    let want = truth();
    let estimates: Vec<LoopFreeEstimate> = ["order2", "order3"].map(loop_free).into();
    for (name, e) in ["order2", "order3"].iter().zip(&estimates) {
        let (g, s) = (e.gamma_hz_per_mps2, e.sigma_hz_per_mps2());
        eprintln!("{name}: {g:?} ± {s:?} (truth {want:?}), {} tracks, {} segments", e.tracks, e.segments);
        let dir = fixtures().join(name);
        let import = ImportSettings::from_conf(Some(&dir.join("gnss-sdr.conf")), None).unwrap();
        let settings = gsens_calib::PipelineSettings::default();
        let closed = gsens_gnss_sdr::calibrate_gnss_sdr(&dir, &import, &fixtures().join("imu.csv"), &settings).unwrap();
        let c = &closed.outcome.calibration;
        for i in 0..3 {
            assert!((g[i] - want[i]).abs() < 3.0 * s[i], "{name} axis {i}: {} ± {} vs {}", g[i], s[i], want[i]);
            let (gc, sc) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
            assert!((g[i] - gc).abs() < 3.0 * s[i].hypot(sc), "{name} axis {i}: {} vs closed loop {gc} ± {sc}", g[i]);
        }
    }
}

/// Dumps of another setting, through the route `gsens estimate --gnss-sdr`
/// takes (the outcome's `loop_free`): `extend_correlation_symbols = 2` (a
/// 35 Hz loop at 1 ms, then 3 Hz at 2 ms records), its own session and
/// truth. (`= 1`, a 1 ms loop logged once per 20 ms bit, is not yet right:
/// the NCO's 19 unlogged updates between records are held at the logged
/// frequency, and Γ̂ comes out 4–6 % low.)
#[test]
fn loop_free_estimates_from_another_integration_setting_are_within_their_sigma() {
    for name in ["ext2"] {
        let dir = fixtures().join(name);
        let text = std::fs::read_to_string(dir.join("truth.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let want = [0, 1, 2].map(|i| v["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap());
        let import = ImportSettings::from_conf(Some(&dir.join("gnss-sdr.conf")), None).unwrap();
        let settings = gsens_calib::PipelineSettings::default();
        let outcome =
            gsens_gnss_sdr::calibrate_gnss_sdr(&dir, &import, &dir.join("imu.csv"), &settings).unwrap().outcome;
        let e = outcome.loop_free.expect("dumps give the loop-free estimate").expect("a loop-free estimate");
        let (g, s) = (e.gamma_hz_per_mps2, e.sigma_hz_per_mps2());
        eprintln!("{name}: {g:?} ± {s:?} (truth {want:?}), {} tracks, {} segments", e.tracks, e.segments);
        for i in 0..3 {
            assert!((g[i] - want[i]).abs() < 3.0 * s[i], "{name} axis {i}: {} ± {} vs {}", g[i], s[i], want[i]);
        }
    }
}
