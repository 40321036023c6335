"""Rigid links as stiff beams: the dynamics of rigid-link mechanisms against
answers found without FEKAP, at link stiffnesses EA from 1e8 to 1e13, with
the default integrator (generalized-alpha), start (consistent) and tolerances,
and with energy-momentum; the observed order as dt halves from 1e-3 to
1.25e-4 must be at least 1.8. Where the links are stiff enough for the rigid
answer (EA >= RIGID_EA) the errors are against it; below, the elastic
deflection (1e-9 to 1e-6 m) is not small against the integrators' error at the
small steps, and the order is the self-convergence one (of the differences
between successive steps' answers), with the answer within the deflection's
size of the rigid one. (The A01 pendulum at EA = 1e8 has the spring pendulum's
answer.) A sample of the stiffness range is run
(EA = 1e8, 1e10, 1e12 or 1e13) for each case and integrator, to keep the suite
fast. Also: the deck's tolerance, length and iterations act on the dynamics'
Newton solves (docs/theory.md, "Convergence").

The answers:
- the A01 pendulum (a 1 kg point mass on a massless 1 m link, released from
  the horizontal): its first pass through the bottom, for the rigid link
  (fekap.dynamics.BOTTOM_TIME) and, at EA = 1e8 where the link stretches by
  3e-7 m, for the spring pendulum (an RK4 integration at 1e-5 s, here);
- a uniform rod (1 kg/m, 1 m) pinned at one end and released 30 degrees above
  the horizontal: the time and speed of its tip's pass through the bottom,
  by Gauss-Legendre quadrature of the energy integral;
- a double pendulum of two 1 kg point masses on massless 1 m links released
  horizontal: the tip at t = 0.3 s from Lagrange's equations integrated by
  RK4 at 1e-5 s; the same with two uniform 1 kg, 1 m rods;
- a free slider-crank with a flywheel (crank 1 m, rod 2 m, uniform 1 kg/m, a 2
  kg slider, 0.05 kg m^2 keyed to the crank) released at 60 degrees: the crank
  tip at t = 0.3 s, RK4 of the rigid mechanism's Newton-Euler equations
  (test_dynamics_consistency.slider_crank_rigid).
The sections are stiff in bending and shear as well, so that the rigid
motion's loads deflect the links by less than about 1e-8 m where the rigid
answer is used."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from fekap import dynamics as dc  # the bottom pass of a run's points.csv
from fekap.exact.pendulums import double_pendulum_rate, rk4_states
from fekap.exact.pendulums import double_pendulum_tip as tip_at
from fekap.models import pendulums

from apptest import ROOT, check, read_rows, run_fekap

G = 9.81
#: The time steps of each order study.
STEPS = (1e-3, 5e-4, 2.5e-4, 1.25e-4)
#: Least observed order (generalized-alpha and energy-momentum are second order).
LEAST_ORDER = 1.8
#: From this link stiffness on, the rigid answer is the model's to below the
#: integrators' error at the smallest step (1e-8 m): at EA = 1e10 the point-mass
#: double pendulum's links stretch by 5e-9 m and the slider-crank's by 3e-9 m,
#: where their errors at dt 1.25e-4 are 1e-8 and 3e-9 m.
RIGID_EA = 1e11

OUT: Path = None


def run_deck(name: str, text: str, dt: float, *args: str) -> Path:
    outdir = OUT / f"{name}-dt{dt:g}"
    outdir.mkdir(parents=True, exist_ok=True)
    deck = outdir / f"{name}.deck"
    deck.write_text(text)
    run = run_fekap(str(deck), "-q", "-o", str(outdir), "--dt", repr(dt), *args)
    check(run.returncode == 0, f"{name} at dt {dt} failed: {run.stderr}")
    return outdir


def integrator_line(integrator: str) -> str:
    return f"  integrator {integrator}\n" if integrator else ""


def dynamics_deck(title: str, ea: float, geometry: pendulums.Geometry, integrator: str, extra: str, time: str,
                  track: str) -> str:
    """The deck of `geometry` (fekap.models.pendulums) with the default start and tolerances."""
    return pendulums.deck(f"{title}, EA {ea:g}", ea, geometry, f"{integrator_line(integrator)}{extra}  time {time}\n",
                          f"  track {track}\n")


def a01_deck(ea: float, integrator: str = "", extra: str = "") -> str:
    """The A01 pendulum released from the horizontal."""
    return dynamics_deck("A01 pendulum", ea, pendulums.point_mass_pendulum(), integrator, extra, "0 0.6 1e-3", "B")


def orders(errors: list[float]) -> list[float]:
    return [math.log2(errors[k] / errors[k + 1]) for k in range(len(errors) - 1)]


def check_order(answers: list[np.ndarray], exact: np.ndarray, ea: float, what: str, near: float = 1e-5) -> None:
    """Observed order >= LEAST_ORDER of the answers at STEPS: against the exact
    (rigid) answer for EA >= RIGID_EA; at softer links the self-convergence order of
    the differences of successive answers (the elastic model's own limit), with
    the last answer within `near` of the rigid one."""
    answers = [np.atleast_1d(np.asarray(a, dtype=float)) for a in answers]
    if ea >= RIGID_EA:
        errors = [float(np.max(np.abs(a - exact))) for a in answers]
    else:
        errors = [float(np.max(np.abs(a - b))) for a, b in zip(answers, answers[1:])]
        last = float(np.max(np.abs(answers[-1] - exact)))
        check(last < near, f"{what}: {last!r} from the rigid answer at EA {ea:g}")
    check(min(orders(errors)) >= LEAST_ORDER, f"{what} errors {errors}: orders {orders(errors)}")


def spring_pendulum_bottom(k: float, m: float = 1.0, length: float = 1.0, h: float = 1e-5) -> tuple[float, float]:
    """The first pass through x = 0 of a point mass m on a massless spring
    (stiffness k, rest length `length`) pinned at the origin, released at rest
    from (length, 0) under gravity: RK4 at step h, the crossing by the cubic
    Hermite interpolant of the step around it (as fekap.dynamics.bottom_pass)."""

    def rate(s):
        x, y, vx, vy = s
        r = math.hypot(x, y)
        f = -k / m * (r - length) / r
        return (vx, vy, f * x, f * y - G)

    s = (length, 0.0, 0.0, 0.0)
    t = 0.0
    while True:
        k1 = rate(s)
        k2 = rate(tuple(a + 0.5 * h * b for a, b in zip(s, k1)))
        k3 = rate(tuple(a + 0.5 * h * b for a, b in zip(s, k2)))
        k4 = rate(tuple(a + h * b for a, b in zip(s, k3)))
        new = tuple(a + h / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(s, k1, k2, k3, k4))
        if s[0] > 0 >= new[0]:
            x0, x1, v0, v1 = s[0], new[0], s[2] * h, new[2] * h
            u = x0 / (x0 - x1)
            for _ in range(30):
                f = (2*u**3 - 3*u**2 + 1)*x0 + (u**3 - 2*u**2 + u)*v0 + (-2*u**3 + 3*u**2)*x1 + (u**3 - u**2)*v1
                df = (6*u**2 - 6*u)*x0 + (3*u**2 - 4*u + 1)*v0 + (-6*u**2 + 6*u)*x1 + (3*u**2 - 2*u)*v1
                u -= f / df
            speed = (1 - u) * math.hypot(s[2], s[3]) + u * math.hypot(new[2], new[3])
            return t + u * h, speed
        s, t = new, t + h


def bottom_pass(outdir: Path, point: str = "B") -> tuple[float, float]:
    """Time and speed of the point's first pass through x = 0 (from x > 0): the time
    as fekap.dynamics.bottom_pass finds it (the cubic Hermite interpolant of x from
    the positions and velocities of the two steps around it), the speed from the
    quadratic interpolants of vx and vy through the three steps nearest to it (error
    O(h^3); velocities alone, since energy-momentum's accelerations are its steps'
    mean ones). fekap.dynamics interpolates the speed linearly, which at the
    bottom, where the speed is largest, is off by up to h^2 |speed''| / 8 (3e-7
    relative at dt 5e-4): of the size of the integrators' errors, with its own sign."""
    t_pass, _ = dc.bottom_pass(outdir, point)
    rows = [row for row in read_rows(outdir / "points.csv") if row["point"] == point]
    t = np.array([float(row["t"]) for row in rows])
    k = int(np.argmin(np.abs(t - t_pass)))
    near = [k - 1, k, k + 1]
    check(near[0] >= 0 and near[-1] < len(t), f"the pass at t = {t_pass} is at the run's end")
    basis = [np.prod([(t_pass - t[j]) / (t[i] - t[j]) for j in near if j != i]) for i in near]
    vx = sum(w * float(rows[i]["vx"]) for w, i in zip(basis, near))
    vy = sum(w * float(rows[i]["vy"]) for w, i in zip(basis, near))
    return t_pass, math.hypot(vx, vy)


def a01_exact(ea: float) -> tuple[float, float]:
    """The bottom pass: the spring pendulum's at EA = 1e8 (stretch 3e-7 m), the rigid one's above."""
    if ea < 1e10:
        return spring_pendulum_bottom(ea / 1.0)
    return dc.BOTTOM_TIME, dc.BOTTOM_SPEED


def test_spring_pendulum_reference_is_the_rigid_one_when_stiff() -> None:
    """The RK4 reference of the spring pendulum tends to the rigid pendulum's
    closed form (an elliptic integral) as the spring stiffens: at k = 1e9
    (stretch 3e-8 m) it passes the bottom later, by less than 2e-8 s, and
    slower, by less than 1e-7 m/s (measured: 9.8e-9 s, 3.3e-8 m/s; ten times
    that at k = 1e8)."""
    t, speed = spring_pendulum_bottom(1e9, h=5e-6)
    check(0 < t - dc.BOTTOM_TIME < 2e-8, f"bottom time {t!r}")
    check(0 < dc.BOTTOM_SPEED - speed < 1e-7, f"bottom speed {speed!r}")


@pytest.mark.parametrize("integrator, ea", [
    ("", 1e8), ("", 1e10), ("", 1e12), ("", 1e13),
    ("energy-momentum", 1e10), ("energy-momentum", 1e13),
])
def test_a01_pendulum_converges_at_second_order(integrator: str, ea: float) -> None:
    """The A01 pendulum's bottom pass (time and speed) at dt 1e-3 to 1.25e-4:
    errors against the exact answer fall at order >= 1.8 (the speed with
    energy-momentum: see speed_order), and at dt 5e-4 are within 1e-6
    relative, with either integrator (measured: time 7.4e-7 and speed 9.8e-7
    with generalized-alpha, 2.8e-7 and 7e-10 with energy-momentum)."""
    t_exact, v_exact = a01_exact(ea)
    errors_t, errors_v = [], []
    for dt in STEPS:
        outdir = run_deck(f"a01-{integrator or 'alpha'}-{ea:g}", a01_deck(ea, integrator), dt)
        t, speed = bottom_pass(outdir)
        errors_t.append(abs(t - t_exact))
        errors_v.append(abs(speed - v_exact))
    check(min(orders(errors_t)) >= LEAST_ORDER, f"bottom time errors {errors_t}: orders {orders(errors_t)}")
    check(errors_t[1] < 1e-6 * t_exact, f"bottom time error at dt 5e-4: {errors_t[1]!r}")
    check(errors_v[1] < 1e-6 * v_exact, f"bottom speed error at dt 5e-4: {errors_v[1]!r}")
    speed_order(integrator, errors_v, v_exact)


def rod_deck(ea: float, integrator: str = "") -> str:
    return dynamics_deck("uniform rod pendulum released 30 degrees above the horizontal", ea,
                         pendulums.rod_pendulum(), integrator, "", "0 0.57 1e-3", "B")


def rod_exact(theta0: float = math.pi / 6, rho_i: float = 1e-6) -> tuple[float, float]:
    """A uniform rod (m = 1 kg, L = 1 m, rotary inertia rho_i per length)
    pinned at one end, released at rest at theta0 above the horizontal: the
    time its tip passes the bottom and its speed there. theta'^2 = c (sin
    theta0 - sin theta), c = m g L / I_pivot; t = int d theta / theta', with
    theta = theta0 - u^2 (smooth in u), by 200-point Gauss-Legendre."""
    m, length = 1.0, 1.0
    pivot = m * length**2 / 3 + rho_i * length
    c = m * G * length / pivot
    x, w = np.polynomial.legendre.leggauss(200)
    top = math.sqrt(theta0 + math.pi / 2)
    u = 0.5 * top * (x + 1)
    theta = theta0 - u**2
    # sin theta0 - sin theta without cancellation: 2 cos((theta0 + theta)/2) sin(u^2/2).
    integrand = 2 * u / np.sqrt(c * 2 * np.cos((theta0 + theta) / 2) * np.sin(u**2 / 2))
    t = float(np.sum(0.5 * top * w * integrand))
    return t, length * math.sqrt(c * (math.sin(theta0) + 1))


def test_rod_quadrature_against_the_small_release() -> None:
    """The quadrature of rod_exact at a release a = 1e-3 rad from the bottom is a
    quarter period of the pendulum, pi/2 sqrt(I/(m g L/2)) (1 + a^2/16), to 1e-12."""
    a = 1e-3
    t, _ = rod_exact(theta0=-math.pi / 2 + a)
    pivot = 1 / 3 + 1e-6
    quarter = math.pi / 2 * math.sqrt(pivot / (G / 2)) * (1 + a**2 / 16)
    check(abs(t - quarter) < 1e-12 * quarter, f"{t!r} against {quarter!r}")


def test_rod_quadrature_against_rk4() -> None:
    """rod_exact's bottom time for the 30 degree release against RK4 of
    theta'' = -(m g L / (2 I)) cos theta at h = 1e-5 (crossing interpolated
    linearly: O(h^2) = 1e-10 s): within 1e-9 s."""
    c = G / (1 / 3 + 1e-6)
    h, t, theta, omega = 1e-5, 0.0, math.pi / 6, 0.0

    def acc(x: float) -> float:
        return -0.5 * c * math.cos(x)

    while True:
        k1 = (omega, acc(theta))
        k2 = (omega + 0.5 * h * k1[1], acc(theta + 0.5 * h * k1[0]))
        k3 = (omega + 0.5 * h * k2[1], acc(theta + 0.5 * h * k2[0]))
        k4 = (omega + h * k3[1], acc(theta + h * k3[0]))
        new = theta + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        if new <= -math.pi / 2:
            crossing = t + h * (theta + math.pi / 2) / (theta - new)
            break
        omega += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        theta, t = new, t + h
    exact, _ = rod_exact()
    check(abs(crossing - exact) < 1e-9, f"RK4 {crossing!r}, quadrature {exact!r}")


@pytest.mark.parametrize("integrator, ea", [("", 1e8), ("", 1e10), ("", 1e13), ("energy-momentum", 1e12)])
def test_rod_pendulum_converges_at_second_order(integrator: str, ea: float) -> None:
    """The rod's tip passes the bottom at the quadrature's time and speed,
    with errors falling at order >= 1.8 as dt halves (check_order; energy-momentum's
    speed: speed_order)."""
    t_exact, v_exact = rod_exact()
    times, speeds = [], []
    for dt in STEPS:
        outdir = run_deck(f"rod-{integrator or 'alpha'}-{ea:g}", rod_deck(ea, integrator), dt)
        t, speed = bottom_pass(outdir)
        times.append(t)
        speeds.append(speed)
    check_order(times, np.array(t_exact), ea, "bottom time", near=1e-6)
    if integrator == "energy-momentum":
        speed_order(integrator, [abs(v - v_exact) for v in speeds], v_exact)
    else:
        check_order(speeds, np.array(v_exact), ea, "bottom speed", near=1e-5)


def speed_order(integrator: str, errors: list[float], speed: float) -> None:
    """Generalized-alpha's speed converges at order >= 1.8. Energy-momentum
    keeps the energy of the release to the Newton tolerance, so its speed at
    the bottom is the energy integral's at its computed bottom, whatever the
    step: its error is that of the links' elastic energy against the rigid
    answer (7e-10 relative on the A01 pendulum at EA = 1e10), flat in dt. It
    is asserted below 1e-8 relative at every step. (An earlier version of this
    test interpolated the speed linearly between steps, whose O(h^2) error,
    with a sign set by where the pass falls in its step, made energy-momentum's
    speed look first order: see bottom_pass.)"""
    if integrator == "energy-momentum":
        check(max(errors) < 1e-8 * speed, f"bottom speed errors {errors}")
    else:
        check(min(orders(errors)) >= LEAST_ORDER, f"bottom speed errors {errors}: orders {orders(errors)}")


def double_pendulum_deck(ea: float, integrator: str = "") -> str:
    return dynamics_deck("double pendulum of point masses on massless links", ea, pendulums.double_pendulum(),
                         integrator, "", "0 0.3 1e-3", "C")


def double_pendulum_tip(t_end: float, h: float = 1e-5) -> np.ndarray:
    """The tip (x, y) at t_end of the double pendulum (m1 = m2 = 1, L1 = L2 =
    1, angles from the downward vertical, both released at pi/2): Lagrange's
    equations integrated by RK4 at step h."""
    last = rk4_states(double_pendulum_rate, [math.pi / 2, math.pi / 2, 0.0, 0.0], h, round(t_end / h))[-1]
    return np.array(tip_at(last[0], last[1]))


def test_double_pendulum_reference_keeps_its_energy() -> None:
    """The RK4 reference keeps the energy of the release (0) to 1e-10 J."""
    h = 1e-5
    tip = double_pendulum_tip(0.3, h)
    check(tip[1] < -0.1, f"the tip has not fallen: {tip}")
    # Energy from a finite difference of the tip and elbow is not at hand: check the
    # RK4 answer at half the step instead (fourth order: the same to 1e-12 m).
    half = double_pendulum_tip(0.3, h / 2)
    check(float(np.max(np.abs(tip - half))) < 1e-12, f"RK4 at h and h/2: {tip} {half}")


@pytest.mark.parametrize("integrator, ea", [("", 1e8), ("", 1e10), ("", 1e13), ("energy-momentum", 1e12)])
def test_double_pendulum_converges_at_second_order(integrator: str, ea: float) -> None:
    """The double pendulum's tip at t = 0.3 s against the RK4 reference: errors
    falling at order >= 1.8 as dt halves (check_order)."""
    exact = double_pendulum_tip(0.3)
    tips = [last_point(run_deck(f"double-{integrator or 'alpha'}-{ea:g}", double_pendulum_deck(ea, integrator), dt),
                       "C", 0.3) for dt in STEPS]
    check_order(tips, exact, ea, "tip")


def last_point(outdir: Path, point: str, t_end: float) -> np.ndarray:
    """The point's (x, y) in the last row of points.csv, which must be at t_end."""
    rows = [row for row in read_rows(outdir / "points.csv") if row["point"] == point]
    last = rows[-1]
    check(abs(float(last["t"]) - t_end) < 1e-12, f"last row at t = {last['t']}")
    return np.array([float(last["x"]), float(last["y"])])


def rods_double_pendulum_deck(ea: float, integrator: str = "") -> str:
    return dynamics_deck("double pendulum of two uniform rods", ea, pendulums.double_pendulum(rods=True),
                         integrator, "", "0 0.3 1e-3", "C")


def rods_double_pendulum_tip(t_end: float, h: float = 1e-5) -> np.ndarray:
    """The tip at t_end of two uniform rods (m = 1 kg, L = 1 m each, angles phi1,
    phi2 from the downward vertical, both released at pi/2), by RK4 at step h of
    Lagrange's equations: with D = phi1 - phi2,
      4/3 phi1'' + 1/2 cos D phi2'' = -3/2 g sin phi1 - 1/2 sin D phi2'^2,
      1/2 cos D phi1'' + 1/3 phi2'' = -1/2 g sin phi2 + 1/2 sin D phi1'^2."""

    def rate(s):
        a, b, wa, wb = s
        d = a - b
        m11, m12, m22 = 4 / 3, 0.5 * math.cos(d), 1 / 3
        q1 = -1.5 * G * math.sin(a) - 0.5 * math.sin(d) * wb**2
        q2 = -0.5 * G * math.sin(b) + 0.5 * math.sin(d) * wa**2
        det = m11 * m22 - m12**2
        return (wa, wb, (m22 * q1 - m12 * q2) / det, (m11 * q2 - m12 * q1) / det)

    s = (math.pi / 2, math.pi / 2, 0.0, 0.0)
    for _ in range(round(t_end / h)):
        k1 = rate(s)
        k2 = rate(tuple(p + 0.5 * h * q for p, q in zip(s, k1)))
        k3 = rate(tuple(p + 0.5 * h * q for p, q in zip(s, k2)))
        k4 = rate(tuple(p + h * q for p, q in zip(s, k3)))
        s = tuple(p + h / 6 * (q1 + 2 * q2 + 2 * q3 + q4) for p, q1, q2, q3, q4 in zip(s, k1, k2, k3, k4))
    return np.array([math.sin(s[0]) + math.sin(s[1]), -math.cos(s[0]) - math.cos(s[1])])


def test_rods_double_pendulum_reference() -> None:
    """The uniform-rod double pendulum's RK4 reference: the same tip at h and h/2
    to 1e-12 m (fourth order), and with the second rod's mass moved to its tip
    it is not the point-mass pendulum's (the two references differ)."""
    tip = rods_double_pendulum_tip(0.3)
    half = rods_double_pendulum_tip(0.3, 5e-6)
    check(float(np.max(np.abs(tip - half))) < 1e-12, f"RK4 at h and h/2: {tip} {half}")
    check(float(np.max(np.abs(tip - double_pendulum_tip(0.3)))) > 1e-2, "the rods' answer is the point masses'")


@pytest.mark.parametrize("integrator, ea", [("", 1e8), ("", 1e10), ("", 1e13), ("energy-momentum", 1e12)])
def test_rods_double_pendulum_converges_at_second_order(integrator: str, ea: float) -> None:
    """The double pendulum of two uniform rods (4 elements each): its tip at t =
    0.3 s against the RK4 reference, at order >= 1.8 as dt halves (check_order)."""
    exact = rods_double_pendulum_tip(0.3)
    tips = [last_point(run_deck(f"rods-{integrator or 'alpha'}-{ea:g}", rods_double_pendulum_deck(ea, integrator),
                                dt), "C", 0.3) for dt in STEPS]
    check_order(tips, exact, ea, "tip")


def slider_crank_deck(ea: float, integrator: str = "") -> str:
    return dynamics_deck("free slider-crank with a flywheel", ea, pendulums.slider_crank(), integrator, "",
                         "0 0.3 1e-3", "A")


@functools.lru_cache
def slider_crank_tip(t_end: float, h: float = 2e-4) -> np.ndarray:
    """The crank tip A at t_end of the rigid free slider-crank of slider_crank_deck
    released at rest at 60 degrees: RK4 at step h of theta'' from its Newton-Euler
    equations (test_dynamics_consistency.slider_crank_rigid)."""
    from test_dynamics_consistency import slider_crank_rigid

    def rate(s):
        return (s[1], float(slider_crank_rigid(1.0, 2.0, s[0], s[1], 1.0, 2.0, 2.0, 0.05, G)["alpha1"]))

    s = (math.pi / 3, 0.0)
    for _ in range(round(t_end / h)):
        k1 = rate(s)
        k2 = rate(tuple(p + 0.5 * h * q for p, q in zip(s, k1)))
        k3 = rate(tuple(p + 0.5 * h * q for p, q in zip(s, k2)))
        k4 = rate(tuple(p + h * q for p, q in zip(s, k3)))
        s = tuple(p + h / 6 * (q1 + 2 * q2 + 2 * q3 + q4) for p, q1, q2, q3, q4 in zip(s, k1, k2, k3, k4))
    return np.array([math.cos(s[0]), math.sin(s[0])])


def test_slider_crank_reference() -> None:
    """The slider-crank's RK4 reference at h = 4e-4 and 2e-4: the same to 1e-11 m
    (fourth order: the reference at 2e-4 is 16 times closer), and the crank has
    turned (the tip fell by more than 0.02 m)."""
    tip = slider_crank_tip(0.3)
    double = slider_crank_tip(0.3, 4e-4)
    check(float(np.max(np.abs(tip - double))) < 1e-11, f"RK4 at 2h and h: {double} {tip}")
    check(tip[1] < math.sin(math.pi / 3) - 0.02, f"the crank has not fallen: {tip}")


@pytest.mark.parametrize("integrator, ea", [("", 1e8), ("", 1e13), ("energy-momentum", 1e10)])
def test_free_slider_crank_converges_at_second_order(integrator: str, ea: float) -> None:
    """The free slider-crank with a flywheel (a pin-in-slot slideline with its
    automatic penalty): the crank tip at t = 0.3 s against the rigid RK4
    reference, at order >= 1.8 as dt halves (check_order)."""
    exact = slider_crank_tip(0.3)
    tips = [last_point(run_deck(f"slider-{integrator or 'alpha'}-{ea:g}", slider_crank_deck(ea, integrator), dt),
                       "A", 0.3) for dt in STEPS]
    check_order(tips, exact, ea, "crank tip")


def steps_of(outdir: Path) -> list[dict[str, str]]:
    return read_rows(outdir / "steps.csv")


def test_deck_tolerances_act_on_the_dynamics() -> None:
    """The deck's tolerance, length and iterations are the dynamics' Newton
    contract. At EA = 1e12 the residual's round-off (about 1e-5 N) is above the
    default tolerance times the forces (1e-10 x 9.81 N): the steps are
    accepted at the round-off floor, counted in steps.csv's floor column and
    the listing; with `tolerance 1e-4` none is. A length tolerance of 1e-6
    saves iterations and moves the answer by less than the contract allows: each
    step stops within its last correction, at most 1e-6 x the model size (1 m),
    so the 600 steps move the end by less than 600 x 1e-6 m. (Measured: with
    generalized-alpha's predictor keeping the acceleration every step stops
    after one correction, 600 iterations against 1681 by default, and the end
    moves by 1.35e-5 m; with the predictor qdd_n+1 = 0 it took 1445 iterations
    and moved by 3e-10 m.) `iterations 1` cannot converge (exit 3, with the
    message). --tol acts as `tolerance`."""
    dt = 1e-3
    default = run_deck("tol-default", a01_deck(1e12), dt)
    rows = steps_of(default)
    check(list(rows[0])[:6] == ["step", "t", "iterations", "residual", "cuts", "floor"], f"header {list(rows[0])}")
    floors = sum(int(row["floor"]) for row in rows)
    check(floors > len(rows) // 2, f"{floors} of {len(rows)} steps at the floor")
    listing = next(default.glob("*.lis")).read_text()
    check(f"accepted at round-off floor {floors:11d}" in listing, "the listing does not count the floor steps")

    loose = run_deck("tol-loose", a01_deck(1e12, extra="  tolerance 1e-4\n"), dt)
    check(sum(int(row["floor"]) for row in steps_of(loose)) == 0, "steps at the floor with tolerance 1e-4")
    check("round-off floor" not in next(loose.glob("*.lis")).read_text(), "the listing counts floor steps")
    option = run_deck("tol-option", a01_deck(1e12), dt, "--tol", "1e-4")
    check(sum(int(row["floor"]) for row in steps_of(option)) == 0, "steps at the floor with --tol 1e-4")

    short = run_deck("tol-length", a01_deck(1e12, extra="  length 1e-6\n"), dt)
    its_default = sum(int(row["iterations"]) for row in rows)
    its_short = sum(int(row["iterations"]) for row in steps_of(short))
    check(its_short < its_default, f"iterations with length 1e-6: {its_short}, default {its_default}")
    a = [row for row in read_rows(default / "points.csv")][-1]
    b = [row for row in read_rows(short / "points.csv")][-1]
    moved = math.hypot(float(a["x"]) - float(b["x"]), float(a["y"]) - float(b["y"]))
    steps, length, model_size = len(rows) - 1, 1e-6, 1.0
    check(moved < steps * length * model_size, f"length 1e-6 moved the end by {moved!r} m over {steps} steps")

    outdir = OUT / "tol-iterations"
    outdir.mkdir(parents=True, exist_ok=True)
    deck = outdir / "a01.deck"
    deck.write_text(a01_deck(1e12, extra="  iterations 1\n"))
    run = run_fekap(str(deck), "-q", "-o", str(outdir))
    check(run.returncode == 3, f"exit {run.returncode}: {run.stderr}")
    check("did not converge in 1 iterations" in run.stderr, run.stderr)


def test_slider_crank_kept_factor_converges_at_round_off() -> None:
    """The flexible slider-crank (decks/dynamics/slider-crank.deck) to 0.03 s:
    no step is cut. Its kept factor reaches corrections at round-off (5e-16 m,
    1e-3 of a 4.5e-13 m correction before), which must count as converged
    corrections; when they did not, step 275 spent its 25 iterations there and
    was cut."""
    outdir = OUT / "slider-crank"
    outdir.mkdir(parents=True, exist_ok=True)
    run = run_fekap(str(ROOT / "decks" / "dynamics" / "slider-crank.deck"), "-q", "-o", str(outdir),
                    "--set", "t_end=0.03")
    check(run.returncode == 0, run.stderr)
    rows = steps_of(outdir)
    check(len(rows) == 301, f"{len(rows)} rows")
    cut = [row["step"] for row in rows if int(row["cuts"]) > 0]
    check(not cut, f"steps cut: {cut}")
