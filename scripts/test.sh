#!/usr/bin/env bash
# The repository's test command: the Rust workspace's tests, then the Python
# module's. Builds the gsens wheel (maturin) into a virtual environment under
# the cargo target directory (made here with what it needs from PyPI), installs it and runs
# python/tests with pytest against the `gsens` binary cargo test built.
#
#   scripts/test.sh              all tests
#   GSENS_SKIP_PYTHON=1 scripts/test.sh   the Rust tests only
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo test --workspace"
cargo test --workspace --locked

if [ "${GSENS_SKIP_PYTHON:-0}" = 1 ]; then
  exit 0
fi

# Where cargo puts its builds (and the binary the tests compare with).
target_dir=${CARGO_TARGET_DIR:-$PWD/target}
python=${PYTHON:-python3}
venv=$target_dir/py-venv
if [ ! -x "$venv/bin/python" ]; then
  echo "== a virtual environment for the Python tests ($venv)"
  if ! "$python" -m venv "$venv" 2>/dev/null; then
    # Debian's python3 lacks the venv module until python3-venv is installed.
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
      apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv python3-pip >/dev/null
      rm -rf "$venv" && "$python" -m venv "$venv"
    else
      echo "$python cannot make a virtual environment: install python3-venv" >&2
      exit 1
    fi
  fi
fi
"$venv/bin/python" -m pip install -q --upgrade pip
"$venv/bin/python" -m pip install -q "maturin>=1.16,<2" "numpy>=1.21" scipy pandas pytest matplotlib "mypy>=1.20,<2"

echo "== the wheel (maturin build, dev profile: optimized like the tests)"
rm -rf "$target_dir/wheels"
# `cargo test --workspace` built the libraries with the features the whole
# workspace unifies (the CLI's clap derives); asking for the same ones here
# lets maturin reuse those builds instead of compiling them a second time.
# They add derives the module does not call and change no behaviour.
"$venv/bin/maturin" build --profile dev --locked --interpreter "$venv/bin/python" --out "$target_dir/wheels" \
  --features gsens-inputs/clap,gsens-sim/clap,gsens-core/default
"$venv/bin/python" -m pip install -q --force-reinstall --no-deps "$target_dir"/wheels/gsens-*.whl

# pytest keeps the tmp_path folders of its last runs under the temporary
# directory; here they go to a folder of this run's own, removed on exit.
pytest_tmp=$(mktemp -d "${TMPDIR:-/tmp}/gsens-pytest-XXXXXX")
trap 'rm -rf "$pytest_tmp"' EXIT

echo "== the type stubs against the module (mypy's stubtest, no cache written)"
(cd "$pytest_tmp" && MYPY_CACHE_DIR=/dev/null "$venv/bin/python" -m mypy.stubtest gsens._gsens)

echo "== pytest python/tests"
# Run from outside the source tree so that `import gsens` is the installed wheel.
GSENS_BIN="$target_dir/debug/gsens" "$venv/bin/python" -m pytest -q "$PWD/python/tests" --rootdir "$PWD/python" \
  -p no:cacheprovider --basetemp "$pytest_tmp/basetemp"
