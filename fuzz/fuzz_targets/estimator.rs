//! The estimator's numeric path, structure-aware: a session of a few
//! channels (a shaken IMU and phase errors of a loop's response, both with
//! arbitrary noise, non-finite values included) and every option of the command line
//! (`gsens_calib::CalibrationOptions`) at a default, a sane, a raw or a
//! special value, through the whole pipeline. It must end (libFuzzer's
//! `-timeout`) with an error or a result, never a panic, and a result never
//! reports a non-finite number as Γ̂ or σ.
#![no_main]
use arbitrary::Arbitrary;
use gsens_calib::{CalibrationOptions, MethodName, TimeOffsetOption, calibrate_logs};
use gsens_core::LoggedPhase;
use gsens_io::{ImuSeries, TrackingLog, TrackingRow};
use libfuzzer_sys::fuzz_target;

/// A number as a user might give it.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Value {
    Default,
    /// A few hundredths to a few hundreds.
    Sane(u16),
    Raw(f64),
    Special(u8),
}

impl Value {
    fn or(self, default: f64) -> f64 {
        match self {
            Value::Default => default,
            Value::Sane(v) => f64::from(v) / 100.0,
            Value::Raw(v) => v,
            Value::Special(k) => {
                [f64::NAN, f64::INFINITY, -f64::INFINITY, 0.0, -0.0, -1.0, 1e300, 1e-300, f64::MIN_POSITIVE]
                    [k as usize % 9]
            }
        }
    }

    fn opt(self, default: Option<f64>) -> Option<f64> {
        match self {
            Value::Default => default,
            v => Some(v.or(0.0)),
        }
    }
}

#[derive(Arbitrary, Debug)]
struct Options {
    carrier_hz: Value,
    order: Option<u8>,
    bn_hz: Value,
    zeta: Value,
    a3: Value,
    b3: Value,
    loop_interval_s: Value,
    logged_phase: Option<bool>,
    loop_implementation: Option<u8>,
    method: u8,
    gain_k: Value,
    lambda: Value,
    warmup_s: Value,
    imu_scale_sigma_ppm: Value,
    imu_misalignment_sigma_mrad: Value,
    highpass_hz: Value,
    huber: bool,
    channels: u8,
    min_cn0_dbhz: Value,
    elevation_mask_deg: Value,
    cn0_weights: bool,
    screening: bool,
    cn0_drop_db: Value,
    max_abs_phase_rad: Value,
    atan2_discriminator: bool,
    loop_tolerance: Value,
    time_offset: Option<Value>,
    time_offset_max_s: Value,
    loop_check: bool,
    identify_damping: bool,
    imu_despike: bool,
}

impl Options {
    fn calibration_options(&self) -> CalibrationOptions {
        let d = CalibrationOptions::default();
        CalibrationOptions {
            carrier_hz: self.carrier_hz.or(d.carrier_hz),
            method: [MethodName::Batch, MethodName::Gls, MethodName::Rls, MethodName::Gradient]
                [self.method as usize % 4],
            measurement: d.measurement,
            receiver_loop: gsens_calib::LoopOptions {
                order: self.order,
                bn_hz: self.bn_hz.opt(d.receiver_loop.bn_hz),
                zeta: self.zeta.or(d.receiver_loop.zeta),
                a3: self.a3.or(d.receiver_loop.a3),
                b3: self.b3.or(d.receiver_loop.b3),
                loop_interval_s: self.loop_interval_s.opt(d.receiver_loop.loop_interval_s),
                logged_phase: self.logged_phase.map(|l| if l { LoggedPhase::Last } else { LoggedPhase::Mean }),
                loop_implementation: self.loop_implementation.map(|k| {
                    use gsens_core::LoopImplementation::{GnssSdr, Kaplan, PocketSdr};
                    [Kaplan, GnssSdr, PocketSdr][usize::from(k) % 3]
                }),
                discriminator: if self.atan2_discriminator {
                    gsens_core::Discriminator::Atan2
                } else {
                    gsens_core::Discriminator::AtanCostas
                },
            },
            estimator: gsens_calib::EstimatorOptions {
                gain_k: self.gain_k.or(d.estimator.gain_k),
                lambda: self.lambda.or(d.estimator.lambda),
                warmup_s: self.warmup_s.or(d.estimator.warmup_s),
                imu_scale_sigma_ppm: self.imu_scale_sigma_ppm.or(d.estimator.imu_scale_sigma_ppm),
                imu_misalignment_sigma_mrad: self
                    .imu_misalignment_sigma_mrad
                    .or(d.estimator.imu_misalignment_sigma_mrad),
                highpass_hz: self.highpass_hz.or(d.estimator.highpass_hz),
                robust: if self.huber { gsens_calib::Robust::Huber } else { gsens_calib::Robust::None },
            },
            selection: gsens_calib::SelectionOptions {
                channels: usize::from(self.channels % 16),
                min_cn0_dbhz: self.min_cn0_dbhz.opt(d.selection.min_cn0_dbhz),
                elevation_mask_deg: self.elevation_mask_deg.opt(d.selection.elevation_mask_deg),
                weights: if self.cn0_weights { gsens_session::Weighting::Cn0 } else { gsens_session::Weighting::Equal },
                screening: self.screening,
                cn0_drop_db: self.cn0_drop_db.or(d.selection.cn0_drop_db),
                max_abs_phase_rad: self.max_abs_phase_rad.opt(d.selection.max_abs_phase_rad),
            },
            systematic: gsens_calib::SystematicOptions {
                loop_tolerance: self.loop_tolerance.opt(d.systematic.loop_tolerance),
                time_offset: match self.time_offset {
                    None => d.systematic.time_offset,
                    Some(Value::Default) => TimeOffsetOption::None,
                    Some(v) => TimeOffsetOption::Seconds(v.or(0.0)),
                },
                time_offset_max_s: self.time_offset_max_s.or(d.systematic.time_offset_max_s),
                loop_check: self.loop_check,
                identify_damping: self.identify_damping,
                imu_despike: self.imu_despike,
            },
        }
    }
}

