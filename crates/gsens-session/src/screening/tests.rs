use super::*;

/// Rows of `tracks` tracks over `epochs` epochs: a common signal plus white
/// noise per track (xorshift), all tracks at every epoch.
fn synthetic_rows(tracks: usize, epochs: usize) -> Rows {
    let mut x: u64 = 0x2545_F491_4F6C_DD1D;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut rows = Rows { track_start: vec![0], ..Rows::default() };
    for i in 0..tracks {
        let (mut epoch, mut phase, mut cn0) = (Vec::new(), Vec::new(), Vec::new());
        for e in 0..epochs {
            epoch.push(e as u32);
            phase.push(0.1 * (e as f64 * 0.2).sin() + 0.05 * rnd() + 0.01 * i as f64);
            cn0.push(40.0 + i as f64 + rnd());
        }
        rows.push_track(epoch, phase, cn0);
    }
    rows
}

#[test]
#[ignore = "timing: cargo test -p gsens-session --release --lib screening::tests::timing -- --ignored --nocapture"]
fn timing() {
    let rows = synthetic_rows(12, 144_000);
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let t = std::time::Instant::now();
        let s = screen(&rows, 144_000, 0.025, &ScreeningConfig::default());
        best = best.min(t.elapsed().as_secs_f64());
        assert_eq!(s.flags.len(), rows.len());
    }
    let s = screen(&rows, 144_000, 0.025, &ScreeningConfig::default());
    let slips: usize = s.summaries.iter().map(|t| t.slips).sum();
    eprintln!("screen, 12 tracks × 144 000 epochs: {:.1} ms (best of 7), {slips} slips", best * 1e3);
}

// ---------------------------------------------------------------------------
// The screening through `prepare_session`, on synthetic logs with known faults.

use crate::session::{PreparedSession, SelectionConfig, prepare_session};
use core::f64::consts::{FRAC_PI_2, PI, TAU};
use gsens_io::{ImuSeries, TrackingLog, TrackingRow, TrackingWriter, read_tracking};

const T: f64 = 0.025;
const EPOCHS: usize = 4800; // 120 s

/// Gaussian draws (Box–Muller on xorshift), deterministic.
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (TAU * self.uniform()).cos()
    }
}

/// The common (oscillator + g-induced) phase: shaking at 0.9 Hz in bursts, plus a slow wander.
fn common(k: usize) -> f64 {
    let t = k as f64 * T;
    let burst = if (t % 30.0) < 20.0 { 1.0 } else { 0.1 };
    0.25 * burst * (TAU * 0.9 * t).sin() + 0.03 * (TAU * t / 47.0).sin()
}

/// A Costas slip seen in the logged (wrapped) discriminator output: the error
/// grows to π/2 over 0.15 s, wraps to −π/2 and the loop pulls it back to 0
/// with a 0.3 s time constant. `s` seconds after the start of the slip.
fn slip_shape(s: f64) -> f64 {
    if s < 0.0 {
        0.0
    } else if s < 0.15 {
        FRAC_PI_2 * s / 0.15
    } else {
        -FRAC_PI_2 * (-(s - 0.15) / 0.3).exp()
    }
}

/// Per channel: offset, C/N0; 5 channels carrying the common signal plus
/// white noise of 0.03 rad.
const OFFSETS: [f64; 5] = [0.02, -0.01, 0.04, -0.03, 0.0];

/// Which faults to put in; `None`: clean.
#[derive(Clone, Copy)]
struct Faults {
    /// Channel 1: a slip excursion at 20 s and a persistent π/2 step at 60 s.
    slip_and_step: bool,
    /// Channel 2: loses lock from 40 to 50 s (noise of 0.6 rad, no common signal).
    lost_lock: bool,
    /// Channel 3: C/N0 15 dB down from 80 to 90 s, with half the signal and 0.3 rad of noise.
    cn0_drop: bool,
}

const ALL: Faults = Faults { slip_and_step: true, lost_lock: true, cn0_drop: true };
const NONE: Faults = Faults { slip_and_step: false, lost_lock: false, cn0_drop: false };

