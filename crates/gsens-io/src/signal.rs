//! The crate documentation's section "Signals and carriers" describes this module.

use std::fmt;

use gsens_core::units::GPS_L1_HZ;

/// One entry of the signal table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignalSpec {
    /// The name used in `tracking.csv`'s `signal` column, e.g. `L1CA`.
    pub name: &'static str,
    /// The constellation, e.g. `GPS`.
    pub system: &'static str,
    /// The carrier \[Hz\]; for an FDMA signal the centre, at k = 0.
    pub carrier_hz: f64,
    /// GLONASS FDMA: the spacing of the frequency channels \[Hz\]
    /// (f = carrier_hz + k·step); `None` for a CDMA signal.
    pub fdma_step_hz: Option<f64>,
}

/// The signals gsens knows (the crate documentation names the sources).
pub const SIGNALS: [SignalSpec; 17] = {
    const fn cdma(name: &'static str, system: &'static str, carrier_hz: f64) -> SignalSpec {
        SignalSpec { name, system, carrier_hz, fdma_step_hz: None }
    }
    [
        cdma("L1CA", "GPS", GPS_L1_HZ),
        cdma("L2C", "GPS", 1_227.60e6),
        cdma("L5I", "GPS", 1_176.45e6),
        cdma("L5Q", "GPS", 1_176.45e6),
        cdma("E1B", "Galileo", GPS_L1_HZ),
        cdma("E1C", "Galileo", GPS_L1_HZ),
        cdma("E5aI", "Galileo", 1_176.45e6),
        cdma("E5aQ", "Galileo", 1_176.45e6),
        cdma("E5bI", "Galileo", 1_207.14e6),
        cdma("E5bQ", "Galileo", 1_207.14e6),
        cdma("B1I", "BeiDou", 1_561.098e6),
        cdma("B1C", "BeiDou", GPS_L1_HZ),
        cdma("B2a", "BeiDou", 1_176.45e6),
        cdma("B3I", "BeiDou", 1_268.52e6),
        cdma("L1SAIF", "QZSS", GPS_L1_HZ),
        SignalSpec { name: "G1", system: "GLONASS", carrier_hz: 1_602.0e6, fdma_step_hz: Some(0.5625e6) },
        SignalSpec { name: "G2", system: "GLONASS", carrier_hz: 1_246.0e6, fdma_step_hz: Some(0.4375e6) },
    ]
};

/// The GLONASS frequency channel numbers k (ICD 5.1: −7 … +6).
pub const GLONASS_K: core::ops::RangeInclusive<i32> = -7..=6;

/// The band every GNSS carrier lies in \[Hz\]: 1.1–1.7 GHz (the lowest, L5/E5a/B2a,
/// at 1176.45 MHz; the highest, GLONASS G1 k = +6, at 1605.375 MHz). A carrier
/// outside it is no GNSS signal's (e.g. a value in MHz, or an intermediate frequency).
pub const GNSS_BAND_HZ: (f64, f64) = (1.1e9, 1.7e9);

/// How far a given `carrier_hz` may lie from the one its signal and k define \[Hz\]
/// (a written carrier reads back exactly; 1 Hz allows rounding to the hertz).
pub const CARRIER_MATCH_HZ: f64 = 1.0;

/// A signal of the table, with its GLONASS frequency channel number k.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Signal {
    index: u8,
    glo_k: i8,
}

