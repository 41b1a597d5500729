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
    let (offset_s, anchor) = match rule {
        SensorTime::FreeRunningMs => match anchor {
            Some((t_s, tag_ms)) => {
                let off = t_s - tag_ms as f64 * 1e-3;
                (off, Some(ImuTimeAnchor { gps_minus_sensor_s: off, at_t_s: t_s }))
            }
            // No RXM-RAWX to tie to: the sensor's own clock from its first tag.
            None => (-(samples.first().map_or(0, |s| s.tag_ms) as f64) * 1e-3, None),
        },
        SensorTime::GpsTowMs => (0.0, None),
    };
    let mut imu = ImuSeries::default();
    let mut dropped = 0;
    let mut week_s = 0.0;
    let mut last_tow_ms: Option<i64> = None;
    for s in samples {
        let t_s = match rule {
            SensorTime::FreeRunningMs => s.tag_ms as f64 * 1e-3 + offset_s,
            SensorTime::GpsTowMs => {
                // The raw tag is the time of week; a fall by more than half a week is the rollover.
                let tow_ms = s.tag_ms.rem_euclid(1 << 32);
                if last_tow_ms.is_some_and(|l| tow_ms < l - (GPS_WEEK_S as i64 * 500)) {
                    week_s += GPS_WEEK_S;
                }
                last_tow_ms = Some(tow_ms);
                week_s + tow_ms as f64 * 1e-3
            }
        };
        if imu.t_s.last().is_some_and(|&last| t_s <= last) {
            dropped += 1;
            continue;
        }
        imu.t_s.push(t_s);
        imu.accel_mps2.push(s.accel_mps2);
    }
    (imu, anchor, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;

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
