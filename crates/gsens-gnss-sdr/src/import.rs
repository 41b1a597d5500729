//! GNSS-SDR tracking dumps → gsens's tracking schema
//! (`t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`, docs/conventions.md).
//!
//! # Records, tracks and stages
//!
//! A dump holds one channel's loop updates. It is cut into *tracks* (one
//! satellite tracked without interruption) where the PRN changes or the
//! sample counter jumps by more than one integration (the channel lost lock
//! and went back to acquisition). Within a track, each record's integration
//! length is the sample-counter step to the previous record (the first
//! record: 1 ms): 1 ms during the pull-in, `extend_correlation_symbols` ms
//! once GNSS-SDR has synchronized to the data bits and switched to the narrow
//! loop (`pll_bw_narrow_hz`). A record is converted to
//!
//! - `t_s`: the middle of its integration, (n − Δn/2)/fs with n the sample
//!   counter at its end (`PRN_start_sample_count`) and Δn its length, in the
//!   receiver's sample time (sample 0 of the file at t = 0);
//! - `phase_err_rad` = 2π·`carr_error_hz` (the discriminator output in cycles;
//!   its sign is θ_signal − θ_replica, docs/conventions.md's);
//! - `cn0_dbhz` = `CN0_SNV_dB_Hz`; the elevation is unknown (empty);
//! - `carrier_lock_test`, an extra column ([`write_imported_csv`]).
//!
//! # What is kept
//!
//! Only the records of the loop the estimator models: the narrow stage after
//! bit synchronization (or, without extended integration, the 1 ms loop),
//! minus its first seconds ([`ImportSettings::settle_time_s`]: the switch's
//! transient). A record whose lock test or C/N0 is below the thresholds is
//! dropped; a track in which they fail for more than
//! 1 − [`ImportSettings::min_good_fraction`] of the records is a false track
//! (a lock on a sidelobe, a cross-correlation peak, a loop that never pulled
//! in) and is dropped whole; a track that never reached the narrow stage is
//! dropped too. Every track is reported with what became of it and why.
//!
//! # A common epoch grid
//!
//! Each channel's integrations end on its own satellite's code epochs, so
//! channels are not sampled at the same instants. [`resample`] puts every
//! track on the common grid t = j·T (T the narrow integration time) by
//! four-point cubic (Lagrange) interpolation between consecutive records (linear at a
//! track's ends; nothing across a dropped record): for the slow phase errors
//! of a calibration (≈ 1 Hz at 50 Hz) the interpolation error is of order
//! (ωT)⁴ ≈ 1e-4 relative, where linear interpolation would bias φ by up to
//! (ωT)²/8 ≈ 0.2 %.

use std::path::Path;

use serde::Serialize;

use gsens_core::gnss_sdr::{GnssSdrPll, GnssSdrStage};
use gsens_io::TrackingRow;

use crate::conf::TrackingConf;
use crate::dump::{DumpLayout, TrackingDump, find_dumps, read_dump};
use crate::error::GnssSdrError;

/// How dumps are converted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportSettings {
    /// Sampling rate of the tracking \[Hz\].
    pub fs_hz: f64,
    /// The tracking configuration that produced the dumps.
    pub tracking: TrackingConf,
    /// Records below this C/N0 are dropped \[dB-Hz\].
    pub min_cn0_dbhz: f64,
    /// Records whose carrier lock test is below this are dropped.
    pub min_lock_test: f64,
    /// Time dropped after the switch to the modelled stage \[s\]; `None`:
    /// five time constants of the modelled loop's slowest mode, at least 1 s
    /// ([`ImportSettings::settle_time_s`]).
    pub settle_s: Option<f64>,
    /// Tracks whose modelled records pass the thresholds less often than this are false tracks.
    pub min_good_fraction: f64,
    /// The dumps' record layout; `None`: detect it.
    #[serde(skip)]
    pub layout: Option<DumpLayout>,
}

impl ImportSettings {
    /// Default thresholds (C/N0 ≥ 25 dB-Hz, lock test ≥ 0.85 as GNSS-SDR's own
    /// lock detector, 2 s of settling, 90 % good records) for `tracking` at `fs_hz`.
    pub fn new(fs_hz: f64, tracking: TrackingConf) -> Self {
        ImportSettings {
            fs_hz,
            tracking,
            min_cn0_dbhz: 25.0,
            min_lock_test: 0.85,
            settle_s: None,
            min_good_fraction: 0.9,
            layout: None,
        }
    }

