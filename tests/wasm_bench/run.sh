#!/usr/bin/env bash
# Builds the wasm bench (release, wasm32-unknown-unknown) and times it under Node.
#   tests/wasm_bench/run.sh          the web build's settings (wasm-pack.toml's rustflags)
#   tests/wasm_bench/run.sh --both   also without them, to compare
# Uses the active rustc's wasm32 std when it has one; otherwise Debian's rustc-web builds std
# from source (as crate/xtask does; see docs/architecture.md, "The build").
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
# The web build's rustflags, from wasm-pack.toml (one place for them): the full engine's, its
# [toolchain] section's (not the player's, whose own flags come first in the file; until session
# 21 this read those, so the bench ran without simd128). ["-C", "x"] -> -C x.
web_flags=$(awk '/^\[/ { section = $0 } section == "[toolchain]" && /^rustflags *=/' "$root/wasm-pack.toml" | sed -n 's/^rustflags *= *\[\(.*\)\].*/\1/p' | head -1 | sed 's/"//g; s/, */ /g')

build() { # target-dir rustflags
  local dir=$1 flags=$2
  if [ -n "$(rustc --print target-libdir --target wasm32-unknown-unknown 2>/dev/null)" ] \
     && ls "$(rustc --print target-libdir --target wasm32-unknown-unknown)"/libstd-* >/dev/null 2>&1; then
    CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="$flags" cargo build -q --release --target wasm32-unknown-unknown --manifest-path "$here/Cargo.toml" --target-dir "$dir"
  else
    CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="$flags" RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc RUSTC_BOOTSTRAP=1 CARGO_UNSTABLE_BUILD_STD=std,panic_abort \
      CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=wasm-ld-19 \
      /usr/bin/cargo build -q --release --target wasm32-unknown-unknown --manifest-path "$here/Cargo.toml" --target-dir "$dir"
  fi
}

build "$root/target/wasm-bench" "$web_flags"
node "$here/run.mjs" "$root/target/wasm-bench/wasm32-unknown-unknown/release/odori_wasm_bench.wasm" "wasm${web_flags:+ ($web_flags)}"
if [ "${1:-}" = --both ] && [ -n "$web_flags" ]; then
  build "$root/target/wasm-bench-plain" ""
  node "$here/run.mjs" "$root/target/wasm-bench-plain/wasm32-unknown-unknown/release/odori_wasm_bench.wasm" "wasm (no rustflags)"
fi
