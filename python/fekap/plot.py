"""Plot the results of a FEKAP run.

    scripts/plot.py OUTDIR [--only KIND ...] [--animate [auto|mp4|gif]] [--instants N]
                           [--magnify M] [--components] [--at T]

draws into OUTDIR:

- paths.png        the whole mechanism (every link, the supports, the sliders' guides) at a few
                   instants coloured by time (a colour bar), with the paths of the tracked points
                   highlighted and those of the other moving nodes faint; the loads as arrows, the
                   point masses as dots (area by mass), the support reactions as arrows at one
                   instant (--at, default the last); meshed links drawn through their mesh points
                   with the elastic deflection magnified (automatically, or --magnify M) and the
                   magnification stated (nodes.csv, mesh.csv, mechanism.txt, reactions.csv);
- reactions.png    runs that write reactions.csv (kinetostatics, statics, dynamics): the drives'
                   torque or force against time and against the drive's angle or stroke, the
                   supports' and joints' force magnitudes (components with --components), the
                   sliders' guide forces;
- deflection.png   runs with meshed links in nodes.csv: the largest transverse deflection of each
                   meshed link from its chord, against time;
- history_<P>.png  time histories of x, y (vx, vy, ax, ay when computed) of each tracked point P;
- angles.png       time histories of the link angles (omega, alpha when computed);
- iterations.png   Newton iterations (and the final residual) per step;
- energy.png       dynamics runs (energy.csv): kinetic, strain, penalty and gravity energy, the work of
                   loads and drives and the damping's dissipation, their balance (the integrator's
                   numerical dissipation), linear and angular momentum;
- motion.mp4       with --animate: the mechanism moving, with the time, the drive's value (an
                   angle wrapped to (-180, 180] deg with its turn) and the tracked points' trails,
                   the legend and the time box beside the drawing (motion.gif where ffmpeg is
                   missing, or asked for).

Every figure carries the deck's title and units on its axes (the deck's OUTPut `units` line; a
deck without one has its lengths labelled "length" and its times "time"). Statics runs are
plotted against the load factor λ, their rates as derivatives by it. Titles and names are drawn
as plain text (no mathtext: a $ is a dollar). Runs of any length are read in streaming fashion and each curve is decimated to
a few thousand points keeping every extremum (fekap.stream). A quantity constant to
round-off is drawn as a flat line and labelled so, instead of autoscaled noise.

A spatial run (mechanism.txt's ``analysis,kinematics,spatial`` record) is drawn by fekap.plot3d
instead: views.png (three orthographic views and an axonometric one), joints.png (joints.csv),
history_<P>.png with x, y and z, iterations.png and the animation of the four views.

Kinds for --only: paths, history, velocity, acceleration, angles, iterations, energy, reactions,
deflection, and of spatial runs views (the same as paths there) and joints. ``velocity`` and
``acceleration`` draw the history figures with only those panels. Bad arguments give a one-line
message on stderr and exit status 2.
"""

from __future__ import annotations

import math
import re
import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fekap import read as fc
from fekap import stream as fs

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PROG = "plot.py"
KINDS = ("paths", "history", "velocity", "acceleration", "angles", "iterations", "energy", "reactions",
         "deflection", "views", "joints")
#: Kinds drawn for spatial runs only (fekap.plot3d).
SPATIAL_KINDS = ("views", "joints")
#: How to ask the deck for the missing quantities (the hint in the error message).
MISSING_HINT = {
    "velocity": "this run computed no velocities; ask for them in the deck's ANALysis block "
                "(compute positions velocities) or with fekap --compute positions,velocities",
    "acceleration": "this run computed no accelerations; ask for them in the deck's ANALysis block "
                    "(compute positions velocities accelerations) or with fekap --compute accelerations",
}
GROUPS = {"position": fc.POSITION, "velocity": fc.VELOCITY, "acceleration": fc.ACCELERATION}
STYLE = Path(__file__).resolve().with_name("fekap.mplstyle")
#: Frames of an animation at most, and its length in seconds when it has that many.
MAX_FRAMES = 150
MOVIE_SECONDS = 10.0
#: A quantity whose range is below this fraction of its group's magnitude is constant to round-off.
ROUND_OFF = 1e-9
#: Automatic magnification: deflections below SMALL_SHAPE of the model's extent are magnified to
#: about SHOWN_SHAPE of it (rounded down to 1, 2 or 5 times a power of ten).
SMALL_SHAPE = 0.01
SHOWN_SHAPE = 0.08
#: Joint and support forces drawn at most (the largest); the figure says how many there are.
MAX_FORCE_CURVES = 10
#: An acceleration that differs from the central differences of the written velocity by more
#: than this fraction of its largest value is not resolved by the output step.
UNRESOLVED_MISFIT = 0.2


def parse_args(argv: list[str] | None):
    """The command line of plot.py."""
    parser = fc.Parser(prog=PROG, description="Plot the results of a FEKAP run into its "
                       "output directory (PNG files, and an MP4 or GIF with --animate).")
    parser.add_argument("outdir", help="the FEKAP output directory (holds points.csv)")
    parser.add_argument("--only", nargs="+", action="extend", choices=KINDS, metavar="KIND",
                        help=f"draw only these figures: {', '.join(KINDS)}")
    parser.add_argument("--animate", nargs="?", const="auto", choices=("auto", "mp4", "gif"),
                        help="also write the mechanism moving: motion.mp4 (ffmpeg), or motion.gif "
                             "where ffmpeg is missing (auto, the default) or when asked for")
    parser.add_argument("--instants", type=int, default=4, metavar="N",
                        help="how many instants of the mechanism paths.png shows (default 4)")
    parser.add_argument("--magnify", type=float, metavar="M",
                        help="magnification of the meshed links' elastic deflection in paths.png "
                             "and the animation (default: chosen from its size; 1: to scale)")
    parser.add_argument("--components", action="store_true",
                        help="reactions.png: the x and y components of the support, joint and "
                             "slider forces besides their magnitudes")
    parser.add_argument("--at", type=float, metavar="T",
                        help="the time (load factor in statics) of the support reaction arrows in "
                             "paths.png (default: the last written step)")
    args = parser.parse_args(argv)
    if args.instants < 0:
        parser.error(f"--instants must be 0 or more, not {args.instants}")
    if args.magnify is not None and not (np.isfinite(args.magnify) and args.magnify > 0):
        parser.error(f"--magnify must be a positive number, not {args.magnify}")
    return args


def pyplot():
    """pyplot on the Agg backend, in FEKAP's style."""
    plt = fc.pyplot()
    plt.style.use(STYLE)
    return plt


#: Names longer than this are shortened in figures and file names.
LONG_NAME = 40


def safe_name(name: str) -> str:
    """A point name usable in a file name (a long one shortened, with a digest of it)."""
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"
    if len(name) > LONG_NAME:
        import hashlib

        name = f"{name[:LONG_NAME // 2]}-{hashlib.sha1(name.encode()).hexdigest()[:12]}"
    return name


def short(name: str) -> str:
    """A node, link or point name as a figure shows it: a long one cut, with its length."""
    if len(name) <= LONG_NAME:
        return name
    return f"{name[:LONG_NAME // 2]}... ({len(name)} characters)"


# --------------------------------------------------------------------------- the run

