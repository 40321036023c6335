#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""FEKAP's performance benchmarks (run through scripts/bench, which builds the
release binary first).

1. Example 1 (decks/fourbar.deck) at dt = 1e-4 over one revolution (10,000
   configurations): microseconds per configuration for positions only,
   positions + velocities, and positions + velocities + accelerations, each
   with CSV output of two tracked points (`files csv listing`, track B C) and
   without (`files listing`); Newton iterations per step and the split of the
   analysis time into assembly, factorisation, solves and the rest, and the
   output time, all from the listing's SUMMARY. Each case is run --repeat
   times, the cases taking turns (a slow spell of a shared machine then falls
   on all of them); the median is reported.

     per configuration "analysis" = listing's "time in analysis" / configurations
     per configuration "total"    = listing's "total time" (analysis + output) / configurations

   Neither includes reading the deck or starting the process.

2. Scale: scissor lifts of N cells (python/fekap/models/scissor.py), time per
   configuration, peak RSS and half-bandwidth for N = 10 ... 10,000 with the
   band solver, and with a dense LU (ANALysis `solver dense`) where feasible.

3. Dynamics (decks/dynamics): microseconds per step (the listing's analysis
   time, and the process's CPU time less a one-step run's) and Newton iterations per step of the
   flexible slider-crank and the A02 chain N = 40, and Exudyn's CPU time and
   iterations per step on the same slider-crank when build/venv-exudyn exists
   (studies/exudyn/exudyn_slider_crank.py --cost), with the speed ratios at equal
   accuracy of the last study it recorded (docs/dynamics/exudyn-slider-crank.json).
   Its line, before the last:

  dynamics slider-crank_us_per_step=X slider-crank_cpu_us_per_step=X ... slider-crank_exudyn_cpu_us_per_step=X ...

The last line printed is

  fourbar us_per_config_full=X us_per_config_positions=X us_per_config_with_output=X iterations_per_step=X

(full and positions: analysis time without output files; with_output: total
time, full kinematics, CSV of B and C written.)

Without --quick the figures also go to docs/performance.md (between the
bench markers), docs/performance/bench.json and docs/performance/scissor.png.

4. Instructions (studies/bench/bench_instructions.py): the marginal user-space
   instructions per configuration of a fixed set of cases under valgrind's
   callgrind (Example 1 P and P+V+A, with the listing alone and with the
   deck's CSV files; the scissor lift at N = 100 and 1,000; a dynamics step of
   the flexible slider-crank), which the machine's load does not move. A full
   run records them in docs/performance/bench.json ("instructions") and in
   docs/performance.md; `--check` runs them alone against bench.json and
   exits 1 when a case rose by more than 5 % (run it before any change to the
   solver; CI does not, it takes minutes).

Usage: scripts/bench [--quick] [--repeat N] [--no-scissor] [--sizes 10,100,1000,10000]
                     [--dense-sizes 10,100] [--bin FEKAP] [--no-docs] [--dynamics-only]
                     [--check] [--instructions-only] [--no-instructions]

