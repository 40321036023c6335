"""Fuzzing the fekap executable with mutated example decks.

Each case takes an example deck, applies one to three random mutations
(deleted, duplicated or swapped lines, swapped fields, huge and tiny numbers,
NaN and Inf text, random bytes, truncation, random keywords) and runs the
checking build of fekap (FEKAP_BIN: -fcheck=all, floating-point traps) on it
with a timeout. Every run must end with exit 0, 2 or 3 (2 and 3 with a
message on stderr), never a signal, a Fortran runtime error or a hang, and no
output file may hold a NaN or an Inf.

The time span of every mutated deck is forced short (an ANALysis block with
`time 0 0.1 0.025` inserted before END: a later setting replaces an earlier
one), so the mutated time lines are still read but runs stay fast.

The random seed is fixed; FEKAP_FUZZ_CASES and FEKAP_FUZZ_SEED override the
case count and the seed. Decks in test/app/fuzz-crashes/ (reproducers of
crashes found earlier) are run first, unmutated.

Run with scripts/test (pytest): scripts/test NAME runs the tests whose names contain NAME.
"""

from __future__ import annotations

import csv
import io
import math
import os
import random
import shutil
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from apptest import ROOT, check, fekap_binary

OUT: Path = None  # a fresh scratch directory for each run, set by conftest.py
CASES = int(os.environ.get("FEKAP_FUZZ_CASES", "6000"))
SEED = int(os.environ.get("FEKAP_FUZZ_SEED", "20240611"))
TIMEOUT = 10.0
SLOW_TIMEOUT = 120.0
SLOW: list[str] = []
WORKERS = max(1, min(4, os.cpu_count() or 1))
CRASH_DIR = ROOT / "test/app/fuzz-crashes"
BASE_DECKS = sorted(p for p in list((ROOT / "decks").glob("*.deck")) + list((ROOT / "decks/hard").glob("*.deck"))
                    if "1000-turns" not in p.name)

SHORT_TIME = "ANALysis\n  time 0 0.1 0.025\n"
BAD_SIGNS = ("Fortran runtime error", "Program received signal", "At line ", "Backtrace", "Segmentation")
NUMBERS = ["1e300", "-1e300", "1e308", "1.7976931348623157e308", "1e100", "-1e100", "1e99", "1e-300", "-1e-300",
           "1e-12", "1e-100", "0", "-0", "0.0", "NaN", "nan", "-NaN", "Inf", "-Inf", "inf", "Infinity",
           "1e400", "-1e400", "1/0", "0/0", "sqrt(-1)", "log(0)", "asin(2)", "1e200*1e200", "-1e200*1e200",
           "1e-200*1e-200", "1e-320", "4.9e-324", "2^1024", "exp(710)", "exp(-1000)", "atan2(0,0)",
           "1e15", "123456789012345678901234567890", "1d400", "0x10", "1..2", "--1", "+-1", "2**-2**3",
           "((((((((((1))))))))))", "(" * 60 + "1" + ")" * 60, "1e", "e1", ".", "-", "pi*1e308",
           "100000", "99999", "1000001", "-1", "2147483648", "9223372036854775808", "1e9", "0.5"]
WORDS = ["TITLe", "SECTions", "NODEs", "COORdinates", "LINKs", "ELEMents", "WELDs", "SUPPorts", "BOUNdary",
         "DRIVes", "LOADs", "SLIDelines", "ANALysis", "OUTPut", "INCLude", "END", "END END", "MATErial",
         "time 0 0.1 0.025", "time 0 1e-300 1e-301", "time 1 0 0.1", "iterations 1", "iterations 0",
         "iterations 1000000000", "tolerance 1e-300", "tolerance 0.999", "length 1e-300", "predictor taylor",
         "predictor previous", "method cartesian", "method angles", "convergence paper", "gauss 2", "gauss 3",
         "redundant remove", "compute positions", "compute accelerations", "every 0", "every 1000000",
         "files vtk", "files csv listing vtk", "track", "angles", "pin", "rot", "x", "y", "guide 0 0 0 0",
         "rotation AB rate 1e300", "x B rate 1", "y C polynomial 0 1e300", "rotation AB table 0 0 0 1",
         "rotation AB harmonic 0 1 1e300", "A pin", "B pin", "C pin", "A 0 0", "Z 1 1", "AB A A bar",
         "AB A B bar 100000", "AB A B bar 0", "bar E=0 G=1 A=1 I=1", "bar EA=1e300 kGA=1e300 EI=1e-300",
         "bar E=-1 G=1 A=1 I=1", "slot C on AB pin penalty=1e300", "s B guide 0 0 1e300 0", "INCLude /dev/zero",
         "INCLude /nonexistent", "INCLude " + "x" * 300, "*", "!", ",", ",,", "=", "k=", "\t", "\\", "\"", "'"]
