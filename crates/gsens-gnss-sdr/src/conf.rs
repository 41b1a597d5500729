//! The crate documentation's section "Configuration files" describes this module.

use gsens_core::units::Decimal;
use std::path::Path;

use serde::Serialize;

use crate::error::GnssSdrError;

/// One `key=value` entry of a configuration file.
#[derive(Debug, Clone, PartialEq)]
struct Entry {
    key: String,
    value: String,
    line: usize,
}

/// A parsed GNSS-SDR configuration file.
#[derive(Debug, Clone, PartialEq)]
pub struct GnssSdrConf {
    source_name: String,
    entries: Vec<Entry>,
}

/// GNSS-SDR 0.0.17's default `pll_filter_order` of the GPS L1 C/A DLL/PLL tracking.
pub(crate) const DEFAULT_PLL_FILTER_ORDER: u8 = 3;
/// GNSS-SDR 0.0.17's default `pll_bw_hz` \[Hz\] (measured).
pub(crate) const DEFAULT_PLL_BW_HZ: f64 = 35.0;
/// GNSS-SDR 0.0.17's default `pll_bw_narrow_hz` \[Hz\] (measured).
pub(crate) const DEFAULT_PLL_BW_NARROW_HZ: f64 = 5.0;
/// GNSS-SDR 0.0.17's default `pull_in_time_s` \[s\] (`dll_pll_conf.h`).
pub(crate) const DEFAULT_PULL_IN_TIME_S: f64 = 10.0;
/// GNSS-SDR's default `carrier_lock_th` (`FLAGS_carrier_lock_th`, `gnss_sdr_flags.cc`):
/// the threshold of the smoothed carrier lock test (I² − Q²)/(I² + Q²) = cos 2φ.
pub(crate) const DEFAULT_CARRIER_LOCK_TH: f64 = 0.7;
/// GNSS-SDR's default `cn0_min` \[dB-Hz\] (`FLAGS_cn0_min`).
pub(crate) const DEFAULT_CN0_MIN_DBHZ: f64 = 25.0;
/// GNSS-SDR's default `max_lock_fail` (`FLAGS_max_lock_fail`): the code-lock (C/N0) fail counter's maximum.
pub(crate) const DEFAULT_MAX_LOCK_FAIL: u32 = 50;
/// GNSS-SDR's default `max_carrier_lock_fail` (`FLAGS_max_carrier_lock_fail`).
pub(crate) const DEFAULT_MAX_CARRIER_LOCK_FAIL: u32 = 5000;
/// GNSS-SDR's default `cn0_samples` (`FLAGS_cn0_samples`): prompt outputs per C/N0 estimate.
pub(crate) const DEFAULT_CN0_SAMPLES: u32 = 20;
/// The tracking implementation whose loop [`gsens_core::gnss_sdr`] models.
pub(crate) const SUPPORTED_TRACKING: &str = "GPS_L1_CA_DLL_PLL_Tracking";

/// Where a setting's value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ValueSource {
    /// The configuration file.
    Conf,
    /// GNSS-SDR's default (the key is absent).
    GnssSdrDefault,
    /// A command-line option of gsens that overrides the configuration.
    Option,
}

impl core::fmt::Display for ValueSource {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ValueSource::Conf => "from the conf",
            ValueSource::GnssSdrDefault => "GNSS-SDR's default",
            ValueSource::Option => "given as an option",
        })
    }
}

/// A setting's value and where it comes from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sourced<T> {
    /// The value in use.
    pub value: T,
    /// Where it comes from.
    pub source: ValueSource,
}

impl<T> Sourced<T> {
    /// A value of GNSS-SDR's default.
    pub fn default_value(value: T) -> Self {
        Sourced { value, source: ValueSource::GnssSdrDefault }
    }

    /// Replaces the value by one given as an option.
    pub fn set_option(&mut self, value: T) {
        self.value = value;
        self.source = ValueSource::Option;
    }
}

/// The settings of GNSS-SDR's tracking lock detector (`Tracking_1C.*`; module
/// docs; the rule they drive: [`crate::import`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LockDetectorConf {
    /// `carrier_lock_th`: a record whose carrier lock test is below it is a carrier-lock failure.
    pub carrier_lock_th: Sourced<f64>,
    /// `max_carrier_lock_fail`: loss of lock when the carrier fail counter exceeds it.
    pub max_carrier_lock_fail: Sourced<u32>,
    /// `cn0_min` \[dB-Hz\]: a record whose C/N0 is below it is a code-lock failure.
    pub cn0_min_dbhz: Sourced<f64>,
    /// `max_lock_fail`: loss of lock when the code (C/N0) fail counter exceeds it.
    pub max_lock_fail: Sourced<u32>,
    /// `cn0_samples`: the first this many records of a track fill the C/N0 buffer and are not judged.
    pub cn0_samples: Sourced<u32>,
}

impl LockDetectorConf {
    /// GNSS-SDR's defaults (module docs).
    pub fn defaults() -> Self {
        LockDetectorConf {
            carrier_lock_th: Sourced::default_value(DEFAULT_CARRIER_LOCK_TH),
            max_carrier_lock_fail: Sourced::default_value(DEFAULT_MAX_CARRIER_LOCK_FAIL),
            cn0_min_dbhz: Sourced::default_value(DEFAULT_CN0_MIN_DBHZ),
            max_lock_fail: Sourced::default_value(DEFAULT_MAX_LOCK_FAIL),
            cn0_samples: Sourced::default_value(DEFAULT_CN0_SAMPLES),
        }
    }
}

