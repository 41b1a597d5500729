"""`gsens.estimate` against `gsens estimate` on the same data, and the
array, DataFrame and file forms of a log against each other."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas
import pytest

import gsens
from conftest import cli_flags, run_cli, write_csv

# Fields of the result document that describe where the logs came from
# rather than what was estimated from them.
PROVENANCE = ("inputs",)


def cli_document(gsens_bin, tmp_path, args):
    out = tmp_path / "out.json"
    r = run_cli(gsens_bin, "estimate", *args, "--json", str(out))
    assert r.returncode == 0, r.stderr
    return json.loads(out.read_text())


def assert_same_document(ours: dict, theirs: dict) -> None:
    for key in set(ours) | set(theirs):
        if key in PROVENANCE:
            continue
        assert key in ours and key in theirs, key
        assert_close(ours[key], theirs[key], key)


def assert_close(a, b, where: str) -> None:
    """Equal, numbers to 1e-12 relative (the same computation in the same order)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), where
        for k in a:
            assert_close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_close(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and isinstance(b, (float, int)) and not isinstance(b, bool):
        assert math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300), f"{where}: {a} != {b}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


@pytest.mark.parametrize("settings", [{}, {"method": "gls", "time_offset": "none"}])
def test_arrays_give_the_cli_estimate_on_the_same_csv(gsens_bin, tmp_path, session, settings):
    settings = {**session.estimate_settings(), **settings}
    write_csv(tmp_path / "imu.csv", session.imu)
    write_csv(tmp_path / "tracking.csv", session.tracking)
    doc = cli_document(
        gsens_bin,
        tmp_path,
        ["--imu", str(tmp_path / "imu.csv"), "--tracking", str(tmp_path / "tracking.csv"), *cli_flags(settings)],
    )
    e = gsens.estimate(session.imu, session.tracking, **settings)
    np.testing.assert_allclose(e.gamma_hz_per_mps2, doc["gamma_hz_per_mps2"], rtol=1e-12, atol=0)
    np.testing.assert_allclose(e.sigma_hz_per_mps2, doc["sigma_hz_per_mps2"], rtol=1e-12, atol=0)
    assert_same_document(e.to_dict(), doc)
    assert json.loads(e.to_json()) == e.to_dict()
    assert e.trustworthy == doc["trustworthy"]


def test_gnss_sdr_dumps_give_the_cli_estimate(gsens_bin, tmp_path, fixtures):
    imu, dumps, conf = fixtures / "imu.csv", fixtures / "order2", fixtures / "order2" / "gnss-sdr.conf"
    doc = cli_document(gsens_bin, tmp_path, ["--imu", str(imu), "--gnss-sdr", str(dumps), "--gnss-sdr-conf", str(conf)])
    e = gsens.estimate(imu, gnss_sdr=dumps, gnss_sdr_conf=conf)
    assert_same_document(e.to_dict(), doc)
    assert e.loop_used == doc["loop_used"]
    assert "GNSS-SDR" in e.loop_description


def test_every_form_of_a_log_gives_the_same_estimate(tmp_path, session):
    settings = {**session.estimate_settings(), "time_offset": "none", "loop_check": False}
    reference = gsens.estimate(session.imu, session.tracking, **settings)
    write_csv(tmp_path / "imu.csv", session.imu)
    write_csv(tmp_path / "tracking.csv", session.tracking)
    forms = [
        (tmp_path / "imu.csv", str(tmp_path / "tracking.csv")),
        (session.imu_frame(), session.tracking_frame()),
        (
            np.column_stack([session.imu[c] for c in gsens.IMU_COLUMNS]),
            np.column_stack([session.tracking[c] for c in gsens.TRACKING_COLUMNS]),
        ),
        ({k: list(v) for k, v in session.imu.items()}, pandas.DataFrame(session.tracking)),
        # Strided views (copied) and contiguous float64 arrays (read in place).
        (
            {k: np.repeat(np.asarray(v, dtype=np.float64), 2)[::2] for k, v in session.imu.items()},
            {k: np.asarray(v, dtype=np.float64) for k, v in session.tracking.items()},
        ),
    ]
    for imu, tracking in forms:
        e = gsens.estimate(imu, tracking, **settings)
        np.testing.assert_array_equal(e.gamma_hz_per_mps2, reference.gamma_hz_per_mps2)
        np.testing.assert_array_equal(e.covariance_hz_per_mps2_sq, reference.covariance_hz_per_mps2_sq)


