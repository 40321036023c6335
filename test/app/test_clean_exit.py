"""The plots' CSV readers end cleanly: no thread pool is alive when the interpreter exits.

pyarrow's CSV reader parsed on Arrow's CPU thread pool, and a pool still running at
interpreter shutdown aborts the process at random (SIGABRT, "terminate called without an
active exception"), even after plot.py printed its usage error: `plot.py DIR --only
acceleration` on a positions-only run aborted 4 times in 40. python/fekap/stream.py now
parses on the calling thread. Run alone: scripts/test clean_exit."""

from __future__ import annotations

import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from apptest import ROOT, run_fekap

PLOT = ROOT / "scripts" / "plot.py"
OUT: Path = None  # a fresh scratch directory, set by conftest.py

#: Repetitions of the error path: at the old rate of 1 in 10, 50 clean exits in a row
#: would happen by chance with probability 0.9^50 = 0.5 %.
REPEATS = 50


def positions_only_run() -> Path:
    out = OUT / "positions"
    if not (out / "points.csv").is_file():
        run = run_fekap("-q", "-o", str(out), "--compute", "positions", "decks/fourbar.deck")
        assert run.returncode == 0, run.stderr
    return out


def test_plot_usage_error_exits_cleanly_every_time() -> None:
    """plot.py (run by its path, as a user does) asked for accelerations a run did not
    compute: exit 2 and the one-line message, 50 times out of 50, never a SIGABRT."""
    out = positions_only_run()

    def once(_: int) -> subprocess.CompletedProcess:
        return subprocess.run([str(PLOT), str(out), "--only", "acceleration"], capture_output=True,
                              text=True, timeout=120)

    with ThreadPoolExecutor(max_workers=3) as pool:
        results = list(pool.map(once, range(REPEATS)))
    bad = [(r.returncode, r.stderr) for r in results
           if r.returncode != 2 or r.stderr.count("\n") != 1 or "computed no accelerations" not in r.stderr]
    assert not bad, f"{len(bad)} of {REPEATS} runs did not end with exit 2 and one line: {bad[:3]}"


def test_reading_starts_no_cpu_thread_pool() -> None:
    """A fresh interpreter reads a run's points, links and steps through fekap.stream:
    the reading leaves at most one thread (the idle readahead thread of Arrow's I/O pool);
    a parse on the CPU pool would leave one thread per core besides (3 or more here). A
    second thread can be alive for a moment right after the reads (25 runs: 2 of them, gone
    within 0.5 s; the test failed about one run in ten when it counted at once), so the
    count is taken once it settles, within 2 s: the CPU pool's threads stay for the
    process's life."""
    out = positions_only_run()
    code = f"""
import os, sys, time
from pathlib import Path
from fekap import stream as fs
import pyarrow
def threads():
    return len(os.listdir('/proc/self/task'))
before = threads()
out = Path({str(out)!r})
for _ in range(3):
    fs.read_long(out / 'points.csv', 'point', ('x', 'y', 'vx', 'vy', 'ax', 'ay'), ('x', 'y'))
    fs.read_steps(out / 'steps.csv')
deadline = time.monotonic() + 2
while threads() - before > 1 and time.monotonic() < deadline:
    time.sleep(0.05)
print(threads() - before, pyarrow.cpu_count())
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    added, cores = (int(v) for v in done.stdout.split())
    assert added <= 1, f"reading left {added} threads (Arrow's CPU pool has {cores})"
