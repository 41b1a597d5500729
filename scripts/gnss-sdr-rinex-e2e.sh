#!/usr/bin/env bash
# End to end through a real receiver's own observables:
#
#   gsens simulate --iq  →  GNSS-SDR 0.0.17 (Debian; PVT and RINEX 3 on)  →  its .??O file
#
# 1. installs gnss-sdr from Debian when it is missing (apt-get, as root);
# 2. writes a scenario: the paper's OCXO, Γ = [0.09, 0.08, -0.08] Hz/(m/s²) (or GAMMA),
#    8 satellites, a 3 Hz 2nd-order PLL, FIRST_REST_S of rest (acquisition, bit
#    synchronization and the first ephemeris: subframes 1–3 repeat every 30 s), then the
#    board shaken by hand along x, y, z for SHAKE_S each at a 1.1 s period with the paper's
#    jitter, REST_S of rest after each;
# 3. generates the IF samples (ibyte, FS_HZ), imu.csv, truth.json and a GNSS-SDR
#    configuration, then switches on the PVT's RINEX output: observations every
#    RINEX_RATE_MS (PVT.output_rate_ms = PVT.rinexobs_rate_ms; GNSS-SDR's observables come
#    every 20 ms, GNSS-SDR.observable_interval_ms), RINEX 3, no ionosphere or troposphere
#    model (none is simulated), dumps on;
# 4. runs GNSS-SDR and reads its observation file with gsens's RINEX reader
#    (crates/gsens-rinex/examples/rinex_csv.rs);
# 5. checks and prints: the first fix against the simulated antenna; every satellite
#    whose ephemeris GNSS-SDR decoded in the file at the expected interval with phase
#    and Doppler; −dL/dt against D; the file's Doppler and phase against the tracking
#    dumps of the same run (carrier_doppler_hz, acc_carrier_phase_rad/2π): the sign and
#    offset of each; fails when one of these does not hold;
# 6. with FIXTURE_DIR set, writes the trimmed fixture there: gnss-sdr.24O, the RINEX
#    file's header and its epochs from the first shake's start − 1 s to the last rest's
#    end, imu.csv trimmed to the same span with t_s on GPS time of week (the RINEX file's
#    time, as gsens estimate --rinex takes it), truth.json
#    (crates/gsens-rinex/tests/fixtures/gnss-sdr/README.md).
#
# Usage: scripts/gnss-sdr-rinex-e2e.sh [OUT_DIR]   (default target/gnss-sdr-rinex-e2e; needs ~1 GB there)
# Environment: FS_HZ (default 4000000), SEED (default 7), GAMMA (TOML array, Hz/(m/s²)),
# RINEX_RATE_MS (default 100: 10 Hz), FIRST_REST_S (60), SHAKE_S (15), REST_S (5),
# KEEP_IQ=1 (keep the sample file), GSENS (a gsens binary to use instead of building one),
# FIXTURE_DIR (write the trimmed fixture there).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh
OUT=$(made_dir "${1:-target/gnss-sdr-rinex-e2e}")
FS_HZ=${FS_HZ:-4000000}
SEED=${SEED:-7}
GAMMA=${GAMMA:-[0.09, 0.08, -0.08]}
RINEX_RATE_MS=${RINEX_RATE_MS:-100}
FIRST_REST_S=${FIRST_REST_S:-60}
SHAKE_S=${SHAKE_S:-15}
REST_S=${REST_S:-5}
gnss_sdr_prelude

{
    paper_session 2 "$GAMMA"
    printf '[satellites]\nelevation_mask_deg = 4.0\nmax_channels = 8\n'
    shake_sequence "$FIRST_REST_S" "$SHAKE_S" "$REST_S" 1
} > "$OUT/scenario.toml"

echo "== IF samples"
t=$(now)
"$G" simulate --scenario "$OUT/scenario.toml" --seed "$SEED" --out "$OUT" --iq "$OUT/signal.bin" --fs-hz "$FS_HZ"
T_IQ=$(elapsed "$t")

d="$OUT/rx"
rm -rf "$d" && mkdir -p "$d/dumps"
sed -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=$d/dumps/trk_ch_|" \
    -e "s|^PVT.output_rate_ms=.*|PVT.output_rate_ms=$RINEX_RATE_MS|" \
    -e "s|^PVT.rinex_output_enabled=.*|PVT.rinex_output_enabled=true|" \
    "$OUT/gnss-sdr.conf" > "$d/gnss-sdr.conf"
