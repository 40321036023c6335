#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""The scissor lift at scale (issue #29, item 3): what a configuration costs per
unknown from N = 10 to 10,000 cells, the memory a run takes, and whether the
rates stay exact.

For each N (python/fekap/models/scissor.py N --law sine --slider, dt 0.01, full
kinematics) it prints:

- equations (the listing's PLAN);
- marginal instructions per configuration under valgrind's callgrind: the
  benchmark's scissor case (studies/bench/bench_instructions.py,
  `scissor_deck`, listing only) at two run lengths (--steps, 10 and 20 as
  the benchmark), (long - short) / (steps between), so that start-up, the
  deck and the set-up drop out; and that per equation;
- CPU milliseconds per configuration: the child's user + system time
  (getrusage through wait4) of the same listing-only deck at two run lengths
  (--cpu-steps, 10 and 100), the difference over the steps between, the
  smallest over --repeat runs of each length. A shared machine's load moves
  these by tens of per cent (other processes share the caches and cores):
  the instruction counts are the measure, this column the order of magnitude;
- peak memory: the largest maximum resident set size (ru_maxrss) of those
  runs and of the check run below;
- Newton iterations per step and the largest error of the top ends'
  positions, velocities and accelerations against the closed form (each
  relative to the largest exact value of its kind): `run_check` of
  fekap.models.scissor (the issue's layout, dt 0.01, 100 steps, CSV files).

Usage:  studies/bench/scissor_scale.py [N ...] [--fekap BIN] [--steps S L]
        [--cpu-steps S L] [--repeat R] [--no-callgrind] [--work DIR]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from fekap.models import scissor
from fekap.run import RELEASE_BIN

import bench_instructions as bi

SIZES = [10, 100, 1000, 10000]


def rusage_run(binary: str, deck: Path, outdir: Path) -> tuple[float, float]:
    """CPU seconds (user + system) and peak resident set (MB) of one run of fekap."""
    outdir.mkdir(parents=True, exist_ok=True)
    proc = subprocess.Popen([binary, "-q", "-o", str(outdir / "run"), str(deck)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    # wait4 rather than wait: the child's own times and peak resident set size.
    _, status, usage = os.wait4(proc.pid, 0)
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"fekap failed on {deck}: {err[-2000:]}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def callgrind_marginal(binary: str, work: Path, cells: int, short: int, long: int) -> int:
    """Marginal instructions per configuration of the benchmark's scissor case."""
    counts = []
    for steps in (short, long):
        deck, options = bi.scissor_deck(work, cells, steps)
        counts.append(bi.instructions(binary, deck, options, work / f"cg-{cells}-{steps}"))
    return round((counts[1] - counts[0]) / (long - short))


def cpu_marginal(binary: str, work: Path, cells: int, short: int, long: int,
                 repeat: int) -> tuple[float, float]:
    """CPU ms per configuration (smallest times of `repeat` runs of each length) and peak MB."""
    best = {}
    peak = 0.0
    for steps in (short, long):
        deck, _ = bi.scissor_deck(work, cells, steps)
        times = []
        for k in range(repeat):
            seconds, mb = rusage_run(binary, deck, work / f"cpu-{cells}-{steps}-{k}")
            times.append(seconds)
            peak = max(peak, mb)
            shutil.rmtree(work / f"cpu-{cells}-{steps}-{k}", ignore_errors=True)
        best[steps] = min(times)
    return (best[long] - best[short]) / (long - short) * 1e3, peak


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sizes", type=int, nargs="*", default=SIZES, help="cells N (default 10 100 1000 10000)")
    parser.add_argument("--fekap", default=os.environ.get("FEKAP_BIN", str(RELEASE_BIN)),
                        help="the release executable (default $FEKAP_BIN or build/local/bin/fekap)")
    parser.add_argument("--steps", type=int, nargs=2, default=[10, 20], metavar=("SHORT", "LONG"),
                        help="run lengths under callgrind (default 10 20, as the benchmark)")
    parser.add_argument("--cpu-steps", type=int, nargs=2, default=[10, 100], metavar=("SHORT", "LONG"),
                        help="run lengths of the CPU times (default 10 100)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each length for the CPU times (default 3)")
    parser.add_argument("--no-callgrind", action="store_true", help="leave out the instruction counts")
    parser.add_argument("--work", type=Path, help="scratch directory (default: a temporary one)")
    args = parser.parse_args(argv)
    if not args.no_callgrind and shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not installed (apt-get install valgrind), or pass --no-callgrind")
    binary = str(Path(args.fekap).resolve())
    print(f"fekap: {binary}")
    print(f"instructions: callgrind, marginal between {args.steps[0]} and {args.steps[1]} steps; "
          f"CPU: user + system, marginal between {args.cpu_steps[0]} and {args.cpu_steps[1]} steps, "
          f"smallest of {args.repeat} (noisy on a shared machine)")
    print("| N | equations | instructions/config | per unknown | CPU ms/config | peak RSS MB "
          "| Newton its/step | pos error | vel error | acc error |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |", flush=True)
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        base = args.work or Path(tmp)
        for cells in args.sizes:
            work = base / f"N{cells}"
            work.mkdir(parents=True, exist_ok=True)
            check = scissor.run_check(cells, 0.01, Path(binary), work)
            shutil.rmtree(work / f"scissor{cells}", ignore_errors=True)
            ms, peak = cpu_marginal(binary, work, cells, *args.cpu_steps, args.repeat)
            peak = max(peak, check["mem_mb"])
            if args.no_callgrind:
                per, per_unknown = "-", "-"
            else:
                count = callgrind_marginal(binary, work, cells, *args.steps)
                per, per_unknown = f"{count:,}", f"{count / check['equations']:,.0f}"
            ms_text = f"{ms:#.3g}".rstrip(".")
            print(f"| {cells:,} | {check['equations']:,} | {per} | {per_unknown} | {ms_text} | {peak:.1f} "
                  f"| {check['its']:.2f} | {check['pos']:.1e} | {check['vel']:.1e} | {check['acc']:.1e} |",
                  flush=True)
            if check["exit"] != 0:
                failed += 1
                print(f"  N = {cells}: exit {check['exit']}: {check.get('error', '')}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
