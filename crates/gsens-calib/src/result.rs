//! The result of the estimation stage.

use crate::JointFit;
use crate::{AxisVerdict, EstimateSettings, HuberFit};
use serde::{Deserialize, Serialize};

/// A calibration result: the public JSON interface of `gsens estimate`
/// (key names in `docs/conventions.md#result-document`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Calibration {
    /// Γ̂ \[Hz/(m/s²)\]; `null` for an unobservable axis.
    pub gamma_hz_per_mps2: [Option<f64>; 3],
    /// Total 1σ \[Hz/(m/s²)\]: the statistical part (autocorrelation-robust) and
    /// the IMU-calibration part combined; `null` for an unobservable axis.
    pub sigma_hz_per_mps2: [Option<f64>; 3],
    /// Statistical 1σ alone \[Hz/(m/s²)\].
    pub sigma_statistical_hz_per_mps2: [Option<f64>; 3],
    /// 1σ from the assumed IMU scale-factor and misalignment errors \[Hz/(m/s²)\].
    pub sigma_imu_hz_per_mps2: [Option<f64>; 3],
    /// Γ̂ \[ppb/g\] at the carrier.
    pub gamma_ppb_per_g: [Option<f64>; 3],
    /// 1σ \[ppb/g\].
    pub sigma_ppb_per_g: [Option<f64>; 3],
    /// Whether the data observe each axis.
    pub observable: [bool; 3],
    /// Unexplained excitation RMS per axis \[rad per Hz/(m/s²)\].
    pub excitation_rms: [f64; 3],
    /// Covariance of Γ̂ \[(Hz/(m/s²))²\]: the statistical part (each axis's
    /// autocorrelation-robust inflation applied as √(r_i·r_j) to entry ij) plus
    /// the IMU-calibration part on the diagonal; `null` in the rows and columns
    /// of unobservable axes.
    pub covariance_hz_per_mps2_sq: [[Option<f64>; 3]; 3],
    /// Condition number of the information matrix (null when singular).
    pub condition_number: Option<f64>,
    /// The estimate of every axis even when unobservable (for experts).
    pub gamma_raw_hz_per_mps2: [f64; 3],
    /// 1σ assuming white residuals (for comparison with the robust one);
    /// `null` where the data hold no information on the axis.
    pub sigma_white_hz_per_mps2: [Option<f64>; 3],
    /// Cramér–Rao bound on each component \[Hz/(m/s²)\]: √(J⁻¹)_ii, J the Fisher
    /// information of the data under the noise spectrum fitted to the residuals
    /// (an AR model, see [`crate::gls`]). The same for every method; `null` for an
    /// unobservable axis.
    pub crlb_hz_per_mps2: [Option<f64>; 3],
    /// Order of the AR model of the residual noise behind `crlb_hz_per_mps2`.
    pub noise_ar_order: usize,
    /// IMU time stamp minus true time applied to the IMU \[s\].
    pub imu_time_offset_s: f64,
    /// Whether `imu_time_offset_s` was estimated (false: assumed by the user).
    pub imu_time_offset_estimated: bool,
    /// 1σ of the estimated time offset \[s\] (when estimated).
    pub imu_time_offset_sigma_s: Option<f64>,
    /// The joint fit of Γ with the loop and the IMU time offset, and the
    /// test of the stated loop (when either was estimated).
    pub joint_fit: Option<JointFit>,
    /// The Huber fit (with `robust = huber`): scale, threshold, epochs down-weighted.
    pub huber: Option<HuberFit>,
    /// The verdict per axis (shaking frequency, sensitivity reached, advice).
    pub axes: [AxisVerdict; 3],
    /// Largest predicted g-induced phase error |φ_aᵀΓ̂| over the log \[rad\].
    pub predicted_peak_phase_err_rad: f64,
    /// The discriminator's linear range the peak is checked against \[rad\],
    /// on L1's scale: from a session's logs, the smallest over the used
    /// channels of [`gsens_core::Discriminator::linear_range_rad`] at the
    /// channel's C/N0 and the loop's update interval, times f_L1/f_c; from an
    /// epoch series alone (no C/N0 known), the noise-free unambiguous range
    /// (π/2 for atan Costas, π for atan2).
    pub discriminator_linear_range_rad: f64,
    /// RMS of the averaged phase error over the used epochs \[rad\].
    pub rms_before_rad: f64,
    /// RMS of φ − φ_aᵀΓ̂ over the same epochs \[rad\].
    pub rms_after_rad: f64,
    /// RMS of the g-induced part φ_aᵀΓ̂ \[rad\].
    pub rms_g_induced_rad: f64,
    /// Residual standard deviation \[rad\].
    pub residual_sigma_rad: f64,
    /// Epochs used by the estimator.
    pub epochs_used: u64,
    /// Epochs in the series (including gaps and warm-up).
    pub epochs_total: usize,
    /// Log interval \[s\].
    pub log_interval_s: f64,
    /// The estimate as it evolved (every [`crate::HISTORY_INTERVAL_S`] after the warm-up).
    #[serde(skip)]
    pub history: Vec<HistoryPoint>,
    /// Loop updates per log epoch in the model.
    pub model_substeps: u32,
    /// The loop the model ran (the receiver loop at its update interval).
    pub loop_used: gsens_core::LoopModel,
    /// Every setting used.
    pub settings: EstimateSettings,
}

