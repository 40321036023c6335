"""The pictures of a spatial run (issue 33, item 4), chosen by mechanism.txt's
``analysis,kinematics,spatial`` record: views.png (front x-y, top x-z, side y-z and an
axonometric view), joints.png, the x-y-z histories and the animation of the four views,
checked through matplotlib's objects against the files they are drawn from.

The runs are written here from closed forms in the format of a spatial run's files (nodes.csv
``step,t,A.x,A.y,A.z,...``, mechanism.txt's node, joint, drive and track records, points.csv
and joints.csv): the RSSR of decks/spatial/rssr.deck and the spatial slider-crank of
decks/spatial/slider-crank.deck (the closed forms of test_spatial_decks.py).

Run alone:  scripts/test spatial_plots
"""

from __future__ import annotations

import csv
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fekap import plot, plot3d

from apptest import ROOT, fekap_binary

PLOT = ROOT / "scripts" / "plot.py"


def fmt(value: float) -> str:
    """A number as FEKAP writes it (round-trip digits)."""
    return f"{value:.16E}"


def fixed(t: np.ndarray, x: float, y: float, z: float) -> tuple[np.ndarray, ...]:
    """A node that does not move: its (position, velocity, acceleration) at the times t."""
    return np.tile([x, y, z], (t.size, 1)), np.zeros((t.size, 3)), np.zeros((t.size, 3))


def rssr(t: np.ndarray) -> tuple[dict, dict]:
    """The RSSR of decks/spatial/rssr.deck at the crank angle phi = 2 pi t: every node's
    (position, velocity, acceleration), and the joints' (angle, rate, acceleration).

    Input crank O-B about z, radius 1; output crank P-C about x through P = (1, 4, 0), radius
    2; C = P + 2 (0, cos psi, sin psi) with cos psi = [12 - (1 - cos phi)^2 - (4 - sin phi)^2]
    / [4 (4 - sin phi)] (sin psi > 0)."""
    w = 2 * math.pi
    phi = w * t
    s, c = np.sin(phi), np.cos(phi)
    n = 12 - (1 - c) ** 2 - (4 - s) ** 2
    n1 = -2 * (1 - c) * s + 2 * (4 - s) * c
    n2 = -2 * s**2 - 2 * (1 - c) * c - 2 * c**2 - 2 * (4 - s) * s
    d, d1, d2 = 4 * (4 - s), -4 * c, 4 * s
    u = n / d
    u1 = (n1 * d - n * d1) / d**2
    u2 = (n2 * d - n * d2) / d**2 - 2 * d1 * (n1 * d - n * d1) / d**3
    root = np.sqrt(1 - u**2)
    psi = np.arccos(u)
    # Rates in time: dpsi/dt = psi' w, d2psi/dt2 = psi'' w^2.
    psi_t, psi_tt = -u1 / root * w, (-u2 / root - u * u1**2 / root**3) * w**2
    zero, one = np.zeros_like(t), np.ones_like(t)
    b = (np.stack([c, s, zero], 1), np.stack([-s * w, c * w, zero], 1), np.stack([-c * w**2, -s * w**2, zero], 1))
    cp = (np.stack([one, 4 + 2 * np.cos(psi), 2 * np.sin(psi)], 1),
          np.stack([zero, -2 * np.sin(psi) * psi_t, 2 * np.cos(psi) * psi_t], 1),
          np.stack([zero, -2 * (np.cos(psi) * psi_t**2 + np.sin(psi) * psi_tt),
                    2 * (-np.sin(psi) * psi_t**2 + np.cos(psi) * psi_tt)], 1))
    nodes = {"O": fixed(t, 0, 0, 0), "B": b, "B2": b, "C2": cp, "C": cp, "P": fixed(t, 1, 4, 0)}
    joints = {"JO": (phi, zero + w, zero), "JP": (psi - psi[0], psi_t, psi_tt)}
    return nodes, joints


RSSR = dict(title="RSSR spatial four-bar", units=None,
            links=[("crank", "O", "B"), ("coupler", "B2", "C2"), ("rocker", "P", "C")],
            joints=[("JO", "revolute", "ground", "O", (0, 0, 1)), ("JB", "spherical", "B", "B2", ()),
                    ("JC", "spherical", "C2", "C", ()), ("JP", "revolute", "ground", "P", (1, 0, 0))],
            drive=("rotation", "JO"), track=("B", "C"), motion=rssr, t_end=1.0)


