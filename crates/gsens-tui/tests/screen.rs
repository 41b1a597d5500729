//! Snapshot tests of the `gsens live` screen: hand-built views drawn on
//! ratatui's `TestBackend` and compared with `tests/snapshots/*.txt`.
//!
//! After an intended change of the screen: `UPDATE_SNAPSHOTS=1 cargo test
//! -p gsens-tui`, then read the diff of the snapshot files before committing.
//!
//! The Γ̂, σ, RMS, C/N0 and phase values below are fixtures chosen to look
//! like a session (of the order of the README's demo), not results; the
//! loop's band is computed from the paper's loop, and each instruction by
//! `gsens_live::instruct` from the fixture's situation, so the
//! screen is drawn from views the session could produce.

use std::path::PathBuf;

use gsens_calib::Measurement;
use gsens_core::{LoopModel, LoopSpec};
use gsens_live::{AxisProgress, Instruction, LiveView, LoopBand, Notice, Shaking};
use gsens_live::{BatchVerdict, ChannelStatus};
use gsens_live::{Situation, instruct};
use gsens_tui::ratatui::backend::TestBackend;
use gsens_tui::ratatui::style::Color;
use gsens_tui::{phase_gauge_is_red, progress_to_target, render_text};

const TARGET: f64 = 8e-4;
const RANGE_RAD: f64 = core::f64::consts::FRAC_PI_4;

fn band() -> LoopBand {
    LoopBand::of(&LoopModel::kaplan(LoopSpec::PAPER, None)).expect("the paper's loop is valid")
}

fn situation(view: &LiveView, rest_more_s: f64) -> Situation {
    Situation {
        data_s: view.data_s,
        rest_more_s,
        shaken: view.shaking.axis.map(|a| (a, view.shaking.frequency_hz)),
        several_axes: view.shaking.several_axes,
        peak_phase_rad: view.peak_phase_rad,
        range_rad: view.range_rad,
        axes: view.axes.map(|a| (a.meets_target, a.more_s)),
        protocol: gsens_live::Protocol::OneRate,
        shaken_by_rate_s: [[0.0; 2]; 3],
    }
}

/// An axis estimated at `sigma` after `then_s` of shaking, shaken `shaken_s`
/// by now: `more_s` as `LiveSession` computes it (σ ∝ 1/√T).
fn axis(shaken_s: f64, then_s: f64, gamma: f64, sigma: f64) -> AxisProgress {
    let meets_target = sigma <= TARGET;
    let needed = then_s * ((sigma / TARGET).powi(2) - 1.0) - (shaken_s - then_s);
    AxisProgress {
        shaken_s,
        gamma_hz_per_mps2: Some(gamma),
        sigma_hz_per_mps2: Some(sigma),
        observable: true,
        meets_target,
        more_s: Some(if meets_target { 0.0 } else { needed.max(1.0) }),
        // The streamed estimate a little ahead of the batch's.
        now_gamma_hz_per_mps2: Some(gamma + 0.1 * sigma),
        now_sigma_hz_per_mps2: Some(sigma * 0.98),
    }
}

fn unobservable(shaken_s: f64) -> AxisProgress {
    AxisProgress { shaken_s, ..AxisProgress::default() }
}

fn channels(t_s: f64, lost_prn: Option<u32>) -> Vec<ChannelStatus> {
    let sats = [
        (3, 44.8, 0.112),
        (7, 47.1, 0.098),
        (11, 41.6, 0.131),
        (16, 45.9, 0.104),
        (22, 38.9, -0.020),
        (27, 43.2, 0.121),
    ];
    sats.iter()
        .enumerate()
        .map(|(k, &(prn, cn0_dbhz, phase_err_rad))| {
            let lost = lost_prn == Some(prn);
            ChannelStatus {
                channel: k as u32,
                prn,
                cn0_dbhz,
                phase_err_rad,
                last_t_s: if lost { t_s - 3.0 } else { t_s },
                rows: (40.0 * t_s) as u64,
                tracking: !lost,
            }
        })
        .collect()
}

fn notice(line: u64, message: &str) -> String {
    Notice { source: "tracking.csv".into(), line, message: message.into() }.to_string()
}

fn waiting() -> LiveView {
    let band = band();
    let mut view = LiveView {
        data_t_s: f64::NEG_INFINITY,
        data_s: 0.0,
        instruction: Instruction::Waiting,
        axes: [AxisProgress::default(); 3],
        target_sigma_hz_per_mps2: TARGET,
        shaking: Shaking::default(),
        band,
        peak_phase_rad: 0.0,
        range_rad: RANGE_RAD,
        channels: Vec::new(),
        batch: None,
        batch_error: None,
        notices: (Vec::new(), 0),
        received: (0, 0),
        ubx: None,
    };
    view.instruction = instruct(&situation(&view, 5.0), &band);
    view
}

