"""The dependency rules of src/ (docs/architecture.md): every module's `use`
lines point down the layers, never up or sideways into a method; only app/
prints; only app/ builds a concrete stepper. Read from the sources, so a new
`use` that breaks a rule fails here with the file and line."""

from __future__ import annotations

import re
import sys
from pathlib import Path

from apptest import ROOT

SRC = ROOT / "src" / "fekap"

# The layer of each folder of src/fekap/. A new folder must be placed here:
# the test refuses folders (and top-level files) it does not know.
LAYER = {
    "core": "core",
    "model": "model",
    "linalg": "linalg",
    "element": "element",
    "contact": "contact",
    "assembly": "assembly",
    "stepping": "stepping",
    "methods": "methods",
    "deck": "deck",
    "output": "output",
    "driver": "driver",
}

# What each layer may use besides itself: the rules, from the bottom up.
MAY_USE = {
    "core": set(),
    # The data, the numerics and the elements know only the core.
    "model": {"core"},
    "linalg": {"core"},
    "element": {"core"},
    "contact": {"core"},
    "assembly": {"core", "model", "linalg", "element", "contact"},
    # Method-agnostic stepping knows no mesh, no method and no output.
    "stepping": {"core", "model", "linalg"},
    # The methods never use the output, the deck reader or the driver.
    "methods": {"core", "model", "linalg", "element", "contact", "assembly", "stepping"},
    "deck": {"core", "model"},
    # The output never uses the stepping or the methods.
    "output": {"core", "model"},
    "driver": {"core", "model", "linalg", "element", "contact", "assembly", "stepping", "methods", "output"},
}

USE = re.compile(r"^\s*use\s+(\w+)", re.IGNORECASE | re.MULTILINE)
MODULE = re.compile(r"^\s*module\s+(\w+)\s*(?:!.*)?$", re.IGNORECASE | re.MULTILINE)
# Printing: a print statement, or a write to the default unit or a standard stream.
PRINT = re.compile(r"^\s*(print\b|write\s*\(\s*(\*|output_unit|error_unit))", re.IGNORECASE)
CONSTRUCTOR = re.compile(r"\bcall\s+(new_\w*_stepper)\b", re.IGNORECASE)


def layer_of(path: Path) -> str:
    rel = path.relative_to(SRC)
    key = rel.parts[0] if len(rel.parts) > 1 else rel.name
    assert key in LAYER, f"{rel}: folder '{key}' has no layer in test_layers.py (and docs/architecture.md)"
    return LAYER[key]


def sources() -> list[Path]:
    return sorted(SRC.rglob("*.f90"))


def owners() -> dict[str, Path]:
    found = {}
    for path in sources():
        for name in MODULE.findall(path.read_text()):
            found[name.lower()] = path
    return found


def test_uses_point_down_the_layers():
    owner = owners()
    broken = []
    for path in sources():
        text = path.read_text()
        mine = layer_of(path)
        for match in USE.finditer(text):
            used = owner.get(match.group(1).lower())
            if used is None:
                continue  # an intrinsic or external module (iso_c_binding, funit)
            theirs = layer_of(used)
            if theirs != mine and theirs not in MAY_USE[mine]:
                line = text.count("\n", 0, match.start()) + 1
                broken.append(f"{path.relative_to(ROOT)}:{line}: {mine} uses {match.group(1)} ({theirs})")
    assert not broken, "uses against the layers:\n" + "\n".join(broken)


def test_only_app_prints():
    printing = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
                for path in sources()
                for n, line in enumerate(path.read_text().splitlines(), start=1)
                if PRINT.match(line)]
    assert not printing, "src/ prints (errors are values; app/ prints):\n" + "\n".join(printing)


def test_only_app_builds_steppers():
    calls = [f"{path.relative_to(ROOT)}: {m.group(1)}"
             for path in sources() for m in CONSTRUCTOR.finditer(path.read_text())]
    assert not calls, "concrete steppers built outside app/:\n" + "\n".join(calls)


def test_the_rules_see_a_breach(tmp_path, monkeypatch):
    """The checks are not vacuous: a core module that uses a method, and one that prints, are caught."""
    fake = tmp_path / "src" / "fekap"
    for folder in ("methods", "core"):
        (fake / folder).mkdir(parents=True)
    (fake / "methods" / "m.f90").write_text("module fekap_m\nend module fekap_m\n")
    (fake / "core" / "kinds.f90").write_text("module fekap_kinds\n   use fekap_m\nend module fekap_kinds\n")
    (fake / "core" / "posix.f90").write_text("module fekap_posix\ncontains\n   print *, 'x'\nend module fekap_posix\n")
    monkeypatch.setattr(sys.modules[__name__], "SRC", fake)
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    for check in (test_uses_point_down_the_layers, test_only_app_prints):
        try:
            check()
        except AssertionError:
            continue
        raise AssertionError(f"{check.__name__} let a breach through")
