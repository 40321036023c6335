"""Read a FEKAP output directory in streaming fashion, for plots of runs of any length.

A run of 10^6 steps writes about 1 GB of CSV text; reading it whole into Python objects took
12 minutes and 10.6 GB. Here each file is read in chunks (pyarrow's streaming CSV reader) and every series is
reduced as it goes to at most about ``3 * MAX_BUCKETS`` rows: the steps are cut into
``MAX_BUCKETS`` buckets of equal width and each bucket keeps its first row and, for every
quantity, the rows of its smallest and its largest value (decimation that keeps extrema: a
spike of one step still shows). A run of at most ``MAX_BUCKETS`` written steps is kept whole.
Memory is bounded by the chunk size and the number of buckets, not by the run's length.

Files (see README.md, "What a run writes"):

- ``nodes.csv``: ``step,t,A.x,A.y,B.x,...``, every node's position at every written step;
- ``points.csv``: ``step,t,point,x,y[,vx,vy[,ax,ay]]``; ``links.csv``: ``step,t,link,angle[,...]``;
- ``steps.csv``: ``step,t,iterations,residual,cuts[,floor[,error_estimate]]``;
- ``mesh.csv``: ``link,node1,node2``; ``mechanism.txt``: title, units, supports, guides, drives,
  loads, masses, the analysis, the nodes' initial coordinates; whether the run is spatial
  (``analysis,kinematics,spatial``: its nodes.csv is ``step,t,A.x,A.y,A.z,B.x,...``, read
  whole with ``read_nodes(..., dim=3)``);
- ``joints.csv``: ``step,t,joint,angle,rate,acceleration`` (spatial runs);
- ``reactions.csv``: ``step,t,kind,link,node,fx,fy,m`` (kinetostatics, statics, dynamics).

Text is read with a tolerant decoding (UTF-8, else Latin-1: a title FEKAP accepted is never an
error here) and fields of any length (a 128 KiB node name) are taken.
"""

from __future__ import annotations

import csv
import io
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fekap.read import UsageError, parse_number

#: Buckets per series: a curve has at most about three times as many points.
MAX_BUCKETS = 1500
#: Bytes of a file parsed at a time.
BLOCK_BYTES = 1 << 24
#: Interior mesh points in nodes.csv are named LINK#k (k = 1 .. elements - 1 from the first end).
INTERIOR = "#"

# A node name, a title may be any length (the csv module's default limit is 128 KiB).
csv.field_size_limit(min(sys.maxsize, 2**31 - 1))


def read_text(path: Path) -> str:
    """A text file FEKAP wrote, decoded tolerantly: UTF-8, else Latin-1 (which takes any byte)."""
    data = Path(path).read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def first_line(path: Path) -> str:
    """The first line of a file (a CSV header), decoded as read_text does."""
    with open(path, "rb") as handle:
        data = handle.readline()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


