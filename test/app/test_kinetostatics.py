"""Kinetostatics through the fekap executable: the deck chooses the effects,
reactions.csv is written only by kinetostatics and statics runs (rows per step: the
drives, the supports, both ends of every link), the listing's plan says which
effects run and why, and a type that cannot run is an input error (exit 2)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from apptest import ROOT, read_rows, run_fekap

DECK = "decks/fourbar-kinetostatics.deck"


def plan(outdir: Path) -> str:
    """The PLAN section of the run's listing."""
    text = next(outdir.glob("*.lis")).read_text()
    return text[text.index("PLAN"):text.index("STEPS")]


def variant(tmp_path: Path, old: str, new: str) -> Path:
    """A copy of the kinetostatics deck with one piece of text replaced."""
    text = (ROOT / DECK).read_text()
    assert old in text
    path = tmp_path / "variant.deck"
    path.write_text(text.replace(old, new))
    return path


def test_reactions_written_per_step(tmp_path):
    out = tmp_path / "ks"
    run = run_fekap("-q", "-o", str(out), DECK)
    assert run.returncode == 0, run.stderr
    rows = read_rows(out / "reactions.csv")
    # 101 steps; 1 drive, 2 supports, 3 links with two ends each.
    assert len(rows) == 101 * 9
    first = rows[:9]
    assert [(r["kind"], r["link"], r["node"]) for r in first] == [
        ("drive", "AB", "A"), ("support", "", "A"), ("support", "", "D"), ("joint", "AB", "A"),
        ("joint", "AB", "B"), ("joint", "BC", "B"), ("joint", "BC", "C"), ("joint", "DC", "D"),
        ("joint", "DC", "C")]
    for r in rows:
        assert all(math.isfinite(float(r[k])) for k in ("fx", "fy", "m"))
    # The drive torque is the crank's end moment at A.
    for k in range(0, len(rows), 9):
        assert float(rows[k]["m"]) == pytest.approx(float(rows[k + 3]["m"]), rel=1e-12, abs=1e-9)
    assert "effects: kinetostatics" in plan(out)


def test_motion_is_the_kinematic_one(tmp_path):
    """Kinetostatics' motion is the unloaded kinematics (its loads act on the deflection): the
    same rates as the deck run as kinematics, and the crank at its drive's 2 pi rad/s, to
    round-off. Measured: velocities 1.1e-14 and accelerations 2.6e-13 apart (of 24 and 268),
    the crank's omega 2.7e-15 off and alpha 2.8e-14; with K's factor (before the square-root
    form took kinetostatics) 5.7e-10, 1.6e-8, 1.8e-10 and 3.4e-9, which these bounds reject.
    1e-12 of each column: the two runs may take different Newton paths (kinematics may carry a
    factor, kinetostatics does not), each within the length tolerance."""
    out = tmp_path / "ks"
    run = run_fekap("-q", "-o", str(out), DECK)
    assert run.returncode == 0, run.stderr
    kin = tmp_path / "kin"
    run = run_fekap("-q", "-o", str(kin), str(variant(tmp_path, "type kinetostatics", "type kinematics")))
    assert run.returncode == 0, run.stderr
    got, want = read_rows(out / "points.csv"), read_rows(kin / "points.csv")
    assert len(got) == len(want) == 2 * 101
    for column in ("x", "y", "vx", "vy", "ax", "ay"):
        largest = max(abs(float(r[column])) for r in want)
        worst = max(abs(float(a[column]) - float(b[column])) for a, b in zip(got, want))
        assert worst <= 1e-12 * largest, (column, worst, largest)
    links = read_rows(out / "links.csv")
    crank = [r for r in links if r["link"] == "AB"]
    assert len(crank) == 101
    largest_alpha = max(abs(float(r["alpha"])) for r in links)
    assert max(abs(float(r["omega"]) - 2 * math.pi) for r in crank) <= 1e-12 * 2 * math.pi
    assert max(abs(float(r["alpha"])) for r in crank) <= 1e-12 * largest_alpha


def test_redundant_slender_mechanism_rates_refined(tmp_path):
    """decks/double-crank.deck (three parallel cranks: redundant) with slender massive bars
    (A = 1e4, I = 1e-4, rho = 1) as kinetostatics: its rates are the K form's refined as in
    kinematics, so F stays on its unit circle at 2 pi rad/s, and the drive torque is zero (the
    kinetic energy is constant, no gravity). Measured: speed 6.7e-13 and acceleration 8.4e-12
    off, torque 3.2e-6 against support forces up to 9.9e5; unrefined (before kinetostatics
    refined them) 1.2e-7, 1.5e-6 and 0.51, which these bounds reject."""
    text = (ROOT / "decks/double-crank.deck").read_text()
    for old, new in (("A=100  I=1  k=5/6", "A=1e4  I=1e-4  k=5/6  rho=1"),
                     ("  time 0 1 0.02", "  type kinetostatics\n  time 0 1 0.02")):
        assert old in text
        text = text.replace(old, new)
    deck = tmp_path / "slender.deck"
    deck.write_text(text)
    out = tmp_path / "slender"
    run = run_fekap("-q", "-o", str(out), str(deck))
    assert run.returncode == 0, run.stderr
    w = 2 * math.pi
    points = read_rows(out / "points.csv")
    assert len(points) == 51
    for r in points:
        assert abs(math.hypot(float(r["vx"]), float(r["vy"])) - w) <= 1e-10 * w, r
        assert abs(math.hypot(float(r["ax"]), float(r["ay"])) - w**2) <= 1e-10 * w**2, r
    rows = read_rows(out / "reactions.csv")
    support = max(math.hypot(float(r["fx"]), float(r["fy"])) for r in rows if r["kind"] == "support")
    torque = max(abs(float(r["m"])) for r in rows if r["kind"] == "drive")
    assert support > 1e5
    assert torque <= 1e-10 * support, (torque, support)


