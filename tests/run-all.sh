#!/usr/bin/env bash
# Every test of the project, in order: the core's dependency check, native Rust tests (unit,
# integration, real data), the npm package in Node, and the app in headless Chromium on both
# graphics back ends. Run through `./dev test`, which installs and builds first.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
# Each step says how long the one before it took, and the end gives the total (the test run's
# budget is 20 minutes on this machine kind).
started=$SECONDS
last=
step() {
  [ -z "$last" ] || printf '   (%d s)\n' $((SECONDS - last))
  last=$SECONDS
  printf '\n\033[1m== %s\033[0m\n' "$*"
}
trap 'rc=$?; [ $rc -ne 0 ] || printf "   (%d s)\n\ntests: all passed in %d min %d s\n" $((SECONDS - last)) $(((SECONDS - started) / 60)) $(((SECONDS - started) % 60))' EXIT

if [ ! -d ../shared/data ]; then
  echo "tests: ../shared/data is missing. The real-data tests need the shared data beside the repository (../shared/data)." >&2
  exit 1
fi

step "core dependency tree has no web crate"
cargo run -q -p xtask -- check-core-deps

step "native tests (cargo test: the core, its real-data integration tests, the build tool)"
cargo test -q

step "short fuzz run (${ODORI_FUZZ_SECS:-10} s per target; ./dev fuzz runs long)"
bash tests/fuzz.sh "${ODORI_FUZZ_SECS:-10}"

step "wasm package in Node and the app in headless Chromium (WebGL2 and WebGPU)"
cargo build -q -p xtask
node --test --test-reporter=spec tests/node/ tests/browser/
