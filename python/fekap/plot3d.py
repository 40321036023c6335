"""The pictures of a spatial run (issue 33), chosen by scripts/plot.py when mechanism.txt has
the record ``analysis,kinematics,spatial``:

- views.png        the mechanism at a few instants (coloured by time, a colour bar) in three
                   orthographic views, front (x-y), top (x-z) and side (y-z), and an axonometric
                   one (matplotlib's mplot3d), all four at one scale with equal axes: the links as
                   lines between their nodes, the joints marked by kind, the ground joints' axes as
                   short arrows (a ring where an axis points along the line of sight: with a dot
                   towards the viewer, a cross away), the tracked points' paths (points.csv) in
                   colour and the other moving nodes' paths dotted (nodes.csv, mesh.csv,
                   mechanism.txt);
- joints.png       joints.csv: the revolute joints' angles and the prismatic joints' strokes, and
                   their rates and accelerations when computed, against time (a column each);
- history_<P>.png  x, y, z (vx, vy, vz, ax, ay, az when computed) of each tracked point P;
- iterations.png   Newton iterations per step, as for a planar run;
- motion.mp4       with --animate: the four views moving, one frame per written step for a run
                   of at most MAX_FRAMES written steps (else MAX_FRAMES evenly spread), the tracked
                   points' trails, the time and the driven joint's angle (wrapped to (-180, 180] deg,
                   with its turn) or stroke beside the views; motion.gif where ffmpeg is missing or
                   when asked for; motion-frame.png, one of its frames.

Kinds for --only: paths or views (views.png), history, velocity, acceleration, joints,
iterations. The planar pictures are fekap.plot's.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fekap import plot as fp
from fekap import read as fc
from fekap import stream as fs

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: The orthographic views: (name, horizontal coordinate, vertical coordinate), 0 x, 1 y, 2 z.
VIEWS = (("front", 0, 1), ("top", 0, 2), ("side", 1, 2))
#: Where each view is in the 2 x 2 grid: the top view under the front view (the same x), the
#: side view beside it, the axonometric view in the fourth place.
PLACES = {"front": (0, 0), "top": (1, 0), "side": (0, 1)}
AXES = ("x", "y", "z")
#: Point quantities of a spatial points.csv, by group.
GROUPS = {"position": ("x", "y", "z"), "velocity": ("vx", "vy", "vz"),
          "acceleration": ("ax", "ay", "az")}
POINT_QUANTITIES = GROUPS["position"] + GROUPS["velocity"] + GROUPS["acceleration"]
JOINT_QUANTITIES = ("angle", "rate", "acceleration")
#: How each kind of joint is marked (matplotlib markers).
JOINT_MARKERS = {"spherical": "o", "revolute": "s", "universal": "D", "prismatic": ">",
                 "cylindrical": "h", "weld": "X"}
#: A ground joint's axis arrow, as a fraction of the model's extent.
AXIS_ARROW = 0.18
#: A projected axis shorter than this fraction of its arrow points along the line of sight.
ALONG_SIGHT = 1e-6
#: What --only may ask of a spatial run.
KINDS = ("paths", "views", "history", "velocity", "acceleration", "joints", "iterations")
#: Kinds a spatial run has no file for, and why.
ABSENT = {"angles": "a spatial run writes its joints' angles to joints.csv: --only joints draws them",
          "energy": "energy.csv is written by dynamics runs, which are planar",
          "reactions": "reactions.csv is written by kinetostatics, statics and dynamics runs, which are planar",
          "deflection": "a spatial run draws its links as straight lines between their nodes"}


class SpatialRun:
    """A spatial run's output directory, read in streaming fashion (fekap.stream)."""

    def __init__(self, directory: str | Path, instants: int, frames: int):
        path = Path(directory)
        if not path.exists():
            raise fc.UsageError(f"{path}: no such directory")
        if not path.is_dir():
            raise fc.UsageError(f"{path}: not a directory (expected a FEKAP output directory)")
        if not (path / "points.csv").is_file():
            raise fc.UsageError(f"{path}: no points.csv (is this a FEKAP output directory?)")
        nodes_file = path / "nodes.csv"
        if not nodes_file.is_file():
            raise fc.UsageError(f"{path}: no nodes.csv: a spatial run's mechanism is drawn from it")
        self.path = path
        #: Title, units and links (mesh.csv) as for a planar run; the joints, their axes and the
        #: drives from the spatial records (fekap.read.read_spatial_mechanism).
        self.mech = fs.read_mechanism(path)
        self.layout = fc.read_spatial_mechanism(path / "mechanism.txt")
        self.title = self.mech.title or path.name
        first, last = fs.step_range(nodes_file)
        self.instant_targets = fs.even_steps(first, last, instants, endpoint=False) if instants else []
        if instants == 1:
            self.instant_targets = [first]
        self.frame_targets = fs.even_steps(first, last, min(frames, last - first + 1)) if frames else []
        targets = sorted(set(self.instant_targets) | set(self.frame_targets) | {first, last})
        self.nodes = fs.read_nodes(nodes_file, targets, dim=3)
        self._points: dict[str, fs.Reduced] | None = None
        self._joints: dict[str, fs.Reduced] | None = None
        if not self.mech.tracked:
            self.mech.tracked = list(self.points)
        names = set(self.nodes.names)
        self.links = [link for link in self.mech.links if link[1] in names and link[2] in names]
        low, high = motion_box(self)
        extent = float(np.max(high - low))
        self.size = extent if extent > 0 and math.isfinite(extent) else max(1.0, float(np.max(np.abs(high))))

    @property
    def points(self) -> dict[str, fs.Reduced]:
        if self._points is None:
            self._points = fs.read_long(self.path / "points.csv", "point", POINT_QUANTITIES,
                                        GROUPS["position"])
            if not self._points:
                raise fc.UsageError(f"{self.path / 'points.csv'}: no steps were written")
        return self._points

    @property
    def joints(self) -> dict[str, fs.Reduced]:
        """joints.csv, one series per joint (empty when absent or without rows)."""
        if self._joints is None:
            file = self.path / "joints.csv"
            try:
                self._joints = (fs.read_long(file, "joint", JOINT_QUANTITIES, ("angle",))
                                if file.is_file() else {})
            except fc.UsageError as exc:
                if "only its header" not in str(exc):
                    raise
                self._joints = {}
        return self._joints

    def frame(self, target: int) -> tuple[int, float, dict[str, tuple[float, float, float]]]:
        """The written step at or after ``target`` with its time and every node's position."""
        steps = list(self.nodes.frames)
        index = min(int(np.searchsorted(steps, target)), len(steps) - 1)
        step = steps[index]
        t, where = self.nodes.frames[step]
        return step, t, where

    def label(self, quantity: str) -> str:
        return f"{self.mech.name(quantity)} ({self.mech.unit(quantity)})"

    def joint_kind(self, name: str) -> str:
        """A joints.csv row's kind: its joint's, and a cylindrical joint's stroke row
        (``JOINT.stroke``) a prismatic one's (its angle row, ``JOINT``, a revolute one's)."""
        kind = next((j.kind for j in self.layout.joints if j.name == name), "")
        if not kind and name.endswith(".stroke"):
            base = next((j.kind for j in self.layout.joints if j.name == name[:-len(".stroke")]), "")
            kind = "prismatic" if base == "cylindrical" else ""
        return kind

    def ground_axes(self) -> list[tuple[str, str, np.ndarray, np.ndarray]]:
        """Each ground joint's axis: (joint, kind, the joint's place at the start, unit axis),
        of a universal joint its first axis as mechanism.txt gives it."""
        start = self.frame(self.nodes.first)[2] if self.nodes.frames else {}
        found = []
        for joint in self.layout.joints:
            node = joint.second if joint.first == "ground" else joint.first
            if "ground" not in (joint.first, joint.second) or node not in start or not joint.axes:
                continue
            axis = np.array(joint.axes[0], dtype=float)
            norm = float(np.linalg.norm(axis))
            if not (norm > 0 and math.isfinite(norm)):
                continue
            found.append((joint.name, joint.kind, np.array(start[node], dtype=float), axis / norm))
        return found


