//! The crate documentation's sections "The log" and "RXM-RAWX" describe this module.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use gsens_io::{ClockEvent, ImuSeries, Observation, ObservationLog, ObservationLogBuilder, obs_flags};
use ublox::proto23::{PacketRef, Proto23};
use ublox::rxm_rawx::RxmRawxRef;
use ublox::{Parser, ParserBuilder, ParserError, UbxPacket};

use crate::esf::{ImuTimeAnchor, RawSample, SampleMapper, SensorTime, Unwrap, group_samples, map_samples};
use crate::signals::ubx_signal;

/// `trkStat` bits of an RXM-RAWX measurement (interface description).
const PR_VALID: u8 = 0x01;
const CP_VALID: u8 = 0x02;
const HALF_CYC: u8 = 0x04;
const SUB_HALF_CYC: u8 = 0x08;
/// `recStat` bit 1: the receiver applied a clock reset.
const CLK_RESET: u8 = 0x02;
/// A frame's bytes besides its payload: sync (2), class, id, length (2), checksum (2).
const FRAME_OVERHEAD: usize = 8;

/// How to read a UBX log. With the `clap` feature it is a command line's
/// options (the field's doc comment is its help).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct UbxSettings {
    /// How the UBX log's ESF sensor time tags map to GPS time: free-running-ms (a millisecond sensor
    /// clock, tied once to an RXM-RAWX epoch; the rest is the IMU offset searched) or gps-tow-ms
    /// (the tags count GPS time of week in ms, as rcvTow).
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "ubx_sensor_time",
            long = "ubx-sensor-time",
            value_name = "UBX_SENSOR_TIME",
            value_enum,
            default_value = "free-running-ms",
            help_heading = "Carrier phase and Doppler logs"
        )
    )]
    pub sensor_time: SensorTime,
}

/// A UBX log read: the RXM-RAWX measurements, the accelerometer samples of
/// ESF-RAW (or ESF-MEAS) and what the reader skipped.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct UbxLog {
    /// The measurements, one series per signal; its `skipped` lists every
    /// frame, message and sample left out, by reason.
    pub observations: ObservationLog,
    /// The accelerometer's specific force on GPS time (`t_s` as the
    /// observations'; see [`SensorTime`]); empty without ESF data.
    pub imu: ImuSeries,
    /// Where the sensor clock was tied to GPS time, under
    /// [`SensorTime::FreeRunningMs`] with an RXM-RAWX before the ESF data.
    pub imu_anchor: Option<ImuTimeAnchor>,
    /// The rule the IMU times follow.
    pub sensor_time: SensorTime,
    /// Frames with a valid checksum.
    pub frames: usize,
    /// Bytes outside every frame read: garbage, and frames corrupt, cut off or
    /// with a malformed payload.
    pub bytes_outside_frames: usize,
}

/// Why a UBX log could not be read. Corrupt content is never an error: it is
/// skipped and counted ([`ObservationLog::skipped`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum UbxError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// Source name.
        file: String,
        /// The underlying error.
        error: std::io::Error,
    },
    /// No RXM-RAWX epoch and no accelerometer sample in the whole log.
    #[error(
        "{file}: no UBX-RXM-RAWX measurement and no ESF accelerometer sample in {frames} valid frames \
         ({skipped} records skipped{first})"
    )]
    NoData {
        /// Source name.
        file: String,
        /// Valid frames seen.
        frames: usize,
        /// Records skipped.
        skipped: usize,
        /// The first reason, as `: 3 × bad checksum …`.
        first: String,
    },
}

/// Reads a UBX log from `input`; `source_name` names it in messages.
pub fn read_ubx<R: Read>(mut input: R, source_name: &str, settings: &UbxSettings) -> Result<UbxLog, UbxError> {
    let mut bytes = Vec::new();
    input.read_to_end(&mut bytes).map_err(|error| UbxError::Io { file: source_name.to_owned(), error })?;
    read_ubx_bytes(&bytes, source_name, settings)
}

/// Reads the UBX log file at `path`.
pub fn read_ubx_file(path: impl AsRef<Path>, settings: &UbxSettings) -> Result<UbxLog, UbxError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|error| UbxError::Io { file: name.clone(), error })?;
    read_ubx(std::io::BufReader::new(file), &name, settings)
}

