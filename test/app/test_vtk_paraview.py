"""VTK output in ParaView's convention, read back by VTK itself (the `vtk` package from PyPI)
and, where Debian's ParaView is installed, by pvpython.

The points of every .vtu are the reference (first-step) positions and `displacement` is the
motion from there, so reference + displacement is where nodes.csv says each node is (Warp By
Vector with scale 1 shows the mechanism where it is); the field data `node_names` names the first
points; the .pvd lists every file with its time, and it is written whole or not at all, even
when the run is killed.
"""

from __future__ import annotations

import csv
import shutil
import signal
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from apptest import ROOT, fekap_binary

vtk = pytest.importorskip("vtk", reason="the vtk package (scripts/setup --test installs it into build/venv)")


def vtk_deck(tmp_path: Path, deck: str, extra: str = "") -> Path:
    """A copy of ``deck`` writing csv, listing and vtk files."""
    text = (ROOT / deck).read_text()
    text = text.replace("OUTPut", "OUTPut\n  files csv listing vtk" + extra, 1)
    path = tmp_path / Path(deck).name
    path.write_text(text)
    return path


def run(deck: Path, out: Path, *options: str) -> None:
    proc = subprocess.run([fekap_binary(), "-q", "-o", str(out), *options, str(deck)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr


def read_pvd(path: Path) -> list[tuple[float, str]]:
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def read_vtu(path: Path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    assert grid.GetNumberOfPoints() > 0, f"{path}: VTK read no points"
    return grid


def as_array(data) -> np.ndarray:
    from vtk.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(data)


def read_nodes(path: Path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    names = [c[:-2] for c in rows[0][2::2]]
    return names, np.array([[float(v) for v in row] for row in rows[1:]])


@pytest.mark.parametrize(("deck", "method"), [
    ("decks/fourbar.deck", "fem"), ("decks/quick-return.deck", "fem"),
    ("decks/cantilever-rollup.deck", "fem"), ("decks/fourbar.deck", "angles"),
    ("decks/peaucellier.deck", "cartesian")])
def test_reference_points_plus_displacement_are_the_nodes(tmp_path, deck, method):
    """Reference points + displacement = nodes.csv positions, at every written step; the
    points are the same in every file; node_names names the first points."""
    out = tmp_path / "out"
    run(vtk_deck(tmp_path, deck), out, "--method", method)
    names, nodes = read_nodes(out / "nodes.csv")
    sets = read_pvd(out / f"{Path(deck).stem}.pvd")
    assert [t for t, _ in sets] == pytest.approx(nodes[:, 1].tolist(), rel=0, abs=1e-15)
    reference = None
    for (t, file), row in zip(sets, nodes):
        grid = read_vtu(out / file)
        points = as_array(grid.GetPoints().GetData())
        if reference is None:
            reference = points
        assert np.array_equal(points, reference), f"{file}: the points moved (not reference positions)"
        displacement = as_array(grid.GetPointData().GetArray("displacement"))
        current = (points + displacement)[: len(names), :2]
        want = row[2:].reshape(-1, 2)
        scale = max(1.0, float(np.abs(want).max()))
        assert np.abs(current - want).max() <= 1e-13 * scale, f"{file}: reference + displacement"
        field = grid.GetFieldData().GetArray("node_names")
        assert field is not None, f"{file}: no node_names field data"
        # Each name's bytes ended by a 0, in a UInt8 array (meshio reads no string arrays).
        # node_names names the model's nodes; nodes.csv may add the meshed links' interior
        # points after them (LINK#k, OUTPut mesh on), which are the mesh's next points.
        codes = bytes(int(field.GetValue(i)) for i in range(field.GetNumberOfValues()))
        assert [n.decode() for n in codes.split(b"\0")[:-1]] == [n for n in names if "#" not in n]
        time_value = as_array(grid.GetFieldData().GetArray("TimeValue"))
        assert float(time_value[0]) == pytest.approx(t, abs=1e-15)


def test_pvd_lists_every_file_of_a_long_run(tmp_path):
    """4,001 files: the .pvd, written at flushes and at the end, lists each once, in order."""
    out = tmp_path / "long"
    run(vtk_deck(tmp_path, "decks/fourbar.deck"), out, "--dt", "2.5e-4")
    sets = read_pvd(out / "fourbar.pvd")
    files = sorted(p.name for p in (out / "vtk").glob("*.vtu"))
    assert len(sets) == 4001 and [Path(f).name for _, f in sets] == files
    assert all(a < b for (a, _), (b, _) in zip(sets, sets[1:]))
    assert not (out / "fourbar.pvd.part").exists()


def test_pvd_is_whole_after_sigkill(tmp_path):
    """A run killed by SIGKILL leaves a well-formed .pvd whose files all exist."""
    out = tmp_path / "killed"
    deck = vtk_deck(tmp_path, "decks/fourbar.deck")
    proc = subprocess.Popen([fekap_binary(), "-q", "-o", str(out), "--dt", "1e-5", str(deck)], cwd=ROOT)
    pvd = out / "fourbar.pvd"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not pvd.exists():
        time.sleep(0.05)
    time.sleep(0.5)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    sets = read_pvd(pvd)
    assert sets, "the .pvd lists no file"
    assert all((out / f).is_file() for _, f in sets)


PVPYTHON_SCRIPT = r"""
import sys
from paraview.simple import PVDReader, WarpByVector, Show, Render, SaveScreenshot, GetActiveViewOrCreate
from paraview import servermanager
from vtk.util.numpy_support import vtk_to_numpy
reader = PVDReader(FileName=sys.argv[1])
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues)
warp = WarpByVector(Input=reader)
warp.Vectors = ["POINTS", "displacement"]
warp.ScaleFactor = 1.0
warp.UpdatePipeline(times[len(times) // 2])
data = servermanager.Fetch(warp)
points = vtk_to_numpy(data.GetPoints().GetData())
print("TIME", times[len(times) // 2])
for p in points[: int(sys.argv[3])]:
    print("POINT", p[0], p[1])
sys.stdout.flush()
if sys.argv[2] == "-":
    sys.exit(0)
view = GetActiveViewOrCreate("RenderView")
Show(warp, view)
view.ViewTime = times[len(times) // 2]
Render(view)
SaveScreenshot(sys.argv[2], view, ImageResolution=[640, 480])
"""


def pvpython(tmp_path: Path, shot: str) -> tuple[list[str], np.ndarray, list[str]]:
    """Run the ParaView script on a quick-return run: (node names, nodes.csv rows, output lines)."""
    out = tmp_path / "pv"
    run(vtk_deck(tmp_path, "decks/quick-return.deck"), out)
    names, nodes = read_nodes(out / "nodes.csv")
    script = tmp_path / "warp.py"
    script.write_text(PVPYTHON_SCRIPT)
    command = ["pvpython", str(script), str(out / "quick-return.pvd"), shot, str(len(names))]
    if shot != "-":
        command = ["xvfb-run", "-a", *command]
    proc = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return names, nodes, proc.stdout.splitlines()


@pytest.mark.skipif(shutil.which("pvpython") is None, reason="no pvpython (apt-get install paraview python3-paraview)")
def test_paraview_warp_by_vector_puts_the_nodes_where_they_are(tmp_path):
    """ParaView's own PVD reader and Warp By Vector (scale 1) put the nodes where nodes.csv has
    them."""
    names, nodes, lines = pvpython(tmp_path, "-")
    t = float(next(line.split()[1] for line in lines if line.startswith("TIME")))
    got = np.array([[float(v) for v in line.split()[1:]] for line in lines if line.startswith("POINT")])
    row = nodes[np.argmin(np.abs(nodes[:, 1] - t))]
    want = row[2:].reshape(-1, 2)
    assert got.shape == want.shape
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()


@pytest.mark.skipif(shutil.which("pvpython") is None or shutil.which("xvfb-run") is None,
                    reason="no pvpython or no xvfb-run (ParaView from Debian renders through X)")
def test_paraview_screenshot(tmp_path):
    """A headless ParaView screenshot of the warped mechanism (through a virtual X server)."""
    shot = tmp_path / "warp.png"
    pvpython(tmp_path, str(shot))
    assert shot.is_file() and shot.stat().st_size > 1000
