"""The local error estimate of every dynamics step (steps.csv's last column,
error_estimate, docs/dynamics.md "Local error estimate and adaptive steps")
and adaptive steps (`time T0 T1 DT adaptive TOL`), checked against exact
motions computed here without FEKAP (RK4 of Lagrange's or Newton-Euler's
equations at h/1000 or 1e-5 s, fourth order: far below the errors compared):

- the A01-style pendulum (1 kg on a stiff massless 1 m link), a uniform rod
  pendulum (1 kg/m, 1 m, 4 elements), a double pendulum of two 1 kg point
  masses on massless 1 m links, the same of two uniform rods (4 elements
  each), and the free slider-crank with a flywheel of test_stiff_links
  (rigid reference: test_dynamics_consistency.slider_crank_rigid); links
  EA = 1e8 to 1e13, with the consistent start so that no stiff transient is
  in the motion;
- each with generalized-alpha at rho_inf 0.8 (the default) and 1, and with
  energy-momentum.

What "the estimate bounds the true error within a factor of 3" means here,
asserted in two ways (each can fail: the error is the distance of the
tracked point from the exact one):

1. one step: from an exact state in mid-motion (VELOcities), the step's
   estimate e against the true local error E of that step:
   E <= e <= 3 E, at h = 1e-3, 4e-3 and 2e-2 s (EA = 1e13) and at 4e-3 s
   with EA = 1e10 and 1e8. (measured e/E: 1.74-2.08 at 4e-3 s, 1.93-2.08
   at 1e-3 s, 1.15-2.35 at 2e-2 s: the estimate is twice the leading term,
   which tends to E as h shrinks.) At EA = 1e8 the links stretch by
   1e-7 to 1e-6 m, not small against E: the exact motion is the model's own
   at h/32 (its local error is E/1000), a reference that agrees with the
   rigid one at EA = 1e13 (asserted);
2. a run: the largest global error E over the run against the sum S of
   the steps' estimates: E <= 3 S and S <= 10 E.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fekap.exact.pendulums import double_pendulum_rate, rk4_states
from fekap.models import pendulums

from apptest import ROOT, check, read_rows, run_fekap

G = 9.81
#: One step's estimate e bounds its true local error E within this factor: E <= e <= BOUND E.
BOUND = 3.0
#: The summed estimates S of a run bound its global error E within BOUND, and are
#: not more pessimistic than this (S <= LOOSEST E): local errors of a run partly cancel.
LOOSEST = 10.0
#: The soft links' reference: the model's own motion at h / SUBSTEPS.
SUBSTEPS = 32

INTEGRATORS = ["generalized-alpha 0.8", "generalized-alpha 1", "energy-momentum"]


def analysis(integrator: str, time: str) -> str:
    return f"  start consistent\n  integrator {integrator}\n  time {time}\n"


def model_deck(title: str, ea: float, geometry: pendulums.Geometry, integrator: str, time: str, track: str) -> str:
    return pendulums.deck(title, ea, geometry, analysis(integrator, time), f"  track {track}\n")


def rk4(rate, s: np.ndarray, h: float, n: int, every: int = 0) -> np.ndarray:
    """n RK4 steps of h from s (fekap.exact.pendulums.rk4_states); the states every `every`
    steps (with the first) or the last."""
    states = rk4_states(rate, s, h, n)
    return states[::every] if every else states[-1]


def pendulum_rate(s):
    """A01: the angle th below the horizontal, th'' = g cos th."""
    return np.array([s[1], G * math.cos(s[0])])


ROD_C = G / (1 / 3 + 1e-6)


def rod_rate(s):
    """The rod (rotary inertia 1e-6 per length): th above the horizontal, th'' = -(c/2) cos th."""
    return np.array([s[1], -0.5 * ROD_C * math.cos(s[0])])


def pendulum_point(s):
    return [math.cos(s[0]), -math.sin(s[0])]


def rod_point(s):
    return [math.cos(s[0]), math.sin(s[0])]


def double_point(s):
    return [math.sin(s[0]) + math.sin(s[1]), -math.cos(s[0]) - math.cos(s[1])]


def pendulum_deck(s, ea, integrator, time):
    return model_deck("A01 pendulum", ea, pendulums.point_mass_pendulum(s), integrator, time, "B")


def rod_deck(s, ea, integrator, time):
    return model_deck("rod pendulum", ea, pendulums.rod_pendulum(s), integrator, time, "B")


def double_deck(s, ea, integrator, time):
    return model_deck("double pendulum", ea, pendulums.double_pendulum(s), integrator, time, "C")


def rods_rate(s):
    """Two uniform rods (1 kg, 1 m each; angles from the downward vertical), Lagrange's
    equations (test_stiff_links.rods_double_pendulum_tip)."""
    a, b, wa, wb = s
    d = a - b
    m11, m12, m22 = 4 / 3, 0.5 * math.cos(d), 1 / 3
    q1 = -1.5 * G * math.sin(a) - 0.5 * math.sin(d) * wb**2
    q2 = -0.5 * G * math.sin(b) + 0.5 * math.sin(d) * wa**2
    det = m11 * m22 - m12**2
    return np.array([wa, wb, (m22 * q1 - m12 * q2) / det, (m11 * q2 - m12 * q1) / det])


def rods_deck(s, ea, integrator, time):
    return model_deck("double pendulum of rods", ea, pendulums.double_pendulum(s, rods=True), integrator, time, "C")


def slider_rate(s):
    """The free slider-crank's crank angle (test_stiff_links.slider_crank_deck): Newton-Euler."""
    from test_dynamics_consistency import slider_crank_rigid

    return np.array([s[1], float(slider_crank_rigid(1.0, 2.0, s[0], s[1], 1.0, 2.0, 2.0, 0.05, G)["alpha1"])])


