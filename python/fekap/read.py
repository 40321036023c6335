"""Read the files of a FEKAP output directory whole (python/fekap/stream.py reads them in
blocks and reduces them, for the plots of runs of any length).

A FEKAP run writes into its output directory (README.md, "What a run writes"):

- ``points.csv``: ``step,t,point,x,y[,vx,vy[,ax,ay]]``, one row per tracked point per step;
- ``links.csv``: ``step,t,link,angle[,omega[,alpha]]`` (angles in radians, unwrapped);
- ``steps.csv``: ``step,t,iterations,residual,cuts[,floor]``;
- ``nodes.csv``: ``step,t,A.x,A.y,...``, every node (and meshed links' interior points) per step;
- ``reactions.csv``: ``step,t,kind,link,node,fx,fy,m``; ``energy.csv``: ``step,t,kinetic,...``;
  ``deflection.csv``: ``step,t,node,ux,uy``;
- ``mesh.csv``: ``link,node1,node2``, the end points of each link by point name;
- a spatial run's (docs/deck-format.md, "Spatial decks"): ``points.csv`` and ``nodes.csv`` with
  z columns (``step,t,A.x,A.y,A.z,...``), ``joints.csv`` (``step,t,joint,angle[,rate[,acceleration]]``)
  and ``mechanism.txt`` with ``node,NAME,x,y,z`` and ``joint`` records.

Any of them: :func:`rows` (dictionaries, as text or numbers) and :func:`columns` (numpy
arrays, rows selected by a name); every node's coordinates of nodes.csv: :func:`node_positions`;
a spatial run's mechanism.txt: :func:`read_spatial_mechanism`; the plots' forms: :func:`load_run`
(points, links, steps and mesh as one :class:`Series` per point and link).

Everything here raises :class:`UsageError` with a one-line message for anything a user can
get wrong (missing files, bad numbers, missing columns), so that the scripts can print it and
exit with status 2 instead of a traceback.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Point quantities in the order FEKAP writes them, grouped by kind.
POSITION = ("x", "y")
VELOCITY = ("vx", "vy")
ACCELERATION = ("ax", "ay")
POINT_QUANTITIES = POSITION + VELOCITY + ACCELERATION
#: Link quantities in the order FEKAP writes them.
LINK_QUANTITIES = ("angle", "omega", "alpha")

#: Fortran may drop the E of a three-digit exponent (1.0-100) or write D for E.
_FORTRAN_EXPONENT = re.compile(r"^([-+]?[0-9.]+)[dD]?([-+][0-9]+)$")


class UsageError(Exception):
    """A problem with the user's arguments or files, reported as one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr and exit status 2."""

    def error(self, message: str) -> None:  # noqa: D102 (argparse's hook)
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")


def run_main(prog: str, main, argv: list[str] | None = None) -> int:
    """Call ``main(argv)`` and turn a UsageError or OSError into a one-line message."""
    try:
        return main(argv)
    except UsageError as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{prog}: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 1


