"""An independent solution of the spin-up beam (decks/dynamics/spin-up.deck):
the transverse tip deflection in the hub's frame by a linear rotating-beam
model with centrifugal (geometric) stiffening, as in Kane, Ryan & Banerjee
(J. Guidance 10(2), 1987), by a Ritz expansion in cantilever modes,
integrated by classical Runge-Kutta. numpy only (test/app/test_dynamics.py
imports it).

The beam (L = 10, EI = 1.4e4, rhoA = 1.2) is clamped at the hub's axis; the
hub turns by theta(t) = (6/15) [t^2/2 + (15/(2 pi))^2 (cos(2 pi t/15) - 1)]
up to t = 15 s, then at 6 rad/s. In the hub's frame (x along the undeformed
beam, v across it) the transverse deflection v(x, t) obeys, to first order
in v and with the axial stretch (about 5e-4) left out,

    rhoA (v_tt - w^2 v + a x) + EI v_xxxx - (N v_x)_x = 0,
    N(x, t) = rhoA w^2 (L^2 - x^2) / 2                    (centrifugal tension)

(w = theta', a = theta''), and with v = sum phi_i(x) q_i(t), phi_i the
clamped-free modes (int phi_i^2 = L),

    M q'' + (K + w^2 (G - M)) q = -a f,
    M = rhoA L I, K = EI diag(beta_i^4) L, G_ij = int N/w^2 phi_i' phi_j',
    f_i = rhoA int x phi_i.

Shear (EI/(GA L^2) = 1.4e-5) and rotary inertia (rhoI/(rhoA L^2) = 5e-6)
change the first frequency by less than 1e-5 and are left out.

    scripts/python -m fekap.exact.spin_up [--modes N] [--dt DT] [--law exact|table]

prints the peak transverse tip deflection and its time, its value at
t = 15 s and its largest magnitude after t = 15 s; `--law table` drives the
model with the deck's cubic-spline table instead of the published law (the
difference is the table's share of any difference from FEKAP).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from fekap.dynamics import spin_up_features as features
from fekap.models import spin_up as spin_up_deck

L, EI, RHOA = 10.0, 1.4e4, 1.2
T_SPIN, OMEGA = 15.0, 6.0


def hub_rates(t: float) -> tuple[float, float]:
    """Angular velocity and acceleration of the published hub law."""
    if t >= T_SPIN:
        return OMEGA, 0.0
    c = 2 * math.pi / T_SPIN
    return OMEGA / T_SPIN * (t - math.sin(c * t) / c), OMEGA / T_SPIN * (1 - math.cos(c * t))


def table_rates(t: float) -> tuple[float, float]:
    """Angular velocity and acceleration of the deck's drive: the natural
    cubic spline through the law's values (python/fekap/models/spin_up.py's table)."""
    return spin_up_deck.table_motion(t)[1:]


def cantilever_betas(n: int) -> np.ndarray:
    """beta_i L of the first n clamped-free modes: roots of 1 + cos(b) cosh(b)."""
    roots = []
    for i in range(n):
        b = (2 * i + 1) * math.pi / 2 if i > 0 else 1.875
        for _ in range(50):  # Newton on cos(b) + 1/cosh(b) = 0
            f = math.cos(b) + 1 / math.cosh(b)
            df = -math.sin(b) - math.tanh(b) / math.cosh(b)
            b -= f / df
        roots.append(b)
    return np.array(roots) / L


def mode_shapes(beta: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """phi and phi' of the clamped-free mode of wave number beta at x,
    written without the cancellation of cosh - sigma sinh for large beta L."""
    bl = beta * L
    s = (math.sinh(bl) + math.sin(bl)) if bl < 700 else math.inf
    one_minus_sigma = (-math.exp(-bl) + math.sin(bl) - math.cos(bl)) / s
    sigma = 1 - one_minus_sigma
    grow = one_minus_sigma * np.exp(beta * x)   # (1 - sigma) e^{bx}, bounded
    decay = (1 + sigma) * np.exp(-beta * x)
    ch_sh = 0.5 * (grow + decay)                # cosh - sigma sinh
    sh_ch = 0.5 * (grow - decay)                # sinh - sigma cosh
    bx = beta * x
    phi = ch_sh - np.cos(bx) + sigma * np.sin(bx)
    dphi = beta * (sh_ch + np.sin(bx) + sigma * np.cos(bx))
    return phi, dphi


def ritz_matrices(n: int):
    """M, K, G (centrifugal stiffness per w^2), f and phi(L) of n modes."""
    betas = cantilever_betas(n)
    xg, wg = np.polynomial.legendre.leggauss(400)
    x = L / 2 * (xg + 1)
    w = L / 2 * wg
    phis, dphis = zip(*(mode_shapes(b, x) for b in betas))
    phi, dphi = np.array(phis), np.array(dphis)
    tension = RHOA * (L * L - x * x) / 2
    mass = RHOA * (phi * w) @ phi.T
    stiff = EI * np.diag(betas ** 4) * L
    geometric = (dphi * tension * w) @ dphi.T
    force = RHOA * (phi * w) @ x
    tip = np.array([mode_shapes(b, np.array([L]))[0][0] for b in betas])
    return mass, stiff, geometric, force, tip


def simulate(n_modes: int = 6, dt: float = 1e-3, t_end: float = 30.0, law: str = "exact",
             every: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Times and transverse tip deflections (every `every` steps) from rest."""
    mass, stiff, geometric, force, tip = ritz_matrices(n_modes)
    minv = np.linalg.inv(mass)
    rates = hub_rates if law == "exact" else table_rates

    def deriv(t: float, y: np.ndarray) -> np.ndarray:
        w, a = rates(t)
        q, qd = y[:n_modes], y[n_modes:]
        qdd = minv @ (-(stiff + w * w * (geometric - mass)) @ q - a * force)
        return np.concatenate([qd, qdd])

    steps = int(round(t_end / dt))
    y = np.zeros(2 * n_modes)
    times, values = [0.0], [0.0]
    for k in range(steps):
        t = k * dt
        k1 = deriv(t, y)
        k2 = deriv(t + dt / 2, y + dt / 2 * k1)
        k3 = deriv(t + dt / 2, y + dt / 2 * k2)
        k4 = deriv(t + dt, y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (k + 1) % every == 0:
            times.append((k + 1) * dt)
            values.append(float(tip @ y[:n_modes]))
    return np.array(times), np.array(values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", type=int, default=6)
    parser.add_argument("--dt", type=float, default=1e-3)
    parser.add_argument("--t-end", type=float, default=30.0)
    parser.add_argument("--law", choices=("exact", "table"), default="exact")
    args = parser.parse_args()
    times, values = simulate(args.modes, args.dt, args.t_end, args.law)
    f = features(times, values)
    print(f"spin-up beam, linear Ritz model, {args.modes} cantilever modes, RK4 dt {args.dt:g}, {args.law} law")
    print(f"  peak transverse tip deflection {f['peak']:.6f} at t = {f['t_peak']:.4f} s; "
          f"at t = 15: {f['at15']:.6f}; largest |v| after t = 15: {f['residual']:.4e}")


if __name__ == "__main__":
    main()
