//! The settings a Monte Carlo compares: one per method, each the same
//! calibration options around the scenario's receiver
//! ([`scenario_settings`]), the receiver's loop optionally stated wrong.

use crate::{MonteCarloError, scenario_settings};
use gsens_calib::{CalibrationOptions, MethodName, PipelineSettings};
use gsens_sim::scenario::Scenario;

/// The pipeline settings of `options` with each of `methods`, around the
/// receiver of `scenario`, its loop's bandwidth stated `stated_bn_scale`
/// times the true one (1: right), as a user who got it wrong would
/// ([`gsens_core::LoopModel::with_bn_scaled`]).
pub fn method_settings(
    scenario: &Scenario,
    options: &CalibrationOptions,
    methods: &[MethodName],
    stated_bn_scale: f64,
) -> Result<Vec<PipelineSettings>, MonteCarloError> {
    methods
        .iter()
        .map(|&method| {
            let o = CalibrationOptions { method, ..options.clone() };
            let mut s = scenario_settings(scenario, &o.estimate_settings())?;
            s.receiver_loop = s.receiver_loop.with_bn_scaled(stated_bn_scale);
            Ok(o.pipeline_settings_around(s)?)
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
        let s = method_settings(&scenario, &options, &[MethodName::Batch, MethodName::Rls], 1.5).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].estimate.method, Method::Batch);
        assert_eq!(s[1].estimate.method, Method::Rls { lambda: 0.999 });
        let bn = |p: &PipelineSettings| p.estimate.receiver_loop.bn_hz().unwrap();
        assert!((bn(&s[0]) - 1.5 * scenario.tracking_loop.bn_hz).abs() < 1e-12);
        assert_eq!(s[0].estimate.logged_phase, scenario.log.phase);
        let mut bad = CalibrationOptions::default();
        bad.estimator.warmup_s = -1.0;
        assert!(matches!(
            method_settings(&scenario, &bad, &[MethodName::Batch], 1.0),
            Err(MonteCarloError::Settings(_))
        ));
    }
}
