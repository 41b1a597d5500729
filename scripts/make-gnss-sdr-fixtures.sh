#!/usr/bin/env bash
# Makes the GNSS-SDR test fixtures in crates/gsens-gnss-sdr/tests/fixtures/:
# real tracking dumps that GNSS-SDR 0.0.17 wrote for short gsens IF files, so
# that the dump reader, the models of GNSS-SDR's loops and the replay of its
# lock detector are tested in CI against its real output without installing it.
#
# 1. fixtures/ (ONLY=quiet): 38 s, 2 satellites at 55 dB-Hz, 2.048 Msps ibyte,
#    the paper's OCXO and Γ, 20 s of rest (acquisition, bit synchronization,
#    settling), then 5 s shakes along x, y and z. GNSS-SDR runs it twice (2nd-
#    and 3rd-order 3 Hz loops at 20 ms after the FLL/35 Hz pull-in). Kept: both
#    channels of the 2nd-order run and channel 0 of the 3rd-order run, each the
#    last 100 records of the 1 ms pull-in and all the 20 ms records (a
#    contiguous stretch of the real dump, cut at record boundaries); imu.csv,
#    truth.json, both gnss-sdr.conf; and the true baseband carrier of the
#    3rd-order channel 0 per millisecond from 22 s to 34 s (f32 little endian,
#    carrier_ch0.f32, described by carrier_ch0.json). About 600 KB.
# 2. fixtures/shaken/ (ONLY=shaken): a board shaken hard from 3 s on, while the
#    channels pull in and switch to the narrow loop: 82 s, 2 satellites at
#    45 dB-Hz, an oscillator with a TCXO's g-sensitivity (Γ = [0.2, 0.16,
#    −0.16] Hz/(m/s²), ≈ 1.2 ppb/g) and the OCXO's noise, shakes of 3 m/s² at
#    a 1.4 s period along x (42 s), y and z (15 s each) with 2 s rests: the
#    carrier lock test falls to 0.75–0.85 while shaking. Both loop orders, both
#    channels, each the last 500 records of the 1 ms stage and all the 20 ms
#    records (channel 1 of the 3rd-order run holds its reacquired track too);
#    imu.csv, truth.json, both gnss-sdr.conf. About 2.4 MB.
#
# 3. fixtures/ext1, fixtures/ext2 (ONLY=ext): the other tracking settings, on
#    one 60 s session (2 satellites at 50 dB-Hz, the paper's OCXO and Γ, 20 s
#    of rest, then 11 s shakes of 3 m/s² at a 1.1 s period along x, y and z with
#    2 s rests). ext1: extend_correlation_symbols=1 (GNSS-SDR's default), a
#    2nd-order loop of pll_bw_hz = 3 Hz updated every 1 ms after a 10 Hz FLL
#    pull-in: one record per 1 ms update before bit synchronization, one per
#    20 ms data bit (the last of its 20 updates) after it. ext2:
#    extend_correlation_symbols=2, no FLL, a 3rd-order 35 Hz loop at 1 ms, then
#    3 Hz at 2 ms after bit synchronization: one record per 20 ms bit (the last
#    of its 10 updates). Kept: both channels, each the last 100 records before
#    bit synchronization and all after it; imu.csv, truth.json, gnss-sdr.conf
#    in each. About 0.9 MB each.
#
# Usage: scripts/make-gnss-sdr-fixtures.sh   (needs gnss-sdr, python3)
# Environment: ONLY=quiet|shaken|ext|mat|kf (one set; default all), GSENS (a gsens binary
# to use instead of building one), WORK (scratch directory).
set -euo pipefail
cd "$(dirname "$0")/.."
FIX=crates/gsens-gnss-sdr/tests/fixtures
WORK=${WORK:-target/gnss-sdr-fixtures}
SEED=11
rm -rf "$WORK" && mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
. scripts/lib/common.sh
gsens_binary
. scripts/lib/scenario.sh

# satellites CHANNELS CN0: that many satellites, all at CN0 dB-Hz.
satellites() {
    printf '[satellites]\nelevation_mask_deg = 10.0\nmax_channels = %s\n[satellites.cn0]\n' "$1"
    printf 'zenith_cn0_dbhz = %s\nhorizon_cn0_dbhz = %s\nper_satellite_offset_sigma_db = 0.0\n' "$2" "$2"
}

