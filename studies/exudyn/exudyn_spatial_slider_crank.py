#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""The IFToMM spatial slider-crank (decks/spatial/slider-crank.deck: crank 0.08 m about +x
at 6 rad/s, rod 0.3 m, spherical joint at the crank, universal joint at the slider, the
slider on the x axis) in kinematics, run by FEKAP and by Exudyn 1.13.6: the time per
configuration of both at equal accuracy against the closed form
x(theta) = sqrt(0.0592 + 0.016 sin theta - 0.0192 cos theta). A benchmark script, not a test.

    studies/exudyn/exudyn_spatial_slider_crank.py [--turns K] [--repeat R] [--no-callgrind] [--json PATH]

Exudyn's kinematic solve is its static solver with the crank's rotation prescribed by a
joint's offset (SolveStatic with load steps: "may also be used to compute kinematic
behavior by prescribing joint motion", its documentation): three rigid bodies, a generic
joint to the ground with every axis held and the offset 6 t about x (a Python
offsetUserFunction), a spherical joint, a generic joint with the rotation about its x axis
held (the universal joint: its y axis +x in the slider, its z axis (0, -2, 1) in the rod),
and a generic joint to the ground with everything but the x translation held (the
prismatic joint). Its Newton tolerances are 1e-12 (absolute and relative), which puts
its slider within 1e-13 of the closed form, where FEKAP's is (the issue's bound: 1e-12).
It computes positions only (a static solve has no velocities); FEKAP computes positions,
velocities and accelerations. Both store the slider's position at every configuration
(FEKAP its CSV files of B and S; Exudyn a sensor).

Both take the deck's step (100 configurations a turn). The time per configuration is
marginal: the CPU time of a K-turn run (default 10) less a one-turn run's, over the
configurations between them, which cancels reading, set-up and the start. CPU time:
FEKAP's process (user + system, fekap.timing), Exudyn's time.process_time() around
SolveStatic; the median of R runs (default 5). FEKAP's instructions per configuration
(valgrind --tool=callgrind of both runs, fekap.timing) do not move with the shared
machine's load; --no-callgrind skips them.

Exudyn comes from PyPI (exudyn==1.13.6, with numpy) into build/venv-exudyn, made on the
first run (fekap.run.in_exudyn_venv); FEKAP is build/local/bin/fekap (scripts/build) or
$FEKAP_BIN.
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
from fekap.timing import run_timed

ROOT = fb.ROOT
DECK = ROOT / "decks" / "spatial" / "slider-crank.deck"
OMEGA = 6.0
STEPS_A_TURN = 100


def exact_x(t):
    """The slider's closed form at time t (theta = 6 t)."""
    theta = OMEGA * t
    return math.sqrt(0.0592 + 0.016 * math.sin(theta) - 0.0192 * math.cos(theta))


def horizon(turns: int) -> float:
    return turns * math.pi / 3


