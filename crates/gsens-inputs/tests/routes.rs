//! The routes on GNSS-SDR 0.0.17 dumps (the fixtures of `gsens-gnss-sdr`):
//! keeping the tracking log changes nothing of the estimate, a log in
//! memory gives what its file gives, and a route that models its receiver's
//! loop refuses settings that state one.

use gsens_calib::PipelineSettings;
use gsens_inputs::{Conversion, IN_MEMORY, Inputs, InputsError, Log};
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures")
}

fn dumps() -> Inputs {
    let f = fixtures();
    let conf = f.join("order2/gnss-sdr.conf");
    let import = gsens_gnss_sdr::ImportSettings::from_conf(Some(&conf), None).unwrap();
    Inputs::GnssSdrDumps { imu: f.join("imu.csv"), dumps_dir: f.join("order2"), import, conf: Some(conf) }
}

fn json(c: &gsens_inputs::Calibrated) -> String {
    c.outcome.document(None).to_json_string().unwrap()
}

#[test]
fn keeping_the_tracking_log_changes_nothing_and_a_log_in_memory_is_its_file() {
    let settings = PipelineSettings::default();
    let plain = dumps().calibrate(&settings).unwrap();
    let kept = dumps().calibrate_keeping_tracking(&settings).unwrap();
    assert!(plain.tracking.is_none() && matches!(kept.conversion, Conversion::GnssSdr(Some(_))));
    assert_eq!(json(&plain), json(&kept));
    assert!(kept.track_summary().unwrap().contains("2 tracks, 2 used"));
    assert!(kept.loop_note().unwrap().starts_with("GNSS-SDR loop: GNSS-SDR"));
    let tracking = kept.tracking.unwrap();
    assert_eq!(tracking.tracks().len(), 2);

    // The dumps' rows as a CSV route: the IMU as its file or in memory.
    let imu_path = fixtures().join("imu.csv");
    let imu = gsens_io::read_imu_file(&imu_path).unwrap();
    let rows = |log| Log::Memory { name: "rows".into(), log };
    let from_file = Inputs::Csv { imu: Log::File(imu_path), tracking: rows(tracking.clone()) };
    let in_memory = Inputs::Csv { imu: Log::Memory { name: "imu".into(), log: imu }, tracking: rows(tracking) };
    let (a, b) = (from_file.calibrate(&settings).unwrap(), in_memory.calibrate_keeping_tracking(&settings).unwrap());
    assert_eq!(a.outcome.calibration.gamma_hz_per_mps2, b.outcome.calibration.gamma_hz_per_mps2);
    assert_eq!(b.outcome.inputs, [("imu".into(), IN_MEMORY.into()), ("tracking".into(), IN_MEMORY.into())]);
    assert!(a.loop_note().is_none() && a.track_summary().is_none() && b.tracking.is_some());
}

#[test]
fn gnss_sdr_rows_refuse_a_stated_loop() {
    let f = fixtures();
    let conf = f.join("order2/gnss-sdr.conf");
    let import = gsens_gnss_sdr::ImportSettings::from_conf(Some(&conf), None).unwrap();
    let mut settings = PipelineSettings::default();
    settings.loop_stated = true;
    let rows = Inputs::GnssSdrRows {
        imu: Log::File(f.join("imu.csv")),
        tracking: Log::File(f.join("no-such-rows.csv")),
        import,
        conf: conf.clone(),
    };
    assert!(rows.models_the_loop());
    match rows.calibrate(&settings) {
        Err(InputsError::LoopStatedTwice { conf: c }) => assert_eq!(c, conf.display().to_string()),
        other => panic!("{other:?}"),
    }
}