fn faulty_log(f: Faults) -> TrackingLog {
    let mut w = TrackingWriter::new(Vec::new()).unwrap();
    let mut noise = Noise(0x9E37_79B9_7F4A_7C15);
    for k in 0..EPOCHS {
        let t = k as f64 * T;
        for ch in 0..5u32 {
            let n = 0.03 * noise.normal();
            let (extra_noise, lock_noise) = (noise.normal(), noise.normal());
            let mut phase = common(k) + OFFSETS[ch as usize] + n;
            let mut cn0 = 42.0 + ch as f64;
            if f.slip_and_step && ch == 1 {
                phase += slip_shape(t - 20.0);
                if t >= 60.0 {
                    phase += FRAC_PI_2;
                }
            }
            if f.lost_lock && ch == 2 && (40.0..50.0).contains(&t) {
                phase = OFFSETS[2] + 0.6 * lock_noise;
            }
            if f.cn0_drop && ch == 3 && (80.0..90.0).contains(&t) {
                cn0 -= 15.0;
                phase = 0.5 * common(k) + OFFSETS[3] + 0.3 * extra_noise;
            }
            let row = TrackingRow {
                t_s: 100.0 + t,
                channel: ch,
                prn: ch + 10,
                cn0_dbhz: cn0,
                elev_deg: None,
                phase_err_rad: phase,
            };
            w.write_row(&row).unwrap();
        }
    }
    read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap()
}

fn imu() -> ImuSeries {
    let n = EPOCHS + 10;
    ImuSeries { t_s: (0..n).map(|k| 99.9 + k as f64 * T).collect(), accel_mps2: vec![[0.0, 0.0, 9.81]; n] }
}

fn prepare(log: &TrackingLog, screening: ScreeningConfig) -> PreparedSession {
    let cfg = SelectionConfig { max_channels: None, screening, ..SelectionConfig::default() };
    prepare_session(log, &imu(), "imu.csv", &cfg, 0.0).unwrap()
}

/// Max and RMS of the difference between two averaged series (epochs where both have a phase),
/// and the number of epochs of `a` without a phase.
fn compare(a: &PreparedSession, b: &PreparedSession) -> (f64, f64, usize) {
    let (mut max, mut ss, mut n, mut gaps) = (0.0f64, 0.0, 0usize, 0usize);
    for (x, y) in a.phase_err_rad.iter().zip(&b.phase_err_rad) {
        match (x, y) {
            (Some(x), Some(y)) => {
                max = max.max((x - y).abs());
                ss += (x - y) * (x - y);
                n += 1;
            }
            (None, _) => gaps += 1,
            _ => {}
        }
    }
    (max, (ss / n as f64).sqrt(), gaps)
}