def run_exudyn(turns: int, tolerance: float = 1e-12) -> dict:
    """Exudyn's kinematic solve of `turns` turns at the deck's step: the slider's
    largest error, the CPU seconds of SolveStatic and its Newton iterations."""
    import exudyn as exu
    import numpy as np
    from exudyn.utilities import InertiaCuboid, SensorNode

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.CreateGround()
    a, b, s = np.array([0.0, 0.1, 0.12]), np.array([0.0, 0.1, 0.2]), np.array([0.2, 0.0, 0.0])

    def body(p, q):
        length = float(np.linalg.norm(q - p))
        return mbs.CreateRigidBody(inertia=InertiaCuboid(7800.0, [max(length, 0.01), 0.01, 0.01]),
                                   referencePosition=(p + q) / 2, gravity=[0.0, 0.0, 0.0])

    crank, rod, slider = body(a, b), body(b, s), body(s, s)

    def drive(mbs, t, item, parameters):
        return [0.0, 0.0, 0.0, OMEGA * t, 0.0, 0.0]

    mbs.CreateGenericJoint(itemNumbers=[ground, crank], position=a, constrainedAxes=[1] * 6,
                           offsetUserFunction=drive)
    mbs.CreateSphericalJoint(itemNumbers=[crank, rod], position=b)
    z = np.array([0.0, -2.0, 1.0]) / math.sqrt(5)
    y = np.array([1.0, 0.0, 0.0])
    mbs.CreateGenericJoint(itemNumbers=[slider, rod], position=s, rotationMatrixAxes=np.stack([np.cross(y, z), y, z], 1),
                           constrainedAxes=[1, 1, 1, 1, 0, 0])
    mbs.CreateGenericJoint(itemNumbers=[ground, slider], position=s, constrainedAxes=[0, 1, 1, 1, 1, 1])
    sensor = mbs.AddSensor(SensorNode(nodeNumber=mbs.GetObject(slider)["nodeNumber"], storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    steps = STEPS_A_TURN * turns
    settings = exu.SimulationSettings()
    settings.staticSolver.numberOfLoadSteps = steps
    settings.staticSolver.loadStepDuration = horizon(turns)
    settings.staticSolver.newton.relativeTolerance = tolerance
    settings.staticSolver.newton.absoluteTolerance = tolerance
    settings.staticSolver.verboseMode = 0
    settings.solution.sensors.writePeriod = horizon(turns) / steps / 2   # every configuration
    settings.solution.file.write = False
    start = time.process_time()
    mbs.SolveStatic(settings)
    cpu = time.process_time() - start
    data = mbs.GetSensorStoredData(sensor)
    if len(data) != steps + 1:
        raise SystemExit(f"Exudyn stored {len(data)} configurations, not {steps + 1}")
    error = max(max(abs(row[1] - exact_x(row[0])), abs(row[2]), abs(row[3])) for row in data)
    return {"cpu": cpu, "error": error, "newton": mbs.sys["staticSolver"].it.newtonStepsCount}


def run_fekap(turns: int, callgrind: bool = False) -> dict:
    """FEKAP's run of the deck over `turns` turns: the slider's largest error, the CPU
    seconds and (with callgrind) the instructions of the process, its Newton iterations."""
    text = DECK.read_text()
    if "  time 0 pi/3 pi/300\n" not in text:
        raise SystemExit(f"{DECK}: its time line changed")
    with tempfile.TemporaryDirectory() as work:
        deck = Path(work) / "slider-crank.deck"
        deck.write_text(text.replace("  time 0 pi/3 pi/300\n", f"  time 0 {turns}*pi/3 pi/300\n"))
        out = Path(work) / "out"
        _, cpu, instructions = run_timed([fb.fekap_binary(), "-q", "-o", str(out), str(deck)],
                                         Path(work) / "cg.out" if callgrind else None)
        with open(out / "points.csv", newline="") as handle:
            rows = [row for row in csv.DictReader(handle) if row["point"] == "S"]
        with open(out / "steps.csv", newline="") as handle:
            newton = sum(int(row["iterations"]) for row in csv.DictReader(handle))
    if len(rows) != STEPS_A_TURN * turns + 1:
        raise SystemExit(f"FEKAP wrote {len(rows)} configurations, not {STEPS_A_TURN * turns + 1}")
    error = max(max(abs(float(r["x"]) - exact_x(float(r["t"]))), abs(float(r["y"])), abs(float(r["z"])))
                for r in rows)
    return {"cpu": cpu, "error": error, "newton": newton, "instructions": instructions}


def marginal(long: float, short: float, turns: int) -> float:
    """Per configuration between a one-turn and a `turns`-turn run."""
    return (long - short) / (STEPS_A_TURN * (turns - 1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--turns", type=int, default=10, help="turns of the long runs (default 10)")
    parser.add_argument("--repeat", type=int, default=5, help="runs of each (the median CPU time; default 5)")
    parser.add_argument("--no-callgrind", action="store_true", help="skip FEKAP's instruction counts")
    parser.add_argument("--json", type=Path, help="write the figures to this file")
    args = parser.parse_args()
    fb.in_exudyn_venv(__file__, sys.argv[1:])
    if args.turns < 2:
        parser.error("--turns must be at least 2")
    runs = {}
    for turns in (1, args.turns):
        fekap = [run_fekap(turns) for _ in range(args.repeat)]
        exudyn = [run_exudyn(turns) for _ in range(args.repeat)]
        runs[turns] = {"FEKAP": dict(fekap[0], cpu=statistics.median(r["cpu"] for r in fekap)),
                       "Exudyn": dict(exudyn[0], cpu=statistics.median(r["cpu"] for r in exudyn))}
    if not args.no_callgrind:
        for turns in (1, args.turns):
            runs[turns]["FEKAP"]["instructions"] = run_fekap(turns, callgrind=True)["instructions"]
    configurations = STEPS_A_TURN * (args.turns - 1)
    print(f"IFToMM spatial slider-crank, kinematics, {STEPS_A_TURN} configurations a turn; marginal cost "
          f"between 1 and {args.turns} turns ({configurations} configurations), CPU median of {args.repeat} runs")
    print(f"{'code':8s} {'slider error':>13s} {'Newton its/conf':>16s} {'CPU us/conf':>12s} {'instructions/conf':>18s}")
    result = {}
    for code in ("FEKAP", "Exudyn"):
        short, long = runs[1][code], runs[args.turns][code]
        us = 1e6 * marginal(long["cpu"], short["cpu"], args.turns)
        its = marginal(long["newton"], short["newton"], args.turns)
        error = max(short["error"], long["error"])
        ins = None
        if code == "FEKAP" and not args.no_callgrind:
            ins = marginal(long["instructions"], short["instructions"], args.turns)
        print(f"{code:8s} {error:13.1e} {its:16.2f} {us:12.1f} {'' if ins is None else f'{ins:18,.0f}':>18s}")
        result[code] = {"slider_error": error, "newton_per_configuration": its, "cpu_us_per_configuration": us,
                        "instructions_per_configuration": ins}
    ratio = result["Exudyn"]["cpu_us_per_configuration"] / result["FEKAP"]["cpu_us_per_configuration"]
    print(f"Exudyn / FEKAP CPU time per configuration: {ratio:.2f}")
    if args.json:
        args.json.write_text(json.dumps({"turns": args.turns, "repeat": args.repeat, "machine": fb.machine(),
                                         **result}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
