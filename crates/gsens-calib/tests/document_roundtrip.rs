//! The result document reads back: the JSON of a document, read with
//! `ResultDocument::from_json_str` and written again, is the same text —
//! for a trusted session, one with an axis never shaken (nulls where there is
//! no number), one whose loop the data chose, and one with a channel that
//! never enters the average.

mod common;

use gsens_calib::{PipelineSettings, ResultDocument, TimeOffset, calibrate_logs};
use gsens_core::{LoopModel, LoopSpec};
use gsens_io::{ImuSeries, TrackingLog, TrackingRow};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// Four channels of the paper's session, each with its own white noise; the
/// fourth at a C/N0 far below the others' and with a gap for half the
/// session when `weak_channel`.
fn logs(shake_z: bool, weak_channel: bool) -> (TrackingLog, ImuSeries) {
    let (phase, accel) = common::paper_session(3, shake_z, |_, _, p| Some(p));
    let t_s = common::times(phase.len());
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(8);
    let noise = Normal::new(0.0, 0.01).unwrap();
    let mut rows = Vec::new();
    for (k, p) in phase.iter().enumerate() {
        for c in 0..4u32 {
            let weak = weak_channel && c == 3;
            if weak && k % 2 == 0 {
                continue;
            }
            rows.push(TrackingRow {
                t_s: t_s[k],
                channel: c,
                prn: 10 + c,
                cn0_dbhz: if weak { 20.0 } else { 45.0 },
                elev_deg: None,
                phase_err_rad: p.unwrap() + noise.sample(&mut rng) * if weak { 30.0 } else { 1.0 },
            });
        }
    }
    (TrackingLog::from_rows("round trip", &rows).unwrap(), ImuSeries { t_s, accel_mps2: accel })
}

fn round_trip(doc: &ResultDocument) {
    let json = doc.to_json_string().unwrap();
    let back = ResultDocument::from_json_str(&json).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back.to_json_string().unwrap(), json);
    assert_eq!(back.trustworthy, doc.trustworthy);
    assert_eq!(back.warnings, doc.warnings);
}

#[test]
fn documents_read_back_to_the_same_json() {
    let mut stated = PipelineSettings::default();
    stated.estimate.receiver_loop = LoopModel::kaplan(LoopSpec::PAPER, Some(common::T));
    stated.loop_stated = true;
    stated.time_offset = TimeOffset::Fixed { imu_time_offset_s: 0.0 };
    let cases = [(true, false, &stated), (false, false, &stated), (true, true, &stated)];
    for (shake_z, weak, settings) in cases {
        let (tracking, imu) = logs(shake_z, weak);
        let doc = calibrate_logs(&tracking, &imu, "imu", settings).unwrap().document(Some(common::GAMMA));
        if !shake_z {
            assert_eq!(doc.calibration.gamma_hz_per_mps2[2], None);
        }
        round_trip(&doc);
    }
    // No loop stated: the data choose one, and the document says so.
    let (tracking, imu) = logs(true, false);
    let doc = calibrate_logs(&tracking, &imu, "imu", &PipelineSettings::default()).unwrap().document(None);
    round_trip(&doc);
}

#[test]
fn a_file_that_is_not_a_document_is_named_with_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("est.json");
    std::fs::write(&path, "{\n  \"tool\": 3\n}\n").unwrap();
    let e = ResultDocument::read_json_file(&path).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}:2:", path.display())) && e.contains("not a gsens result document"), "{e}");
}

/// Γ̂ and its covariance read back from a document file as written; an axis
/// never shaken is an error naming the file and the first null entry.
#[test]
fn gamma_reads_back_from_a_file_and_an_unobservable_axis_is_named() {
    let mut settings = PipelineSettings::default();
    settings.estimate.receiver_loop = LoopModel::kaplan(LoopSpec::PAPER, Some(common::T));
    settings.loop_stated = true;
    settings.time_offset = TimeOffset::Fixed { imu_time_offset_s: 0.0 };
    let dir = tempfile::tempdir().unwrap();
    for shake_z in [true, false] {
        let (tracking, imu) = logs(shake_z, false);
        let doc = calibrate_logs(&tracking, &imu, "imu", &settings).unwrap().document(None);
        let path = dir.path().join(format!("z{shake_z}.json"));
        doc.write_json_file(&path).unwrap();
        let read = ResultDocument::read_gamma_file(&path);
        if shake_z {
            let (gamma, cov) = read.unwrap();
            assert_eq!(gamma.map(Some), doc.calibration.gamma_hz_per_mps2);
            assert_eq!(cov.map(|r| r.map(Some)), doc.calibration.covariance_hz_per_mps2_sq);
        } else {
            // The first entry without a number: x's covariance with the unobservable z.
            let e = read.unwrap_err().to_string();
            let entry = "covariance_hz_per_mps2_sq[0][2]";
            assert_eq!(e, format!("{}: {entry} is null: the axis was not observable", path.display()));
        }
    }
}
