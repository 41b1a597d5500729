"""Bad input raises GsensError with the command line's message (file, line,
column; the setting and what it must be), never a crash or a number."""

from __future__ import annotations

import numpy as np
import pytest

import gsens
from conftest import run_cli, write_csv


def cli_error(gsens_bin, *args) -> str:
    r = run_cli(gsens_bin, "estimate", *args)
    assert r.returncode != 0
    return r.stderr.strip()


def test_a_bad_csv_cell_names_file_line_and_column_as_the_cli_does(gsens_bin, tmp_path, session):
    write_csv(tmp_path / "tracking.csv", session.tracking)
    bad = tmp_path / "imu.csv"
    bad.write_text("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3\n0.025,1,x,3\n")
    with pytest.raises(gsens.GsensError) as raised:
        gsens.estimate(bad, tmp_path / "tracking.csv")
    message = str(raised.value)
    assert f"{bad}: line 3, column 3 (`fy_mps2`)" in message
    assert message in cli_error(gsens_bin, "--imu", str(bad), "--tracking", str(tmp_path / "tracking.csv"))


def test_a_missing_file(gsens_bin, tmp_path, session):
    write_csv(tmp_path / "tracking.csv", session.tracking)
    with pytest.raises(gsens.GsensError, match="nope.csv: cannot read"):
        gsens.estimate(tmp_path / "nope.csv", tmp_path / "tracking.csv")
    # Both missing: the one the command line names.
    with pytest.raises(gsens.GsensError) as raised:
        gsens.estimate(tmp_path / "nope.csv", tmp_path / "t.csv")
    message = str(raised.value)
    assert "cannot read" in message
    assert message in cli_error(gsens_bin, "--imu", str(tmp_path / "nope.csv"), "--tracking", str(tmp_path / "t.csv"))


def test_an_unknown_or_out_of_range_setting(session):
    with pytest.raises(gsens.GsensError, match="unknown field `bn_hertz`"):
        gsens.estimate(session.imu, session.tracking, bn_hertz=3)
    with pytest.raises(gsens.GsensError, match="bn_hz"):
        gsens.estimate(session.imu, session.tracking, bn_hz=-3)
    with pytest.raises(gsens.GsensError, match="order"):
        gsens.estimate(session.imu, session.tracking, order=4)
    with pytest.raises(gsens.GsensError, match="time_offset"):
        gsens.estimate(session.imu, session.tracking, time_offset="later")


def test_missing_columns_and_ragged_arrays(session):
    with pytest.raises(gsens.GsensError, match="missing column `fx_mps2`"):
        gsens.estimate({"t_s": session.imu["t_s"]}, session.tracking)
    ragged = dict(session.imu, fx_mps2=session.imu["fx_mps2"][:-1])
    with pytest.raises(gsens.GsensError, match="fx_mps2"):
        gsens.estimate(ragged, session.tracking)
    with pytest.raises(TypeError, match="N×4"):
        gsens.estimate(np.zeros((5, 3)), session.tracking)


def test_rows_out_of_time_order_and_non_finite_values(session):
    order = np.random.default_rng(7).permutation(len(session.tracking["t_s"]))
    shuffled = {k: v[order] for k, v in session.tracking.items()}
    with pytest.raises(gsens.GsensError, match="goes backwards"):
        gsens.estimate(session.imu, shuffled)
    t = session.imu["t_s"].copy()
    t[10] = np.nan
    with pytest.raises(gsens.GsensError, match="sample 10 is not finite"):
        gsens.estimate(dict(session.imu, t_s=t), session.tracking)
