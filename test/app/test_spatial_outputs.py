"""The outputs of a spatial run (issue 33, item 4) beside points.csv and
joints.csv: nodes.csv with z columns, mechanism.txt with the nodes' z, the
joints and their drives, both read back by fekap.read (node_positions,
read_spatial_mechanism, columns of joints.csv).

Run alone:  scripts/test spatial_outputs
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fekap import read

from apptest import ROOT, check, run_fekap

DECKS = ROOT / "decks" / "spatial"


def run_deck(deck: Path, out: Path, *extra: str) -> Path:
    done = run_fekap("-q", "-o", str(out), *extra, str(deck))
    check(done.returncode == 0, f"{deck.name}: exit {done.returncode}: {done.stderr}")
    return out


@pytest.fixture(scope="module")
def slider_crank(tmp_path_factory) -> Path:
    return run_deck(DECKS / "slider-crank.deck", tmp_path_factory.mktemp("slider-crank"))


@pytest.fixture(scope="module")
def bennett(tmp_path_factory) -> Path:
    return run_deck(DECKS / "bennett.deck", tmp_path_factory.mktemp("bennett"))


def test_nodes_csv_has_every_node_in_3d(slider_crank):
    """nodes.csv: `step,t,A.x,A.y,A.z,...`, every node at every step; the
    tracked nodes' columns are points.csv's numbers, the untracked ones (A,
    B2, S2) the closed form (the pivot fixed, the joint nodes at their
    partners' places)."""
    header = (slider_crank / "nodes.csv").read_text().splitlines()[0]
    check(header == "step,t," + ",".join(f"{n}.x,{n}.y,{n}.z" for n in ("A", "B", "B2", "S", "S2")),
          f"nodes.csv header: {header}")
    steps, t, nodes = read.node_positions(slider_crank / "nodes.csv")
    check(len(t) == 101 and list(steps) == list(range(101)), "every step of the deck")
    for name in ("B", "S"):
        points = read.columns(slider_crank / "points.csv", point=name)
        check(np.array_equal(nodes[name], np.stack([points["x"], points["y"], points["z"]], axis=1)),
              f"{name}: nodes.csv differs from points.csv")
    theta = 6 * t
    x = np.sqrt(0.0592 + 0.016 * np.sin(theta) - 0.0192 * np.cos(theta))
    zero = np.zeros_like(t)
    exact = {"A": np.stack([zero, zero + 0.1, zero + 0.12], axis=1),
             "B2": np.stack([zero, 0.1 - 0.08 * np.sin(theta), 0.12 + 0.08 * np.cos(theta)], axis=1),
             "S2": np.stack([x, zero, zero], axis=1)}
    for name, want in exact.items():
        err = np.max(np.abs(nodes[name] - want))
        check(err < 1e-12, f"{name}: largest error {err:.3e} from the closed form")


def test_mechanism_txt_of_the_slider_crank(slider_crank):
    """mechanism.txt in the format the 3D plots read: the exact records."""
    text = (slider_crank / "mechanism.txt").read_text()
    r = read.read_spatial_mechanism(slider_crank / "mechanism.txt")
    lines = text.splitlines()
    check(lines[0] == "record,fields" and lines[1] == 'title,"IFToMM spatial slider-crank"'
          and lines[2:4] == ["units,length,m", "units,time,s"], f"head of mechanism.txt: {lines[:4]}")
    check("analysis,kinematics,spatial" in lines, "no analysis,kinematics,spatial record")
    check(lines[-2:] == ["drive,rotation,JA", "track,B,S"], f"tail of mechanism.txt: {lines[-2:]}")
    check(r.nodes == {"A": (0.0, 0.1, 0.12), "B": (0.0, 0.1, 0.2), "B2": (0.0, 0.1, 0.2), "S": (0.2, 0.0, 0.0),
                      "S2": (0.2, 0.0, 0.0)}, f"nodes: {r.nodes}")
    check([(j.name, j.kind, j.first, j.second) for j in r.joints] == [
        ("JA", "revolute", "ground", "A"), ("JB", "spherical", "B", "B2"), ("JU", "universal", "S", "S2"),
        ("JS", "prismatic", "ground", "S")], f"joints: {r.joints}")
    axes = {j.name: np.array(j.axes) for j in r.joints}
    check(axes["JB"].size == 0 and np.array_equal(axes["JA"], [[1, 0, 0]]) and np.array_equal(axes["JS"], [[1, 0, 0]]),
          f"axes: {axes}")
    # The deck's second axis (0, -2, 1) as a unit vector.
    err = np.max(np.abs(axes["JU"] - np.array([[1, 0, 0], [0, -2 / math.sqrt(5), 1 / math.sqrt(5)]])))
    check(err < 4e-16, f"universal joint's axes off by {err:.3e}")
    check(r.drives == [("rotation", "JA")] and r.tracked == ["B", "S"] and r.units_given and r.length_unit == "m",
          f"drives, track, units: {r.drives}, {r.tracked}, {r.length_unit}")


def test_mechanism_txt_names_ground_second_and_stroke_drives(bennett, tmp_path):
    """A joint written `NODE ground` keeps the ground second; a stroke drive
    is written `drive,stroke,JOINT`."""
    r = read.read_spatial_mechanism(bennett / "mechanism.txt")
    r4 = [j for j in r.joints if j.name == "R4"]
    check(len(r4) == 1 and (r4[0].first, r4[0].second) == ("J4", "ground"), f"R4: {r4}")
    err = np.max(np.abs(np.array(r4[0].axes) - [[0, math.sqrt(3) / 2, 0.5]]))
    check(err < 1e-15, f"R4's axis off by {err:.3e}")
    text = (DECKS / "slider-crank.deck").read_text()
    check("  rotation JA rate 6\n" in text, "the slider-crank deck's drive changed")
    deck = tmp_path / "stroke.deck"
    deck.write_text(text.replace("  rotation JA rate 6\n", "  stroke JS harmonic 0 0.01 2\n"))
    out = run_deck(deck, tmp_path / "out")
    lines = (out / "mechanism.txt").read_text().splitlines()
    check("drive,stroke,JS" in lines and not any(line.startswith("drive,rotation") for line in lines),
          f"drive records: {[line for line in lines if line.startswith('drive')]}")


def test_joints_csv_reads_as_columns(slider_crank):
    """fekap.read.columns reads joints.csv, the joint names as text."""
    ja = read.columns(slider_crank / "joints.csv", joint="JA")
    check(ja["joint"].dtype.kind == "U" and len(ja["angle"]) == 101, "JA's rows")
    check(np.max(np.abs(ja["angle"] - 6 * ja["t"])) < 1e-12, "JA's angle is not 6 t")


def test_read_spatial_mechanism_refuses_bad_records(tmp_path):
    path = tmp_path / "mechanism.txt"
    path.write_text("record,fields\nanalysis,kinematics,spatial\njoint,J,revolute,ground,A,1,0\n")
    with pytest.raises(read.UsageError, match=r"mechanism.txt:3: bad joint record"):
        read.read_spatial_mechanism(path)
    path.write_text("record,fields\nanalysis,kinematics\n")
    with pytest.raises(read.UsageError, match="not the mechanism.txt of a spatial run"):
        read.read_spatial_mechanism(path)


def test_plots_draw_a_spatial_run(tmp_path):
    """scripts/plot.py reads a spatial run's nodes.csv and draws its 3D
    pictures (fekap.plot3d, test_spatial_plots.py), not the planar paths.png."""
    import subprocess
    import sys

    out = run_deck(DECKS / "slider-crank.deck", tmp_path / "out")
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "plot.py"), str(out)], capture_output=True,
                          text=True, timeout=300)
    check(done.returncode == 0, f"plot.py exit {done.returncode}: {done.stderr}")
    check((out / "views.png").is_file() and not (out / "paths.png").exists(), "no views.png, or a paths.png")


