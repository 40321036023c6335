"""Checks of the dynamics integrators against independent answers (issue 34):
energy-momentum's strain dissipation on a stiff linear oscillator (the ratio
of successive strains is -rho_inf, from the midpoint rule's amplification
alone, not from em_dissipation)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
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
                                      extra="  start unstrained\n"))
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
    support, drive or slider row at every step: the joint rows at the node (each link
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
    # are the same numbers. A slider's slave is a free node too, but its row is the
    # penalty spring's force, which the step's equations balance with the joint rows
    # and the slave's inertia to the Newton tolerance: its nodes are checked as well.
    held = {(int(r["step"]), r["node"]) for r in rows if r["kind"] in ("support", "drive", "slider")}
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
    ("slider-drop.deck", {"B": 2.0}, (0.0, -9.81)),
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


# The consistent start (issue 34 item 3): at t = 0 the reactions are the rigid-body pin
# forces and the accelerations the rigid-body ones, with stiff links (EA 1e10 to 1e12).

#: A driven stiff massless crank OA (r = 0.15) at 150 rad/s and a massless rod AB (l = 0.30)
#: to a slider B on a ground guide along x, point masses at A and B, gravity: at t = 0 the
#: mechanism is stretched along x (theta = 0).
DRIVEN_CRANK = """TITLe  driven stiff massless slider-crank
SECTions
  stiff  EA=1e12  kGA=1e12  EI=1e10
NODEs
  O  0     0
  A  0.15  0
  B  0.45  0
LINKs
  OA  O  A  stiff  2
  AB  A  B  stiff  3
SUPPorts
  O  pin
SLIDelines
  slider  B  guide -1 0 1 0  pin
DRIVes
  rotation OA  rate 150
MASSes
  A  {m_a}
  B  {m_b}
GRAVity  0  -9.81
ANALysis
  type dynamics
{extra}  time 0 {t_end} 1e-5
OUTPut
  track A B
END
"""


def rows_at(outdir: Path, step: int) -> dict[tuple[str, str, str], tuple[float, float, float]]:
    """reactions.csv's rows of one step by (kind, link, node)."""
    return {(r["kind"], r["link"], r["node"]): (float(r["fx"]), float(r["fy"]), float(r["m"]))
            for r in read_rows(outdir / "reactions.csv") if int(r["step"]) == step}


def run_text(tmp_path: Path, name: str, text: str) -> Path:
    deck = tmp_path / f"{name}.deck"
    deck.write_text(text)
    out = tmp_path / name
    run = run_fekap(str(deck), "-o", str(out), "-q")
    check(run.returncode == 0, f"{name} failed: {run.stderr}")
    return out


def close(got: float, want: float, scale: float, tol: float = 1e-6) -> bool:
    return abs(got - want) <= tol * scale


def test_driven_massless_crank_starts_on_the_rigid_motion(tmp_path: Path) -> None:
    """The crank's tip starts at -r omega^2 = -3375 m/s^2 and the slider at
    -r omega^2 (1 + r/l) = -5062.5 (dead centre, theta'' = 0, the rod's phi'' = 0);
    the rod is a two-force member along x, so the pin O carries
    (m_A a_A + m_B a_B, m_A g), the guide m_B g, the drive the moment m_A g r:
    all to 1e-6. The unstrained start has the tip at rest (a = 0, its
    acceleration from M a = -R with nothing strained)."""
    m_a, m_b, r, l, omega, g = 0.5, 2.0, 0.15, 0.30, 150.0, 9.81
    # The default start (no start line) is the consistent one.
    out = run_text(tmp_path, "crank", DRIVEN_CRANK.format(m_a=m_a, m_b=m_b, extra="", t_end=1e-4))
    a_a = -r * omega**2
    a_b = -r * omega**2 * (1 + r / l)
    tip, slider = point_series(out, "A"), point_series(out, "B")
    check(close(tip["ax"][0], a_a, abs(a_a)) and abs(tip["ay"][0]) < 1e-6 * abs(a_a),
          f"tip acceleration ({tip['ax'][0]!r}, {tip['ay'][0]!r}), want ({a_a}, 0)")
    check(close(slider["ax"][0], a_b, abs(a_b)), f"slider acceleration {slider['ax'][0]!r}, want {a_b}")
    rows = rows_at(out, 0)
    pin = rows["support", "", "O"]
    want_pin = (m_a * a_a + m_b * a_b, m_a * g)
    scale = abs(want_pin[0])
    check(close(pin[0], want_pin[0], scale) and close(pin[1], want_pin[1], scale),
          f"pin O carries {pin[:2]}, want {want_pin}")
    guide = rows["slider", "", "B"]
    check(close(guide[0], 0.0, scale) and close(guide[1], m_b * g, scale),
          f"guide force {guide[:2]}, want (0, {m_b * g})")
    drive = rows["drive", "OA", "O"]
    check(close(drive[2], m_a * g * r, scale * r), f"drive moment {drive[2]!r}, want {m_a * g * r}")
    unstrained = run_text(tmp_path, "crank-unstrained",
                          DRIVEN_CRANK.format(m_a=m_a, m_b=m_b, extra="  start unstrained\n", t_end=1e-4))
    check(abs(point_series(unstrained, "A")["ax"][0]) < 1e-6 * abs(a_a), "start unstrained no longer starts at rest")


