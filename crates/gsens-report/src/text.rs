//! The calibration as text: what the CLI prints, rendered from the result document.

use crate::AXES;
use gsens_calib::{LoopResolution, Measurement, ResultDocument};
use gsens_core::units::Decimal;
use gsens_core::units::hz_per_mps2_to_ppb_per_g;
use gsens_core::{LoggedPhase, LoopModel};
use gsens_session::Weighting;
use std::fmt::Write as _;

/// The human-readable report of a calibration (what `gsens estimate` and
/// `gsens demo` print): the warnings first, then the log, the loop, the
/// channels, Γ̂ with its uncertainty (and the truth when known), the shaking
/// verdicts and the compensation figures.
pub fn render_text(doc: &ResultDocument) -> String {
    let mut s = String::new();
    warnings(&mut s, doc);
    log_and_loop(&mut s, doc);
    channels(&mut s, doc);
    method(&mut s, doc);
    loop_check(&mut s, doc);
    if let Some(r) = &doc.loop_response {
        let _ = writeln!(s, "{}", r.summary());
    }
    estimate_table(&mut s, doc);
    nco_estimates(&mut s, doc);
    shaking(&mut s, doc);
    compensation(&mut s, doc);
    let _ = writeln!(s, "\n{}", verdict_line(doc));
    s
}

/// Each warning on its line, and for an untrustworthy estimate the verdict
/// ahead of everything else.
fn warnings(s: &mut String, doc: &ResultDocument) {
    for w in &doc.warnings {
        let _ = writeln!(s, "warning [{}]: {}", w.code, w.message);
    }
    if !doc.trustworthy {
        let _ = writeln!(s, "{}\n", verdict_line(doc));
    }
}

/// The log (epochs, rate, duration, warm-up) and the loop model with its
/// peak and the shaking period it implies.
fn log_and_loop(s: &mut String, doc: &ResultDocument) {
    let c = &doc.calibration;
    let dur = c.epochs_total as f64 * c.log_interval_s;
    let _ = writeln!(
        s,
        "log: {} epochs at {:.3} Hz ({dur:.1} s), {} used after a {} s warm-up",
        c.epochs_total,
        1.0 / c.log_interval_s,
        c.epochs_used,
        c.settings.warmup_s
    );
    if let Some(id) = &doc.identified_loop {
        identified_loop(s, id, &c.loop_used);
    } else {
        let _ = writeln!(
            s,
            "loop model: {} ({} per log epoch, logged: {})",
            c.loop_used,
            c.model_substeps,
            match c.settings.logged_phase {
                LoggedPhase::Last => "the last discriminator output",
                LoggedPhase::Mean => "the mean of the discriminator outputs",
            }
        );
    }
    if let (Some(p), Some([lo, hi])) = (doc.loop_summary.peak_hz, doc.loop_summary.half_power_band_hz) {
        let _ = writeln!(
            s,
            "  |L| peaks at {p:.3} Hz: shake with a period of about {:.2} s (half-power band {lo:.2}–{hi:.2} Hz)",
            1.0 / p
        );
    }
}

