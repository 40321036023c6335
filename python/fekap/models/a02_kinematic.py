"""Write FEKAP decks of the IFToMM A02 N-four-bar (a parallelogram chain with
change points), and its exact motion.

Pivots Ok = (k, 0) and tips Tk = (k, 1), k = 0..N; cranks Ok-Tk and separate
couplers Tk-Tk+1 of length 1, hinged at the tips; crank0 driven
pi/2 + 2 pi t. At t = 0.25 and 0.75 every bar is horizontal and the tangent
loses N ranks (a change point: the chain could fold there). On the
parallelogram tip k is at (k + cos q, sin q), q = pi/2 + 2 pi t.

Usage:  scripts/python -m fekap.models.a02_kinematic N [--dt DT] [--law absolute|relative] [--out DECK]
        scripts/python -m fekap.models.a02_kinematic --grid DIR    (N = 2, 4, 10, 40 x dt = 0.01,
                                              0.02, 0.025, 0.05, 1/12 into DIR)
DT is deck text (`1/12` is allowed). Without --out the deck goes to standard output.
"""

from __future__ import annotations

import argparse
import math
import os
import sys

#: The grid of the change-point study: chain lengths and time steps that land on (0.01, 0.025,
#: 0.05, 1/12) or step over (0.02) the change points.
GRID_N = (2, 4, 10, 40)
GRID_DT = ("0.01", "0.02", "0.025", "0.05", "1/12")


def dt_tag(dt_text: str) -> str:
    """File-name form of a step: 0.01 -> 0p01, 1/12 -> 1o12."""
    return dt_text.replace(".", "p").replace("/", "o")


def deck_name(n: int, dt_text: str, law: str = "absolute") -> str:
    return f"a02-n{n}-dt{dt_tag(dt_text)}" + ("" if law == "absolute" else "-relative")


def a02_deck(n: int, dt_text: str = "0.01", law: str = "absolute") -> str:
    """The deck text of the N-four-bar (law: `rate 2*pi pi/2` or the relative `rate 2*pi`)."""
    if n < 1:
        raise ValueError("N must be at least 1")
    nodes = [f"  O{k}  {k}  0" for k in range(n + 1)] + [f"  T{k}  {k}  1" for k in range(n + 1)]
    links = [f"  crank{k}  O{k}  T{k}  bar" for k in range(n + 1)]
    links += [f"  coupler{k}  T{k}  T{k + 1}  bar" for k in range(n)]
    rate = "rate 2*pi pi/2" if law == "absolute" else "rate 2*pi"
    return "\n".join([
        f"* IFToMM A02 N-four-bar, N = {n} (written by fekap.models.a02_kinematic): pivots Ok = (k, 0), cranks",
        "* Ok-Tk and couplers Tk-Tk+1 of length 1 (separate links, hinged at the tips); crank0",
        "* driven pi/2 + 2 pi t. Change points (every bar horizontal) at t = 0.25 and 0.75.",
        f"TITLe   IFToMM A02 N-four-bar, N = {n}",
        "SECTions", "  bar   E=1  G=1  A=100  I=1  k=5/6",
        "NODEs", *nodes, "LINKs", *links,
        "SUPPorts", *[f"  O{k}  pin" for k in range(n + 1)],
        "DRIVes", f"  rotation crank0  {rate}",
        "ANALysis", f"  time 0 1 {dt_text}",
        "OUTPut", "  units length=m time=s", "  track " + " ".join(f"T{k}" for k in range(n + 1)),
        "END", ""])


def exact(k: int, t: float) -> tuple[tuple[float, float], tuple[float, float], tuple[float, float]]:
    """Position, velocity and acceleration of tip Tk at time t on the parallelogram."""
    q = math.pi / 2 + 2 * math.pi * t
    w = 2 * math.pi
    return ((k + math.cos(q), math.sin(q)), (-w * math.sin(q), w * math.cos(q)),
            (-w * w * math.cos(q), -w * w * math.sin(q)))


def errors(outdir: str, n: int) -> dict:
    """Largest errors of a run's points.csv against the exact motion: positions
    relative to the largest exact coordinate (n + 1), velocities to 2 pi,
    accelerations to 4 pi^2 (over the rows that have them), the parallelogram's
    spread (largest angle between crank 0 and crank k, rad), the rows and the
    rows without rates, and the largest crank length error."""
    import csv
    pos = vel = acc = spread = 0.0
    rows = set()
    no_rates = set()
    angle = {}
    with open(os.path.join(outdir, "points.csv")) as f:
        for r in csv.DictReader(f):
            t = float(r["t"])
            k = int(r["point"][1:])
            (x, y), (vx, vy), (ax, ay) = exact(k, t)
            xf, yf = float(r["x"]), float(r["y"])
            rows.add(r["step"])
            pos = max(pos, abs(xf - x), abs(yf - y))
            angle.setdefault(r["step"], {})[k] = math.atan2(yf, xf - k)
            if r.get("vx", "") == "":
                no_rates.add(r["step"])
                continue
            vel = max(vel, abs(float(r["vx"]) - vx), abs(float(r["vy"]) - vy))
            if r.get("ax", "") != "":
                acc = max(acc, abs(float(r["ax"]) - ax), abs(float(r["ay"]) - ay))
    for a in angle.values():
        for v in a.values():
            d = abs(math.remainder(v - a[0], 2 * math.pi))
            spread = max(spread, d)
    return {"pos": pos / (n + 1), "vel": vel / (2 * math.pi), "acc": acc / (4 * math.pi ** 2),
            "spread": spread, "rows": len(rows), "no_rates": len(no_rates)}


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("n", nargs="?", type=int)
    p.add_argument("--dt", default="0.01")
    p.add_argument("--law", choices=("absolute", "relative"), default="absolute")
    p.add_argument("--out")
    p.add_argument("--grid", metavar="DIR")
    a = p.parse_args(argv)
    if a.grid:
        os.makedirs(a.grid, exist_ok=True)
        for n in GRID_N:
            for dt in GRID_DT:
                with open(os.path.join(a.grid, deck_name(n, dt) + ".deck"), "w") as f:
                    f.write(a02_deck(n, dt))
        return 0
    if a.n is None:
        p.error("give N or --grid DIR")
    text = a02_deck(a.n, a.dt, a.law)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