#: A uniform stiff rod (mass 6 kg, L = 1) pinned at A, released from rest theta0 above the horizontal.
ROD = """TITLe  uniform rod pendulum
SECTions
  rod  EA={ea}  kGA={ea}  EI={ei}  rhoA=6
NODEs
  A  0  0
  B  cos({theta0})  sin({theta0})
LINKs
  AB  A  B  rod  4
SUPPorts
  A  pin
GRAVity  0  -9.81
ANALysis
  type dynamics
{extra}  time 0 {t_end} {dt}
OUTPut
  track B
END
"""


def rod_reaction(theta: float, omega: float, m: float = 6.0, length: float = 1.0, g: float = 9.81
                 ) -> tuple[float, float]:
    """The pin force on a uniform rigid rod at angle theta above the horizontal turning at omega:
    m (a_G - g) with theta'' = -3 g cos(theta) / (2 L)."""
    alpha = -3 * g * math.cos(theta) / (2 * length)
    ax = length / 2 * (-alpha * math.sin(theta) - omega**2 * math.cos(theta))
    ay = length / 2 * (alpha * math.cos(theta) - omega**2 * math.sin(theta))
    return m * ax, m * (ay + g)


def rod_motion(theta0: float, times: list[float], g: float = 9.81, length: float = 1.0) -> list[tuple[float, float]]:
    """theta and omega of the rigid rod at the given times (RK4, 1e-6 s steps from rest)."""
    def rate(y: tuple[float, float]) -> tuple[float, float]:
        return y[1], -3 * g * math.cos(y[0]) / (2 * length)
    y, t, h, out = (theta0, 0.0), 0.0, 1e-6, []
    for target in times:
        while t < target - 1e-12:
            step = min(h, target - t)
            k1 = rate(y)
            k2 = rate((y[0] + step / 2 * k1[0], y[1] + step / 2 * k1[1]))
            k3 = rate((y[0] + step / 2 * k2[0], y[1] + step / 2 * k2[1]))
            k4 = rate((y[0] + step * k3[0], y[1] + step * k3[1]))
            y = (y[0] + step / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]),
                 y[1] + step / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))
            t += step
        out.append(y)
    return out


@pytest.mark.parametrize("ea", [1e10, 1e12])
@pytest.mark.parametrize("integrator", ["generalized-alpha", "energy-momentum 0.8"])
def test_rod_pendulum_reactions_from_the_start(tmp_path: Path, ea: float, integrator: str) -> None:
    """The pin force of a stiff uniform rod released 30 degrees above the horizontal:
    at t = 0 the rigid rod's m (a_G - g) to 1e-6, and over the first 20 steps
    (dt 1e-3) within 1e-3 of the rigid rod's (no stiff-mode ringing: the
    unstrained start's pin force starts near 0 and swings with the axial mode)."""
    theta0 = math.pi / 6
    text = ROD.format(ea=ea, ei=ea / 100, theta0="pi/6", extra=f"  integrator {integrator}\n  start consistent\n",
                      t_end=0.02, dt=1e-3)
    out = run_text(tmp_path, "rod", text)
    pins = {int(r["step"]): (float(r["fx"]), float(r["fy"])) for r in read_rows(out / "reactions.csv")
            if r["kind"] == "support"}
    want0 = rod_reaction(theta0, 0.0)
    scale = math.hypot(*want0)
    check(close(pins[0][0], want0[0], scale) and close(pins[0][1], want0[1], scale),
          f"t = 0: pin force {pins[0]}, rigid {want0}")
    steps = sorted(pins)
    motion = rod_motion(theta0, [1e-3 * s for s in steps])
    worst = max(math.hypot(pins[s][0] - rod_reaction(*motion[i])[0], pins[s][1] - rod_reaction(*motion[i])[1])
                for i, s in enumerate(steps)) / scale
    check(worst < 1e-3, f"the pin force leaves the rigid rod's by {worst:.2e} of it in the first 20 steps")


