"""Tests of scripts/plot.py and scripts/compare.py on synthetic FEKAP output.

Run with pytest (scripts/test plots); each test gets its own tmp_path.

The synthetic runs are an exact four-bar (A = (0, 0), D = (4, 0), crank AB = 2, coupler BC = 4,
rocker DC = 4, crank angle 2*pi*t) whose positions, velocities and accelerations are computed
analytically, written in FEKAP's CSV formats.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
PLOT = ROOT / "scripts" / "plot.py"
COMPARE = ROOT / "scripts" / "compare.py"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Failure(Exception):
    """A failed check, with its reason."""


def check(condition: bool, reason: str) -> None:
    """Fail the current test with ``reason`` unless ``condition`` holds."""
    if not condition:
        raise Failure(reason)


# --------------------------------------------------------------------------- synthetic runs

def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z component of the cross product of rows of 2-vectors."""
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of 2-vectors."""
    return np.sum(a * b, axis=1)


def solve_rows(r1: np.ndarray, r2: np.ndarray, b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
    """Solve [r1; r2] v = [b1; b2] for each row (2x2 systems by Cramer's rule)."""
    det = cross(r1, r2)
    return np.column_stack([(b1 * r2[:, 1] - b2 * r1[:, 1]) / det,
                            (r1[:, 0] * b2 - r2[:, 0] * b1) / det])


def fourbar(t: np.ndarray) -> tuple[dict, dict]:
    """Exact four-bar kinematics: point -> (pos, vel, acc), link -> (angle, omega, alpha)."""
    theta = 2 * np.pi * t
    omega1 = 2 * np.pi
    a = np.zeros((t.size, 2))
    d = np.tile([4.0, 0.0], (t.size, 1))
    b = 2 * np.column_stack([np.cos(theta), np.sin(theta)])
    vb = 2 * omega1 * np.column_stack([-np.sin(theta), np.cos(theta)])
    ab = -omega1**2 * b
    # Upper assembly: C on the left of D - B, equal coupler and rocker lengths (4).
    bd = d - b
    dist = np.linalg.norm(bd, axis=1)
    height = np.sqrt(16 - dist**2 / 4)
    c = (b + d) / 2 + (height / dist)[:, None] * np.column_stack([-bd[:, 1], bd[:, 0]])
    # Velocity: (C - B).(vC - vB) = 0 and (C - D).vC = 0; acceleration by differentiating.
    cb, cd = c - b, c - d
    vc = solve_rows(cb, cd, dot(cb, vb), np.zeros(t.size))
    ac = solve_rows(cb, cd, dot(cb, ab) - dot(vc - vb, vc - vb), -dot(vc, vc))
    points = {"A": (a, a, a), "B": (b, vb, ab), "C": (c, vc, ac), "D": (d, a, a)}
    links = {}
    for name, (p, q) in {"crank": ("A", "B"), "coupler": ("B", "C"),
                         "rocker": ("D", "C")}.items():
        r = points[q][0] - points[p][0]
        v = points[q][1] - points[p][1]
        acc = points[q][2] - points[p][2]
        length2 = dot(r, r)
        links[name] = (np.unwrap(np.arctan2(r[:, 1], r[:, 0])), cross(r, v) / length2,
                       cross(r, acc) / length2)
    return points, links


def fmt(value: float) -> str:
    """A number as FEKAP writes it (Fortran ES format, round-trip digits)."""
    return f"{value:.16E}"


def write_points(path: Path, t: np.ndarray, points: dict, quantities: int,
                 perturb: dict | None = None) -> None:
    """Write points.csv with 1 (x, y), 2 (+ vx, vy) or 3 (+ ax, ay) quantity pairs.

    ``perturb`` maps (point, column index 0..5) to an array added to that column.
    """
    names = ["x", "y", "vx", "vy", "ax", "ay"][:2 * quantities]
    lines = [",".join(["step", "t", "point"] + names)]
    for k, time_k in enumerate(t):
        for name, arrays in points.items():
            row = np.concatenate([arrays[i][k] for i in range(quantities)])
            for (pname, col), delta in (perturb or {}).items():
                if pname == name:
                    row[col] += delta[k]
            lines.append(",".join([str(k), fmt(time_k), name] + [fmt(v) for v in row]))
    path.write_text("\n".join(lines) + "\n")


def write_run(directory: Path, steps: int = 40, quantities: int = 3, mesh: bool = True,
              perturb: dict | None = None, t_end: float = 1.0) -> Path:
    """Write a complete synthetic FEKAP output directory of the exact four-bar."""
    directory.mkdir(parents=True, exist_ok=True)
    t = np.linspace(0.0, t_end, steps + 1)
    points, links = fourbar(t)
    write_points(directory / "points.csv", t, points, quantities, perturb)
    link_names = ["angle", "omega", "alpha"][:max(1, quantities)]
    lines = [",".join(["step", "t", "link"] + link_names)]
    for k, time_k in enumerate(t):
        for name, arrays in links.items():
            lines.append(",".join([str(k), fmt(time_k), name]
                                  + [fmt(arrays[i][k]) for i in range(len(link_names))]))
    (directory / "links.csv").write_text("\n".join(lines) + "\n")
    iterations = [0] + [3 + (k % 3) for k in range(1, t.size)]
    lines = ["step,t,iterations,residual,seconds"]
    lines += [f"{k},{fmt(time_k)},{iterations[k]},{fmt(10.0**(-11 - k % 4))},0.001"
              for k, time_k in enumerate(t)]
    (directory / "steps.csv").write_text("\n".join(lines) + "\n")
    if mesh:
        (directory / "mesh.csv").write_text("link,node1,node2\ncrank,A,B\ncoupler,B,C\n"
                                            "rocker,D,C\n")
    (directory / "fourbar.lis").write_text("FEKAP listing (ignored by the plots)\n")
    return directory


# --------------------------------------------------------------------------- helpers

def run_script(script: Path, *args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """Run a script with the current Python and return the completed process."""
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, str(script), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, env=env, cwd=ROOT)


def check_ok(proc: subprocess.CompletedProcess) -> None:
    """The script succeeded without a traceback."""
    check(proc.returncode == 0, f"exit {proc.returncode}, stderr: {proc.stderr.strip()[-400:]}")
    check("Traceback" not in proc.stderr, f"traceback: {proc.stderr[-400:]}")


def check_usage_error(proc: subprocess.CompletedProcess, *fragments: str) -> None:
    """The script refused its arguments: exit 2, one clear line on stderr, no traceback."""
    check(proc.returncode == 2, f"exit {proc.returncode} (want 2), stderr: {proc.stderr[-300:]}")
    check("Traceback" not in proc.stderr, f"traceback: {proc.stderr[-400:]}")
    lines = proc.stderr.strip().splitlines()
    check(len(lines) == 1, f"want one line on stderr, got {len(lines)}: {proc.stderr!r}")
    for fragment in fragments:
        check(fragment.lower() in lines[0].lower(), f"'{fragment}' not in message: {lines[0]}")


def check_png(path: Path) -> None:
    """``path`` is a non-empty valid PNG whose pixels are not all the same."""
    import matplotlib.image as mpimg

    check(path.is_file(), f"{path.name} was not written")
    data = path.read_bytes()
    check(len(data) > 1000 and data.startswith(PNG_SIGNATURE), f"{path.name} is not a PNG")
    pixels = mpimg.imread(path)
    check(pixels.ndim == 3 and pixels.shape[0] > 100 and pixels.shape[1] > 100,
          f"{path.name}: odd image shape {pixels.shape}")
    check(float(np.var(pixels[..., :3])) > 1e-4, f"{path.name} is blank")


def listed_files(proc: subprocess.CompletedProcess) -> set[str]:
    """The file names a script printed as written."""
    return {Path(line.strip()).name for line in proc.stdout.splitlines() if line.strip()}


def difference_table(stdout: str) -> dict[tuple[str, str], dict[str, float]]:
    """Parse compare.py's table: (run label, point) -> quantity -> max abs difference."""
    lines = stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.split()[:2] == ["run", "point"])
    header = lines[start].split()
    table = {}
    for line in lines[start + 1:]:
        fields = line.split()
        if len(fields) != len(header):
            break
        table[(fields[0], fields[1])] = {q: float(v) for q, v in zip(header[2:], fields[2:])
                                         if v != "-"}
    return table


