#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""The spin-up beam (decks/dynamics/spin-up.deck, Simo & Vu-Quoc 1986) in
Exudyn, an independent code, against FEKAP: the tip's transverse deflection
and axial stretch in the hub's frame over 0-30 s. A comparison script, not a
test; `--store` writes the numbers test/app/test_dynamics.py checks FEKAP
against.

    studies/exudyn/exudyn_spin_up.py [--cases 10:0.01,40:0.0025] [--rho-inf 0.8] [--store]

The model: L = 10, EA = 2.8e7, GA = 1e7, EI = 1.4e4, rhoA = 1.2, rhoI = 6e-4,
clamped to a hub at the origin turned by the deck's drive table (the natural
cubic spline through the published law, python/fekap/models/spin_up.py; the same
motion FEKAP is driven by). Exudyn: NodeRigidBody2D nodes and
ObjectBeamGeometricallyExact2D elements (the 2D Simo-Reissner beam, like
FEKAP's), the first node's x and y held by ObjectConnectorCoordinate and its
rotation set by one with an offset user function (the table's angle),
generalized-alpha with spectral radius rho_inf, its default Newton settings.
FEKAP: the deck with the element count and dt changed, generalized-alpha
rho_inf 0.8 (its default). Each case (elements:dt) runs both codes with the
same mesh and step. Printed: per code the peak deflection and its time, the
value at t = 15 s, the largest magnitude after it, the mean axial stretch over
20-30 s, and the largest difference between the two codes' deflections.
`--store` writes Exudyn's run of the deck's case (10 elements, dt 0.01) every
0.05 s to test/app/data/spin-up-exudyn.csv (with --beta B:
spin-up-exudyn-betaB.csv). `--beta B` damps both: FEKAP's
section gets Rayleigh beta=B, Exudyn's elements the damping of their strain
rates beta EA, beta GA, beta EI (objective: zero for a rigid motion), the
same model once FEKAP's stiffness-proportional damping acts on the material
strain rates.

Exudyn runs in build/venv-exudyn (made on the first run, pinned in
fekap.run.EXUDYN_PACKAGES); FEKAP is build/local/bin/fekap (scripts/build).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from fekap import run as fb

DECK = fb.ROOT / "decks" / "dynamics" / "spin-up.deck"
DATA = fb.ROOT / "test" / "app" / "data"


def stored(beta: float) -> Path:
    """Where --store writes Exudyn's run of the deck's case (with damping beta)."""
    return DATA / ("spin-up-exudyn.csv" if not beta else f"spin-up-exudyn-beta{beta:g}.csv")
L, EA, GA, EI, RHOA, RHOI = 10.0, 2.8e7, 1.0e7, 1.4e4, 1.2, 6e-4
T_END = 30.0


def run_exudyn(elements: int, dt: float, rho_inf: float, t_end: float = T_END, beta: float = 0.0) -> dict:
    """Times, the hub's angle and the tip's position of Exudyn's run, and its CPU seconds;
    `beta`: stiffness-proportional damping of the strain rates (Exudyn's axial, shear and
    bending damping beta EA, beta GA, beta EI: the material strain rates, objective)."""
    import exudyn as exu
    from exudyn.itemInterface import (
        MarkerNodeCoordinate,
        NodePointGround,
        NodeRigidBody2D,
        ObjectBeamGeometricallyExact2D,
        ObjectConnectorCoordinate,
        SensorNode,
    )

    from fekap.models import spin_up as spin_up_deck

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    nodes = [mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[L * k / elements, 0, 0]))
             for k in range(elements + 1)]
    for a, b in zip(nodes, nodes[1:]):
        mbs.AddObject(ObjectBeamGeometricallyExact2D(
            nodeNumbers=[a, b], length=L / elements, massPerLength=RHOA, crossSectionInertia=RHOI,
            bendingStiffness=EI, axialStiffness=EA, shearStiffness=GA,
            bendingDamping=beta * EI, axialDamping=beta * EA, shearDamping=beta * GA))

    def coordinate(node: int, k: int) -> int:
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=k))

    fixed = coordinate(ground, 0)
    for k in (0, 1):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[fixed, coordinate(nodes[0], k)]))
    mbs.AddObject(ObjectConnectorCoordinate(
        markerNumbers=[fixed, coordinate(nodes[0], 2)],
        offsetUserFunction=lambda mbs_, t, item, offset: spin_up_deck.table_motion(t)[0]))
    hub = mbs.AddSensor(SensorNode(nodeNumber=nodes[0], storeInternal=True, writeToFile=False,
                                   outputVariableType=exu.OutputVariableType.Coordinates))
    tip = mbs.AddSensor(SensorNode(nodeNumber=nodes[-1], storeInternal=True, writeToFile=False,
                                   outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_end / dt))
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    settings.timeIntegration.automaticStepSize = False  # every step dt, as FEKAP's
    settings.timeIntegration.verboseMode = 0
    settings.solution.sensors.writePeriod = dt
    settings.solution.file.write = False
    start = time.process_time()
    mbs.SolveDynamic(settings)
    cpu = time.process_time() - start
    h, p = mbs.GetSensorStoredData(hub), mbs.GetSensorStoredData(tip)
    return {"t": h[:, 0], "angle": h[:, 3], "x": p[:, 1], "y": p[:, 2], "cpu": cpu}


