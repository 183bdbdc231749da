"""Ctrl-C: a real SIGINT sent to a Python process in the middle of a long shadelab call stops
the call within half a second and raises KeyboardInterrupt; the next call runs normally."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

# The child: renders a 1024² sphere, says when the long solve starts, and reports when (on the
# system-wide monotonic clock) KeyboardInterrupt reached Python, then runs a short solve to show
# that the library's stop flag was lowered again.
CHILD = textwrap.dedent(
    """
    import sys, time
    import shadelab
    s = shadelab.render("sphere", shape=1024, light="tilt=30,slant=40")
    print("ready", flush=True)
    started = time.monotonic()
    try:
        shadelab.solve(s["img"], light="tilt=30,slant=40", mask=s["target_mask"],
                       method="jacobi", max_iter=100000)
        print("finished", time.monotonic() - started, flush=True)
    except KeyboardInterrupt:
        print("interrupted", time.monotonic(), flush=True)
    small = shadelab.render("sphere", shape=32, light="front")
    r = shadelab.solve(small["img"], light="front", mask=small["target_mask"])
    print("after", r.converged, flush=True)
    """
)


@pytest.mark.skipif(not hasattr(signal, "SIGINT") or os.name != "posix", reason="POSIX signals")
def test_sigint_stops_a_1024_solve_within_half_a_second():
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "ready"
        # Well inside the solve (100,000 Jacobi sweeps of 1024² take minutes).
        time.sleep(1.0)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
    lines = out.split("\n")
    interrupted = [l for l in lines if l.startswith("interrupted")]
    assert interrupted, f"no KeyboardInterrupt: {out!r} {err!r}"
    latency = float(interrupted[0].split()[1]) - sent
    print(f"KeyboardInterrupt {latency:.3f} s after SIGINT")
    assert 0.0 <= latency <= 0.5, f"KeyboardInterrupt {latency:.3f} s after SIGINT"
    assert "after True" in lines, f"the next call did not run normally: {out!r} {err!r}"
    assert child.returncode == 0, err
