"""The example decks run by the fekap executable, checked against independent
exact solutions at every step.

The references are closed-form geometry evaluated with hyper-dual numbers
(value, first and second time derivative carried through the arithmetic), so
velocities and accelerations are exact too, and owe nothing to FEKAP.

Run with scripts/test (pytest): scripts/test NAME runs the tests whose names contain NAME.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

from fekap.exact.fourbar import Dual, angle, cos, fourbar_exact, quick_return_exact, sin, sqrt

from apptest import ROOT, check, point_series, read_rows, run_fekap

OUT: Path = None  # a fresh scratch directory for each run, set by conftest.py


def compare(outdir: Path, point: str, exact, tol: float) -> None:
    """Every row of `point` against exact(t) -> (x, y) of Duals, relative to the
    largest magnitude of each quantity over the run."""
    series = point_series(outdir, point)
    names = [("x", "y", "f"), ("vx", "vy", "d"), ("ax", "ay", "dd")]
    for kx, ky, part in names:
        if kx not in series:
            continue
        got = [(x, y) for x, y in zip(series[kx], series[ky])]
        want = [tuple(getattr(c, part) for c in exact(t)) for t in series["t"]]
        scale = max(1.0, max(max(abs(a), abs(b)) for a, b in want))
        worst = max(max(abs(g[0] - w[0]), abs(g[1] - w[1])) for g, w in zip(got, want)) / scale
        check(worst <= tol, f"{outdir.name}: {point} {kx},{ky}: largest error {worst:.3e} "
                            f"relative to {scale:.3e} exceeds {tol:.0e}")


def run_deck(deck: str, *options: str, outdir: Path | None = None) -> Path:
    outdir = outdir or OUT / (Path(deck).stem + "".join(o.strip("-") for o in options))
    result = run_fekap("-q", "-o", str(outdir), *options, deck)
    check(result.returncode == 0, f"fekap {deck} {' '.join(options)} exited {result.returncode}:\n"
                                  f"{result.stderr}")
    return outdir


def test_fourbar():
    out = run_deck("decks/fourbar.deck")
    compare(out, "B", lambda t: fourbar_exact(t)[0], 1e-9)
    compare(out, "C", lambda t: fourbar_exact(t)[1], 1e-9)


def test_fourbar_rates_of_steps_accepted_at_their_predictor():
    """Example 1 at dt = 1e-4: all but a few steps end at their predictor and
    keep its factor of B_f (fewer than 1.05 factorisations a configuration:
    10,033 for 10,001 measured; 11,934 before Adams-Bashforth was taken up
    to adams_margin, two or more with no factor kept), and their velocities
    and accelerations are those of the predictor's factor and geometry,
    round-off from the accepted configuration's (fekap_fem's solve_step):
    B and C and their rates to 1e-13 of the closed form over the revolution
    (errors of 5e-15 and less measured)."""
    out = run_deck("decks/fourbar.deck", "--dt", "1e-4")
    listing = (out / "fourbar.lis").read_text()
    configurations = int(re.search(r"configurations solved\s+(\d+)", listing).group(1))
    factorisations = int(re.search(r"LU factorisations of B_f\s+(\d+)", listing).group(1))
    check(configurations == 10001 and factorisations < 1.05 * configurations,
          f"{factorisations} factorisations of B_f for {configurations} configurations")
    compare(out, "B", lambda t: fourbar_exact(t)[0], 1e-13)
    compare(out, "C", lambda t: fourbar_exact(t)[1], 1e-13)


@pytest.mark.parametrize("deck", ("decks/fourbar-quarter-turn.deck", "decks/fourbar-half-turn.deck"))
def test_fourbar_large_steps(deck):
    out = run_deck(deck)
    compare(out, "C", lambda t: fourbar_exact(t)[1], 1e-9)


def test_fourbar_appendage():
    def p_exact(t):
        b, c = fourbar_exact(t)
        mx, my = (b[0] + c[0]) / 2, (b[1] + c[1]) / 2
        ux, uy = (c[0] - b[0]) / 4, (c[1] - b[1]) / 4
        return (mx - 1.5 * uy, my + 1.5 * ux)
    out = run_deck("decks/fourbar-appendage.deck")
    compare(out, "P", p_exact, 1e-9)
    # The link angles are the four-bar's: the crank turns at 2*pi, the coupler halves are one body.
    rows = read_rows(out / "links.csv")
    for row in rows:
        if row["link"] == "AB":
            t = float(row["t"])
            check(abs(float(row["angle"]) - 2 * math.pi * t) < 1e-9, f"crank angle at t = {t}")


def test_double_crank():
    def f_exact(t):
        phi = angle(t, math.pi / 2, 2 * math.pi)
        return (4 + cos(phi), sin(phi))
    compare(run_deck("decks/double-crank.deck"), "F", f_exact, 1e-9)


def test_peaucellier():
    def p_exact(t):
        phi = Dual(math.radians(60) + math.radians(30) * math.cos(2 * math.pi * t),
                   -math.radians(30) * 2 * math.pi * math.sin(2 * math.pi * t),
                   -math.radians(30) * (2 * math.pi) ** 2 * math.cos(2 * math.pi * t))
        ax, ay = 1.4 + 1.4 * cos(phi), 1.4 * sin(phi)
        k = 7.56 / (ax * ax + ay * ay)     # OA * OP = 3.0^2 - 1.2^2, P on the ray O->A
        return (k * ax, k * ay)
    out = run_deck("decks/peaucellier.deck")
    compare(out, "P", p_exact, 1e-9)
    x = point_series(out, "P")["x"]
    check(max(abs(v - 2.7) for v in x) < 1e-9, "P leaves the line x = 2.7")


def test_quick_return():
    out = run_deck("decks/quick-return.deck")
    compare(out, "P", quick_return_exact, 1e-8)
    p = point_series(out, "P")
    check(max(abs(y - 500) for y in p["y"]) < 1e-9 * 500, "P leaves the guide y = 500")
    # Stroke: the far end is where vx changes sign from - to +.
    t, x, vx, ax = p["t"], p["x"], p["vx"], p["ax"]
    turns = [i for i in range(1, len(vx)) if vx[i - 1] < 0 <= vx[i]]
    check(len(turns) == 1, f"expected one reversal of P, found {len(turns)}")
    # From FEKAP's own x, vx, ax at the step nearest the reversal: one Newton
    # step on vx = 0 and a Taylor step for x.
    i = min(turns[0] - 1, turns[0], key=lambda k: abs(vx[k]))
    dt = -vx[i] / ax[i]
    t_far = t[i] + dt
    x_far = x[i] + vx[i] * dt + ax[i] * dt**2 / 2
    check(abs(x_far + 300) < 1e-6 * 300, f"stroke: far end at x = {x_far}, want -300")
    check(min(x) > -300 - 1e-9 and abs(x[0]) < 1e-12, "P moves between 0 and -300")
    ratio = t_far / (1 - t_far)
    check(abs(ratio - 1.515) < 0.01, f"time ratio {ratio:.4f}, want 1.515 +- 0.01")
    # The crank pin stays on the lever: C, O4 and the lever direction are collinear.
    c = point_series(out, "C")
    for cx, cy, tt in zip(c["x"], c["y"], c["t"]):
        th = math.atan2(-1, 3) + 2 * math.pi * tt
        check(abs(cx - 100 * math.cos(th)) < 1e-9 * 474 and
              abs(cy - 100 * math.sqrt(10) - 100 * math.sin(th)) < 1e-9 * 474, "crank pin off its circle")


def test_quick_return_pin_on_lever():
    """The crank pin C stays on the slotted lever O4-B: its distance from the
    line O4-B is below 1e-9 of the lever length at every step."""
    deck = OUT / "quick-return-track.deck"
    deck.write_text((ROOT / "decks/quick-return.deck").read_text().replace("track P C", "track B C P"))
    out = run_deck(str(deck))
    b, c = point_series(out, "B"), point_series(out, "C")
    lever = 150 * math.sqrt(10)
    gap = max(abs(cx * by - cy * bx) / math.hypot(bx, by)
              for bx, by, cx, cy in zip(b["x"], b["y"], c["x"], c["y"]))
    check(gap < 1e-9 * lever, f"crank pin off the lever by {gap:.2e}")
    length = max(abs(math.hypot(bx, by) - lever) for bx, by in zip(b["x"], b["y"]))
    check(length < 1e-9 * lever, f"lever length changes by {length:.2e}")


def test_prismatic_block():
    """A slider block B-B2 in a prismatic joint on the x axis (the slider-crank
    with a block instead of a point): the block keeps its angle, so B2 moves
    exactly as B shifted by the block's length; with a pin-in-slot joint the
    block could spin and the tangent would be singular."""
    text = (ROOT / "decks/slider-crank.deck").read_text()
    text = re.sub(r"^(\s*B\s+4\s+0\s*)$", r"\1\n  B2  4.5  0", text, count=1, flags=re.M)
    text = re.sub(r"(LINKs\n(?:.*\n)*?)(SUPPorts|SLIDelines)", r"\1  BB2  B  B2  bar\n\2", text, count=1)
    text = text.replace("guide -5 0 5 0  pin", "guide -5 0 5 0  prismatic BB2")
    text = text.replace("track B", "track B B2")
    deck = OUT / "slider-block.deck"
    deck.write_text(text)
    out = run_deck(str(deck))
    b, b2 = point_series(out, "B"), point_series(out, "B2")
    for key, shift in (("x", 0.5), ("y", 0.0), ("vx", 0.0), ("vy", 0.0), ("ax", 0.0), ("ay", 0.0)):
        worst = max(abs(u + shift - v) for u, v in zip(b[key], b2[key]))
        check(worst < 1e-9 * max(1.0, max(abs(u) for u in b[key])), f"B2.{key} - B.{key}: {worst:.2e}")
    angles = [float(r["angle"]) for r in read_rows(out / "links.csv") if r["link"] == "BB2"]
    check(max(abs(a) for a in angles) < 1e-9, "the block turns")
    def b_exact(t):
        th = angle(t, 0.0, 2 * math.pi)
        s = sin(th)
        return (cos(th) + sqrt(9 - s * s), Dual(0.0))
    compare(out, "B", b_exact, 1e-9)


def test_slider_crank():
    def b_exact(t):
        th = angle(t, 0.0, 2 * math.pi)
        s = sin(th)
        return (cos(th) + sqrt(9 - s * s), Dual(0.0))
    compare(run_deck("decks/slider-crank.deck"), "B", b_exact, 1e-9)


def test_cantilever_rollup():
    out = run_deck("decks/cantilever-rollup.deck")
    tip = point_series(out, "T")
    check(abs(tip["t"][-1] - 1) < 1e-12, "the run ends at t = 1")
    check(math.hypot(tip["x"][-1], tip["y"][-1]) < 1e-9, "M = 2*pi*EI/L closes the circle")


def test_methods_agree():
    """Examples 1, 2, 4, 5 by fem, cartesian and (four-bar) angles agree to 1e-9 (1e-8 for 5)."""
    cases = [("decks/fourbar.deck", ["B", "C"], ["cartesian", "angles"], 1e-9),
             ("decks/fourbar-appendage.deck", ["P"], ["cartesian"], 1e-9),
             ("decks/peaucellier.deck", ["P"], ["cartesian"], 1e-9),
             ("decks/quick-return.deck", ["P"], ["cartesian"], 1e-8)]
    for deck, points, methods, tol in cases:
        fem = run_deck(deck)
        for method in methods:
            other = run_deck(deck, "--method", method)
            for point in points:
                a, b = point_series(fem, point), point_series(other, point)
                for key in ("x", "y", "vx", "vy", "ax", "ay"):
                    scale = max(1.0, max(abs(v) for v in a[key]))
                    worst = max(abs(u - v) for u, v in zip(a[key], b[key])) / scale
                    check(worst <= tol, f"{deck} {point}.{key}: fem and {method} differ by {worst:.2e}")


def test_redundant_cartesian():
    """Example 3 by Cartesian coordinates: the redundancy is an input error; removed, it agrees."""
    result = run_fekap("-q", "-o", str(OUT / "dc-cart"), "--method", "cartesian", "decks/double-crank.deck")
    check(result.returncode == 2, f"exit {result.returncode}, want 2")
    check("redundant" in result.stderr, f"message does not say redundant:\n{result.stderr}")
    text = (ROOT / "decks/double-crank.deck").read_text()
    deck = OUT / "double-crank-remove.deck"
    deck.write_text(text.replace("ANALysis", "ANALysis\n  redundant remove", 1))
    other = run_deck(str(deck), "--method", "cartesian", outdir=OUT / "dc-remove")
    fem = run_deck("decks/double-crank.deck")
    a, b = point_series(fem, "F"), point_series(other, "F")
    for key in ("x", "y", "vx", "vy", "ax", "ay"):
        worst = max(abs(u - v) for u, v in zip(a[key], b[key]))
        check(worst < 1e-9 * max(1.0, max(abs(v) for v in a[key])), f"F.{key}: fem and cartesian differ")


def test_exit_codes_and_messages():
    result = run_fekap("decks/no-such.deck")
    check(result.returncode == 2 and "no-such.deck" in result.stderr, f"missing deck: {result.stderr}")
    result = run_fekap("--frobnicate", "decks/fourbar.deck")
    check(result.returncode == 2 and "--frobnicate" in result.stderr, f"unknown option: {result.stderr}")
    result = run_fekap("--dt", "-1", "decks/fourbar.deck")
    check(result.returncode == 2 and "--dt" in result.stderr, f"negative dt: {result.stderr}")
    result = run_fekap("--version")
    check(result.returncode == 0 and result.stdout.startswith("fekap "), "--version")
    result = run_fekap("--help")
    check(result.returncode == 0 and "usage: fekap" in result.stdout, "--help")
    bad = OUT / "bad.deck"
    bad.write_text((ROOT / "decks/fourbar.deck").read_text().replace("sqrt(15)", "sqrt(1S)"))
    result = run_fekap("-o", str(OUT / "bad"), str(bad))
    check(result.returncode == 2, f"bad number: exit {result.returncode}")
    check(f"{bad}:" in result.stderr and "^" in result.stderr, f"bad number message:\n{result.stderr}")


def test_failure_keeps_results():
    """A slider that runs off its guide stops the run with exit 3; the rows of
    the completed steps stay, and the listing says where and why."""
    deck = OUT / "short-guide.deck"
    deck.write_text((ROOT / "decks/quick-return.deck").read_text().replace("guide -400 500 100 500",
                                                                            "guide -100 500 100 500"))
    out = OUT / "short-guide"
    result = run_fekap("-q", "-o", str(out), str(deck))
    check(result.returncode == 3, f"exit {result.returncode}, want 3:\n{result.stderr}")
    check("slideline" in result.stderr and "step" in result.stderr, f"message:\n{result.stderr}")
    p = point_series(out, "P")
    check(len(p["t"]) > 5 and all(x >= -100 - 1e-6 for x in p["x"]), "rows of the completed steps kept")
    listing = (out / "short-guide.lis").read_text()
    check("RUN STOPPED" in listing, "the listing says the run stopped")
    steps = read_rows(out / "steps.csv")
    check(len(steps) == len(p["t"]), "steps.csv and points.csv hold the same steps")


@pytest.mark.parametrize("name", ("fourbar", "quick-return", "peaucellier", "cantilever-rollup"))
def test_plots_on_real_output(name, tmp_path):
    """The plot script draws the example deck's output (headless)."""
    out = run_deck(f"decks/{name}.deck", outdir=tmp_path / name)
    result = subprocess.run([sys.executable, str(ROOT / "scripts/plot.py"), str(out)],
                            capture_output=True, text=True)
    check(result.returncode == 0, f"plot.py {name}: {result.stderr}")
    for png in ("paths.png", "iterations.png"):
        path = out / png
        check(path.is_file() and path.stat().st_size > 1000, f"{name}: {png} missing or empty")
