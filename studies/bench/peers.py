#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Example 1 (decks/fourbar.deck) in FEKAP and in other codes, in one sitting with the
runs taking turns: the largest error of each code's positions against the closed form
(fekap.exact.fourbar), its CPU time per configuration and the ratio to FEKAP's, and its
instructions per configuration under callgrind. A benchmark script, not a test.

    studies/bench/peers.py [--binary FEKAP] [--repeat N] [--no-callgrind] [--no-peer-callgrind]
                           [--quick] [--no-write] [--json PATH]

The mechanism: crank 2 (A-B) at 2 pi rad/s, coupler 4 (B-C), rocker 4 (D-C), ground 4
(A-D), C on the upper branch; dt = 1e-4, one revolution is 10,000 steps. The cases:

- FEKAP (build/local/bin/fekap, or --binary): positions only and full kinematics, each
  with the listing alone (`files listing`, track B C) and with the deck's CSV files
  (the decks of studies/bench/bench_instructions.py, the cases of `scripts/bench`);
- Exudyn 1.13.6 with rigid bodies (ObjectRigidBody2D, RevoluteJoint2D) and with its
  geometrically exact 2D beams (ObjectBeamGeometricallyExact2D, one element a link, the
  deck's EA = 100, kGA = 250/3, EI = 1), both in its static solver with the crank's
  rotation prescribed (SolveStatic with one load step a configuration: "may also be used
  to compute kinematic behavior by prescribing joint motion", its documentation): a
  CoordinateConstraint of the crank's rotation with the offset 2 pi t as a symbolic user
  function (evaluated in C++; a Python function is slower), Newton tolerances 1e-12 as in
  studies/exudyn/exudyn_spatial_slider_crank.py. A static solve gives positions only. B and
  C are stored at every configuration by sensors in memory;
- pylinkage 1.3.0: `Linkage.step` (positions) and `Linkage.step_with_derivatives`
  (positions, velocities, accelerations), its objects, without numba (pylinkage's default
  install, Python alone: a child process with numba's NUMBA_DISABLE_JIT=1, timed inside
  as here) and with numba (its geometry functions compiled); and its numba-compiled loops
  `step_fast` and `step_fast_with_kinematics`. The cases with numba are left out when
  numba does not import.

Every run's positions of B and C are compared with the closed form at every
configuration (and its velocities and accelerations where it gives them), so that a fast
wrong answer shows. FEKAP's listing-only runs write no positions: their Newton iterations
must equal those of the CSV run of the same quantities, whose positions are checked.

CPU time per configuration, the same rule for every code: marginal, the CPU time of a
two-revolution run less a one-revolution run's, over the 10,000 configurations between
them, so that starting, reading and setting up drop out. FEKAP's is its process's (user +
system, fekap.timing); a peer's is time.process_time() around its solve call (Exudyn's
SolveStatic, pylinkage's loop over its steps; Python's garbage collector off during it, as
timeit does), in this process, after an untimed first run
of every case (imports, numba's compilation). Each case runs --repeat times (default 9),
all cases taking turns in every round; the table gives the median and
the least of the per-round figures and the ratio of each peer's median to FEKAP's median
for the same quantities with the listing alone.

Instructions per configuration (valgrind --tool=callgrind, marginal in the same way):
FEKAP's four cases at one and two revolutions (bench_instructions.measure, as
`scripts/bench`); a peer's whole Python process (this script's --worker mode, one case,
PYTHONHASHSEED=0) at PEER_CALLGRIND_STEPS configurations, since valgrind runs Python some
50 times slower; not pylinkage's cases with numba (NEEDS_NUMBA: their counts include
numba's compiling or cache loading, which differ between runs).

Exudyn comes from PyPI into build/venv-exudyn (fekap.run.in_exudyn_venv, as the studies
of studies/exudyn); pylinkage and numba (PEER_PACKAGES) are installed into that same
environment on the first run. The generated table goes between <!-- peers:begin --> and
<!-- peers:end --> of docs/performance.md ("Example 1 against other codes") unless
--no-write. It took 20-22 minutes on the shared 2-core machine at load averages of 12 to
22 (the timed rounds 5-6 of them, the rest callgrind's: --no-peer-callgrind saves about 8,
--no-callgrind about 15).
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib.util
import json
import math
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from fekap import run as fb
from fekap.exact.fourbar import fourbar_exact
from fekap.timing import callgrind_count, run_timed


