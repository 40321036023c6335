#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""The cost of FEKAP's pictures against the number of steps: a benchmark script, not a test.

    studies/bench/bench_output.py [--plot-steps N ...] [--vtk-steps N ...]

Plotting: Example 1 (decks/fourbar.deck, full kinematics, B and C tracked) run with dt = 1/N for
each N of --plot-steps (default 1e4 1e5 1e6), then `scripts/plot.py OUTDIR` (every figure, no
animation) timed: wall-clock and CPU seconds and the largest resident memory of the plotting
process, and the CSV megabytes it read. VTK: the same deck with `files csv listing vtk` for each
N of --vtk-steps (default 1000 4000 16000), fekap timed whole. Cost per step that stays flat as
N grows is linear cost. Prints one table per part.
"""

from __future__ import annotations

import argparse
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fekap import run as fb

ROOT = fb.ROOT
FEKAP = Path(fb.fekap_binary())


def child_usage() -> tuple[float, int]:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss


def timed(command: list[str]) -> tuple[float, float, int]:
    """Wall and CPU seconds of a command, and the largest resident set (kB) of any child so far."""
    cpu0, _ = child_usage()
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    wall = time.perf_counter() - start
    cpu1, rss = child_usage()
    return wall, cpu1 - cpu0, rss


def deck(work: Path, vtk: bool) -> Path:
    text = (ROOT / "decks" / "fourbar.deck").read_text()
    if vtk:
        text = re.sub(r"(?m)^OUTPut.*$", "OUTPut\n  files csv listing vtk", text, count=1)
    path = work / ("fourbar-vtk.deck" if vtk else "fourbar.deck")
    path.write_text(text)
    return path


def plotting(work: Path, counts: list[int]) -> None:
    print("plot.py (every figure, no animation) after Example 1 with N steps")
    print(f"{'N':>9} {'CSV MB':>8} {'wall s':>8} {'CPU s':>8} {'CPU us/step':>12} {'max RSS MB':>11}")
    for n in counts:
        out = work / f"plot-{n}"
        subprocess.run([str(FEKAP), "-q", "--dt", repr(1.0 / n), "-o", str(out), str(deck(work, False))],
                       check=True, cwd=ROOT)
        size = sum(p.stat().st_size for p in out.glob("*.csv")) / 1e6
        wall, cpu, rss = plot_once(out)
        print(f"{n:>9} {size:>8.0f} {wall:>8.1f} {cpu:>8.1f} {1e6 * cpu / n:>12.1f} {rss / 1e3:>11.0f}")
        shutil.rmtree(out)


def plot_once(out: Path) -> tuple[float, float, int]:
    """Wall and CPU seconds of plot.py drawing every figure of ``out``, and its largest resident
    set (kB), measured by a small parent interpreter of its own."""
    measure = ("import resource, subprocess, sys, time;"
               "t = time.perf_counter();"
               "subprocess.run([sys.executable, sys.argv[1], sys.argv[2]], check=True, stdout=subprocess.DEVNULL);"
               "u = resource.getrusage(resource.RUSAGE_CHILDREN);"
               "print(time.perf_counter() - t, u.ru_utime + u.ru_stime, u.ru_maxrss)")
    proc = subprocess.run([sys.executable, "-c", measure, str(ROOT / "scripts" / "plot.py"), str(out)],
                          capture_output=True, text=True, check=True, cwd=ROOT)
    wall, cpu, rss = proc.stdout.split()
    return float(wall), float(cpu), int(rss)


def vtk_writing(work: Path, counts: list[int]) -> None:
    print("fekap with VTK files (files csv listing vtk), Example 1 with N steps")
    print(f"{'N':>9} {'files':>7} {'wall s':>8} {'CPU s':>8} {'CPU us/step':>12}")
    for n in counts:
        out = work / f"vtk-{n}"
        wall, cpu, _ = timed([str(FEKAP), "-q", "--dt", repr(1.0 / n), "-o", str(out), str(deck(work, True))])
        files = len(list((out / "vtk").glob("*.vtu")))
        print(f"{n:>9} {files:>7} {wall:>8.2f} {cpu:>8.2f} {1e6 * cpu / n:>12.1f}")
        shutil.rmtree(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--plot-steps", type=int, nargs="*", default=[10_000, 100_000, 1_000_000])
    parser.add_argument("--vtk-steps", type=int, nargs="*", default=[1000, 4000, 16000])
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="fekap-bench-output-"))
    try:
        if args.vtk_steps:
            vtk_writing(work, args.vtk_steps)
        if args.plot_steps:
            plotting(work, args.plot_steps)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