def slider_point(s):
    return [math.cos(s[0]), math.sin(s[0])]


def slider_deck(s, ea, integrator, time):
    return model_deck("free slider-crank with a flywheel", ea, pendulums.slider_crank(s), integrator, time, "A")


#: name: (deck, rate, tracked point of a state, its name, a state in mid-motion, the release, run's end)
CASES = {
    "pendulum": (pendulum_deck, pendulum_rate, pendulum_point, "B", [0.7, 3.0], [0.0, 0.0], 0.6),
    "rod": (rod_deck, rod_rate, rod_point, "B", [0.2, -2.5], [math.pi / 6, 0.0], 0.57),
    "double": (double_deck, double_pendulum_rate, double_point, "C", [1.0, 1.8, 1.5, -2.0], [math.pi / 2, math.pi / 2, 0, 0],
               0.3),
    "rods": (rods_deck, rods_rate, double_point, "C", [1.0, 1.8, 1.5, -2.0], [math.pi / 2, math.pi / 2, 0, 0], 0.3),
    "slider": (slider_deck, slider_rate, slider_point, "A", [0.8, -2.5], [math.pi / 3, 0.0], 0.3),
}
#: The one-step checks: (EA, h); below RIGID_EA the model's own motion at h / SUBSTEPS is the reference.
ONE_STEPS = [(1e13, 1e-3), (1e13, 4e-3), (1e13, 2e-2), (1e10, 4e-3), (1e8, 4e-3)]
RIGID_EA = 1e10


def run(tmp: Path, name: str, text: str, *args: str) -> Path:
    out = tmp / name
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.deck"
    path.write_text(text)
    done = run_fekap(str(path), "-q", "-o", str(out), *args)
    check(done.returncode == 0, f"{name} failed: {done.stderr}")
    return out


def tracked(out: Path, point: str) -> tuple[np.ndarray, np.ndarray]:
    rows = [r for r in read_rows(out / "points.csv") if r["point"] == point]
    return np.array([float(r["t"]) for r in rows]), np.array([[float(r["x"]), float(r["y"])] for r in rows])


def estimates(out: Path) -> np.ndarray:
    rows = read_rows(out / "steps.csv")
    check(list(rows[0])[-1] == "error_estimate", f"steps.csv's last column: {list(rows[0])}")
    return np.array([float(r["error_estimate"]) for r in rows])


