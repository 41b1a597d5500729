//! Whole sessions through `gsens_live::Runtime` on an injected clock and
//! injected events: the records of a replayed session up to the target,
//! followed files that stop growing, a restarting logger and garbage. No
//! test waits on the wall clock: idle timeouts run on a `ManualClock`.

use std::sync::Arc;
use std::sync::mpsc;

use gsens_calib::PipelineSettings;
use gsens_live::{
    Clock, Display, Ending, Input, Inputs, LineFormat, ManualClock, Runtime, RuntimeConfig, RuntimeError, Source,
    SourceEvent, merged_header, merged_line, read_session_dir,
};

fn config(inputs: Inputs, out_dir: &std::path::Path, settings: PipelineSettings, idle_timeout_s: f64) -> RuntimeConfig {
    RuntimeConfig {
        inputs,
        out_dir: out_dir.to_path_buf(),
        settings,
        target_sigma_hz_per_mps2: 8e-4,
        batch_every_s: 5.0,
        idle_timeout_s,
    }
}

/// The default session's records as the merged stream's lines, sent at once
/// and the channel closed: the plain lines guide x, then y, then z, the
/// session stops at the target before the data end, and the final estimate
/// on the kept logs (a prefix of the session's) meets it.
#[test]
fn a_replayed_session_reaches_the_target() {
    let scratch = tempfile::Builder::new().prefix("gsens-runtime-replay-").tempdir().unwrap();
    let (sim, out) = (scratch.path().join("sim"), scratch.path().join("live"));
    let settings = simulated_session(&sim);
    let (tx, rx) = mpsc::channel();
    for (k, text) in merged_lines(&sim).into_iter().enumerate() {
        tx.send(SourceEvent::Line { source: 0, line: k as u64 + 1, text }).unwrap();
    }
    tx.send(SourceEvent::Ended { source: 0, why: None }).unwrap();
    drop(tx);
    let sources = vec![Source { name: "stdin".into(), format: Some(LineFormat::Merged) }];
    let inputs = Inputs::Events { sources, events: rx };
    let mut runtime = Runtime::start(config(inputs, &out, settings, 0.0), Arc::new(ManualClock::new())).unwrap();
    assert!(runtime.shaking_advice().starts_with("target σ 0.0008 Hz/(m/s²) per axis; shake each axis at"));
    // The loop is truth.json's, stated: the opening is the advice alone.
    assert_eq!(runtime.opening(), format!("gsens live: {}\n", runtime.shaking_advice()));
    let mut lines = Vec::new();
    let ending = runtime.run(Display::Plain(&mut lines)).unwrap();
    let text = String::from_utf8(lines).unwrap();
    assert_eq!(ending, Ending::TargetMet, "{text}");
    let said: Vec<&str> = text.lines().filter(|l| l.starts_with('[') && !l.contains("Γ̂")).collect();
    let first = |what: &str| said.iter().position(|l| l.contains(what));
    let order = ["rest: measuring", "shake x", "shake y", "shake z", "done: every axis meets the target σ"].map(first);
    assert!(order.iter().all(Option::is_some) && order.is_sorted(), "{}", said.join("\n"));
    // The session logs the NCO's phase: its batch estimates are the loop-free ones.
    assert!(text.lines().any(|l| l.contains("Γ̂ [Hz/(m/s²)]") && l.ends_with("| loop-free: trustworthy")), "{text}");
    assert_eq!(ending.heading(), "ended: every axis meets the target σ; the final estimate on everything received:\n");
    let finished = runtime.finish().unwrap();
    assert!(finished.target_met && finished.target_missed(8e-4).is_none());
    let (outcome, _) = finished.estimate.tracking().unwrap();
    let doc = outcome.document(None);
    assert!(doc.trustworthy, "{:?}", doc.warnings);
    for s in outcome.calibration.sigma_statistical_hz_per_mps2 {
        assert!(s.is_some_and(|s| s <= 8e-4), "{s:?}");
    }
    for name in ["imu.csv", "tracking.csv"] {
        let kept = std::fs::read_to_string(out.join(name)).unwrap();
        let all = std::fs::read_to_string(sim.join(name)).unwrap();
        assert!(all.starts_with(&kept) && kept.len() < all.len(), "{name}");
    }
    assert!(out.join("received/stdin.txt").exists());
}

