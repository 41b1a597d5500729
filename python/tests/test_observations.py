"""RINEX and UBX logs of a simulated session, written by the independent fixture script
(scripts/fixtures/ubx_rinex_from_session.py), calibrated by ``gsens estimate --rinex`` and
``--ubx`` with the receiver's loop identified: the commands of the README's section "RINEX and
u-blox logs"."""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import pytest

from conftest import run_cli

REPO = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = REPO / "scripts" / "fixtures"


@pytest.fixture(scope="module")
def observation_logs(gsens_bin, tmp_path_factory) -> pathlib.Path:
    """The README's session (seed 3, NCO logged, IMU at 100 Hz) as obs.rnx, log.ubx and
    imu_gps.csv."""
    out = tmp_path_factory.mktemp("obs")
    scenario = out / "obs.toml"
    scenario.write_text("[log]\nnco = true\n[imu]\nrate_hz = 100.0\n")
    r = run_cli(gsens_bin, "simulate", "--scenario", str(scenario), "--seed", "3", "--out", str(out))
    assert r.returncode == 0, r.stderr
    for script, args in (
        ("ubx_rinex_from_session.py", [str(out / "obs.rnx"), str(out / "log.ubx"), "--rate-hz", "10", "--seconds", "130"]),
        ("shift_imu_to_gps.py", []),
    ):
        r = subprocess.run([sys.executable, str(FIXTURES / script), str(out), *args], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
    return out


def estimate(gsens_bin: str, out: pathlib.Path, *inputs: str) -> dict:
    doc_path = out / "doc.json"
    r = run_cli(gsens_bin, "estimate", *inputs, "--json", str(doc_path))
    assert r.returncode == 0, r.stdout + r.stderr
    assert "receiver loop identified from the carrier phase differenced: order 2" in r.stdout, r.stdout
    return json.loads(doc_path.read_text())


def check(doc: dict, truth: dict) -> None:
    """Γ̂ within 3σ of the truth on every axis, trustworthy, the loop's Bn within 3σ of 3 Hz, and
    H = 1 flagged: more than 15 % off at the shaking."""
    want = truth["gamma_imu_axes_hz_per_mps2"]
    for g, s, w in zip(doc["gamma_hz_per_mps2"], doc["sigma_hz_per_mps2"], want):
        assert abs(g - w) < 3 * s, (g, s, w)
    assert doc["trustworthy"] and doc["measurement"] == "nco_frequency"
    loop = doc["identified_loop"]
    assert loop["resolution"] == "resolved" and loop["order"] == 2
    assert abs(loop["bn_hz"] / 3.0 - 1.0) < 3 * loop["sigma_ln_bn"], loop["bn_hz"]
    assert loop["h_unity_error"] > 0.15


def test_a_rinex_file_with_an_imu_log_gives_gamma_within_sigma(gsens_bin, observation_logs):
    out = observation_logs
    doc = estimate(gsens_bin, out, "--imu", str(out / "imu_gps.csv"), "--rinex", str(out / "obs.rnx"))
    check(doc, json.loads((out / "truth.json").read_text()))
    assert doc["source"]["receiver"] == "RINEX 3.04" and len(doc["source"]["tracks"]) == 7


def test_a_ubx_log_with_its_own_accelerometer_gives_gamma_within_sigma(gsens_bin, observation_logs):
    out = observation_logs
    doc = estimate(gsens_bin, out, "--ubx", str(out / "log.ubx"))
    check(doc, json.loads((out / "truth.json").read_text()))
    assert doc["source"]["receiver"] == "UBX" and "(ESF; sensor time: free-running, tied" in doc["inputs"]["imu"]


def test_a_rinex_file_without_an_imu_log_is_refused(gsens_bin, observation_logs):
    r = run_cli(gsens_bin, "estimate", "--rinex", str(observation_logs / "obs.rnx"))
    assert r.returncode != 0 and "--imu" in r.stderr, r.stderr


def test_python_estimates_the_same_from_rinex_and_ubx(gsens_bin, observation_logs):
    import gsens

    out = observation_logs
    truth = json.loads((out / "truth.json").read_text())
    est = gsens.estimate(out / "imu_gps.csv", rinex=out / "obs.rnx")
    doc = est.to_dict()
    check(doc, truth)
    cli = estimate(gsens_bin, out, "--imu", str(out / "imu_gps.csv"), "--rinex", str(out / "obs.rnx"))
    assert doc["gamma_hz_per_mps2"] == cli["gamma_hz_per_mps2"]
    check(gsens.estimate(ubx=out / "log.ubx", observable="carrier_phase").to_dict(), truth)
    with pytest.raises(gsens.GsensError, match="observable"):
        gsens.estimate(ubx=out / "log.ubx", observable="phase")


def test_an_imu_on_another_time_base_is_refused_by_name(gsens_bin, observation_logs):
    """The fixture's ESF tags are a free-running sensor clock: read as GPS time of week, the IMU
    misses the log, and the error says how to fix it."""
    r = run_cli(gsens_bin, "estimate", "--ubx", str(observation_logs / "log.ubx"), "--ubx-sensor-time", "gps-tow-ms")
    assert r.returncode != 0 and "overlap by less than half" in r.stderr and "sensor time" in r.stderr, r.stderr


def test_python_and_the_cli_model_gnss_sdrs_loop_from_its_configuration(gsens_bin):
    """GNSS-SDR's own RINEX with the run's configuration: its loop modelled exactly, Γ̂ within 3σ
    of the truth with σ under 1 % of Γ, from Python and the command line alike."""
    import gsens

    d = REPO / "crates" / "gsens-rinex" / "tests" / "fixtures" / "gnss-sdr"
    inputs = ("--imu", str(d / "imu.csv"), "--rinex", str(d / "gnss-sdr.24O"), "--gnss-sdr-conf", str(d / "gnss-sdr.conf"))
    r = run_cli(gsens_bin, "estimate", *inputs)
    assert r.returncode == 0 and "receiver loop: GNSS-SDR's, modelled exactly" in r.stdout, r.stdout + r.stderr
    doc = gsens.estimate(d / "imu.csv", rinex=d / "gnss-sdr.24O", gnss_sdr_conf=d / "gnss-sdr.conf").to_dict()
    want = json.loads((d / "truth.json").read_text())["gamma_imu_axes_hz_per_mps2"]
    for g, s, w in zip(doc["gamma_hz_per_mps2"], doc["sigma_hz_per_mps2"], want):
        assert abs(g - w) < 3 * s and s < 0.01 * abs(w), (g, s, w)
    assert doc["trustworthy"] and doc["inputs"]["gnss_sdr_conf"] == str(d / "gnss-sdr.conf")