def test_stiff_slider_crank_deck_starts_with_the_rigid_pin_force(tmp_path: Path) -> None:
    """decks/dynamics/slider-crank.deck with links 1e4 times stiffer (crank 0.15 m at
    150 rad/s, rod 0.30 m of steel, dead centre at t = 0, no gravity): the rigid
    accelerations are along x (crank and rod angular accelerations vanish), the
    massless slider's guide takes no x force, so the pin O carries m1 a_G1 + m2 a_G2
    along x, a_G1 = -r w^2/2, a_G2 = -r w^2 - r^2 w^2/(2 l)."""
    text = (ROOT / "decks" / "dynamics" / "slider-crank.deck").read_text()
    check("E=2e11  G=7.7e10" in text, "the slider-crank deck's section changed")
    text = text.replace("E=2e11  G=7.7e10", "E=2e15  G=7.7e14").replace("t_end = 0.1", "t_end = 2e-4").replace(
        "  type dynamics\n", "  type dynamics\n  start consistent\n")
    out = run_text(tmp_path, "slider-crank", text)
    r, l, omega, d = 0.15, 0.30, 150.0, 0.006
    rho_a = 7870 * math.pi * d**2 / 4
    want = rho_a * r * (-r * omega**2 / 2) + rho_a * l * (-r * omega**2 - r**2 * omega**2 / (2 * l))
    pin = rows_at(out, 0)["support", "", "O"]
    check(close(pin[0], want, abs(want)) and abs(pin[1]) < 1e-6 * abs(want), f"pin O {pin[:2]}, rigid ({want}, 0)")


