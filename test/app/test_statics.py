"""Statics and kinetostatics with sliders and loads through the fekap
executable, against closed forms: a cantilever's tip deflection under a tip
force and its own weight and its clamp's reactions (exact by equilibrium),
the roll-up's clamp moment, a load with a time law of its own, and a
slider-crank's drive torque from the rigid-body power balance with a slider
mass and a load, and the guide's force normal to the guide."""

from __future__ import annotations

import math
from pathlib import Path

from apptest import ROOT, read_rows, run_fekap

CANTILEVER = "decks/statics-cantilever.deck"
SLIDER_CRANK = "decks/slider-crank-kinetostatics.deck"

# decks/statics-cantilever.deck
L, EI, KGA, P, N, WEIGHT = 2.0, 1.0e4, 1.0e8, 1.0, 16, 0.5 * 2.0 * 9.81


def run(tmp_path: Path, deck: str | Path, name: str) -> Path:
    out = tmp_path / name
    result = run_fekap("-q", "-o", str(out), str(deck))
    assert result.returncode == 0, result.stderr
    return out


def rows_of(out: Path, kind: str, node: str) -> list[dict[str, str]]:
    return [r for r in read_rows(out / "reactions.csv") if r["kind"] == kind and r["node"] == node]


def tip_y(out: Path) -> list[float]:
    return [float(r["y"]) for r in read_rows(out / "points.csv") if r["point"] == "T"]


def test_cantilever_tip_deflection_against_timoshenko(tmp_path):
    out = run(tmp_path, CANTILEVER, "c")
    y = tip_y(out)
    # The tip force alone (t = 1 less t = 0): Timoshenko's beam with n linear
    # one-point elements, P L^3/(3 EI) (1 - 1/(4 n^2)) + P L/kGA.
    want = P * L**3 / (3 * EI) * (1 - 1 / (4 * N**2)) + P * L / KGA
    assert abs((y[0] - y[-1]) / want - 1) < 5e-6, (y[0] - y[-1], want)
    # The weight alone (t = 0): q L^4/(8 EI) + q L^2/(2 kGA).
    q = WEIGHT / L
    want = q * L**4 / (8 * EI) + q * L**2 / (2 * KGA)
    assert abs(-y[0] / want - 1) < 5e-6, (y[0], want)


def test_cantilever_reactions_are_the_loads_resultant(tmp_path):
    out = run(tmp_path, CANTILEVER, "c")
    support = rows_of(out, "support", "R")
    joint = [r for r in rows_of(out, "joint", "R") if r["link"] == "RT"]
    assert len(support) == 5 and len(joint) == 5
    for s, j in zip(support, joint):
        t = float(s["t"])
        fx, fy, m = (float(s[k]) for k in ("fx", "fy", "m"))
        assert abs(fx) < 1e-6 * WEIGHT
        assert abs(fy / (WEIGHT + P * t) - 1) < 1e-9
        # Moments about the clamp, on the deflected arm (within its shortening).
        assert abs(m / (WEIGHT * L / 2 + P * L * t) - 1) < 1e-6
        # The clamp's reaction is the force the joint exerts on the link end.
        for k in ("fx", "fy", "m"):
            assert abs(float(j[k]) - float(s[k])) < 1e-8 * (WEIGHT + P)


def test_rollup_clamp_moment(tmp_path):
    out = run(tmp_path, "decks/cantilever-rollup.deck", "r")
    for s in rows_of(out, "support", "R"):
        t = float(s["t"])
        assert abs(float(s["m"]) + 2 * math.pi * t) < 1e-9 * 2 * math.pi


def test_load_with_a_law_of_its_own(tmp_path):
    text = (ROOT / CANTILEVER).read_text()
    deck = tmp_path / "harmonic.deck"
    deck.write_text(text.replace("  T  0  -1                                    ! times the load factor t",
                                 "  T  0  -1  harmonic 0 1 2*pi").replace("time 0 1 0.25", "time 0 1 0.125"))
    out = run(tmp_path, deck, "h")
    support = rows_of(out, "support", "R")
    assert len(support) == 9
    for s in support:
        t = float(s["t"])
        assert abs(float(s["fy"]) - (WEIGHT + math.cos(2 * math.pi * t))) < 1e-9 * (WEIGHT + 1)


def slider_closed_form(t: float) -> tuple[float, float, float, float]:
    """Crank angle, slider velocity and acceleration, and the rod's slope at time t."""
    r, l, w = 1.0, 3.0, 2 * math.pi
    th = w * t
    s = math.sqrt(l**2 - r**2 * math.sin(th) ** 2)
    v = -r * w * math.sin(th) - r**2 * w * math.sin(th) * math.cos(th) / s
    a = (-r * w**2 * math.cos(th) - r**2 * w**2 * (math.cos(th) ** 2 - math.sin(th) ** 2) / s
         - r**4 * w**2 * math.sin(th) ** 2 * math.cos(th) ** 2 / s**3)
    slope = (0 - r * math.sin(th)) / (r * math.cos(th) + s - r * math.cos(th))
    return th, v, a, slope