/// The receiver's loop as the session identified it: order, update
/// interval and bandwidth with its σ (or the bound), how far H is from 1 at
/// the shaking, and the estimate H = 1 would give. A receiver's own loop
/// (`loop_used` GNSS-SDR's or PocketSDR's, from its configuration) is named:
/// its shape was stated, only its bandwidth fitted.
pub(crate) fn identified_loop(s: &mut String, id: &gsens_calib::LoopIdentification, loop_used: &LoopModel) {
    let l = &id.identified;
    let order =
        if l.order_resolved { format!("order {}", l.order) } else { format!("order {} (not resolved)", l.order) };
    let bn = match l.resolution {
        LoopResolution::Resolved => format!("Bn {:.3} Hz ± {:.1} %", l.bn_hz, 100.0 * l.sigma_ln_bn),
        LoopResolution::Wide => format!("Bn ≥ {:.1} Hz (wide: H ≈ 1 in the shaking's band)", l.bn_hz),
        _ => format!("Bn ≤ {:.2} Hz (at the narrow end of the search)", l.bn_hz),
    };
    let record = match id.record {
        gsens_calib::ObservationRecord::Doppler => "Doppler",
        _ => "carrier phase differenced",
    };
    let receiver = match loop_used {
        LoopModel::GnssSdr(_) => Some("GNSS-SDR"),
        LoopModel::PocketSdr(_) => Some("PocketSDR"),
        _ => None,
    };
    let interval_s = l.loop_interval_s;
    let _ = match receiver {
        // Several shapes with a receiver's among them: the forms of a loop stated in words.
        Some(r) if l.shapes.len() > 1 => writeln!(
            s,
            "receiver loop: the stated loop as {r} implements it (the best fit of {} receivers' forms of it), its \
             bandwidth fitted to the {record}: {order}, updated every {interval_s} s, {bn}",
            l.shapes.len()
        ),
        Some(r) => writeln!(
            s,
            "receiver loop: {r}'s, modelled exactly, its bandwidth fitted to the {record}: {order}, updated every \
             {interval_s} s, {bn}"
        ),
        None => writeln!(s, "receiver loop identified from the {record}: {order}, updated every {interval_s} s, {bn}"),
    };
    if let [first, .., last] = l.alike_intervals_s.as_slice() {
        let _ = writeln!(s, "  update intervals {first}–{last} s fit alike: σ covers the Γ̂ of each");
    }
    if let Some(e) = id.h_unity_error {
        let unity = id.h_unity_estimate.as_ref().map(|u| {
            let g: Vec<String> =
                u.gamma_hz_per_mps2.iter().map(|g| g.map_or("—".into(), |g| format!("{g:+.5}"))).collect();
            format!("; with H = 1 Γ̂ would be [{}]", g.join(", "))
        });
        let judged = match l.resolution {
            LoopResolution::Wide => "the loop is wide: H → 1 as Bn grows past the bound",
            _ if e > 0.01 => "H = 1 does not hold: the loop is narrow for this shaking",
            _ => "H ≈ 1",
        };
        let _ = writeln!(
            s,
            "  |1 − |H|| up to {:.1} % at the shaking frequencies: {judged}{}",
            100.0 * e,
            unity.unwrap_or_default()
        );
    }
}

/// The tracks of a carrier phase and Doppler log: how many gave rows.
fn observation_tracks(s: &mut String, doc: &ResultDocument) {
    let Some(source) = &doc.source else { return };
    let rows = |t: &serde_json::Value| t.get("rows").and_then(serde_json::Value::as_u64).unwrap_or(0);
    let used = source.tracks.iter().filter(|t| rows(t) > 0).count();
    let _ =
        writeln!(s, "tracks: {used} of {} with rows ({}), all averaged on L1", source.tracks.len(), source.receiver);
}

/// The channels: how many used and how, the signals when other than GPS
/// L1 C/A, and every track's line.
fn channels(s: &mut String, doc: &ResultDocument) {
    if doc.identified_loop.is_some() {
        observation_tracks(s, doc);
        return;
    }
    let used: Vec<_> = doc.channels.iter().filter(|ch| ch.used).collect();
    let _ = writeln!(
        s,
        "channels: {} used of {} ({}, {} weights)",
        used.len(),
        doc.channels.len(),
        doc.selection.max_channels.map(|n| format!("top {n} by mean C/N0")).unwrap_or_else(|| "all".into()),
        match doc.selection.weighting {
            Weighting::Equal => "equal",
            Weighting::Cn0 => "C/N0",
        }
    );
    // Other carriers than GPS L1 C/A: each signal with its scaling to L1, and each channel's signal.
    // (A log without carrier columns is GPS L1, unnamed: one signal at L1's carrier.)
    let l1 = gsens_core::units::GPS_L1_HZ;
    let mixed = doc.signals.len() > 1
        || doc.signals.iter().any(|g| g.carrier_hz != l1)
        || doc.channels.iter().any(|c| c.carrier_hz != l1);
    if mixed {
        let list: Vec<String> = doc
            .signals
            .iter()
            .map(|g| {
                format!(
                    "{} {:.4} MHz ×{:.5}, {} of {} tracks",
                    g.signal,
                    g.carrier_hz / 1e6,
                    g.scale_to_l1,
                    g.tracks_used,
                    g.tracks
                )
            })
            .collect();
        let _ = writeln!(s, "signals (phase × f_L1/f_c, averaged on L1): {}", list.join("; "));
    }
    for ch in &doc.channels {
        let signal = if mixed { format!("  {:<6}", ch.signal) } else { String::new() };
        let _ = writeln!(
            s,
            "  ch {:>3}  PRN {:>3}{signal}  C/N0 {:>5.1} dB-Hz  {:>7} epochs  {}{}",
            ch.channel,
            ch.prn,
            ch.mean_cn0_dbhz,
            ch.epochs,
            ch.reason,
            ch.screening.brief().map(|b| format!("; {b}")).unwrap_or_default()
        );
    }
}

