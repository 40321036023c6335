#!/usr/bin/env python3
"""Plot the results of a FEKAP run.

    scripts/plot.py OUTDIR [--only KIND ...] [--animate] [--instants N]

draws into OUTDIR:

- paths.png        the path of every tracked point (a marker per step) over a faint drawing of
                   the mechanism at a few instants (mesh.csv + points.csv);
- history_<P>.png  time histories of x, y (vx, vy, ax, ay when computed) of each point P;
- angles.png       time histories of the link angles (omega, alpha when computed);
- iterations.png   Newton iterations (and the residual) per step;
- motion.gif       with --animate: the mechanism moving (needs mesh.csv).

Kinds for --only: paths, history, velocity, acceleration, angles, iterations. ``velocity`` and
``acceleration`` draw the history figures with only those panels. Bad arguments give a one-line
message on stderr and exit status 2.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

import fekap_csv as fc

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PROG = "plot.py"
KINDS = ("paths", "history", "velocity", "acceleration", "angles", "iterations")
#: How to ask the deck for the missing quantities (the hint in the error message).
MISSING_HINT = {
    "velocity": "this run computed no velocities; ask for them in the deck's ANALysis block "
                "(compute positions velocities) or with fekap --compute positions,velocities",
    "acceleration": "this run computed no accelerations; ask for them in the deck's ANALysis block "
                    "(compute positions velocities accelerations) or with fekap --compute accelerations",
}
GROUPS = {"position": fc.POSITION, "velocity": fc.VELOCITY, "acceleration": fc.ACCELERATION}
MAX_FRAMES = 150
DPI = 110


def parse_args(argv: list[str] | None):
    """The command line of plot.py."""
    parser = fc.Parser(prog=PROG, description="Plot the results of a FEKAP run into its "
                       "output directory (PNG files, and a GIF with --animate).")
    parser.add_argument("outdir", help="the FEKAP output directory (holds points.csv)")
    parser.add_argument("--only", nargs="+", action="extend", choices=KINDS, metavar="KIND",
                        help=f"draw only these figures: {', '.join(KINDS)}")
    parser.add_argument("--animate", action="store_true",
                        help="also write motion.gif, the mechanism moving")
    parser.add_argument("--instants", type=int, default=4, metavar="N",
                        help="how many instants of the mechanism paths.png shows (default 4)")
    args = parser.parse_args(argv)
    if args.instants < 0:
        parser.error(f"--instants must be 0 or more, not {args.instants}")
    return args


def safe_name(name: str) -> str:
    """A point name usable in a file name."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


def instant_steps(steps: np.ndarray, count: int) -> list[int]:
    """``count`` steps spread evenly over the run, starting with the first.

    The end point is left out so that a full revolution does not draw its first configuration
    twice.
    """
    if count == 0:
        return []
    picks = np.floor(np.linspace(0, steps.size, count, endpoint=False)).astype(int)
    return [int(steps[i]) for i in np.unique(picks)]


def is_fixed(series: fc.Series) -> bool:
    """Whether a point never moves (a ground pivot)."""
    x, y = series.values["x"], series.values["y"]
    extent = max(np.ptp(x), np.ptp(y))
    scale = max(1.0, float(np.max(np.abs(np.concatenate([x, y])))))
    return bool(extent <= 1e-12 * scale)


def draw_mechanism(ax, run: fc.Run, step: int, color, label: str | None) -> None:
    """Draw the links of the mechanism at ``step`` as segments between tracked points."""
    where = run.positions_at(step)
    for _, node1, node2 in run.drawable_links():
        if node1 in where and node2 in where:
            (x1, y1), (x2, y2) = where[node1], where[node2]
            ax.plot([x1, x2], [y1, y2], "-o", color=color, lw=2.5, ms=4, alpha=0.5,
                    solid_capstyle="round", zorder=1, label=label)
            label = None  # one legend entry per instant


def label_point(run: fc.Run, steps: list[int]) -> str | None:
    """The mesh end point whose positions at ``steps`` are farthest apart (to label instants)."""
    if not steps:
        return None
    best, spread = None, 0.0
    for name in dict.fromkeys(n for _, n1, n2 in run.drawable_links() for n in (n1, n2)):
        spots = [run.positions_at(step).get(name) for step in steps]
        if None in spots:
            continue
        where = np.array(spots)
        gaps = np.linalg.norm(where[:, None, :] - where[None, :, :], axis=2)
        gap = np.min(gaps + np.diag(np.full(len(steps), np.inf))) if len(steps) > 1 else 1.0
        if gap > spread:
            best, spread = name, gap
    return best


