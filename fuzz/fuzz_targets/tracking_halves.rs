//! `tracking.csv` read by gsens_io's file reader's faster paths — the
//! quote-free fast path (whole, or in two halves at once) and the `csv`
//! reader in two halves — against the one-thread `csv` reader, on the same
//! bytes written to a file: where a faster path gives a log it is the
//! one-thread log (rows, tracks, epochs and their lines); where it declines,
//! nothing is lost (the one-thread reader decides).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("gsens-fuzz-halves-{}.csv", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    let faster = [
        gsens_io::tracking::read_tracking_file_in_halves(&path),
        gsens_io::tracking::read_tracking_file_plain(&path),
    ];
    for log in faster.into_iter().flatten() {
        let one = gsens_io::read_tracking(data, &path.display().to_string())
            .expect("a faster path accepted a log the one-thread reader refuses");
        // NaN elevations (empty cells) compare unequal: compare their bits.
        assert_eq!(format!("{log:?}"), format!("{one:?}"));
    }
});
