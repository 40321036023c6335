"""fekap-batch (python/fekap/batch) on Dask, everything on 127.0.0.1: a 20-case sweep
gives the right table and a rerun does no work; the measures are computed with
the cases and read back; a bad deck is recorded with its error; bad sweep files,
sweeps over the case limit and an output that is a file are refused before
anything runs; a sweep whose every case failed exits 1; a worker killed in
mid-case has its case retried and completed; Ctrl-C returns within seconds with
the finished cases kept and counted, and the servers listen on 127.0.0.1 only;
a sweep through --scheduler on a `dask scheduler` with two `dask worker`s.

Each sweep runs `python -m fekap.batch` as a process, with bounded waits; every
process a test starts is stopped by the test."""

from __future__ import annotations

import csv
import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from apptest import fekap_binary

#: Example 1's four-bar with its lengths, run length and output rate as parameters.
DECK = """\
PARAmeters
  crank = 2
  turns = 1
  dt = 0.05
  every = 1
  ground = 4
  cx = (crank+ground)/2
  cy = sqrt(16-(cx-ground)^2)
SECTions
  bar E=1 G=1 A=100 I=1
NODEs
  A 0 0
  B crank 0
  C cx cy
  D ground 0
LINKs
  AB A B bar
  BC B C bar
  DC D C bar
SUPPorts
  A pin
  D pin
DRIVes
  rotation AB rate 2*pi
ANALysis
  time 0 turns dt
OUTPut
  every every
END
"""

#: A case of this many crank turns at dt = 1e-4 (100,000 steps) runs for about half a second.
LONG = 10


@pytest.fixture(scope="module")
def fekap() -> str:
    return str(Path(fekap_binary()).resolve())


def batch(cwd: Path, fekap: str, *args: str, timeout: float = 120, workers: int = 2
          ) -> subprocess.CompletedProcess:
    """Run fekap-batch to its end."""
    return subprocess.run(batch_command(fekap, *args, workers=workers), cwd=cwd, env=batch_env(),
                          capture_output=True, text=True, timeout=timeout)


def batch_command(fekap: str, *args: str, workers: int = 2) -> list[str]:
    return [sys.executable, "-m", "fekap.batch", "--fekap", fekap, "--workers", str(workers), *args]


def batch_env() -> dict[str, str]:
    return dict(os.environ)


def summary(output: Path) -> list[dict[str, str]]:
    with open(output / "summary.csv", newline="") as handle:
        return list(csv.DictReader(handle))


def write_sweep(directory: Path, text: str, deck: str = DECK) -> Path:
    (directory / "p.deck").write_text(deck)
    path = directory / "sweep.toml"
    path.write_text(text)
    return path


def fekap_processes(marker: str) -> list[int]:
    """Pids of live fekap executables whose command line contains ``marker``.
    The executable is known by its file name: the batch driver's interpreter
    (this test's child) runs from a checkout whose path may hold "fekap"
    too, and killing its parent killed pytest."""
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
            state = (entry / "stat").read_text().split(")")[-1].split()[0]
        except OSError:
            continue
        command = b" ".join(argv).decode(errors="replace")
        if marker in command and "-o" in command and state != "Z" and int(entry.name) != os.getpid():
            if Path(argv[0].decode(errors="replace")).name == "fekap":
                pids.append(int(entry.name))
    return pids


