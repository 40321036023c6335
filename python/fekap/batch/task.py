"""The work of one case on a Dask worker: run fekap into a private directory,
record its exit code and message in case.json with the run's statistics and
the sweep's measures (computed here, on the worker, reading each CSV file once
as a stream), and move the directory into place, so that a case directory with
case.json is always a finished case.

Standard library only: the module is sent to the workers by value (cloudpickle),
so a worker needs nothing but Python and Dask, and the shared file system."""

from __future__ import annotations

import csv
import json
import math
import os
import re
import shutil
import socket
import subprocess
import time
import uuid
from pathlib import Path

#: Exit codes of fekap that are answers (recorded, not retried): success,
#: input error, no convergence, anything else fekap itself reports.
ANSWERS = (0, 1, 2, 3)


class CaseTimeout(Exception):
    """The run exceeded the sweep's timeout (retried, then recorded as lost)."""


def _die_with_parent() -> None:
    """In the child: be killed when the worker dies (Linux prctl PR_SET_PDEATHSIG)."""
    try:
        import ctypes
        import signal
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)
    except OSError:
        pass


#: Linux's setpriv sets the parent-death signal of the run without a Python
#: preexec_fn (which forces a plain fork of the worker: +20 ms a case).
SETPRIV = shutil.which("setpriv")


def statistics(directory: Path) -> dict:
    """The summary's figures of a run: steps, mean Newton iterations of the
    steps after the start, step cuts (steps.csv), and the analysis time per
    configuration (the listing's summary). Computed here, on the worker."""
    stats: dict = {}
    try:
        with open(directory / "steps.csv", newline="") as handle:
            rows = list(csv.DictReader(handle))
    except OSError:
        rows = []
    if rows:
        steps = [int(row["step"]) for row in rows]
        later = [int(row["iterations"]) for row in rows if int(row["step"]) > 0]
        stats["steps"] = max(steps)
        if later:
            stats["iterations_per_step"] = sum(later) / len(later)
        if "cuts" in rows[0]:
            stats["cuts"] = sum(int(row["cuts"]) for row in rows)
    configurations = seconds = None
    for path in directory.glob("*.lis"):
        with open(path, errors="replace") as handle:
            for line in handle:
                if "configurations solved" in line:
                    configurations = float(line.split()[-1])
                elif "time in analysis (s)" in line:
                    seconds = float(line.split()[-1])
    if configurations and seconds is not None:
        stats["analysis_us_per_configuration"] = 1e6 * seconds / configurations
    return stats


#: A Fortran exponent without its letter, as gfortran writes 1.0E-100: 1.0-100.
_FORTRAN_EXPONENT = re.compile(r"^([+-]?[0-9.]+)([+-][0-9]+)$")


def _number(text: str) -> float | None:
    """A CSV field as a finite number; None for an empty field (not computed at that step)
    or one that is no number."""
    text = text.strip().replace("D", "E").replace("d", "e")
    try:
        value = float(text)
    except ValueError:
        match = _FORTRAN_EXPONENT.match(text)
        if match is None:
            return None
        value = float(f"{match.group(1)}e{match.group(2)}")
    return value if math.isfinite(value) else None


class _Reduction:
    """What the measure functions need of a stream of values, kept as it goes."""

    def __init__(self) -> None:
        self.count = 0
        self.total = 0.0
        self.low = self.high = self.first = self.last = math.nan

    def add(self, value: float) -> None:
        if self.count == 0:
            self.low = self.high = self.first = value
        self.low = min(self.low, value)
        self.high = max(self.high, value)
        self.last = value
        self.total += value
        self.count += 1

    def result(self, function: str) -> float | None:
        if self.count == 0:
            return None
        return {"max": self.high, "min": self.low, "range": self.high - self.low,
                "mean": self.total / self.count, "first": self.first, "final": self.last,
                "absmax": max(abs(self.low), abs(self.high))}[function]