--dynamics-only runs section 3 alone (and writes only its table); its line is then the last.
--instructions-only runs section 4 alone and records it (its table and bench.json's "instructions").
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

from fekap import run as fb
from fekap.models import scissor

import bench_instructions as bi

COMPUTE = {
    "positions": "positions",
    "velocities": "positions velocities",
    "full": "positions velocities accelerations",
}
FILES = {"no_output": "listing", "with_output": "csv listing"}
# The scissor lifts run at the default tolerances; the tallest needs more than
# the default 25 Newton iterations per step (see docs/performance.md).
SCISSOR_DT = 0.1
SCISSOR_ITERATIONS = "100"
# The step of the iteration-count aim (the paper's Table 1 step).
AIM_DT = 0.025


def fourbar_deck(work: Path, dt: float, compute: str, files: str) -> Path:
    """Example 1 with these settings, two tracked points."""
    deck = work / f"fourbar-{compute}-{files}.deck"
    text = (fb.ROOT / "decks" / "fourbar.deck").read_text()
    deck.write_text(fb.with_settings(text, {"time": f"0 1 {dt!r}", "compute": COMPUTE[compute]},
                                     {"track": "B C", "files": FILES[files]}))
    return deck


def fourbar_run(binary: str, work: Path, deck: Path, k: int) -> dict:
    """The figures of one run of a deck of fourbar_deck."""
    result = fb.run_deck(binary, deck, work / f"out-{deck.stem}-{k}")
    if result["rc"] != 0 or "summary" not in result:
        raise SystemExit(f"fekap failed on {deck} (exit {result['rc']}):\n{result['stderr']}")
    s = result["summary"]
    n = s["configurations solved"]
    shutil.rmtree(result["outdir"], ignore_errors=True)
    return {
        "configs": n,
        "analysis_us": 1e6 * s["time in analysis (s)"] / n,
        "total_us": 1e6 * s["total time (s)"] / n,
        "output_us": 1e6 * s["time in output (s)"] / n,
        "assembly_us": 1e6 * s["of which assembly (s)"] / n,
        "factorisation_us": 1e6 * s["of which factorisation (s)"] / n,
        "solves_us": 1e6 * s["of which solves (s)"] / n,
        "wall_us": 1e6 * result["wall"] / n,
        "iterations_per_step": s["Newton iterations"] / max(1, n - 1),
    }


def fourbar_cases(binary: str, work: Path, dt: float, repeat: int) -> dict:
    """Median figures of `repeat` runs of every case. The cases take turns
    (one run of each, `repeat` rounds), so that a slow spell of a shared
    machine falls on all of them alike rather than on one case."""
    decks = {(c, f): fourbar_deck(work, dt, c, f) for f in FILES for c in COMPUTE}
    runs: dict = {key: [] for key in decks}
    for k in range(repeat):
        for key, deck in decks.items():
            runs[key].append(fourbar_run(binary, work, deck, k))
    cases = {}
    for key, rs in runs.items():
        median = {name: statistics.median(r[name] for r in rs) for name in rs[0]}
        median["other_us"] = median["analysis_us"] - median["assembly_us"] - median["factorisation_us"] \
            - median["solves_us"]
        median["spread_analysis_us"] = (min(r["analysis_us"] for r in rs), max(r["analysis_us"] for r in rs))
        cases[key] = median
    return cases


def listing_count(result: dict, text: str) -> int:
    """How many lines of a run's listing contain `text`."""
    listing = [p for p in Path(result["outdir"]).glob("*.lis")]
    return sum(line.count(text) for p in listing for line in p.read_text().splitlines())


def aim_iterations(binary: str, work: Path) -> dict:
    """Newton iterations per step of Example 1 as shipped (dt = 0.025, default
    predictor and tolerances): the paper needed 6."""
    deck = work / "fourbar-aim.deck"
    deck.write_text(fb.with_settings((fb.ROOT / "decks" / "fourbar.deck").read_text(),
                                     {"time": f"0 1 {AIM_DT!r}"}, {"files": "listing"}))
    result = fb.run_deck(binary, deck, work / "out-aim")
    if result["rc"] != 0 or "summary" not in result:
        raise SystemExit(f"fekap failed on {deck} (exit {result['rc']}):\n{result['stderr']}")
    s = result["summary"]
    steps = round(1 / AIM_DT)
    shutil.rmtree(result["outdir"], ignore_errors=True)
    return {"dt": AIM_DT, "steps": steps, "iterations": s["Newton iterations"],
            "configurations": s["configurations solved"],
            "per_step": s["Newton iterations"] / steps}


def scissor_case(binary: str, work: Path, cells: int, solver: str, repeat: int) -> dict:
    """Time per configuration, peak RSS and bandwidth of an N-cell scissor lift."""
    deck = work / f"scissor-{cells}-{solver}.deck"
    text = scissor.deck_text(cells, dt=SCISSOR_DT, solver=solver, files="listing")
    deck.write_text(fb.with_settings(text, {"iterations": SCISSOR_ITERATIONS}))
    runs = []
    for k in range(repeat):
        result = fb.run_deck(binary, deck, work / f"out-scissor-{cells}-{solver}-{k}", measure_memory=True)
        if result["rc"] not in (0, 3) or not result.get("summary"):
            raise SystemExit(f"fekap failed on {deck} (exit {result['rc']}):\n{result['stderr']}")
        s = result["summary"]
        n = s["configurations solved"]
        its = max(1, s["Newton iterations"])
        runs.append({
            "rc": result["rc"],
            "ms_per_config": 1e3 * s["time in analysis (s)"] / n if result["rc"] == 0 else float("nan"),
            "ms_per_iteration": 1e3 * s["time in analysis (s)"] / its,
            "factorisation_ms_per_iteration": 1e3 * s["of which factorisation (s)"] / its,
            "iterations_per_step": s["Newton iterations"] / max(1, n - 1) if result["rc"] == 0 else float("nan"),
            "rss_mb": result.get("rss_kb", 0) / 1024,
            "setup_s": result["wall"] - s["total time (s)"],
            "roundoff_steps": listing_count(result, "round-off floor"),
        })
        plan = result["plan"]
        shutil.rmtree(result["outdir"], ignore_errors=True)
    median = {key: statistics.median(r[key] for r in runs) for key in runs[0]}
    median["status"] = "ok" if all(r["rc"] == 0 for r in runs) else \
        "did not converge: " + result["stderr"].strip().split(": ", 1)[-1][:160]
    if median["status"] == "ok" and median["roundoff_steps"] > 0:
        median["status"] = f"ok, {median['roundoff_steps']:g} step(s) stopped at the residual's round-off floor"
    median.update({"cells": cells, "solver": solver, "equations": plan.get("equations", 0),
                   "half_bandwidth": plan.get("half_bandwidth", 0), "repeat": repeat})
    return median


#: Dynamics benchmarks of the bench line: deck, its --set overrides (quick, full, and one step: the start-up).
DYNAMICS = {"slider-crank": ("slider-crank.deck", {"t_end": "0.02"}, {"t_end": "0.1"}, {"t_end": "1e-4"}),
            "a02-n40": ("a02-n40.deck", {"t_end": "0.2"}, {"t_end": "2"}, {"t_end": "0.002"})}


def dynamics_case(binary: str, work: Path, name: str, quick: bool, repeat: int) -> dict:
    """Microseconds per step (analysis time, the listing's wall clock; and the
    process's CPU time less that of a one-step run, the start-up) and Newton
    iterations per step of a dynamics benchmark deck, median of `repeat` runs."""
    deck, short, full, one = DYNAMICS[name]
    sets = [x for key, value in (short if quick else full).items() for x in ("--set", f"{key}={value}")]
    runs = []
    for k in range(repeat):
        cpu = children_cpu()
        fb.run_deck(binary, fb.ROOT / "decks" / "dynamics" / deck, work / f"dyn-{name}-start-{k}",
                    *[x for key, value in one.items() for x in ("--set", f"{key}={value}")])
        start = children_cpu() - cpu
        cpu = children_cpu()
        result = fb.run_deck(binary, fb.ROOT / "decks" / "dynamics" / deck, work / f"dyn-{name}-{k}", *sets)
        cpu = children_cpu() - cpu - start
        if result["rc"] != 0 or "summary" not in result:
            raise SystemExit(f"fekap failed on {deck} (exit {result['rc']}):\n{result['stderr']}")
        s = result["summary"]
        steps = max(1, s["configurations solved"] - 1)
        runs.append({"us_per_step": 1e6 * s["time in analysis (s)"] / steps, "cpu_us_per_step": 1e6 * cpu / steps,
                     "iterations_per_step": s["Newton iterations"] / steps, "steps": steps,
                     "equations": result["plan"].get("equations", 0)})
        shutil.rmtree(result["outdir"], ignore_errors=True)
        shutil.rmtree(work / f"dyn-{name}-start-{k}", ignore_errors=True)
    return {key: statistics.median(r[key] for r in runs) for key in runs[0]}


def children_cpu() -> float:
    """User + system CPU seconds of the finished child processes so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


#: Exudyn's side of the slider-crank (studies/exudyn/exudyn_slider_crank.py, in its own
#: environment) and the last equal-accuracy study it recorded.
EXUDYN_PYTHON = fb.ROOT / "build" / "venv-exudyn" / "bin" / "python"
EXUDYN_STUDY = fb.ROOT / "docs" / "dynamics" / "exudyn-slider-crank.json"


def exudyn_case(quick: bool, repeat: int) -> dict | None:
    """Exudyn's CPU microseconds and Newton iterations per step on the
    slider-crank at the deck's dt (median of `repeat` runs, as FEKAP's); None without
    build/venv-exudyn (made by the first run of studies/exudyn/exudyn_slider_crank.py)."""
    if not EXUDYN_PYTHON.is_file():
        return None
    t_end = DYNAMICS["slider-crank"][1 if quick else 2]["t_end"]
    done = subprocess.run([str(EXUDYN_PYTHON), str(fb.ROOT / "scripts" / "exudyn_slider_crank.py"), "--cost",
                           "--t-end", t_end, "--repeat", str(repeat)], capture_output=True, text=True)
    if done.returncode != 0:
        return None
    return json.loads(done.stdout.strip().splitlines()[-1])


def dynamics_table(cases: dict, exudyn: dict | None) -> str:
    rows = ["| benchmark | equations | steps | us per step (analysis) | CPU us per step | Newton iterations per step |",
            "|---|---|---|---|---|---|"]
    for name, c in cases.items():
        rows.append(f"| {name} | {c['equations']:.0f} | {c['steps']:.0f} | {c['us_per_step']:.1f} | "
                    f"{c['cpu_us_per_step']:.1f} | {c['iterations_per_step']:.2f} |")
    if exudyn:
        rows.append(f"| slider-crank, Exudyn 1.13.6 | | {exudyn['steps']:.0f} | | {exudyn['us_per_step']:.1f} | "
                    f"{exudyn['iterations_per_step']:.2f} |")
    return "\n".join(rows)


def fourbar_table(cases: dict) -> str:
    head = ("| computed | output | us/config analysis | us/config total | assembly | factorisation "
            "| solves | other analysis | output | Newton its/step |\n"
            "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = []
    for (compute, files), c in cases.items():
        rows.append(f"| {COMPUTE[compute].replace(' ', ' + ')} | {FILES[files]} | {c['analysis_us']:.2f} "
                    f"| {c['total_us']:.2f} | {c['assembly_us']:.2f} | {c['factorisation_us']:.2f} "
                    f"| {c['solves_us']:.2f} | {c['other_us']:.2f} | {c['output_us']:.2f} "
                    f"| {c['iterations_per_step']:.3f} |")
    return head + "\n" + "\n".join(rows)


def scissor_table(cases: list[dict]) -> str:
    head = ("| N cells | solver | equations | half-bandwidth | ms/config | ms/Newton iteration "
            "| of which factorisation | Newton its/step | peak RSS (MB) | deck reading + setup (s) | runs |\n"
            "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = [f"| {c['cells']} | {c['solver']} | {c['equations']} | {c['half_bandwidth']} | "
            f"{num(c['ms_per_config'])} | {num(c['ms_per_iteration'])} | "
            f"{num(c['factorisation_ms_per_iteration'])} | {num(c['iterations_per_step'], '.2f')} | "
            f"{c['rss_mb']:.1f} | {c['setup_s']:.2f} | {c['repeat']} |" for c in cases]
    notes = [f"- N = {c['cells']} ({c['solver']}): {c['status']}" for c in cases if c["status"] != "ok"]
    return head + "\n" + "\n".join(rows) + ("\n\n" + "\n".join(notes) if notes else "")


def num(value: float, form: str = ".4g") -> str:
    return "-" if value != value else format(value, form)


def plot_scissor(cases: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for solver, marker in (("band", "o-"), ("dense", "s--")):
        sel = [c for c in cases if c["solver"] == solver]
        if sel:
            ax.loglog([c["cells"] for c in sel], [c["ms_per_iteration"] for c in sel], marker,
                      label=f"{solver} solver")
    band = [c for c in cases if c["solver"] == "band"]
    if band:
        n0, t0 = band[0]["cells"], band[0]["ms_per_iteration"]
        ns = [c["cells"] for c in band]
        ax.loglog(ns, [t0 * n / n0 for n in ns], ":", color="grey", label="slope 1 (linear)")
    ax.set_xlabel("cells N")
    ax.set_ylabel("analysis time per Newton iteration (ms)")
    ax.set_title("Scissor lift: cost per Newton iteration vs size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def dynamics_section(binary: str, work: Path, quick: bool, repeat: int) -> tuple[dict, dict | None, list]:
    """Section 3: the dynamics decks' cost per step, Exudyn's on the
    slider-crank, and the equal-accuracy ratios of the last study; printed."""
    print("\nDynamics (decks/dynamics, generalized-alpha rho_inf 0.8; Exudyn on the slider-crank: "
          "studies/exudyn/exudyn_slider_crank.py)")
    dynamics = {name: dynamics_case(binary, work, name, quick, repeat) for name in DYNAMICS}
    for name, c in dynamics.items():
        print(f"  {name:14s} {c['equations']:5.0f} equations, {c['steps']:6.0f} steps: {c['us_per_step']:9.1f} us "
              f"per step (analysis), {c['cpu_us_per_step']:9.1f} us CPU, "
              f"{c['iterations_per_step']:.2f} Newton iterations per step")
    exudyn = exudyn_case(quick, repeat)
    if exudyn:
        print(f"  slider-crank, Exudyn 1.13.6: {exudyn['us_per_step']:9.1f} us CPU per step, "
              f"{exudyn['iterations_per_step']:.2f} Newton iterations per step "
              f"({exudyn['us_per_step'] / dynamics['slider-crank']['cpu_us_per_step']:.1f} x FEKAP's CPU per step)")
    else:
        print("  slider-crank, Exudyn: not run (no build/venv-exudyn: studies/exudyn/exudyn_slider_crank.py makes it)")
    equal = json.loads(EXUDYN_STUDY.read_text())["equal_error"] if EXUDYN_STUDY.is_file() else []
    if equal:
        print("  at equal accuracy (docs/dynamics.md, studies/exudyn/exudyn_slider_crank.py --study): Exudyn / FEKAP CPU "
              + ", ".join(f"{e['ratio']:.1f} x at {e['error']:.0e} m" for e in equal))
    return dynamics, exudyn, equal


def dynamics_line(dynamics: dict, exudyn: dict | None, equal: list) -> str:
    """The one-line summary of section 3 (see the module's docstring)."""
    return ("dynamics " + " ".join(f"{name}_us_per_step={c['us_per_step']:.2f} "
                                   f"{name}_cpu_us_per_step={c['cpu_us_per_step']:.2f} "
                                   f"{name}_iterations_per_step={c['iterations_per_step']:.3f}"
                                   for name, c in dynamics.items())
            + (f" slider-crank_exudyn_cpu_us_per_step={exudyn['us_per_step']:.2f} "
               f"slider-crank_exudyn_iterations_per_step={exudyn['iterations_per_step']:.3f}" if exudyn else "")
            + "".join(f" slider-crank_equal_error_{e['error']:.0e}_ratio={e['ratio']:.2f}" for e in equal))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="FEKAP benchmarks")
    parser.add_argument("--quick", action="store_true",
                        help="reduced run for the tests: dt = 1e-3, 1 repetition, small scissors, no docs")
    parser.add_argument("--repeat", type=int, help="repetitions per case (default 9, quick 1)")
    parser.add_argument("--dt", type=float, help="time step of Example 1 (default 1e-4, quick 1e-3)")
    parser.add_argument("--no-scissor", action="store_true", help="skip the scissor-lift scaling runs")
    parser.add_argument("--sizes", help="scissor cells, comma-separated (default 10,100,1000,3000,10000)")
    parser.add_argument("--dense-sizes", help="scissor cells for the dense solver (default 10,100)")
    parser.add_argument("--bin", help="fekap executable (default: $FEKAP_BIN, else build/local/bin/fekap)")
    parser.add_argument("--no-docs", action="store_true", help="do not write docs/performance*")
    parser.add_argument("--dynamics-only", action="store_true",
                        help="section 3 only (its table in docs/performance.md); its line is the last")
    parser.add_argument("--check", action="store_true",
                        help="instruction counts only, against docs/performance/bench.json: exit 1 on a rise > 5 %%")
    parser.add_argument("--instructions-only", action="store_true",
                        help="instruction counts only, recorded in bench.json and docs/performance.md")
    parser.add_argument("--no-instructions", action="store_true", help="skip the instruction counts")
    args = parser.parse_args(argv)
    if args.check or args.instructions_only:
        return instructions_main(args)
    repeat = args.repeat or (1 if args.quick else 9)
    dt = args.dt or (1e-3 if args.quick else 1e-4)
    sizes = [int(x) for x in (args.sizes or ("10,30" if args.quick else "10,100,1000,3000,10000")).split(",") if x]
    dense_sizes = [int(x) for x in (args.dense_sizes or ("10" if args.quick else "10,100")).split(",") if x]
    write_docs = not (args.quick or args.no_docs)
    binary = fb.fekap_binary(args.bin)
    work = fb.scratch_dir("fekap-bench-")
    info = fb.machine()
    print(f"machine: {info['nproc']} x {info['cpu']}; {info['gfortran']}; BLAS {info['blas']}")
    print(f"binary: {binary}")
    if args.dynamics_only:
        dynamics, exudyn, equal = dynamics_section(binary, work, args.quick, repeat)
        shutil.rmtree(work, ignore_errors=True)
        if write_docs:
            fb.replace_block(fb.ROOT / "docs" / "performance.md", "bench-dynamics", dynamics_table(dynamics, exudyn))
        print(dynamics_line(dynamics, exudyn, equal))
        return 0

    print(f"\nExample 1, dt = {dt:g} ({round(1 / dt)} steps), median of {repeat} run(s); "
          "us per configuration")
    cases = fourbar_cases(binary, work, dt, repeat)
    for files in FILES:
        for compute in COMPUTE:
            c = cases[(compute, files)]
            print(f"  {COMPUTE[compute]:36s} {FILES[files]:12s} analysis {c['analysis_us']:8.2f}  "
                  f"total {c['total_us']:8.2f}  (assembly {c['assembly_us']:.2f}, factorisation "
                  f"{c['factorisation_us']:.2f}, solves {c['solves_us']:.2f}, other {c['other_us']:.2f}, "
                  f"output {c['output_us']:.2f}; {c['iterations_per_step']:.3f} its/step; "
                  f"analysis range {c['spread_analysis_us'][0]:.2f}-{c['spread_analysis_us'][1]:.2f})")
    print("  simulate only what a deck calls for (analysis time, no output files): "
          f"positions {cases[('positions', 'no_output')]['analysis_us']:.2f} us, "
          f"+velocities {cases[('velocities', 'no_output')]['analysis_us']:.2f} us, "
          f"+accelerations {cases[('full', 'no_output')]['analysis_us']:.2f} us per configuration")

    aim = aim_iterations(binary, work)
    print(f"\nExample 1, dt = {aim['dt']} (as shipped, default predictor and tolerances): "
          f"{aim['iterations']:g} Newton iterations over {aim['steps']} steps = {aim['per_step']:.3f} per step "
          f"({aim['configurations']:g} configurations solved, step-doubling checks included)")

    dynamics, exudyn, equal = dynamics_section(binary, work, args.quick, repeat)

    scissor_cases: list[dict] = []
    if not args.no_scissor:
        print(f"\nScissor lift, dt = {SCISSOR_DT}, default tolerances, at most {SCISSOR_ITERATIONS} iterations: "
              "per configuration "
              "(analysis time), peak RSS")
        for solver, ns in (("band", sizes), ("dense", dense_sizes)):
            for cells in ns:
                reps = 1 if (cells >= 3000 or (solver == "dense" and cells >= 100)) else min(repeat, 3)
                c = scissor_case(binary, work, cells, solver, reps)
                scissor_cases.append(c)
                print(f"  N = {cells:6d} {solver:5s} {c['equations']:7d} equations, half-bandwidth "
                      f"{c['half_bandwidth']:3d}: {c['ms_per_config']:10.4f} ms/config, "
                      f"{c['ms_per_iteration']:.4f} ms/iteration (factorisation "
                      f"{c['factorisation_ms_per_iteration']:.4f}), {c['iterations_per_step']:.2f} its/step, "
                      f"peak RSS {c['rss_mb']:.1f} MB, reading + setup {c['setup_s']:.2f} s; {c['status']}")

    counted = None
    if not (args.quick or args.no_instructions):
        print("\nInstructions per configuration (callgrind, marginal: two run lengths)")
        counted = bi.measure(binary, work)

    shutil.rmtree(work, ignore_errors=True)
    if write_docs:
        doc = fb.ROOT / "docs" / "performance.md"
        if counted:
            fb.replace_block(doc, "bench-instructions", bi.table(counted))
        fb.replace_block(doc, "bench-machine",
                         f"- nproc: {info['nproc']}\n- CPU: {info['cpu']}\n- compiler: {info['gfortran']}\n"
                         f"- BLAS/LAPACK: {info['blas']}")
        fb.replace_block(doc, "bench-fourbar",
                         f"Example 1, dt = {dt:g} ({round(1 / dt)} steps, {round(1 / dt) + 1} configurations), "
                         f"median of {repeat} runs, microseconds per configuration:\n\n" + fourbar_table(cases)
                         + f"\n\nNewton iterations of Example 1 as shipped (dt = {aim['dt']}, default predictor "
                         f"and tolerances): {aim['iterations']:g} over {aim['steps']} steps, "
                         f"**{aim['per_step']:.3f} per step** ({aim['configurations']:g} configurations "
                         "solved, step-doubling checks included).")
        fb.replace_block(doc, "bench-dynamics", dynamics_table(dynamics, exudyn))
        if scissor_cases:
            fb.replace_block(doc, "bench-scissor", scissor_table(scissor_cases))
            plot_scissor(scissor_cases, fb.ROOT / "docs" / "performance" / "scissor.png")
        record = {"machine": info, "dt": dt, "repeat": repeat, "aim_iterations": aim,
                  "fourbar": {f"{k[0]}/{k[1]}": v for k, v in cases.items()}, "scissor": scissor_cases,
                  "dynamics": dynamics, "exudyn": exudyn}
        if counted:
            record["instructions"] = counted
        elif BENCH_JSON.is_file() and "instructions" in json.loads(BENCH_JSON.read_text()):
            # --no-instructions keeps the counts recorded before (--check compares with them).
            record["instructions"] = json.loads(BENCH_JSON.read_text())["instructions"]
        (fb.ROOT / "docs" / "performance").mkdir(parents=True, exist_ok=True)
        (fb.ROOT / "docs" / "performance" / "bench.json").write_text(json.dumps(record, indent=1) + "\n")

    print(dynamics_line(dynamics, exudyn, equal))
    full = cases[("full", "no_output")]
    print(f"fourbar us_per_config_full={full['analysis_us']:.3f} "
          f"us_per_config_positions={cases[('positions', 'no_output')]['analysis_us']:.3f} "
          f"us_per_config_with_output={cases[('full', 'with_output')]['total_us']:.3f} "
          f"iterations_per_step={full['iterations_per_step']:.3f}")
    return 0


