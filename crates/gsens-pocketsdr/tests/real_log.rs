//! The reader, the conversion and the loop model on a real `pocket_trk` 0.17
//! log (`tests/fixtures`, made by `scripts/make-pocketsdr-fixtures.sh`: 39.5 s
//! of a gsens IF file, 3 satellites, default 5 Hz PLL, 10 Hz `$CH` lines),
//! and on damaged copies of it.

use std::path::{Path, PathBuf};

use gsens_core::pocket_sdr::{PocketSdrPll, PocketSdrStage};
use gsens_pocketsdr::{ImportSettings, PocketSdrError, import_log, parse_log, read_log};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn settings() -> ImportSettings {
    ImportSettings::from_options_file(Some(&fixtures().join("opt.conf"))).unwrap()
}

fn log_text() -> String {
    std::fs::read_to_string(fixtures().join("trk.log")).unwrap()
}

fn json(name: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(fixtures().join(name)).unwrap()).unwrap()
}

#[test]
fn reads_the_real_log() {
    let log = read_log(&fixtures().join("trk.log")).unwrap();
    assert_eq!(log.garbled_count, 0, "{:?}", log.garbled);
    assert_eq!((log.fs_hz, log.version.as_deref()), (Some(2e6), Some("0.17")));
    let truth = json("truth.json");
    let prns: Vec<u64> = truth["satellites"].as_array().unwrap().iter().map(|s| s["prn"].as_u64().unwrap()).collect();
    // One channel per satellite of the file, every line L1 C/A, 10 lines a second.
    let mut seen: Vec<u64> = log.records.iter().map(|r| u64::from(r.prn)).collect();
    seen.sort();
    seen.dedup();
    let mut want = prns.clone();
    want.sort();
    assert_eq!(seen, want);
    assert!(log.records.iter().all(|r| r.sig == "L1CA"));
    assert_eq!(log.messages["$CH"] as usize, log.records.len());
    assert!(log.messages["$LOG"] >= 2 && log.messages["$TIME"] >= 30, "{:?}", log.messages);
    let imported = import_log(log, &settings()).unwrap();
    assert_eq!(imported.interval_s(), 0.1);
    assert_eq!(imported.tracks.len(), prns.len());
    assert!(imported.tracks.iter().all(|t| t.used), "{:?}", imported.tracks);
    // The time base: the middle of the logged 1 ms block, on the IF file's sample time.
    for r in &imported.rows {
        let k = ((r.t_s - 5e-4) / 0.1).round();
        assert!((r.t_s - (k * 0.1 + 5e-4)).abs() < 1e-9, "{}", r.t_s);
    }
    // Nothing before the FLL pull-in plus the settling time is kept.
    let settle = imported.settle_s;
    assert!((settle - 5.0 * PocketSdrStage::l1ca(5.0).settling_time_s(1.0)).abs() < 1e-9);
    for t in &imported.tracks {
        let first = imported.rows.iter().find(|r| r.channel == t.channel).unwrap().t_s;
        assert!(first - 5e-4 > t.time_s[0] - t.first_lock_s + 1.0 + settle - 1e-9, "{t:?}");
        assert!(first - 5e-4 < t.time_s[0] - t.first_lock_s + 1.0 + settle + 0.1 + 0.01, "{t:?}");
    }
}