def _sibling(name: str):
    """A script beside this one, imported by its path (also when this script is imported
    as a module by the tests, with no sibling on the import path)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, Path(__file__).resolve().with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


bi = _sibling("bench_instructions")   # the benchmark's decks of Example 1 and its callgrind counts

DT = bi.FOURBAR_DT
STEPS = 10_000                       # one revolution at DT
OMEGA = 2 * math.pi
POINTS = {"A": (0.0, 0.0), "B": (2.0, 0.0), "C": (3.0, math.sqrt(15.0)), "D": (4.0, 0.0)}
LINKS = (("A", "B"), ("B", "C"), ("D", "C"))      # crank, coupler, rocker (first node, second)
#: The deck's section: EA = E A, kGA = k G A, EI = E I (decks/fourbar.deck).
EA, KGA, EI = 100.0, 100.0 * 5 / 6, 1.0
EXUDYN_TOLERANCE = 1e-12
PEER_PACKAGES = ("pylinkage==1.3.0", "numba==0.68.1")
PEER_CALLGRIND_STEPS = (1000, 3000)
#: A row's time must lie within this many steps of a multiple of DT.
TIME_SLACK = 1e-6
DOC = fb.ROOT / "docs" / "performance.md"
BLOCK = "peers"


# --- the closed form and the check -------------------------------------------------------------

def exact_trajectory(steps: int, dt: float = DT) -> dict[str, np.ndarray]:
    """The closed form at t = k dt, k = 0..steps: B, C and their velocities ("vB", "vC")
    and accelerations ("aB", "aC"), each an array (steps + 1, 2)."""
    out = {key: np.empty((steps + 1, 2)) for key in ("B", "C", "vB", "vC", "aB", "aC")}
    for k in range(steps + 1):
        for name, point in zip("BC", fourbar_exact(k * dt)):
            out[name][k] = point[0].f, point[1].f
            out["v" + name][k] = point[0].d, point[1].d
            out["a" + name][k] = point[0].dd, point[1].dd
    return out


def trajectory_errors(t, series: dict, exact: dict, dt: float = DT) -> dict[str, float | None]:
    """The largest difference from the closed form of a code's trajectory: `t` the times of
    its rows, `series` its arrays (rows, 2) by the keys of exact_trajectory (B and C at
    least). Returns the largest error of the positions, velocities and accelerations (None
    for what the code did not give); NaN counts as an infinite error. A row whose time is not
    a step of `exact` is an error (ValueError)."""
    t = np.asarray(t, dtype=float)
    k = np.rint(t / dt).astype(int)
    if t.size == 0:
        raise ValueError("no rows")
    if np.any(np.abs(t / dt - k) > TIME_SLACK) or k.min() < 0 or k.max() >= len(exact["B"]):
        bad = int(np.argmax(np.abs(t / dt - k)))
        raise ValueError(f"row {bad}: t = {t[bad]!r} is not a step of dt = {dt!r} within the closed form's range")
    result: dict[str, float | None] = {}
    for what, keys in (("position", ("B", "C")), ("velocity", ("vB", "vC")), ("acceleration", ("aB", "aC"))):
        if not all(key in series for key in keys):
            if what == "position":
                raise ValueError("the positions of B and C are required")
            result[what] = None
            continue
        worst = 0.0
        for key in keys:
            values = np.asarray(series[key], dtype=float)
            if values.shape != (t.size, 2):
                raise ValueError(f"{key}: shape {values.shape}, not ({t.size}, 2)")
            difference = np.abs(values - exact[key][k])
            worst = max(worst, math.inf if np.isnan(difference).any() else float(difference.max()))
        result[what] = worst
    return result


# --- FEKAP -------------------------------------------------------------------------------------

FEKAP_CASES = {   # name -> (computes, files, the case of bench_instructions.CASES)
    "fekap P listing": ("P", "listing", "fourbar P listing"),
    "fekap PVA listing": ("PVA", "listing", "fourbar PVA listing"),
    "fekap P csv": ("P", "csv", "fourbar P csv"),
    "fekap PVA csv": ("PVA", "csv", "fourbar PVA csv"),
}


def read_points(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """points.csv of a run tracking B and C: the times and the series of B and C (velocities
    and accelerations when the file has them)."""
    import csv
    rows: dict[str, list] = {"B": [], "C": []}
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            if row["point"] in rows:
                rows[row["point"]].append(row)
    if len(rows["B"]) != len(rows["C"]):
        raise SystemExit(f"{path}: {len(rows['B'])} rows of B, {len(rows['C'])} of C")
    t = np.array([float(r["t"]) for r in rows["B"]])
    series = {}
    for name in "BC":
        for prefix, (x, y) in (("", ("x", "y")), ("v", ("vx", "vy")), ("a", ("ax", "ay"))):
            if rows[name] and rows[name][0].get(x, "") != "":
                series[prefix + name] = np.array([[float(r[x]), float(r[y])] for r in rows[name]])
    return t, series


def run_fekap_case(name: str, binary: str, work: Path, steps: int, label: str) -> dict:
    """One FEKAP run of a case over `steps` steps: its CPU seconds, Newton iterations and
    (CSV cases) its trajectory."""
    computes, files, _ = FEKAP_CASES[name]
    deck, options = bi.fourbar_deck(work, computes, files, steps / STEPS)
    out = work / f"{name.replace(' ', '-')}-{steps}-{label}"
    if out.exists():
        shutil.rmtree(out)
    _, cpu, _ = run_timed([binary, "-q", "-o", str(out), *options, str(deck)])
    summary = fb.read_listing(out / (deck.stem + ".lis"))["summary"]
    result = {"cpu": cpu, "newton": summary.get("Newton iterations"),
              "configurations": summary.get("configurations solved")}
    if result["configurations"] != steps + 1:
        raise SystemExit(f"FEKAP ({name}) solved {result['configurations']} configurations, not {steps + 1}")
    if files == "csv":
        result["t"], result["series"] = read_points(out / "points.csv")
    shutil.rmtree(out, ignore_errors=True)
    return result


@contextlib.contextmanager
def quiet_collector():
    """Python's garbage collector emptied before a peer's timed solve and off during it, as
    timeit does: its collections fall on whichever run crosses its thresholds, the likely
    cause of a round, with it on, in which twice the steps took less CPU time."""
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


# --- Exudyn ------------------------------------------------------------------------------------

def exudyn_model(kind: str, steps: int):
    """Example 1 in Exudyn ("rigid": three rigid bodies; "beam": one geometrically exact 2D
    beam element a link) with its static solver's settings for `steps` configurations after
    the first; returns (mbs, settings, sensors of B and C, the user function to keep alive)."""
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import (
        CoordinateConstraint,
        MarkerBodyPosition,
        MarkerNodeCoordinate,
        MarkerNodePosition,
        NodePointGround,
        NodeRigidBody2D,
        ObjectBeamGeometricallyExact2D,
        ObjectGround,
        ObjectRigidBody2D,
        RevoluteJoint2D,
        SensorBody,
        SensorNode,
    )

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    ends: dict[str, list] = {}
    sensors: dict[str, int] = {}
    position = exu.OutputVariableType.Position
    crank_node = None
    for p, q in LINKS:
        a, b = np.array(POINTS[p]), np.array(POINTS[q])
        length = float(np.linalg.norm(b - a))
        phi = math.atan2(b[1] - a[1], b[0] - a[0])
        if kind == "rigid":
            node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[*((a + b) / 2), phi]))
            body = mbs.AddObject(ObjectRigidBody2D(mass=1.0, inertia=length**2 / 12, nodeNumber=node))
            for name, s in ((p, -length / 2), (q, length / 2)):
                ends.setdefault(name, []).append(mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                                                  localPosition=[s, 0, 0])))
                if name in "BC" and name not in sensors:
                    sensors[name] = mbs.AddSensor(SensorBody(bodyNumber=body, localPosition=[s, 0, 0],
                                                             storeInternal=True, outputVariableType=position))
            crank_node = node if crank_node is None else crank_node
        elif kind == "beam":
            nodes = [mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[*x, phi])) for x in (a, b)]
            mbs.AddObject(ObjectBeamGeometricallyExact2D(nodeNumbers=nodes, length=length, massPerLength=1.0,
                                                         crossSectionInertia=1.0, bendingStiffness=EI,
                                                         axialStiffness=EA, shearStiffness=KGA))
            for name, node in zip((p, q), nodes):
                ends.setdefault(name, []).append(mbs.AddMarker(MarkerNodePosition(nodeNumber=node)))
                if name in "BC" and name not in sensors:
                    sensors[name] = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                                             outputVariableType=position))
            crank_node = nodes[0] if crank_node is None else crank_node
        else:
            raise ValueError(f"unknown Exudyn model {kind!r}")
    for name in "AD":
        fixed = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[*POINTS[name], 0.0]))
        mbs.AddObject(RevoluteJoint2D(markerNumbers=[fixed, ends[name][0]]))
    for name in "BC":
        mbs.AddObject(RevoluteJoint2D(markerNumbers=ends[name]))

    def drive(mbs, t, itemNumber, lOffset):
        return 2 * np.pi * t

    drive_symbolic = CreateSymbolicUserFunction(mbs, drive, "offsetUserFunction",
                                                itemTypeName="ObjectConnectorCoordinate")
    still = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    turning = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=crank_node, coordinate=2))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[still, turning], offsetUserFunction=drive_symbolic))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.staticSolver.numberOfLoadSteps = steps
    settings.staticSolver.loadStepDuration = steps * DT
    settings.staticSolver.newton.relativeTolerance = EXUDYN_TOLERANCE
    settings.staticSolver.newton.absoluteTolerance = EXUDYN_TOLERANCE
    settings.staticSolver.verboseMode = 0
    settings.solution.sensors.writePeriod = DT / 2          # every configuration
    settings.solution.file.write = False
    return mbs, settings, sensors, drive_symbolic


def run_exudyn_case(kind: str, steps: int, collect: bool = True) -> dict:
    """One Exudyn run of `steps` steps: its CPU seconds, Newton iterations and (`collect`)
    the sensors' trajectory."""
    mbs, settings, sensors, keep = exudyn_model(kind, steps)
    with quiet_collector():
        start = time.process_time()
        mbs.SolveStatic(settings)
        cpu = time.process_time() - start
    if not collect:
        return {"cpu": cpu}
    data = {name: np.asarray(mbs.GetSensorStoredData(sensor)) for name, sensor in sensors.items()}
    del keep
    if len(data["B"]) != steps + 1:
        raise SystemExit(f"Exudyn ({kind}) stored {len(data['B'])} configurations, not {steps + 1}")
    return {"cpu": cpu, "newton": mbs.sys["staticSolver"].it.newtonStepsCount, "t": data["B"][:, 0],
            "series": {name: values[:, 1:3] for name, values in data.items()}}


