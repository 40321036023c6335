#!/usr/bin/env python3
"""A run removes only what FEKAP wrote (issue #31, item 2): the manifest of
a run (.fekap-manifest) lists its files and those scripts/plot.py draws; the
next run removes those and no other; the deck is never written over; files
of FEKAP's names that no manifest lists stop the run unless --force.

Run alone:  scripts/test output_manifest
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from apptest import ROOT, fekap_binary

FOURBAR = ROOT / "decks/fourbar.deck"
VTK = "OUTPut\n  files csv listing vtk\n"


def fekap(*args, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([fekap_binary(), *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=120)


def manifest(out: Path) -> list[str]:
    return [line for line in (out / ".fekap-manifest").read_text().splitlines() if not line.startswith("#")]


def test_second_run_removes_only_the_first_runs_files(tmp_path):
    out = tmp_path / "project"
    deck = tmp_path / "fourbar.deck"
    deck.write_text(FOURBAR.read_text().replace("OUTPut\n", VTK))
    done = fekap("-q", "-o", out, deck)
    assert done.returncode == 0, done.stderr
    assert set(manifest(out)) == {"points.csv", "links.csv", "steps.csv", "nodes.csv", "mesh.csv",
                                  "mechanism.txt", "fourbar.lis", "fourbar.pvd", "fourbar.pvd.fekap-tmp",
                                  "vtk/fourbar_*.vtu"}
    # A user's files of FEKAP-like names, put there between the runs.
    mine = {"thesis.lis": "my thesis\n", "simulation.pvd": "<mine/>\n", "vtk/mydata.vtu": "<data/>\n",
            "vtk/fourbar_mine.vtu": "<data/>\n", "notes.txt": "notes\n"}
    for name, text in mine.items():
        (out / name).write_text(text)
    # The second run has no VTK: it removes the first run's step files.
    done = fekap("-q", "-o", out, FOURBAR)
    assert done.returncode == 0, done.stderr
    for name, text in mine.items():
        assert (out / name).read_text() == text, f"{name} was touched"
    assert not list((out / "vtk").glob("fourbar_0*.vtu")) and not (out / "fourbar.pvd").exists()
    assert "vtk/fourbar_*.vtu" not in manifest(out)


def test_empty_vtk_directory_of_the_earlier_run_goes(tmp_path):
    out = tmp_path / "o"
    deck = tmp_path / "fourbar.deck"
    deck.write_text(FOURBAR.read_text().replace("OUTPut\n", VTK))
    assert fekap("-q", "-o", out, deck).returncode == 0
    assert (out / "vtk").is_dir()
    assert fekap("-q", "-o", out, FOURBAR).returncode == 0
    assert not (out / "vtk").exists()


def test_deck_under_a_name_the_run_writes_is_refused(tmp_path):
    """`fekap -o . mydeck.lis` and a deck named points.csv: exit 2, the deck intact, forced or not."""
    text = FOURBAR.read_text()
    for name in ("mydeck.lis", "points.csv"):
        deck = tmp_path / name
        deck.write_text(text)
        for extra in ([], ["--force"]):
            done = fekap("-q", "-o", ".", *extra, name, cwd=tmp_path)
            assert done.returncode == 2, (name, extra, done.returncode, done.stderr)
            assert f"the deck {name} is the file" in done.stderr, done.stderr
            assert deck.read_text() == text, f"{name} was changed"
        deck.unlink()
    assert not (tmp_path / ".fekap-manifest").exists()


def test_deck_named_like_an_earlier_runs_file_is_refused(tmp_path):
    """The manifest lists links.csv; a deck of that name put there is not removed by the next run."""
    out = tmp_path / "o"
    assert fekap("-q", "-o", out, FOURBAR).returncode == 0
    deck = out / "links.csv"
    deck.write_text(FOURBAR.read_text())
    done = fekap("-q", "-o", out, deck)
    assert done.returncode == 2 and "the deck" in done.stderr, done.stderr
    assert deck.read_text() == FOURBAR.read_text()


def test_foreign_files_are_named_and_kept_unless_forced(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "points.csv").write_text("their data\n")
    (out / "paths.png").write_text("their picture\n")
    done = fekap("-q", "-o", out, FOURBAR)
    assert done.returncode == 2, done.stderr
    assert "points.csv" in done.stderr and "paths.png" in done.stderr and "--force" in done.stderr
    assert (out / "points.csv").read_text() == "their data\n"
    assert not (out / "steps.csv").exists(), "a refused run wrote files"
    done = fekap("-q", "-o", out, "--force", FOURBAR)
    assert done.returncode == 0, done.stderr
    assert (out / "points.csv").read_text().startswith("step,t,point")
    assert not (out / "paths.png").exists()


def test_a_manifest_cannot_make_a_run_remove_other_files(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    outside = tmp_path / "outside.csv"
    outside.write_text("keep\n")
    (out / "notes.txt").write_text("keep\n")
    (out / "mine.deck").write_text("keep\n")
    (out / ".fekap-manifest").write_text("# hand-made\n../outside.csv\nnotes.txt\nmine.deck\n/etc/hostname\n"
                                         "vtk/../notes.txt\n.fekap-manifest\n")
    done = fekap("-q", "-o", out, FOURBAR)
    assert done.returncode == 0, done.stderr
    assert outside.read_text() == "keep\n"
    assert (out / "notes.txt").read_text() == "keep\n" and (out / "mine.deck").read_text() == "keep\n"


def test_plots_are_recorded_and_removed_by_the_next_run(tmp_path):
    out = tmp_path / "o"
    assert fekap("-q", "-o", out, FOURBAR).returncode == 0
    drawn = subprocess.run([sys.executable, str(ROOT / "scripts/plot.py"), str(out), "--only", "paths"],
                           capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert drawn.returncode == 0, drawn.stderr
    assert (out / "paths.png").is_file() and "paths.png" in manifest(out)
    done = fekap("-q", "-o", out, FOURBAR)
    assert done.returncode == 0, done.stderr
    assert not (out / "paths.png").exists()


def test_the_spatial_pictures_are_fekap_names(tmp_path):
    """views.png and joints.png (a spatial run's pictures, fekap.plot3d) are names of FEKAP's:
    recorded in the manifest they go with the next run; not recorded they stop it (exit 2)
    unless --force."""
    rssr = ROOT / "decks/spatial/rssr.deck"
    out = tmp_path / "o"
    assert fekap("-q", "-o", out, rssr).returncode == 0
    with open(out / ".fekap-manifest", "a") as handle:
        handle.write("views.png\njoints.png\n")
    for name in ("views.png", "joints.png"):
        (out / name).write_text("drawn by plot.py\n")
    done = fekap("-q", "-o", out, rssr)
    assert done.returncode == 0, done.stderr
    assert not (out / "views.png").exists() and not (out / "joints.png").exists()
    for name in ("views.png", "joints.png"):
        (out / name).write_text("their picture\n")
    done = fekap("-q", "-o", out, rssr)
    assert done.returncode == 2, done.stderr
    assert "views.png" in done.stderr and "joints.png" in done.stderr and "--force" in done.stderr
    assert (out / "views.png").read_text() == "their picture\n"
    done = fekap("-q", "-o", out, "--force", rssr)
    assert done.returncode == 0, done.stderr
    assert not (out / "views.png").exists() and not (out / "joints.png").exists()