def parent_of(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("PPid:"):
            return int(line.split()[1])
    raise LookupError(pid)


def wait_until(condition, timeout: float, what: str):
    """Poll ``condition`` every 50 ms until it returns something true."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = condition()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def stop(process: subprocess.Popen) -> None:
    """Stop a process this test started, surely."""
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=10)


@pytest.fixture(scope="module")
def sweep20(tmp_path_factory, fekap):
    """A 20-case grid (10 crank lengths x 2 steps) run once; its directory and result."""
    directory = tmp_path_factory.mktemp("sweep20")
    sweep = write_sweep(directory, """\
decks = ["p.deck"]
output = "out"
measures = ["max(points.B.x)", "range(links.AB.angle)", "max(steps.iterations)"]
[plot]
point = "C"
[parameters]
crank = { linspace = [1.5, 2.4, 10] }
[options]
dt = [0.05, 0.1]
""")
    result = batch(directory, fekap, str(sweep))
    return directory, result


def test_sweep_of_20_cases_gives_the_right_table(sweep20):
    directory, result = sweep20
    assert result.returncode == 0, result.stderr
    rows = summary(directory / "out")
    assert len(rows) == 20
    assert sorted({row["crank"] for row in rows}) == [f"{1.5 + 0.1 * i:.1f}" for i in range(10)]
    assert {(row["crank"], row["dt"]) for row in rows} == {
        (f"{1.5 + 0.1 * i:.1f}", dt) for i in range(10) for dt in ("0.05", "0.1")}
    for row in rows:
        assert row["exit"] == "0" and row["message"] == ""
        # One turn: 1/dt steps; B starts at (crank, 0) and turns once about A.
        assert int(row["steps"]) == round(1 / float(row["dt"]))
        assert float(row["max(points.B.x)"]) == pytest.approx(float(row["crank"]), rel=1e-12)
        assert float(row["range(links.AB.angle)"]) == pytest.approx(2 * math.pi, rel=1e-12)
        assert 1 <= float(row["iterations_per_step"]) <= float(row["max(steps.iterations)"])
        assert float(row["analysis_us_per_configuration"]) > 0
        assert int(row["cuts"]) >= 0
        case = directory / "out" / "cases" / row["case"]
        record = json.loads((case / "case.json").read_text())
        assert record["exit"] == 0 and record["attempt"] == 1
        # The listing echoes the values the case ran with.
        listing = (case / "p.lis").read_text()
        assert f"{float(row['crank']):.15E}"[:8] in listing.split("PARAMETERS")[1].split("NODES")[0]
    # The overlay of C (the cases at dt = 0.05: compare.py needs equal times) and a plot per measure.
    for plot in ("paths-C-y.png", "measure-1.png", "measure-2.png", "measure-3.png"):
        assert (directory / "out" / "plots" / plot).stat().st_size > 10000
    table = (directory / "out" / "summary.md").read_text().splitlines()
    assert len(table) == 22 and table[0].startswith("| case | crank | dt | exit |")
    assert result.stdout.strip().splitlines()[-20:] == table[2:]


def test_rerun_does_no_work(sweep20, fekap):
    directory, first = sweep20
    assert first.returncode == 0, first.stderr
    cases = directory / "out" / "cases"
    before = {path.parent.name: path.stat().st_mtime_ns for path in cases.glob("*/case.json")}
    assert len(before) == 20
    again = batch(directory, fekap, "sweep.toml", "--no-plots", "--measure", "min(points.C.y)")
    assert again.returncode == 0, again.stderr
    assert "20 done before, 0 to run" in again.stderr
    assert "ran 0 cases" in again.stderr
    after = {path.parent.name: path.stat().st_mtime_ns for path in cases.glob("*/case.json")}
    assert after == before
    # A new measure is computed from the kept results, without running anything.
    rows = summary(directory / "out")
    assert len(rows) == 20 and all(float(row["min(points.C.y)"]) < 4 for row in rows)


def test_measures_are_stored_with_the_case_and_read_back(sweep20, fekap):
    """The workers computed the measures with the cases (case.json holds them); a rerun reads
    them back: with one case's CSV files moved away, its row keeps its values."""
    directory, first = sweep20
    assert first.returncode == 0, first.stderr
    rows = summary(directory / "out")
    measures = ["max(points.B.x)", "range(links.AB.angle)", "max(steps.iterations)"]
    for row in rows:
        stored = json.loads((directory / "out" / "cases" / row["case"] / "case.json").read_text())["measures"]
        assert [repr(stored[m]) for m in measures] == [row[m] for m in measures]
    case = directory / "out" / "cases" / rows[0]["case"]
    aside = directory / "aside"
    aside.mkdir()
    files = ("points.csv", "links.csv", "steps.csv")
    try:
        for name in files:
            (case / name).rename(aside / name)
        again = batch(directory, fekap, "sweep.toml", "--no-plots")
        assert again.returncode == 0, again.stderr
        assert "ran 0 cases" in again.stderr
        assert [summary(directory / "out")[0][m] for m in measures] == [rows[0][m] for m in measures]
    finally:
        for name in files:
            (aside / name).rename(case / name)


@pytest.mark.parametrize("text, args, phrase", [
    # 10^9 cases: refused at once, without listing them (that took 19 GiB in a minute).
    ('decks = ["p.deck"]\n[parameters]\ncrank = { linspace = [1, 2, 1000] }\nturns = { linspace = [1, 2, 1000] }\n'
     'dt = { linspace = [0.01, 0.02, 1000] }\n', (), "sweep.toml: the sweep has 1,000,000,000 cases, more than "
     "the limit of 100,000 cases"),
    ('decks = ["p.deck"]\n[parameters]\ncrank = { range = [0, 1e12, 1] }\n', (),
     "sweep.toml:3: parameters.crank: 1,000,000,000,001 values, more than the limit of 100,000 cases"),
    ('decks = ["p.deck"]\nmax_cases = 10\n[parameters]\ncrank = { linspace = [1, 2, 5] }\nturns = [1, 2, 3, 4]\n',
     (), "sweep.toml:2: the sweep has 20 cases, more than the limit of 10 cases"),
    ('decks = ["p.deck"]\n[parameters]\ncrank = { linspace = [1, 2, 5] }\nturns = [1, 2, 3, 4]\n', ("--max-cases", "19"),
     "sweep.toml: the sweep has 20 cases, more than the limit of 19 cases"),
    ('decks = ["p.deck"]\nmax_cases = 0\n', (), "sweep.toml:2: max_cases: expected a whole number >= 1"),
])
def test_sweep_over_its_case_limit_is_refused_before_anything_is_made(tmp_path, text, args, phrase,
                                                                      monkeypatch, capsys):
    sweep = write_sweep(tmp_path, text)
    monkeypatch.chdir(tmp_path)
    from fekap.batch import cli
    start = time.monotonic()
    # No fekap at all: the count is checked before FEKAP is looked for (or built).
    assert cli.main([str(sweep), "-o", "out", "--fekap", str(tmp_path / "none"), *args]) == 2
    assert time.monotonic() - start < 5
    stderr = capsys.readouterr().err
    assert phrase in stderr, stderr
    assert "no fekap executable" not in stderr
    assert not (tmp_path / "out").exists()


def test_case_limit_can_be_raised(tmp_path, monkeypatch, capsys):
    sweep = write_sweep(tmp_path, 'decks = ["p.deck"]\nmax_cases = 10\n[parameters]\ncrank = { linspace = [1, 2, 20] }\n')
    monkeypatch.chdir(tmp_path)
    from fekap.batch import cli
    # Past the count (--max-cases overrides the file's max_cases), on to the missing fekap.
    assert cli.main([str(sweep), "-o", "out", "--fekap", str(tmp_path / "none"), "--max-cases", "20"]) == 2
    assert "no fekap executable" in capsys.readouterr().err


def test_output_that_is_a_file_is_an_error(tmp_path, fekap, monkeypatch, capsys):
    sweep = write_sweep(tmp_path, 'decks = ["p.deck"]\noutput = "results"\n')
    (tmp_path / "results").write_text("mine\n")
    monkeypatch.chdir(tmp_path)
    from fekap.batch import cli
    for args in ((), ("-o", "results"), ("-o", "results/inside")):
        assert cli.main([str(sweep), "--fekap", fekap, *args]) == 2
        stderr = capsys.readouterr().err
        assert "Traceback" not in stderr
        assert "'results" in stderr and ("is not a directory" in stderr or "Not a directory" in stderr), stderr
    assert (tmp_path / "results").read_text() == "mine\n"


def test_sweep_whose_every_case_failed_exits_1(tmp_path, fekap):
    # crank = 13 and 14 leave C unreachable: every case is an input error (exit 2).
    sweep = write_sweep(tmp_path, 'decks = ["p.deck"]\n[parameters]\ncrank = [13, 14]\n')
    result = batch(tmp_path, fekap, str(sweep), "-o", "out", "--no-plots", workers=1)
    assert result.returncode == 1, result.stderr
    assert "every case failed: none of the 2 ended with exit 0" in result.stderr
    assert [row["exit"] for row in summary(tmp_path / "out")] == ["2", "2"]


def test_bad_deck_is_recorded_with_its_error_and_not_retried(tmp_path, fekap):
    # crank = 13 leaves C unreachable: cy is the square root of a negative number.
    sweep = write_sweep(tmp_path, """\
decks = ["p.deck", "broken.deck"]
[parameters]
crank = [2, 13]
""")
    (tmp_path / "broken.deck").write_text(DECK.replace("LINKs", "LINKs\n  XY A Q bar"))
    result = batch(tmp_path, fekap, str(sweep), "-o", "out", "--no-plots", workers=1)
    assert result.returncode == 0, result.stderr
    rows = {(Path(row["deck"]).name, row["crank"]): row for row in summary(tmp_path / "out")}
    assert rows["p.deck", "2.0"]["exit"] == "0"
    bad = rows["p.deck", "13.0"]
    assert bad["exit"] == "2"
    assert "p.deck:8:" in bad["message"] and "error: not a finite number" in bad["message"]
    assert rows["broken.deck", "2.0"]["exit"] == "2"
    assert "broken.deck:17:" in rows["broken.deck", "2.0"]["message"]
    record = json.loads((tmp_path / "out" / "cases" / bad["case"] / "case.json").read_text())
    assert record["attempt"] == 1 and "retrying" not in result.stderr


def test_case_over_the_timeout_is_retried_then_lost(tmp_path, fekap):
    sweep = write_sweep(tmp_path, f"""\
decks = ["p.deck"]
timeout = 1
retries = 1
[parameters]
turns = [1, {50 * LONG}]
every = 10000
[options]
dt = 1e-4
""")
    result = batch(tmp_path, fekap, str(sweep), "-o", "out", "--no-plots", workers=1)
    assert result.returncode == 1, result.stderr
    assert "CaseTimeout: exceeded the timeout of 1 s; retrying (1 of 1 retries)" in result.stderr
    rows = {row["turns"]: row for row in summary(tmp_path / "out")}
    assert rows["1.0"]["exit"] == "0"
    assert rows[f"{50.0 * LONG}"]["exit"] == "lost"
    assert "lost after 2 attempts: CaseTimeout" in rows[f"{50.0 * LONG}"]["message"]
    assert not (tmp_path / "out" / "cases" / rows[f"{50.0 * LONG}"]["case"]).exists()
    wait_until(lambda: not fekap_processes(str(tmp_path)), 10, "no fekap left running")


@pytest.mark.parametrize("text, where, phrase", [
    ('decks = ["p.deck"]\nsweeps = 3\n', "sweep.toml:2: sweeps:", "unknown key"),
    ('decks = ["p.deck"]\n[parameters]\ncrank = 1\nlength = [1, 2]\n', "sweep.toml:4: parameters.length:",
     "parameter 'length' is not in the deck"),
    ('decks = ["p.deck"]\n[parameters]\ncrank = { range = [2, 1, 0.1] }\n', "sweep.toml:3: parameters.crank:",
     "empty range"),
    ('decks = ["p.deck"]\n[parameters]\ncrank = { linspace = [1, 2, 0] }\n', "sweep.toml:3: parameters.crank:",
     "empty range"),
    ('decks = ["p.deck"]\n[parameters]\ncrank = []\n', "sweep.toml:3: parameters.crank:", "empty list"),
    ('\n\ndecks = ["p.deck", "missing.deck"]\n', "sweep.toml:3: decks:", "cannot read the deck 'missing.deck'"),
    ('decks = ["p.deck"]\n[options]\nmethod = ["fem", "finite"]\n', "sweep.toml:3: options.method:",
     "'finite' is not one of"),
    ('decks = ["p.deck"]\n[options]\nsteps = 3\n', "sweep.toml:3: options.steps:", "unknown option"),
    ('decks = ["p.deck"]\ncombine = "zip"\n[parameters]\ncrank = [1, 2]\n[options]\ndt = [0.1, 0.2, 0.3]\n',
     "sweep.toml:4: parameters.crank:", "needs lists of one length"),
    ('decks = ["p.deck"]\nmeasures = ["top(points.C.y)"]\n', "sweep.toml:2: measures:", "unknown function"),
    ('decks = ["p.deck"\n', "sweep.toml:", "not valid TOML"),
])
def test_bad_sweep_file_is_refused_before_any_case_runs(tmp_path, fekap, text, where, phrase, monkeypatch,
                                                        capsys):
    sweep = write_sweep(tmp_path, text)
    monkeypatch.chdir(tmp_path)
    from fekap.batch import cli  # in this process: the checks need no cluster, and no second Python
    assert cli.main([str(sweep), "-o", "out", "--fekap", fekap]) == 2
    stderr = capsys.readouterr().err
    assert where in stderr and phrase in stderr, stderr
    assert not (tmp_path / "out").exists()


def test_killed_worker_has_its_case_retried_and_completed(tmp_path, fekap):
    sweep = write_sweep(tmp_path, f"""\
decks = ["p.deck"]
retries = 2
[parameters]
crank = [1.9, 2.1]
turns = {LONG}
every = 10000
[options]
dt = 1e-4
""")
    process = subprocess.Popen(batch_command(fekap, str(sweep), "-o", "out", "--no-plots"), cwd=tmp_path,
                               env=batch_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        runs = wait_until(lambda: fekap_processes(str(tmp_path)), 60, "a running case")
        worker = parent_of(runs[0])
        os.kill(worker, signal.SIGKILL)
        out, err = process.communicate(timeout=120)
    finally:
        stop(process)
    assert process.returncode == 0, err
    assert "its worker died; retrying (1 of 2 retries)" in err
    rows = summary(tmp_path / "out")
    assert [row["exit"] for row in rows] == ["0", "0"]
    attempts = sorted(json.loads((tmp_path / "out" / "cases" / row["case"] / "case.json").read_text())["attempt"]
                      for row in rows)
    assert attempts == [1, 2]
    for row in rows:
        assert int(row["steps"]) == LONG * 10000
    # The killed worker's run died with it; nothing of the sweep runs on.
    wait_until(lambda: not fekap_processes(str(tmp_path)), 10, "no fekap left running")


def process_tree(root: int) -> list[int]:
    """``root`` and its descendants."""
    tree, todo = [], [root]
    while todo:
        pid = todo.pop()
        tree.append(pid)
        for task in Path(f"/proc/{pid}/task").glob("*"):
            try:
                todo += [int(p) for p in (task / "children").read_text().split()]
            except OSError:
                continue
    return tree


def listening_addresses(pids: list[int]) -> set[str]:
    """The local addresses (hex, as /proc/net/tcp* gives them) of the TCP sockets that the
    processes listen on."""
    inodes = set()
    for pid in pids:
        try:
            for fd in Path(f"/proc/{pid}/fd").iterdir():
                target = os.readlink(fd)
                if target.startswith("socket:["):
                    inodes.add(target[8:-1])
        except OSError:
            continue
    addresses = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "0A" and fields[9] in inodes:  # 0A: LISTEN
                addresses.add(fields[1].split(":")[0])
    return addresses


def test_sigint_keeps_the_finished_cases(tmp_path, fekap):
    # One short case and three five times as long: whichever finishes first,
    # a long one still has at least four short cases' time to run when the
    # SIGINT is sent, however slow the machine (with equal cases both workers'
    # second cases could finish before a loaded machine handled the signal).
    sweep = write_sweep(tmp_path, f"""\
decks = ["p.deck"]
combine = "zip"
[parameters]
crank = {{ linspace = [1.8, 2.1, 4] }}
turns = [{LONG}, {5 * LONG}, {5 * LONG}, {5 * LONG}]
every = 10000
[options]
dt = 1e-4
""")
    # A process group of its own, to which the SIGINT goes as a terminal's Ctrl-C does: to the
    # sweep and its Dask processes alike.
    # SIGINT as a terminal's shell leaves it: a test run started in the background of a
    # non-interactive shell inherits it ignored, and Python then never raises KeyboardInterrupt.
    process = subprocess.Popen(batch_command(fekap, str(sweep), "-o", "out"), cwd=tmp_path, env=batch_env(),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    cases = tmp_path / "out" / "cases"
    try:
        wait_until(lambda: list(cases.glob("*/case.json")) if cases.is_dir() else [], 60, "a finished case")
        # Dask's scheduler, nannies and workers listen on the loopback address only.
        addresses = listening_addresses(process_tree(process.pid))
        assert addresses and addresses <= {"0100007F", "00000000000000000000000001000000"}, addresses
        start = time.monotonic()
        os.killpg(process.pid, signal.SIGINT)
        out, err = process.communicate(timeout=60)
        seconds = time.monotonic() - start
    finally:
        stop(process)
    assert process.returncode == 130, err
    assert seconds < 10, f"Ctrl-C took {seconds:.1f} s to return"
    assert "interrupted; finished cases are kept" in err
    done = {path.parent.name for path in cases.glob("*/case.json")}
    assert 1 <= len(done) < 4
    # The count is the cases finished on disk, whether or not their answers had come back.
    assert f"interrupted: {len(done)} of 4 cases finished ({len(done)} in this run)" in err, err
    rows = summary(tmp_path / "out")
    assert len(rows) == 4
    assert {row["case"] for row in rows if row["exit"] == "0"} == done
    assert all(row["exit"] == "not run" for row in rows if row["case"] not in done)
    wait_until(lambda: not fekap_processes(str(tmp_path)), 10, "no fekap left running")
    # Resuming runs only the rest.
    again = batch(tmp_path, fekap, str(sweep), "-o", "out", "--no-plots")
    assert again.returncode == 0, again.stderr
    assert f"{len(done)} done before, {4 - len(done)} to run" in again.stderr
    assert all(row["exit"] == "0" for row in summary(tmp_path / "out"))


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_sweep_through_a_dask_scheduler_and_two_workers(tmp_path, fekap):
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    # The workers know nothing of FEKAP's scripts: the case code travels with the tasks.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    dask = str(Path(sys.executable).parent / "dask")
    processes = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                   "--no-dashboard"], cwd=tmp_path, env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for name in ("w1", "w2"):
            (tmp_path / name).mkdir()
            processes.append(subprocess.Popen(
                [dask, "worker", address, "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard",
                 "--no-nanny", "--name", name], cwd=tmp_path / name, env=env,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        sweep = write_sweep(tmp_path, """\
decks = ["p.deck"]
combine = "zip"
measures = ["max(points.B.x)"]
[parameters]
crank = [1.7, 1.9, 2.1, 2.3]
[options]
method = ["fem", "cartesian", "angles", "fem"]
""")
        result = batch(tmp_path, fekap, str(sweep), "-o", "out", "--no-plots", "--scheduler", address)
        assert result.returncode == 0, result.stderr
        rows = summary(tmp_path / "out")
        assert [(row["crank"], row["method"]) for row in rows] == [
            ("1.7", "fem"), ("1.9", "cartesian"), ("2.1", "angles"), ("2.3", "fem")]
        workers = set()
        for row in rows:
            assert row["exit"] == "0"
            assert float(row["max(points.B.x)"]) == pytest.approx(float(row["crank"]), rel=1e-12)
            workers.add(json.loads((tmp_path / "out" / "cases" / row["case"] / "case.json").read_text())["worker"])
        assert workers and workers <= {"w1", "w2"}
    finally:
        for process in reversed(processes):
            stop(process)


def test_streamed_measures_equal_those_of_the_loaded_run(sweep20, monkeypatch):
    """The workers' one-pass measures (batch.task.measures) against the same measures taken
    from the whole run as fekap.read loads it (results.Measure.value), every function on
    points, links and steps of one case."""
    directory, first = sweep20
    assert first.returncode == 0, first.stderr
    from fekap.batch import results, task
    case = next((directory / "out" / "cases").glob("*/case.json")).parent
    run = results.load(case)
    texts = [f"{function}({source})" for function in ("max", "min", "range", "mean", "first", "final", "absmax")
             for source in ("points.C.y", "points.B.vx", "links.BC.omega", "steps.iterations", "points.Q.x")]
    measures = [results.parse_measure(text) for text in texts]
    streamed = task.measures(case, [m.spec() for m in measures])
    for measure in measures:
        loaded = measure.value(run, None)
        if measure.name == "Q":  # no such point: no value either way
            assert loaded is None and streamed[measure.text] is None
            continue
        # Exact but for mean(), summed in another order: round-off of the values' size (<= 2 pi * 10).
        assert streamed[measure.text] == pytest.approx(loaded, rel=1e-14, abs=1e-13), measure.text


def test_the_overlay_shows_every_case_with_units_and_title(sweep20, monkeypatch):
    """The paths overlay draws every finished case (both step sizes), its differences only for
    the cases on the first case's times and names the others; axes carry the deck's units."""
    from fekap import compare
    from fekap import stream as fs

    directory, _ = sweep20
    cases = sorted((directory / "out" / "cases").iterdir())
    sources = [compare.load_source(case, case.name) for case in cases]
    steps = {len(s.points["C"].t) for s in sources}
    assert steps == {11, 21}
    mech = fs.read_mechanism(cases[0])
    fig = compare.plot_comparison(sources, "C", "y", "a sweep", mech, f"{len(sources)} cases")
    path_ax, value_ax, diff_ax = fig.axes
    assert len(path_ax.get_lines()) == len(value_ax.get_lines()) == 20
    aligned = sum(len(s.points["C"].t) == len(sources[0].points["C"].t) for s in sources)
    assert len(diff_ax.get_lines()) == aligned - 1 + 1  # the differences and the zero line
    assert "left out" in diff_ax.get_title()
    assert (path_ax.get_xlabel(), value_ax.get_ylabel(), diff_ax.get_xlabel()) == \
        ("x (length)", "y (length)", "t (time)")
    assert fig._suptitle.get_text() == "a sweep\n20 cases"
