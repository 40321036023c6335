"""scripts/setup and the project's environment build/venv: every Python script of scripts/
and studies/ starts through scripts/python (that environment's interpreter, whatever python3 PATH
names); a pip or apt-get failure stops the setup with its message; running a deck needs only the
run packages; the README's run command works with Debian's python3 first on PATH.
Run alone: scripts/test setup."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

from apptest import ROOT, run_fekap

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


def test_an_apt_failure_stops_the_setup_with_its_message(tmp_path: Path) -> None:
    """apt-get that cannot install (a fake one first on PATH, refusing as Debian's does for
    an unknown package): exit 1, apt's E: line and the setup's own message, and nothing
    after it (no environment made). --paraview asks for packages this machine lacks."""
    if shutil.which("pvpython") or os.getuid() != 0:
        pytest.skip("ParaView is installed, or not root (setup would call the real apt-get through sudo)")
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "setup").write_text((ROOT / "scripts" / "setup").read_text())
    (tmp_path / "scripts" / "setup").chmod(0o755)
    fake = tmp_path / "fakebin"
    fake.mkdir()
    (fake / "apt-get").write_text("#!/bin/sh\necho 'E: Unable to locate package paraview' >&2\nexit 100\n")
    (fake / "apt-get").chmod(0o755)
    env = debian_env()
    env["PATH"] = f"{fake}:{DEBIAN_PATH}"
    done = subprocess.run([str(tmp_path / "scripts" / "setup"), "--paraview"], capture_output=True, text=True,
                          env=env, timeout=120)
    assert done.returncode == 1, (done.returncode, done.stderr)
    assert "E: Unable to locate package paraview" in done.stderr, done.stderr
    assert "setup: apt-get could not install paraview" in done.stderr, done.stderr
    assert not (tmp_path / "build" / "venv").exists(), "the setup went on after apt-get failed"


def test_running_a_deck_needs_only_the_run_packages() -> None:
    """The packages a run installs (RUN_PACKAGES) hold none of the test or batch tools, and
    plot.py draws a run's pictures with those tools unimportable (a meta-path finder
    refuses them), as on a machine set up only to run decks."""
    text = (ROOT / "scripts" / "setup").read_text()

    def pinned(name: str) -> set[str]:
        line = next(ln for ln in text.splitlines() if ln.startswith(f"{name}=("))
        return {spec.split("==")[0] for spec in re.findall(r'"([^"$]+)==', line)} | (
            {"fpm"} if "fpm==" in line else set())

    run, test, batch = pinned("RUN_PACKAGES"), pinned("TEST_PACKAGES"), pinned("BATCH_PACKAGES")
    assert run == {"fpm", "numpy", "matplotlib", "pyarrow"}, run
    assert not run & (test | batch), run & (test | batch)
    assert {"pytest", "vtk", "meshio"} <= test and "dask" in batch
    out = Path(tempfile.mkdtemp(prefix="fekap-run-only-"))
    try:
        done = run_fekap("-q", "-o", str(out), "decks/fourbar-quarter-turn.deck")
        assert done.returncode == 0, done.stderr
        blocked = ("pytest", "vtk", "meshio", "dask", "distributed", "fortitude")
        code = f"""
import importlib.abc, runpy, sys
class Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in {blocked!r}:
            raise ImportError('not installed for running a deck: ' + name)
        return None
sys.meta_path.insert(0, Refuse())
sys.argv = ['plot.py', {str(out)!r}]
runpy.run_path({str(ROOT / 'scripts' / 'plot.py')!r}, run_name='__main__')
"""
        plotted = subprocess.run([str(ROOT / "scripts" / "python"), "-c", code], capture_output=True, text=True,
                                 env=dict(debian_env(), MPLBACKEND="Agg"), timeout=600)
        assert plotted.returncode == 0, plotted.stderr[-2000:]
        assert (out / "paths.png").is_file()
    finally:
        shutil.rmtree(out, ignore_errors=True)


def test_the_readme_run_command_with_debians_python_first_on_path(tmp_path: Path) -> None:
    """The README's `scripts/fekap decks/fourbar.deck` (here into tmp_path, without the
    animation) with Debian's own python3 first on PATH, no pyenv: exit 0, the results and
    the pictures. (The usual PATH is test_fekap_wrapper's.)"""
    assert "    scripts/fekap decks/fourbar.deck\n" in (ROOT / "README.md").read_text()
    out = tmp_path / "fourbar"
    done = subprocess.run([str(ROOT / "scripts" / "fekap"), "--no-animation", "-q", "-o", str(out),
                           "decks/fourbar.deck"], cwd=ROOT, capture_output=True, text=True, env=debian_env(),
                          timeout=1200)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (out / "points.csv").is_file() and (out / "paths.png").is_file()
