"""The packaging's optional extras, and what a missing extra says."""

from __future__ import annotations

import sys

import pytest

from conftest import REPO


def _pyproject() -> dict:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - the tests run on CPython >= 3.11 here
        tomllib = pytest.importorskip("tomli")
    with open(REPO / "pyproject.toml", "rb") as f:
        return tomllib.load(f)


def test_the_extras_for_pandas_and_the_examples_are_declared():
    extras = _pyproject()["project"]["optional-dependencies"]
    names = {e: [r.split(">")[0].split("=")[0].split("<")[0].strip() for r in reqs] for e, reqs in extras.items()}
    assert "pandas" in names["pandas"], extras
    # python/examples/paper_figures.py draws with matplotlib.
    assert "matplotlib" in names["examples"], extras
    # The base install stays numpy only.
    deps = _pyproject()["project"]["dependencies"]
    assert [d.split(">")[0] for d in deps] == ["numpy"], deps


@pytest.mark.parametrize("method", ["imu_frame", "tracking_frame"])
def test_a_frame_without_pandas_says_which_extra_to_install(session, monkeypatch, method):
    # A None entry in sys.modules makes `import pandas` raise ImportError, as without pandas.
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r"pip install gsens\[pandas\]") as e:
        getattr(session, method)()
    assert method in str(e.value)
