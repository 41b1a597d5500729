use super::*;
use crate::session::{MemorySink, simulate};

fn scenario(duration_s: f64, cn0_dbhz: f64) -> Scenario {
    let mut sc = Scenario::default();
    sc.session.duration_s = Some(duration_s);
    sc.satellites.cn0.zenith_cn0_dbhz = cn0_dbhz;
    sc.satellites.cn0.horizon_cn0_dbhz = cn0_dbhz;
    sc.satellites.cn0.per_satellite_offset_sigma_db = 0.0;
    sc
}

fn generate(sc: &Scenario, cfg: &IqConfig, seed: u64) -> (Vec<u8>, IqTruth, Vec<(f64, f64)>, MemorySink) {
    let mut bytes = Vec::new();
    let mut blocks = Vec::new();
    let mut sink = MemorySink::default();
    let truth =
        generate_iq(sc, seed, cfg, &mut bytes, &mut sink, |b| blocks.push((b.delta_f_hz, b.carrier_hz[0])), |_| {})
            .unwrap();
    (bytes, truth, blocks, sink)
}

fn as_complex(bytes: &[u8]) -> Vec<[f32; 2]> {
    bytes
        .chunks_exact(8)
        .map(|c| [f32::from_le_bytes(c[..4].try_into().unwrap()), f32::from_le_bytes(c[4..].try_into().unwrap())])
        .collect()
}

#[test]
fn correlation_with_the_true_replica_recovers_amplitude_and_phase() {
    let sc = scenario(0.02, 70.0);
    let fs = 4.0e6;
    let mut cfg = IqConfig::new(fs, IqFormat::GrComplex, &sc);
    cfg.max_satellites = 4;
    let (bytes, truth, blocks, _) = generate(&sc, &cfg, 7);
    assert_eq!(truth.samples, 80_000);
    assert_eq!(bytes.len(), 80_000 * 8);
    let x = as_complex(&bytes);
    let amp = amplitude(cfg.noise_sigma, 70.0, fs) as f64;
    let df = blocks[0].0;
    for s in &truth.satellites {
        let y = df / truth.sensitivity.carrier_hz;
        let f_bb = (s.start_doppler_hz - df) / (1.0 + y);
        let rate = CA_CHIP_RATE_HZ * (1.0 + s.start_doppler_hz / truth.sensitivity.carrier_hz) / (1.0 + y);
        // One code period: the data bit is constant within it.
        let n = 4000;
        let (i, q) =
            correlate(&x[..n], fs, s.prn, s.start_code_phase_chips, rate, f_bb, s.start_carrier_phase_cycles).unwrap();
        let mag = i.hypot(q);
        // Tolerances: the other satellites' cross-correlation (C/A Gold codes: up to −24 dB each).
        assert!((mag / amp - 1.0).abs() < 0.08, "PRN {}: |corr| {mag} vs A {amp}", s.prn);
        assert!((q / mag).abs() < 0.08, "PRN {}: phase {}", s.prn, q.atan2(i));
        // Half a chip off: the correlation drops to about a half.
        let (i2, q2) =
            correlate(&x[..n], fs, s.prn, s.start_code_phase_chips + 0.5, rate, f_bb, s.start_carrier_phase_cycles)
                .unwrap();
        let r = i2.hypot(q2) / mag;
        assert!((r - 0.5).abs() < 0.06, "PRN {}: half-chip ratio {r}", s.prn);
    }
}

#[test]
fn carrier_phase_follows_doppler_minus_delta_f() {
    // A large constant oscillator offset: Δf = 1e-7·f_L1 ≈ 157.5 Hz must come off the signal's carrier.
    let mut sc = scenario(0.05, 70.0);
    sc.oscillator.preset = crate::scenario::OscillatorKind::Ideal;
    sc.oscillator.offset_frac = Some(1e-7);
    let fs = 2.048e6;
    let mut cfg = IqConfig::new(fs, IqFormat::GrComplex, &sc);
    cfg.max_satellites = 1;
    let (bytes, truth, blocks, _) = generate(&sc, &cfg, 3);
    let x = as_complex(&bytes);
    let s = &truth.satellites[0];
    let df = blocks[0].0;
    assert!((df - 157.542).abs() < 1.0, "{df}");
    let y = df / truth.sensitivity.carrier_hz;
    let rate = CA_CHIP_RATE_HZ * (1.0 + s.start_doppler_hz / truth.sensitivity.carrier_hz) / (1.0 + y);
    let n = 2048;
    let mut phases = Vec::new();
    for (with_df, tol) in [(true, 0.05), (false, f64::INFINITY)] {
        phases.clear();
        let f_bb = if with_df { (s.start_doppler_hz - df) / (1.0 + y) } else { s.start_doppler_hz };
        for k in 0..40 {
            let t = (k * n) as f64 / fs;
            let (i, q) = correlate(
                &x[k * n..(k + 1) * n],
                fs,
                s.prn,
                s.start_code_phase_chips + rate * t,
                rate,
                f_bb,
                s.start_carrier_phase_cycles + f_bb * t,
            )
            .unwrap();
            // Modulo π: the data bit may flip.
            phases.push((q / i).atan());
        }
        let spread = phases.iter().map(|p| (p - phases[0]).abs()).fold(0.0, f64::max);
        if with_df {
            assert!(spread < tol, "phase wanders by {spread} rad with the right frequency");
        } else {
            assert!(spread > 0.5, "ignoring Δf should rotate the phase, spread {spread}");
        }
    }
}

