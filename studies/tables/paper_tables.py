#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Example 1 (the four-bar of decks/fourbar.deck) at dt = 0.025, 0.25 and 0.5
with the three methods of FEKAP (fem, cartesian, angles), side by side with
the paper's Tables 1-3 (Eischen, Sun & Marler; iterations per step).

Each method runs twice per time step:
  * with the paper's settings: predictor `previous` (the last configuration,
    the paper's (10)) and the paper's convergence test `convergence paper`
    (||P(i)|| / ||P(0)|| < 1e-10); there is no command-line flag for the test,
    so a temporary copy of the deck gets the ANALysis settings;
  * with FEKAP's defaults: predictor `extrapolate`, convergence test `default`.

Iterations per step come from steps.csv (Newton iterations = linear solves).
Every run's final C is checked against the initial C = (3, sqrt(15)) (one full
turn of the crank); C = (3, -sqrt(15)) is the other assembly branch.

As an independent check of the paper's "Not Converged" (Cartesian, dt = 0.5,
second step), the script also runs a small numpy version of the Cartesian
method in which the crank angle is a Newton unknown (the driving constraint
phi1 - 2 pi t = 0 is one more equation and the predictor keeps the old crank
angle), beside the same code with the crank angle imposed in the predictor as
FEKAP does.