BENCH_JSON = fb.ROOT / "docs" / "performance" / "bench.json"


def instructions_main(args: argparse.Namespace) -> int:
    """--check and --instructions-only: the instruction counts alone."""
    binary = fb.fekap_binary(args.bin)
    work = fb.scratch_dir("fekap-bench-instructions-")
    print(f"binary: {binary}")
    print("Instructions per configuration (callgrind, marginal: two run lengths)")
    counted = bi.measure(binary, work)
    shutil.rmtree(work, ignore_errors=True)
    record = json.loads(BENCH_JSON.read_text()) if BENCH_JSON.is_file() else {}
    if args.check:
        recorded = record.get("instructions")
        if not recorded:
            print(f"{BENCH_JSON} records no instruction counts: run scripts/bench --instructions-only first")
            return 1
        print(f"Against {BENCH_JSON.relative_to(fb.ROOT)} (a rise of more than {bi.CHECK_RISE:.0%} fails):")
        ok = bi.check(counted, recorded)
        print("bench check: " + ("passed" if ok else "FAILED"))
        return 0 if ok else 1
    if not args.no_docs:
        record["instructions"] = counted
        BENCH_JSON.parent.mkdir(parents=True, exist_ok=True)
        BENCH_JSON.write_text(json.dumps(record, indent=1) + "\n")
        fb.replace_block(fb.ROOT / "docs" / "performance.md", "bench-instructions", bi.table(counted))
    return 0


if __name__ == "__main__":
    sys.exit(main())
