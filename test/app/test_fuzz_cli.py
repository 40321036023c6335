#!/usr/bin/env python3
"""Fuzzing fekap's command line and output paths (the approach of
test_fuzz.py, which mutates decks).

Each case runs the checking build on a short Example 1 with a random command
line: options from the help and unknown ones, numbers and expressions (the
NaN/Inf/huge texts of test_fuzz.py), missing values, several decks, and an
output path made of shell characters, blanks, quotes, non-ASCII, long names,
a file in the way or a directory shared with the case before. Every run must
end with exit 0, 2, 3 or 4 (non-zero with a message on stderr), never a signal,
a Fortran runtime error or a hang; no file may appear outside the case's own
directory (a path taken by a shell would); a run that succeeds leaves whole
CSV rows in the directory it named.

FEKAP_FUZZ_CLI_CASES and FEKAP_FUZZ_SEED set the case count and the seed.
"""

from __future__ import annotations

import csv
import os
import random
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from apptest import ROOT, fekap_binary
from test_fuzz import BAD_SIGNS, NUMBERS  # noqa: E402

CASES = int(os.environ.get("FEKAP_FUZZ_CLI_CASES", "120"))
SEED = int(os.environ.get("FEKAP_FUZZ_SEED", "20240611"))

EXPRESSIONS = ["2*0.05", "pi/100", "0.1 junk", "1e-3*2", "sqrt(2)/100", "(0.01)", "0.01,", "0x1", "1_000",
               "--0.1", "0.025d0", "1/40", "deg", "+0.05", " 0.05", "0.05 ", "", "*", "1e-400", "2e-4", "10"]
WORDS = ["fem", "cartesian", "angles", "FEM", "previous", "extrapolate", "taylor", "positions",
         "positions,velocities", "accelerations", "velocities,", ",", "", "x", "positions,,velocities"]
OPTIONS = ["--dt", "--tol", "--method", "--predictor", "--compute", "-o", "-q", "--quiet"]
ODD_OPTIONS = ["--help", "-h", "--version", "--print-outdir", "--bogus", "-", "--", "-x", "--dt=0.1"]
PATH_PARTS = ["$(touch PWNED)", "`touch PWNED`", "$HOME", "${IFS}", "a b", "'q'", '"d"', "x;touch PWNED", "|",
              "&", "*", "?", "[a]", "\\", "ünï", "\t", "-o", ".", "..", "~", "a" * 200, "%s%n", ">x", "<y", "!"]


def random_path(rng: random.Random, case_dir: Path) -> str:
    parts = [rng.choice(PATH_PARTS) + rng.choice(["", "z", str(rng.randrange(9))]) for _ in range(rng.randint(1, 3))]
    path = case_dir / "out"
    for part in parts:
        path = path / part.replace("/", "_")
    if rng.random() < 0.1:
        (case_dir / "file").write_text("in the way\n")
        path = case_dir / "file" / "sub"
    if rng.random() < 0.05:
        path = case_dir / ("n" * 300)
    return str(path) + ("/" if rng.random() < 0.2 else "")


def random_command(rng: random.Random, deck: Path, case_dir: Path) -> list[str]:
    args: list[str] = []
    for _ in range(rng.randint(0, 4)):
        option = rng.choice(ODD_OPTIONS if rng.random() < 0.1 else OPTIONS)
        args.append(option)
        if option in ("--dt", "--tol") and rng.random() < 0.95:
            args.append(rng.choice(NUMBERS + EXPRESSIONS))
        elif option in ("--method", "--predictor", "--compute") and rng.random() < 0.95:
            args.append(rng.choice(WORDS))
        elif option == "-o" and rng.random() < 0.95:
            args.append(random_path(rng, case_dir))
    if rng.random() < 0.9:
        args += ["-o", random_path(rng, case_dir)]
    decks = [str(deck)] if rng.random() < 0.9 else [str(deck), str(deck)][: rng.randint(0, 2)]
    position = rng.randint(0, len(args))
    return args[:position] + decks + args[position:]


def csv_files_whole(directory: Path) -> list[str]:
    problems = []
    for path in directory.glob("*.csv"):
        data = path.read_bytes()
        if data and not data.endswith(b"\n"):
            problems.append(f"{path.name} ends in the middle of a row")
            continue
        rows = list(csv.reader(data.decode(errors="replace").splitlines()))
        if rows and any(len(row) != len(rows[0]) for row in rows):
            problems.append(f"{path.name} has ragged rows")
    return problems


def run_case(k: int, rng: random.Random, work: Path, deck: Path, binary: str) -> list[str]:
    case_dir = work / f"case{k}"
    case_dir.mkdir()
    command = random_command(rng, deck, case_dir)
    try:
        done = subprocess.run([binary, *command], cwd=case_dir, capture_output=True, text=True,
                              errors="replace", timeout=30)
    except subprocess.TimeoutExpired:
        return [f"case {k}: hang: {command!r}"]
    problems = []
    if done.returncode not in (0, 2, 3, 4):
        problems.append(f"exit {done.returncode}")
    if done.returncode != 0 and not done.stderr.strip():
        problems.append("non-zero exit without a message")
    if any(sign in done.stderr for sign in BAD_SIGNS):
        problems.append(f"crash: {done.stderr[-300:]}")
    for name in ("PWNED", "x", "y"):
        for place in (case_dir, ROOT, work):
            if (place / name).exists():
                problems.append(f"{place / name} appeared: a path went through a shell")
    if done.returncode == 0 and "-o" in command and not {"--help", "-h", "--version", "--print-outdir"} & set(command):
        out = Path(command[len(command) - 1 - command[::-1].index("-o") + 1])
        if out.is_dir():
            problems += csv_files_whole(out)
        else:
            problems.append(f"exit 0 but no directory {out}")
    return [f"case {k}: {problem}: {command!r}" for problem in problems]


def test_command_lines_and_output_paths():
    rng = random.Random(SEED)
    work = Path(tempfile.mkdtemp(prefix="fekap-fuzz-cli-"))
    try:
        deck = work / "fourbar.deck"
        deck.write_text((ROOT / "decks/fourbar.deck").read_text().replace("time 0 1 0.025", "time 0 0.1 0.025"))
        problems = []
        binary = fekap_binary()
        for k in range(CASES):
            problems += run_case(k, rng, work, deck, binary)
        assert not problems, "\n".join(problems[:20])
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    import pytest
    sys.exit(pytest.main([__file__, "-q"]))