def measures(directory: Path, specs: list[list]) -> dict[str, float | None]:
    """The measures of a run: ``specs`` are [text, function, source, name, quantity] as
    batch.results parses them (every function but error(), which needs the reference run);
    each source file (points.csv, links.csv, steps.csv) is read once, row by row, whatever
    its size. A measure of a file, column or name the run lacks is None."""
    values: dict[str, float | None] = {}
    by_source: dict[str, list[list]] = {}
    for spec in specs:
        by_source.setdefault(spec[2], []).append(spec)
    for source, group in by_source.items():
        reductions = {spec[0]: _Reduction() for spec in group}
        try:
            with open(directory / f"{source}.csv", newline="", encoding="utf-8", errors="replace") as handle:
                reader = csv.reader(handle)
                header = [field.strip() for field in next(reader, [])]
                key = {"points": "point", "links": "link"}.get(source)
                key_column = header.index(key) if key in header else None
                wanted = []
                for text, _, _, name, quantity in group:
                    column = name if source == "steps" else quantity
                    if column in header and (source == "steps" or key_column is not None):
                        wanted.append((reductions[text], header.index(column), None if source == "steps" else name))
                for row in reader:
                    for reduction, column, only in wanted:
                        if column >= len(row) or (only is not None and (key_column >= len(row)
                                                                        or row[key_column].strip() != only)):
                            continue
                        value = _number(row[column])
                        if value is not None:
                            reduction.add(value)
        except OSError:
            pass
        for text, function, *_ in group:
            values[text] = reductions[text].result(function)
    return values


def worker_name() -> str:
    """The Dask worker running this task ('' outside one)."""
    try:
        from distributed import get_worker
        return str(get_worker().name)
    except (ImportError, ValueError):
        return ""


def run_case(task: dict) -> dict:
    """Run one case; return its record. Raises CaseTimeout or RuntimeError for a
    run that gave no answer (the caller retries those)."""
    final = Path(task["directory"])
    done = final / "case.json"
    if done.is_file():
        return json.loads(done.read_text())
    work = final.parent / f".{final.name}.part-{uuid.uuid4().hex[:8]}"
    work.mkdir(parents=True)
    command = [task["fekap"], "-q", "-o", str(work), *task["arguments"]]
    wrapper = [SETPRIV, "--pdeathsig", "KILL"] if SETPRIV else []
    start = time.perf_counter()
    try:
        # A session of its own: a Ctrl-C at the terminal stops the sweep, not the runs.
        proc = subprocess.run(wrapper + command, cwd=task["cwd"], capture_output=True, text=True,
                              timeout=task["timeout"], start_new_session=True,
                              preexec_fn=None if SETPRIV else _die_with_parent)
    except subprocess.TimeoutExpired:
        shutil.rmtree(work, ignore_errors=True)
        raise CaseTimeout(f"exceeded the timeout of {task['timeout']:g} s") from None
    seconds = time.perf_counter() - start
    if proc.returncode not in ANSWERS:
        shutil.rmtree(work, ignore_errors=True)
        raise RuntimeError(f"fekap ended with status {proc.returncode} (killed?)")
    (work / "stderr.txt").write_text(proc.stderr)
    lines = [line.strip() for line in proc.stderr.splitlines() if line.strip()]
    message = next((line for line in lines if ": error:" in line), lines[0] if lines else "")
    record = {"case": final.name, "exit": proc.returncode, "message": message[:300],
              "seconds": round(seconds, 4), "attempt": task["attempt"], "host": socket.gethostname(),
              "worker": worker_name(),
              "command": command[:3] + ["DIR"] + command[4:], "statistics": statistics(work),
              "measures": measures(work, task.get("measures", []))}
    (work / "case.json.tmp").write_text(json.dumps(record, indent=1))
    os.replace(work / "case.json.tmp", work / "case.json")
    if final.exists():  # a stale, unfinished directory of an earlier attempt
        shutil.rmtree(final, ignore_errors=True)
    try:
        os.rename(work, final)
    except OSError:
        if not done.is_file():  # not another attempt that finished first
            raise
        shutil.rmtree(work, ignore_errors=True)
    return record


def run_cases(tasks: list[dict]) -> list[dict]:
    """Run several cases one after the other (one Dask task); their records."""
    return [run_case(task) for task in tasks]
