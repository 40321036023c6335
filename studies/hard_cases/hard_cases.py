#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Run FEKAP's hard cases and write their table into docs/hard-cases.md.

One row per case: the mechanism and options, the exit code, the rows, the
largest errors against the exact motion (positions relative to the largest
exact coordinate, velocities and accelerations to their scale), the rows left
without rates, Newton iterations per configuration and step cuts (steps.csv),
and the analysis time per configuration (the listing's "time in analysis"
over the rows, the least of three runs). Cases:

* the IFToMM A02 N-four-bar (python/fekap/models/a02_kinematic.py), N = 2, 4, 10, 40, at
  dt = 0.01, 0.02, 0.025, 0.05, 1/12: change points at t = 0.25, 0.75;
* the double crank of Example 3 landing on (0.025, 0.05, 1/12) or stepping
  over (0.02) its collinear positions;
* the near-toggle Grashof four-bar at large steps: `--predictor taylor` at 0.2
  and 0.3, the classical methods with `extrapolate` at 0.2, 0.3 and 0.5;
* the scissor lifts of items 1-2 (N = 10, 100, 1000), by python/fekap/models/scissor.py's run_check()
  when it has one (the rows are that script's; the same columns).

Usage:  studies/hard_cases/hard_cases.py [--fekap BIN] [--doc docs/hard-cases.md] [--print]
BIN defaults to build/local/bin/fekap (scripts/build). The table replaces the
text between the two marker lines of the page (--print: standard output only).
Times are of one run on whatever machine runs it: compare rows of one table.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import tempfile
from pathlib import Path

from fekap import run as fb
from fekap.models import a02_kinematic as a02

ROOT = fb.ROOT

BEGIN = "<!-- hard-cases table: begin (written by studies/hard_cases/hard_cases.py; do not edit by hand) -->"
END = "<!-- hard-cases table: end -->"
COLUMNS = ("case", "options", "exit", "rows", "pos", "vel", "acc", "no rates", "its/config", "cuts",
           "us/config")


#: Runs of each case; the time per configuration is the least of them.
REPEAT = 3


def run(fekap: str, deck: Path, out: Path, options: list[str]) -> tuple[int, Path]:
    """Run a case REPEAT times into out (the last run's files stay); the least
    analysis time goes to out/best-seconds.txt."""
    best = math.inf
    code = 0
    for _ in range(REPEAT):
        result = fb.run_deck(fekap, deck, out, *options, timeout=1800)
        code = result["rc"]
        best = min(best, analysis_seconds(out))
    if out.is_dir():
        (out / "best-seconds.txt").write_text(repr(best))
    return code, out


def analysis_seconds(out: Path) -> float:
    """The listing's analysis time of the run in out (inf without one)."""
    for lis in out.glob("*.lis"):
        seconds = fb.read_listing(lis)["summary"].get("time in analysis (s)")
        if seconds is not None:
            return seconds
    return math.inf


def run_summary(out: Path) -> dict:
    """Rows, iterations per configuration, cuts and analysis time per configuration of a run."""
    steps = list(csv.DictReader(open(out / "steps.csv")))
    its = sum(int(s["iterations"]) for s in steps)
    cuts = sum(int(s["cuts"]) for s in steps)
    best = out / "best-seconds.txt"
    seconds = float(best.read_text()) if best.exists() else analysis_seconds(out)
    n = max(1, len(steps))
    return {"rows": len(steps), "its/config": its / max(1, n - 1), "cuts": cuts, "us/config": 1e6 * seconds / n}


def point_errors(out: Path, exact, scales) -> dict:
    """Largest errors of points.csv against exact(point, t) -> ((x, y), (vx, vy), (ax, ay)) or None."""
    err = [0.0, 0.0, 0.0]
    no_rates = set()
    for r in csv.DictReader(open(out / "points.csv")):
        want = exact(r["point"], float(r["t"]))
        if want is None:
            continue
        (x, y), (vx, vy), (ax, ay) = want
        err[0] = max(err[0], abs(float(r["x"]) - x), abs(float(r["y"]) - y))
        if r.get("vx", "") == "":
            no_rates.add(r["step"])
            continue
        err[1] = max(err[1], abs(float(r["vx"]) - vx), abs(float(r["vy"]) - vy))
        if r.get("ax", "") != "":
            err[2] = max(err[2], abs(float(r["ax"]) - ax), abs(float(r["ay"]) - ay))
    return {"pos": err[0] / scales[0], "vel": err[1] / scales[1], "acc": err[2] / scales[2],
            "no rates": len(no_rates)}


def a02_rows(fekap: str, work: Path) -> list[dict]:
    rows = []
    for n in a02.GRID_N:
        for dt in a02.GRID_DT:
            deck = work / (a02.deck_name(n, dt) + ".deck")
            deck.write_text(a02.a02_deck(n, dt))
            code, out = run(fekap, deck, work / deck.stem, [])
            row = {"case": f"A02 N = {n}", "options": f"dt {dt}", "exit": code}
            if (out / "steps.csv").exists():
                e = a02.errors(str(out), n)
                row |= run_summary(out) | {"pos": e["pos"], "vel": e["vel"], "acc": e["acc"],
                                           "no rates": e["no_rates"]}
            rows.append(row)
    return rows


def double_crank_rows(fekap: str, work: Path) -> list[dict]:
    w = 2 * math.pi

    def exact(point, t):
        if point != "F":
            return None
        q = math.pi / 2 + w * t
        return ((4 + math.cos(q), math.sin(q)), (-w * math.sin(q), w * math.cos(q)),
                (-w * w * math.cos(q), -w * w * math.sin(q)))
    rows = []
    for dt in ("0.02", "0.025", "0.05", "1/12"):
        code, out = run(fekap, ROOT / "decks" / "double-crank.deck", work / f"dc-{a02.dt_tag(dt)}", ["--dt", dt])
        row = {"case": "double crank (Example 3)", "options": f"dt {dt}", "exit": code}
        if (out / "steps.csv").exists():
            row |= run_summary(out) | point_errors(out, exact, (5, w, w * w))
        rows.append(row)
    return rows


class Jet:
    """A value with its first and second derivatives in t (forward mode), for exact rates."""

    def __init__(self, f, d=0.0, dd=0.0):
        self.f, self.d, self.dd = f, d, dd

    def __add__(self, o):
        o = o if isinstance(o, Jet) else Jet(o)
        return Jet(self.f + o.f, self.d + o.d, self.dd + o.dd)

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.f, -self.d, -self.dd)

    def __sub__(self, o):
        return self + (-(o if isinstance(o, Jet) else Jet(o)))

    def __rsub__(self, o):
        return Jet(o) - self

    def __mul__(self, o):
        o = o if isinstance(o, Jet) else Jet(o)
        return Jet(self.f * o.f, self.d * o.f + self.f * o.d, self.dd * o.f + 2 * self.d * o.d + self.f * o.dd)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = o if isinstance(o, Jet) else Jet(o)
        return self * o.inv()

    def inv(self):
        g = 1 / self.f
        return Jet(g, -self.d * g * g, (2 * self.d * self.d * g - self.dd) * g * g)

    def apply(self, f, f1, f2):
        return Jet(f, f1 * self.d, f2 * self.d * self.d + f1 * self.dd)

    def sqrt(self):
        r = math.sqrt(self.f)
        return self.apply(r, 0.5 / r, -0.25 / (r * self.f))

    def cos(self):
        return self.apply(math.cos(self.f), -math.sin(self.f), -math.cos(self.f))

    def sin(self):
        return self.apply(math.sin(self.f), math.cos(self.f), -math.sin(self.f))