#[test]
fn screening_keeps_the_average_of_a_faulty_log_close_to_the_clean_one() {
    let clean = prepare(&faulty_log(NONE), ScreeningConfig::off());
    let faulty = faulty_log(ALL);
    let screened = prepare(&faulty, ScreeningConfig::default());
    let naive = prepare(&faulty, ScreeningConfig::off());
    let (max_s, rms_s, gaps) = compare(&screened, &clean);
    let (max_n, rms_n, _) = compare(&naive, &clean);
    eprintln!("screened: max {max_s:.4} rad, RMS {rms_s:.4} rad, {gaps} gaps; naive: max {max_n:.4}, RMS {rms_n:.4}");
    for c in &screened.channels {
        eprintln!(
            "{} {:?} {:?} {:?}",
            c.channel,
            c.phase_offset_rad,
            c.screening.brief(),
            c.screening.spans.iter().map(|s| (s.start_s, s.end_s)).collect::<Vec<_>>()
        );
    }
    for k in (0..EPOCHS).step_by(200) {
        eprintln!("{k} {:?} {:?}", screened.phase_err_rad[k], clean.phase_err_rad[k]);
    }
    // What is left differs from the clean 5-channel average by the noise of a
    // 4-channel one at most (0.03 rad per channel): well inside 0.06 rad.
    assert!(max_s < 0.06 && rms_s < 0.01, "screened: max {max_s}, RMS {rms_s}");
    assert_eq!(gaps, 0);
    // The naive average carries the faults: the π/2 step alone moves it by π/10.
    assert!(max_n > 0.3 && rms_n > 0.1, "naive: max {max_n}, RMS {rms_n}");

    let ch = |c: u32| screened.channels.iter().find(|s| s.channel == c).unwrap();
    let s1 = &ch(1).screening;
    assert_eq!((s1.slips, s1.steps), (2, 1), "{s1:?}");
    assert_eq!(s1.segment_offsets_rad.len(), 2);
    let step = s1.segment_offsets_rad[1] - s1.segment_offsets_rad[0];
    assert!((step - FRAC_PI_2).abs() < 0.01, "step {step}");
    for sp in &s1.spans {
        assert!(sp.reasons == ["slip"] && sp.end_s - sp.start_s < 3.0, "{sp:?}");
    }
    assert!(s1.spans.iter().any(|sp| sp.start_s < 120.0 && sp.end_s > 120.2), "{:?}", s1.spans);
    assert!(s1.spans.iter().any(|sp| sp.start_s < 160.0 && sp.end_s >= 160.0), "{:?}", s1.spans);
    assert!(s1.rows_excluded < 200, "{s1:?}");
    // Channel 2: the 10 s without lock (400 rows), and little else.
    let s2 = &ch(2).screening;
    assert!((400..560).contains(&s2.rows_excluded), "{s2:?}");
    assert!(s2.spans.iter().all(|sp| sp.start_s >= 139.0 && sp.end_s <= 151.0), "{:?}", s2.spans);
    // Channel 3: the C/N0 drop (400 rows, and the guards).
    let s3 = &ch(3).screening;
    assert!(s3.rows_cn0_drop >= 400 && s3.rows_excluded < 480, "{s3:?}");
    assert!(ch(3).screening.brief().unwrap().contains("C/N0 drop"));
    // Channels 0 and 4 are clean.
    for c in [0, 4] {
        assert_eq!(ch(c).screening.rows_excluded, 0, "{:?}", ch(c).screening);
        assert!(ch(c).screening.brief().is_none());
    }
    assert!(screened.channels.iter().all(|c| c.used));
}

#[test]
fn a_clean_log_is_left_alone() {
    let log = faulty_log(NONE);
    let screened = prepare(&log, ScreeningConfig::default());
    let plain = prepare(&log, ScreeningConfig::off());
    for c in &screened.channels {
        assert_eq!(c.screening.rows_excluded, 0, "channel {}: {:?}", c.channel, c.screening);
        assert_eq!(c.epochs, EPOCHS);
        let sigma = c.screening.deviation_sigma_rad.unwrap();
        // The deviation from the median of four others: 0.03 rad · √(1 + π/(2·4)) ≈ 0.035 rad.
        assert!((0.03..0.04).contains(&sigma), "σ {sigma}");
    }
    assert_eq!(screened.phase_err_rad, plain.phase_err_rad);
}

#[test]
fn a_channel_that_does_not_follow_the_common_signal_is_dropped() {
    // Channel 2 has lost lock for good: noise of 0.15 rad, no common signal;
    // its deviation is not much noisier than a weak channel's, but its gain is 0.
    let mut w = TrackingWriter::new(Vec::new()).unwrap();
    let mut noise = Noise(7);
    for k in 0..EPOCHS {
        for ch in 0..5u32 {
            let n = noise.normal();
            let phase = if ch == 2 { 0.15 * n } else { common(k) + 0.03 * n };
            let row = TrackingRow {
                t_s: k as f64 * T + 100.0,
                channel: ch,
                prn: ch + 10,
                cn0_dbhz: 40.0,
                elev_deg: None,
                phase_err_rad: phase,
            };
            w.write_row(&row).unwrap();
        }
    }
    let log = read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap();
    let s = prepare(&log, ScreeningConfig::default());
    let c2 = s.channels.iter().find(|c| c.channel == 2).unwrap();
    assert!(!c2.used && c2.screening.track_excluded && c2.screening.rows_low_gain > 0, "{c2:?}");
    assert!(c2.reason.contains("excluded by the screening"), "{}", c2.reason);
    for c in s.channels.iter().filter(|c| c.channel != 2) {
        assert!(c.used && c.screening.rows_excluded == 0, "{c:?}");
    }
    // The average is the common signal (4 channels' noise).
    for (k, p) in s.phase_err_rad.iter().enumerate() {
        assert!((p.unwrap() - common(k)).abs() < 0.1, "epoch {k}");
    }
}

