#!/usr/bin/env bash
# The C API's header, crates/gsens-ffi/include/gsens.h, is what cbindgen makes
# of the crate now: this regenerates it and fails when the committed one
# differs (`--update` rewrites it). cbindgen is installed at the version the
# header was made with when it is missing, so that the tests need not build it.
set -euo pipefail
cd "$(dirname "$0")/../crates/gsens-ffi"
version=0.29.4
if ! command -v cbindgen > /dev/null || [ "$(cbindgen --version)" != "cbindgen $version" ]; then
    # Unoptimized: it runs once on one small crate, and builds in half the time.
    cargo install cbindgen --version "$version" --locked --debug
fi
generated=$(mktemp)
trap 'rm -f "$generated"' EXIT
cbindgen --quiet --config cbindgen.toml --crate gsens-ffi --output "$generated" .
if [ "${1:-}" = "--update" ]; then
    cp "$generated" include/gsens.h
elif ! cmp -s "$generated" include/gsens.h; then
    diff -u include/gsens.h "$generated" | head -40 >&2 || true
    echo "crates/gsens-ffi/include/gsens.h is not current: bash scripts/check-header.sh --update rewrites it" >&2
    exit 1
fi
