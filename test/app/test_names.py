"""The names of methods and predictors: one table (fekap_model's method_names
and predictor_names) read by the deck and the command line alike, each name
taken in full or shortened to 4 letters (FEAP's rule), in any case.

Run alone:  scripts/test names
"""

from __future__ import annotations

from pathlib import Path

import pytest

from apptest import ROOT, read_rows, run_fekap

DECK = ROOT / "decks" / "fourbar.deck"
# (option, value as given, full name)
NAMES = [("--method", "cart", "cartesian"), ("--method", "ANGL", "angles"), ("--method", "fem", "fem"),
         ("--predictor", "extr", "extrapolate"), ("--predictor", "Prev", "previous"),
         ("--predictor", "tayl", "taylor")]
BAD = [("--method", "car"), ("--method", "cartesianx"), ("--predictor", "ex"), ("--predictor", "taylors")]


def run(outdir: Path, *args: str):
    return run_fekap("-q", "-o", str(outdir), *args, str(DECK))


@pytest.mark.parametrize("option,short,full", NAMES)
def test_command_line_takes_abbreviations(tmp_path, option, short, full):
    """Each 4-letter abbreviation gives the very rows of the full name."""
    a = run(tmp_path / "short", option, short)
    b = run(tmp_path / "full", option, full)
    assert a.returncode == 0, f"{option} {short}: exit {a.returncode}: {a.stderr}"
    assert b.returncode == 0, f"{option} {full}: exit {b.returncode}: {b.stderr}"
    assert read_rows(tmp_path / "short" / "points.csv") == read_rows(tmp_path / "full" / "points.csv")


@pytest.mark.parametrize("option,value", BAD)
def test_command_line_refuses_other_names(tmp_path, option, value):
    """A prefix shorter than 4 letters, or a longer word, is refused with exit 2."""
    r = run(tmp_path / "out", option, value)
    assert r.returncode == 2, f"{option} {value}: exit {r.returncode}"
    assert f"{option} {value}: expected" in r.stderr


@pytest.mark.parametrize("option,short,full", NAMES)
def test_deck_takes_the_same_abbreviations(tmp_path, option, short, full):
    """The deck's ANALysis block takes the same names as the command line."""
    key = option.lstrip("-")
    lines = [line for line in DECK.read_text().splitlines() if not line.strip().lower().startswith(key[:4])]
    at = next(i for i, line in enumerate(lines) if line.strip().upper().startswith("ANAL"))
    lines.insert(at + 1, f"  {key} {short}")
    deck = tmp_path / f"{key}-{short}.deck"
    deck.write_text("\n".join(lines) + "\n")
    a = run_fekap("-q", "-o", str(tmp_path / "deck"), str(deck))
    b = run(tmp_path / "cli", option, full)
    assert a.returncode == 0, f"deck with '{key} {short}': exit {a.returncode}: {a.stderr}"
    assert b.returncode == 0, f"{option} {full}: exit {b.returncode}: {b.stderr}"
    assert read_rows(tmp_path / "deck" / "points.csv") == read_rows(tmp_path / "cli" / "points.csv")