/// Why a signal name or carrier is refused (the readers add file, line and column).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SignalError {
    /// A name not in [`SIGNALS`].
    Unknown(String),
    /// An FDMA signal without its k.
    MissingK(&'static str),
    /// A k for a CDMA signal.
    UnexpectedK(&'static str, i64),
    /// A k outside [`GLONASS_K`].
    KOutOfRange(&'static str, i64),
    /// A carrier outside [`GNSS_BAND_HZ`].
    OutOfBand(f64),
    /// A carrier off the one the signal defines.
    Mismatch {
        /// The signal's label.
        signal: String,
        /// The signal's carrier \[Hz\].
        expected_hz: f64,
        /// The carrier given \[Hz\].
        given_hz: f64,
    },
    /// A carrier of an FDMA signal off the channel grid.
    OffGrid(&'static str, f64),
}

impl fmt::Display for SignalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SignalError::Unknown(name) => {
                write!(f, "`{name}` is not a signal gsens knows (known: {})", Signal::known_names())
            }
            SignalError::MissingK(name) => write!(
                f,
                "{name} is a GLONASS FDMA signal: give its frequency channel number k ({}…{}) in a `glo_k` \
                 column, or its carrier in a `carrier_hz` column",
                GLONASS_K.start(),
                GLONASS_K.end()
            ),
            SignalError::UnexpectedK(name, k) => {
                write!(f, "glo_k = {k} given for {name}, which is not a GLONASS FDMA signal (leave the cell empty)")
            }
            SignalError::KOutOfRange(name, k) => write!(
                f,
                "glo_k = {k} for {name} is outside the GLONASS frequency channels {}…{}",
                GLONASS_K.start(),
                GLONASS_K.end()
            ),
            SignalError::OutOfBand(hz) => write!(
                f,
                "carrier_hz = {hz} Hz is outside the GNSS bands, {}–{} GHz (L5/E5a at 1176.45 MHz to GLONASS G1 at \
                 1605.375 MHz); carrier_hz is the tracked carrier in Hz, not MHz and not an intermediate frequency",
                GNSS_BAND_HZ.0 / 1e9,
                GNSS_BAND_HZ.1 / 1e9
            ),
            SignalError::Mismatch { signal, expected_hz, given_hz } => write!(
                f,
                "carrier_hz = {given_hz} Hz disagrees with signal {signal}'s carrier {expected_hz} Hz (by more than \
                 {CARRIER_MATCH_HZ} Hz)"
            ),
            SignalError::OffGrid(name, hz) => {
                let spec = &SIGNALS[Signal::index_of(name).expect("a table name") as usize];
                write!(
                    f,
                    "carrier_hz = {hz} Hz is no {name} frequency channel ({} Hz + k·{} Hz, k = {}…{})",
                    spec.carrier_hz,
                    spec.fdma_step_hz.unwrap_or(0.0),
                    GLONASS_K.start(),
                    GLONASS_K.end()
                )
            }
        }
    }
}

impl std::error::Error for SignalError {}

impl Signal {
    /// GPS L1 C/A.
    pub const L1CA: Signal = Signal { index: 0, glo_k: 0 };

    fn index_of(name: &str) -> Option<u8> {
        SIGNALS.iter().position(|s| s.name == name).map(|i| i as u8)
    }

    /// The signal `name` (as in [`SIGNALS`], case-sensitive) with the GLONASS
    /// frequency channel number `glo_k`, which an FDMA signal requires and a
    /// CDMA signal refuses.
    pub fn new(name: &str, glo_k: Option<i64>) -> Result<Signal, SignalError> {
        let index = Self::index_of(name).ok_or_else(|| SignalError::Unknown(name.to_owned()))?;
        let spec = &SIGNALS[index as usize];
        match (spec.fdma_step_hz, glo_k) {
            (None, None) => Ok(Signal { index, glo_k: 0 }),
            (None, Some(k)) => Err(SignalError::UnexpectedK(spec.name, k)),
            (Some(_), None) => Err(SignalError::MissingK(spec.name)),
            (Some(_), Some(k)) if GLONASS_K.contains(&(k as i32)) && k.abs() < 100 => {
                Ok(Signal { index, glo_k: k as i8 })
            }
            (Some(_), Some(k)) => Err(SignalError::KOutOfRange(spec.name, k)),
        }
    }

    /// The signal `name` with its k, if FDMA, taken from `carrier_hz` (which must
    /// lie within [`CARRIER_MATCH_HZ`] of a frequency channel); for a CDMA signal
    /// `carrier_hz` must match its carrier likewise.
    pub fn with_carrier(name: &str, carrier_hz: f64) -> Result<Signal, SignalError> {
        let index = Self::index_of(name).ok_or_else(|| SignalError::Unknown(name.to_owned()))?;
        let spec = &SIGNALS[index as usize];
        let signal = match spec.fdma_step_hz {
            None => Signal { index, glo_k: 0 },
            Some(step) => {
                let k = ((carrier_hz - spec.carrier_hz) / step).round();
                if !(f64::from(*GLONASS_K.start())..=f64::from(*GLONASS_K.end())).contains(&k) {
                    return Err(SignalError::OffGrid(spec.name, carrier_hz));
                }
                let s = Signal { index, glo_k: k as i8 };
                if (s.carrier_hz() - carrier_hz).abs() > CARRIER_MATCH_HZ {
                    return Err(SignalError::OffGrid(spec.name, carrier_hz));
                }
                s
            }
        };
        signal.check_carrier(carrier_hz)?;
        Ok(signal)
    }

