"""Objective Rayleigh damping in dynamics (docs/dynamics.md, "Damping"): the
stiffness-proportional part beta K_m(q) v damps the strain rates at the
current configuration, so a rigidly spinning beam keeps its speed under it
(with the damping frozen at each step's start, c07fa78, the hinged beam below
was dragged from 6 to 0.37 rad/s in 5 s, and the spin-up beam with
beta = 0.01 to a tip deflection of -0.97), and the spin-up beam with
beta = 0.01 reaches 6 rad/s with its centrifugal stretch while its residual
vibration decays."""

from __future__ import annotations

import math
import re
from pathlib import Path

from fekap import dynamics as dc

from apptest import ROOT, check, read_rows, run_fekap

#: The spin-up deck (decks/dynamics/spin-up.deck) without its drive: the hinged beam started
#: spinning rigidly at 6 rad/s (VELOcities), for 5 s (4.8 turns).
SPIN_UP = ROOT / "decks" / "dynamics" / "spin-up.deck"


#: The static centrifugal stretch of the spin-up beam's tip at 6 rad/s (docs/dynamics.md).
CENTRIFUGAL_STRETCH = 5.14317e-4

#: Exudyn 1.13.6's geometrically exact 2D beam on the spin-up deck with strain-rate damping
#: beta = 0.01 (objective; 10 elements, dt 0.01): `studies/exudyn/exudyn_spin_up.py --beta 0.01
#: --cases 10:0.01` (bench@38ed830). Peak transverse tip deflection in the hub's frame and
#: its time, the deflection at t = 15 s, its largest magnitude after 15 s, the mean axial
#: stretch over 20-30 s.
EXUDYN_DAMPED = {"peak": -0.57275, "t_peak": 6.823, "at15": 1.607e-3, "residual": 2.160e-3, "stretch": 5.14570e-4}


def spinning(tmp_path: Path, name: str, beta: float, integrator: str) -> tuple[list[dict[str, str]], list[dict[str, str]]]:
    """points.csv's rows of the tip and energy.csv's rows of a spinning-beam run."""
    text = re.sub(r"DRIVes\n  rotation OT  table [^\n]*\n", "VELOcities\n  OT  0  0  6\n", SPIN_UP.read_text())
    text = text.replace("rhoI=6e-4", f"rhoI=6e-4  beta={beta!r}").replace(
        "  type dynamics\n", f"  type dynamics\n  integrator {integrator}\n")
    check("VELOcities" in text and "beta=" in text and "integrator" in text, "the spin-up deck changed its form")
    deck = tmp_path / f"{name}.deck"
    deck.write_text(text)
    out = tmp_path / name
    run = run_fekap("-q", str(deck), "-o", str(out), "--set", "t_end=5")
    check(run.returncode == 0, f"{name} failed: {run.stderr}")
    return read_rows(out / "points.csv"), read_rows(out / "energy.csv")


def tip_rate(row: dict[str, str]) -> float:
    """The tip's angular rate about the hinge, (x cross v) / |x|^2."""
    x, y, vx, vy = (float(row[key]) for key in ("x", "y", "vx", "vy"))
    return (x * vy - y * vx) / (x * x + y * y)


def test_spinning_beam_with_beta_damping_keeps_its_speed(tmp_path: Path) -> None:
    """Generalized-alpha (0.8, dt 0.01, 5 s = 4.8 turns): with beta = 0.01 the tip's
    rate at 5 s is the undamped run's to 2e-5 relative (6.1e-6 measured; both
    5.9935, GA's own loss of angular momentum at this step over the start's
    axial transient), and the damping dissipates less than 2e-4 of the kinetic
    energy (0.48 J of 7200 J measured: the start's axial vibration).
    Energy-momentum (rho_inf 1): the angular momentum stays 2400.036 to 1e-9
    relative, the balance closes to 2e-6 J (8.7e-7 measured with the Cayley update,
    2.8e-10 of the kinetic energy: the work of the residual Newton leaves at its
    round-off floor, about 4e-7 N here, 500 steps), the tip's rate ends within 1e-3 of
    6 rad/s (5.99926 measured: the stretched beam's larger inertia) and its
    radius at the centrifugal stretch to 1e-3 relative (2e-4 measured)."""
    undamped, _ = spinning(tmp_path, "undamped", 0.0, "generalized-alpha")
    damped, energy = spinning(tmp_path, "damped", 0.01, "generalized-alpha")
    free, damped_rate = tip_rate(undamped[-1]), tip_rate(damped[-1])
    check(abs(damped_rate - free) < 2e-5 * free, f"rate {damped_rate!r} against undamped {free!r}")
    kinetic = float(energy[0]["kinetic"])
    dissipated = float(energy[-1]["dissipated"])
    check(0 < dissipated < 2e-4 * kinetic, f"dissipated {dissipated!r} J of {kinetic!r} J")
    points, energy = spinning(tmp_path, "em", 0.01, "energy-momentum")
    angular = [float(row["angular"]) for row in energy]
    check(max(angular) - min(angular) < 1e-9 * angular[0], f"angular momentum {min(angular)!r}..{max(angular)!r}")
    worst = max(abs(float(row["balance"])) for row in energy)
    check(worst < 2e-6, f"energy balance {worst!r} J")
    check(float(energy[-1]["dissipated"]) > 0, "nothing dissipated")
    rate = tip_rate(points[-1])
    check(abs(rate - 6) < 1e-3, f"tip rate {rate!r}")
    radius = math.hypot(float(points[-1]["x"]), float(points[-1]["y"]))
    check(abs(radius - 10 - CENTRIFUGAL_STRETCH) < 1e-3 * CENTRIFUGAL_STRETCH, f"tip stretch {radius - 10!r}")


