#!/usr/bin/env python3
"""Compare FEKAP's flexible slider-crank (decks/dynamics/slider-crank.deck) with Exudyn's
geometrically exact 2D beam (ObjectBeamGeometricallyExact2D) on the same model: the
connecting rod's midpoint deflection (the distance of M from the line AB) over the run,
and the time per step of both. A comparison script, not a test.

    scripts/exudyn_slider_crank.py [--elements N] [--dt DT] [--t-end T] [--rho-inf R]

Exudyn comes from PyPI (exudyn==1.13.6, with numpy) into its own virtual environment,
build/venv-exudyn, made on the first run; the script then runs itself there. FEKAP is the
release binary of scripts/build (build/local/bin/fekap).

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
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VENV = ROOT / "build" / "venv-exudyn"
EXUDYN = "exudyn==1.13.6"

D = 0.006
E, G, RHO = 2.0e11, 7.7e10, 7870.0
AREA = 3.141592653589793 * D ** 2 / 4
INERTIA = 3.141592653589793 * D ** 4 / 64
CRANK, ROD, OMEGA = 0.15, 0.30, 150.0


def ensure_exudyn() -> None:
    """Run this script in build/venv-exudyn (made and filled on the first run)."""
    try:
        import exudyn  # noqa: F401
        return
    except ImportError:
        pass
    python = VENV / "bin" / "python"
    if not python.is_file():
        print(f"making {VENV} with {EXUDYN} from PyPI ...", file=sys.stderr)
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", EXUDYN, "numpy"], check=True)
    os.execv(str(python), [str(python), __file__, *sys.argv[1:]])


def deflection(a, m, b) -> float:
    """Signed distance of m from the line a -> b."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    return ((m[0] - a[0]) * dy - (m[1] - a[1]) * dx) / (dx * dx + dy * dy) ** 0.5


def run_exudyn(n: int, dt: float, t_end: float, rho_inf: float) -> tuple[list[float], list[float], float, int]:
    """Times, midpoint deflections, seconds and steps of Exudyn's run."""
    import exudyn as exu
    from exudyn.itemInterface import (MarkerNodeCoordinate, MarkerNodePosition, NodePointGround, NodeRigidBody2D,
                                      ObjectBeamGeometricallyExact2D, ObjectConnectorCoordinate,
                                      ObjectJointRevolute2D, SensorNode)

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
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[g, coordinate(crank[0], 2)],
                                            offsetUserFunction=lambda mbs_, t, item, offset: OMEGA * t))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mbs.AddMarker(MarkerNodePosition(nodeNumber=crank[-1])),
                                                       mbs.AddMarker(MarkerNodePosition(nodeNumber=rod[0]))]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[g, coordinate(rod[-1], 1)]))
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.Position))
               for node in (rod[0], rod[n], rod[-1])]
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_end / dt))
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    settings.timeIntegration.verboseMode = 0
    settings.solutionSettings.sensorsWritePeriod = dt
    try:
        settings.solution.file.write = False
    except AttributeError:
        settings.solutionSettings.writeSolutionToFile = False
    settings.timeIntegration.newton.relativeTolerance = 1e-10
    start = time.perf_counter()
    mbs.SolveDynamic(settings)
    seconds = time.perf_counter() - start
    a, m, b = (mbs.GetSensorStoredData(s) for s in sensors)
    times = [row[0] for row in a]
    values = [deflection(ra[1:3], rm[1:3], rb[1:3]) for ra, rm, rb in zip(a, m, b)]
    return times, values, seconds, settings.timeIntegration.numberOfSteps


def run_fekap(n: int, dt: float, t_end: float, rho_inf: float) -> tuple[list[float], list[float], float, int]:
    """Times, midpoint deflections, seconds and steps of FEKAP's run of the deck."""
    binary = ROOT / "build" / "local" / "bin" / "fekap"
    if not binary.is_file():
        sys.exit(f"{binary}: missing; build it with scripts/build")
    deck = (ROOT / "decks" / "dynamics" / "slider-crank.deck").read_text()
    deck = deck.replace("steel  4 ", f"steel  {n} ")
    if rho_inf != 0.8:
        deck = deck.replace("  type dynamics", f"  type dynamics\n  integrator generalized-alpha {rho_inf}")
    with tempfile.TemporaryDirectory() as work:
        path = Path(work) / "slider-crank.deck"
        path.write_text(deck)
        start = time.perf_counter()
        run = subprocess.run([str(binary), str(path), "-o", str(Path(work) / "out"), "--set", f"dt={dt}",
                              "--set", f"t_end={t_end}"], capture_output=True, text=True)
        seconds = time.perf_counter() - start
        if run.returncode != 0:
            sys.exit(f"fekap failed: {run.stderr}")
        steps: dict[int, dict[str, tuple[float, float]]] = {}
        times: dict[int, float] = {}
        with open(Path(work) / "out" / "points.csv", newline="") as handle:
            for row in csv.DictReader(handle):
                step = int(row["step"])
                steps.setdefault(step, {})[row["point"]] = (float(row["x"]), float(row["y"]))
                times[step] = float(row["t"])
        listing = (Path(work) / "out" / "slider-crank.lis").read_text()
    analysis = next((float(line.split()[-1]) for line in listing.splitlines()
                     if "time in analysis" in line), seconds)
    order = sorted(steps)
    return ([times[s] for s in order], [deflection(steps[s]["A"], steps[s]["M"], steps[s]["B"]) for s in order],
            analysis, len(order) - 1)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=4, help="elements per 0.15 m (default 4)")
    parser.add_argument("--dt", type=float, default=1e-4)
    parser.add_argument("--t-end", type=float, default=0.1)
    parser.add_argument("--rho-inf", type=float, default=0.8)
    args = parser.parse_args()
    ensure_exudyn()
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
    print(f"  time per step: FEKAP {1e6 * sf / nf:.1f} us (analysis, from its listing), "
          f"Exudyn {1e6 * se / ne:.1f} us (SolveDynamic)  -> {se / ne / (sf / nf):.1f} x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
