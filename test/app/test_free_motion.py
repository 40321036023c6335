#!/usr/bin/env python3
"""Under-constrained means an error (issue #31, item 3): a mechanism with a
part that neither supports, drives nor its links hold is refused before the
first step (exit 2) with the free nodes and links named, as --method
cartesian refuses it; a determined mechanism, a redundant one included,
runs as before; a statics run that fails is not blamed on a dead point.

Run alone:  scripts/test free_motion
"""

from __future__ import annotations

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
