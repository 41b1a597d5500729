//! A live session on a log that carries the NCO's phase (`nco_phase_cycles`,
//! `nco_freq_hz`): the columns reach the batch estimate, which is then the
//! loop-free one where the measurement choice allows, equal to
//! `calibrate_logs` on the same logs; without the columns it stays the
//! estimate through the loop model. No test waits on the wall clock.

use std::sync::{Arc, Mutex, mpsc};

use gsens_calib::{Measurement, MeasurementChoice, PipelineSettings, calibrate_logs};
use gsens_io::TrackingRecord;
use gsens_live::{
    Display, Ending, Input, LineFormat, LineKind, LiveConfig, LiveSession, ManualClock, ReplaySink, Runtime,
    RuntimeConfig, Source, SourceEvent, read_session_dir, replay,
};

/// The default session (seed 1) with the NCO logged, simulated into a
/// scratch folder; the settings with its loop.
fn nco_session() -> (tempfile::TempDir, PipelineSettings) {
    let scratch = tempfile::Builder::new().prefix("gsens-live-nco-").tempdir().unwrap();
    let mut scenario = gsens_sim::scenario::Scenario::default();
    scenario.log.nco = true;
    gsens_sim::simulate_to_dir(&scenario, 1, scratch.path(), |_| {}).unwrap();
    let settings = gsens_inputs::settings_of_simulated_session(&scratch.path().join("truth.json")).unwrap();
    (scratch, settings)
}

/// A writer into a shared buffer.
#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl std::io::Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The batch estimate of `inputs` pushed into a session under `settings`.
fn final_estimate(inputs: &[Input], settings: PipelineSettings) -> (LiveSession, gsens_live::BatchResult) {
    let mut live = LiveSession::new(LiveConfig::new(settings, 1e-9)).unwrap();
    for (k, x) in inputs.iter().enumerate() {
        assert!(live.push("replay", k as u64 + 1, *x).used, "record {k}");
    }
    let result = live.final_job().run();
    (live, result)
}

/// `gsens replay` of a log with the NCO columns declares them in the merged
/// stream and the records read back the same; the session's batch estimate
/// is loop-free and equal, bit for bit, to `calibrate_logs` on the files;
/// under `measurement = tracking_error`, or on the same rows without the NCO
/// columns, it is the estimate through the loop model.
#[test]
fn a_log_with_the_nco_gives_the_loop_free_estimate_of_its_files() {
    let (scratch, settings) = nco_session();
    let dir = scratch.path();
    let inputs = read_session_dir(dir).unwrap();
    let Some(Input::Tracking(first)) = inputs.iter().find(|x| matches!(x, Input::Tracking(_))) else {
        panic!("no tracking record")
    };
    assert!(first.nco_phase_cycles.is_some() && first.nco_freq_hz.is_some() && first.carrier.is_none());

    // The merged stream: the tagged header once, before the first tracking record.
    let out = Shared::default();
    replay(&inputs, 0.0, &ManualClock::new(), &mut ReplaySink::Merged(Box::new(out.clone()))).unwrap();
    let text = String::from_utf8(out.0.lock().unwrap().clone()).unwrap();
    let header = "trk,t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles,nco_freq_hz";
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.iter().filter(|l| l.starts_with("trk,t_s")).count(), 1);
    let at = lines.iter().position(|l| *l == header).expect("the tagged header");
    assert!(lines[..at].iter().all(|l| l.starts_with("imu,")) && lines[at + 1].starts_with("trk,"));
    let mut parser = LineFormat::Merged.parser();
    let back: Vec<Input> = lines
        .iter()
        .filter_map(|l| match parser.parse(l).unwrap() {
            LineKind::Data(x) => Some(x),
            LineKind::Skip => None,
        })
        .collect();
    assert!(back == inputs, "the merged stream does not read back as the session's records");

    // Files: the same estimate as calibrate_logs on the simulated files.
    let tracking = gsens_io::read_tracking_file(dir.join("tracking.csv")).unwrap();
    let imu = gsens_io::read_imu_file(dir.join("imu.csv")).unwrap();
    assert!(tracking.epoch_t_s().last() <= imu.t_s.last(), "every row is in the session's final job");
    let files = calibrate_logs(&tracking, &imu, "imu.csv", &settings).unwrap();
    assert_eq!(files.measurement, Measurement::InputPhase);
    let (mut live, result) = final_estimate(&inputs, settings.clone());
    let outcome = result.outcome.as_ref().unwrap().tracking().unwrap();
    assert_eq!(outcome.measurement, Measurement::InputPhase);
    assert_eq!(outcome.calibration.gamma_hz_per_mps2, files.calibration.gamma_hz_per_mps2);
    assert_eq!(outcome.calibration.sigma_hz_per_mps2, files.calibration.sigma_hz_per_mps2);
    assert!(outcome.tracking_error.is_some(), "the estimate through the loop model beside it");
    live.apply(result);
    assert_eq!(live.view().batch.unwrap().measurement, Measurement::InputPhase);

    // The measurement chosen by the settings.
    let mut closed = settings.clone();
    closed.measurement = MeasurementChoice::TrackingError;
    let (_, result) = final_estimate(&inputs, closed);
    let outcome = result.outcome.as_ref().unwrap().tracking().unwrap();
    assert_eq!(outcome.measurement, Measurement::TrackingError);
    assert_eq!(outcome.calibration.gamma_hz_per_mps2, files.closed_loop().gamma_hz_per_mps2);

    // The same rows without the NCO columns: through the loop model.
    let plain: Vec<Input> = inputs
        .iter()
        .map(|x| match x {
            Input::Tracking(r) => Input::Tracking(TrackingRecord::plain(r.row)),
            imu => *imu,
        })
        .collect();
    let (_, result) = final_estimate(&plain, settings);
    let outcome = result.outcome.as_ref().unwrap().tracking().unwrap();
    assert_eq!(outcome.measurement, Measurement::TrackingError);
    assert!(outcome.loop_free.is_none());
    assert_eq!(outcome.calibration.gamma_hz_per_mps2, files.closed_loop().gamma_hz_per_mps2);
}