cat >> "$d/gnss-sdr.conf" <<CONF
PVT.rinexobs_rate_ms=$RINEX_RATE_MS
PVT.rinex_version=3
PVT.output_path=$d
PVT.rinex_output_path=$d
PVT.iono_model=OFF
PVT.trop_model=OFF
PVT.elevation_mask=0
CONF
echo "== GNSS-SDR with PVT and RINEX output"
t=$(now)
(cd "$d" && gnss-sdr --config_file="$d/gnss-sdr.conf" --log_dir="$d" > "$d/gnss-sdr.log" 2>&1)
T_RX=$(elapsed "$t")
echo "GNSS-SDR ran $T_RX s"
grep -E "First position fix|New GPS NAV message|Loss of lock" "$d/gnss-sdr.log" | sort | uniq -c | sort -rn | head -5 || true
[ "${KEEP_IQ:-0}" = 1 ] || rm -f "$OUT/signal.bin"

shopt -s nullglob
obs=("$d"/*.[0-9][0-9]O)
if [ ${#obs[@]} = 0 ]; then
    echo "GNSS-SDR wrote no RINEX observation file: its log's last lines:" >&2
    tail -20 "$d/gnss-sdr.log" >&2
    exit 1
fi
echo "== ${obs[0]##*/} through gsens's RINEX reader"
cargo run -q -p gsens-rinex --example rinex_csv -- "${obs[0]}" > "$d/obs.csv"

python3 - "$OUT" "${obs[0]}" "$RINEX_RATE_MS" "$T_IQ" "$T_RX" "$FIRST_REST_S" "$SHAKE_S" "$REST_S" \
    "${FIXTURE_DIR:-}" <<'PY'
import csv, datetime, glob, json, math, os, re, shutil, sys
import numpy as np

out, obs_path, rate_ms, t_iq, t_rx = sys.argv[1], sys.argv[2], int(sys.argv[3]), *map(float, sys.argv[4:6])
first_rest, shake, rest = map(float, sys.argv[6:9])
fixture = sys.argv[9]
truth = json.load(open(f"{out}/truth.json"))
fs = truth["fs_hz"]
week = math.floor(truth["start_gps_s"] / 604800)
tow0 = truth["start_gps_s"] - week * 604800
failed = []

# The first fix against the antenna.
ant = truth["scenario"]["antenna"]
def ecef(lat, lon, h):
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    la, lo = math.radians(lat), math.radians(lon)
    n = a / math.sqrt(1 - e2 * math.sin(la) ** 2)
    return np.array([(n + h) * math.cos(la) * math.cos(lo), (n + h) * math.cos(la) * math.sin(lo),
                     (n * (1 - e2) + h) * math.sin(la)])
log = open(f"{out}/rx/gnss-sdr.log", errors="replace").read()
m = re.search(r"First position fix at (.*?) UTC is Lat = ([-\d.]+) \[deg\], Long = ([-\d.]+) \[deg\], Height= ([-\d.]+) \[m\]", log)
if m:
    fix = ecef(float(m.group(2)), float(m.group(3)), float(m.group(4)))
    err = np.linalg.norm(fix - ecef(ant["lat_deg"], ant["lon_deg"], ant.get("height_m", 0.0)))
    print(f"first fix at {m.group(1)} UTC: {err:.1f} m from the simulated antenna")
    fixes = re.findall(r"Position at .*? is Lat = ([-\d.]+) \[deg\], Long = ([-\d.]+) \[deg\], Height = ([-\d.]+) \[m\]", log)
    if fixes:
        errs = [np.linalg.norm(ecef(*map(float, f)) - ecef(ant["lat_deg"], ant["lon_deg"], ant.get("height_m", 0.0)))
                for f in fixes]
        print(f"{len(errs)} displayed fixes: distance from the antenna median {np.median(errs):.2f} m, max {max(errs):.2f} m")
else:
    failed.append("no position fix")

# The file as gsens read it.
rows = list(csv.DictReader(open(f"{out}/rx/obs.csv")))
tracks = {}
for r in rows:
    tracks.setdefault(r["sv"] + " " + r["code"], []).append(r)
