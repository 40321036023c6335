#!/usr/bin/env python3
"""links.csv's angle is the direction of the link's chord, first node to
last (issue #31, item 8), also for a link meshed with several elements,
whose end rotations differ from it; and --tol says what it changes.

Run alone:  scripts/test link_angles
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

from apptest import ROOT, fekap_binary, read_rows


def fekap(*args) -> subprocess.CompletedProcess:
    return subprocess.run([fekap_binary(), *map(str, args)], cwd=ROOT, capture_output=True, text=True, timeout=300)


def link_rows(out: Path, link: str) -> list[dict[str, str]]:
    return [row for row in read_rows(out / "links.csv") if row["link"] == link]


def test_rolled_up_cantilever_angle_is_its_chord(tmp_path):
    """Under an end moment M = 2 pi t EI/L the beam is a circular arc of angle 2 pi t: its chord
    turns by pi t (exact), while the clamped first end never turns (what links.csv said before).
    At t = 1 the chord has shrunk to nothing and the mean of the end rotations, pi, stands for it."""
    out = tmp_path / "o"
    done = fekap("-q", "-o", out, ROOT / "decks/cantilever-rollup.deck")
    assert done.returncode == 0, done.stderr
    rows = link_rows(out, "RT")
    assert len(rows) == 21
    worst = max(abs(float(row["angle"]) - math.pi * float(row["t"])) for row in rows)
    assert worst < 1e-6, worst
    assert abs(float(rows[-1]["angle"]) - math.pi) < 1e-6


def test_meshed_link_angle_and_rates_follow_its_chord(tmp_path):
    """The quick-return's lever of 4 elements: the angle is the chord's direction read from nodes.csv
    (to round-off), and omega and alpha are its rates (central differences, error O(dt^2))."""
    out = tmp_path / "o"
    done = fekap("-q", "-o", out, "--dt", "0.001", ROOT / "decks/hard/quick-return-meshed-lever.deck")
    assert done.returncode == 0, done.stderr
    nodes = read_rows(out / "nodes.csv")
    rows = link_rows(out, "O4B")
    assert len(rows) == len(nodes) == 1001
    for node_row, row in zip(nodes, rows):
        chord = math.atan2(float(node_row["B.y"]) - float(node_row["O4.y"]),
                           float(node_row["B.x"]) - float(node_row["O4.x"]))
        difference = float(row["angle"]) - chord
        assert abs(difference - 2 * math.pi * round(difference / (2 * math.pi))) < 1e-12, (row, chord)
    dt = 0.001
    angle = [float(row["angle"]) for row in rows]
    omega = [float(row["omega"]) for row in rows]
    alpha = [float(row["alpha"]) for row in rows]
    scale_w = max(map(abs, omega))
    scale_a = max(map(abs, alpha))
    for k in range(1, len(rows) - 1):
        assert abs((angle[k + 1] - angle[k - 1]) / (2 * dt) - omega[k]) < 1e-3 * scale_w, k
        assert abs((omega[k + 1] - omega[k - 1]) / (2 * dt) - alpha[k]) < 1e-2 * scale_a, k


def test_single_element_links_of_a_kinematic_run_are_unchanged(tmp_path):
    """Example 1's links are one element each and unstrained: their angle is the driven crank's
    2 pi t exactly, as before."""
    out = tmp_path / "o"
    assert fekap("-q", "-o", out, ROOT / "decks/fourbar.deck").returncode == 0
    for row in link_rows(out, "AB"):
        assert float(row["angle"]) == 2 * math.pi * float(row["t"]) or \
            abs(float(row["angle"]) - 2 * math.pi * float(row["t"])) < 1e-14, row


def test_tol_below_round_off_is_refused(tmp_path):
    done = fekap("-q", "-o", tmp_path / "o", "--tol", "1e-300", ROOT / "decks/fourbar.deck")
    assert done.returncode == 2 and "--tol '1e-300'" in done.stderr and "1e-15" in done.stderr, done.stderr
    assert not (tmp_path / "o").exists()


def test_tol_with_the_default_test_says_what_it_changes(tmp_path):
    done = fekap("-o", tmp_path / "o", "--tol", "0.5", ROOT / "decks/fourbar.deck")
    assert done.returncode == 0, done.stderr
    assert "note: --tol sets the residual ratio" in done.stdout and "length tolerance" in done.stdout, done.stdout
    quiet = fekap("-q", "-o", tmp_path / "q", "--tol", "0.5", ROOT / "decks/fourbar.deck")
    assert quiet.returncode == 0 and quiet.stdout == "", quiet.stdout


def test_tol_decides_the_papers_test(tmp_path):
    """With the paper's test the tolerance alone ends Newton: another tolerance, other iterations and
    other positions (the loose one stops earlier in a step, and pays for it in the next steps)."""
    deck = tmp_path / "paper.deck"
    deck.write_text((ROOT / "decks/fourbar.deck").read_text().replace("  time 0 1 0.025\n",
                                                                       "  time 0 1 0.025\n  convergence paper\n"))
    iterations = {}
    for tol in ("1e-2", "1e-12"):
        done = fekap("-o", tmp_path / tol, "--tol", tol, deck)
        assert done.returncode == 0, done.stderr
        assert "note:" not in done.stdout
        iterations[tol] = [int(row["iterations"]) for row in read_rows(tmp_path / tol / "steps.csv")]
    assert iterations["1e-2"] != iterations["1e-12"], iterations
    assert (tmp_path / "1e-2/points.csv").read_bytes() != (tmp_path / "1e-12/points.csv").read_bytes()