Usage: studies/tables/paper_tables.py [--short] [--out docs/tables.md] [--bin FEKAP]
  --short: dt = 0.025 only up to t = 0.25 (the paper's 10 rows), for the tests;
           prints the document instead of writing docs/tables.md unless --out is given.
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path

import numpy as np

from fekap import read
from fekap import run as fb

METHODS = ("angles", "cartesian", "fem")
METHOD_NAMES = {"angles": "Orientation angles", "cartesian": "Cartesian coord.", "fem": "FEM"}
SETTINGS = {
    "paper": {"predictor": "previous", "convergence": "paper"},
    "default": {"predictor": "extrapolate", "convergence": "default"},
}
C_UPPER = (3.0, math.sqrt(15.0))

# The paper's Tables 1-3, copied from the seed text: t -> (angles, cartesian, FEM).
PAPER = {
    0.025: {0.025: (5, 5, 6), 0.050: (5, 5, 6), 0.075: (5, 5, 6), 0.100: (5, 5, 6),
            0.125: (5, 4, 6), 0.150: (5, 4, 6), 0.175: (5, 4, 6), 0.200: (5, 4, 6),
            0.225: (5, 4, 6), 0.250: (5, 4, 6)},
    0.25: {0.25: (6, 6, 11), 0.50: (7, 6, 11), 0.75: (6, 6, 12), 1.00: (7, 11, 18)},
    0.5: {0.50: (8, 8, 11), 1.00: (9, "Not Converged", 13)},
}
TABLE_NUMBER = {0.025: 1, 0.25: 2, 0.5: 3}


def run(binary: str, work: Path, dt: float, t_end: float, method: str, setting: str) -> dict:
    """One run of Example 1; its steps, exit code and final C."""
    text = (fb.ROOT / "decks" / "fourbar.deck").read_text()
    analysis = {"method": method, "time": f"0 {t_end!r} {dt!r}", **SETTINGS[setting]}
    deck = work / f"fourbar-{method}-{setting}-{dt}.deck"
    deck.write_text(fb.with_settings(text, analysis))
    outdir = work / deck.stem
    result = fb.run_deck(binary, deck, outdir)
    steps = read.rows(outdir / "steps.csv", True) if (outdir / "steps.csv").is_file() else []
    c_rows = read.rows(outdir / "points.csv", True, point="C") if (outdir / "points.csv").is_file() else []
    final_c = (c_rows[-1]["x"], c_rows[-1]["y"]) if c_rows else None
    off = [r["t"] for r in c_rows if branch((r["x"], r["y"]), r["t"]) != "upper (correct)"]
    shutil.rmtree(outdir, ignore_errors=True)
    return {"rc": result["rc"], "stderr": result["stderr"].strip(), "steps": steps,
            "final_t": steps[-1]["t"] if steps else None, "final_c": final_c,
            "first_off": off[0] if off else None}


def cell(step: dict | None) -> str:
    if step is None:
        return "-"
    text = str(step["iterations"])
    if step["cuts"]:
        text += f" ({step['cuts']} cut{'s' if step['cuts'] > 1 else ''})"
    return text


def step_at(runs: dict, key: tuple, t: float) -> dict | None:
    for s in runs[key]["steps"]:
        if abs(s["t"] - t) < 1e-9:
            return s
    return None


def table(dt: float, runs: dict, t_end: float) -> str:
    """Markdown table of iterations per step for one time step size."""
    head = ["t", *(f"paper {METHOD_NAMES[m]}" for m in METHODS),
            *(f"FEKAP paper settings: {m}" for m in METHODS),
            *(f"FEKAP default: {m}" for m in METHODS)]
    lines = ["| " + " | ".join(head) + " |", "|" + " ---: |" * len(head)]
    paper = PAPER[dt]
    n = round(t_end / dt)
    times = [round(k * dt, 10) for k in range(1, n + 1)]
    shown = [t for t in times if t in paper] if dt == 0.025 else times
    for t in shown:
        row = [f"{t:g}"] + [str(v) for v in paper.get(t, ("-",) * 3)]
        for setting in SETTINGS:
            row += [cell(step_at(runs, (dt, m, setting), t)) for m in METHODS]
        lines.append("| " + " | ".join(row) + " |")
    rest = [t for t in times if t not in shown]
    if rest:
        row = [f"{rest[0]:g} to {rest[-1]:g} ({len(rest)} steps): mean (min-max)", "-", "-", "-"]
        for setting in SETTINGS:
            for m in METHODS:
                its = [s["iterations"] for s in runs[(dt, m, setting)]["steps"][1:]
                       if any(abs(s["t"] - t) < 1e-9 for t in rest)]
                row.append(f"{sum(its) / len(its):.2f} ({min(its)}-{max(its)})" if its else "-")
        lines.append("| " + " | ".join(row) + " |")
    if len(times) > 1:
        row = [f"mean over {len(times)} steps", *mean_paper(dt, times)]
        for setting in SETTINGS:
            for m in METHODS:
                its = [s["iterations"] for s in runs[(dt, m, setting)]["steps"][1:]]
                row.append(f"{sum(its) / len(its):.2f}" if its else "-")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def mean_paper(dt: float, times: list[float]) -> list[str]:
    paper = PAPER[dt]
    if not all(t in paper for t in times):
        return ["-"] * 3
    out = []
    for k in range(3):
        values = [paper[t][k] for t in times]
        out.append(f"{sum(values) / len(values):.2f}" if all(isinstance(v, int) for v in values) else "-")
    return out


def exact_c(t: float, upper: bool = True) -> tuple[float, float]:
    """C of the four-bar at crank angle 2 pi t on the upper (or lower) branch:
    the apex of the isosceles triangle B-C-D (BC = DC = 4)."""
    bx, by = 2 * math.cos(2 * math.pi * t), 2 * math.sin(2 * math.pi * t)
    dx, dy = 4 - bx, -by
    dist = math.hypot(dx, dy)
    h = math.sqrt(16 - (dist / 2) ** 2) * (1 if upper else -1)
    return bx + dx / 2 - h * dy / dist, by + dy / 2 + h * dx / dist


def branch(c: tuple | None, t: float = 1.0) -> str:
    """Which assembly branch C is on at time t."""
    if c is None:
        return "no result"
    up, low = exact_c(t, True), exact_c(t, False)
    if math.hypot(c[0] - up[0], c[1] - up[1]) < 1e-6:
        return "upper (correct)"
    if math.hypot(c[0] - low[0], c[1] - low[1]) < 1e-6:
        return "**lower branch**"
    return "**elsewhere**"


def final_table(runs: dict, horizons: dict) -> str:
    lines = ["| dt | method | settings | exit | last t | C at last t | distance from exact C (upper branch) "
             "| branch | first step off the upper branch |",
             "| ---: | --- | --- | ---: | ---: | --- | ---: | --- | ---: |"]
    for (dt, method, setting), r in runs.items():
        c = r["final_c"]
        if c is not None and r["final_t"] is not None:
            want = exact_c(r["final_t"])
            dist = f"{math.hypot(c[0] - want[0], c[1] - want[1]):.2e}"
            where = branch(c, r["final_t"])
        else:
            dist, where = "-", "no result"
        ctext = f"({c[0]:.6f}, {c[1]:.6f})" if c else "-"
        last = f"{r['final_t']:g}" if r["final_t"] is not None else "-"
        first = f"t = {r['first_off']:g}" if r["first_off"] is not None else "none"
        lines.append(f"| {dt:g} | {method} | {setting} | {r['rc']} | {last} | {ctext} | {dist} | {where} | {first} |")
    return "\n".join(lines)


# ---------------------------------------------------------------------------
# Independent check: Cartesian coordinates (Nikravesh's KAP) in numpy.

L1, L2, L3, D = 2.0, 4.0, 4.0, 4.0


def kap_residual(q: np.ndarray, t: float, driving: bool) -> np.ndarray:
    """Constraints of the four-bar in body coordinates (x, y, phi) of the link
    midpoints; with `driving`, the driving constraint phi1 - 2 pi t as a 9th."""
    x1, y1, p1, x2, y2, p2, x3, y3, p3 = q
    c1, s1, c2, s2, c3, s3 = np.cos(p1), np.sin(p1), np.cos(p2), np.sin(p2), np.cos(p3), np.sin(p3)
    r = [x1 - L1 / 2 * c1, y1 - L1 / 2 * s1,                                  # A pinned
         x1 + L1 / 2 * c1 - (x2 - L2 / 2 * c2), y1 + L1 / 2 * s1 - (y2 - L2 / 2 * s2),   # B
         x2 + L2 / 2 * c2 - (x3 + L3 / 2 * c3), y2 + L2 / 2 * s2 - (y3 + L3 / 2 * s3),   # C
         x3 - L3 / 2 * c3 - D, y3 - L3 / 2 * s3]                               # D pinned
    if driving:
        r.append(p1 - 2 * math.pi * t)
    return np.array(r)


def kap_jacobian(q: np.ndarray, t: float, driving: bool, h: float = 1e-7) -> np.ndarray:
    _, _, p1, _, _, p2, _, _, p3 = q
    s1, c1, s2, c2, s3, c3 = np.sin(p1), np.cos(p1), np.sin(p2), np.cos(p2), np.sin(p3), np.cos(p3)
    j = np.zeros((9 if driving else 8, 9))
    j[0, [0, 2]] = 1, L1 / 2 * s1
    j[1, [1, 2]] = 1, -L1 / 2 * c1
    j[2, [0, 2, 3, 5]] = 1, -L1 / 2 * s1, -1, -L2 / 2 * s2
    j[3, [1, 2, 4, 5]] = 1, L1 / 2 * c1, -1, L2 / 2 * c2
    j[4, [3, 5, 6, 8]] = 1, -L2 / 2 * s2, -1, L3 / 2 * s3
    j[5, [4, 5, 7, 8]] = 1, L2 / 2 * c2, -1, -L3 / 2 * c3
    j[6, [6, 8]] = 1, L3 / 2 * s3
    j[7, [7, 8]] = 1, -L3 / 2 * c3
    if driving:
        j[8, 2] = 1
    return j


def kap_run(dt: float, crank_unknown: bool, tol: float = 1e-10, max_iter: int = 50) -> list[dict]:
    """Cartesian Newton with the previous-configuration predictor and the
    paper's test. crank_unknown: the crank angle is one of the 9 unknowns (the
    predictor keeps its old value); otherwise it is imposed (set to 2 pi t in
    the predictor, 8 unknowns)."""
    sq = math.sqrt(15)
    q = np.array([1, 0, 0, 2.5, sq / 2, math.atan2(sq, 1), 3.5, sq / 2, math.atan2(sq, -1)], float)
    out = []
    for k in range(1, round(1 / dt) + 1):
        t = k * dt
        if not crank_unknown:
            q[2] = 2 * math.pi * t
        free = list(range(9)) if crank_unknown else [0, 1, 3, 4, 5, 6, 7, 8]
        r0 = np.linalg.norm(kap_residual(q, t, crank_unknown))
        its, ok = 0, r0 == 0
        while not ok and its < max_iter:
            r = kap_residual(q, t, crank_unknown)
            jac = kap_jacobian(q, t, crank_unknown)[:, free]
            q[free] -= np.linalg.solve(jac, r)
            its += 1
            ok = np.linalg.norm(kap_residual(q, t, crank_unknown)) < tol * r0
        c = (q[6] + L3 / 2 * math.cos(q[8]), q[7] + L3 / 2 * math.sin(q[8]))
        out.append({"t": t, "iterations": its, "converged": ok, "c": c,
                    "crank_deg": math.degrees(q[2])})
    return out


def kap_section() -> str:
    lines = ["| dt | crank angle | t | iterations | converged | C | branch |",
             "| ---: | --- | ---: | ---: | --- | --- | --- |"]
    for dt in (0.25, 0.5):
        for unknown in (True, False):
            for s in kap_run(dt, unknown):
                lines.append(f"| {dt:g} | {'Newton unknown' if unknown else 'imposed'} | {s['t']:g} | "
                             f"{s['iterations']} | {'yes' if s['converged'] else 'no'} | "
                             f"({s['c'][0]:.4f}, {s['c'][1]:.4f}) | "
                             f"{branch(s['c'], s['t'])} |")
    return "\n".join(lines)


def document(runs: dict, horizons: dict, short: bool, notes: str) -> str:
    parts = ["# Example 1: iterations per step, FEKAP against the paper's Tables 1-3", "",
             "Generated by `studies/tables/paper_tables.py`"
             + (" --short (reduced horizon)" if short else "") + "; the prose sections are kept in the script.",
             "",
             "Columns: the paper's numbers (copied from its Tables 1-3); FEKAP with the paper's settings "
             "(predictor `previous`, `convergence paper`, tolerance 1e-10); FEKAP with its defaults "
             "(predictor `extrapolate`, `convergence default`). Counts are Newton iterations = linear solves "
             "per step, from steps.csv; \"(k cuts)\" marks steps FEKAP had to halve.", ""]
    for dt in horizons:
        t_end = horizons[dt]
        title = f"## Table {TABLE_NUMBER[dt]}: dt = {dt:g}"
        if dt == 0.025:
            title += (" (the paper lists t = 0.025 to 0.25; FEKAP's later steps are summarised)"
                      if t_end > 0.25 else "")
        parts += [title, "", table(dt, runs, t_end), ""]
    parts += ["## Where every run ends", "",
              "C at the last step of each run; after one full turn it must be back at (3, sqrt(15)) = "
              "(3, 3.872983); (3, -3.872983) is the other assembly branch.", "",
              final_table(runs, horizons), "",
              "## Independent check: the Cartesian method with the crank angle as a Newton unknown", "",
              "A 30-line numpy version of the Cartesian method (body coordinates of the link midpoints, "
              "8 joint constraints, previous-configuration predictor, the paper's test), once with the "
              "driving constraint phi1 - 2 pi t = 0 as a ninth equation, its unknown starting from the old "
              "crank angle, once with the crank angle imposed in the predictor as FEKAP does:", "",
              kap_section(), "", notes]
    return "\n".join(parts) + "\n"


NOTES = """## What the differences mean

The iteration counts are deterministic (they do not depend on the machine);
the numbers quoted below are those of the tables above when this text was
written, and the tables are regenerated by the script.

**Geometry.** The paper's Fig. 10 did not survive, so the ground pivots, the
initial assembly and the drive were reconstructed (`../shared/examples.md`):
A = (0, 0), D = (4, 0), B = (2, 0), C = (3, sqrt(15)) on the upper branch,
crank angle 2 pi t from t = 0. The link lengths, section data and tolerance are
the paper's. With another placement of the pivots or another starting angle the
counts change from step to step (they follow how far C moves in a step), so
what can be compared is their level and trend, not every row.

**Counting.** FEKAP counts Newton iterations as linear solves (corrections
applied) per step. With the paper's test, iterations stop at the first iterate
with ||P(i)|| < 1e-10 ||P(0)||, P(0) being the residual at the predictor, so a
step that needs k corrections counts k. The paper does not say whether it
counted the final residual evaluation as an iteration; counting it would add
one to every FEKAP column.

**FEM, dt = 0.025.** The paper's FEM needed 6 iterations in each of its ten
listed steps. FEKAP with the paper's settings (the same Simo-Reissner element,
one per link, reduced integration, the paper's section data, predictor =
the last configuration with only the driven rotation advanced, the paper's
test) needs 5 per step, 5.35 on average over the turn: the exception is
t = 0.125 (19), where the crank and the coupler pass through collinear and the
branch-jump check has the step confirmed by solving it again in halves
(docs/hard-cases.md, rule 3). The difference of one iteration elsewhere is
within what the reconstructed geometry and the counting convention can
explain. FEKAP's defaults need 1.65 per step over the 40 steps (66 solves in
41 configurations; 1 on 18 steps, 2 near t = 0 and 1 where the path curves
most, 3-4 on the first three steps while the predictor's history fills).
Three things bring it there (measured before, 4.45): Newton's tangent leaves
out the geometric stiffness of the iterate's small spurious strains, so
convergence is quadratic from the first iteration (4.45 -> 3.2); the
predictor is the Hermite extrapolation through the last four configurations
and their velocities (the linear response the branch check computes anyway),
accurate to 2e-7 to 5e-7 of the model size mid-turn (1e-5 with three);
and the iteration stops on the quadratic-convergence estimate of the next
correction instead of computing it (docs/theory.md, section 3). The default
test is also what makes the answer accurate to round-off (see
docs/performance.md): the paper's test stops on the residual ratio alone and
leaves position errors of the order of its tolerance (about 3e-9 at 1e-8).

**Classical methods, dt = 0.025.** FEKAP's orientation-angle and Cartesian
methods need 3-4 iterations per step with the paper's settings (3.5 on
average), about one fewer than the paper's 5 (angles) and 4-5 (Cartesian).
Both impose the driven crank angle in the predictor (the paper's (8)), so each
step starts with the driving constraint satisfied and only the dependent
coordinates are iterated. All three methods converge quadratically. With the
paper's settings FEKAP's FEM needs about 1.5 more solves than its classical
methods, the paper's "one additional step" plus the counting; with the
defaults it needs fewer (1.65 against 3.5), since the classical methods keep
the Lagrange predictor and the verifying iteration.

**dt = 0.25 (Table 2).** With the paper's settings FEKAP's classical methods
need 6, 5, 5, 5 iterations (paper: angles 6, 7, 6, 7; Cartesian 6, 6, 6, 11).
FEKAP's FEM needs 77, 9, 50 and 9 (paper: 11, 11, 12, 18): at t = 0.25 and
0.75 the step makes a hinged pair of links pass through collinear while
turning it by more than 0.1 rad, and FEKAP does not accept such a step before
the same interval, solved again in halves (and the halves in halves, down to
turns below 0.1 rad), ends at the same configuration. Endpoint data cannot
tell a legitimate crossing from a jump over a near-toggle to the mirror
branch, which is what this check catches (docs/hard-cases.md, rule 3). The
steps without a crossing take 9 iterations (earlier, before the check: 11, 9,
8, 11). With the defaults the FEM needs 49, 10, 30, 7 for the same reason.
The paper's large counts at t = 1 (Cartesian 11, FEM 18) are not reproduced.

**dt = 0.5 (Table 3).** With the paper's settings FEKAP's classical methods
need 4 and 4 (paper: angles 8 and 9) and its FEM 98 and 72 (paper: 11 and 13;
FEKAP before the crossing check: 12 and 14), the halving confirmation of both
half turns. With the defaults the FEM's first half turn is also cut once (a
rejected configuration) and takes 67 solves over its sub-steps; the second
51.

**The paper's "Not Converged" (Cartesian, dt = 0.5) is not reproduced.**
FEKAP's Cartesian method converges at both steps of dt = 0.5, in 4 iterations
each, and ends at the right configuration. The difference is where the crank
angle is: FEKAP imposes it in the predictor. The numpy check above makes the
crank angle a Newton unknown, with the driving constraint as a ninth equation
and the previous configuration (old crank angle included) as the predictor.
Then dt = 0.5 does go wrong, but not as the paper reports: the first half turn
converges in 5 iterations to the **lower** branch, C = (1, -2.6458) instead of
(1, 2.6458), a wrong configuration that satisfies every constraint; the second
step needs 11 iterations and happens to come back to the upper branch at
t = 1. At dt = 0.25 the unknown-crank variant stays on the upper branch with
9, 5, 5, 7 iterations (imposed: 6, 5, 5, 5). So the classical-methods author's
finding holds in this sense: with the crank angle as an unknown, dt = 0.5
yields a configuration on the wrong branch (here at t = 0.5), not a failure to
converge. The paper's own Cartesian code may have differed in other details
(reference points, predictor, iteration cap), which the paper does not give.

**Assembly branches with the default predictor.** Before their assembly-mode
check (issue #7) FEKAP's classical methods with the default (extrapolating)
predictor landed on the **other assembly branch** at dt = 0.25 and at
dt = 0.5: C = (3, -3.873) at t = 1 instead of (3, 3.873), exit 0.
Extrapolating through configurations a quarter or half turn apart gives a
predictor nearer the mirror-image configuration, and both branches satisfy
every constraint. Now both methods check every converged step (the sign of
the Jacobian's determinant, and each angle's change against its linear
response to the drive increment; docs/hard-cases.md, section 1b) and cut a
rejected step in halves, so every run in the table "Where every run ends"
stays on the upper branch; the cut steps cost iterations (the counts of
Tables 2 and 3 with the defaults include those of their sub-steps, marked
"(k cuts)"). With the paper's predictor no step of these runs is rejected.
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Example 1 against the paper's Tables 1-3")
    parser.add_argument("--short", action="store_true", help="reduced horizon (dt = 0.025 to t = 0.25)")
    parser.add_argument("--out", type=Path, help="document to write (default docs/tables.md; "
                        "with --short the document is printed)")
    parser.add_argument("--bin", help="fekap executable")
    args = parser.parse_args(argv)
    binary = fb.fekap_binary(args.bin)
    work = fb.scratch_dir("fekap-tables-")
    horizons = {0.025: 0.25 if args.short else 1.0, 0.25: 1.0, 0.5: 1.0}
    runs: dict = {}
    for dt, t_end in horizons.items():
        for setting in SETTINGS:
            for method in METHODS:
                runs[(dt, method, setting)] = run(binary, work, dt, t_end, method, setting)
    shutil.rmtree(work, ignore_errors=True)
    text = document(runs, horizons, args.short, NOTES)
    out = args.out if args.out else (None if args.short else fb.ROOT / "docs" / "tables.md")
    if out:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
        print(f"wrote {out}")
    else:
        sys.stdout.write(text)
    for (dt, method, setting), r in runs.items():
        its = [s["iterations"] for s in r["steps"][1:]]
        c = r["final_c"]
        print(f"dt={dt:g} method={method} settings={setting} exit={r['rc']} iterations={its} "
              f"C=({c[0]:.6f},{c[1]:.6f})" if c else f"dt={dt:g} method={method} settings={setting} "
              f"exit={r['rc']} no result")
    return 0


if __name__ == "__main__":
    sys.exit(main())