class Run:
    """A FEKAP output directory, read in streaming fashion."""

    def __init__(self, directory: str | Path, instants: int, frames: int,
                 magnify: float | None = None):
        path = Path(directory)
        if not path.exists():
            raise fc.UsageError(f"{path}: no such directory")
        if not path.is_dir():
            raise fc.UsageError(f"{path}: not a directory (expected a FEKAP output directory)")
        if not (path / "points.csv").is_file():
            raise fc.UsageError(f"{path}: no points.csv (is this a FEKAP output directory?)")
        self.path = path
        self.mech = fs.read_mechanism(path)
        self.title = self.mech.title or path.name
        self._points: dict[str, fs.Reduced] | None = None
        self._links: dict[str, fs.Reduced] | None = None
        self._reactions: dict[str, fs.Reduced] | None = None
        nodes_file = path / "nodes.csv"
        points_file = path / "points.csv"
        source = nodes_file if nodes_file.is_file() else points_file
        first, last = fs.step_range(source)
        self.instant_targets = fs.even_steps(first, last, instants, endpoint=False) if instants else []
        if instants == 1:
            self.instant_targets = [first]
        elif instants > 1 and self.mech.statics:
            # The last instant of a statics run is its full load.
            self.instant_targets = fs.even_steps(first, last, instants)
        self.frame_targets = fs.even_steps(first, last, min(frames, last - first + 1)) if frames else []
        targets = sorted(set(self.instant_targets) | set(self.frame_targets) | {first, last})
        if nodes_file.is_file():
            self.nodes = fs.read_nodes(nodes_file, targets)
        else:
            # A run written before nodes.csv existed: its tracked points stand in for the nodes.
            self.nodes = nodes_from_points(self.points, targets)
        if not self.mech.tracked:
            self.mech.tracked = list(self.points)
        self.chains = link_chains(self.mech.links, self.nodes.names)
        self.size = model_size(self)
        self.magnification, self.shape_kind = choose_magnification(self, magnify)

    @property
    def points(self) -> dict[str, fs.Reduced]:
        if self._points is None:
            self._points = fs.read_long(self.path / "points.csv", "point", fc.POINT_QUANTITIES,
                                        fc.POSITION)
            if not self._points:
                raise fc.UsageError(f"{self.path / 'points.csv'}: no steps were written")
        return self._points

    @property
    def links(self) -> dict[str, fs.Reduced]:
        if self._links is None:
            file = self.path / "links.csv"
            # A spatial run's links.csv holds rotations (q0, ...), not planar angles: none drawn.
            planar = file.is_file() and "angle" in fs.first_line(file).strip().split(",")
            try:
                self._links = fs.read_long(file, "link", fc.LINK_QUANTITIES, ("angle",)) if planar else {}
            except fc.UsageError as exc:
                if "only its header" not in str(exc):
                    raise
                self._links = {}
        return self._links

    @property
    def reactions(self) -> dict[str, fs.Reduced]:
        """reactions.csv as one series per row kind and place, named ``kind|link|node``."""
        if self._reactions is None:
            file = self.path / "reactions.csv"
            try:
                self._reactions = (fs.read_long(file, ("kind", "link", "node"), ("fx", "fy", "m"),
                                                ("fx", "fy", "m")) if file.is_file() else {})
            except fc.UsageError as exc:
                if "only its header" not in str(exc):
                    raise
                self._reactions = {}
        return self._reactions

    def frame(self, target: int) -> tuple[int, float, dict[str, tuple[float, float]]]:
        """The written step at or after ``target`` with its time and every node's position."""
        steps = list(self.nodes.frames)
        index = min(int(np.searchsorted(steps, target)), len(steps) - 1)
        step = steps[index]
        t, where = self.nodes.frames[step]
        return step, t, where

    def drawable_links(self) -> list[tuple[str, str, str]]:
        """The links whose two end nodes have positions."""
        names = set(self.nodes.names)
        return [link for link in self.mech.links if link[1] in names and link[2] in names]

    def meshed(self) -> list[str]:
        """The links drawn through interior mesh points (nodes.csv's LINK#k)."""
        return [link for link, chain in self.chains.items() if len(chain) > 2]

    def shape(self, where: dict[str, tuple[float, float]]) -> dict[str, tuple[float, float]]:
        """The positions drawn for one instant: with a magnification, the deflection from the
        undeformed geometry (statics) or the meshed links' deviation from their chords (other
        analyses) times it."""
        if self.magnification == 1.0 or not self.shape_kind:
            return where
        m = self.magnification
        drawn = dict(where)
        if self.shape_kind == "displacement":
            for name, (x0, y0) in self.reference().items():
                if name in where:
                    x, y = where[name]
                    drawn[name] = (x0 + m * (x - x0), y0 + m * (y - y0))
            return drawn
        for chain in self.chains.values():
            if len(chain) <= 2 or chain[0] not in where or chain[-1] not in where:
                continue
            a, b = np.array(where[chain[0]]), np.array(where[chain[-1]])
            for k, name in enumerate(chain[1:-1], start=1):
                if name in where:
                    c = a + (b - a) * k / (len(chain) - 1)
                    drawn[name] = tuple(c + m * (np.array(where[name]) - c))
        return drawn

    def reference(self) -> dict[str, tuple[float, float]]:
        """The undeformed geometry: the named nodes' initial coordinates and the interior mesh
        points evenly between their link's ends (as the mesh places them)."""
        initial = dict(self.mech.initial)
        for chain in self.chains.values():
            if chain[0] in initial and chain[-1] in initial and len(chain) > 2:
                a, b = np.array(initial[chain[0]]), np.array(initial[chain[-1]])
                for k, name in enumerate(chain[1:-1], start=1):
                    initial[name] = tuple(a + (b - a) * k / (len(chain) - 1))
        return initial

    def magnification_text(self) -> str:
        """What the drawing of the elastic shape is, for the figure."""
        if not self.shape_kind:
            return ""
        what = ("deflections" if self.shape_kind == "displacement"
                else "link deflections from their chords")
        if self.magnification == 1.0:
            return f"{what} to scale (magnification 1)"
        return f"{what} magnified {self.magnification:g} times"

    def unit(self, quantity: str) -> str:
        return self.mech.unit(quantity)

    def label(self, quantity: str) -> str:
        """An axis label with its unit, e.g. ``vx (m/s)``, ``dx/dλ (m)`` in statics."""
        return f"{self.mech.name(quantity)} ({self.unit(quantity)})"


def link_chains(links: list[tuple[str, str, str]], names: list[str]) -> dict[str, list[str]]:
    """Each link's points in order: its first node, its interior mesh points LINK#1, LINK#2, ...
    when nodes.csv has them, its second node."""
    present = set(names)
    chains = {}
    for link, node1, node2 in links:
        if node1 not in present or node2 not in present:
            continue
        interior = []
        k = 1
        while f"{link}{fs.INTERIOR}{k}" in present:
            interior.append(f"{link}{fs.INTERIOR}{k}")
            k += 1
        chains[link] = [node1, *interior, node2]
    return chains


def nice_down(value: float) -> float:
    """The largest 1, 2 or 5 times a power of ten at most ``value``."""
    exponent = math.floor(math.log10(value))
    for mantissa in (5, 2, 1):
        if mantissa * 10.0**exponent <= value * (1 + 1e-12):
            return mantissa * 10.0**exponent
    return 10.0**exponent


