#!/usr/bin/env python3
"""Write a FEKAP deck for a scissor lift of N cells.

Each cell is two bars of length 2 crossing at their midpoints and hinged there;
cells are hinged end to end. Cell i (1..N) joins the left and right ends of
level i-1 to those of level i:

    bar P_i from L_{i-1} to R_i, bar Q_i from R_{i-1} to L_i, crossing at M_i.

Each bar is two links welded at the crossing (P_ia, P_ib and Q_ia, Q_ib), so
the two bars of a cell are two rigid groups hinged to each other at M_i. The
bottom left end L_0 is pinned, the bottom right end R_0 is a roller on the
ground (support `y`), and the lift is driven by the angle theta of the bottom
bar's first link L_0 -> M_1:

    theta(t) = THETA0 + (THETA1 - THETA0) t,  t in [0, 1]

so that L_i = (0, 2 i sin(theta)), R_i = (2 cos(theta), 2 i sin(theta)) and the
platform (the top ends L_N, R_N) is exactly at height 2 N sin(theta).

Usage:  python3 scripts/scissor.py N [--out DECK] [--dt DT] [--theta0 DEG]
        [--theta1 DEG] [--elements K] [--solver band|dense]
        [--compute positions,velocities,accelerations] [--files csv,listing]
Without --out the deck goes to standard output.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

THETA0_DEG = 30.0
THETA1_DEG = 60.0


def theta(t: float, theta0_deg: float = THETA0_DEG, theta1_deg: float = THETA1_DEG) -> float:
    """The drive angle (radians) at time t."""
    return math.radians(theta0_deg + (theta1_deg - theta0_deg) * t)


def platform_height(cells: int, t: float, theta0_deg: float = THETA0_DEG,
                    theta1_deg: float = THETA1_DEG) -> float:
    """The exact height of the top ends: 2 N sin(theta(t))."""
    return 2 * cells * math.sin(theta(t, theta0_deg, theta1_deg))


def deck_text(cells: int, dt: float = 0.05, theta0_deg: float = THETA0_DEG,
              theta1_deg: float = THETA1_DEG, elements: int = 1, solver: str = "band",
              compute: str = "positions,velocities,accelerations",
              files: str = "csv,listing") -> str:
    """The deck of an N-cell scissor lift."""
    if cells < 1:
        raise ValueError("a scissor lift has at least one cell")
    c, s = (f"cos({theta0_deg}*deg)", f"sin({theta0_deg}*deg)")
    lines = [
        f"* Scissor lift of {cells} cells, written by scripts/scissor.py: bars of length 2",
        "* crossing and hinged at their midpoints, cells hinged end to end; L0 pinned,",
        "* R0 on a roller (y fixed); driven by the angle of the bottom bar L0 -> M1.",
        f"* Exact platform height: 2*{cells}*sin(theta), theta = {theta0_deg} + "
        f"{theta1_deg - theta0_deg}*t degrees.",
        f"TITLe   Scissor lift, {cells} cells",
        "SECTions",
        "  bar   E=1  G=1  A=100  I=1  k=5/6",
        "NODEs",
    ]
    for i in range(cells + 1):
        lines.append(f"  L{i}  0  2*{i}*{s}")
        lines.append(f"  R{i}  2*{c}  2*{i}*{s}")
    for i in range(1, cells + 1):
        lines.append(f"  M{i}  {c}  (2*{i}-1)*{s}")
    lines.append("LINKs")
    for i in range(1, cells + 1):
        lines.append(f"  P{i}a  L{i - 1}  M{i}  bar  {elements}")
        lines.append(f"  P{i}b  M{i}  R{i}  bar  {elements}")
        lines.append(f"  Q{i}a  R{i - 1}  M{i}  bar  {elements}")
        lines.append(f"  Q{i}b  M{i}  L{i}  bar  {elements}")
    lines.append("WELDs")
    for i in range(1, cells + 1):
        lines.append(f"  M{i}  P{i}a  P{i}b")
        lines.append(f"  M{i}  Q{i}a  Q{i}b")
    lines += [
        "SUPPorts",
        "  L0  pin",
        "  R0  y",
        "DRIVes",
        f"  rotation P1a  rate ({theta1_deg}-{theta0_deg})*deg",
        "ANALysis",
        f"  time 0 1 {dt!r}",
        "  compute " + " ".join(compute.replace(",", " ").split()),
        f"  solver {solver}",
        "OUTPut",
        f"  track L{cells} R{cells}",
        "  angles P1a",
        "  files " + " ".join(files.replace(",", " ").split()),
        "END",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cells", type=int, help="number of cells N")
    parser.add_argument("--out", type=Path, help="deck file to write (default: standard output)")
    parser.add_argument("--dt", type=float, default=0.05, help="time step (default 0.05)")
    parser.add_argument("--theta0", type=float, default=THETA0_DEG, help="drive angle at t = 0, degrees")
    parser.add_argument("--theta1", type=float, default=THETA1_DEG, help="drive angle at t = 1, degrees")
    parser.add_argument("--elements", type=int, default=1, help="elements per link (default 1)")
    parser.add_argument("--solver", choices=["band", "dense"], default="band")
    parser.add_argument("--compute", default="positions,velocities,accelerations")
    parser.add_argument("--files", default="csv,listing")
    args = parser.parse_args(argv)
    if args.cells < 1:
        parser.error("N must be at least 1")
    text = deck_text(args.cells, args.dt, args.theta0, args.theta1, args.elements, args.solver,
                     args.compute, args.files)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