/// x met, y being shaken in the loop's band, z not yet shaken.
fn mid_session() -> LiveView {
    let band = band();
    let t = 48.0;
    let mut view = LiveView {
        data_t_s: t,
        data_s: t,
        axes: [axis(16.3, 16.3, 0.08934, 0.00071), axis(9.8, 7.5, 0.07911, 0.00142), unobservable(0.0)],
        shaking: Shaking {
            rms_mps2: [0.06, 1.91, 0.05],
            axis: Some(1),
            several_axes: false,
            frequency_hz: Some(band.peak_hz * 0.97),
            window_s: 4.0,
        },
        peak_phase_rad: 0.21,
        channels: channels(t, Some(22)),
        batch: Some(BatchVerdict::new(45.0, Measurement::TrackingError, Vec::new())),
        notices: (vec![notice(17, "garbage line: expected 6 fields, found 2")], 1),
        received: (1920, 11_232),
        ubx: None,
        ..waiting()
    };
    view.instruction = instruct(&situation(&view, 0.0), &band);
    view
}

/// y shaken too hard: the phase error near the discriminator's range.
fn gentler() -> LiveView {
    let band = band();
    let mut view = LiveView {
        shaking: Shaking { rms_mps2: [0.11, 4.8, 0.09], ..mid_session().shaking },
        peak_phase_rad: 0.64,
        batch: Some(BatchVerdict::new(
            45.0,
            Measurement::TrackingError,
            vec![gsens_calib::Warning {
                code: gsens_calib::WarningCode::DiscriminatorRange,
                message: "the predicted g-induced phase error peaks at 0.62 rad, beyond the discriminator's \
                          linear range: shake more gently"
                    .into(),
            }],
        )),
        ..mid_session()
    };
    view.instruction = instruct(&situation(&view, 0.0), &band);
    view
}

/// Every axis meets the target.
fn done() -> LiveView {
    let band = band();
    let t = 96.5;
    let mut view = LiveView {
        data_t_s: t,
        data_s: t,
        axes: [
            axis(16.3, 16.3, 0.08934, 0.00071),
            axis(19.0, 19.0, 0.07909, 0.00074),
            axis(17.2, 17.2, -0.07986, 0.00069),
        ],
        shaking: Shaking { rms_mps2: [0.02, 0.03, 0.02], window_s: 4.0, ..Shaking::default() },
        peak_phase_rad: 0.02,
        channels: channels(t, None),
        batch: Some(BatchVerdict::new(95.0, Measurement::TrackingError, Vec::new())),
        notices: (
            vec![
                notice(17, "garbage line: expected 6 fields, found 2"),
                notice(2210, "tracking time 55.2 s before the previous row's 55.3 s: not used (kept in the raw log)"),
            ],
            2,
        ),
        received: (3860, 22_584),
        ubx: None,
        ..waiting()
    };
    view.instruction = instruct(&situation(&view, 0.0), &band);
    view
}

fn views() -> [(&'static str, LiveView); 4] {
    [("waiting", waiting()), ("mid_session", mid_session()), ("gentler", gentler()), ("done", done())]
}

/// Compares `text` with `tests/snapshots/<name>.txt`, or writes the file
/// when the environment has `UPDATE_SNAPSHOTS=1`.
fn check_snapshot(name: &str, text: &str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots").join(format!("{name}.txt"));
    if std::env::var("UPDATE_SNAPSHOTS").as_deref() == Ok("1") {
        std::fs::create_dir_all(path.parent().expect("a snapshot file has a directory")).expect("snapshot dir");
        std::fs::write(&path, text).expect("snapshot written");
        return;
    }
    let expected = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (UPDATE_SNAPSHOTS=1 writes it)", path.display()));
    if expected == text {
        return;
    }
    let (old, new): (Vec<&str>, Vec<&str>) = (expected.lines().collect(), text.lines().collect());
    let mut diff = String::new();
    for i in 0..old.len().max(new.len()) {
        let (o, n) = (old.get(i).copied(), new.get(i).copied());
        if o != n {
            diff.push_str(&format!(
                "line {:>3} - {}\n         + {}\n",
                i + 1,
                o.unwrap_or("<none>"),
                n.unwrap_or("<none>")
            ));
        }
    }
    panic!(
        "{} differs from the screen drawn (- snapshot, + now; UPDATE_SNAPSHOTS=1 rewrites it):\n{diff}",
        path.display()
    );
}

/// The screen's line that contains all of `parts`, or a panic showing the screen.
fn line_with<'a>(screen: &'a str, parts: &[&str]) -> &'a str {
    screen
        .lines()
        .find(|l| parts.iter().all(|p| l.contains(p)))
        .unwrap_or_else(|| panic!("no line with {parts:?} in\n{screen}"))
}

