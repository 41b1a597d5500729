//! `imu.csv` (gsens_io::read_imu): any bytes give a series or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(imu) = gsens_io::read_imu(data, "imu.csv") {
        // What the reader accepts it promises: strictly increasing, finite stamps.
        assert!(imu.t_s.windows(2).all(|w| w[0] < w[1]));
        assert!(imu.accel_mps2.iter().flatten().all(|v| v.is_finite()));
        let _ = imu.validate("imu.csv");
    }
});
