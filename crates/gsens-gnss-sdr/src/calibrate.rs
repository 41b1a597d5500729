//! The crate documentation's section "The estimate with GNSS-SDR's own loop" describes this module.

use gsens_calib::{
    LoopFreeError, LoopFreeEstimate, MeasurementChoice, Outcome, PipelineSettings, SourceConversion, calibrate_logs,
    estimate_loop_free_from,
};
use gsens_core::units::Decimal;
use gsens_core::{Discriminator, LoopModel};
use gsens_io::{FormatError, TrackingLog};
use serde::Serialize;
use std::path::Path;

use crate::error::GnssSdrError;
use crate::import::{ImportSettings, Imported, TrackSummary, import_dir, resample};
use crate::input_phase::gnss_sdr_input_phases;

/// What a conversion of GNSS-SDR dumps did: its settings and every track's
/// fate (what `gsens import gnss-sdr --tracks-json` writes, and the result
/// document's `source` block).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Conversion {
    /// The conversion settings (thresholds, the tracking configuration).
    pub conversion: ImportSettings,
    /// Every track found and what became of it.
    pub tracks: Vec<TrackSummary>,
}

impl Conversion {
    /// The result document's record of this conversion (receiver `gnss-sdr`).
    pub fn source(&self) -> SourceConversion {
        SourceConversion {
            receiver: "gnss-sdr".into(),
            conversion: serde_json::to_value(&self.conversion).unwrap_or_default(),
            tracks: self.tracks.iter().map(|t| serde_json::to_value(t).unwrap_or_default()).collect(),
        }
    }
}

/// The tracking log of GNSS-SDR dumps on their common grid (every track
/// resampled at t = j·T, T = 20 ms the record interval: each row holds the last
/// of the 20/N loop updates since the previous one, which
/// [`with_gnss_sdr_loop`]'s `last` logged phase states).
pub fn gnss_sdr_tracking_log(dir: &Path, imported: &Imported) -> Result<TrackingLog, FormatError> {
    let rows = resample(imported, imported.interval_s);
    let name = format!("{} (GNSS-SDR dumps on a {} ms grid)", dir.display(), Decimal(imported.interval_s * 1e3));
    TrackingLog::from_rows(&name, &rows)
}

/// `settings` with GNSS-SDR's own carrier loop of `import` (its configuration)
/// modelled exactly: the receiver loop is GNSS-SDR's stage, each row holds its
/// last discriminator output, the loop counts as stated, and it is exact,
/// with a tolerance of 0 unless one was given. For tracking rows that came from GNSS-SDR by another
/// path than its dumps (its tracking monitor): a Kaplan model of the same
/// order and bandwidth at its 20 ms integration is not its loop.
pub fn with_gnss_sdr_loop(settings: &PipelineSettings, import: &ImportSettings) -> PipelineSettings {
    // dll_pll_veml_tracking's PLL on GPS L1 C/A: pll_cloop_two_quadrant_atan
    // (its four-quadrant pll_four_quadrant_atan only with track_pilot, and L1 C/A has no pilot).
    settings.with_exact_loop(LoopModel::GnssSdr(import.stage()), Discriminator::AtanCostas)
}

/// Why settings that state a receiver loop are refused with a GNSS-SDR
/// configuration, which states its own ([`with_gnss_sdr_loop`]): the
/// options named by `name` (a command line's flag, say).
pub fn loop_stated_twice(name: impl Fn(&str) -> String) -> String {
    let (conf, order, bn_hz) = (name("gnss_sdr_conf"), name("order"), name("bn_hz"));
    format!("{conf} states the receiver loop: leave out {order}, {bn_hz} and the like")
}

/// A calibration from GNSS-SDR dumps: the pipeline's outcome, what the
/// conversion did, and the tracking log the dumps became.
#[derive(Debug, Clone)]
pub struct GnssSdrOutcome {
    /// The calibration (its `source` holds [`Conversion::source`]).
    pub outcome: Outcome,
    /// What the conversion did, typed.
    pub conversion: Conversion,
    /// The rows the estimate was made from ([`gnss_sdr_tracking_log`]), for
    /// what needs them besides the estimate (the C/N0 of a report's figures).
    pub tracking: TrackingLog,
}

/// Calibrates from GNSS-SDR tracking dumps (`Tracking_1C.dump=true`) and an
/// IMU log, with GNSS-SDR's own carrier loop modelled exactly, and the
/// loop-free estimate from the records' NCO beside it
/// ([`crate::gnss_sdr_input_phases`], the outcome's `loop_free`): the loop and
/// logged-phase settings of `settings` are replaced by the ones the dumps
/// were made with ([`with_gnss_sdr_loop`]). The records begin at the narrow
/// loop's switch, possibly mid-shake: the pipeline's warm-up covers the
/// regressor models' start-up ([`gsens_calib::models_warmup_s`]).
pub fn calibrate_gnss_sdr(
    dumps_dir: &Path,
    import: &ImportSettings,
    imu: &Path,
    settings: &PipelineSettings,
) -> Result<GnssSdrOutcome, GnssSdrError> {
    let imported = import_dir(dumps_dir, import)?;
    let tracking = gnss_sdr_tracking_log(dumps_dir, &imported)?;
    let imu_series = gsens_io::read_imu_file(imu)?;
    let settings = with_gnss_sdr_loop(settings, import);
    // The dumps' input phases come beside the log, not in it: the
    // measurement is chosen once the loop-free estimate is there.
    let mut closed_loop = settings.clone();
    closed_loop.measurement = MeasurementChoice::TrackingError;
    let mut outcome = calibrate_logs(&tracking, &imu_series, &imu.display().to_string(), &closed_loop)?;
    outcome.loop_free = Some(loop_free(&imported, &imu_series, &settings));
    outcome.choose_measurement(settings.measurement)?;
    let conversion = Conversion { conversion: import.clone(), tracks: imported.tracks };
    outcome.source = Some(conversion.source());
    outcome.inputs =
        vec![("imu".into(), imu.display().to_string()), ("gnss_sdr_dumps".into(), dumps_dir.display().to_string())];
    Ok(GnssSdrOutcome { outcome, conversion, tracking })
}

/// The loop-free estimate beside the one through GNSS-SDR's loop, from the
/// records' NCO ([`gnss_sdr_input_phases`]; the replica's phase as
/// `crate::nco` books it, for every `extend_correlation_symbols`).
fn loop_free(
    imported: &Imported,
    imu: &gsens_io::ImuSeries,
    settings: &PipelineSettings,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    let free = settings.loop_free(imported.interval_s);
    let phases = gnss_sdr_input_phases(imported, imported.interval_s, free.max_abs_phase_rad);
    estimate_loop_free_from(&phases, imu, &free)
}

#[cfg(test)]
mod tests {
    /// The refusal names the options as the caller spells them.
    #[test]
    fn a_loop_stated_twice_names_the_options() {
        let said = super::loop_stated_twice(|n| format!("<{n}>"));
        assert_eq!(said, "<gnss_sdr_conf> states the receiver loop: leave out <order>, <bn_hz> and the like");
    }
}