def pyplot():
    """matplotlib.pyplot on the headless Agg backend, drawing every text as plain text.

    Imported only when a figure is drawn, so that bad arguments are refused at once.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # Titles, units and names are plain text: a $ in a title is a dollar, not mathtext.
    plt.rcParams["text.parse_math"] = False
    plt.rcParams["text.usetex"] = False
    return plt


def parse_number(text: str) -> float:
    """Convert one CSV field to float, accepting Fortran spellings (1.0D+00, 1.0-100).

    An empty field is a value the run did not compute at that step (FEKAP leaves
    velocities and accelerations out of a row at a singular configuration): NaN,
    which matplotlib draws as a gap.
    """
    text = text.strip()
    if not text:
        return float("nan")
    try:
        return float(text)
    except ValueError:
        match = _FORTRAN_EXPONENT.match(text)
        if match is None:
            raise
        return float(f"{match.group(1)}e{match.group(2)}")


def read_table(path: Path, names: tuple[str, ...], required: tuple[str, ...]
               ) -> tuple[list[str], dict[str, np.ndarray]]:
    """Read a CSV file with a header line into columns.

    ``names`` are the columns kept as strings; every other known column is converted to float
    (``step`` to int). Columns in ``required`` must be present. Returns the header and the
    columns; an empty file (header only) gives zero-length columns.
    """
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = [row for row in csv.reader(handle) if row and any(f.strip() for f in row)]
    except UnicodeDecodeError as exc:
        raise UsageError(f"{path}: not a text CSV file ({exc.reason})") from None
    if not rows:
        raise UsageError(f"{path}: the file is empty (not even a header line)")
    header = [field.strip() for field in rows[0]]
    missing = [name for name in required if name not in header]
    if missing:
        raise UsageError(f"{path}: missing column(s) {', '.join(missing)} in header "
                         f"'{','.join(header)}'")
    columns: dict[str, list] = {name: [] for name in header}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) < len(header):
            raise UsageError(f"{path}:{line}: {len(row)} fields, the header has {len(header)}")
        for name, field in zip(header, row):
            if name in names:
                columns[name].append(field.strip())
                continue
            try:
                columns[name].append(parse_number(field))
            except ValueError:
                raise UsageError(f"{path}:{line}: column {name}: '{field.strip()}' is not a "
                                 "number") from None
    arrays = {}
    for name, values in columns.items():
        if name in names:
            arrays[name] = np.array(values, dtype=str)
        elif name == "step":
            arrays[name] = np.array(values, dtype=float).astype(int)
        else:
            arrays[name] = np.array(values, dtype=float)
    return header, arrays


#: The text columns of FEKAP's CSV files (names of points, links and nodes, the kind of a
#: reaction); every other column is a number.
TEXT_COLUMNS = ("point", "link", "node", "kind", "node1", "node2", "joint")
#: The columns of whole numbers.
INTEGER_COLUMNS = ("step", "iterations", "cuts", "floor")


def rows(path: Path, numbers: bool = False, **where: str) -> list[dict]:
    """The rows of a CSV file FEKAP writes, as dictionaries by column name, in file order.

    ``where`` keeps the rows whose text columns have the given values (``rows(p, point="C")``).
    The fields are the text as written, or with ``numbers`` numbers: int in INTEGER_COLUMNS,
    float in the others, None for an empty field (a rate not computed at a singular
    configuration); the text columns stay text.
    """
    with open(path, newline="", encoding="utf-8") as handle:
        found = [row for row in csv.DictReader(handle)
                 if all(row.get(name) == value for name, value in where.items())]
    if not numbers:
        return found

    def number(name: str, field: str):
        if name in TEXT_COLUMNS:
            return field
        if not field.strip():
            return None
        return int(field) if name in INTEGER_COLUMNS else parse_number(field)

    return [{name: number(name, field) for name, field in row.items()} for row in found]


def columns(path: Path, **where: str) -> dict[str, np.ndarray]:
    """The columns of a CSV file FEKAP writes as numpy arrays (``step`` of ints, the text
    columns of strings, every other of floats, NaN for an empty field), with the rows whose
    text columns have the values of ``where`` (``columns(p, point="T")``)."""
    header, table = read_table(Path(path), TEXT_COLUMNS, ())
    keep = np.ones(len(table[header[0]]) if header else 0, dtype=bool)
    for name, value in where.items():
        if name not in table:
            raise UsageError(f"{path}: no column {name} in header '{','.join(header)}'")
        keep &= table[name] == value
    return {name: values[keep] for name, values in table.items()}


def node_positions(path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """nodes.csv whole: the steps, the times, and each node's coordinates by step, an array of
    shape (steps, 2) for a planar run (``A.x,A.y``) or (steps, 3) for a spatial one
    (``A.x,A.y,A.z``); a planar run's meshed links' interior points (``LINK#k``) are nodes here too.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"{path}: no such file")
    header, table = read_table(path, (), ("step", "t"))
    names = header[2:]
    dims = 3 if any(name.endswith(".z") for name in names) else 2
    axes = ("x", "y", "z")[:dims]
    if header[:2] != ["step", "t"] or len(names) % dims or any(
            name != f"{names[k - k % dims][:-2]}.{axes[k % dims]}" for k, name in enumerate(names)):
        raise UsageError(f"{path}: expected the header step,t,A.x,A.y{',A.z' if dims == 3 else ''},...")
    nodes = {names[k][:-2]: np.stack([table[names[k + j]] for j in range(dims)], axis=1)
             for k in range(0, len(names), dims)}
    return table["step"], table["t"], nodes


@dataclass(frozen=True)
class SpatialJoint:
    """A joint of a spatial run's mechanism.txt: its nodes (``ground`` for the ground) and its
    unit axes in global coordinates at the deck's configuration (none, one or two)."""

    name: str
    kind: str
    first: str
    second: str
    axes: tuple[tuple[float, float, float], ...]


@dataclass
class SpatialMechanism:
    """A spatial run's mechanism.txt (README.md, "What a run writes")."""

    title: str = ""
    length_unit: str = "length"
    time_unit: str = "time"
    units_given: bool = False
    #: The analysis record's fields after ``analysis`` (``("kinematics", "spatial")``).
    analysis: tuple[str, ...] = ()
    #: node -> initial (x, y, z).
    nodes: dict[str, tuple[float, float, float]] = dataclasses.field(default_factory=dict)
    joints: list[SpatialJoint] = dataclasses.field(default_factory=list)
    #: ("rotation" | "stroke", joint).
    drives: list[tuple[str, str]] = dataclasses.field(default_factory=list)
    tracked: list[str] = dataclasses.field(default_factory=list)


#: How many axes each kind of joint has in a joint record.
JOINT_AXES = {"spherical": 0, "weld": 0, "revolute": 1, "prismatic": 1, "cylindrical": 1, "universal": 2}


def read_spatial_mechanism(path: Path) -> SpatialMechanism:
    """A spatial run's mechanism.txt (``record,fields``, ``title``, ``units``, ``node,NAME,x,y,z``,
    ``analysis,kinematics,spatial``, ``joint,NAME,KIND,FIRST,SECOND[,axes]``,
    ``drive,rotation|stroke,JOINT``, ``track,NODE...``); a record of another kind is skipped, a
    known record with the wrong fields is a UsageError naming its line."""
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"{path}: no such file")
    mech = SpatialMechanism()
    with open(path, newline="", encoding="utf-8", errors="replace") as handle:
        for line, row in enumerate(csv.reader(handle), start=1):
            if not row:
                continue
            kind, rest = row[0], row[1:]
            bad = UsageError(f"{path}:{line}: bad {kind} record: {','.join(row)}")
            try:
                if kind == "title" and rest:
                    mech.title = rest[0]
                elif kind == "units" and len(rest) == 2 and rest[0] in ("length", "time"):
                    mech.units_given = True
                    setattr(mech, f"{rest[0]}_unit", rest[1])
                elif kind == "node":
                    if len(rest) != 4:
                        raise bad
                    mech.nodes[rest[0]] = tuple(parse_number(v) for v in rest[1:])
                elif kind == "analysis":
                    mech.analysis = tuple(rest)
                elif kind == "joint":
                    if len(rest) < 4 or rest[1] not in JOINT_AXES or len(rest) != 4 + 3 * JOINT_AXES[rest[1]]:
                        raise bad
                    values = [parse_number(v) for v in rest[4:]]
                    mech.joints.append(SpatialJoint(rest[0], rest[1], rest[2], rest[3], tuple(
                        tuple(values[k:k + 3]) for k in range(0, len(values), 3))))
                elif kind == "drive":
                    if len(rest) != 2 or rest[0] not in ("rotation", "stroke"):
                        raise bad
                    mech.drives.append((rest[0], rest[1]))
                elif kind == "track":
                    mech.tracked = list(rest)
            except ValueError:
                raise bad from None
    if mech.analysis[-1:] != ("spatial",):
        raise UsageError(f"{path}: not the mechanism.txt of a spatial run (its analysis record is "
                         f"'{','.join(mech.analysis)}')")
    return mech


