"""scripts/fekap, the main command: many calls at once build once and all run; a signal to the
script reaches fekap; plots are drawn only for a run that wrote new results.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from apptest import ROOT

WRAPPER = ROOT / "scripts" / "fekap"


def default_sigint() -> None:
    """In the child: SIGINT, SIGTERM and SIGHUP as a terminal's shell leaves them. A test run
    started in the background of a non-interactive shell inherits SIGINT ignored, and one started
    under nohup SIGHUP ignored; bash cannot trap a signal ignored on entry (nor Python raise
    KeyboardInterrupt for it)."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)


def start(*args: str) -> subprocess.Popen:
    return subprocess.Popen([str(WRAPPER), *args], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True, preexec_fn=default_sigint)


@pytest.fixture(scope="module", autouse=True)
def built():
    """One build first (a fresh checkout has none): the parallel test then times the runs."""
    subprocess.run([str(ROOT / "scripts" / "build")], check=True, cwd=ROOT, timeout=1200)


def test_sixteen_calls_at_once_all_run(tmp_path):
    """No "Text file busy" (exit 126): the executable is installed by rename, the build locked."""
    calls = [start("--no-plots", "-q", "-o", str(tmp_path / f"run{k}"), "decks/fourbar.deck") for k in range(16)]
    results = [(call.wait(timeout=600), call.stderr.read()) for call in calls]
    assert all(status == 0 for status, _ in results), results
    assert all((tmp_path / f"run{k}" / "points.csv").is_file() for k in range(16))


def children(pid: int) -> list[int]:
    found = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            text = (task / "children").read_text().split()
        except OSError:  # the thread ended since the listing
            continue
        found += [int(p) for p in text]
    return found


def process_state(pid: int) -> str:
    """The process's state as /proc/PID/status names it (e.g. "zombie");
    empty if it has ended (reaped between a check and the read)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("State:"):
                return line.split("(")[-1].rstrip(")")
    except OSError:
        return ""
    return ""


def command_line(pid: int) -> str:
    """The process's command line; empty if it has ended since it was listed
    (the script's short-lived helpers: one ended between the two reads on a
    loaded machine)."""
    try:
        return Path(f"/proc/{pid}/cmdline").read_text()
    except OSError:
        return ""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_a_signal_to_the_script_stops_fekap_and_no_plots_follow(tmp_path, sig):
    out = tmp_path / "long"
    call = start("-q", "--dt", "1e-6", "-o", str(out), "decks/fourbar.deck")
    fekap = []
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (out / "points.csv").exists():
        fekap = [p for p in children(call.pid) if "fekap" in command_line(p)] or fekap
        time.sleep(0.05)
    fekap = fekap or [p for p in children(call.pid)]
    assert fekap, "fekap did not start"
    time.sleep(0.3)
    call.send_signal(sig)
    status = call.wait(timeout=30)
    stderr = call.stderr.read()
    assert status != 0
    assert f"stopped by SIG{sig.name[3:]}" in stderr, stderr
    for pid in fekap:
        assert process_state(pid) in ("", "zombie"), f"fekap {pid} still runs"
    assert not list(out.glob("*.png")), "plots drawn after a signal"


def test_no_plots_after_an_input_error(tmp_path):
    """Old pictures are not redrawn when the new run fails on its input."""
    out = tmp_path / "out"
    assert start("--no-animation", "-q", "-o", str(out), "decks/fourbar-half-turn.deck").wait(timeout=300) == 0
    paths = out / "paths.png"
    assert paths.is_file()
    before = paths.stat().st_mtime_ns
    bad = tmp_path / "bad.deck"
    bad.write_text((ROOT / "decks" / "fourbar-half-turn.deck").read_text().replace("ANALysis", "ANALysis\n  bogus 1"))
    call = start("-q", "-o", str(out), str(bad))
    assert call.wait(timeout=300) == 2
    assert paths.stat().st_mtime_ns == before
    assert "plots in" not in call.stdout.read()


def test_a_plotting_failure_fails_the_command(tmp_path):
    """Plotting that fails (here matplotlib refuses the backend MPLBACKEND names) makes the
    script exit 1 after a run that ended with exit 0, with plot.py's message and its own;
    the run's results stay."""
    out = tmp_path / "out"
    call = subprocess.run([str(WRAPPER), "--no-animation", "-q", "-o", str(out), "decks/fourbar-half-turn.deck"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, MPLBACKEND="no-such-backend"))
    assert call.returncode == 1, (call.returncode, call.stderr)
    assert "no-such-backend" in call.stderr, call.stderr
    assert "fekap: plotting failed" in call.stderr, call.stderr
    assert (out / "points.csv").is_file()
    assert not list(out.glob("*.png"))


def test_help_lists_the_wrappers_own_options():
    """scripts/fekap --help: fekap's options and exit codes, and the two the script takes itself."""
    done = subprocess.run([str(WRAPPER), "--help"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "usage: fekap" in done.stdout and "exit codes:" in done.stdout, done.stdout
    assert "--no-plots" in done.stdout and "--no-animation" in done.stdout, done.stdout
