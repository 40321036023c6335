"""Rigid pendulums by Runge-Kutta: the references of the dynamics tests and studies whose
links are stiff (test_stiff_links, test_error_estimate, studies/accuracy).

The double pendulum has two unit point masses on massless links of length 1, its angles
a, b measured from the downward vertical; its rate is Lagrange's equations solved for the
angular accelerations."""

from __future__ import annotations

import math

import numpy as np

#: Gravity of the decks these references stand beside (m/s^2).
G = 9.81


def double_pendulum_rate(s: np.ndarray) -> np.ndarray:
    """d/dt (a, b, a', b') of the double pendulum (m1 = m2 = 1, L1 = L2 = 1)."""
    a, b, wa, wb = s
    d = a - b
    den = 3 - math.cos(2 * d)
    acc_a = (-3 * G * math.sin(a) - G * math.sin(a - 2 * b) - 2 * math.sin(d) * (wb**2 + wa**2 * math.cos(d))) / den
    acc_b = 2 * math.sin(d) * (2 * wa**2 + 2 * G * math.cos(a) + wb**2 * math.cos(d)) / den
    return np.array([wa, wb, acc_a, acc_b])


def double_pendulum_tip(a: float, b: float) -> tuple[float, float]:
    """The outer mass (x, y) at angles a, b, the pivot at the origin."""
    return math.sin(a) + math.sin(b), -math.cos(a) - math.cos(b)


def rk4_states(rate, state, h: float, n: int) -> np.ndarray:
    """Classical RK4 of y' = rate(y) from `state`: all n + 1 states at step h, one a row."""
    out = np.empty((n + 1, len(state)))
    y = np.array(state, dtype=float)
    out[0] = y
    for i in range(n):
        k1 = rate(y)
        k2 = rate(y + 0.5 * h * k1)
        k3 = rate(y + 0.5 * h * k2)
        k4 = rate(y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out[i + 1] = y
    return out
