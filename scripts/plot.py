#!/usr/bin/env python3
"""Plot the results of a FEKAP run.

    scripts/plot.py OUTDIR [--only KIND ...] [--animate [auto|mp4|gif]] [--instants N]

draws into OUTDIR:

- paths.png        the whole mechanism (every link, the supports, the sliders' guides) at a few
                   instants, with the paths of the tracked points highlighted and those of the
                   other moving nodes faint (nodes.csv, mesh.csv, mechanism.txt);
- history_<P>.png  time histories of x, y (vx, vy, ax, ay when computed) of each tracked point P;
- angles.png       time histories of the link angles (omega, alpha when computed);
- iterations.png   Newton iterations (and the final residual) per step;
- energy.png       dynamics runs (energy.csv): kinetic, strain, penalty and gravity energy, the work of
                   loads and drives and the damping's dissipation, their balance (the integrator's
                   numerical dissipation), linear and angular momentum;
- motion.mp4       with --animate: the mechanism moving, with the time, the drive's value and
                   the tracked points' trails (motion.gif where ffmpeg is missing, or asked for).

Every figure carries the deck's title and units on its axes (the deck's OUTPut `units` line,
SI by default). Runs of any length are read in streaming fashion and each curve is decimated to
a few thousand points keeping every extremum (fekap_stream.py). A quantity constant to
round-off is drawn as a flat line and labelled so, instead of autoscaled noise.

Kinds for --only: paths, history, velocity, acceleration, angles, iterations, energy. ``velocity`` and
``acceleration`` draw the history figures with only those panels. Bad arguments give a one-line
message on stderr and exit status 2.
"""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

import fekap_csv as fc
import fekap_stream as fs

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PROG = "plot.py"
KINDS = ("paths", "history", "velocity", "acceleration", "angles", "iterations", "energy")
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
    args = parser.parse_args(argv)
    if args.instants < 0:
        parser.error(f"--instants must be 0 or more, not {args.instants}")
    return args


def pyplot():
    """pyplot on the Agg backend, in FEKAP's style."""
    plt = fc.pyplot()
    plt.style.use(STYLE)
    return plt


