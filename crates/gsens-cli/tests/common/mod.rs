//! What every CLI test needs: run `gsens`, read its JSON, a scratch folder.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs `gsens` with `args`.
pub(crate) fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gsens")).args(args).output().unwrap()
}

/// Runs `gsens` with `args`, asserts success and returns its standard output.
pub(crate) fn gsens(args: &[&str]) -> String {
    let out = run(args);
    assert!(out.status.success(), "gsens {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// Runs `gsens` with `args`, asserts that it produced an estimate (exit
/// status 0, or 3: produced but not trustworthy) and returns its standard
/// output and whether it was trustworthy.
pub(crate) fn gsens_any(args: &[&str]) -> (String, bool) {
    let out = run(args);
    let code = out.status.code();
    assert!(matches!(code, Some(0 | 3)), "gsens {args:?}: status {code:?}: {}", String::from_utf8_lossy(&out.stderr));
    (String::from_utf8(out.stdout).unwrap(), code == Some(0))
}

/// The JSON file at `path`.
pub(crate) fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A JSON array of three numbers (null → NaN).
pub(crate) fn vec3(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|i| v[i].as_f64().unwrap_or(f64::NAN))
}

/// A scratch folder, removed with everything in it when dropped (at the end
/// of the test, passed or failed); it derefs to its path.
pub(crate) struct TestDir(tempfile::TempDir);

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A fresh scratch folder for test `name` in the system's temporary
/// directory, removed when the returned value is dropped.
pub(crate) fn temp_dir(name: &str) -> TestDir {
    TestDir(tempfile::Builder::new().prefix(&format!("gsens-test-{name}-")).tempdir().unwrap())
}

/// A path as a string argument.
pub(crate) fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Runs `gsens` with `args`, asserts exit status 2 (an error, not a panic)
/// and returns its standard error.
pub(crate) fn fails(args: &[&str]) -> String {
    let out = run(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "gsens {args:?}: {err}");
    assert!(!err.contains("panicked"), "gsens {args:?} panicked: {err}");
    err
}

/// Writes `src` (an imu.csv in m/s²) as `dst` in g: fx, fy, fz divided by
/// g₀ = 9.80665 m/s², as an IMU logging in g would have written it.
pub(crate) fn imu_in_g(src: &Path, dst: &Path) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let mut g = String::from(lines.next().unwrap());
    g.push('\n');
    for l in lines {
        let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        g += &format!("{},{},{},{}\n", f[0], f[1] / 9.80665, f[2] / 9.80665, f[3] / 9.80665);
    }
    std::fs::write(dst, g).unwrap();
}