#[test]
fn formats_sizes_determinism_and_imu_shared_with_the_session() {
    let sc = scenario(0.3, 45.0);
    for format in [IqFormat::Ibyte, IqFormat::Ishort, IqFormat::GrComplex] {
        let cfg = IqConfig::new(2.0e6, format, &sc);
        let (a, ta, _, _) = generate(&sc, &cfg, 11);
        let (b, _, _, _) = generate(&sc, &cfg, 11);
        assert_eq!(a, b, "{format:?}: same seed, same bytes");
        assert_eq!(a.len() as u64, ta.samples * format.bytes_per_sample() as u64);
        assert_eq!(ta.samples, 600_000);
        if format == IqFormat::Ibyte {
            // Noise σ = 8 LSB plus the satellites' power A²/2 per component and
            // the quantization's 1/12 LSB²; nothing clips.
            let v: Vec<f64> = a.iter().map(|&x| f64::from(x as i8)).collect();
            let sd = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
            let amp = f64::from(amplitude(8.0, 45.0, 2.0e6));
            let want = (64.0 + ta.satellites.len() as f64 * amp * amp / 2.0 + 1.0 / 12.0).sqrt();
            assert!((sd / want - 1.0).abs() < 0.01, "{sd} vs {want}");
            assert!(v.iter().all(|&x| x > -128.0 && x < 127.0));
        }
    }
    // The IMU log equals the session simulator's for the same seed (1 ms loop interval).
    let (_, _, _, iq_sink) = generate(&sc, &IqConfig::new(2.0e6, IqFormat::Ibyte, &sc), 5);
    let mut sim_sink = MemorySink::default();
    simulate(&sc, 5, &mut sim_sink, |_| {}).unwrap();
    assert_eq!(iq_sink.imu, sim_sink.imu);
}

#[test]
fn bad_settings_are_refused() {
    let sc = scenario(0.1, 45.0);
    let mut cfg = IqConfig::new(0.5e6, IqFormat::Ibyte, &sc);
    let e = generate_iq(&sc, 1, &cfg, Vec::new(), &mut MemorySink::default(), |_| {}, |_| {}).unwrap_err();
    assert!(e.to_string().contains("sampling rate"), "{e}");
    cfg.fs_hz = 4e6;
    cfg.noise_sigma = 0.0;
    let e = generate_iq(&sc, 1, &cfg, Vec::new(), &mut MemorySink::default(), |_| {}, |_| {}).unwrap_err();
    assert!(e.to_string().contains("noise"), "{e}");
}

#[test]
fn normal_quantiles_and_noise_table() {
    assert!(normal_quantile(0.5).abs() < 1e-12);
    assert!((normal_quantile(0.975) - 1.959_963_984_540_054).abs() < 1e-8);
    assert!((normal_quantile(0.001) + 3.090_232_306_167_813_5).abs() < 1e-8);
    assert!((normal_quantile(1e-6) + 4.753_424_308_822_899).abs() < 1e-7);
    let t = NoiseTable::new(2.0);
    let n = t.values.len() as f64;
    let mean = t.values.iter().map(|&x| f64::from(x)).sum::<f64>() / n;
    let var = t.values.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / n;
    let kurt = t.values.iter().map(|&x| f64::from(x).powi(4)).sum::<f64>() / n / (var * var);
    assert!(mean.abs() < 1e-6 && (var - 4.0).abs() < 1e-5, "{mean} {var}");
    assert!((kurt - 3.0).abs() < 0.01, "kurtosis {kurt}");
    // Drawn deviates: variance and independence of consecutive values.
    let mut rng = substream(1, 2);
    let mut buf = vec![0f32; 400_003];
    t.fill(&mut rng, &mut buf);
    let m = buf.len() as f64;
    let v = buf.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / m;
    let r1 = buf.windows(2).map(|w| f64::from(w[0]) * f64::from(w[1])).sum::<f64>() / m / v;
    assert!((v - 4.0).abs() < 0.03 && r1.abs() < 0.005, "{v} {r1}");
}

#[test]
fn without_navigation_data_the_code_is_sent_bare() {
    // One satellite, float samples, same seed: where the data bit is +1 the
    // two streams are the same samples, where it is −1 they differ; the LNAV
    // subframe (preamble 10001011 and the TOW) has bits of both signs within 1 s.
    let sc = scenario(1.0, 60.0);
    let fs = 1.2e6;
    let mut cfg = IqConfig::new(fs, IqFormat::GrComplex, &sc);
    cfg.max_satellites = 1;
    let (with_data, ..) = generate(&sc, &cfg, 3);
    cfg.navigation_data = false;
    let (bare, ..) = generate(&sc, &cfg, 3);
    let (bare2, ..) = generate(&sc, &cfg, 3);
    assert_eq!(bare, bare2, "same seed, same bytes");
    let block = (fs / 1000.0) as usize * 8;
    let same = with_data.chunks(block).zip(bare.chunks(block)).filter(|(a, b)| a == b).count();
    let blocks = with_data.len() / block;
    assert_eq!(blocks, 1000);
    // 50 bits of 20 ms: ± bits cover at least 10 % of the second each.
    assert!((100..=900).contains(&same), "{same} of {blocks} 1 ms blocks identical");
    // Where they differ, it is the signal's sign: a = n − s against b = n + s
    // correlates below b's energy (s dominates at 60 dB-Hz and 1.2 Msps).
    let (a, b) = (as_complex(&with_data), as_complex(&bare));
    let n = (fs / 1000.0) as usize;
    for k in (0..blocks).filter(|&k| a[k * n..(k + 1) * n] != b[k * n..(k + 1) * n]) {
        let dot: f64 = (k * n..(k + 1) * n).map(|j| f64::from(a[j][0] * b[j][0] + a[j][1] * b[j][1])).sum();
        let e: f64 = (k * n..(k + 1) * n).map(|j| f64::from(b[j][0] * b[j][0] + b[j][1] * b[j][1])).sum();
        assert!(dot < e, "block {k}: {dot} vs {e}");
    }
}
