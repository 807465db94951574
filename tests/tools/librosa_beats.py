"""librosa's beat tracker on the shared music files, side by side with Odori's results.

Reads Odori's JSON (from `cargo run --release -p odori-tests --example music_beats` with
MUSIC_BEATS_TIMES=1), runs `librosa.beat.beat_track` (librosa defaults: 22050 Hz mono, hop 512)
on the same files, and prints tempo and F-measures (±70 ms, no trimming) for both. The
F-measure is computed here with the same greedy one-to-one matching as Odori's
`music::eval::f_measure`, and cross-checked with `mir_eval.beat.f_measure`.
librosa has no downbeat tracker, so only Odori has a downbeat F-measure.
"""

import argparse
import json
import os
import time

import librosa
import mir_eval
import numpy as np

DRUMS = "beats/drummer1_eval_session_1_funk-groove1_138_beat_4-4.FluidR3GM.flac"
DRUMS_BEATS = "beats/drummer1_eval_session_1_funk-groove1_138_beat_4-4.beats"


def f_measure(est, ref, tol=0.07):
    if len(est) == 0 and len(ref) == 0:
        return 1.0
    if len(est) == 0 or len(ref) == 0:
        return 0.0
    pairs = sorted((abs(e - r), i, j) for i, e in enumerate(est) for j, r in enumerate(ref) if abs(e - r) <= tol)
    used_e, used_r, hits = set(), set(), 0
    for _, i, j in pairs:
        if i not in used_e and j not in used_r:
            used_e.add(i)
            used_r.add(j)
            hits += 1
    if hits == 0:
        return 0.0
    p, r = hits / len(est), hits / len(ref)
    return 2 * p * r / (p + r)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--ours", required=True)
    args = ap.parse_args()
    ours = {e["file"]: e for e in json.load(open(args.ours))}
    ref = np.loadtxt(os.path.join(args.data, DRUMS_BEATS))
    ref_beats, ref_down = ref[:, 0], ref[ref[:, 1] == 1, 0]
    print(f"librosa {librosa.__version__}, mir_eval {mir_eval.__version__}")
    # Warm up numba's JIT so the timings below are librosa's, not the compiler's.
    librosa.beat.beat_track(y=np.random.default_rng(0).standard_normal(22050 * 3).astype(np.float32), sr=22050)
    print(f"{'file':<62} {'ours BPM':>9} {'librosa BPM':>12}")
    rows = []
    for rel, o in ours.items():
        y, sr = librosa.load(os.path.join(args.data, rel))
        t = time.perf_counter()
        tempo, frames = librosa.beat.beat_track(y=y, sr=sr)
        secs = time.perf_counter() - t
        lib_beats = librosa.frames_to_time(frames, sr=sr)
        lib_bpm = float(np.atleast_1d(tempo)[0])
        print(f"{rel:<62} {o.get('bpm', float('nan')):9.2f} {lib_bpm:12.2f}   (beat_track {secs*1000:.0f} ms from PCM; ours {o['analysisSecs']*1000:.1f} ms from the envelope)")
        rows.append((rel, o, lib_beats, lib_bpm))
    print()
    print("agreement between the two trackers where no ground truth exists (F of ours against librosa's beats, +-70 ms):")
    for rel, o, lib_beats, lib_bpm in rows:
        if rel != DRUMS:
            print(f"  {rel:<62} {f_measure(np.array(o.get('beatTimesSecs', [])), lib_beats):.3f}")
    for rel, o, lib_beats, lib_bpm in rows:
        if rel != DRUMS:
            continue
        our_beats = np.array(o["beatTimesSecs"])
        our_down = np.array(o["downbeatTimesSecs"])
        print()
        print(f"drum performance (true 138 BPM, {len(ref_beats)} beats, {len(ref_down)} downbeats), F-measure at +-70 ms:")
        print(f"  {'':<10} {'beat F':>8} {'(mir_eval)':>11} {'downbeat F':>11} {'BPM':>8}")
        print(f"  {'ours':<10} {f_measure(our_beats, ref_beats):8.3f} {mir_eval.beat.f_measure(ref_beats, our_beats, 0.07):11.3f} "
              f"{f_measure(our_down, ref_down):11.3f} {o['bpm']:8.2f}")
        print(f"  {'librosa':<10} {f_measure(lib_beats, ref_beats):8.3f} {mir_eval.beat.f_measure(ref_beats, lib_beats, 0.07):11.3f} "
              f"{'n/a':>11} {lib_bpm:8.2f}")


if __name__ == "__main__":
    main()
