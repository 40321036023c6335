#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Two fekap executables on the same cases of Example 1, taking turns: a
before/after comparison on a shared machine whose speed drifts over minutes
(a slow spell then falls on both alike). Full kinematics at dt (default
1e-4) over one revolution, with `files listing` and with `files csv listing`
(track B C), --repeat rounds (default 9); prints the medians and ranges of
the analysis and total time per configuration and the ratio of the medians.

Usage: studies/bench/bench_against.py BEFORE AFTER [--dt DT] [--repeat N]

To compare with an earlier commit:
  git worktree add /tmp/fekap-old REV && (cd /tmp/fekap-old && fpm build --profile release)
  studies/bench/bench_against.py /tmp/fekap-old/build/gfortran_*/app/fekap build/local/bin/fekap
"""

from __future__ import annotations

import argparse
import shutil
import statistics

from fekap import run as fb

from bench import FILES, fourbar_deck, fourbar_run


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("before", help="the fekap executable before the change")
    parser.add_argument("after", help="the fekap executable after it")
    parser.add_argument("--dt", type=float, default=1e-4, help="time step of Example 1 (default 1e-4)")
    parser.add_argument("--repeat", type=int, default=9, help="rounds (default 9)")
    args = parser.parse_args(argv)
    binaries = {"before": fb.fekap_binary(args.before), "after": fb.fekap_binary(args.after)}
    work = fb.scratch_dir("fekap-against-")
    decks = {files: fourbar_deck(work, args.dt, "full", files) for files in FILES}
    runs: dict = {(label, files): [] for label in binaries for files in FILES}
    for k in range(args.repeat):
        for label, binary in binaries.items():
            for files, deck in decks.items():
                runs[label, files].append(fourbar_run(binary, work, deck, k))
    shutil.rmtree(work, ignore_errors=True)
    print(f"Example 1, dt = {args.dt:g}, full kinematics, {args.repeat} rounds taking turns; "
          "us per configuration, median (min-max)")
    for files in FILES:
        medians = {}
        for label in binaries:
            rs = runs[label, files]
            for name in ("analysis_us", "total_us"):
                values = [r[name] for r in rs]
                medians[label, name] = statistics.median(values)
                print(f"  {FILES[files]:12s} {label:6s} {name[:-3]:8s} {statistics.median(values):8.2f} "
                      f"({min(values):.2f}-{max(values):.2f})")
        for name in ("analysis_us", "total_us"):
            print(f"  {FILES[files]:12s} after/before {name[:-3]:8s} "
                  f"{medians['after', name] / medians['before', name]:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
