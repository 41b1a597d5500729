"""The Python binding's overhead: ``gsens.estimate`` on numpy arrays against
the library pipeline on the same logs in memory (``cargo run --release -p
gsens-calib --example in_memory``), the CSV parsing left out of both.

    python python/benchmarks/binding_overhead.py DIR RUNS ['{"bn_hz": 3, ...}']

DIR holds imu.csv and tracking.csv (``cargo run --release --example long_log
-- /tmp/long1h 1 12`` makes the 1-hour log of BENCHMARKS.md).
"""

from __future__ import annotations

import json
import pathlib
import sys
import time

import numpy as np

import gsens


def read_columns(path: pathlib.Path) -> dict:
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {name: np.ascontiguousarray(data[name], dtype=np.float64) for name in data.dtype.names}


def main() -> None:
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    directory, runs = pathlib.Path(sys.argv[1]), int(sys.argv[2])
    settings = json.loads(sys.argv[3]) if len(sys.argv) > 3 else {}
    imu = read_columns(directory / "imu.csv")
    tracking = read_columns(directory / "tracking.csv")
    wall_s = []
    for _ in range(max(runs, 1)):
        start = time.perf_counter()
        e = gsens.estimate(imu, tracking, **settings)
        wall_s.append(time.perf_counter() - start)
    wall_s.sort()
    print(
        f"gsens.estimate on arrays: median {1e3 * wall_s[len(wall_s) // 2]:.1f} ms over {len(wall_s)} runs "
        f"(min {1e3 * wall_s[0]:.1f}, max {1e3 * wall_s[-1]:.1f}); Γ̂ = {list(e.gamma_hz_per_mps2)}"
    )


if __name__ == "__main__":
    main()