/// Reads a UBX log held in memory.
pub fn read_ubx_bytes(bytes: &[u8], source_name: &str, settings: &UbxSettings) -> Result<UbxLog, UbxError> {
    let mut stream = UbxStream::new(source_name);
    stream.push(bytes);
    stream.finish(settings)
}

/// A UBX log read as it arrives, in pieces of any size (a serial port, a
/// file being written): each piece's complete frames are read at once, the
/// bytes of a frame not yet complete wait for the next piece. The log read
/// from all the pieces is the log read from their concatenation
/// ([`read_ubx_bytes`]).
pub struct UbxStream {
    reader: Reader,
    parser: Parser<Vec<u8>, Proto23>,
    /// The bytes waiting in the parser (its buffer is always the stream's
    /// last bytes): what a clone's parser starts from.
    waiting: Vec<u8>,
    /// Bytes received.
    received: usize,
    /// Frames dropped for their checksum.
    checksum_failures: usize,
    /// Accelerometer samples on the log's time already handed out by [`UbxStream::take_imu`].
    imu_taken: usize,
    /// The mapping of the sample list in use so far: whether it is ESF-RAW's,
    /// the rule, the mapper, the samples mapped and of them those kept.
    imu_mapped: Option<MappedSamples>,
}

/// How far [`UbxStream::take_imu`] has mapped a sample list.
#[derive(Debug, Clone)]
struct MappedSamples {
    raw: bool,
    rule: SensorTime,
    mapper: SampleMapper,
    mapped: usize,
    kept: usize,
}

impl core::fmt::Debug for UbxStream {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UbxStream")
            .field("received", &self.received)
            .field("frames", &self.reader.frames)
            .field("checksum_failures", &self.checksum_failures)
            .finish_non_exhaustive()
    }
}

impl Clone for UbxStream {
    /// The stream as it is, its waiting bytes given to a new parser.
    fn clone(&self) -> Self {
        let mut parser = ParserBuilder::new().with_protocol::<Proto23>().with_vec_buffer();
        let mut it = parser.consume_ubx(&self.waiting);
        // The bytes of a frame not yet complete: they stay in the buffer.
        while it.next().is_some() {}
        drop(it);
        UbxStream {
            reader: self.reader.clone(),
            parser,
            waiting: self.waiting.clone(),
            received: self.received,
            checksum_failures: self.checksum_failures,
            imu_taken: self.imu_taken,
            imu_mapped: self.imu_mapped.clone(),
        }
    }
}

impl UbxStream {
    /// A stream with nothing received yet; `source_name` names it in messages.
    pub fn new(source_name: &str) -> UbxStream {
        UbxStream {
            reader: Reader::new(source_name),
            parser: ParserBuilder::new().with_protocol::<Proto23>().with_vec_buffer(),
            waiting: Vec::new(),
            received: 0,
            checksum_failures: 0,
            imu_taken: 0,
            imu_mapped: None,
        }
    }

    /// Reads the complete frames `bytes` brings (with the waiting bytes
    /// before them); what follows the last complete frame waits.
    pub fn push(&mut self, bytes: &[u8]) {
        self.received += bytes.len();
        let r = &mut self.reader;
        let mut it = self.parser.consume_ubx(bytes);
        while let Some(item) = it.next() {
            let frames = r.frames;
            let at = move || format!("after {frames} valid frames");
            match item {
                Ok(UbxPacket::Proto23(packet)) => {
                    r.frames += 1;
                    r.frame_bytes += FRAME_OVERHEAD + packet.payload_len();
                    r.packet(packet);
                }
                #[allow(unreachable_patterns, reason = "other protocols' variants exist only with their features")]
                Ok(_) => r.b.skip("message of another UBX protocol version", at),
                Err(ParserError::InvalidChecksum { .. }) => {
                    self.checksum_failures += 1;
                    r.b.skip("bad checksum (frame dropped)", at);
                }
                Err(ParserError::InvalidPacketLen { packet, .. } | ParserError::InvalidField { packet, .. }) => {
                    r.frames += 1;
                    r.b.skip(&format!("{packet} with a malformed payload"), at);
                }
                Err(ParserError::OutOfMemory { .. }) => r.b.skip("frame longer than the parser's buffer", at),
            }
        }
        drop(it);
        let n = self.parser.buffer_len();
        let keep = self.waiting.len().min(n.saturating_sub(bytes.len()));
        self.waiting.drain(..self.waiting.len() - keep);
        self.waiting.extend_from_slice(&bytes[bytes.len() - (n - keep)..]);
    }

