//! The settings a Monte Carlo compares: one per method, each the same
//! calibration options around the scenario's receiver
//! ([`scenario_settings`]), the receiver's loop optionally stated wrong or
//! not stated at all. Every method estimates from the tracking error; the
//! loop-free estimate, the same for every method, is taken beside them
//! ([`crate::LOOP_FREE`]).

use crate::{MonteCarloError, scenario_settings};
use gsens_calib::{CalibrationOptions, MeasurementChoice, MethodName, PipelineSettings};
use gsens_sim::scenario::Scenario;

/// The pipeline settings of `options` with each of `methods`, around the
/// receiver of `scenario`, its loop's bandwidth stated `stated_bn_scale`
/// times the true one (1: right), as a user who got it wrong would
/// ([`gsens_core::LoopModel::with_bn_scaled`]), or, with `None`, no loop
/// stated (the data choose it, [`gsens_calib::choose_loop`]). Each estimates
/// from the tracking error ([`MeasurementChoice::TrackingError`]).
pub fn method_settings(
    scenario: &Scenario,
    options: &CalibrationOptions,
    methods: &[MethodName],
    stated_bn_scale: Option<f64>,
) -> Result<Vec<PipelineSettings>, MonteCarloError> {
    if let Some(scale) = stated_bn_scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
        let expected = "finite and > 0";
        return Err(gsens_calib::CalibError::Setting { name: "stated_bn_scale", value: scale, expected }.into());
    }
    methods
        .iter()
        .map(|&method| {
            let o = CalibrationOptions { method, measurement: MeasurementChoice::TrackingError, ..options.clone() };
            let mut s = scenario_settings(scenario, &o.estimate_settings())?;
            s.receiver_loop = s.receiver_loop.with_bn_scaled(stated_bn_scale.unwrap_or(1.0));
            let mut p = o.pipeline_settings_around(s)?;
            if stated_bn_scale.is_none() {
                p.estimate.receiver_loop = o.estimate_settings().receiver_loop;
                p.loop_stated = false;
            }
            Ok(p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_calib::Method;

    #[test]
    fn one_setting_per_method_around_the_scenarios_loop_scaled() {
        let scenario = Scenario::default();
        let mut options = CalibrationOptions::default();
        options.estimator.lambda = 0.999;
        let s = method_settings(&scenario, &options, &[MethodName::Batch, MethodName::Rls], Some(1.5)).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].estimate.method, Method::Batch);
        assert_eq!(s[1].estimate.method, Method::Rls { lambda: 0.999 });
        let bn = |p: &PipelineSettings| p.estimate.receiver_loop.bn_hz().unwrap();
        assert!((bn(&s[0]) - 1.5 * scenario.tracking_loop.bn_hz).abs() < 1e-12);
        assert_eq!(s[0].estimate.logged_phase, scenario.log.phase);
        let mut bad = CalibrationOptions::default();
        bad.estimator.warmup_s = -1.0;
        assert!(matches!(
            method_settings(&scenario, &bad, &[MethodName::Batch], Some(1.0)),
            Err(MonteCarloError::Settings(_))
        ));
        assert!(matches!(
            method_settings(&scenario, &options, &[MethodName::Batch], Some(0.0)),
            Err(MonteCarloError::Settings(_))
        ));
        let unstated = method_settings(&scenario, &options, &[MethodName::Batch], None).unwrap();
        assert!(!unstated[0].loop_stated);
        assert_eq!(unstated[0].measurement, MeasurementChoice::TrackingError);
    }
}
