//! Text and JSON presentation of a calibration.

use anyhow::Result;
use gsens_calib::Calibration;
use gsens_core::pll::LoopSpec;
use gsens_core::units::hz_per_mps2_to_ppb_per_g;
use gsens_session::PreparedSession;
use std::fmt::Write as _;
use std::path::Path;

const AXES: [&str; 3] = ["x", "y", "z"];

fn loop_text(l: &LoopSpec) -> String {
    let fn_hz = l.wn_rad_per_s().map(|w| w / std::f64::consts::TAU);
    let nat = fn_hz.map(|f| format!(", ωn/2π {f:.3} Hz")).unwrap_or_default();
    match *l {
        LoopSpec::SecondOrder { bn_hz, zeta } => format!("2nd order, Bn {bn_hz} Hz, ζ {zeta:.3}{nat}"),
        LoopSpec::ThirdOrder { bn_hz, a3, b3 } => format!("3rd order, Bn {bn_hz} Hz, a3 {a3}, b3 {b3}{nat}"),
        LoopSpec::Coefficients(c) => {
            format!("filter c0 {} /s, c1 {} /s², c2 {} /s³{nat}", c.c0_per_s, c.c1_per_s2, c.c2_per_s3)
        }
    }
}

/// The human-readable report of `estimate` and `demo`.
pub fn text(session: &PreparedSession, c: &Calibration, truth: Option<[f64; 3]>) -> String {
    let mut s = String::new();
    let s_ = &mut s;
    let dur = c.epochs_total as f64 * c.log_interval_s;
    let loop_t = c.settings.loop_interval_s.unwrap_or(c.log_interval_s);
    let _ = writeln!(
        s_,
        "log: {} epochs at {:.3} Hz ({dur:.1} s), {} used after a {} s warm-up",
        c.epochs_total,
        1.0 / c.log_interval_s,
        c.epochs_used,
        c.settings.warmup_s
    );
    let _ = writeln!(
        s_,
        "loop model: {}, updated every {} s ({} per log epoch, logged: {:?})",
        loop_text(&c.settings.loop_spec),
        loop_t,
        c.model_substeps,
        c.settings.logged_phase
    );
    let used: Vec<_> = session.channels.iter().filter(|ch| ch.used).collect();
    let _ = writeln!(
        s_,
        "channels: {} used of {} ({}, {:?} weights)",
        used.len(),
        session.channels.len(),
        session.selection.max_channels.map(|n| format!("top {n} by mean C/N0")).unwrap_or_else(|| "all".into()),
        session.selection.weighting
    );
    for ch in &session.channels {
        let _ = writeln!(
            s_,
            "  ch {:>3}  PRN {:>3}  C/N0 {:>5.1} dB-Hz  {:>7} epochs  {}{}",
            ch.channel,
            ch.prn,
            ch.mean_cn0_dbhz,
            ch.epochs,
            ch.reason,
            ch.screening.brief().map(|b| format!("; {b}")).unwrap_or_default()
        );
    }
    let _ = writeln!(s_, "method: {:?}", c.settings.method);
    if let Some(h) = &c.huber {
        let _ = writeln!(
            s_,
            "robust: Huber, c = 1.345·σ̂ = {:.4} rad, {} of {} epochs down-weighted, {} iterations{}",
            h.threshold_rad,
            h.epochs_downweighted,
            h.epochs,
            h.iterations,
            if h.converged { "" } else { " (not converged)" }
        );
    }
    match c.imu_time_offset_sigma_s {
        Some(sd) => {
            let _ = writeln!(
                s_,
                "IMU time offset (IMU stamp − true time): {:+.4} s ± {:.4} s, estimated jointly with Γ and applied",
                c.imu_time_offset_s, sd
            );
        }
        None => {
            let _ = writeln!(s_, "IMU time offset: {:+.4} s, assumed", c.imu_time_offset_s);
        }
    }
    if let Some(id) = &c.loop_identification {
        let _ = writeln!(
            s_,
            "loop identification: ωn/2π = {:.4} ± {:.4} Hz{} (assumed {:.4} Hz{}), likelihood ratio {:.1}: {}",
            id.natural_frequency_hz,
            id.sigma_natural_frequency_hz,
            id.zeta.map(|z| format!(", ζ {z:.3}")).unwrap_or_default(),
            id.assumed_natural_frequency_hz,
            id.assumed_zeta.map(|z| format!(", ζ {z:.3}")).unwrap_or_default(),
            id.likelihood_ratio,
            if id.assumed_loop_rejected {
                "the data reject the assumed loop; the identified one is used"
            } else {
                "the data agree with the assumed loop; it is kept"
            }
        );
        let s = id.gamma_sensitivity_per_percent_wn;
        let _ = writeln!(
            s_,
            "  sensitivity of Γ̂ to the loop: {:+.2} %, {:+.2} %, {:+.2} % (x, y, z) per +1 % of ωn",
            100.0 * s[0],
            100.0 * s[1],
            100.0 * s[2]
        );
    }
    let head = if truth.is_some() { "      truth       error" } else { "" };
    let _ = writeln!(s_, "\n     Γ̂ [Hz/(m/s²)]      1σ        Γ̂ [ppb/g]     1σ{head}");
    let fn_hz = c.settings.loop_spec.wn_rad_per_s().map(|w| w / std::f64::consts::TAU).unwrap_or(0.9);
    for i in 0..3 {
        match (c.gamma_hz_per_mps2[i], c.sigma_hz_per_mps2[i]) {
            (Some(g), Some(sg)) => {
                let ppb = hz_per_mps2_to_ppb_per_g(g, c.settings.carrier_hz);
                let sppb = hz_per_mps2_to_ppb_per_g(sg, c.settings.carrier_hz);
                let _ = write!(s_, "  {}  {g:+.5}  ±{sg:.5}     {ppb:+.4}  ±{sppb:.4}", AXES[i]);
                if let Some(t) = truth {
                    let _ = write!(s_, "     {:+.5}  {:+.5} ({:+.2}σ)", t[i], g - t[i], (g - t[i]) / sg);
                }
                let _ = writeln!(s_);
            }
            _ => {
                let _ = write!(
                    s_,
                    "  {}  unobservable: too little excitation (RMS {:.3} rad per Hz/(m/s²)) — shake harder along {} or closer to {:.2} Hz",
                    AXES[i], c.excitation_rms[i], AXES[i], fn_hz
                );
                if let Some(t) = truth {
                    let _ = write!(s_, "  [truth {:+.5}]", t[i]);
                }
                let _ = writeln!(s_);
            }
        }
    }
    if let Some(t) = truth {
        let norm = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        let err: f64 = (0..3).filter_map(|i| c.gamma_hz_per_mps2[i].map(|g| (g - t[i]).powi(2))).sum::<f64>().sqrt();
        let _ = writeln!(s_, "  |Γ̂ − Γ| = {err:.5} Hz/(m/s²) = {:.2} % of |Γ|", 100.0 * err / norm);
    }
    let _ = writeln!(s_, "\nshaking:");
    for v in &c.axes {
        let _ = writeln!(s_, "  {}", v.text);
    }
    let peak = c.predicted_peak_phase_err_rad;
    let lin = c.discriminator_linear_range_rad;
    if peak > lin {
        let _ = writeln!(
            s_,
            "  warning: the predicted g-induced phase error reaches {peak:.2} rad, beyond the discriminator's linear \
             range ({lin:.2} rad): shake more gently or the loss of discriminator gain biases Γ̂ low"
        );
    } else {
        let _ = writeln!(
            s_,
            "  predicted g-induced phase error peaks at {peak:.3} rad, inside the discriminator's linear range ({lin:.2} rad)"
        );
    }
    let _ = writeln!(
        s_,
        "\nphase error RMS: {:.4} rad before compensation, {:.4} rad after (g-induced part {:.4} rad)",
        c.rms_before_rad, c.rms_after_rad, c.rms_g_induced_rad
    );
    let _ = writeln!(
        s_,
        "information matrix condition number: {}",
        c.condition_number.map(|x| format!("{x:.1}")).unwrap_or_else(|| "∞ (singular)".into())
    );
    if c.crlb_hz_per_mps2.iter().any(Option::is_some) {
        let b = c.crlb_hz_per_mps2.map(|v| v.map_or("—".to_owned(), |v| format!("{v:.5}")));
        let _ = writeln!(
            s_,
            "Cramér–Rao bound [Hz/(m/s²)]: x {}, y {}, z {} (residual noise: AR({}) model)",
            b[0], b[1], b[2], c.noise_ar_order
        );
    }
    s
}

/// Writes the calibration, the channels and the inputs as JSON.
pub fn write_json(
    path: &Path,
    session: &PreparedSession,
    c: &Calibration,
    truth: Option<[f64; 3]>,
    inputs: &[(&str, &Path)],
) -> Result<()> {
    let mut v = serde_json::to_value(c)?;
    let obj = v.as_object_mut().expect("a struct serializes to an object");
    obj.insert("channels".into(), serde_json::to_value(&session.channels)?);
    obj.insert("selection".into(), serde_json::to_value(&session.selection)?);
    let inputs: serde_json::Map<String, serde_json::Value> =
        inputs.iter().map(|(k, p)| (k.to_string(), p.display().to_string().into())).collect();
    obj.insert("inputs".into(), inputs.into());
    if let Some(t) = truth {
        obj.insert("truth_gamma_hz_per_mps2".into(), serde_json::to_value(t)?);
    }
    std::fs::write(path, serde_json::to_string_pretty(&v)? + "\n")?;
    Ok(())
}
