//! Loops built from absurd parameters are refused as unstable, at once:
//! their state matrices (entries near 1e200) once sent nalgebra's Schur
//! iteration into a loop that never ended (a GNSS-SDR `.conf`
//! with `pll_bw_narrow_hz=1e200` hung the importer).

use gsens_core::gnss_sdr::{GnssSdrPll, GnssSdrStage};
use gsens_core::{LoopModel, LoopSpec};

#[test]
fn absurd_bandwidths_are_unstable_not_hangs() {
    for bn_hz in [1e6, 1e100, 1e200, f64::MAX] {
        let kaplan = LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz, zeta: 0.707 }, Some(0.001));
        assert!(kaplan.check().is_err(), "Kaplan Bn {bn_hz}");
        let third = LoopModel::kaplan(LoopSpec::third_order_kaplan(bn_hz), Some(0.001));
        assert!(third.check().is_err(), "3rd order Bn {bn_hz}");
        for order in [2, 3] {
            let stage = GnssSdrStage { order, bw_hz: bn_hz, symbols: 20 };
            match GnssSdrPll::new(stage) {
                Err(_) => {}
                Ok(pll) => {
                    assert!(!pll.is_stable(), "GNSS-SDR order {order} Bn {bn_hz}");
                    assert_eq!(pll.settling_time_s(5.0), f64::INFINITY, "GNSS-SDR order {order} Bn {bn_hz}");
                }
            }
        }
    }
}