    /// The default thresholds for dumps made with the configuration file
    /// `conf` (GNSS-SDR's defaults when `None`), at the sampling rate
    /// `fs_hz` or, when `None`, the configuration's.
    pub fn from_conf(conf: Option<&Path>, fs_hz: Option<f64>) -> Result<Self, GnssSdrError> {
        let tracking = match conf {
            Some(p) => crate::GnssSdrConf::read(p)?.tracking()?,
            None => TrackingConf::defaults(),
        };
        let fs_hz = fs_hz.or(tracking.fs_hz).ok_or(GnssSdrError::UnknownSamplingRate)?;
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(GnssSdrError::Setting { name: "the sampling rate", value: fs_hz, expected: "positive" });
        }
        Ok(ImportSettings::new(fs_hz, tracking))
    }

    /// The integration time of the modelled stage \[s\].
    pub fn interval_s(&self) -> f64 {
        self.tracking.narrow_interval_s()
    }

    /// The modelled stage of GNSS-SDR's loop (after bit synchronization).
    pub fn stage(&self) -> GnssSdrStage {
        let t = &self.tracking;
        GnssSdrStage { order: t.pll_filter_order, bw_hz: t.narrow_bw_hz(), symbols: t.extend_correlation_symbols }
    }

    /// The settling time in use \[s\]: [`ImportSettings::settle_s`], or five
    /// time constants of the modelled loop's slowest mode, at least 1 s (the
    /// switch to the narrow loop starts a transient the models do not know:
    /// 13 s for GNSS-SDR's lightly damped 3rd-order 3 Hz loop, 1.3 s for its
    /// 2nd-order one).
    pub fn settle_time_s(&self) -> f64 {
        self.settle_s.unwrap_or_else(|| match GnssSdrPll::new(self.stage()) {
            Ok(p) => p.settling_time_s(5.0).clamp(1.0, 60.0),
            Err(_) => 2.0,
        })
    }
}

/// One converted record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImportedRow {
    /// Middle of the integration \[s\].
    pub t_s: f64,
    /// Channel (from the dump's file name).
    pub channel: u32,
    /// PRN.
    pub prn: u32,
    /// C/N0 \[dB-Hz\].
    pub cn0_dbhz: f64,
    /// Phase error θ_signal − θ_replica \[rad\].
    pub phase_err_rad: f64,
    /// Carrier lock test.
    pub lock_test: f64,
    /// Integration length \[ms\].
    pub symbols: u32,
    /// Index of the track in [`Imported::tracks`].
    pub track: usize,
}

impl ImportedRow {
    /// The record as a row of `tracking.csv` (elevation unknown).
    pub fn tracking_row(&self) -> gsens_io::TrackingRow {
        gsens_io::TrackingRow {
            t_s: self.t_s,
            channel: self.channel,
            prn: self.prn,
            cn0_dbhz: self.cn0_dbhz,
            elev_deg: None,
            phase_err_rad: self.phase_err_rad,
        }
    }
}

/// What became of one track.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackSummary {
    /// The dump file.
    pub file: String,
    /// Channel.
    pub channel: u32,
    /// PRN.
    pub prn: u32,
    /// Time of its first record \[s\].
    pub start_s: f64,
    /// Time of the first record of the modelled stage \[s\] (`None`: never reached).
    pub switch_s: Option<f64>,
    /// Time of its last record \[s\].
    pub end_s: f64,
    /// Records in the track.
    pub records: usize,
    /// Records of the modelled stage after the settling time.
    pub modelled_records: usize,
    /// Of those, the records that pass the lock and C/N0 thresholds.
    pub good_records: usize,
    /// Mean C/N0 over the modelled records \[dB-Hz\] (NaN when none).
    pub mean_cn0_dbhz: f64,
    /// Whether its rows are kept.
    pub used: bool,
    /// `"used"` or why not.
    pub reason: String,
}

/// Converted dumps.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Imported {
    /// The kept rows, by time then channel.
    pub rows: Vec<ImportedRow>,
    /// Every track found.
    pub tracks: Vec<TrackSummary>,
    /// Integration time of the modelled stage \[s\].
    pub interval_s: f64,
}

