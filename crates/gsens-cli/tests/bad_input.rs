//! Every malformed input gets a clear message naming the file, line and
//! column, and a non-zero exit status; never a panic.

use std::path::{Path, PathBuf};
use std::process::Command;

const IMU_OK: &str = "t_s,fx_mps2,fy_mps2,fz_mps2\n0,0,0,9.8\n0.025,0.1,0,9.8\n0.05,0.2,0,9.8\n0.075,0.1,0,9.8\n";
const TRK_OK: &str = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n\
0,1,5,45,30,0.01\n0.025,1,5,45,30,0.02\n0.05,1,5,45,30,0.01\n0.075,1,5,45,30,0.0\n";

struct Case {
    dir: PathBuf,
}

impl Case {
    fn new(name: &str, imu: &str, tracking: &str) -> Case {
        let dir = std::env::temp_dir().join(format!("gsens-bad-input-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("imu.csv"), imu).unwrap();
        std::fs::write(dir.join("tracking.csv"), tracking).unwrap();
        Case { dir }
    }
    fn path(&self, f: &str) -> PathBuf {
        self.dir.join(f)
    }
}

impl Drop for Case {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn estimate(imu: &Path, tracking: &Path, extra: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .arg("estimate")
        .arg("--imu")
        .arg(imu)
        .arg("--tracking")
        .arg(tracking)
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

/// Runs `estimate` on the case and checks a non-zero exit and every fragment in stderr.
fn expect_error(name: &str, imu: &str, tracking: &str, fragments: &[&str]) {
    let case = Case::new(name, imu, tracking);
    let (code, stderr) = estimate(&case.path("imu.csv"), &case.path("tracking.csv"), &[]);
    assert_ne!(code, 0, "{name}: exit status 0");
    assert_eq!(code, 2, "{name}: {stderr}");
    for f in fragments {
        assert!(stderr.contains(f), "{name}: `{f}` not in: {stderr}");
    }
}

#[test]
fn missing_column() {
    expect_error(
        "missing-col",
        "t_s,fx_mps2,fz_mps2\n0,0,9.8\n",
        TRK_OK,
        &["imu.csv", "line 1", "missing column `fy_mps2`"],
    );
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
    expect_error(
        "header-only",
        IMU_OK,
        "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n",
        &["tracking.csv", "header only"],
    );
}

#[test]
fn streams_not_overlapping_in_time() {
    let imu = "t_s,fx_mps2,fy_mps2,fz_mps2\n100,0,0,9.8\n100.025,0,0,9.8\n";
    expect_error("no-overlap", imu, TRK_OK, &["imu.csv", "tracking.csv", "overlap"]);
}

#[test]
fn no_channel_passing_the_selection() {
    let case = Case::new("no-channel", IMU_OK, TRK_OK);
    let (code, stderr) = estimate(&case.path("imu.csv"), &case.path("tracking.csv"), &["--min-cn0-dbhz", "50"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("no channel") || stderr.contains("No channel"), "{stderr}");
    assert!(stderr.contains("C/N0"), "{stderr}");
}

#[test]
fn missing_file() {
    let case = Case::new("missing-file", IMU_OK, TRK_OK);
    let (code, stderr) = estimate(&case.path("nope.csv"), &case.path("tracking.csv"), &[]);
    assert_eq!(code, 2);
    assert!(stderr.contains("nope.csv"), "{stderr}");
    // The OS's reason is said once, not once per level of the error chain.
    assert_eq!(stderr.matches("os error").count(), 1, "{stderr}");
}

/// Cases found by hand: an absurd offset bound hung (its search grid
/// grew without limit), a NaN C/N0 drop switched the test off, a negative
/// warm-up was taken. Each is now an error naming the setting and its range.
/// (A high-pass above the log's Nyquist frequency is not refused here: it is
/// what time stamps in milliseconds make of the default, which the
/// `time_units` check names; the estimate is then not trustworthy.)
#[test]
fn out_of_range_options_are_errors_not_hangs_or_silent_changes() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-bad-options-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    let sim = Command::new(env!("CARGO_BIN_EXE_gsens")).args(["simulate", "--out"]).arg(&dir).output().unwrap();
    assert!(sim.status.success());
    let (imu, trk) = (dir.join("imu.csv"), dir.join("tracking.csv"));
    for (args, said) in [
        (&["--time-offset-max-s", "1e18"][..], "time_offset.max_abs_s"),
        (&["--cn0-drop-db", "nan"][..], "--cn0-drop-db"),
        (&["--warmup-s=-1"][..], "--warmup-s"),
        // Found by fuzzing: a loop updated every nanosecond ran for minutes; the
        // others were accepted.
        (&["--loop-interval-s", "1e-9"][..], "loop_interval_s = 1e-9 is out of range: expected at least 0.001 s"),
        (&["--carrier-hz", "1e300"][..], "carrier_hz = 1e300 is out of range"),
        (&["--imu-scale-sigma-ppm", "1e300"][..], "imu_scale_sigma = 1e294 is out of range"),
    ] {
        let started = std::time::Instant::now();
        let (code, stderr) = estimate(&imu, &trk, args);
        assert_eq!(code, 2, "{args:?}: {stderr}");
        assert!(stderr.contains(said), "{args:?}: {stderr}");
        assert!(started.elapsed().as_secs() < 60, "{args:?} took {:?}", started.elapsed());
    }
    // A high-pass above the loop's band leaves nothing to estimate: the verdict names it (it was
    // "unobservable: shake harder" with exit 0, found by fuzzing).
    let out = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["estimate", "--order", "2", "--bn-hz", "3", "--loop-interval-s", "0.001", "--highpass-hz", "25"])
        .arg("--imu")
        .arg(&imu)
        .arg("--tracking")
        .arg(&trk)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(3), "{stdout}");
    assert!(
        stdout.contains(
            "warning [highpass]: the high-pass at 25 Hz is at or above the top of the loop's half-power band"
        ),
        "{stdout}"
    );
    // A warm-up as long as the log is named with the option and the log's length, once.
    let (code, stderr) = estimate(&imu, &trk, &["--order", "2", "--bn-hz", "3", "--warmup-s", "500"]);
    assert_eq!(code, 2, "{stderr}");
    let cause = "the warm-up of 500 s (warmup_s, --warmup-s) is not shorter than the log (";
    assert!(stderr.contains(cause), "{stderr}");
    assert_eq!(stderr.matches(cause).count(), 1, "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Options are checked as they are parsed, before any file is read (the
/// logs named here do not exist): each error names the option and its
/// range, a negative number is read as the value it is, a method's
/// parameter given to another method is refused, and an output that cannot
/// be written is named before the work.
#[test]
fn options_are_checked_before_any_file_is_read() {
    let dir = std::env::temp_dir().join(format!("gsens-options-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (imu, trk) = (dir.join("missing-imu.csv"), dir.join("missing-tracking.csv"));
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let under_file = format!("{}/r.json", file.display());
    for (args, said) in [
        (&["--bn-hz", "-3"][..], "invalid value '-3' for '--bn-hz <BN_HZ>': -3 is not a finite number > 0"),
        (&["--bn-hz", "0"][..], "for '--bn-hz <BN_HZ>': 0 is not a finite number > 0"),
        (&["--zeta", "0"][..], "'--zeta <ZETA>': 0 is not a finite number > 0"),
        (&["--loop-interval-s", "-0.001"][..], "'--loop-interval-s <LOOP_INTERVAL_S>': -0.001 is not"),
        (&["--carrier-hz", "-1575.42e6"][..], "'--carrier-hz <CARRIER_HZ>'"),
        (&["--method", "rls", "--lambda", "2"][..], "'--lambda <LAMBDA>': 2 is not in (0, 1]"),
        (&["--lambda", "0.99"][..], "--lambda is the RLS estimator's forgetting factor: it needs --method rls"),
        (
            &["--gain-k", "2", "--method", "rls"][..],
            "--gain-k is the gradient observer's gain: it needs --method gradient",
        ),
        (&["--time-offset", "5"][..], "5 s is beyond ±1 s"),
        (&["--order", "3", "--zeta", "0.8"][..], "--zeta is the damping of a 2nd-order loop"),
        (&["--a3", "1.2"][..], "--a3 and --b3 shape a 3rd-order loop: they need --order 3"),
        (&["--json", "/nonexistent-gsens-dir/r.json"][..], "--json /nonexistent-gsens-dir/r.json: the directory"),
        (&["--epochs-out", &under_file][..], "--epochs-out"),
    ] {
        let (code, stderr) = estimate(&imu, &trk, args);
        assert_eq!(code, 2, "{args:?}: {stderr}");
        assert!(stderr.contains(said), "{args:?}: {stderr}");
        assert!(!stderr.contains("missing-imu.csv"), "{args:?}: a log was read first: {stderr}");
    }
    // A converter's option takes a negative number as its value, and its own check names it.
    let o = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["import", "pocketsdr", "missing.log", "--pocketsdr-toff-s", "-1"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(2) && e.contains("--pocketsdr-toff-s must be ≥ 0 and finite, got -1"), "{e}");
    // Every on/off option's help says on|off, never clap's true/false beside a default of `on`.
    let help = Command::new(env!("CARGO_BIN_EXE_gsens")).args(["estimate", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("--loop-check <on|off>") && help.contains("--screening <on|off>"), "{help}");
    assert!(!help.contains("possible values: true, false"), "{help}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A file given as a configuration that is too large to be one (a log in its
/// place) is refused before it is read: scenario, GNSS-SDR and PocketSDR options.
#[test]
fn configuration_files_beyond_a_megabyte_are_refused() {
    let case = Case::new("big-config", IMU_OK, TRK_OK);
    let big = case.path("big.toml");
    std::fs::File::create(&big).unwrap().set_len(2 << 20).unwrap();
    for args in [
        vec!["simulate".to_string(), "--scenario".into(), big.display().to_string(), "--out".into()],
        vec!["estimate".to_string(), "--gnss-sdr".into(), case.dir.display().to_string(), "--gnss-sdr-conf".into()],
    ] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_gsens"));
        cmd.args(&args);
        if args[0] == "simulate" {
            cmd.arg(case.path("out"));
        } else {
            cmd.arg(&big).arg("--imu").arg(case.path("imu.csv"));
        }
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("big.toml") && stderr.contains("2097152 bytes is not a configuration file"),
            "{stderr}"
        );
    }
}

/// The other commands' number options are checked as they are parsed too,
/// naming the option and its range.
#[test]
fn other_commands_check_their_numbers_as_parsed() {
    for (args, said) in [
        (&["validate", "--latency-s", "-1"][..], "'--latency-s <LATENCY_S>': -1 is not a finite number ≥ 0"),
        (&["simulate", "--out", "unused", "--iq", "unused/s.bin", "--fs-hz", "0"][..], "'--fs-hz <FS_HZ>': 0 is not"),
        (&["montecarlo", "--stated-bn-scale", "-1"][..], "'--stated-bn-scale <STATED_BN_SCALE>': -1 is not"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_gsens")).args(args).output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.code() == Some(2) && e.contains(said), "{args:?}: {e}");
    }
}
