"""What fekap tells its user: the exit codes of --help and of the README agree (read from both,
not from a list kept here); a run stopped at a dead point names one time and does not advise a
smaller time step; the listing echoes the drive laws and names each slideline apart from its
text.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from apptest import ROOT, fekap_binary  # noqa: E402


def fekap(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([fekap_binary(), *args], capture_output=True, text=True, timeout=120, cwd=ROOT)


def help_codes() -> dict[int, str]:
    """The exit codes of `fekap --help`: lines `  N  meaning` after `exit codes:`."""
    text = fekap("--help").stdout
    block = text[text.index("exit codes:"):]
    return {int(m.group(1)): m.group(2) for m in re.finditer(r"(?m)^\s+(\d+)\s+(.+)$", block)}


def readme_codes() -> dict[int, str]:
    """The exit codes of the README's table after `Exit codes`: rows `| N | meaning |`."""
    text = (ROOT / "README.md").read_text()
    block = text[text.index("Exit codes"):].split("\n\n")[1]
    return {int(m.group(1)): m.group(2) for m in re.finditer(r"(?m)^\| (\d+) \| (.+) \|$", block)}


def test_help_and_readme_list_the_same_exit_codes():
    helped, documented = help_codes(), readme_codes()
    assert helped and set(helped) == set(documented), (helped, documented)
    assert 0 in helped and 2 in helped and 3 in helped


def test_exit_code_3_means_the_same_in_help_and_readme():
    """Both say what 3 is (no convergence), and neither calls a singular configuration an exit 3
    (the run goes on there)."""
    helped, documented = help_codes(), readme_codes()
    assert "converge" in helped[3] and "converge" in documented[3]
    assert "singular" not in helped[3]


def dead_point_deck(tmp_path: Path) -> Path:
    """The four-bar driven by its rocker DC, which cannot turn round: a dead point."""
    text = (ROOT / "decks" / "fourbar.deck").read_text()
    text = re.sub(r"(?m)^(\s*)rotation AB.*$", r"\1rotation DC rate 2*pi", text)
    deck = tmp_path / "dead.deck"
    deck.write_text(text)
    return deck


def test_dead_point_message_names_one_time_and_no_smaller_step(tmp_path):
    proc = fekap("-q", "-o", str(tmp_path / "out"), str(dead_point_deck(tmp_path)))
    assert proc.returncode == 3
    message = proc.stderr.strip()
    assert len(message.splitlines()) == 1
    assert message.count("t = ") == 1, message
    assert "smaller time step will not help" in message and "dead point" in message
    assert "try a smaller time step" not in message
    listing = (tmp_path / "out" / "dead.lis").read_text()
    assert "try a smaller time step" not in listing


def test_listing_echoes_drive_laws_and_slidelines(tmp_path):
    out = tmp_path / "qr"
    assert fekap("-q", "-o", str(out), "decks/quick-return.deck").returncode == 0
    listing = (out / "quick-return.lis").read_text()
    assert "angle of link O2C at node O2: angle = (initial angle) + 6.28318531*t" in listing
    assert "  slot: node C on link O4B, pin-in-slot" in listing
    assert "  guide: node P on the ground guide from (-400, 500) to (100, 500), pin-in-slot" in listing
    assert "slotslave" not in listing


def test_listing_echoes_harmonic_drive(tmp_path):
    out = tmp_path / "pl"
    assert fekap("-q", "-o", str(out), "decks/peaucellier.deck").returncode == 0
    listing = (out / "peaucellier.lis").read_text()
    drives = listing[listing.index("DRIVES"):].split("\n\n")[0]
    assert "cos(" in drives and "*t + " in drives, drives
