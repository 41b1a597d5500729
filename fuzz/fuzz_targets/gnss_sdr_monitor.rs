//! GNSS-SDR's tracking monitor: its datagrams (protobuf over UDP,
//! gsens_gnss_sdr::monitor::decode_datagram) and the length-prefixed capture
//! files of them (`split_capture`); any bytes, never a panic.
#![no_main]
use gsens_gnss_sdr::monitor::{decode_datagram, split_capture};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = decode_datagram(data);
    if let Ok(datagrams) = split_capture(data) {
        for d in datagrams {
            let _ = decode_datagram(d);
        }
    }
});
