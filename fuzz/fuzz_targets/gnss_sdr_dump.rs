//! GNSS-SDR tracking dumps (gsens_gnss_sdr::parse_dump): the first
//! byte picks the layout (any known one found by the reader, or one given),
//! the rest is the file; a dump or an error, never a panic.
#![no_main]
use gsens_gnss_sdr::{DumpLayout, parse_dump};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, bytes)) = data.split_first() else { return };
    let layout = match pick % 4 {
        0 => None,
        1 => Some(DumpLayout::v0_0_17()),
        2 => Some(DumpLayout::v0_0_21()),
        _ => Some(DumpLayout::kf_cc()),
    };
    if let Ok(d) = parse_dump(bytes, "trk_ch_0.dat", layout.as_ref()) {
        assert!(!d.records.is_empty());
    }
});
