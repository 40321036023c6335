"""The results of a sweep: one row per case (its parameters and options, exit
code and message, steps, Newton iterations per step, step cuts, analysis time
per configuration and the user's measures), as summary.csv and a Markdown
table; and the comparison plots (drawn by scripts/compare.py)."""

from __future__ import annotations

import csv
import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fekap import compare
from fekap import read as fc
from fekap import stream as fs

from . import task
from .sweep import Case, format_value

FUNCTIONS = ("max", "min", "range", "mean", "first", "final", "absmax", "error")
MEASURE = re.compile(r"^\s*(\w+)\(\s*(points|links|steps)\.([^.()\s]+)(?:\.(\w+))?\s*\)\s*$")


class MeasureError(Exception):
    """A measure that does not parse."""


@dataclass(frozen=True)
class Measure:
    """A scalar from a case's results: FUNCTION(points.P.Q), (links.L.Q), (steps.Q)."""

    text: str
    function: str
    source: str
    name: str
    quantity: str | None

    def spec(self) -> list:
        """The measure as batch.task.measures takes it (on a worker: plain data)."""
        return [self.text, self.function, self.source, self.name, self.quantity]

    def value(self, run: fc.Run, reference: fc.Run | None) -> float | None:
        series = self._series(run)
        if series is None:
            return None
        t, values = series
        if self.function == "error":
            if reference is None:
                return None
            ref = self._series(reference)
            if ref is None:
                return None
            ref_t, ref_values = ref
            inside = (t >= ref_t[0] - 1e-12) & (t <= ref_t[-1] + 1e-12)
            diff = values[inside] - np.column_stack([np.interp(t[inside], ref_t, column)
                                                     for column in ref_values.T])
            return float(np.max(np.linalg.norm(diff, axis=1))) if diff.size else None
        column = values[:, 0]
        column = column[np.isfinite(column)]
        if column.size == 0:
            return None
        return float({"max": np.max, "min": np.min, "mean": np.mean, "absmax": lambda v: np.max(np.abs(v)),
                      "range": lambda v: np.max(v) - np.min(v), "first": lambda v: v[0],
                      "final": lambda v: v[-1]}[self.function](column))

    def _series(self, run: fc.Run) -> tuple[np.ndarray, np.ndarray] | None:
        """Times and the quantity's values (columns: x and y for error(points.P))."""
        if self.source == "steps":
            if run.steps is None or self.name not in run.steps:
                return None
            return run.steps["t"], run.steps[self.name][:, None]
        table = run.points if self.source == "points" else run.links
        series = table.get(self.name)
        if series is None:
            return None
        quantities = [self.quantity] if self.quantity else ["x", "y"]
        if not all(series.has(q) for q in quantities):
            return None
        return series.t, np.column_stack([series.values[q] for q in quantities])


def parse_measure(text: str) -> Measure:
    """A measure from its text, e.g. max(points.C.y), range(links.DC.angle),
    error(points.C) (the largest distance from the reference run's C)."""
    match = MEASURE.match(text)
    if not match:
        raise MeasureError(f"{text!r}: expected FUNCTION(points.POINT.QUANTITY), "
                           f"FUNCTION(links.LINK.QUANTITY) or FUNCTION(steps.COLUMN), FUNCTION one of "
                           + " ".join(FUNCTIONS))
    function, source, name, quantity = match.groups()
    if function not in FUNCTIONS:
        raise MeasureError(f"{text!r}: unknown function {function!r} (functions: {' '.join(FUNCTIONS)})")
    if source == "steps":
        if quantity is not None:
            raise MeasureError(f"{text!r}: steps.COLUMN takes no point or link name")
        return Measure(text.strip(), function, source, name, None)
    allowed = fc.POINT_QUANTITIES if source == "points" else fc.LINK_QUANTITIES
    if quantity is None and not (function == "error" and source == "points"):
        raise MeasureError(f"{text!r}: name the quantity, e.g. {source}.{name}.{allowed[0]}")
    if quantity is not None and quantity not in allowed:
        raise MeasureError(f"{text!r}: {source} have the quantities {' '.join(allowed)}")
    return Measure(text.strip(), function, source, name, quantity)


def load(directory: Path) -> fc.Run | None:
    """A case's results, None when there are none to read."""
    try:
        return fc.load_run(directory)
    except (fc.UsageError, OSError, ValueError):
        return None


