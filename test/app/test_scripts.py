"""The benchmark and study scripts on reduced sizes: studies/tables/paper_tables.py
--short, scripts/bench --quick, fekap.models.scissor (a 3-cell lift against its
exact platform height, with the band and the dense solver),
studies/bench/scissor_scale.py on small lifts and
studies/accuracy/accuracy_study.py --short. They run with the executable under test
($FEKAP_BIN, set by scripts/test) and write nothing into docs/.

Run with scripts/test (pytest): scripts/test NAME runs the tests whose names contain NAME.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

from fekap.models import scissor

from apptest import ROOT, check, read_rows, run_fekap, study_module

OUT: Path = None  # a fresh scratch directory for each run, set by conftest.py
LAST_LINE = re.compile(r"^fourbar us_per_config_full=(\S+) us_per_config_positions=(\S+) "
                       r"us_per_config_with_output=(\S+) iterations_per_step=(\S+)$")


def script(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    result = subprocess.run([*args], cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    check(result.returncode == 0, f"{' '.join(args)} exited {result.returncode}:\n{result.stdout[-2000:]}\n"
                                  f"{result.stderr[-2000:]}")
    return result


def test_paper_tables_short(fekap: Path) -> None:
    out = OUT / "tables.md"
    result = script(sys.executable, "studies/tables/paper_tables.py", "--short", "--out", str(out),
                    "--bin", str(fekap))
    text = out.read_text()
    for method in ("angles", "cartesian", "fem"):
        check(f"FEKAP paper settings: {method}" in text and f"FEKAP default: {method}" in text,
              f"the tables lack the {method} columns")
        check(f"method={method}" in result.stdout, f"no {method} run reported")
    for dt in ("0.025", "0.25", "0.5"):
        check(f"dt = {dt}" in text, f"no table for dt = {dt}")
    # The paper's Table 1 first row, copied exactly.
    check(re.search(r"^\| 0\.025 \| 5 \| 5 \| 6 \|", text, re.M) is not None, "paper's Table 1 row missing")
    check("Not Converged" in text, "the paper's Table 3 entry is missing")
    # Every run with the paper's settings ends on the upper branch; all runs exit 0.
    for line in result.stdout.splitlines():
        if line.startswith("dt="):
            check("exit=0" in line, f"a run failed: {line}")
    rows = [line for line in text.splitlines() if re.match(r"^\| [0-9.]+ \| \w+ \| paper \|", line)]
    check(len(rows) == 9 and all("upper (correct)" in row for row in rows),
          "runs with the paper's settings must end on the upper branch:\n" + "\n".join(rows))


def test_bench_quick(fekap: Path) -> None:
    result = script(str(ROOT / "scripts" / "bench"), "--quick", "--no-build", "--bin", str(fekap),
                    "--sizes", "10", "--dense-sizes", "10", timeout=180)
    lines = result.stdout.strip().splitlines()
    match = LAST_LINE.match(lines[-1])
    check(match is not None, f"last line has the wrong format: {lines[-1]!r}")
    values = [float(v) for v in match.groups()]
    check(all(v > 0 and math.isfinite(v) for v in values), f"non-positive figures: {lines[-1]}")
    check(1.0 <= values[3] <= 25, f"iterations per step out of range: {values[3]}")
    check(any("simulate only what a deck calls for" in line for line in lines), "no positions/full split")
    check(any("N =     10 dense" in line for line in lines), "no dense scissor run")


def test_bench_against_short(fekap: Path) -> None:
    """The before/after comparison of two executables (here the same one
    twice): both cases, both binaries, and the ratios of the medians."""
    result = script(sys.executable, str(ROOT / "studies" / "bench" / "bench_against.py"), str(fekap), str(fekap),
                    "--dt", "0.01", "--repeat", "1", timeout=120)
    lines = result.stdout.splitlines()
    for files in ("listing", "csv listing"):
        for label in ("before", "after"):
            check(any(line.startswith(f"  {files:12s} {label:6s} analysis") for line in lines),
                  f"no {label} analysis line for {files}:\n{result.stdout}")
        ratios = [float(line.split()[-1]) for line in lines if line.startswith(f"  {files:12s} after/before")]
        check(len(ratios) == 2 and all(r > 0 and math.isfinite(r) for r in ratios),
              f"ratios for {files}: {ratios}\n{result.stdout}")


def test_scissor_height_exact() -> None:
    cells = 3
    for solver in ("band", "dense"):
        deck = OUT / f"scissor3-{solver}.deck"
        script(sys.executable, "-m", "fekap.models.scissor", str(cells), "--out", str(deck), "--solver", solver)
        outdir = OUT / f"scissor3-{solver}"
        result = run_fekap("-q", "-o", str(outdir), str(deck))
        check(result.returncode == 0, f"fekap on {deck} exited {result.returncode}: {result.stderr}")
        rows = read_rows(outdir / "points.csv")
        check(len(rows) == 2 * 21, f"expected 2 tracked points x 21 steps, got {len(rows)} rows")
        worst = max(abs(float(r["y"]) - scissor.platform_height(cells, float(r["t"]))) for r in rows)
        check(worst <= 1e-9, f"{solver}: platform height off by {worst:.3e}")
        # The right end sits at 2 cos(theta): the lift closes as theta grows.
        right = [r for r in rows if r["point"] == f"R{cells}"]
        worst_x = max(abs(float(r["x"]) - 2 * math.cos(scissor.theta(float(r["t"])))) for r in right)
        check(worst_x <= 1e-9, f"{solver}: x of R{cells} off by {worst_x:.3e}")
        if solver == "dense":
            listing = (outdir / f"{deck.stem}.lis").read_text()
            check(re.search(r"Cholesky factorisations\s+0$", listing, re.M) is not None,
                  "the dense solver should factor every tangent by LU")


def test_scissor_scale_short(fekap: Path) -> None:
    """studies/bench/scissor_scale.py on lifts of 3 and 6 cells (short runs,
    its callgrind counts where valgrind is installed): a row per lift with 12 N
    + 1 equations, positive counts and memory, the issue's rates to round-off
    at one Newton iteration a step or so."""
    options = ["--steps", "2", "4", "--cpu-steps", "2", "6", "--repeat", "1"]
    callgrind = shutil.which("valgrind") is not None
    if not callgrind:
        options.append("--no-callgrind")
    result = script(sys.executable, str(ROOT / "studies" / "bench" / "scissor_scale.py"), "3", "6",
                    "--fekap", str(fekap), *options, timeout=300)
    rows = [line.split("|")[1:-1] for line in result.stdout.splitlines() if re.match(r"^\| \d", line)]
    check(len(rows) == 2, f"expected rows for N = 3 and 6:\n{result.stdout}")
    for cells, row in zip((3, 6), rows):
        n, equations, count, per, ms, mb, its, pos, vel, acc = (field.strip() for field in row)
        check(int(n) == cells and int(equations) == 12 * cells + 1, f"N and equations: {row}")
        if callgrind:
            check(int(count.replace(",", "")) > 0 and int(per.replace(",", "")) > 0, f"instructions: {row}")
        # The CPU time of a few steps of so small a lift is within the clock's
        # noise (it may even come out negative); only its form is checked.
        check(math.isfinite(float(ms)) and float(mb) > 0, f"CPU time and memory: {row}")
        check(1.0 <= float(its) <= 1.5, f"Newton iterations per step: {row}")
        check(max(float(pos), float(vel), float(acc)) < 1e-12, f"errors against the closed form: {row}")


def test_scissor_deck_text() -> None:
    text = scissor.deck_text(2)
    check(text.count("\n  M") >= 2 and "R0  y" in text and "L0  pin" in text, "unexpected deck:\n" + text)
    check(abs(scissor.platform_height(2, 0.0) - 2.0) < 1e-15, "height at theta0 = 30 deg is 2 N sin 30 = N")


def test_accuracy_study_short(fekap: Path) -> None:
    result = script(sys.executable, "studies/accuracy/accuracy_study.py", "--short", "--bin", str(fekap),
                    timeout=300)
    rows = [line for line in result.stdout.splitlines() if line.startswith("| ") and "---" not in line][1:]
    check(len(rows) >= 15, f"too few rows:\n{result.stdout}")
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        study, case, setting, rc, position = cells[:5]
        if case == "Example 1, default test" or study in ("step", "predictor", "penalty"):
            check(rc == "0" and float(position) < 1e-12, f"expected round-off accuracy: {row}")
    rollup = {c[2]: float(c[4]) for c in ([x.strip() for x in r.strip("|").split("|")] for r in rows)
              if c[1] == "cantilever roll-up"}
    check(rollup["16 elements"] < rollup["4 elements"] / 8, f"roll-up error does not fall as h^2: {rollup}")
    # The A02 chain's plateau over the change points is the elastic bars': with energy-momentum
    # it falls as they stiffen (EA 1e8 -> 1e12 at dt 5e-4: 1.6e-3 -> 4.3e-6 rad).
    summary = [line for line in result.stdout.splitlines() if line.startswith("- energy-momentum 0.8, dt 0.0005")]
    check(len(summary) == 1 and "falls as the bars stiffen" in summary[0], f"the stiffness sweep's summary: {summary}")



def test_bench_check_verdict_and_record() -> None:
    """scripts/bench --check's verdict (bench_instructions.check): a case more
    than 5 % above its recorded instruction count fails, a rise of exactly 5 %
    or a fall passes; and the committed docs/performance/bench.json records
    every case of the fixed set, so that --check has something to compare."""
    import json

    bi = study_module("bench/bench_instructions.py")

    recorded = {"a": {"instructions_per_configuration": 10000}, "b": {"instructions_per_configuration": 10000}}
    quiet = lambda line: None  # noqa: E731

    def now(count: int) -> dict:
        return {"instructions_per_configuration": count}

    check(bi.check({"a": now(10500), "b": now(9000)}, recorded, log=quiet), "a 5 % rise and a fall must pass")
    check(not bi.check({"a": now(10000), "b": now(10501)}, recorded, log=quiet), "a rise above 5 % must fail")
    record = json.loads((ROOT / "docs" / "performance" / "bench.json").read_text())
    missing = set(bi.CASES) - set(record.get("instructions", {}))
    check(not missing, f"bench.json records no instruction count for {sorted(missing)}")
    for name in bi.CASES:
        count = record["instructions"][name]["instructions_per_configuration"]
        check(count > 0, f"{name}: recorded count {count}")