# --------------------------------------------------------------------------- plot.py tests

ALL_PNGS = {"paths.png", "history_A.png", "history_B.png", "history_C.png", "history_D.png",
            "angles.png", "iterations.png"}


def test_full_run(tmp_path: Path) -> None:
    """A run with velocities and accelerations: every figure, valid and not blank."""
    out = write_run(tmp_path / "full")
    proc = run_script(PLOT, out)
    check_ok(proc)
    check(listed_files(proc) == ALL_PNGS, f"listed {sorted(listed_files(proc))}")
    for name in ALL_PNGS:
        check_png(out / name)


def test_positions_only(tmp_path: Path) -> None:
    """A run without velocities or mesh.csv still gives every figure."""
    out = write_run(tmp_path / "positions", quantities=1, mesh=False)
    proc = run_script(PLOT, out)
    check_ok(proc)
    check(proc.stderr.strip() == "", f"unexpected message: {proc.stderr.strip()}")
    for name in ALL_PNGS:
        check_png(out / name)


def test_only_and_instants(tmp_path: Path) -> None:
    """--only draws just the named figures; --instants changes the mechanism drawing."""
    out = write_run(tmp_path / "only", steps=12)
    proc = run_script(PLOT, out, "--only", "paths", "iterations", "--instants", "2")
    check_ok(proc)
    check(listed_files(proc) == {"paths.png", "iterations.png"}, f"listed {proc.stdout}")
    check(not (out / "angles.png").exists(), "angles.png written despite --only")
    check_png(out / "paths.png")
    two = (out / "paths.png").read_bytes()
    check_ok(run_script(PLOT, out, "--only", "paths", "--instants", "0"))
    check((out / "paths.png").read_bytes() != two, "--instants 0 drew the same picture")
    proc = run_script(PLOT, out, "--only", "velocity")
    check_ok(proc)
    check(listed_files(proc) == {f"history_{p}.png" for p in "ABCD"}, f"listed {proc.stdout}")