def slider_crank(t: np.ndarray) -> tuple[dict, dict]:
    """The spatial slider-crank of decks/spatial/slider-crank.deck at theta = 6 t: crank tip
    B = A + r (0, -sin, cos), A = (0, 0.1, 0.12), r = 0.08; slider S = (x, 0, 0),
    x = sqrt(0.0592 + 0.016 sin theta - 0.0192 cos theta)."""
    w, r = 6.0, 0.08
    theta = w * t
    g = 0.0592 + 0.016 * np.sin(theta) - 0.0192 * np.cos(theta)
    g1 = 0.016 * np.cos(theta) + 0.0192 * np.sin(theta)
    g2 = -0.016 * np.sin(theta) + 0.0192 * np.cos(theta)
    x = np.sqrt(g)
    xd = w * g1 / (2 * x)
    xdd = w**2 * (g2 / (2 * x) - g1**2 / (4 * x**3))
    zero = np.zeros_like(t)
    b = (np.stack([zero, 0.1 - r * np.sin(theta), 0.12 + r * np.cos(theta)], 1),
         np.stack([zero, -r * w * np.cos(theta), -r * w * np.sin(theta)], 1),
         np.stack([zero, r * w**2 * np.sin(theta), -r * w**2 * np.cos(theta)], 1))
    s = (np.stack([x, zero, zero], 1), np.stack([xd, zero, zero], 1), np.stack([xdd, zero, zero], 1))
    nodes = {"A": fixed(t, 0, 0.1, 0.12), "B": b, "B2": b, "S": s, "S2": s}
    joints = {"JA": (theta, zero + w, zero), "JS": (x - 0.2, xd, xdd)}
    return nodes, joints


SLIDER_CRANK = dict(title="IFToMM spatial slider-crank", units=("m", "s"),
                    links=[("crank", "A", "B"), ("rod", "B2", "S2")],
                    joints=[("JA", "revolute", "ground", "A", (1, 0, 0)), ("JB", "spherical", "B", "B2", ()),
                            ("JU", "universal", "S", "S2", (1, 0, 0, 0, -2, 1)),
                            ("JS", "prismatic", "ground", "S", (1, 0, 0))],
                    drive=("rotation", "JA"), track=("B", "S"), motion=slider_crank, t_end=math.pi / 3)


def write_spatial_run(directory: Path, model: dict, steps: int) -> Path:
    """A spatial run's output directory, in the format of FEKAP's files, from a closed form."""
    directory.mkdir(parents=True, exist_ok=True)
    t = np.linspace(0.0, model["t_end"], steps + 1)
    nodes, joints = model["motion"](t)
    lines = ["record,fields", f'title,"{model["title"]}"']
    if model["units"]:
        lines += [f"units,length,{model['units'][0]}", f"units,time,{model['units'][1]}"]
    lines += [f"node,{name},{','.join(fmt(v) for v in value[0][0])}" for name, value in nodes.items()]
    lines.append("analysis,kinematics,spatial")
    for name, kind, first, second, axes in model["joints"]:
        lines.append(",".join(["joint", name, kind, first, second] + [fmt(float(v)) for v in axes]))
    lines.append(",".join(["drive", *model["drive"]]))
    lines.append(",".join(["track", *model["track"]]))
    (directory / "mechanism.txt").write_text("\n".join(lines) + "\n")
    (directory / "mesh.csv").write_text("link,node1,node2\n" + "".join(f"{','.join(link)}\n"
                                                                        for link in model["links"]))
    header = ["step", "t"] + [f"{name}.{axis}" for name in nodes for axis in "xyz"]
    rows = [",".join([str(k), fmt(tk)] + [fmt(v) for name in nodes for v in nodes[name][0][k]])
            for k, tk in enumerate(t)]
    (directory / "nodes.csv").write_text("\n".join([",".join(header)] + rows) + "\n")
    rows = ["step,t,point,x,y,z,vx,vy,vz,ax,ay,az"]
    rows += [",".join([str(k), fmt(tk), name] + [fmt(v) for part in nodes[name] for v in part[k]])
             for k, tk in enumerate(t) for name in model["track"]]
    (directory / "points.csv").write_text("\n".join(rows) + "\n")
    rows = ["step,t,joint,angle,rate,acceleration"]
    rows += [",".join([str(k), fmt(tk), name] + [fmt(part[k]) for part in value])
             for k, tk in enumerate(t) for name, value in joints.items()]
    (directory / "joints.csv").write_text("\n".join(rows) + "\n")
    rows = ["step,t,iterations,residual,cuts"] + [f"{k},{fmt(tk)},{1 + k % 2},{fmt(1e-15)},0"
                                                  for k, tk in enumerate(t)]
    (directory / "steps.csv").write_text("\n".join(rows) + "\n")
    return directory


