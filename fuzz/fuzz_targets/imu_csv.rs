//! `imu.csv`: any bytes give a series or an error, never a panic; and the
//! file reader (its quote-free fast path, or `csv` where that declines) gives
//! what the stream reader gives on the same bytes, errors included.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("gsens-fuzz-imu-{}.csv", std::process::id()));
    let name = path.display().to_string();
    let stream = gsens_io::read_imu(data, &name);
    if let Ok(imu) = &stream {
        // What the reader accepts it promises: strictly increasing, finite stamps.
        assert!(imu.t_s.windows(2).all(|w| w[0] < w[1]));
        assert!(imu.accel_mps2.iter().flatten().all(|v| v.is_finite()));
        let _ = imu.validate("imu.csv");
    }
    if std::fs::write(&path, data).is_ok() {
        match (gsens_io::read_imu_file(&path), stream) {
            (Ok(a), Ok(b)) => assert_eq!(a, b),
            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
            (a, b) => panic!("file reader {a:?}, stream reader {b:?}"),
        }
    }
});