def test_spin_up_beam_with_beta_reaches_its_speed_and_stretch(tmp_path: Path) -> None:
    """decks/dynamics/spin-up.deck with beta = 0.01 (dt 0.01): the tip turns at the
    hub's 6 rad/s (its rate's mean over 20-30 s within 5e-3: 1.9e-3 measured, the
    residual vibration's rate, 7.6 rad/s x 2e-3 m / 10 m, in it), its mean axial
    stretch over 20-30 s is the centrifugal one to 1e-3 relative (5.1457e-4
    measured, 5.4e-4 off), the spin-up's peak deflection is the undamped one's
    to 1 % (-0.5728 against -0.5738), and the residual transverse vibration
    decays: its largest value over 25-30 s is below 0.65 of that over 15-20 s
    (0.52 measured; the first mode's decay rate beta omega_b^2 / 2 = 0.072/s with
    omega_b = 3.80 rad/s the non-rotating first bending frequency gives
    e^-0.72 = 0.49 over 10 s), where the undamped beam keeps 3.78e-3.
    Against Exudyn's objective strain-rate damping on the same model (EXUDYN_DAMPED,
    an independent code): peak within 5e-4 relative (1.0e-4 measured) and 0.01 s
    (3e-3 s), the deflection at 15 s and the largest after 15 s within 5 % (2.1 %,
    1.4 %), the mean stretch within 2e-5 relative (2e-6)."""
    deck = tmp_path / "spin-up.deck"
    deck.write_text((ROOT / "decks" / "dynamics" / "spin-up.deck").read_text().replace(
        "rhoI=6e-4", "rhoI=6e-4  beta=0.01"))
    out = tmp_path / "out"
    run = run_fekap("-q", str(deck), "-o", str(out))
    check(run.returncode == 0, f"spin-up failed: {run.stderr}")
    points = read_rows(out / "points.csv")
    # The hub's frame: the drive's rotation (links.csv's angle is the bent beam's chord).
    hub = dc.spin_up_hub_angle([float(p["t"]) for p in points])
    rows = [(float(p["t"]), float(p["x"]), float(p["y"]), float(a), tip_rate(p)) for p, a in zip(points, hub)]
    across = [(t, -x * math.sin(a) + y * math.cos(a)) for t, x, y, a, _ in rows]
    along = [x * math.cos(a) + y * math.sin(a) - 10 for t, x, y, a, _ in rows if t >= 20]
    rates = [r for t, *_, r in rows if t >= 20]
    rate = sum(rates) / len(rates)
    check(abs(rate - 6) < 5e-3, f"mean tip rate {rate!r}")
    stretch = sum(along) / len(along)
    check(abs(stretch - CENTRIFUGAL_STRETCH) < 1e-3 * CENTRIFUGAL_STRETCH, f"mean stretch {stretch!r}")
    peak = min(v for _, v in across)
    check(abs(peak + 0.5738) < 0.01 * 0.5738, f"peak deflection {peak!r}")
    t_peak = min(across, key=lambda row: row[1])[0]
    at15 = next(v for t, v in across if t >= 15 - 1e-9)
    residual = max(abs(v) for t, v in across if t >= 15 - 1e-9)
    exudyn = EXUDYN_DAMPED
    check(abs(peak - exudyn["peak"]) < 5e-4 * abs(exudyn["peak"]) and abs(t_peak - exudyn["t_peak"]) < 0.01,
          f"peak {peak!r} at {t_peak!r} against Exudyn's {exudyn['peak']} at {exudyn['t_peak']}")
    check(abs(at15 - exudyn["at15"]) < 0.05 * exudyn["at15"], f"at 15 s {at15!r} against Exudyn's {exudyn['at15']}")
    check(abs(residual - exudyn["residual"]) < 0.05 * exudyn["residual"],
          f"largest after 15 s {residual!r} against Exudyn's {exudyn['residual']}")
    check(abs(stretch - exudyn["stretch"]) < 2e-5 * exudyn["stretch"],
          f"mean stretch {stretch!r} against Exudyn's {exudyn['stretch']}")
    early = max(abs(v) for t, v in across if 15 <= t <= 20)
    late = max(abs(v) for t, v in across if t >= 25)
    check(late < 0.65 * early and early < 3e-3, f"residual vibration {early!r} then {late!r}")
