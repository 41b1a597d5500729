#!/usr/bin/env bash
# End to end through a real software receiver, live over UDP:
#
#   gsens simulate --iq  →  GNSS-SDR 0.0.17 (Debian), TrackingMonitor on  →  UDP 127.0.0.1
#                        →  gsens import gnss-sdr-monitor  →  tracking.csv  →  gsens estimate --tracking
#
# 1. installs gnss-sdr from Debian when it is missing (apt-get, as root);
# 2. writes the scenario of scripts/gnss-sdr-e2e.sh (the paper's OCXO, Γ = [0.09, 0.08, -0.08]
#    Hz/(m/s²), 8 satellites, rest 30 s, then x, y, z shaken 30 s each with 10 s of rest);
# 3. generates the IF samples (ibyte, FS_HZ), imu.csv, truth.json and gsens's GNSS-SDR conf, and
#    adds the TrackingMonitor keys (127.0.0.1, PORT, decimation 1); the dumps stay on, to compare;
# 4. starts `gsens import gnss-sdr-monitor --listen 127.0.0.1:PORT`, runs GNSS-SDR, and lets the
#    recorder stop IDLE_S seconds after the last datagram;
# 5. estimates Γ from the received tracking.csv with GNSS-SDR's exact loop from the .conf
#    (`--tracking … --gnss-sdr-conf`); for comparison from the dumps of the same run with the same
#    exact loop, and from the received rows with a Kaplan model of the .conf's order, narrow Bn
#    and 20 ms (not GNSS-SDR's loop: it biases Γ̂ by about +4 % on this scenario);
# 6. prints the table and fails when the estimate from the monitor is more than 2 % from the truth.
#
# Usage: scripts/gnss-sdr-monitor-e2e.sh [OUT_DIR]   (default target/gnss-sdr-monitor-e2e)
# Environment: RECEIVER=live (gsens live receives the monitor, following imu.csv, instead of
# gsens import gnss-sdr-monitor), FS_HZ (default 2048000), SEED (7), ORDER (2), PORT (17234), IDLE_S (5),
# GAMMA (TOML array), KEEP_IQ=1, GSENS (a gsens binary; the build honours CARGO_TARGET_DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-target/gnss-sdr-monitor-e2e}
FS_HZ=${FS_HZ:-2048000}
SEED=${SEED:-7}
ORDER=${ORDER:-2}
PORT=${PORT:-17234}
IDLE_S=${IDLE_S:-5}
GAMMA=${GAMMA:-[0.09, 0.08, -0.08]}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
. scripts/lib/common.sh

ensure_gnss_sdr

gsens_binary
. scripts/lib/scenario.sh

{
    paper_session "$ORDER" "$GAMMA"
    printf '[satellites]\nelevation_mask_deg = 4.0\nmax_channels = 8\n'
    shake_sequence 30.0 30.0 10.0 1
} > "$OUT/scenario.toml"

echo "== IF samples"
t=$(now)
"$G" simulate --scenario "$OUT/scenario.toml" --seed "$SEED" --out "$OUT" --iq "$OUT/signal.bin" --fs-hz "$FS_HZ"
T_IQ=$(elapsed "$t")

rm -rf "$OUT/dumps" && mkdir -p "$OUT/dumps"
sed -e "s|^Tracking_1C.pll_filter_order=.*|Tracking_1C.pll_filter_order=$ORDER|" \
    -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=$OUT/dumps/trk_ch_|" \
    "$OUT/gnss-sdr.conf" > "$OUT/run.conf"
cat >> "$OUT/run.conf" <<CONF

TrackingMonitor.enable_monitor=true
TrackingMonitor.enable_protobuf=true
TrackingMonitor.client_addresses=127.0.0.1
TrackingMonitor.udp_port=$PORT
TrackingMonitor.decimation_factor=1
CONF

if [ "${RECEIVER:-import}" = live ]; then
    # gsens live receives the monitor and follows imu.csv (complete already: the IMU log of a
    # simulated run); the target σ is out of reach so it runs to the end of the stream.
    echo "== gsens live --gnss-sdr-monitor 127.0.0.1:$PORT, GNSS-SDR sending"
    rm -rf "$OUT/live"
    "$G" live --gnss-sdr-monitor "127.0.0.1:$PORT" --gnss-sdr-conf "$OUT/run.conf" --follow-imu "$OUT/imu.csv" \
        --plain --target-sigma 1e-9 --idle-timeout-s "$IDLE_S" --out "$OUT/live" > "$OUT/import.txt" 2> "$OUT/import.err" &
else
    echo "== gsens import gnss-sdr-monitor on 127.0.0.1:$PORT, GNSS-SDR sending"
    "$G" import gnss-sdr-monitor --listen "127.0.0.1:$PORT" --gnss-sdr-conf "$OUT/run.conf" \
        --out "$OUT/tracking.csv" --idle-timeout-s "$IDLE_S" > "$OUT/import.txt" 2> "$OUT/import.err" &