#[test]
fn a_lone_excursion_beyond_the_linear_range_is_excluded_a_common_one_kept() {
    let mut w = TrackingWriter::new(Vec::new()).unwrap();
    let mut noise = Noise(11);
    for k in 0..1200 {
        let t = k as f64 * T;
        // A common excursion to 1.0 rad from 10 to 11 s (the oscillator's).
        let base = if (10.0..11.0).contains(&t) { 1.0 } else { 0.0 };
        for ch in 0..4u32 {
            let mut phase = base + 0.02 * noise.normal();
            // Channel 0 alone at 0.9 rad from 20 to 20.5 s.
            if ch == 0 && (20.0..20.5).contains(&t) {
                phase = 0.9;
            }
            let row = TrackingRow {
                t_s: t + 100.0,
                channel: ch,
                prn: ch + 1,
                cn0_dbhz: 45.0,
                elev_deg: None,
                phase_err_rad: phase,
            };
            w.write_row(&row).unwrap();
        }
    }
    let log = read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap();
    let s = prepare(&log, ScreeningConfig::default());
    let c0 = &s.channels[0].screening;
    assert!(c0.rows_phase_range >= 20 && c0.rows_phase_range <= 20 + 2 * 20 + 2, "{c0:?}");
    for c in &s.channels[1..] {
        assert_eq!(c.screening.rows_phase_range, 0, "{:?}", c.screening);
    }
    // The common excursion stays in the average.
    assert!(s.phase_err_rad[420].unwrap() > 0.9);
}

#[test]
fn screening_settings_are_checked() {
    let log = faulty_log(NONE);
    for (cfg, key) in [
        (ScreeningConfig { deviation_k: 0.0, ..ScreeningConfig::default() }, "deviation_k"),
        (ScreeningConfig { cn0_drop_db: Some(f64::NAN), ..ScreeningConfig::default() }, "cn0_drop_db"),
        (ScreeningConfig { max_excluded_fraction: 1.5, ..ScreeningConfig::default() }, "max_excluded_fraction"),
    ] {
        let sel = SelectionConfig { screening: cfg, ..SelectionConfig::default() };
        let e = prepare_session(&log, &imu(), "imu.csv", &sel, 0.0).unwrap_err().to_string();
        assert!(e.contains("invalid selection settings") && e.contains(key), "{e}");
    }
    // The typed errors, and the messages they display (unchanged from the former strings).
    use crate::error::{ScreeningConfigError, SessionError};
    let cfg = ScreeningConfig { guard_s: -1.0, ..ScreeningConfig::default() };
    assert_eq!(cfg.validate(), Err(ScreeningConfigError::MustBeNonNegative { key: "guard_s", value: -1.0 }));
    assert_eq!(cfg.validate().unwrap_err().to_string(), "screening.guard_s = -1 must be ≥ 0");
    let cfg = ScreeningConfig { max_abs_phase_rad: Some(0.0), ..ScreeningConfig::default() };
    assert_eq!(cfg.validate().unwrap_err().to_string(), "screening.max_abs_phase_rad = 0 must be positive");
    let cfg = ScreeningConfig { max_excluded_fraction: 1.5, ..ScreeningConfig::default() };
    assert_eq!(cfg.validate().unwrap_err().to_string(), "screening.max_excluded_fraction = 1.5 must be in [0, 1]");
    let sel = SelectionConfig { screening: cfg, ..SelectionConfig::default() };
    let e = prepare_session(&log, &imu(), "imu.csv", &sel, 0.0).unwrap_err();
    assert!(matches!(e, SessionError::InvalidScreening { error: ScreeningConfigError::MustBeFraction { .. }, .. }));
    assert_eq!(
        e.to_string(),
        "tracking.csv: invalid selection settings: screening.max_excluded_fraction = 1.5 must be in [0, 1]"
    );
    assert!(std::error::Error::source(&e).is_none(), "the reason is in the message, not repeated as a source");
    assert!(ScreeningConfig::default().validate().is_ok() && ScreeningConfig::off().validate().is_ok());
}

