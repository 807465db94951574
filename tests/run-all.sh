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

# One test binary per core, longest first (cargo test runs them one after another, and many hold
# a single long real-data test): crate/xtask/src/native_tests.rs.
step "native tests (the core, its real-data integration tests, the build tool; one binary per core)"
cargo run -q -p xtask -- test-native

# The Node and browser tests run two files at a time (each file its own Chromium; much of their
# time is spent waiting on the page), and the short fuzz run goes beside them at low priority
# (tests/fuzz.sh runs libFuzzer under nice), taking the cores they leave idle. Its report is
# printed after them.
step "wasm package in Node and the app in headless Chromium (WebGL2 and WebGPU), two files at a time; beside them the short fuzz run (${ODORI_FUZZ_SECS:-10} s per target; ./dev fuzz runs long)"
cargo build -q -p xtask
fuzz_log=$(mktemp)
( fuzz_started=$SECONDS; rc=0; bash tests/fuzz.sh "${ODORI_FUZZ_SECS:-10}" || rc=$?; echo "fuzz: took $((SECONDS - fuzz_started)) s beside the browser tests"; exit $rc ) >"$fuzz_log" 2>&1 &
fuzz=$!
trap 'kill $fuzz 2>/dev/null || true' INT TERM
node_rc=0
node --test --test-concurrency=2 --test-reporter=spec tests/node/ tests/browser/ || node_rc=$?

step "short fuzz run (ran beside the browser tests; this is the wait for it to end)"
fuzz_rc=0
wait $fuzz || fuzz_rc=$?
cat "$fuzz_log"
rm -f "$fuzz_log"
[ $node_rc -eq 0 ] || { echo "tests: the Node or browser tests failed (above)"; exit $node_rc; }
[ $fuzz_rc -eq 0 ] || { echo "tests: the fuzz run failed (above)"; exit $fuzz_rc; }