# --- pylinkage ---------------------------------------------------------------------------------

def pylinkage_model():
    """Example 1 in pylinkage: the crank turns 2 pi dt a step (so its step k is t = k dt),
    C an RRR dyad started on the upper branch; the crank's rate set for the derivatives."""
    import pylinkage as pl
    a, d = pl.Ground(*POINTS["A"], name="A"), pl.Ground(*POINTS["D"], name="D")
    crank = pl.Crank(anchor=a, radius=2.0, angular_velocity=OMEGA * DT, initial_angle=0.0, name="B")
    c = pl.RRRDyad(crank.output, d, 4.0, 4.0, x=POINTS["C"][0], y=POINTS["C"][1], name="C")
    linkage = pl.Linkage([a, d, crank, c])
    linkage.set_input_velocity(crank, omega=OMEGA, alpha=0.0)
    names = [component.name for component in linkage.components]
    return linkage, names.index("B"), names.index("C")


def pylinkage_has_numba() -> bool:
    from pylinkage._numba_compat import HAS_NUMBA
    return bool(HAS_NUMBA)


def run_pylinkage_case(method: str, steps: int, collect: bool = True) -> dict:
    """One pylinkage run of `steps` steps by `method` (a Linkage method): its CPU seconds
    and (`collect`) its trajectory, whose rows are the configurations after each step,
    t = dt .. steps dt."""
    linkage, ib, ic = pylinkage_model()
    if method.startswith("step_fast"):
        linkage.compile()
    with quiet_collector():
        start = time.process_time()
        if method.startswith("step_fast"):
            out = getattr(linkage, method)(iterations=steps)
        else:
            out = list(getattr(linkage, method)(iterations=steps))
        cpu = time.process_time() - start
    if not collect:
        return {"cpu": cpu}
    if method == "step_fast":
        arrays = {"": out}
    elif method == "step_fast_with_kinematics":
        arrays = dict(zip(("", "v", "a"), out))
    elif method == "step":
        arrays = {"": np.array(out, dtype=float)}
    else:
        arrays = {prefix: np.array([row[i] for row in out], dtype=float) for i, prefix in enumerate(("", "v", "a"))}
    series = {}
    for prefix, values in arrays.items():
        series[prefix + "B"], series[prefix + "C"] = values[:, ib, :], values[:, ic, :]
    return {"cpu": cpu, "newton": None, "t": DT * np.arange(1, steps + 1), "series": series}