def safe_name(name: str) -> str:
    """A point name usable in a file name."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


# --------------------------------------------------------------------------- the run

class Run:
    """A FEKAP output directory, read in streaming fashion."""

    def __init__(self, directory: str | Path, instants: int, frames: int):
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
        nodes_file = path / "nodes.csv"
        points_file = path / "points.csv"
        source = nodes_file if nodes_file.is_file() else points_file
        first, last = fs.step_range(source)
        self.instant_targets = fs.even_steps(first, last, instants, endpoint=False) if instants else []
        if instants == 1:
            self.instant_targets = [first]
        self.frame_targets = fs.even_steps(first, last, min(frames, last - first + 1)) if frames else []
        targets = sorted(set(self.instant_targets) | set(self.frame_targets))
        if nodes_file.is_file():
            self.nodes = fs.read_nodes(nodes_file, targets)
        else:
            # A run written before nodes.csv existed: its tracked points stand in for the nodes.
            self.nodes = nodes_from_points(self.points, targets)
        if not self.mech.tracked:
            self.mech.tracked = list(self.points)

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
            try:
                self._links = (fs.read_long(file, "link", fc.LINK_QUANTITIES, ("angle",))
                               if file.is_file() else {})
            except fc.UsageError as exc:
                if "only its header" not in str(exc):
                    raise
                self._links = {}
        return self._links

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

    def unit(self, quantity: str) -> str:
        return self.mech.unit(quantity)

    def label(self, quantity: str) -> str:
        """An axis label with its unit, e.g. ``vx (m/s)``."""
        return f"{quantity} ({self.unit(quantity)})"


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


def model_size(run: Run) -> float:
    """The extent of the mechanism over the run (for marker and guide sizes)."""
    lows, highs = [], []
    for series in run.nodes.paths.values():
        if series.rows.size:
            lows.append(np.nanmin(series.rows[:, 2:4], axis=0))
            highs.append(np.nanmax(series.rows[:, 2:4], axis=0))
    for guide in run.mech.guides:
        lows.append(np.minimum(guide[2:4], guide[4:6]))
        highs.append(np.maximum(guide[2:4], guide[4:6]))
    if not lows:
        return 1.0
    return float(max(np.max(np.array(highs) - np.array(lows)), 1e-12))


# --------------------------------------------------------------------------- drawing the mechanism

def draw_ground(ax, run: Run, size: float) -> None:
    """Supports (a hatched ground triangle under each supported node) and ground guides."""
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
    for index, (name, slave, x1, y1, x2, y2) in enumerate(run.mech.guides):
        ax.plot([x1, x2], [y1, y2], color="0.25", lw=4.5, alpha=0.35, solid_capstyle="butt",
                zorder=1.2, label=f"ground guide of {slave}")


def draw_links(ax, run: Run, where: dict[str, tuple[float, float]], color, alpha: float,
               label: str | None, lw: float = 2.6) -> list:
    """Every link of the mechanism at one instant, as segments between its end nodes."""
    artists = []
    for _, node1, node2 in run.drawable_links():
        if node1 in where and node2 in where:
            (x1, y1), (x2, y2) = where[node1], where[node2]
            artists += ax.plot([x1, x2], [y1, y2], "-o", color=color, lw=lw, ms=4.5, alpha=alpha,
                               solid_capstyle="round", zorder=2, label=label, mfc="white")
            label = None  # one legend entry per instant
    return artists


def draw_paths(ax, run: Run) -> None:
    """Paths of the tracked points (coloured) and of the other moving nodes (faint)."""
    tracked = [n for n in run.mech.tracked if n in run.nodes.paths]
    for name, series in run.nodes.paths.items():
        if name in tracked or is_fixed(series):
            continue
        _, _, x, y = series.curve("x", "y")
        ax.plot(x, y, ":", color="0.55", lw=0.9, zorder=1.8)
    for index, name in enumerate(tracked):
        series = run.nodes.paths[name]
        color = f"C{index % 10}"
        _, _, x, y = series.curve("x", "y")
        if is_fixed(series):
            ax.plot(x[:1], y[:1], "s", color=color, ms=7, zorder=3, label=f"{name} (fixed)")
        else:
            ax.plot(x, y, "-", color=color, lw=1.8, zorder=3, label=f"path of {name}")


def mechanism_axes(ax, run: Run) -> None:
    """Equal scales, axis labels with units."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(run.label("x"))
    ax.set_ylabel(run.label("y"))