def test_animate(tmp_path: Path) -> None:
    """--animate writes a GIF of the mechanism."""
    out = write_run(tmp_path / "anim", steps=10)
    proc = run_script(PLOT, out, "--animate", "--only", "paths")
    check_ok(proc)
    gif = out / "motion.gif"
    check(gif.is_file() and gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a"), "no valid GIF")
    check("motion.gif" in listed_files(proc), "motion.gif not listed")


def test_animate_without_mesh(tmp_path: Path) -> None:
    """--animate without mesh.csv says so and still draws the rest."""
    out = write_run(tmp_path / "nomesh", steps=8, mesh=False)
    proc = run_script(PLOT, out, "--animate")
    check_ok(proc)
    check("mesh.csv" in proc.stderr, f"no clear message: {proc.stderr!r}")
    check(not (out / "motion.gif").exists(), "motion.gif written without mesh.csv")
    check_png(out / "paths.png")


def test_mesh_with_untracked_point(tmp_path: Path) -> None:
    """Links whose end points are not tracked are skipped silently."""
    out = write_run(tmp_path / "untracked", steps=8)
    (out / "mesh.csv").write_text("link,node1,node2\ncrank,A,B\nghost,B,Q\n")
    proc = run_script(PLOT, out, "--only", "paths")
    check_ok(proc)
    check(proc.stderr.strip() == "", f"unexpected message: {proc.stderr.strip()}")
    check_png(out / "paths.png")


def test_fortran_number_spellings(tmp_path: Path) -> None:
    """1.0D+00 and exponents without E (1.0-100), and extra steps.csv columns, are read."""
    out = write_run(tmp_path / "fortran", steps=6, quantities=1)
    text = (out / "points.csv").read_text()
    text = text.replace("0000E+00,", "0000D+00,", 3)
    text = re.sub(r"^0,(.*),A,.*$", r"0,\1,A,0.0000000000000000-100,0.0", text, count=1,
                  flags=re.M)
    (out / "points.csv").write_text(text)
    check_ok(run_script(PLOT, out, "--only", "paths", "history", "iterations"))


def test_bad_arguments(tmp_path: Path) -> None:
    """Each bad argument: exit 2, one line on stderr, no traceback."""
    positions = write_run(tmp_path / "bad_positions", steps=4, quantities=1)
    empty = tmp_path / "bad_empty"
    empty.mkdir()
    (empty / "points.csv").write_text("step,t,point,x,y\n")
    no_points = tmp_path / "bad_nopoints"
    no_points.mkdir()
    garbled = write_run(tmp_path / "bad_garbled", steps=4, quantities=1)
    (garbled / "points.csv").write_text("step,t,point,x,y\n0,0.0,A,abc,0.0\n")
    cases = [
        ((tmp_path / "missing",), ("no such directory",)),
        ((no_points,), ("no points.csv",)),
        ((empty,), ("no steps were written",)),
        ((positions, "--only", "velocity"), ("computed no velocities", "compute")),
        ((positions, "--only", "acceleration"), ("computed no accelerations",)),
        ((positions, "--only", "bogus"), ("invalid choice", "bogus")),
        ((positions, "--instants", "-1"), ("--instants",)),
        ((garbled,), ("not a number",)),
        ((), ("outdir",)),
    ]
    for args, fragments in cases:
        try:
            check_usage_error(run_script(PLOT, *args), *fragments)
        except Failure as exc:
            raise Failure(f"plot.py {' '.join(map(str, args))}: {exc}") from None


# --------------------------------------------------------------------------- compare.py tests

def test_compare_identical(tmp_path: Path) -> None:
    """Two identical runs differ by exactly zero in every quantity."""
    one = write_run(tmp_path / "cmp_fem", steps=20)
    two = write_run(tmp_path / "cmp_angles", steps=20)
    target = tmp_path / "identical.png"
    proc = run_script(COMPARE, one, two, "--labels", "fem,angles", "-o", target)
    check_ok(proc)
    check_png(target)
    table = difference_table(proc.stdout)
    check(set(table) == {("angles", p) for p in "ABCD"}, f"table rows {sorted(table)}")
    for row in table.values():
        check(set(row) == {"x", "y", "vx", "vy", "ax", "ay"}, f"columns {sorted(row)}")
        check(all(v == 0.0 for v in row.values()), f"nonzero difference {row}")


def test_compare_perturbed(tmp_path: Path) -> None:
    """A perturbed y of C shows up as its exact maximum, the rest stays zero."""
    steps = 20
    t = np.linspace(0.0, 1.0, steps + 1)
    delta = 1e-3 * np.sin(2 * np.pi * t) + 2.5e-4
    base = write_run(tmp_path / "pert_base", steps=steps)
    bent = write_run(tmp_path / "pert_bent", steps=steps, perturb={("C", 1): delta})
    exact = tmp_path / "exact.csv"
    exact.write_text((base / "points.csv").read_text())
    target = tmp_path / "perturbed.png"
    proc = run_script(COMPARE, exact, base, bent, "--point", "C", "--quantity", "y",
                      "--labels", "exact,fem,bent", "-o", target)
    check_ok(proc)
    check_png(target)
    table = difference_table(proc.stdout)
    check(set(table) == {("fem", "C"), ("bent", "C")}, f"table rows {sorted(table)}")
    want = float(np.max(np.abs(delta)))
    got = table[("bent", "C")]["y"]
    check(abs(got - want) <= 1e-3 * want, f"max |dy| = {got}, want {want}")
    others = [v for q, v in table[("bent", "C")].items() if q != "y"]
    check(all(v == 0.0 for v in others) and all(v == 0.0 for v in table[("fem", "C")].values()),
          f"spurious differences {table}")


def test_compare_positions_only_and_default_output(tmp_path: Path) -> None:
    """Runs with positions only compare on x, y; the default output file is compare.png."""
    one = write_run(tmp_path / "cmp_pos1", steps=8, quantities=1)
    two = write_run(tmp_path / "cmp_pos2", steps=8, quantities=1)
    workdir = tmp_path / "cwd"
    workdir.mkdir()
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(COMPARE), str(one), str(two)], cwd=workdir,
                          capture_output=True, text=True, timeout=60, env=env)
    check_ok(proc)
    check_png(workdir / "compare.png")
    table = difference_table(proc.stdout)
    check(all(set(row) == {"x", "y"} for row in table.values()), f"columns {table}")


