//! `gsens live --plain` driven by `gsens replay` of the default session at
//! full speed: the guidance asks for x, then y, then z, stops when every
//! axis meets the target σ, keeps what it received, and its final Γ̂ is
//! `gsens report`'s on the logs it kept (within 0.1σ; the same numbers).
//! Smoke tests of the command whose end does not depend on the machine's
//! speed (the input's end, the target); the runtime's timing is tested in
//! gsens-live on an injected clock.

mod common;
use common::*;
use std::process::{Command, Stdio};

#[test]
fn live_guides_x_y_z_and_stops_at_the_target_with_the_batch_estimate() {
    let dir = temp_dir("live");
    let sim = dir.join("sim");
    let out = dir.join("live");
    gsens(&["simulate", "--out", sim.to_str().unwrap(), "--seed", "1"]);
    let truth = sim.join("truth.json");
    let live = replay_into_live(&sim, &["--target-sigma", "8e-4", "--out", &s(&out), "--truth", &s(&truth)]);
    let text = String::from_utf8(live.stdout).unwrap();
    assert!(live.status.success(), "{text}\n{}", String::from_utf8_lossy(&live.stderr));
    check_the_run(&text, &dir, &sim, &out);
    assert!(out.join("received/stdin.txt").exists());
}

/// `gsens replay DIR --speed 0` piped into `gsens live --stdin --plain` with `args`.
fn replay_into_live(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    let mut replay = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["replay", dir.to_str().unwrap(), "--speed", "0"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let live = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["live", "--stdin", "--plain"])
        .args(args)
        .stdin(replay.stdout.take().unwrap())
        .output()
        .unwrap();
    let _ = replay.wait();
    live
}

/// The same through files followed from their start (read whole at once,
/// merged in time order): it stops at the target, so neither the speed of
/// the machine nor the idle timeout (a safety here) decides the end.
/// Following files as they grow, the idle timeout and the merging are
/// gsens-live's tests (tests/runtime.rs), on an injected clock.
#[test]
fn live_follows_files() {
    let dir = temp_dir("live-follow");
    let sim = dir.join("sim");
    let out = dir.join("live");
    gsens(&["simulate", "--out", sim.to_str().unwrap(), "--seed", "1"]);
    let truth = sim.join("truth.json");
    let live = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["live", "--plain", "--target-sigma", "8e-4", "--idle-timeout-s", "60"])
        .args(["--follow-imu", &s(&sim.join("imu.csv")), "--follow-tracking", &s(&sim.join("tracking.csv"))])
        .args(["--out", out.to_str().unwrap(), "--truth", truth.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8(live.stdout).unwrap();
    assert!(live.status.success(), "{text}\n{}", String::from_utf8_lossy(&live.stderr));
    check_the_run(&text, &dir, &sim, &out);
    assert!(out.join("received").read_dir().unwrap().count() == 2);
}

/// The guidance sequence, the stop at the target before the data end, the
/// kept logs a prefix of the replayed ones, and the final Γ̂ that of `gsens
/// report` on the kept logs.
fn check_the_run(text: &str, dir: &std::path::Path, sim: &std::path::Path, out: &std::path::Path) {
    let truth = sim.join("truth.json");
    // The instructions in order.
    let said: Vec<&str> = text.lines().filter(|l| l.starts_with('[') && !l.contains("Γ̂")).collect();
    let first = |what: &str| said.iter().position(|l| l.contains(what));
    let (rest, x, y, z, done) = (
        first("rest: measuring"),
        first("shake x"),
        first("shake y"),
        first("shake z"),
        first("done: every axis meets the target σ"),
    );
    assert!(rest.is_some() && rest < x && x < y && y < z && z < done, "{}", said.join("\n"));
    assert!(text.contains("ended: every axis meets the target σ"), "{text}");
    // Stopped before the session's end (130 s): what was kept is a prefix of the logs replayed.
    for name in ["imu.csv", "tracking.csv"] {
        let kept = std::fs::read_to_string(out.join(name)).unwrap();
        let all = std::fs::read_to_string(sim.join(name)).unwrap();
        assert!(all.starts_with(&kept) && kept.len() < all.len(), "{name}");
    }
    // `gsens report` on the kept logs: the same Γ̂ within 0.1σ.
    let batch = dir.join("batch");
    let (imu, trk) = (out.join("imu.csv"), out.join("tracking.csv"));
    gsens_any(&[
        "report",
        "--imu",
        imu.to_str().unwrap(),
        "--tracking",
        trk.to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
        "--out",
        batch.to_str().unwrap(),
    ]);
    let (l, b) = (json(&out.join("report.json")), json(&batch.join("report.json")));
    let (gl, gb) = (vec3(&l["gamma_hz_per_mps2"]), vec3(&b["gamma_hz_per_mps2"]));
    let sb = vec3(&b["sigma_hz_per_mps2"]);
    for i in 0..3 {
        assert!(sb[i] <= 8e-4, "axis {i}: σ {} above the target", sb[i]);
        assert!((gl[i] - gb[i]).abs() <= 0.1 * sb[i], "axis {i}: live {} vs batch {} ± {}", gl[i], gb[i], sb[i]);
    }
    assert!(out.join("gsens_gamma.h").exists() && out.join("report.html").exists());
}

/// The terminal screen of a real session: the default session fed record by
/// record (the estimate re-run every 5 s of data, in line) up to 60 s, drawn
/// at 100×32 by `gsens_tui::render_text`, against the committed snapshot
/// (`UPDATE_SNAPSHOTS=1` rewrites it) that the README shows.
#[test]
fn the_screen_of_the_default_session_at_60_s() {
    use gsens_live::{LiveConfig, LiveSession, read_session_dir};
    let dir = temp_dir("live-screen");
    gsens(&["simulate", "--out", dir.to_str().unwrap(), "--seed", "1"]);
    let mut settings = gsens_inputs::settings_of_simulated_session(&dir.join("truth.json")).unwrap();
    // The screen of the estimate through the loop model, which the snapshot (and the README) shows.
    settings.measurement = gsens_calib::MeasurementChoice::TrackingError;
    let mut live = LiveSession::new(LiveConfig::new(settings, 8e-4)).unwrap();
    for (k, x) in read_session_dir(&dir).unwrap().iter().enumerate() {
        if x.t_s() > 60.0 {
            break;
        }
        live.push("stdin", k as u64 + 1, *x);
        if let Some(job) = live.batch_due() {
            live.apply(job.run());
        }
    }
    let text = gsens_tui::render_text(&live.view(), 100, 32);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots/live_default_60s.txt");
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &text).unwrap();
    }
    let expected = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text, expected, "the screen changed: UPDATE_SNAPSHOTS=1 rewrites {}", path.display());
    for what in ["has enough: shake z", "x  ", "met", "tracking", "TRUSTWORTHY"] {
        assert!(text.contains(what), "{what}:\n{text}");
    }
    // The README shows this screen.
    let readme =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap();
    assert!(readme.contains(expected.trim_end()), "README.md does not show tests/snapshots/live_default_60s.txt");
}