def plot_paths(run: fc.Run, instants: int) -> Figure:
    """The path of every point, with a marker per step, over the mechanism at a few instants."""
    plt = fc.pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    if run.drawable_links():
        steps = instant_steps(run.step_numbers(), instants)
        shades = np.linspace(0.8, 0.3, max(len(steps), 1))
        labelled = label_point(run, steps)
        for step, shade in zip(steps, shades):
            time_text = f"t = {run.time_of(step):.4g}"
            draw_mechanism(ax, run, step, str(shade), f"mechanism at {time_text}")
            if labelled is not None:
                ax.annotate(time_text, run.positions_at(step)[labelled], xytext=(6, 6),
                            textcoords="offset points", fontsize="small", color="0.25",
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none",
                                      alpha=0.75), zorder=4)
    for index, series in enumerate(run.points.values()):
        color = f"C{index % 10}"
        x, y = series.values["x"], series.values["y"]
        if is_fixed(series):
            ax.plot(x[:1], y[:1], "^", color=color, ms=9, zorder=3,
                    label=f"{series.name} (fixed)")
        else:
            ax.plot(x, y, "-o", color=color, lw=0.8, ms=4.5, mfc="none", zorder=2,
                    label=f"path of {series.name}")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"{run.path.name}: paths of the points")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    return fig


def history_groups(run: fc.Run, kinds: set[str] | None) -> list[str]:
    """The quantity groups (position, velocity, acceleration) the history figures show."""
    present = set(run.point_quantities())
    available = [g for g, names in GROUPS.items() if set(names) <= present]
    if kinds is None or "history" in kinds:
        return available
    wanted = [g for g in ("velocity", "acceleration") if g in kinds]
    for group in wanted:
        if group not in available:
            raise fc.UsageError(MISSING_HINT[group])
    return wanted


def plot_history(series: fc.Series, groups: list[str]) -> Figure:
    """Stacked time histories of one point: a row per group, x and y components side by side."""
    plt = fc.pyplot()
    fig, axes = plt.subplots(len(groups), 2, figsize=(10, 1.2 + 2.3 * len(groups)),
                             sharex=True, squeeze=False)
    for row, group in enumerate(groups):
        for col, quantity in enumerate(GROUPS[group]):
            ax = axes[row, col]
            ax.plot(series.t, series.values[quantity], "-o", color=f"C{row}", lw=1, ms=3)
            ax.set_ylabel(quantity)
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("t")
    fig.suptitle(f"point {series.name}: time histories")
    fig.tight_layout()
    return fig


def plot_angles(run: fc.Run) -> Figure:
    """Time histories of the link angles (and omega, alpha when computed)."""
    plt = fc.pyplot()
    first = next(iter(run.links.values()))
    quantities = [q for q in fc.LINK_QUANTITIES if first.has(q)]
    labels = {"angle": "angle (rad)", "omega": "omega", "alpha": "alpha"}
    fig, axes = plt.subplots(len(quantities), 1, figsize=(9, 1.4 + 2.4 * len(quantities)),
                             sharex=True, squeeze=False)
    for ax, quantity in zip(axes[:, 0], quantities):
        for index, series in enumerate(run.links.values()):
            if series.has(quantity):
                ax.plot(series.t, series.values[quantity], "-o", color=f"C{index % 10}",
                        lw=1, ms=2.5, label=series.name)
        ax.set_ylabel(labels[quantity])
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small",
                      title="link")
    axes[-1, 0].set_xlabel("t")
    fig.suptitle(f"{run.path.name}: link angles")
    fig.tight_layout()
    return fig


def plot_iterations(steps: dict[str, np.ndarray], name: str) -> Figure:
    """Newton iterations per step (bars) and, when written, the final residual per step."""
    plt = fc.pyplot()
    residual = steps.get("residual")
    rows = 2 if residual is not None else 1
    fig, axes = plt.subplots(rows, 1, figsize=(9, 1.4 + 2.4 * rows), sharex=True,
                             squeeze=False)
    ax = axes[0, 0]
    ax.bar(steps["step"], steps["iterations"], width=0.8, color="C0")
    ax.set_ylabel("Newton iterations")
    ax.yaxis.get_major_locator().set_params(integer=True)
    ax.grid(True, axis="y", alpha=0.3)
    if residual is not None:
        ax = axes[1, 0]
        ax.plot(steps["step"], residual, "o", color="C3", ms=3)
        if np.all(residual[np.isfinite(residual)] > 0) and np.any(np.isfinite(residual)):
            ax.set_yscale("log")
        ax.set_ylabel("residual")
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("step")
    fig.suptitle(f"{name}: Newton iterations per step")
    fig.tight_layout()
    return fig