def choose_magnification(run: Run, wanted: float | None) -> tuple[float, str]:
    """The deflection magnification and what it magnifies: ``displacement`` (statics: from the
    undeformed geometry), ``chord`` (meshed links' deviation from their chords) or ``""`` (no
    elastic shape to draw: rigid links, kinematics)."""
    if run.mech.statics and run.mech.initial:
        kind = "displacement"
    elif any(len(chain) > 2 for chain in run.chains.values()):
        kind = "chord"
    else:
        return 1.0, ""
    if wanted is not None:
        return float(wanted), kind
    largest = 0.0
    for _, where in run.nodes.frames.values():
        if kind == "displacement":
            for name, (x0, y0) in run.reference().items():
                if name in where:
                    largest = max(largest, math.hypot(where[name][0] - x0, where[name][1] - y0))
        else:
            for chain in run.chains.values():
                largest = max(largest, chord_deviation(chain, where))
    if not (largest > 0 and math.isfinite(largest)) or largest >= SMALL_SHAPE * run.size:
        return 1.0, kind
    return max(1.0, nice_down(SHOWN_SHAPE * run.size / largest)), kind


def chord_deviation(chain: list[str], where: dict[str, tuple[float, float]]) -> float:
    """The largest distance of a link's interior points from where the chord puts them."""
    if len(chain) <= 2 or any(name not in where for name in chain):
        return 0.0
    points = np.array([where[name] for name in chain])
    fractions = np.linspace(0, 1, len(chain))[:, None]
    chord = points[0] + (points[-1] - points[0]) * fractions
    return float(np.max(np.hypot(*(points - chord).T)))


def nodes_from_points(points: dict[str, fs.Reduced], targets: list[int]) -> fs.Nodes:
    """Nodes made of the tracked points (for a run without nodes.csv)."""
    paths = {name: fs.Reduced(name, ("x", "y"), series.rows[:, :4],
                              np.where(series.masks == -1, -1, series.masks & 0b111))
             for name, series in points.items()}
    frames: dict[int, tuple[float, dict[str, tuple[float, float]]]] = {}
    first_series = next(iter(points.values()))
    steps = first_series.rows[:, 0]
    for target in targets:
        index = min(int(np.searchsorted(steps, target)), len(steps) - 1)
        step = int(steps[index])
        where = {}
        for name, series in points.items():
            rows = np.flatnonzero(series.rows[:, 0] == step)
            if rows.size:
                where[name] = (float(series.rows[rows[0], 2]), float(series.rows[rows[0], 3]))
        frames[step] = (float(first_series.rows[index, 1]), where)
    first, last = int(steps[0]), int(steps[-1])
    return fs.Nodes(list(points), paths, dict(sorted(frames.items())), first, last)


def is_fixed(series: fs.Reduced) -> bool:
    """Whether a node never moves (a ground pivot)."""
    x, y = series.rows[:, 2], series.rows[:, 3]
    if not x.size:
        return True
    extent = max(np.nanmax(x) - np.nanmin(x), np.nanmax(y) - np.nanmin(y))
    scale = max(1.0, float(np.nanmax(np.abs(np.concatenate([x, y])))))
    return bool(extent <= 1e-12 * scale)


def motion_box(run: Run) -> tuple[np.ndarray, np.ndarray]:
    """The lower left and upper right corners of every node's path over the run (the guides
    are not part of it: a long guide does not squeeze the mechanism)."""
    lows, highs = [], []
    for series in run.nodes.paths.values():
        if series.rows.size and np.isfinite(series.rows[:, 2:4]).any():
            lows.append(np.nanmin(series.rows[:, 2:4], axis=0))
            highs.append(np.nanmax(series.rows[:, 2:4], axis=0))
    if not lows:
        return np.zeros(2), np.ones(2)
    return np.min(lows, axis=0), np.max(highs, axis=0)


def model_size(run: Run) -> float:
    """The extent of the mechanism over its motion (for symbol, arrow and frame sizes): the
    larger side of the box of every node's path, never a guide's length."""
    low, high = motion_box(run)
    size = float(np.max(high - low))
    if size > 0 and math.isfinite(size):
        return size
    return max(1.0, float(np.max(np.abs(high))))


# --------------------------------------------------------------------------- drawing the mechanism

def draw_ground(ax, run: Run, size: float) -> None:
    """Supports (a hatched ground triangle under each supported node) and ground guides; the
    symbols are sized from the model's extent."""
    from matplotlib.patches import Polygon

    start = run.frame(run.nodes.first)[2] if run.nodes.frames else {}
    h = 0.045 * size
    for node in run.mech.supports:
        if node not in start:
            continue
        x, y = start[node]
        ax.add_patch(Polygon([(x, y), (x - 0.7 * h, y - h), (x + 0.7 * h, y - h)], closed=True,
                             fc="0.85", ec="0.2", lw=1.0, zorder=1.5))
        ax.plot([x - 1.1 * h, x + 1.1 * h], [y - h, y - h], color="0.2", lw=1.2, zorder=1.5)
        for k in range(5):
            u = x - 1.1 * h + k * 0.5 * h
            ax.plot([u, u - 0.35 * h], [y - h, y - 1.4 * h], color="0.35", lw=0.8, zorder=1.5)
    for _name, slave, x1, y1, x2, y2 in run.mech.guides:
        ax.plot([x1, x2], [y1, y2], color="0.25", lw=4.5, alpha=0.35, solid_capstyle="butt",
                zorder=1.2, label=f"ground guide of {slave}")


def link_xy(run: Run, chain: list[str], where: dict[str, tuple[float, float]]
            ) -> tuple[list[float], list[float]] | None:
    """The x and y of a link's points at one instant (None when an end is missing)."""
    if chain[0] not in where or chain[-1] not in where:
        return None
    points = [where[name] for name in chain if name in where]
    return [p[0] for p in points], [p[1] for p in points]


def draw_links(ax, run: Run, where: dict[str, tuple[float, float]], color, alpha: float,
               label: str | None, lw: float = 2.6) -> list:
    """Every link of the mechanism at one instant: through its mesh points when nodes.csv has
    them (the elastic shape, magnified as run.shape says), its end nodes marked."""
    artists = []
    drawn = run.shape(where)
    for chain in run.chains.values():
        xy = link_xy(run, chain, drawn)
        if xy is None:
            continue
        x, y = xy
        artists += ax.plot(x, y, "-", color=color, lw=lw, alpha=alpha, solid_capstyle="round",
                           zorder=2, label=label)
        artists += ax.plot([x[0], x[-1]], [y[0], y[-1]], "o", color=color, ms=4.5, alpha=alpha,
                           zorder=2.1, mfc="white")
        label = None  # one legend entry per instant
    return artists


def draw_paths(ax, run: Run) -> None:
    """Paths of the tracked points (coloured) and of the other moving named nodes (faint)."""
    tracked = [n for n in run.mech.tracked if n in run.nodes.paths]
    for name, series in run.nodes.paths.items():
        if name in tracked or fs.INTERIOR in name or is_fixed(series):
            continue
        _, _, x, y = series.curve("x", "y")
        ax.plot(x, y, ":", color="0.55", lw=0.9, zorder=1.8)
    reference = run.reference() if run.shape_kind == "displacement" else {}
    for index, name in enumerate(tracked):
        series = run.nodes.paths[name]
        color = f"C{index % 10}"
        _, _, x, y = series.curve("x", "y")
        if name in reference and run.magnification != 1:
            # The path magnified as the shapes are: from the undeformed position.
            (x0, y0), m = reference[name], run.magnification
            x, y = x0 + m * (x - x0), y0 + m * (y - y0)
        if is_fixed(series):
            ax.plot(x[:1], y[:1], "s", color=color, ms=7, zorder=3, label=f"{short(name)} (fixed)")
        else:
            ax.plot(x, y, "-", color=color, lw=1.8, zorder=3, label=f"path of {short(name)}")


