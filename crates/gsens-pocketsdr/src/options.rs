//! The crate documentation's section "The options file" describes this module.

use gsens_core::units::Decimal;
use std::path::Path;

use serde::Serialize;

use gsens_core::pocket_sdr::DEFAULT_BW_HZ;

use crate::error::PocketSdrError;

/// `pocket_trk`'s `epoch` when not set (PocketSDR's `SDR_EPOCH`) \[s\].
pub(crate) const DEFAULT_EPOCH_S: f64 = 1.0;

/// The keys `pocket_trk` knows (`sdr_rcv_setopt`, and `fftw_wisdom`).
pub(crate) const KNOWN_KEYS: [&str; 18] = [
    "epoch",
    "lag_epoch",
    "el_mask",
    "sp_corr",
    "t_acq",
    "t_dll",
    "b_dll",
    "b_pll",
    "b_fll_w",
    "b_fll_n",
    "max_dop",
    "thres_cn0_l",
    "thres_cn0_u",
    "thres_pli",
    "lost_th",
    "bump_jump",
    "max_acq",
    "fftw_wisdom",
];

/// Where a setting's value comes from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SettingSource {
    /// PocketSDR's built-in default.
    Default,
    /// A line of the options file.
    File {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
    },
    /// Measured from the log itself.
    Log,
}

/// A value and where it comes from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Setting {
    /// The value.
    pub value: f64,
    /// Its source.
    pub source: SettingSource,
}

impl Setting {
    fn default_value(value: f64) -> Self {
        Setting { value, source: SettingSource::Default }
    }
}

impl Setting {
    /// The value with its unit and source, e.g. `5 Hz (PocketSDR's default)`.
    pub fn with_unit(&self, unit: &str) -> String {
        match &self.source {
            SettingSource::Default => format!("{} {unit} (PocketSDR's default)", Decimal(self.value)),
            SettingSource::File { file, line } => format!("{} {unit} ({file}:{line})", Decimal(self.value)),
            SettingSource::Log => format!("{} {unit} (measured from the log)", Decimal(self.value)),
        }
    }
}

/// The options that decide the loop and the log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PocketSdrOptions {
    /// The options file, if one was read.
    pub file: Option<String>,
    /// `b_pll`: the PLL noise bandwidth \[Hz\].
    pub b_pll_hz: Setting,
    /// `epoch`: the `$CH` log interval \[s\]; `None` when no file sets it
    /// (the log's own interval is used, PocketSDR's default being 1 s).
    pub epoch_s: Option<Setting>,
    /// Every other `key = value`, as text, with its line.
    pub others: Vec<(String, String, usize)>,
    /// Lines `pocket_trk` ignores (no `=`, unknown key), with their line.
    pub ignored: Vec<(usize, String)>,
}

impl Default for PocketSdrOptions {
    fn default() -> Self {
        PocketSdrOptions {
            file: None,
            b_pll_hz: Setting::default_value(DEFAULT_BW_HZ),
            epoch_s: None,
            others: Vec::new(),
            ignored: Vec::new(),
        }
    }
}

impl PocketSdrOptions {
    /// Reads an options file.
    pub fn read(path: &Path) -> Result<Self, PocketSdrError> {
        let name = path.display().to_string();
        let text =
            gsens_io::read_config_text(path).map_err(|error| PocketSdrError::Io { file: name.clone(), error })?;
        Self::parse(&text, &name)
    }

    /// Parses an options file's text; `file` names it in messages.
    pub fn parse(text: &str, file: &str) -> Result<Self, PocketSdrError> {
        let mut o = PocketSdrOptions { file: Some(file.to_string()), ..Default::default() };
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let l = raw.split('#').next().unwrap_or("").trim();
            if l.is_empty() {
                continue;
            }
            let Some((key, value)) = l.split_once('=') else {
                o.ignored.push((line, format!("{l:?}: no `=` (pocket_trk ignores the line)")));
                continue;
            };
            let (key, value) = (key.trim(), value.trim());
            if !KNOWN_KEYS.contains(&key) {
                o.ignored.push((line, format!("{key:?}: not a pocket_trk option (pocket_trk ignores it)")));
                continue;
            }
            let err = |reason: String| PocketSdrError::Options { file: file.into(), line, key: key.into(), reason };
            let number = || -> Result<f64, PocketSdrError> {
                match value.parse::<f64>() {
                    Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
                    _ => Err(err(format!("{value:?} is not a positive number"))),
                }
            };
            let setting = |v: f64| Setting { value: v, source: SettingSource::File { file: file.into(), line } };
            match key {
                "b_pll" => o.b_pll_hz = setting(number()?),
                "epoch" => {
                    let v = number()?;
                    let ms = (v * 1e3).round();
                    if ms < 1.0 || (v * 1e3 - ms).abs() > 1e-6 {
                        return Err(err(format!(
                            "{value} s is not a whole number of milliseconds (pocket_trk logs on its 1 ms cycles)"
                        )));
                    }
                    o.epoch_s = Some(setting(v));
                }
                _ => {
                    o.others.retain(|(k, _, _)| k != key);
                    o.others.push((key.to_string(), value.to_string(), line));
                }
            }
        }
        Ok(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_b_pll_and_epoch_with_their_lines_like_pocket_trk() {
        let text =
            "# options\nepoch       = 0.025   # 40 Hz\n\nb_pll = 5\nb_pll = 10.0\nb_dll=0.5\nnonsense\nfoo = 1\n";
        let o = PocketSdrOptions::parse(text, "o.conf").unwrap();
        assert_eq!(o.b_pll_hz.value, 10.0);
        assert_eq!(o.b_pll_hz.source, SettingSource::File { file: "o.conf".into(), line: 5 });
        assert_eq!(o.epoch_s.as_ref().map(|s| s.value), Some(0.025));
        assert_eq!(o.others, vec![("b_dll".to_string(), "0.5".to_string(), 6)]);
        assert_eq!(o.ignored.iter().map(|(l, _)| *l).collect::<Vec<_>>(), vec![7, 8]);
        let d = PocketSdrOptions::default();
        assert_eq!((d.b_pll_hz.value, d.epoch_s), (5.0, None));
    }

    #[test]
    fn a_value_that_is_not_a_number_names_file_line_and_key() {
        let e = PocketSdrOptions::parse("epoch = 0.025\nb_pll = 10Hz\n", "o.conf").unwrap_err().to_string();
        assert_eq!(e, "o.conf: line 2: b_pll: \"10Hz\" is not a positive number");
        let e = PocketSdrOptions::parse("epoch = 0.0255\n", "o.conf").unwrap_err().to_string();
        assert!(e.starts_with("o.conf: line 1: epoch:") && e.contains("milliseconds"), "{e}");
    }
}
