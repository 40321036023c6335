#!/usr/bin/env python3
"""What surrounds the analysis (issue #21): checked writes on a full disk, an
output directory made without a shell, locked for one run and cleared of an
earlier run's files, command-line numbers read as deck expressions, the deck
reader's limits, signals and messages.

Each test runs the fekap executable (FEKAP_BIN, the checking build under
scripts/test) in a few seconds. The full-disk tests mount a small tmpfs of
their own and are skipped, saying why, where that is not allowed (not root,
no mount).

Run alone:  scripts/test robust
"""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import pytest

from apptest import ROOT, fekap_binary

FOURBAR = ROOT / "decks/fourbar.deck"
VTK_DECK_LINE = "  files csv listing vtk\n"


def fekap(*args: str, cwd: Path = ROOT, timeout: float = 60, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([fekap_binary(), *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, **kw)


def deck_text(**replace: str) -> str:
    """Example 1 with lines replaced (old text -> new text)."""
    text = FOURBAR.read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    return text


def write_deck(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def whole_rows(path: Path) -> list[list[str]]:
    """The rows of a CSV file, checking that it ends with a whole line and no row is ragged."""
    data = path.read_bytes()
    assert data == b"" or data.endswith(b"\n"), f"{path} ends in the middle of a row: {data[-60:]!r}"
    rows = list(csv.reader(data.decode().splitlines()))
    if rows:
        width = len(rows[0])
        ragged = [row for row in rows if len(row) != width]
        assert not ragged, f"{path}: ragged rows {ragged[:3]}"
        if path.name != "mesh.csv":
            for row in rows[1:]:
                for field in row[:2]:
                    float(field)
    return rows


# --- 1. checked writes on a full disk -------------------------------------------------------------

class SmallFileSystem:
    """A tmpfs of `size` bytes mounted on a fresh directory (root only)."""

    def __init__(self, size: int):
        self.path = Path(tempfile.mkdtemp(prefix="fekap-fs-"))
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(self.path)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            self.path.rmdir()
            pytest.skip(f"cannot mount a small tmpfs for the full-disk test (needs root): {done.stderr.strip()}")

    def fill(self, leave: int) -> None:
        """Fill the file system up to `leave` free bytes."""
        stat = os.statvfs(self.path)
        free = stat.f_bavail * stat.f_frsize
        if free > leave:
            (self.path / "filler").write_bytes(b"x" * (free - leave))

    def close(self) -> None:
        subprocess.run(["umount", str(self.path)], capture_output=True)
        self.path.rmdir()


def test_full_disk_stops_with_exit_4_and_keeps_whole_rows():
    fs = SmallFileSystem(256 * 1024)
    try:
        out = fs.path / "run"
        done = fekap("-q", "-o", out, "--dt", "1e-4", FOURBAR)
        assert done.returncode == 4, (done.returncode, done.stderr)
        assert "No space left on device" in done.stderr, done.stderr
        assert str(out) in done.stderr and "cannot write" in done.stderr, done.stderr
        assert "Fortran runtime error" not in done.stderr and "Backtrace" not in done.stderr
        for name in ("points.csv", "links.csv", "steps.csv", "mesh.csv"):
            whole_rows(out / name)
        listing = (out / "fourbar.lis").read_bytes()
        assert listing == b"" or listing.endswith(b"\n")
    finally:
        fs.close()


def test_nearly_full_disk_never_reports_success_with_cut_files():
    # The first files fit, the later ones do not: either the run succeeds
    # with complete files, or it says which file failed (exit 4).
    for leave in (4096, 16384, 40960):
        fs = SmallFileSystem(128 * 1024)
        try:
            fs.fill(leave)
            out = fs.path / "run"
            done = fekap("-q", "-o", out, FOURBAR)
            assert done.returncode in (0, 4), (leave, done.returncode, done.stderr)
            if done.returncode == 0:
                steps = whole_rows(out / "steps.csv")
                assert len(steps) == 1 + 41, (leave, len(steps))
                assert b"SUMMARY" in (out / "fourbar.lis").read_bytes()
            else:
                assert "cannot write" in done.stderr
                for name in ("points.csv", "links.csv", "steps.csv"):
                    if (out / name).exists():
                        whole_rows(out / name)
        finally:
            fs.close()


def test_file_size_limit_stops_with_exit_4_and_keeps_whole_rows(tmp_path):
    # `ulimit -f`: a write past the limit fails with EFBIG as on a full disk.
    # Before, the Fortran runtime's SIGXFSZ handler ended the run (exit 153,
    # a backtrace, points.csv cut inside a row).
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (16384, 16384))

    out = tmp_path / "run"
    done = fekap("-q", "-o", out, "--dt", "1e-4", FOURBAR, preexec_fn=limit)
    assert done.returncode == 4, (done.returncode, done.stderr)
    assert "File too large" in done.stderr and "cannot write" in done.stderr, done.stderr
    assert "Program received signal" not in done.stderr and "Backtrace" not in done.stderr, done.stderr
    for name in ("points.csv", "links.csv", "steps.csv", "mesh.csv"):
        whole_rows(out / name)


def test_full_disk_leaves_no_cut_vtk_file(tmp_path):
    fs = SmallFileSystem(192 * 1024)
    try:
        deck = write_deck(tmp_path / "fourbar.deck", deck_text(**{"OUTPut\n": "OUTPut\n" + VTK_DECK_LINE}))
        out = fs.path / "run"
        done = fekap("-q", "-o", out, "--dt", "0.005", deck)
        assert done.returncode == 4, (done.returncode, done.stderr)
        assert "No space left on device" in done.stderr
        files = sorted((out / "vtk").glob("*.vtu"))
        assert files, "no VTK file written before the disk filled"
        for path in files + sorted(out.glob("*.pvd")):
            ElementTree.parse(path)   # raises on a cut file
        assert not list(out.glob("*.fekap-tmp"))
    finally:
        fs.close()


def test_unwritable_directory_is_exit_4_with_reason(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory\n")
    done = fekap("-q", "-o", blocker / "sub", FOURBAR)
    assert done.returncode == 4, (done.returncode, done.stderr)
    assert "cannot create the directory" in done.stderr and "Not a directory" in done.stderr, done.stderr


# --- 2. directories made without a shell ----------------------------------------------------------

@pytest.mark.parametrize("name", ["$(touch PWNED)x", "`touch PWNED`", 'a"b', "x $HOME y", "it's", "a\\b", "semi;colon"])
def test_output_path_is_taken_literally(tmp_path, name):
    out = tmp_path / "deep" / name
    done = fekap("-q", "-o", out, FOURBAR, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (out / "points.csv").is_file()
    assert not (tmp_path / "PWNED").exists() and not (ROOT / "PWNED").exists()
    assert [p.name for p in (tmp_path / "deep").iterdir()] == [name]


def test_deck_name_with_shell_characters_gives_a_literal_default_directory(tmp_path):
    name = 'a$(touch PWNED) `touch PWNED` "q"'
    deck = write_deck(tmp_path / f"{name}.deck", FOURBAR.read_text())
    done = fekap("-q", deck.name, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / name / "points.csv").is_file()
    assert not (tmp_path / "PWNED").exists()


# --- 3 and 8. one run per output directory, stale files -------------------------------------------

def long_run(out: Path, *extra: str) -> subprocess.Popen:
    """A run of some seconds into `out`, started once its files exist."""
    proc = subprocess.Popen([fekap_binary(), "-q", "-o", str(out), "--dt", "2e-6", *extra, str(FOURBAR)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 20
    while not (out / "steps.csv").exists():
        assert proc.poll() is None, proc.communicate()
        assert time.time() < deadline, "the long run did not start"
        time.sleep(0.02)
    return proc


def test_second_run_into_a_locked_directory_stops_with_exit_2(tmp_path):
    out = tmp_path / "same"
    first = long_run(out)
    try:
        second = fekap("-q", "-o", out, FOURBAR)
        assert second.returncode == 2, (second.returncode, second.stderr)
        assert "another fekap run is writing" in second.stderr, second.stderr
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=30)
    assert first.returncode == 1
    rows = whole_rows(out / "steps.csv")
    assert [int(row[0]) for row in rows[1:]] == list(range(len(rows) - 1)), "steps.csv mixes two runs"


def test_lock_of_a_killed_run_does_not_block(tmp_path):
    out = tmp_path / "killed"
    first = long_run(out)
    first.kill()
    first.communicate(timeout=30)
    done = fekap("-q", "-o", out, FOURBAR)
    assert done.returncode == 0, done.stderr


def test_runs_started_together_into_one_directory_never_mix(tmp_path):
    out = tmp_path / "together"
    procs = [subprocess.Popen([fekap_binary(), "-q", "-o", str(out), "--dt", "1e-3", str(FOURBAR)], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(6)]
    codes = [p.wait(timeout=60) for p in procs]
    assert set(codes) <= {0, 2} and codes.count(0) >= 1, codes
    rows = whole_rows(out / "steps.csv")
    assert len(rows) == 1 + 1001
    assert (out / "fourbar.lis").read_text().count("SUMMARY") == 1


def test_files_of_fekaps_names_without_a_manifest_are_refused_unless_forced(tmp_path):
    # Issue #31: only the files a run's manifest lists are removed; files of
    # the names a run writes that no manifest lists stop the run (exit 2)
    # unless --force, which removes them (energy.csv too, which a kinematics
    # run does not write: plot.py would read it as the run's). Other files are
    # kept either way.
    out = tmp_path / "reused"
    (out / "vtk").mkdir(parents=True)
    stale = ["old.pvd", "old.lis", "paths.png", "history_P.png", "energy.csv", "angles.png", "iterations.png",
             "motion.gif", "links.csv", "x.pvd.fekap-tmp", "vtk/old_000001.vtu"]
    for name in stale:
        (out / name).write_text("stale\n")
    (out / "notes.txt").write_text("mine\n")
    done = fekap("-q", "-o", out, FOURBAR)
    assert done.returncode == 2, done.stderr
    for name in ("paths.png", "history_P.png", "links.csv", "energy.csv"):
        assert name in done.stderr, done.stderr
    assert "of the names FEKAP's runs and plots write" in done.stderr, done.stderr
    assert "give --force to remove them" in done.stderr, done.stderr
    for name in ("old.pvd", "old.lis", "notes.txt", "old_000001.vtu"):
        assert name not in done.stderr, done.stderr
    assert all((out / name).read_text() == "stale\n" for name in stale), "a refused run changed files"
    done = fekap("-q", "-o", out, "--force", FOURBAR)
    assert done.returncode == 0, done.stderr
    left = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    assert left == [".fekap-manifest", "fourbar.lis", "links.csv", "mechanism.txt", "mesh.csv", "nodes.csv",
                    "notes.txt", "old.lis", "old.pvd", "points.csv", "steps.csv", "vtk", "vtk/old_000001.vtu",
                    "x.pvd.fekap-tmp"], left
    assert (out / "links.csv").read_text() != "stale\n"


# --- 7. command-line numbers ----------------------------------------------------------------------

@pytest.mark.parametrize("value, step", [("2*0.05", "1.00000E-01"), ("pi/100", "3.14159E-02"), ("1e-2", "1.00000E-02")])
def test_dt_is_an_expression(tmp_path, value, step):
    done = fekap("-q", "-o", tmp_path / "o", "--dt", value, FOURBAR)
    assert done.returncode == 0, done.stderr
    assert f"step  {step}" in (tmp_path / "o/fourbar.lis").read_text()


@pytest.mark.parametrize("option, value, why", [("--dt", "0.1 junk", "expected a real number"),
                                                ("--dt", "2*", "expected a real number"),
                                                ("--dt", "-0.1", "expected a positive number"),
                                                ("--dt", "1/0", "not a finite number"),
                                                ("--tol", "abc", "unknown name"),
                                                ("--tol", "2", "between 0 and 1")])
def test_bad_numbers_on_the_command_line_are_refused(tmp_path, option, value, why):
    done = fekap("-q", "-o", tmp_path / "o", option, value, FOURBAR)
    assert done.returncode == 2, done.stderr
    assert f"{option} '{value}'" in done.stderr and why in done.stderr, done.stderr


def test_tol_is_an_expression(tmp_path):
    done = fekap("-q", "-o", tmp_path / "o", "--tol", "2*1e-3", FOURBAR)
    assert done.returncode == 0, done.stderr
    assert "tolerance  2.00E-03" in (tmp_path / "o/fourbar.lis").read_text()


# --- 9. deck reader limits ------------------------------------------------------------------------

@pytest.mark.parametrize("field", ["(" * 20000 + "1" + ")" * 20000, "-" * 100000 + "1", "sqrt(" * 5000 + "1" + ")" * 5000])
def test_deeply_nested_expression_is_a_deck_error(tmp_path, field):
    deck = write_deck(tmp_path / "deep.deck", deck_text(**{"  B   2   0": f"  B   {field}   0"}))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2, (done.returncode, done.stderr[-500:])
    assert "nested too deeply" in done.stderr


def chain_deck(n: int, drive: bool = True) -> str:
    lines = ["TITLe chain", "SECTions", "  bar E=1 G=1 A=100 I=1 k=5/6", "NODEs"]
    lines += [f"  N{i} {i} 0" for i in range(n + 1)]
    lines += ["LINKs"] + [f"  L{i} N{i} N{i + 1} bar" for i in range(n)]
    lines += ["WELDs"] + [f"  N{i} L{i - 1} L{i}" for i in range(1, n)]
    lines += ["SUPPorts", "  N0 pin"]
    if drive:
        lines += ["DRIVes", "  rotation L0 rate 1"]
    lines += ["ANALysis", "  time 0 1 1", "END"]
    return "\n".join(lines) + "\n"


def test_long_welded_chain_reads_in_linear_time(tmp_path):
    # 100,000 welded links and no drive: everything is read and checked, then
    # one deck error. Quadratic lookups took 53 s here (checking build); the
    # timeout is a hang guard, not a timing.
    deck = write_deck(tmp_path / "chain.deck", chain_deck(100000, drive=False))
    done = fekap("-q", "-o", tmp_path / "o", deck, timeout=30)
    assert done.returncode == 2
    assert "missing required block DRIVes or LOADs" in done.stderr
    assert done.stderr.count("error:") == 1


def test_welded_twice_is_still_found(tmp_path):
    text = chain_deck(4).replace("WELDs\n", "WELDs\n  N2 L2 L1\n")
    done = fekap("-q", "-o", tmp_path / "o", write_deck(tmp_path / "c.deck", text))
    assert done.returncode == 2
    assert "is already welded at node N2" in done.stderr


def test_many_bad_lines_give_a_bounded_report(tmp_path):
    lines = "".join(f"  N{i} 1+ x*y\n" for i in range(200000))
    deck = write_deck(tmp_path / "bad.deck", "NODEs\n" + lines + "END\n")
    done = fekap("-q", "-o", tmp_path / "o", deck, timeout=60)
    assert done.returncode == 2
    assert len(done.stderr) < 100000, len(done.stderr)
    assert "more errors not shown" in done.stderr
    # The first errors in deck order are the ones shown.
    assert "bad.deck:2:" in done.stderr


# --- 10. signals and messages ---------------------------------------------------------------------

def test_sighup_stops_the_run_like_sigterm(tmp_path):
    out = tmp_path / "hup"
    proc = long_run(out)
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 1, (proc.returncode, err)
    assert "interrupted by signal 1" in err
    assert "RUN STOPPED" in (out / "fourbar.lis").read_text()
    whole_rows(out / "points.csv")


#: A cantilever of 20,000 elements: step 0 load-steps a dead tip force of 60 (about 100 Newton
#: iterations), step 1 adds 1000 more in one step (about 160 iterations and 5 step cuts: 4 s in
#: the release build, longer in the checking one).
SLOW_STEP_DECK = """TITLe  a slow step: a cantilever of 20000 elements under a large tip force in one step
SECTions
  beam  EA=1e5  kGA=1e5  EI=1
NODEs
  R  0  0
  T  1  0
LINKs
  RT  R  T  beam  20000
SUPPorts
  R  pin  rot RT
LOADs
  T  0  -60  constant
  T  0  -1000  linear 0 0 1 1
ANALysis
  type statics
  time 0 2 1
END
"""


@pytest.mark.parametrize("sig", (signal.SIGTERM, signal.SIGINT), ids=lambda s: s.name)
def test_a_signal_stops_a_slow_step_between_newton_iterations(tmp_path, sig):
    """The signal comes once step 0's rows are on disk: the time loop looks for a signal after a
    step before it flushes that step's rows, so the signal is seen inside step 1 (the slow one,
    seconds long), never after step 0. The run stops inside step 1 (not after it), exits 1, says
    so on stderr and in the listing, and keeps step 0's rows whole."""
    out = tmp_path / "slow"
    deck = write_deck(tmp_path / "slow.deck", SLOW_STEP_DECK)
    proc = subprocess.Popen([fekap_binary(), "-q", "-o", str(out), str(deck)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    points = out / "points.csv"
    deadline = time.time() + 120
    # The rows of step 0 reach the file at the first flush after it (a flush waits 0.1 s from the
    # last, and step 0 takes longer), after the loop's signal check of step 0.
    while not (points.exists() and "\n0," in points.read_text()):
        assert proc.poll() is None, proc.communicate()
        assert time.time() < deadline, "step 0 did not finish"
        time.sleep(0.02)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, (proc.returncode, err)
    assert f"interrupted by signal {int(sig)} during step 1 " in err, err
    assert "the step was stopped, the rows of the completed steps are kept" in err
    listing = (out / "slow.lis").read_text()
    assert f"interrupted by signal {int(sig)} during step 1" in listing and "SUMMARY" in listing
    rows = whole_rows(points)
    assert [row[0] for row in rows] == ["step", "0", "0"], rows
    reactions = whole_rows(out / "reactions.csv")[1:]
    assert reactions and all(row[0] == "0" for row in reactions), reactions


def test_closed_standard_output_is_not_a_failure(tmp_path):
    done = subprocess.run(["bash", "-c", '"$0" -o "$1" "$2" | head -c 1 >/dev/null; echo "${PIPESTATUS[0]}"',
                           fekap_binary(), str(tmp_path / "o"), str(FOURBAR)], capture_output=True, text=True,
                          timeout=60)
    assert done.stdout.strip() == "0", (done.stdout, done.stderr)
    assert "SUMMARY" in (tmp_path / "o/fourbar.lis").read_text()


def reference_steps(tmp_path: Path) -> bytes:
    done = fekap("-q", "-o", tmp_path / "ref", FOURBAR)
    assert done.returncode == 0
    return (tmp_path / "ref/points.csv").read_bytes()


def test_byte_order_mark_is_skipped(tmp_path):
    deck = tmp_path / "bom.deck"
    deck.write_bytes(b"\xef\xbb\xbf" + FOURBAR.read_bytes())
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "o/points.csv").read_bytes() == reference_steps(tmp_path)


def test_carriage_return_line_ends_are_line_ends(tmp_path):
    deck = tmp_path / "mac.deck"
    deck.write_bytes(FOURBAR.read_bytes().replace(b"\n", b"\r"))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "o/points.csv").read_bytes() == reference_steps(tmp_path)


def test_deck_from_a_pipe(tmp_path):
    done = subprocess.run([fekap_binary(), "-q", "-o", str(tmp_path / "o"), "/dev/stdin"], input=FOURBAR.read_text(),
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "o/points.csv").read_bytes() == reference_steps(tmp_path)


def test_endless_inputs_are_refused_not_read_forever(tmp_path):
    deck = write_deck(tmp_path / "z.deck", "INCLude /dev/zero\nEND\n")
    done = fekap("-q", "-o", tmp_path / "o", deck, timeout=30)
    # A device is no regular file: refused before it is opened (issue #31).
    assert done.returncode == 2 and "a device, not a regular file" in done.stderr, done.stderr[-300:]


def test_element_count_above_the_limit_names_the_limit(tmp_path):
    deck = write_deck(tmp_path / "e.deck", deck_text(**{"  AB  A  B  bar": "  AB  A  B  bar 100001"}))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2
    assert "at most 100000" in done.stderr and "at least 1" not in done.stderr, done.stderr


def test_a_drive_law_that_overflows_is_named(tmp_path):
    # Every number of the law is within the deck's limits, but 1e15 t^33 at
    # t = 1e9 is 1e312: an input error at the law (exit 2), before any
    # arithmetic overflows with it. Before, the run stopped at step 1 asking
    # for the deck to be reported as a failure of the method (exit 3), and
    # the checking build stopped on a floating-point trap.
    law = "polynomial " + "0 " * 33 + "1e15"
    deck = write_deck(tmp_path / "p.deck", deck_text(**{"rate 2*pi": law, "time 0 1 0.025": "time 0 1e9 1e8"}))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2, done.stderr
    line = next(k for k, text in enumerate(deck.read_text().splitlines(), 1) if "polynomial" in text)
    assert f"{deck}:{line}:" in done.stderr and "end time is beyond 1e100" in done.stderr, done.stderr
    assert "please report" not in done.stderr and "signal" not in done.stderr, done.stderr


def test_elements_in_all_above_the_limit_name_the_link(tmp_path):
    # 11 links of 100,000 elements each: 1,100,000 in all, above the deck's
    # 1,000,000. Before, 200 such links ended in the runtime's "Error
    # allocating ... bytes" and a backtrace (exit 1), or in the system's
    # out-of-memory killer; the error is now the reader's, at the eleventh.
    lines = [f"  L{k}  N{k}  N{k + 1}  bar 100000" for k in range(11)]
    nodes = [f"  N{k}  {k}  0" for k in range(12)]
    text = ("TITLe t\nSECTions\n  bar E=1 G=1 A=1 I=1 k=1\nNODEs\n" + "\n".join(nodes) + "\nLINKs\n"
            + "\n".join(lines) + "\nSUPPorts\n  N0 clamp\nANALysis\n  time 0 1 0.1\nEND\n")
    deck = write_deck(tmp_path / "big.deck", text)
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2, done.stderr
    line = 6 + 12 + 10
    assert f"{deck}:{line}:" in done.stderr and "1100000" in done.stderr, done.stderr
    assert "at most 100000" not in done.stderr and "Backtrace" not in done.stderr, done.stderr
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_three_digit_exponents_keep_their_e(tmp_path):
    deck = write_deck(tmp_path / "x.deck", deck_text(**{"  A   0   0 ": "  A   1e-200   0 "}))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 0, done.stderr
    listing = (tmp_path / "o/x.lis").read_text()
    assert "1.000000000000000E-200" in listing, listing[:800]


@pytest.mark.parametrize("span", ["0 1e300 1e299", "1e300 2e300 1e300", "-1e300 0 1e299"])
def test_huge_times_are_a_deck_error_not_a_trap(tmp_path, span):
    deck = write_deck(tmp_path / "t.deck", deck_text(**{"time 0 1 0.025": f"time {span}"}))
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2, (done.returncode, done.stderr[-400:])
    assert "beyond 1e9" in done.stderr


def last_positions(directory: Path) -> dict[str, list[float]]:
    """Each point's x, y (and z, in a spatial run) in the last row of points.csv."""
    with open(directory / "points.csv") as f:
        rows = list(csv.DictReader(f))
    last = rows[-1]["step"]
    columns = [c for c in ("x", "y", "z") if c in rows[0]]
    return {r["point"]: [float(r[c]) for c in columns] for r in rows if r["step"] == last}


@pytest.mark.parametrize("deck", ["decks/fourbar.deck", "decks/spatial/rssr.deck", "decks/spatial/slider-crank.deck"])
def test_a_step_longer_than_the_run_ends_where_short_steps_end(tmp_path, deck):
    """--dt above the run's length makes one step, the run: the spatial
    stepper's differences for its predictor were a quarter of the given step
    (NaN from 1e100 on, written as results with exit 0). The end's positions
    are those of a run of short steps, and no file holds a number that is not
    finite."""
    done = fekap("-q", "-o", tmp_path / "one", "--dt", "1e300", deck)
    assert done.returncode == 0, done.stderr[-600:]
    for path in (tmp_path / "one").glob("*.csv"):
        text = path.read_text().lower()
        assert "nan" not in text and "inf" not in text, path.name
    done = fekap("-q", "-o", tmp_path / "short", deck)
    assert done.returncode == 0, done.stderr[-600:]
    one, short = last_positions(tmp_path / "one"), last_positions(tmp_path / "short")
    assert one.keys() == short.keys()
    for point, x in one.items():
        assert max(abs(a - b) for a, b in zip(x, short[point])) < 1e-9, (point, x, short[point])


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
