# Shared by the end-to-end and fixture scripts (source it from the repository root).
#
# now / elapsed T0: wall-clock seconds, and the seconds since T0 to one decimal.
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

# gsens_binary: the gsens to run: $GSENS, else gsens-cli built here (honouring
# CARGO_TARGET_DIR). Sets G.
gsens_binary() {
    if [ -z "${GSENS:-}" ]; then
        echo "== building gsens"
        cargo build --release -q -p gsens-cli
        GSENS=${CARGO_TARGET_DIR:-$PWD/target}/release/gsens
    fi
    G=$GSENS
}

# ensure_gnss_sdr: installs gnss-sdr from Debian when missing (apt-get, as root), prints its version.
ensure_gnss_sdr() {
    if ! command -v gnss-sdr >/dev/null; then
        echo "== installing gnss-sdr from Debian"
        local t
        t=$(now)
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq gnss-sdr >/dev/null
        echo "installed in $(elapsed "$t") s"
    fi
    gnss-sdr --version
}

# made_dir DIR: creates DIR when missing and prints its absolute path.
made_dir() { mkdir -p "$1" && (cd "$1" && pwd); }

# gnss_sdr_prelude: gnss-sdr installed (ensure_gnss_sdr), the gsens to run in G
# (gsens_binary) and the scenario pieces loaded (scripts/lib/scenario.sh).
gnss_sdr_prelude() {
    ensure_gnss_sdr
    gsens_binary
    . scripts/lib/scenario.sh
}