def grashof_rows(fekap: str, work: Path) -> list[dict]:
    w = 2 * math.pi

    def exact(point, t):
        """C of decks/hard/grashof-limit.deck (A = 0, D = (2.99, 0), 1, 2, 2), upper branch."""
        if point != "C":
            return None
        th = Jet(w * t, w)
        bx, by = th.cos(), th.sin()
        dx, dy = 2.99 - bx, -by
        d = (dx * dx + dy * dy).sqrt()
        ex, ey = dx / d, dy / d
        al = d * 0.5
        h = (4 - al * al).sqrt()
        cx, cy = bx + al * ex - h * ey, by + al * ey + h * ex
        return (cx.f, cy.f), (cx.d, cy.d), (cx.dd, cy.dd)
    rows = []
    cases = [("fem", "taylor", "0.2"), ("fem", "taylor", "0.3"), ("angles", "extrapolate", "0.2"),
             ("angles", "extrapolate", "0.3"), ("angles", "extrapolate", "0.5"), ("cartesian", "extrapolate", "0.2"),
             ("cartesian", "extrapolate", "0.3"), ("cartesian", "extrapolate", "0.5")]
    for method, predictor, dt in cases:
        options = ["--method", method, "--predictor", predictor, "--dt", dt]
        code, out = run(fekap, ROOT / "decks" / "hard" / "grashof-limit.deck", work / f"g-{method}-{predictor}-{dt}",
                        options)
        row = {"case": "Grashof-limit four-bar", "options": f"{method}, {predictor}, dt {dt}", "exit": code}
        if (out / "steps.csv").exists():
            row |= run_summary(out) | point_errors(out, exact, (3, 2 * w, 2 * w * w))
        rows.append(row)
    return rows


