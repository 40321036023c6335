"""`fekap --spatial PLANAR.deck` (issue 33): every planar kinematics deck of
decks/ and decks/hard/ run as a spatial model (z = 0, hinges and pins
revolute joints about +z, SE(3) beams) reproduces its planar points.csv:
positions within 1e-12 of the model size, velocities and accelerations
within 1e-10 of the planar run's largest, z, vz and az zero; the decks'
redundant constraints (a planar loop of revolute joints about parallel axes
has three in 3D) included. Besides the decks: a roller with an x drive, a
prismatic ground guide, a clamp, a meshed link, a prismatic slider on a
moving link, each against its planar run; and what --spatial refuses
(kinetostatics, statics, dynamics, a rotation drive at a hinge, a prismatic
slider on a line of several links), each an input error that names the deck
(and its line) with nothing written. The sliders on moving links
(quick-return, quick-return-meshed-lever, slider-meshed-guide) run as
spatial slides (fekap_spatial_slideline); the slider on a line of two links
hinged together (hard/slider-over-hinge) as a slide whose line is carried
segment by segment, both runs checked against the deck's closed form."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from apptest import ROOT, check, read_rows, run_fekap

# The thresholds: positions relative to the model size (the largest
# coordinate of the planar run), rates relative to the planar run's largest.
POSITION_TOL = 1e-12
RATE_TOL = 1e-10
# z, vz, az of a planar mechanism: zero to round-off (relative to the same scales).
OUT_OF_PLANE_TOL = 1e-13

# Decks that are no kinematics: --spatial refuses them.
NOT_KINEMATICS = {"cantilever-rollup", "fourbar-kinetostatics", "slider-crank-kinetostatics", "statics-cantilever"}
# Decks the spatial stepper does not pass, and why (docs/spatial.md, "Planar decks with --spatial").
KNOWN_FAILURES: dict[str, dict[str, str]] = {}
# A row whose tangent is near singular (the listing's note "near a stationary
# configuration": the planar run's pivot ratio, the spatial run's condition
# estimate, against the run's best) has rates whose round-off grows as the
# inverse of that ratio (flat Peaucellier at t = 0.5, 0.013 degrees from its
# bifurcation: P's ax, exactly 0, is -3.2e-7 planar and -5.4e-7 spatial, and
# both shrink as the output time moves away from it; docs/spatial.md). There
# the rates are held to RATE_TOL over the spatial run's ratio, and the
# spatial run must flag no row that the planar run does not.
NEAR_SINGULAR = re.compile(r"note: step (\d+), [^\n]*?near a stationary configuration "
                           r"\((?:pivot ratio +([-+.0-9Ee]+)|the tangent's condition +([-+.0-9Ee]+) of the run's best)\)")
# Decks whose spatial run takes too long for the suite (none since the band solver).
TOO_SLOW: set[str] = set()


def planar_decks() -> list[str]:
    paths = sorted((ROOT / "decks").glob("*.deck")) + sorted((ROOT / "decks" / "hard").glob("*.deck"))
    return [str(p.relative_to(ROOT)) for p in paths]


def stem(deck: str) -> str:
    return Path(deck).stem


KINEMATICS = [d for d in planar_decks() if stem(d) not in NOT_KINEMATICS | TOO_SLOW]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The planar and the spatial run of a deck, each made once."""
    made: dict[str, tuple[Path, Path, object]] = {}

    def run(deck: str) -> tuple[Path, Path, object]:
        if deck not in made:
            base = tmp_path_factory.mktemp(stem(deck))
            planar, spatial = base / "planar", base / "spatial"
            done = run_fekap("-q", "-o", str(planar), deck, timeout=900)
            check(done.returncode == 0, f"{deck} planar: exit {done.returncode}: {done.stderr}")
            done = run_fekap("-q", "--spatial", "-o", str(spatial), deck, timeout=900)
            made[deck] = (planar, spatial, done)
        return made[deck]

    return run


def table(out: Path) -> dict[str, np.ndarray]:
    """points.csv by column; an empty field (the rates of a change point's
    singular row, left out) is NaN."""
    rows = read_rows(out / "points.csv", numbers=True)
    check(bool(rows), f"{out}: no rows")
    return {k: np.array([r[k] for r in rows]) if k == "point" else
            np.array([np.nan if r[k] is None else float(r[k]) for r in rows]) for k in rows[0]}