/// `gsens live --plain` on a session whose IMU logs in g: the batch lines
/// name the warning that decides the verdict, the warning is printed once
/// with its message, the end report says NOT TRUSTWORTHY with it, and the
/// kept report has no gsens_gamma.h.
#[test]
fn live_names_the_warnings_of_an_untrustworthy_session() {
    let dir = temp_dir("live-untrusted");
    let sim = dir.join("sim");
    let out = dir.join("live");
    gsens(&["simulate", "--out", sim.to_str().unwrap(), "--seed", "3"]);
    let g = dir.join("g");
    std::fs::create_dir_all(&g).unwrap();
    imu_in_g(&sim.join("imu.csv"), &g.join("imu.csv"));
    std::fs::copy(sim.join("tracking.csv"), g.join("tracking.csv")).unwrap();
    let live = replay_into_live(&g, &["--out", &s(&out), "--truth", &s(&sim.join("truth.json"))]);
    let (text, err) = (String::from_utf8(live.stdout).unwrap(), String::from_utf8_lossy(&live.stderr));
    assert_eq!(live.status.code(), Some(3), "{text}\n{err}");
    let batches: Vec<&str> = text.lines().filter(|l| l.starts_with('[') && l.contains("Γ̂ [Hz/(m/s²)]")).collect();
    assert!(batches.len() > 10, "{text}");
    // Every batch names imu_units among the codes that decide its verdict.
    // (The simulator logs the NCO: the lines' estimates are loop-free, and say so.)
    let named =
        |l: &&str| l.rsplit_once("| loop-free: NOT TRUSTWORTHY (").is_some_and(|(_, c)| c.contains("imu_units"));
    assert!(batches.iter().all(named), "{}", batches.join("\n"));
    // The warning with its fix, once while live, once more in the end report.
    assert_eq!(text.matches("warning [imu_units]: the specific force at rest").count(), 2, "{text}");
    let end = &text[text.find("ended: ").unwrap()..];
    assert!(end.contains("verdict: NOT TRUSTWORTHY (imu_units)"), "{end}");
    assert!(err.contains("gsens_gamma.h not written: the estimate is not trustworthy (imu_units)"), "{err}");
    assert!(!out.join("gsens_gamma.h").exists() && out.join("report.html").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// What a first-time user of `gsens live` runs into: no input option, a
/// mistyped file to follow (each refused at once, saying what is needed),
/// and the output cut short by `head` (ends quietly, never a panic; the
/// missing loop is said at the start).
#[test]
fn live_refuses_missing_inputs_and_ends_quietly_on_a_closed_pipe() {
    let dir = temp_dir("live-newcomer");
    let out = dir.join("live");
    let e = fails(&["live", "--plain", "--out", &s(&out)]);
    assert!(e.contains("no input: give --stdin") && e.contains("--follow-imu IMU.CSV with --follow-tracking"), "{e}");
    let sim = dir.join("sim");
    gsens(&["simulate", "--out", &s(&sim), "--seed", "1"]);
    let typo = dir.join("imu-typo.csv");
    let args = ["live", "--plain", "--follow-imu", &s(&typo), "--follow-tracking", &s(&sim.join("tracking.csv"))];
    let e = fails(&[&args[..], &["--out", &s(&out)]].concat());
    assert!(e.contains(&format!("--follow-imu {}: no such file", typo.display())), "{e}");
    // `2>&1 | head -4`, three times: the pipe closes under live while it prints.
    let gsens_bin = env!("CARGO_BIN_EXE_gsens");
    for run in 0..3 {
        let script = format!(
            "{gsens_bin} replay {} --speed 0 | {gsens_bin} live --stdin --plain --out {} 2>&1 | head -4; \
             echo \"status ${{PIPESTATUS[1]}}\"",
            s(&sim),
            s(&dir.join(format!("piped{run}")))
        );
        let o = Command::new("bash").args(["-c", &script]).output().unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.trim_end().ends_with("status 0"), "run {run}: {text}");
        assert!(!text.contains("panicked"), "run {run}: {text}");
        // No loop stated: said on the second line, not only in the final report.
        assert!(text.lines().nth(1).is_some_and(|l| l.starts_with("warning [loop_not_stated]")), "{text}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A session that ends (its input) before the target σ exits with 4 when
/// its estimate is trustworthy (3 is for an untrustworthy one).
#[test]
fn a_missed_target_exits_4() {
    let dir = temp_dir("live-missed");
    let sim = dir.join("sim");
    gsens(&["simulate", "--out", &s(&sim), "--seed", "1"]);
    let truth = s(&sim.join("truth.json"));
    let piped = replay_into_live(&sim, &["--target-sigma", "1e-6", "--out", &s(&dir.join("a")), "--truth", &truth]);
    let text = String::from_utf8_lossy(&piped.stdout);
    assert!(text.contains("ended: the input ended"), "{text}");
    assert!(text.contains("verdict: TRUSTWORTHY") && text.contains("was not met on every axis"), "{text}");
    assert_eq!(piped.status.code(), Some(4), "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `gsens live --ubx` following the fixture script's UBX log
/// (crates/gsens-live/tests/fixtures), complete from the start: the idle
/// timeout ends it (its length decides nothing but when), the batch lines
/// name the loop identified, and the report's Γ̂ and σ are those of
/// `gsens estimate --ubx` on the same log; so are they with the log on
/// standard input. A missing log is refused.
#[test]
fn live_follows_a_ubx_log_and_reports_as_estimate() {
    let dir = temp_dir("live-ubx");
    let log = concat!(env!("CARGO_MANIFEST_DIR"), "/../gsens-live/tests/fixtures/shaken.ubx");
    let out = dir.join("live");
    let args = ["live", "--plain", "--ubx", log, "--idle-timeout-s", "0.5", "--out", &s(&out)];
    let live = run(&args);
    let text = String::from_utf8_lossy(&live.stdout);
    // 40 s with x shaken alone: the target is missed, the estimate trustworthy.
    assert_eq!(live.status.code(), Some(4), "{text}\n{}", String::from_utf8_lossy(&live.stderr));
    assert!(text.contains("the receiver's loop is identified from the module's carrier phase"), "{text}");
    assert!(text.lines().any(|l| l.contains("Γ̂ [Hz/(m/s²)] x +0.08") && l.contains("| loop: order 2")), "{text}");
    assert!(text.contains("no new byte for 0.5 s") && text.contains("ended: the input ended"), "{text}");
    // The line the README shows of this log.
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let shown = readme.lines().find(|l| l.starts_with("[388851.90 s] Γ̂")).expect("the README shows a UBX batch line");
    assert!(text.lines().any(|l| l == shown), "{shown}\n---\n{text}");
    assert_eq!(std::fs::read(out.join("received.ubx")).unwrap(), std::fs::read(log).unwrap());
    let doc_path = dir.join("estimate.json");
    gsens(&["estimate", "--ubx", log, "--json", &s(&doc_path)]);
    let (report, estimate) = (json(&out.join("report.json")), json(&doc_path));
    for key in ["gamma_hz_per_mps2", "sigma_hz_per_mps2"] {
        assert_eq!(report[key], estimate[key], "{key}");
    }
    assert_eq!(report["identified_loop"]["bn_hz"], estimate["identified_loop"]["bn_hz"]);
    assert!(out.join("report.html").exists());
    // The same bytes on standard input (`--ubx -`), read until it closes.
    let piped = dir.join("piped");
    let live = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["live", "--plain", "--ubx", "-", "--out", &s(&piped)])
        .stdin(std::fs::File::open(log).unwrap())
        .output()
        .unwrap();
    assert_eq!(live.status.code(), Some(4), "{}", String::from_utf8_lossy(&live.stderr));
    let report = json(&piped.join("report.json"));
    assert_eq!(report["gamma_hz_per_mps2"], estimate["gamma_hz_per_mps2"]);
    assert_eq!(report["sigma_hz_per_mps2"], estimate["sigma_hz_per_mps2"]);
    let missing = dir.join("nothing.ubx");
    let e = fails(&["live", "--plain", "--ubx", &s(&missing), "--out", &s(&dir.join("b"))]);
    assert!(e.contains(&format!("--ubx {}: no such file", missing.display())), "{e}");
}
