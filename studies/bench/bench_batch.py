#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Throughput of fekap-batch: cases per second for N short cases (default 1,000:
decks/sweeps/fourbar-crank.deck, one crank turn at dt = 0.05, 20 steps, each
case its own crank length) run three ways:

  serial     a plain loop of the same fekap runs (subprocess.run, one at a time);
  2 by hand  two loops over half the cases each, at the same time;
  batch      scripts/fekap-batch on a LocalCluster (one worker per core),
             cluster start and stop, hashing, case.json and summary included.

    studies/bench/bench_batch.py [N] [--fekap PATH]

Prints the figures; docs/performance.md quotes them. Not a test: it times."""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DECK = ROOT / "decks" / "sweeps" / "fourbar-crank.deck"


def cranks(n: int) -> list[str]:
    return [repr(round(1.6 + 0.8 * i / max(n - 1, 1), 12)) for i in range(n)]


def loop(fekap: str, values: list[str], out: Path) -> None:
    for value in values:
        subprocess.run([fekap, "-q", "-o", str(out / value), "--set", f"crank={value}", "--dt", "0.05",
                        str(DECK)], check=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", nargs="?", type=int, default=1000)
    parser.add_argument("--fekap", default=str(ROOT / "build" / "local" / "bin" / "fekap"))
    args = parser.parse_args()
    values = cranks(args.n)
    work = Path(tempfile.mkdtemp(prefix="bench-batch-"))
    try:
        start = time.perf_counter()
        loop(args.fekap, values, work / "serial")
        serial = time.perf_counter() - start

        start = time.perf_counter()
        halves = [threading.Thread(target=loop, args=(args.fekap, values[k::2], work / "two")) for k in (0, 1)]
        for thread in halves:
            thread.start()
        for thread in halves:
            thread.join()
        two = time.perf_counter() - start

        sweep = work / "sweep.toml"
        sweep.write_text(f'decks = ["{DECK}"]\n[parameters]\ncrank = {{ linspace = [1.6, 2.4, {args.n}] }}\n'
                         '[options]\ndt = [0.05]\n')
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "fekap.batch", str(sweep), "-o", str(work / "batch"), "--fekap",
                        args.fekap, "--no-plots", "-q"], check=True)
        batch = time.perf_counter() - start
    finally:
        shutil.rmtree(work, ignore_errors=True)
    cores = os.cpu_count()
    print(f"{args.n} cases of {DECK.name} (20 steps each), {cores} cores:")
    for name, seconds in (("serial loop", serial), ("2 processes by hand", two),
                          (f"fekap-batch, LocalCluster of {cores}", batch)):
        print(f"  {name:32s} {seconds:7.2f} s  {args.n / seconds:7.1f} cases/s  "
              f"{1e3 * seconds / args.n:6.2f} ms/case")
    print(f"  batch overhead per case against 2 by hand: {1e3 * (batch - two) / args.n:.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