def flagged(out: Path) -> dict[int, float]:
    """The steps whose rates the listing notes as ill-conditioned (near a
    stationary configuration), with the ratio it gives."""
    listing = next(out.glob("*.lis")).read_text()
    return {int(m[1]): float(m[2] or m[3]) for m in NEAR_SINGULAR.finditer(listing)}


def compare(planar: Path, spatial: Path, what: str, steps: set[int] | None = None) -> dict[str, float]:
    """The largest differences of the spatial points.csv from the planar one,
    relative to the model size and the planar rates' largest values (the
    scales over every row); over the rows of the given steps only, if given."""
    p, s = table(planar), table(spatial)
    check(len(p["t"]) == len(s["t"]) and list(p["point"]) == list(s["point"]) and np.array_equal(p["t"], s["t"]),
          f"{what}: the spatial points.csv has other rows than the planar one")
    size = max(np.max(np.abs(p["x"])), np.max(np.abs(p["y"])))
    result = {"pos": max(np.max(np.abs(p[c] - s[c])) for c in "xy") / size,
              "z": np.max(np.abs(s["z"])) / size}
    for kind, cols, out_of_plane in (("vel", ("vx", "vy"), "vz"), ("acc", ("ax", "ay"), "az")):
        if cols[0] not in p:
            continue
        check(cols[0] in s, f"{what}: the spatial run has no {kind}")
        # Rates left out (a change point's singular row) in the same rows of both runs.
        for c in (*cols, out_of_plane):
            check(np.array_equal(np.isnan(p[cols[0]]), np.isnan(s[c])), f"{what}: {c} left out in other rows")
        scale = max(max(np.nanmax(np.abs(p[c])) for c in cols), 1e-300)
        rows = np.isin(p["step"], sorted(steps)) if steps is not None else np.full(len(p["t"]), True)
        result[kind] = max(np.nanmax(np.abs(p[c] - s[c])[rows], initial=0.0) for c in cols) / scale
        result[out_of_plane] = np.nanmax(np.abs(s[out_of_plane])[rows], initial=0.0) / scale
    return result


def mark_known(deck: str, part: str):
    reason = KNOWN_FAILURES.get(stem(deck), {}).get(part)
    return [pytest.mark.xfail(reason=reason, strict=True)] if reason else []


@pytest.mark.parametrize("deck", [pytest.param(d, marks=mark_known(d, "run")) for d in KINEMATICS])
def test_positions_match_planar(runs, deck):
    planar, spatial, done = runs(deck)
    check(done.returncode == 0, f"{deck} --spatial: exit {done.returncode}: {done.stderr}")
    err = compare(planar, spatial, deck)
    check(err["pos"] <= POSITION_TOL, f"{deck}: positions {err['pos']:.2e} of the model size off the planar run")
    check(err["z"] <= OUT_OF_PLANE_TOL, f"{deck}: z up to {err['z']:.2e} of the model size")


@pytest.mark.parametrize("deck", [pytest.param(d, marks=mark_known(d, "run") + mark_known(d, "rates"))
                                  for d in KINEMATICS])
def test_rates_match_planar(runs, deck):
    planar, spatial, done = runs(deck)
    check(done.returncode == 0, f"{deck} --spatial: exit {done.returncode}: {done.stderr}")
    near_p, near_s = flagged(planar), flagged(spatial)
    check(set(near_s) <= set(near_p), f"{deck}: the spatial run flags steps {sorted(set(near_s) - set(near_p))} "
                                      "ill-conditioned, the planar run does not")
    steps = set(table(planar)["step"].astype(int))
    groups = [(steps - set(near_s), 1.0)] + [({step}, ratio) for step, ratio in near_s.items()]
    for rows, ratio in groups:
        err = compare(planar, spatial, deck, rows)
        where = f" at step {min(rows)} (condition {ratio:.2e} of the best)" if ratio < 1 else ""
        for kind in ("vel", "acc"):
            if kind in err:
                check(err[kind] <= RATE_TOL / ratio,
                      f"{deck}: {kind} {err[kind]:.2e} of the largest off the planar run{where}")
        for kind in ("vz", "az"):
            if kind in err:
                check(err[kind] <= OUT_OF_PLANE_TOL, f"{deck}: {kind} up to {err[kind]:.2e} of the in-plane scale")


