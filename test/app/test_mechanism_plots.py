"""The figures of scripts/plot.py, checked through matplotlib's objects (not pixels): every
axis labelled with its unit, the deck's title in every figure, every link of the deck drawn in
the mechanism plot at every instant, round-off drawn as round-off; the animation and its layout;
decimation that keeps extrema; the deck's units line; the reaction, deflection and energy
figures of kinetostatics, statics and dynamics; text that cannot break a plot.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fekap import plot
from fekap import stream as fs

from apptest import ROOT, fekap_binary

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
    its x axis with one that has (the bottom row of stacked histories); a colour bar has its
    label with a unit."""
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            assert WITH_UNIT.match(ax.get_ylabel()), f"colour bar without a unit: {ax.get_ylabel()!r}"
            continue
        if not ax.has_data():
            continue
        assert WITH_UNIT.match(ax.get_ylabel()), f"y label without a unit: {ax.get_ylabel()!r}"
        xlabels = [other.get_xlabel() for other in ax.get_shared_x_axes().get_siblings(ax)]
        assert any(WITH_UNIT.match(label) for label in xlabels), f"x labels without a unit: {xlabels}"


#: Dynamics decks plotted too (short runs).
DYNAMICS = {"dynamics/slider-crank": ["--set", "t_end=0.02"], "dynamics/pendulum": []}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("examples")
    out = {name: run_deck(tmp, ROOT / "decks" / f"{name}.deck") for name in EXAMPLES}
    for name, args in DYNAMICS.items():
        deck = ROOT / "decks" / f"{name}.deck"
        proc = subprocess.run([fekap_binary(), "-q", "-o", str(tmp / name), *args, str(deck)],
                              capture_output=True, text=True, timeout=300, cwd=ROOT)
        assert proc.returncode == 0, proc.stderr
        out[name] = tmp / name
    return out


def all_figures(run, out):
    """Every figure plot.py draws of a run, the animation's included."""
    figures = [plot.plot_paths(run), plot.plot_angles(run),
               plot.plot_iterations(run, fs.read_steps(out / "steps.csv"))]
    figures += [plot.plot_history(run, series, plot.history_groups(run, None))
                for series in run.points.values()]
    if run.reactions:
        figures.append(plot.plot_reactions(run, components=True))
    if run.meshed():
        figures.append(plot.plot_deflection(run))
    energy = fs.read_energy(out / "energy.csv")
    if energy is not None:
        figures.append(plot.plot_energy(run, energy))
    return figures


@pytest.mark.parametrize("name", EXAMPLES + list(DYNAMICS))
def test_every_figure_has_units_and_the_deck_title(runs, name):
    out = runs[name]
    run = plot.Run(out, 4, 12)
    title = deck_title(ROOT / "decks" / f"{name}.deck")
    figures = all_figures(run, out)
    movie = plot.Movie(run)
    figures.append(movie.fig)
    expected = {"reactions": (out / "reactions.csv").is_file(), "energy": (out / "energy.csv").is_file()}
    texts = [figure_texts(fig) for fig in figures]
    assert any("reactions" in text for text in texts) == expected["reactions"]
    assert any("energy and momentum" in text for text in texts) == expected["energy"]
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
    nodes.csv (as magnified, where a magnification is stated), at each of the instants."""
    out = runs[name]
    run = plot.Run(out, 3, 0)
    links = [row.split(",") for row in (out / "mesh.csv").read_text().split()[1:]]
    assert len(run.drawable_links()) == len(links) > 0
    fig = plot.plot_paths(run)
    drawn = segments(fig)
    assert 2 <= len(run.instant_targets) <= 3
    for target in run.instant_targets:
        _, _, where = run.frame(target)
        where = run.shape(where)
        for link, node1, node2 in links:
            (x1, y1), (x2, y2) = where[node1], where[node2]
            assert tuple(np.round([x1, y1, x2, y2], 9)) in drawn, f"{name}: link {link} not drawn"
    if run.magnification != 1:
        assert f"magnified {run.magnification:g} times" in figure_texts(fig)
    labels = [text.get_text() for ax in fig.axes if ax.get_legend()
              for text in ax.get_legend().get_texts()]
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


def without_units(deck: Path) -> str:
    """A deck's text without its units line."""
    return "\n".join(line for line in deck.read_text().splitlines()
                     if not line.strip().startswith("units")) + "\n"