def run_fekap(elements: int, dt: float, rho_inf: float, t_end: float = T_END, beta: float = 0.0) -> dict:
    """The same from FEKAP's run of the deck (element count, dt, rho_inf and the
    section's Rayleigh beta changed)."""
    from fekap import dynamics as dc

    text = DECK.read_text()
    if "OT  O  T  beam  10" not in text:
        sys.exit(f"{DECK}: its link line changed; this script sets the element count on it")
    text = text.replace("OT  O  T  beam  10", f"OT  O  T  beam  {elements}")
    if beta:
        text = text.replace("rhoI=6e-4", f"rhoI=6e-4  beta={beta!r}")
    work = fb.scratch_dir("fekap-spin-up-")
    deck = work / "spin-up.deck"
    deck.write_text(fb.with_settings(text, {"integrator": f"generalized-alpha {rho_inf!r}"}))
    result = fb.run_deck(fb.fekap_binary(), deck, work / "out", "--set", f"dt={dt!r}", "--set", f"t_end={t_end!r}")
    if result["rc"] != 0:
        sys.exit(f"fekap failed ({elements} elements, dt {dt}): {result['stderr']}")
    points = dc.columns(work / "out" / "points.csv", "T")
    return {"t": points["t"], "angle": dc.spin_up_hub_angle(points["t"]), "x": points["x"], "y": points["y"],
            "cpu": result["summary"].get("time in analysis (s)", math.nan)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="10:0.01,40:0.0025", help="elements:dt pairs, comma-separated")
    parser.add_argument("--rho-inf", type=float, default=0.8)
    parser.add_argument("--beta", type=float, default=0.0,
                        help="stiffness-proportional damping in both codes (FEKAP: the section's beta=)")
    parser.add_argument("--store", action="store_true",
                        help="write Exudyn's run of 10:0.01 to test/app/data/spin-up-exudyn[-betaB].csv")
    args = parser.parse_args()
    fb.in_exudyn_venv(__file__, sys.argv[1:])
    import numpy as np

    from fekap import dynamics as dc

    print(f"spin-up beam, generalized-alpha rho_inf {args.rho_inf:g}, 0-{T_END:g} s, beta {args.beta:g}; "
          "tip in the hub's frame")
    print("| code | elements | dt (s) | peak | t of peak (s) | at t = 15 s | largest after 15 s "
          "| mean stretch 20-30 s | largest difference Exudyn - FEKAP (after 15 s) | time (s) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    cases = [(int(e), float(d)) for e, d in (c.split(":") for c in args.cases.split(","))]
    for elements, dt in cases:
        runs = {name: run(elements, dt, args.rho_inf, beta=args.beta)
                for name, run in (("Exudyn 1.13.6", run_exudyn), ("FEKAP", run_fekap))}
        tips = {name: dc.hub_frame(r["t"], r["x"], r["y"], r["angle"]) for name, r in runs.items()}
        t_ex, _, v_ex = tips["Exudyn 1.13.6"]
        t_fe, _, v_fe = tips["FEKAP"]
        diff = np.abs(np.interp(t_ex, t_fe, v_fe) - v_ex)
        for name, (t, along, across) in tips.items():
            f = dc.spin_up_features(t, across)
            stretch = float(np.mean(along[t >= 20]))
            column = f"{diff.max():.2e} ({diff[t_ex >= 15].max():.2e})" if name == "FEKAP" else ""
            print(f"| {name} | {elements} | {dt:g} | {f['peak']:.5f} | {f['t_peak']:.4f} | {f['at15']:.3e} | "
                  f"{f['residual']:.3e} | {stretch:.5e} | {column} | {runs[name]['cpu']:.2f} |")
        if args.store and (elements, dt) == (10, 0.01):
            # Exudyn's steps end within 1e-5 s of multiples of dt (its own time bookkeeping; the
            # hub's angle is the table's at those times): interpolated to the 0.05 s grid.
            t, along, across = tips["Exudyn 1.13.6"]
            grid = np.round(np.arange(0, T_END + 1e-9, 0.05), 2)
            path = stored(args.beta)
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(path, "w") as handle:
                handle.write("# The spin-up beam in Exudyn 1.13.6 "
                             f"(studies/exudyn/exudyn_spin_up.py --store --beta {args.beta:g}):\n"
                             f"# 10 ObjectBeamGeometricallyExact2D elements, dt 0.01, generalized-alpha {args.rho_inf:g};\n"
                             "# the tip's axial stretch and transverse deflection in the hub's frame every 0.05 s.\n")
                handle.write("t,along,across\n")
                for g, a, c in zip(grid, np.interp(grid, t, along), np.interp(grid, t, across)):
                    handle.write(f"{g:.2f},{a:.9e},{c:.9e}\n")
            print(f"wrote {path.relative_to(fb.ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