#[test]
fn screening_config_serde_and_brief() {
    let cfg: ScreeningConfig = serde_json::from_str(r#"{"cn0_drop_db": 10, "max_abs_phase_rad": null}"#).unwrap();
    assert_eq!(cfg.cn0_drop_db, Some(10.0));
    assert_eq!(cfg.max_abs_phase_rad, None);
    assert!(cfg.enabled);
    let s = TrackScreening { rows_excluded: 30, slips: 2, steps: 1, rows_cn0_drop: 5, ..TrackScreening::default() };
    assert_eq!(s.brief().unwrap(), "screened out 30 rows: 2 slips (1 step), 5 C/N0 drop");
    let _ = PI;
}

/// Single 1 ms Costas outputs at 39 dB-Hz (σ = 1/√(2·C/N0·T) ≈ 0.25 rad, as
/// PocketSDR logs them) riding on a common 0.9 Hz signal of 0.5 rad: noise
/// alone crosses π/4 in about one row of 200 here. The linear-range test must
/// not exclude those rows (it would select on the noise and on the signal
/// under it, biasing the average towards zero), and the kept average must
/// follow the common signal with gain 1 (within 3 standard errors).
#[test]
fn noise_crossing_the_linear_range_is_not_an_excursion() {
    let mut w = TrackingWriter::new(Vec::new()).unwrap();
    let mut noise = Noise(29);
    let sigma = 1.0 / (2.0 * gsens_core::units::cn0_dbhz_to_ratio_hz(39.0) * 1e-3).sqrt();
    let signal = |t: f64| 0.5 * (TAU * 0.9 * t).sin();
    let epochs = EPOCHS;
    for k in 0..epochs {
        let t = k as f64 * T;
        for ch in 0..4u32 {
            let row = TrackingRow {
                t_s: t + 100.0,
                channel: ch,
                prn: ch + 1,
                cn0_dbhz: 39.0,
                elev_deg: None,
                phase_err_rad: signal(t) + sigma * noise.normal(),
            };
            w.write_row(&row).unwrap();
        }
    }
    let log = read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap();
    let s = prepare(&log, ScreeningConfig::default());
    for c in &s.channels {
        assert_eq!(c.screening.rows_phase_range, 0, "{:?}", c.screening);
    }
    let (mut sxy, mut sxx, mut n) = (0.0, 0.0, 0.0);
    let mut resid = Vec::new();
    for (k, p) in s.phase_err_rad.iter().enumerate() {
        if let Some(p) = p {
            let x = signal(k as f64 * T);
            sxy += x * p;
            sxx += x * x;
            n += 1.0;
            resid.push((x, *p));
        }
    }
    assert!(
        n > 0.95 * epochs as f64,
        "{n} of {epochs} epochs kept: {:?}",
        s.channels.iter().map(|c| &c.screening).collect::<Vec<_>>()
    );
    let slope = sxy / sxx;
    // The average of 4 tracks has σ/2.
    let se = 0.5 * sigma / sxx.sqrt();
    assert!((slope - 1.0).abs() < 3.0 * se, "slope {slope} ± {se}");
}

/// The per-row arrays split by track are the tracks' rows, empty tracks included.
#[test]
fn per_track_splits_rows_by_track() {
    let mut v: Vec<u32> = (0..7).collect();
    let parts = per_track(&mut v, &[0, 2, 2, 7]);
    let parts: Vec<Vec<u32>> = parts.into_iter().map(|p| p.to_vec()).collect();
    assert_eq!(parts, vec![vec![0, 1], vec![], vec![2, 3, 4, 5, 6]]);
}

/// Lone rows far out (as an atan discriminator's output of one short
/// integration has at low C·T: its tail is erfc(√(C·T)·sin x), not
/// Gaussian) are no slip; a slip's excursion, several rows long, still is.
#[test]
fn lone_tail_rows_are_not_slips() {
    let log = faulty_log(NONE);
    let mut rows: Vec<TrackingRow> = Vec::new();
    let mut w = TrackingWriter::new(Vec::new()).unwrap();
    for t in log.tracks() {
        for j in 0..t.t_s.len() {
            let k = ((t.t_s[j] - 100.0) / T).round() as usize;
            let lone = t.channel == 4 && k % 400 == 200;
            let slip = t.channel == 0 && (2400..2440).contains(&k);
            let extra = if lone { 1.3 * if k % 800 == 200 { 1.0 } else { -1.0 } } else { 0.0 };
            let s = if slip { slip_shape((k - 2400) as f64 * T) } else { 0.0 };
            rows.push(TrackingRow {
                t_s: t.t_s[j],
                channel: t.channel,
                prn: t.prn,
                cn0_dbhz: t.cn0_dbhz[j],
                elev_deg: None,
                phase_err_rad: t.phase_err_rad[j] + extra + s,
            });
        }
    }
    rows.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.channel.cmp(&b.channel)));
    for r in &rows {
        w.write_row(r).unwrap();
    }
    let log = read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap();
    let s = prepare(&log, ScreeningConfig::default());
    let ch = |c: u32| s.channels.iter().find(|x| x.channel == c).unwrap();
    assert_eq!((ch(4).screening.slips, ch(4).screening.rows_slip), (0, 0), "{:?}", ch(4).screening);
    assert_eq!(ch(0).screening.slips, 1, "{:?}", ch(0).screening);
}

