"""The example that reproduces the paper's figures runs, and its predicted
phase error explains the measured one (the compensation figure's claim)."""

from __future__ import annotations

import importlib.util
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import gsens

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "paper_figures.py"
FIGURES = ("loop_response", "shaking", "phase_error", "convergence", "compensation")


def test_the_figures_are_written(tmp_path):
    pytest.importorskip("matplotlib")
    r = subprocess.run([sys.executable, str(EXAMPLE), "--out", str(tmp_path), "--seed", "2"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for name in FIGURES:
        png = tmp_path / f"{name}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name


def test_the_predicted_phase_error_explains_the_measured_one(session):
    pytest.importorskip("matplotlib")
    spec = importlib.util.spec_from_file_location("paper_figures", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    settings = session.estimate_settings()
    e = gsens.estimate(session.imu, session.tracking, **settings)
    ep = e.epochs()
    loop = gsens.Loop(order=settings["order"], bn_hz=settings["bn_hz"], interval_s=settings["loop_interval_s"])
    substeps = int(round(e.to_dict()["log_interval_s"] / settings["loop_interval_s"]))
    predicted = example.predicted_phase_err_rad(loop, ep["accel_mps2"] - ep["accel_mps2"][0], e.gamma_hz_per_mps2, substeps)
    measured = ep["phase_err_rad"] - np.nanmedian(ep["phase_err_rad"])
    keep = np.isfinite(measured) & (ep["t_s"] > ep["t_s"][0] + 5.0)
    before = np.sqrt(np.mean(measured[keep] ** 2))
    after = np.sqrt(np.mean((measured - predicted)[keep] ** 2))
    # The document's RMS after compensation is the estimator's own residual;
    # this rough model (aᵀΓ held per epoch, median for the high-pass) must
    # come within 50 % of it and remove most of the g-induced error.
    assert after < 0.2 * before
    assert after < 1.5 * e.to_dict()["rms_after_rad"]