#[derive(Arbitrary, Debug)]
struct Session {
    /// Epochs (at most 1200: 30 s at 40 Hz; longer sessions only cost time here).
    epochs: u16,
    channels: u8,
    /// Log interval: one of the usual ones.
    interval: u8,
    /// Shaking per axis: amplitude [m/s²] and frequency [Hz], in hundredths.
    shake: [(u16, u16); 3],
    gamma_milli_hz_per_mps2: [i16; 3],
    /// Phase noise samples [rad], cycled; may hold any f64.
    noise: Vec<f64>,
    /// IMU noise samples [m/s²], cycled over the samples and axes; may hold any f64.
    imu_noise: Vec<f64>,
    /// IMU samples per log epoch (1–4) and a clock offset [ms].
    imu_per_epoch: u8,
    imu_offset_ms: i16,
    options: Options,
}

fuzz_target!(|s: Session| {
    let n = usize::from(s.epochs % 1201);
    let t = [0.005, 0.01, 0.02, 0.025, 0.05][usize::from(s.interval % 5)];
    let channels = u32::from(s.channels % 8) + 1;
    let per = usize::from(s.imu_per_epoch % 4) + 1;
    let gamma = s.gamma_milli_hz_per_mps2.map(|g| f64::from(g) * 1e-3);
    let accel = |tk: f64| -> [f64; 3] {
        let mut a = [0.0, 0.0, 9.81];
        for (i, &(amp, f)) in s.shake.iter().enumerate() {
            a[i] += f64::from(amp) / 100.0 * (std::f64::consts::TAU * f64::from(f) / 100.0 * tk).sin();
        }
        a
    };
    let dt = t / per as f64;
    let offset_s = f64::from(s.imu_offset_ms) * 1e-3;
    let imu_n = n * per + 2 * per;
    let imu = ImuSeries {
        t_s: (0..imu_n).map(|j| -t + j as f64 * dt + offset_s).collect(),
        accel_mps2: (0..imu_n)
            .map(|j| {
                let mut a = accel(-t + j as f64 * dt);
                if !s.imu_noise.is_empty() {
                    for (i, v) in a.iter_mut().enumerate() {
                        *v += s.imu_noise[(3 * j + i) % s.imu_noise.len()];
                    }
                }
                a
            })
            .collect(),
    };
    let mut rows = Vec::with_capacity(n * channels as usize);
    for k in 0..n {
        let tk = k as f64 * t;
        let a = accel(tk);
        // A crude stand-in for the loop's response: the g-induced Δf scaled, plus noise.
        let df = a[0] * gamma[0] + a[1] * gamma[1] + (a[2] - 9.81) * gamma[2];
        for c in 0..channels {
            let j = k * channels as usize + c as usize;
            let noise = if s.noise.is_empty() { 0.0 } else { s.noise[j % s.noise.len()] };
            rows.push(TrackingRow {
                t_s: tk,
                channel: c,
                prn: c + 1,
                cn0_dbhz: 40.0 + f64::from(c),
                elev_deg: Some(30.0),
                phase_err_rad: 0.05 * df + noise,
            });
        }
    }
    let Ok(log) = TrackingLog::from_rows("fuzz", &rows) else { return };
    let Ok(settings) = s.options.calibration_options().pipeline_settings() else { return };
    let Ok(outcome) = calibrate_logs(&log, &imu, "imu", &settings) else { return };
    let c = &outcome.calibration;
    for i in 0..3 {
        if let Some(g) = c.gamma_hz_per_mps2[i] {
            assert!(g.is_finite(), "Γ̂[{i}] = {g}");
        }
        if let Some(sd) = c.sigma_hz_per_mps2[i] {
            assert!(sd.is_finite() && sd >= 0.0, "σ[{i}] = {sd}");
        }
    }
    // Every output serializes the one document; it must too.
    let _ = serde_json::to_string(&outcome.document(None)).expect("the result document serializes");
});