def test_slider_crank_torque_from_the_power_balance(tmp_path):
    """The slider-crank's kinetostatics (a slideline, a LOAD on the slider): drive torque and guide
    force against the closed form. Its LOAD leaves the FEM before the run (the motion is the
    kinematic one), which then takes the square-root form. Measured: torque 2.2e-13 and the force
    across the guide 1.4e-14 off (largest torque 50.9); in the K form (before kinetostatics
    took the square-root form) 2.8e-12 and 8.4e-13, which these bounds reject."""
    out = run(tmp_path, SLIDER_CRANK, "s")
    mass, force, w = 2.0, -5.0, 2 * math.pi
    drive = rows_of(out, "drive", "O")
    slider = rows_of(out, "slider", "B")
    assert len(drive) == 101 and len(slider) == 101
    largest = max(abs(float(d["m"])) for d in drive)
    assert largest > 10
    worst = 0.0
    for d, s in zip(drive, slider):
        th, v, a, slope = slider_closed_form(float(d["t"]))
        torque = (mass * a - force) * v / w
        worst = max(worst, abs(float(d["m"]) - torque))
        # The guide pushes across itself only, and balances the rod's force across it:
        # the rod (massless, pinned) pushes along itself with x component m a - F.
        assert abs(float(s["fx"])) < 1e-9 * largest
        assert abs(float(s["fy"]) - (-(mass * a - force) * slope)) < 4e-15 * largest
    assert worst < 2e-14 * largest, worst


# --- a full dead load at the start: load stepping ------------------------------------------------

DEAD_LOAD_DECK = """TITLe  cantilever under a tip force of P L^2/EI = 30 from t = 0 (a dead load)
SECTions
  beam  EA=1e9  kGA=1e9  EI=1
NODEs
  R  0  0
  T  1  0
LINKs
  RT  R  T  beam  64
SUPPorts
  R  pin  rot RT
LOADs
  T  0  -30  constant
ANALysis
  type statics
  time 0 1 0.5
END
"""


def elastica_tip(k: float, n: int = 4000) -> tuple[float, float]:
    """The inextensible elastica of a cantilever (L = EI = 1) under a downward tip force k:
    theta'' = k cos(theta), theta(0) = 0, theta'(1) = 0, by RK4 shooting on theta'(0) (bisection);
    returns the tip's (x, y)."""
    def shoot(c: float) -> list[float]:
        def f(state: list[float]) -> list[float]:
            th, w, _, _ = state
            return [w, k * math.cos(th), math.cos(th), math.sin(th)]
        h = 1.0 / n
        state = [0.0, c, 0.0, 0.0]
        for _ in range(n):
            k1 = f(state)
            k2 = f([s + h / 2 * d for s, d in zip(state, k1)])
            k3 = f([s + h / 2 * d for s, d in zip(state, k2)])
            k4 = f([s + h * d for s, d in zip(state, k3)])
            state = [s + h / 6 * (a + 2 * b + 2 * c_ + d) for s, a, b, c_, d in zip(state, k1, k2, k3, k4)]
        return state
    lo, hi = -k, 0.0
    for _ in range(50):
        mid = (lo + hi) / 2
        if shoot(mid)[1] > 0:
            hi = mid
        else:
            lo = mid
    state = shoot((lo + hi) / 2)
    return state[2], state[3]


def test_full_dead_load_at_the_start_is_load_stepped(tmp_path):
    """A tip force of P L^2/EI = 30 from t = 0: Newton from the straight cantilever does not
    converge (before load stepping: exit 3); the start steps the load factor 0 -> 1 with the step
    control's cuts, the listing says so, and the tip is the elastica's (Mattiasson's benchmark;
    EA and kGA stiff: within the 64 linear elements' discretisation error, 4e-5 measured)."""
    deck = tmp_path / "dead.deck"
    deck.write_text(DEAD_LOAD_DECK)
    out = run(tmp_path, deck, "dead")
    listing = (out / "dead.lis").read_text()
    note = [line for line in listing.splitlines() if "load stepped" in line]
    assert len(note) == 1 and "step 0," in note[0] and "Newton did not converge" in note[0], note
    assert note[0].split("factors ")[1].split(" (")[0].split()[-1] == "1.000E+00"
    steps = [r for r in read_rows(out / "steps.csv")]
    assert int(steps[0]["cuts"]) >= 1
    want = elastica_tip(30.0)
    for row in read_rows(out / "points.csv"):
        if row["point"] == "T":
            assert abs(float(row["x"]) - want[0]) < 1.5e-4, (row["x"], want)
            assert abs(float(row["y"]) - want[1]) < 1.5e-4, (row["y"], want)


def test_load_stepping_that_cannot_reach_the_full_load_stops_with_exit_3(tmp_path):
    """Two Newton iterations a solve: no load step converges; the message says the start was
    load stepped and why it failed, and the run exits 3."""
    deck = tmp_path / "hopeless.deck"
    deck.write_text(DEAD_LOAD_DECK.replace("  type statics", "  type statics\n  iterations 2"))
    result = run_fekap("-q", "-o", str(tmp_path / "hopeless"), str(deck))
    assert result.returncode == 3, result.stderr
    assert "nor in load steps from 0 to 1" in result.stderr, result.stderr