def draw_loads_and_masses(ax, run: Run, where: dict[str, tuple[float, float]]) -> None:
    """The loads as arrows (their direction at unit load factor) ending at their node, the
    point masses as dots whose area grows with the mass."""
    size = run.size
    drawn = run.shape(where)
    loads = [(node, fx, fy, m) for node, fx, fy, m in run.mech.loads if node in drawn]
    for node, fx, fy, moment in loads:
        x, y = drawn[node]
        norm = math.hypot(fx, fy) if math.isfinite(fx) and math.isfinite(fy) else 0.0
        if norm > 0:
            dx, dy = 0.14 * size * fx / norm, 0.14 * size * fy / norm
            ax.annotate("", xy=(x, y), xytext=(x - dx, y - dy), zorder=6,
                        arrowprops=dict(arrowstyle="-|>", color="C3", lw=2.0, mutation_scale=14))
        if math.isfinite(moment) and moment != 0:
            # A moment load: a ring around its node.
            ax.plot([x], [y], "o", ms=16, mfc="none", mec="C3", mew=2.0, zorder=6)
    if loads:
        moments = any(math.isfinite(m) and m != 0 for *_, m in loads)
        forces = any(math.hypot(fx, fy) > 0 for _, fx, fy, _ in loads
                     if math.isfinite(fx) and math.isfinite(fy))
        what = ", ".join(w for w, there in (("forces: arrows (direction)", forces),
                                            ("moments: rings", moments)) if there)
        ax.plot([], [], "-", color="C3", lw=2.0, label=f"loads ({what})")
    masses = {node: mass for node, mass in run.mech.masses.items() if node in drawn and mass > 0}
    if masses:
        largest = max(masses.values())
        xs = [drawn[node][0] for node in masses]
        ys = [drawn[node][1] for node in masses]
        areas = [30 + 220 * mass / largest for mass in masses.values()]
        ax.scatter(xs, ys, s=areas, color="C4", alpha=0.75, zorder=5, edgecolors="0.2",
                   label=f"point masses (area by mass, largest {largest:.3g})")


def reaction_instant(run: Run, at: float | None) -> int | None:
    """The written step of the support reaction arrows: the last, or the first at or after
    time ``at``."""
    supports = [s for name, s in run.reactions.items() if name.startswith("support|")]
    if not supports:
        return None
    steps, t = supports[0].rows[:, 0], supports[0].rows[:, 1]
    if at is None:
        return int(steps[-1])
    index = min(int(np.searchsorted(t, at - 1e-12 * max(1.0, abs(at)))), len(steps) - 1)
    return int(steps[index])


def draw_support_reactions(ax, run: Run, step: int) -> None:
    """Each support's reaction force at one step as an arrow pointing at the support, the
    largest 0.15 of the model's extent long."""
    _, _, where = run.frame(step)
    drawn = run.shape(where)
    forces = []
    for name, series in run.reactions.items():
        kind, _, node = name.split("|", 2)
        if kind != "support" or node not in drawn:
            continue
        rows = np.flatnonzero(series.rows[:, 0] == step)
        if rows.size:
            fx, fy = series.rows[rows[0], 2:4]
            if np.isfinite(fx) and np.isfinite(fy):
                forces.append((node, float(fx), float(fy), float(series.rows[rows[0], 1])))
    largest = max((math.hypot(fx, fy) for _, fx, fy, _ in forces), default=0.0)
    if largest <= 0:
        return
    scale = 0.15 * run.size / largest
    for node, fx, fy, _ in forces:
        x, y = drawn[node]
        ax.annotate("", xy=(x, y), xytext=(x - fx * scale, y - fy * scale), zorder=6,
                    arrowprops=dict(arrowstyle="-|>", color="0.1", lw=2.2, mutation_scale=14))
    time = forces[0][3]
    ax.plot([], [], "-", color="0.1", lw=2.2,
            label=f"support reactions at {run.mech.name('t')} = {time:.4g} "
                  f"(largest {largest:.3g} {run.unit('force')})")


def motion_limits(run: Run, instants: list[dict[str, tuple[float, float]]]
                  ) -> tuple[tuple[float, float], tuple[float, float]]:
    """Axis limits around the nodes' motion and the drawn (magnified) shapes, with a margin for
    the ground symbols; a guide reaching beyond is cut at the frame."""
    low, high = motion_box(run)
    for where in instants:
        drawn = np.array([xy for xy in run.shape(where).values() if np.isfinite(xy).all()])
        if drawn.size:
            low, high = np.minimum(low, drawn.min(axis=0)), np.maximum(high, drawn.max(axis=0))
    pad = 0.08 * run.size
    xlim, ylim = [low[0] - pad, high[0] + pad], [low[1] - 1.5 * pad, high[1] + pad]
    # A frame between 2.6 / 6.4 and 7.5 / 6.4 as high as wide (the drawing's sizes): a flat
    # or a tall mechanism is centred in the wider span.
    aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    for limits, factor in ((ylim, 2.6 / 6.4 / aspect), (xlim, aspect / (7.5 / 6.4))):
        if factor > 1:
            middle, half = 0.5 * (limits[0] + limits[1]), 0.5 * (limits[1] - limits[0]) * factor
            limits[:] = [middle - half, middle + half]
    return (xlim[0], xlim[1]), (ylim[0], ylim[1])


def mechanism_axes(ax, run: Run) -> None:
    """Equal scales, axis labels with units."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(run.label("x"))
    ax.set_ylabel(run.label("y"))


def plot_paths(run: Run, at: float | None = None) -> Figure:
    """The whole mechanism at a few instants (coloured by time, with a colour bar), the tracked
    points' paths highlighted, loads, masses and support reactions; the drawing fitted to the
    motion, the legend below it."""
    from matplotlib import cm
    from matplotlib.colors import ListedColormap, Normalize
    from matplotlib.transforms import offset_copy

    plt = pyplot()
    instants = [run.frame(target) for target in run.instant_targets]
    instants = list({step: (step, t, where) for step, t, where in instants}.values())
    xlim, ylim = motion_limits(run, [where for _, _, where in instants])
    # The drawing 6.4 inches wide and as high as the motion's aspect asks (2.6 to 7.5).
    width = 6.4
    height = float(np.clip(width * (ylim[1] - ylim[0]) / (xlim[1] - xlim[0]), 2.6, 7.5))
    fig = plt.figure(figsize=(width + 2.2, height + 1.4))
    ax = fig.add_axes((0.8 / (width + 2.2), 0.35 / (height + 1.4), width / (width + 2.2), height / (height + 1.4)))
    size = run.size
    draw_ground(ax, run, size)
    draw_paths(ax, run)
    t_first, t_last = run.nodes.frames[min(run.nodes.frames)][0], run.nodes.frames[max(run.nodes.frames)][0]
    norm = Normalize(t_first, t_last if t_last > t_first else t_first + 1)
    # viridis without its palest yellows (faint on white).
    cmap = ListedColormap(plt.get_cmap("viridis")(np.linspace(0.0, 0.85, 256)), name="instants")
    for _step, t, where in instants:
        draw_links(ax, run, where, cmap(norm(t)), 0.85, None)
    if instants:
        draw_loads_and_masses(ax, run, instants[-1][2])
        step = reaction_instant(run, at)
        if step is not None:
            draw_support_reactions(ax, run, step)
        # Node names at the first instant.
        shown = run.shape(instants[0][2])
        for name, (x, y) in shown.items():
            if fs.INTERIOR in name:
                continue
            if any(name in link[1:] for link in run.drawable_links()) or name in run.mech.tracked:
                ax.annotate(short(name), (x, y), xytext=(5, 5), textcoords="offset points",
                            fontsize="small", color="0.1", zorder=5,
                            bbox=dict(boxstyle="round,pad=0.12", fc="white", ec="none", alpha=0.7))
    mechanism_axes(ax, run)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal", adjustable="box")
    if instants:
        # The colour bar beside the drawing, as high as it is once its aspect is applied.
        fig.canvas.draw()
        box = ax.get_position()
        bar_ax = fig.add_axes((box.x1 + 0.02, box.y0, 0.025, box.height), label="<colorbar>")
        bar = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), cax=bar_ax)
        bar.set_label(f"instant: {run.label('t')}")
        bar.set_ticks([t for _, t, _ in instants])
        bar.ax.set_yticklabels([f"{t:.4g}" for _, t, _ in instants])
    fig.suptitle(run.title)
    what = "the mechanism at " + (f"{len(instants)} instants" if instants else "no instant")
    title = f"{what}, paths of the tracked points"
    if run.magnification_text():
        title += f"\n{run.magnification_text()}"
    ax.set_title(title, color="0.3")
    handles, _ = ax.get_legend_handles_labels()
    if handles:
        # Below the x axis's label, whatever the drawing's height.
        ax.legend(loc="upper left", bbox_to_anchor=(0.0, 0.0), ncol=2, fontsize="small",
                  bbox_transform=offset_copy(ax.transAxes, fig, y=-42, units="points"))
    return fig


# --------------------------------------------------------------------------- time histories

def round_off_floor(ax, values: np.ndarray, scale: float) -> None:
    """Draw a quantity that is constant to round-off as constant: a y range of a few percent of
    its group's magnitude around it, and a note with the actual spread."""
    finite = values[np.isfinite(values)]
    if not finite.size:
        return
    spread = float(finite.max() - finite.min())
    scale = max(scale, float(np.max(np.abs(finite))), 1e-300)
    if spread > ROUND_OFF * scale:
        return
    centre = float(0.5 * (finite.max() + finite.min()))
    half = 0.05 * scale if scale > 0 else 1.0
    ax.set_ylim(centre - half, centre + half)
    ax.text(0.02, 0.92, f"constant to round-off (spread {spread:.1e})", transform=ax.transAxes,
            fontsize="small", color="0.3", va="top")