@pytest.mark.parametrize("deck, dt", (("decks/double-crank.deck", "1e-4"), ("decks/hard/a02-n2-dt0p01.deck", "1e-3")))
def test_refined_steps_write_only_mechanism_rows(tmp_path, deck, dt):
    """At a step ten times finer than the deck's, the spatial stepper does not
    pass these change points (the double crank's collinear cranks at t =
    0.25, the A02 chain's flat configuration at t = 0.25), while the planar
    one does; today it stops there (exit 3; a run that passes them one day
    is held to the planar rows all the same), and every row it wrote is the
    planar run's. Before, the double crank went on past t = 0.25 on self-stressed
    configurations (links up to 0.42 off their lengths, the residual at
    round-off) and the chain wrote row 0.249 from a quintic fill through the
    unbounded rates of the change point (a residual of 2.5e12, T1 at
    y = 1.3e5)."""
    planar, spatial = tmp_path / "planar", tmp_path / "spatial"
    done = run_fekap("-q", "--dt", dt, "-o", str(planar), deck)
    check(done.returncode == 0, f"{deck} planar: exit {done.returncode}: {done.stderr}")
    done = run_fekap("-q", "--spatial", "--dt", dt, "-o", str(spatial), deck)
    check(done.returncode in (0, 3), f"{deck} spatial: exit {done.returncode}: {done.stderr}")
    p, s = table(planar), table(spatial)
    rows = len(s["t"])
    check(rows > 0 and np.array_equal(p["t"][:rows], s["t"]), f"{deck}: the spatial rows are not the planar ones")
    size = max(np.max(np.abs(p["x"])), np.max(np.abs(p["y"])))
    worst = max(np.max(np.abs(p[c][:rows] - s[c])) for c in "xy") / size
    check(worst <= 1e-9, f"{deck}: a spatial row is {worst:.2e} model sizes off the planar run's")


def test_joint_angles_of_large_steps(runs):
    """fourbar-quarter-turn (a quarter of a crank turn a step) has, at each of
    its times, the unwrapped joint angles of fourbar (Example 1 at dt = 0.025),
    not only its points: a step that turns a joint by 2 pi the wrong way
    leaves the points right (before the verification of crossing steps the
    coupler's joint B.BC ended at 0 instead of -2 pi)."""
    angles = {}
    for deck in ("decks/fourbar-quarter-turn.deck", "decks/fourbar.deck"):
        _, spatial, done = runs(deck)
        check(done.returncode == 0, f"{deck} --spatial: exit {done.returncode}: {done.stderr}")
        angles[deck] = {(round(float(r["t"]), 9), r["joint"]): float(r["angle"]) for r in read_rows(spatial / "joints.csv")}
    coarse, fine = angles["decks/fourbar-quarter-turn.deck"], angles["decks/fourbar.deck"]
    check(len(coarse) == 20 and set(coarse) <= set(fine), f"the quarter-turn run's rows: {sorted(coarse)}")
    worst = max(abs(angle - fine[key]) for key, angle in coarse.items())
    check(worst <= 1e-12, f"joint angles {worst:.2e} rad off the run at dt = 0.025")


def test_thousand_turns_at_two_iterations(runs):
    """The crank driven 1,000 turns (revolute angles up to 6,283 rad, whose
    round-off the corrections inherit): at most 2 Newton iterations a step,
    and back at the start after every turn within 1e-10."""
    deck = "decks/hard/fourbar-1000-turns.deck"
    _, spatial, done = runs(deck)
    check(done.returncode == 0, f"{deck} --spatial: exit {done.returncode}: {done.stderr}")
    steps = read_rows(spatial / "steps.csv", numbers=True)
    check(len(steps) == 40001, f"{deck}: {len(steps)} rows of steps.csv")
    worst = max(r["iterations"] for r in steps)
    check(worst <= 2, f"{deck}: up to {worst} Newton iterations a step")
    s = table(spatial)
    turn_ends = s["step"] % 40 == 0
    for point in ("B", "C"):
        rows = turn_ends & (s["point"] == point)
        start = (s["x"][rows][0], s["y"][rows][0])
        off = max(np.max(np.abs(s["x"][rows] - start[0])), np.max(np.abs(s["y"][rows] - start[1])))
        check(np.count_nonzero(rows) == 1001 and off <= 1e-10, f"{deck}: {point} {off:.2e} from its start")


