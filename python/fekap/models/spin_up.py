"""Write the spin-up beam deck (Simo & Vu-Quoc 1986) for dynamics:
decks/dynamics/spin-up.deck.

A free beam (L = 10, EA = 2.8e7, GA = 1e7, EI = 1.4e4, rhoA = 1.2, rhoI = 6e-4)
clamped to a hub whose angle is (6/15) [t^2/2 + (15/(2 pi))^2 (cos(2 pi t/15) - 1)]
up to t = 15 s, then 6 rad/s. FEKAP's drive laws have no such law; the table
law (a natural cubic spline) through its values every 0.25 s up to 15 s and
every second after is within 2e-6 rad of it up to 15 s (this script prints
the largest difference on standard error) and turns at 6 rad/s after it to
the spline's decay of the kink in the third derivative at 15 s.

    scripts/python -m fekap.models.spin_up > decks/dynamics/spin-up.deck
"""
import math
import sys

import numpy as np


def hub(t: float) -> float:
    if t <= 15:
        return 6 / 15 * (t * t / 2 + (15 / (2 * math.pi)) ** 2 * (math.cos(2 * math.pi * t / 15) - 1))
    return 45 + 6 * (t - 15)


def natural_spline(ts, vs):
    """Second derivatives of the natural cubic spline through (ts, vs)."""
    n = len(ts)
    a = np.zeros((n, n))
    b = np.zeros(n)
    a[0, 0] = a[-1, -1] = 1
    for i in range(1, n - 1):
        h0, h1 = ts[i] - ts[i - 1], ts[i + 1] - ts[i]
        a[i, i - 1:i + 2] = [h0, 2 * (h0 + h1), h1]
        b[i] = 6 * ((vs[i + 1] - vs[i]) / h1 - (vs[i] - vs[i - 1]) / h0)
    return np.linalg.solve(a, b)


def spline_value(ts, vs, ms, t):
    i = min(max(np.searchsorted(ts, t) - 1, 0), len(ts) - 2)
    h = ts[i + 1] - ts[i]
    x, y = (ts[i + 1] - t) / h, (t - ts[i]) / h
    return x * vs[i] + y * vs[i + 1] + ((x ** 3 - x) * ms[i] + (y ** 3 - y) * ms[i + 1]) * h * h / 6


def knots() -> tuple[list[float], list[float], np.ndarray]:
    """The drive table's times and angles (every 0.25 s up to 15 s, every
    second after) and its natural spline's second derivatives."""
    ts = [0.25 * k for k in range(61)] + [float(t) for t in range(16, 41)]
    vs = [hub(t) for t in ts]
    return ts, vs, natural_spline(ts, vs)


def table_motion(t: float) -> tuple[float, float, float]:
    """Angle, rate and angular acceleration of the deck's drive (the natural
    cubic spline through the knots) at time t."""
    ts, vs, ms = _KNOTS
    i = min(max(int(np.searchsorted(ts, t)) - 1, 0), len(ts) - 2)
    h = ts[i + 1] - ts[i]
    x, y = (ts[i + 1] - t) / h, (t - ts[i]) / h
    angle = x * vs[i] + y * vs[i + 1] + ((x ** 3 - x) * ms[i] + (y ** 3 - y) * ms[i + 1]) * h * h / 6
    rate = (vs[i + 1] - vs[i]) / h + ((1 - 3 * x * x) * ms[i] + (3 * y * y - 1) * ms[i + 1]) * h / 6
    return float(angle), float(rate), float(x * ms[i] + y * ms[i + 1])


_KNOTS = knots()


def main() -> None:
    ts, vs, ms = knots()
    worst = max(abs(spline_value(ts, vs, ms, t) - hub(t)) for t in np.linspace(0, 15, 3001))
    print(f"largest difference of the table from the hub law up to 15 s: {worst:.3g} rad", file=sys.stderr)
    table = " ".join(f"{t:g} {v:.12g}" for t, v in zip(ts, vs))
    sys.stdout.write(f"""* Spin-up of a flexible beam (Simo & Vu-Quoc 1986), written by fekap.models.spin_up:
* a beam of length 10 clamped to a hub whose angle rises smoothly to 6 rad/s at
* t = 15 s (a table through the published law, within {worst:.1g} rad of it), then
* turns at 6 rad/s. The tip's axial stretch settles at the centrifugal value
* 5.1432e-4 (rhoA omega^2 L^3 / (3 EA) = 5.1429e-4 plus the geometric stiffening);
* test/app/test_dynamics.py.
TITLe   Spin-up beam (Simo and Vu-Quoc)
PARAmeters
  t_end = 30
  dt = 0.01       ! fekap --set dt=...
SECTions
  beam  EA=2.8e7  kGA=1e7  EI=1.4e4  rhoA=1.2  rhoI=6e-4
NODEs
  O   0  0
  T  10  0
LINKs
  OT  O  T  beam  10
SUPPorts
  O  pin
DRIVes
  rotation OT  table {table}
ANALysis
  type dynamics
  time 0 t_end dt
OUTPut
  units length=m time=s
  track T
END
""")


if __name__ == "__main__":
    main()
