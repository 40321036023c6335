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

With --law sine the drive is instead theta(t) = 30 deg + 20 deg sin(2 pi t) (the
layout of the scale study), and with --slider R0 slides on a floor slideline (a ground
guide along y = 0) instead of a roller support; both keep the closed form.

Usage:  scripts/python -m fekap.models.scissor N [--out DECK] [--dt DT] [--theta0 DEG]
        [--theta1 DEG] [--law ramp|sine] [--slider] [--elements K] [--solver band|dense]
        [--compute positions,velocities,accelerations] [--files csv,listing]
Without --out the deck goes to standard output.

        scripts/python -m fekap.models.scissor --check N [N ...] [--dt DT] [--fekap BIN]
runs the issue's layout (--law sine --slider, dt 0.01 unless given) for each N
and prints, per N: the largest error of the top ends' positions, velocities
and accelerations against the closed form (each relative to the largest exact
value of its kind), Newton iterations per step, microseconds per unknown per
configuration (the listing's time in analysis over the configurations and the
equations) and the peak memory of the run (maximum resident set size).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from fekap.run import RELEASE_BIN

THETA0_DEG = 30.0
THETA1_DEG = 60.0


def theta(t: float, theta0_deg: float = THETA0_DEG, theta1_deg: float = THETA1_DEG) -> float:
    """The drive angle (radians) at time t."""
    return math.radians(theta0_deg + (theta1_deg - theta0_deg) * t)


def platform_height(cells: int, t: float, theta0_deg: float = THETA0_DEG,
                    theta1_deg: float = THETA1_DEG) -> float:
    """The exact height of the top ends: 2 N sin(theta(t))."""
    return 2 * cells * math.sin(theta(t, theta0_deg, theta1_deg))


# The drive: theta(t) = SINE_MEAN + SINE_AMP sin(2 pi t) (degrees).
SINE_MEAN_DEG = 30.0
SINE_AMP_DEG = 20.0


def sine_theta(t: float) -> tuple[float, float, float]:
    """The --law sine drive angle and its first and second time derivatives (radians)."""
    w = 2 * math.pi
    mean, amp = math.radians(SINE_MEAN_DEG), math.radians(SINE_AMP_DEG)
    return mean + amp * math.sin(w * t), amp * w * math.cos(w * t), -amp * w * w * math.sin(w * t)


def top_exact(cells: int, t: float) -> dict[str, tuple[float, ...]]:
    """Closed form of the top ends under the sine drive: per point, (x, y, vx, vy, ax, ay).

    L_N = (0, 2 N sin theta) and R_N = (2 cos theta, 2 N sin theta)."""
    th, w, al = sine_theta(t)
    c, s = math.cos(th), math.sin(th)
    h, vh, ah = 2 * cells * s, 2 * cells * c * w, 2 * cells * (c * al - s * w * w)
    return {f"L{cells}": (0.0, h, 0.0, vh, 0.0, ah),
            f"R{cells}": (2 * c, h, -2 * s * w, vh, -2 * (s * al + c * w * w), ah)}


