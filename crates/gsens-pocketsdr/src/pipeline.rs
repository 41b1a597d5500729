//! The estimate from a `pocket_trk` log with PocketSDR's own loop.

use gsens_core::units::Decimal;
use std::path::Path;

use gsens_calib::{Outcome, PipelineSettings, SourceConversion, calibrate_logs};
use gsens_core::LoopModel;
use gsens_io::{FormatError, TrackingLog};

use crate::error::PocketSdrError;
use crate::import::{ImportSettings, Imported, import_file};

/// A calibration from a PocketSDR log: the pipeline's outcome and what the
/// conversion did.
#[derive(Debug, Clone)]
pub struct PocketSdrOutcome {
    /// The calibration.
    pub outcome: Outcome,
    /// The conversion of the log.
    pub imported: Imported,
}

/// The tracking log of a converted PocketSDR log (every channel already on
/// the log's common epochs, every row on GPS L1 C/A), with each row's NCO
/// record (`adr` as `nco_phase_cycles`, `dop` as `nco_freq_hz`) for the
/// loop-free estimate ([`gsens_calib::estimate_loop_free`]).
pub fn pocketsdr_tracking_log(imported: &Imported) -> Result<TrackingLog, FormatError> {
    let name = format!("{} (PocketSDR $CH lines, every {} s)", imported.file, Decimal(imported.interval_s()));
    let rows = imported.rows.iter().zip(&imported.nco).map(|(r, n)| (r, gsens_io::Carrier::GPS_L1, *n));
    TrackingLog::from_rows_with_nco(&name, rows)
}

impl Imported {
    /// The result document's record of this conversion (receiver
    /// `pocketsdr`): the conversion as [`Imported`] serializes it, its tracks
    /// apart.
    pub fn source(&self) -> SourceConversion {
        let mut conversion = serde_json::to_value(self).unwrap_or_default();
        let tracks = match conversion.as_object_mut().and_then(|o| o.remove("tracks")) {
            Some(serde_json::Value::Array(tracks)) => tracks,
            _ => Vec::new(),
        };
        SourceConversion { receiver: "pocketsdr".into(), conversion, tracks }
    }
}

/// Calibrates from a `pocket_trk` log and an IMU log with PocketSDR's own
/// carrier loop modelled exactly ([`gsens_core::pocket_sdr`]): the loop of
/// `settings` is replaced by PocketSDR's at the options' `b_pll`, each row
/// is the single 1 ms discriminator output at its epoch
/// ([`gsens_core::LoggedPhase::Last`]), the loop is exact (a tolerance of 0 unless
/// `settings` give one: tested, not fitted); the pipeline's warm-up covers
/// the regressor models' start-up ([`gsens_calib::models_warmup_s`]).
pub fn calibrate_pocketsdr(
    log: &Path,
    import: &ImportSettings,
    imu: &Path,
    settings: &PipelineSettings,
) -> Result<PocketSdrOutcome, PocketSdrError> {
    let imported = import_file(log, import)?;
    // With the NCO's phase (adr) the pipeline makes the loop-free estimate beside this one.
    let tracking = pocketsdr_tracking_log(&imported)?;
    let imu_series = gsens_io::read_imu_file(imu)?;
    // PocketSDR's loop is known exactly from its options: tested, not fitted.
    // pocket_trk's err_phas on L1CA: atan(Q/I), the two-quadrant Costas discriminator.
    let settings =
        settings.with_exact_loop(LoopModel::PocketSdr(imported.stage), gsens_core::Discriminator::AtanCostas);
    let mut outcome = calibrate_logs(&tracking, &imu_series, &imu.display().to_string(), &settings)?;
    outcome.inputs =
        vec![("imu".into(), imu.display().to_string()), ("pocketsdr_log".into(), log.display().to_string())];
    if let Some(f) = &import.options.file {
        outcome.inputs.push(("pocketsdr_options".into(), f.clone()));
    }
    outcome.source = Some(imported.source());
    Ok(PocketSdrOutcome { outcome, imported })
}