def test_kinematics_decks_write_no_reactions(tmp_path):
    out = tmp_path / "fourbar"
    run = run_fekap("-q", "-o", str(out), "decks/fourbar.deck")
    assert run.returncode == 0, run.stderr
    assert not (out / "reactions.csv").exists()
    assert "effects: kinematics (auto: no masses, no loads)" in plan(out)


@pytest.mark.parametrize("option, why", [
    (("--method", "cartesian"), "method fem"),
    (("--compute", "positions,velocities"), "accelerations"),
])
def test_auto_falls_back_to_kinematics_and_says_why(tmp_path, option, why):
    deck = variant(tmp_path, "  type kinetostatics", "  type auto")
    out = tmp_path / "auto"
    run = run_fekap("-q", "-o", str(out), *option, str(deck))
    assert run.returncode == 0, run.stderr
    assert not (out / "reactions.csv").exists()
    text = plan(out)
    assert "effects: kinematics (auto: masses are given, but" in text and why in text
    assert "masses and gravity are left out" in text


def test_explicit_kinetostatics_overridden_to_cartesian_is_an_input_error(tmp_path):
    run = run_fekap("-q", "-o", str(tmp_path / "x"), "--method", "cartesian", DECK)
    assert run.returncode == 2
    assert "kinetostatics runs with method fem only" in run.stderr


def test_gravity_without_masses_is_noted(tmp_path):
    deck = variant(tmp_path, "rho=100", "")
    deck.write_text(deck.read_text().replace("  type kinetostatics", "  type auto"))
    out = tmp_path / "g"
    run = run_fekap("-q", "-o", str(out), str(deck))
    assert run.returncode == 0, run.stderr
    assert "GRAVity does nothing without masses" in plan(out)
    assert not (out / "reactions.csv").exists()


def test_statics_needs_loads(tmp_path):
    deck = variant(tmp_path, "  type kinetostatics", "  type statics")
    deck.write_text(deck.read_text().replace("GRAVity  0  -9.81", ""))
    run = run_fekap("-q", "-o", str(tmp_path / "s"), str(deck))
    assert run.returncode == 2
    assert "variant.deck:26:8: error: statics cannot run: statics needs loads" in run.stderr


# --- the elastic deflection (OUTPut deflection on) --------------------------------------------------

RHO_A = 100 * 1e-2  # decks/fourbar-kinetostatics.deck: rho = 100, A = 1e-2
LINKS = {"AB": ("A", "B"), "BC": ("B", "C"), "DC": ("D", "C")}


def stiff_run(tmp_path: Path, e: float, name: str) -> Path:
    """The four-bar kinetostatics deck with sections E = e, G = 0.4 e (stiff links), every node
    tracked and the deflection written."""
    text = (ROOT / DECK).read_text().replace("E=1e7  G=4e6", f"E={e:g}  G={0.4 * e:g}")
    text = text.replace("  track B C\n", "  deflection on\n")
    deck = tmp_path / f"{name}.deck"
    deck.write_text(text)
    out = tmp_path / name
    run = run_fekap("-q", "-o", str(out), str(deck))
    assert run.returncode == 0, run.stderr
    return out


def by_step_node(rows: list[dict[str, str]], key: str, *columns: str) -> dict[tuple[int, str], tuple[float, ...]]:
    return {(int(r["step"]), r[key]): tuple(float(r[c]) for c in columns) for r in rows}


