#!/usr/bin/env python3
"""Under-constrained means an error (issue #31, item 3): a mechanism with a
part that neither supports, drives nor its links hold is refused before the
first step (exit 2) with the free nodes and links named, as --method
cartesian refuses it; a determined mechanism, a redundant one included,
runs as before; a statics run that fails is not blamed on a dead point. During the run a
singular configuration that moves freely with the drives held at two times stops the run
(exit 3) naming the part; a change point, singular at one time, is stepped over.

Run alone:  scripts/test free_motion
"""

from __future__ import annotations

import re
import subprocess

import pytest

from apptest import ROOT, fekap_binary

FOURBAR = (ROOT / "decks" / "fourbar.deck").read_text()


def fekap(*args) -> subprocess.CompletedProcess:
    return subprocess.run([fekap_binary(), *map(str, args)], cwd=ROOT, capture_output=True, text=True, timeout=120)


def named(stderr: str, what: str) -> set[str]:
    """The names the message lists after 'nodes ' (or 'links '): 'nodes A, B, C; links ...' -> {A, B, C}."""
    listing = stderr.split("hold): ", 1)[1].split("; support", 1)[0]
    for part in listing.split("; "):
        kind, _, names = part.partition(" ")
        if kind.rstrip("s") == what:
            return set(names.split(", "))
    raise AssertionError(f"no {what}s named: {stderr}")


def without_supports() -> str:
    return FOURBAR.replace("SUPPorts\n  A  pin\n  D  pin\n", "")


def with_undriven_fourbar() -> str:
    """Example 1 and beside it a second four-bar (E F G H) with ground pivots and no drive."""
    text = FOURBAR.replace("  D   4   0                 ! ground pivot of the rocker\n",
                           "  D   4   0\n  E   10  0\n  F   12  0\n  G   13  sqrt(15)\n  H   14  0\n")
    text = text.replace("  DC  D  C  bar             ! rocker, l3 = 4\n",
                        "  DC  D  C  bar\n  EF  E  F  bar\n  FG  F  G  bar\n  HG  H  G  bar\n")
    return text.replace("  D  pin\n", "  D  pin\n  E  pin\n  H  pin\n")


def test_fourbar_without_supports_is_refused_naming_its_parts(tmp_path):
    deck = tmp_path / "free.deck"
    deck.write_text(without_supports())
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert done.stderr.startswith(f"{deck}: the mechanism is not determined"), done.stderr
    assert named(done.stderr, "node") == {"A", "B", "C", "D"}
    assert named(done.stderr, "link") == {"AB", "BC", "DC"}
    # Grubler: 3 links (9) less 2 pins (4) and the drive (1): 4 free.
    assert "at least 4 degrees of freedom" in done.stderr, done.stderr
    assert not (tmp_path / "o").exists(), "a refused run wrote files"
    # The Cartesian method refuses the same deck.
    cartesian = fekap("-q", "-o", tmp_path / "c", "--method", "cartesian", deck)
    assert cartesian.returncode == 2 and "not determined by its constraints" in cartesian.stderr


def test_undriven_second_fourbar_is_refused_naming_only_it(tmp_path):
    deck = tmp_path / "two.deck"
    deck.write_text(with_undriven_fourbar())
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert named(done.stderr, "node") == {"F", "G"}
    assert named(done.stderr, "link") == {"EF", "FG", "HG"}
    assert "at least 1 degree of freedom" in done.stderr, done.stderr
    # Driven, the same deck runs: the check names free motion only.
    driven = deck.read_text().replace("  rotation AB  rate 2*pi", "  rotation AB  rate 2*pi\n  rotation EF rate pi")
    deck.write_text(driven)
    done = fekap("-q", "-o", tmp_path / "d", deck)
    assert done.returncode == 0, done.stderr


def test_free_motion_is_refused_in_kinetostatics_and_statics(tmp_path):
    kinetostatics = (ROOT / "decks" / "fourbar-kinetostatics.deck").read_text()
    assert "  A  pin\n" in kinetostatics
    deck = tmp_path / "k.deck"
    deck.write_text(kinetostatics.replace("  A  pin\n", ""))
    done = fekap("-q", "-o", tmp_path / "k", deck)
    assert done.returncode == 2 and "not determined" in done.stderr and "A" in named(done.stderr, "node"), \
        done.stderr
    # A statics deck without a drive whose links form a mechanism: refused at
    # the start, not run into a failure blamed on a dead point.
    statics = (ROOT / "decks" / "statics-cantilever.deck").read_text()
    deck = tmp_path / "s.deck"
    text = statics.replace("  R  pin  rot RT", "  R  pin")
    assert text != statics
    deck.write_text(text)
    done = fekap("-q", "-o", tmp_path / "s", deck)
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert "not determined" in done.stderr and "dead point" not in done.stderr, done.stderr