    /// Bytes received.
    pub fn received_bytes(&self) -> usize {
        self.received
    }

    /// Bytes waiting for the rest of their frame.
    pub fn waiting_bytes(&self) -> usize {
        self.parser.buffer_len()
    }

    /// Frames read with a valid checksum.
    pub fn frames(&self) -> usize {
        self.reader.frames
    }

    /// Frames dropped for a bad checksum.
    pub fn checksum_failures(&self) -> usize {
        self.checksum_failures
    }

    /// Frames, messages and samples skipped so far, for any reason
    /// (checksum failures among them).
    pub fn skipped(&self) -> usize {
        self.reader.b.skipped_count()
    }

    /// RXM-RAWX epochs read.
    pub fn epochs(&self) -> usize {
        self.reader.b.epochs()
    }

    /// The latest RXM-RAWX epoch's time \[s\] (`t_s` as the log's) and its
    /// measurements with a valid carrier phase.
    pub fn latest_epoch(&self) -> Option<(f64, usize)> {
        self.reader.last_epoch_s.map(|t_s| (t_s, self.reader.last_epoch_phases))
    }

    /// The accelerometer samples not handed out before, on the log's time
    /// by `settings` ([`SensorTime`]): under [`SensorTime::FreeRunningMs`]
    /// none before the sensor clock is tied to an RXM-RAWX epoch, then every
    /// sample since the first. Samples of ESF-RAW where the log has it, else
    /// of ESF-MEAS; a sample not after its predecessor is left out.
    pub fn take_imu(&mut self, settings: &UbxSettings) -> ImuSeries {
        let r = &self.reader;
        let raw = !r.raw.is_empty();
        let (samples, anchor) = if raw { (&r.raw, r.raw_anchor) } else { (&r.meas, r.meas_anchor) };
        let untied = settings.sensor_time == SensorTime::FreeRunningMs && anchor.is_none();
        if untied {
            return ImuSeries::default();
        }
        // Mapped from the list's first sample on, as the whole log is (a week's
        // rollover of GPS-time tags and the samples left out follow the
        // list's order), each sample once: a list taken over by ESF-RAW, or
        // asked for by another rule, is mapped afresh.
        let m = match &mut self.imu_mapped {
            Some(m) if m.raw == raw && m.rule == settings.sensor_time => m,
            slot => {
                let (mapper, _) = SampleMapper::new(settings.sensor_time, anchor, samples.first());
                slot.insert(MappedSamples { raw, rule: settings.sensor_time, mapper, mapped: 0, kept: 0 })
            }
        };
        let new_samples = m.mapped < samples.len();
        let mut imu = ImuSeries::default();
        for s in &samples[m.mapped..] {
            if let Some(t_s) = m.mapper.map(s) {
                // Samples of the list in use before this many were handed out already.
                if m.kept >= self.imu_taken {
                    imu.t_s.push(t_s);
                    imu.accel_mps2.push(s.accel_mps2);
                }
                m.kept += 1;
            }
        }
        m.mapped = samples.len();
        if new_samples {
            self.imu_taken = m.kept;
        }
        imu
    }

    /// The log of the complete frames received so far, as [`read_ubx_bytes`]
    /// reads those bytes (the bytes waiting are not counted).
    pub fn snapshot(&self, settings: &UbxSettings) -> Result<UbxLog, UbxError> {
        self.reader.clone().finish(self.received - self.waiting_bytes(), settings)
    }

    /// The log of everything received: the bytes still waiting are an
    /// incomplete frame at its end, skipped and counted.
    pub fn finish(mut self, settings: &UbxSettings) -> Result<UbxLog, UbxError> {
        let leftover = self.parser.buffer_len();
        if leftover > 0 {
            let frames = self.reader.frames;
            self.reader.b.skip("incomplete frame at the end of the log", || {
                format!("the last {leftover} bytes, after {frames} valid frames")
            });
        }
        self.reader.finish(self.received, settings)
    }
}

/// The state of one track's lock between RXM-RAWX epochs.
#[derive(Debug, Clone, Copy)]
struct Lock {
    t_s: f64,
    lock_time_s: f64,
    phase_valid: bool,
}

