"""Rates of a redundant mechanism at stiffness extremes: the double parallel
crank of Example 3 (decks/double-crank.deck) with its bars' section spread
EA/EI from 1e2 to 1e10, against its exact answer and against differences of
its positions.

A redundant mechanism has more strain rows than free dofs, so its rates are
solved with K = B^T W B, whose error is about eps kappa(K) = eps (EA/EI)
kappa(B)^2; the solves are refined with residuals from the element strain
rates (fekap_fem_rates' refine_rates; docs/theory.md, "Rates at scale").
Before that the velocities were 1.3e-11 to 7.6e-6 off and the accelerations
4.5e-10 to 5.6e-4 over these spreads.

The exact answer: every crank turns with the driven one, so F = O3 + (cos th,
sin th), th = pi/2 + 2 pi t, and F's rates are those of a point on the unit
circle at 2 pi rad/s."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from apptest import ROOT, check, point_series, run_fekap

#: Largest error of F's velocities and accelerations against the exact circle
#: over every row (the rows next to the collinear configurations at t = 0.25
#: and 0.75 included, where the rates are the least well conditioned): the
#: release build measured at most 6.7e-13 and 1.3e-10 at these spreads.
VELOCITY_TOL = 1e-11
ACCELERATION_TOL = 1e-9
#: Against fourth-order central differences of the positions at dt = 2e-3
#: (truncation about w^5 dt^4 / 30 = 5e-9 for the velocities and w^6 dt^4 / 90
#: = 1e-8 for the accelerations, w = 2 pi): measured 5.2e-9 and 1.1e-8.
DIFFERENCE_STEP = 2e-3
VELOCITY_DIFFERENCE_TOL = 2e-8
ACCELERATION_DIFFERENCE_TOL = 1e-7
#: Cross-section (A, I) of the bars, E = G = 1: EA/EI from 1e2 (the shipped
#: deck) to 1e10, and a stiff bar of ordinary bending stiffness.
SECTIONS = [("100", "1"), ("1e2", "1e-2"), ("1e3", "1e-3"), ("1e4", "1e-4"), ("1e5", "1e-5"), ("1e6", "1")]

OUT: Path = None


def run_spread(area: str, inertia: str, time: str = "") -> dict[str, np.ndarray]:
    """F's series for the double crank with section (area, inertia), over
    `time` (the ANALysis time line's values; the deck's if empty)."""
    text = (ROOT / "decks/double-crank.deck").read_text()
    changed = text.replace("A=100  I=1 ", f"A={area}  I={inertia} ")
    check(changed != text or (area, inertia) == ("100", "1"), "the deck's SECTions line was not found")
    if time:
        check("time 0 1 0.02" in changed, "the deck's time line was not found")
        changed = changed.replace("time 0 1 0.02", f"time {time}")
    outdir = OUT / f"A{area}-I{inertia}{'-' + time.replace(' ', '_') if time else ''}"
    outdir.mkdir(parents=True, exist_ok=True)
    deck = outdir / "double-crank.deck"
    deck.write_text(changed)
    run = run_fekap(str(deck), "-q", "-o", str(outdir))
    check(run.returncode == 0, f"A={area} I={inertia}: exit {run.returncode}: {run.stderr}")
    return {key: np.array(values) for key, values in point_series(outdir, "F").items()}


@pytest.mark.parametrize(("area", "inertia"), SECTIONS)
def test_double_crank_rates_exact_at_section_spread(area, inertia):
    f = run_spread(area, inertia)
    th = math.pi / 2 + 2 * math.pi * f["t"]
    w = 2 * math.pi
    velocity = max(np.abs(f["vx"] + w * np.sin(th)).max(), np.abs(f["vy"] - w * np.cos(th)).max())
    acceleration = max(np.abs(f["ax"] + w * w * np.cos(th)).max(), np.abs(f["ay"] + w * w * np.sin(th)).max())
    check(f["t"].size == 51 and np.isfinite(f["vx"]).all() and np.isfinite(f["ax"]).all(),
          f"rows or rates missing: {f['t'].size} rows")
    check(velocity < VELOCITY_TOL, f"EA/EI = {float(area) / float(inertia):g}: velocities {velocity:.2e} off")
    check(acceleration < ACCELERATION_TOL,
          f"EA/EI = {float(area) / float(inertia):g}: accelerations {acceleration:.2e} off")


def test_double_crank_rates_match_position_differences_at_spread_1e10():
    """At EA/EI = 1e10 the rates are those of the positions the run computed
    (fourth-order central differences over t in [0, 0.2], away from the
    collinear configuration at t = 0.25)."""
    f = run_spread("1e5", "1e-5", f"0 0.2 {DIFFERENCE_STEP!r}")
    check(f["t"].size == 101, f"{f['t'].size} rows, not 101")
    h = DIFFERENCE_STEP
    for axis in ("x", "y"):
        x = f[axis]
        rate = (-x[4:] + 8 * x[3:-1] - 8 * x[1:-3] + x[:-4]) / (12 * h)
        rate2 = (-x[4:] + 16 * x[3:-1] - 30 * x[2:-2] + 16 * x[1:-3] - x[:-4]) / (12 * h * h)
        velocity = np.abs(f["v" + axis][2:-2] - rate).max()
        acceleration = np.abs(f["a" + axis][2:-2] - rate2).max()
        check(velocity < VELOCITY_DIFFERENCE_TOL, f"v{axis} {velocity:.2e} from the positions' differences")
        check(acceleration < ACCELERATION_DIFFERENCE_TOL,
              f"a{axis} {acceleration:.2e} from the positions' differences")
