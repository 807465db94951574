#!/usr/bin/env python3
"""Peer comparison for the search benchmark (issue 3): time dtaidistance's C subsequence
alignment on the same arrays the Rust bench searched.

Run `cargo bench -p odori-tests --bench search` first: it writes target/search-bench/
{query.f32, library.f32, shape.json, timings.json}. Then:

    python3 tests/tools/peer_dtaidistance.py

The script makes a venv under target/peer-venv (once), installs dtaidistance and numpy from
PyPI into it, and re-runs itself there. Honest caveats, printed with the figures: dtaidistance
computes DTW with its own definitions (inner distance = Euclidean over the whole 63-value frame,
not a sum of per-joint distances; unconstrained 1/1/1 steps with a penalty, not the slope-
constrained P = 1 steps; score divided by the query length), so it does the same amount of DP work on the same arrays but does not
return the same matches. It also keeps the whole (query+1) x (library+1) matrix in memory.
"""
import json
import os
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BENCH = os.path.join(ROOT, "target", "search-bench")
VENV = os.path.join(ROOT, "target", "peer-venv")
VPY = os.path.join(VENV, "bin", "python")


def ensure_venv():
    if os.path.abspath(sys.prefix) == os.path.abspath(VENV):
        return
    if not os.path.exists(VPY):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([VPY, "-m", "pip", "install", "-q", "dtaidistance", "numpy"])
    os.execv(VPY, [VPY, os.path.abspath(__file__)] + sys.argv[1:])


def main():
    ensure_venv()
    import numpy as np
    import dtaidistance
    from dtaidistance import dtw
    from dtaidistance.subsequence.subsequencealignment import subsequence_alignment

    if not os.path.exists(os.path.join(BENCH, "shape.json")):
        sys.exit("run `cargo bench -p odori-tests --bench search` first (it exports the arrays)")
    shape = json.load(open(os.path.join(BENCH, "shape.json")))
    width = shape["floatsPerFrame"]
    lib = np.fromfile(os.path.join(BENCH, "library.f32"), dtype="<f4").reshape(-1, width).astype(np.float64)
    assert lib.shape[0] == shape["libraryFrames"], lib.shape
    print(f"dtaidistance {dtaidistance.__version__}, C library available: {dtw.try_import_c(verbose=False)}")
    tpath = os.path.join(BENCH, "timings.json")
    cases = json.load(open(tpath))["cases"] if os.path.exists(tpath) else []
    for tag, label in [("in", "query whose source is in the library"), ("novel", "novel query (source held out)")]:
        qpath = os.path.join(BENCH, f"query_{tag}.f32")
        if not os.path.exists(qpath):
            continue
        q = np.fromfile(qpath, dtype="<f4").reshape(-1, width).astype(np.float64)
        assert q.shape[0] == shape["queryFrames"], q.shape
        print(f"{label}: query {q.shape[0]} frames x {width}, library {lib.shape[0]} frames x {width}")
        for k in (1, 10):
            times = []
            cpus = []
            best = None
            for _ in range(3):
                t0 = time.perf_counter()
                c0 = time.process_time()
                sa = subsequence_alignment(q, lib, use_c=True)
                sa.align()
                matches = list(sa.kbest_matches(k=k, minlength=q.shape[0] // 2, maxlength=2 * q.shape[0]))
                times.append(time.perf_counter() - t0)
                cpus.append(time.process_time() - c0)
                best = matches[0] if matches else None
                del sa
            times.sort()
            ms = times[len(times) // 2] * 1e3
            cpus.sort()
            cpu = cpus[len(cpus) // 2] * 1e3
            # CPU time as well as wall: the machine is shared, and CPU time does not depend on its load.
            line = f"  dtaidistance C subsequence alignment, top {k}: {ms:.1f} ms wall, CPU {cpu:.1f} ms (median of 3)"
            if best is not None:
                line += f"; its best match: frames {best.segment[0]}..={best.segment[1]}"
            print(line)
            for case in cases:
                if case.get("query") == tag and case.get("k") == k:
                    line = f"    vs Odori '{case['name']}': fast {case['fastMs']:.2f} ms -> dtaidistance / Odori fast = {ms / case['fastMs']:.2f}x"
                    if case.get("plainMs", 0) > 0:
                        line += f"; Odori plain DP {case['plainMs']:.1f} ms, dtaidistance / Odori plain = {ms / case['plainMs']:.2f}x"
                    if case.get("fastCpuMs", 0) > 0:
                        line += f"; CPU: Odori fast {case['fastCpuMs']:.2f} ms, dtaidistance / Odori fast = {cpu / case['fastCpuMs']:.2f}x"
                    if case.get("threadsMs", 0) > 0:
                        line += f"; Odori fast on {case['threads']} threads {case['threadsMs']:.2f} ms wall, dtaidistance / that = {ms / case['threadsMs']:.2f}x"
                    print(line)
    print("caveat: different distance and step weights (see the script's docstring); same arrays, same DP size.")


if __name__ == "__main__":
    main()