# 1. The quiet set.
quiet() {
paper_session 2 > "$WORK/scenario.toml"
satellites 2 55.0 >> "$WORK/scenario.toml"
shake_sequence 20.0 5.0 1.0 >> "$WORK/scenario.toml"
"$G" simulate --scenario "$WORK/scenario.toml" --seed $SEED --out "$WORK" --iq "$WORK/signal.bin" \
    --fs-hz 2048000 --iq-carrier-truth
for order in 2 3; do
    d="$WORK/order$order"
    mkdir -p "$d/dumps"
    sed -e "s|^Tracking_1C.pll_filter_order=.*|Tracking_1C.pll_filter_order=$order|" \
        -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=./trk_ch_|" \
        -e "s|^SignalSource.filename=.*|SignalSource.filename=signal.bin|" "$WORK/gnss-sdr.conf" > "$d/gnss-sdr.conf"
    ln -sf "$WORK/signal.bin" "$d/signal.bin"
    (cd "$d" && gnss-sdr --config_file=gnss-sdr.conf --log_dir="$d" > gnss-sdr.log 2>&1)
done
# The quiet set only: the shaken set in fixtures/shaken is left alone.
rm -rf "$FIX"/order2 "$FIX"/order3 && mkdir -p "$FIX"
cp "$WORK/imu.csv" "$WORK/truth.json" "$FIX/"
python3 - "$WORK" "$FIX" <<'PY'
import json, os, struct, sys
work, fix = sys.argv[1], sys.argv[2]
REC = 96
fs = 2048000.0
for order in (2, 3):
    os.makedirs(f"{fix}/order{order}", exist_ok=True)
    conf = open(f"{work}/order{order}/gnss-sdr.conf").read()
    open(f"{fix}/order{order}/gnss-sdr.conf", "w").write(conf)
    for ch in ((0, 1) if order == 2 else (0,)):
        b = open(f"{work}/order{order}/trk_ch_{ch}.dat", "rb").read()
        n = [struct.unpack_from("<Q", b, i * REC + 28)[0] for i in range(len(b) // REC)]
        first20 = next(i for i in range(1, len(n)) if n[i] - n[i - 1] > 15 * fs / 1000)
        start = max(0, first20 - 100)
        open(f"{fix}/order{order}/trk_ch_{ch}.dat", "wb").write(b[start * REC:])
        print(f"order {order} ch {ch}: records {start}..{len(n)} of {len(n)}, switch at {first20}")
        if order == 3 and ch == 0:
            prn = struct.unpack_from("<I", b, first20 * REC + 92)[0]
            import csv
            rows = list(csv.reader(open(f"{work}/carrier.csv")))
            col = rows[0].index(f"prn{prn}_hz")
            b0, b1 = 22000, 34000
            vals = [float(r[col]) for r in rows[1 + b0:1 + b1]]
            ref = round(sum(vals) / len(vals))
            open(f"{fix}/carrier_ch0.f32", "wb").write(b"".join(struct.pack("<f", v - ref) for v in vals))
            json.dump({"prn": prn, "first_block": b0, "block_s": 0.001, "offset_hz": ref, "fs_hz": fs,
                       "what": "baseband carrier of channel 0 of order3 per 1 ms block b (receiver time [b, b+1) ms), "
                               "minus offset_hz, f32 little endian, from first_block on"},
                      open(f"{fix}/carrier_ch0.json", "w"), indent=1)
PY
}

# 2. The shaken set: lock tests below 0.85 while shaking, the switch to the narrow loop mid-shake.
shaken() {
    local W="$WORK/shaken" F="$FIX/shaken"
    mkdir -p "$W"
    cat > "$W/scenario.toml" <<'TOML'
[session]
start_utc = "2024-02-08T12:00:00Z"
[oscillator]
preset = "ocxo"
gamma_hz_per_mps2 = [0.2, 0.16, -0.16]
[loop]
order = 2
bn_hz = 3.0
[satellites]
elevation_mask_deg = 10.0
max_channels = 2
[satellites.cn0]
zenith_cn0_dbhz = 45.0
horizon_cn0_dbhz = 45.0
per_satellite_offset_sigma_db = 0.0
[[motion.segments]]
kind = "rest"
duration_s = 3.0
TOML
    for seg in "x 42.0" "y 15.0" "z 15.0"; do
        set -- $seg
        printf '[[motion.segments]]\nkind = "shake"\naxis = "%s"\nduration_s = %s\nperiod_s = 1.4\namplitude_mps2 = 3.0\n' "$1" "$2"
        printf '[[motion.segments]]\nkind = "rest"\nduration_s = %s\n' "$([ "$1" = z ] && echo 3.0 || echo 2.0)"
    done >> "$W/scenario.toml"
    "$G" simulate --scenario "$W/scenario.toml" --seed $SEED --out "$W" --iq "$W/signal.bin" --fs-hz 2048000
    for order in 2 3; do
        d="$W/order$order"
        mkdir -p "$d"
        sed -e "s|^Tracking_1C.pll_filter_order=.*|Tracking_1C.pll_filter_order=$order|" \
            -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=./trk_ch_|" \
            -e "s|^SignalSource.filename=.*|SignalSource.filename=signal.bin|" "$W/gnss-sdr.conf" > "$d/gnss-sdr.conf"
        ln -sf "$W/signal.bin" "$d/signal.bin"
        (cd "$d" && gnss-sdr --config_file=gnss-sdr.conf --log_dir="$d" > gnss-sdr.log 2>&1)
    done
    rm -rf "$F" && mkdir -p "$F"
    cp "$W/imu.csv" "$W/truth.json" "$F/"
    python3 - "$W" "$F" <<'PY'
import os, struct, sys
work, fix = sys.argv[1], sys.argv[2]
REC = 96
fs = 2048000.0
for order in (2, 3):
    os.makedirs(f"{fix}/order{order}", exist_ok=True)
    open(f"{fix}/order{order}/gnss-sdr.conf", "w").write(open(f"{work}/order{order}/gnss-sdr.conf").read())
    for ch in (0, 1):
        b = open(f"{work}/order{order}/trk_ch_{ch}.dat", "rb").read()
        n = [struct.unpack_from("<Q", b, i * REC + 28)[0] for i in range(len(b) // REC)]
        first20 = next(i for i in range(1, len(n)) if n[i] - n[i - 1] > 15 * fs / 1000)
        start = max(0, first20 - 500)
        open(f"{fix}/order{order}/trk_ch_{ch}.dat", "wb").write(b[start * REC:])
        print(f"shaken order {order} ch {ch}: records {start}..{len(n)} of {len(n)}, switch at {first20}")
PY
}

# 3. The other extend_correlation_symbols settings: one record per 20 ms bit after bit synchronization.
ext() {
    local W="$WORK/ext"
    mkdir -p "$W"
    paper_session 2 > "$W/scenario.toml"
    satellites 2 50.0 >> "$W/scenario.toml"
    shake_sequence 20.0 11.0 2.0 >> "$W/scenario.toml"
    "$G" simulate --scenario "$W/scenario.toml" --seed $SEED --out "$W" --iq "$W/signal.bin" --fs-hz 2048000
    # name: symbols order pll_bw_hz fll_pull_in
    for run in "ext1 1 2 3 true" "ext2 2 3 35 false"; do
        set -- $run
        local d="$W/$1"
        mkdir -p "$d"
        sed -e "s|^Tracking_1C.pll_filter_order=.*|Tracking_1C.pll_filter_order=$3|" \
            -e "s|^Tracking_1C.extend_correlation_symbols=.*|Tracking_1C.extend_correlation_symbols=$2|" \
            -e "s|^Tracking_1C.pll_bw_hz=.*|Tracking_1C.pll_bw_hz=$4|" \
            -e "s|^Tracking_1C.enable_fll_pull_in=.*|Tracking_1C.enable_fll_pull_in=$5|" \
            -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=./trk_ch_|" \
            -e "s|^SignalSource.filename=.*|SignalSource.filename=signal.bin|" "$W/gnss-sdr.conf" > "$d/gnss-sdr.conf"
        ln -sf "$W/signal.bin" "$d/signal.bin"
        (cd "$d" && gnss-sdr --config_file=gnss-sdr.conf --log_dir="$d" > gnss-sdr.log 2>&1)
        rm -rf "${FIX:?}/$1" && mkdir -p "$FIX/$1"
        cp "$W/imu.csv" "$W/truth.json" "$d/gnss-sdr.conf" "$FIX/$1/"
        python3 - "$d" "$FIX/$1" <<'PY'
import glob, os, struct, sys
work, fix = sys.argv[1], sys.argv[2]
REC = 96
fs = 2048000.0
for path in sorted(glob.glob(f"{work}/trk_ch_*.dat")):
    b = open(path, "rb").read()
    n = [struct.unpack_from("<Q", b, i * REC + 28)[0] for i in range(len(b) // REC)]
    # The first 20 ms step (not a re-acquisition's longer one): the first record after bit synchronization.
    synced = next((i for i in range(1, len(n)) if abs(n[i] - n[i - 1] - 20 * fs / 1000) < fs / 1000), None)
    if synced is None:
        print(f"{path}: never synchronized, not kept")
        continue
    start = max(0, synced - 100)
    open(f"{fix}/{os.path.basename(path)}", "wb").write(b[start * REC:])
    print(f"{path}: records {start}..{len(n)} of {len(n)}, bit synchronization at {synced}")
PY
    done
}

# 4. fixtures/mat (ONLY=mat): GNSS-SDR's own .dat and .mat of one short run
#    (1.2 s, one satellite at 50 dB-Hz, the default DLL/PLL tracking with
#    Tracking_1C.dump_mat=true; about 160 KB), for the test that the .mat
#    reader gives the .dat's records bit for bit.
# 5. fixtures/kf (ONLY=kf): the same for GPS_L1_CA_KF_Tracking (another record
#    layout of the same size as the DLL/PLL's) on 0.3 s (about 90 KB).
# $1: mat|kf; $2: Tracking_1C.implementation; $3: dump prefix; $4: IF duration [s].
short_fixture() {
    local name=$1 impl=$2 prefix=$3 d="$WORK/short-$1"
    mkdir -p "$d"
    paper_session 2 > "$d/short.toml"
    satellites 1 50.0 >> "$d/short.toml"
    printf '[[motion.segments]]\nkind = "rest"\nduration_s = %s\n' "$4" >> "$d/short.toml"
    "$G" simulate --scenario "$d/short.toml" --seed 5 --out "$d" --iq "$d/signal.bin" --fs-hz 2048000
    sed -i -e "s|^Tracking_1C.implementation=.*|Tracking_1C.implementation=$impl|" \
        -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=./$prefix|" \
        -e "s|^Tracking_1C.dump_mat=.*|Tracking_1C.dump_mat=true|" \
        -e "s|^SignalSource.filename=.*|SignalSource.filename=signal.bin|" \
        -e "s|$d/||g" "$d/gnss-sdr.conf"
    (cd "$d" && gnss-sdr --config_file=gnss-sdr.conf --log_dir="$d" > gnss-sdr.log 2>&1)
    rm -rf "${FIX:?}/$name" && mkdir -p "$FIX/$name"
    cp "$d/gnss-sdr.conf" "$d/${prefix}0.dat" "$d/${prefix}0.mat" "$FIX/$name/"
}

case "${ONLY:-both}" in
    quiet) quiet ;;
    shaken) shaken ;;
    ext) ext ;;
    mat) short_fixture mat GPS_L1_CA_DLL_PLL_Tracking trk_ch_ 1.2 ;;
    kf) short_fixture kf GPS_L1_CA_KF_Tracking trk_kf_ch_ 0.3 ;;
    *) quiet; shaken; ext; short_fixture mat GPS_L1_CA_DLL_PLL_Tracking trk_ch_ 1.2;
       short_fixture kf GPS_L1_CA_KF_Tracking trk_kf_ch_ 0.3 ;;
esac
du -ah "$FIX" | sort -k2
echo "total: $(du -sk "$FIX" | cut -f1) KB"