@pytest.mark.parametrize("deck", ["fourbar.deck", "double-crank.deck", "peaucellier.deck", "quick-return.deck",
                                  "slider-crank.deck", "cantilever-rollup.deck", "fourbar-appendage.deck",
                                  "statics-cantilever.deck", "slider-crank-kinetostatics.deck",
                                  "hard/scissor-10.deck", "hard/slider-meshed-guide.deck"])
def test_determined_mechanisms_still_run(tmp_path, deck):
    done = fekap("-q", "-o", tmp_path / "o", "--dt", "0.25", ROOT / "decks" / deck)
    assert done.returncode == 0, done.stderr


def test_free_part_in_dynamics_is_left_to_its_mass(tmp_path):
    """Dynamics moves a free part by its mass: the flying spaghetti has no support at all."""
    done = fekap("-q", "-o", tmp_path / "o", "--dt", "0.05", ROOT / "decks/dynamics/flying-spaghetti.deck")
    assert done.returncode == 0, done.stderr


# During the run (issue #31 item 3, "at every singular configuration"): a free
# motion that only the geometry allows passes the count before the first step;
# the FEM meets it as a singular configuration that moves freely with the
# drives held at two times, and stops there (exit 3) naming the part; a change
# point, singular at one time that the drives pass through, is stepped over.

def with_undriven_double_parallelogram() -> str:
    """Example 1 and beside it a double parallelogram (cranks EE, FF, GG of one length on
    ground pivots E, F, G, one welded coupler E2-F2-G2) that nothing drives: Grubler's
    count is 0, its geometry lets it swing."""
    text = FOURBAR.replace("  D   4   0                 ! ground pivot of the rocker\n",
                           "  D   4   0\n  E   10  0\n  F   12  0\n  G   14  0\n"
                           "  E2  11  2\n  F2  13  2\n  G2  15  2\n")
    text = text.replace("  DC  D  C  bar             ! rocker, l3 = 4\n",
                        "  DC  D  C  bar\n  EE  E  E2 bar\n  FF  F  F2 bar\n  GG  G  G2 bar\n"
                        "  C1  E2 F2 bar\n  C2  F2 G2 bar\nWELDs\n  F2 C1 C2\n")
    return text.replace("  D  pin\n", "  D  pin\n  E  pin\n  F  pin\n  G  pin\n")


def parts(stderr: str) -> tuple[set[str], set[str]]:
    """The nodes and links a free-motion message names ('nodes A, B; links AB, BC')."""
    found = re.search(r"nodes ([^;]+); links ([^;)]+)", stderr)
    assert found, stderr
    return set(found.group(1).split(", ")), set(found.group(2).split(", "))


@pytest.mark.parametrize("options", [(), ("--predictor", "previous"), ("--predictor", "taylor"),
                                     ("--compute", "positions")], ids=["default", "previous", "taylor", "positions"])
