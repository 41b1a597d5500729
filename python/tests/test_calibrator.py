"""gsens.Calibrator (the streaming calibrator of the C API and `gsens live`)
against the batch estimate on the same epochs."""

from __future__ import annotations

import numpy as np
import pytest

import gsens


@pytest.fixture(scope="module")
def batch(session):
    settings = {**session.estimate_settings(), "time_offset": "none", "loop_check": False}
    return settings, gsens.estimate(session.imu, session.tracking, **settings)


def test_fed_the_batch_epochs_it_ends_at_the_batch_least_squares(batch):
    settings, e = batch
    ep = e.epochs()
    c = gsens.Calibrator(e.to_dict()["log_interval_s"], **settings)
    c.feed_many(ep["accel_mps2"], ep["phase_err_rad"])
    c.finish()
    r = c.estimate()
    d = e.to_dict()
    np.testing.assert_allclose(r["gamma_hz_per_mps2"], d["gamma_raw_hz_per_mps2"], rtol=1e-9)
    np.testing.assert_allclose(r["sigma_hz_per_mps2"], d["sigma_white_hz_per_mps2"], rtol=1e-9)
    assert r["observable"] == [True, True, True]


def test_one_epoch_at_a_time_is_the_same_as_many(batch):
    settings, e = batch
    ep = e.epochs()
    n = 3000
    one, many = gsens.Calibrator(0.025, **settings), gsens.Calibrator(0.025, **settings)
    for a, p in zip(ep["accel_mps2"][:n], ep["phase_err_rad"][:n]):
        one.feed(list(a), None if np.isnan(p) else float(p))
    many.feed_many(ep["accel_mps2"][:n], ep["phase_err_rad"][:n])
    a, b = one.estimate(), many.estimate()
    np.testing.assert_array_equal(a["gamma_hz_per_mps2"], b["gamma_hz_per_mps2"])
    assert a["epochs"] == b["epochs"]


def test_misuse_is_an_error(batch):
    settings, e = batch
    c = gsens.Calibrator(0.025, **settings)
    with pytest.raises(gsens.GsensError):
        c.feed_many(np.zeros((5, 3)), np.zeros(4))
    c.finish()
    with pytest.raises(gsens.GsensError):
        c.feed([0.0, 0.0, 9.8], 0.0)
    with pytest.raises(gsens.GsensError):
        gsens.Calibrator(-1.0)
