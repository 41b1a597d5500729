#!/usr/bin/env bash
# End to end through PocketSDR, T. Takasu's software receiver:
#
#   gsens simulate --iq  →  pocket_trk (PocketSDR 0.17, built here)  →  gsens estimate --pocketsdr
#
# 1. fetches and builds pocket_trk outside the repository (scripts/lib/pocketsdr.sh:
#    from the local mirror /work/.mirror/tomojitakasu+PocketSDR/repo when present,
#    else cloned from https://github.com/tomojitakasu/PocketSDR; POCKETSDR_SRC overrides);
# 2. writes two scenarios: the paper's OCXO with its Γ = [0.09, 0.08, -0.08] Hz/(m/s²)
#    and a TCXO-like Γ = [-0.2, 0.15, 0.12] Hz/(m/s²) (other signs and sizes), 8
#    satellites, 10 s of rest (acquisition, the 1 s FLL pull-in, the PLL's settling),
#    then the board shaken by hand along x, y, z for 45 s each (1.1 s period, 3 m/s²,
#    the paper's jitter) with 1 s rests: 148 s, as long as GNSS-SDR's;
# 3. generates each scenario's IF samples (interleaved int8 I/Q, FS_HZ, default 2 Msps),
#    imu.csv and truth.json, without the navigation message (`--iq-no-data`, the bare C/A
#    code): at `epoch` below 0.07 s pocket_trk writes no more $CH lines once it has decoded
#    the GPS week (docs/conventions.md, from its sdr_pvt.c; 78 s and 125 s into these files
#    with the data), and without the data it never does. Its PLL sees the same carrier: the
#    Costas discriminator ignores the data's sign;
# 4. runs pocket_trk on each file twice, with `epoch = 0.02` (50 Hz $CH lines; EPOCH_S
#    overrides) and the PLL at its default b_pll = 5 Hz and at 10 Hz (options files).
#    Why 0.02 s and not 0.025 s (40 Hz): should pocket_trk decode the navigation data (a
#    file with it), it logs at its PVT epochs, which start on a multiple of 20 ms; at 0.025 s
#    that moves the $CH grid mid-log. `lag_epoch = 30` makes such PVT epochs wait for the
#    channels (replayed faster than real time they may lag the reader by more than 0.5 s);
# 5. estimates Γ from each log with PocketSDR's exact loop (tested, not fitted), every
#    channel weighted by its C/N0 (`--channels 0 --weights cn0`: a single 1 ms discriminator
#    output per line is thermal-noise-limited, its variance ∝ 1/(C/N0)), and, for comparison,
#    from gsens's own simulator logs of the same scenario (Kaplan's 3rd-order loop at the
#    same bandwidth, 1 ms updates, the last output logged, same channel options);
# 6. prints the table (truth, PocketSDR, gsens simulator) and fails when an estimate
#    from PocketSDR's log is more than 2 % from the truth at b_pll = 5 Hz, or outside its own
#    2σ at 10 Hz (noise-limited there: |L| is four times smaller), or when the loop response
#    check (`loop_response`) fails. 2σ is taken family-wise over the 6 checks at 10 Hz (2.66σ
#    each, Šidák: each at 2σ would fail a correct estimator 24 % of the time).
#
# Usage: scripts/pocketsdr-e2e.sh [OUT_DIR]   (default target/pocketsdr-e2e; needs ~1.2 GB there)
# Environment: FS_HZ, SEED, KEEP_IQ=1 (keep the sample files), GSENS (a gsens binary to use
# instead of building one; the build honours CARGO_TARGET_DIR), POCKETSDR_DIR (where
# pocket_trk is built, default $CARGO_TARGET_DIR/pocketsdr or target/pocketsdr),
# POCKETSDR_TSCALE (file replay speed, default 4).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-target/pocketsdr-e2e}
FS_HZ=${FS_HZ:-2000000}
EPOCH_S=${EPOCH_S:-0.02}
SEED=${SEED:-7}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
. scripts/lib/common.sh

