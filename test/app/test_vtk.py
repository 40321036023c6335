"""The VTK output of the fekap executable, read back with VTK's own reader
(the vtk package) and xml.etree, and checked against the CSV output of
the same run: one .vtu per written step and a .pvd listing them with their
times; the model's nodes are the first points; cells connect the right
points; displacement, velocity and acceleration; stress resultants of a
beam in pure bending; classical methods; a run that stops early.

Run with scripts/test (pytest): scripts/test NAME runs the tests whose names contain NAME.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from apptest import ROOT, check, read_rows, run_fekap

OUT: Path = None  # a fresh scratch directory for each run, set by conftest.py


def vtk_deck(deck: str, name: str, *replace: tuple[str, str], extra: str = "") -> Path:
    """A copy of ``deck`` (as ``name``.deck) that tracks every node and writes
    csv, listing and vtk files; ``replace`` pairs edit the text, ``extra``
    lines go into the OUTPut block."""
    text = (ROOT / deck).read_text()
    for old, new in replace:
        check(old in text, f"{deck}: no {old!r} to replace")
        text = text.replace(old, new)
    # No track lines: every node is tracked, in deck order.
    text = re.sub(r"(?im)^\s*track\b.*\n", "", text)
    text, count = re.subn(r"(?im)^OUTPut.*$", lambda m: m.group(0) + "\n  files csv listing vtk" + extra, text,
                          count=1)
    check(count == 1, f"{deck}: no OUTPut block")
    path = OUT / f"{name}.deck"
    path.write_text(text)
    return path


def run(deck: Path, *options: str, status: int = 0) -> Path:
    """Run fekap on ``deck`` into its own directory; check the exit status."""
    out = OUT / (deck.stem + "".join(o.strip("-") for o in options))
    result = run_fekap("-q", "-o", str(out), *options, str(deck))
    check(result.returncode == status, f"fekap {deck.name} {' '.join(options)} exited {result.returncode}, "
                                       f"want {status}:\n{result.stderr}")
    return out


def read_pvd(path: Path) -> list[tuple[float, str]]:
    """(time, file) of every DataSet of a .pvd collection (parsing it checks it is well-formed XML)."""
    root = ET.parse(path).getroot()
    check(root.tag == "VTKFile" and root.get("type") == "Collection", f"{path}: not a VTK collection")
    collection = root.find("Collection")
    check(collection is not None, f"{path}: no Collection element")
    sets = []
    for dataset in collection:
        check(dataset.tag == "DataSet" and dataset.get("part") == "0", f"{path}: bad element {dataset.tag}")
        sets.append((float(dataset.get("timestep")), dataset.get("file")))
    return sets


def close(got, want, tol: float = 1e-14) -> bool:
    """Arrays equal to ``tol`` relative to the largest magnitude of ``want`` (at least 1)."""
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    scale = max(1.0, float(np.max(np.abs(want)))) if want.size else 1.0
    return got.shape == want.shape and bool(np.all(np.abs(got - want) <= tol * scale))


class Mesh:
    """A .vtu read by VTK, shaped like a meshio mesh: ``points`` are the current positions
    (the file's reference points plus its displacement, ParaView's convention), ``reference``
    the file's points; ``point_data``, ``cell_data`` (a list per name), ``cells`` (one block of
    lines)."""

    def __init__(self, path: Path):
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy

        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(path))
        reader.Update()
        grid = reader.GetOutput()
        check(grid.GetNumberOfPoints() > 0, f"{path}: VTK read no points")
        self.reference = vtk_to_numpy(grid.GetPoints().GetData())
        self.point_data = {grid.GetPointData().GetArrayName(i): vtk_to_numpy(grid.GetPointData().GetArray(i))
                           for i in range(grid.GetPointData().GetNumberOfArrays())}
        self.cell_data = {grid.GetCellData().GetArrayName(i): [vtk_to_numpy(grid.GetCellData().GetArray(i))]
                          for i in range(grid.GetCellData().GetNumberOfArrays())}
        self.points = self.reference + self.point_data["displacement"]
        fields = grid.GetFieldData()
        self.field_data = {fields.GetArrayName(i): vtk_to_numpy(fields.GetArray(i))
                           for i in range(fields.GetNumberOfArrays()) if fields.GetArray(i) is not None}
        types = {int(grid.GetCellType(i)) for i in range(grid.GetNumberOfCells())}
        check(types <= {3}, f"{path}: cells of VTK types {types}, want lines (3)")
        connectivity = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 2)
        self.cells = [type("Cells", (), {"type": "line", "data": connectivity})()]


class Run:
    """A finished run with VTK output: its CSV tables and its .vtu meshes, all checked."""

    def __init__(self, out: Path, stem: str):
        self.out, self.stem = out, stem
        self.steps = read_rows(out / "steps.csv")
        self.points = read_rows(out / "points.csv")
        self.links = read_rows(out / "mesh.csv")
        self.node_names = []
        for row in self.points:
            if row["step"] != self.steps[0]["step"]:
                break
            self.node_names.append(row["point"])
        self.collection = read_pvd(out / f"{stem}.pvd")
        self.meshes = [Mesh(out / file) for _, file in self.collection]

    def check_files(self) -> None:
        """One file per written step, named after its step, with the step's time."""
        check(len(self.collection) == len(self.steps),
              f"{self.stem}: {len(self.collection)} files in the .pvd, {len(self.steps)} rows in steps.csv")
        on_disk = sorted(p.name for p in (self.out / "vtk").glob("*.vtu"))
        check(len(on_disk) == len(self.steps), f"{self.stem}: {len(on_disk)} .vtu files in vtk/")
        for (t, file), row, mesh in zip(self.collection, self.steps, self.meshes):
            want = f"vtk/{self.stem}_{int(row['step']):06d}.vtu"
            check(file == want, f"{self.stem}: file {file}, want {want}")
            check(t == float(row["t"]), f"{file}: timestep {t}, steps.csv t {row['t']}")
            check(float(mesh.field_data["TimeValue"][0]) == t, f"{file}: TimeValue differs from the .pvd")
        listing = (self.out / f"{self.stem}.lis").read_text()
        check(re.search(rf"VTK files written\s+{len(self.steps)}\b", listing) is not None,
              f"{self.stem}: the listing does not count {len(self.steps)} VTK files")

    def check_fields(self) -> None:
        """Nodes are the first points and match points.csv; rates and
        displacement match; z = 0; cells chain each link from its first node to its second."""
        nnode = len(self.node_names)
        initial = self.meshes[0].points
        by_step: dict[str, list[dict[str, str]]] = {}
        for row in self.points:
            by_step.setdefault(row["step"], []).append(row)
        for (_, file), row, mesh in zip(self.collection, self.steps, self.meshes):
            rows = by_step[row["step"]]
            check([r["point"] for r in rows] == self.node_names, f"{file}: points.csv rows out of order")
            p = mesh.points
            check(np.array_equal(mesh.reference, self.meshes[0].reference), f"{file}: points are not the reference")
            check(p.shape[0] >= nnode and p.shape[1] == 3, f"{file}: points of shape {p.shape}")
            check(np.all(p[:, 2] == 0), f"{file}: z is not 0")
            xy = [[float(r["x"]), float(r["y"])] for r in rows]
            check(close(p[:nnode, :2], xy), f"{file}: the first {nnode} points are not the nodes of points.csv")
            check(close(mesh.point_data["displacement"], p - initial), f"{file}: displacement is not x - x0")
            for name, keys in (("velocity", ("vx", "vy")), ("acceleration", ("ax", "ay"))):
                if keys[0] not in rows[0] or not rows[0][keys[0]]:
                    check(name not in mesh.point_data, f"{file}: {name} written but not computed")
                    continue
                check(name in mesh.point_data, f"{file}: no {name}")
                data = mesh.point_data[name]
                check(np.all(data[:, 2] == 0), f"{file}: {name} z is not 0")
                want = [[float(r[keys[0]]), float(r[keys[1]])] for r in rows]
                check(close(data[:nnode, :2], want), f"{file}: {name} differs from points.csv")
            check(len(mesh.cells) == 1 and mesh.cells[0].type == "line", f"{file}: cells are not one line block")
            cells = mesh.cells[0].data
            link = mesh.cell_data["link"][0]
            check(link.dtype.kind == "i", f"{file}: link is not an integer array")
            for name in ("N", "V", "M"):
                check(len(mesh.cell_data[name][0]) == len(cells), f"{file}: {name} not one value per cell")
            check(set(link) == set(range(1, len(self.links) + 1)), f"{file}: links {sorted(set(link))}")
            for index, lrow in enumerate(self.links, start=1):
                chain = cells[link == index]
                first = self.node_names.index(lrow["node1"])
                last = self.node_names.index(lrow["node2"])
                check(chain[0, 0] == first and chain[-1, 1] == last,
                      f"{file}: link {lrow['link']} does not run from {lrow['node1']} to {lrow['node2']}")
                check(np.all(chain[1:, 0] == chain[:-1, 1]), f"{file}: cells of {lrow['link']} are not a chain")

    def check_meshio(self) -> None:
        """meshio, the Python ecosystem's usual mesh reader, reads every file as VTK does,
        and the node names (field data, each name's bytes ended by a 0) are the model's nodes."""
        import meshio

        for (_, file), mesh in zip(self.collection, self.meshes):
            got = meshio.read(self.out / file)
            check(np.array_equal(got.points, mesh.reference), f"{file}: meshio's points differ from VTK's")
            for name, values in mesh.point_data.items():
                check(np.array_equal(got.point_data[name], values), f"{file}: meshio's {name} differs")
            check(np.array_equal(got.cells[0].data, mesh.cells[0].data), f"{file}: meshio's cells differ")
            for name, values in mesh.cell_data.items():
                check(np.array_equal(got.cell_data[name][0], values[0]), f"{file}: meshio's cell {name} differs")
            names = bytes(got.field_data["node_names"].astype(np.uint8)).split(b"\0")[:-1]
            nnode = len(names)
            check([n.decode() for n in names] == self.node_names[:nnode] and nnode >= 2,
                  f"{file}: node_names {names[:4]}... are not the first points of points.csv")

    def check_all(self) -> Run:
        self.check_files()
        self.check_fields()
        self.check_meshio()
        return self