# --- the cases ---------------------------------------------------------------------------------

#: name -> (code, what it computes: "P" or "PVA", how, the runner's key)
CASES = {
    "fekap P listing": ("FEKAP", "P", "listing only (`files listing`, track B C)"),
    "fekap PVA listing": ("FEKAP", "PVA", "listing only (`files listing`, track B C)"),
    "fekap P csv": ("FEKAP", "P", "the deck's CSV files"),
    "fekap PVA csv": ("FEKAP", "PVA", "the deck's CSV files"),
    "exudyn rigid": ("Exudyn 1.13.6", "P", "rigid bodies, static solver a configuration"),
    "exudyn beam": ("Exudyn 1.13.6", "P", "geometrically exact 2D beams, static solver a configuration"),
    "pylinkage step, no numba": ("pylinkage 1.3.0", "P", "`step`, without numba (Python alone)"),
    "pylinkage derivatives, no numba": ("pylinkage 1.3.0", "PVA",
                                        "`step_with_derivatives`, without numba (Python alone)"),
    "pylinkage step": ("pylinkage 1.3.0", "P", "`step`, its geometry compiled by numba"),
    "pylinkage derivatives": ("pylinkage 1.3.0", "PVA", "`step_with_derivatives`, its geometry compiled by numba"),
    "pylinkage numba": ("pylinkage 1.3.0", "P", "`step_fast` (numba)"),
    "pylinkage numba derivatives": ("pylinkage 1.3.0", "PVA", "`step_fast_with_kinematics` (numba)"),
}
PYLINKAGE_METHODS = {"pylinkage step": "step", "pylinkage derivatives": "step_with_derivatives",
                     "pylinkage numba": "step_fast", "pylinkage numba derivatives": "step_fast_with_kinematics"}
