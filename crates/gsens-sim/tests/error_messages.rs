//! Exact texts of the errors users see (scenario validation, the models'
//! constructors, the IQ generator, the YUMA parser) and the typed fields
//! behind them: the messages are derived from the fields and must not drift.

use gsens_sim::error::{AlmanacError, ConfigError, UtcError};
use gsens_sim::iq::IqError;
use gsens_sim::iq::{IqConfig, IqFormat, generate_iq};
use gsens_sim::motion::{Axis, Motion, MotionConfig, Segment};
use gsens_sim::oscillator::{Oscillator, OscillatorConfig};
use gsens_sim::rng::seeded;
use gsens_sim::satellites::Constellation;
use gsens_sim::scenario::{LoopSection, Scenario, ScenarioError, parse_utc_to_gps_s};
use gsens_sim::session::NullSink;
use gsens_sim::session::SimError;

/// (scenario TOML, the error's text).
const CASES: &[(&str, &str)] = &[
    (
        "[session]\nstart_utc = \"yesterday\"\n",
        "invalid scenario: session.start_utc must look like 2024-02-08T12:00:00Z (got \"yesterday\")",
    ),
    (
        "[session]\nstart_utc = \"2024-13-01T00:00:00Z\"\n",
        "invalid scenario: session.start_utc must look like 2024-02-08T12:00:00Z (got \"2024-13-01T00:00:00Z\")",
    ),
    (
        "[session]\nstart_utc = \"2024-02-08T12:00\"\n",
        "invalid scenario: session.start_utc must look like 2024-02-08T12:00:00Z (got \"2024-02-08T12:00\")",
    ),
    ("[session]\nduration_s = -1.0\n", "invalid scenario: session.duration_s must be in (0, 1e6] s (got -1)"),
    ("[motion]\nsegments = []\n", "invalid scenario: the session is empty: give motion.segments or session.duration_s"),
    (
        "[antenna]\nlat_deg = 95.0\nlon_deg = 0.0\n",
        "invalid scenario: antenna.lat_deg must be within [-90, 90] (got 95)",
    ),
    (
        "[antenna]\nlat_deg = 0.0\nlon_deg = 400.0\n",
        "invalid scenario: antenna.lon_deg must be within [-360, 360] (got 400)",
    ),
    (
        "[antenna]\nlat_deg = 0.0\nlon_deg = 0.0\nheight_m = 1e6\n",
        "invalid scenario: antenna.height_m must be within (-10 km, 100 km) (got 1000000)",
    ),
    ("[oscillator]\nh0 = -1.0\n", "invalid scenario: oscillator.h0 must be finite and >= 0 (got -1)"),
    (
        "[oscillator]\nh_neg1 = -1e-20\n",
        "invalid scenario: oscillator.h_neg1 must be finite and >= 0 (got -0.00000000000000000001)",
    ),
    ("[oscillator]\nh_neg2 = nan\n", "invalid scenario: oscillator.h_neg2 must be finite and >= 0 (got NaN)"),
    ("[oscillator]\nh2 = -2.5\n", "invalid scenario: oscillator.h2 must be finite and >= 0 (got -2.5)"),
    ("[oscillator]\noffset_frac = nan\n", "invalid scenario: oscillator.offset_frac must be finite (got NaN)"),
    (
        "[oscillator]\ndrift_frac_per_s = inf\n",
        "invalid scenario: oscillator.drift_frac_per_s must be finite (got inf)",
    ),
    (
        "[oscillator]\ntemp_cycle_amplitude_frac = -inf\n",
        "invalid scenario: oscillator.temp_cycle_amplitude_frac must be finite (got -inf)",
    ),
    (
        "[oscillator]\ntemp_cycle_phase_rad = nan\n",
        "invalid scenario: oscillator.temp_cycle_phase_rad must be finite (got NaN)",
    ),
    ("[oscillator]\noffset_frac = 0.01\n", "invalid scenario: oscillator.offset_frac must be within ±1e-3 (got 0.01)"),
    (
        "[oscillator]\ntemp_cycle_period_s = 0.0\n",
        "invalid scenario: oscillator.temp_cycle_period_s must be > 0 (got 0)",
    ),
    (
        "[oscillator]\nflicker_low_cutoff_hz = -1e-5\n",
        "invalid scenario: oscillator.flicker_low_cutoff_hz must be > 0 (got -0.00001)",
    ),
    (
        "[oscillator]\ngamma_hz_per_mps2 = [0.0, 200.0, 0.0]\n",
        "invalid scenario: oscillator.gamma_hz_per_mps2[1] must be finite and within ±100 Hz/(m/s²) (got 200)",
    ),
    (
        "[oscillator]\ncarrier_hz = 5.0\n",
        "invalid scenario: oscillator.carrier_hz must be within [1e8, 1e11] Hz (got 5)",
    ),
    ("[loop]\norder = 4\n", "invalid scenario: loop.order must be 2 or 3 (got 4)"),
    ("[loop]\nbn_hz = -1.0\n", "invalid scenario: loop.bn_hz must be > 0 (got -1)"),
    ("[loop]\nzeta = 0.0\n", "invalid scenario: loop.zeta must be > 0 (got 0)"),
    ("[loop]\norder = 3\na3 = 0.0\n", "invalid scenario: loop.a3 must be > 0 (got 0)"),
    ("[loop]\norder = 3\nb3 = -1.5\n", "invalid scenario: loop.b3 must be > 0 (got -1.5)"),
    (
        "[loop]\norder = 3\na3 = 0.5\nb3 = 1.5\n",
        "invalid scenario: loop.a3 * loop.b3 must be > 1 for a stable loop (got 0.75)",
    ),
    (
        "[loop]\ninterval_s = 0.03\n",
        "invalid scenario: loop.interval_s must be in [0.001, 0.02] s (at least one 1 ms C/A code period, at most one 20 \
         ms data bit) (got 0.03)",
    ),
    (
        "[loop]\ninterval_s = 0.003\n",
        "invalid scenario: loop.interval_s must divide the 20 ms data bit (1, 2, 4, 5, 10 or 20 ms, …) (got 0.003)",
    ),
    (
        "[loop]\nbn_hz = 600.0\n",
        "invalid scenario: loop.bn_hz = 600 is too wide for loop.interval_s = 0.001: the discrete loop is unstable",
    ),
    (
        "[loop]\ninitial_freq_err_hz = -0.5\n",
        "invalid scenario: loop.initial_freq_err_hz must be within [0, 500] Hz (1/(2·loop.interval_s): a larger error aliases in the loop) (got -0.5)",
    ),
    ("[loop]\nlock_threshold = 1.0\n", "invalid scenario: loop.lock_threshold must be in (0, 1) (got 1)"),
    ("[loop]\nlock_tau_s = 0.0\n", "invalid scenario: loop.lock_tau_s must be > 0 (got 0)"),
    ("[log]\ninterval_s = 0.0\n", "invalid scenario: log.interval_s must be in (0, 10] s (got 0)"),
    (
        "[log]\ninterval_s = 0.0255\n",
        "invalid scenario: log.interval_s must be a whole multiple of loop.interval_s = 0.001 (got 0.0255)",
    ),
    ("[imu]\nrate_hz = 0.0\n", "invalid scenario: imu.rate_hz must be within [1, 10000] Hz (got 0)"),
    ("[imu]\ntime_offset_s = 20.0\n", "invalid scenario: imu.time_offset_s must be within ±10 s (got 20)"),
    ("[imu]\nvrw_mps2_per_rthz = -1.0\n", "invalid scenario: imu.vrw_mps2_per_rthz must be within [0, 1] (got -1)"),
    ("[imu]\nbias_sigma_mps2 = 11.0\n", "invalid scenario: imu.bias_sigma_mps2 must be within [0, 10] (got 11)"),
    (
        "[imu]\nscale_factor_sigma_ppm = 1e6\n",
        "invalid scenario: imu.scale_factor_sigma_ppm must be within [0, 100000] (got 1000000)",
    ),
    (
        "[imu]\nmisalignment_sigma_rad = 0.2\n",
        "invalid scenario: imu.misalignment_sigma_rad must be within [0, 0.1] (got 0.2)",
    ),
    ("[imu]\nquantization_mps2 = 2.0\n", "invalid scenario: imu.quantization_mps2 must be within [0, 1] (got 2)"),
    (
        "[[motion.segments]]\nkind = \"rest\"\nduration_s = -1.0\n",
        "invalid scenario: the session is empty: give motion.segments or session.duration_s",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 0.0\nperiod_s = 1\namplitude_mps2 = 1\n",
        "invalid scenario: the session is empty: give motion.segments or session.duration_s",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 2e6\nperiod_s = 1\namplitude_mps2 = 1\n",
        "invalid scenario: motion.segments[0].duration_s must be > 0 and <= 1e6 s (got 2000000)",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = [0.0, 0.0, 0.0]\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = 1\n",
        "invalid scenario: motion.segments[0].axis: axis vector [0.0, 0.0, 0.0] must be finite and non-zero",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 0.01\namplitude_mps2 = 1\n",
        "invalid scenario: motion.segments[0].period_s must be within [0.02, 100] s (got 0.01)",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = -1\n",
        "invalid scenario: motion.segments[0].amplitude_mps2 must be within [0, 100] m/s² (got -1)",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = 1\njitter = { period_rel = 0.5 }\n",
        "invalid scenario: motion.segments[0].jitter.period_rel must be within [0, 0.5) (got 0.5)",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = 1\njitter = { amplitude_rel = -0.1 }\n",
        "invalid scenario: motion.segments[0].jitter.amplitude_rel must be within [0, 0.5) (got -0.1)",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = 1\njitter = { correlation_s = 0.0 }\n",
        "invalid scenario: motion.segments[0].jitter.correlation_s must be > 0 (got 0)",
    ),
    (
        "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = 1\nramp_s = 0.6\n",
        "invalid scenario: motion.segments[0].ramp_s must be > 0 and <= duration_s/2 (got 0.6)",
    ),
    (
        "[[motion.segments]]\nkind = \"rest\"\nduration_s = 1\n[[motion.segments]]\nkind = \"rotate\"\naxis = [1.0, nan, 0.0]\nangle_deg = 90\nduration_s = 1\n",
        "invalid scenario: motion.segments[1].axis: axis vector [1.0, NaN, 0.0] must be finite and non-zero",
    ),
    (
        "[[motion.segments]]\nkind = \"rotate\"\naxis = \"y\"\nangle_deg = 4000\nduration_s = 1\n",
        "invalid scenario: motion.segments[0].angle_deg must be within ±3600° (got 4000)",
    ),
    (
        "[[motion.segments]]\nkind = \"rotate\"\naxis = \"y\"\nangle_deg = 90\nduration_s = 0\n",
        "invalid scenario: the session is empty: give motion.segments or session.duration_s",
    ),
    (
        "[[motion.segments]]\nkind = \"wobble\"\naxis = [0.0, 0.0, 0.0]\namplitude_deg = 10\nperiod_s = 1\nduration_s = 4\n",
        "invalid scenario: motion.segments[0].axis: axis vector [0.0, 0.0, 0.0] must be finite and non-zero",
    ),
    (
        "[[motion.segments]]\nkind = \"wobble\"\naxis = \"z\"\namplitude_deg = 90\nperiod_s = 1\nduration_s = 4\n",
        "invalid scenario: motion.segments[0].amplitude_deg must be within (-90°, 90°) (got 90)",
    ),
    (
        "[[motion.segments]]\nkind = \"wobble\"\naxis = \"z\"\namplitude_deg = 10\nperiod_s = 200\nduration_s = 4\n",
        "invalid scenario: motion.segments[0].period_s must be within [0.02, 100] s (got 200)",
    ),
    (
        "[[motion.segments]]\nkind = \"wobble\"\naxis = \"z\"\namplitude_deg = 10\nperiod_s = 1\nduration_s = 4\nramp_s = 0.0\n",
        "invalid scenario: motion.segments[0].ramp_s must be > 0 and <= duration_s/2 (got 0)",
    ),
    (
        "[satellites]\nelevation_mask_deg = 85.0\n",
        "invalid scenario: satellites.elevation_mask_deg must be within [-5, 80] (got 85)",
    ),
    ("[satellites]\nmax_channels = 0\n", "invalid scenario: satellites.max_channels must be within [1, 64] (got 0)"),
    (
        "[satellites.cn0]\nzenith_cn0_dbhz = 99.0\n",
        "invalid scenario: satellites.cn0.zenith_cn0_dbhz must be within [0, 70] dB-Hz (got 99)",
    ),
    (
        "[satellites.cn0]\nhorizon_cn0_dbhz = -1.0\n",
        "invalid scenario: satellites.cn0.horizon_cn0_dbhz must be within [0, 70] dB-Hz (got -1)",
    ),
    (
        "[satellites.cn0]\nelevation_exponent = 0.0\n",
        "invalid scenario: satellites.cn0.elevation_exponent must be > 0 (got 0)",
    ),
    (
        "[satellites.cn0]\nper_satellite_offset_sigma_db = 11.0\n",
        "invalid scenario: satellites.cn0.per_satellite_offset_sigma_db must be within [0, 10] dB (got 11)",
    ),
    (
        "[[motion.segments]]\nkind = \"rest\"\nduration_s = 5\n[[motion.segments]]\nkind = \"rest\"\nduration_s = -1.0\n",
        "invalid scenario: motion.segments[1].duration_s must be >= 0 and <= 1e6 s (got -1)",
    ),
    (
        "[[motion.segments]]\nkind = \"rest\"\nduration_s = 5\n[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 0.0\nperiod_s = 1\namplitude_mps2 = 1\n",
        "invalid scenario: motion.segments[1].duration_s must be > 0 and <= 1e6 s (got 0)",
    ),
    (
        "[[motion.segments]]\nkind = \"rest\"\nduration_s = 5\n[[motion.segments]]\nkind = \"rotate\"\naxis = \"y\"\nangle_deg = 90\nduration_s = nan\n",
        "invalid scenario: the session is empty: give motion.segments or session.duration_s",
    ),
    (
        "[loop]\nbandwidth = 2\n",
        "invalid scenario: TOML parse error at line 2, column 1\n  |\n2 | bandwidth = 2\n  | ^^^^^^^^^\nunknown field `bandwidth`, expected one of `order`, `bn_hz`, `zeta`, `a3`, `b3`, `interval_s`, `discriminator`, `doppler_aiding`, `initial_freq_err_hz`, `lock_threshold`, `lock_tau_s`",
    ),
    (
        "[loop]\nbn_hz = \"3\"\n",
        "invalid scenario: TOML parse error at line 2, column 9\n  |\n2 | bn_hz = \"3\"\n  |         ^^^\ninvalid type: string \"3\", expected f64",
    ),
];