/// A whole session on the merged stream `gsens replay` writes of a log with
/// the NCO: every batch line says its estimate is loop-free, a bad NCO cell
/// is a notice naming its line and column, a row without the NCO columns
/// after rows with them is refused, and the final estimate on the kept logs
/// (which keep the columns) is loop-free.
#[test]
fn a_live_session_says_it_runs_on_the_loop_free_estimate() {
    let (scratch, settings) = nco_session();
    let inputs = read_session_dir(scratch.path()).unwrap();
    let out = Shared::default();
    replay(&inputs, 0.0, &ManualClock::new(), &mut ReplaySink::Merged(Box::new(out.clone()))).unwrap();
    let text = String::from_utf8(out.0.lock().unwrap().clone()).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // After the header and a few rows: a row of the six only (declared as
    // such: a row with cells missing is not a row), then the NCO columns
    // declared again and a row with a bad NCO cell.
    let header = lines.iter().position(|l| l.starts_with("trk,t_s")).unwrap();
    let at = header + 40;
    let row: Vec<&str> = lines[at].split(',').collect();
    let bad = format!("{},nan,{}", row[..7].join(","), row[8]);
    let six = row[..7].join(",");
    let inserted = [format!("trk,{}", gsens_io::TRACKING_COLUMNS.join(",")), six, lines[header].clone(), bad];
    lines.splice(at..at, inserted);
    let (tx, rx) = mpsc::channel();
    for (k, text) in lines.into_iter().enumerate() {
        tx.send(SourceEvent::Line { source: 0, line: k as u64 + 1, text }).unwrap();
    }
    tx.send(SourceEvent::Ended { source: 0, why: None }).unwrap();
    drop(tx);
    let live = scratch.path().join("live");
    let config = RuntimeConfig {
        inputs: gsens_live::Inputs::Events {
            sources: vec![Source { name: "stdin".into(), format: Some(LineFormat::Merged) }],
            events: rx,
        },
        out_dir: live.clone(),
        settings,
        target_sigma_hz_per_mps2: 1e-6,
        batch_every_s: 20.0,
        idle_timeout_s: 0.0,
    };
    let mut runtime = Runtime::start(config, Arc::new(ManualClock::new())).unwrap();
    let mut said = Vec::new();
    assert_eq!(runtime.run(Display::Plain(&mut said)).unwrap(), Ending::InputEnded);
    let said = String::from_utf8(said).unwrap();
    let batches: Vec<&str> =
        said.lines().filter(|l| l.contains("Γ̂ [Hz/(m/s²)]") && !l.contains("| no estimate")).collect();
    assert!(batches.len() >= 4, "{said}");
    assert!(batches.iter().all(|l| l.contains("| loop-free: ")), "{said}");
    let (six_line, bad_line) = (at + 2, at + 4);
    let notice = format!("notice: stdin:{bad_line}: column 8 (`nco_phase_cycles`): `nan` is not a finite number");
    assert!(said.contains(&notice), "{said}");
    assert!(said.contains(&format!("notice: stdin:{six_line}: a tracking row with the columns ")), "{said}");
    let finished = runtime.finish().unwrap();
    let (outcome, tracking) = finished.estimate.tracking().unwrap();
    assert_eq!(outcome.measurement, Measurement::InputPhase);
    let kept = std::fs::read_to_string(live.join("tracking.csv")).unwrap();
    assert!(kept.starts_with(&format!("{}\n", &header_of(&inputs)[4..])), "{}", &kept[..200]);
    assert!(tracking.tracks().iter().all(|t| t.nco_phase_cycles.len() == t.len()));
}

/// The tagged header of the session's tracking records.
fn header_of(inputs: &[Input]) -> String {
    let first = inputs.iter().find_map(|x| match x {
        Input::Tracking(r) => Some(r),
        Input::Imu { .. } => None,
    });
    gsens_live::merged_header(first.unwrap())
}
