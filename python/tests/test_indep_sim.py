"""scripts/indep_sim.py, the independent simulator: its files' shape, its
determinism, and the thermal noise of its discriminator against theory."""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "indep_sim.py"


def run(out: pathlib.Path, *args: str) -> None:
    r = subprocess.run([sys.executable, str(SCRIPT), "--out", str(out), *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def read_csv(path: pathlib.Path) -> np.ndarray:
    return np.genfromtxt(path, delimiter=",", names=True)


def test_the_files_have_gsens_columns_and_the_truth_its_settings(tmp_path):
    run(tmp_path, "--seed", "4", "--channels", "3", "--cn0-dbhz", "45,42,39", "--shake", "x:1.1:5:6",
        "--shake", "x:0.7:5:6", "--rest-s", "2", "--preroll-s", "2")
    imu, trk = read_csv(tmp_path / "imu.csv"), read_csv(tmp_path / "tracking.csv")
    assert imu.dtype.names == ("t_s", "fx_mps2", "fy_mps2", "fz_mps2")
    assert trk.dtype.names == ("t_s", "channel", "prn", "cn0_dbhz", "elev_deg", "phase_err_rad")
    truth = json.loads((tmp_path / "truth.json").read_text())
    # 2 + 6 + 2 + 6 + 2 = 18 s: 720 epochs of 25 ms, 3 rows each; IMU at 200 Hz from t = 0.
    assert truth["duration_s"] == 18.0 and len(trk) == 720 * 3 and len(imu) == 18 * 200 + 1
    np.testing.assert_allclose(np.unique(trk["t_s"]), 0.025 * np.arange(1, 721), rtol=1e-12)
    assert sorted(set(trk["cn0_dbhz"])) == [39.0, 42.0, 45.0]
    assert [s["start_s"] for s in truth["segments"]] == [2.0, 10.0]
    assert len(truth["gamma_hz_per_mps2"]) == 3 and truth["discriminator"] == "atan"
    # Board level at rest: |f| = g0 on z; the shaking only on x.
    rest = imu["t_s"] < 1.9
    assert abs(imu["fz_mps2"][rest].mean() - 9.80665) < 0.01
    assert np.abs(imu["fy_mps2"]).max() < 0.2 and np.abs(imu["fx_mps2"]).max() > 4.5
    assert all(c["discriminator_range_exits"] == 0 for c in truth["channels"])


def test_the_same_seed_writes_the_same_bytes(tmp_path):
    args = ("--seed", "7", "--channels", "2", "--duration-s", "3", "--rest-s", "1", "--preroll-s", "1")
    run(tmp_path / "a", *args)
    run(tmp_path / "b", *args)
    run(tmp_path / "c", *args[:1], "8", *args[2:])
    for name in ("imu.csv", "tracking.csv", "truth.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert (tmp_path / "a" / "tracking.csv").read_bytes() != (tmp_path / "c" / "tracking.csv").read_bytes()


def test_a_static_session_has_the_thermal_sigma_its_cn0_predicts(tmp_path):
    cn0_dbhz, t_s, channels = 45.0, 1e-3, 8
    run(tmp_path, "--seed", "2", "--duration-s", "30", "--rest-s", "0", "--osc-rw-hz-per-sqrt-s", "0",
        "--channels", str(channels), "--cn0-dbhz", str(cn0_dbhz), "--order", "3", "--preroll-s", "5")
    trk = read_csv(tmp_path / "tracking.csv")
    c = 10 ** (cn0_dbhz / 10)
    theory = (1 + 1 / (2 * t_s * c)) / (2 * t_s * c)
    variances, dof = [], 0
    for ch in range(channels):
        p = trk["phase_err_rad"][trk["channel"] == ch]
        variances.append(p.var(ddof=1))
        dof += p.size - 1
    measured = float(np.mean(variances))
    # The variance of a Gaussian sample has relative standard error sqrt(2/dof).
    assert abs(measured / theory - 1) < 3 * np.sqrt(2 / dof), (measured, theory)
