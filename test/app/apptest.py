"""Small shared pieces of the app-level tests (run by pytest, see conftest.py):
the fekap executable, running it, reading its CSV output, and `check`, an
assertion with a reason."""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


class Failure(AssertionError):
    """A failed check, with its reason (an AssertionError: pytest reports it as a failure)."""


def check(condition: bool, reason: str) -> None:
    """Fail the current test with ``reason`` unless ``condition`` holds."""
    if not condition:
        raise Failure(reason)


def fekap_binary() -> str:
    """The fekap executable: $FEKAP_BIN (set by scripts/test), else the one fpm builds."""
    binary = os.environ.get("FEKAP_BIN")
    if binary and Path(binary).is_file():
        return binary
    out = subprocess.run(["fpm", "run", "--runner", "echo"], cwd=ROOT, capture_output=True, text=True)
    return str(ROOT / out.stdout.strip().splitlines()[-1])


def run_fekap(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run fekap from the repository root with ``args``."""
    return subprocess.run([fekap_binary(), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout)


def read_rows(path: Path) -> list[dict[str, str]]:
    """The rows of a CSV file as dictionaries."""
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def point_series(outdir: Path, point: str) -> dict[str, list[float]]:
    """Columns of points.csv for one point, as floats (empty fields are NaN)."""
    rows = [row for row in read_rows(outdir / "points.csv") if row["point"] == point]
    check(bool(rows), f"no rows for point {point} in {outdir / 'points.csv'}")
    return {key: [float(row[key]) if row[key] else float("nan") for row in rows]
            for key in rows[0] if key != "point"}