. scripts/lib/scenario.sh
. scripts/lib/pocketsdr.sh
t=$(now)
PT=$(build_pocket_trk "${POCKETSDR_DIR:-${CARGO_TARGET_DIR:-$PWD/target}/pocketsdr}")
echo "pocket_trk: $PT ($("$PT" -v 2>/dev/null | head -1); ready in $(elapsed "$t") s)"

gsens_binary

scenario() { # $1 = Γ as a TOML array, $2 = the loop's bandwidth for gsens's own simulator
    paper_session 3 | sed -e "s/^gamma_hz_per_mps2 = .*/gamma_hz_per_mps2 = $1/" -e "s/^bn_hz = .*/bn_hz = $2/"
    cat <<TOML
[satellites]
elevation_mask_deg = 4.0
max_channels = 8
[log]
interval_s = $EPOCH_S
phase = "last"
TOML
    shake_sequence 10.0 45.0 1.0 1
}

declare -A GAMMA=([paper]="[0.09, 0.08, -0.08]" [tcxo]="[-0.2, 0.15, 0.12]")
declare -A T_RX
for case in paper tcxo; do
    c="$OUT/$case"
    mkdir -p "$c"
    for bw in 5 10; do
        scenario "${GAMMA[$case]}" "$bw" > "$c/scenario-bw$bw.toml"
    done
    echo "== IF samples, Γ = ${GAMMA[$case]}"
    t=$(now)
    "$G" simulate --scenario "$c/scenario-bw5.toml" --seed "$SEED" --out "$c" --iq "$c/signal.bin" --fs-hz "$FS_HZ" --iq-no-data \
        >/dev/null
    echo "generated in $(elapsed "$t") s"
    prns=$(truth_prns "$c/truth.json")
    for bw in 5 10; do
        d="$c/bw$bw"
        rm -rf "$d" && mkdir -p "$d"
        printf '# $CH lines every %s s; PVT epochs wait for the channels\nepoch = %s\nlag_epoch = 30\n' \
            "$EPOCH_S" "$EPOCH_S" > "$d/opt.conf"
        if [ "$bw" = 5 ]; then
            echo '# the default PLL (b_pll = 5 Hz)' >> "$d/opt.conf"
        else
            printf 'b_pll = %s\n' "$bw" >> "$d/opt.conf"
        fi
        echo "== pocket_trk, b_pll $bw Hz, PRNs $prns"
        t=$(now)
        run_pocket_trk "$PT" "$c/signal.bin" "$FS_HZ" "$prns" "$d/opt.conf" "$d/trk.log" 2>/dev/null
        T_RX[$case$bw]=$(elapsed "$t")
        echo "pocket_trk ran ${T_RX[$case$bw]} s; $(grep -c '^\$CH' "$d/trk.log") \$CH lines"
        last=$(grep '^\$CH' "$d/trk.log" | tail -1 | cut -d, -f2)
        if awk -v l="$last" -v d="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["duration_s"])' "$c/truth.json")" \
            'BEGIN { exit !(l < d - 1) }'; then
            echo "NOTE: pocket_trk wrote its last \$CH line at $last s, before the file's end" \
                "($(grep -c PNTPOS "$d/trk.log") PVT epochs without observations after it)"
        fi
        echo "== estimate from PocketSDR's log, b_pll $bw Hz"
        "$G" estimate --imu "$c/imu.csv" --pocketsdr "$d/trk.log" --pocketsdr-conf "$d/opt.conf" \
            --channels 0 --weights cn0 --json "$d/estimate.json" > "$d/estimate.txt" || [ $? = 3 ]
        grep -E "^PocketSDR log|^  ch |^loop check|^measured loop|^verdict" "$d/estimate.txt" || true
        echo "== gsens's own simulator, same scenario, Kaplan 3rd order $bw Hz"
        s="$d/sim"
        "$G" simulate --scenario "$c/scenario-bw$bw.toml" --seed "$SEED" --out "$s" >/dev/null
        "$G" estimate --imu "$s/imu.csv" --tracking "$s/tracking.csv" --order 3 --bn-hz "$bw" \
            --loop-interval-s 0.001 --logged-phase last --channels 0 --weights cn0 --json "$s/estimate.json" > "$s/estimate.txt" || [ $? = 3 ]
    done
    [ "${KEEP_IQ:-0}" = 1 ] || rm -f "$c/signal.bin"
