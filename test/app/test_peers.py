"""studies/bench/peers.py's parts that do not time (Example 1 in FEKAP, Exudyn and
pylinkage): the check of a trajectory against the closed form, which must catch a wrong
position, velocity, time or NaN; the table of docs/performance.md's peers block; and,
where Exudyn or pylinkage import (build/venv-exudyn, not build/venv), the peers' models of
Example 1 on a few steps against the closed form. Nothing here is timed.

Run with scripts/test peers (pytest)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from apptest import check, study_module

peers = study_module("bench/peers.py")

#: The closed form's round-off: lengths of 2-4, positions to a few ulp.
ROUND_OFF = 1e-13


def closed_form_rows(steps: int, start: int = 0) -> tuple[np.ndarray, dict]:
    """A trajectory that is the closed form itself, rows start..steps (t = k dt)."""
    exact = peers.exact_trajectory(steps)
    k = np.arange(start, steps + 1)
    return peers.DT * k, {key: values[k].copy() for key, values in exact.items()}


def test_closed_form_is_the_four_bar() -> None:
    """exact_trajectory is Example 1: the links keep their lengths at every step, C stays
    on the upper branch, B turns at 2 pi rad/s (|vB| = 4 pi), and the rates are the
    differences of the positions (central differences, error O(dt^2))."""
    exact = peers.exact_trajectory(400, dt=1e-3)
    a, d = np.array(peers.POINTS["A"]), np.array(peers.POINTS["D"])
    b, c = exact["B"], exact["C"]
    for name, length, values in (("AB", 2.0, np.linalg.norm(b - a, axis=1)), ("BC", 4.0, np.linalg.norm(c - b, axis=1)),
                                 ("DC", 4.0, np.linalg.norm(c - d, axis=1))):
        check(np.abs(values - length).max() < ROUND_OFF, f"{name}: length off by {np.abs(values - length).max():.1e}")
    check(c[:, 1].min() > 0, "C left the upper branch")
    speed = np.linalg.norm(exact["vB"], axis=1)
    check(np.abs(speed - 4 * math.pi).max() < 1e-12, "B's speed is not 4 pi")
    for rate, of in (("vC", "C"), ("aC", "vC")):
        difference = (exact[of][2:] - exact[of][:-2]) / 2e-3
        off = np.abs(difference - exact[rate][1:-1]).max()
        check(off < 1e-3 * np.abs(exact[rate]).max(), f"{rate} is not the rate of {of}: {off:.1e}")


def test_errors_of_the_closed_form_itself_are_round_off() -> None:
    """Rows from t = dt (pylinkage's) or t = 0 (FEKAP's, Exudyn's): no error; what was
    not given is None."""
    exact = peers.exact_trajectory(50)
    for start in (0, 1):
        t, series = closed_form_rows(50, start)
        errors = peers.trajectory_errors(t, series, exact)
        check(all(errors[what] == 0.0 for what in ("position", "velocity", "acceleration")),
              f"rows from {start}: {errors}")
        positions = {key: series[key] for key in ("B", "C")}
        errors = peers.trajectory_errors(t, positions, exact)
        check(errors == {"position": 0.0, "velocity": None, "acceleration": None}, f"positions only: {errors}")


def test_a_wrong_answer_shows() -> None:
    """A position, a velocity or an acceleration off at one row is reported with the size
    of its error; a NaN counts as an infinite error."""
    exact = peers.exact_trajectory(40)
    for key, what in (("C", "position"), ("B", "position"), ("vC", "velocity"), ("aB", "acceleration")):
        t, series = closed_form_rows(40)
        series[key][17, 1] += 3e-7
        errors = peers.trajectory_errors(t, series, exact)
        check(abs(errors[what] - 3e-7) < 1e-12, f"{key} off by 3e-7 at row 17: {errors}")
    t, series = closed_form_rows(40)
    series["C"][5, 0] = math.nan
    check(peers.trajectory_errors(t, series, exact)["position"] == math.inf, "a NaN position was not caught")


def test_rows_off_the_time_grid_or_incomplete_are_refused() -> None:
    """A row at a time that is no step, beyond the closed form's range, or a series of
    the wrong length is an error, not a comparison with the wrong instant."""
    exact = peers.exact_trajectory(20)
    t, series = closed_form_rows(20)
    with pytest.raises(ValueError, match="not a step"):
        peers.trajectory_errors(t + peers.DT / 2, series, exact)       # half a step late
    with pytest.raises(ValueError, match="not a step"):
        peers.trajectory_errors(t + 5 * peers.DT, series, exact)       # beyond the closed form's range
    with pytest.raises(ValueError, match="shape"):
        peers.trajectory_errors(t[:-1], series, exact)
    with pytest.raises(ValueError, match="positions of B and C"):
        peers.trajectory_errors(t, {"B": series["B"]}, exact)


def result(code: str, computes: str, us: float, position: float, velocity=None, instructions=None) -> dict:
    return {"code": code, "computes": computes, "how": "how", "us_median": us, "us_min": us * 0.9,
            "us_rounds": [us], "newton_per_configuration": 1.0 if code == "FEKAP" else None,
            "position": position, "velocity": velocity, "acceleration": velocity,
            "instructions_per_configuration": instructions}


def test_table_rows_and_ratios() -> None:
    """One row a case; each row's ratio is its median over FEKAP's for the same quantities
    with the listing alone; the header names the command and the load."""
    results = {"fekap P listing": result("FEKAP", "P", 2.0, 3.6e-15, instructions=27366.4),
               "fekap PVA listing": result("FEKAP", "PVA", 4.0, 3.6e-15, 3.9e-14),
               "exudyn rigid": result("Exudyn 1.13.6", "P", 10.0, 2.7e-13),
               "pylinkage derivatives": result("pylinkage 1.3.0", "PVA", 30.0, 5.5e-14, 6.1e-13, 1234.0)}
    ratios = peers.ratios(results)
    check(ratios == {"fekap P listing": 1.0, "fekap PVA listing": 1.0, "exudyn rigid": 5.0,
                     "pylinkage derivatives": 7.5}, f"ratios {ratios}")
    meta = {"command": "studies/bench/peers.py --repeat 3", "date": "2026-11-28 18:00 UTC", "binary": "FEKAP x",
            "load_start": 12.34, "load_end": 9.87, "minutes": 4.2, "short": 10000, "long": 20000, "repeat": 3,
            "peer_callgrind": (1000, 3000), "notes": ["a note"]}
    text = peers.table(results, meta)
    lines = text.splitlines()
    rows = [line for line in lines if line.startswith("| ") and not line.startswith(("| code", "| ---"))]
    check(len(rows) == 4, f"{len(rows)} rows:\n{text}")
    check("`studies/bench/peers.py --repeat 3`" in lines[0] and "load average 12.3" in lines[0]
          and "9.9 at the end" in lines[0] and "4.2 minutes" in lines[0], f"header: {lines[0]}")
    exudyn = next(row for row in rows if row.startswith("| Exudyn"))
    cells = [cell.strip() for cell in exudyn.strip("|").split("|")]
    check(cells[3:11] == ["2.7e-13", "-", "-", "-", "10.00", "9.00", "5.00", "-"], f"Exudyn's row: {cells}")
    pylinkage = next(row for row in rows if row.startswith("| pylinkage"))
    check(pylinkage.rstrip(" |").endswith("1,234") and "| 7.50 |" in pylinkage, f"pylinkage's row: {pylinkage}")
    check(lines[-1] == "a note", "the notes follow the table")


def test_exudyn_models_follow_the_closed_form() -> None:
    """Exudyn's rigid-body and beam models of Example 1 (its static solver, the crank's
    rotation prescribed) on 20 steps: B and C at every configuration within 1e-11 of the
    closed form. Only where Exudyn imports (build/venv-exudyn; the script's own runs check
    the same on every timed run)."""
    pytest.importorskip("exudyn", reason="Exudyn is not in this environment (build/venv-exudyn has it)")
    exact = peers.exact_trajectory(20)
    for kind in ("rigid", "beam"):
        run = peers.run_exudyn_case(kind, 20)
        errors = peers.trajectory_errors(run["t"], run["series"], exact)
        check(len(run["t"]) == 21 and errors["position"] < 1e-11, f"Exudyn {kind}: {errors}")


def test_pylinkage_follows_the_closed_form() -> None:
    """pylinkage's Python paths on 20 steps: positions, velocities and accelerations of B
    and C within 1e-10 of the closed form. Only where pylinkage imports."""
    pytest.importorskip("pylinkage", reason="pylinkage is not in this environment (build/venv-exudyn has it)")
    exact = peers.exact_trajectory(20)
    for method in ("step", "step_with_derivatives"):
        run = peers.run_pylinkage_case(method, 20)
        errors = peers.trajectory_errors(run["t"], run["series"], exact)
        worst = max(value for value in errors.values() if value is not None)
        check(len(run["t"]) == 20 and worst < 1e-10, f"pylinkage {method}: {errors}")


def test_fekap_cases_are_the_benchmarks() -> None:
    """Each FEKAP case of peers.py is a case of bench_instructions.py (scripts/bench) with
    the same quantities and files, so that its callgrind count is that case's."""
    bi = peers.bi
    for name, (computes, files, case) in peers.FEKAP_CASES.items():
        check(case in bi.CASES, f"{name}: {case!r} is not a case of bench_instructions.py")
        check(case.split()[1:] == [computes, files], f"{name}: {case!r} is not {computes} {files}")
        check(peers.CASES[name][1] == computes, f"{name}: computes {peers.CASES[name][1]}, not {computes}")
