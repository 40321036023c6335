"""The exact motion of the IFToMM A02 N-four-bar in dynamics (decks/dynamics/a02-*.deck):
with rigid bars the chain is one pendulum about the crank pivots, of inertia
I = (N+1) m L^2/3 + N m L^2 and gravity moment G cos(theta), G = ((N+1)/2 + N) m g L
(m = 1 kg, L = 1 m, g = 9.81), started at theta = pi/2 with the rate -1 rad/s
(crank tips at 1 m/s along x). Its energy integral gives the rate at every angle,

    omega(theta) = -sqrt(1 + 2 G/I (1 - sin theta)),

never zero, and the time at which the crank passes theta is the quadrature

    t(theta) = int_theta^(pi/2) dphi / |omega(phi)|,

here by 20-point Gauss-Legendre panels of 1/16 rad (the integrand is analytic:
exact to round-off, about 1e-15 s over 20 s); theta(t) by Newton on t(theta) = t.

Usage: scripts/python -m fekap.exact.a02 N T...   (prints t, theta, omega)
"""

from __future__ import annotations

import math
import sys

import numpy as np

PANEL = 1.0 / 16
NODES, WEIGHTS = np.polynomial.legendre.leggauss(20)


def constants(n: int) -> tuple[float, float]:
    """G/I and I of the chain of n four-bars."""
    inertia = (n + 1) / 3 + n
    moment = ((n + 1) / 2 + n) * 9.81
    return moment / inertia, inertia


def rate(n: int, theta):
    """The crank rate at the angle theta (energy integral)."""
    ratio, _ = constants(n)
    return -np.sqrt(1 + 2 * ratio * (1 - np.sin(theta)))


def _segment(n: int, a, b):
    """int_a^b dphi/|omega| by one Gauss-Legendre rule on each [a, b] (arrays)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    mid, half = (a + b) / 2, (b - a) / 2
    phi = mid[..., None] + half[..., None] * NODES
    return half * np.sum(WEIGHTS / np.sqrt(1 + 2 * constants(n)[0] * (1 - np.sin(phi))), axis=-1)


def exact(n: int, times) -> tuple[np.ndarray, np.ndarray]:
    """Angle and rate of the first crank at the times (seconds, >= 0)."""
    times = np.asarray(times, float)
    # Panels from pi/2 downwards, far enough for the last time (|omega| >= 1).
    count = int(math.ceil((times.max() * math.sqrt(1 + 4 * constants(n)[0]) + 1) / PANEL)) + 2
    edges = math.pi / 2 - PANEL * np.arange(count + 1)
    cumulative = np.concatenate([[0.0], np.cumsum(_segment(n, edges[1:], edges[:-1]))])
    k = np.clip(np.searchsorted(cumulative, times) - 1, 0, count - 1)
    # Start inside the panel by linear interpolation, then Newton on t(theta) = t.
    theta = edges[k] - PANEL * (times - cumulative[k]) / (cumulative[k + 1] - cumulative[k])
    for _ in range(8):
        t_theta = cumulative[k] + _segment(n, theta, edges[k])
        theta = theta + (t_theta - times) * np.abs(rate(n, theta))
    return theta, rate(n, theta)


def main(argv: list[str]) -> int:
    n = int(argv[0])
    times = [float(t) for t in argv[1:]]
    theta, omega = exact(n, times)
    for t, a, w in zip(times, theta, omega):
        print(f"{t:.6f} {a:.15f} {w:.15f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