#[test]
fn scenario_errors_keep_their_texts() {
    for (toml, expected) in CASES {
        let e = Scenario::from_toml_str(toml).unwrap_err();
        assert_eq!(e.to_string(), *expected, "{toml:?}");
        // Through a simulation the text is the same.
        if let Ok(sc) = toml::from_str::<Scenario>(toml) {
            let e = gsens_sim::session::simulate(&sc, 1, &mut NullSink, |_| {}).unwrap_err();
            assert_eq!(e.to_string(), *expected, "{toml:?}");
        }
    }
}

#[test]
fn scenario_errors_carry_the_key_value_and_range() {
    let e = Scenario::from_toml_str("[loop]\nbn_hz = -1.0\n").unwrap_err();
    assert_eq!(
        e,
        ScenarioError::Invalid(ConfigError::OutOfRange {
            key: "loop.bn_hz".into(),
            value: -1.0,
            allowed: "> 0".into()
        })
    );
    let key = |toml: &str| match Scenario::from_toml_str(toml).unwrap_err() {
        ScenarioError::Invalid(c) => c.key().map(str::to_owned),
        ScenarioError::Parse(p) => panic!("{p}"),
        _ => unreachable!(),
    };
    assert_eq!(key("[antenna]\nlat_deg = 95.0\nlon_deg = 0.0\n").as_deref(), Some("antenna.lat_deg"));
    assert_eq!(
        key("[satellites.cn0]\nelevation_exponent = 0.0\n").as_deref(),
        Some("satellites.cn0.elevation_exponent")
    );
    assert_eq!(key("[log]\ninterval_s = 0.0255\n").as_deref(), Some("log.interval_s"));
    assert_eq!(key("[loop]\nbn_hz = 600.0\n").as_deref(), Some("loop.bn_hz"));
    assert_eq!(key("[motion]\nsegments = []\n"), None);
    match Scenario::from_toml_str("[session]\nstart_utc = \"2024-02-08T24:00:00Z\"\n").unwrap_err() {
        ScenarioError::Invalid(ConfigError::Time { key, error }) => {
            assert_eq!(key, "session.start_utc");
            assert_eq!(error, UtcError::OutOfRange { input: "2024-02-08T24:00:00Z".into(), field: "hour" });
        }
        e => panic!("{e:?}"),
    }
    match Scenario::from_toml_str("[[motion.segments]]\nkind = \"wobble\"\naxis = [0.0, 0.0, 0.0]\namplitude_deg = 10\nperiod_s = 1\nduration_s = 4\n").unwrap_err() {
        ScenarioError::Invalid(ConfigError::InvalidAxis { key, vector }) => {
            assert_eq!((key.as_str(), vector), ("motion.segments[0].axis", [0.0; 3]));
        }
        e => panic!("{e:?}"),
    }
    // A TOML error keeps toml's own error, with its span.
    match Scenario::from_toml_str("[loop]\nbandwidth = 2\n").unwrap_err() {
        ScenarioError::Parse(p) => assert_eq!(p.span(), Some(7..16)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn model_errors_keep_their_texts() {
    let lp = LoopSection { bn_hz: -1.0, ..Default::default() };
    assert_eq!(
        lp.coeffs().unwrap_err().to_string(),
        "invalid scenario: loop: loop parameter bn_hz must be finite and positive"
    );
    let e = Oscillator::try_new(&OscillatorConfig::ocxo(), 0.0, seeded(1)).unwrap_err();
    assert_eq!(e.to_string(), "oscillator sample interval must be > 0 s (got 0)");
    assert_eq!(e.key(), None);
    let cfg = OscillatorConfig { h0: -1.0, ..OscillatorConfig::ocxo() };
    let e = Oscillator::try_new(&cfg, 0.001, seeded(1)).unwrap_err();
    assert_eq!(e.to_string(), "oscillator.h0 must be finite and >= 0 (got -1)");
    let mut m = MotionConfig::paper_default();
    m.segments[1] = Segment::shake(Axis::Vector([0.0; 3]), 1.0, 1.0, 1.0);
    let e = Motion::try_new(&m, &mut seeded(1)).unwrap_err();
    assert_eq!(e.to_string(), "motion.segments[1].axis: axis vector [0.0, 0.0, 0.0] must be finite and non-zero");
    // Alone, an axis does not know where it is.
    let e = Axis::Vector([0.0; 3]).unit().unwrap_err();
    assert_eq!(e.to_string(), "axis: axis vector [0.0, 0.0, 0.0] must be finite and non-zero");
    assert_eq!(e.under("motion.segments[4]").key(), Some("motion.segments[4].axis"));
}

#[test]
fn utc_errors() {
    assert_eq!(
        parse_utc_to_gps_s("2024-02-10T25:00:00Z"),
        Err(UtcError::OutOfRange { input: "2024-02-10T25:00:00Z".into(), field: "hour" })
    );
    assert_eq!(
        parse_utc_to_gps_s("2024-02-10T25:00:00Z").unwrap_err().to_string(),
        "the hour of the UTC time \"2024-02-10T25:00:00Z\" is out of range"
    );
    let e = parse_utc_to_gps_s("yesterday").unwrap_err();
    assert_eq!(e, UtcError::Malformed { input: "yesterday".into() });
    assert_eq!(e.to_string(), "expected a UTC time like 2024-02-08T12:00:00Z, got \"yesterday\"");
    assert_eq!(e.input(), "yesterday");
}

#[test]
fn iq_errors_keep_their_texts() {
    let sc = Scenario::default();
    let expected = [
        "IQ sampling rate must be within [1.1, 100] MHz (got 100000 Hz)",
        "IQ noise sigma must be > 0 (got 0)",
        "IQ generator needs at least one satellite",
    ];
    for ((fs_hz, noise_sigma, max_satellites), text) in
        [(1e5, 1.0, 1), (2e6, 0.0, 1), (2e6, 1.0, 0)].into_iter().zip(expected)
    {
        let cfg = IqConfig { fs_hz, format: IqFormat::Ishort, noise_sigma, max_satellites, navigation_data: true };
        let e = generate_iq(&sc, 1, &cfg, Vec::new(), &mut NullSink, |_| {}, |_| {}).unwrap_err();
        assert!(matches!(e, SimError::Iq(_)), "{e:?}");
        assert_eq!(e.to_string(), text);
    }
    assert_eq!(IqError::NoneInView.to_string(), "no GPS satellite above the elevation mask at the start");
}

#[test]
fn almanac_errors_keep_their_texts() {
    for (yuma, text) in [
        ("", "YUMA almanac holds no satellite"),
        ("ID: x1\n", "YUMA line 1: bad number 'x1': invalid float literal"),
        ("ID: 1\nfoo\n", "YUMA line 2: expected 'key: value'"),
        ("****\nID: 1\nHealth: 0\n", "YUMA record lacks 'week'"),
        ("# only a comment\n", "YUMA almanac holds no satellite"),
        ("ID: 1 # note\nweek: 1.5e\n", "YUMA line 2: bad number '1.5e': invalid float literal"),
    ] {
        assert_eq!(Constellation::from_yuma(yuma, 2300).unwrap_err().to_string(), text, "{yuma:?}");
    }
    assert_eq!(
        Constellation::from_yuma("****\nID: 1\nHealth: 0\n", 2300),
        Err(AlmanacError::MissingField { line: 2, field: "week" })
    );
    assert_eq!(Constellation::from_yuma("ID: 1\nfoo\n", 2300), Err(AlmanacError::ExpectedKeyValue { line: 2 }));
}