#: The cases run in a child process of this script with numba switched off (NUMBA_DISABLE_JIT=1,
#: numba's own switch: its decorators return the Python functions), as pylinkage runs where
#: numba, an optional extra, is not installed: the case name less this suffix.
NO_NUMBA = ", no numba"
#: The cases that need numba: left out when it does not import, and not counted under callgrind,
#: where a run's count includes numba's compiling or its loading from its cache, which differ
#: between the two run lengths (a negative marginal count was measured).
NEEDS_NUMBA = ("pylinkage step", "pylinkage derivatives", "pylinkage numba", "pylinkage numba derivatives")
NOT_UNDER_CALLGRIND = NEEDS_NUMBA
#: The FEKAP case a peer is compared with: the same quantities, the listing alone.
REFERENCE = {"P": "fekap P listing", "PVA": "fekap PVA listing"}
COMPUTES = {"P": "positions", "PVA": "positions, velocities, accelerations"}


def run_without_numba(name: str, steps: int, work: Path, collect: bool = True) -> dict:
    """A case run by this script's --worker in a child process with numba switched off: the
    child's CPU seconds of the solve (time.process_time() around it, as in this process) and
    its trajectory, handed over in a .npz file."""
    saved = work / f"no-numba-{steps}.npz"
    command = [sys.executable, str(Path(__file__).resolve()), "--worker", name, str(steps)]
    if collect:
        command += ["--save", str(saved)]
    proc = subprocess.run(command, capture_output=True, text=True, env=dict(os.environ, NUMBA_DISABLE_JIT="1"),
                          check=False)
    if proc.returncode != 0:
        raise SystemExit(f"{name} ({steps} steps) failed in its child process: {proc.stderr[-2000:]}")
    result = {"cpu": json.loads(proc.stdout.splitlines()[-1])["cpu"]}
    if collect:
        with np.load(saved) as data:
            result["t"] = data["t"]
            result["series"] = {key: data[key] for key in data.files if key != "t"}
        saved.unlink()
    return result


