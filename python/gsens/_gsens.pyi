"""Type stubs of the extension module gsens._gsens (crates/gsens-py)."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union, final, overload

from typing_extensions import Self

import numpy as np
import numpy.typing as npt

__all__ = [
    "GsensError",
    "__version__",
    "estimate",
    "options_defaults",
    "Estimate",
    "Loop",
    "simulate",
    "default_scenario",
    "montecarlo",
    "Calibrator",
]

__version__: str

_Path = Union[str, "os.PathLike[str]"]
_Columns = Mapping[str, npt.NDArray[np.float64]]

class GsensError(ValueError):
    """A bad input, setting or log: the command line's message (file, line, column)."""

@final
class Estimate:
    """The result of :func:`estimate`: the result document of ``gsens estimate --json``."""

    @property
    def gamma_hz_per_mps2(self) -> npt.NDArray[np.float64]:
        """Γ̂ [Hz/(m/s²)] per axis (NaN: unobservable)."""
    @property
    def sigma_hz_per_mps2(self) -> npt.NDArray[np.float64]:
        """1σ of Γ̂ [Hz/(m/s²)] (NaN: unobservable)."""
    @property
    def gamma_ppb_per_g(self) -> npt.NDArray[np.float64]:
        """Γ̂ in ppb/g at the carrier."""
    @property
    def sigma_ppb_per_g(self) -> npt.NDArray[np.float64]:
        """1σ in ppb/g."""
    @property
    def covariance_hz_per_mps2_sq(self) -> npt.NDArray[np.float64]:
        """3×3 covariance of Γ̂ [(Hz/(m/s²))²] (NaN rows/columns: unobservable)."""
    @property
    def crlb_hz_per_mps2(self) -> npt.NDArray[np.float64]:
        """The Cramér–Rao bound per axis [Hz/(m/s²)]."""
    @property
    def observable(self) -> List[bool]:
        """Whether the shaking made each axis observable."""
    @property
    def imu_time_offset_s(self) -> float:
        """IMU stamp − true time [s], estimated or as given."""
    @property
    def imu_time_offset_sigma_s(self) -> Optional[float]:
        """1σ of the estimated offset [s] (None when given)."""
    @property
    def trustworthy(self) -> bool:
        """The verdict: False when a warning other than the informational ones
        (imu_spikes, imu_stuck, imu_clipped, response_unchecked, clock_jumps,
        records_skipped) was raised or no
        axis is observable; ``repr`` names the codes that decide it."""
    @property
    def warnings(self) -> List[Dict[str, str]]:
        """Every warning as ``{"code": ..., "message": ...}``: what failed, why and the fix."""
    @property
    def verdicts(self) -> List[Dict[str, Any]]:
        """Per axis: the shaking's frequency, excitation and observability."""
    @property
    def loop_used(self) -> Dict[str, Any]:
        """The loop Γ̂ is given under (the document's ``loop_used``)."""
    @property
    def loop_description(self) -> str:
        """``loop_used`` in words."""
    def epochs(self) -> Dict[str, npt.NDArray[np.float64]]:
        """``t_s``, channel-averaged ``phase_err_rad`` and ``accel_mps2`` (N×3): the estimator's input."""
    def to_dict(self) -> Dict[str, Any]:
        """The result document as a dict (equal to ``gsens estimate --json``)."""
    def to_json(self) -> str:
        """The result document as JSON."""
    def report(self) -> str:
        """The text report of ``gsens estimate``."""

@final
class Loop:
    """A carrier PLL (Kaplan & Hegarty): continuous, or discrete with ``interval_s``."""

    def __new__(
        cls,
        order: int = 2,
        bn_hz: float = 3.0,
        zeta: float = ...,
        a3: float = 1.1,
        b3: float = 2.4,
        interval_s: Optional[float] = None,
    ) -> Self: ...
    @property
    def order(self) -> int: ...
    @property
    def bn_hz(self) -> Optional[float]: ...
    @property
    def natural_frequency_hz(self) -> Optional[float]: ...
    @property
    def interval_s(self) -> Optional[float]: ...
    def coefficients(self) -> Tuple[float, float, float]:
        """The loop filter's c0 [1/s], c1 [1/s²], c2 [1/s³]."""
    @overload
    def response(self, f_hz: float) -> complex: ...
    @overload
    def response(self, f_hz: npt.ArrayLike) -> npt.NDArray[np.complex128]: ...
    def peak(self) -> Tuple[float, float]:
        """(frequency [Hz], |L| [rad/Hz]) of the response's peak."""
    def half_power_band_hz(self) -> Tuple[float, float]:
        """Where |L| falls to peak/√2 on either side [Hz]."""
    def filter(self, delta_f_hz: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The discrete loop run over Δf [Hz] per update: φ [rad] per update."""

@final
class Calibrator:
    """The streaming calibrator: one epoch of specific force and phase error at a time."""

    def __new__(cls, log_interval_s: float, **settings: Any) -> Self: ...
    def feed(self, accel_mps2: Sequence[float], phase_err_rad: Optional[float] = None) -> None: ...
    def feed_many(self, accel_mps2: npt.ArrayLike, phase_err_rad: npt.ArrayLike) -> None: ...
    def finish(self) -> None: ...
    def estimate(self) -> Dict[str, Any]: ...

def estimate(
    imu: Optional[Union[_Path, _Columns]] = None,
    tracking: Optional[Union[_Path, _Columns]] = None,
    *,
    gnss_sdr: Optional[_Path] = None,
    gnss_sdr_conf: Optional[_Path] = None,
    pocketsdr: Optional[_Path] = None,
    pocketsdr_conf: Optional[_Path] = None,
    rinex: Optional[_Path] = None,
    ubx: Optional[_Path] = None,
    observable: Optional[str] = None,
    **settings: Any,
) -> Estimate: ...
def options_defaults() -> Dict[str, Any]: ...
def default_scenario() -> str: ...
def simulate(scenario: Optional[_Path] = None, seed: int = 1, **overrides: Any) -> Dict[str, Any]: ...
def montecarlo(
    scenario: Optional[_Path] = None,
    runs: int = 20,
    seed: int = 1,
    methods: Sequence[str] = ...,
    stated_bn_scale: Optional[float] = ...,
    overrides: Optional[Mapping[str, Any]] = None,
    **settings: Any,
) -> Dict[str, Any]: ...