def table(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def node_positions(out: Path) -> dict[int, dict[str, np.ndarray]]:
    """nodes.csv read independently of fekap.stream: step -> node -> (x, y, z)."""
    found = {}
    for row in table(out / "nodes.csv"):
        names = [key[:-2] for key in row if key.endswith(".x")]
        found[int(row["step"])] = {n: np.array([float(row[f"{n}.{a}"]) for a in "xyz"]) for n in names}
    return found


def point_columns(out: Path, name: str) -> dict[str, np.ndarray]:
    rows = [row for row in table(out / "points.csv") if row["point"] == name]
    return {key: np.array([float(row[key]) for row in rows]) for key in rows[0] if key != "point"}


def flat_lines(ax) -> list[np.ndarray]:
    """The data of every line of a 2D axes, as (n, 2) arrays."""
    return [np.column_stack(line.get_data()).astype(float) for line in ax.get_lines()]


def iso_lines(ax) -> list[np.ndarray]:
    """The data of every line of the axonometric axes, as (n, 3) arrays."""
    return [np.column_stack(line.get_data_3d()).astype(float) for line in ax.get_lines()]


def has_line(lines: list[np.ndarray], want: np.ndarray) -> bool:
    return any(line.shape == want.shape and np.array_equal(line, want) for line in lines)


@pytest.fixture
def rssr_run(tmp_path):
    return write_spatial_run(tmp_path / "rssr", RSSR, 40)


def test_the_views_project_every_link_at_every_instant(rssr_run):
    """views.png: in the front, top and side views a link is the segment between its nodes'
    (x, y), (x, z) and (y, z) of nodes.csv at each instant, in the axonometric view between
    their (x, y, z); the four views at one scale."""
    run = plot3d.SpatialRun(rssr_run, 4, 0)
    fig = plot3d.plot_views(run)
    panels = {ax.get_title(): ax for ax in fig.axes}
    front, top, side = (panels[f"{v} view ({a})"] for v, a in (("front", "x-y"), ("top", "x-z"), ("side", "y-z")))
    iso = panels["axonometric view"]
    assert (front.get_xlabel(), front.get_ylabel()) == ("x (length)", "y (length)")
    assert (top.get_xlabel(), top.get_ylabel()) == ("x (length)", "z (length)")
    assert (side.get_xlabel(), side.get_ylabel()) == ("y (length)", "z (length)")
    positions = node_positions(rssr_run)
    instants = sorted({run.frame(target)[0] for target in run.instant_targets})
    assert instants == [0, 10, 20, 30]
    for step in instants:
        where = positions[step]
        for _, a, b in RSSR["links"]:
            segment = np.array([where[a], where[b]])
            for ax, (i, j) in ((front, (0, 1)), (top, (0, 2)), (side, (1, 2))):
                assert has_line(flat_lines(ax), segment[:, [i, j]]), (step, a, b, ax.get_title())
            assert has_line(iso_lines(iso), segment), (step, a, b)
    # One scale: every view spans the same length across and up, the axonometric box a cube.
    spans = [np.diff(lim)[0] for ax in (front, top, side, iso) for lim in (ax.get_xlim(), ax.get_ylim())]
    assert np.allclose(spans, spans[0], rtol=1e-12)
    assert np.diff(iso.get_zlim())[0] == pytest.approx(spans[0], rel=1e-12)
    assert np.allclose(iso.get_box_aspect(), iso.get_box_aspect()[0])
    for ax in (front, top, side):
        assert ax.get_aspect() == 1.0


def test_the_paths_are_the_tracked_coordinates_of_points_csv(rssr_run):
    run = plot3d.SpatialRun(rssr_run, 4, 0)
    fig = plot3d.plot_views(run)
    front, top, side, iso = fig.axes[:4]
    assert "front" in front.get_title() and "top" in top.get_title() and "side" in side.get_title()
    for name in RSSR["track"]:
        p = point_columns(rssr_run, name)
        xyz = np.column_stack([p["x"], p["y"], p["z"]])
        assert len(xyz) == 41
        for ax, (i, j) in ((front, (0, 1)), (top, (0, 2)), (side, (1, 2))):
            assert has_line(flat_lines(ax), xyz[:, [i, j]]), (name, ax.get_title())
        assert has_line(iso_lines(iso), xyz), name
    labels = fig.legends[0].get_texts()
    assert {"path of B", "path of C", "revolute joint", "spherical joint",
            "ground joints' axes"} <= {text.get_text() for text in labels}


def test_joints_are_marked_by_kind_and_the_ground_axes_drawn(rssr_run):
    """The revolute joints at O and P, the spherical ones at B and C2, marked by kind at each
    instant; the ground axes: JO's (+z) an arrow in the top and side views and a ring with a dot
    in the front view (z points at the viewer), JP's (+x) an arrow in the front and top views
    and a ring with a dot in the side view (e_y x e_z = +x)."""
    run = plot3d.SpatialRun(rssr_run, 2, 0)
    fig = plot3d.plot_views(run)
    front, top, side = fig.axes[:3]
    positions = node_positions(rssr_run)
    for step in (0, 20):
        where = positions[step]
        for kind, nodes in (("revolute", ("O", "P")), ("spherical", ("B", "C2"))):
            marker = plot3d.JOINT_MARKERS[kind]
            marked = [np.column_stack(line.get_data()) for line in front.get_lines()
                      if line.get_marker() == marker and line.get_linestyle() == "None"]
            assert has_line(marked, np.array([where[n][:2] for n in nodes])), (step, kind)
    length = plot3d.AXIS_ARROW * run.size
    arrows = {ax.get_title(): {(tuple(np.round(a.xyann, 12)), tuple(np.round(a.xy, 12)))
                               for a in ax.texts if a.arrow_patch is not None} for ax in (front, top, side)}
    assert arrows["top view (x-z)"] == {((0, 0), (0, round(length, 12))), ((1, 0), (round(1 + length, 12), 0))}
    assert arrows["front view (x-y)"] == {((1, 4), (round(1 + length, 12), 4))}
    assert arrows["side view (y-z)"] == {((0, 0), (0, round(length, 12)))}
    for ax, place in ((front, (0, 0)), (side, (4, 0))):
        rings = [line for line in ax.get_lines() if line.get_marker() in ("o", ".") and
                 np.array_equal(np.column_stack(line.get_data()), [place])]
        assert {line.get_marker() for line in rings} == {"o", "."}, ax.get_title()


def test_the_joints_figure_is_joints_csv(tmp_path):
    """joints.png of the slider-crank: the crank JA in the revolute column (rad), the slider JS
    in the prismatic column (m), each curve joints.csv's."""
    out = write_spatial_run(tmp_path / "sc", SLIDER_CRANK, 30)
    run = plot3d.SpatialRun(out, 4, 0)
    fig = plot3d.plot_joints(run)
    axes = np.array(fig.axes).reshape(3, 2)
    assert [ax.get_ylabel() for ax in axes[:, 0]] == ["angle (rad)", "rate (rad/s)", "acceleration (rad/s²)"]
    assert [ax.get_ylabel() for ax in axes[:, 1]] == ["stroke (m)", "rate (m/s)", "acceleration (m/s²)"]
    rows = table(out / "joints.csv")
    for column, joint in ((0, "JA"), (1, "JS")):
        mine = [row for row in rows if row["joint"] == joint]
        t = np.array([float(row["t"]) for row in mine])
        for ax, quantity in zip(axes[:, column], plot3d.JOINT_QUANTITIES):
            (line,) = ax.get_lines()
            assert line.get_label() == joint
            want = np.column_stack([t, [float(row[quantity]) for row in mine]])
            assert np.array_equal(np.column_stack(line.get_data()), want)


def test_the_histories_have_x_y_and_z(tmp_path):
    out = write_spatial_run(tmp_path / "sc", SLIDER_CRANK, 30)
    run = plot3d.SpatialRun(out, 4, 0)
    series = run.points["B"]
    fig = plot.plot_history(run, series, plot.history_groups(run, None, plot3d.GROUPS), plot3d.GROUPS)
    axes = np.array(fig.axes).reshape(3, 3)
    p = point_columns(out, "B")
    for ax, quantity in zip(axes.flat, plot3d.POINT_QUANTITIES):
        unit = {"": "m", "v": "m/s", "a": "m/s²"}[quantity[:-1]]
        assert ax.get_ylabel() == f"{quantity} ({unit})"
        (line,) = ax.get_lines()
        assert np.array_equal(np.column_stack(line.get_data()), np.column_stack([p["t"], p[quantity]]))


def frame_count(movie: Path) -> int:
    if movie.suffix == ".gif":
        from PIL import Image

        with Image.open(movie) as image:
            return image.n_frames
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                            "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0", str(movie)],
                           capture_output=True, text=True, check=True)
    return int(probe.stdout.strip())