def run_case(name: str, steps: int, binary: str | None = None, work: Path | None = None, label: str = "",
             collect: bool = True) -> dict:
    if name.endswith(NO_NUMBA) and os.environ.get("NUMBA_DISABLE_JIT") != "1":
        return run_without_numba(name, steps, work, collect)
    name = name.removesuffix(NO_NUMBA)
    if name in FEKAP_CASES:
        return run_fekap_case(name, binary, work, steps, label)
    if name.startswith("exudyn "):
        return run_exudyn_case(name.split()[1], steps, collect)
    return run_pylinkage_case(PYLINKAGE_METHODS[name], steps, collect)


def marginal(short: float, long: float, steps_between: int) -> float:
    return (long - short) / steps_between


def summarise(name: str, rounds: list[tuple[dict, dict]], steps_between: int, errors: dict) -> dict:
    """A case's figures from its rounds (short run, long run): CPU us per configuration
    (marginal, median and least over the rounds), Newton iterations per configuration."""
    per_round = [1e6 * marginal(short["cpu"], long["cpu"], steps_between) for short, long in rounds]
    short, long = rounds[0]
    newton = None
    if short.get("newton") is not None:
        newton = marginal(short["newton"], long["newton"], steps_between)
    code, computes, how = CASES[name]
    return {"code": code, "computes": computes, "how": how, "us_median": statistics.median(per_round),
            "us_min": min(per_round), "us_rounds": per_round, "newton_per_configuration": newton, **errors}


# --- the table ---------------------------------------------------------------------------------

def _error(value: float | None) -> str:
    return "-" if value is None else f"{value:.1e}"


def ratios(results: dict) -> dict[str, float | None]:
    """Each case's median CPU per configuration over FEKAP's for the same quantities with the
    listing alone (None where that FEKAP case is missing)."""
    out = {}
    for name, r in results.items():
        reference = results.get(REFERENCE[r["computes"]])
        out[name] = r["us_median"] / reference["us_median"] if reference and reference["us_median"] > 0 else None
    return out