#[test]
fn snapshots_match() {
    for (name, view) in views() {
        for (w, h) in [(100, 30), (80, 24), (40, 12)] {
            check_snapshot(&format!("{name}_{w}x{h}"), &render_text(&view, w, h));
        }
    }
}

#[test]
fn the_screen_shows_the_instruction_axes_and_channels() {
    for (name, view) in views() {
        for (w, h) in [(100, 30), (80, 24)] {
            let screen = render_text(&view, w, h);
            let instruction = view.instruction.to_string();
            assert!(screen.contains(&instruction), "{name} {w}x{h}: no {instruction:?} in\n{screen}");
            for (i, a) in view.axes.iter().enumerate() {
                let x = ["x", "y", "z"][i];
                // Γ̂ to σ's second significant digit, as the screen shows it.
                let shown = |g: f64, sigma: f64| {
                    let d = (1.0 - sigma.log10().floor()) as usize;
                    format!("{g:+.d$}")
                };
                // The axes' rows show the streamed estimate …
                let gamma = match (a.now_gamma_hz_per_mps2, a.now_sigma_hz_per_mps2) {
                    (Some(g), Some(s)) => shown(g, s),
                    _ if view.batch.is_some() && !a.observable => "unobservable".to_string(),
                    _ => "—".to_string(),
                };
                // … the checked panel the batch's (where it has the room: 30 lines).
                if view.batch.is_some() && a.observable && h >= 30 {
                    let g = a.gamma_hz_per_mps2.expect("an observable axis has Γ̂");
                    let sigma = a.sigma_hz_per_mps2.expect("an observable axis has σ");
                    line_with(&screen, &[&format!("{x} {}", shown(g, sigma))]);
                }
                line_with(&screen, &[&format!(" {x} "), &format!("{:.1}", a.shaken_s), &gamma]);
            }
            for c in &view.channels {
                let state = if c.tracking { "tracking" } else { "lost" };
                line_with(&screen, &[&c.prn.to_string(), &format!("{:.1}", c.cn0_dbhz), state]);
            }
            line_with(&screen, &["received", &view.received.0.to_string(), &view.received.1.to_string()]);
            line_with(&screen, &["notices", &view.notices.1.to_string()]);
        }
    }
}

#[test]
fn the_mid_session_screen_says_what_is_met_and_what_is_needed() {
    let view = mid_session();
    assert!(matches!(view.instruction, Instruction::Shake { axis: 1, .. }), "{}", view.instruction);
    let screen = render_text(&view, 100, 30);
    line_with(&screen, &[" x ", "met", "0"]);
    let more = format!("{:.0}", view.axes[1].more_s.expect("y has an estimate").ceil());
    line_with(&screen, &["▶ y", &more]);
    line_with(&screen, &[" z ", "unobservable"]);
    line_with(&screen, &["TRUSTWORTHY"]);
    line_with(&screen, &["in the loop's band"]);
    line_with(&screen, &["aim at", &format!("{:.2} s per cycle", view.band.period_s())]);
    // Progress (target/σ)² for y, σ above the target.
    let p = progress_to_target(&view.axes[1], TARGET);
    assert!((p - (TARGET / 0.00142f64).powi(2)).abs() < 1e-12);
    line_with(&screen, &["▶ y", &format!("{:.0}%", 100.0 * p)]);
    assert_eq!(progress_to_target(&view.axes[2], TARGET), 0.0);
    assert_eq!(progress_to_target(&view.axes[0], TARGET), 1.0);
}

#[test]
fn the_gentler_screen_shows_the_phase_gauge_in_red() {
    let view = gentler();
    assert!(matches!(view.instruction, Instruction::Gentler { .. }), "{}", view.instruction);
    assert!(phase_gauge_is_red(&view));
    assert!(!phase_gauge_is_red(&mid_session()));
    let mut terminal = gsens_tui::ratatui::Terminal::new(TestBackend::new(100, 30)).unwrap();
    let frame = terminal.draw(|f| gsens_tui::draw(f, &view)).unwrap();
    let buf = frame.buffer;
    let row = (0..buf.area.height)
        .find(|&y| {
            (0..buf.area.width)
                .map(|x| buf[(x, y)].symbol())
                .collect::<String>()
                .contains(" rad of the discriminator's ")
        })
        .expect("a phase error line");
    let red = (0..buf.area.width).filter(|&x| buf[(x, row)].symbol() == "█" && buf[(x, row)].fg == Color::Red).count();
    assert!(red > 0, "no red gauge cells on the phase error line");
    let screen = render_text(&view, 100, 30);
    line_with(&screen, &["NOT TRUSTWORTHY"]);
    line_with(&screen, &["discriminator_range"]);
}