def slider_crank_rigid(r: float, l: float, theta: float, omega1: float, m1: float, m2: float, m_b: float,
                       j_fly: float, g: float) -> dict[str, np.ndarray | float]:
    """The rigid slider-crank at one instant, by Newton-Euler (independent of FEKAP): a
    uniform crank OA (length r, mass m1, a flywheel of inertia j_fly keyed to it at O)
    pinned at O, a uniform rod AB (l, m2), a slider of mass m_b at B on the x axis,
    crank angle theta turning at omega1, gravity (0, -g). Returns the accelerations of A
    and B, the crank's and rod's angular accelerations, and the forces: F_O (ground on
    the crank at O), F_A (the pin A on the rod), F_B (the pin B on the slider... by the
    rod: the slider's pin force on the rod is -F_B) and N (the guide on the slider, along y)."""
    o = np.zeros(2)
    a_pt = r * np.array([math.cos(theta), math.sin(theta)])
    b_pt = np.array([a_pt[0] + math.sqrt(l**2 - a_pt[1] ** 2), 0.0])
    g1, g2 = a_pt / 2, (a_pt + b_pt) / 2
    omega2 = -omega1 * a_pt[0] / (b_pt[0] - a_pt[0])
    i1, i2 = m1 * r**2 / 12 + j_fly, m2 * l**2 / 12
    grav = np.array([0.0, -g])

    def cross(s: np.ndarray) -> np.ndarray:
        """Coefficients of (Fx, Fy) in the moment s x F."""
        return np.array([-s[1], s[0]])

    def perp(s: np.ndarray) -> np.ndarray:
        """k x s: the acceleration of a point at s per unit angular acceleration."""
        return np.array([-s[1], s[0]])

    # Unknowns: a1 (2), alpha1, a2 (2), alpha2, aBx, F_O (2), F_A (2), F_B (2), N.
    a_mat, rhs = np.zeros((14, 14)), np.zeros(14)
    # Crank: m1 a1 = F_O - F_A + m1 g; I1 alpha1 = (O - G1) x F_O - (A - G1) x F_A.
    for k in range(2):
        a_mat[k, k], a_mat[k, 7 + k], a_mat[k, 9 + k], rhs[k] = m1, -1, 1, m1 * grav[k]
    a_mat[2, 2], a_mat[2, 7:9], a_mat[2, 9:11] = i1, -cross(o - g1), cross(a_pt - g1)
    # Rod: m2 a2 = F_A - F_B + m2 g; I2 alpha2 = (A - G2) x F_A - (B - G2) x F_B.
    for k in range(2):
        a_mat[3 + k, 3 + k], a_mat[3 + k, 9 + k], a_mat[3 + k, 11 + k], rhs[3 + k] = m2, -1, 1, m2 * grav[k]
    a_mat[5, 5], a_mat[5, 9:11], a_mat[5, 11:13] = i2, -cross(a_pt - g2), cross(b_pt - g2)
    # Slider: m_b (aBx, 0) = F_B + (0, N) + m_b g.
    a_mat[6, 6], a_mat[6, 11], rhs[6] = m_b, -1, 0.0
    a_mat[7, 12], a_mat[7, 13], rhs[7] = -1, -1, m_b * grav[1]
    # O fixed: a1 + alpha1 k x (O - G1) - omega1^2 (O - G1) = 0.
    a_mat[8:10, 0:2], a_mat[8:10, 2], rhs[8:10] = np.eye(2), perp(o - g1), omega1**2 * (o - g1)
    # A shared: crank's point A = rod's point A.
    a_mat[10:12, 0:2], a_mat[10:12, 2] = np.eye(2), perp(a_pt - g1)
    a_mat[10:12, 3:5], a_mat[10:12, 5] = -np.eye(2), -perp(a_pt - g2)
    rhs[10:12] = omega1**2 * (a_pt - g1) - omega2**2 * (a_pt - g2)
    # B: rod's point B = (aBx, 0).
    a_mat[12:14, 3:5], a_mat[12:14, 5], a_mat[12, 6] = np.eye(2), perp(b_pt - g2), -1
    rhs[12:14] = omega2**2 * (b_pt - g2)
    x = np.linalg.solve(a_mat, rhs)
    acc_a = x[0:2] + x[2] * perp(a_pt - g1) - omega1**2 * (a_pt - g1)
    return {"A": a_pt, "B": b_pt, "omega2": omega2, "acc_A": acc_a, "acc_B": np.array([x[6], 0.0]),
            "alpha1": x[2], "alpha2": x[5], "F_O": x[7:9], "F_A": x[9:11], "F_B": x[11:13], "N": x[13]}


#: A free slider-crank with a flywheel: crank OA (1 m, 1 kg) and rod AB (2 m, 2 kg) of stiff
#: uniform sections, a 2 kg slider at B on a ground guide along x, a flywheel of 0.5 kg m^2
#: keyed to the crank at O, released at 60 degrees with the crank turning at OMEGA1; no
#: drives, gravity: the default start.
FREE_SLIDER_CRANK = """TITLe  free slider-crank with a flywheel
SECTions
  stiff  EA={ea}  kGA={ea}  EI={ei}  rhoA=1  rhoI=0
NODEs
  O  0  0
  A  {ax!r}  {ay!r}
  B  {bx!r}  0
LINKs
  OA  O  A  stiff  2
  AB  A  B  stiff  4
SUPPorts
  O  pin
SLIDelines
  slider  B  guide -5 0 5 0  pin
MASSes
  B  2
  O  0  0.5  OA
VELOcities
  OA  0  0  {omega1!r}
  AB  {vax!r}  {vay!r}  {omega2!r}
GRAVity  0  -9.81
ANALysis
  type dynamics
  time 0 {t_end} 1e-4
OUTPut
  track A B
END
"""