def motion_box(run: SpatialRun) -> tuple[np.ndarray, np.ndarray]:
    """The corners of the box of every node's path over the run."""
    lows, highs = [], []
    for series in run.nodes.paths.values():
        xyz = series.rows[:, 2:5]
        if xyz.size and np.isfinite(xyz).any():
            lows.append(np.nanmin(xyz, axis=0))
            highs.append(np.nanmax(xyz, axis=0))
    if not lows:
        return np.zeros(3), np.ones(3)
    return np.min(lows, axis=0), np.max(highs, axis=0)


def cube(run: SpatialRun) -> list[tuple[float, float]]:
    """The limits of x, y and z: one cube around the motion, so that every view has one scale."""
    low, high = motion_box(run)
    middle = 0.5 * (low + high)
    half = 0.5 * run.size * 1.25
    return [(float(m - half), float(m + half)) for m in middle]


def is_fixed(series: fs.Reduced) -> bool:
    """Whether a node never moves."""
    xyz = series.rows[:, 2:5]
    if not xyz.size:
        return True
    extent = float(np.nanmax(np.nanmax(xyz, axis=0) - np.nanmin(xyz, axis=0)))
    return extent <= 1e-12 * max(1.0, float(np.nanmax(np.abs(xyz))))


def joint_places(run: SpatialRun, where: dict[str, tuple[float, float, float]]
                 ) -> dict[str, list[tuple[float, float, float]]]:
    """Where each kind of joint is at one instant: at its first node that is not the ground."""
    places: dict[str, list[tuple[float, float, float]]] = {}
    for joint in run.layout.joints:
        node = joint.second if joint.first == "ground" else joint.first
        if node in where:
            places.setdefault(joint.kind, []).append(where[node])
    return places