def table(results: dict, meta: dict) -> str:
    """The Markdown block of docs/performance.md: what was run, then one row a case."""
    lines = [f"`{meta['command']}` ({meta['date']}; {meta['binary']}; load average {meta['load_start']:.1f} at the "
             f"start, {meta['load_end']:.1f} at the end; the run took {meta['minutes']:.1f} minutes). Example 1, "
             f"dt = {DT:g}; CPU time per configuration marginal between {meta['short']:,} and {meta['long']:,} "
             f"steps, the median and least of {meta['repeat']} rounds, the cases taking turns; instructions "
             "marginal under callgrind (FEKAP between one and two revolutions, the peers' Python processes "
             f"between {meta['peer_callgrind'][0]:,} and {meta['peer_callgrind'][1]:,} steps). Errors: the "
             "largest difference of B and C from the closed form over every configuration of the timed runs.",
             "",
             "| code | what | computes | position error | velocity error | acceleration error | "
             "Newton its / configuration | CPU us / configuration, median | least | x FEKAP (same quantities, "
             "listing only) | instructions / configuration |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    ratio = ratios(results)
    for name, r in results.items():
        its = "-" if r.get("newton_per_configuration") is None else f"{r['newton_per_configuration']:.3f}"
        instructions = r.get("instructions_per_configuration")
        lines.append(f"| {r['code']} | {r['how']} | {COMPUTES[r['computes']]} | {_error(r['position'])} | "
                     f"{_error(r.get('velocity'))} | {_error(r.get('acceleration'))} | {its} | "
                     f"{r['us_median']:.2f} | {r['us_min']:.2f} | "
                     f"{'-' if ratio[name] is None else f'{ratio[name]:.2f}'} | "
                     f"{'-' if instructions is None else f'{instructions:,.0f}'} |")
    for note in meta.get("notes", []):
        lines += ["", note]
    return "\n".join(lines)


# --- running it --------------------------------------------------------------------------------

def ensure_peer_packages() -> None:
    """pylinkage and numba in this (build/venv-exudyn's) environment, installed on first use;
    never into another environment."""
    missing = []
    for package in PEER_PACKAGES:
        module = package.split("==")[0]
        try:
            __import__(module)
        except ImportError:
            missing.append(package)
    if not missing:
        return
    if Path(sys.prefix).resolve() != fb.EXUDYN_VENV.resolve():
        raise SystemExit(f"{', '.join(missing)} missing, and this is not {fb.EXUDYN_VENV}: not installing here")
    print(f"installing {', '.join(missing)} into {fb.EXUDYN_VENV} from PyPI ...", file=sys.stderr)
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", *missing], check=True)
    importlib.invalidate_caches()


def peer_instructions(name: str, steps: tuple[int, int], work: Path) -> float:
    """Marginal instructions per configuration of a peer's whole Python process (--worker)."""
    counts = []
    env = dict(os.environ, PYTHONHASHSEED="0")
    if name.endswith(NO_NUMBA):
        env["NUMBA_DISABLE_JIT"] = "1"
    for n in steps:
        out = work / f"cg-{name.replace(' ', '-')}-{n}.out"
        command = ["nice", "valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
                   str(Path(__file__).resolve()), "--worker", name, str(n)]
        proc = subprocess.run(command, capture_output=True, text=True, env=env)
        if proc.returncode != 0:
            raise SystemExit(f"callgrind run of {name} failed ({proc.returncode}): {proc.stderr[-2000:]}")
        counts.append(callgrind_count(proc.stderr))
        out.unlink(missing_ok=True)
    return (counts[1] - counts[0]) / (steps[1] - steps[0])


def worker(name: str, steps: int, save: Path | None = None) -> int:
    """One run of a peer's case in a child process: prints its CPU seconds; with `save`, its
    trajectory into that .npz file (the runs without numba). Without, the solve alone: under
    callgrind, reading the results would add instructions that grow with the steps too (the
    timed runs check every configuration)."""
    r = run_case(name, steps, collect=save is not None)
    if save is not None:
        np.savez(save, t=r["t"], **r["series"])
    print(json.dumps({"case": name, "steps": steps, "cpu": r["cpu"]}))
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", help="the fekap executable (default build/local/bin/fekap or $FEKAP_BIN)")
    parser.add_argument("--repeat", type=int, default=9, help="rounds of every case (default 9)")
    parser.add_argument("--no-callgrind", action="store_true", help="no instruction counts at all")
    parser.add_argument("--no-peer-callgrind", action="store_true", help="instruction counts of FEKAP only")
    parser.add_argument("--quick", action="store_true",
                        help="a smoke run: 1,000 and 2,000 steps, 2 rounds, no callgrind, nothing written")
    parser.add_argument("--no-write", action="store_true", help="do not rewrite docs/performance.md's block")
    parser.add_argument("--json", type=Path, help="write the figures to this file")
    parser.add_argument("--worker", nargs=2, metavar=("CASE", "STEPS"), help=argparse.SUPPRESS)
    parser.add_argument("--save", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        return worker(args.worker[0], int(args.worker[1]), args.save)
    command = shlex.join(["studies/bench/peers.py", *(sys.argv[1:] if argv is None else argv)])
    binary = fb.fekap_binary(args.binary)       # before re-executing: a missing binary stops here
    fb.in_exudyn_venv(__file__, sys.argv[1:])
    ensure_peer_packages()
    started, load_start = time.time(), os.getloadavg()[0]
    if args.quick:
        args.repeat, args.no_callgrind, args.no_write = min(args.repeat, 2), True, True
    short, long = (1000, 2000) if args.quick else (STEPS, 2 * STEPS)
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    names = list(CASES)
    notes = []
    if not pylinkage_has_numba():
        names = [n for n in names if n not in NEEDS_NUMBA]
        notes.append("pylinkage's numba paths not run: numba does not import.")
    work = fb.scratch_dir("fekap-peers-")
    print(f"Example 1, dt = {DT:g}: {len(names)} cases, {args.repeat} rounds of {short:,} and {long:,} steps "
          f"taking turns; FEKAP {binary}", flush=True)
    exact = exact_trajectory(long)
    for name in names:      # untimed: imports, numba's compilation, first touches of the files
        run_case(name, short, binary, work, "warm")
    rounds: dict[str, list] = {name: [] for name in names}
    errors: dict[str, dict] = {name: {"position": 0.0, "velocity": None, "acceleration": None} for name in names}
    for k in range(args.repeat):
        for name in names:
            pair = []
            for steps in (short, long):
                r = run_case(name, steps, binary, work, f"r{k}")
                if "series" in r:
                    found = trajectory_errors(r["t"], r["series"], exact)
                    for what, value in found.items():
                        if value is not None:
                            errors[name][what] = max(errors[name][what] or 0.0, value)
                pair.append({key: r.get(key) for key in ("cpu", "newton")})
            rounds[name].append(pair)
        print(f"  round {k + 1} of {args.repeat} done ({(time.time() - started) / 60:.1f} min)", flush=True)
    # The listing-only runs are the CSV runs' arithmetic: the same Newton iterations.
    for computes in ("P", "PVA"):
        listing, csv_case = f"fekap {computes} listing", f"fekap {computes} csv"
        its = {rounds[c][0][1]["newton"] for c in (listing, csv_case)}
        if len(its) != 1:
            raise SystemExit(f"{listing} and {csv_case} took different Newton iterations: {sorted(its)}")
        errors[listing] = dict(errors[csv_case])
    results = {name: summarise(name, rounds[name], long - short, errors[name]) for name in names}
    if not args.no_callgrind:
        print("instructions (callgrind) ...", flush=True)
        fekap_names = [name for name in names if name in FEKAP_CASES]
        counted = bi.measure(binary, work, [FEKAP_CASES[name][2] for name in fekap_names], log=lambda *a: None)
        for name in fekap_names:
            figures = counted[FEKAP_CASES[name][2]]
            results[name]["instructions_per_configuration"] = figures["instructions_per_configuration"]
            print(f"  {name}: {figures['instructions_per_configuration']:,.0f}", flush=True)
        if not args.no_peer_callgrind:
            for name in names:
                if name not in FEKAP_CASES and name not in NOT_UNDER_CALLGRIND:
                    results[name]["instructions_per_configuration"] = peer_instructions(name, PEER_CALLGRIND_STEPS,
                                                                                          work)
                    print(f"  {name}: {results[name]['instructions_per_configuration']:,.0f}", flush=True)
    shutil.rmtree(work, ignore_errors=True)
    load_end = os.getloadavg()[0]
    minutes = (time.time() - started) / 60
    git = subprocess.run(["git", "-C", str(fb.ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    shown = os.path.relpath(binary, fb.ROOT) if binary.startswith(str(fb.ROOT)) else binary
    meta = {"command": command, "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(started)),
            "binary": f"FEKAP {shown} (tree at {git.stdout.strip() or 'unknown'})", "load_start": load_start,
            "load_end": load_end, "minutes": minutes, "short": short, "long": long, "repeat": args.repeat,
            "peer_callgrind": PEER_CALLGRIND_STEPS, "notes": notes}
    if not args.no_callgrind and not args.no_peer_callgrind and any(name in NOT_UNDER_CALLGRIND for name in names):
        notes.append("pylinkage's cases with numba are not counted under callgrind: a run's count includes "
                     "numba's compiling or loading from its cache, which differ between two runs (a negative "
                     "marginal count was measured; a run of `step_fast_with_kinematics` had not finished after "
                     "4 CPU minutes under valgrind).")
    if args.no_callgrind or args.no_peer_callgrind:
        notes.append("Instructions: " + ("none counted (--no-callgrind)." if args.no_callgrind
                                         else "the peers' not counted (--no-peer-callgrind)."))
    text = table(results, meta)
    print(text)
    if not args.no_write:
        fb.replace_block(DOC, BLOCK, text)
        print(f"wrote the {BLOCK} block of {DOC.relative_to(fb.ROOT)}")
    if args.json:
        args.json.write_text(json.dumps({"meta": meta, "machine": fb.machine(), "results": results}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
