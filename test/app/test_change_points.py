"""Change points (#16 item 3): the IFToMM A02 N-four-bar, whose tangent loses N
ranks where every bar is horizontal (t = 0.25, 0.75), and the double crank of
Example 3 at its collinear positions. FEKAP must follow the parallelogram for
every time step that lands on or steps over them, fill the rows it steps over
(positions exact, rates left out with a note), and never jump silently; the
leftovers of item 4 (the near-toggle Grashof four-bar with the Taylor
predictor, the classical methods with `extrapolate` at large steps) follow
their branch or stop with the jump diagnostic. docs/hard-cases.md (Change
points) has the numbers.

Run with scripts/test (pytest): scripts/test change_points.
"""

from __future__ import annotations

import math

import pytest

from fekap.models import a02_kinematic as a02

from apptest import ROOT, check, read_rows, run_fekap

OUT = None  # a fresh scratch directory for each module, set by conftest.py
GRID = [(n, dt) for n in a02.GRID_N for dt in a02.GRID_DT]


def run(deck_path, *options, want=0):
    tag = deck_path.stem + "".join(o.replace("-", "").replace("/", "o") for o in options)
    outdir = OUT / tag
    result = run_fekap("-q", "-o", str(outdir), *options, str(deck_path))
    check(result.returncode == want, f"fekap {deck_path.name} {' '.join(options)} exited {result.returncode}, "
                                     f"want {want}:\n{result.stderr}")
    return outdir, result.stderr


def listing(outdir):
    return "".join(p.read_text() for p in outdir.glob("*.lis"))


def landing(t):
    return min(abs(t - 0.25), abs(t - 0.75)) < 1e-12


def write_deck(n, dt, law="absolute"):
    path = OUT / (a02.deck_name(n, dt, law) + ".deck")
    path.write_text(a02.a02_deck(n, dt, law))
    return path


@pytest.mark.parametrize("n,dt", GRID, ids=[f"N{n}-dt{dt}" for n, dt in GRID])
def test_a02_follows_the_parallelogram(n, dt):
    """Every run of the grid ends (exit 0) on the parallelogram: tips to 1e-12
    relative to the chain's length, cranks parallel to 1e-11 rad; rates exact
    (velocities to 1e-9 of 2 pi, accelerations to 1e-8 of 4 pi^2: the K form's
    conditioning at N = 40) on every row but the ones landing on a change
    point, which are filled with a note and no rates; no jump, no cut."""
    out, _ = run(write_deck(n, dt))
    e = a02.errors(str(out), n)
    steps = read_rows(out / "steps.csv")
    check(e["rows"] == len(steps) == round(1 / eval(dt)) + 1, f"rows: {e['rows']}")
    check(e["pos"] < 1e-12, f"positions {e['pos']:.1e}")
    check(e["spread"] < 1e-11, f"spread {e['spread']:.1e} rad")
    check(e["vel"] < 1e-9, f"velocities {e['vel']:.1e}")
    check(e["acc"] < 1e-8, f"accelerations {e['acc']:.1e}")
    lands = sum(landing(float(s["t"])) for s in steps)
    check(e["no_rates"] == lands, f"{e['no_rates']} rows without rates, {lands} landing on a change point")
    text = listing(out)
    check(text.count("singular configuration (a change point") == lands, "a note per filled row")
    check("jump" not in text and sum(int(s["cuts"]) for s in steps) == 0, "a jump rejection or a cut")


def test_a02_before_this_change_stopped():
    """The deck of the issue (N = 2, dt = 0.01, committed under decks/hard/)
    used to stop with exit 3 after 26 of 101 steps; the relative drive law
    (the same motion, rounded differently) and positions only pass too, and
    the positions-only run notes the change points."""
    deck = ROOT / "decks" / "hard" / "a02-n2-dt0p01.deck"
    check(deck.read_text() == a02.a02_deck(2, "0.01"), "the committed deck is the generator's")
    out, _ = run(deck)
    check(len(read_rows(out / "steps.csv")) == 101, "101 rows")
    out, _ = run(write_deck(4, "0.025", "relative"))
    check(a02.errors(str(out), 4)["pos"] < 1e-12, "relative law")
    out, _ = run(deck, "--compute", "positions")
    e = a02.errors(str(out), 2)
    check(e["pos"] < 1e-12, f"positions only: {e['pos']:.1e}")
    check(listing(out).count("singular configuration (a change point") == 2, "positions only: both noted")