@pytest.mark.parametrize("kind", ["auto", "gif"])
def test_plot_py_draws_a_spatial_run(tmp_path, kind):
    """scripts/plot.py --animate on a spatial run: the spatial pictures (no paths.png, no
    angles.png), each recorded in the manifest, and an animation of one frame per written
    step (24 steps: 25 frames)."""
    out = write_spatial_run(tmp_path / "sc", SLIDER_CRANK, 24)
    done = subprocess.run([sys.executable, str(PLOT), str(out), "--animate", kind], capture_output=True,
                          text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    movie = "motion.gif" if kind == "gif" or not shutil.which("ffmpeg") else "motion.mp4"
    want = {"views.png", "joints.png", "history_B.png", "history_S.png", "iterations.png", movie,
            "motion-frame.png"}
    assert {Path(line.removeprefix("wrote ")).name for line in done.stdout.splitlines()} == want - {"motion-frame.png"}
    assert set((out / ".fekap-manifest").read_text().split()) == want
    for name in want:
        assert (out / name).stat().st_size > 1000, name
    assert frame_count(out / movie) == 25


def test_the_animation_frames_are_the_written_steps(tmp_path):
    """Movie.update(k) draws the links between the nodes of the k-th written step and the
    trails up to it; the time box gives the time and the crank's angle."""
    out = write_spatial_run(tmp_path / "rssr", RSSR, 20)
    run = plot3d.SpatialRun(out, 0, plot.MAX_FRAMES)
    movie = plot3d.Movie(run)
    assert [step for step, _, _ in movie.frames] == list(range(21))
    positions = node_positions(out)
    b = point_columns(out, "B")
    for k in (0, 7, 20):
        movie.update(k)
        where = positions[k]
        for a, c, lines in movie.links:
            segment = np.array([where[a], where[c]])
            for line, (_, i, j) in zip(lines[:3], movie.panels.flat):
                assert np.array_equal(np.column_stack(line.get_data()), segment[:, [i, j]])
            assert np.array_equal(np.column_stack(lines[3].get_data_3d()), segment)
        trail = movie.trails[0][0][3]
        assert np.array_equal(np.column_stack(trail.get_data_3d()),
                              np.column_stack([b["x"], b["y"], b["z"]])[:k + 1])
        assert movie.clock.get_text().startswith(f"t = {k / 20:.4g} time\n")
    # At step 7 the crank JO has turned 7/20 of a turn: 126 degrees.
    movie.update(7)
    assert "angle of JO = 126.0 deg" in movie.clock.get_text()
    plot.fc.pyplot().close(movie.fig)


def test_kinds_that_do_not_fit_the_run_are_refused(tmp_path, rssr_run):
    """--only angles on a spatial run, --only views or joints on a planar one: exit 2 and why."""
    done = subprocess.run([sys.executable, str(PLOT), str(rssr_run), "--only", "angles"], capture_output=True,
                          text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 2 and "joints.csv" in done.stderr, done.stderr
    planar = tmp_path / "planar"
    shutil.copytree(rssr_run, planar)
    text = (planar / "mechanism.txt").read_text().replace("analysis,kinematics,spatial", "analysis,kinematics")
    (planar / "mechanism.txt").write_text(text)
    for kind in ("views", "joints"):
        done = subprocess.run([sys.executable, str(PLOT), str(planar), "--only", kind], capture_output=True,
                              text=True, timeout=120, cwd=ROOT)
        assert done.returncode == 2 and "spatial runs only" in done.stderr, done.stderr


def test_every_figure_has_units_and_the_title(tmp_path):
    """Every axis of views.png, joints.png and the histories labelled with its unit (the deck's
    m and s), the colour bar too, and the title in every figure."""
    out = write_spatial_run(tmp_path / "sc", SLIDER_CRANK, 12)
    run = plot3d.SpatialRun(out, 3, 0)
    figures = [plot3d.plot_views(run), plot3d.plot_joints(run),
               plot.plot_history(run, run.points["S"], plot.history_groups(run, None, plot3d.GROUPS), plot3d.GROUPS)]
    with_unit = re.compile(r"^.+ \((m|s|rad|m/s|m/s²|rad/s|rad/s²)\)$")
    for fig in figures:
        assert fig._suptitle.get_text().startswith(SLIDER_CRANK["title"])
        for ax in fig.axes:
            labels = [ax.get_ylabel()] if ax.get_label() == "<colorbar>" else [ax.get_xlabel(), ax.get_ylabel()]
            if hasattr(ax, "get_zlabel"):
                labels.append(ax.get_zlabel())
            if ax.get_label() != "<colorbar>" and not ax.get_xlabel():
                # Stacked histories share the bottom row's time axis.
                labels = labels[1:]
            for label in labels:
                assert with_unit.match(label), (fig._suptitle.get_text(), label)
        plot.fc.pyplot().close(fig)


@pytest.mark.parametrize("deck", ["rssr", "slider-crank"])
def test_a_real_spatial_run_is_drawn_in_3d(tmp_path, deck):
    """fekap's own run of a spatial deck: views.png holds every link between its nodes of
    nodes.csv at each instant and the tracked paths of points.csv, joints.png joints.csv.
    Needs the 3D nodes.csv and mechanism.txt (branch spout); until then a spatial run's
    mechanism.txt has no spatial record and plot.py draws it as a planar one."""
    out = tmp_path / deck
    done = subprocess.run([fekap_binary(), "-q", "-o", str(out), str(ROOT / "decks" / "spatial" / f"{deck}.deck")],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    if "analysis,kinematics,spatial" not in (out / "mechanism.txt").read_text().splitlines():
        pytest.skip("this fekap writes a spatial run's nodes.csv and mechanism.txt in 2D")
    run = plot3d.SpatialRun(out, 3, 0)
    fig = plot3d.plot_views(run)
    front, top, side, iso = fig.axes[:4]
    positions = node_positions(out)
    links = [tuple(row.values()) for row in table(out / "mesh.csv")]
    for step in sorted({run.frame(target)[0] for target in run.instant_targets}):
        for _, a, b in links:
            segment = np.array([positions[step][a], positions[step][b]])
            for ax, (i, j) in ((front, (0, 1)), (top, (0, 2)), (side, (1, 2))):
                assert has_line(flat_lines(ax), segment[:, [i, j]]), (step, a, b, ax.get_title())
            assert has_line(iso_lines(iso), segment), (step, a, b)
    for name in run.mech.tracked:
        p = point_columns(out, name)
        assert has_line(iso_lines(iso), np.column_stack([p["x"], p["y"], p["z"]])), name
    joints = plot3d.plot_joints(run)
    rows = table(out / "joints.csv")
    for ax in joints.axes:
        for line in ax.get_lines():
            mine = [row for row in rows if row["joint"] == line.get_label()]
            assert mine, line.get_label()
            assert np.array_equal(line.get_xdata(), [float(row["t"]) for row in mine])