/// The merged stream of the session in `dir`, as `gsens replay` writes it:
/// a line per record, the tracking records' columns declared before the first.
fn merged_lines(dir: &std::path::Path) -> Vec<String> {
    let inputs = read_session_dir(dir).unwrap();
    let first = inputs.iter().position(|x| matches!(x, Input::Tracking(_))).unwrap();
    let Input::Tracking(r) = &inputs[first] else { unreachable!() };
    let mut lines: Vec<String> = inputs.iter().map(merged_line).collect();
    lines.insert(first, merged_header(r));
    lines
}

/// The default session (seed 1) simulated into `dir`; the settings with its loop.
fn simulated_session(dir: &std::path::Path) -> PipelineSettings {
    gsens_sim::simulate_to_dir(&gsens_sim::scenario::Scenario::default(), 1, dir, |_| {}).unwrap();
    gsens_inputs::settings_of_simulated_session(&dir.join("truth.json")).unwrap()
}

/// The session's plain lines (instructions, batch estimates) and its end,
/// the target σ unreachable (1e-6): it runs to the end of its input.
fn whole_session(inputs: Inputs, out: &std::path::Path, settings: PipelineSettings) -> (Vec<String>, bool, bool) {
    let mut config = config(inputs, out, settings, 2.0);
    config.target_sigma_hz_per_mps2 = 1e-6;
    let mut runtime = Runtime::start(config, Arc::new(ManualClock::new())).unwrap();
    let mut lines = Vec::new();
    assert_eq!(runtime.run(Display::Plain(&mut lines)).unwrap(), Ending::InputEnded);
    let said = String::from_utf8(lines).unwrap().lines().filter(|l| l.starts_with('[')).map(String::from).collect();
    let finished = runtime.finish().unwrap();
    let missed = finished.target_missed(1e-6).unwrap();
    assert_eq!(
        missed,
        "the target σ (0.000001 Hz/(m/s²)) was not met on every axis: shake longer, or lower the target\n"
    );
    let trustworthy = finished.estimate.tracking().unwrap().0.document(None).trustworthy;
    (said, finished.target_met, trustworthy)
}

/// Files followed from their start give the session the records in time
/// order, as the merged stream does: the same guidance (the rest first) and
/// the same estimates on the same data. Ended before the target σ, the
/// estimate is trustworthy and the target missed (`gsens live` exits 4).
#[test]
fn followed_files_guide_as_the_merged_stream() {
    let scratch = tempfile::Builder::new().prefix("gsens-runtime-files-").tempdir().unwrap();
    let sim = scratch.path().join("sim");
    let settings = simulated_session(&sim);
    let merged: String = merged_lines(&sim).iter().map(|l| format!("{l}\n")).collect();
    let reader = Box::new(std::io::Cursor::new(merged.into_bytes()));
    let stdin = Inputs::Merged { name: "stdin".into(), reader };
    let (a, a_met, a_trusted) = whole_session(stdin, &scratch.path().join("a"), settings.clone());
    let files = Inputs::Files { imu: sim.join("imu.csv"), tracking: sim.join("tracking.csv") };
    let (b, b_met, b_trusted) = whole_session(files, &scratch.path().join("b"), settings);
    assert!(a.iter().take(2).any(|l| l.contains("rest: measuring")), "{}", a.join("\n"));
    assert_eq!(a, b, "the merged stream and the followed files differ");
    assert!(a_trusted && b_trusted && !a_met && !b_met);
}

