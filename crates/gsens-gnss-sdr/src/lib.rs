//! # gsens-gnss-sdr
//!
//! Interoperability with GNSS-SDR (<https://gnss-sdr.org>), the open-source
//! software receiver:
//!
//! - `conf`: its configuration files — the carrier-loop settings that
//!   produced a dump, and a configuration that tracks `gsens simulate --iq`
//!   files;
//! - `dump`: its tracking dumps (`Tracking_1C.dump=true`, `trk_ch_N.dat`),
//!   every record layout from 0.0.17 to 0.0.21 (and the Kalman, FPGA, GLONASS,
//!   GPU and TCP blocks), recognised from the file itself, with errors that
//!   name the file, record and byte offset;
//! - [`mat`]: the `.mat` copies of the dumps (MATLAB v7.3 = HDF5,
//!   `dump_mat=true`), read by a built-in reader of the part of HDF5 they use
//!   to exactly the records of the `.dat`;
//! - `import`: dumps → the `tracking.csv` schema (φ in rad, time at the
//!   middle of each integration), each track judged by GNSS-SDR's own lock
//!   detector replayed with the configuration's settings, with a reason;
//! - `calibrate`: the estimate from the dumps with GNSS-SDR's own loop
//!   modelled exactly (the adapter between these files and `gsens_calib`);
//! - [`monitor`]: its tracking monitor (`TrackingMonitor.enable_monitor`),
//!   protobuf over UDP, received live and converted to the same rows;
//! - the exact models of its carrier loops live in
//!   [`gsens_core::gnss_sdr`] (no_std, shared with the estimator).
//!
//! # Configuration files
//!
//! GNSS-SDR configuration files (`.conf`): the reader of what decides the
//! carrier loop of each tracking record, and the writer of a configuration
//! that tracks a file of `gsens simulate --iq`.
//!
//! ## Format
//!
//! GNSS-SDR reads an INI file: `[section]` lines, `key=value` lines with keys
//! such as `Tracking_1C.pll_bw_hz`, comments from `;` or `#` at the start of a
//! line, and a `;` anywhere in a value starts a comment too (the shipped
//! examples write `Tracking_1C.pll_bw_hz=40.0;`). Keys are case-sensitive and
//! the last occurrence of a key wins. Numbers are read like a C++ stream reads
//! them: the longest numeric prefix of the value.
//!
//! ## Tracking settings and their defaults
//!
//! [`TrackingConf`] collects the `Tracking_1C.*` keys that shape the carrier
//! loop of GNSS-SDR 0.0.17's `GPS_L1_CA_DLL_PLL_Tracking` (the
//! `dll_pll_veml_tracking` block). Where the file leaves a key out, the
//! defaults are GNSS-SDR 0.0.17's: `pll_filter_order` 3, `pll_bw_hz` 35 and
//! `pll_bw_narrow_hz` 5 (measured: the loop-filter coefficients fitted on the
//! dumps of a run without these keys are those of a 3rd-order 35 Hz loop at
//! 1 ms and a 5 Hz one at 20 ms, residual 1e-4 Hz), `extend_correlation_symbols`
//! 1 (GNSS-SDR's documentation; not measured), `pull_in_time_s` 10 s
//! (`dll_pll_conf.h`).
//!
//! ## The lock detector
//!
//! `LockDetectorConf` holds the keys of the tracking's loss-of-lock rule
//! (read in GNSS-SDR's `dll_pll_conf.cc`; their defaults are the command-line
//! flags of `gnss_sdr_flags.cc`, the same in 0.0.17 and 0.0.20):
//! `carrier_lock_th` 0.7, `cn0_min` 25 dB-Hz, `max_lock_fail` 50,
//! `max_carrier_lock_fail` 5000 and `cn0_samples` 20. GNSS-SDR reads the
//! integer ones as a C++ stream reads an `int` (`25.5` is 25); so does this
//! reader. How the rule is applied: `crate::import`.
//!
//! # Tracking dumps
//!
//! GNSS-SDR tracking dumps: the `.dat` files its DLL/PLL tracking writes with
//! `Tracking_1C.dump=true`, one per channel (`<dump_filename><channel>.dat`),
//! and (module [`crate::mat`]) the `.mat` copies it makes of
//! them at the end of a run (`dump_mat=true`, the default).
//!
//! ## Format
//!
//! A dump is a sequence of packed little-endian records, one per loop update
//! (every 1 ms until bit synchronization, then one per extended integration),
//! with no header. The layout is not stored in the file and has changed
//! between versions without a word in the changelog (GNSS-SDR issue #1006:
//! 0.0.21 appended two fields, and a user's reader that assumed the old
//! record got sample-counter steps twenty times too long from 0.0.21's
//! dumps), so the reader knows every layout of the versions and blocks it
//! was checked against ([`DumpLayout::known`]), keeps those whose record size
//! divides the file length, and checks every record of each for plausibility
//! ([`DumpLayout`]'s rules: PRN, finite correlators, discriminator and
//! lock-test ranges, a code rate, the sample counter increasing, and the
//! relations between fields that the writing block guarantees). A file that
//! no layout explains is refused with an error that lists every layout tried
//! and why it failed (file, record, byte offset, field); a truncated file, a
//! file appended by two versions and an empty file get errors of their own.
//!
//! ## Layouts
//!
//! Learned from GNSS-SDR's sources, tag by tag from v0.0.17 to v0.0.21 and the
//! `main`/`next` branches of May 2026 (`log_data` in
//! `src/algorithms/tracking/gnuradio_blocks/*.cc` and each block's
//! `save_matfile`, which names the fields), and the branch of PR #1071
//! (August 2026). Field names are GNSS-SDR's (the `.mat` variable names).
//!
//! [`DumpLayout::v0_0_17`], 96 bytes: `dll_pll_veml_tracking` 0.0.17 … 0.0.20
//! (the `GPS_L1_CA_DLL_PLL_Tracking` and every other `*_DLL_PLL_*Tracking`
//! adapter), and the same bytes with the same meanings from
//! `dll_pll_veml_tracking_fpga` 0.0.17 … 0.0.21 and the Kalman tracker
//! `kf_tracking` 0.0.18 … 0.0.21 (`kf_vtl_tracking` in 0.0.17), whose
//! Doppler and filter slots hold its Kalman state's Doppler:
//!
//! | field | type | unit |
//! | --- | --- | --- |
//! | `abs_VE`, `abs_E`, `abs_P`, `abs_L`, `abs_VL` | f32 | correlator magnitudes |
//! | `Prompt_I`, `Prompt_Q` | f32 | prompt correlator |
//! | `PRN_start_sample_count` | u64 | sample counter at the end of the integration |
//! | `acc_carrier_phase_rad` | f32 | rad |
//! | `carrier_doppler_hz` | f32 | Hz: the NCO command for the *next* integration |
//! | `carrier_doppler_rate_hz` | f32 | Hz/s |
//! | `code_freq_chips`, `code_freq_rate_chips` | f32 | chip/s, chip/s² |
//! | `carr_error_hz` | f32 | **cycles** (not Hz, whatever the name): the PLL discriminator atan(Q/I)/2π, θ_signal − θ_replica |
//! | `carr_error_filt_hz` | f32 | Hz: the loop filter output, which *is* the NCO command (`carrier_doppler_hz`, bit for bit) |
//! | `code_error_chips`, `code_error_filt_chips` | f32 | chips |
//! | `CN0_SNV_dB_Hz` | f32 | dB-Hz (0 until the estimator has filled its window) |
//! | `carrier_lock_test` | f32 | cos 2φ estimate, in \[−1, 1\] |
//! | `aux1` | f32 | (the remnant code phase \[samples\]) |
//! | `aux2` | f64 | (the sample counter again, = `PRN_start_sample_count`) |
//! | `PRN` | u32 | satellite |
//!
//! The Kalman trackers' records are these bytes with these meanings, so the
//! file cannot tell them from `dll_pll_veml_tracking`'s: the configuration's
//! `Tracking_1C.implementation` does (the importer refuses a Kalman tracker
//! there, `crate::conf`), which is why `estimate --gnss-sdr` needs the
//! configuration.
//!
//! (GNSS-SDR issue #734 asks why `carr_error_filt_hz` equals
//! `carrier_doppler_hz`: the block assigns the one to the other after every
//! filter update; the reader checks it, which tells this layout from byte
//! patterns of the same size.)
//!
//! [`DumpLayout::v0_0_21`], 108 bytes: `dll_pll_veml_tracking` from 0.0.21 on
//! (commit "Annotate TOW and WN in tracking dump", October 2025; unchanged on
//! `next` in May 2026 and on the PR #1071 branch in August 2026): the 96
//! bytes above, then `TOW_ms` (u64, the time of week from the telemetry when
//! `GNSS-SDR.tow_to_trk=true`, else 0; < 604 800 000) and `WN` (u32 in the
//! `.dat`, written as int32 to the `.mat`; the week number, 0 when unknown).
//! The changelog of 0.0.21 does not mention it. 0.0.22 (October 2026) was
//! released after the newest source read here; its notes list no dump change.
//!
//! [`DumpLayout::kf_cc`], 96 bytes: `gps_l1_ca_kf_tracking_cc` 0.0.17
//! (`GPS_L1_CA_KF_Tracking`), renamed `gps_l1_ca_gaussian_tracking_cc` from
//! 0.0.18 on: the same field sizes, other meanings — `PRN_start_sample_count`
//! is the counter at the *start* of the integration (`aux2` = it + the
//! integration length), the Doppler-rate slot is the Kalman Doppler rate
//! (`carrier_dopplerrate_hz2`), and the three slots after `code_freq_chips`
//! hold the discriminator in rad·2π (`carr_error_hz`), its variance
//! (`carr_noise_sigma2`) and the remnant carrier phase·2π (under the name
//! `carr_error_filt_hz`), as its `save_matfile` names them. It writes a
//! record every millisecond even while the channel is idle (all zeros).
//!
//! [`DumpLayout::legacy_88`], 88 bytes: the older blocks that write no
//! Doppler rate and no code-rate field — `glonass_l1_ca_dll_pll_tracking_cc`,
//! `glonass_l1/l2_ca_dll_pll_c_aid_tracking_cc/_sc` (0.0.17 … 0.0.20, removed
//! in 0.0.21), `gps_l1_ca_dll_pll_tracking_gpu_cc`,
//! `gps_l1_ca_tcp_connector_tracking_cc` and
//! `galileo_e1_tcp_connector_tracking_cc` (0.0.17 … 0.0.21): counter at the
//! start of the integration, `aux2` = it + the integration length.
//!
//! Only the two `dll_pll_veml_tracking` layouts come from the loop that
//! [`gsens_core::gnss_sdr`] models; the importer refuses the others with the
//! reason ([`DumpLayout::modelled`]). Other layouts can be given with
//! [`DumpLayout::parse_spec`].
//!
//! ## PR #1071 (frequency-error reduction)
//!
//! `Tracking_<sig>.f_error_step_num` (default 0, off; with
//! `f_error_doppler_step`, `f_error_accumulation`) adds a state that, once
//! per track right after the code alignment, holds the NCO at a few Doppler
//! offsets around the acquisition's estimate, accumulates |prompt|² for each
//! and keeps the strongest, with no loop-filter update and no dump record;
//! then the wide FLL/PLL stage starts as before. The loop after bit
//! synchronization, the one gsens models, is unchanged, and the first record
//! of a track is still the first update of the wide stage (the pull-in time
//! budget starts after the scan), so nothing in the model or the importer
//! depends on these keys.
//!
//! # From dumps to tracking rows
//!
//! GNSS-SDR tracking dumps → gsens's tracking schema
//! (`t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`, docs/conventions.md).
//!
//! ## Records, tracks and stages
//!
//! A dump holds one channel's records. Before bit synchronization GNSS-SDR
//! writes one per 1 ms loop update; after it one per 20 ms data bit, holding
//! the last of the 20/N updates of N = `extend_correlation_symbols` ms since
//! the previous record (module docs of [`gsens_core::gnss_sdr`]). A dump is
//! cut into *tracks* (one satellite tracked without interruption) where the
//! PRN changes or the sample counter steps by anything but 1 ms before bit
//! synchronization or one bit after it (the channel lost lock and went back to
//! acquisition). After bit synchronization the loop runs N ms integrations at
//! `pll_bw_narrow_hz` when N > 1; with N = 1 it keeps its 1 ms update and
//! `pll_bw_hz`. A record is converted to
//!
//! - `t_s`: the middle of its integration, (n − N₁·fs·1 ms/2)/fs with n the
//!   sample counter at its end (`PRN_start_sample_count`) and N₁ its
//!   integration in ms (1 before bit synchronization, N after), in the
//!   receiver's sample time (sample 0 of the file at t = 0);
//! - `phase_err_rad` = 2π·`carr_error_hz` (the discriminator output in cycles;
//!   its sign is θ_signal − θ_replica, docs/conventions.md's);
//! - `cn0_dbhz` = `CN0_SNV_dB_Hz`; the elevation is unknown (empty);
//! - `carrier_lock_test`, an extra column (`write_imported_csv`).
//!
//! ## What is kept
//!
//! A track is judged by the receiver's own rule: GNSS-SDR's lock detector,
//! with the configuration's `carrier_lock_th`, `max_carrier_lock_fail`,
//! `cn0_min` and `max_lock_fail` (GNSS-SDR's defaults when absent; options may
//! override them), is replayed over its records (`replay_lock_detector`).
//! Where GNSS-SDR would have declared a loss of lock, the track ends: that
//! record and the later ones are not tracking and are dropped. No record is
//! dropped for a low lock test or C/N0 alone: GNSS-SDR went on tracking
//! through them, and the lock test falls exactly while the board is shaken
//! (it is the smoothed cos 2φ). Whether a kept channel follows the signal the
//! others see is the session screening's judgement (`gsens-session`), not the
//! importer's.
//!
//! Of the tracking records, only those of the loop the estimator models are
//! kept, minus its first seconds ([`ImportSettings::settle_time_s`]: the
//! transient of the switch to it): with N > 1 the narrow stage from bit
//! synchronization on; with N = 1 the 1 ms loop from the end of GNSS-SDR's
//! pull-in transitory (`pull_in_time_s`, the FLL's time when
//! `enable_fll_pull_in`), its 1 ms records before bit synchronization thinned
//! to one per data bit on the lattice of the later ones, so that every kept
//! record holds the last of 20/N updates. A track that never reached the
//! modelled loop is dropped. Every track is reported with what became of it
//! (`TrackSummary::fate`) and the rule and values that decided
//! (`TrackSummary::reason`); when nothing is kept, the error gives one line
//! per channel and fate (`nothing_usable_reason`).
//!
//! ## A common epoch grid
//!
//! Each channel's integrations end on its own satellite's code epochs, so
//! channels are not sampled at the same instants. [`resample`] puts every
//! track on the common grid t = j·T (T = 20 ms, the record interval) by
//! four-point cubic (Lagrange) interpolation between consecutive records (linear at a
//! track's ends; nothing across a dropped record): for the slow phase errors
//! of a calibration (≈ 1 Hz at 50 Hz) the interpolation error is of order
//! (ωT)⁴ ≈ 1e-4 relative, where linear interpolation would bias φ by up to
//! (ωT)²/8 ≈ 0.2 %.
//!
//! # The estimate with GNSS-SDR's own loop
//!
//! The estimate from GNSS-SDR's tracking dumps with GNSS-SDR's own loop: the
//! dumps converted to the pipeline's tracking log ([`gnss_sdr_tracking_log`]),
//! the settings given the loop of the configuration they were made with
//! ([`with_gnss_sdr_loop`]), and what the conversion did kept in the result
//! document ([`Conversion::source`]).
#![deny(missing_docs)]

mod calibrate;
mod conf;
mod dump;
mod error;
mod export;
mod import;
mod input_phase;
pub mod mat;
pub mod monitor;
pub(crate) mod nco;

pub use calibrate::{
    Conversion, GnssSdrOutcome, calibrate_gnss_sdr, gnss_sdr_tracking_log, loop_stated_twice, with_gnss_sdr_loop,
};
pub use conf::{GnssSdrConf, IqConfOptions, TrackingConf, write_iq_conf};
pub use dump::{DumpLayout, TrackingDump, TrackingRecord, find_dumps, parse_dump, read_dump};
pub use error::{GnssSdrError, LayoutSpecError};
pub use export::Export;
pub use import::{
    ImportOverrides, ImportSettings, Imported, TrackFate, import_dir, import_dump, render_tracks, resample,
};
pub use input_phase::gnss_sdr_input_phases;
#[doc(hidden)]
pub use {import::import_dir_booked, nco::NcoBookkeeping};