def case_row(case: Case, directory: Path, record: dict | None, lost: str | None,
             measures: list[Measure], reference_dir: Path | None) -> dict:
    """The summary row of one case."""
    row = {"case": case.name, "deck": str(case.deck)}
    row.update({name: format_value(value) for name, value in case.parameters})
    row.update({name: format_value(value) for name, value in case.options})
    if record is None:
        row.update(exit="lost" if lost else "not run", message=lost or "")
        return row
    row.update(exit=str(record["exit"]), message=record["message"])
    stats = record.get("statistics", {})
    for key, form in (("steps", "{:d}"), ("iterations_per_step", "{:.3f}"), ("cuts", "{:d}"),
                      ("analysis_us_per_configuration", "{:.2f}")):
        if key in stats:
            row[key] = form.format(stats[key])
    if measures:
        values = measure_values(directory, record, measures, reference_dir)
        for measure in measures:
            value = values.get(stored_key(measure, reference_dir))
            row[measure.text] = "" if value is None or not math.isfinite(value) else repr(value)
    row["seconds"] = f"{record['seconds']:.3f}"
    return row


def stored_key(measure: Measure, reference_dir: Path | None) -> str:
    """The name of a measure's value in case.json: its text, and for error() the reference run."""
    if measure.function == "error":
        return f"{measure.text} against {reference_dir.name if reference_dir is not None else '-'}"
    return measure.text


def measure_values(directory: Path, record: dict, measures: list[Measure], reference_dir: Path | None
                   ) -> dict[str, float | None]:
    """The case's measures as case.json holds them (the worker computed them with the case);
    those it lacks (a measure added on a rerun; error(), which needs the reference run) are
    computed here once and stored beside it in measures.json (case.json stays the worker's
    record), so that the next rerun reads them back."""
    later = directory / "measures.json"
    try:
        added = json.loads(later.read_text()) if later.is_file() else {}
    except (OSError, json.JSONDecodeError):
        added = {}
    stored = dict(record.get("measures", {}), **added)
    missing = [m for m in measures if stored_key(m, reference_dir) not in stored]
    if not missing:
        return stored
    streamed = [m.spec() for m in missing if m.function != "error"]
    if streamed:
        added.update(task.measures(directory, streamed))
    errors = [m for m in missing if m.function == "error"]
    if errors:
        run = load(directory)
        reference = load(reference_dir) if reference_dir is not None else None
        for measure in errors:
            value = measure.value(run, reference) if run is not None and reference is not None else None
            added[stored_key(measure, reference_dir)] = value if value is None or math.isfinite(value) else None
    if (directory / "case.json").is_file():
        temporary = directory / "measures.json.tmp"
        temporary.write_text(json.dumps(added, indent=1))
        os.replace(temporary, later)
    return dict(stored, **added)


def columns_of(rows: list[dict], measures: list[Measure]) -> list[str]:
    fixed = ["exit", "message", "steps", "iterations_per_step", "cuts", "analysis_us_per_configuration"]
    first = ["case", "deck"]
    swept = [k for row in rows for k in row if k not in first + fixed + ["seconds"]
             and k not in [m.text for m in measures]]
    return first + list(dict.fromkeys(swept)) + fixed + [m.text for m in measures] + ["seconds"]


def write_csv(path: Path, rows: list[dict], columns: list[str]) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({c: row.get(c, "") for c in columns})


def markdown(rows: list[dict], columns: list[str], measures: list[Measure] = ()) -> str:
    """The rows as a Markdown table (the deck column only when there are several
    decks; measures to 10 digits, summary.csv has them in full)."""
    if len({row["deck"] for row in rows}) <= 1:
        columns = [c for c in columns if c != "deck"]
    short = {m.text for m in measures}

    def cell(column: str, text: str) -> str:
        if column in short and is_float(text):
            text = f"{float(text):.10g}"
        return text.replace("|", "\\|")
    lines = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    for row in rows:
        lines.append("| " + " | ".join(cell(c, row.get(c, "")) for c in columns) + " |")
    return "\n".join(lines)


def swept_keys(cases: list[Case]) -> list[str]:
    """Parameters and options that take more than one value over the cases."""
    values: dict[str, set] = {}
    for case in cases:
        for name, value in list(case.parameters) + list(case.options):
            values.setdefault(name, set()).add(format_value(value))
    keys = [name for name, seen in values.items() if len(seen) > 1]
    if len({case.deck for case in cases}) > 1:
        keys.insert(0, "deck")
    return keys


def short_label(case: Case, keys: list[str]) -> str:
    items = dict((n, format_value(v)) for n, v in list(case.parameters) + list(case.options))
    items["deck"] = case.deck.stem
    return " ".join(f"{k}={items[k]}" for k in keys if k in items) or case.name


