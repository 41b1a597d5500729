# Shared by the PocketSDR scripts: fetch and build PocketSDR's pocket_trk
# outside the repository (nothing of it is committed).
#
# build_pocket_trk DIR
#   builds pocket_trk under DIR (once; DIR/bin/pocket_trk) and prints its path
#   on stdout (progress on stderr). The source, PocketSDR at commit
#   $POCKETSDR_COMMIT (version 0.17, the one gsens's model was read from), comes from
#   $POCKETSDR_SRC:
#     - a local git directory (e.g. a bare mirror of the repository; the
#       default is /work/.mirror/tomojitakasu+PocketSDR/repo when it exists):
#       only src/, lib/ and app/pocket_trk/ are exported (`git archive`), so a
#       mirror without the repository's large binaries works;
#     - otherwise a URL to clone (default https://github.com/tomojitakasu/PocketSDR).
#   Needs gcc/g++, make and libusb-1.0 headers (Debian libusb-1.0-0-dev; installed with
#   apt-get when missing and running as root). Built without SoapySDR, with PocketFFT.
POCKETSDR_COMMIT=${POCKETSDR_COMMIT:-b6af31fbcd3ffeabfcc167eb22c32ca357a503a0}
build_pocket_trk() {
    local dir=$1 src=${POCKETSDR_SRC:-}
    if [ -x "$dir/bin/pocket_trk" ]; then
        echo "$dir/bin/pocket_trk"
        return
    fi
    if [ -z "$src" ]; then
        if [ -d /work/.mirror/tomojitakasu+PocketSDR/repo ]; then
            src=/work/.mirror/tomojitakasu+PocketSDR/repo
        else
            src=https://github.com/tomojitakasu/PocketSDR
        fi
    fi
    if [ ! -f /usr/include/libusb-1.0/libusb.h ]; then
        echo "== installing libusb-1.0-0-dev (Debian)" >&2
        apt-get update -qq >&2 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libusb-1.0-0-dev >&2
    fi
    rm -rf "$dir/src" && mkdir -p "$dir/src" "$dir/bin"
    echo "== PocketSDR $POCKETSDR_COMMIT from $src" >&2
    if [ -d "$src" ]; then
        git --git-dir="$src" archive "$POCKETSDR_COMMIT" src lib/build lib/RTKLIB lib/pocketfft app/pocket_trk \
            | tar -x -C "$dir/src"
    else
        git clone -q "$src" "$dir/src" >&2
        git -C "$dir/src" checkout -q "$POCKETSDR_COMMIT" >&2
    fi
    mkdir -p "$dir/src/lib/linux"
    (cd "$dir/src/lib/build" && make USE_SOAPY=0 >&2 && make USE_SOAPY=0 install >&2) >"$dir/build.log" 2>&1
    (cd "$dir/src/app/pocket_trk" && make USE_SOAPY=0 pocket_trk >&2) >>"$dir/build.log" 2>&1
    cp "$dir/src/app/pocket_trk/pocket_trk" "$dir/bin/pocket_trk"
    echo "$dir/bin/pocket_trk"
}

# run_pocket_trk POCKET_TRK IQ_FILE FS_HZ PRNS OPT_FILE LOG
#   tracks GPS L1 C/A of the PRNs (comma-separated) in a `gsens simulate --iq
#   --iq-format ibyte` file (interleaved int8 I/Q: PocketSDR's CS8; its INT8X2
#   would invert Q), zero IF, with the options file OPT_FILE, writing the log
#   LOG. The file is replayed POCKETSDR_TSCALE (default 4) times faster than
#   real time: pocket_trk paces file input by the wall clock, and its channels
#   keep up at this rate with 8 channels at 2–4 Msps on one core.
run_pocket_trk() {
    local bin=$1 iq=$2 fs_hz=$3 prns=$4 opt=$5 log=$6
    local fs_mhz
    fs_mhz=$(awk -v f="$fs_hz" 'BEGIN { printf "%.6f", f / 1e6 }')
    "$bin" -sig L1CA -prn "$prns" -fmt CS8 -f "$fs_mhz" -fo 0 -IQ 2 -tscale "${POCKETSDR_TSCALE:-4}" \
        -opt "$opt" -log "$log" "$iq" >/dev/null
}

# truth_prns TRUTH_JSON
#   the PRNs of a `gsens simulate --iq` file, comma-separated.
truth_prns() {
    python3 -c 'import json, sys; print(",".join(str(s["prn"]) for s in json.load(open(sys.argv[1]))["satellites"]))' "$1"
}
