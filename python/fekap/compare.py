"""Compare several FEKAP runs (or exact solutions) point by point.

    scripts/compare.py RUN1 RUN2 [RUN...] [--labels a,b,c] [--point P]
                       [--quantity x|y|vx|vy|ax|ay] [-o OUT.png]

Each RUN is a FEKAP output directory or a CSV file in the points.csv format (e.g. an exact
solution). The runs must have been written at the same times. The figure overlays the path of
point P and the time history of the quantity for every run, with a panel of the differences
with respect to RUN1. The standard output is a table of the maximum absolute difference from
RUN1 per run, point and quantity (every common point unless --point is given).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fekap import read as fc
from fekap import stream as fs

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PROG = "compare.py"
STYLES = [dict(marker="o", mfc="none", ms=6, lw=1.2), dict(marker="+", ms=8, lw=1.0),
          dict(marker="x", ms=6, lw=1.0), dict(marker=".", ms=6, lw=1.0),
          dict(marker="s", mfc="none", ms=5, lw=1.0), dict(marker="^", mfc="none", ms=5, lw=1.0)]
GROUP_OF = {q: group for group, names in (("positions", fc.POSITION),
                                          ("velocities", fc.VELOCITY),
                                          ("accelerations", fc.ACCELERATION)) for q in names}


@dataclass(frozen=True)
class Source:
    """One run to compare: its label, where it came from and its point histories."""

    label: str
    path: Path
    points: dict[str, fc.Series]


def parse_args(argv: list[str] | None):
    """The command line of compare.py."""
    parser = fc.Parser(prog=PROG, description="Overlay several FEKAP runs (output directories "
                       "or points.csv-format files) and tabulate their differences from the "
                       "first.")
    parser.add_argument("runs", nargs="*", metavar="RUN",
                        help="FEKAP output directories or points.csv-format files (two or more)")
    parser.add_argument("--labels", help="comma-separated labels, one per run")
    parser.add_argument("--point", help="the point to plot and tabulate (default: the first "
                        "point common to all runs; the table then covers every common point)")
    parser.add_argument("--quantity", default="x", choices=fc.POINT_QUANTITIES,
                        help="the quantity of the time-history panels (default x)")
    parser.add_argument("-o", "--output", default="compare.png", metavar="OUT.png",
                        help="the figure to write (default compare.png)")
    args = parser.parse_args(argv)
    if len(args.runs) < 2:
        parser.error(f"give at least two runs to compare, got {len(args.runs)}")
    return args


def run_labels(paths: list[Path], labels: str | None) -> list[str]:
    """The label of each run: given by --labels, else the directory or file name."""
    if labels is not None:
        names = [name.strip() for name in labels.split(",")]
        if len(names) != len(paths) or not all(names):
            raise fc.UsageError(f"--labels gives {len(names)} labels for {len(paths)} runs")
        return names
    names = [path.stem if path.is_file() else path.name for path in paths]
    if len(set(names)) < len(names):
        names = [str(path) for path in paths]
    return names


def load_source(path: Path, label: str) -> Source:
    """Read one run: an output directory's points.csv, or a points.csv-format file."""
    if path.is_file():
        return Source(label, path, fc.read_points(path))
    return Source(label, path, fc.load_run(path).points)


def chosen_points(sources: list[Source], point: str | None) -> list[str]:
    """The points to tabulate; the first is the one plotted."""
    common = [name for name in sources[0].points
              if all(name in source.points for source in sources[1:])]
    if point is not None:
        for source in sources:
            if point not in source.points:
                raise fc.UsageError(f"run {source.label} has no point {point} "
                                    f"(it has {', '.join(source.points)})")
        return [point]
    if not common:
        raise fc.UsageError("the runs have no point in common")
    return common


def check_times(sources: list[Source], point: str) -> None:
    """All runs must have written ``point`` at the same times as the first."""
    reference = sources[0].points[point].t
    for source in sources[1:]:
        t = source.points[point].t
        scale = max(1.0, float(np.max(np.abs(reference))))
        if t.shape != reference.shape or not np.allclose(t, reference, rtol=0,
                                                         atol=1e-9 * scale):
            raise fc.UsageError(
                f"the runs' times differ: {sources[0].label} has {reference.size} steps "
                f"(t = {reference[0]:.6g} .. {reference[-1]:.6g}), {source.label} has "
                f"{t.size} (t = {t[0]:.6g} .. {t[-1]:.6g}); compare runs with the same steps")


def check_quantity(sources: list[Source], point: str, quantity: str) -> None:
    """All runs must carry the plotted quantity."""
    for source in sources:
        if not source.points[point].has(quantity):
            raise fc.UsageError(f"run {source.label} has no {quantity} (it computed no "
                                f"{GROUP_OF[quantity]})")