/// The model of `gsens_core::pocket_sdr`, driven by the true carrier of a
/// satellite (the simulator's, per 1 ms block), reproduces the `err_phas` that
/// pocket_trk logged for it to the thermal noise: the residual's RMS is the
/// 1 ms discriminator's thermal σ at the logged C/N0 within 3 standard errors
/// of an RMS, and the logged φ regresses on the model's with slope 1 within
/// 3 standard errors (with the sign of φ flipped, the slope is −1).
#[test]
fn the_model_driven_by_the_true_carrier_reproduces_err_phas() {
    let desc = json("carrier.json");
    let bytes = std::fs::read(fixtures().join("carrier.f32")).unwrap();
    let carrier: Vec<f64> =
        bytes.chunks_exact(4).map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))).collect();
    let (prn, first_block) = (desc["prn"].as_u64().unwrap() as u32, desc["first_block"].as_u64().unwrap() as usize);
    assert_eq!(carrier.len(), desc["blocks"].as_u64().unwrap() as usize);
    let log = read_log(&fixtures().join("trk.log")).unwrap();
    let logged: std::collections::BTreeMap<usize, (f64, f64)> = log
        .records
        .iter()
        .filter(|r| r.prn == prn)
        .map(|r| ((r.time_s * 1e3).round() as usize, (r.err_phas_cyc * std::f64::consts::TAU, r.cn0_dbhz)))
        .collect();
    let mut model = PocketSdrPll::new(PocketSdrStage::l1ca(5.0)).unwrap();
    // Started in the steady state of the first block's frequency; compared after
    // six time constants of the slowest mode (its Doppler-rate transient gone).
    gsens_core::LinearLoop::settle(&mut model, -carrier[0]);
    let skip = (6.0 * PocketSdrStage::l1ca(5.0).settling_time_s(1.0) / 1e-3) as usize;
    let (mut pairs, mut var_th) = (Vec::new(), 0.0);
    for (i, &g) in carrier.iter().enumerate() {
        let phi = model.step_signal(g);
        if let Some(&(measured, cn0)) = logged.get(&(first_block + i))
            && i >= skip
        {
            pairs.push((phi, measured));
            let c = gsens_core::units::cn0_dbhz_to_ratio_hz(cn0) * 1e-3;
            var_th += (1.0 + 1.0 / (2.0 * c)) / (2.0 * c);
        }
    }
    let n = pairs.len() as f64;
    assert!(n >= 100.0, "{n}");
    let sigma_th = (var_th / n).sqrt();
    let rms = |f: &dyn Fn(&(f64, f64)) -> f64| (pairs.iter().map(|p| f(p).powi(2)).sum::<f64>() / n).sqrt();
    let rms_resid = rms(&|p| p.1 - p.0);
    let rms_model = rms(&|p| p.0);
    // Standard error of an RMS of n Gaussian samples: σ/√(2n).
    let se = sigma_th / (2.0 * n).sqrt();
    assert!((rms_resid - sigma_th).abs() < 3.0 * se, "residual {rms_resid} vs thermal {sigma_th} ± {se}");
    let slope = |sign: f64| {
        let sxy: f64 = pairs.iter().map(|p| p.0 * sign * p.1).sum();
        let sxx: f64 = pairs.iter().map(|p| p.0 * p.0).sum();
        sxy / sxx
    };
    let se_slope = sigma_th / (rms_model * n.sqrt());
    assert!(rms_model > 5.0 * se_slope * sigma_th, "the model's signal must be measurable: {rms_model}");
    assert!((slope(1.0) - 1.0).abs() < 3.0 * se_slope, "slope {} ± {se_slope}", slope(1.0));
    assert!((slope(-1.0) + 1.0).abs() < 3.0 * se_slope);
}

#[test]
fn a_cut_log_keeps_its_complete_lines_and_reports_the_last() {
    // The receiver stopped while writing a $CH line: the log ends in its middle.
    let text = log_text();
    let start = text.rfind("\n$CH,").unwrap() + 1;
    let cut = &text[..start + 50];
    let line = text[..start].lines().count() as u64 + 1;
    let whole_before: String = text[..start].to_string();
    let log = parse_log(cut.as_bytes(), "cut.log").unwrap();
    assert_eq!(log.garbled_count, 1, "{:?}", log.garbled);
    assert_eq!(log.garbled[0].line, line);
    assert!(log.garbled[0].to_string().contains("cut short"), "{}", log.garbled[0]);
    // Every complete line is read as in the log without the cut one.
    let cut_rows = import_log(log, &settings()).unwrap().rows;
    let rows = import_log(parse_log(whole_before.as_bytes(), "before.log").unwrap(), &settings()).unwrap().rows;
    assert_eq!(cut_rows, rows);
}