@pytest.mark.parametrize("dt", ["0.01", "0.025", "0.05", "1/12"])
def test_a02_taylor_predictor(dt):
    """The Taylor predictor on N = 10: exit 0, on the parallelogram (tips to
    1e-8: where its predictor lands far from the change point, Newton solves
    there as before and the row's position is fixed only to second order)."""
    out, _ = run(write_deck(10, dt), "--predictor", "taylor")
    e = a02.errors(str(out), 10)
    check(e["pos"] < 1e-8, f"positions {e['pos']:.1e}")
    check(e["vel"] < 1e-9, f"velocities {e['vel']:.1e}")


@pytest.mark.parametrize("dt", ["0.02", "0.025", "0.05", "1/12"])
def test_double_crank_collinear(dt):
    """Example 3 (redundant: three cranks on one coupler): F exact to 1e-12 at
    every row; dt = 0.025, 0.05 and 1/12 land on the collinear positions, whose
    rows are filled (no rates, a note), dt = 0.02 steps over them."""
    out, _ = run(ROOT / "decks" / "double-crank.deck", "--dt", dt)
    w = 2 * math.pi
    filled = 0
    for r in read_rows(out / "points.csv"):
        t = float(r["t"])
        q = math.pi / 2 + w * t
        err = max(abs(float(r["x"]) - 4 - math.cos(q)), abs(float(r["y"]) - math.sin(q)))
        check(err < 1e-12, f"t = {t}: position error {err:.1e}")
        if landing(t):
            filled += 1
            check(r["vx"] == "", f"t = {t}: rates not left out")
        else:
            check(abs(float(r["vx"]) + w * math.sin(q)) < 1e-9 * w, f"t = {t}: velocity")
    check(filled == (0 if dt == "0.02" else 2), f"{filled} filled rows")
    check(listing(out).count("singular configuration (a change point") == filled, "a note per filled row")


def grashof_c(t):
    th = 2 * math.pi * t
    bx, by = math.cos(th), math.sin(th)
    dx, dy = 2.99 - bx, -by
    d = math.hypot(dx, dy)
    ex, ey = dx / d, dy / d
    al = d / 2
    h = math.sqrt(4 - al * al)
    return bx + al * ex - h * ey, by + al * ey + h * ex


LEFTOVERS = [("fem", "taylor", "0.2"), ("fem", "taylor", "0.3"), ("fem", "extrapolate", "0.2"),
             ("angles", "extrapolate", "0.2"), ("angles", "extrapolate", "0.3"), ("angles", "extrapolate", "0.5"),
             ("cartesian", "extrapolate", "0.2"), ("cartesian", "extrapolate", "0.3"),
             ("cartesian", "extrapolate", "0.5"), ("angles", "taylor", "0.3"), ("cartesian", "taylor", "0.3")]


@pytest.mark.parametrize("method,predictor,dt", LEFTOVERS, ids=["-".join(c) for c in LEFTOVERS])
def test_grashof_limit_large_steps(method, predictor, dt):
    """The near-toggle Grashof four-bar (decks/hard/grashof-limit.deck) at
    large steps, FEM and classical: every run follows the upper branch (C to
    1e-8 at every row) or stops with the jump diagnostic; those listed here all
    follow it, rejecting the jumps their predictors make on the way."""
    out, err = run(ROOT / "decks" / "hard" / "grashof-limit.deck", "--method", method, "--predictor", predictor,
                   "--dt", dt)
    for r in read_rows(out / "points.csv"):
        if r["point"] != "C":
            continue
        x, y = grashof_c(float(r["t"]))
        e = max(abs(float(r["x"]) - x), abs(float(r["y"]) - y))
        check(e < 1e-8, f"t = {r['t']}: C off by {e:.1e}")
