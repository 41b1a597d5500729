//! PocketSDR option files (gsens_pocketsdr::PocketSdrOptions::parse): any text, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = gsens_pocketsdr::PocketSdrOptions::parse(text, "pocket_trk.conf");
});
