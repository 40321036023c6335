"""steps.csv's `floor` column and the listing's count outside dynamics: a step
of the kinematics (and of kinetostatics and statics, which solve with it) or
of the classical methods that Newton accepted at the residual's round-off
floor, with the residual above the tolerance, is counted in both
(docs/theory.md, "Convergence"). Example 1's deck asks, with `tolerance
1e-15`, for less than its floor (about 1e-13 of its stiffness EA = 100):
steps end at the floor; with the deck's own tolerance none does."""

from __future__ import annotations

from pathlib import Path

import pytest

from apptest import ROOT, check, read_rows, run_fekap

#: Below Example 1's round-off floor relative to its drive increment's residual.
TIGHT = "1e-15"
HEADER = ["step", "t", "iterations", "residual", "cuts", "floor"]


def run(tmp_path: Path, name: str, deck: str, *options: str) -> tuple[list[dict[str, str]], str]:
    out = tmp_path / name
    r = run_fekap("-q", "-o", out, *options, ROOT / "decks" / deck)
    check(r.returncode == 0, f"{deck} {options}: exit {r.returncode}: {r.stderr}")
    rows = read_rows(out / "steps.csv")
    check(list(rows[0]) == HEADER, f"steps.csv's header: {list(rows[0])}")
    return rows, next(out.glob("*.lis")).read_text()


def tight_deck(tmp_path: Path) -> Path:
    """Example 1 with `tolerance 1e-15` in its ANALysis block."""
    text = (ROOT / "decks" / "fourbar.deck").read_text()
    text = text.replace("  time 0 1 0.025\n", f"  time 0 1 0.025\n  tolerance {TIGHT}\n")
    check(f"tolerance {TIGHT}" in text, "the deck's ANALysis line moved")
    path = tmp_path / "fourbar-tight.deck"
    path.write_text(text)
    return path


@pytest.mark.parametrize("method", ["fem", "angles", "cartesian"])
def test_steps_at_the_floor_are_counted(tmp_path: Path, method: str) -> None:
    """Kinematic steps accepted at the floor: some rows of steps.csv count them
    (0 or 1 each: no step is cut), the listing's summary gives their total, and
    the positions are those of the deck's own tolerance to 1e-9 (a floor step
    is converged in its length test)."""
    options = [] if method == "fem" else ["--method", method]
    deck = tight_deck(tmp_path)
    out = tmp_path / f"tight-{method}"
    r = run_fekap("-q", "-o", out, *options, deck)
    check(r.returncode == 0, f"exit {r.returncode}: {r.stderr}")
    rows = read_rows(out / "steps.csv")
    check(list(rows[0]) == HEADER, f"steps.csv's header: {list(rows[0])}")
    floors = [int(row["floor"]) for row in rows]
    check(set(floors) <= {0, 1} and sum(floors) > 0, f"floor column {floors}")
    listing = next(out.glob("*.lis")).read_text()
    check(f"accepted at round-off floor {sum(floors):11d}" in listing,
          f"the listing does not count {sum(floors)} floor steps")
    run(tmp_path, f"normal-{method}", "fourbar.deck", *options)
    tight_points = read_rows(out / "points.csv", numbers=True)
    normal_points = read_rows(tmp_path / f"normal-{method}" / "points.csv", numbers=True)
    worst = max(abs(a[k] - b[k]) for a, b in zip(tight_points, normal_points) for k in ("x", "y"))
    check(len(tight_points) == len(normal_points) and worst < 1e-9, f"positions moved by {worst}")


@pytest.mark.parametrize("deck, options", [("fourbar.deck", ()), ("fourbar.deck", ("--method", "angles")),
                                           ("fourbar.deck", ("--method", "cartesian")),
                                           ("fourbar-kinetostatics.deck", ()),
                                           ("slider-crank-kinetostatics.deck", ())])
def test_normal_decks_have_no_floor_steps(tmp_path: Path, deck: str, options: tuple[str, ...]) -> None:
    """With the deck's own tolerance no step ends at the floor: the column is
    there and all zero, and the listing has no floor line."""
    rows, listing = run(tmp_path, "out", deck, *options)
    check(all(row["floor"] == "0" for row in rows), f"floor steps: {[r['floor'] for r in rows]}")
    check("round-off floor" not in listing, "the listing counts floor steps")


def test_statics_and_kinetostatics_count_floor_steps(tmp_path: Path) -> None:
    """`--tol 1e-15` on the kinetostatics and statics decks: their FEM steps at
    the floor are counted as the kinematics' are."""
    for deck in ("fourbar-kinetostatics.deck", "statics-cantilever.deck"):
        rows, listing = run(tmp_path, deck, deck, "--tol", TIGHT)
        total = sum(int(row["floor"]) for row in rows)
        check(total > 0, f"{deck}: no floor step with --tol {TIGHT}")
        check(f"accepted at round-off floor {total:11d}" in listing, f"{deck}: the listing's count is not {total}")
