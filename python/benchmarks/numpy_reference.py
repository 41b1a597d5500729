"""An independent reference estimator in numpy and scipy (no gsens code): the
speed yardstick of BENCHMARKS.md for ``gsens estimate`` with a loop stated.

    python python/benchmarks/numpy_reference.py DIR [BN_HZ] [LOOP_INTERVAL_S] [READER]

DIR holds imu.csv and tracking.csv (``cargo run --release --example long_log
-- /tmp/long1h 1 12`` makes the 1-hour log). It does far less than gsens: the
phase error averaged over channels per epoch, a 2nd-order loop (ζ = 1/√2,
docs/conventions.md's difference equations) run at LOOP_INTERVAL_S on the
linearly interpolated specific force, the mean of each log interval's
discriminator outputs, 2 s of warm-up dropped, and ordinary least squares:
no screening, no high-pass, no offset search, no noise model, no checks.
READER is ``loadtxt`` (numpy's C parser, the default) or ``genfromtxt`` (the
reader of binding_overhead.py, several times slower). Prints Γ̂ [Hz/(m/s²)]
and the time it took.
"""

from __future__ import annotations

import pathlib
import sys
import time

import numpy as np
from scipy import signal


def loop_filter(bn_hz: float, t_s: float) -> tuple[np.ndarray, np.ndarray]:
    """L_d(z) from Δf to φ of the 2nd-order loop, as lfilter's (b, a)."""
    zeta = 1.0 / np.sqrt(2.0)
    wn = 2.0 * bn_hz / (zeta + 1.0 / (4.0 * zeta))
    c0, c1 = 2.0 * zeta * wn, wn * wn
    k = np.pi * t_s
    # State (e, f, a1): φ = e − πT·f − πT·Δf; e' = e − 2πT·(f + Δf);
    # a1' = a1 + T·c1·φ; f' = (c0·φ + a1')/2π.
    phi_row = np.array([1.0, -k, 0.0])
    phi_in = -k
    a1_row = np.array([0.0, 0.0, 1.0]) + t_s * c1 * phi_row
    a1_in = t_s * c1 * phi_in
    a = np.array([
        [1.0, -2.0 * k, 0.0],
        (c0 * phi_row + a1_row) / (2.0 * np.pi),
        a1_row,
    ])
    b = np.array([[-2.0 * k], [(c0 * phi_in + a1_in) / (2.0 * np.pi)], [a1_in]])
    num, den = signal.ss2tf(a, b, phi_row[None, :], np.array([[phi_in]]))
    return num[0], den


def main() -> None:
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    folder = pathlib.Path(sys.argv[1])
    bn_hz = float(sys.argv[2]) if len(sys.argv) > 2 else 3.0
    loop_t_s = float(sys.argv[3]) if len(sys.argv) > 3 else 0.001
    reader = sys.argv[4] if len(sys.argv) > 4 else "loadtxt"
    if reader not in ("loadtxt", "genfromtxt"):
        sys.exit(f"READER must be loadtxt or genfromtxt, not {reader!r}")

    def read(path: pathlib.Path, usecols=None) -> np.ndarray:
        if reader == "loadtxt":
            return np.loadtxt(path, delimiter=",", skiprows=1, usecols=usecols)
        return np.genfromtxt(path, delimiter=",", skip_header=1, usecols=usecols)

    start = time.perf_counter()
    imu = read(folder / "imu.csv")
    trk = read(folder / "tracking.csv", usecols=(0, 5))
    t_s, accel = imu[:, 0], imu[:, 1:4]
    log_t_s = float(np.median(np.diff(t_s)))
    n_sub = int(round(log_t_s / loop_t_s))
    # Channel average per epoch (the IMU's epochs are the log's).
    epoch = np.rint((trk[:, 0] - t_s[0]) / log_t_s).astype(np.int64)
    counts = np.bincount(epoch, minlength=len(t_s))
    sums = np.bincount(epoch, weights=trk[:, 1], minlength=len(t_s))
    phase = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    # The loop at its own rate on the interpolated force, from rest at the first sample.
    fine_t = t_s[0] + loop_t_s * np.arange(1, n_sub * (len(t_s) - 1) + 1)
    num, den = loop_filter(bn_hz, loop_t_s)
    regressors = np.empty_like(accel)
    for axis in range(3):
        fine = np.interp(fine_t, t_s, accel[:, axis]) - accel[0, axis]
        out = signal.lfilter(num, den, fine).reshape(-1, n_sub).mean(axis=1)
        regressors[:, axis] = np.concatenate([[0.0], out])
    keep = np.isfinite(phase) & (t_s >= t_s[0] + 2.0)
    x, y = regressors[keep], phase[keep]
    gamma, *_ = np.linalg.lstsq(x, y - y.mean(), rcond=None)
    elapsed = time.perf_counter() - start
    print("gamma_hz_per_mps2", " ".join(f"{g:.6f}" for g in gamma))
    print(f"elapsed_s {elapsed:.3f}")


if __name__ == "__main__":
    main()
