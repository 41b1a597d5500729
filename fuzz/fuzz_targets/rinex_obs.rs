//! RINEX observation files (gsens_rinex::read_rinex_bytes): any bytes give a log or an error,
//! never a panic out of the reader; an accepted log keeps its invariants (equal column lengths,
//! increasing times). The reader catches the `rinex` crate's own panics and refuses such input:
//! the panic hook here stays quiet, so that only a panic escaping the reader reaches
//! libfuzzer-sys, which aborts on it.
#![no_main]
use libfuzzer_sys::fuzz_target;

static QUIET: std::sync::Once = std::sync::Once::new();

fuzz_target!(|data: &[u8]| {
    QUIET.call_once(|| std::panic::set_hook(Box::new(|_| {})));
    if let Ok(log) = gsens_rinex::read_rinex_bytes(data, "fuzz.rnx") {
        assert!(log.epochs > 0);
        log.validate().unwrap();
    }
});
