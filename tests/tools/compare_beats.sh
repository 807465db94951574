#!/usr/bin/env bash
# Side-by-side beat tracking report (issue 4): Odori's analysis and librosa's `beat_track` on
# the same files from ../shared/data, scored with the same F-measure (±70 ms) and cross-checked
# with mir_eval. A report tool, not part of `cargo test`.
#
# Usage: tests/tools/compare_beats.sh        (from anywhere; needs python3, cargo, network for pip)
# Env:   ODORI_DATA  data directory (default ../shared/data next to the repository)
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
data="${ODORI_DATA:-$root/../shared/data}"
venv="$root/target/librosa-venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --disable-pip-version-check librosa soundfile mir_eval
mkdir -p "$root/tests/artifacts"
ours="$root/tests/artifacts/ours_beats.json"
(cd "$root" && ODORI_DATA="$data" MUSIC_BEATS_TIMES=1 cargo run -q --release -p odori-tests --example music_beats) > "$ours"
"$venv/bin/python" "$root/tests/tools/librosa_beats.py" --data "$data" --ours "$ours"