def max_differences(sources: list[Source], points: list[str]
                    ) -> list[tuple[str, str, dict[str, float | None]]]:
    """Max |run - first run| per run (after the first), point and quantity of the first run."""
    rows = []
    for source in sources[1:]:
        for point in points:
            reference = sources[0].points[point]
            other = source.points[point]
            cells = {}
            for quantity in reference.values:
                if other.has(quantity):
                    diff = other.values[quantity] - reference.values[quantity]
                    cells[quantity] = float(np.max(np.abs(diff)))
                else:
                    cells[quantity] = None
            rows.append((source.label, point, cells))
    return rows


def format_table(rows, reference: str, steps: int) -> str:
    """The difference table as aligned text."""
    quantities = list(dict.fromkeys(q for _, _, cells in rows for q in cells))
    header = ["run", "point"] + quantities
    body = [[label, point] + ["-" if cells.get(q) is None else f"{cells[q]:.3e}"
                              for q in quantities] for label, point, cells in rows]
    widths = [max(len(line[i]) for line in [header] + body) for i in range(len(header))]
    lines = [f"max |difference| from {reference} over {steps} steps:"]
    for line in [header] + body:
        lines.append("  ".join(field.ljust(width) for field, width in zip(line, widths))
                     .rstrip())
    return "\n".join(lines)


def plot_comparison(sources: list[Source], point: str, quantity: str, title: str | None = None,
                    mech=None, note: str = "") -> Figure:
    """Path of ``point`` for every run, the quantity against t, and its differences from the
    first run (of the runs written at its times; the panel says which are left out).

    ``mech`` (fekap.stream.Mechanism, optional) labels the axes with the deck's units;
    ``title`` and ``note`` (which cases are shown) head the figure."""
    plt = fc.pyplot()
    fig = plt.figure(figsize=(13, 6.4))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.0, 1.3])
    ax_path = fig.add_subplot(grid[:, 0])
    ax_value = fig.add_subplot(grid[0, 1])
    ax_diff = fig.add_subplot(grid[1, 1], sharex=ax_value)
    reference = sources[0].points[point]
    unit = (lambda q: mech.unit(q)) if mech is not None else (lambda q: "as in the runs")
    name = (lambda q: mech.name(q)) if mech is not None else (lambda q: q)
    left_out = []
    for index, source in enumerate(sources):
        series = source.points[point]
        style = dict(STYLES[index % len(STYLES)], color=f"C{index % 10}", label=source.label)
        ax_path.plot(series.values["x"], series.values["y"], **style)
        ax_value.plot(series.t, series.values[quantity], **style)
        if index == 0:
            continue
        if series.t.shape == reference.t.shape and np.allclose(series.t, reference.t, rtol=0, atol=1e-9):
            ax_diff.plot(series.t, series.values[quantity] - reference.values[quantity], **style)
        else:
            left_out.append(source.label)
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set_xlabel(f"x ({unit('x')})")
    ax_path.set_ylabel(f"y ({unit('y')})")
    ax_path.set_title(f"path of {point}")
    ax_path.legend(fontsize="small")
    ax_value.set_ylabel(f"{name(quantity)} ({unit(quantity)})")
    ax_value.set_title(f"{name(quantity)} of {point}")
    ax_value.tick_params(labelbottom=False)
    ax_diff.set_ylabel(f"difference ({unit(quantity)})")
    ax_diff.set_title(f"{name(quantity)} - {name(quantity)}[{sources[0].label}]"
                      + (f"; not on its times, left out: {', '.join(left_out)}" if left_out else ""),
                      fontsize="small")
    ax_diff.set_xlabel(f"{name('t')} ({unit('t')})")
    ax_diff.axhline(0.0, color="0.6", lw=0.8)
    for ax in (ax_path, ax_value, ax_diff):
        ax.grid(True, alpha=0.3)
    heading = [text for text in (title, note) if text]
    if heading:
        fig.suptitle("\n".join(heading))
    fig.tight_layout()
    return fig


def main(argv: list[str] | None = None) -> int:
    """Compare the runs: print the difference table and write the figure."""
    plt = fc.pyplot()
    args = parse_args(argv)
    paths = [Path(run) for run in args.runs]
    for path in paths:
        if not path.exists():
            raise fc.UsageError(f"{path}: no such directory or file")
    output = Path(args.output)
    if not output.parent.is_dir():
        raise fc.UsageError(f"-o {output}: no such directory {output.parent}")
    labels = run_labels(paths, args.labels)
    sources = [load_source(path, label) for path, label in zip(paths, labels)]
    points = chosen_points(sources, args.point)
    for point in points:
        check_times(sources, point)
    check_quantity(sources, points[0], args.quantity)
    print(format_table(max_differences(sources, points), sources[0].label,
                       sources[0].points[points[0]].t.size))
    mech = next((fs.read_mechanism(path) for path in paths if path.is_dir()), None)
    title = mech.title if mech is not None and mech.title else None
    fig = plot_comparison(sources, points[0], args.quantity, title, mech,
                          f"runs: {', '.join(source.label for source in sources)}")
    fig.savefig(output, dpi=110, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {output}")
    return 0


if __name__ == "__main__":
    sys.exit(fc.run_main(PROG, main))
