#!/usr/bin/env python3
"""Reading a deck in linear time, only from regular files, and stopping
cleanly on a signal while reading (issue #31, item 4).

The times asserted are hang guards of a few seconds for inputs that took
from half a minute to over a minute when reading was quadratic (a 2 MiB
TITLe, 100,000 PARAmeters lines); each is also checked for its result, so a
fast wrong answer fails too.

Run alone:  scripts/test linear_reading
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from apptest import ROOT, fekap_binary

FOURBAR = ROOT / "decks/fourbar.deck"
TITLE = "TITLe   Four-bar linkage, dt = 0.025"

#: Wall-clock guard of one run (the checking build on a loaded machine): the
#: quadratic reader needed 37 s for 1 MiB of title and over 60 s for 100,000
#: parameters.
GUARD = 20.0


def fekap(*args, timeout: float = 60, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([fekap_binary(), *map(str, args)], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout, **kw)


def timed(*args) -> tuple[subprocess.CompletedProcess, float]:
    start = time.monotonic()
    done = fekap(*args, timeout=120)
    return done, time.monotonic() - start


def test_two_mebibyte_title_reads_in_linear_time(tmp_path):
    title = "x" * (2 * 1024 * 1024 - 10) + ' "q" end'
    deck = tmp_path / "t.deck"
    deck.write_text(FOURBAR.read_text().replace(TITLE, "TITLe " + title))
    done, seconds = timed("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 0, done.stderr[-500:]
    assert seconds < GUARD, seconds
    # mechanism.txt carries the whole title, its quotes doubled (CSV).
    record = (tmp_path / "o/mechanism.txt").read_text().splitlines()[1]
    assert record == 'title,"' + title.replace('"', '""') + '"'


def test_hundred_thousand_parameters_read_in_linear_time(tmp_path):
    # Each parameter uses the one before it (a name lookup per line), and a
    # section uses the last one.
    n = 100_000
    lines = ["PARAmeters", "  p0 = 1"] + [f"  p{i} = p{i - 1}+1" for i in range(1, n)]
    text = FOURBAR.read_text().replace("SECTions", "\n".join(lines) + "\nSECTions", 1)
    text = text.replace("A=100", f"A=p{n - 1}/{n}*100")
    deck = tmp_path / "p.deck"
    deck.write_text(text)
    done, seconds = timed("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 0, done.stderr[-500:]
    assert seconds < GUARD, seconds
    reference = fekap("-q", "-o", tmp_path / "r", FOURBAR)
    assert reference.returncode == 0
    assert (tmp_path / "o/points.csv").read_bytes() == (tmp_path / "r/points.csv").read_bytes()


def test_unknown_name_among_many_parameters_gives_a_short_message(tmp_path):
    lines = ["PARAmeters"] + [f"  p{i} = {i}" for i in range(50_000)]
    text = FOURBAR.read_text().replace("SECTions", "\n".join(lines) + "\nSECTions", 1)
    deck = tmp_path / "u.deck"
    deck.write_text(text.replace("A=100", "A=nosuch"))
    done, seconds = timed("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2 and "unknown name 'nosuch'" in done.stderr, done.stderr[-500:]
    assert "and 49980 more" in done.stderr, done.stderr[-500:]
    assert len(done.stderr) < 2000, len(done.stderr)
    assert seconds < GUARD, seconds


def test_duplicate_parameter_is_still_found_through_the_index(tmp_path):
    text = FOURBAR.read_text().replace("SECTions", "PARAmeters\n  a = 1\n  b = a+1\n  A = 3\nSECTions", 1)
    deck = tmp_path / "d.deck"
    deck.write_text(text)
    done = fekap("-q", "-o", tmp_path / "o", deck)
    assert done.returncode == 2 and "parameter 'A' is defined twice" in done.stderr, done.stderr


# --- only regular files --------------------------------------------------------------------------

def with_include(tmp_path: Path, target: str) -> Path:
    deck = tmp_path / "inc.deck"
    deck.write_text(FOURBAR.read_text().replace("OUTPut", f"INCLude {target}\nOUTPut", 1))
    return deck


def test_fifo_as_deck_is_an_input_error_not_a_hang(tmp_path):
    fifo = tmp_path / "deck.fifo"
    os.mkfifo(fifo)
    done = fekap("-q", "-o", tmp_path / "o", fifo, timeout=30)
    assert done.returncode == 2, done.stderr
    assert "a FIFO (named pipe), not a regular file" in done.stderr, done.stderr
    assert not (tmp_path / "o").exists()


def test_fifo_as_include_is_an_input_error_not_a_hang(tmp_path):
    fifo = tmp_path / "part.fifo"
    os.mkfifo(fifo)
    done = fekap("-q", "-o", tmp_path / "o", with_include(tmp_path, fifo.name), timeout=30)
    assert done.returncode == 2, done.stderr
    assert "inc.deck:" in done.stderr and "a FIFO (named pipe), not a regular file" in done.stderr, done.stderr


@pytest.mark.parametrize("device", ["/dev/null", "/dev/zero", "/dev/urandom"])
def test_device_as_deck_or_include_is_an_input_error(tmp_path, device):
    # Standard input a pipe: a device that is fekap's standard input is read as a deck from a pipe is.
    done = fekap("-q", "-o", tmp_path / "o", device, timeout=30, input="")
    assert done.returncode == 2 and "a device, not a regular file" in done.stderr, done.stderr
    done = fekap("-q", "-o", tmp_path / "o", with_include(tmp_path, device), timeout=30, input="")
    assert done.returncode == 2 and "a device, not a regular file" in done.stderr, done.stderr


def test_directory_as_deck_is_an_input_error(tmp_path):
    done = fekap("-q", "-o", tmp_path / "o", tmp_path, timeout=30)
    assert done.returncode == 2 and "it is a directory" in done.stderr, done.stderr


def test_deck_from_a_pipe_still_reads(tmp_path):
    done = subprocess.run([fekap_binary(), "-q", "-o", str(tmp_path / "o"), "/dev/stdin"], cwd=ROOT,
                          input=FOURBAR.read_text(), capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "o/points.csv").stat().st_size > 0


# --- a signal while reading ----------------------------------------------------------------------

@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_signal_while_reading_ends_with_exit_1_and_a_message(tmp_path, sig):
    # The deck comes from a pipe that stays open: fekap is still reading it
    # when the signal comes.
    out = tmp_path / "o"
    proc = subprocess.Popen([fekap_binary(), "-q", "-o", str(out), "/dev/stdin"], cwd=ROOT,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        proc.stdin.write(FOURBAR.read_text().replace("END\n", ""))
        proc.stdin.flush()
        time.sleep(0.5)
        assert proc.poll() is None, "fekap did not wait for the rest of the deck"
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 1, (proc.returncode, stderr)
    assert f"interrupted by signal {int(sig)} while the deck was read" in stderr, stderr
    assert not out.exists(), "files were written for a run that never started"
