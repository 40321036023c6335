#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""The double crank of Example 3 (decks/double-crank.deck, redundant) at
section spreads EA/EI: the largest error of F's positions and rates against
the exact motion over every row (F = O3 + (cos th, sin th), th = pi/2 + 2 pi
t), and away from the collinear configurations (|t - 0.25|, |t - 0.75| >
0.03). The bars' SECTions line `A=100  I=1` is replaced by each (A, I).

Usage:  studies/redundant_rates/spread.py [--fekap BIN] [A,I ...]
BIN defaults to build/local/bin/fekap; without pairs, the spreads of
docs/theory.md ("Redundant mechanisms: the K form's rates refined").
"""

from __future__ import annotations

import argparse
import csv
import math
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAIRS = ["100,1", "1e2,1e-2", "1e3,1e-3", "1e4,1e-4", "1e5,1e-5", "1e6,1", "1e6,1e-6", "1e7,1e-7", "1e8,1e-8"]
W = 2 * math.pi


def errors(points: Path) -> tuple[int, dict[str, float], dict[str, float]]:
    """Rows, and the largest errors (x, v, a) over all rows and away from t = 0.25, 0.75."""
    every = {"x": 0.0, "v": 0.0, "a": 0.0}
    away = dict(every)
    rows = list(csv.DictReader(points.open())) if points.exists() else []
    for row in rows:
        t = float(row["t"])
        th = math.pi / 2 + 2 * math.pi * t
        found = {"x": max(abs(float(row["x"]) - 4 - math.cos(th)), abs(float(row["y"]) - math.sin(th)))}
        if row["vx"].strip():
            found["v"] = max(abs(float(row["vx"]) + W * math.sin(th)), abs(float(row["vy"]) - W * math.cos(th)))
        if row["ax"].strip():
            found["a"] = max(abs(float(row["ax"]) + W * W * math.cos(th)), abs(float(row["ay"]) + W * W * math.sin(th)))
        far = abs(t - 0.25) > 0.03 and abs(t - 0.75) > 0.03
        for key, value in found.items():
            every[key] = max(every[key], value)
            if far:
                away[key] = max(away[key], value)
    return len(rows), every, away


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fekap", default=str(ROOT / "build/local/bin/fekap"))
    parser.add_argument("pairs", nargs="*", default=PAIRS)
    args = parser.parse_args()
    text = (ROOT / "decks/double-crank.deck").read_text()
    with tempfile.TemporaryDirectory() as scratch:
        for pair in args.pairs:
            area, inertia = pair.split(",")
            out = Path(scratch) / pair
            out.mkdir()
            deck = out / "double-crank.deck"
            deck.write_text(text.replace("A=100  I=1 ", f"A={area}  I={inertia} "))
            run = subprocess.run([args.fekap, "-q", "-o", str(out), str(deck)], check=False, capture_output=True, text=True)
            rows, every, away = errors(out / "points.csv")
            line = (f"A={area:>5} I={inertia:>5} exit {run.returncode} rows {rows:3d}  pos {every['x']:.1e}  "
                    f"vel {every['v']:.1e} ({away['v']:.1e} away)  acc {every['a']:.1e} ({away['a']:.1e} away)")
            if run.returncode != 0:
                line += "  " + run.stderr.strip().splitlines()[-1][:90]
            print(line)


if __name__ == "__main__":
    main()