class Panels:
    """The four views of one figure: three orthographic axes and the axonometric one, with
    equal scales, and the helpers that draw a polyline or markers into all four."""

    def __init__(self, fig, run: SpatialRun, grid):
        limits = cube(run)
        self.flat = []
        for name, i, j in VIEWS:
            ax = fig.add_subplot(grid[PLACES[name]])
            ax.set_xlim(*limits[i])
            ax.set_ylim(*limits[j])
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlabel(run.label(AXES[i]))
            ax.set_ylabel(run.label(AXES[j]))
            ax.set_title(f"{name} view ({AXES[i]}-{AXES[j]})", fontsize="small", color="0.3")
            ax.grid(alpha=0.3)
            self.flat.append((ax, i, j))
        self.iso = fig.add_subplot(grid[1, 1], projection="3d")
        self.iso.set_xlim(*limits[0])
        self.iso.set_ylim(*limits[1])
        self.iso.set_zlim(*limits[2])
        # A cube: equal scales; zoomed, as mplot3d leaves a wide margin around its box.
        self.iso.set_box_aspect((1, 1, 1), zoom=1.1)
        self.iso.set_xlabel(run.label("x"))
        self.iso.set_ylabel(run.label("y"))
        self.iso.set_zlabel(run.label("z"))
        self.iso.set_title("axonometric view", fontsize="small", color="0.3")

    def plot(self, points: np.ndarray, *args, **kwargs) -> list:
        """A polyline (or markers) of 3D points, shape (n, 3), in every view."""
        artists = []
        for ax, i, j in self.flat:
            artists += ax.plot(points[:, i], points[:, j], *args, **kwargs)
            kwargs.pop("label", None)
        artists += self.iso.plot(points[:, 0], points[:, 1], points[:, 2], *args, **kwargs)
        return artists

    def axis_arrow(self, base: np.ndarray, axis: np.ndarray, length: float, **style) -> None:
        """A ground joint's axis as an arrow from its place; where it points along a view's line
        of sight, a ring with a dot (towards the viewer) or a cross (away)."""
        tip = base + length * axis
        for ax, i, j in self.flat:
            if math.hypot(axis[i], axis[j]) > ALONG_SIGHT:
                ax.annotate("", xy=(tip[i], tip[j]), xytext=(base[i], base[j]), zorder=5,
                            arrowprops=dict(arrowstyle="-|>", mutation_scale=12, lw=1.6, **style))
            else:
                # The view's out-of-page direction is e_i x e_j.
                towards = float(np.cross(np.eye(3)[i], np.eye(3)[j]) @ axis) > 0
                ax.plot([base[i]], [base[j]], "o", ms=11, mfc="none", mec=style["color"], mew=1.4, zorder=5)
                ax.plot([base[i]], [base[j]], "." if towards else "x", ms=6, color=style["color"], zorder=5)
        self.iso.quiver(base[0], base[1], base[2], *(length * axis), arrow_length_ratio=0.25,
                        color=style["color"], lw=1.6)


def draw_instant(panels: Panels, run: SpatialRun, where: dict, color, label: str | None) -> None:
    """The mechanism at one instant: its links and its joints marked by kind."""
    for _, a, b in run.links:
        panels.plot(np.array([where[a], where[b]]), "-", color=color, lw=2.4, solid_capstyle="round",
                    zorder=2, label=label)
        label = None
    for kind, places in joint_places(run, where).items():
        panels.plot(np.array(places), JOINT_MARKERS.get(kind, "*"), color=color, ms=6, mfc="white",
                    mew=1.3, linestyle="none", zorder=3)