/// Two followed files that stop growing: each ends after the stated idle
/// time on the injected clock (which moves only as the followers pause
/// between polls), saying so, and the session ends with its input; with
/// no tracking row there is nothing to estimate from.
#[test]
fn an_idle_timeout_fires_after_the_stated_time() {
    let scratch = tempfile::Builder::new().prefix("gsens-runtime-idle-").tempdir().unwrap();
    let (imu, trk) = (scratch.path().join("imu.csv"), scratch.path().join("tracking.csv"));
    std::fs::write(&imu, "t_s,fx_mps2,fy_mps2,fz_mps2\n0,0,0,9.81\n0.025,0,0,9.81\n0.05,0,0,9.81\n").unwrap();
    std::fs::write(&trk, "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n").unwrap();
    let clock = Arc::new(ManualClock::new());
    let inputs = Inputs::Files { imu: imu.clone(), tracking: trk.clone() };
    let out = scratch.path().join("live");
    let mut runtime = Runtime::start(config(inputs, &out, PipelineSettings::default(), 5.0), clock.clone()).unwrap();
    let mut lines = Vec::new();
    let ending = runtime.run(Display::Plain(&mut lines)).unwrap();
    let text = String::from_utf8(lines).unwrap();
    assert_eq!(ending, Ending::InputEnded, "{text}");
    for path in [&imu, &trk] {
        assert!(text.contains(&format!("notice: {}: no new line for 5 s", path.display())), "{text}");
    }
    // Both followers pause on the one clock, which only their pauses move:
    // none ends before 5 s of its own, and the later one starts at the latest
    // when the earlier ends (where the threads start is the scheduler's).
    let elapsed_s = clock.now().as_secs_f64();
    assert!((5.0..10.5).contains(&elapsed_s), "{elapsed_s} s");
    match runtime.finish() {
        Err(RuntimeError::NothingReceived { imu_samples: 3, tracking_rows: 0 }) => {}
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("an estimate without tracking"),
    }
}

/// A logger that restarts its file and lines that are not records: a notice
/// each, naming the source, the line and the column, and the session goes on.
#[test]
fn a_restarting_logger_and_garbage_lines_give_notices() {
    let scratch = tempfile::Builder::new().prefix("gsens-runtime-notices-").tempdir().unwrap();
    let (tx, rx) = mpsc::channel();
    let line = |source, line, text: &str| SourceEvent::Line { source, line, text: text.into() };
    for event in [
        line(0, 1, "t_s,fx_mps2,fy_mps2,fz_mps2"),
        line(0, 2, "0,0,0,9.81"),
        line(0, 3, "0.025,abc,0,9.81"),
        line(1, 1, "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad"),
        line(1, 2, "0,1,5,45,,0.01,7"),
        SourceEvent::Restarted { source: 0 },
        line(0, 1, "t_s,fx_mps2,fy_mps2,fz_mps2"),
        SourceEvent::Ended { source: 0, why: None },
        SourceEvent::Ended { source: 1, why: Some("no new line for 5 s".into()) },
    ] {
        tx.send(event).unwrap();
    }
    let sources = vec![
        Source { name: "imu.csv".into(), format: Some(LineFormat::Imu) },
        Source { name: "tracking.csv".into(), format: Some(LineFormat::Tracking) },
    ];
    let inputs = Inputs::Events { sources, events: rx };
    let out = scratch.path().join("live");
    let mut runtime =
        Runtime::start(config(inputs, &out, PipelineSettings::default(), 0.0), Arc::new(ManualClock::new())).unwrap();
    let mut lines = Vec::new();
    assert_eq!(runtime.run(Display::Plain(&mut lines)).unwrap(), Ending::InputEnded);
    let text = String::from_utf8(lines).unwrap();
    let notices: Vec<&str> = text.lines().filter(|l| l.starts_with("notice: ")).collect();
    assert_eq!(notices.len(), 4, "{text}");
    assert!(notices[0].starts_with("notice: imu.csv:3: ") && notices[0].contains("fx_mps2"), "{text}");
    assert!(notices[0].contains("abc") && notices[0].ends_with(": line not used"), "{text}");
    assert!(notices[1].starts_with("notice: tracking.csv:2: ") && notices[1].contains("columns"), "{text}");
    assert!(notices[2].contains("imu.csv: the file became shorter (a logger restarted?)"), "{text}");
    assert_eq!(notices[3], "notice: tracking.csv: no new line for 5 s");
    assert_eq!(runtime.session().view().notices.1, 4);
    // Every line is kept as received, the restart included.
    let kept = std::fs::read_to_string(out.join("received/imu.csv.txt")).unwrap();
    assert_eq!(kept.lines().count(), 4);
}