/// The estimate at one epoch of the run (the paper's Fig. 4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HistoryPoint {
    /// Epoch time \[s\].
    pub t_s: f64,
    /// Γ̂ so far \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Its 1σ so far, assuming white residuals \[Hz/(m/s²)\] (+∞ while unexcited).
    pub sigma_hz_per_mps2: [f64; 3],
}

impl Calibration {
    /// Γ̂ \[Hz/(m/s²)\] and its covariance \[(Hz/(m/s²))²\] as plain numbers,
    /// for a compensator; `Err` names the first entry without a number
    /// (`gamma_hz_per_mps2[2]`: that axis was not observable).
    pub fn gamma_with_covariance(&self) -> Result<([f64; 3], [[f64; 3]; 3]), String> {
        let mut gamma = [0.0; 3];
        let mut cov = [[0.0; 3]; 3];
        for i in 0..3 {
            gamma[i] = self.gamma_hz_per_mps2[i].ok_or_else(|| format!("gamma_hz_per_mps2[{i}]"))?;
            for j in 0..3 {
                cov[i][j] = self.covariance_hz_per_mps2_sq[i][j]
                    .ok_or_else(|| format!("covariance_hz_per_mps2_sq[{i}][{j}]"))?;
            }
        }
        Ok((gamma, cov))
    }

