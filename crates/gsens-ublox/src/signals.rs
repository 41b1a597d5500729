//! The crate documentation's section "Signals" describes this module.

use gsens_io::{Carrier, Signal};

/// GPS L1, Galileo E1, SBAS L1, QZSS L1 \[Hz\].
const L1_HZ: f64 = 1_575.42e6;
/// GPS/QZSS L2 \[Hz\].
const L2_HZ: f64 = 1_227.60e6;
/// GPS/QZSS L5, Galileo E5a, BeiDou B2a, NavIC L5 \[Hz\].
const L5_HZ: f64 = 1_176.45e6;
/// Galileo E5b, BeiDou B2I \[Hz\].
const E5B_HZ: f64 = 1_207.14e6;

/// A UBX signal as RINEX names it: the satellite, the observation code and the carrier.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct UbxSignal {
    pub(crate) sv: String,
    pub(crate) code: &'static str,
    pub(crate) carrier: Carrier,
}

/// Why a measurement's signal could not be named (the reader counts it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SignalSkip {
    /// A (gnssId, sigId) pair outside the table.
    UnknownSignal,
    /// A svId outside the system's range (GLONASS 255: slot unknown).
    UnknownSatellite,
    /// A GLONASS freqId outside 0…13.
    BadFreqId,
}

impl SignalSkip {
    pub(crate) fn reason(self) -> &'static str {
        match self {
            SignalSkip::UnknownSignal => "RXM-RAWX measurement of an unknown (gnssId, sigId)",
            SignalSkip::UnknownSatellite => "RXM-RAWX measurement of an unknown satellite (svId)",
            SignalSkip::BadFreqId => "RXM-RAWX GLONASS measurement with freqId outside 0…13",
        }
    }
}

/// The satellite, RINEX code and carrier of a RXM-RAWX measurement: u-blox
/// `gnssId`/`svId`/`sigId`/`freqId` (interface description, "GNSS identifiers"
/// and "Signal identifiers") to RINEX 3 names.
pub(crate) fn ubx_signal(gnss_id: u8, sv_id: u8, sig_id: u8, freq_id: u8) -> Result<UbxSignal, SignalSkip> {
    use SignalSkip::*;
    let named = |name: &str| Carrier::of(Signal::new(name, None).expect("a table signal"));
    let by_hz = |hz: f64| Carrier::from_hz(hz).expect("a GNSS band");
    let (letter, number, code, carrier) = match gnss_id {
        0 => {
            let (code, carrier) = match sig_id {
                0 => ("1C", named("L1CA")),
                3 => ("2L", named("L2C")),
                4 => ("2S", named("L2C")),
                6 => ("5I", named("L5I")),
                7 => ("5Q", named("L5Q")),
                _ => return Err(UnknownSignal),
            };
            ('G', sv_range(sv_id, 1, 32)?, code, carrier)
        }
        // SBAS PRN 120…158 is RINEX S20…S58.
        1 if sig_id == 0 => ('S', sv_range(sv_id, 120, 158)? - 100, "1C", by_hz(L1_HZ)),
        2 => {
            let (code, carrier) = match sig_id {
                0 => ("1C", named("E1C")),
                1 => ("1B", named("E1B")),
                3 => ("5I", named("E5aI")),
                4 => ("5Q", named("E5aQ")),
                5 => ("7I", named("E5bI")),
                6 => ("7Q", named("E5bQ")),
                _ => return Err(UnknownSignal),
            };
            ('E', sv_range(sv_id, 1, 36)?, code, carrier)
        }
        3 => {
            let (code, carrier) = match sig_id {
                // B1I of D1 (MEO/IGSO) and D2 (GEO) satellites: one RINEX code.
                0 | 1 => ("2I", named("B1I")),
                2 | 3 => ("7I", by_hz(E5B_HZ)),
                5 => ("1P", named("B1C")),
                6 => ("1D", named("B1C")),
                7 => ("5P", named("B2a")),
                8 => ("5D", named("B2a")),
                _ => return Err(UnknownSignal),
            };
            ('C', sv_range(sv_id, 1, 63)?, code, carrier)
        }
        5 => {
            let (code, carrier) = match sig_id {
                0 => ("1C", by_hz(L1_HZ)),
                1 => ("1Z", named("L1SAIF")),
                4 => ("2S", by_hz(L2_HZ)),
                5 => ("2L", by_hz(L2_HZ)),
                8 => ("5I", by_hz(L5_HZ)),
                9 => ("5Q", by_hz(L5_HZ)),
                _ => return Err(UnknownSignal),
            };
            ('J', sv_range(sv_id, 1, 10)?, code, carrier)
        }
        6 => {
            // freqId = k + 7 (interface description: "0-13 for GLONASS").
            let k = i64::from(freq_id) - 7;
            let name = match sig_id {
                0 => "G1",
                2 => "G2",
                _ => return Err(UnknownSignal),
            };
            let signal = Signal::new(name, Some(k)).map_err(|_| BadFreqId)?;
            let code = if name == "G1" { "1C" } else { "2C" };
            ('R', sv_range(sv_id, 1, 32)?, code, Carrier::of(signal))
        }
        7 if sig_id == 0 => ('I', sv_range(sv_id, 1, 14)?, "5A", by_hz(L5_HZ)),
        _ => return Err(UnknownSignal),
    };
    Ok(UbxSignal { sv: format!("{letter}{number:02}"), code, carrier })
}

fn sv_range(sv_id: u8, lo: u8, hi: u8) -> Result<u8, SignalSkip> {
    if (lo..=hi).contains(&sv_id) { Ok(sv_id) } else { Err(SignalSkip::UnknownSatellite) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_rinex() {
        let g = ubx_signal(0, 5, 0, 0).unwrap();
        assert_eq!((g.sv.as_str(), g.code, g.carrier.label()), ("G05", "1C", "L1CA".to_owned()));
        let r = ubx_signal(6, 12, 0, 3).unwrap();
        assert_eq!((r.sv.as_str(), r.code, r.carrier.carrier_hz), ("R12", "1C", 1_602.0e6 - 4.0 * 0.5625e6));
        assert_eq!(ubx_signal(1, 123, 0, 0).unwrap().sv, "S23");
        assert_eq!(ubx_signal(3, 20, 2, 0).unwrap().carrier.carrier_hz, E5B_HZ);
        assert_eq!(ubx_signal(6, 255, 0, 7), Err(SignalSkip::UnknownSatellite));
        assert_eq!(ubx_signal(6, 3, 0, 14), Err(SignalSkip::BadFreqId));
        assert_eq!(ubx_signal(0, 3, 1, 0), Err(SignalSkip::UnknownSignal));
    }
}
