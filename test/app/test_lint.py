"""The code's own checks: the Fortran linter (fortitude, pinned in
scripts/setup; its settings, and each rule left out with the reason, in
fpm.toml's [extra.fortitude]) finds nothing in src/ and app/; the Python linter (ruff,
pinned in scripts/setup, configured in python/pyproject.toml) finds nothing in the Python
of python/, scripts/, studies/ and test/; no sys.path manipulation outside
test/app/conftest.py; docs/architecture.md's
map of modules matches the modules; no module is over 600 lines without a
reason at its top.

Run alone:  scripts/test lint
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

from apptest import ROOT

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


def python_files() -> list[Path]:
    """The project's Python: the package, the commands of scripts/ (the *.py and those whose
    first line names python, such as scripts/gallery), the studies and the tests."""
    files = sorted(ROOT.glob("python/**/*.py")) + sorted(ROOT.glob("studies/**/*.py"))
    files += sorted(ROOT.glob("test/**/*.py"))
    for path in sorted((ROOT / "scripts").iterdir()):
        if path.is_file() and (path.suffix == ".py" or "python" in path.read_text(errors="replace")[:200].split("\n")[0]):
            files.append(path)
    return [path for path in files if "fuzz-crashes" not in path.parts]


def test_ruff_finds_nothing():
    """ruff check on every Python file of the project passes (exit 0)."""
    ruff = shutil.which("ruff") or str(Path(sys.executable).parent / "ruff")
    assert Path(ruff).is_file(), "ruff is not installed (scripts/setup --test installs ruff into build/venv)"
    files = python_files()
    assert len(files) > 60, f"only {len(files)} Python files found"
    r = subprocess.run([ruff, "check", "--no-cache", "--output-format", "concise", "--config", "python/pyproject.toml",
                        *(str(path.relative_to(ROOT)) for path in files)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, f"ruff found problems:\n{r.stdout}{r.stderr}"


def test_no_sys_path_tricks():
    """Scripts, studies and tests import the package `fekap` as installed (scripts/setup:
    pip install -e python/), not through sys.path or PYTHONPATH edits; the one place
    allowed is the tests' conftest.py."""
    pattern = re.compile(r"sys\.path\.(insert|append)|syspath_prepend|PYTHONPATH=")
    found = []
    for path in python_files() + [ROOT / "scripts" / name for name in ("fekap", "fekap-batch", "bench", "test")]:
        if path.name == "conftest.py" or path == Path(__file__).resolve():
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), start=1):
            if pattern.search(line):
                found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not found, "sys.path edited outside test/app/conftest.py:\n" + "\n".join(found)


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