/// Converts one decoded dump (see the module docs); `track_base` numbers its tracks.
pub fn import_dump(
    dump: &TrackingDump,
    settings: &ImportSettings,
    track_base: usize,
) -> (Vec<ImportedRow>, Vec<TrackSummary>) {
    let fs = settings.fs_hz;
    let samples_per_ms = fs * 1e-3;
    let ext = settings.tracking.extend_correlation_symbols.max(1);
    let channel = dump.channel.unwrap_or(0);
    let settle_s = settings.settle_time_s();
    let mut rows = Vec::new();
    let mut tracks = Vec::new();
    let recs = &dump.records;
    let mut i = 0;
    while i < recs.len() {
        // One track: records i..j.
        let mut j = i + 1;
        let mut symbols = vec![1u32];
        while j < recs.len() {
            let dn = recs[j].prn_start_sample_count - recs[j - 1].prn_start_sample_count;
            let s = (dn as f64 / samples_per_ms).round().max(1.0) as u32;
            let last = *symbols.last().expect("non-empty");
            let restart = recs[j].prn != recs[i].prn || s > ext + 1 || (ext > 1 && last == ext && s == 1);
            if restart {
                break;
            }
            symbols.push(if ext > 1 && s >= ext - 1 { ext } else { s });
            j += 1;
        }
        let track = track_base + tracks.len();
        let t_mid = |k: usize| {
            let dn = if k == i {
                f64::from(symbols[0]) * samples_per_ms
            } else {
                (recs[k].prn_start_sample_count - recs[k - 1].prn_start_sample_count) as f64
            };
            (recs[k].prn_start_sample_count as f64 - 0.5 * dn) / fs
        };
        let modelled_symbols = if ext > 1 { ext } else { 1 };
        let switch = (i..j).find(|&k| symbols[k - i] == modelled_symbols && (ext == 1 || k > i));
        // Without extended integration the modelled loop runs from the start,
        // after the FLL pull-in when there is one.
        let fll_s =
            if ext == 1 && settings.tracking.enable_fll_pull_in { settings.tracking.pull_in_time_s } else { 0.0 };
        let switch_s = switch.map(|k| t_mid(k) + fll_s);
        let (mut modelled, mut good, mut cn0_sum) = (0usize, 0usize, 0.0);
        let mut track_rows = Vec::new();
        if let (Some(k0), Some(t0)) = (switch, switch_s) {
            for k in k0..j {
                let t = t_mid(k);
                if t < t0 + settle_s - 1e-9 {
                    continue;
                }
                let r = &recs[k];
                modelled += 1;
                cn0_sum += r.cn0_dbhz;
                if r.carrier_lock_test >= settings.min_lock_test && r.cn0_dbhz >= settings.min_cn0_dbhz {
                    good += 1;
                    track_rows.push(ImportedRow {
                        t_s: t,
                        channel,
                        prn: r.prn,
                        cn0_dbhz: r.cn0_dbhz,
                        phase_err_rad: core::f64::consts::TAU * r.carr_error_cycles,
                        lock_test: r.carrier_lock_test,
                        symbols: symbols[k - i],
                        track,
                    });
                }
            }
        }
        let frac = if modelled > 0 { good as f64 / modelled as f64 } else { 0.0 };
        let reason = if switch.is_none() {
            format!(
                "never reached the modelled loop ({} ms integrations{}): no bit synchronization in its {} records",
                modelled_symbols,
                if ext > 1 {
                    format!(", pll_bw_narrow_hz = {}", settings.tracking.pll_bw_narrow_hz)
                } else {
                    String::new()
                },
                j - i
            )
        } else if modelled == 0 {
            format!("fewer than {settle_s:.1} s of the modelled loop (its settling time)")
        } else if frac < settings.min_good_fraction {
            format!(
                "false track: lock test ≥ {} and C/N0 ≥ {} dB-Hz in only {:.0} % of its {} modelled records",
                settings.min_lock_test,
                settings.min_cn0_dbhz,
                100.0 * frac,
                modelled
            )
        } else {
            "used".to_owned()
        };
        let used = reason == "used";
        if used {
            rows.extend(track_rows);
        }
        tracks.push(TrackSummary {
            file: dump.file.clone(),
            channel,
            prn: recs[i].prn,
            start_s: t_mid(i),
            switch_s,
            end_s: t_mid(j - 1),
            records: j - i,
            modelled_records: modelled,
            good_records: good,
            mean_cn0_dbhz: if modelled > 0 { cn0_sum / modelled as f64 } else { f64::NAN },
            used,
            reason,
        });
        i = j;
    }
    (rows, tracks)
}

