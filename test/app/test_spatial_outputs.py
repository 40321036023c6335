"""The outputs of a spatial run (issue 33, item 4) beside points.csv and
joints.csv: nodes.csv with z columns, mechanism.txt with the nodes' z, the
joints and their drives, both read back by fekap.read (node_positions,
read_spatial_mechanism, columns of joints.csv).

Run alone:  scripts/test spatial_outputs
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fekap import read

from apptest import ROOT, check, run_fekap

DECKS = ROOT / "decks" / "spatial"


def run_deck(deck: Path, out: Path, *extra: str) -> Path:
    done = run_fekap("-q", "-o", str(out), *extra, str(deck))
    check(done.returncode == 0, f"{deck.name}: exit {done.returncode}: {done.stderr}")
    return out


@pytest.fixture(scope="module")
def slider_crank(tmp_path_factory) -> Path:
    return run_deck(DECKS / "slider-crank.deck", tmp_path_factory.mktemp("slider-crank"))


@pytest.fixture(scope="module")
def bennett(tmp_path_factory) -> Path:
    return run_deck(DECKS / "bennett.deck", tmp_path_factory.mktemp("bennett"))


def test_nodes_csv_has_every_node_in_3d(slider_crank):
    """nodes.csv: `step,t,A.x,A.y,A.z,...`, every node at every step; the
    tracked nodes' columns are points.csv's numbers, the untracked ones (A,
    B2, S2) the closed form (the pivot fixed, the joint nodes at their
    partners' places)."""
    header = (slider_crank / "nodes.csv").read_text().splitlines()[0]
    check(header == "step,t," + ",".join(f"{n}.x,{n}.y,{n}.z" for n in ("A", "B", "B2", "S", "S2")),
          f"nodes.csv header: {header}")
    steps, t, nodes = read.node_positions(slider_crank / "nodes.csv")
    check(len(t) == 101 and list(steps) == list(range(101)), "every step of the deck")
    for name in ("B", "S"):
        points = read.columns(slider_crank / "points.csv", point=name)
        check(np.array_equal(nodes[name], np.stack([points["x"], points["y"], points["z"]], axis=1)),
              f"{name}: nodes.csv differs from points.csv")
    theta = 6 * t
    x = np.sqrt(0.0592 + 0.016 * np.sin(theta) - 0.0192 * np.cos(theta))
    zero = np.zeros_like(t)
    exact = {"A": np.stack([zero, zero + 0.1, zero + 0.12], axis=1),
             "B2": np.stack([zero, 0.1 - 0.08 * np.sin(theta), 0.12 + 0.08 * np.cos(theta)], axis=1),
             "S2": np.stack([x, zero, zero], axis=1)}
    for name, want in exact.items():
        err = np.max(np.abs(nodes[name] - want))
        check(err < 1e-12, f"{name}: largest error {err:.3e} from the closed form")


def test_mechanism_txt_of_the_slider_crank(slider_crank):
    """mechanism.txt in the format the 3D plots read: the exact records."""
    text = (slider_crank / "mechanism.txt").read_text()
    r = read.read_spatial_mechanism(slider_crank / "mechanism.txt")
    lines = text.splitlines()
    check(lines[0] == "record,fields" and lines[1] == 'title,"IFToMM spatial slider-crank"'
          and lines[2:4] == ["units,length,m", "units,time,s"], f"head of mechanism.txt: {lines[:4]}")
    check("analysis,kinematics,spatial" in lines, "no analysis,kinematics,spatial record")
    check(lines[-2:] == ["drive,rotation,JA", "track,B,S"], f"tail of mechanism.txt: {lines[-2:]}")
    check(r.nodes == {"A": (0.0, 0.1, 0.12), "B": (0.0, 0.1, 0.2), "B2": (0.0, 0.1, 0.2), "S": (0.2, 0.0, 0.0),
                      "S2": (0.2, 0.0, 0.0)}, f"nodes: {r.nodes}")
    check([(j.name, j.kind, j.first, j.second) for j in r.joints] == [
        ("JA", "revolute", "ground", "A"), ("JB", "spherical", "B", "B2"), ("JU", "universal", "S", "S2"),
        ("JS", "prismatic", "ground", "S")], f"joints: {r.joints}")
    axes = {j.name: np.array(j.axes) for j in r.joints}
    check(axes["JB"].size == 0 and np.array_equal(axes["JA"], [[1, 0, 0]]) and np.array_equal(axes["JS"], [[1, 0, 0]]),
          f"axes: {axes}")
    # The deck's second axis (0, -2, 1) as a unit vector.
    err = np.max(np.abs(axes["JU"] - np.array([[1, 0, 0], [0, -2 / math.sqrt(5), 1 / math.sqrt(5)]])))
    check(err < 4e-16, f"universal joint's axes off by {err:.3e}")
    check(r.drives == [("rotation", "JA")] and r.tracked == ["B", "S"] and r.units_given and r.length_unit == "m",
          f"drives, track, units: {r.drives}, {r.tracked}, {r.length_unit}")


def test_mechanism_txt_names_ground_second_and_stroke_drives(bennett, tmp_path):
    """A joint written `NODE ground` keeps the ground second; a stroke drive
    is written `drive,stroke,JOINT`."""
    r = read.read_spatial_mechanism(bennett / "mechanism.txt")
    r4 = [j for j in r.joints if j.name == "R4"]
    check(len(r4) == 1 and (r4[0].first, r4[0].second) == ("J4", "ground"), f"R4: {r4}")
    err = np.max(np.abs(np.array(r4[0].axes) - [[0, math.sqrt(3) / 2, 0.5]]))
    check(err < 1e-15, f"R4's axis off by {err:.3e}")
    text = (DECKS / "slider-crank.deck").read_text()
    check("  rotation JA rate 6\n" in text, "the slider-crank deck's drive changed")
    deck = tmp_path / "stroke.deck"
    deck.write_text(text.replace("  rotation JA rate 6\n", "  stroke JS harmonic 0 0.01 2\n"))
    out = run_deck(deck, tmp_path / "out")
    lines = (out / "mechanism.txt").read_text().splitlines()
    check("drive,stroke,JS" in lines and not any(line.startswith("drive,rotation") for line in lines),
          f"drive records: {[line for line in lines if line.startswith('drive')]}")


def test_joints_csv_reads_as_columns(slider_crank):
    """fekap.read.columns reads joints.csv, the joint names as text."""
    ja = read.columns(slider_crank / "joints.csv", joint="JA")
    check(ja["joint"].dtype.kind == "U" and len(ja["angle"]) == 101, "JA's rows")
    check(np.max(np.abs(ja["angle"] - 6 * ja["t"])) < 1e-12, "JA's angle is not 6 t")


def test_read_spatial_mechanism_refuses_bad_records(tmp_path):
    path = tmp_path / "mechanism.txt"
    path.write_text("record,fields\nanalysis,kinematics,spatial\njoint,J,revolute,ground,A,1,0\n")
    with pytest.raises(read.UsageError, match=r"mechanism.txt:3: bad joint record"):
        read.read_spatial_mechanism(path)
    path.write_text("record,fields\nanalysis,kinematics\n")
    with pytest.raises(read.UsageError, match="not the mechanism.txt of a spatial run"):
        read.read_spatial_mechanism(path)


def test_plots_draw_a_spatial_run(tmp_path):
    """scripts/plot.py reads a spatial run's nodes.csv and draws its 3D
    pictures (fekap.plot3d, test_spatial_plots.py), not the planar paths.png."""
    import subprocess
    import sys

    out = run_deck(DECKS / "slider-crank.deck", tmp_path / "out")
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "plot.py"), str(out)], capture_output=True,
                          text=True, timeout=300)
    check(done.returncode == 0, f"plot.py exit {done.returncode}: {done.stderr}")
    check((out / "views.png").is_file() and not (out / "paths.png").exists(), "no views.png, or a paths.png")
