#!/usr/bin/env bash
# Makes the PocketSDR test fixtures in crates/gsens-pocketsdr/tests/fixtures/:
# a real log that PocketSDR's pocket_trk (version 0.17) wrote for a short gsens IF
# file, so that the log reader and the model of PocketSDR's loop are tested in
# CI against its real output without building it.
#
# 39.5 s, 3 satellites (41–46 dB-Hz), 2 Msps interleaved int8 I/Q, the paper's
# OCXO and Γ, 8 s of rest (acquisition, the 1 s FLL pull-in, settling), then
# 10 s shakes along x, y and z (1.1 s period, 3 m/s², the paper's jitter) with 0.5 s rests.
# pocket_trk runs with its default loop (b_pll = 5 Hz) and `epoch = 0.1`
# (10 Hz $CH lines). Kept: the whole log (trk.log), opt.conf, imu.csv,
# truth.json, and the true baseband carrier of the first satellite per
# millisecond from 6 s to 26 s (f32 little endian, carrier.f32, described by
# carrier.json). About 300 KB.
#
# Usage: scripts/make-pocketsdr-fixtures.sh   (needs python3, a C compiler; see scripts/lib/pocketsdr.sh)
# Environment: GSENS (a gsens binary to use instead of building one), WORK (scratch directory).
set -euo pipefail
cd "$(dirname "$0")/.."
FIX=crates/gsens-pocketsdr/tests/fixtures
WORK=${WORK:-target/pocketsdr-fixtures}
SEED=5
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
if [ -z "${GSENS:-}" ]; then
    cargo build --release -q -p gsens-cli
    GSENS=${CARGO_TARGET_DIR:-$PWD/target}/release/gsens
fi
. scripts/lib/scenario.sh
. scripts/lib/pocketsdr.sh
PT=$(build_pocket_trk "${POCKETSDR_DIR:-${CARGO_TARGET_DIR:-$PWD/target}/pocketsdr}")

{
    paper_session 3
    printf '[satellites]\nelevation_mask_deg = 10.0\nmax_channels = 3\n'
    shake_sequence 8.0 10.0 0.5 1
} > "$WORK/scenario.toml"
"$GSENS" simulate --scenario "$WORK/scenario.toml" --seed "$SEED" --out "$WORK" --iq "$WORK/signal.bin" \
    --fs-hz 2000000 --iq-carrier-truth >/dev/null
printf '# pocket_trk options: 10 Hz $CH logging, the default PLL (b_pll = 5 Hz)\nepoch = 0.1\n' > "$WORK/opt.conf"
run_pocket_trk "$PT" "$WORK/signal.bin" 2000000 "$(truth_prns "$WORK/truth.json")" "$WORK/opt.conf" "$WORK/trk.log"

rm -rf "$FIX" && mkdir -p "$FIX"
cp "$WORK/trk.log" "$WORK/opt.conf" "$WORK/imu.csv" "$WORK/truth.json" "$FIX/"
python3 - "$WORK" "$FIX" <<'PY'
import csv, json, struct, sys
work, fix = sys.argv[1:3]
prn = json.load(open(f"{work}/truth.json"))["satellites"][0]["prn"]
t0, t1 = 6.0, 26.0
vals = []
with open(f"{work}/carrier.csv") as f:
    r = csv.reader(f)
    col = next(r).index(f"prn{prn}_hz")
    for row in r:
        t = float(row[0])
        if t0 <= t < t1:
            vals.append(float(row[col]))
with open(f"{fix}/carrier.f32", "wb") as f:
    f.write(struct.pack(f"<{len(vals)}f", *vals))
json.dump({"prn": prn, "first_block": round(t0 * 1000), "blocks": len(vals), "block_s": 0.001,
           "what": "baseband carrier frequency f_bb [Hz] of the PRN over each 1 ms block [k ms, (k+1) ms), "
                   "k = first_block + i, f32 little endian"},
          open(f"{fix}/carrier.json", "w"), indent=1)
PY
[ "${KEEP_IQ:-0}" = 1 ] || rm -f "$WORK/signal.bin"
du -sh "$FIX"; ls -l "$FIX"