def test_deflection_is_each_links_axial_stretch(tmp_path):
    """With stiff links each link's stretch in deflection.csv, (u2 - u1) . t, is the integral of
    its axial force over EA: N(s) = -g1 . t - int_0^s p . t, p = rhoA (g - a(s)) with a(s) linear
    between the ends' accelerations (points.csv), g1 the joint's force on the link's first end
    (reactions.csv). Linear elements with consistent loads have exact nodal values in 1D."""
    e = 1e11
    out = stiff_run(tmp_path, e, "stiff")
    ea = e * 1e-2
    u = by_step_node(read_rows(out / "deflection.csv"), "node", "ux", "uy")
    points = by_step_node(read_rows(out / "points.csv"), "point", "x", "y", "ax", "ay")
    joints = {(int(r["step"]), r["link"], r["node"]): (float(r["fx"]), float(r["fy"]))
              for r in read_rows(out / "reactions.csv") if r["kind"] == "joint"}
    steps = sorted({s for s, _ in u})
    assert len(steps) == 101 and len(u) == 101 * 4
    worst = largest = 0.0
    for step in steps:
        for link, (n1, n2) in LINKS.items():
            x1, y1, ax1, ay1 = points[step, n1]
            x2, y2, ax2, ay2 = points[step, n2]
            length = math.hypot(x2 - x1, y2 - y1)
            t = ((x2 - x1) / length, (y2 - y1) / length)
            p1 = RHO_A * ((0 - ax1) * t[0] + (-9.81 - ay1) * t[1])
            p2 = RHO_A * ((0 - ax2) * t[0] + (-9.81 - ay2) * t[1])
            g1 = joints[step, link, n1]
            want = (-(g1[0] * t[0] + g1[1] * t[1]) * length - length**2 * (p1 / 3 + p2 / 6)) / ea
            got = (u[step, n2][0] - u[step, n1][0]) * t[0] + (u[step, n2][1] - u[step, n1][1]) * t[1]
            worst = max(worst, abs(got - want))
            largest = max(largest, abs(want))
    assert largest > 1e-8, largest
    assert worst < 1e-6 * largest, (worst, largest)
    # The listing names the run's largest deflection (over every point of the mesh).
    listing = next(out.glob("*.lis")).read_text()
    assert "deflection.csv" in plan(out)
    note = [line for line in listing.splitlines() if "largest elastic deflection" in line]
    assert len(note) == 1 and "step 100," in note[0], note
    value = float(note[0].split("largest elastic deflection ")[1].split()[0])
    assert value >= max(math.hypot(*v) for v in u.values()) * (1 - 1e-5)


def test_deflection_scales_as_one_over_the_stiffness(tmp_path):
    """The motion is the kinematic one whatever E is, and the four-bar held at its drive is
    statically determinate: doubling E and G halves the deflection."""
    u1 = by_step_node(read_rows(stiff_run(tmp_path, 1e11, "e1") / "deflection.csv"), "node", "ux", "uy")
    u2 = by_step_node(read_rows(stiff_run(tmp_path, 2e11, "e2") / "deflection.csv"), "node", "ux", "uy")
    assert u1.keys() == u2.keys()
    scale = max(max(abs(c) for c in v) for v in u1.values())
    assert scale > 0
    worst = max(max(abs(a - 2 * b) for a, b in zip(u1[k], u2[k])) for k in u1)
    assert worst < 1e-8 * scale, (worst, scale)


@pytest.mark.parametrize("line, message", [
    ("  deflection maybe", "expected on or off, not 'maybe'"),
    ("  defl 1", "expected on or off, not '1'"),
    ("  deflection on off", "unexpected field 'off'"),
])
def test_bad_deflection_switch_is_an_input_error(tmp_path, line, message):
    deck = variant(tmp_path, "  track B C\n", line + "\n")
    run = run_fekap("-q", "-o", str(tmp_path / "bad"), str(deck))
    assert run.returncode == 2
    row = (ROOT / DECK).read_text().splitlines().index("  track B C") + 1
    assert f"variant.deck:{row}:" in run.stderr and message in run.stderr, run.stderr


def test_deflection_is_kinetostatics_only(tmp_path):
    """Statics with the switch on: the plan says the deflection is not written, and it is not."""
    deck = tmp_path / "statics.deck"
    deck.write_text((ROOT / "decks/statics-cantilever.deck").read_text().replace(
        "  track T\n", "  track T\n  deflection on\n"))
    out = tmp_path / "statics"
    run = run_fekap("-q", "-o", str(out), str(deck))
    assert run.returncode == 0, run.stderr
    assert "OUTPut deflection: not written" in plan(out)
    assert not (out / "deflection.csv").exists()


def test_a_row_without_accelerations_has_no_deflection(tmp_path):
    """Example 3's double crank with masses, dt 0.025: the row at t = 0.25 is
    exactly singular and has no accelerations, so no reactions and no
    deflection; its deflection.csv cells are empty, not the previous row's."""
    text = (ROOT / "decks" / "double-crank.deck").read_text()
    for old, new in [("k=5/6", "k=5/6  rho=1"), ("  track F", "  track F\n  deflection on"),
                     ("time 0 1 0.02", "time 0 1 0.025")]:
        assert old in text
        text = text.replace(old, new)
    deck = tmp_path / "double-crank-masses.deck"
    deck.write_text(text)
    run = run_fekap(str(deck), "-o", str(tmp_path / "out"))
    assert run.returncode == 0, run.stderr
    rows = read_rows(tmp_path / "out" / "deflection.csv")
    singular = [row for row in rows if row["step"] == "10"]
    assert singular and all(row["ux"] == "" and row["uy"] == "" for row in singular)
    # The rows either side have their deflection.
    assert all(row["ux"] != "" for row in rows if row["step"] in ("9", "11"))
