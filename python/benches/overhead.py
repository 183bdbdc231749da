"""Per-call overhead of the Python module over the Rust library (docs/performance.md).

Times shadelab.render("checkerboard", shape=1024) and shadelab.solve on a 256² sphere from
Python (N calls each, three rounds), runs python/examples/overhead.rs for the same library
calls in Rust between the rounds, and prints the minimum and median of both with the
difference. Run from python/ with the wheel installed:

    python benches/overhead.py [N]
"""

import os
import pathlib
import subprocess
import sys
import time

import numpy as np

import shadelab

RUNS = int(sys.argv[1]) if len(sys.argv) > 1 else 21
ROUNDS = 3
HERE = pathlib.Path(__file__).resolve().parents[1]


def times_ms(f):
    f()
    times = []
    for _ in range(RUNS):
        t = time.perf_counter()
        f()
        times.append((time.perf_counter() - t) * 1e3)
    return times


def rust_times():
    env = dict(os.environ, CARGO_TARGET_DIR=str(HERE.parent / "target" / "python"))
    out = subprocess.run(
        ["cargo", "run", "--quiet", "--release", "--example", "overhead", "--", str(RUNS)],
        cwd=HERE, env=env, check=True, capture_output=True, text=True,
    ).stdout
    return {k: [float(v) for v in vs.split(",")] for k, vs in (l.split() for l in out.splitlines())}


def main():
    light = (0.3, 0.4, 0.866)
    s = shadelab.render("sphere", shape=256, light=light)
    inside = s["target_mask"] == 1
    py = {"render_ms": [], "solve_ms": []}
    rs = {"render_ms": [], "solve_ms": []}
    for _ in range(ROUNDS):  # alternate, so that a busy spell of the machine hits both
        py["render_ms"] += times_ms(lambda: shadelab.render("checkerboard", shape=1024, ppd=32))
        py["solve_ms"] += times_ms(lambda: shadelab.solve(s["img"], light=light, mask=inside))
        for k, v in rust_times().items():
            rs[k] += v
    # In one process: the whole Python call against the compiled module's call alone (the
    # library's work and the arrays' handover), i.e. what the pure-Python layer adds.
    raw = times_ms(lambda: shadelab._shadelab.render("checkerboard", "{}", None, 32.0,
                                                     (1024, 1024), 0, False, None, None,
                                                     "unit", None, None, None))
    full = times_ms(lambda: shadelab.render("checkerboard", shape=1024, ppd=32))
    tiny = times_ms(lambda: shadelab.render("checkerboard", shape=8, ppd=8))
    print(f"render 1024², Python layer alone: {1e3 * (np.min(full) - np.min(raw)):+.1f} µs (min), "
          f"{1e3 * (np.median(full) - np.median(raw)):+.1f} µs (median); "
          f"a whole 8×8 render from Python: {1e3 * np.min(tiny):.1f} µs")
    for key, name in [("render_ms", "render 1024² checkerboard"), ("solve_ms", "solve 256² sphere")]:
        for stat in (np.min, np.median):
            p, r = float(stat(py[key])), float(stat(rs[key]))
            print(f"{name} ({stat.__name__}): Rust {r:.3f} ms, Python {p:.3f} ms, "
                  f"overhead {p - r:+.3f} ms ({100 * (p - r) / r:+.1f} %)")


if __name__ == "__main__":
    main()
