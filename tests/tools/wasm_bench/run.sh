#!/usr/bin/env bash
# Builds the wasm bench (release, wasm32-unknown-unknown) and times it under Node.
# Needs: rustup target add wasm32-unknown-unknown; node >= 18.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
cargo build -q --release --target wasm32-unknown-unknown --manifest-path "$here/Cargo.toml" --target-dir "$root/target/wasm-bench"
node "$here/run.mjs" "$root/target/wasm-bench/wasm32-unknown-unknown/release/odori_music_wasm_bench.wasm"