def time_axis(ax) -> None:
    """A readable time axis: few, round ticks."""
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(nbins=7, steps=[1, 2, 2.5, 5, 10]))


def history_groups(run: Run, kinds: set[str] | None, quantities: dict[str, tuple[str, ...]] = GROUPS) -> list[str]:
    """The quantity groups (position, velocity, acceleration) the history figures show;
    `quantities` names each group's components (x, y here; x, y, z for a spatial run)."""
    first = next(iter(run.points.values()))
    available = [g for g, names in quantities.items() if all(first.has(q) for q in names)]
    if kinds is None or "history" in kinds:
        return available
    wanted = [g for g in ("velocity", "acceleration") if g in kinds]
    for group in wanted:
        if group not in available:
            raise fc.UsageError(MISSING_HINT[group])
    return wanted


def plot_history(run: Run, series: fs.Reduced, groups: list[str],
                 quantities: dict[str, tuple[str, ...]] = GROUPS) -> Figure:
    """Stacked time histories of one point: a row per group, its components
    (`quantities`: x and y here, x, y and z for a spatial run) side by side."""
    plt = pyplot()
    columns = len(quantities["position"])
    fig, axes = plt.subplots(len(groups), columns, figsize=(3 * columns + 4, 1.4 + 2.4 * len(groups)),
                             sharex=True, squeeze=False)
    marker = "o" if len(series.rows) <= 200 else None
    for row, group in enumerate(groups):
        curves = [series.curve(q) for q in quantities[group]]
        scale = max((float(np.nanmax(np.abs(c[2]))) for c in curves if np.isfinite(c[2]).any()),
                    default=0.0)
        for col, (quantity, (_, t, values)) in enumerate(zip(quantities[group], curves)):
            ax = axes[row, col]
            ax.plot(t, values, "-", marker=marker, color=f"C{row}", ms=3)
            ax.set_ylabel(run.label(quantity))
            round_off_floor(ax, values, scale)
            time_axis(ax)
            if group == "acceleration" and run.mech.analysis == "dynamics" and run.meshed():
                note = unresolved_note(series, quantity)
                if note:
                    ax.set_title(note, fontsize="small", color="C3")
    for ax in axes[-1]:
        ax.set_xlabel(run.label("t"))
    what = "against the load factor" if run.mech.statics else "time histories"
    fig.suptitle(f"{run.title}\npoint {short(series.name)}: {what}")
    fig.tight_layout()
    return fig


def unresolved_note(series: fs.Reduced, quantity: str) -> str:
    """A note for an acceleration that is not the rate of the written velocity: where the
    output step resolves the motion, a = dv/dt to within the step's error (central differences
    of the written v); where the flexible links' stiff modes are faster than it, the samples of
    a are those modes aliased and differ from dv/dt by as much as they are large. Only for a
    run read whole (at most MAX_BUCKETS written steps)."""
    velocity = {"ax": "vx", "ay": "vy"}[quantity]
    if not (series.masks == -1).all() or not series.has(velocity):
        return ""
    t = series.rows[:, 1]
    a = series.rows[:, 2 + series.quantities.index(quantity)]
    v = series.rows[:, 2 + series.quantities.index(velocity)]
    good = np.isfinite(a) & np.isfinite(v)
    if good.sum() < 20:
        return ""
    t, a, v = t[good], a[good], v[good]
    rate = np.gradient(v, t)
    scale = float(np.max(np.abs(a)))
    if scale <= 0:
        return ""
    misfit = float(np.max(np.abs(a - rate)[1:-1])) / scale
    if misfit <= UNRESOLVED_MISFIT:
        return ""
    step = float(np.median(np.diff(t)))
    return (f"the output step ({step:.3g}) does not resolve the flexible links' stiff modes:\n"
            f"a differs from the rate of the written v by {misfit:.0%} of its largest value")


def plot_angles(run: Run) -> Figure:
    """Time histories of the link angles (and omega, alpha when computed)."""
    plt = pyplot()
    first = next(iter(run.links.values()))
    quantities = [q for q in fc.LINK_QUANTITIES if first.has(q)]
    fig, axes = plt.subplots(len(quantities), 1, figsize=(9, 1.6 + 2.4 * len(quantities)),
                             sharex=True, squeeze=False)
    marker = "o" if len(first.rows) <= 200 else None
    for ax, quantity in zip(axes[:, 0], quantities):
        for index, series in enumerate(run.links.values()):
            if series.has(quantity):
                _, t, values = series.curve(quantity)
                ax.plot(t, values, "-", marker=marker, color=f"C{index % 10}", ms=2.5,
                        label=short(series.name))
        ax.set_ylabel(run.label(quantity))
        time_axis(ax)
    axes[0, 0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), title="link")
    axes[-1, 0].set_xlabel(run.label("t"))
    what = "against the load factor" if run.mech.statics else ""
    fig.suptitle(f"{run.title}\nlink angles {what}".rstrip())
    fig.tight_layout()
    return fig


