//! The outputs of the studies around a calibration besides its report: a
//! loop's response as JSON (`gsens response --json`), a prediction's lock
//! margin over the loop bandwidth (`gsens predict --figure`) and a
//! validation's g-induced phase error without and with −aᵀΓ̂ in the loop
//! (`gsens validate --figure`).

use crate::figures::{
    CompensationData, CompensationKind, DEFAULT_SIZE, LockMarginData, ResponseData, fig_compensation, fig_lock_margin,
};
use crate::figures::{Format, Image, RenderError};
use gsens_calib::LoopSummary;
use gsens_calib::predict::{COSTAS_LOCK_RULE_RAD, SweepContext, SweepSettings};
use gsens_core::LoopModel;
use serde::Serialize;

/// The response's JSON: the loop's update interval, the shaking period to
/// use (1/the peak's frequency), the loop and the table.
#[derive(Serialize)]
struct ResponseJson<'a> {
    loop_interval_s: Option<f64>,
    recommended_period_s: f64,
    #[serde(rename = "loop")]
    summary: LoopSummary,
    #[serde(flatten)]
    table: &'a ResponseData,
}

/// The response `table` of `model` as pretty JSON with a final newline.
pub fn response_json(model: &LoopModel, table: &ResponseData) -> Result<String, serde_json::Error> {
    let json = ResponseJson {
        loop_interval_s: model.interval_s(),
        recommended_period_s: 1.0 / table.peak_hz,
        summary: LoopSummary::of(model),
        table,
    };
    Ok(serde_json::to_string_pretty(&json)? + "\n")
}

/// The lock margin 3σ + θₑ without and with compensation over the loop's
/// bandwidth at `level` ([`SweepSettings::lock_margin`]) against the
/// Costas rule's π/4, titled with the level, the oscillator and the C/N0.
pub fn fig_lock_margin_at(
    settings: &SweepSettings,
    context: &SweepContext,
    level: f64,
    format: Format,
) -> Result<Image, RenderError> {
    let (bns, without, with) = settings.lock_margin(level);
    let cn0 = settings.base.cn0_dbhz.map_or("no thermal noise".to_string(), |c| format!("C/N0 {c} dB-Hz"));
    let label = format!("vibration level {level}, {} oscillator, {cn0}", context.oscillator);
    let data = LockMarginData {
        bn_hz: &bns,
        without_rad: &without,
        with_rad: &with,
        threshold_rad: COSTAS_LOCK_RULE_RAD,
        label: &label,
    };
    fig_lock_margin(&data, format, DEFAULT_SIZE)
}

/// The g-induced phase error of one channel over time `t_s`, without and
/// with the feed-forward in the loop \[rad\].
pub fn fig_in_the_loop(
    t_s: &[f64],
    without_rad: &[f64],
    with_rad: &[f64],
    format: Format,
) -> Result<Image, RenderError> {
    let before: Vec<Option<f64>> = without_rad.iter().map(|&v| Some(v)).collect();
    let after: Vec<Option<f64>> = with_rad.iter().map(|&v| Some(v)).collect();
    let data = CompensationData { t_s, before_rad: &before, after_rad: &after, kind: CompensationKind::InTheLoop };
    fig_compensation(&data, format, DEFAULT_SIZE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_calib::predict::{FeedForward, PredictionInput, Vibration};
    use gsens_core::LoopSpec;

    #[test]
    fn the_response_json_recommends_the_peaks_period() {
        let model = LoopModel::kaplan(LoopSpec::PAPER, Some(0.001));
        let table = ResponseData::from_loop(&model, 0.05, 20.0, 5, model.to_string()).unwrap();
        let json: serde_json::Value = serde_json::from_str(&response_json(&model, &table).unwrap()).unwrap();
        assert_eq!(json["loop_interval_s"], 0.001);
        assert_eq!(json["recommended_period_s"].as_f64().unwrap(), 1.0 / table.peak_hz);
        // The paper's loop peaks at ωn/2π ≈ 0.9 Hz.
        assert!((table.peak_hz - 0.9).abs() < 0.02, "{}", table.peak_hz);
        assert_eq!(json["loop"]["order"], 2);
        assert_eq!(json["frequency_hz"].as_array().unwrap().len(), 5);
    }

    #[test]
    fn the_study_figures_draw_as_svg() {
        let settings = SweepSettings {
            base: PredictionInput {
                gamma_hz_per_mps2: [0.09, 0.08, -0.08],
                covariance: [[1e-6, 0.0, 0.0], [0.0, 1e-6, 0.0], [0.0, 0.0, 1e-6]],
                vibration: Vibration::Tones(vec![(0.9, [3.0, 0.0, 0.0])]),
                oscillator: None,
                cn0_dbhz: Some(45.0),
                delay_s: 0.0125,
                imu_noise_mps2_per_rthz: 0.0,
                doppler_rate_hz_per_s: 0.9,
            },
            levels: vec![1.0],
            bn_hz: 3.0,
            zeta: std::f64::consts::FRAC_1_SQRT_2,
            loop_interval_s: 0.001,
        };
        let context =
            SweepContext { oscillator: "noise-free", feed_forward: FeedForward { imu_rate_hz: 40.0, latency_s: 0.0 } };
        let svg = fig_lock_margin_at(&settings, &context, 2.0, Format::Svg).unwrap();
        assert!(svg.svg().unwrap().contains("vibration level 2, noise-free oscillator, C/N0 45 dB-Hz"));
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.02).collect();
        let without: Vec<f64> = t.iter().map(|t| 0.2 * (6.0 * t).sin()).collect();
        let with: Vec<f64> = without.iter().map(|v| v / 10.0).collect();
        assert!(fig_in_the_loop(&t, &without, &with, Format::Svg).unwrap().svg().is_some());
        assert!(fig_in_the_loop(&t, &without, &with[..10], Format::Svg).is_err());
    }
}