def draw_paths(panels: Panels, run: SpatialRun) -> None:
    """The tracked points' paths (points.csv) in colour, the other moving nodes' (nodes.csv) dotted."""
    tracked = [n for n in run.mech.tracked if n in run.points]
    for name, series in run.nodes.paths.items():
        if name in tracked or fs.INTERIOR in name or is_fixed(series):
            continue
        _, _, x, y, z = series.curve("x", "y", "z")
        panels.plot(np.column_stack([x, y, z]), ":", color="0.55", lw=0.9, zorder=1.8)
    for index, name in enumerate(tracked):
        _, _, x, y, z = run.points[name].curve("x", "y", "z")
        panels.plot(np.column_stack([x, y, z]), "-", color=f"C{index % 10}", lw=1.8, zorder=2.5,
                    label=f"path of {fp.short(name)}")


def legend_handles(run: SpatialRun) -> list:
    """Legend entries of the joint kinds and the ground axes (drawn nowhere)."""
    from matplotlib.lines import Line2D

    kinds = sorted({j.kind for j in run.layout.joints})
    handles = [Line2D([], [], marker=JOINT_MARKERS.get(kind, "*"), color="0.2", mfc="white",
                      linestyle="none", label=f"{kind} joint") for kind in kinds]
    if run.ground_axes():
        handles.append(Line2D([], [], color="C3", lw=1.6, label="ground joints' axes"))
    return handles


def plot_views(run: SpatialRun) -> Figure:
    """views.png: three orthographic views and an axonometric one of the mechanism at a few
    instants, with the tracked points' paths."""
    from matplotlib import cm
    from matplotlib.colors import ListedColormap, Normalize

    plt = fp.pyplot()
    fig = plt.figure(figsize=(11.0, 11.0))
    grid = fig.add_gridspec(2, 2, left=0.08, right=0.86, bottom=0.14, top=0.91, wspace=0.3, hspace=0.25)
    panels = Panels(fig, run, grid)
    draw_paths(panels, run)
    instants = [run.frame(target) for target in run.instant_targets]
    instants = list({step: (step, t, where) for step, t, where in instants}.values())
    cmap = plt.get_cmap("viridis")
    t_first, t_last = run.nodes.frames[min(run.nodes.frames)][0], run.nodes.frames[max(run.nodes.frames)][0]
    norm = Normalize(t_first, t_last if t_last > t_first else t_first + 1.0)
    colours = [cmap(0.85 * norm(t)) for _, t, _ in instants]
    for (_, t, where), colour in zip(instants, colours):
        draw_instant(panels, run, where, colour, f"{run.mech.name('t')} = {t:.4g}")
    for _, _, base, axis in run.ground_axes():
        panels.axis_arrow(base, axis, AXIS_ARROW * run.size, color="C3")
    if instants:
        bar_ax = fig.add_axes((0.92, 0.3, 0.02, 0.45), label="<colorbar>")
        bar = fig.colorbar(cm.ScalarMappable(norm=Normalize(0, len(instants)),
                                             cmap=ListedColormap(colours)), cax=bar_ax)
        bar.set_label(f"instant: {run.label('t')}")
        bar.set_ticks([k + 0.5 for k in range(len(instants))])
        bar.ax.set_yticklabels([f"{t:.4g}" for _, t, _ in instants])
    handles, _ = panels.flat[0][0].get_legend_handles_labels()
    handles = [h for h in handles if h.get_label().startswith("path of")] + legend_handles(run)
    if handles:
        fig.legend(handles=handles, loc="lower center", ncol=4, fontsize="small", bbox_to_anchor=(0.47, 0.01))
    fig.suptitle(f"{run.title}\nthe mechanism at {len(instants)} instants in three orthographic views "
                 "and an axonometric one, paths of the tracked points")
    return fig


# --------------------------------------------------------------------------- time histories

# --------------------------------------------------------------------------- joints

def joint_units(run: SpatialRun, prismatic: bool) -> dict[str, tuple[str, str]]:
    """(axis name, unit) of each joints.csv quantity: a revolute joint's angle in radians, a
    prismatic joint's stroke in the length unit."""
    length, time = run.mech.length_unit, run.mech.time_unit
    base = length if prismatic else "rad"
    return {"angle": ("stroke" if prismatic else "angle", base), "rate": ("rate", f"{base}/{time}"),
            "acceleration": ("acceleration", f"{base}/{time}²")}