#[test]
fn garbled_and_merged_lines_are_skipped_and_named() {
    let text = log_text();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let ch: Vec<usize> = (0..lines.len()).filter(|&i| lines[i].starts_with("$CH")).collect();
    let (a, b, c) = (ch[500], ch[600], ch[700]);
    // A line repeated, a damaged err_phas, and two messages on one line (a
    // write interleaved with another), from the last to the first.
    let dup = lines[c].clone();
    lines.insert(c + 1, dup);
    let mut f: Vec<String> = lines[b].split(',').map(String::from).collect();
    f[17] = "0.0\u{fffd}1".into();
    lines[b] = f.join(",");
    let merged = format!("{}{}", &lines[a][..30], lines[a + 1]);
    lines[a] = merged;
    lines.remove(a + 1);
    let damaged = lines.join("\n");
    let full = import_log(parse_log(text.as_bytes(), "full.log").unwrap(), &settings()).unwrap();
    let imported = import_log(parse_log(damaged.as_bytes(), "bad.log").unwrap(), &settings()).unwrap();
    assert_eq!(imported.garbled_count, 3, "{:?}", imported.garbled);
    let g: Vec<String> = imported.garbled.iter().map(|g| g.to_string()).collect();
    assert!(g.iter().any(|g| g.starts_with(&format!("line {}: two messages", a + 1))), "{g:?}");
    assert!(
        g.iter().any(|g| g.starts_with(&format!("line {b}: field 17 (err_phas)")) && g.contains("not a number")),
        "{g:?}"
    );
    assert!(g.iter().any(|g| g.contains("again or back in time")), "{g:?}");
    // At most the three lost lines are missing from the rows; nothing else changes.
    assert!(full.rows.len() - imported.rows.len() <= 3);
    let summary = gsens_pocketsdr::render_summary(&imported);
    assert!(summary.contains("3 garbled lines skipped") && summary.contains("bad.log: line"), "{summary}");
}

#[test]
fn channels_that_come_and_go_and_other_signals() {
    let text = log_text();
    let mut out = Vec::new();
    for l in text.lines() {
        let f: Vec<&str> = l.split(',').collect();
        let t: f64 = if f[0] == "$CH" { f[1].parse().unwrap() } else { -1.0 };
        // Channel 2 has no line from 20 s to 21 s (not tracked between).
        if f[0] == "$CH" && f[2] == "2" && (20.0..21.0).contains(&t) {
            continue;
        }
        // Channel 3 is lost and reacquired at 25 s: its lock time restarts.
        if f[0] == "$CH" && f[2] == "3" && t >= 25.0 {
            let mut g: Vec<String> = f.iter().map(|s| s.to_string()).collect();
            g[7] = format!("{:.3}", t - 25.0 + 0.05);
            out.push(g.join(","));
            continue;
        }
        out.push(l.to_string());
        // Another signal on another channel.
        if f[0] == "$CH" && f[2] == "1" {
            let mut g: Vec<String> = f.iter().map(|s| s.to_string()).collect();
            (g[2], g[5]) = ("9".into(), "L1CP".into());
            out.push(g.join(","));
        }
    }
    let imported = import_log(parse_log(out.join("\n").as_bytes(), "t.log").unwrap(), &settings()).unwrap();
    let ch2: Vec<_> = imported.tracks.iter().filter(|t| t.channel == 2).collect();
    assert_eq!(ch2.len(), 2, "{ch2:?}");
    assert!(ch2[0].reason.starts_with("no line from 19.900 s to 21.000 s"), "{}", ch2[0].reason);
    let ch3: Vec<_> = imported.tracks.iter().filter(|t| t.channel == 3).collect();
    assert_eq!(ch3.len(), 2, "{ch3:?}");
    assert!(ch3[0].reason.starts_with("lost and reacquired (lock time 0.05 s"), "{}", ch3[0].reason);
    // The reacquired track is kept after its own pull-in and settling only.
    let first_after = imported.rows.iter().find(|r| r.channel == 3 && r.t_s > 25.0).unwrap().t_s;
    assert!(first_after > 25.0 + 1.0 + imported.settle_s - 0.05, "{first_after}");
    assert!(first_after < 25.0 + 1.0 + imported.settle_s + 0.1, "{first_after}");
    assert_eq!(imported.other_signals.get("L1CP").copied(), Some(394), "{:?}", imported.other_signals);
    assert!(imported.rows.iter().all(|r| r.channel != 9));
    assert!(gsens_pocketsdr::render_summary(&imported).contains("L1CP: 394 $CH lines skipped"));
}

