#!/usr/bin/env bash
# Coverage-guided fuzzing of the core's input boundaries (cargo-fuzz / libFuzzer, nightly):
#   tests/fuzz.sh SECS [TARGET...]   each target for SECS seconds (default: every target)
# `./dev fuzz [SECS]` runs it long (default 600 s per target); `./dev test` runs it short.
# The committed seeds (fuzz/corpus/<target>/) are read, never written: what libFuzzer finds is
# kept in fuzz/corpus-work/<target>/ (not committed; it carries over between runs). A crash is
# written to fuzz/artifacts/<target>/ and fails the run: once fixed, copy the input into
# fuzz/corpus/<target>/ so `cargo test --test fuzz_corpus` keeps it fixed. Without the nightly
# toolchain or cargo-fuzz it says so and exits 0: `cargo test` (tests/native/fuzz_corpus.rs)
# still replays the whole corpus through the same entry points on stable.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
secs=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(import_bvh import_gltf music_envelope text_parse project_open import_vmd import_pmx import_files)

if [ "$secs" = 0 ]; then
  echo "fuzz: skipped (0 s asked); the corpus is replayed by 'cargo test --test fuzz_corpus'."
  exit 0
fi
if ! rustup toolchain list 2>/dev/null | grep -q '^nightly' || ! command -v cargo-fuzz >/dev/null; then
  echo "fuzz: skipped (needs rustup's nightly toolchain and cargo-fuzz; ./dev setup installs cargo-fuzz when nightly is there). The corpus is still replayed on stable by 'cargo test --test fuzz_corpus'."
  exit 0
fi
# Safe Rust: no sanitizer (more executions per second); debug assertions on, so an arithmetic
# overflow is a finding too. -rss_limit_mb: an input that makes the engine allocate past 2 GB
# (what a browser tab can give) is a crash. -max_len 64 KiB: big enough for rigs (see below).
# -timeout 10 s per input: a hang is a crash.
# Shorter inputs for the song analysis: its cost is legitimate and linear (about 1.3 µs a
# frame: 5 ms for 4,000 frames), so 64 KiB envelopes (minutes of song) held the target to a few
# hundred runs/s; 4 KiB (2,048 values) still spans 10 s to 100 s of song at the hops the target
# allows. (The text parser's slowness on long text was a defect, fixed in the parser: it
# scanned the whole Japanese lexicon at every character.)
max_len_for() {
  case "$1" in
    music_envelope) echo 4096 ;;
    project_open) echo 131072 ;;
    *) echo 65536 ;;
  esac
}
# The .odori reader is also seeded with the reviewed golden project (tests/golden/, 103 KB: read
# in place rather than copied into the corpus, hence its 128 KiB input length).
extra_seeds_for() {
  case "$1" in
    project_open) echo tests/golden ;;
  esac
}
# A short run (`./dev test`) builds every target once, first, with the dev profile (opt-level 1,
# fuzz/Cargo.toml): the release build's CPU time is what a short run cannot afford. A build
# error is reported as one, not as a crash.
profile=()
if [ "$secs" -lt 60 ]; then
  profile=(--dev)
  build_log=$(mktemp)
  build_started=$SECONDS
  if ! nice -n 15 cargo +nightly fuzz build -s none -a "${profile[@]}" >"$build_log" 2>&1; then
    tail -40 "$build_log"
    echo "fuzz: the fuzz targets did not build (above)"
    exit 1
  fi
  rm -f "$build_log"
  echo "fuzz: built ${#targets[@]} targets (dev profile) in $((SECONDS - build_started)) s"
fi
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus-work/$t" "fuzz/artifacts/$t"
  echo "== fuzz $t for ${secs}s"
  log=$(mktemp)
  if ! nice -n 15 cargo +nightly fuzz run -s none -a "${profile[@]}" "$t" "fuzz/corpus-work/$t" "fuzz/corpus/$t" $(extra_seeds_for "$t") -- \
      -max_total_time="$secs" -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len="$(max_len_for "$t")" -timeout=10 \
      -artifact_prefix="fuzz/artifacts/$t/" -print_final_stats=1 >"$log" 2>&1; then
    tail -40 "$log"
    echo "fuzz: $t FAILED (crash input in fuzz/artifacts/$t/)"
    exit 1
  fi
  grep -E '^stat::number_of_executed_units|^stat::peak_rss_mb|Done [0-9]+ runs' "$log" | sed "s/^/  $t: /"
  rm -f "$log"
done
