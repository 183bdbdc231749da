"""Ctrl-C: a real SIGINT sent to a Python process in the middle of a long shadelab call stops
the call within half a second and raises KeyboardInterrupt; the next call runs normally."""

import os
import queue
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

# The child: renders a 1024² sphere, says when the long solve starts, and reports when (on the
# system-wide monotonic clock) KeyboardInterrupt reached Python, then runs a short solve to show
# that the library's stop flag was lowered again.
CHILD = textwrap.dedent(
    """
    import signal, sys, time
    import shadelab
    # Python's own Ctrl-C handler, whatever the child inherited: a job started in the
    # background by a non-interactive shell starts with SIGINT ignored, and Python then
    # installs no handler (a CI run launched with `&` hung here).
    signal.signal(signal.SIGINT, signal.default_int_handler)
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


# The child for the Levenberg–Marquardt methods: on each "go" line it starts one 1024² solve
# (saying so) and reports how it ended; a SIGINT that arrives between solves is ignored.
PHASES_CHILD = textwrap.dedent(
    """
    import signal, sys, time
    import shadelab
    signal.signal(signal.SIGINT, signal.default_int_handler)  # as in CHILD
    method = sys.argv[1]
    s = shadelab.render("sphere", shape=1024, light="tilt=30,slant=40")
    print("ready", flush=True)
    while True:
        try:
            line = sys.stdin.readline()
        except KeyboardInterrupt:
            continue
        if line.strip() != "go":
            break
        try:
            print("started", time.monotonic(), flush=True)
            shadelab.solve(s["img"], light="tilt=30,slant=40", mask=s["target_mask"],
                           method=method, tol=1e-12, max_iter=1000000)
            print("finished", time.monotonic(), flush=True)
        except KeyboardInterrupt:
            print("interrupted", time.monotonic(), flush=True)
    """
)


@pytest.mark.skipif(not hasattr(signal, "SIGINT") or os.name != "posix", reason="POSIX signals")
@pytest.mark.parametrize("method", ["integrable-lm", "nested-lm"])
def test_sigint_stops_every_phase_of_a_1024_lm_solve_within_half_a_second(method):
    # Signalled 0.5, 1, 2 and 3 s into the solve: the warm start, the depth's Poisson solve,
    # the first step's planning of the aggregation multigrid, its conjugate gradients and
    # the later steps all look for the stop.
    child = subprocess.Popen(
        [sys.executable, "-c", PHASES_CHILD, method],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    latencies = []
    # The child's lines, read on a thread so that a child that never answers fails the test
    # (after a resent SIGINT says whether the first was lost or ignored) instead of hanging it.
    lines = queue.Queue()
    threading.Thread(target=lambda: [lines.put(l) for l in child.stdout], daemon=True).start()

    def answer(timeout):
        try:
            return lines.get(timeout=timeout).split()
        except queue.Empty:
            return None

    def interrupted_after(delay):
        child.stdin.write("go\n")
        child.stdin.flush()
        kind, started = answer(60)
        assert kind == "started"
        time.sleep(max(0.0, float(started) + delay - time.monotonic()))
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        reply = answer(10)
        resent = 0
        while reply is None and resent < 3:
            # No answer in 10 s: a lost signal is answered by the next one; an ignored stop
            # (the call saw the signal but its work does not stop) by none.
            child.send_signal(signal.SIGINT)
            resent += 1
            reply = answer(10)
        assert reply is not None, f"{method}: no answer to {resent + 1} SIGINTs {delay} s in"
        kind, at = reply
        assert kind == "interrupted", f"{method} ended by itself {delay} s in ({float(at) - float(started):.2f} s)"
        if resent:
            print(f"{method}: {delay} s in, answered only after {resent} more SIGINT(s)")
        return float(at) - sent

    try:
        assert answer(120) == ["ready"]
        for delay in (0.5, 1.0, 2.0, 3.0):
            # The fastest of up to three solves: the bound is on how often the solve looks for
            # the stop, and a suite run beside other work can lose the cores for a moment; a
            # phase that looks too seldom is slow every time.
            best = interrupted_after(delay)
            for _ in range(2):
                if best <= 0.5:
                    break
                best = min(best, interrupted_after(delay))
            latencies.append((delay, best))
        child.stdin.write("end\n")
        child.stdin.close()
        child.wait(timeout=60)
        err = child.stderr.read()
    finally:
        if child.poll() is None:
            child.kill()
    print(method, ", ".join(f"{d} s in: {l:.3f} s" for d, l in latencies))
    for delay, latency in latencies:
        assert 0.0 <= latency <= 0.5, f"{method}: KeyboardInterrupt {latency:.3f} s after a SIGINT {delay} s in"
    assert child.returncode == 0, err