def test_compare_with_positions_only_exact(tmp_path: Path) -> None:
    """An exact solution with positions only: differences in x, y, '-' for the rest."""
    run = write_run(tmp_path / "cmp_full", steps=8)
    exact = tmp_path / "exact_positions.csv"
    lines = (run / "points.csv").read_text().splitlines()
    exact.write_text("\n".join(",".join(line.split(",")[:5]) for line in lines) + "\n")
    proc = run_script(COMPARE, run, exact, "--quantity", "y", "-o", tmp_path / "exact.png")
    check_ok(proc)
    table = difference_table(proc.stdout)
    check(set(table) == {("exact_positions", p) for p in "ABCD"}, f"rows {sorted(table)}")
    check(all(row == {"x": 0.0, "y": 0.0} for row in table.values()), f"table {table}")
    check(proc.stdout.count(" - ") >= 4, f"no '-' for missing quantities: {proc.stdout}")


def test_compare_bad_arguments(tmp_path: Path) -> None:
    """compare.py refuses bad arguments with exit 2 and one clear line."""
    one = write_run(tmp_path / "cbad_1", steps=10)
    coarse = write_run(tmp_path / "cbad_coarse", steps=5)
    positions = write_run(tmp_path / "cbad_pos", steps=10, quantities=1)
    out = tmp_path / "cbad.png"
    cases = [
        ((one, coarse), ("times differ",)),
        ((one,), ("at least two",)),
        ((one, tmp_path / "nowhere"), ("no such",)),
        ((one, one, "--labels", "a,b,c"), ("labels",)),
        ((one, one, "--point", "Z"), ("Z",)),
        ((one, positions, "--quantity", "vx"), ("velocities",)),
        ((one, one, "--quantity", "speed"), ("invalid choice",)),
        ((one, one, "-o", tmp_path / "nowhere" / "x.png"), ("no such directory",)),
    ]
    for args, fragments in cases:
        try:
            output = () if "-o" in args else ("-o", out)
            check_usage_error(run_script(COMPARE, *args, *output), *fragments)
        except Failure as exc:
            raise Failure(f"compare.py {' '.join(map(str, args))}: {exc}") from None
