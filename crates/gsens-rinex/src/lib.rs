//! # gsens-rinex
//!
//! RINEX observation files for gsens: every system and signal's carrier
//! phase, Doppler, pseudorange and C/N0 with their flags, read into
//! [`gsens_io::ObservationLog`] ([`read_rinex_file`], [`read_rinex`]). A
//! receiver adapter not yet wired to the calibration.
//!
//! # Reading
//!
//! The `rinex` crate parses the file: RINEX 3.x and 2.x observation files,
//! plain or Hatanaka-compressed (CRINEX, detected from the header). Each
//! (satellite, observation code) of the file becomes one
//! [`gsens_io::SatelliteSeries`]: `L` the carrier phase \[cycles\], `C` the
//! pseudorange \[m\], `D` the Doppler \[Hz\], `S` the C/N0 \[dB-Hz\], as the
//! file states them — Doppler positive for an approaching satellite (RINEX
//! 3.04 §3.4), phase changing in the same sense as the range (§3.3). A
//! RINEX 2 code is its band alone (`L1`, `C1` → `1`); its P-code
//! pseudoranges are skipped and counted (the C/A code's is kept). `t_s`
//! comes from the epoch in the header's time system, converted to GPS time
//! (GLONASS's UTC(SU) and others with the leap seconds the crate knows).
//!
//! Carriers ("Signals"): GLONASS G1/G2 take their frequency channel k from
//! the header's `GLONASS SLOT / FRQ #`; a GLONASS satellite the header does
//! not list, a band the system does not define and NavIC's S band are skipped
//! and counted.
//!
//! The header must parse: a file that is not RINEX, or not an observation
//! file, is an error naming it (and the line, where the crate names one); so
//! is an input on which the crate panics (it slices some malformed lines
//! unchecked: the panic is caught, its message printed by the panic hook). An
//! epoch the crate cannot decode is skipped and counted with its line in the
//! file. A field the crate cannot read as a number is absent from its
//! epoch, as a blank one is.
//!
//! # Flags and events
//!
//! The phase's loss-of-lock indicator (LLI) becomes
//! [`obs_flags`](gsens_io::obs_flags) bits 0…2 unchanged (loss of lock,
//! half-cycle ambiguity, anti-spoofing / BOC tracking); its signal strength
//! indicator (1…9, RINEX 3.04 §5.7; the pseudorange's where the phase has
//! none; 0 where blank) is kept in `strength`. A signal without a phase or a
//! pseudorange in an epoch has `PHASE_INVALID` or `PSEUDORANGE_INVALID`.
//!
//! Epoch flags: 0 read; 1 (power failure since the previous epoch) read with
//! `LOSS_OF_LOCK` on every signal; 2–5 (events with their special records)
//! and 6 (cycle slip records) skipped and counted. A step of the epoch line's
//! receiver clock offset by more than [`CLOCK_JUMP_S`] is reported as a
//! [`gsens_io::ClockEvent`].
//!
//! # Signals
//!
//! RINEX 3.04 Tables 4–10: GPS `1C` L1 C/A, `2S`/`2L`/`2X` L2C, `5I`/`5Q`
//! L5, other L1/L2/L5 codes by frequency; GLONASS `1x`/`2x` G1/G2 with k,
//! bands 4, 6, 3 (G1a, G2a, G3) by frequency; Galileo `1B`/`1C` E1, `5I`/`5Q`
//! E5a, `7I`/`7Q` E5b, bands 8 and 6 by frequency; BeiDou `2I` B1I, `1P`/
//! `1D`/`1X` B1C, `5P`/`5D`/`5X` B2a, `6I` B3I, bands 7 and 8 by frequency;
//! QZSS `1Z` L1S (`L1SAIF`), L1/L2/L5/L6 by frequency; SBAS L1 and L5; NavIC
//! L5.
#![deny(missing_docs)]

mod read;
mod signals;

pub use read::{CLOCK_JUMP_S, RinexError, read_rinex, read_rinex_bytes, read_rinex_file};