def test_fourbar_fem():
    out = run(vtk_deck("decks/fourbar.deck", "fourbar"), "--method", "fem")
    r = Run(out, "fourbar").check_all()
    check(len(r.meshes) == 41 and r.meshes[0].points.shape[0] == 4, "41 files of the 4 points")
    for mesh in r.meshes:
        for name in ("N", "V", "M"):
            check(np.max(np.abs(mesh.cell_data[name][0])) < 1e-9, f"a rigid motion has {name} != 0")


def test_thinned_steps():
    """`every 7` writes the same steps as the CSV: the first, every 7th and the last."""
    out = run(vtk_deck("decks/fourbar.deck", "fourbar-every", extra="\n  every 7"))
    r = Run(out, "fourbar-every").check_all()
    check([int(row["step"]) for row in r.steps] == [0, 7, 14, 21, 28, 35, 40], "steps written")


def test_cantilever_pure_bending():
    """16 elements; at t = 1 the end moment 2*pi*EI/L is carried by every cell, with N = V = 0."""
    out = run(vtk_deck("decks/cantilever-rollup.deck", "cantilever"))
    r = Run(out, "cantilever").check_all()
    last = r.meshes[-1]
    check(float(last.field_data["TimeValue"][0]) == 1.0, "the last file is at t = 1")
    check(last.points.shape[0] == 17 and len(last.cells[0].data) == 16, "17 points, 16 cells")
    ei, length = 1.0, 1.0  # the deck's section: E = 1, I = 1; L = 1
    m_want = 2 * math.pi * ei / length
    n, v, m = (last.cell_data[k][0] for k in ("N", "V", "M"))
    check(np.max(np.abs(n)) < 1e-6 * m_want and np.max(np.abs(v)) < 1e-6 * m_want,
          f"pure bending: largest |N| {np.max(np.abs(n)):.2e}, |V| {np.max(np.abs(v)):.2e}")
    check(np.max(np.abs(m - m_want)) < 1e-6 * m_want, f"M = {m}, want {m_want} in every cell")
    # Half way the moment (and the bending) is half.
    half = r.meshes[len(r.meshes) // 2]
    t_half = float(half.field_data["TimeValue"][0])
    check(close(half.cell_data["M"][0], np.full(16, m_want * t_half), 1e-6), "M = t*2*pi*EI/L half way")


def test_quick_return():
    """Sliding joints: the slider P stays on y = 500 in the point data too."""
    out = run(vtk_deck("decks/quick-return.deck", "quick-return"))
    r = Run(out, "quick-return").check_all()
    p = r.node_names.index("P")
    check(all(abs(mesh.points[p, 1] - 500) < 1e-9 * 500 for mesh in r.meshes), "P leaves y = 500")


def test_classical_methods():
    """Cartesian and angles: points are the nodes, cells the links, resultants zero."""
    deck = vtk_deck("decks/fourbar.deck", "fourbar-classical")
    for method in ("cartesian", "angles"):
        out = run(deck, "--method", method)
        r = Run(out, "fourbar-classical").check_all()
        for mesh in r.meshes:
            check(mesh.points.shape[0] == 4, f"{method}: {mesh.points.shape[0]} points, want the 4 nodes")
            check(np.array_equal(mesh.cells[0].data, [[0, 1], [1, 2], [3, 2]]), f"{method}: cells are not the links")
            check(np.array_equal(mesh.cell_data["link"][0], [1, 2, 3]), f"{method}: cell l is not link l")
            for name in ("N", "V", "M"):
                check(np.all(mesh.cell_data[name][0] == 0), f"{method}: {name} is not zero")


def test_early_stop():
    """A run that stops (the slider runs off a short guide, exit 3) leaves a
    valid .pvd listing exactly the written steps."""
    deck = vtk_deck("decks/quick-return.deck", "short-guide",
                    ("guide -400 500 100 500", "guide -100 500 100 500"))
    out = run(deck, status=3)
    r = Run(out, "short-guide").check_all()
    check(5 < len(r.steps) < 101, f"{len(r.steps)} steps written before the stop")

