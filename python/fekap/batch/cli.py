"""The fekap-batch command: read a sweep (a TOML file and/or command-line
options), check it whole, run the cases that are not done yet on Dask, and
write summary.csv, a Markdown table and the comparison plots.

    fekap-batch [SWEEP.toml] [--deck DECK] [--param NAME=VALUES] [--option NAME=VALUES]
                [--zip] [-o DIR] [--scheduler ADDRESS] [--workers N] [--timeout S]
                [--retries N] [--measure EXPR] [--plot-point P] [--plot-quantity Q]
                [--plot-parameter NAME] [--no-plots] [--max-cases N] [--fekap PATH] [-q]

Exit codes: 0 every case has an answer (fekap's exit code, 0, 2 or 3, is in the
table) and at least one ended with exit 0, 1 some cases were lost (their workers
died or they timed out on every attempt) or every case failed, 2 a bad sweep or
command line (nothing ran: also a sweep of more cases than its limit, or an
output that is no directory), 130 interrupted (the finished cases are kept; run
the same command again to resume).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from . import engine, results
from .sweep import (
    MAX_CASES,
    Place,
    Problems,
    Sweep,
    SweepError,
    check_count,
    expand,
    expand_decks,
    load_sweep,
    option_values,
    values_of,
)

ROOT = Path(__file__).resolve().parents[3]
PROG = "fekap-batch"


def parse_args(argv):
    parser = argparse.ArgumentParser(prog=PROG, description="Run parameter sweeps of FEKAP decks on "
                                     "Dask distributed (see docs/batch.md).")
    parser.add_argument("sweep", nargs="?", help="sweep file (TOML); optional with --deck")
    parser.add_argument("--deck", action="append", default=[], help="a deck or a glob (repeatable)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUES",
                        help="deck parameter values: 1,2,3 or linspace(a,b,n) or range(start,stop,step)")
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUES",
                        help="fekap option values, e.g. method=fem,cartesian or dt=0.01,0.02")
    parser.add_argument("--zip", action="store_true", help="combine the lists element by element "
                        "(default: every combination)")
    parser.add_argument("-o", "--output", help="output directory (default out/batch/<sweep name>)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, "
                        "e.g. tcp://host:8786 (default: a LocalCluster on this machine)")
    parser.add_argument("--workers", type=int, help="LocalCluster workers (default: one per core)")
    parser.add_argument("--timeout", type=float, help="seconds a case may run (default 600)")
    parser.add_argument("--retries", type=int, help="retries of a case whose worker died or that "
                        "timed out (default 2)")
    parser.add_argument("--measure", action="append", default=[], metavar="EXPR",
                        help="a scalar result per case, e.g. 'max(points.C.y)' (repeatable)")
    parser.add_argument("--plot-point", help="point of the path/history overlay")
    parser.add_argument("--plot-quantity", help="quantity of the history overlay (default y)")
    parser.add_argument("--plot-parameter", help="x axis of the measure plots")
    parser.add_argument("--no-plots", action="store_true", help="write no plots")
    parser.add_argument("--max-cases", type=positive, metavar="N", help="most cases the sweep may have "
                        f"(default: the sweep file's max_cases, else {MAX_CASES:,})")
    parser.add_argument("--fekap", help="the fekap executable (default build/local/bin/fekap, built "
                        "by scripts/build when needed)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress, no table")
    return parser.parse_args(argv)


def positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def command_line_sweep(args, sweep: Sweep | None) -> Sweep:
    """The sweep file's sweep with the command line's decks and values added."""
    places = {"decks": Place("command line --deck"), "combine": Place("command line --zip")}
    if sweep is None:
        sweep = Sweep(source="command line", decks=[], places={})
        if args.max_cases is not None:
            sweep.max_cases = args.max_cases
        if not args.deck:
            raise SweepError("command line: give a sweep file or --deck DECK")
    problems = Problems(places, "command line", sweep.max_cases)
    sweep.places.update({k: v for k, v in places.items() if k not in sweep.places or args.deck})
    if args.deck:
        sweep.decks += expand_decks(args.deck, Path.cwd(), "decks", problems)
    if args.zip:
        sweep.combine = "zip"
    for kind, items in (("parameters", args.param), ("options", args.option)):
        for item in items:
            name, _, text = item.partition("=")
            key = f"{kind}.{name}"
            sweep.places[key] = Place(f"command line --{'param' if kind == 'parameters' else 'option'} {item}")
            problems.places = sweep.places
            if not name or not text:
                problems.add(key, "expected NAME=VALUES")
                continue
            spec = value_spec(text)
            if kind == "parameters":
                sweep.parameters[name] = values_of(spec, key, problems)
            else:
                sweep.options[name] = option_values(name, spec, key, problems)
    for text in args.measure:
        sweep.places["measures"] = Place("command line --measure")
        sweep.measures.append(text)
    problems.check()
    return sweep


def value_spec(text: str):
    """A command-line value list as a sweep file would give it."""
    match = re.fullmatch(r"(linspace|range)\((.*)\)", text.strip())
    if match:
        return {match.group(1): [number(v) for v in match.group(2).split(",")]}
    return [number(v) for v in text.split(",")]


def number(text: str):
    try:
        value = float(text)
    except ValueError:
        return text.strip()
    return int(value) if value.is_integer() and "." not in text and "e" not in text.lower() else value


def fekap_version(fekap: str) -> str:
    out = subprocess.run([fekap, "--version"], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise SweepError(f"{fekap}: --version failed: {out.stderr.strip()}")
    return out.stdout.strip()


def output_directory(args, sweep: Sweep, make: bool) -> Path:
    """The sweep's output directory, made (``make``) with its cases/ directory; a SweepError
    when it cannot be (a regular file of that name, no permission)."""
    stem = Path(args.sweep).stem if args.sweep else "sweep"
    output = Path(args.output or sweep.output or Path("out") / "batch" / stem)
    where = "command line -o" if args.output else str(sweep.places.get("output") or sweep.source)
    if output.exists() and not output.is_dir():
        raise SweepError(f"{where}: output {str(output)!r} is not a directory: give another output")
    if not make:
        return output
    try:
        (output / "cases").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SweepError(f"{where}: cannot make the output directory {str(output)!r}: "
                         f"{exc.strerror or exc}") from None
    return output


def build() -> str:
    """Build FEKAP (release, scripts/build: nothing to do when it is current); its path."""
    fekap = str(ROOT / "build" / "local" / "bin" / "fekap")
    if os.environ.get("FEKAP_BATCH_NO_BUILD"):
        return fekap
    done = subprocess.run([str(ROOT / "scripts" / "build")], stdout=sys.stderr)
    if done.returncode != 0:
        raise SweepError(f"scripts/build failed (exit {done.returncode}): see above")
    return fekap


def main(argv=None) -> int:
    try:
        return run(argv)
    except KeyboardInterrupt:  # outside the sweep's runs (they stop on their own)
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


def run(argv=None) -> int:
    args = parse_args(argv)
    try:
        sweep = load_sweep(Path(args.sweep), args.max_cases) if args.sweep else None
        sweep = command_line_sweep(args, sweep)
        measures = []
        problems = Problems(sweep.places, sweep.source)
        for text in sweep.measures:
            try:
                measures.append(results.parse_measure(text))
            except results.MeasureError as exc:
                problems.add("measures", str(exc))
        problems.check()
        if any(m.function == "error" for m in measures) and not sweep.reference:
            raise SweepError(f"{sweep.places.get('measures', Place(sweep.source))}: measures: error(...) "
                             "needs a [reference] table (the values of the reference run)")
        # Counted before anything is made or built: the list of cases, the output, FEKAP.
        check_count(sweep)
        output_directory(args, sweep, make=False)
    except SweepError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return 2
    try:
        fekap = args.fekap or build()
    except SweepError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return 1
    try:
        if not Path(fekap).is_file():
            raise SweepError(f"{fekap}: no fekap executable (run scripts/build, or give --fekap)")
        fekap = str(Path(fekap).resolve())
        version = fekap_version(fekap)
        cases, references = expand(sweep, version)
        output = output_directory(args, sweep, make=True)
    except SweepError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return 2

    cases_dir = output / "cases"
    for stale in cases_dir.glob(".*.part-*"):  # attempts of an earlier, stopped sweep
        shutil.rmtree(stale, ignore_errors=True)
    timeout = args.timeout or sweep.timeout or 600.0
    retries = args.retries if args.retries is not None else (sweep.retries if sweep.retries is not None else 2)

    every = list(dict.fromkeys(list(references.values()) + cases))
    directories = {case.name: cases_dir / case.name for case in every}
    todo = [case for case in every if not (directories[case.name] / "case.json").is_file()]
    labels = {case.name: case.label() for case in every}
    progress = engine.Progress(len(todo), quiet=args.quiet)
    if not args.quiet:
        print(f"{PROG}: {len(cases)} cases ({len(every) - len(cases)} reference runs), "
              f"{len(every) - len(todo)} done before, {len(todo)} to run; results in {output}/",
              file=sys.stderr)
    # The measures go with the cases: each worker computes its case's (but error(), which
    # needs the reference run) and stores them in case.json.
    specs = [m.spec() for m in measures if m.function != "error"]
    tasks = [{"name": case.name, "directory": str(directories[case.name].resolve()), "fekap": fekap,
              "arguments": [str(Path(a).resolve()) if a == str(case.deck) else a for a in case.arguments()],
              "cwd": str(Path.cwd()), "timeout": timeout, "attempt": 1, "measures": specs} for case in todo]
    outcome = engine.run_all(tasks, labels, args.scheduler, args.workers, retries, progress)

    rows = []
    for case in cases:
        directory = directories[case.name]
        record = results.read_record(directory)
        reference = references.get(case)
        ref_dir = directories[reference.name] if reference is not None else None
        rows.append(results.case_row(case, directory, record, outcome.lost.get(case.name), measures, ref_dir))
    columns = results.columns_of(rows, measures)
    results.write_csv(output / "summary.csv", rows, columns)
    table = results.markdown(rows, columns, measures)
    (output / "summary.md").write_text(table + "\n")
    if not args.quiet:
        print(table)
    plots = []
    if not args.no_plots and not outcome.interrupted:
        plot_dir = output / "plots"
        plot_dir.mkdir(exist_ok=True)
        finished = [c for c in cases if (results.read_record(directories[c.name]) or {}).get("exit") == 0]
        point = args.plot_point or sweep.plot.get("point")
        quantity = args.plot_quantity or sweep.plot.get("quantity", "y")
        path = results.plot_paths(finished, directories, point, quantity, plot_dir)
        plots += [path] if path else []
        plots += results.plot_measures(cases, {r["case"]: r for r in rows}, measures,
                                       args.plot_parameter or sweep.plot.get("parameter"), plot_dir,
                                       directories)
    if not args.quiet:
        ran = len(outcome.records)
        print(f"{PROG}: ran {ran} cases, {len(outcome.lost)} lost; wrote {output / 'summary.csv'}, "
              f"{output / 'summary.md'}" + "".join(f", {p}" for p in plots), file=sys.stderr)
    if outcome.interrupted:
        # Counted on disk: a case finished on a worker whose answer had not reached us yet
        # is finished too (its case.json is there), and a rerun will not run it again.
        finished = sum((directories[case.name] / "case.json").is_file() for case in every)
        print(f"{PROG}: interrupted: {finished} of {len(every)} cases finished "
              f"({finished - (len(every) - len(todo))} in this run); run the same command again "
              "to run the rest", file=sys.stderr)
        return 130
    if outcome.lost:
        return 1
    if not any(row["exit"] == "0" for row in rows):
        print(f"{PROG}: every case failed: none of the {len(rows)} ended with exit 0 "
              f"(their messages: {output / 'summary.csv'})", file=sys.stderr)
        return 1
    return 0