    /// `Ok` when `carrier_hz` lies within [`CARRIER_MATCH_HZ`] of the signal's carrier.
    pub fn check_carrier(&self, carrier_hz: f64) -> Result<(), SignalError> {
        if (self.carrier_hz() - carrier_hz).abs() <= CARRIER_MATCH_HZ {
            Ok(())
        } else {
            Err(SignalError::Mismatch { signal: self.label(), expected_hz: self.carrier_hz(), given_hz: carrier_hz })
        }
    }

    /// The signal written as [`Signal::label`] (`L1CA`, `G1:+3`, `G1:-7`).
    pub fn from_label(label: &str) -> Result<Signal, SignalError> {
        match label.split_once(':') {
            Some((name, k)) => {
                let k: i64 = k.trim_start_matches('+').parse().map_err(|_| SignalError::Unknown(label.to_owned()))?;
                Signal::new(name, Some(k))
            }
            None => Signal::new(label, None),
        }
    }

    /// The table entry.
    pub fn spec(&self) -> &'static SignalSpec {
        &SIGNALS[self.index as usize]
    }

    /// The name, e.g. `G1`.
    pub fn name(&self) -> &'static str {
        self.spec().name
    }

    /// The GLONASS frequency channel number k of an FDMA signal.
    pub fn glo_k(&self) -> Option<i8> {
        self.spec().fdma_step_hz.map(|_| self.glo_k)
    }

    /// The carrier \[Hz\]: the table's, plus k·step for an FDMA signal.
    pub fn carrier_hz(&self) -> f64 {
        let s = self.spec();
        match s.fdma_step_hz {
            Some(step) => s.carrier_hz + f64::from(self.glo_k) * step,
            None => s.carrier_hz,
        }
    }

    /// The name, with `:k` (sign always written) for an FDMA signal: `L1CA`, `G1:+3`.
    pub fn label(&self) -> String {
        match self.glo_k() {
            Some(k) => format!("{}:{k:+}", self.name()),
            None => self.name().to_owned(),
        }
    }

    /// The names of the table, for error messages: `L1CA, L2C, …, G1 (with k), G2 (with k)`.
    pub fn known_names() -> String {
        SIGNALS
            .iter()
            .map(|s| {
                if s.fdma_step_hz.is_some() {
                    format!("{} (with glo_k or carrier_hz)", s.name)
                } else {
                    s.name.to_owned()
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The carrier a channel tracks: the frequency, and the signal when the log names it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Carrier {
    /// The carrier \[Hz\].
    pub carrier_hz: f64,
    /// The signal, when the log names it (a `signal` column); `None` for a
    /// carrier given by frequency alone, or assumed (GPS L1, no column).
    pub signal: Option<Signal>,
}

impl Carrier {
    /// GPS L1, unnamed: what a log without carrier columns is read as.
    pub const GPS_L1: Carrier = Carrier { carrier_hz: GPS_L1_HZ, signal: None };

    /// The carrier of `signal`.
    pub fn of(signal: Signal) -> Carrier {
        Carrier { carrier_hz: signal.carrier_hz(), signal: Some(signal) }
    }

    /// A carrier given by frequency alone, checked within [`GNSS_BAND_HZ`].
    pub fn from_hz(carrier_hz: f64) -> Result<Carrier, SignalError> {
        if carrier_hz.is_finite() && (GNSS_BAND_HZ.0..=GNSS_BAND_HZ.1).contains(&carrier_hz) {
            Ok(Carrier { carrier_hz, signal: None })
        } else {
            Err(SignalError::OutOfBand(carrier_hz))
        }
    }

    /// The factor f_L1/f_c that puts this carrier's phase error on L1's scale
    /// (Δf_c = f_c·y, so φ_c = (f_c/f_L1)·φ_L1 for one loop).
    pub fn scale_to_l1(&self) -> f64 {
        GPS_L1_HZ / self.carrier_hz
    }

    /// `true` for a carrier that `tracking.csv` without carrier columns holds
    /// as well: GPS L1's frequency, and no signal or L1 C/A.
    pub fn is_default(&self) -> bool {
        self.carrier_hz == GPS_L1_HZ && self.signal.is_none_or(|s| s == Signal::L1CA)
    }

    /// The signal's label, or the frequency in MHz for an unnamed carrier
    /// (`1575.42 MHz`).
    pub fn label(&self) -> String {
        match self.signal {
            Some(s) => s.label(),
            None => format!("{} MHz", self.carrier_hz / 1e6),
        }
    }
}

impl Default for Carrier {
    fn default() -> Self {
        Carrier::GPS_L1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glonass_channels_follow_the_icd() {
        // ICD: G1 = 1602 MHz + k·562.5 kHz; k = −7 → 1598.0625 MHz, k = +6 → 1605.375 MHz.
        assert_eq!(Signal::new("G1", Some(-7)).unwrap().carrier_hz(), 1_598.062_5e6);
        assert_eq!(Signal::new("G1", Some(6)).unwrap().carrier_hz(), 1_605.375e6);
        assert_eq!(Signal::new("G2", Some(1)).unwrap().carrier_hz(), 1_246.437_5e6);
        let s = Signal::with_carrier("G1", 1_602.562_5e6).unwrap();
        assert_eq!((s.glo_k(), s.label()), (Some(1), "G1:+1".to_owned()));
        assert_eq!(Signal::from_label("G1:-4").unwrap(), Signal::new("G1", Some(-4)).unwrap());
        assert_eq!(Signal::from_label("L5I").unwrap().carrier_hz(), 1_176.45e6);
        assert!(matches!(Signal::new("G1", Some(7)), Err(SignalError::KOutOfRange("G1", 7))));
        assert!(matches!(Signal::new("G1", None), Err(SignalError::MissingK("G1"))));
        assert!(matches!(Signal::new("L1CA", Some(0)), Err(SignalError::UnexpectedK("L1CA", 0))));
        assert!(matches!(Signal::with_carrier("G1", 1_602.3e6), Err(SignalError::OffGrid("G1", _))));
        assert!(matches!(Signal::with_carrier("B1I", GPS_L1_HZ), Err(SignalError::Mismatch { .. })));
    }

    #[test]
    fn every_carrier_lies_in_the_band_and_names_are_unique() {
        for (i, s) in SIGNALS.iter().enumerate() {
            assert!(SIGNALS[..i].iter().all(|o| o.name != s.name), "{} twice", s.name);
            let ks = if s.fdma_step_hz.is_some() { vec![-7, 6] } else { vec![0] };
            for k in ks {
                let sig = Signal::new(s.name, s.fdma_step_hz.map(|_| k)).unwrap();
                assert!(Carrier::from_hz(sig.carrier_hz()).is_ok(), "{}", sig.label());
                assert_eq!(Signal::from_label(&sig.label()).unwrap(), sig);
            }
        }
        assert!(Carrier::from_hz(1575.42).is_err() && Carrier::from_hz(4.092e6).is_err());
        let m = Signal::new("L1", None).unwrap_err().to_string();
        assert!(
            m.contains("`L1` is not a signal") && m.contains("L1CA") && m.contains("G1 (with glo_k or carrier_hz)"),
            "{m}"
        );
        assert!(SignalError::OutOfBand(1575.42).to_string().contains("1.1–1.7 GHz"));
    }

    #[test]
    fn scale_factors() {
        assert_eq!(Carrier::GPS_L1.scale_to_l1(), 1.0);
        let l5 = Carrier::of(Signal::new("L5Q", None).unwrap());
        assert!((l5.scale_to_l1() - 154.0 / 115.0).abs() < 1e-15); // 1575.42/1176.45 = 154/115
        assert!(Carrier::of(Signal::L1CA).is_default() && !l5.is_default());
        assert_eq!(Carrier::GPS_L1.label(), "1575.42 MHz");
    }
}