# ----------------------------------------------------------------- links.csv

def quaternion_product(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton products of rows of quaternions (q0, q1, q2, q3)."""
    p0, pv, q0, qv = p[:, :1], p[:, 1:], q[:, :1], q[:, 1:]
    return np.concatenate([p0 * q0 - np.sum(pv * qv, axis=1, keepdims=True),
                           p0 * qv + q0 * pv + np.cross(pv, qv)], axis=1)


def rotate(q: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Each row of x turned by the rotation of the same row of q."""
    xq = np.concatenate([np.zeros((len(x), 1)), x], axis=1)
    return quaternion_product(quaternion_product(q, xq), q * [1, -1, -1, -1])[:, 1:]


def link_series(out: Path, link: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """t, the quaternions, omega and alpha of one link of links.csv."""
    c = read.columns(out / "links.csv", link=link)
    check(c["t"].size > 0, f"no rows of {link} in links.csv")
    return (c["t"], np.stack([c[f"q{i}"] for i in range(4)], axis=1),
            np.stack([c[f"omega_{k}"] for k in "xyz"], axis=1), np.stack([c[f"alpha_{k}"] for k in "xyz"], axis=1))


def test_links_csv_header_and_closed_forms(slider_crank, tmp_path):
    """links.csv of a spatial run: `step,t,link,q0,q1,q2,q3,omega_*,alpha_*`,
    one row per link a step. The slider-crank's crank turns about +x by 6 t:
    q = (cos 3t, sin 3t, 0, 0) through the whole turn (q0 = -1 at its end:
    the sign follows the motion), omega = (6, 0, 0), alpha = 0. The RSSR's
    rocker turns about +x by psi - psi0; its coupler (a truss) carries its
    reference chord to the current one, with omega normal to it."""
    header = (slider_crank / "links.csv").read_text().splitlines()[0]
    check(header == "step,t,link,q0,q1,q2,q3,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z", f"header: {header}")
    t, q, w, a = link_series(slider_crank, "crank")
    zero = np.zeros_like(t)
    err = np.max(np.abs(q - np.stack([np.cos(3 * t), np.sin(3 * t), zero, zero], axis=1)))
    check(err < 1e-12 and q[-1, 0] < -1 + 1e-12, f"crank's quaternion off by {err:.3e}; at the end {q[-1]}")
    err = max(np.max(np.abs(w - [6, 0, 0])), np.max(np.abs(a)))
    check(err < 1e-10, f"crank's omega, alpha off by {err:.3e}")

    out = run_deck(DECKS / "rssr.deck", tmp_path / "rssr")
    t, q, w, a = link_series(out, "rocker")
    c = read.columns(out / "points.csv", point="C")
    psi = np.arctan2(c["z"], c["y"] - 4)
    rate = (c["vz"] * (c["y"] - 4) - c["vy"] * c["z"]) / 4
    half = (psi - psi[0]) / 2
    err = np.max(np.abs(q - np.stack([np.cos(half), np.sin(half), zero[:1] * half, zero[:1] * half], axis=1)))
    check(err < 1e-12, f"rocker's quaternion off by {err:.3e}")
    err = np.max(np.abs(w - np.stack([rate, 0 * rate, 0 * rate], axis=1)))
    check(err < 1e-10, f"rocker's omega off by {err:.3e}")
    t, q, w, a = link_series(out, "coupler")
    b = read.columns(out / "points.csv", point="B")
    chord = np.stack([c[k] - b[k] for k in "xyz"], axis=1)
    chord /= np.linalg.norm(chord, axis=1, keepdims=True)
    err = np.max(np.abs(rotate(q, np.broadcast_to(chord[0], chord.shape)) - chord))
    check(err < 1e-12, f"coupler: R e0 differs from the chord by {err:.3e}")
    check(np.max(np.abs(np.sum(w * chord, axis=1))) < 1e-10, "coupler's omega is not normal to its chord")
    vchord = np.stack([c["v" + k] - b["v" + k] for k in "xyz"], axis=1) / 4
    err = np.max(np.abs(np.cross(w, chord) - vchord))
    check(err < 1e-10, f"coupler: omega x e differs from e' by {err:.3e}")


@pytest.mark.parametrize("name", ["slider-crank", "bennett", "rssr", "bricard"])
def test_link_rates_match_differences_of_rotations(tmp_path, name):
    """omega = 2 vec(q' q*) and alpha = 2 vec(q'' q*) against central
    differences of the written quaternions, at two steps: the differences'
    error is O(h^2), so it falls by 4 when the step is halved (a link that
    turns at a constant rate is at round-off at both)."""
    end = math.pi / 3 if name == "slider-crank" else 1.0
    errors = {}
    for steps in (1000, 2000):
        out = run_deck(DECKS / f"{name}.deck", tmp_path / str(steps), "--dt", repr(end / steps))
        links = dict.fromkeys(read.columns(out / "links.csv")["link"].tolist())
        mesh = [row["link"] for row in read.rows(out / "mesh.csv")]
        check(list(links) == mesh, f"links.csv's links {list(links)}, not mesh.csv's {mesh}")
        for link in links:
            t, q, w, a = link_series(out, link)
            h = t[1] - t[0]
            conj = q[1:-1] * [1, -1, -1, -1]
            wd = 2 * quaternion_product((q[2:] - q[:-2]) / (2 * h), conj)[:, 1:]
            ad = 2 * quaternion_product((q[2:] - 2 * q[1:-1] + q[:-2]) / h**2, conj)[:, 1:]
            jump = np.max(np.linalg.norm(np.diff(q, axis=0), axis=1))
            check(jump < 20 * h, f"{link}: the quaternion jumps by {jump:.3e} in a step of {h:.3e}")
            errors.setdefault(link, []).append((np.max(np.abs(w[1:-1] - wd)), np.max(np.abs(a[1:-1] - ad)),
                                                np.max(np.abs(a))))
    for link, ((w1, a1, size), (w2, a2, _)) in errors.items():
        for what, e1, e2, floor in (("omega", w1, w2, 1e-9), ("alpha", a1, a2, 1e-6)):
            check(e2 < floor or 3.5 < e1 / e2 < 4.5,
                  f"{name} {link}: {what} against differences: {e1:.3e}, {e2:.3e} at h and h/2 (not O(h^2))")
        check(size > 0 or (a1 < 1e-6 and a2 < 1e-6), f"{name} {link}: alpha")


@pytest.mark.parametrize("name", ["rssr", "bricard"])
def test_link_rotations_stay_continuous_for_1000_turns(tmp_path, name):
    """Driven 1,000 turns at 25 steps a turn, written once a turn: the RSSR's
    crank is back at its start with its quaternion's sign flipped each turn
    ((-1)^k, as q(theta) = (cos theta/2, ...) goes), so the sign was followed
    through the steps not written; every other link (the rocker, the
    coupler's transported frame, Bricard's swinging links) is back at its
    start quaternion, sign included, within 1e-10, but the RSSR's coupler: a
    truss's transported frame comes back turned about its chord by the same
    angle each turn (test_truss_rotation_turns_by_the_swept_solid_angle)."""
    text = (DECKS / f"{name}.deck").read_text()
    check("  time 0 1 0.01\n" in text and "\n  track " in text, "the deck's time and track lines changed")
    deck = tmp_path / f"{name}.deck"
    deck.write_text(text.replace("  time 0 1 0.01\n", "  time 0 1000 0.04\n").replace(
        "\n  track ", "\n  every 25\n  track "))
    out = tmp_path / "out"
    done = run_fekap("-q", "-o", str(out), str(deck), timeout=900)
    check(done.returncode == 0, f"exit {done.returncode}: {done.stderr}")
    for link in dict.fromkeys(read.columns(out / "links.csv")["link"].tolist()):
        t, q, _, _ = link_series(out, link)
        check(len(t) == 1001, f"{link}: {len(t)} rows, not one a turn")
        sign = (-1.0) ** np.arange(1001) if (name, link) == ("rssr", "crank") else np.ones(1001)
        if (name, link) == ("rssr", "coupler"):
            # q_k = exp(k twist e0 / 2) q_0, e0 = q_0's chord (q_0 = 1).
            twist = 2 * math.atan2(np.linalg.norm(q[1, 1:]), q[1, 0])
            axis = q[1, 1:] / np.linalg.norm(q[1, 1:])
            k = np.arange(1001)[:, None]
            want = np.concatenate([np.cos(k * twist / 2), np.sin(k * twist / 2) * axis], axis=1)
            err = np.max(np.abs(q - want))
        else:
            err = np.max(np.abs(q - sign[:, None] * q[0]))
        check(err < 1e-10, f"{name} {link}: the quaternion after each turn differs by {err:.3e}")


def solid_angle(chords: np.ndarray) -> float:
    """The signed solid angle enclosed by a closed path of unit vectors: the
    sum of the triangles (e_0, e_i, e_i+1) (Van Oosterom and Strackee)."""
    a, b, c = chords[0], chords[:-1], chords[1:]
    numerator = np.einsum("j,ij->i", a, np.cross(b, c))
    denominator = 1 + b @ a + np.sum(b * c, axis=1) + c @ a
    return float(np.sum(2 * np.arctan2(numerator, denominator)))


def test_truss_rotation_turns_by_the_swept_solid_angle(tmp_path):
    """The RSSR's coupler (a truss) after one turn of the crank: its chord
    is back, and its frame, carried along without spin, is turned about the
    chord by the solid angle the chord swept (the holonomy of the transport),
    computed from points.csv at a fine step; the error falls by 4 when the
    step is halved (the frame is accumulated step by step, O(h^2))."""
    fine = run_deck(DECKS / "rssr.deck", tmp_path / "fine", "--dt", "1e-4")
    b, c = (read.columns(fine / "points.csv", point=p) for p in "BC")
    chords = np.stack([c[k] - b[k] for k in "xyz"], axis=1)
    chords /= np.linalg.norm(chords, axis=1, keepdims=True)
    omega = solid_angle(chords)
    check(abs(omega) > 0.01, f"the coupler's chord sweeps a solid angle of only {omega:.3e}")
    errors = []
    for dt in ("0.01", "0.005"):
        out = run_deck(DECKS / "rssr.deck", tmp_path / dt, "--dt", dt)
        _, q, _, _ = link_series(out, "coupler")
        turn = q[-1]
        check(np.linalg.norm(np.cross(turn[1:], chords[0])) < 1e-12, f"dt {dt}: not a turn about the chord: {turn}")
        angle = 2 * math.atan2(float(turn[1:] @ chords[0]), turn[0])
        errors.append(abs(angle - omega))
    check(errors[0] < 1e-3 and 3.5 < errors[0] / errors[1] < 4.5,
          f"twist after a turn against the solid angle {omega:.6f}: errors {errors[0]:.3e}, {errors[1]:.3e}")


# ----------------------------------------------------------------------- VTK

def test_vtk_files_of_a_spatial_run(tmp_path):
    """`files csv listing vtk` in a spatial deck: one .vtu a written step and
    the .pvd with their times; VTK and meshio read the same 3D points, the
    reference points are the deck's nodes (mechanism.txt), reference plus
    displacement is nodes.csv's positions at each step, velocity and
    acceleration are points.csv's, the cells are mesh.csv's links, and the
    node names are the model's."""
    import meshio
    from test_vtk import Mesh, read_pvd

    text = (DECKS / "slider-crank.deck").read_text()
    check("  track B S\n" in text, "the slider-crank deck's track line changed")
    deck = tmp_path / "crank.deck"
    deck.write_text(text.replace("  track B S\n", "  every 10\n  files csv listing vtk\n"))
    out = run_deck(deck, tmp_path / "out")
    collection = read_pvd(out / "crank.pvd")
    steps, t, nodes = read.node_positions(out / "nodes.csv")
    check([c[0] for c in collection] == t.tolist() and len(t) == 11, f"the .pvd's times {collection}")
    check(sorted(p.name for p in (out / "vtk").iterdir()) == [f"crank_{s:06d}.vtu" for s in steps],
          "one .vtu a written step")
    mech = read.read_spatial_mechanism(out / "mechanism.txt")
    names = list(mech.nodes)
    reference = np.array([mech.nodes[n] for n in names])
    links = read.rows(out / "mesh.csv")
    for k, (time, file) in enumerate(collection):
        mesh = Mesh(out / file)
        check(np.array_equal(mesh.reference, reference), f"{file}: the points are not the deck's nodes")
        where = np.stack([nodes[n][k] for n in names])
        err = np.max(np.abs(mesh.points - where))
        check(err < 1e-15, f"{file}: points + displacement differ from nodes.csv by {err:.3e}")
        for name, keys in (("velocity", ("vx", "vy", "vz")), ("acceleration", ("ax", "ay", "az"))):
            for node in ("B", "S"):
                row = read.rows(out / "points.csv", numbers=True, point=node)[k]
                got = mesh.point_data[name][names.index(node)]
                check(np.array_equal(got, [row[q] for q in keys]), f"{file}: {name} of {node} is not points.csv's")
        want = [[names.index(r["node1"]), names.index(r["node2"])] for r in links]
        check(np.array_equal(mesh.cells[0].data, want), f"{file}: cells {mesh.cells[0].data}, not mesh.csv's links")
        got = meshio.read(out / file)
        check(np.array_equal(got.points, mesh.reference) and np.array_equal(
            got.point_data["displacement"], mesh.point_data["displacement"]), f"{file}: meshio reads other points")
        node_names = [n.decode() for n in bytes(got.field_data["node_names"].astype(np.uint8)).split(b"\0")[:-1]]
        check(node_names == names, f"{file}: node_names {node_names}")
        check(float(mesh.field_data["TimeValue"][0]) == time, f"{file}: TimeValue differs from the .pvd")


def listing_block(listing: Path, title: str) -> list[list[str]]:
    """The rows of a listing block (the lines after its title and column
    header, to the blank line), split into fields."""
    lines = listing.read_text().splitlines()
    starts = [k for k, line in enumerate(lines) if line == title or line.startswith(title + " (")]
    check(len(starts) == 1, f"{listing.name}: {len(starts)} blocks {title}")
    rows = []
    for line in lines[starts[0] + 2:]:
        if not line.strip():
            break
        rows.append(line.split())
    return rows


def test_listing_echoes_the_spatial_model(slider_crank):
    """The listing of a spatial run echoes the model it ran: the nodes with
    z, the sections' six stiffnesses and orientation vector, the links as
    beams or trusses with their lengths in 3D (the IFToMM crank 0.08, its rod
    0.3), the joints with kind, nodes and axes, the drive of a joint angle."""
    listing = slider_crank / "slider-crank.lis"
    lines = listing.read_text().splitlines()
    header = lines[lines.index("NODES") + 1].split()
    check(header == ["name", "x", "y", "z"], f"NODES header: {header}")
    nodes = {row[0]: [float(v) for v in row[1:]] for row in listing_block(listing, "NODES")}
    want = {"A": [0, 0.1, 0.12], "B": [0, 0.1, 0.2], "B2": [0, 0.1, 0.2], "S": [0.2, 0, 0], "S2": [0.2, 0, 0]}
    check(nodes == want, f"NODES: {nodes}")
    sections = listing_block(listing, "SECTIONS")
    check([row[0] for row in sections] == ["rod"], f"SECTIONS: {sections}")
    check([float(v) for v in sections[0][1:7]] == [1.6e7, 6.0e6, 6.0e6, 1.2e2, 1.0e2, 1.0e2]
          and sections[0][7:] == ["0", "0", "0"], f"SECTIONS: {sections}")
    links = {row[0]: row[1:] for row in listing_block(listing, "LINKS")}
    check(set(links) == {"crank", "rod"}, f"LINKS: {links}")
    for name, ends, length in (("crank", ["A", "B"], 0.08), ("rod", ["B2", "S2"], 0.3)):
        row = links[name]
        check(row[:5] == [*ends, "rod", "1", "beam"] and abs(float(row[5]) - length) < 1e-11, f"{name}: {row}")
    joints = {row[0]: row[1:] for row in listing_block(listing, "JOINTS")}
    check({name: row[:3] for name, row in joints.items()} == {
        "JA": ["revolute", "ground", "A"], "JB": ["spherical", "B", "B2"], "JU": ["universal", "S", "S2"],
        "JS": ["prismatic", "ground", "S"]}, f"JOINTS: {joints}")
    # The axes as unit vectors, to the listing's 9 digits; a spherical joint has none.
    want_axes = {"JA": [1, 0, 0], "JB": [], "JU": [1, 0, 0, 0, -2 / math.sqrt(5), 1 / math.sqrt(5)], "JS": [1, 0, 0]}
    for name, axes in want_axes.items():
        got = [float(v.rstrip(",")) for v in joints[name][3:]]
        check(len(got) == len(axes) and np.allclose(got, axes, rtol=0, atol=1e-9), f"{name} axes: {joints[name]}")
    check(lines[lines.index("DRIVES") + 1].strip() == "angle of joint JA: angle = (initial angle) + 6*t",
          f"DRIVES: {lines[lines.index('DRIVES') + 1]}")


def test_listing_of_a_truss_a_ground_second_and_a_stroke_drive(bennett, tmp_path):
    """The RSSR's coupler listed as a truss of length 4 (its ends (1, 0, 0)
    and (1, 3.5, sqrt(15)/2)) whose section gives EA alone (the others
    left out as '-'); Bennett's joint R4 `J4 ground` keeps the ground second;
    a stroke drive is listed as the joint's stroke."""
    text = (DECKS / "rssr.deck").read_text()
    old = "  bar  EA=1  GA2=1  GA3=1  GJ=1  EI2=1  EI3=1\n"
    check(old in text and "  coupler  B2  C2  bar  truss\n" in text, "the RSSR deck's lines changed")
    deck = tmp_path / "rssr.deck"
    deck.write_text(text.replace(old, old + "  tie  EA=5\n").replace("  coupler  B2  C2  bar  truss\n",
                                                                    "  coupler  B2  C2  tie  truss\n"))
    out = run_deck(deck, tmp_path / "rssr")
    listing = out / "rssr.lis"
    links = {row[0]: row[1:] for row in listing_block(listing, "LINKS")}
    check(links["coupler"][:5] == ["B2", "C2", "tie", "1", "truss"] and abs(float(links["coupler"][5]) - 4) < 1e-11,
          f"coupler: {links['coupler']}")
    sections = {row[0]: row[1:] for row in listing_block(listing, "SECTIONS")}
    check(sections["tie"][:6] == ["5.0000000E+00", "-", "-", "-", "-", "-"], f"tie: {sections['tie']}")
    r4 = {row[0]: row[1:] for row in listing_block(bennett / "bennett.lis", "JOINTS")}["R4"]
    check(r4[:3] == ["revolute", "J4", "ground"], f"R4: {r4}")
    text = (DECKS / "slider-crank.deck").read_text()
    stroke = tmp_path / "stroke.deck"
    stroke.write_text(text.replace("  rotation JA rate 6\n", "  stroke JS harmonic 0 0.01 2\n"))
    lines = (run_deck(stroke, tmp_path / "stroke") / "stroke.lis").read_text().splitlines()
    check(lines[lines.index("DRIVES") + 1].strip().startswith("stroke of joint JS: stroke = "),
          f"DRIVES: {lines[lines.index('DRIVES') + 1]}")


def test_planar_listing_keeps_its_model_echo(tmp_path):
    """A planar run's listing keeps its planar echo (x and y, kGA, link
    angles); the same deck with --spatial lists its spatial model: z, the
    six stiffnesses, every hinge a revolute joint about +z."""
    deck = ROOT / "decks" / "fourbar.deck"
    planar = run_deck(deck, tmp_path / "planar") / "fourbar.lis"
    lines = planar.read_text().splitlines()
    check(lines[lines.index("NODES") + 1].split() == ["name", "x", "y"], "planar NODES header")
    check(lines[lines.index("SECTIONS") + 1].split() == ["name", "EA", "kGA", "EI"], "planar SECTIONS header")
    check("JOINTS (axes in global coordinates)" not in lines, "a planar listing with JOINTS")
    spatial = run_deck(deck, tmp_path / "spatial", "--spatial") / "fourbar.lis"
    lines = spatial.read_text().splitlines()
    check(lines[lines.index("NODES") + 1].split() == ["name", "x", "y", "z"], "--spatial NODES header")
    check(all(float(row[3]) == 0 for row in listing_block(spatial, "NODES")), "--spatial: z not 0")
    joints = listing_block(spatial, "JOINTS")
    check(bool(joints) and all(row[1] == "revolute" and row[-3:] == ["0", "0", "1"] for row in joints),
          f"--spatial joints: {joints}")
