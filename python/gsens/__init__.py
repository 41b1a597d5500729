"""gsens: calibrate the g-sensitivity of a GNSS receiver's oscillator with
nothing but the live signal, the receiver's own PLLs and its IMU.

The functions here are the library pipeline of the ``gsens`` command line,
on numpy arrays, pandas DataFrames or files:

- :func:`estimate` -- Γ̂ with its uncertainty, the verdicts and warnings
  (the result document of ``gsens estimate --json``);
- :class:`Loop` -- a carrier PLL's response, peak, band, coefficients, and
  the discrete loop run over an array;
- :func:`simulate` and :func:`montecarlo` -- the closed-loop simulator and
  Monte Carlo statistics against the Cramér–Rao bound;
- :class:`Calibrator` -- the streaming calibrator, one epoch at a time.

Units are in the names (``bn_hz``, ``phase_err_rad``,
``gamma_hz_per_mps2``); the method, signs and conventions are in
``docs/conventions.md`` of the repository.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Dict, Mapping, Optional, Union

import numpy as np

from . import _gsens
from ._gsens import Calibrator, Estimate, GsensError, Loop, __version__, default_scenario

__all__ = [
    "Calibrator",
    "Estimate",
    "GsensError",
    "Loop",
    "Simulation",
    "IMU_COLUMNS",
    "TRACKING_COLUMNS",
    "default_scenario",
    "default_settings",
    "estimate",
    "montecarlo",
    "simulate",
    "__version__",
]

#: The columns of an IMU log (``imu.csv``).
IMU_COLUMNS = ("t_s", "fx_mps2", "fy_mps2", "fz_mps2")
#: The columns of a tracking log (``tracking.csv``, one row per channel per epoch).
TRACKING_COLUMNS = ("t_s", "channel", "prn", "cn0_dbhz", "elev_deg", "phase_err_rad")

Log = Union[str, "os.PathLike[str]", Mapping[str, Any], np.ndarray, Any]


def _log(log: Log, names: tuple, role: str) -> Union[str, Dict[str, np.ndarray]]:
    """A log as the extension takes it: a path, or float64 columns by name."""
    if isinstance(log, (str, os.PathLike)):
        return os.fspath(log)
    if hasattr(log, "columns") and hasattr(log, "to_numpy"):  # a pandas DataFrame
        return {str(c): np.ascontiguousarray(log[c].to_numpy(dtype=np.float64)) for c in log.columns if str(c) in names}
    if isinstance(log, Mapping):
        return {str(k): np.ascontiguousarray(np.asarray(v, dtype=np.float64)) for k, v in log.items() if str(k) in names}
    array = np.asarray(log, dtype=np.float64)
    if array.ndim == 2 and array.shape[1] == len(names):
        return {n: np.ascontiguousarray(array[:, i]) for i, n in enumerate(names)}
    raise TypeError(
        f"{role}: expected a file path, a dict of columns, a pandas DataFrame or an N×{len(names)} array "
        f"with the columns {', '.join(names)}"
    )


def estimate(
    imu: Optional[Log] = None,
    tracking: Optional[Log] = None,
    *,
    gnss_sdr: Optional[Union[str, "os.PathLike[str]"]] = None,
    gnss_sdr_conf: Optional[Union[str, "os.PathLike[str]"]] = None,
    pocketsdr: Optional[Union[str, "os.PathLike[str]"]] = None,
    pocketsdr_conf: Optional[Union[str, "os.PathLike[str]"]] = None,
    rinex: Optional[Union[str, "os.PathLike[str]"]] = None,
    ubx: Optional[Union[str, "os.PathLike[str]"]] = None,
    observable: Optional[str] = None,
    **settings: Any,
) -> Estimate:
    """Estimate Γ from an IMU log and a tracking log, as ``gsens estimate`` does.

    ``imu`` and ``tracking`` are each a file path (``imu.csv``,
    ``tracking.csv``), a pandas DataFrame or a dict of 1-D arrays with the
    CSV's column names (:data:`IMU_COLUMNS`, :data:`TRACKING_COLUMNS`;
    ``elev_deg`` may be left out), or an N×4 / N×6 array in that column
    order. Instead of ``tracking``: ``gnss_sdr`` (a directory of GNSS-SDR
    tracking dumps, with ``gnss_sdr_conf``) or ``pocketsdr`` (a pocket_trk
    log, optionally with ``pocketsdr_conf``); those take the IMU as a file.
    A receiver that logs carrier phase or Doppler: ``rinex`` (a RINEX
    observation file, with ``imu`` a file whose ``t_s`` is GPS seconds of the
    week) or ``ubx`` (a u-blox log; its own accelerometer unless ``imu`` is
    given), the receiver's loop identified from the session (or, for a
    RINEX file from GNSS-SDR with ``gnss_sdr_conf``, GNSS-SDR's own loop);
    ``observable`` is ``"auto"``, ``"carrier_phase"`` or ``"doppler"``.

    The settings are the command line's options with ``_`` for ``-``
    (``order=2, bn_hz=3.0`` for ``--order 2 --bn-hz 3``,
    ``time_offset="none"``, ``method="gls"``, ``loop_check=False``, …;
    :func:`default_settings` lists them). Without a stated loop the data
    choose one and the result is flagged until it is stated.

    Returns an :class:`Estimate`; raises :class:`GsensError` with the
    command line's message (naming the file, line and column, or the setting).
    """
    path = lambda p: None if p is None else os.fspath(p)  # noqa: E731
    if rinex is not None or ubx is not None:
        return _gsens.estimate(
            path(imu),
            tracking,
            gnss_sdr=path(gnss_sdr),
            gnss_sdr_conf=path(gnss_sdr_conf),
            pocketsdr=path(pocketsdr),
            rinex=path(rinex),
            ubx=path(ubx),
            observable=observable,
            **settings,
        )
    if imu is None:
        raise GsensError("imu is required (except with ubx)")
    return _gsens.estimate(
        _log(imu, IMU_COLUMNS, "imu"),
        None if tracking is None else _log(tracking, TRACKING_COLUMNS, "tracking"),
        gnss_sdr=None if gnss_sdr is None else os.fspath(gnss_sdr),
        gnss_sdr_conf=None if gnss_sdr_conf is None else os.fspath(gnss_sdr_conf),
        pocketsdr=None if pocketsdr is None else os.fspath(pocketsdr),
        pocketsdr_conf=None if pocketsdr_conf is None else os.fspath(pocketsdr_conf),
        **settings,
    )


def default_settings() -> Dict[str, Any]:
    """The settings :func:`estimate` takes, with their defaults (the command line's)."""
    return _gsens.options_defaults()


def _pandas(caller: str):
    """The pandas module, or an ImportError that says how to install it."""
    try:
        import pandas
    except ImportError as e:
        raise ImportError(
            f"gsens: {caller}() returns a pandas DataFrame and pandas is not installed: "
            "pip install gsens[pandas] (or pip install pandas)"
        ) from e
    return pandas


@dataclass(frozen=True)
class Simulation:
    """A simulated session: the logs as columns of arrays, and the truth."""

    #: The IMU log: ``t_s``, ``fx_mps2``, ``fy_mps2``, ``fz_mps2``.
    imu: Dict[str, np.ndarray]
    #: The tracking log: ``t_s``, ``channel``, ``prn``, ``cn0_dbhz``, ``elev_deg``, ``phase_err_rad``.
    tracking: Dict[str, np.ndarray]
    #: ``truth.json`` as a dict (Γ, the loop, the IMU's errors, the seed, the scenario, …).
    truth: Dict[str, Any]
    #: The scenario as run (TOML).
    scenario: str

    @property
    def gamma_hz_per_mps2(self) -> np.ndarray:
        """The true Γ [Hz/(m/s²)] in the body frame."""
        return np.asarray(self.truth["gamma_hz_per_mps2"], dtype=np.float64)

    def imu_frame(self):
        """The IMU log as a pandas DataFrame (needs pandas: ``pip install gsens[pandas]``)."""
        return _pandas("imu_frame").DataFrame(self.imu)

    def tracking_frame(self):
        """The tracking log as a pandas DataFrame (needs pandas: ``pip install gsens[pandas]``)."""
        return _pandas("tracking_frame").DataFrame(self.tracking)

    def estimate_settings(self) -> Dict[str, Any]:
        """The loop settings that describe this session's receiver (for :func:`estimate`),
        its implementation included: the simulator runs gsens's own discrete loop."""
        loop = self.truth["scenario"]["loop"]
        s: Dict[str, Any] = {"order": loop["order"], "bn_hz": loop["bn_hz"], "loop_interval_s": loop["interval_s"]}
        s["zeta" if loop["order"] == 2 else "a3"] = loop["zeta"] if loop["order"] == 2 else loop["a3"]
        if loop["order"] == 3:
            s["b3"] = loop["b3"]
        s["logged_phase"] = self.truth["logged_phase"]
        s["loop_implementation"] = "kaplan"
        return s


def simulate(scenario: Optional[Union[str, "os.PathLike[str]"]] = None, seed: int = 1, **overrides: Any) -> Simulation:
    """Simulate a calibration session (by default the paper's experiment).

    ``scenario`` is a scenario TOML file (:func:`default_scenario` shows the
    embedded one); each keyword overrides a table of it, merged key by key:
    ``simulate(oscillator={"gamma_hz_per_mps2": [0.1, 0, 0]}, imu={"time_offset_s": 0.01})``.
    The same seed gives the same arrays.
    """
    out = _gsens.simulate(None if scenario is None else os.fspath(scenario), seed, **overrides)
    return Simulation(imu=out["imu"], tracking=out["tracking"], truth=out["truth"], scenario=out["scenario"])


def montecarlo(
    scenario: Optional[Union[str, "os.PathLike[str]"]] = None,
    runs: int = 20,
    seed: int = 1,
    methods=("batch",),
    stated_bn_scale: Optional[float] = 1.0,
    overrides: Optional[Mapping[str, Any]] = None,
    **settings: Any,
) -> Dict[str, Any]:
    """Simulate ``runs`` sessions (seeds ``seed``, ``seed + 1``, …) in parallel and
    estimate each with every method of ``methods`` (``batch``, ``gls``, ``rls``,
    ``gradient``) under the scenario's own loop, as ``gsens montecarlo``.

    ``overrides`` changes the scenario as :func:`simulate`'s keywords do; the
    other keywords are :func:`estimate`'s settings (not the loop's).
    ``stated_bn_scale`` states the loop's Bn that many times the true one;
    ``None`` states no loop (the data choose it). Returns the JSON document of
    ``gsens montecarlo --json`` as a dict: ``methods`` (per method: bias, RMSE,
    CRLB, z RMS, coverage, …; ``loop-free`` for the estimate from the NCO's
    phase where the scenario logs it) and ``per_run``.
    """
    return _gsens.montecarlo(
        None if scenario is None else os.fspath(scenario),
        runs,
        seed,
        list(methods),
        stated_bn_scale,
        dict(overrides or {}),
        **settings,
    )
