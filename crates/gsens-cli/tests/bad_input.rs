//! Bad input as the command line meets it: options checked as they are
//! parsed (each error naming its flag), before any file is read; a missing
//! file named once; a configuration too large to be one refused; an error
//! is exit status 2, never a panic. What each malformed log or out-of-range
//! setting is told is tested where it is made: `gsens-inputs`' tests
//! (`csv_errors.rs`) and `gsens-montecarlo`'s (`option_ranges.rs`).

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

#[test]
fn a_missing_file_is_named_with_the_reason_once() {
    let case = Case::new("missing-file", IMU_OK, TRK_OK);
    let (code, stderr) = estimate(&case.path("nope.csv"), &case.path("tracking.csv"), &[]);
    assert_eq!(code, 2);
    assert!(stderr.contains("nope.csv"), "{stderr}");
    // The OS's reason is said once, not once per level of the error chain.
    assert_eq!(stderr.matches("os error").count(), 1, "{stderr}");
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
        (&["--cn0-drop-db", "nan"][..], "--cn0-drop-db"),
        (&["--warmup-s=-1"][..], "--warmup-s"),
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