BYTES = [b"\x00", b"\xff", b"\xfe\xff", b"\x1b[0m", b"\t", b"\r", b"\r\n", b"\x7f", b"\xc3\xa9", b"\xe2\x80\x8b",
         b"\x0c", b"\x08", b"\n\n\n", b" " * 200, b"A" * 5000, b"1" * 400, b"(" * 300, b"*" * 50]


def mutate(rng: random.Random, data: bytes) -> tuple[bytes, list[str]]:
    """Apply one to three random mutations; return the new deck and what was done."""
    done = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        lines = data.split(b"\n")
        kind = rng.randrange(14)
        i = rng.randrange(len(lines))
        if kind == 0 and len(lines) > 1:
            del lines[i]
            done.append(f"delete line {i + 1}")
        elif kind == 1:
            lines.insert(i, lines[i])
            done.append(f"duplicate line {i + 1}")
        elif kind == 2:
            j = rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
            done.append(f"swap lines {i + 1} {j + 1}")
        elif kind == 3:
            fields = lines[i].split()
            if len(fields) >= 2:
                a, b = rng.sample(range(len(fields)), 2)
                fields[a], fields[b] = fields[b], fields[a]
                lines[i] = b"  ".join(fields)
                done.append(f"swap fields in line {i + 1}")
        elif kind in (4, 5):
            # A number (or NaN/Inf text) in place of a field, numeric fields preferred.
            fields = lines[i].split()
            if fields:
                numeric = [k for k, f in enumerate(fields) if f[:1] in b"0123456789-+.(" or b"=" in f]
                k = rng.choice(numeric or list(range(len(fields))))
                value = rng.choice(NUMBERS).encode()
                if b"=" in fields[k]:
                    fields[k] = fields[k].split(b"=")[0] + b"=" + value
                else:
                    fields[k] = value
                lines[i] = b"  ".join(fields)
                done.append(f"number {value.decode()!r} in line {i + 1}")
        elif kind == 6:
            pos = rng.randrange(len(data) + 1)
            chunk = rng.choice(BYTES) if rng.random() < 0.5 else bytes(rng.randrange(256)
                                                                        for _ in range(rng.randrange(1, 9)))
            data = data[:pos] + chunk + data[pos:]
            done.append(f"bytes {chunk[:20]!r} at {pos}")
            continue
        elif kind == 7:
            pos = rng.randrange(len(data) + 1)
            data = data[:pos]
            done.append(f"truncate at {pos}")
            continue
        elif kind in (8, 9):
            word = rng.choice(WORDS).encode()
            if rng.random() < 0.5:
                lines.insert(i, word)
                done.append(f"insert {word.decode()!r} at line {i + 1}")
            else:
                fields = lines[i].split()
                if fields:
                    fields[rng.randrange(len(fields))] = word
                    lines[i] = b"  ".join(fields)
                    done.append(f"word {word.decode()!r} in line {i + 1}")
        elif kind in (11, 12, 13):
            # Keep the deck valid more often: scale or nudge a plain number.
            fields = lines[i].split(b" ")
            numeric = [k for k, f in enumerate(fields) if f and _is_number(f.split(b"=")[-1])]
            if numeric:
                k = rng.choice(numeric)
                key, _, value = fields[k].rpartition(b"=")
                x = float(value)
                if kind == 11:
                    x *= 10.0 ** rng.randint(-12, 12)
                elif kind == 12:
                    x += rng.uniform(-1, 1) * 10.0 ** rng.randint(-9, 0)
                else:
                    x = -x
                fields[k] = (key + b"=" if key else b"") + repr(x).encode()
                lines[i] = b" ".join(fields)
                done.append(f"number {x!r} in line {i + 1}")
        else:
            # Duplicate a block of lines (a whole card's block, often).
            j = min(len(lines), i + rng.randrange(1, 8))
            lines[j:j] = lines[i:j]
            done.append(f"duplicate lines {i + 1}-{j}")
        data = b"\n".join(lines)
    return data, done


def _is_number(field: bytes) -> bool:
    try:
        return math.isfinite(float(field))
    except ValueError:
        return False


def shorten(data: bytes) -> bytes:
    """Insert the short time span before the first END line, if any."""
    lines = data.split(b"\n")
    for k, line in enumerate(lines):
        if line.strip().upper() == b"END":
            lines[k:k] = SHORT_TIME.encode().rstrip(b"\n").split(b"\n")
            break
    return b"\n".join(lines)