/// The estimator, its robust weighting if any, and the IMU time offset.
fn method(s: &mut String, doc: &ResultDocument) {
    let c = &doc.calibration;
    if doc.measurement != Measurement::TrackingError {
        let what = if doc.measurement == Measurement::InputPhase { "loop-free" } else { "NCO frequency through H" };
        let _ = writeln!(s, "method: generalized least squares, an AR noise model per segment ({what})");
        let how = if c.imu_time_offset_estimated { "searched" } else { "given" };
        // A receiver's measurement latency delays its rows as an IMU offset
        // of the opposite sign would: the fitted offset is their sum.
        let with_latency =
            if doc.identified_loop.is_some() { " (with the receiver's measurement latency)" } else { "" };
        let _ = writeln!(s, "IMU time offset{with_latency}: {:+.4} s, {how}", c.imu_time_offset_s);
        return;
    }
    let _ = writeln!(s, "method: {}", c.settings.method);
    if let Some(h) = &c.huber {
        let _ = writeln!(
            s,
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
                s,
                "IMU time offset (IMU stamp − true time): {:+.4} s ± {:.4} s, estimated jointly with Γ and applied",
                c.imu_time_offset_s, sd
            );
        }
        None => {
            let _ = writeln!(s, "IMU time offset: {:+.4} s, assumed", c.imu_time_offset_s);
        }
    }
}

/// The joint fit's check of the stated loop, and what not knowing the loop
/// and the offset costs.
fn loop_check(s: &mut String, doc: &ResultDocument) {
    let c = &doc.calibration;
    let Some(j) = &c.joint_fit else { return };
    let (Some(f), Some(sf), Some(f0), Some(z)) =
        (j.natural_frequency_hz, j.sigma_natural_frequency_hz, j.stated_natural_frequency_hz, j.loop_test_z)
    else {
        return;
    };
    let _ = writeln!(
        s,
        "loop check: ωn/2π fits at {f:.4} ± {sf:.4} Hz{} (stated {f0:.4} Hz{}{}), z = {z:+.2}: {}",
        j.zeta.map(|z| format!(", ζ {:.3} ± {:.3}", z[0], z[1])).unwrap_or_default(),
        j.stated_zeta.map(|z| format!(", ζ {z:.3}")).unwrap_or_default(),
        match j.loop_tolerance {
            Some(t) if t > 0.0 => format!(" ± {} %", percent(t)),
            Some(_) => ", exact".to_string(),
            None => String::new(),
        },
        if j.stated_loop_rejected {
            format!("the data REJECT the stated loop (|z| > {:.2})", j.loop_test_threshold_z)
        } else if j.loop_tolerance.is_none() {
            "not tested (no tolerance: only the loop's shape is taken as known)".to_string()
        } else {
            format!(
                "consistent with the stated loop (|z| ≤ {:.2}, {} % false alarms)",
                j.loop_test_threshold_z,
                Decimal(100.0 * j.loop_test_false_alarm)
            )
        }
    );
    if let Some(forms) = &j.loop_forms {
        loop_forms(s, forms);
    }
    let inflation = j.variance_inflation.map(f64::sqrt);
    let _ = writeln!(
        s,
        "  {}{}widens σ by ×{:.2}, ×{:.2}, ×{:.2} (x, y, z){}",
        if doc.measurement == Measurement::TrackingError { "" } else { "(the cross-check through the loop model) " },
        loop_used_phrase(j),
        inflation[0],
        inflation[1],
        inflation[2],
        j.correlation_loop_offset
            .filter(|r| r.abs() > 0.9)
            .map(|r| format!(
                "; loop and offset are confounded (correlation {r:+.2}): to separate them, {}",
                gsens_calib::two_rate_advice(&c.loop_used)
            ))
            .unwrap_or_default()
    );
}

