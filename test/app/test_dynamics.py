"""The dynamics benchmarks of decks/dynamics/ against their exact answers
(issue 19 item 4), run through the command line: the stiff pendulum's first
pass through the bottom, and the A02 N-four-bar (N = 2 and 40) against its
energy integral, with the energy balance of energy.csv."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from apptest import ROOT, check, read_rows, run_fekap

#: The rigid pendulum (L = 1, g = 9.81) released from the horizontal: T/4 and the speed there.
BOTTOM_TIME = 0.591960487
BOTTOM_SPEED = 4.429446918


def run_deck(deck: str, outdir: Path, *args: str) -> None:
    run = run_fekap(str(ROOT / "decks" / "dynamics" / deck), "-o", str(outdir), *args)
    check(run.returncode == 0, f"{deck} failed: {run.stderr}")


def test_pendulum_deck_passes_the_bottom_at_the_exact_time(tmp_path: Path) -> None:
    run_deck("pendulum.deck", tmp_path)
    rows = read_rows(tmp_path / "points.csv")
    listing = (tmp_path / "pendulum.lis").read_text()
    check("effects: dynamics (ANALysis type dynamics)" in listing, "the plan does not say dynamics")
    for before, after in zip(rows, rows[1:]):
        x0, x1 = float(before["x"]), float(after["x"])
        if x0 > 0 >= x1:
            t0, t1 = float(before["t"]), float(after["t"])
            h = t1 - t0
            v0, v1 = float(before["vx"]) * h, float(after["vx"]) * h
            s = x0 / (x0 - x1)
            for _ in range(30):  # the cubic Hermite interpolant of x through both steps
                f = (2*s**3 - 3*s**2 + 1)*x0 + (s**3 - 2*s**2 + s)*v0 + (-2*s**3 + 3*s**2)*x1 + (s**3 - s**2)*v1
                df = (6*s**2 - 6*s)*x0 + (3*s**2 - 4*s + 1)*v0 + (-6*s**2 + 6*s)*x1 + (3*s**2 - 2*s)*v1
                s -= f / df
            t = t0 + s * h
            speed = (1 - s) * math.hypot(float(before["vx"]), float(before["vy"])) + \
                s * math.hypot(float(after["vx"]), float(after["vy"]))
            check(abs(t - BOTTOM_TIME) < 1e-5, f"bottom pass at t = {t!r}, exact {BOTTOM_TIME}")
            check(abs(speed - BOTTOM_SPEED) < 1e-5 * BOTTOM_SPEED, f"speed {speed!r}, exact {BOTTOM_SPEED}")
            break
    else:
        check(False, "the pendulum did not reach the bottom")
    energy = read_rows(tmp_path / "energy.csv")
    worst = max(abs(float(row["balance"])) for row in energy)
    check(worst < 1e-4 * 9.81, f"energy balance {worst!r} J")


def a02_errors(outdir: Path, n: int) -> tuple[float, float, float, float]:
    """Worst errors of the first crank's rate (away from the change points)
    and angle against the energy integral, the worst energy balance, and the
    last angle."""
    inertia = (n + 1) / 3 + n
    moment = ((n + 1) / 2 + n) * 9.81
    rows = read_rows(outdir / "links.csv")
    y = [math.pi / 2, -1.0]

    def f(y: list[float]) -> list[float]:
        return [y[1], -moment / inertia * math.cos(y[0])]

    worst_rate = worst_angle = 0.0
    previous = 0.0
    for row in rows:
        t = float(row["t"])
        sub = 50
        h = (t - previous) / sub
        for _ in range(sub if t > previous else 0):  # RK4 of I theta'' = -G cos(theta)
            k1 = f(y)
            k2 = f([y[i] + h / 2 * k1[i] for i in range(2)])
            k3 = f([y[i] + h / 2 * k2[i] for i in range(2)])
            k4 = f([y[i] + h * k3[i] for i in range(2)])
            y = [y[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]) for i in range(2)]
        previous = t
        angle, omega = float(row["angle"]), float(row["omega"])
        exact = -math.sqrt(1 + 2 * moment / inertia * (1 - math.sin(angle)))
        # Within 0.15 rad of a change point the elastic couplers swing briefly.
        if abs(math.sin(angle)) > 0.15:
            worst_rate = max(worst_rate, abs(omega - exact))
        worst_angle = max(worst_angle, abs(angle - y[0]))
    balance = max(abs(float(row["balance"])) for row in read_rows(outdir / "energy.csv"))
    return worst_rate, worst_angle, balance / moment, float(rows[-1]["angle"])


def test_a02_two_four_bar_follows_its_energy_integral(tmp_path: Path) -> None:
    run_deck("a02-n2.deck", tmp_path)
    listing = (tmp_path / "a02-n2.lis").read_text()
    check("effects: dynamics (auto: masses on a flexible scene without drives)" in listing, "auto did not choose dynamics")
    rate, angle, balance, last = a02_errors(tmp_path, 2)
    check(last < -6 * math.pi, f"the chain did not go round three times: last angle {last}")
    check(rate < 1e-3, f"crank rate {rate!r} off its energy integral")
    check(angle < 5e-3, f"crank angle {angle!r} rad off its energy integral over 20 s")
    check(balance < 1e-3, f"energy balance {balance!r} of G")


def test_a02_forty_four_bar_follows_its_energy_integral(tmp_path: Path) -> None:
    run_deck("a02-n40.deck", tmp_path, "--set", "t_end=5")
    rate, angle, balance, last = a02_errors(tmp_path, 40)
    check(last < -2 * math.pi, f"the chain did not go round: last angle {last}")
    check(rate < 2e-3, f"crank rate {rate!r} off its energy integral")
    check(angle < 2e-3, f"crank angle {angle!r} rad off its energy integral over 5 s")
    check(balance < 1e-3, f"energy balance {balance!r} of G")


def test_spin_up_beam_settles_at_the_centrifugal_stretch(tmp_path: Path) -> None:
    """Simo and Vu-Quoc's spin-up beam: the tip's axial stretch in the hub's
    frame settles at 5.1432e-4 (mean over 20-30 s, measured 5.1427e-4), and
    after the spin-up the transverse tip deflection stays within 0.01 (it is
    about -0.5 while the hub accelerates, as published)."""
    run_deck("spin-up.deck", tmp_path)
    points = read_rows(tmp_path / "points.csv")
    links = read_rows(tmp_path / "links.csv")
    axial, transverse, peak = [], [], 0.0
    for p, l in zip(points, links):
        t, angle = float(p["t"]), float(l["angle"])
        x, y = float(p["x"]), float(p["y"])
        along = x * math.cos(angle) + y * math.sin(angle) - 10
        across = -x * math.sin(angle) + y * math.cos(angle)
        if t >= 20:
            axial.append(along)
        if t >= 16:
            transverse.append(abs(across))
        peak = min(peak, across)
    stretch = sum(axial) / len(axial)
    check(abs(stretch - 5.1432e-4) < 1e-3 * 5.1432e-4, f"tip axial stretch {stretch!r}, published 5.1432e-4")
    check(max(transverse) < 0.01, f"transverse tip deflection {max(transverse)!r} after the spin-up")
    check(-0.7 < peak < -0.4, f"transverse tip deflection during the spin-up peaks at {peak!r}")


def pendulum_variant(tmp_path: Path, extra: str) -> Path:
    """decks/dynamics/pendulum.deck with a second link and `extra` cards before END."""
    text = (ROOT / "decks" / "dynamics" / "pendulum.deck").read_text()
    text = text.replace("  B   1   0\n", "  B   1   0\n  C   2   0\n").replace(
        "  AB  A  B  rod  1\n", "  AB  A  B  rod  1\n  BC  B  C  rod  1\n").replace(
        "  B  1\n", "  B  1\n  C  1\n").replace("END", extra + "END")
    deck = tmp_path / "variant.deck"
    deck.write_text(text)
    return deck


@pytest.mark.parametrize("card, message", [
    ("VELOcities\n  XY 0 0 1\n", "undefined link 'XY'"),
    ("VELOcities\n  AB 0 0\n", "missing field 'omega'"),
    ("VELOcities\n  AB 0 0 1 2\n", "a VELOcities line has 4 fields"),
    ("VELOcities\n  AB 0 0 1\n  AB 0 0 1\n", "link AB has a velocity already"),
    ("VELOcities\n  AB 0 0 1\n  BC 0 0 1\n", "links AB and BC give node B different velocities"),
    ("VELOcities\n  AB 0 0 1e20\n", "velocity too large"),
])
def test_bad_start_velocities_are_deck_errors(tmp_path: Path, card: str, message: str) -> None:
    run = run_fekap("-q", "-o", str(tmp_path / "out"), str(pendulum_variant(tmp_path, card)))
    check(run.returncode == 2, f"exit {run.returncode}: {run.stderr}")
    check(message in run.stderr, f"no '{message}' in: {run.stderr}")


def test_start_velocities_of_two_links_that_agree(tmp_path: Path) -> None:
    """AB turning at 1 rad/s about A and BC translating with B (0, 1): B's
    velocity agrees; the run starts with it."""
    deck = pendulum_variant(tmp_path, "VELOcities\n  AB 0 0 1\n  BC 0 1 0\n")
    out = tmp_path / "out"
    run = run_fekap("-q", "-o", str(out), str(deck))
    check(run.returncode == 0, run.stderr)
    first = [row for row in read_rows(out / "points.csv") if row["step"] == "0" and row["point"] == "B"]
    check(first and abs(float(first[0]["vy"]) - 1) < 1e-12, f"B's start velocity: {first}")


def spaghetti(tmp_path: Path, rho_inf: float) -> list[dict[str, float]]:
    out = tmp_path / f"rho{rho_inf}"
    run_deck("flying-spaghetti.deck", out, "--set", f"rho_inf={rho_inf}")
    return [{key: float(value) for key, value in row.items()} for row in read_rows(out / "energy.csv")]


def test_flying_spaghetti_keeps_momentum_and_energy(tmp_path: Path) -> None:
    """Simo and Vu-Quoc's flying spaghetti, 10 elements, dt 0.01, to t = 15.
    After the loads (t >= 5): linear momentum 20 N s along x to round-off
    (rho_inf = 1 from t = 5; rho_inf = 0.8 from t = 6, once the integrator's
    filter of the accelerations has settled); with rho_inf = 1 the angular
    momentum and the energy constant to 1e-5 (measured 2.7e-6 and 3.3e-6).
    With rho_inf = 0.8 the energy ends below its value at t = 5 and below
    the rho_inf = 1 run's, and never exceeds it by 1e-5 (step to step it
    moves both ways by up to 2e-7: the decay is not monotone at this dt)."""
    rows = {rho: spaghetti(tmp_path, rho) for rho in (1.0, 0.8)}
    for rho, settle in ((1.0, 5.0), (0.8, 6.0)):
        after = [row for row in rows[rho] if row["t"] >= settle - 1e-9]
        check(all(abs(row["px"] - 20) < 1e-11 and abs(row["py"]) < 1e-11 for row in after),
              f"rho_inf {rho}: momentum after t = {settle} is not (20, 0)")
    free = [row for row in rows[1.0] if row["t"] >= 5 - 1e-9]
    angular = [row["angular"] for row in free]
    energy = [row["kinetic"] + row["strain"] for row in free]
    check(max(angular) - min(angular) < 1e-5 * abs(angular[0]), f"angular momentum varies by {max(angular) - min(angular)!r}")
    check(max(energy) - min(energy) < 1e-5 * energy[0], f"energy varies by {max(energy) - min(energy)!r}")
    damped = [row["kinetic"] + row["strain"] for row in rows[0.8] if row["t"] >= 5 - 1e-9]
    check(damped[-1] < damped[0] and damped[-1] < energy[-1], "no energy decay with rho_inf = 0.8")
    check(max(damped) < damped[0] * (1 + 1e-5), f"energy grew to {max(damped)!r} from {damped[0]!r}")


def slider_drop(tmp_path: Path, name: str, *sets: str) -> list[dict[str, float]]:
    out = tmp_path / name
    args = [arg for s in sets for arg in ("--set", s)]
    run_deck("slider-drop.deck", out, "-q", *args)
    return [{key: float(value) for key, value in row.items()} for row in read_rows(out / "energy.csv")]


def test_slideline_penalty_energy_closes_the_balance(tmp_path: Path) -> None:
    """decks/dynamics/slider-drop.deck (a slider-crank falling under gravity, a soft slideline,
    rho_inf = 1, dt 1e-3, 2 s): the slideline's spring holds up to 0.49 J (the penalty column);
    with it the balance stays within 1.5e-3 J (8.9e-4 measured) of the 27 J that move between
    kinetic and potential energy, 300 times less than the penalty energy left out would make
    it; half the step quarters it (second order, 2.2e-4 measured)."""
    energy = slider_drop(tmp_path, "undamped")
    penalty = max(row["penalty"] for row in energy)
    worst = max(abs(row["balance"]) for row in energy)
    check(max(row["kinetic"] for row in energy) > 20, "the mechanism does not fall")
    check(penalty > 0.3, f"penalty energy {penalty!r} J")
    check(worst < 1.5e-3, f"energy balance {worst!r} J")
    check(all(row["dissipated"] == 0 for row in energy), "nothing dissipates without damping")
    # The balance counts the penalty energy: without it the balance would be off by this much.
    check(max(abs(row["balance"] - row["penalty"]) for row in energy) > 100 * worst, "penalty too small to tell")
    halved = slider_drop(tmp_path, "halved", "dt=5e-4")
    check(max(abs(row["balance"]) for row in halved) < worst / 3, "the balance is not second order in dt")


def test_slideline_dashpot_dissipates_into_the_balance(tmp_path: Path) -> None:
    """The same with a dashpot of 200 N s/m on the gap rate: its work (the dissipated column,
    0.10 J measured) grows monotonically, the balance still closes within 1.5e-3 J, and the
    slideline's spring oscillation is damped (its largest energy 0.12 J against 0.49 J)."""
    undamped = slider_drop(tmp_path, "undamped")
    damped = slider_drop(tmp_path, "damped", "c=200")
    dissipated = [row["dissipated"] for row in damped]
    check(dissipated[-1] > 0.05, f"dissipated {dissipated[-1]!r} J")
    check(all(b >= a for a, b in zip(dissipated, dissipated[1:])), "the dashpot's work decreases")
    worst = max(abs(row["balance"]) for row in damped)
    check(worst < 1.5e-3, f"energy balance {worst!r} J")
    check(max(row["penalty"] for row in damped) < 0.5 * max(row["penalty"] for row in undamped),
          "the dashpot does not damp the slideline's oscillation")