def bad_numbers(outdir: Path) -> list[str]:
    """NaN or Inf values, or ragged rows, in the output CSV files."""
    problems = []
    if not outdir.is_dir():
        return problems
    for path in outdir.glob("*.csv"):
        text = path.read_text(errors="replace")
        rows = list(csv.reader(io.StringIO(text)))
        if not rows:
            continue
        header = rows[0]
        for row in rows[1:]:
            if len(row) != len(header):
                problems.append(f"{path.name}: ragged row {row}")
                continue
            for name, field in zip(header, row):
                if name in ("point", "link", "node1", "node2", "kind", "node") or field == "":
                    continue
                try:
                    value = float(field)
                except ValueError:
                    problems.append(f"{path.name}: {name} = {field!r}")
                    continue
                if not math.isfinite(value):
                    problems.append(f"{path.name}: {name} = {field}")
        if not text.endswith("\n"):
            problems.append(f"{path.name}: incomplete last line")
    for path in outdir.glob("*.vtk"):
        text = path.read_text(errors="replace").lower()
        if "nan" in text or "inf" in text.replace("info", ""):
            problems.append(f"{path.name}: NaN or Inf")
    return problems


def run_one(case: int, deck: Path, data: bytes, what: list[str]) -> str | None:
    """Run one mutated deck; return a failure description or None."""
    # One directory per case: cases run concurrently.
    work = OUT / f"case{case}"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    path = work / f"case{case}.deck"
    path.write_bytes(data)
    outdir = work / "out"
    try:
        result = subprocess.run([fekap_binary(), "-q", "-o", str(outdir), str(path)], cwd=work,
                                capture_output=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        # Slow is not hung: a big mesh (up to 100,000 elements per link) may
        # take long in the checking build. Give it SLOW_TIMEOUT once more.
        try:
            result = subprocess.run([fekap_binary(), "-q", "-o", str(outdir), str(path)], cwd=work,
                                    capture_output=True, timeout=SLOW_TIMEOUT)
        except subprocess.TimeoutExpired:
            return save(case, deck, data, what, f"timeout after {SLOW_TIMEOUT} s")
        SLOW.append(f"case {case} ({deck.name}: {', '.join(what)})")
    stderr = result.stderr.decode(errors="replace")
    stdout = result.stdout.decode(errors="replace")
    if result.returncode not in (0, 2, 3):
        return save(case, deck, data, what, f"exit {result.returncode}:\n{stderr[-2000:]}")
    if any(sign in stderr or sign in stdout for sign in BAD_SIGNS):
        return save(case, deck, data, what, f"runtime error:\n{stderr[-2000:]}")
    if result.returncode in (2, 3) and not stderr.strip():
        return save(case, deck, data, what, f"exit {result.returncode} without a message")
    problems = bad_numbers(outdir)
    if problems:
        return save(case, deck, data, what, "bad output: " + "; ".join(problems[:5]))
    shutil.rmtree(work, ignore_errors=True)
    return None


def save(case: int, deck: Path, data: bytes, what: list[str], why: str) -> str:
    """Keep a failing case's deck (outside the repository) and describe it."""
    keep = OUT / "failures"
    keep.mkdir(exist_ok=True)
    path = keep / f"{deck.stem}-case{case}.deck"
    path.write_bytes(data)
    return f"case {case} ({deck.name}: {', '.join(what)}): {why}\n      reproducer: {path}"


KNOWN_CRASHES = sorted(CRASH_DIR.glob("*.deck")) if CRASH_DIR.is_dir() else []


def test_known_crashes_present():
    """The reproducers of crashes found earlier are there to be run."""
    check(bool(KNOWN_CRASHES), f"no reproducers in {CRASH_DIR}")


@pytest.mark.parametrize("deck", KNOWN_CRASHES, ids=lambda d: d.stem)
def test_known_crashes(deck):
    """A reproducer of a crash found earlier (test/app/fuzz-crashes/, all fixed)
    must now end with exit 0, 2 or 3 and a message, like any deck."""
    failure = run_one(KNOWN_CRASHES.index(deck), deck, deck.read_bytes(), ["reproducer"])
    check(failure is None, str(failure))


def test_mutated_decks():
    rng = random.Random(SEED)
    cases = []
    for case in range(CASES):
        deck = rng.choice(BASE_DECKS)
        data, what = mutate(rng, deck.read_bytes())
        cases.append((case, deck, shorten(data), what))
    start = time.time()
    with ThreadPoolExecutor(max_workers=WORKERS) as pool:
        results = list(pool.map(lambda c: run_one(*c), cases))
    failures = [r for r in results if r]
    print(f"  fuzz: {CASES} mutated decks (seed {SEED}) from {len(BASE_DECKS)} base decks "
          f"in {time.time() - start:.1f} s: {len(failures)} failures, {len(SLOW)} slow (over {TIMEOUT:.0f} s)")
    for line in SLOW[:5]:
        print("    " + line.splitlines()[0])
    check(not failures, "\n".join(failures[:20]) + (f"\n... and {len(failures) - 20} more"
                                                     if len(failures) > 20 else ""))