def test_a_log_without_elevation(session):
    settings = {**session.estimate_settings(), "time_offset": "none", "loop_check": False}
    reference = gsens.estimate(session.imu, session.tracking, **settings)
    without = {k: v for k, v in session.tracking.items() if k != "elev_deg"}
    e = gsens.estimate(session.imu, without, **settings)
    np.testing.assert_allclose(e.gamma_hz_per_mps2, reference.gamma_hz_per_mps2, rtol=1e-12)


def test_the_result_object(session):
    e = gsens.estimate(session.imu, session.tracking, **session.estimate_settings())
    d = e.to_dict()
    assert e.covariance_hz_per_mps2_sq.shape == (3, 3)
    np.testing.assert_allclose(np.sqrt(np.diag(e.covariance_hz_per_mps2_sq)), e.sigma_hz_per_mps2, rtol=1e-12)
    np.testing.assert_allclose(e.gamma_ppb_per_g, d["gamma_ppb_per_g"], rtol=1e-12)
    np.testing.assert_allclose(e.crlb_hz_per_mps2, d["crlb_hz_per_mps2"], rtol=1e-12)
    assert e.imu_time_offset_s == d["imu_time_offset_s"]
    assert list(e.observable) == d["observable"] == [True, True, True]
    assert e.warnings == d["warnings"]
    # Γ̂ is within 3σ of the truth on every axis (the seed's draw; the
    # Monte Carlo tests of the Rust crates check the coverage itself).
    z = (e.gamma_hz_per_mps2 - session.gamma_hz_per_mps2) / e.sigma_hz_per_mps2
    assert np.all(np.abs(z) < 3), z
    assert "Γ̂" in e.report() and str(e) == e.report()
    ep = e.epochs()
    assert ep["accel_mps2"].shape == (len(ep["t_s"]), 3)


def test_an_axis_the_shaking_missed_is_nan_not_a_number():
    # 40 s of the paper's schedule shake only x.
    s = gsens.simulate(seed=2, session={"duration_s": 40})
    e = gsens.estimate(s.imu, s.tracking, **s.estimate_settings())
    assert list(e.observable) == [True, False, False]
    assert np.isfinite(e.gamma_hz_per_mps2[0])
    assert np.all(np.isnan(e.gamma_hz_per_mps2[1:])) and np.all(np.isnan(e.sigma_hz_per_mps2[1:]))
    assert e.to_dict()["gamma_hz_per_mps2"][1] is None


def test_an_unstated_loop_is_flagged(session):
    e = gsens.estimate(session.imu, session.tracking)
    assert not e.trustworthy
    assert e.warnings, "a loop the user did not state must be named in the warnings"


def test_an_imu_logged_in_g_gives_an_untrustworthy_estimate_that_says_why(session):
    g0 = 9.80665
    imu_g = {k: (v / g0 if k != "t_s" else v) for k, v in session.imu.items()}
    e = gsens.estimate(imu_g, session.tracking, **session.estimate_settings())
    assert not e.trustworthy
    assert [w["code"] for w in e.warnings] == ["imu_units"], e.warnings
    assert "in g" in e.warnings[0]["message"]
    assert repr(e).endswith("; NOT trustworthy (imu_units)>"), repr(e)
    assert "verdict: NOT TRUSTWORTHY (imu_units)" in e.report()
    assert e.to_dict()["trustworthy"] is False
    # The same session in m/s²: trustworthy, and the repr says so.
    ok = gsens.estimate(session.imu, session.tracking, **session.estimate_settings())
    assert ok.trustworthy and ok.warnings == [] and repr(ok).endswith("; trustworthy>"), (repr(ok), ok.warnings)


def test_default_settings_are_the_cli_defaults():
    d = gsens.default_settings()
    assert d["time_offset"] == "auto" and d["loop_check"] is True and d["method"] == "batch"
    assert d["carrier_hz"] == 1575.42e6
