"""Kinetostatics through the fekap executable: the deck chooses the effects,
reactions.csv is written only by kinetostatics and statics runs (rows per step: the
drives, the supports, both ends of every link), the listing's plan says which
effects run and why, and a type that cannot run is an input error (exit 2)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from apptest import ROOT, read_rows, run_fekap  # noqa: E402

DECK = "decks/fourbar-kinetostatics.deck"


def plan(outdir: Path) -> str:
    """The PLAN section of the run's listing."""
    text = next(outdir.glob("*.lis")).read_text()
    return text[text.index("PLAN"):text.index("STEPS")]


def variant(tmp_path: Path, old: str, new: str) -> Path:
    """A copy of the kinetostatics deck with one piece of text replaced."""
    text = (ROOT / DECK).read_text()
    assert old in text
    path = tmp_path / "variant.deck"
    path.write_text(text.replace(old, new))
    return path


def test_reactions_written_per_step(tmp_path):
    out = tmp_path / "ks"
    run = run_fekap("-q", "-o", str(out), DECK)
    assert run.returncode == 0, run.stderr
    rows = read_rows(out / "reactions.csv")
    # 101 steps; 1 drive, 2 supports, 3 links with two ends each.
    assert len(rows) == 101 * 9
    first = rows[:9]
    assert [(r["kind"], r["link"], r["node"]) for r in first] == [
        ("drive", "AB", "A"), ("support", "", "A"), ("support", "", "D"), ("joint", "AB", "A"),
        ("joint", "AB", "B"), ("joint", "BC", "B"), ("joint", "BC", "C"), ("joint", "DC", "D"),
        ("joint", "DC", "C")]
    for r in rows:
        assert all(math.isfinite(float(r[k])) for k in ("fx", "fy", "m"))
    # The drive torque is the crank's end moment at A.
    for k in range(0, len(rows), 9):
        assert float(rows[k]["m"]) == pytest.approx(float(rows[k + 3]["m"]), rel=1e-12, abs=1e-9)
    assert "effects: kinetostatics" in plan(out)


def test_kinematics_decks_write_no_reactions(tmp_path):
    out = tmp_path / "fourbar"
    run = run_fekap("-q", "-o", str(out), "decks/fourbar.deck")
    assert run.returncode == 0, run.stderr
    assert not (out / "reactions.csv").exists()
    assert "effects: kinematics (auto: no masses, no loads)" in plan(out)


@pytest.mark.parametrize("option, why", [
    (("--method", "cartesian"), "method fem"),
    (("--compute", "positions,velocities"), "accelerations"),
])
def test_auto_falls_back_to_kinematics_and_says_why(tmp_path, option, why):
    deck = variant(tmp_path, "  type kinetostatics", "  type auto")
    out = tmp_path / "auto"
    run = run_fekap("-q", "-o", str(out), *option, str(deck))
    assert run.returncode == 0, run.stderr
    assert not (out / "reactions.csv").exists()
    text = plan(out)
    assert "effects: kinematics (auto: masses are given, but" in text and why in text
    assert "masses and gravity are left out" in text


def test_explicit_kinetostatics_overridden_to_cartesian_is_an_input_error(tmp_path):
    run = run_fekap("-q", "-o", str(tmp_path / "x"), "--method", "cartesian", DECK)
    assert run.returncode == 2
    assert "kinetostatics runs with method fem only" in run.stderr


def test_gravity_without_masses_is_noted(tmp_path):
    deck = variant(tmp_path, "rho=100", "")
    deck.write_text(deck.read_text().replace("  type kinetostatics", "  type auto"))
    out = tmp_path / "g"
    run = run_fekap("-q", "-o", str(out), str(deck))
    assert run.returncode == 0, run.stderr
    assert "GRAVity does nothing without masses" in plan(out)
    assert not (out / "reactions.csv").exists()


def test_statics_needs_loads(tmp_path):
    deck = variant(tmp_path, "  type kinetostatics", "  type statics")
    deck.write_text(deck.read_text().replace("GRAVity  0  -9.81", ""))
    run = run_fekap("-q", "-o", str(tmp_path / "s"), str(deck))
    assert run.returncode == 2
    assert "variant.deck:26:8: error: statics cannot run: statics needs loads" in run.stderr
