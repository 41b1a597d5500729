#!/usr/bin/env bash
# Regenerates crates/gsens-gnss-sdr/tests/fixtures/monitor/: GNSS-SDR 0.0.17's tracking monitor
# (protobuf over UDP, decimation 1) captured for a short 2-satellite `gsens simulate --iq` file,
# the first 2 500 datagrams as received (u32 little-endian length, then the bytes), and the
# tracking dumps of the same run cut to the span of those datagrams (±3 records of 20 ms).
#
# The committed fixture was captured by a plain UDP reader (Python); this script captures with
# `gsens import gnss-sdr-monitor --raw`, which writes the same format. GNSS-SDR 0.0.17 re-sends
# old outputs (the whole capture of this 26 s run is millions of datagrams, hundreds of MB), so
# only the start is kept: its first ~1 030 datagrams are fresh outputs, the rest re-sends.
#
# Usage: scripts/make-gnss-sdr-monitor-fixture.sh   (WORK, PORT, GSENS as in the other scripts)
set -euo pipefail
cd "$(dirname "$0")/.."
FIX=crates/gsens-gnss-sdr/tests/fixtures/monitor
WORK=${WORK:-target/gnss-sdr-monitor-fixture}
PORT=${PORT:-17234}
rm -rf "$WORK" && mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
. scripts/lib/common.sh
gsens_binary
. scripts/lib/scenario.sh
{
    paper_session 2
    printf '[satellites]\nelevation_mask_deg = 10.0\nmax_channels = 2\n[satellites.cn0]\n'
    printf 'zenith_cn0_dbhz = 50.0\nhorizon_cn0_dbhz = 50.0\nper_satellite_offset_sigma_db = 0.0\n'
    shake_sequence 14.0 3.0 1.0
} > "$WORK/scenario.toml"
"$G" simulate --scenario "$WORK/scenario.toml" --seed 11 --out "$WORK" --iq "$WORK/signal.bin" --fs-hz 2048000
sed -e "s|^Tracking_1C.dump_filename=.*|Tracking_1C.dump_filename=./trk_ch_|" \
    -e "s|^SignalSource.filename=.*|SignalSource.filename=signal.bin|" "$WORK/gnss-sdr.conf" > "$WORK/run.conf"
printf 'TrackingMonitor.enable_monitor=true\nTrackingMonitor.client_addresses=127.0.0.1\nTrackingMonitor.udp_port=%s\nTrackingMonitor.decimation_factor=1\nTrackingMonitor.enable_protobuf=true\n' \
    "$PORT" >> "$WORK/run.conf"
"$G" import gnss-sdr-monitor --listen "127.0.0.1:$PORT" --gnss-sdr-conf "$WORK/run.conf" \
    --out "$WORK/tracking.csv" --raw "$WORK/monitor-all.bin" --idle-timeout-s 5 &
REC=$!
sleep 1
(cd "$WORK" && gnss-sdr --config_file=run.conf --log_dir="$WORK" > gnss-sdr.log 2>&1)
wait $REC
mkdir -p "$FIX"
python3 - "$WORK" "$FIX" <<'PY'
import struct, sys
work, fix = sys.argv[1], sys.argv[2]
N, REC, STEP = 2500, 96, 40960
def varint(b, i):
    v = s = 0
    while True:
        c = b[i]; i += 1; v |= (c & 0x7f) << s; s += 7
        if c < 0x80: return v, i
def fields(b):  # protobuf fields of one message: {number: [values]} (varints and byte strings only)
    i, out = 0, {}
    while i < len(b):
        k, i = varint(b, i); f, w = k >> 3, k & 7
        if w == 0: v, i = varint(b, i)
        elif w == 1: v = None; i += 8
        elif w == 5: v = None; i += 4
        else: l, i = varint(b, i); v = b[i:i + l]; i += l
        out.setdefault(f, []).append(v)
    return out
kept, lo, hi = [], {}, {}
with open(f"{work}/monitor-all.bin", "rb") as f:
    for _ in range(N):
        (l,) = struct.unpack("<I", f.read(4)); d = f.read(l); kept.append(d)
        for g in fields(d).get(1, []):
            m = fields(g); ch = m.get(4, [0])[0]; n = m[17][0]
            lo[ch] = min(lo.get(ch, n), n); hi[ch] = max(hi.get(ch, n), n)
open(f"{fix}/monitor.bin", "wb").write(b"".join(struct.pack("<I", len(d)) + d for d in kept))
for ch in sorted(lo):
    b = open(f"{work}/trk_ch_{ch}.dat", "rb").read()
    recs = [b[i * REC:(i + 1) * REC] for i in range(len(b) // REC)]
    keep = [r for r in recs if lo[ch] - 3 * STEP <= struct.unpack_from("<Q", r, 28)[0] <= hi[ch] + 3 * STEP]
    open(f"{fix}/trk_ch_{ch}.dat", "wb").write(b"".join(keep))
    print(f"channel {ch}: counters {lo[ch]}..{hi[ch]}, {len(keep)} dump records kept")
PY
sed -e "s|^TrackingMonitor.udp_port=.*|TrackingMonitor.udp_port=17234|" "$WORK/run.conf" > "$FIX/gnss-sdr.conf"
ls -l "$FIX"
