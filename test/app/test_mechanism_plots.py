"""The figures of scripts/plot.py, checked through matplotlib's objects (not pixels): every
axis labelled with its unit, the deck's title in every figure, every link of the deck drawn in
the mechanism plot at every instant, round-off drawn as round-off; the animation; decimation
that keeps extrema; the deck's units line.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from apptest import ROOT, fekap_binary  # noqa: E402

sys.path.insert(0, str(ROOT / "scripts"))
import fekap_stream as fs  # noqa: E402
import plot  # noqa: E402

EXAMPLES = sorted(p.stem for p in (ROOT / "decks").glob("*.deck"))
#: An axis label with a unit: "name (unit)".
WITH_UNIT = re.compile(r"^.+ \([^()]+\)$")


def run_deck(tmp_path: Path, deck: Path, *options: str) -> Path:
    out = tmp_path / deck.stem
    proc = subprocess.run([fekap_binary(), "-q", "-o", str(out), *options, str(deck)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    return out


def deck_title(deck: Path) -> str:
    match = re.search(r"(?im)^TITLe?\s+(.*?)\s*(!.*)?$", deck.read_text())
    return match.group(1)


def figure_texts(fig) -> str:
    return "\n".join([fig._suptitle.get_text() if fig._suptitle else ""]
                     + [ax.get_title() for ax in fig.axes])


def check_labels(fig) -> None:
    """Every axis with data has a y label with its unit, and an x label with its unit or shares
    its x axis with one that has (the bottom row of stacked histories)."""
    for ax in fig.axes:
        if not ax.has_data():
            continue
        assert WITH_UNIT.match(ax.get_ylabel()), f"y label without a unit: {ax.get_ylabel()!r}"
        xlabels = [other.get_xlabel() for other in ax.get_shared_x_axes().get_siblings(ax)]
        assert any(WITH_UNIT.match(label) for label in xlabels), f"x labels without a unit: {xlabels}"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("examples")
    return {name: run_deck(tmp, ROOT / "decks" / f"{name}.deck") for name in EXAMPLES}


@pytest.mark.parametrize("name", EXAMPLES)
def test_every_figure_has_units_and_the_deck_title(runs, name):
    out = runs[name]
    run = plot.Run(out, 4, 0)
    title = deck_title(ROOT / "decks" / f"{name}.deck")
    figures = [plot.plot_paths(run), plot.plot_angles(run),
               plot.plot_iterations(run, fs.read_steps(out / "steps.csv"))]
    figures += [plot.plot_history(run, series, plot.history_groups(run, None))
                for series in run.points.values()]
    for fig in figures:
        assert title in figure_texts(fig), f"{name}: no deck title in {figure_texts(fig)!r}"
        check_labels(fig)
        plot.fc.pyplot().close(fig)


def segments(fig) -> set[tuple[float, float, float, float]]:
    """Every straight two-point line of a figure, rounded."""
    found = set()
    for ax in fig.axes:
        for line in ax.get_lines():
            x, y = line.get_data()
            if len(x) == 2:
                found.add(tuple(np.round([x[0], y[0], x[1], y[1]], 9)))
    return found


@pytest.mark.parametrize("name", EXAMPLES)
def test_the_mechanism_plot_draws_every_link_at_every_instant(runs, name):
    """Whatever the deck tracks: every link of mesh.csv, between its end nodes' positions of
    nodes.csv, at each of the instants."""
    out = runs[name]
    run = plot.Run(out, 3, 0)
    links = [row.split(",") for row in (out / "mesh.csv").read_text().split()[1:]]
    assert len(run.drawable_links()) == len(links) > 0
    fig = plot.plot_paths(run)
    drawn = segments(fig)
    assert 2 <= len(run.instant_targets) <= 3
    for target in run.instant_targets:
        _, _, where = run.frame(target)
        for link, node1, node2 in links:
            (x1, y1), (x2, y2) = where[node1], where[node2]
            assert tuple(np.round([x1, y1, x2, y2], 9)) in drawn, f"{name}: link {link} not drawn"
    labels = [text.get_text() for ax in fig.axes for text in ax.get_legend().get_texts()]
    tracked = (out / "mechanism.txt").read_text().split("track,")[1].split()[0].split(",")
    assert all(f"path of {p}" in labels or f"{p} (fixed)" in labels for p in tracked)
    plot.fc.pyplot().close(fig)


def test_supports_and_guides_are_drawn(runs):
    """The quick-return's two pivots get ground symbols and its slider's guide a band."""
    run = plot.Run(runs["quick-return"], 2, 0)
    fig = plot.plot_paths(run)
    ax = fig.axes[0]
    assert len(ax.patches) == 2
    guide = [line for line in ax.get_lines() if line.get_label() == "ground guide of P"]
    assert len(guide) == 1 and list(guide[0].get_xdata()) == [-400, 100]
    plot.fc.pyplot().close(fig)


def test_round_off_is_drawn_as_round_off(runs):
    """The slider-crank's slider stays on y = 0: its y, vy and ay axes span a few percent of
    the x components' magnitudes, not the 1e-15 of the noise, and say so."""
    run = plot.Run(runs["slider-crank"], 0, 0)
    fig = plot.plot_history(run, run.points["B"], ["position", "velocity", "acceleration"])
    axes = np.array(fig.axes).reshape(3, 2)
    for row in range(3):
        x_span = np.ptp(axes[row, 0].get_ylim())
        low, high = axes[row, 1].get_ylim()
        assert high - low >= 0.02 * x_span, f"row {row}: y axis {low, high} shows the noise"
        assert any("round-off" in text.get_text() for text in axes[row, 1].texts)
    plot.fc.pyplot().close(fig)