@pytest.mark.parametrize("deck", [d for d in planar_decks() if stem(d) in NOT_KINEMATICS])
def test_other_analyses_are_refused(tmp_path, deck):
    out = tmp_path / "out"
    done = run_fekap("-q", "--spatial", "-o", str(out), deck)
    check(done.returncode == 2, f"{deck}: exit {done.returncode}, not 2: {done.stderr}")
    check(f"{deck}: --spatial runs kinematics only" in done.stderr, f"{deck}: {done.stderr}")
    check(not out.exists(), f"{deck}: {out} was written")


# Decks for what the shipped decks do not have: a roller driven along x, a
# prismatic ground guide, a roller with a clamp, a ground link clamped at one
# end, a meshed coupler, a block on a moving link (an inverted slider-crank:
# the crank's pin A slides along the lever QB on a block, the link BLK, that
# keeps the lever's angle).
HEADER = "SECTions\n  bar E=1 G=1 A=100 I=1 k=5/6\nANALysis\n  time 0 1 0.02\n"
ROLLER = HEADER + """NODEs
  O 0 0
  A 0 1
  B sqrt(8) 0
LINKs
  OA O A bar
  AB A B bar
SUPPorts
  O pin
  B y
DRIVes
  x B rate -0.5
END
"""
PRISMATIC_GUIDE = HEADER + """NODEs
  O 0 0
  A 0 1
  B sqrt(8) 0
  E sqrt(8)+0.5 0
LINKs
  OA O A bar
  AB A B bar
  BE B E bar
SUPPorts
  O pin
SLIDelines
  guide B guide -5 0 5 0 prismatic BE
DRIVes
  rotation OA rate 2*pi
END
"""
ROLLER_CLAMP = PRISMATIC_GUIDE.replace("SLIDelines\n  guide B guide -5 0 5 0 prismatic BE\n", "").replace(
    "  O pin\n", "  O pin\n  B y rot BE\n")
CLAMPED_MESHED = HEADER + """NODEs
  A 0 0
  B 2 0
  C 3 sqrt(15)
  D 4 0
LINKs
  AB A B bar
  BC B C bar 4
  DC D C bar
  AD A D bar 3
SUPPorts
  A pin rot AD
  D pin
DRIVes
  rotation AB rate 2*pi
END
"""
PRISMATIC_ON_LINK = HEADER + """NODEs
  O 0 0
  A 1 0
  Q 3 0
  B -1 0
  A2 1.5 0
LINKs
  OA O A bar
  QB Q B bar
  BLK A A2 bar
SUPPorts
  O pin
  Q pin
SLIDelines
  slot A on QB prismatic BLK
DRIVes
  rotation OA rate 2*pi
OUTPut
  track A A2 B
END
"""


# hard/slider-over-hinge with its line's links meshed (GH 3 elements, HK 2)
# and HK written from K to H: the line's segments are the elements, in order.
LINE_MESHED = (ROOT / "decks/hard/slider-over-hinge.deck").read_text().replace(
    "  GH  G   H   bar ", "  GH  G   H   bar  3").replace("  HK  H   K   bar ", "  HK  K   H   bar  2")


@pytest.mark.parametrize("name,text", [("roller", ROLLER), ("prismatic-guide", PRISMATIC_GUIDE),
                                       ("roller-clamp", ROLLER_CLAMP),
                                       ("clamped-meshed", CLAMPED_MESHED),
                                       ("prismatic-on-link", PRISMATIC_ON_LINK),
                                       ("line-meshed", LINE_MESHED)])
