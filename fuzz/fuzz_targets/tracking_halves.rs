//! `tracking.csv` read in two halves at once (gsens_io's reader of long
//! files) against the one-thread reader, on the same bytes written to a
//! file: where the halves give a log it is the one-thread log (rows, tracks,
//! epochs and their lines); where they decline, nothing is lost (the
//! one-thread reader decides).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("gsens-fuzz-halves-{}.csv", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Some(halves) = gsens_io::tracking::read_tracking_file_in_halves(&path) {
        let one = gsens_io::read_tracking(data, &path.display().to_string())
            .expect("the halves accepted a log the one-thread reader refuses");
        // NaN elevations (empty cells) compare unequal: compare their bits.
        assert_eq!(format!("{halves:?}"), format!("{one:?}"));
    }
});
