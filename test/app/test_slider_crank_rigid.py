"""The standard flexible slider-crank (decks/dynamics/slider-crank-rigid-crank.deck: rigid
crank 0.15 m at 150 rad/s, rod 0.30 m of 6 mm round steel, massless slider) against
answers found without FEKAP:

- the published first peak of the rod's midpoint deflection, about 5.1 mm at about
  5.5 ms (Simo & Vu-Quoc 1986 and the SPACAR / Bauchau slider-crank; read off their
  figures, two digits: here within 2 % and 0.15 ms);
- Exudyn 1.13.6's converged run of the same model (its geometrically exact 2D beam,
  extrapolated from 8, 16 and 32 rod elements at dt 2.5e-6: test/app/data/
  slider-crank-rigid-exudyn.csv, written by studies/exudyn/exudyn_slider_crank_rigid.py --store;
  stored, so no Exudyn is needed here);

and the convergence of FEKAP's own answer: as the rod's element count doubles (dt fixed)
and as dt halves (mesh fixed) the differences of successive runs fall at the observed
order 2 (generalized-alpha and the linear Reissner element with one Gauss point are both
second order), and the mesh's extrapolation lands on Exudyn's converged answer.

The midpoint deflection is the distance of node M from the line AB. The mesh's runs start
as the benchmark (and Exudyn) does, from the undeformed rod (`start unstrained`), the
step's runs from the deck's `start consistent` (why: there); the two starts are checked
against each other."""

from __future__ import annotations

import csv
import math
from pathlib import Path

from apptest import ROOT, check, read_rows, run_fekap

DECK = ROOT / "decks" / "dynamics" / "slider-crank-rigid-crank.deck"
EXUDYN = ROOT / "test" / "app" / "data" / "slider-crank-rigid-exudyn.csv"
SAMPLE = 1e-4  # compared every 0.1 ms

#: The published first peak (m, s) and the tolerances of a value read off a figure.
PUBLISHED_PEAK, PUBLISHED_TIME = 5.1e-3, 5.5e-3
PEAK_TOL, TIME_TOL = 0.02, 0.15e-3

OUT: Path = None  # a fresh scratch directory, set by conftest.py


def deck_text(start: str = "consistent") -> str:
    text = DECK.read_text()
    check("  start consistent" in text, f"{DECK}: the ANALysis block no longer says `start consistent`")
    return text.replace("  start consistent", f"  start {start}")


def deflections(n: int, dt: float, t_end: float, start: str = "unstrained") -> dict[int, float]:
    """The rod's midpoint deflection at the instants k * SAMPLE (key k) of a run with n
    elements per half rod."""
    name = f"n{n}-dt{dt:g}-{start}"
    outdir = OUT / name
    outdir.mkdir(parents=True, exist_ok=True)
    deck = outdir / "rigid.deck"
    deck.write_text(deck_text(start))
    run = run_fekap(str(deck), "-q", "-o", str(outdir), "--set", f"n={n}", "--set", f"dt={dt!r}",
                    "--set", f"t_end={t_end!r}")
    check(run.returncode == 0, f"{name} failed: {run.stderr}")
    points: dict[int, dict[str, tuple[float, float]]] = {}
    times: dict[int, float] = {}
    for row in read_rows(outdir / "points.csv"):
        step = int(row["step"])
        points.setdefault(step, {})[row["point"]] = (float(row["x"]), float(row["y"]))
        times[step] = float(row["t"])
    out = {}
    for step, p in points.items():
        k = round(times[step] / SAMPLE)
        if abs(times[step] - k * SAMPLE) > 1e-9 * SAMPLE:
            continue
        (ax, ay), (mx, my), (bx, by) = p["A"], p["M"], p["B"]
        out[k] = ((mx - ax) * (by - ay) - (my - ay) * (bx - ax)) / math.hypot(bx - ax, by - ay)
    check(len(out) >= round(t_end / SAMPLE), f"{name}: {len(out)} instants on the 0.1 ms grid")
    return out


def worst(a: dict[int, float], b: dict[int, float]) -> float:
    common = set(a) & set(b)
    check(bool(common), "no common instants")
    return max(abs(a[k] - b[k]) for k in common)


def first_peak(series: dict[int, float]) -> tuple[float, float]:
    """(time, |deflection|) of the first local maximum of |deflection| above 1 mm,
    refined by the parabola through the three samples around it."""
    keys = sorted(series)
    for i in range(1, len(keys) - 1):
        y0, y1, y2 = (abs(series[keys[j]]) for j in (i - 1, i, i + 1))
        if y1 > 1e-3 and y1 >= y0 and y1 > y2:
            shift = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
            return (keys[i] + shift) * SAMPLE, y1 - 0.25 * (y0 - y2) * shift
    raise AssertionError("no peak of the midpoint deflection above 1 mm")


