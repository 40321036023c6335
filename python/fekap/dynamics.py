"""The dynamics benchmarks' answers read from a run's CSV output, written once
for the tests (test/app/test_dynamics.py) and the comparison and study
scripts (accuracy_study.py, spin_up_compare.py, exudyn_spin_up.py,
exudyn_a02.py):

- the stiff pendulum's first pass through the bottom (time and speed, by the
  cubic Hermite interpolant of x through the two steps around it);
- the A02 N-four-bar's first crank against its exact motion (fekap.exact.a02);
- the spin-up beam's tip in the hub's frame (axial stretch, transverse
  deflection).

numpy only: the Exudyn scripts import it in their own environment too.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fekap import read
from fekap.exact import a02 as a02_exact

#: The rigid pendulum (L = 1, g = 9.81) released from the horizontal: T/4 and the speed there.
BOTTOM_TIME = 0.591960487
BOTTOM_SPEED = 4.429446918

#: The A02 chain (N = 2) reaches its first change point (every bar flat) at t = 0.7148 s.
A02_FIRST_CHANGE = 0.70

#: The spin-up beam's length (decks/dynamics/spin-up.deck).
SPIN_UP_LENGTH = 10.0


def columns(path: Path, point: str | None = None) -> dict[str, np.ndarray]:
    """The columns of a run's CSV file (points.csv: the rows of one point) as arrays; an
    error when there is no such row."""
    table = read.columns(path, **({"point": point} if point else {}))
    if table["t"].size == 0:
        raise ValueError(f"{path}: no rows" + (f" for point {point}" if point else ""))
    return table


def bottom_pass(outdir: Path, point: str = "B") -> tuple[float, float]:
    """Time and speed of the pendulum's first pass through x = 0 (from x > 0):
    Newton on the cubic Hermite interpolant of x (positions and velocities of
    the two steps around it), the speed interpolated linearly there. NaN when
    it does not pass."""
    p = columns(outdir / "points.csv", point)
    t, x, vx, vy = p["t"], p["x"], p["vx"], p["vy"]
    for k in range(len(t) - 1):
        if x[k] > 0 >= x[k + 1]:
            h = t[k + 1] - t[k]
            x0, x1, v0, v1 = x[k], x[k + 1], vx[k] * h, vx[k + 1] * h
            s = x0 / (x0 - x1)
            for _ in range(30):
                f = (2*s**3 - 3*s**2 + 1)*x0 + (s**3 - 2*s**2 + s)*v0 + (-2*s**3 + 3*s**2)*x1 + (s**3 - s**2)*v1
                df = (6*s**2 - 6*s)*x0 + (3*s**2 - 4*s + 1)*v0 + (-6*s**2 + 6*s)*x1 + (3*s**2 - 2*s)*v1
                s -= f / df
            speed = (1 - s) * math.hypot(vx[k], vy[k]) + s * math.hypot(vx[k + 1], vy[k + 1])
            return float(t[k] + s * h), float(speed)
    return math.nan, math.nan


def a02_errors(outdir: Path, n: int) -> dict[str, float]:
    """The first crank (links.csv's first link) of a run against the exact
    motion (a02_crank_errors), with ``balance``: the worst energy balance of
    energy.csv over G = ((N+1)/2 + N) m g L."""
    links = columns(outdir / "links.csv")
    errors = a02_crank_errors(n, links["t"], links["angle"], links["omega"])
    energy = outdir / "energy.csv"
    moment = ((n + 1) / 2 + n) * 9.81
    errors["balance"] = float(np.max(np.abs(columns(energy)["balance"]))) / moment if energy.is_file() else math.nan
    return errors


def a02_crank_errors(n: int, times, angle, rate) -> dict[str, float]:
    """The first crank's angle and rate at the times against the exact motion
    of the chain of n four-bars (fekap.exact.a02: the energy integral and its
    quadrature):

    - ``angle``, ``rate``: the worst angle (rad) and rate (rad/s) errors at the
      same time, over every time;
    - ``angle_before``, ``rate_before``: the same before the first change point
      (t <= 0.7 s: the integrator's error alone);
    - ``energy``, ``rate_away``: the worst rate error against the energy
      integral at the computed angle, and against the exact rate at the same
      time, both more than 0.15 rad from the change points (where the elastic
      bars take a kick);
    - ``last``: the last angle."""
    times, angle, rate = np.asarray(times, float), np.asarray(angle, float), np.asarray(rate, float)
    theta, omega = a02_exact.exact(n, times)
    angle_error, rate_error = np.abs(angle - theta), np.abs(rate - omega)
    away = np.abs(np.sin(theta)) > math.sin(0.15)
    before = times <= A02_FIRST_CHANGE
    return {"angle": float(angle_error.max()), "rate": float(rate_error.max()),
            "angle_before": float(angle_error[before].max()), "rate_before": float(rate_error[before].max()),
            "energy": float(np.max(np.abs(rate - a02_exact.rate(n, angle))[away])),
            "rate_away": float(np.max(rate_error[away])), "last": float(angle[-1])}


def spin_up_hub_angle(times) -> np.ndarray:
    """The hub's rotation at the times: the spin-up deck's drive table (the
    natural cubic spline through its knots, as FEKAP drives it). Not links.csv's
    angle, which is the beam's chord direction and so turns with its bending."""
    from fekap.models import spin_up as spin_up_deck

    return np.array([spin_up_deck.table_motion(float(t))[0] for t in np.asarray(times)])


def spin_up_tip(outdir: Path, tip: str = "T") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times and the tip's axial stretch and transverse deflection in the hub's
    frame (the drive's rotation, spin_up_hub_angle) of a spin-up run."""
    points = columns(outdir / "points.csv", tip)
    return hub_frame(points["t"], points["x"], points["y"], spin_up_hub_angle(points["t"]))


def hub_frame(times, x, y, angle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times, and the tip (x, y) in the frame turned by `angle`: along the
    undeformed beam minus its length, and across it."""
    x, y, angle = np.asarray(x), np.asarray(y), np.asarray(angle)
    along = x * np.cos(angle) + y * np.sin(angle) - SPIN_UP_LENGTH
    across = -x * np.sin(angle) + y * np.cos(angle)
    return np.asarray(times), along, across


def spin_up_features(times, values) -> dict[str, float]:
    """Peak (most negative) transverse deflection and its time (the parabola
    through the three samples around it), the value at t = 15 s and the
    largest magnitude after t = 15 s (the residual vibration)."""
    times, values = np.asarray(times), np.asarray(values)
    k = int(np.argmin(values))
    if 0 < k < len(values) - 1:
        y0, y1, y2 = values[k - 1:k + 2]
        h = times[k + 1] - times[k]
        s = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
        peak, t_peak = y1 - 0.25 * (y0 - y2) * s, times[k] + s * h
    else:
        peak, t_peak = values[k], times[k]
    at15 = float(np.interp(15.0, times, values))
    after = np.abs(values[times >= 15.0])
    return {"peak": float(peak), "t_peak": float(t_peak), "at15": at15, "residual": float(after.max())}