def animate(run: fc.Run, target: Path) -> None:
    """Write a GIF of the mechanism moving, with the paths traced so far."""
    plt = fc.pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    steps = run.step_numbers()
    frames = steps[np.unique(np.linspace(0, steps.size - 1, min(steps.size, MAX_FRAMES))
                             .astype(int))]
    fig, ax = plt.subplots(figsize=(5.5, 5))
    xs = np.concatenate([s.values["x"] for s in run.points.values()])
    ys = np.concatenate([s.values["y"] for s in run.points.values()])
    pad = 0.05 * max(np.ptp(xs), np.ptp(ys), 1e-12)
    ax.set_xlim(xs.min() - pad, xs.max() + pad)
    ax.set_ylim(ys.min() - pad, ys.max() + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.grid(True, alpha=0.3)
    links = [ax.plot([], [], "-o", color="0.3", lw=2.5, ms=4)[0] for _ in run.drawable_links()]
    moving = [s for s in run.points.values() if not is_fixed(s)]
    traces = [ax.plot([], [], "-", color=f"C{i % 10}", lw=1)[0] for i in range(len(moving))]
    title = ax.set_title("")

    def update(step):
        where = run.positions_at(step)
        for line, (_, node1, node2) in zip(links, run.drawable_links()):
            if node1 in where and node2 in where:
                line.set_data([where[node1][0], where[node2][0]],
                              [where[node1][1], where[node2][1]])
            else:
                line.set_data([], [])
        for line, series in zip(traces, moving):
            upto = series.step <= step
            line.set_data(series.values["x"][upto], series.values["y"][upto])
        title.set_text(f"{run.path.name}: t = {run.time_of(step):.4g}")
        return links + traces + [title]

    movie = FuncAnimation(fig, update, frames=[int(s) for s in frames], blit=False)
    movie.save(target, writer=PillowWriter(fps=15), dpi=80)
    plt.close(fig)


def save(fig: Figure, target: Path, written: list[Path]) -> None:
    """Save a figure as PNG, close it and remember the file."""
    plt = fc.pyplot()
    fig.savefig(target, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    written.append(target)


def main(argv: list[str] | None = None) -> int:
    """Draw the requested figures of one FEKAP output directory."""
    args = parse_args(argv)
    run = fc.load_run(args.outdir)
    kinds = set(args.only) if args.only else None

    def wanted(kind: str) -> bool:
        return kinds is None or kind in kinds

    def explicit(kind: str) -> bool:
        return kinds is not None and kind in kinds

    if explicit("angles") and not run.links:
        raise fc.UsageError(f"{run.path}: no links.csv (or it is empty): no angles to plot")
    if explicit("iterations") and (run.steps is None or not run.steps["step"].size):
        raise fc.UsageError(f"{run.path}: no steps.csv (or it is empty): no iterations to plot")
    groups = history_groups(run, kinds) if kinds is None or kinds & {
        "history", "velocity", "acceleration"} else []

    written: list[Path] = []
    if wanted("paths"):
        save(plot_paths(run, args.instants), run.path / "paths.png", written)
    for series in run.points.values() if groups else ():
        save(plot_history(series, groups), run.path / f"history_{safe_name(series.name)}.png",
             written)
    if wanted("angles") and run.links:
        save(plot_angles(run), run.path / "angles.png", written)
    if wanted("iterations") and run.steps is not None and run.steps["step"].size:
        save(plot_iterations(run.steps, run.path.name), run.path / "iterations.png", written)
    if args.animate:
        if not run.mesh:
            print(f"{PROG}: no mesh.csv in {run.path}: motion.gif not written", file=sys.stderr)
        elif not run.drawable_links():
            print(f"{PROG}: no link of mesh.csv has both end points in points.csv: "
                  "motion.gif not written", file=sys.stderr)
        else:
            animate(run, run.path / "motion.gif")
            written.append(run.path / "motion.gif")
    for target in written:
        print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(fc.run_main(PROG, main))