/// Which receiver's form of a loop stated in words the data fit, and what
/// σ covers of the others.
pub(crate) fn loop_forms(s: &mut String, forms: &gsens_calib::LoopForms) {
    let chosen = forms.chosen_form();
    let others: Vec<String> = forms
        .forms
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != forms.chosen)
        .map(|(_, f)| format!("{} by {:.1}", f.form, f.delta_m2lnl))
        .collect();
    let alike: Vec<&str> = forms.alike().map(|f| f.form.as_str()).collect();
    let _ = writeln!(
        s,
        "  the stated loop's form: the data fit {} best (−2 ln L higher: {}); {}",
        chosen.form,
        others.join("; "),
        if alike.is_empty() {
            "σ takes in the others' Γ̂ by the data's odds for them".to_string()
        } else {
            format!(
                "σ reaches the Γ̂ of {}, which fit alike (within {})",
                alike.join(" and "),
                Decimal(forms.alike_within)
            )
        },
    );
    let added = forms.added_variance_hz_per_mps2_sq.map(f64::sqrt);
    let _ = writeln!(
        s,
        "    adding ±{:.5}, ±{:.5}, ±{:.5} Hz/(m/s²) in quadrature (x, y, z); name the implementation to spare it",
        added[0], added[1], added[2]
    );
}

/// Which loop Γ̂ is under and what is not known, leading the joint fit's
/// second line.
fn loop_used_phrase(j: &gsens_calib::JointFit) -> String {
    let used = match (j.used_natural_frequency_hz, j.sigma_used_natural_frequency_hz) {
        (Some(f), Some(s)) if s > 0.0 => format!("ωn/2π {f:.4} ± {s:.4} Hz"),
        (Some(f), _) => format!("ωn/2π {f:.4} Hz"),
        _ => String::new(),
    };
    match (j.fitted_loop_used, j.loop_tolerance, j.imu_time_offset_s.is_some()) {
        (true, None, true) => format!("Γ̂ under the fitted loop ({used}); not knowing the loop and the offset "),
        (true, None, false) => format!("Γ̂ under the fitted loop ({used}); not knowing the loop "),
        (true, Some(_), true) if !j.stated_loop_rejected => format!(
            "Γ̂ under the fit and the stated loop's tolerance combined ({used}); not knowing the loop and the \
             offset exactly "
        ),
        (true, Some(_), false) if !j.stated_loop_rejected => {
            format!("Γ̂ under the fit and the stated loop's tolerance combined ({used}); not knowing the loop exactly ")
        }
        (true, _, true) => format!("Γ̂ under the fitted loop ({used}); not knowing the loop and the offset "),
        (true, _, false) => format!("Γ̂ under the fitted loop ({used}); not knowing the loop "),
        (false, _, true) => "Γ̂ under the stated loop, taken as exact; not knowing the offset ".to_string(),
        (false, _, false) => "Γ̂ under the stated loop, taken as exact; ".to_string(),
    }
}

/// Γ̂ per axis in Hz/(m/s²) and ppb/g with its 1σ (beside the truth when
/// known), or why the axis is unobservable; then |Γ̂ − Γ| against the truth.
fn estimate_table(s: &mut String, doc: &ResultDocument) {
    let c = &doc.calibration;
    let truth = doc.truth_gamma_hz_per_mps2;
    let head = if truth.is_some() { "      truth       error" } else { "" };
    if doc.measurement != Measurement::TrackingError {
        let _ = write!(s, "\nestimate from {}:", doc.measurement.description());
    }
    let _ = writeln!(s, "\n     Γ̂ [Hz/(m/s²)]      1σ        Γ̂ [ppb/g]     1σ{head}");
    for i in 0..3 {
        match (c.gamma_hz_per_mps2[i], c.sigma_hz_per_mps2[i]) {
            (Some(g), Some(sg)) => {
                let ppb = hz_per_mps2_to_ppb_per_g(g, c.settings.carrier_hz);
                let sppb = hz_per_mps2_to_ppb_per_g(sg, c.settings.carrier_hz);
                let _ = write!(s, "  {}  {g:+.5}  ±{sg:.5}     {ppb:+.4}  ±{sppb:.4}", AXES[i]);
                if let Some(t) = truth {
                    let _ = write!(s, "     {:+.5}  {:+.5} ({:+.2}σ)", t[i], g - t[i], (g - t[i]) / sg);
                }
                let _ = writeln!(s);
            }
            _ => {
                // The verdict's reason ("x: too little excitation — …"), without its axis.
                let text = &c.axes[i].text;
                let reason = text.split_once(": ").map_or(text.as_str(), |(_, r)| r);
                let _ = write!(
                    s,
                    "  {}  unobservable: {reason} (excitation RMS {:.3} rad per Hz/(m/s²))",
                    AXES[i], c.excitation_rms[i]
                );
                if let Some(t) = truth {
                    let _ = write!(s, "  [truth {:+.5}]", t[i]);
                }
                let _ = writeln!(s);
            }
        }
    }
    // |Γ̂ − Γ| over the axes with an estimate (none: no number to show).
    if let Some(t) = truth {
        let axes: Vec<usize> = (0..3).filter(|&i| c.gamma_hz_per_mps2[i].is_some()).collect();
        let err = axes.iter().map(|&i| (c.gamma_hz_per_mps2[i].unwrap_or(0.0) - t[i]).powi(2)).sum::<f64>().sqrt();
        let norm = axes.iter().map(|&i| t[i] * t[i]).sum::<f64>().sqrt();
        let over = if axes.len() == 3 {
            String::new()
        } else {
            format!(" (over {})", axes.iter().map(|&i| AXES[i]).collect::<Vec<_>>().join(", "))
        };
        if !axes.is_empty() && norm > 0.0 {
            let _ = writeln!(s, "  |Γ̂ − Γ|{over} = {err:.5} Hz/(m/s²) = {:.2} % of |Γ|{over}", 100.0 * err / norm);
        }
    }
}