def test_joints_of_other_decks_match_planar(tmp_path, name, text):
    deck = tmp_path / f"{name}.deck"
    deck.write_text(text)
    planar, spatial = tmp_path / "planar", tmp_path / "spatial"
    for out, extra in ((planar, ()), (spatial, ("--spatial",))):
        done = run_fekap("-q", *extra, "-o", str(out), str(deck))
        check(done.returncode == 0, f"{name} {extra}: exit {done.returncode}: {done.stderr}")
    err = compare(planar, spatial, name)
    check(err["pos"] <= POSITION_TOL and err["z"] <= OUT_OF_PLANE_TOL, f"{name}: {err}")
    check(err["vel"] <= RATE_TOL and err["acc"] <= RATE_TOL, f"{name}: {err}")
    check(err["vz"] <= OUT_OF_PLANE_TOL and err["az"] <= OUT_OF_PLANE_TOL, f"{name}: {err}")
    # The motion is not trivial: every tracked point off the ground moves.
    p = table(planar)
    check(name != "line-meshed" or "bar  3" in text and "K   H   bar  2" in text, "the meshed line's deck")
    for point in set(p["point"]) - ({"A", "D"} if name == "clamped-meshed" else {"O"}):
        rows = p["point"] == point
        check(np.ptp(p["x"][rows]) + np.ptp(p["y"][rows]) > 0.1, f"{name}: {point} does not move")


@pytest.mark.parametrize("drive,line,message", [
    ("rotation BC rate 0.2", 19, "--spatial drives the rotation of a link only at a node held to the ground"),
    ("x C rate 0.2", 19, "--spatial drives the x of a node only on a roller or a ground guide"),
])
def test_drives_without_a_joint_are_refused(tmp_path, drive, line, message):
    text = CLAMPED_MESHED.replace("rotation AB rate 2*pi", drive)
    check(text.splitlines()[line - 1].strip() == drive, "the drive's line")
    deck = tmp_path / "drive.deck"
    deck.write_text(text)
    out = tmp_path / "out"
    planar = run_fekap("-q", "-o", str(tmp_path / "planar"), str(deck))
    check(planar.returncode == 0, f"the planar run: {planar.stderr}")
    done = run_fekap("-q", "--spatial", "-o", str(out), str(deck))
    check(done.returncode == 2, f"exit {done.returncode}, not 2: {done.stderr}")
    check(done.stderr.startswith(f"{deck}:{line}:3: error: {message}"), done.stderr)
    check(not out.exists(), f"{out} was written")


def test_help_names_the_option():
    done = run_fekap("--help")
    check(done.returncode == 0 and "--spatial" in done.stdout, done.stdout)


def test_vtk_files_of_a_spatial_run_of_a_planar_deck(tmp_path):
    """Example 1 with `files csv listing vtk` under --spatial: one .vtu a
    written step whose points plus displacement are, in x and y, the planar
    run's nodes.csv positions of the same step (z zero), read back by VTK."""
    from test_vtk import Mesh, read_pvd

    from fekap import read

    text = (ROOT / "decks" / "fourbar.deck").read_text()
    check("  track B C\n" in text, "the fourbar deck's track line changed")
    deck = tmp_path / "fourbar.deck"
    deck.write_text(text.replace("  track B C\n", "  track B C\n  files csv listing vtk\n"))
    planar, spatial = tmp_path / "planar", tmp_path / "spatial"
    for out, extra in ((planar, ()), (spatial, ("--spatial",))):
        done = run_fekap("-q", *extra, "-o", str(out), str(deck))
        check(done.returncode == 0, f"{extra}: exit {done.returncode}: {done.stderr}")
    _, t, nodes = read.node_positions(planar / "nodes.csv")
    collection = read_pvd(spatial / "fourbar.pvd")
    check([c[0] for c in collection] == t.tolist(), "the spatial .pvd's times are not the planar run's")
    names = list(read.read_spatial_mechanism(spatial / "mechanism.txt").nodes)
    for k, (_, file) in enumerate(collection):
        mesh = Mesh(spatial / file)
        for name in ("A", "B", "C", "D"):
            got = mesh.points[names.index(name)]
            err = max(np.max(np.abs(got[:2] - nodes[name][k])), abs(got[2]))
            check(err < 1e-12, f"{file}: node {name} at {got}, planar {nodes[name][k]} ({err:.2e})")


# decks/hard/slider-over-hinge.deck: a slider S on the line of the links GH and
# HK, hinged at H, passing from one to the other and back (its header).
OVER_HINGE = "decks/hard/slider-over-hinge.deck"
# Closed-form rates from differences of the closed-form positions (five-point
# stencils of step STENCIL_H): truncation h^4 and round-off eps/h^2 both below
# 1e-9 of the largest rates, so 1e-8 of them tells a wrong rate.
STENCIL_H = 1e-3
DIFFERENCE_TOL = 1e-8


