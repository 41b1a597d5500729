//! # gsens-ublox
//!
//! u-blox UBX logs for gsens: the receiver's carrier phase and Doppler
//! (UBX-RXM-RAWX) and its own IMU's accelerometer (UBX-ESF-RAW, or
//! UBX-ESF-MEAS), read into [`gsens_io::ObservationLog`] and
//! [`gsens_io::ImuSeries`] ([`read_ubx_file`], [`read_ubx`]), or as it
//! arrives in pieces from a serial port or a file being written
//! ([`UbxStream`]).
//!
//! # The log
//!
//! A UBX log is a stream of frames: sync `B5 62`, class, id, payload length
//! (U2, little endian), payload, and the 8-bit Fletcher checksum CK_A, CK_B
//! over class, id, length and payload (u-blox interface description, "UBX
//! checksum"). The `ublox` crate finds the frames, checks every checksum and
//! lays out the payloads (protocol 23). A frame with a bad checksum is
//! dropped and the search for the next sync goes on from its third byte; a
//! frame cut off at the end of the log, a payload whose length disagrees with
//! its contents and every message not read here (NAV-PVT, …) are skipped.
//! Everything skipped is counted by reason in the log's
//! [`ObservationLog::skipped`](gsens_io::ObservationLog), never an error, and
//! [`UbxLog::bytes_outside_frames`] counts the bytes that no valid frame
//! holds.
//!
//! # RXM-RAWX
//!
//! UBX-RXM-RAWX (0x02 0x15), one per measurement epoch: `rcvTow` (R8, s,
//! receiver time of week, steered close to GPS time), `week` (U2, GPS weeks),
//! `leapS`, `numMeas`, `recStat` (bit 1 `clkReset`: a clock reset, reported
//! as a [`gsens_io::ClockEvent`]), then per measurement (32 bytes):
//! `prMes` (R8, m), `cpMes` (R8, cycles), `doMes` (R4, Hz), `gnssId`, `svId`,
//! `sigId`, `freqId` (GLONASS k + 7), `locktime` (U2, ms, capped at 64500),
//! `cno` (U1, dB-Hz), the standard deviations and `trkStat` (bit 0 `prValid`,
//! 1 `cpValid`, 2 `halfCyc`, 3 `subHalfCyc`).
//!
//! Each (satellite, signal) becomes one [`gsens_io::SatelliteSeries`] named
//! as RINEX names it ("Signals"), `t_s` from `week` and `rcvTow`. The values
//! are the message's: `doMes` positive for an approaching satellite and
//! `cpMes` changing in the same sense as the pseudorange (d`cpMes`/dt ≈
//! −`doMes`), as the interface description defines them; a pseudorange or
//! phase without its valid bit is NaN, with
//! [`obs_flags::PSEUDORANGE_INVALID`](gsens_io::obs_flags) or
//! `PHASE_INVALID`. `halfCyc` clear sets `HALF_CYCLE_AMBIGUOUS`, `subHalfCyc`
//! `HALF_CYCLE_SUBTRACTED`. RXM-RAWX has no loss-of-lock bit: `LOSS_OF_LOCK`
//! is set where a valid phase follows an invalid one, or `locktime` fell
//! below its previous value or below the time since the track's previous
//! observation (the lock began after it).
//!
//! # Signals
//!
//! `gnssId`/`sigId` (interface description, "Signal identifiers") to RINEX 3
//! codes and carriers: GPS (0) L1C/A `1C`, L2 CL `2L`, L2 CM `2S`, L5 I `5I`,
//! L5 Q `5Q`; SBAS (1) L1C/A `1C` (PRN 120…158 as S20…S58); Galileo (2) E1 C
//! `1C`, E1 B `1B`, E5a I/Q `5I`/`5Q`, E5b I/Q `7I`/`7Q`; BeiDou (3) B1I D1/D2
//! `2I`, B2I D1/D2 `7I`, B1C pilot/data `1P`/`1D`, B2a pilot/data `5P`/`5D`;
//! QZSS (5) L1C/A `1C`, L1S `1Z`, L2 CM/CL `2S`/`2L`, L5 I/Q `5I`/`5Q`;
//! GLONASS (6) L1OF `1C`, L2OF `2C` with k = `freqId` − 7; NavIC (7) L5 A
//! `5A`. A carrier in gsens's signal table keeps its signal, the others
//! (B2I, QZSS L1C/A, L2, L5, SBAS, NavIC) their frequency. Other signals,
//! unknown satellites (GLONASS slot 255) and freqIds outside 0…13 are skipped
//! and counted.
//!
//! # ESF-RAW and ESF-MEAS
//!
//! UBX-ESF-RAW (0x10 0x03): 4 reserved bytes, then blocks of `data` (X4: the
//! field in bits 0…23, the data type in bits 24…31) and `sTtag` (U4, sensor
//! time tag). UBX-ESF-MEAS (0x10 0x02): `timeTag` (U4), `flags` (X2, numMeas
//! in bits 11…15), `id`, numMeas `data` blocks (type in bits 24…29), an
//! optional `calibTtag`; decoded here from its payload, as the crate reads the
//! 24-bit field as sign and magnitude. The accelerometer's x, y, z are data
//! types 16, 17, 18 ([`ACCEL_DATA_TYPES`]): 24-bit two's complement, 2⁻¹⁰
//! m/s² per LSB ([`ACCEL_MPS2_PER_LSB`]). The blocks sharing a time tag make
//! one sample, which needs all three axes; gyroscope, temperature and wheel
//! data are ignored. Where a log holds both messages, ESF-RAW's samples are
//! kept and ESF-MEAS's counted as skipped.
//!
//! # Sensor time
//!
//! The interface descriptions call `sTtag` the "sensor time tag" and state no
//! tie to GPS time; on the M8U and F9R it is the IMU's own millisecond
//! counter, which wraps at 2³². [`SensorTime::FreeRunningMs`] (the default)
//! unwraps it and ties it to GPS time once, at the first ESF message after an
//! RXM-RAWX: that message's last sample is taken to be at the RXM-RAWX's
//! `rcvTow` ([`UbxLog::imu_anchor`]). The anchor is exact only where the
//! module sends the ESF data of an epoch right after its RXM-RAWX, and
//! otherwise off by the module's output latency (tens of ms): the rest is the
//! IMU time offset the session estimates. A log without any RXM-RAWX keeps
//! the sensor clock, counted from its first tag. [`SensorTime::GpsTowMs`]
//! reads the tag as GPS time of week in ms instead, for firmware or
//! converters that write it so.
#![deny(missing_docs)]

mod esf;
mod log;
mod signals;

pub use esf::{ACCEL_DATA_TYPES, ACCEL_MPS2_PER_LSB, ImuTimeAnchor, SensorTime};
pub use log::{UbxError, UbxLog, UbxSettings, UbxStream, read_ubx, read_ubx_bytes, read_ubx_file};
