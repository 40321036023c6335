"""Timing of FEKAP's runs for the studies that compare it with other codes
(studies/exudyn/exudyn_*.py): the CPU time of a child process, its
instructions under callgrind, and the SUMMARY numbers of its listing. One
copy for every study, so that the codes are timed alike."""

from __future__ import annotations

import re
import resource
import subprocess
from pathlib import Path


def children_cpu() -> float:
    """User + system CPU seconds of the finished child processes so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def callgrind_count(stderr: str) -> int:
    """The instructions valgrind --tool=callgrind reports in a run's stderr."""
    found = re.search(r"Collected\s*:\s*(\d+)", stderr)
    if not found:
        raise SystemExit(f"callgrind gave no count: {stderr[-400:]}")
    return int(found.group(1))


def run_timed(command: list[str], callgrind_out: Path | None = None) -> tuple[subprocess.CompletedProcess, float,
                                                                              int | None]:
    """Run `command` (with `callgrind_out`: under valgrind --tool=callgrind,
    writing that file): the finished process, its CPU seconds and, under
    callgrind, its instructions. A failed run stops the study with its stderr."""
    if callgrind_out is not None:
        command = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={callgrind_out}", *command]
    cpu = children_cpu()
    run = subprocess.run(command, capture_output=True, text=True)
    cpu = children_cpu() - cpu
    if run.returncode != 0:
        raise SystemExit(f"{Path(command[0]).name} failed ({run.returncode}): {run.stderr}")
    return run, cpu, callgrind_count(run.stderr) if callgrind_out is not None else None


def listing_summary(listing: str) -> dict[str, float]:
    """The numbers of a FEKAP listing's SUMMARY block, by their labels."""
    summary = {}
    for line in listing.split("SUMMARY", 1)[-1].splitlines():
        label, _, value = line.strip().rpartition(" ")
        try:
            summary[label.strip()] = float(value)
        except ValueError:
            pass
    return summary