/// The ranks of up to 16 keys compared in registers are the pairwise
/// counts, for every count of keys from none to beyond the registers' 16
/// (distinct keys of either sign, in any order, the extremes included).
#[test]
fn ranks_in_registers_are_the_pairwise_ranks() {
    let mut noise = Noise(0x9E37_79B9_7F4A_7C15);
    for m in 0..=20 {
        for _ in 0..200 {
            let mut keys: Vec<i32> = Vec::with_capacity(m);
            while keys.len() < m {
                let k = match noise.uniform() {
                    u if u < 0.05 => i32::MIN,
                    u if u < 0.10 => i32::MAX - 1,
                    u => ((u - 0.5) * 2.0 * i32::MAX as f64) as i32,
                };
                if !keys.contains(&k) {
                    keys.push(k);
                }
            }
            let (mut fast, mut pairwise) = (vec![usize::MAX; m], vec![usize::MAX; m]);
            rank_keys(&keys, &mut fast);
            rank_keys_pairwise(&keys, &mut pairwise);
            assert_eq!(fast, pairwise, "{keys:?}");
            let mut seen = pairwise.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..m).collect::<Vec<_>>(), "ranks are a permutation");
        }
    }
}

/// Each present track's deviation is its value less the median of the other
/// tracks' values, sorted plainly (values far enough apart that the keys'
/// single precision orders them exactly), NaN with fewer than two others:
/// for 1 to 20 tracks, values and presence drawn at random.
#[test]
fn medians_of_the_others_are_their_definition() {
    let mut noise = Noise(0x2545_F491_4F6C_DD1D);
    for n_tracks in 1..=20 {
        let mut scratch = MedianScratch::new(n_tracks);
        for _ in 0..300 {
            // Distinct values on a grid of 0.0137 rad between −3 and +3.
            let mut grid: Vec<f64> = (0..438).map(|k| -3.0 + 0.0137 * k as f64).collect();
            let mut draw = |noise: &mut Noise| grid.swap_remove((noise.uniform() * grid.len() as f64) as usize);
            let v_row: Vec<f64> =
                (0..n_tracks).map(|_| if noise.uniform() < 0.2 { f64::NAN } else { draw(&mut noise) }).collect();
            let p_row: Vec<f64> = v_row
                .iter()
                .map(|&v| match noise.uniform() {
                    u if u < 0.1 => f64::NAN,
                    u if u < 0.3 || v.is_nan() => draw(&mut noise),
                    _ => v,
                })
                .collect();
            let mut d_row = vec![0.25; n_tracks];
            scratch.deviations(&p_row, &v_row, &mut d_row);
            for i in 0..n_tracks {
                let mut others: Vec<f64> =
                    (0..n_tracks).filter(|&j| j != i && v_row[j].is_finite()).map(|j| v_row[j]).collect();
                others.sort_by(f64::total_cmp);
                let n = others.len();
                let expected = match (p_row[i].is_finite(), n >= 2) {
                    (false, _) => 0.25,
                    (true, false) => f64::NAN,
                    (true, true) => p_row[i] - 0.5 * (others[(n - 1) / 2] + others[n / 2]),
                };
                assert!(
                    d_row[i].to_bits() == expected.to_bits() || (d_row[i].is_nan() && expected.is_nan()),
                    "track {i} of {v_row:?} / {p_row:?}: {} against {expected}",
                    d_row[i]
                );
            }
        }
    }
}
