"""Checks of the dynamics integrators against independent answers (issue 34):
energy-momentum's strain dissipation on a stiff linear oscillator (the ratio
of successive strains is -rho_inf, from the midpoint rule's amplification
alone, not from em_dissipation)."""

from __future__ import annotations

from pathlib import Path

import pytest

from apptest import ROOT, check, point_series, read_rows, run_fekap

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


#: A uniform rod (no point masses) pinned at A, released 30 degrees above the horizontal.
ROD_PENDULUM = """TITLe  uniform rod pendulum
SECTions
  rod  EA=1e10  kGA=1e10  EI=1e9  rhoA=6
NODEs
  A  0  0
  B  cos(pi/6)  sin(pi/6)
LINKs
  AB  A  B  rod  4
SUPPorts
  A  pin
GRAVity  0  -9.81
ANALysis
  type dynamics
  time 0 0.05 1e-3
END
"""


def node_balance(outdir: Path, masses: dict[str, float], gravity: tuple[float, float]) -> float:
    """The largest imbalance, relative to the step's largest row, of every node with a
    support or drive row at every step: the joint rows at the node (each link
    end's force from its node's pin) plus m (a - g) of its point mass must be what its
    support, drive and slider rows apply."""
    rows = read_rows(outdir / "reactions.csv")
    check(bool(rows), f"no reactions in {outdir}")
    accel = {}
    for node in masses:
        series = point_series(outdir, node)
        for step, ax, ay in zip(series["step"], series["ax"], series["ay"]):
            accel[int(step), node] = (ax, ay)
    sums: dict[tuple[int, str], list[float]] = {}
    scale: dict[int, float] = {}
    for row in rows:
        step, node = int(row["step"]), row["node"]
        force = [float(row["fx"]), float(row["fy"])]
        sign = 1.0 if row["kind"] == "joint" else -1.0
        total = sums.setdefault((step, node), [0.0, 0.0])
        total[0] += sign * force[0]
        total[1] += sign * force[1]
        scale[step] = max(scale.get(step, 0.0), abs(force[0]), abs(force[1]))
    # The joint rows at a free node add up to the equations' residual there (Newton's
    # tolerance, the round-off of stiff links' forces): only the constrained nodes' rows
    # are the same numbers.
    # A slider's slave is a free node too (its row is the penalty spring's force).
    held = {(int(r["step"]), r["node"]) for r in rows if r["kind"] in ("support", "drive")}
    worst = 0.0
    for (step, node), total in sums.items():
        if (step, node) not in held:
            continue
        if node in masses:
            ax, ay = accel[step, node]
            total = [total[0] + masses[node] * (ax - gravity[0]), total[1] + masses[node] * (ay - gravity[1])]
        if scale[step] > 0:
            worst = max(worst, max(abs(total[0]), abs(total[1])) / scale[step])
    return worst


@pytest.mark.parametrize("integrator", ["generalized-alpha", "energy-momentum 0.8", "energy-momentum 1"])
@pytest.mark.parametrize("deck, masses, gravity", [
    ("rod-pendulum", {}, (0.0, -9.81)),
    ("pendulum.deck", {"B": 1.0}, (0.0, -9.81)),
    ("slider-crank.deck", {}, (0.0, 0.0)),
    ("a02-n2.deck", {}, (0.0, -9.81)),
])
def test_every_node_is_in_equilibrium_under_its_reactions(tmp_path: Path, deck: str, masses: dict[str, float],
                                                          gravity: tuple[float, float], integrator: str) -> None:
    """Issue 34 item 4: at each node the joint rows of reactions.csv add up to its
    support, drive and slider rows (with m (a - g) of a point mass), to 1e-10 of the
    step's largest row, at every step, under both integrators (energy-momentum's rows
    are those of its step's discrete-gradient equations)."""
    if deck == "rod-pendulum":
        text = ROD_PENDULUM
    else:
        text = (ROOT / "decks" / "dynamics" / deck).read_text()
    check("  type dynamics\n" in text or "ANALysis\n" in text, f"{deck}: no ANALysis block")
    text = text.replace("ANALysis\n", f"ANALysis\n  integrator {integrator}\n", 1)
    path = tmp_path / "deck.deck"
    path.write_text(text)
    run = run_fekap(str(path), "-o", str(tmp_path / "out"), "-q", "--set", "t_end=0.01")
    if run.returncode != 0 and "t_end" in run.stderr:
        run = run_fekap(str(path), "-o", str(tmp_path / "out"), "-q")
    check(run.returncode == 0, f"fekap failed: {run.stderr}")
    worst = node_balance(tmp_path / "out", masses, gravity)
    check(worst < 1e-10, f"{deck} with {integrator}: a node's rows are out of balance by {worst:.3e} of the largest")