dumps = {}
rec = np.dtype([("abs_VE", "<f4"), ("abs_E", "<f4"), ("abs_P", "<f4"), ("abs_L", "<f4"), ("abs_VL", "<f4"),
                ("Prompt_I", "<f4"), ("Prompt_Q", "<f4"), ("PRN_start_sample_count", "<u8"),
                ("acc_carrier_phase_rad", "<f4"), ("carrier_doppler_hz", "<f4"), ("carrier_doppler_rate_hz", "<f4"),
                ("code_freq_chips", "<f4"), ("code_freq_rate_chips", "<f4"), ("carr_error_hz", "<f4"),
                ("carr_error_filt_hz", "<f4"), ("code_error_chips", "<f4"), ("code_error_filt_chips", "<f4"),
                ("CN0_SNV_dB_Hz", "<f4"), ("carrier_lock_test", "<f4"), ("aux1", "<f4"), ("aux2", "<f8"), ("PRN", "<u4")])
for f in sorted(glob.glob(f"{out}/rx/dumps/trk_ch_*.dat")):
    x = np.fromfile(f, dtype=rec)
    x = x[x["PRN"] > 0]
    if len(x):
        dumps.setdefault(int(x["PRN"][-1]), []).append(x)
tracked = sorted(dumps)
print(f"satellites simulated {[s['prn'] for s in truth['satellites']]}, tracked (dumps) {tracked}")
print(f"{'signal':8} {'epochs':>6} {'span [s]':>17} {'dt [ms]':>8} {'L':>6} {'D':>6} "
      f"{'-dL/dt-D [Hz]':>19} {'D-dump [Hz]':>17} {'L-dump/2π [cyc]':>22}")
# The satellites whose ephemeris GNSS-SDR decoded (subframes 1, 2 and 3): those a fix can use.
decoded = {}
for ch, sf, prn in re.findall(r"New GPS NAV message received in channel (\d+): subframe (\d) from satellite GPS PRN (\d+)", log):
    decoded.setdefault(int(prn), set()).add(int(sf))
with_eph = sorted(p for p, s in decoded.items() if {1, 2, 3} <= s)
print(f"ephemeris decoded for {with_eph}; tracked without: {sorted(set(tracked) - set(with_eph))}")
expected = rate_ms / 1000
pooled = []
for prn in with_eph:
    key = f"G{prn:02d} 1C"
    if key not in tracks:
        failed.append(f"G{prn:02d}: ephemeris decoded but not in the file")
        continue
    tr = tracks[key]
    t = np.array([float(r["t_s"]) for r in tr])
    L = np.array([float(r["carrier_phase_cycles"]) for r in tr])
    D = np.array([float(r["doppler_hz"]) for r in tr])
    dt = np.diff(t)
    ok = np.isfinite(L[1:]) & np.isfinite(L[:-1]) & (np.abs(dt - expected) < 1e-6)
    resid = (-(L[1:] - L[:-1]) / dt - 0.5 * (D[1:] + D[:-1]))[ok]
    # The dump of the same satellite at the file's epochs (the sample counter to GPS time of week:
    # sample n at tow0 + n/fs; the receiver's clock offset from it is ms at most).
    x = np.concatenate(dumps[prn])
    ts = tow0 + x["PRN_start_sample_count"] / fs
    inside = (t >= ts[0]) & (t <= ts[-1])
    d_dump = np.interp(t[inside], ts, x["carrier_doppler_hz"].astype(float))
    # acc_carrier_phase_rad accumulates without wrapping (f32: 0.02 cycle steps near 1e6 rad).
    ph_dump = np.interp(t[inside], ts, x["acc_carrier_phase_rad"].astype(float)) / (2 * math.pi)
    dd = D[inside] - d_dump
    same, opposite = L[inside] - ph_dump, L[inside] + ph_dump
    # An epoch stamped δ before the samples it was measured at gives L − dump/2π = const − D·δ.
    ok_pairs = np.isfinite(same) & np.isfinite(D[inside])
    pooled.append((same[ok_pairs] - same[ok_pairs].mean(), D[inside][ok_pairs] - D[inside][ok_pairs].mean()))
    print(f"{key:8} {len(t):6d} {t[0] - tow0:8.2f}…{t[-1] - tow0:8.2f} {1000 * np.median(dt):8.1f} "
          f"{np.isfinite(L).sum():6d} {np.isfinite(D).sum():6d} "
          f"{np.mean(resid):+8.4f} ± {np.std(resid):7.4f} {np.nanmean(dd):+8.4f} ± {np.nanstd(dd):6.4f} "
          f"{np.nanmedian(same):+11.1f} ± {np.nanstd(same):7.4f}   (L+dump/2π: ± {np.nanstd(opposite):.0f})")
    if abs(np.median(dt) - expected) > 1e-6:
        failed.append(f"{key}: interval {np.median(dt)} s")
    if np.isfinite(L).sum() < 0.99 * len(t) or np.isfinite(D).sum() < 0.99 * len(t):
        failed.append(f"{key}: phase or Doppler missing")
    if abs(np.mean(resid)) > 0.05:
        failed.append(f"{key}: -dL/dt differs from D by {np.mean(resid):+.3f} Hz")
    if np.nanstd(dd) > 0.01 or np.nanstd(same) > 0.1:
        failed.append(f"{key}: D or L is not the tracking dump's carrier_doppler_hz or acc_carrier_phase_rad/2π")