def plot_joints(run: SpatialRun) -> Figure:
    """joints.png: each joint's angle (revolute) or stroke (prismatic), rate and acceleration
    against time; revolute and prismatic joints in columns of their own (their units differ)."""
    plt = fp.pyplot()
    first = next(iter(run.joints.values()))
    quantities = [q for q in JOINT_QUANTITIES if first.has(q)]
    groups = {"revolute": [], "prismatic": []}
    for name in run.joints:
        groups["prismatic" if run.joint_kind(name) == "prismatic" else "revolute"].append(name)
    groups = {kind: names for kind, names in groups.items() if names}
    fig, axes = plt.subplots(len(quantities), len(groups), figsize=(5.5 * len(groups) + 2.5,
                                                                     1.6 + 2.4 * len(quantities)),
                             sharex=True, squeeze=False)
    marker = "o" if len(first.rows) <= 200 else None
    for col, (kind, names) in enumerate(groups.items()):
        units = joint_units(run, kind == "prismatic")
        for row, quantity in enumerate(quantities):
            ax = axes[row, col]
            curves = [run.joints[name].curve(quantity) for name in names]
            for index, (name, (_, t, values)) in enumerate(zip(names, curves)):
                ax.plot(t, values, "-", marker=marker, ms=2.5, color=f"C{index % 10}", label=fp.short(name))
            if len(names) == 1 and np.nanmax(np.abs(curves[0][2]), initial=0.0) > 0:
                # A constant rate (a driven crank's) drawn as constant, not as autoscaled noise.
                fp.round_off_floor(ax, curves[0][2], 0.0)
            what, unit = units[quantity]
            ax.set_ylabel(f"{what} ({unit})")
            fp.time_axis(ax)
        axes[0, col].set_title(f"{kind} joints: " + ("stroke" if kind == "prismatic" else "relative angle"),
                               fontsize="small", color="0.3")
        axes[0, col].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), title="joint", fontsize="small")
        axes[-1, col].set_xlabel(run.label("t"))
    fig.suptitle(f"{run.title}\njoints: the second node's motion relative to the first")
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- animation

def drive_values(run: SpatialRun, steps: list[int]) -> tuple[str, np.ndarray] | None:
    """The first drive's joint value at the given steps: a revolute joint's angle in degrees
    (continuous over turns) or a prismatic joint's stroke; None when joints.csv lacks it."""
    if not run.layout.drives:
        return None
    kind, joint = run.layout.drives[0]
    if kind == "stroke" and run.joint_kind(f"{joint}.stroke") == "prismatic":
        joint = f"{joint}.stroke"            # a cylindrical joint's stroke row
    if joint not in run.joints:
        return None
    step, _, angle = run.joints[joint].curve("angle")
    values = np.interp(np.asarray(steps, dtype=float), step.astype(float), angle)
    if kind == "rotation":
        return f"angle of {fp.short(joint)}", np.degrees(values)
    return f"stroke of {fp.short(joint)}", values


