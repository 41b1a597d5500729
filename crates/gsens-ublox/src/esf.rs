//! The crate documentation's sections "ESF-RAW and ESF-MEAS" and "Sensor time" describe this module.

use gsens_io::{GPS_WEEK_S, ImuSeries};

/// ESF data types of the accelerometer's x, y, z axes (interface description,
/// "ESF measurement data types": 16, 17, 18).
pub const ACCEL_DATA_TYPES: [u8; 3] = [16, 17, 18];

/// The accelerometer's scale: m/s² per LSB of the 24-bit signed data field (2⁻¹⁰).
pub const ACCEL_MPS2_PER_LSB: f64 = 1.0 / 1024.0;

/// How the sensor time tags (ESF-RAW `sTtag`, ESF-MEAS `timeTag`) map to GPS time.
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum SensorTime {
    /// The tag is a free-running millisecond counter of the sensor clock
    /// (wrapping at 2³²). Its offset to GPS time is anchored once: the last
    /// sample of the first ESF message that follows an RXM-RAWX is taken to be
    /// at that RXM-RAWX's `rcvTow` ([`ImuTimeAnchor`]). The anchor is as good
    /// as the module's output order: u-blox does not state the latency, so
    /// the rest is the IMU time offset the session estimates.
    #[default]
    FreeRunningMs,
    /// The tag is GPS time of week in milliseconds, as RXM-RAWX's `rcvTow`
    /// (counted on from the first epoch's week, a week's rollover followed).
    GpsTowMs,
}

/// Where the sensor clock was tied to GPS time ([`SensorTime::FreeRunningMs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuTimeAnchor {
    /// GPS time minus sensor time \[s\]: t_s = tag·10⁻³ + this, with the tag
    /// unwrapped over the counter's wraps (t_s as [`gsens_io::SatelliteSeries::t_s`]).
    pub gps_minus_sensor_s: f64,
    /// The RXM-RAWX epoch it was tied to \[s\] (as `t_s`).
    pub at_t_s: f64,
}

/// One accelerometer sample on the sensor clock, before the time mapping.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RawSample {
    /// The tag, unwrapped \[ms\].
    pub(crate) tag_ms: i64,
    pub(crate) accel_mps2: [f64; 3],
}

/// Sign-extends a 24-bit two's complement field.
pub(crate) fn signed_24(field: u32) -> i32 {
    ((field << 8) as i32) >> 8
}

/// Accelerometer samples of one ESF message from its (data type, field, tag)
/// blocks: blocks sharing a tag form one sample, which needs all three axes.
/// Returns the samples and the number of tags left without all three.
pub(crate) fn group_samples(blocks: &[(u8, u32, u32)]) -> (Vec<(u32, [f64; 3])>, usize) {
    let mut out: Vec<(u32, [Option<f64>; 3])> = Vec::new();
    for &(data_type, field, tag) in blocks {
        let Some(axis) = ACCEL_DATA_TYPES.iter().position(|&t| t == data_type) else { continue };
        let value = f64::from(signed_24(field)) * ACCEL_MPS2_PER_LSB;
        let i = match out.iter().position(|(t, _)| *t == tag) {
            Some(i) => i,
            None => {
                out.push((tag, [None; 3]));
                out.len() - 1
            }
        };
        out[i].1[axis] = Some(value);
    }
    let complete: Vec<_> = out.iter().filter_map(|(t, a)| Some((*t, [a[0]?, a[1]?, a[2]?]))).collect();
    let incomplete = out.len() - complete.len();
    (complete, incomplete)
}

/// Unwraps a 32-bit millisecond counter: each tag is taken as the nearest
/// value to the previous one (steps of less than 2³¹ ms either way).
#[derive(Debug, Clone, Default)]
pub(crate) struct Unwrap {
    last: Option<(u32, i64)>,
}

impl Unwrap {
    pub(crate) fn next(&mut self, tag: u32) -> i64 {
        let value = match self.last {
            None => i64::from(tag),
            Some((raw, value)) => value + i64::from(tag.wrapping_sub(raw) as i32),
        };
        self.last = Some((tag, value));
        value
    }
}

/// Maps the samples to GPS time by `rule` and returns the IMU series (strictly
/// increasing: a sample not after its predecessor is dropped and counted) and
/// the anchor used. `anchor` is (t_s of the RXM-RAWX, unwrapped tag of the
/// sample tied to it).
pub(crate) fn map_samples(
    samples: &[RawSample],
    rule: SensorTime,
    anchor: Option<(f64, i64)>,
) -> (ImuSeries, Option<ImuTimeAnchor>, usize) {
    let (mut mapper, anchor) = SampleMapper::new(rule, anchor, samples.first());
    let mut imu = ImuSeries::default();
    for s in samples {
        if let Some(t_s) = mapper.map(s) {
            imu.t_s.push(t_s);
            imu.accel_mps2.push(s.accel_mps2);
        }
    }
    (imu, anchor, mapper.dropped)
}

