"""Per-call overhead of the Python module over the Rust library (docs/performance.md).

Times shadelab.render("checkerboard", shape=1024) and shadelab.solve on a 256² sphere from
Python (median of N calls), runs python/examples/overhead.rs for the same library calls in
Rust, and prints both with the difference. Run from python/ with the wheel installed:

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
HERE = pathlib.Path(__file__).resolve().parents[1]


def median_ms(f):
    f()
    times = []
    for _ in range(RUNS):
        t = time.perf_counter()
        f()
        times.append((time.perf_counter() - t) * 1e3)
    return float(np.median(times))


def main():
    light = (0.3, 0.4, 0.866)
    py_render = median_ms(lambda: shadelab.render("checkerboard", shape=1024, ppd=32))
    s = shadelab.render("sphere", shape=256, light=light)
    inside = s["target_mask"] == 1
    py_solve = median_ms(lambda: shadelab.solve(s["img"], light=light, mask=inside))
    env = dict(os.environ, CARGO_TARGET_DIR=str(HERE.parent / "target" / "python"))
    out = subprocess.run(
        ["cargo", "run", "--quiet", "--release", "--example", "overhead", "--", str(RUNS)],
        cwd=HERE, env=env, check=True, capture_output=True, text=True,
    ).stdout
    rust = dict((k, float(v)) for k, v in (line.split() for line in out.splitlines()))
    for name, py, rs in [("render 1024² checkerboard", py_render, rust["render_ms"]),
                         ("solve 256² sphere", py_solve, rust["solve_ms"])]:
        print(f"{name}: Rust {rs:.3f} ms, Python {py:.3f} ms, "
              f"overhead {py - rs:+.3f} ms ({100 * (py - rs) / rs:+.1f} %)")


if __name__ == "__main__":
    main()
