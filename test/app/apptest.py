"""Small shared pieces of the app-level tests: the fekap executable, running
it, reading its CSV output, and a plain test runner that ends with
"<suite>: N passed, M failed"."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


class Failure(Exception):
    """A failed check, with its reason."""


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


def run_suite(name: str, tests: list) -> int:
    """Run test functions, print PASS/FAIL lines and the closing count; return the exit code."""
    passed = failed = 0
    start = time.time()
    for test in tests:
        try:
            test()
        except Failure as failure:
            failed += 1
            print(f"  FAIL {name}/{test.__name__}")
            for line in str(failure).splitlines():
                print(f"      {line}")
        except Exception as exc:  # a crash of the test itself counts as a failure
            failed += 1
            print(f"  FAIL {name}/{test.__name__}: {type(exc).__name__}: {exc}")
        else:
            passed += 1
            print(f"  PASS {name}/{test.__name__}")
    print(f"  ({time.time() - start:.1f} s)")
    print(f"{name}: {passed} passed, {failed} failed")
    sys.stdout.flush()
    return 1 if failed else 0
