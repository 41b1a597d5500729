"""Shared fixtures: the command-line binary the bindings are checked against,
the repository's GNSS-SDR fixtures and one simulated session."""

from __future__ import annotations

import os
import pathlib
import subprocess

import pytest

import gsens

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def gsens_bin() -> str:
    """The ``gsens`` binary: ``$GSENS_BIN`` (scripts/test.sh sets it), else
    the workspace's debug build, built if missing."""
    path = os.environ.get("GSENS_BIN")
    if path:
        assert os.access(path, os.X_OK), f"GSENS_BIN={path} is not an executable"
        return path
    built = REPO / "target" / "debug" / "gsens"
    if not built.exists():
        subprocess.run(["cargo", "build", "-p", "gsens-cli", "--locked"], cwd=REPO, check=True)
    return str(built)


@pytest.fixture(scope="session")
def fixtures() -> pathlib.Path:
    """GNSS-SDR tracking dumps and their IMU log (crates/gsens-gnss-sdr/tests/fixtures)."""
    return REPO / "crates" / "gsens-gnss-sdr" / "tests" / "fixtures"


@pytest.fixture(scope="session")
def session() -> gsens.Simulation:
    """The paper's experiment, seed 3."""
    return gsens.simulate(seed=3)


def write_csv(path: pathlib.Path, columns: dict) -> None:
    """Columns as CSV, floats with 17 significant digits (every double round-trips)."""
    names = list(columns)
    with open(path, "w") as f:
        f.write(",".join(names) + "\n")
        cols = [columns[n] for n in names]
        for i in range(len(cols[0])):
            f.write(
                ",".join(str(int(c[i])) if c.dtype.kind in "iu" else format(float(c[i]), ".17g") for c in cols) + "\n"
            )


def run_cli(gsens_bin: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([gsens_bin, *args], capture_output=True, text=True)


def cli_flags(settings: dict) -> list:
    """``estimate``'s keyword settings as the command line's flags."""
    flags = []
    for name, value in settings.items():
        flag = "--" + name.replace("_", "-")
        if isinstance(value, bool):
            flags += [flag, "on" if value else "off"]
        else:
            flags += [flag, str(value)]
    return flags
