//! The crate documentation's section "Signals" describes this module.

use gsens_io::{Carrier, Signal, SignalError};

/// Why an observation code's carrier is not known (the reader counts it).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum CarrierSkip {
    /// A band the system does not have in RINEX 3.04's tables.
    UnknownBand,
    /// A GLONASS FDMA signal of a satellite without a `GLONASS SLOT / FRQ #` entry.
    NoGlonassChannel,
    /// A carrier outside gsens's GNSS bands (NavIC S band) or a k outside −7…+6.
    Refused(SignalError),
}

impl CarrierSkip {
    pub(crate) fn reason(&self, system: char, code: &str) -> String {
        match self {
            CarrierSkip::UnknownBand => format!("{system} {code}: a band RINEX 3.04 does not define for the system"),
            CarrierSkip::NoGlonassChannel => {
                format!("{system} {code}: GLONASS satellite without a GLONASS SLOT / FRQ # entry (carrier unknown)")
            }
            CarrierSkip::Refused(e) => format!("{system} {code}: {e}"),
        }
    }
}

/// The carrier of observation code `code` (band digit and attribute, `1C`; a
/// RINEX 2 code is the band alone, `1`) of `system` (the RINEX system letter),
/// with the GLONASS frequency channel `glo_k` where the header gives it.
/// Bands and frequencies: RINEX 3.04 Tables 4–10.
pub(crate) fn carrier(system: char, code: &str, glo_k: Option<i8>) -> Result<Carrier, CarrierSkip> {
    let mut chars = code.chars();
    let band = chars.next().ok_or(CarrierSkip::UnknownBand)?;
    let attribute = chars.next();
    let named = |name: &str| Ok(Carrier::of(Signal::new(name, None).expect("a table signal")));
    let hz = |mhz: f64| Carrier::from_hz(mhz * 1e6).map_err(CarrierSkip::Refused);
    match (system, band, attribute) {
        ('G', '1', Some('C')) => named("L1CA"),
        ('G', '1', _) => hz(1575.42),
        ('G', '2', Some('S' | 'L' | 'X')) => named("L2C"),
        ('G', '2', _) => hz(1227.60),
        ('G', '5', Some('I')) => named("L5I"),
        ('G', '5', Some('Q')) => named("L5Q"),
        ('G', '5', _) => hz(1176.45),
        ('R', '1' | '2', _) => {
            let k = glo_k.ok_or(CarrierSkip::NoGlonassChannel)?;
            let name = if band == '1' { "G1" } else { "G2" };
            Signal::new(name, Some(i64::from(k))).map(Carrier::of).map_err(CarrierSkip::Refused)
        }
        ('R', '4', _) => hz(1600.995),
        ('R', '6', _) => hz(1248.06),
        ('R', '3', _) => hz(1202.025),
        ('E', '1', Some('B')) => named("E1B"),
        ('E', '1', Some('C')) => named("E1C"),
        ('E', '1', _) => hz(1575.42),
        ('E', '5', Some('I')) => named("E5aI"),
        ('E', '5', Some('Q')) => named("E5aQ"),
        ('E', '5', _) => hz(1176.45),
        ('E', '7', Some('I')) => named("E5bI"),
        ('E', '7', Some('Q')) => named("E5bQ"),
        ('E', '7', _) => hz(1207.14),
        ('E', '8', _) => hz(1191.795),
        ('E', '6', _) => hz(1278.75),
        ('C', '2', Some('I')) => named("B1I"),
        ('C', '2', _) => hz(1561.098),
        ('C', '1', Some('P' | 'D' | 'X')) => named("B1C"),
        ('C', '1', _) => hz(1575.42),
        ('C', '5', Some('P' | 'D' | 'X')) => named("B2a"),
        ('C', '5', _) => hz(1176.45),
        ('C', '7', _) => hz(1207.14),
        ('C', '8', _) => hz(1191.795),
        ('C', '6', Some('I')) => named("B3I"),
        ('C', '6', _) => hz(1268.52),
        ('J', '1', Some('Z')) => named("L1SAIF"),
        ('J', '1', _) => hz(1575.42),
        ('J', '2', _) => hz(1227.60),
        ('J', '5', _) => hz(1176.45),
        ('J', '6', _) => hz(1278.75),
        ('S', '1', _) => hz(1575.42),
        ('S', '5', _) => hz(1176.45),
        ('I', '5', _) => hz(1176.45),
        ('I', '9', _) => hz(2492.028),
        _ => Err(CarrierSkip::UnknownBand),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_map_to_the_tables_carriers() {
        assert_eq!(carrier('G', "1C", None).unwrap().label(), "L1CA");
        assert_eq!(carrier('G', "2W", None).unwrap().carrier_hz, 1_227.60e6);
        assert_eq!(carrier('R', "1C", Some(-4)).unwrap().label(), "G1:-4");
        assert_eq!(carrier('R', "2P", Some(6)).unwrap().carrier_hz, 1_246e6 + 6.0 * 437.5e3);
        assert_eq!(carrier('R', "1C", None), Err(CarrierSkip::NoGlonassChannel));
        assert_eq!(carrier('C', "2I", None).unwrap().label(), "B1I");
        assert_eq!(carrier('E', "5X", None).unwrap().carrier_hz, 1_176.45e6);
        assert_eq!(carrier('G', "1", None).unwrap().carrier_hz, 1_575.42e6);
        assert!(matches!(carrier('I', "9A", None), Err(CarrierSkip::Refused(SignalError::OutOfBand(_)))));
        assert_eq!(carrier('G', "7Q", None), Err(CarrierSkip::UnknownBand));
    }
}