/// [`map_samples`] one sample at a time, for samples that arrive as a log is
/// received: the same times and the same samples dropped, however the list
/// is cut.
#[derive(Debug, Clone)]
pub(crate) struct SampleMapper {
    rule: SensorTime,
    /// GPS − sensor time of a free-running tag \[s\].
    offset_s: f64,
    /// Whole weeks added to GPS time-of-week tags \[s\].
    week_s: f64,
    last_tow_ms: Option<i64>,
    /// The time of the last sample kept \[s\].
    last_t_s: Option<f64>,
    /// Samples dropped for not being after their predecessor.
    pub(crate) dropped: usize,
}

impl SampleMapper {
    /// The mapper of a list whose first sample is `first` (a free-running
    /// clock without an RXM-RAWX to tie to counts from it), and the anchor
    /// it uses.
    pub(crate) fn new(
        rule: SensorTime,
        anchor: Option<(f64, i64)>,
        first: Option<&RawSample>,
    ) -> (SampleMapper, Option<ImuTimeAnchor>) {
        let (offset_s, anchor) = match rule {
            SensorTime::FreeRunningMs => match anchor {
                Some((t_s, tag_ms)) => {
                    let off = t_s - tag_ms as f64 * 1e-3;
                    (off, Some(ImuTimeAnchor { gps_minus_sensor_s: off, at_t_s: t_s }))
                }
                // No RXM-RAWX to tie to: the sensor's own clock from its first tag.
                None => (-(first.map_or(0, |s| s.tag_ms) as f64) * 1e-3, None),
            },
            SensorTime::GpsTowMs => (0.0, None),
        };
        let mapper = SampleMapper { rule, offset_s, week_s: 0.0, last_tow_ms: None, last_t_s: None, dropped: 0 };
        (mapper, anchor)
    }

    /// The next sample's time on the log's time, `None` when it is dropped
    /// (not after the last sample kept).
    pub(crate) fn map(&mut self, s: &RawSample) -> Option<f64> {
        let t_s = match self.rule {
            SensorTime::FreeRunningMs => s.tag_ms as f64 * 1e-3 + self.offset_s,
            SensorTime::GpsTowMs => {
                // The raw tag is the time of week; a fall by more than half a week is the rollover.
                let tow_ms = s.tag_ms.rem_euclid(1 << 32);
                if self.last_tow_ms.is_some_and(|l| tow_ms < l - (GPS_WEEK_S as i64 * 500)) {
                    self.week_s += GPS_WEEK_S;
                }
                self.last_tow_ms = Some(tow_ms);
                self.week_s + tow_ms as f64 * 1e-3
            }
        };
        if self.last_t_s.is_some_and(|last| t_s <= last) {
            self.dropped += 1;
            return None;
        }
        self.last_t_s = Some(t_s);
        Some(t_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sample by sample, the mapper gives the times and drops of the whole
    /// list's mapping: a GPS week's rollover, a repeated tag and a tag going
    /// back included.
    #[test]
    fn the_mapper_maps_as_the_whole_list_is_mapped() {
        let week_ms = (GPS_WEEK_S * 1e3) as i64;
        let tags = [week_ms - 20, week_ms - 10, week_ms - 10, 0, 10, 5, 20];
        let samples: Vec<RawSample> = tags
            .iter()
            .enumerate()
            .map(|(k, &tag_ms)| RawSample { tag_ms, accel_mps2: [k as f64, 0.0, 9.8] })
            .collect();
        let anchor = Some((1000.0, week_ms - 20));
        for rule in [SensorTime::GpsTowMs, SensorTime::FreeRunningMs] {
            let (whole, _, dropped) = map_samples(&samples, rule, anchor);
            let (mut mapper, _) = SampleMapper::new(rule, anchor, samples.first());
            let one_by_one: Vec<f64> = samples.iter().filter_map(|s| mapper.map(s)).collect();
            assert_eq!((&one_by_one, mapper.dropped), (&whole.t_s, dropped), "{rule:?}");
        }
        // Time of week: the rollover continues the week; the repeat and the step back are dropped.
        let (gps, _, dropped) = map_samples(&samples, SensorTime::GpsTowMs, None);
        let want = [-0.02, -0.01, 0.0, 0.01, 0.02].map(|d| GPS_WEEK_S + d);
        assert_eq!(dropped, 2);
        assert!(gps.t_s.iter().zip(want).all(|(t, w)| (t - w).abs() < 1e-9), "{:?}", gps.t_s);
    }

    #[test]
    fn fields_and_counters() {
        assert_eq!(signed_24(0x00_0400), 1024);
        assert_eq!(signed_24(0xFF_FC00), -1024);
        assert_eq!(signed_24(0x80_0000), -(1 << 23));
        let mut u = Unwrap::default();
        assert_eq!([u.next(u32::MAX - 5), u.next(4), u.next(2)], [4_294_967_290, 4_294_967_300, 4_294_967_298]);
        let blocks = [(5, 0, 10), (16, 0x400, 10), (17, 0xFF_FC00, 10), (18, 0x2740, 10), (16, 1, 20)];
        let (s, incomplete) = group_samples(&blocks);
        assert_eq!((s, incomplete), (vec![(10, [1.0, -1.0, 9.8125])], 1));
    }
}