def one_step(tmp: Path, case: str, integrator: str, ea: float, h: float, dt: float) -> tuple[np.ndarray, float]:
    """The tracked point after a run from the mid-motion state to h at steps dt, and the estimate of its last step."""
    make, _, _, name, state, _, _ = CASES[case]
    out = run(tmp, f"one-{case}-{integrator.replace(' ', '')}-{ea:g}-{h:g}-{dt:g}",
              make(np.array(state, dtype=float), ea, integrator, f"0 {h!r} {dt!r}"))
    return tracked(out, name)[1][-1], float(estimates(out)[-1])


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("case", list(CASES))
def test_one_step_estimate_bounds_its_local_error(tmp_path: Path, case: str, integrator: str) -> None:
    """One step of h from an exact state in mid-motion, for each (EA, h) of
    ONE_STEPS: the true local error E <= e <= 3 E. For EA >= RIGID_EA, E
    is the distance from the rigid motion (the links stretch by 1e-14 to
    1e-10 m, far below E: 4e-10 to 4e-5 m); at EA = 1e8 from the model's own
    motion at h / SUBSTEPS, which at EA = 1e13 is the rigid motion to within
    E / 20."""
    _, rate, point, _, state, _, _ = CASES[case]
    s0 = np.array(state, dtype=float)
    for ea, h in ONE_STEPS:
        xy, e = one_step(tmp_path, case, integrator, ea, h, h)
        exact = np.array(point(rk4(rate, s0, h / 1000, 1000)))
        if ea < RIGID_EA:
            exact, _ = one_step(tmp_path, case, integrator, ea, h, h / SUBSTEPS)
        true = float(np.hypot(*(xy - exact)))
        where = f"{case}, {integrator}, EA {ea:g}, h {h:g}"
        check(true <= e, f"{where}: true local error {true:.3e} above the estimate {e:.3e}")
        check(e <= BOUND * true, f"{where}: estimate {e:.3e} above {BOUND} x the true local error {true:.3e}")
    # The soft links' reference, where the rigid one is the model's.
    h = 4e-3
    fine, _ = one_step(tmp_path, case, integrator, 1e13, h, h / SUBSTEPS)
    xy, _ = one_step(tmp_path, case, integrator, 1e13, h, h)
    exact = np.array(point(rk4(rate, s0, h / 1000, 1000)))
    true = float(np.hypot(*(xy - exact)))
    check(float(np.hypot(*(fine - exact))) <= true / 20, f"{case}, {integrator}: the fine-step reference "
          f"{fine} is not the rigid motion {exact} (the step's error {true:.3e})")


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("case", list(CASES))
def test_summed_estimates_bound_the_global_error(tmp_path: Path, case: str, integrator: str) -> None:
    """A run from the release at dt 1e-3: the largest distance E of the
    tracked point from the exact one over the run, against the sum S of the
    steps' estimates: E <= 3 S and S <= 10 E."""
    make, rate, point, name, _, release, t_end = CASES[case]
    dt = 1e-3
    out = run(tmp_path, f"run-{case}-{integrator.replace(' ', '')}",
              make(np.array(release, dtype=float), 1e10, integrator, f"0 {t_end!r} {dt!r}"))
    t, xy = tracked(out, name)
    h = 1e-5
    states = rk4(rate, np.array(release, dtype=float), h, round(t_end / h), every=round(dt / h))
    exact = np.array([point(s) for s in states])
    check(len(exact) == len(xy), f"{len(exact)} exact states, {len(xy)} rows")
    errors = np.hypot(*(xy - exact).T)
    largest, total = float(errors.max()), float(estimates(out).sum())
    check(largest <= BOUND * total, f"global error {largest:.3e} above {BOUND} x the summed estimates {total:.3e}")
    check(total <= LOOSEST * largest, f"summed estimates {total:.3e} above {LOOSEST} x the global error {largest:.3e}")


def test_adaptive_steps_keep_the_tolerance_and_write_the_output_instants(tmp_path: Path) -> None:
    """`time 0 0.6 0.01 adaptive TOL` on the A01 pendulum: rows at exactly
    k 0.01 (61 rows), every row's estimate (the largest of its steps) at or
    below TOL, and the error against the exact motion falls with TOL (local
    error ~ h^3, global ~ h^2: TOL / 100 takes it down about 20 times;
    asserted: at least 5)."""
    release = np.array([0.0, 0.0])
    h = 1e-5
    states = rk4(pendulum_rate, release, h, round(0.6 / h), every=round(0.01 / h))
    exact = np.array([pendulum_point(s) for s in states])
    errors = []
    for tol in (1e-8, 1e-10):
        out = run(tmp_path, f"adaptive-{tol:g}", pendulum_deck(release, 1e10, "generalized-alpha 0.8",
                                                            f"0 0.6 0.01 adaptive {tol!r}"))
        t, xy = tracked(out, "B")
        check(len(t) == 61 and all(t[k] == 0.01 * k or abs(t[k] - 0.01 * k) <= 1e-15 for k in range(61)),
              f"rows at {t}")
        e = estimates(out)
        check(bool(np.all(e <= tol)), f"estimates above {tol}: {e[e > tol]}")
        steps = sum(int(r["cuts"]) for r in read_rows(out / "steps.csv"))
        listing = next(out.glob("*.lis")).read_text()
        check("largest local error estimate" in listing, "the listing has no largest estimate")
        check(steps == 0 or "adaptive steps rejected" in listing, "the listing does not count the rejected steps")
        errors.append(float(np.hypot(*(xy - exact).T).max()))
    check(errors[1] < errors[0] / 5, f"errors at TOL 1e-8 and 1e-10: {errors}")


