#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""The IFToMM A02 N-four-bar (decks/dynamics/a02-n40.deck) in Exudyn, as rigid
bodies, against its exact energy integral and against FEKAP's flexible run of
the deck: the first crank's rate and angle errors and the CPU time per step of
both. A comparison script, not a test.

    studies/exudyn/exudyn_a02.py [--n 40] [--dt 0.002] [--t-end 5]

The chain: N + 1 vertical cranks (1 m, 1 kg, uniform) pinned at (i, 0) and N
horizontal couplers (1 m, 1 kg) between their tips, g = 9.81 along -y, the
crank tips starting at 1 m/s along x. Exudyn: ObjectRigidBody2D bars (inertia
m L^2 / 12 about the centre), ObjectJointRevolute2D pins (index 3,
generalized-alpha with rho_inf 0.8, its default Newton tolerances). It is one
pendulum of inertia I = (N+1)/3 + N about the pivots and gravity moment
G cos(theta), G = ((N+1)/2 + N) g, so omega^2 = 1 + 2 G/I (1 - sin theta)
and theta(t) by its quadrature (python/fekap/exact/a02.py) give the exact motion. The rigid chain's constraints
(3N + 1 pins of 2 equations: 3 (2N + 1) - 1 equations on 3 (2N + 1)
coordinates) are redundant where every bar is horizontal (the change points),
which a constraint-based code must pass; FEKAP's elastic bars (EA = 1e10) pass
them without constraints. CPU time: Exudyn's time.process_time() around
SolveDynamic; FEKAP's process (start-up and the CSV output of every step
included). Exudyn runs in build/venv-exudyn (made on the first run, fekap.run.EXUDYN_PACKAGES); FEKAP is build/local/bin/fekap
(fekap.run.run_deck). Errors: fekap.dynamics.a02_crank_errors, as the tests.
"""

from __future__ import annotations

import argparse
import math
import resource
import shutil
import sys
import time

from fekap import run as fb


def run_exudyn(n: int, dt: float, t_end: float) -> dict:
    import exudyn as exu
    from exudyn.itemInterface import (
        LoadMassProportional,
        MarkerBodyMass,
        MarkerBodyPosition,
        NodeRigidBody2D,
        ObjectGround,
        ObjectJointRevolute2D,
        ObjectRigidBody2D,
        SensorNode,
    )

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))

    def bar(x: float, y: float, phi: float, v: list[float]) -> tuple[int, int]:
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x, y, phi], initialVelocities=v))
        body = mbs.AddObject(ObjectRigidBody2D(physicsMass=1.0, physicsInertia=1.0 / 12, nodeNumber=node))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=body)),
                                         loadVector=[0, -9.81, 0]))
        return node, body

    def pin(body_a: int, local_a: list[float], body_b: int, local_b: list[float]) -> None:
        ma = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body_a, localPosition=local_a))
        mb = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body_b, localPosition=local_b))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[ma, mb]))

    cranks = [bar(i, 0.5, math.pi / 2, [0.5, 0, -1.0]) for i in range(n + 1)]
    couplers = [bar(k + 0.5, 1.0, 0.0, [1.0, 0, 0]) for k in range(n)]
    for i, (_, body) in enumerate(cranks):
        pin(ground, [i, 0, 0], body, [-0.5, 0, 0])
    for k, (_, body) in enumerate(couplers):
        pin(cranks[k][1], [0.5, 0, 0], body, [-0.5, 0, 0])
        pin(cranks[k + 1][1], [0.5, 0, 0], body, [0.5, 0, 0])
    sensor = mbs.AddSensor(SensorNode(nodeNumber=cranks[0][0], storeInternal=True, writeToFile=False,
                                      outputVariableType=exu.OutputVariableType.Coordinates))
    velocity = mbs.AddSensor(SensorNode(nodeNumber=cranks[0][0], storeInternal=True, writeToFile=False,
                                        outputVariableType=exu.OutputVariableType.Coordinates_t))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_end / dt))
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.generalizedAlpha.spectralRadius = 0.8
    settings.timeIntegration.verboseMode = 0
    settings.solution.sensors.writePeriod = dt
    settings.solution.file.write = False
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    start = time.process_time()
    ok = True
    try:
        ok = mbs.SolveDynamic(settings, storeSolver=True)
    except Exception as failure:  # Exudyn raises when Newton fails below its smallest step
        ok = False
        print(f"  Exudyn: {str(failure).splitlines()[0][:200]}", file=sys.stderr)
    cpu = time.process_time() - start
    it = mbs.sys["dynamicSolver"].it
    q, v = mbs.GetSensorStoredData(sensor), mbs.GetSensorStoredData(velocity)
    return {"ok": ok, "cpu": cpu, "steps": it.currentStepIndex, "iterations": it.newtonStepsCount,
            "times": [row[0] for row in q], "angles": [math.pi / 2 + row[3] for row in q], "rates": [row[3] for row in v]}


def run_fekap(n: int, dt: float, t_end: float) -> dict:
    from fekap import dynamics as dc

    deck = fb.ROOT / "decks" / "dynamics" / f"a02-n{n}.deck"
    work = fb.scratch_dir("fekap-a02-")
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    result = fb.run_deck(fb.fekap_binary(), deck, work, "--set", f"dt={dt!r}", "--set", f"t_end={t_end!r}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - usage.ru_utime - usage.ru_stime
    links = dc.columns(work / "links.csv")
    shutil.rmtree(work, ignore_errors=True)
    return {"ok": result["rc"] == 0, "cpu": cpu, "steps": len(links["t"]) - 1,
            "iterations": result["summary"].get("Newton iterations", 0.0),
            "times": list(links["t"]), "angles": list(links["angle"]), "rates": list(links["omega"])}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=40)
    parser.add_argument("--dt", type=float, default=0.002)
    parser.add_argument("--t-end", type=float, default=5.0)
    args = parser.parse_args()
    fb.in_exudyn_venv(__file__, sys.argv[1:])
    from fekap import dynamics as dc
    print(f"A02 N = {args.n}, dt {args.dt:g}, {args.t_end:g} s, rho_inf 0.8; first crank against the energy integral")
    for name, run in (("Exudyn 1.13.6, rigid bars", run_exudyn), ("FEKAP, elastic bars (the deck)", run_fekap)):
        r = run(args.n, args.dt, args.t_end)
        steps = max(1, round(r["times"][-1] / args.dt)) if r["times"] else 1
        e = dc.a02_crank_errors(args.n, r["times"], r["angles"], r["rates"]) if r["times"] else {}
        rate, angle = e.get("energy", math.nan), e.get("angle", math.nan)
        print(f"  {name}: {'finished' if r['ok'] else 'FAILED'} at t = {r['times'][-1] if r['times'] else 0:.4g}; "
              f"rate error {rate:.3e} rad/s, angle error {angle:.3e} rad; {r['steps']} steps, "
              f"{r['iterations'] / max(1, r['steps']):.2f} Newton iterations per step, "
              f"{1e6 * r['cpu'] / steps:.0f} us CPU per step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
