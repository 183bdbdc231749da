#!/usr/bin/env python3
"""Times the test suite from a warm build and writes the tables of docs/testing.md.

    cargo build --release --all-targets
    python3 benches/time_tests.py            # per binary, per module, the 20 slowest tests
    python3 benches/time_tests.py --whole    # and the README's `cargo test --release`, timed

Every test binary that `cargo test --release` runs is run here on its own, as cargo runs it
(from the repository root, cargo's default thread count), with libtest's `--report-time`
(an unstable flag, allowed by RUSTC_BOOTSTRAP=1 in the test process only: the build is not
touched). The doctests are timed as `cargo test --release --doc` (their compilation is most
of their time). The tables between the markers of docs/testing.md are replaced, the rest of
the page is kept, and docs/test-names.txt gets every test's name, one per line, so that a
change that drops a test shows in its diff.
"""

import json
import os
import re
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "testing.md"
NAMES = ROOT / "docs" / "test-names.txt"
BEGIN = "<!-- BEGIN: written by benches/time_tests.py -->"
END = "<!-- END: written by benches/time_tests.py -->"


def executables():
    """(kind, name, path) of every test executable of `cargo test --release`, built if needed."""
    out = subprocess.run(
        ["cargo", "test", "--release", "--no-run", "--message-format=json"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    found = []
    for line in out.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("reason") != "compiler-artifact" or not msg.get("executable"):
            continue
        # Only what `cargo test` runs: test harnesses, and the examples marked `test = true`
        # (built as tests without a harness); the other examples are only compiled.
        if not msg.get("profile", {}).get("test"):
            continue
        kind = msg["target"]["kind"][0]
        found.append((kind, msg["target"]["name"], msg["executable"]))
    return found


def run_harness(path):
    """Runs one libtest binary; returns (wall seconds, {test name: seconds})."""
    env = dict(os.environ, RUSTC_BOOTSTRAP="1")
    started = time.monotonic()
    proc = subprocess.run(
        [path, "-Z", "unstable-options", "--format", "json", "--report-time"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    wall = time.monotonic() - started
    times, failed = {}, []
    for line in proc.stdout.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("type") == "test" and msg.get("event") in ("ok", "failed", "ignored"):
            times[msg["name"]] = msg.get("exec_time", 0.0)
            if msg["event"] == "failed":
                failed.append(msg["name"])
    if proc.returncode != 0:
        sys.exit(f"{path} failed ({', '.join(failed) or proc.stderr[-2000:]})")
    return wall, times


def timed(cmd):
    started = time.monotonic()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    return time.monotonic() - started, proc.stdout


def main():
    whole = "--whole" in sys.argv[1:]
    rows, tests, names = [], [], []
    for kind, name, path in executables():
        if kind == "example":
            wall, _ = timed([path])
            rows.append((f"example `{name}`", 1, wall))
            names.append(f"example {name}")
            continue
        wall, times = run_harness(path)
        label = "unit tests (`src/`)" if kind == "lib" else f"`tests/{name}.rs` and its modules"
        rows.append((label, len(times), wall))
        prefix = "lib" if kind == "lib" else name
        tests += [(t, f"{prefix} {n}") for n, t in times.items()]
        names += [f"{prefix} {n}" for n in times]
    _, out = timed(["cargo", "test", "--release", "--doc", "--", "--list"])
    doctests = [l[: -len(": test")] for l in out.splitlines() if l.endswith(": test")]
    wall, _ = timed(["cargo", "test", "--release", "--doc"])
    rows.append(("doctests (compiled and run)", len(doctests), wall))
    names += [f"doc {n}" for n in doctests]

    modules = defaultdict(lambda: [0, 0.0])
    for t, n in tests:
        binary, test = n.split(" ", 1)
        key = f"{binary} {test.split('::')[0]}"
        modules[key][0] += 1
        modules[key][1] += t

    lines = [BEGIN, ""]
    lines.append(
        f"Measured {time.strftime('%Y-%m-%d')} by `python3 benches/time_tests.py"
        f"{' --whole' if whole else ''}` on {os.cpu_count()} cores, after "
        "`cargo build --release --all-targets`."
    )
    lines.append("")
    if whole:
        total, _ = timed(["cargo", "test", "--release"])
        lines += [f"**`cargo test --release`, the whole command: {total:.0f} s.**", ""]
    lines += ["| binary | tests | wall |", "|---|---:|---:|"]
    lines += [f"| {label} | {n} | {wall:.1f} s |" for label, n, wall in rows]
    lines += [
        f"| **all** | {sum(r[1] for r in rows)} | {sum(r[2] for r in rows):.1f} s |",
        "",
        "Per module (the sum of its tests' own times; tests run two at a time, so the sum",
        "is more than the binary's wall time):",
        "",
        "| module | tests | time |",
        "|---|---:|---:|",
    ]
    for key, (n, t) in sorted(modules.items(), key=lambda kv: -kv[1][1]):
        lines.append(f"| {key} | {n} | {t:.1f} s |")
    lines += ["", "The 20 slowest tests:", "", "| test | time |", "|---|---:|"]
    for t, n in sorted(tests, reverse=True)[:20]:
        lines.append(f"| `{n}` | {t:.1f} s |")
    lines += ["", END]

    text = DOC.read_text() if DOC.exists() else f"# Testing\n\n{BEGIN}\n{END}\n"
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
    if not pattern.search(text):
        sys.exit(f"{DOC} has no {BEGIN} ... {END} markers")
    DOC.write_text(pattern.sub(lambda _: "\n".join(lines), text))
    NAMES.write_text("".join(f"{n}\n" for n in sorted(names)))
    print("\n".join(lines[2:-2]))
    print(f"\nwrote {DOC.relative_to(ROOT)} and {NAMES.relative_to(ROOT)} ({len(names)} tests)")


if __name__ == "__main__":
    main()