def test_adaptive_tolerance_must_be_positive(tmp_path: Path) -> None:
    """TOL <= 0 is an input error at its field (exit 2)."""
    path = tmp_path / "bad.deck"
    path.write_text(pendulum_deck(np.array([0.0, 0.0]), 1e10, "generalized-alpha", "0 0.6 0.01 adaptive 0"))
    done = run_fekap(str(path), "-q", "-o", str(tmp_path / "bad"))
    line = next(k for k, text in enumerate(path.read_text().splitlines(), 1) if "adaptive" in text)
    check(done.returncode == 2, f"exit {done.returncode}: {done.stderr}")
    check(f"bad.deck:{line}:28: error: the adaptive tolerance must be positive" in done.stderr, done.stderr)


#: At rest until a side load of 100 N comes on at t = 0.05 within 1e-12 s:
#: the acceleration jumps by 100 m/s^2 in a time no step above the least
#: (1e-12 of the span: 1e-13 s) resolves to TOL 1e-28.
UNREACHABLE = """TITLe a side load ramped in over 1e-12 s at t = 0.05
SECTions
  rod  E=1e13  G=4e12  A=1e-3  I=1e-5
NODEs
  A 0 0
  B 0 -1
LINKs
  AB A B rod 1
SUPPorts
  A pin
MASSes
  B 1
LOADs
  B 100 0 linear 0 0 0.05 0 0.050000000001 1 1 1
ANALysis
  type dynamics
  start consistent
  time 0 0.1 0.01 adaptive 1e-28
OUTPut
  track B
END
"""


def test_adaptive_step_that_cannot_meet_the_tolerance_is_a_run_error(tmp_path: Path) -> None:
    """The load's jump cannot be stepped over within TOL: exit 3, the message
    names the time and the estimate, and the rows of t = 0 to 0.05 are kept."""
    path = tmp_path / "jump.deck"
    path.write_text(UNREACHABLE)
    out = tmp_path / "jump"
    done = run_fekap(str(path), "-q", "-o", str(out))
    check(done.returncode == 3, f"exit {done.returncode}: {done.stderr}")
    check("t = 5.00000E-02: the adaptive step cannot meet the tolerance 1.000E-28: the local error estimate is"
          in done.stderr, done.stderr)
    rows = read_rows(out / "steps.csv")
    times = [float(r["t"]) for r in rows]
    check(len(times) == 6 and all(abs(t - 0.01 * k) <= 1e-15 for k, t in enumerate(times)), f"rows kept: {times}")


def test_accuracy_study_plots_fixed_against_adaptive(fekap: Path, tmp_path: Path) -> None:
    """studies/accuracy/accuracy_study.py --adaptive --short: every run ends well, the
    table has the three cases with both kinds of steps, and the PNG is written."""
    png = tmp_path / "adaptive.png"
    done = subprocess.run([sys.executable, str(ROOT / "studies" / "accuracy" / "accuracy_study.py"), "--adaptive", "--short",
                           "--bin", str(fekap), "--plot", str(png), "--repeat", "1"],
                          capture_output=True, text=True, timeout=900)
    check(done.returncode == 0, done.stdout + done.stderr)
    for case in ("pendulum", "double pendulum", "flexible slider-crank"):
        for kind in ("fixed", "adaptive"):
            check(f"| {case} | {kind} |" in done.stdout, f"no {kind} row of {case}:\n{done.stdout}")
    check(png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "no PNG written")
