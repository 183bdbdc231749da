"""Times stimupy on the stimuli that benches/stimuli.rs times in shadelab (1024x1024 each),
and checks that the pictures agree with shadelab's.

    pip install stimupy
    python benches/stimupy_compare.py [path/to/shadelab]

Prints the median of repeated runs in milliseconds. With a shadelab binary it also renders
the same stimuli to .npy and compares them pixel for pixel.
"""
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from stimupy.components import shapes
from stimupy.stimuli import checkerboards

CASES = {
    "checkerboard": (
        lambda: checkerboards.checkerboard(visual_size=32, ppd=32, check_visual_size=1),
        ["checkerboard", "--visual-size", "32", "--ppd", "32", "--set", "check=1"],
    ),
    "disc": (
        lambda: shapes.disc(visual_size=16, ppd=64, radius=4),
        ["disc", "--visual-size", "16", "--ppd", "64", "--set", "radius=4"],
    ),
}


def median_ms(fn, repeats=15):
    fn()  # warm-up: imports, caches
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t) * 1000)
    return statistics.median(times)


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else None
    for name, (fn, args) in CASES.items():
        print(f"stimupy {name} 1024x1024: {median_ms(fn):.1f} ms (median)")
        if binary:
            with tempfile.TemporaryDirectory() as d:
                out = os.path.join(d, name + ".npy")
                subprocess.run([binary, "--quiet", "render", *args, "--out", out], check=True)
                ours = np.load(out)
                theirs = fn()["img"]
                differ = int((ours != theirs).sum())
                print(f"  pixels that differ from shadelab's: {differ} of {ours.size}")


if __name__ == "__main__":
    main()