def plot_iterations(run: Run, steps: fs.Reduced) -> Figure:
    """Newton iterations per step (bars, or their extremes per stretch of a long run) and,
    when written, the final residual per step."""
    plt = pyplot()
    has_residual = steps.has("residual")
    rows = 2 if has_residual else 1
    fig, axes = plt.subplots(rows, 1, figsize=(9, 1.6 + 2.4 * rows), sharex=True, squeeze=False)
    ax = axes[0, 0]
    step, _, iterations = steps.curve("iterations")
    if len(step) <= 400:
        ax.bar(step, iterations, width=0.8, color="C0")
    else:
        ax.plot(step, iterations, "-", color="C0", lw=0.8, drawstyle="steps-mid")
    ax.set_ylabel("Newton iterations (count)")
    ax.yaxis.get_major_locator().set_params(integer=True)
    if has_residual:
        ax = axes[1, 0]
        step, _, residual = steps.curve("residual")
        ax.plot(step, residual, "o", color="C1", ms=2.5)
        finite = residual[np.isfinite(residual)]
        if finite.size and np.all(finite > 0):
            ax.set_yscale("log")
        ax.set_ylabel("final residual (force)")
    axes[-1, 0].set_xlabel("step (count)")
    axes[-1, 0].xaxis.get_major_locator().set_params(integer=True)
    fig.suptitle(f"{run.title}\nNewton iterations per step")
    fig.tight_layout()
    return fig


def balance_meaning(run: Run) -> str:
    """What the energy balance of a dynamics run is, from its integrator."""
    integrator = run.mech.integrator
    if integrator == "energy-momentum":
        return ("energy-momentum conserves energy: the balance is round-off "
                "(Newton's tolerance), not a physical loss")
    if integrator == "generalized-alpha":
        rho = run.mech.rho_inf
        if math.isfinite(rho) and rho >= 1:
            return ("generalized-alpha with rho_inf = 1 (the trapezoidal rule): the balance is the "
                    "Newton tolerance's round-off")
        return ("generalized-alpha" + (f" with rho_inf = {rho:g}" if math.isfinite(rho) else "")
                + ": the balance is the integrator's numerical dissipation\n"
                "of the high-frequency modes (it falls), not a physical loss")
    return "the balance is zero for the exact motion: what is left is the integrator's error"


def plot_energy(run: Run, energy: fs.Reduced) -> Figure:
    """Energies and work (top), their balance with what it means (middle), momenta (bottom) of
    a dynamics run."""
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(9, 10), sharex=True)
    ax = axes[0]
    labels = {"kinetic": "kinetic", "strain": "strain", "penalty": "slidelines' penalty",
              "gravity": "gravity potential",
              "work_loads": "work of the loads", "work_drives": "work of the drives",
              "dissipated": "dissipated by damping"}
    for index, (quantity, label) in enumerate(labels.items()):
        _, t, value = energy.curve(quantity)
        if np.any(value != 0):
            ax.plot(t, value, "-", color=f"C{index}", lw=1.2, label=label)
    ax.set_ylabel(f"energy ({run.unit('energy')})")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    ax = axes[1]
    _, t, balance = energy.curve("balance")
    ax.plot(t, balance, "-", color="C3", lw=1.0, label="balance")
    ax.set_ylabel(f"balance ({run.unit('energy')})")
    ax.set_title("balance = kinetic + strain + penalty + gravity - work + dissipated, less its start "
                 f"value\n{balance_meaning(run)}", color="0.3", fontsize="small")
    ax = axes[2]
    for index, (quantity, label, unit) in enumerate((
            ("px", "p_x", "momentum"), ("py", "p_y", "momentum"),
            ("angular", "angular about the origin", "angular momentum"))):
        _, t, value = energy.curve(quantity)
        ax.plot(t, value, "-", color=f"C{index}", lw=1.2, label=f"{label} ({run.unit(unit)})")
    ax.set_ylabel(f"momentum ({run.unit('momentum')}, {run.unit('angular momentum')})")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    axes[-1].set_xlabel(run.label("t"))
    time_axis(axes[-1])
    fig.suptitle(f"{run.title}\nenergy and momentum")
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- reactions

def reaction_label(run: Run, name: str) -> str:
    """A reaction series' name for a legend, e.g. ``joint at B on link BC``."""
    kind, link, node = name.split("|", 2)
    link, node = short(link), short(node)
    if kind == "support":
        return f"support {node}"
    if kind == "slider":
        return f"guide on {node}" + (f" ({link})" if link else "")
    if kind == "joint":
        return f"joint {node} on {link}"
    return f"{kind} {link} {node}".strip()


def drive_axis(run: Run, drive: tuple[str, ...], steps: np.ndarray
               ) -> tuple[str, np.ndarray] | None:
    """The drive's own coordinate at the given steps: the driven link's angle in degrees
    (continuous over turns), or the driven node's coordinate; None when not written."""
    if drive[0] == "rotation" and len(drive) >= 3 and drive[1] in run.links:
        link = run.links[drive[1]]
        step, _, angle = link.curve("angle")
        return (f"angle of {drive[1]} (deg)",
                np.degrees(np.interp(steps, step, np.unwrap(angle))))
    if drive[0] in ("x", "y") and len(drive) >= 2 and drive[1] in run.nodes.paths:
        step, _, value = run.nodes.paths[drive[1]].curve(drive[0])
        return f"{drive[0]} of {drive[1]} (stroke, {run.unit('x')})", np.interp(steps, step, value)
    return None


def plot_reactions(run: Run, components: bool = False) -> Figure:
    """The drives' torque or force against time and against the drive's own coordinate (what a
    machine designer reads), the supports' and joints' force magnitudes and the sliders' guide
    forces against time."""
    plt = pyplot()
    series = run.reactions
    drives = {n: s for n, s in series.items() if n.startswith("drive|")}
    supports = {n: s for n, s in series.items() if n.startswith("support|")}
    joints = {n: s for n, s in series.items() if n.startswith("joint|")}
    sliders = {n: s for n, s in series.items() if n.startswith("slider|")}
    rows = [("drive", drives)] if drives else []
    rows += [(kind, group) for kind, group in (("support", supports), ("slider", sliders),
                                               ("joint", joints)) if group]
    fig, axes = plt.subplots(len(rows), 2, figsize=(11, 1.4 + 2.9 * len(rows)), squeeze=False)
    t_label = run.label("t")
    for row, (kind, group) in enumerate(rows):
        ax, side = axes[row]
        if kind == "drive":
            draw_drives(run, group, ax, side)
            continue
        magnitude = {}
        for name, s in group.items():
            _, t, fx, fy = s.curve("fx", "fy")
            magnitude[name] = (t, np.hypot(fx, fy), fx, fy)
        order = sorted(magnitude, key=lambda n: -np.nanmax(magnitude[n][1], initial=0.0))
        shown = order[:MAX_FORCE_CURVES]
        for index, name in enumerate(shown):
            t, value, fx, fy = magnitude[name]
            ax.plot(t, value, "-", color=f"C{index % 10}", lw=1.3, label=reaction_label(run, name))
            if components:
                ax.plot(t, fx, "--", color=f"C{index % 10}", lw=0.8)
                ax.plot(t, fy, ":", color=f"C{index % 10}", lw=0.8)
        what = {"support": "support reaction forces", "slider": "guide (slider) forces",
                "joint": "joint forces on the links"}[kind]
        count = f" (the {len(shown)} largest of {len(order)})" if len(order) > len(shown) else ""
        parts = ", magnitude solid, x dashed, y dotted" if components else ", magnitude"
        ax.set_title(what + parts + count, fontsize="small", color="0.3")
        ax.set_ylabel(f"|F| ({run.unit('force')})")
        ax.set_xlabel(t_label)
        time_axis(ax)
        moments = [(name, group[name].curve("m")) for name in shown
                   if np.nanmax(np.abs(group[name].curve("m")[2]), initial=0.0) > 0]
        if moments and kind != "joint":
            for index, (name, (_, t, m)) in enumerate(moments):
                side.plot(t, m, "-", color=f"C{index % 10}", lw=1.3, label=reaction_label(run, name))
            side.set_title(f"{kind} moments", fontsize="small", color="0.3")
            side.set_ylabel(f"M ({run.unit('moment')})")
            side.set_xlabel(t_label)
            side.legend(fontsize="small")
            time_axis(side)
            ax.legend(fontsize="small")
        else:
            side.remove()
            ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    fig.suptitle(f"{run.title}\nreactions" + (" against the load factor" if run.mech.statics else ""))
    fig.tight_layout()
    return fig


