#!/usr/bin/env bash
# The C API for a bare-metal Cortex-M4F (thumbv7em-none-eabihf): builds
# gsens-ffi without std (profile `embedded`: opt-level "s", LTO), links the
# static library with only the calibrator's or the compensator's entry points
# kept (rust-lld --gc-sections), and prints the code (.text) and constant
# (.rodata) bytes each needs. Without the target installed (and no rustup to
# add it) it says so and builds the crate without std for the host instead.
set -euo pipefail
cd "$(dirname "$0")/.."
TARGET=thumbv7em-none-eabihf
if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
  rustup target add "$TARGET" >/dev/null 2>&1 || true
fi
if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
  echo "embedded-size: the $TARGET target is not installed and cannot be added here;"
  echo "building gsens-core and gsens-ffi without std for the host instead (no size report)"
  cargo build -p gsens-core -p gsens-ffi --no-default-features --locked
  exit 0
fi
cargo build -p gsens-ffi --target "$TARGET" --no-default-features --features panic-halt --profile embedded --locked
LIB="${CARGO_TARGET_DIR:-target}/$TARGET/embedded/libgsens_ffi.a"
LLD=$(find "$(rustc --print sysroot)" -name rust-lld -type f | head -1)
ELF=$(mktemp)
trap 'rm -f "$ELF"' EXIT
size_of() {
  local undefined=()
  for s in "$@"; do undefined+=("--undefined=$s"); done
  "$LLD" -flavor gnu --gc-sections -e 0 "${undefined[@]}" "$LIB" -o "$ELF"
  local text ro
  text=$(readelf -S -W "$ELF" | awk '{ for (i = 1; i <= NF; i++) if ($i == ".text") print $(i + 4) }')
  ro=$(readelf -S -W "$ELF" | awk '{ for (i = 1; i <= NF; i++) if ($i == ".rodata") print $(i + 4) }')
  printf "%7d B code, %6d B constants\n" "$((16#${text:-0}))" "$((16#${ro:-0}))"
}
echo "gsens-ffi on $TARGET (profile embedded), bytes kept by the linker:"
printf "  calibrator, all its calls:              "
size_of gsens_calibrator_config_default gsens_calibrator_init gsens_calibrator_feed gsens_calibrator_feed_channels \
  gsens_calibrator_finish gsens_calibrator_estimate gsens_calibrator_drop
printf "  calibrator without the estimate:        "
size_of gsens_calibrator_init gsens_calibrator_feed gsens_calibrator_finish gsens_calibrator_drop
printf "  compensator (init, NCO correction):     "
size_of gsens_compensator_init gsens_compensator_nco_correction_hz