def over_hinge_exact(t: float) -> dict[str, tuple[np.ndarray, int, float]]:
    """The deck's closed form at time t: S, H, K, each with the link of the
    line S is on (1: GH, 2: HK) and S's arc length along the line from G."""
    phi = np.deg2rad(12 + 4 * np.cos(2 * np.pi * t))
    theta = np.pi + 2 * np.pi * t
    a = np.array([-1 + 0.6 * np.cos(theta), 0.6 * np.sin(theta)])
    d1, d2 = np.array([np.cos(phi), np.sin(phi)]), np.array([np.cos(phi), -np.sin(phi)])
    h, k = 4 * d1, np.array([8 * np.cos(phi), 0.0])
    b = d1 @ a
    u = b + np.sqrt(b * b - a @ a + 25)
    if u <= 4:
        s, on, arc = u * d1, 1, u
    else:
        r = a - h
        b = d2 @ r
        w = b + np.sqrt(b * b - r @ r + 25)
        s, on, arc = h + w * d2, 2, 4 + w
    return {"S": (s, on, arc), "H": (h, on, arc), "K": (k, on, arc)}


def over_hinge_rates(t: float, point: str) -> tuple[np.ndarray, np.ndarray] | None:
    """Velocity and acceleration of the point from five-point differences of
    the closed-form positions; None where the stencil spans S's passing from
    one link to the other (there its path has a corner)."""
    samples = [over_hinge_exact(t + j * STENCIL_H) for j in (-2, -1, 0, 1, 2)]
    if len({e["S"][1] for e in samples}) > 1:
        return None
    x = [e[point][0] for e in samples]
    h = STENCIL_H
    v = (x[0] - 8 * x[1] + 8 * x[3] - x[4]) / (12 * h)
    a = (-x[0] + 16 * x[1] - 30 * x[2] + 16 * x[3] - x[4]) / (12 * h * h)
    return v, a


def check_over_hinge(out: Path) -> None:
    """points.csv of a run of hard/slider-over-hinge against the deck's
    closed form at every row (see test_slider_over_a_hinge_against_its_closed_form)."""
    p = table(out)
    size = max(np.max(np.abs(p["x"])), np.max(np.abs(p["y"])))
    vscale = max(np.max(np.abs(p[c])) for c in ("vx", "vy"))
    ascale = max(np.max(np.abs(p[c])) for c in ("ax", "ay"))
    links, worst, compared = set(), {"pos": 0.0, "vel": 0.0, "acc": 0.0}, 0
    for i, t in enumerate(p["t"]):
        exact = over_hinge_exact(t)
        want, on, _ = exact[p["point"][i]]
        links.add(on)
        got = np.array([p["x"][i], p["y"][i]])
        worst["pos"] = max(worst["pos"], np.max(np.abs(got - want)) / size)
        rates = over_hinge_rates(t, p["point"][i])
        if rates is None:
            continue
        compared += 1
        worst["vel"] = max(worst["vel"], np.max(np.abs([p["vx"][i], p["vy"][i]] - rates[0])) / vscale)
        worst["acc"] = max(worst["acc"], np.max(np.abs([p["ax"][i], p["ay"][i]] - rates[1])) / ascale)
    check(links == {1, 2}, f"{out}: S stays on link {links} of its line")
    check(compared >= len(p["t"]) - 12, f"{out}: the rates of only {compared} of {len(p['t'])} rows compared")
    check(worst["pos"] <= POSITION_TOL, f"{out}: positions {worst['pos']:.2e} of the model size off the exact")
    check(worst["vel"] <= DIFFERENCE_TOL and worst["acc"] <= DIFFERENCE_TOL,
          f"{out}: rates off the differences of the exact positions: {worst}")


