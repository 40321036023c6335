#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""What the slideline penalty does: Newton iterations, gap, accuracy and
conditioning of the slider-crank and the quick-return mechanism for penalty
parameters from 1e-2 to 1e8 times FEKAP's default.

    studies/penalty/penalty_study.py [--out docs/penalty.md] [--short]

Runs the release build (scripts/build) on copies of decks/slider-crank.deck and
decks/quick-return.deck with `penalty=` set on every slideline, and writes a
markdown table.
"""

from __future__ import annotations

import argparse
import math
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from fekap import run as fb

ROOT = fb.ROOT
FEKAP = fb.RELEASE_BIN


def run(deck: Path, outdir: Path) -> tuple[int, str]:
    result = fb.run_deck(str(FEKAP), deck, outdir)
    return result["rc"], result["stderr"].strip()


def default_penalties(listing: str) -> dict[str, float]:
    return {m.group(1): float(m.group(2))
            for m in re.finditer(r"slideline (\S+): penalty\s+(\S+),", listing)}


def summary(listing: str, label: str) -> float:
    match = re.search(rf"{label}\s+(\S+)", listing)
    return float(match.group(1)) if match else float("nan")


def rows(path: Path, point: str) -> list[dict[str, float]]:
    lines = path.read_text().splitlines()
    head = lines[0].split(",")
    out = []
    for line in lines[1:]:
        fields = dict(zip(head, line.split(",")))
        if fields["point"] == point:
            out.append({k: float(v) for k, v in fields.items() if k != "point" and v})
    return out


def slider_error(outdir: Path) -> tuple[float, float]:
    """Largest |x - exact| of the slider and largest gap |y|."""
    err = gap = 0.0
    for r in rows(outdir / "points.csv", "B"):
        th = 2 * math.pi * r["t"]
        err = max(err, abs(r["x"] - (math.cos(th) + math.sqrt(9 - math.sin(th) ** 2))))
        gap = max(gap, abs(r["y"]))
    return err, gap


def quick_return_error(outdir: Path) -> tuple[float, float]:
    """Largest |x - exact| of P and largest gap: |y_P - 500| and C's distance from the lever."""
    err = gap = 0.0
    c_rows = rows(outdir / "points.csv", "C")
    for r, _c in zip(rows(outdir / "points.csv", "P"), c_rows):
        th = math.atan2(-1, 3) + 2 * math.pi * r["t"]
        cx, cy = 100 * math.cos(th), 100 * math.sqrt(10) + 100 * math.sin(th)
        k = 150 * math.sqrt(10) / math.hypot(cx, cy)
        bx, by = k * cx, k * cy
        err = max(err, abs(r["x"] - (bx - math.sqrt(25000 - (500 - by) ** 2))))
        gap = max(gap, abs(r["y"] - 500))
    # C on the lever O4-B: B is tracked too.
    for c, b in zip(c_rows, rows(outdir / "points.csv", "B")):
        gap = max(gap, abs(c["x"] * b["y"] - c["y"] * b["x"]) / math.hypot(b["x"], b["y"]))
    return err, gap


def study(deck: Path, track: str, factors: list[float], work: Path, error_of) -> list[list[str]]:
    base = work / f"{deck.stem}-default"
    status, message = run(deck, base)
    if status != 0:
        sys.exit(f"penalty_study: {deck} failed: {message}")
    defaults = default_penalties((base / f"{deck.stem}.lis").read_text())
    table = []
    for factor in factors:
        text = deck.read_text()
        for name, kp in defaults.items():
            text = re.sub(rf"^(\s*{re.escape(name)}\s.*?)(\s*!.*)?$",
                          lambda m: f"{m.group(1)}  penalty={kp * factor:.6e}", text, count=1, flags=re.M)  # noqa: B023 (called at once)
        text = re.sub(r"^\s*track .*$", f"  track {track}", text, count=1, flags=re.M)
        variant = work / f"{deck.stem}-{factor:g}.deck"
        variant.write_text(text)
        outdir = work / variant.stem
        status, message = run(variant, outdir)
        listing = (outdir / f"{variant.stem}.lis").read_text() if (outdir / f"{variant.stem}.lis").exists() else ""
        if status != 0:
            table.append([f"{factor:g}", "stopped", "-", "-", "-", "-", message.splitlines()[0][:60]])
            continue
        err, gap = error_of(outdir)
        table.append([f"{factor:g}", f"{summary(listing, 'iterations per configuration'):.2f}",
                      f"{gap:.1e}", f"{err:.1e}", f"{summary(listing, 'smallest pivot ratio'):.1e}",
                      f"{int(summary(listing, 'LU factorisations [(]fallback[)]'))}", ""])
    return table


def markdown(title: str, table: list[list[str]]) -> str:
    head = ["penalty / default", "iterations per step", "largest gap", "largest error of P/slider x",
            "smallest pivot ratio", "LU fallbacks", "note"]
    lines = [f"### {title}", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(row) + " |" for row in table]
    return "\n".join(lines) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs" / "penalty.md"))
    parser.add_argument("--short", action="store_true", help="three penalty values only (for the tests)")
    args = parser.parse_args()
    subprocess.run([str(ROOT / "scripts" / "build")], check=True)
    factors = [1e-2, 1, 1e4] if args.short else [1e-2, 1e-1, 1, 1e1, 1e2, 1e4, 1e6, 1e8]
    work = Path(tempfile.mkdtemp(prefix="fekap-penalty-"))
    slider = study(ROOT / "decks" / "slider-crank.deck", "B", factors, work, slider_error)
    quick = study(ROOT / "decks" / "quick-return.deck", "B C P", factors, work, quick_return_error)
    text = ["# The slideline penalty: iterations, gap and conditioning", "",
            "Generated by `studies/penalty/penalty_study.py` (release build). Each deck is run with the",
            "penalty of every slideline set to a multiple of FEKAP's default (the largest EA/L of the",
            "elements the spring couples). The gap is measured from the written positions; the error",
            "against the independent closed form (docs/theory.md, section 6); the pivot ratio is the",
            "smallest min_j U(j,j)^2/K(j,j) of the velocity tangents (docs/theory.md), a measure of",
            "conditioning.", "",
            markdown("Slider-crank (decks/slider-crank.deck, dt = 0.01)", slider), "",
            markdown("Quick-return mechanism, Example 5 (decks/quick-return.deck, dt = 0.01)", quick), "",
            "What to read from it: at a converged kinematic configuration every force vanishes, so",
            "the gap is zero to round-off whatever the penalty (the gap and error columns). The",
            "penalty only shapes the iteration: on the slider-crank (a horizontal guide, a constraint",
            "linear in y) nothing changes; on the quick-return mechanism, whose lever is slender",
            "(EI/L^3 of 1e-8 against EA/L of 0.2), penalties far above the default cost Newton",
            "iterations, worsen the conditioning of the tangent (the pivot ratio) and make the",
            "Cholesky factorisation fail more often during the iterations (LU fallbacks). The",
            "default, the largest EA/L of the coupled elements, sits at the cheap end.", ""]
    Path(args.out).write_text("\n".join(text))
    print(f"wrote {args.out}")
    print("\n".join(text[10:]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
