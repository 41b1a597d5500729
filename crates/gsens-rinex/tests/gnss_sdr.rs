//! The reader on GNSS-SDR 0.0.17's own RINEX 3.02 observation file of a simulated
//! shaken session (tests/fixtures/gnss-sdr/README.md): its header, epochs and satellites,
//! and its carrier phase against its Doppler.

use gsens_rinex::read_rinex_file;

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/gnss-sdr");

/// GPS time of week of the simulated session's first sample (2024-02-08 12:00:00 UTC,
/// GPS − UTC = 18 s): the fixture spans 59 s … 119.7 s of it.
const TOW0_S: f64 = 388_818.0;
/// The satellites whose ephemeris GNSS-SDR decoded in that run (of the 8 simulated).
const SATELLITES: [&str; 8] = ["G01", "G03", "G08", "G13", "G23", "G28", "G31", "G32"];
/// GNSS-SDR's observation interval in the run (`PVT.rinexobs_rate_ms = 100`) \[s\].
const INTERVAL_S: f64 = 0.1;

#[test]
fn header_epochs_and_satellites_are_the_runs() {
    let log = read_rinex_file(format!("{DIR}/gnss-sdr.24O")).unwrap();
    assert!(log.validate().is_ok());
    assert_eq!((log.format.as_str(), log.gps_week), ("RINEX 3.02", 2300));
    assert!(log.skipped.is_empty() && log.clock_events.is_empty(), "{:?} {:?}", log.skipped, log.clock_events);
    // Every epoch on GNSS-SDR's 100 ms grid from 59 s to 119.7 s of the session.
    assert_eq!(log.epochs, 608);
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{DIR}/truth.json")).unwrap()).unwrap();
    let simulated: Vec<String> =
        truth["satellites"].as_array().unwrap().iter().map(|s| format!("G{:02}", s["prn"].as_u64().unwrap())).collect();
    let mut svs: Vec<&str> = log.tracks.iter().map(|t| t.sv.as_str()).collect();
    svs.sort_unstable();
    assert_eq!(svs, SATELLITES);
    assert!(svs.iter().all(|s| simulated.iter().any(|x| x == s)), "{svs:?} not all in {simulated:?}");
    for t in &log.tracks {
        assert_eq!((t.code.as_str(), t.carrier.label()), ("1C", "L1CA".to_owned()), "{}", t.sv);
        // Contiguous to the end at the interval, every observable present, no loss of lock.
        let last = *t.t_s.last().unwrap();
        assert!((last - (TOW0_S + 119.7)).abs() < 1e-6, "{}: last epoch {last}", t.sv);
        assert!(t.t_s.windows(2).all(|w| (w[1] - w[0] - INTERVAL_S).abs() < 1e-6), "{}", t.sv);
        for v in [&t.pseudorange_m, &t.carrier_phase_cycles, &t.doppler_hz, &t.cn0_dbhz] {
            assert!(v.iter().all(|x| x.is_finite()), "{}", t.sv);
        }
        assert!(t.flags.iter().all(|&f| f == 0), "{}", t.sv);
        // The simulated C/N0 (39–47 dB-Hz) and GPS ranges.
        assert!(t.cn0_dbhz.iter().all(|c| (35.0..50.0).contains(c)), "{}", t.sv);
        assert!(t.pseudorange_m.iter().all(|p| (19e6..26e6).contains(p)), "{}", t.sv);
    }
    // All but G01 (decoded later) from the first epoch.
    let first = |sv: &str| log.tracks.iter().find(|t| t.sv == sv).unwrap().t_s[0] - TOW0_S;
    assert!(SATELLITES.iter().filter(|s| **s != "G01").all(|s| (first(s) - 59.0).abs() < 1e-6));
    assert!((first("G01") - 83.9).abs() < 1e-6);
    // The IMU log trimmed to the same span on the same time, at the simulator's 40 Hz.
    let imu = std::fs::read_to_string(format!("{DIR}/imu.csv")).unwrap();
    let t_imu: Vec<f64> = imu.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert_eq!((t_imu[0], *t_imu.last().unwrap(), t_imu.len()), (TOW0_S + 59.0, TOW0_S + 120.0, 2441));
}

/// Per interval k of one track: r = −(L[k+1] − L[k])/Δt − (D[k] + D[k+1])/2 \[Hz\] and
/// the Doppler's slope (D[k+1] − D[k])/Δt \[Hz/s\].
fn phase_minus_doppler(t: &gsens_io::SatelliteSeries) -> (Vec<f64>, Vec<f64>) {
    let (mut r, mut slope) = (Vec::new(), Vec::new());
    for k in 0..t.len() - 1 {
        let dt = t.t_s[k + 1] - t.t_s[k];
        let (l, d) = (&t.carrier_phase_cycles, &t.doppler_hz);
        r.push(-(l[k + 1] - l[k]) / dt - 0.5 * (d[k] + d[k + 1]));
        slope.push((d[k + 1] - d[k]) / dt);
    }
    (r, slope)
}

#[test]
fn differenced_phase_is_the_doppler_half_an_update_earlier() {
    // RINEX's signs (−dL/dt = D) hold to a few mHz where D is thousands of Hz: a phase of
    // the other sign would leave 2·D. GNSS-SDR's D at an epoch is its loop's NCO frequency
    // for the next 20 ms integration, so it leads the phase's slope: r = δ·dD/dt with δ
    // about −10 ms, fitted over all tracks; the rest is noise (each track's mean within three
    // standard errors, from the means of 1 s batches: the loop's noise is correlated).
    let log = read_rinex_file(format!("{DIR}/gnss-sdr.24O")).unwrap();
    let per_track: Vec<(Vec<f64>, Vec<f64>)> = log.tracks.iter().map(phase_minus_doppler).collect();
    let (num, den) =
        per_track.iter().flat_map(|(r, s)| r.iter().zip(s)).fold((0.0, 0.0), |(n, d), (r, s)| (n + r * s, d + s * s));
    let delta_s = num / den;
    assert!((-0.015..-0.005).contains(&delta_s), "D leads the phase by {delta_s} s");
    for (t, (r, s)) in log.tracks.iter().zip(&per_track) {
        let n = r.len() as f64;
        let mean_raw = r.iter().sum::<f64>() / n;
        let d_mean = t.doppler_hz.iter().map(|d| d.abs()).sum::<f64>() / t.len() as f64;
        assert!(mean_raw.abs() < 0.02 && d_mean > 100.0, "{}: r {mean_raw} Hz, |D| {d_mean} Hz", t.sv);
        let rest: Vec<f64> = r.iter().zip(s).map(|(r, s)| r - delta_s * s).collect();
        let mean = rest.iter().sum::<f64>() / n;
        let sd = (rest.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!(sd < 0.1, "{}: residual σ {sd} Hz", t.sv);
        let batch = (1.0 / INTERVAL_S).round() as usize;
        let means: Vec<f64> = rest.chunks_exact(batch).map(|c| c.iter().sum::<f64>() / batch as f64).collect();
        let m = means.len() as f64;
        let mm = means.iter().sum::<f64>() / m;
        let se = (means.iter().map(|x| (x - mm).powi(2)).sum::<f64>() / (m - 1.0) / m).sqrt();
        assert!(mean.abs() < 3.0 * se, "{}: mean residual {mean} Hz, standard error {se} Hz", t.sv);
    }
}