#[derive(Clone)]
struct Reader {
    b: ObservationLogBuilder,
    /// The source's name in messages.
    name: String,
    /// Measurements of the latest epoch with a valid carrier phase.
    last_epoch_phases: usize,
    frames: usize,
    frame_bytes: usize,
    last_epoch_s: Option<f64>,
    locks: HashMap<(String, &'static str), Lock>,
    raw_tags: Unwrap,
    meas_tags: Unwrap,
    raw: Vec<RawSample>,
    meas: Vec<RawSample>,
    raw_anchor: Option<(f64, i64)>,
    meas_anchor: Option<(f64, i64)>,
}

impl Reader {
    fn new(source_name: &str) -> Reader {
        Reader {
            b: ObservationLogBuilder::new(source_name, "UBX"),
            name: source_name.to_owned(),
            last_epoch_phases: 0,
            frames: 0,
            frame_bytes: 0,
            last_epoch_s: None,
            locks: HashMap::new(),
            raw_tags: Unwrap::default(),
            meas_tags: Unwrap::default(),
            raw: Vec::new(),
            meas: Vec::new(),
            raw_anchor: None,
            meas_anchor: None,
        }
    }

    fn packet(&mut self, packet: PacketRef<'_>) {
        let frames = self.frames;
        match packet {
            PacketRef::RxmRawx(p) => self.rawx(&p),
            PacketRef::EsfRaw(p) => {
                let blocks: Vec<_> = p.data().map(|d| (d.data_type, d.data_field, d.sensor_time_tag)).collect();
                self.esf(&blocks, true);
            }
            // Decoded here from the payload: the crate reads the 24-bit field as sign and
            // magnitude, where the accelerometer's is two's complement.
            PacketRef::EsfMeas(p) => match esf_meas_blocks(p.as_bytes()) {
                Some(blocks) => self.esf(&blocks, false),
                None => self.b.skip("ESF-MEAS whose numMeas disagrees with its length", || format!("frame {frames}")),
            },
            other => {
                let (class, id) = other.class_and_msg_id();
                self.b.skip(&format!("message 0x{class:02X} 0x{id:02X} (not read)"), || format!("frame {frames}"));
            }
        }
    }

    fn rawx(&mut self, p: &RxmRawxRef<'_>) {
        let frames = self.frames;
        let at = || format!("frame {frames}");
        let payload = p.as_bytes();
        if payload.len() != 16 + 32 * usize::from(p.num_meas()) {
            self.b.skip("RXM-RAWX whose numMeas disagrees with its length", at);
            return;
        }
        let Some(t_s) = self.b.start_epoch(u32::from(p.week()), p.rcv_tow(), at) else { return };
        self.last_epoch_s = Some(t_s);
        self.last_epoch_phases = 0;
        if p.rec_stat().bits() & CLK_RESET != 0 {
            self.b.clock_event(ClockEvent { t_s, jump_s: None, what: "RXM-RAWX recStat clkReset".to_owned() });
        }
        // The crate names byte 22 of a measurement `reserved2` (protocol 23's M8 layout of
        // version 0); version 1 (M8 protocol ≥ 17.20, every F9) holds sigId there.
        for (m, bytes) in p.measurements().zip(payload[16..].chunks_exact(32)) {
            let (pr_m, cp_cycles, do_hz) = (m.pr_mes(), m.cp_mes(), m.do_mes());
            let lock_time_s = f64::from(m.lock_time()) * 1e-3;
            let (cno, trk) = (m.cno(), m.trk_stat().bits());
            let signal = match ubx_signal(m.gnss_id(), m.sv_id(), bytes[22], m.freq_id()) {
                Ok(s) => s,
                Err(e) => {
                    self.b.skip(e.reason(), || format!("frame {frames}"));
                    continue;
                }
            };
            let phase_valid = trk & CP_VALID != 0;
            self.last_epoch_phases += usize::from(phase_valid);
            let mut flags = 0;
            if trk & PR_VALID == 0 {
                flags |= obs_flags::PSEUDORANGE_INVALID;
            }
            if !phase_valid {
                flags |= obs_flags::PHASE_INVALID;
            }
            if trk & HALF_CYC == 0 {
                flags |= obs_flags::HALF_CYCLE_AMBIGUOUS;
            }
            if trk & SUB_HALF_CYC != 0 {
                flags |= obs_flags::HALF_CYCLE_SUBTRACTED;
            }
            let key = (signal.sv.clone(), signal.code);
            let now = Lock { t_s, lock_time_s, phase_valid };
            if let Some(prev) = self.locks.insert(key, now) {
                // RXM-RAWX has no loss-of-lock bit: a lock time that fell, or that began
                // after the previous observation, or a phase valid again, is one.
                let relocked = lock_time_s < prev.lock_time_s || lock_time_s < t_s - prev.t_s - 1e-3;
                if phase_valid && (relocked || !prev.phase_valid) {
                    flags |= obs_flags::LOSS_OF_LOCK;
                }
            }
            let obs = Observation {
                pseudorange_m: if trk & PR_VALID != 0 { pr_m } else { f64::NAN },
                carrier_phase_cycles: if phase_valid { cp_cycles } else { f64::NAN },
                doppler_hz: f64::from(do_hz),
                cn0_dbhz: f64::from(cno),
                flags,
                strength: None,
                lock_time_s: Some(lock_time_s),
            };
            self.b.push(&signal.sv, signal.code, signal.carrier, t_s, &obs);
        }
    }