def draw_drives(run: Run, drives: dict[str, fs.Reduced], ax, side) -> None:
    """The drives' torques or forces against time (ax) and against the drive (side)."""
    declared = {d[1] if d[0] == "rotation" else d[-1]: d for d in run.mech.drives}
    on_side = False
    for index, (name, s) in enumerate(drives.items()):
        _, link, node = name.split("|", 2)
        step, t, fx, fy, m = s.curve("fx", "fy", "m")
        drive = declared.get(link) or declared.get(node)
        if drive is not None and drive[0] == "rotation":
            value, what, unit = m, f"torque on {link} at {node}", run.unit("moment")
        elif drive is not None:
            value = fx if drive[0] == "x" else fy
            what, unit = f"force on {node} in {drive[0]}", run.unit("force")
        else:
            nonzero = [v for v in (m, fx, fy) if np.nanmax(np.abs(v), initial=0.0) > 0]
            value, what, unit = (nonzero or [m])[0], f"drive {link} {node}", run.unit("force")
        ax.plot(t, value, "-", color=f"C{index % 10}", lw=1.5, label=what)
        ax.set_ylabel(f"drive torque or force ({unit})" if len(drives) > 1 else f"{what} ({unit})")
        if drive is not None:
            along = drive_axis(run, drive, step.astype(float))
            if along is not None:
                label, coordinate = along
                side.plot(coordinate, value, "-", color=f"C{index % 10}", lw=1.5, label=what)
                side.set_xlabel(label)
                side.set_ylabel(ax.get_ylabel())
                on_side = True
    ax.set_xlabel(run.label("t"))
    ax.set_title("drive " + ("torques and forces" if len(drives) > 1 else "torque" if
                             run.mech.drives and run.mech.drives[0][0] == "rotation" else "force"),
                 fontsize="small", color="0.3")
    time_axis(ax)
    if len(drives) > 1:
        ax.legend(fontsize="small")
    if on_side:
        side.set_title("against the drive", fontsize="small", color="0.3")
    else:
        side.remove()


# --------------------------------------------------------------------------- deflection

def plot_deflection(run: Run) -> Figure:
    """The largest transverse deflection of each meshed link from its chord, against time."""
    plt = pyplot()
    deflections = fs.read_deflections(run.path / "nodes.csv",
                                      {link: run.chains[link] for link in run.meshed()})
    fig, ax = plt.subplots(figsize=(9, 4.6))
    for index, link in enumerate(deflections.quantities):
        _, t, value = deflections.curve(link)
        ax.plot(t, value, "-", color=f"C{index % 10}", lw=1.2,
                label=f"{link} ({len(run.chains[link]) - 1} elements)")
    ax.set_xlabel(run.label("t"))
    ax.set_ylabel(f"deflection ({run.unit('x')})")
    ax.set_title("largest transverse deflection of each meshed link from its chord (signed: "
                 "+ to the left of first -> second end)", fontsize="small", color="0.3")
    time_axis(ax)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), title="link")
    fig.suptitle(f"{run.title}\nlink deflection" + (" against the load factor" if run.mech.statics else ""))
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- animation

def wrap_degrees(angles: np.ndarray) -> np.ndarray:
    """Angles in degrees wrapped to (-180, 180]."""
    return 180.0 - np.mod(180.0 - np.asarray(angles, dtype=float), 360.0)


def drive_values(run: Run, frames: list[tuple[int, float, dict]]) -> tuple[str, np.ndarray] | None:
    """The first drive's value at each frame (the driven link's angle in degrees, continuous
    over turns, or the driven coordinate), or None for a load-driven model."""
    if not run.mech.drives:
        return None
    drive = run.mech.drives[0]
    if drive[0] == "rotation" and len(drive) >= 3:
        link = next((l for l in run.mech.links if l[0] == drive[1]), None)
        if link is None:
            return None
        angles = []
        for _, _, where in frames:
            if link[1] not in where or link[2] not in where:
                return None
            (x1, y1), (x2, y2) = where[link[1]], where[link[2]]
            angles.append(np.arctan2(y2 - y1, x2 - x1))
        return f"angle of {link[0]}", np.degrees(np.unwrap(np.array(angles)))
    if drive[0] in ("x", "y"):
        node, axis = drive[1], 0 if drive[0] == "x" else 1
        if any(node not in where for _, _, where in frames):
            return None
        return f"{drive[0]} of {node}", np.array([where[node][axis] for _, _, where in frames])
    return None


def drive_text(name: str, value: float, start: float, length_unit: str) -> str:
    """A drive's value for the time box: an angle wrapped to (-180, 180] deg with the turns made
    since the start, or a coordinate."""
    if not name.startswith("angle"):
        return f"{name} = {value:.4g} {length_unit}"
    turn = int(np.floor(abs(value - start) / 360.0 + 1e-9)) + 1
    return f"{name} = {float(wrap_degrees(value)):.1f} deg\n  (in turn {turn})"


def movie_format(wanted: str) -> str:
    """mp4 when asked for or (auto) when ffmpeg is there, else gif."""
    if wanted == "gif":
        return "gif"
    if shutil.which("ffmpeg"):
        return "mp4"
    if wanted == "mp4":
        print(f"{PROG}: no ffmpeg on PATH: writing a GIF instead of an MP4 "
              "(scripts/setup installs ffmpeg)", file=sys.stderr)
    return "gif"