def plot_paths(run: Run) -> Figure:
    """The whole mechanism at a few instants, with the tracked points' paths highlighted."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8.0, 6.8))
    size = model_size(run)
    draw_ground(ax, run, size)
    draw_paths(ax, run)
    instants = [run.frame(target) for target in run.instant_targets]
    instants = list({step: (step, t, where) for step, t, where in instants}.values())
    shades = np.linspace(0.15, 0.6, max(len(instants), 1))
    for (step, t, where), shade in zip(instants, shades):
        draw_links(ax, run, where, str(shade), 0.75,
                   f"mechanism at t = {t:.4g} {run.unit('t')}")
    if instants:
        # Node names at the first instant.
        for name, (x, y) in instants[0][2].items():
            if any(name in link[1:] for link in run.drawable_links()) or name in run.mech.tracked:
                ax.annotate(name, (x, y), xytext=(5, 5), textcoords="offset points",
                            fontsize="small", color="0.1", zorder=5,
                            bbox=dict(boxstyle="round,pad=0.12", fc="white", ec="none", alpha=0.7))
    mechanism_axes(ax, run)
    fig.suptitle(run.title)
    what = "the mechanism at " + (f"{len(instants)} instants" if instants else "no instant")
    ax.set_title(f"{what}, paths of the tracked points", color="0.3")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
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


def history_groups(run: Run, kinds: set[str] | None) -> list[str]:
    """The quantity groups (position, velocity, acceleration) the history figures show."""
    first = next(iter(run.points.values()))
    present = set(first.quantities)
    available = [g for g, names in GROUPS.items() if set(names) <= present]
    if kinds is None or "history" in kinds:
        return available
    wanted = [g for g in ("velocity", "acceleration") if g in kinds]
    for group in wanted:
        if group not in available:
            raise fc.UsageError(MISSING_HINT[group])
    return wanted


def plot_history(run: Run, series: fs.Reduced, groups: list[str]) -> Figure:
    """Stacked time histories of one point: a row per group, x and y components side by side."""
    plt = pyplot()
    fig, axes = plt.subplots(len(groups), 2, figsize=(10, 1.4 + 2.4 * len(groups)),
                             sharex=True, squeeze=False)
    marker = "o" if len(series.rows) <= 200 else None
    for row, group in enumerate(groups):
        curves = [series.curve(q) for q in GROUPS[group]]
        scale = max((float(np.nanmax(np.abs(c[2]))) for c in curves if np.isfinite(c[2]).any()),
                    default=0.0)
        for col, (quantity, (_, t, values)) in enumerate(zip(GROUPS[group], curves)):
            ax = axes[row, col]
            ax.plot(t, values, "-", marker=marker, color=f"C{row}", ms=3)
            ax.set_ylabel(run.label(quantity))
            round_off_floor(ax, values, scale)
            time_axis(ax)
    for ax in axes[-1]:
        ax.set_xlabel(run.label("t"))
    fig.suptitle(f"{run.title}\npoint {series.name}: time histories")
    fig.tight_layout()
    return fig


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
                        label=series.name)
        ax.set_ylabel(run.label(quantity))
        time_axis(ax)
    axes[0, 0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), title="link")
    axes[-1, 0].set_xlabel(run.label("t"))
    fig.suptitle(f"{run.title}\nlink angles")
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


def plot_energy(run: Run, energy: fs.Reduced) -> Figure:
    """Energies and work (top), their balance (middle), momenta (bottom) of a dynamics run."""
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(9, 9.5), sharex=True)
    ax = axes[0]
    labels = {"kinetic": "kinetic", "strain": "strain", "penalty": "slidelines' penalty",
              "gravity": "gravity potential",
              "work_loads": "work of the loads", "work_drives": "work of the drives",
              "dissipated": "dissipated by damping"}
    for index, (quantity, label) in enumerate(labels.items()):
        _, t, value = energy.curve(quantity)
        if np.any(value != 0):
            ax.plot(t, value, "-", color=f"C{index}", lw=1.2, label=label)
    ax.set_ylabel("energy (J)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    ax = axes[1]
    _, t, balance = energy.curve("balance")
    ax.plot(t, balance, "-", color="C3", lw=1.0)
    ax.set_ylabel("balance (J)")
    ax.set_title("kinetic + strain + penalty + gravity - work + dissipated, less its start value", color="0.3",
                 fontsize="small")
    ax = axes[2]
    for index, (quantity, label) in enumerate((("px", "p_x (N s)"), ("py", "p_y (N s)"),
                                               ("angular", "angular about the origin (N m s)"))):
        _, t, value = energy.curve(quantity)
        ax.plot(t, value, "-", color=f"C{index}", lw=1.2, label=label)
    ax.set_ylabel("momentum")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    axes[-1].set_xlabel(run.label("t"))
    time_axis(axes[-1])
    fig.suptitle(f"{run.title}\nenergy and momentum")
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- animation

def drive_values(run: Run, frames: list[tuple[int, float, dict]]) -> tuple[str, np.ndarray] | None:
    """The first drive's value at each frame (the driven link's angle in degrees, unwrapped, or
    the driven coordinate), or None for a load-driven model."""
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


def animate(run: Run, directory: Path, wanted: str) -> Path:
    """The mechanism moving: every link, supports, guides, the tracked points' trails, the time
    and the drive's value; at most MAX_FRAMES frames, about MOVIE_SECONDS long."""
    plt = pyplot()
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter

    frames = [run.frame(target) for target in run.frame_targets]
    frames = list({step: (step, t, where) for step, t, where in frames}.values())
    size = model_size(run)
    lows = np.nanmin([np.nanmin(s.rows[:, 2:4], axis=0) for s in run.nodes.paths.values()], axis=0)
    highs = np.nanmax([np.nanmax(s.rows[:, 2:4], axis=0) for s in run.nodes.paths.values()], axis=0)
    for guide in run.mech.guides:
        lows = np.minimum(lows, np.minimum(guide[2:4], guide[4:6]))
        highs = np.maximum(highs, np.maximum(guide[2:4], guide[4:6]))
    pad = 0.08 * size
    xlim = (lows[0] - pad, highs[0] + pad)
    ylim = (lows[1] - 1.5 * pad, highs[1] + pad)
    # The frame follows the mechanism's shape: 8 inches wide, 3.6 to 8 high (even pixel counts
    # for the MP4 encoder).
    aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    height = round(float(np.clip(1.2 + 7.0 * aspect, 3.6, 8.0)) * 50) / 50
    fig, ax = plt.subplots(figsize=(8.0, height))
    draw_ground(ax, run, size)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    mechanism_axes(ax, run)
    ax.set_aspect("equal", adjustable="box")
    tracked = [n for n in run.mech.tracked if n in run.nodes.paths
               and not is_fixed(run.nodes.paths[n])]
    trails = []
    for index, name in enumerate(tracked):
        step, _, x, y = run.nodes.paths[name].curve("x", "y")
        ax.plot(x, y, "-", color=f"C{index % 10}", lw=0.8, alpha=0.25)
        line, = ax.plot([], [], "-", color=f"C{index % 10}", lw=2.0, label=f"path of {name}")
        trails.append((line, step, x, y))
    links = [ax.plot([], [], "-o", color="0.2", lw=3.0, ms=5, mfc="white", zorder=4)[0]
             for _ in run.drawable_links()]
    drive = drive_values(run, frames)
    clock = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", family="monospace",
                    fontsize=11, bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.7", alpha=0.9))
    fig.suptitle(run.title)
    if trails:
        ax.legend(loc="upper right")
    t_unit = run.unit("t")

    def update(index: int):
        step, t, where = frames[index]
        for line, (_, node1, node2) in zip(links, run.drawable_links()):
            if node1 in where and node2 in where:
                line.set_data([where[node1][0], where[node2][0]], [where[node1][1], where[node2][1]])
        for line, steps, x, y in trails:
            upto = steps <= step
            line.set_data(x[upto], y[upto])
        text = f"t = {t:.4g} {t_unit}"
        if drive is not None:
            name, values = drive
            unit = "deg" if name.startswith("angle") else run.unit("x")
            text += f"\n{name} = {values[index]:.4g} {unit}"
        elif run.mech.loads:
            text += "\n(load factor t)"
        clock.set_text(text)
        return links + [line for line, *_ in trails] + [clock]

    fmt = movie_format(wanted)
    fps = int(min(30, max(8, round(len(frames) / MOVIE_SECONDS))))
    target = directory / f"motion.{fmt}"
    movie = FuncAnimation(fig, update, frames=len(frames), blit=False)
    record(target)
    record(directory / "motion-frame.png")
    if fmt == "mp4":
        writer = FFMpegWriter(fps=fps, codec="libx264", bitrate=-1,
                              extra_args=["-pix_fmt", "yuv420p", "-preset", "veryfast", "-crf", "23"])
        movie.save(target, writer=writer, dpi=100)
    else:
        movie.save(target, writer=PillowWriter(fps=fps), dpi=80)
    # One frame as a picture, for the gallery and for a look without a player.
    update(len(frames) // 3)
    fig.savefig(directory / "motion-frame.png", dpi=100)
    plt.close(fig)
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
    kinds = set(args.only) if args.only else None
    run = Run(args.outdir, args.instants, MAX_FRAMES if args.animate else 0)

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
    groups = history_groups(run, kinds) if kinds is None or kinds & {
        "history", "velocity", "acceleration"} else []

    written: list[Path] = []
    if wanted("paths"):
        save(plot_paths(run), run.path / "paths.png", written)
    for series in run.points.values() if groups else ():
        save(plot_history(run, series, groups), run.path / f"history_{safe_name(series.name)}.png",
             written)
    if wanted("angles") and run.links:
        save(plot_angles(run), run.path / "angles.png", written)
    if wanted("iterations") and steps is not None and len(steps.rows):
        save(plot_iterations(run, steps), run.path / "iterations.png", written)
    if energy is not None:
        save(plot_energy(run, energy), run.path / "energy.png", written)
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