def observed_order(runs: list[dict[int, float]]) -> tuple[float, float, float]:
    d1, d2 = worst(runs[0], runs[1]), worst(runs[1], runs[2])
    return math.log2(d1 / d2), d1, d2


def exudyn() -> dict[int, float]:
    with open(EXUDYN, newline="") as handle:
        rows = csv.DictReader(line for line in handle if not line.startswith("#"))
        return {round(float(r["t"]) / SAMPLE): float(r["deflection"]) for r in rows}


def test_rigid_crank_first_peak_is_the_published_one() -> None:
    """The deck as shipped (16 rod elements, dt 2e-5, start consistent): the first peak of
    the midpoint deflection within 2 % of 5.1 mm and 0.15 ms of 5.5 ms; the literal
    benchmark's start (the rod undeformed) within 1e-5 m (0.2 % of the peak) of it."""
    consistent = deflections(8, 2e-5, 0.01, "consistent")
    t_peak, peak = first_peak(consistent)
    check(abs(peak - PUBLISHED_PEAK) <= PEAK_TOL * PUBLISHED_PEAK,
          f"first peak {peak:.4e} m, published {PUBLISHED_PEAK} m (tolerance {PEAK_TOL:.0%})")
    check(abs(t_peak - PUBLISHED_TIME) <= TIME_TOL,
          f"first peak at {t_peak:.5f} s, published {PUBLISHED_TIME} s (tolerance {TIME_TOL} s)")
    unstrained = deflections(8, 2e-5, 0.01, "unstrained")
    gap = worst(consistent, unstrained)
    check(gap <= 1e-5, f"start consistent against unstrained: {gap:.3e} m apart")


def test_rigid_crank_converges_as_the_rod_mesh_doubles() -> None:
    """8, 16, 32 rod elements at dt 1e-5 over 10 ms: the differences of successive runs
    fall at the observed order 2 (1.8 to 2.3); their distances from Exudyn's converged run
    fall at least at order 1.6 (that run carries an error of its own of a few 1e-6 m: its
    extrapolation from 8, 16 and 32 elements); the mesh's extrapolation from 16 and 32
    elements is within 1e-5 m of it (0.2 % of the peak) and at most half as far as the
    32-element run. Exudyn's stored first peak is itself the published one."""
    runs = [deflections(n, 1e-5, 0.01) for n in (4, 8, 16)]
    order, d1, d2 = observed_order(runs)
    check(1.8 <= order <= 2.3, f"observed order in the mesh {order:.2f} (differences {d1:.3e}, {d2:.3e} m)")
    reference = exudyn()
    t_peak, peak = first_peak(reference)
    check(abs(peak - PUBLISHED_PEAK) <= PEAK_TOL * PUBLISHED_PEAK and abs(t_peak - PUBLISHED_TIME) <= TIME_TOL,
          f"Exudyn's stored first peak {peak:.4e} m at {t_peak:.5f} s is not the published one")
    errors = [worst(run, reference) for run in runs]
    orders = [math.log2(errors[0] / errors[1]), math.log2(errors[1] / errors[2])]
    check(min(orders) >= 1.6, f"distances from Exudyn's answer {errors} m fall at orders {orders}")
    extrapolated = {k: v + (v - runs[1][k]) / 3 for k, v in runs[2].items()}
    error = worst(extrapolated, reference)
    check(error <= 1e-5 and error <= 0.5 * errors[2],
          f"extrapolated mesh answer {error:.3e} m from Exudyn's (32 elements: {errors[2]:.3e} m)")


def test_rigid_crank_converges_as_dt_halves() -> None:
    """16 rod elements, dt 5e-5, 2.5e-5, 1.25e-5 over 20 ms, the deck's consistent start:
    the differences of successive runs fall at the observed order 2 (1.8 to 2.3). (From
    the undeformed rod the rod's axial vibration, 8 kHz and a few 1e-6 m in the deflection,
    is part of the answer; generalized-alpha damps it at a rate that depends on dt until dt
    resolves it: from dt 5e-5 to 1.25e-5 the differences stall near 8e-6 m, from 1e-5 to
    1.25e-6 they fall at order 1.9.)"""
    runs = [deflections(8, dt, 0.02, "consistent") for dt in (5e-5, 2.5e-5, 1.25e-5)]
    order, d1, d2 = observed_order(runs)
    check(1.8 <= order <= 2.3, f"observed order in dt {order:.2f} (differences {d1:.3e}, {d2:.3e} m)")
