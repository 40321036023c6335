#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Compare FEKAP's flexible slider-crank (decks/dynamics/slider-crank.deck) with Exudyn's
geometrically exact 2D beam (ObjectBeamGeometricallyExact2D) on the same model: the
connecting rod's midpoint deflection (the distance of M from the line AB) over the run,
and the time per step of both. A comparison script, not a test.

    studies/exudyn/exudyn_slider_crank.py [--elements N] [--dt DT] [--t-end T] [--rho-inf R]
    studies/exudyn/exudyn_slider_crank.py --study [--t-end 0.05] [--repeat R] [--json PATH]
    studies/exudyn/exudyn_slider_crank.py --cost [--dt DT] [--t-end T] [--repeat R]

--cost prints one JSON line: Exudyn's CPU microseconds and Newton iterations
per step at DT (the median of R runs, as scripts/bench takes FEKAP's), for
scripts/bench's dynamics line.

--study compares the two at equal accuracy (docs/dynamics.md uses --t-end 0.05:
later the rod's large vibration makes the deflection sensitive to every
digit): each code's midpoint deflection at dt = 1 ms / 2^k (k = 0..6) against
its own converged run (Richardson's extrapolation of its runs at 1 ms / 2^9
and 2^10; the run at 2^8 gives the observed order, which says whether these
are in the asymptotic range; the two codes' converged runs are compared too),
at the instants every millisecond. Both codes are treated alike: both store
their output every millisecond only (FEKAP `every` in OUTPut, Exudyn's
sensors' writePeriod; where Exudyn cuts steps, at the coarsest dt, its
sensors then leave the milliseconds and it stores every step, said in the
table), both have the CPU time of a one-step run subtracted
(FEKAP: the child process's user + system time, its reading, set-up, start
and output files; Exudyn: time.process_time() around SolveDynamic, its
solver set-up and start accelerations), and both take the median of R runs.
It prints the error and CPU time per step and per simulated second of each,
and the speed ratio at equal error (log-log interpolation of each code's
error against its CPU time).

Exudyn comes from PyPI (exudyn==1.13.6, with numpy) into its own virtual environment,
build/venv-exudyn, made on the first run; the script then runs itself there. FEKAP is the
release binary of scripts/build (build/local/bin/fekap), or $FEKAP_BIN (an earlier
binary, for a before-and-after study in the same spell of the shared machine).

The model: crank 0.15 m and rod 0.30 m of 6 mm round steel (E = 200 GPa, G = 77 GPa,
rho = 7870), N elements per 0.15 m, the crank's first node turning at 150 rad/s from t = 0
(its rotation coordinate prescribed), a hinge at A, the rod's end B on the x axis (its y
coordinate held; FEKAP: a pin-in-slot slideline by penalty), the start velocities those of
the rigid mechanism (at t = 0 the crank and the rod lie along x: A moves at 22.5 m/s along y,
B is at rest, the rod turns at -75 rad/s), generalized-alpha with the same rho_inf and dt.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

from fekap import run as fb  # the Exudyn environment, shared with the other exudyn_*.py
from fekap.timing import listing_summary, run_timed

ROOT = fb.ROOT

D = 0.006
E, G, RHO = 2.0e11, 7.7e10, 7870.0
AREA = 3.141592653589793 * D ** 2 / 4
INERTIA = 3.141592653589793 * D ** 4 / 64
CRANK, ROD, OMEGA = 0.15, 0.30, 150.0


def ensure_exudyn() -> None:
    """Run this script in build/venv-exudyn (made and filled on the first run: fekap.run.in_exudyn_venv)."""
    fb.in_exudyn_venv(__file__, sys.argv[1:])


def deflection(a, m, b) -> float:
    """Signed distance of m from the line a -> b."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    return ((m[0] - a[0]) * dy - (m[1] - a[1]) * dx) / (dx * dx + dy * dy) ** 0.5


def run_exudyn(n: int, dt: float, t_end: float, rho_inf: float, details: dict | None = None,
               write_period: float | None = None) -> tuple[list[float], list[float], float, int]:
    """Times, midpoint deflections, CPU seconds (time.process_time() around
    SolveDynamic) and steps of Exudyn's run, its sensors stored every
    `write_period` (default: every step) (its default Newton tolerances:
    relative 1e-8; a relative 1e-10 is below its round-off at fine steps,
    where it then cuts steps for nothing); `details` receives the solver's
    steps taken, Newton iterations and Jacobians."""
    import exudyn as exu
    from exudyn.itemInterface import (
        MarkerNodeCoordinate,
        MarkerNodePosition,
        NodePointGround,
        NodeRigidBody2D,
        ObjectBeamGeometricallyExact2D,
        ObjectConnectorCoordinate,
        ObjectJointRevolute2D,
        SensorNode,
    )

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    beam = dict(massPerLength=RHO * AREA, crossSectionInertia=RHO * INERTIA, bendingStiffness=E * INERTIA,
                axialStiffness=E * AREA, shearStiffness=G * AREA * 5 / 6)  # FEKAP's default k = 5/6

    def chain(x0: float, length: float, elements: int, velocity) -> list[int]:
        nodes = []
        for k in range(elements + 1):
            x = x0 + length * k / elements
            vx, vy, w = velocity(x)
            nodes.append(mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x, 0, 0], initialVelocities=[vx, vy, w])))
        for k in range(elements):
            mbs.AddObject(ObjectBeamGeometricallyExact2D(nodeNumbers=[nodes[k], nodes[k + 1]],
                                                         length=length / elements, **beam))
        return nodes

    crank = chain(0.0, CRANK, n, lambda x: (0.0, OMEGA * x, OMEGA))
    rod_omega = -OMEGA * CRANK / ROD
    rod = chain(CRANK, ROD, 2 * n, lambda x: (0.0, OMEGA * CRANK + rod_omega * (x - CRANK), rod_omega))

    def coordinate(node: int, k: int) -> int:
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=k))

    g = coordinate(ground, 0)
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[g, coordinate(crank[0], 0)]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[g, coordinate(crank[0], 1)]))
    # The crank's rotation at 150 rad/s: its rate prescribed (velocity level), from the start angle 0; the
    # same motion as an offset user function OMEGA t to 1e-15 here, without a Python call per iteration.
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[g, coordinate(crank[0], 2)], velocityLevel=True,
                                            offset=OMEGA))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mbs.AddMarker(MarkerNodePosition(nodeNumber=crank[-1])),
                                                       mbs.AddMarker(MarkerNodePosition(nodeNumber=rod[0]))]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[g, coordinate(rod[-1], 1)]))
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True, writeToFile=False,
                                        outputVariableType=exu.OutputVariableType.Position))
               for node in (rod[0], rod[n], rod[-1])]
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_end / dt))
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    settings.timeIntegration.verboseMode = 0
    settings.solution.sensors.writePeriod = write_period or dt
    settings.solution.file.write = False
    start = time.process_time()
    mbs.SolveDynamic(settings, storeSolver=True)
    seconds = time.process_time() - start
    if details is not None:
        it = mbs.sys["dynamicSolver"].it
        details.update({"steps taken": it.currentStepIndex, "Newton iterations": it.newtonStepsCount,
                        "Jacobians": it.newtonJacobiCount})
    a, m, b = (mbs.GetSensorStoredData(s) for s in sensors)
    times = [row[0] for row in a]
    values = [deflection(ra[1:3], rm[1:3], rb[1:3]) for ra, rm, rb in zip(a, m, b)]
    return times, values, seconds, settings.timeIntegration.numberOfSteps


def run_fekap(n: int, dt: float, t_end: float, rho_inf: float, details: dict | None = None,
              every: int = 1) -> tuple[list[float], list[float], float, int]:
    """Times, midpoint deflections, seconds in analysis (the listing's wall
    time) and steps of FEKAP's run of the deck, writing every `every`-th step;
    `details` receives the run's process CPU seconds ("cpu") and the
    listing's SUMMARY numbers."""
    binary = fb.fekap_binary()
    deck = (ROOT / "decks" / "dynamics" / "slider-crank.deck").read_text()
    deck = deck.replace("steel  4 ", f"steel  {n} ")
    if rho_inf != 0.8:
        deck = deck.replace("  type dynamics", f"  type dynamics\n  integrator generalized-alpha {rho_inf}")
    if every > 1:
        deck = deck.replace("  track A M B", f"  track A M B\n  every {every}")
    with tempfile.TemporaryDirectory() as work:
        path = Path(work) / "slider-crank.deck"
        path.write_text(deck)
        start = time.perf_counter()
        _, cpu, _ = run_timed([str(binary), str(path), "-o", str(Path(work) / "out"), "--set", f"dt={dt!r}",
                               "--set", f"t_end={t_end!r}"])
        seconds = time.perf_counter() - start
        steps: dict[int, dict[str, tuple[float, float]]] = {}
        times: dict[int, float] = {}
        with open(Path(work) / "out" / "points.csv", newline="") as handle:
            for row in csv.DictReader(handle):
                step = int(row["step"])
                steps.setdefault(step, {})[row["point"]] = (float(row["x"]), float(row["y"]))
                times[step] = float(row["t"])
        listing = (Path(work) / "out" / "slider-crank.lis").read_text()
    summary = listing_summary(listing)
    if details is not None:
        details.update(summary, cpu=cpu)
    order = sorted(steps)
    return ([times[s] for s in order], [deflection(steps[s]["A"], steps[s]["M"], steps[s]["B"]) for s in order],
            summary.get("time in analysis (s)", seconds), len(order) - 1)


#: The study's steps: dt = 1 ms / 2^k, k = 0..6; the converged runs from 1 ms / 2^9 and 2^10
#: (2^8 too for the observed order).
STUDY_DTS = [1e-3 / 2 ** k for k in range(7)]
REFERENCE_LEVELS = (9, 10)
SAMPLE = 1e-3  # the instants compared: every millisecond


def sampled(times: list[float], values: list[float]) -> dict[int, float]:
    """The values at the whole milliseconds (key: the millisecond): the
    sample there, or the cubic through the four samples around it (after a
    cut step a code's steps no longer end on the milliseconds)."""
    out = {}
    last = round(times[-1] / SAMPLE)
    j = 0
    for k in range(last + 1):
        target = k * SAMPLE
        while j + 1 < len(times) and times[j + 1] <= target + 1e-12:
            j += 1
        if abs(times[j] - target) <= 1e-12:
            out[k] = values[j]
            continue
        i0 = min(max(j - 1, 0), len(times) - 4)
        nodes = range(i0, i0 + 4)
        out[k] = sum(values[i] * math.prod((target - times[m]) / (times[i] - times[m]) for m in nodes if m != i)
                     for i in nodes)
    return out


def worst_difference(a: dict[int, float], b: dict[int, float]) -> float:
    common = sorted(set(a) & set(b))
    return max(abs(a[k] - b[k]) for k in common)


def cpu_at_error(points: list[tuple[float, float]], error: float) -> float:
    """CPU seconds at `error` by log-log interpolation of (error, cpu) points;
    NaN outside their range."""
    ordered = sorted(points)
    for (e0, c0), (e1, c1) in zip(ordered, ordered[1:]):
        if e0 <= error <= e1 and e1 > e0:
            s = math.log(error / e0) / math.log(e1 / e0)
            return math.exp(math.log(c0) + s * math.log(c1 / c0))
    return math.nan


def on_samples(times: list[float]) -> bool:
    """Whether the stored instants lie on the milliseconds (so that a
    series is not interpolated between samples a millisecond apart)."""
    return all(abs(t / SAMPLE - round(t / SAMPLE)) <= 1e-6 for t in times)


def study(n: int, t_end: float, rho_inf: float, repeat: int, json_path: Path | None) -> int:
    """Error against the converged run and CPU time of both codes by dt; the
    speed ratio at equal error. Both codes alike: output every millisecond,
    the CPU time of a one-step run subtracted, the median of `repeat` runs."""
    def fekap(dt: float, reps: int = repeat) -> dict:
        runs = []
        for _ in range(reps):
            details: dict = {}
            times, values, _, _ = run_fekap(n, dt, t_end, rho_inf, details, every=max(1, round(SAMPLE / dt)))
            if not on_samples(times):
                sys.exit(f"FEKAP at dt {dt:g}: stored instants off the milliseconds")
            runs.append(dict(details, series=sampled(times, values)))
        return dict(runs[0], cpu=statistics.median(r["cpu"] for r in runs), written="every ms")

    def exudyn(dt: float, reps: int = repeat) -> dict:
        # Where Exudyn cuts steps its sensors' instants leave the milliseconds:
        # then it stores every step, and the series is interpolated (`sampled`).
        for period, written in ((SAMPLE, "every ms"), (dt, "every step")):
            runs = []
            for _ in range(reps):
                details: dict = {}
                times, values, cpu, _ = run_exudyn(n, dt, t_end, rho_inf, details, write_period=period)
                if period == SAMPLE and not on_samples(times):
                    break
                runs.append(dict(details, cpu=cpu, series=sampled(times, values)))
            else:
                return dict(runs[0], cpu=statistics.median(r["cpu"] for r in runs), written=written)
        sys.exit(f"Exudyn at dt {dt:g}: stored instants off the milliseconds")

    startup = {"FEKAP": statistics.median(fekap_startup(n, rho_inf) for _ in range(repeat)),
               "Exudyn": statistics.median(exudyn_startup(n, rho_inf) for _ in range(repeat))}
    print(f"flexible slider-crank, {n} elements per 0.15 m, t_end {t_end:g} s, rho_inf {rho_inf:g}; "
          f"median of {repeat} runs; output every {1e3 * SAMPLE:g} ms by both; start-up (a one-step run, "
          f"subtracted): FEKAP {1e3 * startup['FEKAP']:.2f} ms CPU, Exudyn {1e3 * startup['Exudyn']:.2f} ms CPU")
    # The converged runs: Richardson's extrapolation (second order) of the two
    # finest; the observed order from the three finest says whether they are
    # in the asymptotic range.
    levels = [REFERENCE_LEVELS[0] - 1, *REFERENCE_LEVELS]
    fine = {code: [run(1e-3 / 2 ** k, 1)["series"] for k in levels]
            for code, run in (("FEKAP", fekap), ("Exudyn", exudyn))}
    reference, order = {}, {}
    for code, (coarse, half, finest) in fine.items():
        reference[code] = {k: v + (v - half[k]) / 3 for k, v in finest.items()}
        d1, d2 = worst_difference(coarse, half), worst_difference(half, finest)
        order[code] = {"dt": [1e-3 / 2 ** k for k in levels], "differences": [d1, d2],
                       "order": math.log2(d1 / d2), "finest_error": d2 / 3}
        print(f"{code}: dt 1 ms / 2^{levels[0]} - 2^{levels[1]}: {d1:.3e} m, 2^{levels[1]} - 2^{levels[2]}: "
              f"{d2:.3e} m, observed order {order[code]['order']:.2f}; the finest run's error "
              f"(Richardson) {d2 / 3:.2e} m")
    peak = max(abs(v) for v in reference["Exudyn"].values())
    between = worst_difference(reference["FEKAP"], reference["Exudyn"])
    print(f"converged runs: peak midpoint deflection {peak:.6e} m; FEKAP - Exudyn {between:.3e} m")
    rows = []
    print("| dt (s) | code | steps (taken) | output | Newton its/step | error (m) | CPU us/step | CPU s per simulated s |")
    print("| ---: | --- | ---: | --- | ---: | ---: | ---: | ---: |")
    for dt in STUDY_DTS:
        steps = round(t_end / dt)
        f, e = fekap(dt), exudyn(dt)
        for code, run in (("FEKAP", f), ("Exudyn", e)):
            cpu = max(run["cpu"] - startup[code], 1e-9)
            its = run.get("Newton iterations", math.nan) / steps
            taken = run.get("configurations solved", run.get("steps taken", math.nan))
            row = {"dt": dt, "code": code, "steps": steps, "taken": taken, "output": run["written"],
                   "iterations_per_step": its,
                   "error": worst_difference(run["series"], reference[code]), "cpu": cpu,
                   "us_per_step": 1e6 * cpu / steps, "cpu_per_simulated_second": cpu / t_end}
            rows.append(row)
            print(f"| {dt:.4g} | {code} | {steps} ({taken:.0f}) | {run['written']} | {its:.2f} | {row['error']:.3e} | "
                  f"{row['us_per_step']:.1f} | {row['cpu_per_simulated_second']:.3g} |")
    curves = {code: [(r["error"], r["cpu_per_simulated_second"]) for r in rows if r["code"] == code]
              for code in ("FEKAP", "Exudyn")}
    print("\nat equal error (each against its own converged run; log-log interpolation):")
    print("| error (m) | FEKAP CPU s per simulated s | Exudyn | Exudyn / FEKAP |")
    print("| ---: | ---: | ---: | ---: |")
    ratios = []
    for error in (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6):
        cf, ce = cpu_at_error(curves["FEKAP"], error), cpu_at_error(curves["Exudyn"], error)
        if math.isnan(cf) or math.isnan(ce):
            continue
        ratios.append({"error": error, "fekap": cf, "exudyn": ce, "ratio": ce / cf})
        print(f"| {error:.0e} | {cf:.3g} | {ce:.3g} | {ce / cf:.1f} |")
    if json_path is not None:
        json_path.write_text(json.dumps({"elements": n, "t_end": t_end, "rho_inf": rho_inf, "repeat": repeat,
                                         "statistic": "median", "output_every": SAMPLE, "startup": startup,
                                         "reference": order, "peak": peak, "converged_difference": between,
                                         "rows": rows, "equal_error": ratios}, indent=1) + "\n")
    return 0


def fekap_startup(n: int, rho_inf: float) -> float:
    """CPU seconds of a one-step run: reading, setup, start and output files."""
    details: dict = {}
    run_fekap(n, 1e-5, 1e-5, rho_inf, details)
    return details["cpu"]


def exudyn_startup(n: int, rho_inf: float) -> float:
    """CPU seconds of a one-step SolveDynamic: the solver's set-up and start accelerations."""
    return run_exudyn(n, 1e-5, 1e-5, rho_inf)[2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=4, help="elements per 0.15 m (default 4)")
    parser.add_argument("--dt", type=float, default=1e-4)
    parser.add_argument("--t-end", type=float, default=0.1)
    parser.add_argument("--rho-inf", type=float, default=0.8)
    parser.add_argument("--study", action="store_true", help="error and CPU time by dt of both codes")
    parser.add_argument("--repeat", type=int, default=3, help="runs per point of the study (the median CPU time)")
    parser.add_argument("--json", type=Path, help="write the study's numbers to this file")
    parser.add_argument("--cost", action="store_true", help="Exudyn's CPU time per step only, as JSON")
    args = parser.parse_args()
    ensure_exudyn()
    if args.study:
        return study(args.elements, args.t_end, args.rho_inf, args.repeat, args.json)
    if args.cost:
        runs = []
        for _ in range(args.repeat):
            details: dict = {}
            _, _, cpu, steps = run_exudyn(args.elements, args.dt, args.t_end, args.rho_inf, details)
            runs.append((cpu, details["Newton iterations"] / steps, steps))
        cpu = statistics.median(r[0] for r in runs)
        _, its, steps = runs[0]
        print(json.dumps({"us_per_step": 1e6 * cpu / steps, "iterations_per_step": its, "steps": steps}))
        return 0
    te, de, se, ne = run_exudyn(args.elements, args.dt, args.t_end, args.rho_inf)
    tf, df, sf, nf = run_fekap(args.elements, args.dt, args.t_end, args.rho_inf)
    by_time = {round(t / args.dt): d for t, d in zip(tf, df)}
    pairs = [(by_time[round(t / args.dt)], d) for t, d in zip(te, de) if round(t / args.dt) in by_time]
    worst = max(abs(a - b) for a, b in pairs)
    peak = max(abs(b) for _, b in pairs)
    print(f"flexible slider-crank, {args.elements} elements per 0.15 m, dt {args.dt:g}, t_end {args.t_end:g}, "
          f"rho_inf {args.rho_inf:g}")
    print(f"  rod midpoint deflection: Exudyn peak {peak:.6e} m, FEKAP peak {max(abs(a) for a, _ in pairs):.6e} m")
    print(f"  largest difference FEKAP - Exudyn: {worst:.3e} m ({worst / peak:.2e} of the peak), "
          f"over {len(pairs)} common instants")
    for t_mark in (0.02, 0.05, 0.1):
        k = round(t_mark / args.dt)
        if k in by_time:
            e_value = next(d for t, d in zip(te, de) if round(t / args.dt) == k)
            print(f"  t = {t_mark:g}: FEKAP {by_time[k]: .6e}  Exudyn {e_value: .6e}")
    print(f"  time per step: FEKAP {1e6 * sf / nf:.1f} us (analysis, from its listing, wall), "
          f"Exudyn {1e6 * se / ne:.1f} us (SolveDynamic, CPU)  -> {se / ne / (sf / nf):.1f} x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