/// The carrier-loop settings of GNSS-SDR's GPS L1 C/A tracking (`Tracking_1C.*`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackingConf {
    /// `Tracking_1C.implementation`.
    pub implementation: String,
    /// `pll_filter_order`: 2 or 3.
    pub pll_filter_order: u8,
    /// `pll_bw_hz`: the PLL noise bandwidth before bit synchronization \[Hz\].
    pub pll_bw_hz: f64,
    /// `pll_bw_narrow_hz`: the PLL bandwidth once the integration is extended \[Hz\].
    pub pll_bw_narrow_hz: f64,
    /// `extend_correlation_symbols`: 1 ms symbols per coherent integration
    /// after bit synchronization (a divisor of 20: 1, 2, 4, 5, 10, 20).
    pub extend_correlation_symbols: u32,
    /// `enable_fll_pull_in`: an FLL during the pull-in (before the modelled records).
    pub enable_fll_pull_in: bool,
    /// `enable_fll_steady_state`: an FLL-assisted PLL throughout (not modelled).
    pub enable_fll_steady_state: bool,
    /// `pull_in_time_s`: how long the pull-in lasts \[s\], a whole number
    /// (`DEFAULT_PULL_IN_TIME_S` when absent): the FLL's time when it is
    /// enabled, and always the time during which the lock detector counts no failure.
    pub pull_in_time_s: f64,
    /// The lock detector's settings.
    pub lock: LockDetectorConf,
    /// The sampling rate the tracking runs at \[Hz\]: `GNSS-SDR.internal_fs_sps`,
    /// else `SignalSource.sampling_frequency`; `None` when neither is given.
    pub fs_hz: Option<f64>,
    /// `Tracking_1C.dump_filename` (the dumps are `<dump_filename><channel>.dat`).
    pub dump_filename: Option<String>,
}

impl TrackingConf {
    /// The settings of a configuration that has none of the keys: GNSS-SDR 0.0.17's defaults.
    pub fn defaults() -> Self {
        TrackingConf {
            implementation: SUPPORTED_TRACKING.into(),
            pll_filter_order: DEFAULT_PLL_FILTER_ORDER,
            pll_bw_hz: DEFAULT_PLL_BW_HZ,
            pll_bw_narrow_hz: DEFAULT_PLL_BW_NARROW_HZ,
            extend_correlation_symbols: 1,
            enable_fll_pull_in: false,
            enable_fll_steady_state: false,
            pull_in_time_s: DEFAULT_PULL_IN_TIME_S,
            lock: LockDetectorConf::defaults(),
            fs_hz: None,
            dump_filename: None,
        }
    }

    /// The coherent integration after bit synchronization \[s\]:
    /// `extend_correlation_symbols` × 1 ms.
    pub fn narrow_interval_s(&self) -> f64 {
        f64::from(self.extend_correlation_symbols) * 1e-3
    }

    /// The PLL bandwidth after bit synchronization \[Hz\]: `pll_bw_narrow_hz`
    /// when the integration is extended, else `pll_bw_hz` (GNSS-SDR switches
    /// bandwidth only together with the integration time).
    pub fn narrow_bw_hz(&self) -> f64 {
        if self.extend_correlation_symbols > 1 { self.pll_bw_narrow_hz } else { self.pll_bw_hz }
    }
}

/// The longest prefix of `s` that a C++ stream would read as a number.
fn numeric_prefix(s: &str) -> &str {
    let b = s.as_bytes();
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let digits = |i: &mut usize| {
        let start = *i;
        while *i < b.len() && b[*i].is_ascii_digit() {
            *i += 1;
        }
        *i > start
    };
    let mut any = digits(&mut i);
    if i < b.len() && b[i] == b'.' {
        i += 1;
        any |= digits(&mut i);
    }
    if !any {
        return "";
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        if digits(&mut j) {
            i = j;
        }
    }
    &s[..i]
}

