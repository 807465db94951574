#!/usr/bin/env bash
# Browser-vs-native check of the RMS envelope and bars (see check.mjs). Usage:
#   tests/tools/webaudio_check/run.sh [data-relative file ...]   (default: the drum performance)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
data="${ODORI_DATA:-$root/../shared/data}"
(cd "$root" && cargo build -q --release -p odori-tests --example music_envelope)
files=("$@")
[ ${#files[@]} -gt 0 ] || files=("beats/drummer1_eval_session_1_funk-groove1_138_beat_4-4.FluidR3GM.flac")
for f in "${files[@]}"; do
  node "$here/check.mjs" "$data" "$f" "$root/target/release/examples/music_envelope"
done