class Movie:
    """The animation's figure: the drawing on the left, the legend and the time box in a column
    beside it (never over the mechanism), and update(index) that draws frame ``index``."""

    #: Width of the column beside the drawing, inches.
    SIDE = 2.9

    def __init__(self, run: Run):
        plt = pyplot()
        self.run = run
        frames = [run.frame(target) for target in run.frame_targets]
        self.frames = list({step: (step, t, where) for step, t, where in frames}.values())
        size = run.size
        # The frame fits the drawn mechanism over its motion (magnified shapes included), not
        # the guides (they are clipped).
        xlim, ylim = motion_limits(run, [where for _, _, where in self.frames])
        # The drawing 7 inches wide, 3.2 to 7 high (even pixel counts for the MP4 encoder).
        aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
        draw_w = 7.0
        draw_h = float(np.clip(draw_w * aspect, 3.2, 7.0))
        # Whole even pixel counts at 100 dpi (a hair over, as matplotlib truncates).
        width = 2 * round((0.9 + draw_w + self.SIDE) * 50) / 100 + 1e-6
        height = 2 * round((draw_h + 1.5) * 50) / 100 + 1e-6
        self.fig = fig = plt.figure(figsize=(width, height))
        self.ax = ax = fig.add_axes((0.8 / width, 0.7 / height, draw_w / width, draw_h / height))
        draw_ground(ax, run, size)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        mechanism_axes(ax, run)
        ax.set_aspect("equal", adjustable="box")
        tracked = [n for n in run.mech.tracked if n in run.nodes.paths
                   and not is_fixed(run.nodes.paths[n])]
        self.trails = []
        for index, name in enumerate(tracked):
            step, _, x, y = run.nodes.paths[name].curve("x", "y")
            ax.plot(x, y, "-", color=f"C{index % 10}", lw=0.8, alpha=0.25)
            line, = ax.plot([], [], "-", color=f"C{index % 10}", lw=2.0, label=f"path of {short(name)}")
            self.trails.append((line, step, x, y))
        self.links = [(chain, ax.plot([], [], "-", color="0.2", lw=3.0, zorder=4)[0],
                       ax.plot([], [], "o", color="0.2", ms=5, mfc="white", zorder=4.1)[0])
                      for chain in run.chains.values()]
        self.drive = drive_values(run, self.frames)
        side_x = (0.8 + draw_w + 0.25) / width
        self.clock = fig.text(side_x, (0.7 + draw_h) / height, "", va="top", ha="left",
                              family="monospace", fontsize=10,
                              bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.7"))
        fig.suptitle(run.title)
        if run.magnification_text():
            ax.set_title(run.magnification_text(), fontsize="small", color="0.3")
        handles, labels = ax.get_legend_handles_labels()
        self.legend = (fig.legend(handles, labels, loc="lower left", bbox_to_anchor=(side_x, 0.7 / height),
                                  fontsize="small") if handles else None)

    def update(self, index: int):
        run = self.run
        step, t, where = self.frames[index]
        drawn = run.shape(where)
        for chain, line, ends in self.links:
            xy = link_xy(run, chain, drawn)
            if xy is not None:
                line.set_data(*xy)
                ends.set_data([xy[0][0], xy[0][-1]], [xy[1][0], xy[1][-1]])
        for line, steps, x, y in self.trails:
            upto = steps <= step
            line.set_data(x[upto], y[upto])
        text = f"{run.mech.name('t')} = {t:.4g} {run.unit('t')}"
        if self.drive is not None:
            name, values = self.drive
            text += "\n" + drive_text(name, float(values[index]), float(values[0]), run.unit("x"))
        elif run.mech.loads and run.mech.statics:
            text += "\n(loads times λ)"
        self.clock.set_text(text)
        return ([line for _, line, _ in self.links] + [ends for *_, ends in self.links]
                + [line for line, *_ in self.trails] + [self.clock])


def animate(run: Run, directory: Path, wanted: str) -> Path:
    """The mechanism moving: every link, supports, guides, the tracked points' trails, the time
    and the drive's value; at most MAX_FRAMES frames, about MOVIE_SECONDS long."""
    return save_movie(Movie(run), directory, wanted)


def save_movie(movie, directory: Path, wanted: str) -> Path:
    """Write `movie` (a figure `fig`, its `frames` and `update(k)`, which draws frame k) as
    motion.mp4 or motion.gif (movie_format) in directory, about MOVIE_SECONDS long, and one
    frame as motion-frame.png; both names go in the manifest first."""
    plt = pyplot()
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter

    fmt = movie_format(wanted)
    fps = int(min(30, max(8, round(len(movie.frames) / MOVIE_SECONDS))))
    target = directory / f"motion.{fmt}"
    animation = FuncAnimation(movie.fig, movie.update, frames=len(movie.frames), blit=False)
    record(target)
    record(directory / "motion-frame.png")
    # Not savefig's "tight" box: every frame must have the same size.
    with plt.rc_context({"savefig.bbox": None}):
        if fmt == "mp4":
            writer = FFMpegWriter(fps=fps, codec="libx264", bitrate=-1,
                                  extra_args=["-pix_fmt", "yuv420p", "-preset", "veryfast", "-crf", "23"])
            animation.save(target, writer=writer, dpi=100)
        else:
            animation.save(target, writer=PillowWriter(fps=fps), dpi=80)
        # One frame as a picture, for the gallery and for a look without a player.
        movie.update(len(movie.frames) // 3)
        movie.fig.savefig(directory / "motion-frame.png", dpi=100)
    plt.close(movie.fig)
    return target


# --------------------------------------------------------------------------- main

def record(target: Path) -> None:
    """Add a file to the directory's manifest before writing it: the next fekap run there removes
    the files listed, and no other (README, "What a run writes")."""
    with open(target.parent / ".fekap-manifest", "a", encoding="utf-8") as manifest:
        manifest.write(target.name + "\n")


def save(fig: Figure, target: Path, written: list[Path]) -> None:
    """Save a figure as PNG, close it and remember the file."""
    plt = fc.pyplot()
    record(target)
    fig.savefig(target)
    plt.close(fig)
    written.append(target)


def main(argv: list[str] | None = None) -> int:
    """Draw the requested figures of one FEKAP output directory."""
    args = parse_args(argv)
    directory = Path(args.outdir)
    if directory.is_dir() and fs.read_mechanism(directory).spatial:
        from fekap import plot3d

        return plot3d.main(args)
    kinds = set(args.only) if args.only else None
    for kind in SPATIAL_KINDS:
        if kinds is not None and kind in kinds:
            raise fc.UsageError(f"--only {kind}: drawn for spatial runs only ({directory / 'mechanism.txt'} "
                                "has no analysis,kinematics,spatial record)")
    run = Run(args.outdir, args.instants, MAX_FRAMES if args.animate else 0, args.magnify)

    def wanted(kind: str) -> bool:
        return kinds is None or kind in kinds

    def explicit(kind: str) -> bool:
        return kinds is not None and kind in kinds

    if explicit("angles") and not run.links:
        raise fc.UsageError(f"{run.path}: no links.csv (or it is empty): no angles to plot")
    steps = fs.read_steps(run.path / "steps.csv") if wanted("iterations") else None
    if explicit("iterations") and (steps is None or not len(steps.rows)):
        raise fc.UsageError(f"{run.path}: no steps.csv (or it is empty): no iterations to plot")
    energy = fs.read_energy(run.path / "energy.csv") if wanted("energy") else None
    if explicit("energy") and energy is None:
        raise fc.UsageError(f"{run.path}: no energy.csv (or it is empty): energy is written by dynamics runs")
    if explicit("reactions") and not run.reactions:
        raise fc.UsageError(f"{run.path}: no reactions.csv (or it is empty): reactions are written "
                            "by kinetostatics, statics and dynamics runs")
    if explicit("deflection") and not run.meshed():
        raise fc.UsageError(f"{run.path}: nodes.csv holds no meshed link's interior points (OUTPut "
                            "mesh on writes them; on by default in statics and dynamics)")
    groups = history_groups(run, kinds) if kinds is None or kinds & {
        "history", "velocity", "acceleration"} else []

    written: list[Path] = []
    if wanted("paths"):
        save(plot_paths(run, args.at), run.path / "paths.png", written)
    for series in run.points.values() if groups else ():
        save(plot_history(run, series, groups), run.path / f"history_{safe_name(series.name)}.png",
             written)
    if wanted("angles") and run.links:
        save(plot_angles(run), run.path / "angles.png", written)
    if wanted("iterations") and steps is not None and len(steps.rows):
        save(plot_iterations(run, steps), run.path / "iterations.png", written)
    if energy is not None:
        save(plot_energy(run, energy), run.path / "energy.png", written)
    if wanted("reactions") and run.reactions:
        save(plot_reactions(run, args.components), run.path / "reactions.png", written)
    if wanted("deflection") and run.meshed():
        save(plot_deflection(run), run.path / "deflection.png", written)
    if args.animate:
        if not run.mech.links:
            print(f"{PROG}: no mesh.csv in {run.path}: no animation written", file=sys.stderr)
        elif not run.drawable_links():
            print(f"{PROG}: no link of mesh.csv has both end nodes in nodes.csv or points.csv: "
                  "no animation written", file=sys.stderr)
        else:
            written.append(animate(run, run.path, args.animate))
    for target in written:
        print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(fc.run_main(PROG, main))