    /// Makes an estimate from the NCO's record this calibration's (the
    /// loop-free one from its phase, or the one from its frequency, as
    /// `measurement` says): Γ̂, its statistical
    /// covariance and bound, and the IMU offset are `free`'s; the IMU's
    /// systematic σ ([`crate::imu_systematic_sigma`] at the new Γ̂) is added
    /// on the diagonal as for any estimate; the compensation figures are
    /// `figures`, computed with the new Γ̂. What describes the data and the
    /// loop (the loop check's joint fit, the shaking verdicts, the history)
    /// stays; the Huber fit and the white σ, which belong to the estimate
    /// through the tracking error, are dropped. Whether an axis is observable
    /// is the new estimate's own: its excitation RMS (the detrended
    /// regressor's) at or above the same threshold, and a finite σ.
    pub(crate) fn adopt_direct(
        &mut self,
        measurement: crate::Measurement,
        free: &crate::LoopFreeEstimate,
        figures: crate::estimate::ResidualFigures,
    ) {
        let estimate_name = match measurement {
            crate::Measurement::NcoFrequency => "the estimate from the NCO frequency",
            _ => "the loop-free estimate",
        };
        let gamma = free.gamma_hz_per_mps2;
        let stat = free.sigma_hz_per_mps2();
        let sys = crate::imu_systematic_sigma(
            &gamma,
            self.settings.imu_scale_sigma,
            self.settings.imu_misalignment_sigma_rad,
        );
        let ppb = |v: f64| gsens_core::units::hz_per_mps2_to_ppb_per_g(v, self.settings.carrier_hz);
        let min_excitation = self.settings.criteria.min_excitation_rms;
        let usable: [bool; 3] = [0, 1, 2].map(|i| {
            free.excitation_rms[i] >= min_excitation && gamma[i].is_finite() && stat[i].is_finite() && stat[i] > 0.0
        });
        for i in 0..3 {
            if !usable[i] {
                continue;
            }
            let sigma = stat[i].hypot(sys[i]);
            if !self.observable[i] {
                let v = &mut self.axes[i];
                v.observable = true;
                v.text = format!(
                    "{}: observable in {estimate_name} (excitation RMS {:.2}); through the tracking error: {}",
                    v.axis,
                    free.excitation_rms[i],
                    v.text.split_once(": ").map_or(v.text.as_str(), |(_, r)| r)
                );
            }
            self.observable[i] = true;
            self.excitation_rms[i] = free.excitation_rms[i];
            self.gamma_hz_per_mps2[i] = Some(gamma[i]);
            self.sigma_statistical_hz_per_mps2[i] = Some(stat[i]);
            self.sigma_imu_hz_per_mps2[i] = Some(sys[i]);
            self.sigma_hz_per_mps2[i] = Some(sigma);
            self.gamma_ppb_per_g[i] = Some(ppb(gamma[i]));
            self.sigma_ppb_per_g[i] = Some(ppb(sigma));
            self.crlb_hz_per_mps2[i] = Some(free.crlb_hz_per_mps2[i]).filter(|c| c.is_finite());
            for j in 0..3 {
                let imu = if i == j { sys[i] * sys[i] } else { 0.0 };
                self.covariance_hz_per_mps2_sq[i][j] = usable[j].then_some(free.covariance[i][j] + imu);
            }
        }
        self.gamma_raw_hz_per_mps2 = gamma;
        self.sigma_white_hz_per_mps2 = [None; 3];
        self.huber = None;
        self.imu_time_offset_s = free.imu_time_offset_s;
        self.imu_time_offset_estimated = free.time_offset_searched;
        self.imu_time_offset_sigma_s = None;
        self.epochs_used = free.epochs as u64;
        self.noise_ar_order = free.noise_ar_order;
        self.rms_before_rad = figures.rms_before_rad;
        self.rms_after_rad = figures.rms_after_rad;
        self.rms_g_induced_rad = figures.rms_g_induced_rad;
        self.predicted_peak_phase_err_rad = figures.peak_phase_err_rad;
        for i in 0..3 {
            if !usable[i] {
                self.make_unobservable(i, &format!("too little excitation in {estimate_name}"));
            }
        }
    }

    /// Makes axis `i` unobservable: Γ̂, σ, the CRLB and its covariance row and
    /// column `null`, its verdict saying `why`. A σ of exactly 0 (or not a
    /// number) is no uncertainty but the absence of information on the axis.
    pub(crate) fn make_unobservable(&mut self, i: usize, why: &str) {
        self.observable[i] = false;
        self.gamma_hz_per_mps2[i] = None;
        self.sigma_hz_per_mps2[i] = None;
        self.sigma_statistical_hz_per_mps2[i] = None;
        self.sigma_imu_hz_per_mps2[i] = None;
        self.gamma_ppb_per_g[i] = None;
        self.sigma_ppb_per_g[i] = None;
        self.crlb_hz_per_mps2[i] = None;
        for j in 0..3 {
            self.covariance_hz_per_mps2_sq[i][j] = None;
            self.covariance_hz_per_mps2_sq[j][i] = None;
        }
        let v = &mut self.axes[i];
        v.observable = false;
        v.text = format!("{}: unobservable — {why}", v.axis);
    }

