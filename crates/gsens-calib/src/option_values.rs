//! Option values read from text, as a command line gives them: numbers
//! within a range (the message says the range, the caller names the
//! option), and the IMU time offset within what an IMU's latency can be.
//! Surrounding white space is ignored.

use crate::{TimeOffset, TimeOffsetOption};

/// The largest IMU time offset that can be stated \[s\]: an IMU's latency
/// is milliseconds to a few hundred; more is a clock on another time base.
pub const MAX_STATED_TIME_OFFSET_S: f64 = 1.0;

fn number(text: &str, or: &str) -> Result<f64, String> {
    text.trim().parse().map_err(|_| format!("`{text}` is not a number{or}"))
}

/// A number ≥ 0, or `inf`.
pub fn non_negative_or_inf(text: &str) -> Result<f64, String> {
    let x = number(text, " (or inf)")?;
    if x >= 0.0 { Ok(x) } else { Err(format!("{x} is not a number ≥ 0 (or inf)")) }
}

/// A finite number ≥ 0.
pub fn finite_non_negative(text: &str) -> Result<f64, String> {
    let x = number(text, "")?;
    if x.is_finite() && x >= 0.0 { Ok(x) } else { Err(format!("{x} is not a finite number ≥ 0")) }
}

/// A finite number > 0.
pub fn positive(text: &str) -> Result<f64, String> {
    let x = number(text, "")?;
    if x.is_finite() && x > 0.0 { Ok(x) } else { Err(format!("{x} is not a finite number > 0")) }
}

/// A finite number.
pub fn finite(text: &str) -> Result<f64, String> {
    let x = number(text, "")?;
    if x.is_finite() { Ok(x) } else { Err(format!("{x} is not a finite number")) }
}

/// A forgetting factor, in (0, 1].
pub fn forgetting_factor(text: &str) -> Result<f64, String> {
    let x = number(text, "")?;
    if x > 0.0 && x <= 1.0 { Ok(x) } else { Err(format!("{x} is not in (0, 1] (1: no forgetting)")) }
}

/// An elevation, in [−90, 90] degrees.
pub fn elevation_deg(text: &str) -> Result<f64, String> {
    let x = number(text, "")?;
    if (-90.0..=90.0).contains(&x) { Ok(x) } else { Err(format!("{x} is not an elevation in [-90, 90] degrees")) }
}

/// `auto`, `none` or seconds within ±[`MAX_STATED_TIME_OFFSET_S`].
pub fn stated_time_offset(text: &str) -> Result<TimeOffset, String> {
    let t: TimeOffset = text.trim().parse().map_err(|e| format!("{e}"))?;
    match t {
        TimeOffset::Fixed { imu_time_offset_s: s } if s.abs() > MAX_STATED_TIME_OFFSET_S => Err(format!(
            "{s} s is beyond ±{MAX_STATED_TIME_OFFSET_S} s: an IMU's latency is milliseconds to a few hundred, more \
             is a clock on another time base; stamp both logs by one clock (shift the IMU's t_s) instead"
        )),
        t => Ok(t),
    }
}

/// [`stated_time_offset`] as the options name it: `auto`, or seconds (`none`: 0).
pub fn stated_time_offset_option(text: &str) -> Result<TimeOffsetOption, String> {
    Ok(match stated_time_offset(text)? {
        TimeOffset::Auto { .. } => TimeOffsetOption::Auto,
        TimeOffset::Fixed { imu_time_offset_s } => TimeOffsetOption::Seconds(imu_time_offset_s),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_outside_their_range_are_refused_with_the_range() {
        assert_eq!(positive(" 2.5 "), Ok(2.5));
        assert_eq!(positive("0"), Err("0 is not a finite number > 0".into()));
        assert_eq!(positive("x"), Err("`x` is not a number".into()));
        assert_eq!(finite_non_negative("0"), Ok(0.0));
        assert_eq!(finite_non_negative("inf"), Err("inf is not a finite number ≥ 0".into()));
        assert_eq!(non_negative_or_inf("inf"), Ok(f64::INFINITY));
        assert_eq!(non_negative_or_inf("-1"), Err("-1 is not a number ≥ 0 (or inf)".into()));
        assert_eq!(non_negative_or_inf("y"), Err("`y` is not a number (or inf)".into()));
        assert_eq!(finite("-3"), Ok(-3.0));
        assert!(finite("nan").is_err());
        assert_eq!(forgetting_factor("1"), Ok(1.0));
        assert!(forgetting_factor("0").is_err() && forgetting_factor("1.01").is_err());
        assert_eq!(elevation_deg("-90"), Ok(-90.0));
        assert!(elevation_deg("91").unwrap_err().contains("[-90, 90]"));
    }

    #[test]
    fn a_time_offset_beyond_a_second_is_refused() {
        assert_eq!(stated_time_offset("none"), Ok(TimeOffset::Fixed { imu_time_offset_s: 0.0 }));
        assert_eq!(stated_time_offset("-0.01"), Ok(TimeOffset::Fixed { imu_time_offset_s: -0.01 }));
        assert_eq!(stated_time_offset("1"), Ok(TimeOffset::Fixed { imu_time_offset_s: 1.0 }));
        assert!(matches!(stated_time_offset("auto"), Ok(TimeOffset::Auto { .. })));
        assert!(stated_time_offset("3").unwrap_err().starts_with("3 s is beyond ±1 s"));
        assert!(stated_time_offset("later").unwrap_err().contains("auto, none or a number of seconds"));
        assert_eq!(stated_time_offset_option("auto"), Ok(TimeOffsetOption::Auto));
        assert_eq!(stated_time_offset_option("none"), Ok(TimeOffsetOption::Seconds(0.0)));
        assert_eq!(stated_time_offset_option(" 0.01"), Ok(TimeOffsetOption::Seconds(0.01)));
        assert!(stated_time_offset_option("-2").unwrap_err().starts_with("-2 s is beyond ±1 s"));
    }
}
