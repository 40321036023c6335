"""The code's own checks: the Fortran linter (fortitude, pinned in
scripts/setup; its settings, and each rule left out with the reason, in
fpm.toml's [extra.fortitude]) finds nothing in src/ and app/; docs/architecture.md's
map of modules matches the modules; no module is over 600 lines without a
reason at its top.

Run alone:  python3 -m pytest -c test/pytest.ini test/app/test_lint.py
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from apptest import ROOT  # noqa: E402

# Lines of a module above which its header must say why it is one module.
LONGEST_MODULE = 600
REASON = "over 600 lines"


def test_fortitude_finds_nothing():
    """fortitude check src app passes (exit 0)."""
    fortitude = shutil.which("fortitude")
    assert fortitude is not None, "fortitude is not installed (scripts/setup --test installs fortitude-lint into build/venv)"
    r = subprocess.run([fortitude, "check", "--output-format", "concise", "src", "app"], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 0, f"fortitude found problems:\n{r.stdout}{r.stderr}"


def test_module_map_is_current():
    """docs/architecture.md's map of modules is what scripts/module_map.py makes of the code."""
    r = subprocess.run([sys.executable, "scripts/module_map.py", "--check"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_long_modules_say_why():
    """A module over 600 lines says why at its top (the words 'over 600
    lines' in its header comment)."""
    long_without_reason = []
    for path in sorted(ROOT.glob("src/**/*.f90")) + sorted(ROOT.glob("app/*.f90")):
        lines = path.read_text().splitlines()
        if len(lines) <= LONGEST_MODULE:
            continue
        header = " ".join(line.lstrip("!>").strip() for line in lines if line.startswith("!"))
        if REASON not in header.lower():
            long_without_reason.append(f"{path.relative_to(ROOT)} ({len(lines)} lines)")
    assert not long_without_reason, "modules over 600 lines without a reason at their top: " + \
        ", ".join(long_without_reason)