/// The estimates from the NCO's record, for logs that hold it: the
/// loop-free one from its phase, then the one from its frequency.
fn nco_estimates(s: &mut String, doc: &ResultDocument) {
    for check in [&doc.loop_free, &doc.nco_frequency].into_iter().flatten() {
        nco_estimate(s, doc, check);
    }
}

/// One estimate from the NCO's record: what went into it, and either its Γ̂
/// with its σ per axis beside the estimate above, or, where it is the
/// estimate above, the estimate through the loop model as the cross-check.
fn nco_estimate(s: &mut String, doc: &ResultDocument, check: &gsens_calib::LoopFreeCheck) {
    let (name, short) = match check.measurement {
        Measurement::NcoFrequency => ("estimate from the NCO frequency", "NCO frequency"),
        _ => ("loop-free estimate", "loop-free"),
    };
    let Some(free) = &check.estimate else {
        let source = if check.measurement == Measurement::NcoFrequency { "" } else { " (from the NCO's phase)" };
        let _ = writeln!(s, "\n{name}{source}: none: {}", check.error.as_deref().unwrap_or("?"));
        return;
    };
    let offset = if free.time_offset_searched { "searched" } else { "given" };
    let details = match check.measurement {
        Measurement::NcoFrequency => format!(
            "f_NCO through the loop model's closed loop H; {} channel(s), {} segment(s); IMU offset {:+.4} s, {offset}",
            free.tracks, free.segments, free.imu_time_offset_s
        ),
        _ => format!(
            "θ_NCO + φ, no loop model; {} channel(s), {} segment(s), {} left out for a slip; IMU offset {:+.4} s, \
             {offset}",
            free.tracks, free.segments, free.slipped_segments, free.imu_time_offset_s
        ),
    };
    let sigma = free.sigma_hz_per_mps2();
    // The other estimate's rows: the one through the loop model where this one is above.
    let (heading, rows, difference): (String, [Option<(f64, f64)>; 3], String) =
        match (doc.measurement == check.measurement, &doc.tracking_error) {
            (true, Some(closed)) => (
                format!(
                    "\nthe estimate above is the {short} one ({details})\ncross-check, the estimate through the loop \
                     model ({}):",
                    doc.calibration.loop_used
                ),
                [0, 1, 2].map(|i| closed.gamma_hz_per_mps2[i].zip(closed.sigma_hz_per_mps2[i])),
                format!("through the loop − {short}"),
            ),
            _ => (
                format!("\n{name} ({details}):"),
                [0, 1, 2].map(|i| Some((free.gamma_hz_per_mps2[i], sigma[i]))),
                match doc.measurement {
                    Measurement::TrackingError => format!("above − {short}"),
                    _ => format!("through the loop − {short}"),
                },
            ),
        };
    let _ = writeln!(s, "{heading}");
    for (i, row) in rows.iter().enumerate() {
        let Some((g, sg)) = *row else {
            let _ = writeln!(s, "  {}  unobservable", AXES[i]);
            continue;
        };
        let _ = write!(s, "  {}  {g:+.5}  ±{sg:.5}", AXES[i]);
        if let Some(z) = check.z_difference[i] {
            let _ = write!(s, "     {difference}: {z:+.2}σ");
        }
        if let Some(t) = doc.truth_gamma_hz_per_mps2 {
            let _ = write!(s, "     error {:+.5} ({:+.2}σ)", g - t[i], (g - t[i]) / sg);
        }
        let _ = writeln!(s);
    }
}