#[test]
fn empty_foreign_and_mismatched_inputs_are_errors_naming_the_file() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-pocketsdr-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    std::fs::create_dir_all(&dir).unwrap();
    let empty = dir.join("empty.log");
    std::fs::write(&empty, b"").unwrap();
    let e = read_log(&empty).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: empty log", empty.display())), "{e}");
    let e = read_log(&dir.join("missing.log")).unwrap_err().to_string();
    assert!(e.contains("missing.log: cannot read"), "{e}");
    // Only other signals.
    let l5 = log_text().replace(",L1CA,", ",L5I,");
    let e = import_log(parse_log(l5.as_bytes(), "l5.log").unwrap(), &settings()).unwrap_err();
    assert!(matches!(e, PocketSdrError::NoL1ca { .. }) && e.to_string().contains("L5I ("), "{e}");
    // The options say 40 Hz, the log is at 10 Hz: not the options it was made with.
    let o = dir.join("opt40.conf");
    std::fs::write(&o, "epoch = 0.025\n").unwrap();
    let s40 = ImportSettings::from_options_file(Some(&o)).unwrap();
    let e = import_log(read_log(&fixtures().join("trk.log")).unwrap(), &s40).unwrap_err().to_string();
    assert!(e.contains("are 0.1 s apart (lines") && e.contains("opt40.conf:1 gives epoch = 0.025"), "{e}");
    // A log that ends before any track settles.
    let short: String = log_text().lines().take(40).collect::<Vec<_>>().join("\n");
    let e = import_log(parse_log(short.as_bytes(), "short.log").unwrap(), &settings()).unwrap_err().to_string();
    assert!(e.starts_with("short.log: no GPS L1 C/A track is left"), "{e}");
}

/// The fixture calibrated with PocketSDR's exact loop and default settings.
fn closed_loop() -> gsens_pocketsdr::PocketSdrOutcome {
    let f = fixtures();
    gsens_pocketsdr::calibrate_pocketsdr(
        &f.join("trk.log"),
        &settings(),
        &f.join("imu.csv"),
        &gsens_calib::PipelineSettings::default(),
    )
    .unwrap()
}

