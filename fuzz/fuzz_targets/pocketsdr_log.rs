//! PocketSDR logs (gsens_pocketsdr::parse_log): any bytes give a log or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = gsens_pocketsdr::parse_log(data, "pocket_trk.log");
});