    fn esf(&mut self, blocks: &[(u8, u32, u32)], raw: bool) {
        let frames = self.frames;
        let (samples, incomplete) = group_samples(blocks);
        let name = if raw { "ESF-RAW" } else { "ESF-MEAS" };
        for _ in 0..incomplete {
            self.b.skip(&format!("{name} sample without all three accelerometer axes"), || format!("frame {frames}"));
        }
        let (tags, list, anchor) = if raw {
            (&mut self.raw_tags, &mut self.raw, &mut self.raw_anchor)
        } else {
            (&mut self.meas_tags, &mut self.meas, &mut self.meas_anchor)
        };
        for (tag, accel_mps2) in samples {
            list.push(RawSample { tag_ms: tags.next(tag), accel_mps2 });
        }
        if anchor.is_none()
            && let (Some(t_s), Some(last)) = (self.last_epoch_s, list.last())
        {
            *anchor = Some((t_s, last.tag_ms));
        }
    }

    fn finish(mut self, total_bytes: usize, settings: &UbxSettings) -> Result<UbxLog, UbxError> {
        let source_name = std::mem::take(&mut self.name);
        let (samples, anchor) = if !self.raw.is_empty() {
            for _ in 0..self.meas.len() {
                self.b.skip("ESF-MEAS accelerometer sample (the log has ESF-RAW)", || "ESF-MEAS".to_owned());
            }
            (&self.raw, self.raw_anchor)
        } else {
            (&self.meas, self.meas_anchor)
        };
        let (imu, imu_anchor, dropped) = map_samples(samples, settings.sensor_time, anchor);
        for _ in 0..dropped {
            self.b.skip("accelerometer sample not after its predecessor", || "ESF data".to_owned());
        }
        let frames = self.frames;
        let bytes_outside_frames = total_bytes.saturating_sub(self.frame_bytes);
        let observations = self.b.finish();
        if observations.epochs == 0 && imu.is_empty() {
            let first = observations.skipped.first().map(|s| format!(": {s}")).unwrap_or_default();
            return Err(UbxError::NoData {
                file: source_name.to_owned(),
                frames,
                skipped: observations.skipped_count(),
                first,
            });
        }
        Ok(UbxLog { observations, imu, imu_anchor, sensor_time: settings.sensor_time, frames, bytes_outside_frames })
    }
}

/// The (data type, field, time tag) blocks of an ESF-MEAS payload: timeTag U4,
/// flags X2 (numMeas in bits 11…15, calibTtagValid bit 3), id U2, numMeas × data
/// X4 (field bits 0…23, type bits 24…29), calibTtag U4 if valid. `None` when
/// the length disagrees with numMeas.
fn esf_meas_blocks(payload: &[u8]) -> Option<Vec<(u8, u32, u32)>> {
    let time_tag = u32::from_le_bytes(payload.get(0..4)?.try_into().ok()?);
    let flags = u16::from_le_bytes(payload.get(4..6)?.try_into().ok()?);
    let n = usize::from(flags >> 11);
    let calib = if flags & 0x08 != 0 { 4 } else { 0 };
    if payload.len() != 8 + 4 * n + calib {
        return None;
    }
    let blocks = payload[8..8 + 4 * n]
        .chunks_exact(4)
        .map(|c| {
            let w = u32::from_le_bytes(c.try_into().expect("4 bytes"));
            (((w >> 24) & 0x3F) as u8, w & 0xFF_FFFF, time_tag)
        })
        .collect();
    Some(blocks)
}