def deck_text(cells: int, dt: float = 0.05, theta0_deg: float = THETA0_DEG,
              theta1_deg: float = THETA1_DEG, elements: int = 1, solver: str = "band",
              compute: str = "positions,velocities,accelerations",
              files: str = "csv,listing", law: str = "ramp", slider: bool = False) -> str:
    """The deck of an N-cell scissor lift (law "ramp" or "sine"; slider: R0 on a floor slideline)."""
    if cells < 1:
        raise ValueError("a scissor lift has at least one cell")
    if law == "sine":
        theta0_deg = SINE_MEAN_DEG
    c, s = (f"cos({theta0_deg}*deg)", f"sin({theta0_deg}*deg)")
    lines = [
        f"* Scissor lift of {cells} cells, written by fekap.models.scissor: bars of length 2",
        "* crossing and hinged at their midpoints, cells hinged end to end; L0 pinned,",
        "* R0 on a roller (y fixed); driven by the angle of the bottom bar L0 -> M1.",
        f"* Exact platform height: 2*{cells}*sin(theta), theta = " + (
            f"{SINE_MEAN_DEG} + {SINE_AMP_DEG}*sin(2*pi*t) degrees." if law == "sine" else
            f"{theta0_deg} + {theta1_deg - theta0_deg}*t degrees."),
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
    lines += ["SUPPorts", "  L0  pin"]
    if slider:
        lines += ["SLIDelines", f"  floor  R0  guide -1  0  {2 * cells + 4}  0  pin"]
    else:
        lines.append("  R0  y")
    lines.append("DRIVes")
    if law == "sine":
        lines.append(f"  rotation P1a  harmonic {SINE_MEAN_DEG}*deg {SINE_AMP_DEG}*deg 2*pi -pi/2")
    else:
        lines.append(f"  rotation P1a  rate ({theta1_deg}-{theta0_deg})*deg")
    lines += [
        "ANALysis",
        f"  time 0 1 {dt!r}",
        "  compute " + " ".join(compute.replace(",", " ").split()),
        f"  solver {solver}",
        "OUTPut",
        "  units length=length time=s   ! the paper's units: lengths in no named unit, times in seconds",
        f"  track L{cells} R{cells}",
        "  angles P1a",
        "  files " + " ".join(files.replace(",", " ").split()),
        "END",
    ]
    return "\n".join(lines) + "\n"


def run_check(cells: int, dt: float, fekap: Path, workdir: Path) -> dict[str, float]:
    """Run the issue's layout of N cells and measure it against the closed form."""
    deck = workdir / f"scissor{cells}.deck"
    deck.write_text(deck_text(cells, dt, law="sine", slider=True))
    outdir = workdir / f"scissor{cells}"
    errfile = workdir / f"scissor{cells}.err"
    with open(errfile, "w") as handle:
        proc = subprocess.Popen([str(fekap), "-q", "-o", str(outdir), str(deck)], stdout=subprocess.DEVNULL,
                                stderr=handle)
        # wait4 rather than wait: the child's own peak resident set size.
        _, status, usage = os.wait4(proc.pid, 0)
    returncode = os.waitstatus_to_exitcode(status)
    err = errfile.read_text()
    result: dict[str, float] = {"N": cells, "exit": returncode}
    result["mem_mb"] = usage.ru_maxrss / 1024
    worst = {"pos": 0.0, "vel": 0.0, "acc": 0.0}
    scale = {"pos": 0.0, "vel": 0.0, "acc": 0.0}
    with open(outdir / "points.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            exact = top_exact(cells, float(row["t"]))[row["point"]]
            for kind, cols, ex in (("pos", ("x", "y"), exact[0:2]), ("vel", ("vx", "vy"), exact[2:4]),
                                   ("acc", ("ax", "ay"), exact[4:6])):
                for col, value in zip(cols, ex):
                    scale[kind] = max(scale[kind], abs(value))
                    if row[col] == "":
                        worst[kind] = math.inf
                    else:
                        worst[kind] = max(worst[kind], abs(float(row[col]) - value))
    for kind in worst:
        result[kind] = worst[kind] / scale[kind]
    with open(outdir / "steps.csv", newline="") as handle:
        steps = list(csv.DictReader(handle))
    result["steps"] = len(steps) - 1
    result["its"] = sum(int(s["iterations"]) for s in steps[1:]) / max(1, len(steps) - 1)
    listing = (outdir / f"scissor{cells}.lis").read_text()
    equations = int(re.search(r"(\d+) equations", listing).group(1))
    seconds = float(re.search(r"time in analysis \(s\)\s+(\S+)", listing).group(1))
    result["equations"] = equations
    result["us"] = seconds / len(steps) / equations * 1e6
    if returncode != 0:
        result["error"] = err.strip().splitlines()[-1] if err.strip() else ""
    return result


def check_main(sizes: list[int], dt: float, fekap: Path) -> int:
    """Print the check table for the sizes."""
    print("|      N | equations | pos error | vel error | acc error | its/step | us/unknown/config | memory MB |")
    print("|-------:|----------:|----------:|----------:|----------:|---------:|------------------:|----------:|")
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for cells in sizes:
            r = run_check(cells, dt, fekap, Path(tmp))
            print(f"| {cells:6d} | {r['equations']:9d} | {r['pos']:9.1e} | {r['vel']:9.1e} | {r['acc']:9.1e} "
                  f"| {r['its']:8.2f} | {r['us']:17.3f} | {r['mem_mb']:9.1f} |", flush=True)
            if r["exit"] != 0:
                failed += 1
                print(f"  exit {r['exit']}: {r.get('error', '')}")
    return 1 if failed else 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--check":
        parser = argparse.ArgumentParser(description="check scissor lifts against the closed form")
        parser.add_argument("sizes", type=int, nargs="+")
        parser.add_argument("--dt", type=float, default=0.01)
        parser.add_argument("--fekap", type=Path, default=RELEASE_BIN)
        args = parser.parse_args(argv[1:])
        return check_main(args.sizes, args.dt, args.fekap)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cells", type=int, help="number of cells N")
    parser.add_argument("--out", type=Path, help="deck file to write (default: standard output)")
    parser.add_argument("--dt", type=float, default=0.05, help="time step (default 0.05)")
    parser.add_argument("--theta0", type=float, default=THETA0_DEG, help="drive angle at t = 0, degrees")
    parser.add_argument("--theta1", type=float, default=THETA1_DEG, help="drive angle at t = 1, degrees")
    parser.add_argument("--elements", type=int, default=1, help="elements per link (default 1)")
    parser.add_argument("--solver", choices=["band", "dense"], default="band")
    parser.add_argument("--law", choices=["ramp", "sine"], default="ramp")
    parser.add_argument("--slider", action="store_true", help="R0 on a floor slideline instead of a roller")
    parser.add_argument("--compute", default="positions,velocities,accelerations")
    parser.add_argument("--files", default="csv,listing")
    args = parser.parse_args(argv)
    if args.cells < 1:
        parser.error("N must be at least 1")
    text = deck_text(args.cells, args.dt, args.theta0, args.theta1, args.elements, args.solver,
                     args.compute, args.files, args.law, args.slider)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