@dataclass(frozen=True)
class Series:
    """The time history of one point or link: steps, times and named quantities."""

    name: str
    step: np.ndarray
    t: np.ndarray
    values: dict[str, np.ndarray]

    def has(self, quantity: str) -> bool:
        """Whether this series carries ``quantity`` (e.g. ``vx``)."""
        return quantity in self.values


def split_series(columns: dict[str, np.ndarray], key: str, quantities: tuple[str, ...]
                 ) -> dict[str, Series]:
    """Split long-format columns into one Series per name in column ``key``, by step."""
    present = tuple(q for q in quantities if q in columns)
    series = {}
    names = columns[key]
    for name in dict.fromkeys(names.tolist()):  # first-appearance order
        rows = np.flatnonzero(names == name)
        rows = rows[np.argsort(columns["step"][rows], kind="stable")]
        series[name] = Series(name=name, step=columns["step"][rows], t=columns["t"][rows],
                              values={q: columns[q][rows] for q in present})
    return series


def read_points(path: Path) -> dict[str, Series]:
    """Read a points.csv file (or an exact solution in the same format) into Series."""
    if not path.is_file():
        raise UsageError(f"{path}: no such file")
    _, columns = read_table(path, ("point",), ("step", "t", "point") + POSITION)
    if columns["step"].size == 0:
        raise UsageError(f"{path}: no steps were written (the file has only its header)")
    return split_series(columns, "point", POINT_QUANTITIES)