def test_units_line_of_the_deck_labels_the_axes(tmp_path):
    text = (ROOT / "decks" / "fourbar.deck").read_text().replace("OUTPut", "OUTPut\n  units length=mm time=ms", 1)
    deck = tmp_path / "mm.deck"
    deck.write_text(text)
    out = run_deck(tmp_path, deck)
    run = plot.Run(out, 2, 0)
    fig = plot.plot_history(run, run.points["C"], ["position", "velocity", "acceleration"])
    labels = [ax.get_ylabel() for ax in fig.axes] + [fig.axes[-1].get_xlabel()]
    assert labels == ["x (mm)", "y (mm)", "vx (mm/ms)", "vy (mm/ms)", "ax (mm/ms²)", "ay (mm/ms²)", "t (ms)"]
    plot.fc.pyplot().close(fig)


@pytest.mark.parametrize(("line", "message"), [
    ("units length", "expected length=NAME or time=NAME"),
    ("units mass=kg", "unknown unit 'mass'"),
    ("units length=", "a unit name of 1 to 16 characters"),
])
def test_bad_units_lines_are_deck_errors(tmp_path, line, message):
    text = (ROOT / "decks" / "fourbar.deck").read_text().replace("OUTPut", f"OUTPut\n  {line}", 1)
    deck = tmp_path / "bad.deck"
    deck.write_text(text)
    proc = subprocess.run([fekap_binary(), "-q", "-o", str(tmp_path / "o"), str(deck)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert message in proc.stderr and f"{deck}:" in proc.stderr


def test_animation_is_written_with_bounded_frames(tmp_path):
    """A 2,000-step run: an MP4 (or a GIF without ffmpeg) of at most MAX_FRAMES frames, the
    time and the drive's value shown."""
    out = run_deck(tmp_path, ROOT / "decks" / "fourbar.deck", "--dt", "5e-4")
    run = plot.Run(out, 0, plot.MAX_FRAMES)
    assert len(run.frame_targets) == plot.MAX_FRAMES
    target = plot.animate(run, out, "auto")
    assert target.is_file() and target.stat().st_size > 10_000
    frames = [run.frame(t) for t in run.frame_targets]
    name, values = plot.drive_values(run, frames)
    assert name == "angle of AB"
    # The crank turns once: 0 to 360 degrees.
    assert values[-1] - values[0] == pytest.approx(360, abs=1e-6)
    if target.suffix == ".mp4":
        probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                                "-show_entries", "stream=nb_read_frames,width,height", "-of", "csv=p=0",
                                str(target)], capture_output=True, text=True)
        width, height, count = map(int, probe.stdout.strip().split(","))
        assert count == plot.MAX_FRAMES and width >= 640 and height >= 480


def test_decimation_keeps_every_extremum():
    """A million-row series with one-step spikes: the kept rows hold every spike and at most
    about three rows per bucket."""
    steps = np.arange(1_000_000)
    values = np.sin(steps * 1e-5)
    spikes = [12_345, 500_000, 999_998]
    values[spikes] = [5.0, -7.0, 9.0]
    reducer = fs.Reducer(0, steps[-1], 1, buckets=1000)
    for start in range(0, steps.size, 65_536):
        block = np.column_stack([steps, steps * 1e-6, values])[start:start + 65_536]
        reducer.feed(block)
    rows, masks = reducer.finish()
    series = fs.Reduced("s", ("v",), rows, masks)
    kept_steps, _, kept = series.curve("v")
    assert len(kept) <= 3 * 1000 + 3
    assert set(spikes) <= set(kept_steps.tolist())
    assert kept.max() == 9.0 and kept.min() == -7.0
    assert np.all(np.diff(kept_steps) > 0)


def test_plot_reads_a_run_without_nodes_csv(runs, tmp_path):
    """An output directory of an older run (no nodes.csv, no mechanism.txt): the tracked points
    stand in for the nodes and the directory's name for the title."""
    import shutil

    out = tmp_path / "old"
    shutil.copytree(runs["fourbar"], out)
    (out / "nodes.csv").unlink()
    (out / "mechanism.txt").unlink()
    run = plot.Run(out, 2, 0)
    fig = plot.plot_paths(run)
    assert fig._suptitle.get_text() == "old"
    assert run.drawable_links() == [("BC", "B", "C")]
    plot.fc.pyplot().close(fig)