def test_units_line_of_the_deck_labels_the_axes(tmp_path):
    text = without_units(ROOT / "decks" / "fourbar.deck").replace("OUTPut", "OUTPut\n  units length=mm time=ms", 1)
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
    text = without_units(ROOT / "decks" / "fourbar.deck").replace("OUTPut", f"OUTPut\n  {line}", 1)
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


def reaction_rows(path: Path, kind: str) -> dict[tuple[str, str], np.ndarray]:
    """reactions.csv's rows of one kind: (link, node) -> rows of (t, fx, fy, m), read by the csv
    module (not plot.py's reader)."""
    import csv

    rows: dict[tuple[str, str], list] = {}
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            if row["kind"] == kind:
                rows.setdefault((row["link"], row["node"]), []).append(
                    [float(row[c]) for c in ("t", "fx", "fy", "m")])
    return {key: np.array(value) for key, value in rows.items()}


def test_the_kinetostatics_torque_figure_draws_reactions_csv(runs):
    """The four-bar's crank torque against time and against the crank angle: the data of the
    lines are reactions.csv's drive row (t, m), and the crank angle is links.csv's, in degrees."""
    out = runs["fourbar-kinetostatics"]
    run = plot.Run(out, 4, 0)
    fig = plot.plot_reactions(run)
    torque = reaction_rows(out / "reactions.csv", "drive")[("AB", "A")]
    lines = [line for ax in fig.axes for line in ax.get_lines() if line.get_label() == "torque on AB at A"]
    assert len(lines) == 2
    against_time, against_angle = lines
    np.testing.assert_array_equal(against_time.get_xdata(), torque[:, 0])
    np.testing.assert_array_equal(against_time.get_ydata(), torque[:, 3])
    np.testing.assert_array_equal(against_angle.get_ydata(), torque[:, 3])
    angle = np.array([float(r.split(",")[3]) for r in (out / "links.csv").read_text().split()[1:]
                      if r.split(",")[2] == "AB"])
    np.testing.assert_allclose(against_angle.get_xdata(), np.degrees(np.unwrap(angle)), atol=1e-9)
    assert against_time.axes.get_ylabel() == "torque on AB at A (N m)"
    assert against_angle.axes.get_xlabel() == "angle of AB (deg)"
    # The supports' force magnitudes are those of reactions.csv's support rows.
    supports = reaction_rows(out / "reactions.csv", "support")
    for (_link, node), rows in supports.items():
        line, = [l for ax in fig.axes for l in ax.get_lines() if l.get_label() == f"support {node}"]
        np.testing.assert_allclose(line.get_ydata(), np.hypot(rows[:, 1], rows[:, 2]), rtol=1e-15)
    plot.fc.pyplot().close(fig)


def test_the_statics_cantilever_is_drawn_through_its_17_nodes_magnified(runs):
    """nodes.csv holds the 15 interior mesh points by default in statics; paths.png draws the
    beam through all 17 points at each instant, with the deflection from the undeformed
    geometry magnified by the stated factor."""
    out = runs["statics-cantilever"]
    header = (out / "nodes.csv").read_text().split("\n", 1)[0].split(",")
    assert len(header) == 2 + 2 * 17 and "RT#15.x" in header
    run = plot.Run(out, 4, 0)
    assert run.chains["RT"] == ["R", *(f"RT#{k}" for k in range(1, 16)), "T"]
    fig = plot.plot_paths(run)
    beams = [line for line in fig.axes[0].get_lines() if len(line.get_xdata()) == 17]
    assert len(beams) == len(run.instant_targets) == 4
    m = run.magnification
    assert m > 10 and f"deflections magnified {m:g} times" in figure_texts(fig)
    _, _, where = run.frame(run.instant_targets[-1])
    x, y = beams[-1].get_data()
    # The tip: its initial position (2, 0) plus m times its displacement.
    assert x[-1] == pytest.approx(2 + m * (where["T"][0] - 2), abs=1e-12)
    assert y[-1] == pytest.approx(m * where["T"][1], abs=1e-12)
    assert -0.2 * run.size < y[-1] < -0.02 * run.size
    plot.fc.pyplot().close(fig)