@dataclass
class Mechanism:
    """What mechanism.txt and mesh.csv say about the model (for drawing and labelling)."""

    title: str = ""
    #: Without a units record (a deck without a units line) lengths and times are unlabelled.
    length_unit: str = "length"
    time_unit: str = "time"
    units_given: bool = False
    #: kinematics, kinetostatics, statics or dynamics ("" for a run of an older FEKAP).
    analysis: str = ""
    #: A spatial run (``analysis,kinematics,spatial``): drawn in three dimensions (fekap.plot3d,
    #: which reads its joints with fekap.read.read_spatial_mechanism).
    spatial: bool = False
    #: Dynamics: the integrator's name and rho_inf.
    integrator: str = ""
    rho_inf: float = float("nan")
    #: (link, first node, second node).
    links: list[tuple[str, str, str]] = field(default_factory=list)
    #: node -> fixed freedoms, e.g. "x y" or "x y rotation".
    supports: dict[str, str] = field(default_factory=dict)
    #: (name, slave node, x1, y1, x2, y2): fixed ground guides.
    guides: list[tuple[str, str, float, float, float, float]] = field(default_factory=list)
    #: (name, slave node, master links).
    slots: list[tuple[str, str, list[str]]] = field(default_factory=list)
    #: ("rotation", link, node) or ("x"|"y", node).
    drives: list[tuple[str, ...]] = field(default_factory=list)
    #: (node, fx, fy, m) at unit load factor (NaN: a run of an older FEKAP gives only the node).
    loads: list[tuple[str, float, float, float]] = field(default_factory=list)
    #: node -> point mass.
    masses: dict[str, float] = field(default_factory=dict)
    #: node -> initial (x, y), the undeformed geometry.
    initial: dict[str, tuple[float, float]] = field(default_factory=dict)
    tracked: list[str] = field(default_factory=list)

    @property
    def statics(self) -> bool:
        return self.analysis == "statics"

    @property
    def si(self) -> bool:
        """Lengths in metres and times in seconds: forces are newtons."""
        return self.units_given and self.length_unit == "m" and self.time_unit == "s"

    def unit(self, quantity: str) -> str:
        """The unit of a quantity of points.csv, links.csv, nodes.csv or reactions.csv, e.g.
        ``vx`` -> ``m/s``; in statics the rates are derivatives by the load factor."""
        length, time = self.length_unit, self.time_unit
        if self.statics:
            # d/d(load factor): the load factor has no unit.
            time_units = {"vx": length, "vy": length, "ax": length, "ay": length,
                          "omega": "rad", "alpha": "rad", "t": "-"}
            if quantity in time_units:
                return time_units[quantity]
        force = "N" if self.si else "force"
        return {"x": length, "y": length, "z": length, "vx": f"{length}/{time}", "vy": f"{length}/{time}",
                "vz": f"{length}/{time}", "ax": f"{length}/{time}²", "ay": f"{length}/{time}²",
                "az": f"{length}/{time}²", "angle": "rad",
                "omega": f"rad/{time}", "alpha": f"rad/{time}²", "t": time,
                "force": force, "moment": "N m" if self.si else f"{force} {length}",
                "energy": "J" if self.si else f"{force} {length}",
                "momentum": "N s" if self.si else f"{force} {time}",
                "angular momentum": "N m s" if self.si else f"{force} {length} {time}"}[quantity]

    def name(self, quantity: str) -> str:
        """How a quantity is called on an axis: in statics the time is the load factor and the
        rates are derivatives by it."""
        if not self.statics:
            return quantity
        return {"t": "load factor λ", "vx": "dx/dλ", "vy": "dy/dλ", "ax": "d²x/dλ²",
                "ay": "d²y/dλ²", "omega": "dθ/dλ", "alpha": "d²θ/dλ²"}.get(quantity, quantity)


def read_mechanism(directory: Path) -> Mechanism:
    """mechanism.txt and mesh.csv of a run (defaults for what is missing: an older run)."""
    mech = Mechanism()
    path = directory / "mechanism.txt"
    if path.is_file():
        for row in csv.reader(io.StringIO(read_text(path), newline="")):
            if not row:
                continue
            kind, rest = row[0], row[1:]
            try:
                if kind == "title" and rest:
                    mech.title = rest[0]
                elif kind == "units" and len(rest) >= 2:
                    mech.units_given = True
                    if rest[0] == "length":
                        mech.length_unit = rest[1]
                    elif rest[0] == "time":
                        mech.time_unit = rest[1]
                elif kind == "analysis" and rest:
                    mech.analysis = rest[0]
                    mech.spatial = "spatial" in rest[1:]
                    if len(rest) >= 3 and not mech.spatial:
                        mech.integrator, mech.rho_inf = rest[1], parse_number(rest[2])
                elif kind == "mass" and len(rest) >= 2:
                    mech.masses[rest[0]] = mech.masses.get(rest[0], 0.0) + parse_number(rest[1])
                elif kind == "node" and len(rest) >= 3:
                    mech.initial[rest[0]] = (parse_number(rest[1]), parse_number(rest[2]))
                elif kind == "support" and len(rest) >= 2:
                    mech.supports[rest[0]] = rest[1]
                elif kind == "guide" and len(rest) >= 6:
                    mech.guides.append((rest[0], rest[1], *(parse_number(v) for v in rest[2:6])))
                elif kind == "slot" and len(rest) >= 3:
                    mech.slots.append((rest[0], rest[1], rest[2:]))
                elif kind == "drive" and len(rest) >= 2:
                    mech.drives.append(tuple(rest))
                elif kind == "load" and rest:
                    values = [parse_number(v) for v in rest[1:4]] + [math.nan] * 3
                    mech.loads.append((rest[0], *values[:3]))
                elif kind == "track":
                    mech.tracked = list(rest)
            except ValueError:
                raise UsageError(f"{path}: bad {kind} record: {','.join(row)}") from None
    if not mech.units_given and not path.is_file():
        # A run of a FEKAP that wrote no mechanism.txt plotted in SI.
        mech.length_unit, mech.time_unit = "m", "s"
    mesh = directory / "mesh.csv"
    if mesh.is_file():
        rows = [r for r in csv.reader(io.StringIO(read_text(mesh), newline="")) if r]
        mech.links = [(r[0], r[1], r[2]) for r in rows[1:] if len(r) >= 3]
    return mech