extra = sorted(k for k in tracks if int(k[1:3]) not in with_eph)
if extra:
    failed.append(f"in the file but not tracked: {extra}")
if pooled:
    y = np.concatenate([p[0] for p in pooled])
    x_d = np.concatenate([p[1] for p in pooled])
    delta = -np.dot(x_d, y) / np.dot(x_d, x_d)
    se = np.std(y + delta * x_d) / math.sqrt(np.dot(x_d, x_d))
    print(f"epoch time − sample time (tow0 + n/fs) from L − dump/2π against D: δ = {1e6 * delta:+.1f} ± {1e6 * se:.1f} µs")
n_epochs = len({r["t_s"] for r in rows})
print(f"{n_epochs} epochs from {min(float(r['t_s']) for r in rows) - tow0:.2f} s to "
      f"{max(float(r['t_s']) for r in rows) - tow0:.2f} s after the first sample")
print(f"timings: IF generation {t_iq:.1f} s for {truth['duration_s']:.0f} s of signal, GNSS-SDR {t_rx:.1f} s")

if fixture:
    # The shaken part: from 1 s before the first shake to the end of the last rest.
    t0 = tow0 + first_rest - 1.0
    t1 = tow0 + first_rest + 3 * (shake + rest)
    os.makedirs(fixture, exist_ok=True)
    lines = open(obs_path).read().splitlines(keepends=True)
    head = next(i for i, l in enumerate(lines) if "END OF HEADER" in l) + 1
    kept, keep = lines[:head], False
    for l in lines[head:]:
        if l.startswith(">"):
            f = l[1:].split()
            sec = float(f[5])
            # The epoch's time of week from its calendar date (GPS time).
            day = datetime.datetime(int(f[0]), int(f[1]), int(f[2]), int(f[3]), int(f[4]))
            tow = (day - datetime.datetime(1980, 1, 6)).total_seconds() + sec - week * 604800
            keep = t0 <= tow <= t1
        if keep:
            kept.append(l)
    name = "gnss-sdr.24O"
    open(f"{fixture}/{name}", "w").write("".join(kept))
    # The IMU log on the RINEX file's time: t_s the GPS time of week (the first sample's + t_s).
    imu = open(f"{out}/imu.csv").read().splitlines(keepends=True)
    sel = [imu[0]]
    for l in imu[1:]:
        t, rest = l.split(",", 1)
        if t0 - tow0 <= float(t) <= t1 - tow0:
            sel.append(f"{round(tow0 + float(t), 9)!r},{rest}")
    open(f"{fixture}/imu.csv", "w").write("".join(sel))
    shutil.copy(f"{out}/truth.json", f"{fixture}/truth.json")
    print(f"fixture: {fixture}/{name} ({sum(map(len, kept)) / 1024:.0f} KB), imu.csv ({len(sel) - 1} rows), truth.json")

if failed:
    print("FAILED: " + "; ".join(failed))
sys.exit(1 if failed else 0)
PY
