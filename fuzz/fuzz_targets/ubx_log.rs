//! UBX logs (gsens_ublox::read_ubx_bytes), the first byte picking the sensor time rule: any
//! bytes give a log or an error, never a panic; an accepted log keeps its invariants
//! (observation columns of equal length and increasing times, an IMU series strictly
//! increasing and finite).
#![no_main]
use gsens_ublox::{SensorTime, UbxSettings, read_ubx_bytes};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else { return };
    let sensor_time = if first & 1 == 0 { SensorTime::FreeRunningMs } else { SensorTime::GpsTowMs };
    if let Ok(log) = read_ubx_bytes(rest, "fuzz.ubx", &UbxSettings { sensor_time }) {
        log.observations.validate().unwrap();
        if !log.imu.is_empty() {
            log.imu.validate("imu").unwrap();
        }
        assert!(log.bytes_outside_frames <= rest.len());
    }
});