done

python3 - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
truth_s = json.load(open(f"{out}/paper/truth.json"))["duration_s"]
# 2σ per check at 10 Hz, family-wise: 6 checks (2 files × 3 axes) each at 2σ would fail a
# correct estimator 24 % of the time; z_fw gives the family the 95 % of a single 2σ check (Šidák).
from statistics import NormalDist
n_checks = 6
z_fw = NormalDist().inv_cdf(1 - (1 - 0.9545 ** (1 / n_checks)) / 2)
print(f"\nΓ [Hz/(m/s²)], {truth_s:.0f} s sessions; PocketSDR: pocket_trk 0.17 logs, its exact loop;"
      " simulator: gsens's own logs of the same scenario")
print(f"{'case':22} {'axis':>4} {'truth':>9} {'PocketSDR':>22} {'err %':>7} {'err/σ':>6} {'gsens simulator':>22} {'err %':>7}")
ok = True
for case in ("paper", "tcxo"):
    truth = json.load(open(f"{out}/{case}/truth.json"))
    g = truth["gamma_imu_axes_hz_per_mps2"]
    for bw in (5, 10):
        e = json.load(open(f"{out}/{case}/bw{bw}/estimate.json"))
        s = json.load(open(f"{out}/{case}/bw{bw}/sim/estimate.json"))
        for i, ax in enumerate("xyz"):
            def cell(r):
                v, sd = r["gamma_hz_per_mps2"][i], r["sigma_hz_per_mps2"][i]
                if v is None:
                    return "unobservable", float("nan"), float("nan")
                return f"{v:+.5f} ± {sd:.5f}", 100 * (v - g[i]) / abs(g[i]), (v - g[i]) / sd
            c1, e1, z1 = cell(e)
            c2, e2, _ = cell(s)
            # 5 Hz: within 2 %; 10 Hz: within z_fw·σ.
            passed = abs(e1) <= 2.0 if bw == 5 else abs(z1) <= z_fw
            ok &= passed
            name = f"Γ {case}, b_pll {bw} Hz" if i == 0 else ""
            mark = "" if passed else "  FAIL"
            print(f"{name:22} {ax:>4} {g[i]:+9.5f} {c1:>22} {e1:+7.2f} {z1:+6.2f} {c2:>22} {e2:+7.2f}{mark}")
        lr = e.get("loop_response")
        consistent = bool(lr) and lr.get("consistent") is True
        ok &= consistent
        used = [t for t in e["channels"] if t.get("used")]
        lrs = (f"(largest deviation {max(lr['max_magnitude_deviation_sigma'], lr['max_phase_deviation_sigma']):.1f}σ, "
               f"threshold {lr['threshold_sigma']:.1f}σ)") if lr else "(not measured)"
        print(f"{'':22} {len(used)} channels, {e['epochs_used']} epochs, RMS {e['rms_before_rad']:.4f} → "
              f"{e['rms_after_rad']:.4f} rad; loop test z = {e['joint_fit']['loop_test_z']:+.2f}; "
              f"loop_response {'consistent' if consistent else 'NOT consistent'} {lrs}"
              f"; trustworthy {e['trustworthy']}")
print(f"criterion: within 2 % at b_pll = 5 Hz, within its own {z_fw:.2f}σ at 10 Hz",
      f"({z_fw:.2f}σ: 2σ family-wise over its {n_checks} checks), loop_response consistent:",
      "PASS" if ok else "FAIL")
sys.exit(0 if ok else 1)
PY
