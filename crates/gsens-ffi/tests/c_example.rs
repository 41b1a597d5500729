//! `examples/c/calibrate.c`, built with the system C compiler against the
//! static library and run on the default session's epoch series (as `gsens
//! estimate --epochs-out` writes it), gives the Γ̂ of the Rust pipeline on
//! the same log to 1e-9 relative.

use std::path::{Path, PathBuf};
use std::process::Command;

use gsens_core::{LoggedPhase, LoopModel, LoopSpec};

/// The static library, built by cargo into a target directory of its own
/// beside this test's (`cargo test` builds the crate as an rlib only, and a
/// nested build in the same directory would wait for the outer one's lock):
/// the release build the README's C API section makes there too (the CLI's
/// `c_api_readme` test), so that whichever runs second finds it built.
fn static_library() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    // target/<profile>/deps/<test> → target/
    let target = exe.parent().and_then(Path::parent).and_then(Path::parent).unwrap();
    let dir = target.join("ffi-c-example");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(&cargo)
        .args(["build", "--release", "-p", "gsens-ffi", "--locked", "--target-dir"])
        .arg(&dir)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .unwrap_or_else(|e| panic!("cannot run {cargo}: {e}"));
    assert!(status.success(), "cargo build -p gsens-ffi failed");
    let lib = dir.join("release/libgsens_ffi.a");
    assert!(lib.exists(), "{} not built", lib.display());
    lib
}

/// Compiles the C example with `$CC` (default `cc`).
fn build_example(out: &Path) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let exe = out.join("calibrate");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-O2"])
        .arg(root.join("examples/c/calibrate.c"))
        .arg("-I")
        .arg(root.join("crates/gsens-ffi/include"))
        .arg(static_library())
        // What the Rust standard library needs from the system (rustc --print native-static-libs).
        .args(["-lgcc_s", "-lutil", "-lrt", "-lpthread", "-lm", "-ldl", "-lc", "-o"])
        .arg(&exe)
        .status()
        .unwrap_or_else(|e| panic!("cannot run the C compiler {cc}: {e}"));
    assert!(status.success(), "the C example does not build");
    exe
}

#[test]
fn the_c_example_gives_the_pipelines_gamma() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-ffi-c-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    gsens_sim::simulate_to_dir(&gsens_sim::scenario::Scenario::default(), 1, &dir, |_| {}).unwrap();
    let truth_loop = gsens_sim::read_truth_loop(&dir.join("truth.json")).unwrap().unwrap();
    let mut settings = gsens_calib::PipelineSettings::default();
    settings.estimate.receiver_loop = truth_loop.receiver_loop;
    settings.estimate.logged_phase = truth_loop.logged_phase;
    settings.loop_stated = true;
    // The C API estimates through the loop model: compared with the pipeline's estimate through it.
    settings.measurement = gsens_calib::MeasurementChoice::TrackingError;
    let outcome = gsens_calib::calibrate_files(&dir.join("tracking.csv"), &dir.join("imu.csv"), &settings).unwrap();
    let series = outcome.series();
    let epochs = dir.join("epochs.csv");
    gsens_io::write_epochs_csv(
        std::fs::File::create(&epochs).unwrap(),
        series.t_s,
        series.phase_err_rad,
        series.accel_mps2,
    )
    .unwrap();
    let c = &outcome.calibration;
    let LoopModel::Kaplan { spec: LoopSpec::SecondOrder { bn_hz, zeta }, interval_s: Some(loop_t) } = c.loop_used
    else {
        panic!("the default session's loop is a 2nd-order Kaplan loop: {:?}", c.loop_used)
    };
    let logged = match c.settings.logged_phase {
        LoggedPhase::Mean => "mean",
        LoggedPhase::Last => "last",
    };
    let exe = build_example(&dir);
    let args = [
        epochs.display().to_string(),
        "2".into(),
        format!("{bn_hz:e}"),
        format!("{zeta:e}"),
        format!("{loop_t:e}"),
        format!("{:e}", series.log_interval_s),
        logged.into(),
        format!("{:e}", c.settings.warmup_s),
        format!("{:e}", c.settings.highpass_hz),
    ];
    let run = Command::new(&exe).args(&args).output().unwrap();
    let text = String::from_utf8(run.stdout).unwrap();
    assert!(run.status.success(), "{text}\n{}", String::from_utf8_lossy(&run.stderr));
    eprintln!("{text}");
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        let line = text.lines().find(|l| l.starts_with(&format!("gamma_{axis} "))).unwrap();
        let fields: Vec<&str> = line.split_whitespace().collect();
        let from_c: f64 = fields[1].parse().unwrap_or_else(|_| panic!("{line}"));
        let rust = c.gamma_hz_per_mps2[i].expect("the default session observes every axis");
        let rel = ((from_c - rust) / rust).abs();
        eprintln!("{axis}: C {from_c:.17e}, pipeline {rust:.17e}, relative {rel:.1e}");
        assert!(rel <= 1e-9, "{axis}: C {from_c} vs the pipeline's {rust} ({rel:e} relative)");
        // σ: the white-noise σ of the pipeline (sigma_colour_factor 1) …
        let sigma_c: f64 = fields[2].parse().unwrap();
        let white = c.sigma_white_hz_per_mps2[i].unwrap();
        assert!(((sigma_c - white) / white).abs() <= 1e-9, "{axis}: σ {sigma_c} vs {white}");
        // … which the residuals' colour makes 2.5–2.8× too small here (the factors the header's docs quote).
        let colour = c.sigma_hz_per_mps2[i].unwrap() / white;
        eprintln!("{axis}: σ/σ_white of the pipeline {colour:.2}");
        assert!((2.4..3.0).contains(&colour), "{axis}: {colour}");
    }
    // The compensator on the first epoch's specific force: −aᵀΓ̂.
    let line = text.lines().find(|l| l.starts_with("nco_correction_hz ")).unwrap();
    let hz: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    let g = c.gamma_hz_per_mps2.map(|g| g.unwrap());
    let a = series.accel_mps2[0];
    let expected = -(a[0] * g[0] + a[1] * g[1] + a[2] * g[2]);
    assert!((hz - expected).abs() <= 1e-9 * expected.abs(), "{hz} vs {expected}");
    std::fs::remove_dir_all(&dir).ok();
}
