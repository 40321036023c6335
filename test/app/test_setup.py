"""scripts/setup and the project's environment build/venv: every Python script of scripts/
and studies/ starts through scripts/python (that environment's interpreter, whatever python3 PATH names),
and a pip failure stops the setup with pip's message. Run alone: scripts/test setup."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from apptest import ROOT

#: The first line of a Python script in scripts/ (UP = "") and in studies/NAME/ (UP = "../../").
LAUNCHER = """#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/{UP}python" "$0" "$@"'"""
#: PATH of a stock Debian 12 shell: Debian's own python3, which refuses pip (PEP 668).
DEBIAN_PATH = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"


def debian_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYENV_ROOT", "VIRTUAL_ENV", "PYTHONPATH")}
    env["PATH"] = DEBIAN_PATH
    return env


def test_every_python_script_starts_through_the_environment() -> None:
    """The commands of scripts/ and the studies of studies/ start through scripts/python; the
    package python/fekap/ holds modules only (run as `scripts/python -m fekap.NAME`)."""
    def python_scripts(files):
        return [p for p in files if p.is_file() and p.read_text(errors="replace").startswith("#!")
                and "python" in p.read_text(errors="replace").splitlines()[0]]

    commands = python_scripts(sorted((ROOT / "scripts").iterdir()))
    studies = python_scripts(sorted((ROOT / "studies").glob("*/*.py")))
    assert len(commands) >= 4 and len(studies) >= 12, (commands, studies)
    wrong = [str(p.relative_to(ROOT)) for up, group in (("", commands), ("../../scripts/", studies)) for p in group
             if p.read_text().splitlines()[0] != LAUNCHER.format(UP=up) or not os.access(p, os.X_OK)]
    assert not wrong, f"not started through scripts/python (or not executable): {wrong}"
    untidy = [str(p.relative_to(ROOT)) for p in sorted((ROOT / "python").rglob("*.py"))
              if p.read_text().startswith("#!") or os.access(p, os.X_OK)]
    assert not untidy, f"modules of the package with a #! line or executable: {untidy}"
    moved = [str(p.relative_to(ROOT)) for p in sorted((ROOT / "scripts").glob("*.py"))
             if p.stem not in ("plot", "compare", "module_map")]
    assert not moved, f"scripts/ holds the user commands only; studies go to studies/, libraries to python/: {moved}"


def test_a_script_run_by_its_path_gets_the_environment_interpreter() -> None:
    """With Debian's PATH (no pyenv), scripts/module_map.py and a study run on build/venv's Python."""
    done = subprocess.run([str(ROOT / "scripts" / "python"), "-c", "import sys, numpy, matplotlib, pyarrow; "
                           "print(sys.prefix)"], capture_output=True, text=True, env=debian_env(), timeout=600)
    assert done.returncode == 0, done.stderr
    assert Path(done.stdout.strip()) == ROOT / "build" / "venv"
    check = subprocess.run([str(ROOT / "scripts" / "module_map.py"), "--check"], cwd=ROOT, capture_output=True,
                           text=True, env=debian_env(), timeout=120)
    assert check.returncode == 0, check.stdout + check.stderr
    # A study, two folders down, finds scripts/python and imports the package (installed in
    # editable mode by scripts/setup).
    study = subprocess.run([str(ROOT / "studies" / "tables" / "paper_tables.py"), "--help"], cwd="/",
                           capture_output=True, text=True, env=debian_env(), timeout=120)
    assert study.returncode == 0 and "usage:" in study.stdout, study.stdout + study.stderr


def test_a_pip_failure_stops_the_setup_with_its_message(tmp_path: Path) -> None:
    """A checkout whose setup pins a package PyPI does not have: exit 1, pip's ERROR line and
    the setup's own message, and nothing after it (no 'fpm is missing')."""
    (tmp_path / "scripts").mkdir()
    text = (ROOT / "scripts" / "setup").read_text()
    pins = 'RUN_PACKAGES=("fpm==$FPM_VERSION"'
    assert pins in text
    (tmp_path / "scripts" / "setup").write_text(text.replace(pins, 'RUN_PACKAGES=("fekap-no-such-package==0.0.0"'))
    (tmp_path / "scripts" / "setup").chmod(0o755)
    done = subprocess.run([str(tmp_path / "scripts" / "setup")], capture_output=True, text=True,
                          env=debian_env(), timeout=600)
    assert done.returncode == 1, done.stderr
    assert "ERROR" in done.stderr, done.stderr
    assert "setup: pip could not install fekap-no-such-package==0.0.0" in done.stderr, done.stderr
    assert "fpm is missing" not in done.stderr
    # The environment was made (by Debian's python3) but is not marked as set up.
    assert (tmp_path / "build" / "venv" / "bin" / "python").exists()
    assert not (tmp_path / "build" / "venv" / ".fekap-run").exists()
    shutil.rmtree(tmp_path / "build")
