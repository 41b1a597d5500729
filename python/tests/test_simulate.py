"""gsens.simulate against `gsens simulate` (the same seed, the same numbers),
its determinism, its overrides, and gsens.montecarlo against single runs."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gsens
from conftest import run_cli


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def test_the_arrays_are_the_cli_logs_of_the_same_seed(gsens_bin, tmp_path):
    r = run_cli(gsens_bin, "simulate", "--seed", "5", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    s = gsens.simulate(seed=5)
    imu = read_csv(tmp_path / "imu.csv")
    for c in gsens.IMU_COLUMNS:
        np.testing.assert_array_equal(s.imu[c], imu[c])
    tracking = read_csv(tmp_path / "tracking.csv")
    order = np.lexsort((tracking["channel"], tracking["t_s"]))
    for c in gsens.TRACKING_COLUMNS:
        np.testing.assert_array_equal(s.tracking[c], tracking[c][order])
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert truth == s.truth


def test_the_same_seed_gives_the_same_arrays_and_another_seed_others():
    a, b, c = gsens.simulate(seed=9), gsens.simulate(seed=9), gsens.simulate(seed=10)
    for k in a.tracking:
        np.testing.assert_array_equal(a.tracking[k], b.tracking[k])
    assert not np.array_equal(a.tracking["phase_err_rad"][:1000], c.tracking["phase_err_rad"][:1000])
    assert a.imu["fx_mps2"].dtype == np.float64 and a.tracking["channel"].dtype == np.int64


def test_overrides_change_the_scenario_key_by_key():
    s = gsens.simulate(seed=1, oscillator={"gamma_hz_per_mps2": [0.2, 0.0, -0.1]}, session={"duration_s": 30})
    np.testing.assert_array_equal(s.gamma_hz_per_mps2, [0.2, 0.0, -0.1])
    assert s.truth["duration_s"] == 30
    assert s.imu["t_s"][-1] == pytest.approx(30.0)
    with pytest.raises(gsens.GsensError):
        gsens.simulate(oscilator={"gamma_hz_per_mps2": [0.2, 0.0, -0.1]})
    with pytest.raises(gsens.GsensError):
        gsens.simulate("no-such-scenario.toml")
    assert "[oscillator]" in gsens.default_scenario()


def test_montecarlo_runs_are_the_single_estimates_of_their_seeds():
    mc = gsens.montecarlo(runs=2, seed=3, methods=["batch", "gls"])
    # The default scenario logs the NCO: the rows from its phase and its frequency beside the methods asked for.
    assert set(mc["methods"]) == {"batch", "gls", "loop-free", "nco-frequency"} and mc["runs"] == 2
    for run in mc["per_run"]:
        s = gsens.simulate(seed=run["seed"])
        e = gsens.estimate(s.imu, s.tracking, **s.estimate_settings())
        batch = next(m for m in run["methods"] if m["method"] == "batch")
        np.testing.assert_allclose(batch["gamma_hz_per_mps2"], e.gamma_hz_per_mps2, rtol=1e-12)
    stats = mc["methods"]["batch"]
    errors = np.array([next(m for m in r["methods"] if m["method"] == "batch")["gamma_hz_per_mps2"] for r in mc["per_run"]])
    # RMSE against Γ in the IMU's axes (what the IMU's misalignment lets an
    # estimate reach), and against the body frame's Γ.
    for key, truth_key in (("rmse", "gamma_imu_axes_hz_per_mps2"), ("rmse_body", "gamma_hz_per_mps2")):
        truth = np.array([r[truth_key] for r in mc["per_run"]])
        np.testing.assert_allclose(stats[key], np.sqrt(np.mean((errors - truth) ** 2, axis=0)), rtol=1e-9)


def test_montecarlo_refuses_a_stated_loop():
    with pytest.raises(gsens.GsensError):
        gsens.montecarlo(runs=1, bn_hz=3)
