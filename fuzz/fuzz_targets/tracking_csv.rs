//! `tracking.csv` (gsens_io::read_tracking): any bytes give a log or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(log) = gsens_io::read_tracking(data, "tracking.csv") {
        // The invariants the reader promises.
        assert!(log.epoch_t_s().windows(2).all(|w| w[0] < w[1]));
        let rows: usize = log.tracks().iter().map(|t| t.len()).sum();
        assert_eq!(rows, log.rows());
        for t in log.tracks() {
            assert!(t.t_s.windows(2).all(|w| w[0] < w[1]));
            assert!(t.phase_err_rad.iter().chain(&t.cn0_dbhz).all(|v| v.is_finite()));
        }
    }
});