#[test]
fn small_and_odd_terminals_do_not_panic_and_keep_the_instruction() {
    for (name, view) in views() {
        for (w, h) in [(40, 12), (30, 8), (20, 5), (80, 3), (10, 1), (1, 1), (0, 0), (200, 60), (250, 10)] {
            let screen = render_text(&view, w, h);
            assert_eq!(screen.lines().count(), usize::from(h), "{name} {w}x{h}");
        }
        let screen = render_text(&view, 40, 12);
        let first_word = view.instruction.to_string().split_whitespace().next().unwrap().to_string();
        assert!(screen.contains(&first_word), "{name} 40x12 lost the instruction:\n{screen}");
        line_with(&screen, &[" x "]);
        line_with(&screen, &[" z "]);
    }
}

#[test]
fn odd_values_do_not_panic() {
    let long = "a notice with a very-long-word-that-does-not-fit-on-any-line-of-a-small-terminal-at-all ".repeat(4);
    let mut many = channels(60.0, Some(3));
    for k in 0..40 {
        many.push(ChannelStatus { channel: 100 + k, prn: 200 + k, ..many[0] });
    }
    let nan_axis = AxisProgress {
        shaken_s: f64::NAN,
        gamma_hz_per_mps2: Some(f64::NAN),
        sigma_hz_per_mps2: Some(f64::INFINITY),
        observable: true,
        meets_target: false,
        more_s: Some(f64::INFINITY),
        now_gamma_hz_per_mps2: Some(f64::NAN),
        now_sigma_hz_per_mps2: Some(f64::NEG_INFINITY),
    };
    let zero_sigma = AxisProgress { sigma_hz_per_mps2: Some(0.0), ..nan_axis };
    let odd = [
        LiveView {
            axes: [nan_axis, zero_sigma, AxisProgress { sigma_hz_per_mps2: None, ..nan_axis }],
            target_sigma_hz_per_mps2: f64::NAN,
            shaking: Shaking { frequency_hz: Some(f64::NAN), rms_mps2: [f64::INFINITY; 3], ..mid_session().shaking },
            peak_phase_rad: f64::NAN,
            channels: many.clone(),
            batch: Some(BatchVerdict::new(
                f64::NAN,
                Measurement::TrackingError,
                vec![gsens_calib::Warning { code: gsens_calib::WarningCode::NotFinite, message: long.clone() }; 6],
            )),
            notices: (vec![long.clone(); 5], u64::MAX),
            received: (u64::MAX, u64::MAX),
            ubx: None,
            ..mid_session()
        },
        LiveView {
            peak_phase_rad: 50.0,
            range_rad: 0.0,
            target_sigma_hz_per_mps2: 0.0,
            shaking: Shaking { frequency_hz: Some(0.0), several_axes: true, axis: None, ..Shaking::default() },
            channels: many,
            batch: None,
            batch_error: Some(long.clone()),
            ..waiting()
        },
    ];
    for view in &odd {
        for (w, h) in [(100, 30), (80, 24), (40, 12), (20, 5), (1, 1), (0, 0), (300, 80)] {
            assert_eq!(render_text(view, w, h).lines().count(), usize::from(h));
        }
    }
    // Forty-odd channels at 80x24: the table says how many it could not show.
    line_with(&render_text(&odd[0], 80, 24), &["channels:", "not shown"]);
}

/// A UBX stream's session has no tracking rows: the channels panel says
/// so, and the status line gives the stream's counts (the plain line's
/// words, `UbxStatus::summary`).
#[test]
fn a_ubx_session_shows_its_stream_in_the_status_line() {
    let mut view = waiting();
    let ubx = gsens_live::UbxStatus {
        bytes: 123_456,
        frames: 677,
        checksum_failures: 1,
        skipped: 2,
        epochs: 150,
        tracks: 7,
        identified_loop: None,
    };
    view.ubx = Some(ubx.clone());
    let screen = render_text(&view, 100, 30);
    assert!(screen.contains("a UBX stream: its tracks below"), "{screen}");
    let status = format!("UBX: {}", ubx.summary());
    assert_eq!(status, "UBX: 7 tracks, 677 frames, 1 bad checksums, 2 skipped");
    assert!(screen.contains(&status), "{screen}");
}
