#!/usr/bin/env python3
"""OUTPut `files points`: of the CSV files points.csv alone (the tracked points, what a
benchmark against another code stores, studies/exudyn/exudyn_slider_crank_rigid.py). Its
points.csv is the full run's, byte for byte, in kinematics, dynamics and a spatial run; no
other CSV file is written; the listing only with `listing`; an unknown kind names the
allowed ones.

Run alone:  scripts/test files_points
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from apptest import ROOT, fekap_binary

#: (deck, --set options): a kinematics deck, the standard slider-crank's dynamics (short),
#: a spatial deck.
CASES = {
    "fourbar": (ROOT / "decks/fourbar.deck", []),
    "rigid-crank": (ROOT / "decks/dynamics/slider-crank-rigid-crank.deck",
                    ["--set", "n=2", "--set", "dt=2e-4", "--set", "t_end=4e-3"]),
    "spatial": (ROOT / "decks/spatial/rssr.deck", []),
}


def with_files(deck: Path, files: str, tmp_path: Path) -> Path:
    """The deck with a `files` line added to its OUTPut block (the deck's own files line,
    if any, is replaced)."""
    text = re.sub(r"(?im)^\s*files\b.*\n", "", deck.read_text())
    text, count = re.subn(r"(?im)^OUTPut.*$", lambda m: m.group(0) + f"\n  files {files}", text, count=1)
    assert count == 1, f"{deck}: no OUTPut block"
    path = tmp_path / deck.name
    path.write_text(text)
    return path


def run(deck: Path, out: Path, options: list[str]) -> subprocess.CompletedProcess:
    done = subprocess.run([fekap_binary(), "-q", "-o", str(out), *options, str(deck)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done


def written(out: Path) -> set[str]:
    return {p.name for p in out.iterdir() if not p.name.startswith(".")}


@pytest.mark.parametrize("case", sorted(CASES))
def test_points_alone_is_the_full_runs_points_csv(case, tmp_path):
    deck, options = CASES[case]
    run(deck, tmp_path / "full", options)
    alone = with_files(deck, "points", tmp_path)
    run(alone, tmp_path / "points", options)
    assert written(tmp_path / "points") == {"points.csv"}
    assert (tmp_path / "points" / "points.csv").read_bytes() == (tmp_path / "full" / "points.csv").read_bytes()
    # With the listing: points.csv and the listing, whose steps are the full run's.
    listed = with_files(deck, "points listing", tmp_path)
    run(listed, tmp_path / "listed", options)
    assert written(tmp_path / "listed") == {"points.csv", f"{deck.stem}.lis"}
    assert (tmp_path / "listed" / "points.csv").read_bytes() == (tmp_path / "full" / "points.csv").read_bytes()
    full_steps = (tmp_path / "full" / f"{deck.stem}.lis").read_text().split("STEPS", 1)[1].split("SUMMARY", 1)[0]
    steps = (tmp_path / "listed" / f"{deck.stem}.lis").read_text().split("STEPS", 1)[1].split("SUMMARY", 1)[0]
    assert steps == full_steps


def test_unknown_kind_names_the_allowed_ones(tmp_path):
    deck = with_files(ROOT / "decks/fourbar.deck", "points tables", tmp_path)
    done = subprocess.run([fekap_binary(), "-q", "-o", str(tmp_path / "out"), str(deck)], capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    assert "unknown output file kind 'tables'" in done.stderr
    assert "allowed: csv points listing vtk" in done.stderr
    assert re.search(r"fourbar\.deck:\d+:\d+:", done.stderr), done.stderr
