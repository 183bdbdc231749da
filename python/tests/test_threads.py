"""The GIL is released while the library works; threads get real parallelism."""

import threading
import time

import numpy as np

import shadelab
from conftest import LIGHT


def _slow_solve(img, inside):
    # Jacobi sweeps: long enough (≈ 0.2–2 s) to watch another thread run meanwhile.
    return shadelab.solve(img, light=LIGHT, mask=inside, method="jacobi", max_iter=4000, tol=1e-12)


def test_another_thread_runs_while_a_solve_runs(sphere):
    """While one thread is inside the solve, the main thread keeps executing Python. With
    the GIL held, the main thread could run only in the first switch interval (5 ms)."""
    inside = sphere["target_mask"] == 1
    span = {}

    def worker():
        span["start"] = time.perf_counter()
        _slow_solve(sphere["img"], inside)
        span["end"] = time.perf_counter()

    t = threading.Thread(target=worker)
    stamps = []
    t.start()
    while t.is_alive():
        stamps.append(time.perf_counter())
    t.join()
    start, end = span["start"], span["end"]
    assert end - start > 0.05, "the solve was too short to tell"
    middle = [s for s in stamps if start + 0.25 * (end - start) < s < start + 0.75 * (end - start)]
    assert len(middle) > 100, f"the main thread ran {len(middle)} times in the middle of the solve"


def test_concurrent_solves_give_the_serial_results(sphere):
    inside = sphere["target_mask"] == 1
    serial = shadelab.solve(sphere["img"], light=LIGHT, mask=inside).normals
    results = [None] * 3

    def worker(i):
        results[i] = shadelab.solve(sphere["img"], light=LIGHT, mask=inside).normals

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r, serial)