def test_slider_over_a_hinge_against_its_closed_form(runs):
    """Both runs of hard/slider-over-hinge against the deck's closed form at
    every row: positions within 1e-12 of the model size, velocities and
    accelerations within 1e-8 of the largest of differences of the exact
    positions (rows whose stencil spans the corner of S's path left out);
    S passes from GH to HK and back; the spatial run's stroke of the slide
    (joints.csv, S.line) is S's arc length along the line since the start."""
    planar, spatial, done = runs(OVER_HINGE)
    check(done.returncode == 0, f"--spatial: exit {done.returncode}: {done.stderr}")
    for out in (planar, spatial):
        check_over_hinge(out)
    rows = [r for r in read_rows(spatial / "joints.csv", numbers=True) if r["joint"] == "S.line"]
    check(len(rows) == 101, f"{len(rows)} rows of the slide S.line in joints.csv")
    start = over_hinge_exact(0.0)["S"][2]
    off = max(abs(r["angle"] - (over_hinge_exact(r["t"])["S"][2] - start)) for r in rows)
    check(off <= POSITION_TOL * 8, f"the stroke of S.line {off:.2e} off S's arc length along the line")


def test_cartesian_slider_over_a_hinge_against_its_closed_form(tmp_path):
    """The constraint-equation method on the same deck (the closed form is
    here): its slave's equations follow the master segment S is on at the
    converged configuration, not only at the step's start (before: S 1.5e-2
    off at t = 0.29, where it passes H, with exit 0)."""
    out = tmp_path / "cartesian"
    done = run_fekap("-q", "-o", str(out), "--method", "cartesian", OVER_HINGE)
    check(done.returncode == 0, f"exit {done.returncode}: {done.stderr}")
    check_over_hinge(out)


def test_prismatic_slider_on_several_links_is_refused(tmp_path):
    """A prismatic slider on a line of several links: its planar tie turns
    the slave link at once by the change of the angle between two links as
    the slave passes from one to the next, which no spatial joint does."""
    text = (ROOT / OVER_HINGE).read_text()
    line = "  line  S  on GH HK  pin\n"
    check(line in text, "the deck's slideline changed")
    text = text.replace(line, "  line  S  on GH HK  prismatic AS\n")
    number = text.splitlines().index("  line  S  on GH HK  prismatic AS") + 1
    deck = tmp_path / "prismatic.deck"
    deck.write_text(text)
    out = tmp_path / "out"
    done = run_fekap("-q", "--spatial", "-o", str(out), str(deck))
    check(done.returncode == 2, f"exit {done.returncode}, not 2: {done.stderr}")
    check(done.stderr.startswith(f"{deck}:{number}:3: error: --spatial takes a prismatic slider on one moving link "
                                 "only: slideline line ties the angle of link AS"), done.stderr)
    check("make it a pin slider" in done.stderr, done.stderr)
    check(not out.exists(), f"{out} was written")


def test_first_master_link_written_towards_the_second(tmp_path, runs):
    """The planar slideline takes the first link of its line from its end
    away from the second, however the link is written: hard/slider-over-hinge
    with GH written from H to G (driven at H by the same angle, turned by pi)
    gives the deck's points (before, its chain ran from H to G and on from H
    to K, and the run stopped where S passed H: the slave left its line)."""
    text = (ROOT / OVER_HINGE).read_text()
    for old, new in (("  GH  G   H   bar ", "  HG  H   G   bar "), ("on GH HK", "on HG HK"),
                     ("rotation GH   harmonic 12*deg", "rotation HG   harmonic 192*deg")):
        check(old in text, f"the deck's line {old!r}")
        text = text.replace(old, new)
    deck = tmp_path / "reversed.deck"
    deck.write_text(text)
    done = run_fekap("-q", "-o", str(tmp_path / "out"), str(deck))
    check(done.returncode == 0, f"exit {done.returncode}: {done.stderr}")
    planar, _, _ = runs(OVER_HINGE)
    p, r = table(planar), table(tmp_path / "out")
    check(list(p["point"]) == list(r["point"]) and np.array_equal(p["t"], r["t"]), "other rows")
    for cols, tol in ((("x", "y"), POSITION_TOL), (("vx", "vy"), RATE_TOL), (("ax", "ay"), RATE_TOL)):
        scale = max(np.max(np.abs(p[c])) for c in cols)
        err = max(np.max(np.abs(p[c] - r[c])) for c in cols) / scale
        check(err <= tol, f"{cols}: {err:.2e} of the largest off the deck's run")
