#!/usr/bin/env bash
# Pools the estimates of several scripts/pocketsdr-e2e.sh runs (different SEEDs) and tests
# whether their σ are honest: for each file (paper's Γ, TCXO-like Γ) and bandwidth, the sum
# of z² = ((Γ̂ − Γ)/σ)² over the runs' axes against χ² with as many degrees of freedom
# (its p-value: the probability of a sum at least this large with honest σ), and the
# fraction of estimates within 2σ.
#
# Usage: scripts/pocketsdr-pool.sh OUT_DIR...   e.g. for s in 7 8 9 10; do SEED=$s scripts/pocketsdr-e2e.sh target/pe2e-$s; done
#        scripts/pocketsdr-pool.sh target/pe2e-{7,8,9,10}
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 OUT_DIR..." >&2; exit 2; }
python3 - "$@" <<'PY'
import json, math, sys

def chi2_sf(x, k):
    # P(χ²_k ≥ x) by the series of the regularized lower incomplete gamma function.
    a, s, term, n = k / 2, 0.0, 1.0 / (k / 2), 0
    term = math.exp(-x / 2 + a * math.log(x / 2) - math.lgamma(a + 1)) if x > 0 else 0.0
    while term > 1e-16 * max(s, 1e-300):
        s += term
        n += 1
        term *= (x / 2) / (a + n)
    return max(0.0, 1.0 - s)

rows, all_z = [], []
for case in ("paper", "tcxo"):
    for bw in (5, 10):
        z = []
        for d in sys.argv[1:]:
            g = json.load(open(f"{d}/{case}/truth.json"))["gamma_imu_axes_hz_per_mps2"]
            e = json.load(open(f"{d}/{case}/bw{bw}/estimate.json"))
            for i in range(3):
                v, s = e["gamma_hz_per_mps2"][i], e["sigma_hz_per_mps2"][i]
                if v is not None:
                    z.append((v - g[i]) / s)
        all_z += z
        rows.append((f"Γ {case}, b_pll {bw} Hz", z))
rows.append(("all", all_z))
print(f"{len(sys.argv) - 1} runs: {' '.join(sys.argv[1:])}")
print(f"{'':22} {'n':>3} {'Σz²':>6} {'p':>7} {'within 2σ':>10}")
for name, z in rows:
    s = sum(v * v for v in z)
    print(f"{name:22} {len(z):3d} {s:6.1f} {chi2_sf(s, len(z)):7.3f} {sum(abs(v) <= 2 for v in z):5d} of {len(z)}")
PY
