"""The package python/fekap on its own: one reader of every output file (fekap.read.rows and
columns agree with each other and with the CSV text on real runs, Fortran's number
spellings included), and one rule for the executable (fekap.run.fekap_binary).

Run alone:  scripts/test package
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from fekap import read, run

from apptest import ROOT, run_fekap

#: Decks whose runs write every CSV file: kinematics with kinetostatics' reactions, and a
#: dynamics run's energy (at a tenth of its steps).
RUNS = (("decks/fourbar-kinetostatics.deck", ()), ("decks/dynamics/pendulum.deck", ("--dt", "0.01")))


@pytest.fixture(scope="module")
def outputs(tmp_path_factory) -> list[Path]:
    made = []
    for deck, options in RUNS:
        out = tmp_path_factory.mktemp(Path(deck).stem)
        done = run_fekap("-q", "-o", str(out), *options, deck)
        assert done.returncode == 0, done.stderr
        made.append(out)
    return made


def test_rows_and_columns_read_every_csv_file_alike(outputs: list[Path]) -> None:
    """For every CSV file of the runs: rows (text), rows (numbers) and columns hold the same
    fields, numbers parsed alike (an empty field is None in rows and NaN in columns)."""
    names = set()
    for out in outputs:
        for path in sorted(out.glob("*.csv")):
            names.add(path.name)
            text = read.rows(path)
            numbers = read.rows(path, numbers=True)
            table = read.columns(path)
            assert text, f"{path}: no rows"
            assert len(numbers) == len(text) and all(len(a) == len(text) for a in table.values()), path
            assert list(table) == list(text[0]), path
            for i, (raw, row) in enumerate(zip(text, numbers)):
                for name, field in raw.items():
                    value, column = row[name], table[name][i]
                    if name in read.TEXT_COLUMNS:
                        assert value == field == column, (path, i, name)
                    elif field == "":
                        assert value is None and math.isnan(column), (path, i, name)
                    else:
                        assert value == float(field) == column, (path, i, name, field, value, column)
                        if name in read.INTEGER_COLUMNS:
                            assert isinstance(value, int), (path, name, value)
    want = {"points.csv", "links.csv", "steps.csv", "nodes.csv", "mesh.csv", "reactions.csv", "energy.csv"}
    assert want <= names, f"files not read: {sorted(want - names)}"


def test_a_selection_keeps_the_rows_of_one_name(outputs: list[Path]) -> None:
    points = outputs[0] / "points.csv"
    every = read.rows(points, numbers=True)
    c_rows = read.rows(points, numbers=True, point="C")
    c = read.columns(points, point="C")
    assert c_rows and len(c_rows) < len(every) and all(row["point"] == "C" for row in c_rows)
    assert c_rows == [row for row in every if row["point"] == "C"]
    np.testing.assert_array_equal(c["x"], [row["x"] for row in c_rows])
    np.testing.assert_array_equal(c["step"], [row["step"] for row in c_rows])
    reactions = read.columns(outputs[0] / "reactions.csv", kind="drive")
    assert reactions["t"].size > 0 and set(reactions["kind"]) == {"drive"}
    with pytest.raises(read.UsageError, match="no column point"):
        read.columns(outputs[0] / "steps.csv", point="C")


def test_fortran_spellings_and_empty_fields(tmp_path: Path) -> None:
    """1.0D+00 and a three-digit exponent without its E (2.5-100) are numbers; an empty
    field (a rate left out at a singular configuration) is None, or NaN in an array."""
    path = tmp_path / "points.csv"
    path.write_text("step,t,point,x,y,vx,vy\n0,0.0,A,1.0D+00,2.5-100,,\n1,1.0E-01,A,-3.5d-1,4,5,6\n")
    rows = read.rows(path, numbers=True)
    assert rows[0] == {"step": 0, "t": 0.0, "point": "A", "x": 1.0, "y": 2.5e-100, "vx": None, "vy": None}
    assert rows[1]["x"] == -0.35 and rows[1]["t"] == 0.1
    table = read.columns(path, point="A")
    assert table["step"].dtype.kind == "i" and math.isnan(table["vx"][0]) and table["vy"][1] == 6.0


def test_one_rule_finds_the_executable(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An explicit path first, then $FEKAP_BIN, then the release build; a path given that
    does not exist is an error naming it, never a quiet fall back on another executable."""
    first, second = tmp_path / "first", tmp_path / "second"
    for path in (first, second):
        path.write_text("#!/bin/sh\n")
        path.chmod(0o755)
    monkeypatch.setenv("FEKAP_BIN", str(second))
    assert run.fekap_binary(str(first)) == str(first)
    assert run.fekap_binary() == str(second)
    with pytest.raises(SystemExit, match="no-such-fekap"):
        run.fekap_binary(str(tmp_path / "no-such-fekap"))
    monkeypatch.setenv("FEKAP_BIN", str(tmp_path / "no-such-fekap"))
    with pytest.raises(SystemExit, match=r"no-such-fekap \(FEKAP_BIN\)"):
        run.fekap_binary()
    monkeypatch.delenv("FEKAP_BIN")
    if run.RELEASE_BIN.is_file():
        assert run.fekap_binary() == str(run.RELEASE_BIN)
    else:
        with pytest.raises(SystemExit, match="scripts/build"):
            run.fekap_binary()


def test_the_package_is_the_checkout_s(monkeypatch: pytest.MonkeyPatch) -> None:
    """The tests import the package of this checkout (scripts/setup installs it in editable
    mode), so that an edit of python/fekap is what they test."""
    import fekap

    assert Path(fekap.__file__).resolve() == ROOT / "python" / "fekap" / "__init__.py"
    assert os.access(ROOT / "scripts" / "plot.py", os.X_OK)