def test_undriven_double_parallelogram_stops_during_the_run(tmp_path, options):
    deck = tmp_path / "dp.deck"
    deck.write_text(with_undriven_double_parallelogram())
    out = tmp_path / "o"
    done = fekap("-q", "-o", out, *options, deck)
    assert done.returncode == 3, (done.returncode, done.stderr)
    assert done.stderr.startswith(f"{deck}: step 1: t =  2.50000E-02: the mechanism is not determined"), done.stderr
    assert "moves freely here and at t =  0.00000E+00" in done.stderr, done.stderr
    assert "not a change point" in done.stderr and "dead point" not in done.stderr, done.stderr
    assert parts(done.stderr) == ({"E2", "F2", "G2"}, {"EE", "FF", "GG", "C1", "C2"})
    # The start's rows are kept, whole.
    rows = (out / "points.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 and all(r.startswith("0,") for r in rows[1:]), rows  # track B C


def test_driven_double_parallelogram_runs(tmp_path):
    deck = tmp_path / "dp.deck"
    deck.write_text(with_undriven_double_parallelogram().replace(
        "  rotation AB  rate 2*pi", "  rotation AB  rate 2*pi\n  rotation EE  rate pi"))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 0, done.stderr
    listing = (tmp_path / "o" / "dp.lis").read_text()
    assert "singular configuration" not in listing


A02_N2 = (ROOT / "decks" / "hard" / "a02-n2-dt0p01.deck").read_text()


def test_parallelogram_chain_started_flat_cannot_leave_its_start(tmp_path):
    """The A02 chain started at its change point (every bar horizontal: T0 on O1, T1 on O2):
    crank1 and coupler0 turn freely about O1 with the drive held, so the drive does not
    say where the chain goes. Told so, with the part, not blamed on a dead point."""
    text = A02_N2.replace("  T0  0  1\n  T1  1  1\n  T2  2  1\n", "  T0  1  0\n  T1  2  0\n  T2  3  0\n")
    text = text.replace("rate 2*pi pi/2", "rate 2*pi").replace("time 0 1 0.01", "time 0 0.5 0.01")
    assert "  T1  2  0\n" in text and "rate 2*pi\n" in text
    deck = tmp_path / "flat.deck"
    deck.write_text(text)
    for predictor in ("extrapolate", "previous", "taylor"):
        done = fekap("-q", "-o", tmp_path / predictor, "--predictor", predictor, deck)
        assert done.returncode == 3, (predictor, done.returncode, done.stderr)
        assert "the run cannot leave its start: at t =  0.00000E+00" in done.stderr, done.stderr
        assert "dead point" not in done.stderr, done.stderr
        nodes, links = parts(done.stderr)
        assert nodes <= {"T1", "T2"} and nodes, done.stderr
        assert links <= {"crank1", "crank2", "coupler0", "coupler1"}, done.stderr


@pytest.mark.parametrize("deck", ["hard/a02-n2-dt0p01.deck", "hard/a02-n4-dt0p025.deck", "hard/grashof-limit.deck",
                                  "hard/peaucellier-flat.deck", "double-crank.deck"])
def test_change_points_are_stepped_over_not_called_free_motion(tmp_path, deck):
    """The decks whose drives pass through change points run to their end."""
    done = fekap("-q", "-o", tmp_path / "o", ROOT / "decks" / deck)
    assert done.returncode == 0, done.stderr
    assert "moves freely" not in done.stderr


def test_a02_chain_with_the_previous_predictor_still_fails_at_its_change_point(tmp_path):
    """With the paper's predictor the run lands on the change point (singular, and turning
    freely there) and fails after it: one singular time is a change point, not a free
    motion, and the advice to try another predictor stays."""
    done = fekap("-q", "-o", tmp_path / "o", "--predictor", "previous", ROOT / "decks/hard/a02-n2-dt0p01.deck")
    assert done.returncode == 3, done.stderr
    assert "moves freely" not in done.stderr and "try another predictor" in done.stderr, done.stderr
    listing = (tmp_path / "o" / "a02-n2-dt0p01.lis").read_text()
    assert "t =  2.50000E-01: singular configuration" in listing


def test_undriven_double_parallelogram_in_kinetostatics_stops_at_step_1(tmp_path):
    """Meshed links under gravity (kinetostatics): singular from the start, so the run's own
    reference pivot is singular too; the probe still looks, and the run stops at step 1
    (before: exit 0, the reactions of a mechanism that moves freely)."""
    text = (ROOT / "decks" / "fourbar-kinetostatics.deck").read_text()
    text = text.replace("  D   4   0                 ! ground pivot of the rocker\n",
                        "  D   4   0\n  E   10  0\n  F   12  0\n  G   14  0\n  E2  11  2\n  F2  13  2\n  G2  15  2\n")
    text = text.replace("  DC  D  C  bar  4          ! rocker, 4 long, mass 4\n",
                        "  DC  D  C  bar  4\n  EE  E  E2 bar\n  FF  F  F2 bar\n  GG  G  G2 bar\n"
                        "  C1  E2 F2 bar\n  C2  F2 G2 bar\nWELDs\n  F2 C1 C2\n")
    text = text.replace("  D  pin\n", "  D  pin\n  E  pin\n  F  pin\n  G  pin\n")
    assert text.count("G2") == 3 and text.count(" pin") == 5
    deck = tmp_path / "k.deck"
    deck.write_text(text)
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 3, (done.returncode, done.stderr)
    assert f"{deck}: step 1: " in done.stderr and "moves freely here" in done.stderr, done.stderr
    assert parts(done.stderr) == ({"E2", "F2", "G2"}, {"EE", "FF", "GG", "C1", "C2"})