class Movie:
    """The animation's figure: the four views, the time box and the legend beside them, and
    update(index) that draws frame ``index``."""

    def __init__(self, run: SpatialRun):
        plt = fp.pyplot()
        self.run = run
        frames = [run.frame(target) for target in run.frame_targets]
        self.frames = list({step: (step, t, where) for step, t, where in frames}.values())
        # 1200 x 960 pixels at 100 dpi: even counts for the MP4 encoder (a hair over, as
        # matplotlib truncates).
        self.fig = fig = plt.figure(figsize=(12.0 + 1e-6, 9.6 + 1e-6))
        grid = fig.add_gridspec(2, 2, left=0.07, right=0.76, bottom=0.07, top=0.92, wspace=0.3, hspace=0.25)
        self.panels = panels = Panels(fig, run, grid)
        for _, _, base, axis in run.ground_axes():
            panels.axis_arrow(base, axis, AXIS_ARROW * run.size, color="C3")
        self.trails = []
        for index, name in enumerate(n for n in run.mech.tracked if n in run.points):
            step, _, x, y, z = run.points[name].curve("x", "y", "z")
            xyz = np.column_stack([x, y, z])
            panels.plot(xyz, "-", color=f"C{index % 10}", lw=0.8, alpha=0.25)
            lines = panels.plot(np.empty((0, 3)), "-", color=f"C{index % 10}", lw=2.0,
                                label=f"path of {fp.short(name)}")
            self.trails.append((lines, step, xyz))
        self.links = [(a, b, panels.plot(np.empty((0, 3)), "-", color="0.2", lw=3.0, zorder=4))
                      for _, a, b in run.links]
        self.joints = {kind: panels.plot(np.empty((0, 3)), JOINT_MARKERS.get(kind, "*"), color="0.2", ms=6,
                                         mfc="white", linestyle="none", zorder=4.1)
                       for kind in sorted({j.kind for j in run.layout.joints})}
        self.drive = drive_values(run, [step for step, _, _ in self.frames])
        self.clock = fig.text(0.8, 0.92, "", va="top", ha="left", family="monospace", fontsize=10,
                              bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.7"))
        fig.suptitle(run.title)
        handles, _ = panels.flat[0][0].get_legend_handles_labels()
        handles = handles + legend_handles(run)
        self.legend = (fig.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.8, 0.07),
                                  fontsize="small") if handles else None)

    def update(self, index: int) -> list:
        run, panels = self.run, self.panels
        step, t, where = self.frames[index]
        for a, b, lines in self.links:
            set_points(panels, lines, np.array([where[a], where[b]]))
        for kind, lines in self.joints.items():
            set_points(panels, lines, np.array(joint_places(run, where).get(kind, np.empty((0, 3)))))
        for lines, steps, xyz in self.trails:
            set_points(panels, lines, xyz[steps <= step])
        text = f"{run.mech.name('t')} = {t:.4g} {run.mech.unit('t')}"
        if self.drive is not None:
            name, values = self.drive
            text += "\n" + fp.drive_text(name, float(values[index]), float(values[0]), run.mech.unit("x"))
        self.clock.set_text(text)
        return [line for _, _, lines in self.links for line in lines] + [self.clock]


def set_points(panels: Panels, lines: list, points: np.ndarray) -> None:
    """Give the four lines of panels.plot (three views, then the axonometric) new 3D points."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    for line, (_, i, j) in zip(lines[:3], panels.flat):
        line.set_data(points[:, i], points[:, j])
    lines[3].set_data_3d(points[:, 0], points[:, 1], points[:, 2])


def animate(run: SpatialRun, directory: Path, wanted: str) -> Path:
    """motion.mp4 (or .gif) of the four views, and motion-frame.png."""
    return fp.save_movie(Movie(run), directory, wanted)


# --------------------------------------------------------------------------- main

def main(args) -> int:
    """Draw the requested figures of a spatial run (args: fekap.plot's parsed command line)."""
    kinds = set(args.only) if args.only else None
    for kind in sorted(kinds or ()):
        if kind in ABSENT:
            raise fc.UsageError(f"--only {kind}: not drawn for a spatial run: {ABSENT[kind]}")
    run = SpatialRun(args.outdir, args.instants, fp.MAX_FRAMES if args.animate else 0)

    def wanted(*names: str) -> bool:
        return kinds is None or any(name in kinds for name in names)

    if kinds and "joints" in kinds and not run.joints:
        raise fc.UsageError(f"{run.path}: no joints.csv (or it is empty): no joints to plot")
    steps = fs.read_steps(run.path / "steps.csv") if wanted("iterations") else None
    if kinds and "iterations" in kinds and (steps is None or not len(steps.rows)):
        raise fc.UsageError(f"{run.path}: no steps.csv (or it is empty): no iterations to plot")
    groups = fp.history_groups(run, kinds, GROUPS) if wanted("history", "velocity", "acceleration") else []

    written: list[Path] = []
    if wanted("paths", "views"):
        fp.save(plot_views(run), run.path / "views.png", written)
    for series in run.points.values() if groups else ():
        fp.save(fp.plot_history(run, series, groups, GROUPS), run.path / f"history_{fp.safe_name(series.name)}.png",
                written)
    if wanted("joints") and run.joints:
        fp.save(plot_joints(run), run.path / "joints.png", written)
    if steps is not None and len(steps.rows):
        fp.save(fp.plot_iterations(run, steps), run.path / "iterations.png", written)
    if args.animate:
        if not run.links:
            print(f"{fp.PROG}: no link of mesh.csv has both end nodes in nodes.csv: no animation written",
                  file=sys.stderr)
        else:
            written.append(animate(run, run.path, args.animate))
    for target in written:
        print(f"wrote {target}")
    return 0
