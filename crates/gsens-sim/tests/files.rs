//! What the simulator reads and writes as files: a session simulated into a
//! folder is the same bytes for the same seed; a scenario file with a bad
//! value or an unknown key, or too large to be a configuration, is refused
//! naming the file.

use gsens_sim::scenario::Scenario;
use gsens_sim::{load_scenario, simulate_to_dir};

fn scratch(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("gsens-sim-{name}-")).tempdir().unwrap()
}

#[test]
fn same_seed_same_bytes() {
    let base = scratch("seed");
    let (a, b, c) = (base.path().join("a"), base.path().join("b"), base.path().join("c"));
    let scenario = Scenario::default();
    for (dir, seed) in [(&a, 3), (&b, 3), (&c, 4)] {
        std::fs::create_dir_all(dir).unwrap();
        simulate_to_dir(&scenario, seed, dir, |_| {}).unwrap();
    }
    for f in ["imu.csv", "tracking.csv", "truth.json"] {
        let (x, y) = (std::fs::read(a.join(f)).unwrap(), std::fs::read(b.join(f)).unwrap());
        assert!(x == y, "{f} differs between two runs with the same seed");
    }
    assert!(std::fs::read(a.join("tracking.csv")).unwrap() != std::fs::read(c.join("tracking.csv")).unwrap());
}

#[test]
fn a_bad_scenario_file_is_refused_naming_the_file_and_the_key() {
    let dir = scratch("scenario");
    let bad = dir.path().join("bad.toml");
    let text = Scenario::default_toml();
    std::fs::write(&bad, text.replace("bn_hz = 3.0", "bn_hz = -3.0")).unwrap();
    let err = load_scenario(Some(&bad)).unwrap_err().to_string();
    assert!(err.contains("bad.toml") && err.contains("bn_hz"), "{err}");
    std::fs::write(&bad, text.replace("bn_hz = 3.0", "bn_hz = 3.0\nbandwidth = 2")).unwrap();
    let err = load_scenario(Some(&bad)).unwrap_err().to_string();
    assert!(err.contains("bandwidth"), "{err}");
    // A file too large to be a configuration (a log in its place) is refused before it is read.
    let big = dir.path().join("big.toml");
    std::fs::File::create(&big).unwrap().set_len(2 << 20).unwrap();
    let err = load_scenario(Some(&big)).unwrap_err().to_string();
    assert!(err.contains("big.toml") && err.contains("2097152 bytes is not a configuration file"), "{err}");
}