def test_the_deflection_figure_is_the_largest_distance_from_the_chord(runs):
    """deflection.png's curve of the cantilever: at each load step the largest distance of an
    interior mesh point from the line R-T, computed here from nodes.csv."""
    out = runs["statics-cantilever"]
    run = plot.Run(out, 0, 0)
    fig = plot.plot_deflection(run)
    line, = fig.axes[0].get_lines()
    rows = np.array([[float(v) for v in r.split(",")] for r in (out / "nodes.csv").read_text().split()[1:]])
    xy = rows[:, 2:].reshape(len(rows), -1, 2)
    order = [0, *range(2, 17), 1]  # R, RT#1..RT#15, T
    chain = xy[:, order]
    chord = chain[:, -1] - chain[:, 0]
    offset = chain[:, 1:-1] - chain[:, :1]
    side = (chord[:, None, 0] * offset[..., 1] - chord[:, None, 1] * offset[..., 0]) / np.hypot(*chord.T)[:, None]
    expected = side[np.arange(len(side)), np.argmax(np.abs(side), axis=1)]
    np.testing.assert_allclose(line.get_ydata(), expected, rtol=1e-12, atol=1e-18)
    assert np.all(line.get_ydata()[1:] > 0)  # the chord R-T lies below the sagging beam's middle
    plot.fc.pyplot().close(fig)


@pytest.mark.parametrize("name", ["quick-return", "fourbar", "slider-crank-kinetostatics",
                                  "dynamics/slider-crank"])
def test_no_legend_or_text_box_covers_the_mechanism(runs, name):
    """In every frame of the animation the mechanism (every link and trail drawn) lies inside
    the drawing area and neither the legend nor the time box overlaps its bounding box; the
    frame is fitted to the motion (the mechanism spans at least half of it), not to a guide."""
    run = plot.Run(runs[name], 0, 60)
    movie = plot.Movie(run)
    renderer = movie.fig.canvas.get_renderer()
    boxes = [movie.clock] + ([movie.legend] if movie.legend is not None else [])
    ax_box = movie.ax.get_window_extent(renderer)
    for index in range(len(movie.frames)):
        movie.update(index)
        movie.fig.canvas.draw()
        drawn = [artist for _, line, ends in movie.links for artist in (line, ends)]
        drawn += [line for line, *_ in movie.trails]
        points = np.vstack([movie.ax.transData.transform(np.column_stack(a.get_data()))
                            for a in drawn if len(a.get_xdata())])
        low, high = points.min(axis=0), points.max(axis=0)
        assert ax_box.x0 <= low[0] and high[0] <= ax_box.x1 and ax_box.y0 <= low[1] and high[1] <= ax_box.y1
        for box in boxes:
            extent = box.get_window_extent(renderer)
            if hasattr(box, "get_bbox_patch") and box.get_bbox_patch() is not None:
                extent = box.get_bbox_patch().get_window_extent(renderer)
            overlap = not (extent.x1 < low[0] or high[0] < extent.x0 or extent.y1 < low[1] or high[1] < extent.y0)
            assert not overlap, f"{name}, frame {index}: {type(box).__name__} over the mechanism"
    # The motion fills the frame: no guide's length squeezes it.
    span = np.array([[movie.ax.get_xlim()], [movie.ax.get_ylim()]]).reshape(2, 2)
    low, high = plot.motion_box(run)
    assert max((high - low) / (span[:, 1] - span[:, 0])) > 0.5
    plot.fc.pyplot().close(movie.fig)


def test_the_drive_angle_is_wrapped():
    assert plot.wrap_degrees(np.array([849.5, 180.0, -180.0, 360.0, -190.0])).tolist() == \
        [129.5, 180.0, 180.0, 0.0, 170.0]
    assert plot.drive_text("angle of AB", 849.5, 0.0, "m") == "angle of AB = 129.5 deg\n  (in turn 3)"