impl GnssSdrConf {
    /// Parses the text of a configuration file; `source_name` names it in errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, GnssSdrError> {
        let mut entries = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let t = raw.trim();
            if t.is_empty() || t.starts_with(';') || t.starts_with('#') || (t.starts_with('[') && t.ends_with(']')) {
                continue;
            }
            let t = t.split(';').next().unwrap_or("").trim();
            let Some((k, v)) = t.split_once('=') else {
                return Err(GnssSdrError::Conf {
                    file: source_name.into(),
                    line,
                    reason: format!("expected `key=value`, found `{}`", raw.trim()),
                });
            };
            entries.push(Entry { key: k.trim().into(), value: v.trim().into(), line });
        }
        Ok(GnssSdrConf { source_name: source_name.into(), entries })
    }

    /// Reads and parses a configuration file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, GnssSdrError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = gsens_io::read_config_text(path).map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
        Self::parse(&text, &name)
    }

    /// The file's name as given to the reader.
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// The value of `key` (its last occurrence), comments stripped.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.entries.iter().rev().find(|e| e.key == key).map(|e| e.value.as_str())
    }

    fn entry(&self, key: &str) -> Option<&Entry> {
        self.entries.iter().rev().find(|e| e.key == key)
    }

    /// `key` as a number (its numeric prefix), `None` when absent.
    pub fn get_f64(&self, key: &str) -> Result<Option<f64>, GnssSdrError> {
        let Some(e) = self.entry(key) else { return Ok(None) };
        numeric_prefix(&e.value).parse::<f64>().map(Some).map_err(|_| GnssSdrError::Conf {
            file: self.source_name.clone(),
            line: e.line,
            reason: format!("`{key}` = `{}` is not a number", e.value),
        })
    }

    /// `key` as GNSS-SDR reads an unsigned integer (a C++ stream: digits, the
    /// rest ignored), `None` when absent; an error naming the line when the
    /// value does not start with a whole number ≥ 0.
    pub fn get_count(&self, key: &str) -> Result<Option<u32>, GnssSdrError> {
        match self.get_int(key)? {
            None => Ok(None),
            Some(n) => u32::try_from(n).map(Some).map_err(|_| self.bad_value(key, "must be a whole number ≥ 0")),
        }
    }

    /// `key` as GNSS-SDR reads an `int` (optional sign and digits, the rest
    /// ignored: `25.5` is 25), `None` when absent.
    pub fn get_int(&self, key: &str) -> Result<Option<i32>, GnssSdrError> {
        let Some(e) = self.entry(key) else { return Ok(None) };
        let v = e.value.as_str();
        let sign = usize::from(v.starts_with(['+', '-']));
        let digits = v[sign..].bytes().take_while(u8::is_ascii_digit).count();
        if digits == 0 {
            return Err(self.bad_value(key, "is not an integer"));
        }
        v[..sign + digits].parse().map(Some).map_err(|_| self.bad_value(key, "is out of range"))
    }

    fn bad_value(&self, key: &str, what: &str) -> GnssSdrError {
        let e = self.entry(key);
        GnssSdrError::Conf {
            file: self.source_name.clone(),
            line: e.map_or(0, |e| e.line),
            reason: format!("`{key}` = `{}` {what}", e.map_or("", |e| e.value.as_str())),
        }
    }

    /// `key` as a boolean (`true`/`false`/`1`/`0`), `None` when absent.
    pub fn get_bool(&self, key: &str) -> Result<Option<bool>, GnssSdrError> {
        let Some(e) = self.entry(key) else { return Ok(None) };
        match e.value.as_str() {
            "true" | "1" => Ok(Some(true)),
            "false" | "0" => Ok(Some(false)),
            v => Err(GnssSdrError::Conf {
                file: self.source_name.clone(),
                line: e.line,
                reason: format!("`{key}` = `{v}` is not a boolean (true/false)"),
            }),
        }
    }

    /// The GPS L1 C/A carrier-loop settings (module docs), checked: a
    /// supported tracking implementation, order 2 or 3, positive bandwidths,
    /// 1…20 symbols dividing 20, no steady-state FLL.
    pub fn tracking(&self) -> Result<TrackingConf, GnssSdrError> {
        let implementation = self.tracking_implementation()?;
        let (pll_filter_order, pll_bw_hz, pll_bw_narrow_hz) = self.pll_order_and_bandwidths()?;
        let extend_correlation_symbols = self.extend_correlation_symbols()?;
        self.check_bandwidths_below_update_rate(pll_bw_hz, pll_bw_narrow_hz, extend_correlation_symbols)?;
        let enable_fll_pull_in = self.get_bool("Tracking_1C.enable_fll_pull_in")?.unwrap_or(false);
        let enable_fll_steady_state = self.get_bool("Tracking_1C.enable_fll_steady_state")?.unwrap_or(false);
        if enable_fll_steady_state {
            return Err(self.conf_error(
                "Tracking_1C.enable_fll_steady_state",
                "enable_fll_steady_state = true: an FLL-assisted PLL is not modelled".into(),
            ));
        }
        // GNSS-SDR holds it as an unsigned integer.
        let pull_in_time_s = self.get_count("Tracking_1C.pull_in_time_s")?.map_or(DEFAULT_PULL_IN_TIME_S, f64::from);
        let lock = self.lock_detector()?;
        let fs_hz = self.sampling_rate_hz()?;
        Ok(TrackingConf {
            implementation,
            pll_filter_order,
            pll_bw_hz,
            pll_bw_narrow_hz,
            extend_correlation_symbols,
            enable_fll_pull_in,
            enable_fll_steady_state,
            pull_in_time_s,
            lock,
            fs_hz,
            dump_filename: self.get("Tracking_1C.dump_filename").map(str::to_owned),
        })
    }

    /// An error at `key`'s line (0 when absent) saying `reason`.
    fn conf_error(&self, key: &str, reason: String) -> GnssSdrError {
        let line = self.entry(key).map_or(0, |e| e.line);
        GnssSdrError::Conf { file: self.source_name.clone(), line, reason }
    }

    /// `Tracking_1C.implementation`: GNSS-SDR's DLL/PLL (the default), the
    /// one tracking loop modelled.
    fn tracking_implementation(&self) -> Result<String, GnssSdrError> {
        let implementation = self.get("Tracking_1C.implementation").unwrap_or(SUPPORTED_TRACKING).to_owned();
        if implementation != SUPPORTED_TRACKING {
            return Err(self.conf_error(
                "Tracking_1C.implementation",
                format!(
                    "Tracking_1C.implementation = {implementation}: only {SUPPORTED_TRACKING} (GNSS-SDR's DLL/PLL) is modelled"
                ),
            ));
        }
        Ok(implementation)
    }

    /// The PLL's order (2 or 3) and its wide and narrow noise bandwidths
    /// \[Hz\] (> 0), GNSS-SDR's defaults for absent keys.
    fn pll_order_and_bandwidths(&self) -> Result<(u8, f64, f64), GnssSdrError> {
        let d = TrackingConf::defaults();
        let order = self.get_f64("Tracking_1C.pll_filter_order")?.unwrap_or(f64::from(d.pll_filter_order));
        if order != 2.0 && order != 3.0 {
            let reason = format!("pll_filter_order = {order}: must be 2 or 3");
            return Err(self.conf_error("Tracking_1C.pll_filter_order", reason));
        }
        let pll_bw_hz = self.get_f64("Tracking_1C.pll_bw_hz")?.unwrap_or(d.pll_bw_hz);
        let pll_bw_narrow_hz = self.get_f64("Tracking_1C.pll_bw_narrow_hz")?.unwrap_or(d.pll_bw_narrow_hz);
        for (key, v) in [("Tracking_1C.pll_bw_hz", pll_bw_hz), ("Tracking_1C.pll_bw_narrow_hz", pll_bw_narrow_hz)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(self.conf_error(key, format!("{key} = {v}: must be > 0")));
            }
        }
        Ok((order as u8, pll_bw_hz, pll_bw_narrow_hz))
    }

    /// `Tracking_1C.extend_correlation_symbols` N, clamped to [1, 20] as
    /// GNSS-SDR clamps it (1 when absent); an error unless N divides 20.
    fn extend_correlation_symbols(&self) -> Result<u32, GnssSdrError> {
        let symbols = self.get_f64("Tracking_1C.extend_correlation_symbols")?.unwrap_or(1.0);
        let n = if symbols.is_finite() { symbols.round().clamp(1.0, 20.0) as u32 } else { 1 };
        // After bit synchronization GNSS-SDR writes the record of the millisecond
        // that closes a 20 ms data bit; only when N divides 20 does that
        // millisecond close an integration, so that the record holds its update.
        let stage = gsens_core::gnss_sdr::GnssSdrStage { order: 2, bw_hz: 1.0, symbols: n };
        if stage.updates_per_record().is_none() {
            return Err(self.conf_error(
                "Tracking_1C.extend_correlation_symbols",
                format!(
                    "extend_correlation_symbols = {n}: GNSS-SDR writes one record per 20 ms \
                     data bit, which then falls inside an integration and holds an older loop update; gsens models \
                     1, 2, 4, 5, 10 and 20 (the divisors of 20)"
                ),
            ));
        }
        Ok(n)
    }

    /// An error when a stage's bandwidth exceeds 1/(2T) for its update
    /// interval T (1 ms wide, N ms narrow): a loop updated every T cannot have
    /// a noise bandwidth beyond it (the discrete loop is unstable long before),
    /// 500 Hz at the C/A code's 1 ms, less once the integration is extended.
    fn check_bandwidths_below_update_rate(
        &self,
        pll_bw_hz: f64,
        pll_bw_narrow_hz: f64,
        extend_correlation_symbols: u32,
    ) -> Result<(), GnssSdrError> {
        let stages = [
            ("Tracking_1C.pll_bw_hz", pll_bw_hz, 1.0),
            ("Tracking_1C.pll_bw_narrow_hz", pll_bw_narrow_hz, f64::from(extend_correlation_symbols)),
        ];
        for (key, v, symbols) in stages {
            let t_s = gsens_core::units::L1CA_CODE_PERIOD_S * symbols;
            if v * t_s > 0.5 {
                return Err(self.conf_error(
                    key,
                    format!(
                        "{key} = {v}: above 1/(2T) = {} Hz for a loop updated every T = {} ms (no carrier loop is \
                         that wide)",
                        Decimal(0.5 / t_s),
                        Decimal(t_s * 1e3)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The sampling rate \[Hz\]: `GNSS-SDR.internal_fs_sps`, else the
    /// source's `SignalSource.sampling_frequency`; `None` when neither is
    /// given, an error when not > 0.
    fn sampling_rate_hz(&self) -> Result<Option<f64>, GnssSdrError> {
        let fs_hz = match self.get_f64("GNSS-SDR.internal_fs_sps")? {
            Some(v) => Some(v),
            None => self.get_f64("SignalSource.sampling_frequency")?,
        };
        if let Some(fs) = fs_hz.filter(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(self.conf_error("GNSS-SDR.internal_fs_sps", format!("sampling rate {fs}: must be > 0")));
        }
        Ok(fs_hz)
    }
}

impl GnssSdrConf {
    /// The lock detector's settings (module docs), GNSS-SDR's defaults for
    /// absent keys; `carrier_lock_th` must lie in [−1, 1] (the lock test's range).
    pub fn lock_detector(&self) -> Result<LockDetectorConf, GnssSdrError> {
        let d = LockDetectorConf::defaults();
        let from = |v: Option<f64>, dflt: Sourced<f64>| match v {
            Some(value) => Sourced { value, source: ValueSource::Conf },
            None => dflt,
        };
        let count = |key: &str, dflt: Sourced<u32>| -> Result<Sourced<u32>, GnssSdrError> {
            Ok(match self.get_count(key)? {
                Some(value) => Sourced { value, source: ValueSource::Conf },
                None => dflt,
            })
        };
        let carrier_lock_th = from(self.get_f64("Tracking_1C.carrier_lock_th")?, d.carrier_lock_th);
        if !(-1.0..=1.0).contains(&carrier_lock_th.value) {
            return Err(
                self.bad_value("Tracking_1C.carrier_lock_th", "is outside [−1, 1], the range of the lock test cos 2φ")
            );
        }
        // cn0_min is an int in GNSS-SDR.
        let cn0_min = self.get_int("Tracking_1C.cn0_min")?.map(f64::from);
        Ok(LockDetectorConf {
            carrier_lock_th,
            max_carrier_lock_fail: count("Tracking_1C.max_carrier_lock_fail", d.max_carrier_lock_fail)?,
            cn0_min_dbhz: from(cn0_min, d.cn0_min_dbhz),
            max_lock_fail: count("Tracking_1C.max_lock_fail", d.max_lock_fail)?,
            cn0_samples: count("Tracking_1C.cn0_samples", d.cn0_samples)?,
        })
    }
}

/// What `iq_file_conf` needs to know.
#[derive(Debug, Clone, PartialEq)]
pub struct IqConfOptions {
    /// Path of the sample file, as GNSS-SDR will open it.
    pub filename: String,
    /// GNSS-SDR's `item_type`: `ibyte`, `ishort` or `gr_complex`.
    pub item_type: String,
    /// Sampling rate \[Hz\].
    pub fs_hz: f64,
    /// Tracking channels.
    pub channels: u32,
    /// Carrier-loop order, 2 or 3.
    pub pll_filter_order: u8,
    /// Pull-in PLL bandwidth at 1 ms \[Hz\].
    pub pll_bw_hz: f64,
    /// PLL bandwidth after bit synchronization \[Hz\].
    pub pll_bw_narrow_hz: f64,
    /// Symbols (ms) per coherent integration after bit synchronization.
    pub extend_correlation_symbols: u32,
    /// Prefix of the tracking dumps (`<prefix><channel>.dat`).
    pub dump_filename: String,
    /// Largest Doppler searched by acquisition \[Hz\].
    pub doppler_max_hz: f64,
}

impl IqConfOptions {
    /// The settings `gsens simulate --iq` writes: a pull-in from acquisition's
    /// 250 Hz grid by a 10 Hz FLL for 2 s, then a 35 Hz PLL of `order` at
    /// 1 ms, then, after bit synchronization, 20 ms integrations with the
    /// narrow loop of `narrow_bw_hz` (a 3 Hz loop cannot pull in from the
    /// acquisition grid by itself).
    pub fn for_iq_file(
        filename: &str,
        item_type: &str,
        fs_hz: f64,
        channels: u32,
        order: u8,
        narrow_bw_hz: f64,
    ) -> Self {
        IqConfOptions {
            filename: filename.into(),
            item_type: item_type.into(),
            fs_hz,
            channels,
            pll_filter_order: order,
            pll_bw_hz: 35.0,
            pll_bw_narrow_hz: narrow_bw_hz,
            extend_correlation_symbols: 20,
            dump_filename: "./trk_ch_".into(),
            doppler_max_hz: 6000.0,
        }
    }
}

/// A GNSS-SDR 0.0.17 configuration that tracks a complex baseband GPS L1 C/A
/// sample file (such as `gsens simulate --iq` writes) and dumps its tracking:
/// file source without throttling, GPS L1 C/A PCPS acquisition
/// (non-blocking: blocking acquisition in file mode corrupts the pull-in of
/// narrow loops), DLL/PLL tracking with an FLL pull-in, a wide PLL and a
/// narrow PLL after bit synchronization, dumps on (`dump_mat=false`: the raw `.dat` only),
/// telemetry decoding, observables and a PVT that writes no files.
pub(crate) fn iq_file_conf(o: &IqConfOptions) -> String {
    [source_section(o), conditioner_section(&o.item_type), acquisition_section(o), tracking_section(o)].concat()
        + NAVIGATION_SECTION
}

/// The header (what the file tracks, how to run it) and the file source:
/// the whole file, once, at `fs_hz`, without throttling.
fn source_section(o: &IqConfOptions) -> String {
    format!(
        "; GNSS-SDR 0.0.17 configuration written by gsens: tracks {file}
; Run: gnss-sdr --config_file=<this file>   (the tracking dumps go to {dump}<channel>.dat)
[GNSS-SDR]
GNSS-SDR.internal_fs_sps={fs}

SignalSource.implementation=File_Signal_Source
SignalSource.filename={file}
SignalSource.item_type={item}
SignalSource.sampling_frequency={fs}
SignalSource.freq=1575420000
SignalSource.samples=0
SignalSource.repeat=false
SignalSource.enable_throttle_control=false

",
        file = o.filename,
        dump = o.dump_filename,
        fs = o.fs_hz,
        item = o.item_type,
    )
}

/// The signal conditioner: the data-type adapter that turns `item_type`'s
/// interleaved integers into complex samples, no filter, no resampler.
fn conditioner_section(item_type: &str) -> String {
    let adapter = match item_type {
        "ibyte" => "Ibyte_To_Complex",
        "ishort" => "Ishort_To_Complex",
        _ => "Pass_Through",
    };
    format!(
        "SignalConditioner.implementation=Signal_Conditioner
DataTypeAdapter.implementation={adapter}
DataTypeAdapter.item_type={item_type}
InputFilter.implementation=Pass_Through
InputFilter.input_item_type=gr_complex
InputFilter.output_item_type=gr_complex
InputFilter.item_type=gr_complex
Resampler.implementation=Pass_Through
Resampler.item_type=gr_complex

"
    )
}

/// The channels and GPS L1 C/A PCPS acquisition over ±`doppler_max_hz` on a
/// 250 Hz grid, non-blocking (blocking acquisition in file mode corrupts the
/// pull-in of narrow loops).
fn acquisition_section(o: &IqConfOptions) -> String {
    format!(
        "Channels_1C.count={channels}
Channels.in_acquisition=1
Channel.signal=1C

Acquisition_1C.implementation=GPS_L1_CA_PCPS_Acquisition
Acquisition_1C.item_type=gr_complex
Acquisition_1C.coherent_integration_time_ms=1
Acquisition_1C.pfa=0.01
Acquisition_1C.doppler_max={dmax}
Acquisition_1C.doppler_step=250
Acquisition_1C.blocking=false
Acquisition_1C.dump=false

",
        channels = o.channels,
        dmax = o.doppler_max_hz,
    )
}

/// DLL/PLL tracking: a 10 Hz FLL pull-in for 2 s, the wide PLL at 1 ms, the
/// narrow PLL over `extend_correlation_symbols` ms after bit
/// synchronization; its dumps on (the raw `.dat` only).
fn tracking_section(o: &IqConfOptions) -> String {
    format!(
        "Tracking_1C.implementation=GPS_L1_CA_DLL_PLL_Tracking
Tracking_1C.item_type=gr_complex
Tracking_1C.pll_filter_order={order}
Tracking_1C.pll_bw_hz={bw}
Tracking_1C.pll_bw_narrow_hz={bwn}
Tracking_1C.extend_correlation_symbols={ext}
Tracking_1C.dll_filter_order=2
Tracking_1C.dll_bw_hz=2.0
Tracking_1C.dll_bw_narrow_hz=0.5
Tracking_1C.early_late_space_chips=0.5
Tracking_1C.early_late_space_narrow_chips=0.5
Tracking_1C.enable_fll_pull_in=true
Tracking_1C.fll_bw_hz=10.0
Tracking_1C.pull_in_time_s=2
Tracking_1C.enable_fll_steady_state=false
Tracking_1C.dump=true
Tracking_1C.dump_filename={dump}
Tracking_1C.dump_mat=false

",
        order = o.pll_filter_order,
        bw = o.pll_bw_hz,
        bwn = o.pll_bw_narrow_hz,
        ext = o.extend_correlation_symbols,
        dump = o.dump_filename,
    )
}

/// Telemetry decoding, observables and a single-point PVT that writes no
/// files: GNSS-SDR needs the chain to run, gsens only its tracking dumps.
const NAVIGATION_SECTION: &str = "TelemetryDecoder_1C.implementation=GPS_L1_CA_Telemetry_Decoder
TelemetryDecoder_1C.dump=false

Observables.implementation=Hybrid_Observables
Observables.dump=false

PVT.implementation=RTKLIB_PVT
PVT.positioning_mode=Single
PVT.output_rate_ms=1000
PVT.display_rate_ms=1000
PVT.output_enabled=false
PVT.rinex_output_enabled=false
PVT.gpx_output_enabled=false
PVT.geojson_output_enabled=false
PVT.kml_output_enabled=false
PVT.xml_output_enabled=false
PVT.nmea_output_file_enabled=false
PVT.rtcm_output_file_enabled=false
PVT.an_output_enabled=false
PVT.flag_rtcm_server=false
PVT.flag_rtcm_tty_port=false
PVT.flag_nmea_tty_port=false
PVT.dump=false
";

/// Writes `gnss-sdr.conf` into `dir` for the IF file `options.filename`
/// (made absolute, so the configuration runs from anywhere), with the
/// tracking dumps going to `dir/gnss-sdr/trk_ch_<N>.dat`; returns the
/// configuration's absolute path.
pub fn write_iq_conf(dir: &Path, mut options: IqConfOptions) -> Result<std::path::PathBuf, GnssSdrError> {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let write_err = |p: &Path| {
        let file = p.display().to_string();
        move |error| GnssSdrError::Write { file, error }
    };
    let dumps = dir.join("gnss-sdr");
    std::fs::create_dir_all(&dumps).map_err(write_err(&dumps))?;
    options.filename = abs(Path::new(&options.filename)).display().to_string();
    options.dump_filename = format!("{}/trk_ch_", abs(&dumps).display());
    let conf_path = dir.join("gnss-sdr.conf");
    std::fs::write(&conf_path, iq_file_conf(&options)).map_err(write_err(&conf_path))?;
    Ok(abs(&conf_path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_values_with_trailing_semicolons_and_comments() {
        let text = "; comment\n[GNSS-SDR]\nGNSS-SDR.internal_fs_sps=4000000\n# other\n\
                    Tracking_1C.pll_bw_hz=40.0;\nTracking_1C.pll_filter_order = 2 ; inline\n\
                    Tracking_1C.extend_correlation_symbols=20\nTracking_1C.pll_bw_narrow_hz=3\n\
                    Tracking_1C.pll_bw_hz=35\nTracking_1C.dump_filename=./trk_ch_\n";
        let c = GnssSdrConf::parse(text, "x.conf").unwrap();
        let t = c.tracking().unwrap();
        assert_eq!(t.pll_filter_order, 2);
        assert_eq!(t.pll_bw_hz, 35.0, "last occurrence wins");
        assert_eq!(t.pll_bw_narrow_hz, 3.0);
        assert_eq!(t.extend_correlation_symbols, 20);
        assert_eq!(t.fs_hz, Some(4e6));
        assert_eq!(t.dump_filename.as_deref(), Some("./trk_ch_"));
        assert_eq!(t.narrow_interval_s(), 0.02);
        assert_eq!(t.narrow_bw_hz(), 3.0);
    }

    #[test]
    fn defaults_and_errors() {
        let t = GnssSdrConf::parse("", "empty.conf").unwrap().tracking().unwrap();
        assert_eq!(t, TrackingConf::defaults());
        assert_eq!(t.narrow_bw_hz(), DEFAULT_PLL_BW_HZ, "no extension, no narrow bandwidth");
        let e = GnssSdrConf::parse("a\nb=1\n", "bad.conf").unwrap_err().to_string();
        assert!(e.contains("bad.conf") && e.contains("line 1"), "{e}");
        let e = GnssSdrConf::parse("x=1\nTracking_1C.pll_filter_order=4\n", "o.conf").unwrap().tracking().unwrap_err();
        assert!(e.to_string().contains("line 2") && e.to_string().contains("2 or 3"), "{e}");
        let e = GnssSdrConf::parse("Tracking_1C.pll_bw_hz=abc\n", "n.conf").unwrap().tracking().unwrap_err();
        assert!(e.to_string().contains("not a number"), "{e}");
        let e = GnssSdrConf::parse("Tracking_1C.implementation=GPS_L1_CA_KF_VTL_Tracking\n", "k.conf")
            .unwrap()
            .tracking()
            .unwrap_err();
        assert!(e.to_string().contains("only GPS_L1_CA_DLL_PLL_Tracking"), "{e}");
        let e =
            GnssSdrConf::parse("Tracking_1C.enable_fll_steady_state=true\n", "f.conf").unwrap().tracking().unwrap_err();
        assert!(e.to_string().contains("FLL"), "{e}");
        // N not dividing 20: the record of a data bit's last millisecond falls inside an integration.
        for n in [3, 7, 19] {
            let text = format!("x=1\nTracking_1C.extend_correlation_symbols={n}\n");
            let e = GnssSdrConf::parse(&text, "e.conf").unwrap().tracking().unwrap_err().to_string();
            assert!(e.contains("e.conf: line 2") && e.contains("divisors of 20"), "{e}");
        }
        for n in [1, 2, 4, 5, 10, 20] {
            let text = format!("Tracking_1C.extend_correlation_symbols={n}\n");
            assert_eq!(GnssSdrConf::parse(&text, "e.conf").unwrap().tracking().unwrap().extend_correlation_symbols, n);
        }
        // Bandwidths no loop at its update interval can have (1e200 once sent the
        // importer's eigenvalue search into a long loop; found by fuzzing).
        for (conf, want) in [
            ("Tracking_1C.pll_bw_narrow_hz=1e200\nTracking_1C.extend_correlation_symbols=20\n", "25 Hz"),
            ("Tracking_1C.pll_bw_narrow_hz=30\nTracking_1C.extend_correlation_symbols=20\n", "25 Hz"),
            ("Tracking_1C.pll_bw_hz=501\n", "500 Hz"),
        ] {
            let e = GnssSdrConf::parse(conf, "w.conf").unwrap().tracking().unwrap_err().to_string();
            assert!(e.contains("above 1/(2T)") && e.contains(want), "{e}");
        }
        let t = GnssSdrConf::parse(
            "Tracking_1C.pll_bw_narrow_hz=25\nTracking_1C.extend_correlation_symbols=20\n",
            "ok.conf",
        );
        assert!(t.unwrap().tracking().is_ok());
    }

    #[test]
    fn the_stages_of_the_tracking_settings() {
        let conf = |text: &str| GnssSdrConf::parse(text, "s.conf").unwrap();
        assert_eq!(conf("").tracking_implementation().unwrap(), SUPPORTED_TRACKING);
        assert_eq!(conf("").pll_order_and_bandwidths().unwrap(), (3, 35.0, 5.0));
        let c = conf("Tracking_1C.pll_filter_order=2.0\nTracking_1C.pll_bw_hz=20\nTracking_1C.pll_bw_narrow_hz=2\n");
        assert_eq!(c.pll_order_and_bandwidths().unwrap(), (2, 20.0, 2.0));
        let e = conf("x=1\nTracking_1C.pll_bw_narrow_hz=-2\n").pll_order_and_bandwidths().unwrap_err().to_string();
        assert!(e.contains("s.conf: line 2") && e.contains("pll_bw_narrow_hz = -2: must be > 0"), "{e}");
        // Clamped to [1, 20] as GNSS-SDR clamps it; rounded; 1 when absent.
        for (text, n) in [
            ("", 1),
            ("Tracking_1C.extend_correlation_symbols=40\n", 20),
            ("Tracking_1C.extend_correlation_symbols=0\n", 1),
            ("Tracking_1C.extend_correlation_symbols=4.6\n", 5),
        ] {
            assert_eq!(conf(text).extend_correlation_symbols().unwrap(), n, "{text}");
        }
        // 1/(2T): 500 Hz at 1 ms, 50 Hz at 10 ms.
        let c = conf("");
        assert!(c.check_bandwidths_below_update_rate(500.0, 50.0, 10).is_ok());
        let e = c.check_bandwidths_below_update_rate(35.0, 50.1, 10).unwrap_err().to_string();
        assert!(e.contains("pll_bw_narrow_hz = 50.1: above 1/(2T) = 50 Hz for a loop updated every T = 10 ms"), "{e}");
        // The internal rate first, else the source's.
        assert_eq!(conf("").sampling_rate_hz().unwrap(), None);
        assert_eq!(conf("SignalSource.sampling_frequency=4e6\n").sampling_rate_hz().unwrap(), Some(4e6));
        let c = conf("SignalSource.sampling_frequency=4e6\nGNSS-SDR.internal_fs_sps=2e6\n");
        assert_eq!(c.sampling_rate_hz().unwrap(), Some(2e6));
        assert!(
            conf("GNSS-SDR.internal_fs_sps=0\n").sampling_rate_hz().unwrap_err().to_string().contains("must be > 0")
        );
    }

    #[test]
    fn lock_detector_keys_defaults_and_sources() {
        let l = GnssSdrConf::parse("", "e.conf").unwrap().lock_detector().unwrap();
        assert_eq!(l, LockDetectorConf::defaults());
        assert_eq!(
            (l.carrier_lock_th.value, l.cn0_min_dbhz.value, l.max_lock_fail.value, l.max_carrier_lock_fail.value),
            (0.7, 25.0, 50, 5000)
        );
        assert_eq!(l.cn0_samples.value, 20);
        assert_eq!(l.carrier_lock_th.source, ValueSource::GnssSdrDefault);
        let text = "Tracking_1C.carrier_lock_th=0.85;\nTracking_1C.cn0_min=30.7\nTracking_1C.max_lock_fail=100\n\
                    Tracking_1C.max_carrier_lock_fail=200 ; comment\nTracking_1C.pull_in_time_s=2.9\n";
        let t = GnssSdrConf::parse(text, "l.conf").unwrap().tracking().unwrap();
        let l = t.lock;
        assert_eq!(l.carrier_lock_th, Sourced { value: 0.85, source: ValueSource::Conf });
        // Integers read as GNSS-SDR's stream reads an int: 30.7 is 30, 2.9 s is 2 s.
        assert_eq!(l.cn0_min_dbhz.value, 30.0);
        assert_eq!((l.max_lock_fail.value, l.max_carrier_lock_fail.value), (100, 200));
        assert_eq!(l.max_lock_fail.source, ValueSource::Conf);
        assert_eq!(l.cn0_samples.source, ValueSource::GnssSdrDefault);
        assert_eq!(t.pull_in_time_s, 2.0);
        for (text, want) in [
            ("Tracking_1C.max_lock_fail=-3\n", "whole number ≥ 0"),
            ("x=1\nTracking_1C.max_carrier_lock_fail=many\n", "not an integer"),
            ("Tracking_1C.carrier_lock_th=1.2\n", "outside [−1, 1]"),
        ] {
            let e = GnssSdrConf::parse(text, "b.conf").unwrap().tracking().unwrap_err().to_string();
            assert!(e.contains("b.conf") && e.contains(want), "{e}");
        }
        let e = GnssSdrConf::parse("x=1\nTracking_1C.max_carrier_lock_fail=many\n", "b.conf").unwrap();
        assert!(e.tracking().unwrap_err().to_string().contains("line 2"));
    }

    #[test]
    fn numeric_prefixes_like_a_stream() {
        assert_eq!(numeric_prefix("40.0;"), "40.0");
        assert_eq!(numeric_prefix("-1.5e3x"), "-1.5e3");
        assert_eq!(numeric_prefix("2e"), "2");
        assert_eq!(numeric_prefix(".5"), ".5");
        assert_eq!(numeric_prefix("abc"), "");
    }

    #[test]
    fn written_conf_parses_back() {
        let o = IqConfOptions::for_iq_file("/tmp/x.bin", "ibyte", 4e6, 8, 2, 3.0);
        let c = GnssSdrConf::parse(&iq_file_conf(&o), "w.conf").unwrap();
        let t = c.tracking().unwrap();
        assert_eq!(
            (t.pll_filter_order, t.pll_bw_hz, t.pll_bw_narrow_hz, t.extend_correlation_symbols),
            (2, 35.0, 3.0, 20)
        );
        assert_eq!(t.fs_hz, Some(4e6));
        assert_eq!(c.get("SignalSource.filename"), Some("/tmp/x.bin"));
        assert_eq!(c.get("DataTypeAdapter.implementation"), Some("Ibyte_To_Complex"));
        assert_eq!(c.get("Acquisition_1C.blocking"), Some("false"));
        assert_eq!(c.get("Tracking_1C.enable_fll_pull_in"), Some("true"));
        assert!(!t.enable_fll_steady_state);
    }

    #[test]
    fn each_section_of_the_written_conf_holds_its_blocks() {
        let o = IqConfOptions::for_iq_file("/tmp/x.bin", "ishort", 2.048e6, 3, 3, 5.0);
        let sections = [
            source_section(&o),
            conditioner_section(&o.item_type),
            acquisition_section(&o),
            tracking_section(&o),
            NAVIGATION_SECTION.to_string(),
        ];
        assert_eq!(iq_file_conf(&o), sections.concat());
        let blocks: [&[&str]; 5] = [
            &["GNSS-SDR.", "SignalSource."],
            &["SignalConditioner.", "DataTypeAdapter.", "InputFilter.", "Resampler."],
            &["Channels_1C.", "Channels.", "Channel.", "Acquisition_1C."],
            &["Tracking_1C."],
            &["TelemetryDecoder_1C.", "Observables.", "PVT."],
        ];
        for (i, (section, prefixes)) in sections.iter().zip(blocks).enumerate() {
            // Blocks are separated by a blank line; the last one ends the file.
            assert_eq!(section.ends_with("\n\n"), i < 4, "{section}");
            for e in &GnssSdrConf::parse(section, "s.conf").unwrap().entries {
                assert!(prefixes.iter().any(|p| e.key.starts_with(p)), "{} in {prefixes:?}", e.key);
            }
        }
        let source = GnssSdrConf::parse(&sections[0], "s.conf").unwrap();
        assert_eq!(source.get("GNSS-SDR.internal_fs_sps"), Some("2048000"));
        assert_eq!(source.get("SignalSource.sampling_frequency"), Some("2048000"));
        assert_eq!(source.get("SignalSource.item_type"), Some("ishort"));
        assert!(sections[0].starts_with("; GNSS-SDR 0.0.17 configuration written by gsens: tracks /tmp/x.bin\n"));
        assert!(sections[0].contains("(the tracking dumps go to ./trk_ch_<channel>.dat)"));
        for (item, adapter) in
            [("ibyte", "Ibyte_To_Complex"), ("ishort", "Ishort_To_Complex"), ("gr_complex", "Pass_Through")]
        {
            let c = GnssSdrConf::parse(&conditioner_section(item), "c.conf").unwrap();
            assert_eq!(
                (c.get("DataTypeAdapter.implementation"), c.get("DataTypeAdapter.item_type")),
                (Some(adapter), Some(item))
            );
        }
        let acquisition = GnssSdrConf::parse(&sections[2], "a.conf").unwrap();
        assert_eq!(
            (acquisition.get("Channels_1C.count"), acquisition.get("Acquisition_1C.doppler_max")),
            (Some("3"), Some("6000"))
        );
        let tracking = GnssSdrConf::parse(&sections[3], "t.conf").unwrap();
        let t = tracking.tracking().unwrap();
        assert_eq!(
            (t.pll_filter_order, t.pll_bw_hz, t.pll_bw_narrow_hz, t.extend_correlation_symbols, t.pull_in_time_s),
            (3, 35.0, 5.0, 20, 2.0)
        );
        assert_eq!(tracking.get("Tracking_1C.dump_filename"), Some("./trk_ch_"));
    }
}