/// The shaking verdict of every axis and the predicted g-induced phase
/// error against the discriminator's linear range.
fn shaking(s: &mut String, doc: &ResultDocument) {
    let c = &doc.calibration;
    let _ = writeln!(s, "\nshaking:");
    for v in &c.axes {
        let _ = writeln!(s, "  {}", v.text);
    }
    let peak = c.predicted_peak_phase_err_rad;
    let lin = c.discriminator_linear_range_rad;
    if peak > lin {
        let _ = writeln!(
            s,
            "  the predicted g-induced phase error reaches {peak:.2} rad, beyond the discriminator's linear range \
             ({lin:.2} rad): see the warning above"
        );
    } else {
        let _ = writeln!(
            s,
            "  predicted g-induced phase error peaks at {peak:.3} rad, inside the discriminator's linear range ({lin:.2} rad)"
        );
    }
}

/// The phase error's RMS before and after compensation, the information
/// matrix's condition number and the Cramér–Rao bound.
fn compensation(s: &mut String, doc: &ResultDocument) {
    let c = &doc.calibration;
    let what = if doc.identified_loop.is_some() { "carrier phase (common mode)" } else { "phase error" };
    let _ = writeln!(
        s,
        "\n{what} RMS: {:.4} rad before compensation, {:.4} rad after (g-induced part {:.4} rad)",
        c.rms_before_rad, c.rms_after_rad, c.rms_g_induced_rad
    );
    let _ = writeln!(
        s,
        "information matrix condition number: {}",
        c.condition_number.map(|x| format!("{x:.1}")).unwrap_or_else(|| "∞ (singular)".into())
    );
    if c.crlb_hz_per_mps2.iter().any(Option::is_some) {
        let b = c.crlb_hz_per_mps2.map(|v| v.map_or("—".to_owned(), |v| format!("{v:.5}")));
        let _ = writeln!(
            s,
            "Cramér–Rao bound [Hz/(m/s²)]: x {}, y {}, z {} (residual noise: {})",
            b[0],
            b[1],
            b[2],
            match doc.measurement {
                Measurement::TrackingError => format!("AR({}) model", c.noise_ar_order),
                _ => format!("AR({}) model restarted per segment", c.noise_ar_order),
            }
        );
    }
}

/// The one-line verdict: trustworthy, or not and why (the warning codes).
fn verdict_line(doc: &ResultDocument) -> String {
    if doc.trustworthy {
        "verdict: TRUSTWORTHY: Γ̂ holds within its σ as far as gsens's checks can tell".into()
    } else {
        let codes = doc.untrusted_codes();
        format!("verdict: NOT TRUSTWORTHY ({}): do not use Γ̂ before the warnings are resolved", codes.join(", "))
    }
}

/// A loop's response as a table (f, |L|, phase) with its peak, the shaking
/// period it implies and the half-power band (what `gsens response` prints).
pub fn render_response_text(r: &crate::figures::ResponseData) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "L(j2πf) = φ/Δf of the loop: {}", r.description);
    let _ = writeln!(s, "   f [Hz]   |L| [rad/Hz]   phase [deg]");
    for k in 0..r.frequency_hz.len() {
        let (f, m, p) = (r.frequency_hz[k], r.magnitude_rad_per_hz[k], r.phase_deg[k]);
        let _ = writeln!(s, "{f:>9.4}   {m:>11.5}   {p:>10.1}");
    }
    let _ = write!(
        s,
        "peak: |L| = {:.4} rad/Hz at {:.4} Hz → shake with a period of about {:.2} s",
        r.peak_rad_per_hz,
        r.peak_hz,
        1.0 / r.peak_hz
    );
    if let Some([lo, hi]) = r.half_power_band_hz {
        let _ = write!(s, " (half-power band {lo:.2}–{hi:.2} Hz, periods {:.2}–{:.2} s)", 1.0 / hi, 1.0 / lo);
    }
    s.push('\n');
    s
}

/// A fraction as a percentage at the precision it was given (0.05 → "5").
fn percent(fraction: f64) -> String {
    format!("{}", (fraction * 100.0 * 1e6).round() / 1e6)
}
