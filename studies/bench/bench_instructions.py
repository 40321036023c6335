#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Instruction counts of FEKAP's fixed benchmark cases (valgrind's callgrind):
the machine's load cannot move them, so they catch a regression that timings
on a shared machine would drown.

Each case runs twice under `valgrind --tool=callgrind`, at two run lengths;
the figure is the marginal count per configuration (per step),

    (instructions of the long run - instructions of the short run) / (steps of the difference)

so that starting the process, reading the deck and setting up drop out.
User-space instructions only: the kernel's share of writing files is not
counted.

Cases (CASES below):

- Example 1 (decks/fourbar.deck) at dt = 1e-4, 10,000 and 20,000 steps (one
  and two revolutions): positions only and positions + velocities +
  accelerations, each with the listing alone (`files listing`, track B C)
  and with the CSV files that `fekap decks/fourbar.deck --dt 1e-4` writes
  (the deck's own output: points, links, steps, nodes, mesh, listing);
- the scissor lift of issue #16 (python/fekap/models/scissor.py N --law sine --slider,
  dt 0.01, full kinematics, listing only) at N = 100 and 1,000, 10 and 20 steps;
- the flexible slider-crank (decks/dynamics/slider-crank.deck, dt 1e-4,
  generalized-alpha), 100 and 200 steps.

Used by scripts/bench (bench.py): a full run records the counts in
docs/performance/bench.json ("instructions") and docs/performance.md;
`scripts/bench --check` runs these cases alone and fails (exit 1) when one
rises by more than CHECK_RISE against bench.json.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from fekap import run as fb
from fekap.models import scissor

#: A rise of a case's count above this fraction fails `scripts/bench --check`.
CHECK_RISE = 0.05

FOURBAR_DT = 1e-4
FOURBAR_COMPUTE = {"P": "positions", "PVA": "positions velocities accelerations"}
SCISSOR_DT = 0.01


def fourbar_deck(work: Path, compute: str, files: str, revolutions: int) -> tuple[Path, list[str]]:
    """Example 1 at FOURBAR_DT over `revolutions` revolutions; files "listing"
    (track B C, the listing alone) or "csv" (the deck's own output files)."""
    text = (fb.ROOT / "decks" / "fourbar.deck").read_text()
    output = {"track": "B C", "files": "listing"} if files == "listing" else None
    deck = work / f"fourbar-{compute}-{files}-{revolutions}.deck"
    deck.write_text(fb.with_settings(text, {"time": f"0 {revolutions} {FOURBAR_DT!r}",
                                            "compute": FOURBAR_COMPUTE[compute]}, output))
    return deck, []


def scissor_deck(work: Path, cells: int, steps: int) -> tuple[Path, list[str]]:
    """The issue-16 scissor lift of `cells` cells over `steps` steps of SCISSOR_DT."""
    text = scissor.deck_text(cells, dt=SCISSOR_DT, files="listing", law="sine", slider=True)
    deck = work / f"scissor-{cells}-{steps}.deck"
    deck.write_text(fb.with_settings(text, {"time": f"0 {steps * SCISSOR_DT!r} {SCISSOR_DT!r}"}))
    return deck, []


def slider_crank_deck(work: Path, steps: int) -> tuple[Path, list[str]]:
    """The flexible slider-crank (dt 1e-4) over `steps` steps, listing only."""
    deck = fb.ROOT / "decks" / "dynamics" / "slider-crank.deck"
    return deck, ["--set", f"t_end={steps * 1e-4!r}"]


#: name -> (what it is, deck maker of a run length, short length, long length, steps between them)
CASES = {
    "fourbar P listing": ("Example 1, positions, listing only",
                          lambda w, n: fourbar_deck(w, "P", "listing", n), 1, 2, 10000),
    "fourbar PVA listing": ("Example 1, positions + velocities + accelerations, listing only",
                            lambda w, n: fourbar_deck(w, "PVA", "listing", n), 1, 2, 10000),
    "fourbar P csv": ("Example 1, positions, the deck's CSV files",
                      lambda w, n: fourbar_deck(w, "P", "csv", n), 1, 2, 10000),
    "fourbar PVA csv": ("Example 1, positions + velocities + accelerations, the deck's CSV files "
                        "(`fekap decks/fourbar.deck --dt 1e-4`)",
                        lambda w, n: fourbar_deck(w, "PVA", "csv", n), 1, 2, 10000),
    "scissor 100": ("scissor lift N = 100 (1,201 equations), full kinematics, listing only",
                    lambda w, n: scissor_deck(w, 100, n), 10, 20, 10),
    "scissor 1000": ("scissor lift N = 1,000 (12,001 equations), full kinematics, listing only",
                     lambda w, n: scissor_deck(w, 1000, n), 10, 20, 10),
    "slider-crank dynamics": ("flexible slider-crank, dynamics (generalized-alpha), per step",
                              lambda w, n: slider_crank_deck(w, n), 100, 200, 100),
}


def instructions(binary: str, deck: Path, options: list[str], outdir: Path) -> int:
    """User-space instructions of one run of fekap under callgrind."""
    outdir.mkdir(parents=True, exist_ok=True)
    command = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={outdir / 'callgrind.out'}",
               binary, "-q", "-o", str(outdir / "run"), *options, str(deck)]
    proc = subprocess.run(command, capture_output=True, text=True, cwd=fb.ROOT)
    found = re.search(r"Collected : (\d+)", proc.stderr)
    if proc.returncode != 0 or not found:
        raise SystemExit(f"callgrind run failed (exit {proc.returncode}): {' '.join(command)}\n{proc.stderr[-2000:]}")
    return int(found.group(1))


def measure(binary: str, work: Path, names: list[str] | None = None, log=print) -> dict:
    """Marginal instructions per configuration of each case (all, or `names`)."""
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not installed (apt-get install valgrind)")
    results = {}
    for name in names or list(CASES):
        what, make, short, long, steps = CASES[name]
        counts = []
        for length in (short, long):
            deck, options = make(work, length)
            counts.append(instructions(binary, deck, options, work / f"cg-{len(results)}-{length}"))
        per = (counts[1] - counts[0]) / steps
        results[name] = {"what": what, "instructions_per_configuration": round(per),
                         "short_run": counts[0], "long_run": counts[1], "steps_between": steps}
        log(f"  {name:24s} {per:14,.0f} instructions per configuration ({what})")
    return results


def table(results: dict) -> str:
    """The Markdown table of measure's results."""
    rows = ["| case | instructions per configuration (marginal) | short run | long run | steps between |",
            "| --- | ---: | ---: | ---: | ---: |"]
    for r in results.values():
        rows.append(f"| {r['what']} | {r['instructions_per_configuration']:,} | {r['short_run']:,} | "
                    f"{r['long_run']:,} | {r['steps_between']:,} |")
    return "\n".join(rows)


def check(results: dict, recorded: dict, rise: float = CHECK_RISE, log=print) -> bool:
    """Whether no case rose by more than `rise` against the recorded counts."""
    ok = True
    for name, r in results.items():
        if name not in recorded:
            log(f"  {name}: not in the recorded file (no comparison)")
            continue
        before = recorded[name]["instructions_per_configuration"]
        now = r["instructions_per_configuration"]
        change = (now - before) / before
        verdict = "ok" if change <= rise else f"FAIL: rose more than {rise:.0%}"
        if change > rise:
            ok = False
        log(f"  {name:24s} recorded {before:12,} now {now:12,} ({change:+.1%}) {verdict}")
    return ok