fi
REC=$!
trap 'kill $REC 2>/dev/null || true' EXIT
sleep 1
t=$(now)
(cd "$OUT" && gnss-sdr --config_file="$OUT/run.conf" --log_dir="$OUT" > "$OUT/gnss-sdr.log" 2>&1)
T_RX=$(elapsed "$t")
wait $REC || [ $? = 3 ]
trap - EXIT
if [ "${RECEIVER:-import}" = live ]; then
    grep -v "Γ̂ \[Hz" "$OUT/import.txt" | head -40
    cp "$OUT/live/tracking.csv" "$OUT/tracking.csv"
else
    cat "$OUT/import.err" "$OUT/import.txt"
fi
echo "GNSS-SDR ran $T_RX s"
[ "${KEEP_IQ:-0}" = 1 ] || rm -f "$OUT/signal.bin"

read -r BN SYM < <(awk -F= '/^Tracking_1C.pll_bw_narrow_hz=/ {b=$2} /^Tracking_1C.extend_correlation_symbols=/ {s=$2} END {print b, s}' "$OUT/run.conf")
T_S=$(awk -v s="$SYM" 'BEGIN { printf "%g", s / 1000 }')
echo "== estimate from the monitor's tracking.csv (GNSS-SDR's exact loop from the .conf)"
if [ "${RECEIVER:-import}" = live ]; then
    cp "$OUT/live/report.json" "$OUT/estimate-monitor.json"  # gsens live's final estimate
else
    "$G" estimate --imu "$OUT/imu.csv" --tracking "$OUT/tracking.csv" --gnss-sdr-conf "$OUT/run.conf" \
        --json "$OUT/estimate-monitor.json" | tee "$OUT/estimate-monitor.txt" || [ "${PIPESTATUS[0]}" = 3 ]
fi
echo "== estimate from the dumps of the same run (GNSS-SDR's exact loop model)"
"$G" estimate --imu "$OUT/imu.csv" --gnss-sdr "$OUT/dumps" --gnss-sdr-conf "$OUT/run.conf" \
    --json "$OUT/estimate-dumps.json" > "$OUT/estimate-dumps.txt" || [ $? = 3 ]

echo "== the monitor's rows with a Kaplan model of the .conf's order, Bn and interval (not GNSS-SDR's loop)"
"$G" estimate --imu "$OUT/imu.csv" --tracking "$OUT/tracking.csv" --order "$ORDER" --bn-hz "$BN" \
    --loop-interval-s "$T_S" --json "$OUT/estimate-dumps-kaplan.json" > "$OUT/estimate-dumps-kaplan.txt" || [ $? = 3 ]

python3 - "$OUT" "$T_IQ" "$T_RX" <<'PY'
import json, sys
out, t_iq, t_rx = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
truth = json.load(open(f"{out}/truth.json"))
g = truth["gamma_hz_per_mps2"]
m = json.load(open(f"{out}/estimate-monitor.json"))
d = json.load(open(f"{out}/estimate-dumps.json"))
k = json.load(open(f"{out}/estimate-dumps-kaplan.json"))
print(f"\nΓ [Hz/(m/s²)]; truth {g}")
print(f"{'':14} {'monitor (UDP), exact loop':>30} {'monitor, Kaplan model':>30} {'dumps, exact loop':>30}")
print(f"{'axis':>4} {'truth':>9} " + f"{'Γ̂ ± 1σ':>22} {'err %':>7} " * 3)
worst = 0.0
for i, ax in enumerate("xyz"):
    def cell(r):
        v, sd = r["gamma_hz_per_mps2"][i], r["sigma_hz_per_mps2"][i]
        if v is None:
            return "unobservable", float("inf")
        return f"{v:+.5f} ± {sd:.5f}", 100 * (v - g[i]) / abs(g[i])
    c1, e1 = cell(m)
    c2, e2 = cell(k)
    c3, e3 = cell(d)
    worst = max(worst, abs(e1))
    print(f"{ax:>4} {g[i]:+9.5f} {c1:>22} {e1:+7.2f} {c2:>22} {e2:+7.2f} {c3:>22} {e3:+7.2f}")
for name, r in (("monitor, exact", m), ("monitor, Kaplan", k), ("dumps, exact", d)):
    codes = [w["code"] for w in r["warnings"]]
    print(f"{name}: {r['epochs_used']} epochs, RMS {r['rms_before_rad']:.4f} → {r['rms_after_rad']:.4f} rad; "
          + ("trustworthy" if r["trustworthy"] else f"NOT trustworthy ({', '.join(codes)})"))
print(f"timings: IF generation {t_iq:.1f} s for {truth['duration_s']:.0f} s of signal; GNSS-SDR with the monitor {t_rx:.1f} s")
print(f"worst error of the estimate from the monitor: {worst:.2f} % (limit 2 %)")
sys.exit(0 if worst <= 2.0 else 1)
PY