/// Reads every dump `<prefix><channel>.dat` in `dir` (the prefix from the
/// configuration's `dump_filename` when it has one) and converts them.
pub fn import_dir(dir: &Path, settings: &ImportSettings) -> Result<Imported, GnssSdrError> {
    let prefix = settings
        .tracking
        .dump_filename
        .as_deref()
        .and_then(|f| Path::new(f).file_name().and_then(|n| n.to_str()).map(str::to_owned));
    let files = match find_dumps(dir, prefix.as_deref()) {
        Ok(f) => f,
        // A configuration's prefix that matches nothing: take any dump.
        Err(GnssSdrError::NoDumps { .. }) if prefix.is_some() => find_dumps(dir, None)?,
        Err(e) => return Err(e),
    };
    let mut rows = Vec::new();
    let mut tracks = Vec::new();
    for (_, path) in &files {
        let dump = read_dump(path, settings.layout.as_ref())?;
        let (r, t) = import_dump(&dump, settings, tracks.len());
        rows.extend(r);
        tracks.extend(t);
    }
    if rows.is_empty() {
        let reason = tracks
            .iter()
            .map(|t| format!("channel {} (PRN {}): {}", t.channel, t.prn, t.reason))
            .collect::<Vec<_>>()
            .join("; ");
        return Err(GnssSdrError::NothingUsable {
            dir: dir.display().to_string(),
            reason: if reason.is_empty() { "the dumps hold no record".into() } else { reason },
        });
    }
    rows.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.channel.cmp(&b.channel)));
    Ok(Imported { rows, tracks, interval_s: settings.interval_s() })
}

/// Puts every track on the common grid t = j·`interval_s` (module docs): rows
/// of `tracking.csv` (elevation unknown) by time then channel.
pub fn resample(imported: &Imported, interval_s: f64) -> Vec<TrackingRow> {
    let mut by_track: Vec<Vec<&ImportedRow>> = vec![Vec::new(); imported.tracks.len()];
    for r in &imported.rows {
        by_track[r.track].push(r);
    }
    let mut out = Vec::new();
    let t = interval_s;
    let consecutive = |a: &ImportedRow, b: &ImportedRow| {
        let d = b.t_s - a.t_s;
        d > 0.75 * t && d < 1.25 * t
    };
    for rows in by_track.iter().filter(|r| r.len() >= 2) {
        for k in 0..rows.len() - 1 {
            let (a, b) = (rows[k], rows[k + 1]);
            if !consecutive(a, b) {
                continue;
            }
            let j0 = (a.t_s / t).ceil() as i64;
            let j1 = (b.t_s / t).ceil() as i64; // grid points in [a, b)
            for jj in j0..j1 {
                let tg = jj as f64 * t;
                let u = (tg - a.t_s) / (b.t_s - a.t_s);
                let prev = (k > 0 && consecutive(rows[k - 1], a)).then(|| rows[k - 1]);
                let next = (k + 2 < rows.len() && consecutive(b, rows[k + 2])).then(|| rows[k + 2]);
                let phase = match (prev, next) {
                    (Some(p), Some(n)) => cubic(p.phase_err_rad, a.phase_err_rad, b.phase_err_rad, n.phase_err_rad, u),
                    _ => a.phase_err_rad + u * (b.phase_err_rad - a.phase_err_rad),
                };
                out.push(TrackingRow {
                    t_s: tg,
                    channel: a.channel,
                    prn: a.prn,
                    cn0_dbhz: a.cn0_dbhz + u * (b.cn0_dbhz - a.cn0_dbhz),
                    elev_deg: None,
                    phase_err_rad: phase,
                });
            }
        }
    }
    out.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.channel.cmp(&b.channel)));
    // Two tracks of one channel cannot overlap in time, but keep the first if they touch.
    out.dedup_by(|b, a| a.t_s == b.t_s && a.channel == b.channel);
    out
}

