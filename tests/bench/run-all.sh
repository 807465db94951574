#!/usr/bin/env bash
# Every benchmark: each prints its figures (and a ratio against a baseline measured in the
# same run). Run through `./dev bench`.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo bench -p odori-tests
# The core in wasm under Node (song analysis, choreography), built with the web build's flags.
bash tests/wasm_bench/run.sh
# The search in wasm in headless Chromium (needs pkg/, which ./dev bench builds).
cargo build -q -p xtask
node tests/bench/search-browser.mjs
# Drawing the playing demo in software (no GPU): Chromium's CPU, cap lifted vs capped.
node tests/bench/draw-budget.mjs
# Ten hours of motion indexed, stored in IndexedDB and reopened (issue 16; about 3 GB of memory).
node tests/bench/search-index-10h.mjs
# Embedding (issue 12): player and full bundle sizes and time to the first pose, beside
# <model-viewer> in the same run.
node tests/bench/embed.mjs 3
# MMD import in wasm (issue 28): WAVEFILE with miku_v2 and alone, Gene; beside `--bench mmd_import`.
node tests/bench/mmd-wasm.mjs