def step_range(path: Path) -> tuple[int, int]:
    """The first and the last step of a CSV file of FEKAP's (header, then rows by step)."""
    with open(path, "rb") as handle:
        handle.readline()
        first = handle.readline()
        if not first.strip():
            raise UsageError(f"{path}: no steps were written (the file has only its header)")
        handle.seek(0, 2)
        size = handle.tell()
        # Back from the end until the tail holds a whole last row (a row can be long: a name of
        # any length).
        back = min(size, 65536)
        while True:
            handle.seek(size - back)
            tail = handle.read(back)
            if back == size or tail.rstrip().count(b"\n") >= 1:
                break
            back = min(size, 4 * back)
        lines = [line for line in tail.splitlines() if line.strip()]
    try:
        return int(first.split(b",")[0]), int(lines[-1].split(b",")[0])
    except ValueError:
        raise UsageError(f"{path}: the first field of a row is not a step number") from None


class Reducer:
    """Decimation that keeps extrema, fed with blocks of rows ``step, t, q1, q2, ...`` in step order."""

    def __init__(self, first: int, last: int, quantities: int, buckets: int = MAX_BUCKETS):
        self.first = first
        self.width = max(1, math.ceil((last - first + 1) / buckets))
        self.quantities = quantities
        self.rows: list[np.ndarray] = []
        self.masks: list[np.ndarray] = []
        self.carry: np.ndarray | None = None

    def feed(self, block: np.ndarray) -> None:
        """Add rows; those of the last bucket wait for the next block (it may go on there)."""
        if self.carry is not None and self.carry.size:
            block = np.vstack([self.carry, block])
        self.carry = None
        if not block.size:
            return
        if self.width == 1:
            self.rows.append(block)
            self.masks.append(np.full(len(block), -1, dtype=np.int64))
            return
        bucket = (block[:, 0] - self.first) // self.width
        tail = bucket == bucket[-1]
        self.carry = block[tail]
        self._reduce(block[~tail], bucket[~tail])

    def _reduce(self, block: np.ndarray, bucket: np.ndarray) -> None:
        count = len(block)
        if not count:
            return
        starts = np.flatnonzero(np.r_[True, bucket[1:] != bucket[:-1]])
        segment = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, count]))
        mask = np.zeros(count, dtype=np.int64)
        mask[starts] |= 1
        with np.errstate(invalid="ignore"):
            for column in range(self.quantities):
                values = block[:, 2 + column]
                for extreme in (np.fmin, np.fmax):
                    best = extreme.reduceat(values, starts)
                    hits = np.flatnonzero(values == best[segment])
                    if hits.size:
                        owner = segment[hits]
                        hits = hits[np.r_[True, owner[1:] != owner[:-1]]]
                        mask[hits] |= 1 << (column + 1)
        keep = mask != 0
        self.rows.append(block[keep])
        self.masks.append(mask[keep])

    def finish(self) -> tuple[np.ndarray, np.ndarray]:
        """All kept rows (in step order) and their masks (bit 0: first of a bucket; bit c + 1:
        an extreme of quantity c)."""
        if self.carry is not None and self.carry.size:
            block = self.carry
            self.carry = None
            self._reduce(block, (block[:, 0] - self.first) // self.width)
        if not self.rows:
            return np.empty((0, 2 + self.quantities)), np.empty(0, dtype=np.int64)
        return np.vstack(self.rows), np.concatenate(self.masks)


@dataclass
class Reduced:
    """One decimated series: the kept rows ``step, t, q...`` and which quantity each serves."""

    name: str
    quantities: tuple[str, ...]
    rows: np.ndarray
    masks: np.ndarray

    def has(self, quantity: str) -> bool:
        return quantity in self.quantities

    def curve(self, *quantities: str) -> tuple[np.ndarray, ...]:
        """(step, t, values...) of the rows that draw these quantities (extrema of each kept)."""
        want = 1
        for quantity in quantities:
            want |= 1 << (self.quantities.index(quantity) + 1)
        rows = self.rows[(self.masks & want) != 0]
        return (rows[:, 0].astype(np.int64), rows[:, 1],
                *(rows[:, 2 + self.quantities.index(q)] for q in quantities))


class _SlowPath(Exception):
    """A file with numbers in Fortran spellings that the fast parser does not take (1.0-100)."""


def _header(path: Path) -> list[str]:
    return [field.strip() for field in next(csv.reader([first_line(path)]), [])]


def _blocks(path: Path, key: str | None, slow: bool):
    """(names, numbers, columns) blocks of a FEKAP CSV file: the ``key`` column's values (or
    None), the other columns as a float array (empty fields NaN) and their names.

    Blocks of BLOCK_BYTES parsed by pyarrow's CSV reader with every column but ``key`` typed as
    float64 (pyarrow's own streaming reader held up to 400 MB for a 360 MB file); with ``slow``,
    every column read as text and converted by parse_number (Fortran spellings)."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    header = _header(path)
    keys = key if isinstance(key, tuple) else (key,)
    numeric = [c for c in header if c not in keys]
    types = {c: (pa.string() if slow or c in keys else pa.float64()) for c in header}
    # use_threads=False: the parse runs on this thread, and Arrow's CPU thread pool is never
    # started. A pool still alive when the interpreter exits aborts it at random (SIGABRT,
    # "terminate called without an active exception"), after a usage error's message too.
    options = dict(read_options=pacsv.ReadOptions(column_names=header, use_threads=False),
                   convert_options=pacsv.ConvertOptions(column_types=types, strings_can_be_null=False,
                                                        quoted_strings_can_be_null=False))
    try:
        for block in _byte_blocks(path):
            # A block of pyarrow's must hold a whole row, however long a name in it.
            options["read_options"].block_size = max(1 << 20, len(block) + 1)
            table = pacsv.read_csv(pa.BufferReader(block), **options)
            if isinstance(key, tuple):
                names = np.array(["|".join(parts) for parts in zip(
                    *(table.column(k).to_pylist() for k in key))], dtype=object)
            elif key:
                names = table.column(key).to_numpy()
            else:
                names = None
            numbers = np.empty((table.num_rows, len(numeric)))
            for index, name in enumerate(numeric):
                column = table.column(name)
                if slow:
                    numbers[:, index] = [parse_number(v) for v in column.to_pylist()]
                else:
                    numbers[:, index] = column.to_numpy()
            del table
            yield names, numbers, numeric
    except pa.ArrowInvalid as exc:
        if not slow and "conver" in str(exc).lower():
            raise _SlowPath() from None
        raise UsageError(f"{path}: not a FEKAP CSV table ({str(exc).splitlines()[0]})") from None
    except ValueError:
        raise UsageError(f"{path}: a field is not a number") from None


def _byte_blocks(path: Path):
    """The file after its header line in pieces of about BLOCK_BYTES, each ending at a line
    end: what is in memory at a time, whatever the file's size."""
    with open(path, "rb") as handle:
        handle.readline()
        rest = b""
        while True:
            data = handle.read(BLOCK_BYTES)
            if not data:
                break
            data = rest + data
            cut = data.rfind(b"\n") + 1
            rest = data[cut:]
            if cut:
                yield data[:cut]
        if rest.strip():
            yield rest


def _twice(read):
    """Run a reader on the fast path, and again on the slow one if the file needs it."""
    def wrapper(*args, **kwargs):
        try:
            return read(*args, slow=False, **kwargs)
        except _SlowPath:
            return read(*args, slow=True, **kwargs)
    wrapper.__doc__ = read.__doc__
    return wrapper


@_twice
def read_long(path: Path, key: str, known: tuple[str, ...], required: tuple[str, ...],
              buckets: int = MAX_BUCKETS, slow: bool = False) -> dict[str, Reduced]:
    """A long table (points.csv, links.csv, reactions.csv) as one decimated series per name in
    column ``key`` (or per combination of the columns of a tuple ``key``, joined by ``|``)."""
    header = _header(path)
    keys = key if isinstance(key, tuple) else (key,)
    missing = [c for c in ("step", "t", *keys) + required if c not in header]
    if missing:
        raise UsageError(f"{path}: missing column(s) {', '.join(missing)} in header '{','.join(header)}'")
    first, last = step_range(path)
    quantities = tuple(q for q in known if q in header)
    series: dict[str, Reducer] = {}
    for names, numbers, columns in _blocks(path, key, slow):
        numbers = numbers[:, [columns.index(c) for c in ("step", "t", *quantities)]]
        for name in dict.fromkeys(names.tolist()):
            if name not in series:
                series[name] = Reducer(first, last, len(quantities), buckets)
            series[name].feed(numbers[names == name])
    out = {}
    for name, reducer in series.items():
        rows, masks = reducer.finish()
        out[name] = Reduced(name, quantities, rows, masks)
    return out


@dataclass
class Nodes:
    """nodes.csv, decimated: every node's path, and every node's position at chosen steps."""

    names: list[str]
    paths: dict[str, Reduced]
    #: step -> (t, {node: (x, y)}) at the chosen steps (the first written step at or after each).
    frames: dict[int, tuple[float, dict[str, tuple[float, float]]]]
    first: int
    last: int


#: The coordinates of nodes.csv: a planar run's x, y; a spatial run's x, y, z.
COORDINATES = ("x", "y", "z")


@_twice
def read_nodes(path: Path, targets: list[int] | None = None, count: int = 0,
               buckets: int = MAX_BUCKETS, slow: bool = False, dim: int = 2) -> Nodes:
    """nodes.csv: decimated paths of every node and the positions at ``count`` evenly spread
    steps (or at the given target steps), in ``dim`` coordinates: 2, x and y (of a spatial
    run's nodes.csv too: a planar drawing of it), or 3, x, y and z (a spatial run's
    ``step,t,A.x,A.y,A.z,...``)."""
    header = _header(path)
    # A spatial run's nodes.csv has a z column after each y (A.x,A.y,A.z).
    width = 3 if len(header) > 4 and header[4].endswith(".z") else 2
    axes = COORDINATES[:width]
    if (header[:2] != ["step", "t"] or (len(header) - 2) % width
            or any(not c.endswith(f".{axes[k % width]}") for k, c in enumerate(header[2:]))):
        raise UsageError(f"{path}: expected the header step,t,A.x,A.y,... (A.x,A.y,A.z,... of a spatial run)")
    if dim > width:
        raise UsageError(f"{path}: no z columns (a spatial run's nodes.csv is step,t,A.x,A.y,A.z,...)")
    names = [c[:-2] for c in header[2::width]]
    first, last = step_range(path)
    if targets is None:
        targets = even_steps(first, last, count)
    pending = sorted(set(targets))
    frames: dict[int, tuple[float, dict[str, tuple[float, ...]]]] = {}
    reducers = {n: Reducer(first, last, dim, buckets) for n in names}
    for _, numbers, _ in _blocks(path, None, slow):
        if not len(numbers):
            continue
        for index, name in enumerate(names):
            reducers[name].feed(numbers[:, [0, 1, *range(2 + width * index, 2 + width * index + dim)]])
        steps = numbers[:, 0]
        while pending and pending[0] <= steps[-1]:
            row = numbers[int(np.searchsorted(steps, pending[0]))]
            frames[int(row[0])] = (float(row[1]), {
                n: tuple(float(v) for v in row[2 + width * i:2 + width * i + dim]) for i, n in enumerate(names)})
            pending.pop(0)
    paths = {}
    for name, reducer in reducers.items():
        rows, masks = reducer.finish()
        paths[name] = Reduced(name, COORDINATES[:dim], rows, masks)
    return Nodes(names, paths, dict(sorted(frames.items())), first, last)


@_twice
def read_deflections(path: Path, chains: dict[str, list[str]], buckets: int = MAX_BUCKETS,
                     slow: bool = False) -> Reduced:
    """Of each link in ``chains`` (its points in order, first node to second, as named in
    nodes.csv), at every written step: the interior point's signed distance from the chord with
    the largest size (positive to the left of the first -> second direction); decimated."""
    header = _header(path)
    columns = {c[:-2]: i for i, c in enumerate(header) if c.endswith(".x")}
    links = [link for link, chain in chains.items() if all(n in columns for n in chain)]
    first, last = step_range(path)
    reducer = Reducer(first, last, len(links), buckets)
    for _, numbers, _ in _blocks(path, None, slow):
        if not len(numbers):
            continue
        out = np.empty((len(numbers), 2 + len(links)))
        out[:, :2] = numbers[:, :2]
        for index, link in enumerate(links):
            xs = numbers[:, [columns[n] for n in chains[link]]]
            ys = numbers[:, [columns[n] + 1 for n in chains[link]]]
            dx, dy = xs[:, -1] - xs[:, 0], ys[:, -1] - ys[:, 0]
            length = np.hypot(dx, dy)
            length[length == 0] = np.nan
            # Cross product of the chord's unit vector with each point's offset from the start.
            side = (dx[:, None] * (ys[:, 1:-1] - ys[:, :1]) - dy[:, None] * (xs[:, 1:-1] - xs[:, :1]))
            side /= length[:, None]
            pick = np.nanargmax(np.abs(np.nan_to_num(side, nan=-1.0)), axis=1)
            out[:, 2 + index] = side[np.arange(len(side)), pick]
        reducer.feed(out)
    rows, masks = reducer.finish()
    return Reduced("deflection", tuple(links), rows, masks)


def even_steps(first: int, last: int, count: int, endpoint: bool = True) -> list[int]:
    """``count`` target steps spread evenly from first to last."""
    if count <= 0:
        return []
    if count == 1:
        return [first]
    return sorted(set(np.linspace(first, last, count, endpoint=endpoint).round().astype(int).tolist()))


def _read_table(path: Path, name: str, wanted: tuple[str, ...], required: tuple[str, ...],
                buckets: int, slow: bool) -> Reduced | None:
    """A wide table of one row per step (steps.csv, energy.csv) decimated: the ``wanted`` columns
    it has (every ``required`` one must be there), or None when absent or empty."""
    if not path.is_file():
        return None
    header = _header(path)
    missing = [c for c in ("step", "t", *required) if c not in header]
    if missing:
        raise UsageError(f"{path}: missing column(s) {', '.join(missing)}")
    try:
        first, last = step_range(path)
    except UsageError:
        return None
    quantities = tuple(q for q in wanted if q in header)
    reducer = Reducer(first, last, len(quantities), buckets)
    for _, numbers, columns in _blocks(path, None, slow):
        reducer.feed(numbers[:, [columns.index(c) for c in ("step", "t", *quantities)]])
    rows, masks = reducer.finish()
    return Reduced(name, quantities, rows, masks)


@_twice
def read_steps(path: Path, buckets: int = MAX_BUCKETS, slow: bool = False) -> Reduced | None:
    """steps.csv decimated (iterations, residual, cuts), or None when absent or empty."""
    return _read_table(path, "steps", ("iterations", "residual", "cuts"), ("iterations",), buckets, slow)


#: The columns of energy.csv (dynamics runs) after step, t.
ENERGY_COLUMNS = ("kinetic", "strain", "penalty", "gravity", "work_loads", "work_drives", "dissipated",
                  "balance", "px", "py", "angular")


@_twice
def read_energy(path: Path, buckets: int = MAX_BUCKETS, slow: bool = False) -> Reduced | None:
    """energy.csv of a dynamics run decimated, or None when absent or empty."""
    return _read_table(path, "energy", ENERGY_COLUMNS, ENERGY_COLUMNS, buckets, slow)
