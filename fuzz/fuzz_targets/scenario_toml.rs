//! The scenario TOML (gsens_sim::Scenario): any text gives a validated
//! scenario or an error naming the key, never a panic; an accepted scenario
//! has a bounded size (duration and rates), so simulating it ends.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(s) = gsens_sim::scenario::Scenario::from_toml_str(text) {
        let d = s.duration_s();
        assert!(d.is_finite() && d > 0.0 && d <= 1e6, "duration {d}");
        assert!(s.tracking_loop.interval_s >= 1e-3 - 1e-12);
        let _ = s.to_toml_string();
    }
});
