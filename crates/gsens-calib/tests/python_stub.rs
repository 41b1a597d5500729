//! The Python stub (python/gsens/_gsens.pyi) writes the `Loop` keywords'
//! defaults as numbers for type checkers and editors; the module takes them
//! from the library's constants. This test keeps the two equal.

use gsens_calib::defaults::{DEFAULT_BN_HZ, DEFAULT_ORDER};
use gsens_core::{KAPLAN_A3, KAPLAN_B3};

/// The default written for `name` in the stub's `class Loop` constructor.
fn loop_default(stub: &str, name: &str) -> f64 {
    let class = &stub[stub.find("class Loop:").expect("class Loop in the stub")..];
    let init = &class[..class.find(") -> None").expect("Loop.__init__ in the stub")];
    let line = init
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with(&format!("{name}:")))
        .unwrap_or_else(|| panic!("{name} in Loop.__init__"));
    let value = line.split('=').nth(1).unwrap_or_else(|| panic!("a default for {name}: {line}"));
    value.trim().trim_end_matches(',').parse().unwrap_or_else(|e| panic!("{name}: {line}: {e}"))
}

#[test]
fn the_stubs_loop_defaults_are_the_librarys() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../python/gsens/_gsens.pyi");
    let stub = std::fs::read_to_string(path).unwrap();
    assert_eq!(loop_default(&stub, "order"), f64::from(DEFAULT_ORDER));
    assert_eq!(loop_default(&stub, "bn_hz"), DEFAULT_BN_HZ);
    assert_eq!(loop_default(&stub, "a3"), KAPLAN_A3);
    assert_eq!(loop_default(&stub, "b3"), KAPLAN_B3);
}