@pytest.mark.parametrize("ea", [1e10, 1e11, 1e12])
@pytest.mark.parametrize("omega1", [0.0, 3.0])
def test_free_slider_crank_with_flywheel_starts_with_the_rigid_pin_forces(tmp_path: Path, ea: float,
                                                                            omega1: float) -> None:
    """The default start of a free slider-crank with a flywheel (stiff links, released at
    60 degrees at rest or turning): at t = 0 the pin O, the pin A (the rod's joint row),
    the guide (the slider row) and the accelerations of A and B are the rigid
    mechanism's (Newton-Euler, slider_crank_rigid) to 1e-6 of the largest force, or to
    the round-off of the element forces where that is larger: a strain computed from
    coordinates of size |x| on elements of length h carries eps |x| / h, a force EA
    times that (times 10 for the sum of a few elements' terms). At EA = 1e12 this is
    2e-3 N against forces of 30 N (the start's residual is 3e-4 N there, 1.4e-5 of the
    forces; it is 4e-6 N, 2e-7 of them, at EA = 1e10)."""
    r, l, theta, g = 1.0, 2.0, math.pi / 3, 9.81
    rigid = slider_crank_rigid(r, l, theta, omega1, 1.0, 2.0, 2.0, 0.5, g)
    a_pt, b_pt = rigid["A"], rigid["B"]
    text = FREE_SLIDER_CRANK.format(ea=ea, ei=ea / 100, ax=float(a_pt[0]), ay=float(a_pt[1]), bx=float(b_pt[0]),
                                    omega1=omega1, vax=float(-omega1 * a_pt[1]), vay=float(omega1 * a_pt[0]),
                                    omega2=float(rigid["omega2"]), t_end=2e-4)
    out = run_text(tmp_path, "free", text)
    listing = next(out.glob("*.lis")).read_text()
    check("; consistent (rigid-link accelerations" in listing, "the default start is not the consistent one")
    rows = rows_at(out, 0)
    scale = max(float(np.max(np.abs(rigid[k]))) for k in ("F_O", "F_A", "F_B"))
    round_off = 10 * np.finfo(float).eps * ea * float(b_pt[0]) / 0.5
    tol = max(1e-6 * scale, round_off)
    want = {("support", "", "O"): rigid["F_O"], ("joint", "AB", "A"): rigid["F_A"],
            ("slider", "", "B"): np.array([0.0, rigid["N"]])}
    for key, force in want.items():
        got = np.array(rows[key][:2])
        check(float(np.max(np.abs(got - force))) <= tol, f"{key}: {got}, rigid {force} (tolerance {tol:.1e})")
    for node in ("A", "B"):
        series = point_series(out, node)
        got = np.array([series["ax"][0], series["ay"][0]])
        acc = rigid[f"acc_{node}"]
        check(float(np.max(np.abs(got - acc))) <= 1e-6 * max(1.0, float(np.max(np.abs(acc)))),
              f"acceleration of {node}: {got}, rigid {acc}")


#: A flexible beam (2 m, EI = 20) driven from rest by a quintic under gravity: its linear
#: deflection under the weights is 0.9 (rad, at the tip) and far from small.
FLEXIBLE_DRIVEN = """TITLe  flexible driven beam
SECTions
  beam  EA=1e5  kGA=1e5  EI=20  rhoA=0.5  rhoI=1e-3
NODEs
  A  0  0
  B  2  0
LINKs
  AB  A  B  beam  6
SUPPorts
  A  pin
DRIVes
  rotation AB  polynomial 0 0 0 0.75 -0.1875
MASSes
  B  0.3
GRAVity  0  -9.81
ANALysis
  type dynamics
{extra}  time 0 0.1 0.002
END
"""


def test_links_too_flexible_for_the_consistent_start_start_unstrained(tmp_path: Path) -> None:
    """The consistent start is linear in the links' compliance: on a beam whose
    deflection under its weight is not small (EI = 20 over 2 m) its passes left
    a residual 5e3 times the forces, and the second diverged (Newton then failed
    at step 9). The start falls back to the unstrained one and says so: the
    run's rows are those of `start unstrained`, bit for bit."""
    out = run_text(tmp_path, "default", FLEXIBLE_DRIVEN.format(extra=""))
    note = [line for line in next(out.glob("*.lis")).read_text().splitlines() if "note: step 0" in line]
    check(len(note) == 1 and "unstrained" in note[0] and "too flexible" in note[0], f"the start's note: {note}")
    unstrained = run_text(tmp_path, "unstrained", FLEXIBLE_DRIVEN.format(extra="  start unstrained\n"))
    for name in ("points.csv", "reactions.csv"):
        check((out / name).read_text() == (unstrained / name).read_text(), f"{name} differs from start unstrained's")