    /// Takes in the joint fit's uncertainty. The batch estimator (and RLS
    /// without forgetting, the same solution) gets the Γ block of the joint
    /// sandwich itself; the others their own statistical covariance scaled by
    /// √(r_i·r_j), r the fit's variance inflation (the loop and the offset
    /// unknown instead of known). The offset and its σ are the fitted ones.
    pub(crate) fn include_nuisance(&mut self, fit: &JointFit) {
        let batch_like = match self.settings.method {
            crate::Method::Batch => true,
            crate::Method::Rls { lambda } => lambda == 1.0,
            _ => false,
        };
        let imu = self.sigma_imu_hz_per_mps2.map(|s| s.unwrap_or(0.0));
        let stat_of = |c: &Self, i: usize, j: usize| -> Option<f64> {
            let imu_ij = if i == j { imu[i] * imu[i] } else { 0.0 };
            c.covariance_hz_per_mps2_sq[i][j].map(|v| v - imu_ij)
        };
        let mut stat = [[None; 3]; 3];
        for (i, row) in stat.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = stat_of(self, i, j).map(|old| {
                    if batch_like {
                        fit.gamma_covariance_hz_per_mps2_sq[i][j]
                    } else {
                        old * (fit.variance_inflation[i] * fit.variance_inflation[j]).sqrt()
                    }
                });
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                let imu_ij = if i == j { imu[i] * imu[i] } else { 0.0 };
                self.covariance_hz_per_mps2_sq[i][j] = stat[i][j].map(|v| v + imu_ij);
            }
            if let (Some(var), Some(total)) = (stat[i][i], self.sigma_hz_per_mps2[i]) {
                if !(var > 0.0 && var.is_finite()) {
                    continue;
                }
                let s = var.sqrt();
                self.sigma_statistical_hz_per_mps2[i] = Some(s);
                let new_total = s.hypot(imu[i]);
                self.sigma_hz_per_mps2[i] = Some(new_total);
                if let Some(p) = &mut self.sigma_ppb_per_g[i] {
                    *p *= if total > 0.0 { new_total / total } else { 1.0 };
                }
            }
        }
        // A variance of 0 (or none) is no σ: the joint fit holds no
        // information on the axis once the loop and the offset are free.
        for i in 0..3 {
            if self.observable[i] && !stat[i][i].is_some_and(|v| v > 0.0 && v.is_finite()) {
                self.make_unobservable(
                    i,
                    "with the loop and the IMU time offset fitted too, the data hold no information on it (the \
                     joint fit's variance is 0 or undefined): state the loop and the offset, or shake along it",
                );
            }
        }
        if let Some(offset_s) = fit.imu_time_offset_s {
            self.imu_time_offset_estimated = true;
            self.imu_time_offset_sigma_s = fit.sigma_imu_time_offset_s;
            self.imu_time_offset_s = offset_s;
        }
        self.joint_fit = Some(fit.clone());
    }
}

impl Calibration {
    /// The calibration of an estimate made without a tracking error (from a
    /// receiver's NCO frequency): `estimate`'s Γ̂ and covariance with the
    /// IMU's systematic σ, each axis's verdict from the specific force on
    /// `epoch_t_s` (at the estimate's IMU offset) and `settings`' loop, the
    /// compensation figures `figures`.
    pub(crate) fn of_direct(
        settings: crate::EstimateSettings,
        epoch_t_s: &[f64],
        imu: &gsens_io::ImuSeries,
        estimate: &crate::LoopFreeEstimate,
        figures: crate::estimate::ResidualFigures,
        model_substeps: u32,
    ) -> Calibration {
        let log_interval_s = crate::loop_free::median_step(epoch_t_s);
        let mut cursor = 0;
        let accel: Vec<[f64; 3]> =
            epoch_t_s.iter().map(|t| imu.interpolate_at(t + estimate.imu_time_offset_s, &mut cursor)).collect();
        let observable = [true; 3];
        let min_excitation = settings.criteria.min_excitation_rms;
        let axes = crate::verdict::axis_verdicts(
            &accel,
            log_interval_s,
            &settings.receiver_loop,
            observable,
            estimate.excitation_rms,
            min_excitation,
        );
        let mut c = Calibration {
            gamma_hz_per_mps2: [None; 3],
            sigma_hz_per_mps2: [None; 3],
            sigma_statistical_hz_per_mps2: [None; 3],
            sigma_imu_hz_per_mps2: [None; 3],
            gamma_ppb_per_g: [None; 3],
            sigma_ppb_per_g: [None; 3],
            observable,
            excitation_rms: estimate.excitation_rms,
            covariance_hz_per_mps2_sq: [[None; 3]; 3],
            condition_number: condition_number(&estimate.covariance),
            gamma_raw_hz_per_mps2: estimate.gamma_hz_per_mps2,
            sigma_white_hz_per_mps2: [None; 3],
            crlb_hz_per_mps2: [None; 3],
            noise_ar_order: estimate.noise_ar_order,
            imu_time_offset_s: estimate.imu_time_offset_s,
            imu_time_offset_estimated: estimate.time_offset_searched,
            imu_time_offset_sigma_s: None,
            joint_fit: None,
            huber: None,
            axes,
            predicted_peak_phase_err_rad: 0.0,
            discriminator_linear_range_rad: settings.discriminator.unambiguous_range_rad(),
            rms_before_rad: 0.0,
            rms_after_rad: 0.0,
            rms_g_induced_rad: 0.0,
            residual_sigma_rad: figures.rms_after_rad,
            epochs_used: estimate.epochs as u64,
            epochs_total: epoch_t_s.len(),
            log_interval_s,
            history: Vec::new(),
            model_substeps,
            loop_used: settings.receiver_loop,
            settings,
        };
        c.adopt_direct(crate::Measurement::NcoFrequency, estimate, figures);
        c
    }
}

