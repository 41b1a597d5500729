//! GNSS-SDR's `.mat` tracking dumps (gsens_gnss_sdr::mat::parse_mat_dump, its
//! own reader of the HDF5 that matio writes): the first byte picks the layout
//! (0: the known one whose fields are the file's variables; k: the k-th known
//! layout, cyclically), the rest is the file; a dump or an error, never a
//! panic, a hang or an allocation the file cannot back.
#![no_main]
use gsens_gnss_sdr::DumpLayout;
use gsens_gnss_sdr::mat::parse_mat_dump;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, file)) = data.split_first() else { return };
    let known = DumpLayout::known();
    let forced = usize::from(pick).checked_sub(1).map(|k| &known[k % known.len()]);
    if let Ok(dump) = parse_mat_dump(file, "trk_ch_0.mat", forced) {
        assert!(!dump.records.is_empty());
    }
});