/// The estimate from the fixture with PocketSDR's exact loop: every axis
/// within 3σ of the truth, the stated loop passes its test and the measured
/// response fits the model.
#[test]
fn calibrates_within_its_uncertainty() {
    let r = closed_loop();
    let truth = json("truth.json");
    let c = &r.outcome.calibration;
    for i in 0..3 {
        let t = truth["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap();
        let (g, s) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
        assert!((g - t).abs() < 3.0 * s, "axis {i}: {g} ± {s} vs {t}");
        assert!(s < 0.1 * t.abs(), "axis {i}: σ {s}");
    }
    assert_eq!(c.loop_used, gsens_core::LoopModel::PocketSdr(PocketSdrStage::l1ca(5.0)));
    let check = r.outcome.loop_response.as_ref().unwrap();
    assert!(check.consistent, "{check:?}");
}

/// The loop-free estimate from the same log: `adr` (the NCO's accumulated
/// phase) plus `err_phas` is the phase each loop was fed, so Γ follows with
/// no loop model (only T = 1 ms and single-block rows). Every axis within 3σ
/// of the truth, and within 3 joint σ of the closed-loop estimate with
/// PocketSDR's exact loop.
#[test]
fn the_loop_free_estimate_agrees_with_the_truth_and_the_closed_loop() {
    let f = fixtures();
    let imported = gsens_pocketsdr::import_file(&f.join("trk.log"), &settings()).unwrap();
    let tracking = gsens_pocketsdr::pocketsdr_tracking_log(&imported).unwrap();
    assert!(tracking.tracks().iter().all(|t| t.nco_phase_cycles.len() == t.len() && t.nco_freq_hz.len() == t.len()));
    let imu = gsens_io::read_imu_file(f.join("imu.csv")).unwrap();
    let settings = gsens_calib::LoopFreeSettings::new(1e-3, gsens_core::LoggedPhase::Last);
    let free = gsens_calib::estimate_loop_free(&tracking, &imu, &settings).unwrap();
    let closed = closed_loop();
    let truth = json("truth.json");
    let c = &closed.outcome.calibration;
    for i in 0..3 {
        let t = truth["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap();
        let (g, s) = (free.gamma_hz_per_mps2[i], free.sigma_hz_per_mps2()[i]);
        let (gc, sc) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
        eprintln!("axis {i}: loop-free {g} ± {s}, closed loop {gc} ± {sc}, truth {t}");
        assert!((g - t).abs() < 3.0 * s, "axis {i}: {g} ± {s} vs {t}");
        assert!((g - gc).abs() < 3.0 * s.hypot(sc), "axis {i}: {g} ± {s} vs closed loop {gc} ± {sc}");
    }
}

/// The estimate from the same log's NCO frequency (`dop`) through PocketSDR's
/// exact closed loop, as the pipeline makes it beside the others: every axis
/// within 3σ of the truth and within 3 joint σ of the loop-free estimate.
#[test]
fn the_nco_frequency_estimate_agrees_with_the_truth_and_the_loop_free_one() {
    let r = closed_loop();
    let truth = json("truth.json");
    let nco = r.outcome.nco_frequency.as_ref().expect("dop logged").as_ref().expect("an estimate");
    let free = r.outcome.loop_free.as_ref().expect("adr logged").as_ref().expect("an estimate");
    for i in 0..3 {
        let t = truth["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap();
        let (g, s) = (nco.gamma_hz_per_mps2[i], nco.sigma_hz_per_mps2()[i]);
        let (gf, sf) = (free.gamma_hz_per_mps2[i], free.sigma_hz_per_mps2()[i]);
        eprintln!("axis {i}: NCO frequency {g} ± {s}, loop-free {gf} ± {sf}, truth {t}");
        assert!((g - t).abs() < 3.0 * s, "axis {i}: {g} ± {s} vs {t}");
        assert!((g - gf).abs() < 3.0 * s.hypot(sf), "axis {i}: {g} ± {s} vs loop-free {gf} ± {sf}");
    }
}

/// With nothing of the loop told, the loop-free estimate chooses the rows'
/// bookkeeping itself. On PocketSDR's log (one 1 ms discriminator output per
/// 0.1 s row) it keeps `last` rows and a typical update interval (those up
/// to 20 ms fit within 1 % of each other's residual), and Γ̂ stays within 3σ
/// of the truth and within 1σ of the estimate told the 1 ms update. Compared
/// at the logged command instead of the phase's rate, the candidates once
/// chose the log interval, 0.1 s, with Γ̂ 25 % low.
#[test]
fn the_loop_free_bookkeeping_is_found_with_no_loop_told() {
    let f = fixtures();
    let imported = gsens_pocketsdr::import_file(&f.join("trk.log"), &settings()).unwrap();
    let tracking = gsens_pocketsdr::pocketsdr_tracking_log(&imported).unwrap();
    let imu = gsens_io::read_imu_file(f.join("imu.csv")).unwrap();
    // What the pipeline starts from with no loop stated: the log interval.
    let settings = gsens_calib::LoopFreeSettings::new(imported.interval_s(), gsens_core::LoggedPhase::Last);
    let chosen =
        gsens_calib::estimate_loop_free_choosing(&tracking, &imu, &settings, &gsens_calib::TYPICAL_LOOP_INTERVALS_S)
            .unwrap();
    eprintln!("chosen: {} s, {:?}", chosen.loop_interval_s, chosen.logged_phase);
    assert!(chosen.bookkeeping_chosen);
    assert!(chosen.loop_interval_s <= 0.02 + 1e-12, "{}", chosen.loop_interval_s);
    assert_eq!(chosen.logged_phase, gsens_core::LoggedPhase::Last);
    let told = gsens_calib::LoopFreeSettings::new(1e-3, gsens_core::LoggedPhase::Last);
    let told = gsens_calib::estimate_loop_free(&tracking, &imu, &told).unwrap();
    let truth = json("truth.json");
    for i in 0..3 {
        let t = truth["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap();
        let (g, s) = (chosen.gamma_hz_per_mps2[i], chosen.sigma_hz_per_mps2()[i]);
        eprintln!("axis {i}: chosen {g} ± {s}, told {}, truth {t}", told.gamma_hz_per_mps2[i]);
        assert!((g - t).abs() < 3.0 * s, "axis {i}: {g} ± {s} vs {t}");
        assert!((g - told.gamma_hz_per_mps2[i]).abs() < s, "axis {i}: {g} vs told {}", told.gamma_hz_per_mps2[i]);
    }
}
