#!/usr/bin/env bash
# Runs every fuzz target for SECONDS (default 60) each, one after another:
#   scripts/fuzz.sh [SECONDS] [TARGET...]
# cargo-fuzz (libFuzzer with AddressSanitizer) needs a nightly compiler's
# flags: on a stable toolchain they are allowed with RUSTC_BOOTSTRAP=1, as
# here. Each target starts from its committed seeds (fuzz/seeds/<target>)
# and grows its working corpus in fuzz/corpus/<target> (not committed); a
# crash, timeout or out-of-memory input lands in fuzz/artifacts/<target> and
# stops the script with a non-zero exit. The last lines of each run's
# statistics go to fuzz/logs/<target>.log.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
export RUSTC_BOOTSTRAP=1
if ! command -v cargo-fuzz > /dev/null; then
    cargo install cargo-fuzz --version 0.13.2 --locked
fi
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    mapfile -t targets < <(cargo fuzz list)
fi
cargo fuzz build -O
mkdir -p fuzz/logs
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t" "fuzz/seeds/$t"
    echo "fuzz: $t for ${seconds} s"
    # -timeout: an input running longer than this is a hang (a reader: 10 s;
    # the estimator, a whole calibration of up to a few minutes of log under
    # the sanitizer and the coverage counters, some 20 times slower than a
    # release build: 60 s); -rss_limit_mb: more than 2 GB is a reader
    # allocating without limit.
    timeout_s=10
    if [ "$t" = estimator ]; then timeout_s=60; fi
    # -max_len: 16 kB, but a .mat (HDF5) seed is some 70 kB, most of it the
    # B-tree nodes libhdf5 allocates whole.
    max_len=16384
    if [ "$t" = gnss_sdr_mat ]; then max_len=131072; fi
    cargo fuzz run -O "$t" "fuzz/corpus/$t" "fuzz/seeds/$t" -- \
        -max_total_time="$seconds" -timeout="$timeout_s" -rss_limit_mb=2048 -max_len="$max_len" \
        -print_final_stats=1 > "fuzz/logs/$t.log" 2>&1 || {
        echo "fuzz: $t FAILED (see fuzz/logs/$t.log and fuzz/artifacts/$t)"
        tail -40 "fuzz/logs/$t.log"
        exit 1
    }
    grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|cov: " "fuzz/logs/$t.log" | tail -3
done
