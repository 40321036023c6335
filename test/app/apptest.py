"""Small shared pieces of the app-level tests (run by pytest, see conftest.py): the
fekap executable and running it (the package's fekap.run), reading its CSV output (the
package's fekap.read), `check`, an assertion with a reason, and a study script as a module."""

from __future__ import annotations

import importlib.util
from pathlib import Path

from fekap.read import columns
from fekap.read import rows as read_rows
from fekap.run import fekap_binary, run_fekap

ROOT = Path(__file__).resolve().parents[2]


class Failure(AssertionError):
    """A failed check, with its reason (an AssertionError: pytest reports it as a failure)."""


def check(condition: bool, reason: str) -> None:
    """Fail the current test with ``reason`` unless ``condition`` holds."""
    if not condition:
        raise Failure(reason)


def point_series(outdir: Path, point: str) -> dict[str, list[float]]:
    """Columns of points.csv for one point, as floats (empty fields are NaN)."""
    table = columns(outdir / "points.csv", point=point)
    check(table["t"].size > 0, f"no rows for point {point} in {outdir / 'points.csv'}")
    return {key: values.tolist() for key, values in table.items() if key != "point"}


def study_module(path: str):
    """A script of studies/ (``path`` below studies/) imported as a module, for the tests of
    its functions: the studies are scripts, not a package."""
    file = ROOT / "studies" / path
    spec = importlib.util.spec_from_file_location(file.stem, file)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


__all__ = ["ROOT", "Failure", "check", "fekap_binary", "point_series", "read_rows", "run_fekap", "study_module"]