def test_the_energy_figure_says_what_the_balance_is(runs):
    """generalized-alpha's balance is its numerical dissipation (the slider-crank, rho_inf 0.8)."""
    out = runs["dynamics/slider-crank"]
    run = plot.Run(out, 0, 0)
    fig = plot.plot_energy(run, fs.read_energy(out / "energy.csv"))
    assert "numerical dissipation" in figure_texts(fig) and "rho_inf = 0.8" in figure_texts(fig)
    assert fig.axes[0].get_ylabel() == "energy (J)"
    plot.fc.pyplot().close(fig)
    run.mech.integrator = "energy-momentum"
    assert "round-off" in plot.balance_meaning(run)


def test_statics_is_plotted_against_the_load_factor(runs):
    out = runs["statics-cantilever"]
    run = plot.Run(out, 0, 0)
    fig = plot.plot_history(run, run.points["T"], plot.history_groups(run, None))
    labels = [ax.get_ylabel() for ax in fig.axes] + [fig.axes[-1].get_xlabel()]
    assert labels == ["x (m)", "y (m)", "dx/dλ (m)", "dy/dλ (m)", "d²x/dλ² (m)", "d²y/dλ² (m)",
                      "load factor λ (-)"]
    plot.fc.pyplot().close(fig)


def test_the_support_symbol_is_sized_from_the_model(runs):
    """The clamp's ground symbol of the 2 m cantilever is 0.045 of its extent, not of the tip's
    millimetre of travel."""
    run = plot.Run(runs["statics-cantilever"], 2, 0)
    assert run.size == pytest.approx(2.0, rel=1e-3)
    fig = plot.plot_paths(run)
    triangle = fig.axes[0].patches[0].get_xy()
    assert np.ptp(triangle[:, 1]) == pytest.approx(0.045 * run.size, rel=1e-9)
    plot.fc.pyplot().close(fig)


def test_loads_masses_and_support_reactions_are_drawn(runs):
    """The slider-crank's load on the slider is an arrow, its 2 kg slider a dot, the pivot's
    reaction an arrow at the last step with its size in the legend."""
    run = plot.Run(runs["slider-crank-kinetostatics"], 3, 0)
    fig = plot.plot_paths(run)
    ax = fig.axes[0]
    arrows = [t for t in ax.texts if getattr(t, "arrow_patch", None) is not None]
    assert len(arrows) == 1 + len(run.mech.supports)
    assert len(ax.collections) == 1 and ax.collections[0].get_offsets().shape == (1, 2)
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert "loads (forces: arrows (direction))" in labels and any(l.startswith("support reactions at t = 1 ") for l in labels)
    plot.fc.pyplot().close(fig)


HOSTILE_TITLES = ["Cost $\\frac{1}{$ of a crank", "Crank $20 vs rocker $30", "_{x}^2 \\alpha $$ %s {}"]


@pytest.mark.parametrize("title", HOSTILE_TITLES)
def test_titles_are_plain_text(tmp_path, title):
    """A title with mathtext's characters is drawn as given, and every figure is written."""
    text = (ROOT / "decks" / "fourbar.deck").read_text().replace("TITLe   Four-bar linkage, dt = 0.025", f"TITLe {title}")
    deck = tmp_path / "hostile.deck"
    deck.write_text(text)
    out = run_deck(tmp_path, deck)
    assert plot.main([str(out), "--instants", "2"]) == 0
    run = plot.Run(out, 2, 0)
    fig = plot.plot_paths(run)
    assert fig._suptitle.get_text() == title
    fig.savefig(tmp_path / "check.png")
    plot.fc.pyplot().close(fig)


