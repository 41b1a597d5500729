//! The demo of a scenario: its session simulated into a folder as a
//! receiver's logs (`imu.csv`, `tracking.csv`, `truth.json`), estimated from
//! those files as a user would, with the scenario's receiver stated
//! ([`scenario_settings`]), and compared with the truth.

use crate::{MonteCarloError, scenario_settings};
use gsens_calib::{CalibError, CalibrationOptions, Outcome, PipelineError, PipelineSettings, ResultDocument};
use gsens_core::units::{Decimal, GPS_L1_HZ};
use gsens_sim::LogsError;
use gsens_sim::error::ConfigError;
use gsens_sim::oscillator::{AllanComparison, allan_comparison};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::Truth;
use std::path::{Path, PathBuf};

/// Why a demo could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DemoError {
    /// The session could not be simulated or written.
    #[error(transparent)]
    Simulation(#[from] LogsError),
    /// The scenario's receiver could not be stated.
    #[error(transparent)]
    Scenario(#[from] MonteCarloError),
    /// The options are not valid settings.
    #[error(transparent)]
    Options(#[from] CalibError),
    /// The oscillator's Allan deviation could not be simulated.
    #[error(transparent)]
    Oscillator(#[from] ConfigError),
    /// No folder of the demo's own could be made for its logs.
    #[error("cannot make a folder in the system's temporary directory for the demo's logs")]
    Scratch(#[source] std::io::Error),
}

/// Where a demo's logs go: the folder a caller names, kept, or a fresh
/// folder of the run's own in the system's temporary directory
/// (`gsens-demo-…`), removed with everything in it when this is dropped.
#[derive(Debug)]
pub enum DemoFolder {
    /// The caller's folder.
    Named(PathBuf),
    /// The run's own, removed at the end.
    Scratch(tempfile::TempDir),
}

impl DemoFolder {
    /// `named`, or a fresh scratch folder when `None`.
    pub fn new(named: Option<&Path>) -> Result<Self, DemoError> {
        Ok(match named {
            Some(dir) => DemoFolder::Named(dir.to_path_buf()),
            None => DemoFolder::Scratch(
                tempfile::Builder::new().prefix("gsens-demo-").tempdir().map_err(DemoError::Scratch)?,
            ),
        })
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        match self {
            DemoFolder::Named(dir) => dir,
            DemoFolder::Scratch(dir) => dir.path(),
        }
    }

    /// Whether it is removed at the end.
    pub fn is_scratch(&self) -> bool {
        matches!(self, DemoFolder::Scratch(_))
    }
}

/// A scenario's session simulated into a folder, ready to be estimated.
#[derive(Debug, Clone)]
pub struct Demo {
    /// The scenario simulated.
    pub scenario: Scenario,
    /// Its seed.
    pub seed: u64,
    /// The session's truth (what `truth.json` holds).
    pub truth: Truth,
    /// The IMU log written.
    pub imu: PathBuf,
    /// The tracking log written.
    pub tracking: PathBuf,
    /// The estimate's settings: the options around the scenario's receiver.
    pub settings: PipelineSettings,
}

/// Simulates `scenario` with `seed` into `dir` (`progress` is told the
/// fraction done) and states its receiver in the settings of `options`
/// ([`CalibrationOptions::pipeline_settings_around`] of
/// [`scenario_settings`]): the loop, the logged phase, the carrier and the
/// IMU's datasheet accuracy are the scenario's, the rest the options'.
pub fn simulate_demo(
    scenario: &Scenario,
    seed: u64,
    dir: &Path,
    options: &CalibrationOptions,
    progress: impl FnMut(f64),
) -> Result<Demo, DemoError> {
    let truth = gsens_sim::simulate_to_dir(scenario, seed, dir, progress)?;
    let settings = options.pipeline_settings_around(scenario_settings(scenario, &options.estimate_settings())?)?;
    let (imu, tracking) = (dir.join("imu.csv"), dir.join("tracking.csv"));
    Ok(Demo { scenario: scenario.clone(), seed, truth, imu, tracking, settings })
}

/// The line that opens a demo of `scenario` (`named`: the caller's, else
/// the embedded paper experiment) at `seed` into `dir`, a folder of the
/// run's own removed at the end when `scratch` (the option `out`, named by
/// `name`, keeps the logs).
pub fn render_demo_start(
    scenario: &Scenario,
    named: bool,
    seed: u64,
    dir: &Path,
    scratch: bool,
    name: impl Fn(&str) -> String,
) -> String {
    let which = if named { "given scenario" } else { "paper's experiment" };
    let kept =
        if scratch { format!(" (removed at the end: {} DIR keeps the logs)", name("out")) } else { String::new() };
    format!("simulating {:.0} s of the {which} (seed {seed}) into {}{kept} …\n", scenario.duration_s(), dir.display())
}

impl Demo {
    /// The estimate from the files written, as `calibrate_files` makes it.
    pub fn calibrate(&self) -> Result<Outcome, PipelineError> {
        gsens_calib::calibrate_files(&self.tracking, &self.imu, &self.settings)
    }

    /// The result document of `outcome` with the true Γ.
    pub fn document(&self, outcome: &Outcome) -> ResultDocument {
        outcome.document(Some(self.truth.sensitivity.gamma_hz_per_mps2))
    }

    /// The calibration options ([`CalibrationOptions`]' names, with their
    /// values as text) that state the scenario's receiver to an estimate of
    /// these logs: the loop's order, bandwidth, update interval and logged
    /// phase, the carrier when it is not GPS L1, and the IMU's datasheet
    /// accuracy when the scenario gives one.
    pub fn stated_options(&self) -> Vec<(&'static str, String)> {
        let l = &self.scenario.tracking_loop;
        let mut options = vec![
            ("order", l.order.to_string()),
            ("bn_hz", l.bn_hz.to_string()),
            ("loop_interval_s", l.interval_s.to_string()),
            ("logged_phase", self.scenario.log.phase.name().to_string()),
        ];
        let e = &self.settings.estimate;
        if e.carrier_hz != GPS_L1_HZ {
            options.push(("carrier_hz", e.carrier_hz.to_string()));
        }
        // The scenario's IMU error model enters σ as a datasheet's would.
        if e.imu_scale_sigma > 0.0 {
            options.push(("imu_scale_sigma_ppm", Decimal(e.imu_scale_sigma * 1e6).to_string()));
        }
        if e.imu_misalignment_sigma_rad > 0.0 {
            options.push(("imu_misalignment_sigma_mrad", Decimal(e.imu_misalignment_sigma_rad * 1e3).to_string()));
        }
        options
    }

    /// The line that says how the demo estimates: from the logs written,
    /// as `gsens estimate` would with the [`Demo::stated_options`] and
    /// `given` (the caller's own estimation options, as given), every
    /// option named by `name` (a command line's flag, say).
    pub fn estimate_line(&self, given: &[String], name: impl Fn(&str) -> String) -> String {
        let (i, t) = (self.imu.display(), self.tracking.display());
        let stated = self.stated_options().into_iter().map(|(option, v)| format!("{} {v}", name(option)));
        let options: Vec<String> = stated.chain(given.iter().cloned()).collect();
        format!(
            "estimating from {i} and {t} (the command line: gsens estimate {} {i} {} {t} {})\n\n",
            name("imu"),
            name("tracking"),
            options.join(" ")
        )
    }

    /// The Allan deviation of the scenario's oscillator, simulated for 20
    /// minutes at 40 Hz with the demo's seed, against its model; `None` for
    /// an oscillator without noise.
    pub fn oscillator_allan(&self) -> Result<Option<AllanComparison>, DemoError> {
        let cfg = self.scenario.oscillator.config();
        let noisy = cfg.h0 + cfg.h_neg1 + cfg.h_neg2 + cfg.h2 > 0.0;
        Ok(if noisy { Some(allan_comparison(&cfg, 0.025, 48_000, self.seed)?) } else { None })
    }

    /// The oscillator's name for the Allan figure's legend.
    pub fn oscillator_label(&self) -> String {
        self.scenario.oscillator.preset.description().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A named folder is the caller's and kept; a scratch folder exists,
    /// is the run's own and goes with everything in it when dropped.
    #[test]
    fn a_scratch_folder_is_removed_a_named_one_kept() {
        let kept = tempfile::tempdir().unwrap();
        let named = DemoFolder::new(Some(kept.path())).unwrap();
        assert_eq!((named.path(), named.is_scratch()), (kept.path(), false));
        drop(named);
        assert!(kept.path().is_dir());
        let scratch = DemoFolder::new(None).unwrap();
        let dir = scratch.path().to_path_buf();
        assert!(scratch.is_scratch() && dir.is_dir());
        assert!(dir.file_name().unwrap().to_str().unwrap().starts_with("gsens-demo-"));
        std::fs::write(dir.join("imu.csv"), "t_s\n").unwrap();
        drop(scratch);
        assert!(!dir.exists());
    }
    use gsens_sim::scenario::OscillatorKind;

    fn demo_of(scenario: &Scenario, dir: &Path) -> Demo {
        let mut last = 0.0;
        let demo = simulate_demo(scenario, 3, dir, &CalibrationOptions::default(), |f| last = f).unwrap();
        assert_eq!(last, 1.0);
        demo
    }

    /// A short session of the embedded scenario: its receiver is stated by
    /// name as the scenario gives it, and the files estimate close to the truth.
    #[test]
    fn the_demo_states_the_scenarios_receiver_and_estimates_its_files() {
        let mut scenario = Scenario::default();
        scenario.session.duration_s = Some(45.0);
        let dir = tempfile::tempdir().unwrap();
        let demo = demo_of(&scenario, dir.path());
        assert!(demo.imu.is_file() && demo.tracking.is_file() && dir.path().join("truth.json").is_file());
        let stated: Vec<String> = demo.stated_options().iter().map(|(k, v)| format!("{k}={v}")).collect();
        let line = demo.estimate_line(&["<method>".into(), "gls".into()], |n| format!("<{n}>"));
        let (i, t) = (demo.imu.display(), demo.tracking.display());
        let expected = format!(
            "estimating from {i} and {t} (the command line: gsens estimate <imu> {i} <tracking> {t} <order> 2 <bn_hz> 3 \
             <loop_interval_s> 0.001 <logged_phase> mean <imu_scale_sigma_ppm> 1000 <imu_misalignment_sigma_mrad> 1 \
             <method> gls)\n\n"
        );
        assert_eq!(line, expected);
        let start = render_demo_start(&scenario, false, 3, dir.path(), true, |n| format!("<{n}>"));
        let into = dir.path().display();
        let expected = format!(
            "simulating 45 s of the paper's experiment (seed 3) into {into} (removed at the end: <out> DIR keeps the logs) …\n"
        );
        assert_eq!(start, expected);
        let kept = render_demo_start(&scenario, true, 3, dir.path(), false, |n| format!("<{n}>"));
        assert_eq!(kept, format!("simulating 45 s of the given scenario (seed 3) into {into} …\n"));
        // The embedded scenario: the paper's 2nd-order 3 Hz loop at 1 ms, the mean logged,
        // an IMU with 1000 ppm scale and 1 mrad misalignment; GPS L1.
        let expected = [
            "order=2",
            "bn_hz=3",
            "loop_interval_s=0.001",
            "logged_phase=mean",
            "imu_scale_sigma_ppm=1000",
            "imu_misalignment_sigma_mrad=1",
        ];
        assert_eq!(stated, expected);
        assert!(demo.settings.loop_stated);
        let outcome = demo.calibrate().unwrap();
        let truth = demo.truth.sensitivity.gamma_hz_per_mps2;
        assert_eq!(demo.document(&outcome).truth_gamma_hz_per_mps2, Some(truth));
        let x = outcome.calibration.gamma_hz_per_mps2[0].unwrap();
        assert!((x - truth[0]).abs() < 0.1 * truth[0].abs(), "{x} vs {}", truth[0]);
        let allan = demo.oscillator_allan().unwrap().expect("the OCXO has noise");
        assert_eq!(allan.duration_s, 1200.0);
        assert_eq!(demo.oscillator_label(), "OCXO preset");
    }

    /// A noise-free oscillator has no Allan deviation to draw; another
    /// carrier is stated.
    #[test]
    fn a_noise_free_oscillator_has_no_allan_figure() {
        let mut scenario = Scenario::default();
        scenario.session.duration_s = Some(20.0);
        scenario.oscillator.preset = OscillatorKind::Ideal;
        scenario.oscillator.carrier_hz = 1_176.45e6;
        let dir = tempfile::tempdir().unwrap();
        let demo = demo_of(&scenario, dir.path());
        assert!(demo.oscillator_allan().unwrap().is_none());
        assert!(demo.stated_options().contains(&("carrier_hz", "1176450000".to_string())));
    }
}