def scissor_rows(fekap: str, work: Path, sizes: tuple[int, ...] = (10, 100, 1000)) -> tuple[list[dict], str]:
    """The scissor lifts of items 1-2 (python/fekap/models/scissor.py's run_check: the issue's
    layout, errors relative to the closed form's largest value of each kind)."""
    try:
        from fekap.models import scissor
    except ImportError as e:
        return [], f"python/fekap/models/scissor.py could not be imported ({e})"
    rows = []
    for cells in sizes:
        r = scissor.run_check(cells, 0.01, Path(fekap), work)
        rows.append({"case": f"scissor lift N = {cells}", "options": "dt 0.01", "exit": r["exit"],
                     "rows": r["steps"] + 1, "pos": r["pos"], "vel": r["vel"], "acc": r["acc"],
                     "its/config": r["its"], "us/config": r["us"] * r["equations"]})
    return rows, ("scissor rows: errors relative to the closed form's largest value; N = 10,000 with "
                  "`scripts/python -m fekap.models.scissor --check 10000` (section 7)")


def cell(row: dict, key: str) -> str:
    v = row.get(key, "")
    if v == "" or v is None:
        return ""
    if key in ("pos", "vel", "acc"):
        return f"{v:.1e}"
    if key == "its/config":
        return f"{v:.2f}"
    if key == "us/config":
        return "" if not math.isfinite(v) else f"{v:.0f}"
    return str(v)


def table(rows: list[dict], remark: str) -> str:
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(cell(r, k) for k in COLUMNS) + " |" for r in rows]
    if remark:
        lines += ["", remark + "."]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--fekap", default=str(ROOT / "build" / "local" / "bin" / "fekap"))
    p.add_argument("--doc", default=str(ROOT / "docs" / "hard-cases.md"))
    p.add_argument("--print", action="store_true", help="print the table instead of writing the page")
    a = p.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="fekap-hard-cases-") as tmp:
        work = Path(tmp)
        sc, remark = scissor_rows(a.fekap, work)
        rows = a02_rows(a.fekap, work) + double_crank_rows(a.fekap, work) + grashof_rows(a.fekap, work) + sc
    text = table(rows, remark)
    if a.print:
        print(text)
        return 0
    doc = Path(a.doc)
    page = doc.read_text()
    if BEGIN not in page or END not in page:
        print(f"{doc}: no marker lines\n{BEGIN}\n{END}", file=sys.stderr)
        return 1
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    doc.write_text(head + BEGIN + "\n\n" + text + "\n\n" + END + tail)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
