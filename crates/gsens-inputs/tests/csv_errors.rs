//! Every malformed CSV log gets a clear error naming the file, line and
//! column, through the route every front end reads logs with; never a panic.

use gsens_calib::{CalibrationOptions, PipelineSettings};
use gsens_inputs::{Inputs, Log};

const IMU_OK: &str = "t_s,fx_mps2,fy_mps2,fz_mps2\n0,0,0,9.8\n0.025,0.1,0,9.8\n0.05,0.2,0,9.8\n0.075,0.1,0,9.8\n";
const TRK_OK: &str = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n\
0,1,5,45,30,0.01\n0.025,1,5,45,30,0.02\n0.05,1,5,45,30,0.01\n0.075,1,5,45,30,0.0\n";

/// The error of calibrating `imu` and `tracking` (written as `imu.csv` and
/// `tracking.csv`) under `settings`.
fn error_with(imu: &str, tracking: &str, settings: &PipelineSettings) -> String {
    let dir = tempfile::Builder::new().prefix("gsens-inputs-csv-").tempdir().unwrap();
    let (imu_path, tracking_path) = (dir.path().join("imu.csv"), dir.path().join("tracking.csv"));
    std::fs::write(&imu_path, imu).unwrap();
    std::fs::write(&tracking_path, tracking).unwrap();
    let inputs = Inputs::Csv { imu: Log::File(imu_path), tracking: Log::File(tracking_path) };
    let Err(e) = inputs.calibrate(settings) else { panic!("no error") };
    e.to_string()
}

/// Checks that calibrating the case fails with every fragment in its error.
fn expect_error(name: &str, imu: &str, tracking: &str, fragments: &[&str]) {
    let e = error_with(imu, tracking, &CalibrationOptions::default().pipeline_settings().unwrap());
    for f in fragments {
        assert!(e.contains(f), "{name}: `{f}` not in: {e}");
    }
}

#[test]
fn missing_column() {
    let imu = "t_s,fx_mps2,fz_mps2\n0,0,9.8\n";
    expect_error("missing-col", imu, TRK_OK, &["imu.csv", "line 1", "missing column `fy_mps2`"]);
}

#[test]
fn non_numeric_cell() {
    let trk = TRK_OK.replace("0.025,1,5,45,30,0.02", "0.025,1,5,45,30,abc");
    expect_error("non-numeric", IMU_OK, &trk, &["tracking.csv", "line 3", "column 6 (`phase_err_rad`)", "`abc`"]);
}

#[test]
fn nan_and_inf() {
    let imu = IMU_OK.replace("0.05,0.2,0,9.8", "0.05,NaN,0,9.8");
    expect_error("nan", &imu, TRK_OK, &["imu.csv", "line 4", "column 2 (`fx_mps2`)", "not a finite number"]);
    let trk = TRK_OK.replace("0.05,1,5,45,30,0.01", "0.05,1,5,inf,30,0.01");
    expect_error("inf", IMU_OK, &trk, &["tracking.csv", "line 4", "column 4 (`cn0_dbhz`)", "not a finite number"]);
}

#[test]
fn time_going_backwards_or_repeated() {
    let imu = IMU_OK.replace("0.05,0.2,0,9.8", "0.01,0.2,0,9.8");
    expect_error("backwards", &imu, TRK_OK, &["imu.csv", "line 4", "column 1 (`t_s`)", "goes backwards"]);
    let imu = IMU_OK.replace("0.05,0.2,0,9.8", "0.025,0.2,0,9.8");
    expect_error("repeated", &imu, TRK_OK, &["imu.csv", "line 4", "repeated time stamp"]);
    let trk = TRK_OK.replace("0.05,1,5,45,30,0.01", "0.025,1,5,45,30,0.01");
    expect_error("repeated-channel", IMU_OK, &trk, &["tracking.csv", "line 4", "channel 1 appears twice"]);
}

#[test]
fn empty_file_and_header_only() {
    expect_error("empty", "", TRK_OK, &["imu.csv", "empty file"]);
    let header_only = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n";
    expect_error("header-only", IMU_OK, header_only, &["tracking.csv", "header only"]);
}

#[test]
fn streams_not_overlapping_in_time() {
    let imu = "t_s,fx_mps2,fy_mps2,fz_mps2\n100,0,0,9.8\n100.025,0,0,9.8\n";
    expect_error("no-overlap", imu, TRK_OK, &["imu.csv", "tracking.csv", "overlap"]);
}

#[test]
fn no_channel_passing_the_selection() {
    let options = {
        let mut o = CalibrationOptions::default();
        o.selection.min_cn0_dbhz = Some(50.0);
        o
    };
    let e = error_with(IMU_OK, TRK_OK, &options.pipeline_settings().unwrap());
    assert!(e.contains("no channel") || e.contains("No channel"), "{e}");
    assert!(e.contains("C/N0"), "{e}");
}

#[test]
fn a_missing_file_is_named() {
    let dir = tempfile::Builder::new().prefix("gsens-inputs-missing-").tempdir().unwrap();
    let (imu, tracking) = (dir.path().join("nope.csv"), dir.path().join("tracking.csv"));
    std::fs::write(&tracking, TRK_OK).unwrap();
    let inputs = Inputs::Csv { imu: Log::File(imu), tracking: Log::File(tracking) };
    let Err(e) = inputs.calibrate(&PipelineSettings::default()) else { panic!("no error") };
    let e = e.to_string();
    assert!(e.contains("nope.csv"), "{e}");
}
