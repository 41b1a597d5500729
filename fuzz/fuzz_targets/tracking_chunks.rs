//! `tracking.csv` read by gsens_io's file reader's fast path — the
//! quote-free parser over chunks split at line ends, joined in file order —
//! against the `csv` reader, on the same bytes written to a file: where the
//! fast path gives a log it is the `csv` reader's log (rows, tracks, epochs
//! and their lines), whatever the chunk size; where it declines, nothing is
//! lost (the `csv` reader decides).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("gsens-fuzz-chunks-{}.csv", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    // Chunk sizes from the data, so that short inputs are read in many chunks.
    let small = 1 + u64::from(data.first().copied().unwrap_or(0) % 64);
    let faster = [
        gsens_io::read_tracking_file_in_chunks(&path, small),
        gsens_io::read_tracking_file_in_chunks(&path, 1),
        gsens_io::read_tracking_file_plain(&path),
    ];
    for log in faster.into_iter().flatten() {
        let one = gsens_io::read_tracking(data, &path.display().to_string())
            .expect("the fast path accepted a log the csv reader refuses");
        // NaN elevations (empty cells) compare unequal: compare their bits.
        assert_eq!(format!("{log:?}"), format!("{one:?}"));
    }
});