def read_links(path: Path) -> dict[str, Series]:
    """Read links.csv into Series (empty when the file is absent or has no rows)."""
    if not path.is_file():
        return {}
    _, columns = read_table(path, ("link",), ("step", "t", "link", "angle"))
    return split_series(columns, "link", LINK_QUANTITIES)


def read_steps(path: Path) -> dict[str, np.ndarray] | None:
    """Read steps.csv (None when absent); unknown columns are kept but not needed."""
    if not path.is_file():
        return None
    _, columns = read_table(path, (), ("step", "t", "iterations"))
    order = np.argsort(columns["step"], kind="stable")
    return {name: values[order] for name, values in columns.items()}


def read_mesh(path: Path) -> list[tuple[str, str, str]]:
    """Read mesh.csv as (link, node1, node2) triples (empty when the file is absent)."""
    if not path.is_file():
        return []
    _, columns = read_table(path, ("link", "node1", "node2"), ("link", "node1", "node2"))
    return list(zip(columns["link"].tolist(), columns["node1"].tolist(),
                    columns["node2"].tolist()))


@dataclass(frozen=True)
class Run:
    """Everything a FEKAP output directory holds that the plots need."""

    path: Path
    points: dict[str, Series]
    links: dict[str, Series]
    steps: dict[str, np.ndarray] | None
    mesh: list[tuple[str, str, str]]

    def point_quantities(self) -> tuple[str, ...]:
        """The point quantities present in this run, in FEKAP's order."""
        first = next(iter(self.points.values()))
        return tuple(q for q in POINT_QUANTITIES if first.has(q))

    def drawable_links(self) -> list[tuple[str, str, str]]:
        """The mesh links whose two end points are tracked (the others cannot be drawn)."""
        return [link for link in self.mesh if link[1] in self.points and link[2] in self.points]

    def step_numbers(self) -> np.ndarray:
        """All written step numbers, sorted."""
        return np.unique(np.concatenate([s.step for s in self.points.values()]))

    def positions_at(self, step: int) -> dict[str, tuple[float, float]]:
        """The (x, y) of every point written at ``step``."""
        where = {}
        for name, series in self.points.items():
            rows = np.flatnonzero(series.step == step)
            if rows.size:
                where[name] = (series.values["x"][rows[0]], series.values["y"][rows[0]])
        return where

    def time_of(self, step: int) -> float:
        """The time of a written step."""
        for series in self.points.values():
            rows = np.flatnonzero(series.step == step)
            if rows.size:
                return float(series.t[rows[0]])
        raise KeyError(step)


def load_run(directory: str | Path) -> Run:
    """Read a FEKAP output directory; raise UsageError when it cannot be plotted."""
    path = Path(directory)
    if not path.exists():
        raise UsageError(f"{path}: no such directory")
    if not path.is_dir():
        raise UsageError(f"{path}: not a directory (expected a FEKAP output directory)")
    points_file = path / "points.csv"
    if not points_file.is_file():
        raise UsageError(f"{path}: no points.csv (is this a FEKAP output directory?)")
    return Run(path=path, points=read_points(points_file), links=read_links(path / "links.csv"),
               steps=read_steps(path / "steps.csv"), mesh=read_mesh(path / "mesh.csv"))
