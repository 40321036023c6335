"""The work of one case on a Dask worker: run fekap into a private directory,
record its exit code and message in case.json, and move the directory into
place, so that a case directory with case.json is always a finished case.

Standard library only: the module is sent to the workers by value (cloudpickle),
so a worker needs nothing but Python and Dask, and the shared file system."""

from __future__ import annotations

import csv
import json
import os
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
              "command": command[:3] + ["DIR"] + command[4:], "statistics": statistics(work)}
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