/// The condition number of a covariance (the information's is the same):
/// the ratio of its largest to its smallest eigenvalue; `None` where singular.
fn condition_number(covariance: &[[f64; 3]; 3]) -> Option<f64> {
    let m = nalgebra::Matrix3::from_fn(|i, j| covariance[i][j]);
    let e = m.symmetric_eigenvalues();
    let (lo, hi) = (e.min(), e.max());
    (lo > 0.0 && hi.is_finite()).then(|| hi / lo)
}

#[cfg(test)]
mod tests {
    use crate::{EpochSeries, EstimateSettings, JointSpec, calibrate, joint_fit};
    use gsens_core::{DiscretePll, LoopSpec};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::TAU;

    /// 60 s at 40 Hz, the three axes shaken at once at 0.7, 0.9 and 1.1 Hz,
    /// the phase from the paper's loop plus 0.05 rad of white noise.
    fn session() -> (Vec<f64>, Vec<Option<f64>>, Vec<[f64; 3]>) {
        let (t_log, gamma) = (0.025, [0.09, 0.08, -0.08]);
        let mut pll = DiscretePll::new(LoopSpec::PAPER.coeffs().unwrap(), t_log);
        pll.settle(9.80665 * gamma[2]);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let noise = Normal::new(0.0, 0.05).unwrap();
        let (mut t_s, mut phase, mut accel) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..2400 {
            let t = k as f64 * t_log;
            let a = [2.0 * (TAU * 0.7 * t).sin(), 2.0 * (TAU * 0.9 * t).sin(), 9.80665 + 2.0 * (TAU * 1.1 * t).sin()];
            let df: f64 = (0..3).map(|i| a[i] * gamma[i]).sum();
            t_s.push(t);
            phase.push(Some(pll.step(df) + noise.sample(&mut rng)));
            accel.push(a);
        }
        (t_s, phase, accel)
    }

    /// A joint fit with no variance on an axis (the sandwich of a singular
    /// fit: 0 from a zero-filled inverse, NaN from this one) leaves that axis
    /// unobservable, saying why, instead of reporting σ = 0.
    #[test]
    fn an_axis_the_joint_fit_has_no_variance_for_is_unobservable_not_sigma_zero() {
        let (t_s, phase, accel) = session();
        let series = EpochSeries::without_offset(0.025, &t_s, &phase, &accel);
        let settings = EstimateSettings::default();
        let c = calibrate(&series, &settings).unwrap();
        assert!(c.observable.iter().all(|&o| o), "{:?}", c.axes);
        let spec =
            JointSpec { natural_frequency: true, damping: false, offset_max_abs_s: Some(0.05), loop_tolerance: None };
        let fit = joint_fit(&series, &settings, spec).unwrap();
        for no_variance in [0.0, f64::NAN] {
            let mut fit = fit.clone();
            for j in 0..3 {
                fit.gamma_covariance_hz_per_mps2_sq[1][j] = no_variance;
                fit.gamma_covariance_hz_per_mps2_sq[j][1] = no_variance;
            }
            let mut c = c.clone();
            c.include_nuisance(&fit);
            assert_eq!((c.observable[1], c.gamma_hz_per_mps2[1], c.sigma_hz_per_mps2[1]), (false, None, None));
            assert!(c.covariance_hz_per_mps2_sq[0][1].is_none() && c.covariance_hz_per_mps2_sq[1][1].is_none());
            assert!(c.axes[1].text.starts_with("y: unobservable — with the loop and the IMU time offset fitted"));
            for i in [0, 2] {
                assert!(c.observable[i] && c.sigma_hz_per_mps2[i].is_some_and(|s| s > 0.0), "{:?}", c.axes[i]);
            }
        }
        // Untouched, every σ is positive.
        let mut c = c.clone();
        c.include_nuisance(&fit);
        assert!(c.sigma_hz_per_mps2.iter().all(|s| s.is_some_and(|s| s > 0.0)));
    }
}
