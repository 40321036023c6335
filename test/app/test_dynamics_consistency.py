"""Checks of the dynamics integrators against independent answers (issue 34):
energy-momentum's strain dissipation on a stiff linear oscillator (the ratio
of successive strains is -rho_inf, from the midpoint rule's amplification
alone, not from em_dissipation)."""

from __future__ import annotations

from pathlib import Path

import pytest

from apptest import check, point_series, run_fekap

#: A massless bar of axial stiffness EA along x, pinned at A, a point mass m at B, and
#: gravity g along the bar: B's axial motion is a linear oscillator of omega^2 = EA/(m L)
#: about the static stretch m g L / EA (the Simo-Reissner bar's axial strain is linear in
#: B's x along its axis; y and the rotations stay zero by symmetry).
OSCILLATOR = """TITLe  stiff axial oscillator
SECTions
  bar  EA={ea}  kGA={ea}  EI=1e2
NODEs
  A  0  0
  B  1  0
LINKs
  AB  A  B  bar  1
SUPPorts
  A  pin
MASSes
  B  {mass}
GRAVity  {g}  0
ANALysis
  type dynamics
  integrator energy-momentum {rho}
{extra}  time 0 {t_end} {dt}
OUTPut
  track B
END
"""


@pytest.mark.parametrize("rho_inf", [0.8, 0.5])
@pytest.mark.parametrize("omega_h", [1.0e3, 1.0e4])
def test_energy_momentum_strain_ratio_is_minus_rho_inf(tmp_path: Path, rho_inf: float, omega_h: float) -> None:
    """At omega h >> 1 the midpoint rule with the dissipative discrete
    gradient (stress D (eps0 + eps1)/2 + chi/2 D Delta eps) leaves the mass
    term O(1/(omega h)^2) behind: (1 + chi) u1 = -(1 - chi) u0, so the
    deviation from the static stretch shrinks by -rho_inf each step once chi =
    (1 - rho)/(1 + rho). The 2 x 2 amplification matrix of (u, v) has
    eigenvalues -rho_inf and -1 + O(1/(omega h)^2); from rest the first ratios
    are -rho_inf within 25/(omega h)^2 (computed from the matrix). A chi off by
    a factor 2 moves the ratio by 0.1 or more."""
    ea, mass, length, g = 1.0e4, 1.0, 1.0, 10.0
    omega = (ea / (mass * length)) ** 0.5
    dt = omega_h / omega
    deck = tmp_path / "oscillator.deck"
    deck.write_text(OSCILLATOR.format(ea=ea, mass=mass, g=g, rho=rho_inf, t_end=4 * dt, dt=dt,
                                      extra=""))
    run = run_fekap(str(deck), "-o", str(tmp_path / "out"), "-q")
    check(run.returncode == 0, f"fekap failed: {run.stderr}")
    x = point_series(tmp_path / "out", "B")["x"]
    check(len(x) == 5, f"expected 5 rows of B, got {len(x)}")
    static = mass * g * length / ea
    deviation = [xi - length - static for xi in x]
    check(abs(deviation[0] + static) < 1e-15, f"not started unstrained: {deviation[0]!r}")
    for n in range(2):
        ratio = deviation[n + 1] / deviation[n]
        check(abs(ratio + rho_inf) < 25 / omega_h**2,
              f"step {n + 1}: strain ratio {ratio!r}, want {-rho_inf} (omega h {omega_h:g})")