/// Four-point Lagrange (cubic) interpolation between p1 (u = 0) and p2
/// (u = 1) of samples at u = −1, 0, 1, 2: exact for cubics.
fn cubic(p0: f64, p1: f64, p2: f64, p3: f64, u: f64) -> f64 {
    let (um, u1, u2) = (u + 1.0, u - 1.0, u - 2.0);
    -p0 * u * u1 * u2 / 6.0 + p1 * um * u1 * u2 / 2.0 - p2 * um * u * u2 / 2.0 + p3 * um * u * u1 / 6.0
}

/// Writes converted records as `tracking.csv` with a seventh column,
/// `carrier_lock_test` (readers of the schema ignore extra columns); the
/// elevation is empty. Written by [`gsens_io::TrackingWriter`]: numbers in
/// the shortest round-trip form, and a non-finite value is refused
/// (`InvalidInput`).
pub fn write_imported_csv<W: std::io::Write>(w: W, rows: &[ImportedRow]) -> std::io::Result<W> {
    let mut out = gsens_io::TrackingWriter::with_extra_columns(w, &["carrier_lock_test"])?;
    for r in rows {
        out.write_row_with(&r.tracking_row(), &[r.lock_test])?;
    }
    out.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dump::TrackingRecord;

    fn rec(n: u64, e: f64, cn0: f64, lock: f64, prn: u32) -> TrackingRecord {
        TrackingRecord {
            abs_ve: 0.0,
            abs_e: 0.0,
            abs_p: 0.0,
            abs_l: 0.0,
            abs_vl: 0.0,
            prompt_i: 0.0,
            prompt_q: 0.0,
            prn_start_sample_count: n,
            acc_carrier_phase_rad: 0.0,
            carrier_doppler_hz: 1000.0,
            carrier_doppler_rate_hz_per_s: 0.0,
            code_freq_chips_per_s: 1.023e6,
            code_freq_rate_chips_per_s2: 0.0,
            carr_error_cycles: e,
            carr_error_filt_hz: 1000.0,
            code_error_chips: 0.0,
            code_error_filt_chips: 0.0,
            cn0_dbhz: cn0,
            carrier_lock_test: lock,
            aux1: 0.0,
            aux2: n as f64,
            prn,
        }
    }

    fn settings() -> ImportSettings {
        let mut tc = TrackingConf::defaults();
        tc.extend_correlation_symbols = 20;
        tc.pll_bw_narrow_hz = 3.0;
        let mut s = ImportSettings::new(1.0e6, tc);
        s.settle_s = Some(0.1);
        s
    }

    /// A dump: `pull_in` 1 ms records then `narrow` 20 ms records, starting at sample `start`.
    fn records(start: u64, pull_in: usize, narrow: usize, prn: u32, lock: f64) -> Vec<TrackingRecord> {
        let mut v = Vec::new();
        let mut n = start;
        for _ in 0..pull_in {
            n += 1000;
            v.push(rec(n, 0.01, 45.0, lock, prn));
        }
        for k in 0..narrow {
            n += 20_000;
            v.push(rec(n, 0.02 * (k as f64 * 0.1).sin(), 44.0, lock, prn));
        }
        v
    }

    #[test]
    fn stages_times_and_false_tracks() {
        let s = settings();
        let mut recs = records(0, 100, 50, 5, 0.95);
        // The channel loses lock and restarts on another satellite, which never syncs.
        recs.extend(records(recs.last().unwrap().prn_start_sample_count + 50_000, 300, 0, 9, 0.95));
        // Then a false lock: synchronized, but the lock test is poor.
        recs.extend(records(recs.last().unwrap().prn_start_sample_count + 70_000, 50, 40, 11, 0.3));
        let d = TrackingDump { file: "trk_ch_2.dat".into(), channel: Some(2), layout: "x".into(), records: recs };
        let (rows, tracks) = import_dump(&d, &s, 0);
        assert_eq!(tracks.len(), 3);
        assert!(tracks[0].used, "{}", tracks[0].reason);
        assert!(tracks[1].reason.contains("no bit synchronization"), "{}", tracks[1].reason);
        assert!(tracks[2].reason.contains("false track") && tracks[2].reason.contains("0 %"), "{}", tracks[2].reason);
        // Track 0: first 20 ms record ends at sample 120 000, its middle at 0.110 s; settling 0.1 s.
        assert!((tracks[0].switch_s.unwrap() - 0.110).abs() < 1e-12);
        assert_eq!(tracks[0].modelled_records, 45);
        assert_eq!(rows.len(), 45);
        assert!(rows.iter().all(|r| r.channel == 2 && r.prn == 5 && r.symbols == 20));
        assert!((rows[0].t_s - 0.210).abs() < 1e-12, "{}", rows[0].t_s);
        let want = core::f64::consts::TAU * 0.02 * (5.0f64 * 0.1).sin();
        assert!((rows[0].phase_err_rad - want).abs() < 1e-12);
    }

    #[test]
    fn resampling_is_exact_for_cubics_and_skips_gaps() {
        let s = settings();
        let tracks = vec![TrackSummary {
            file: String::new(),
            channel: 0,
            prn: 1,
            start_s: 0.0,
            switch_s: Some(0.0),
            end_s: 1.0,
            records: 0,
            modelled_records: 0,
            good_records: 0,
            mean_cn0_dbhz: 40.0,
            used: true,
            reason: "used".into(),
        }];
        // Records at 0.007 + k·0.02 except one dropped; φ a cubic in t.
        let f = |t: f64| 0.1 + 2.0 * t - 3.0 * t * t + 1.5 * t * t * t;
        let rows: Vec<ImportedRow> = (0..30)
            .filter(|&k| k != 20)
            .map(|k| {
                let t = 0.007 + 0.02 * k as f64;
                ImportedRow {
                    t_s: t,
                    channel: 0,
                    prn: 1,
                    cn0_dbhz: 40.0,
                    phase_err_rad: f(t),
                    lock_test: 1.0,
                    symbols: 20,
                    track: 0,
                }
            })
            .collect();
        let imp = Imported { rows, tracks, interval_s: s.interval_s() };
        let g = resample(&imp, 0.02);
        // Interior points with two neighbours on each side are exact for a cubic.
        for r in &g {
            let j = (r.t_s / 0.02).round() as i64;
            assert!((r.t_s - j as f64 * 0.02).abs() < 1e-15);
            let near_gap = (18..=22).contains(&j) || j <= 1 || j >= 28;
            if !near_gap {
                assert!((r.phase_err_rad - f(r.t_s)).abs() < 1e-12, "{j}");
            }
        }
        // Grid points 0.40 and 0.42 fall in the gap left by the record at 0.407: none.
        assert!(g.iter().all(|r| (r.t_s - 0.40).abs() > 1e-9));
        assert_eq!(g.len(), 27);
    }

    #[test]
    fn csv_writers_go_through_the_tracking_writer() {
        let row = |t_s: f64, lock_test: f64| ImportedRow {
            t_s,
            channel: 1,
            prn: 31,
            cn0_dbhz: 52.60313415527344,
            phase_err_rad: -0.10144092814183144,
            lock_test,
            symbols: 20,
            track: 0,
        };
        let rows = [row(7.39735791015625, 0.9902583956718445), row(7.41735791015625, 1.0)];
        let text = String::from_utf8(write_imported_csv(Vec::new(), &rows).unwrap()).unwrap();
        // The bytes the former hand-written writer produced.
        let mut want = String::from("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,carrier_lock_test\n");
        for r in &rows {
            want += &format!("{},{},{},{},,{},{}\n", r.t_s, r.channel, r.prn, r.cn0_dbhz, r.phase_err_rad, r.lock_test);
        }
        assert_eq!(text, want);
        // Every number is checked finite, the extra column too.
        let e = write_imported_csv(Vec::new(), &[row(7.4, f64::NAN)]).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("carrier_lock_test"), "{e}");
        let grid = |cn0_dbhz| gsens_io::TrackingRow {
            t_s: 0.02,
            channel: 0,
            prn: 1,
            cn0_dbhz,
            elev_deg: None,
            phase_err_rad: -0.25,
        };
        let e = gsens_io::write_tracking_csv(Vec::new(), &[grid(f64::INFINITY)]).unwrap_err();
        assert!(e.to_string().contains("cn0_dbhz"), "{e}");
        let text = gsens_io::write_tracking_csv(Vec::new(), &[grid(40.5)]).unwrap();
        assert_eq!(text, b"t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n0.02,0,1,40.5,,-0.25\n");
    }
}