def plot_paths(cases: list[Case], directories: dict[str, Path], point: str | None, quantity: str,
               output: Path) -> Path | None:
    """Overlay of a point's path and a quantity's history over the finished
    cases written at the first case's times, by compare.py's plot_comparison."""
    keys = swept_keys(cases)
    sources = []
    for case in cases:
        directory = directories[case.name]
        if not (directory / "points.csv").is_file():
            continue
        try:
            sources.append(compare.load_source(directory, short_label(case, keys)))
        except (fc.UsageError, ValueError):
            continue
    if not sources:
        return None
    point = point or next(iter(sources[0].points))
    sources = [s for s in sources if point in s.points and s.points[point].has(quantity)
               and s.points[point].has("x")]
    if not sources:
        return None
    # Every finished case is drawn; compare.py's difference panel takes those on the first
    # case's times and names the others.
    mech = fs.read_mechanism(sources[0].path)
    note = (f"{len(sources)} of {len(cases)} finished cases shown: "
            + ", ".join(source.label for source in sources))
    plt = fc.pyplot()
    fig = compare.plot_comparison(sources, point, quantity, mech.title or None, mech, note)
    path = output / f"paths-{point}-{quantity}.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_measures(cases: list[Case], rows: dict[str, dict], measures: list[Measure], parameter: str | None,
                  output: Path, directories: dict[str, Path] | None = None) -> list[Path]:
    """Each measure against a swept parameter, one line per combination of the
    other swept values; labelled with the deck's units and title (from a finished case's
    mechanism.txt, when ``directories`` are given) and how many cases it shows."""
    keys = swept_keys(cases)
    numeric = [k for k in keys if k != "deck" and all(is_float(rows[c.name].get(k, "")) for c in cases)]
    parameter = parameter or (numeric[0] if numeric else None)
    if parameter is None or not measures:
        return []
    others = [k for k in keys if k != parameter]
    finished = [c for c in cases if (c.name in rows and str(rows[c.name].get("exit", "")) == "0")]
    mech = next((fs.read_mechanism(directories[c.name]) for c in finished
                 if directories and c.name in directories and directories[c.name].is_dir()), None)
    plt = fc.pyplot()
    paths = []
    for index, measure in enumerate(measures):
        groups: dict[str, list[tuple[float, float]]] = {}
        for case in cases:
            row = rows[case.name]
            if not is_float(row.get(measure.text, "")) or not is_float(row.get(parameter, "")):
                continue
            label = " ".join(f"{k}={row.get(k, '')}" if k != "deck" else case.deck.stem for k in others)
            groups.setdefault(label, []).append((float(row[parameter]), float(row[measure.text])))
        if not groups:
            continue
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for number, (label, points) in enumerate(sorted(groups.items())):
            points.sort()
            style = dict(compare.STYLES[number % len(compare.STYLES)], color=f"C{number % 10}")
            ax.plot([p[0] for p in points], [p[1] for p in points], label=label or None, **style)
        ax.set_xlabel(parameter_label(parameter, mech))
        ax.set_ylabel(f"{measure.text} ({measure_unit(measure, mech)})")
        count = sum(len(points) for points in groups.values())
        ax.set_title(f"{measure.text} against {parameter}: {count} of {len(cases)} cases"
                     + (f", a line per {', '.join(others)}" if others else ""), fontsize="small")
        if mech is not None and mech.title:
            fig.suptitle(mech.title)
        ax.grid(True, alpha=0.3)
        if any(groups):
            ax.legend(fontsize="small")
        fig.tight_layout()
        path = output / f"measure-{index + 1}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def measure_unit(measure: Measure, mech) -> str:
    """The unit of a measure's values, from the deck's units (mechanism.txt)."""
    if measure.source == "steps":
        return {"iterations": "count", "cuts": "count", "residual": "force"}.get(measure.name, "-")
    if mech is None:
        mech = fs.Mechanism()
    if measure.quantity is None:
        return mech.unit("x")
    return mech.unit(measure.quantity)


def parameter_label(parameter: str, mech) -> str:
    """A swept parameter's axis label: the step and the end time in time units, a deck
    parameter in the deck's own units."""
    if parameter in ("dt", "t_end", "t-end") and mech is not None:
        return f"{parameter} ({mech.unit('t')})"
    return f"{parameter} (deck parameter, in the deck's units)"


def is_float(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except (TypeError, ValueError):
        return False


def read_record(directory: Path) -> dict | None:
    path = directory / "case.json"
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None