def test_a_latin1_title_and_a_128_kib_name_plot(tmp_path):
    """A Latin-1 byte in the title (fekap takes it as it is) and a node name of 128 KiB + 1:
    plot.py draws every figure, the title decoded as Latin-1."""
    name = "C" * (128 * 1024 + 1)
    text = (ROOT / "decks" / "fourbar.deck").read_text()
    text = text.replace("TITLe   Four-bar linkage, dt = 0.025", "TITLe   Vier-Gelenk f\xfcr M\xfcller")
    text = text.replace("  C   3", f"  {name}   3").replace("BC  B  C", f"BC  B  {name}") \
        .replace("DC  D  C", f"DC  D  {name}").replace("track B C", f"track B {name}")
    deck = tmp_path / "latin1.deck"
    deck.write_bytes(text.encode("latin-1"))
    out = run_deck(tmp_path, deck)
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "plot.py"), str(out), "--instants", "2"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (out / "paths.png").is_file() and (out / "history_B.png").is_file()
    run = plot.Run(out, 2, 0)
    assert run.title == "Vier-Gelenk für Müller"
    assert name in run.nodes.names and len(run.drawable_links()) == 3


def test_a_deck_without_units_is_labelled_length(tmp_path):
    """Without a units line: lengths "length", times "time", and the listing says so."""
    text = without_units(ROOT / "decks" / "fourbar.deck")
    deck = tmp_path / "nounits.deck"
    deck.write_text(text)
    out = run_deck(tmp_path, deck)
    run = plot.Run(out, 2, 0)
    assert (run.label("x"), run.label("vx"), run.label("t")) == ("x (length)", "vx (length/time)", "t (time)")
    assert "units: none given" in (out / "nounits.lis").read_text()


@pytest.mark.parametrize("name", ["fourbar-kinetostatics", "dynamics/pendulum"])
def test_a_units_line_changes_no_number(tmp_path, name):
    """The same deck without its units line: every CSV file byte for byte the same."""
    deck = ROOT / "decks" / f"{name}.deck"
    bare = tmp_path / "bare.deck"
    bare.write_text(without_units(deck))
    args = ["--dt", "0.01"] if name.startswith("dynamics") else []
    first = run_deck(tmp_path / "with", deck, *args)
    second = run_deck(tmp_path / "without", bare, *args)
    files = sorted(p.name for p in first.glob("*.csv"))
    assert "points.csv" in files and "reactions.csv" in files
    for file in files:
        assert (first / file).read_bytes() == (second / file).read_bytes(), file


def test_mesh_nodes_are_an_output_option(tmp_path):
    """Kinematics writes the named nodes only; OUTPut mesh on adds the interior points of a
    meshed link (on the straight link, for the rigid kinematics of the FEM and of the Cartesian
    method alike); mesh off leaves statics with its named nodes."""
    deck = ROOT / "decks" / "hard" / "quick-return-meshed-lever.deck"
    plain = run_deck(tmp_path / "plain", deck)
    header = (plain / "nodes.csv").read_text().split("\n", 1)[0]
    assert "#" not in header
    text = deck.read_text().replace("OUTPut", "OUTPut\n  mesh on", 1)
    meshed_deck = tmp_path / "meshed.deck"
    meshed_deck.write_text(text)
    for method in ("fem", "cartesian"):
        out = run_deck(tmp_path / method, meshed_deck, "--method", method)
        lines = (out / "nodes.csv").read_text().split()
        header = lines[0].split(",")
        interior = [c[:-2] for c in header if "#" in c and c.endswith(".x")]
        assert len(interior) == 3, header
        assert lines[0].startswith((plain / "nodes.csv").read_text().split("\n", 1)[0])
        run = plot.Run(out, 2, 0)
        link = interior[0].split("#")[0]
        chain = run.chains[link]
        assert len(chain) == 5
        for _, where in run.nodes.frames.values():
            assert plot.chord_deviation(chain, where) < 1e-6 * run.size
    text = (ROOT / "decks" / "statics-cantilever.deck").read_text().replace("OUTPut", "OUTPut\n  mesh off", 1)
    off = tmp_path / "off.deck"
    off.write_text(text)
    out = run_deck(tmp_path / "off", off)
    assert (out / "nodes.csv").read_text().split("\n", 1)[0] == "step,t,R.x,R.y,T.x,T.y"
