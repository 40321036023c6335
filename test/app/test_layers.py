"""The dependency rules of src/ (docs/architecture.md): every module's `use`
lines point down the layers, never up or sideways into a method; only app/
prints; only driver/ names a concrete stepper (its factory). Read from the sources, so a new
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
    # The driver (the factory, the output registry, the time loop and the
    # module `fekap` that the app uses) may use every layer below the app.
    "driver": {"core", "model", "linalg", "element", "contact", "assembly", "stepping", "methods", "deck", "output"},
}

USE = re.compile(r"^\s*use\s+(\w+)", re.IGNORECASE | re.MULTILINE)
MODULE = re.compile(r"^\s*module\s+(\w+)\s*(?:!.*)?$", re.IGNORECASE | re.MULTILINE)
# Printing: a print statement, or a write to the default unit or a standard stream.
PRINT = re.compile(r"^\s*(print\b|write\s*\(\s*(\*|output_unit|error_unit))", re.IGNORECASE)
# Naming a concrete stepper: calling its constructor, or declaring its type.
CONSTRUCTOR = re.compile(r"\bcall\s+(new_\w*_stepper)\b", re.IGNORECASE)
STEPPER_TYPE = re.compile(r"\b(?:type|class)\s*\(\s*(\w+_stepper_type)\s*\)", re.IGNORECASE)
APP = ROOT / "app"


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


def concrete_steppers_named_outside_the_driver() -> list[str]:
    """Constructor calls of concrete steppers outside src/fekap/driver/, and
    declarations of a concrete stepper type in app/ (a method's own modules
    declare their types, and a method may hold another's stepper)."""
    found = []
    for path in [*sources(), *sorted(APP.rglob("*.f90"))]:
        if path.is_relative_to(SRC) and layer_of(path) == "driver":
            continue
        text = path.read_text()
        found += [f"{path.relative_to(ROOT)}: {m.group(1)}" for m in CONSTRUCTOR.finditer(text)]
        if path.is_relative_to(APP):
            found += [f"{path.relative_to(ROOT)}: {m.group(1)}" for m in STEPPER_TYPE.finditer(text)]
    return found


def test_only_the_driver_names_concrete_steppers():
    named = concrete_steppers_named_outside_the_driver()
    assert not named, "concrete steppers named outside driver/ (its factory builds them):\n" + "\n".join(named)


def test_the_driver_builds_the_steppers():
    """The rule above is not vacuous: the factory is where the constructors are called."""
    calls = [m.group(1) for path in sources() if layer_of(path) == "driver"
             for m in CONSTRUCTOR.finditer(path.read_text())]
    assert "new_fem_stepper" in calls and "new_dynamic_stepper" in calls, calls


def test_the_rules_see_a_breach(tmp_path, monkeypatch):
    """The checks are not vacuous: a core module that uses a method, one that
    prints, a method that builds a stepper and an app that declares one are caught."""
    fake = tmp_path / "src" / "fekap"
    for folder in ("methods", "core", "driver"):
        (fake / folder).mkdir(parents=True)
    (tmp_path / "app").mkdir()
    (fake / "methods" / "m.f90").write_text("module fekap_m\nend module fekap_m\n")
    (fake / "core" / "kinds.f90").write_text("module fekap_kinds\n   use fekap_m\nend module fekap_kinds\n")
    (fake / "core" / "posix.f90").write_text("module fekap_posix\ncontains\n   print *, 'x'\nend module fekap_posix\n")
    (fake / "methods" / "r.f90").write_text("module fekap_r\ncontains\n   call new_fem_stepper(f, m)\nend module fekap_r\n")
    (fake / "driver" / "factory.f90").write_text("module fekap_f\ncontains\n   call new_fem_stepper(f, m)\nend module\n")
    (tmp_path / "app" / "main.f90").write_text("program p\n   type(fem_stepper_type) :: s\nend program p\n")
    monkeypatch.setattr(sys.modules[__name__], "SRC", fake)
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    monkeypatch.setattr(sys.modules[__name__], "APP", tmp_path / "app")
    named = concrete_steppers_named_outside_the_driver()
    assert named == ["src/fekap/methods/r.f90: new_fem_stepper", "app/main.f90: fem_stepper_type"], named
    for check in (test_uses_point_down_the_layers, test_only_app_prints):
        try:
            check()
        except AssertionError:
            continue
        raise AssertionError(f"{check.__name__} let a breach through")


# The FEM stepper's component records whose fields are public for reading
# (Fortran has no read-only components): the component's name on
# fem_core_type and the one file whose procedures may assign its fields. (The
# factor record's fields are private: the compiler checks that one.)
RECORD_OWNER = {
    "change": SRC / "methods" / "fem" / "change_point.f90",
    "prediction": SRC / "methods" / "fem" / "prediction.f90",
}
# An assignment to a field of a record, `x%change%found = ...` (not `==`).
RECORD_ASSIGNMENT = re.compile(r"%(" + "|".join(RECORD_OWNER) + r")%\w+\s*(\([^=]*\))?\s*=(?!=)", re.IGNORECASE)


def records_assigned_outside_their_owners(paths: list[Path]) -> list[tuple[Path, int]]:
    """(file, line) of every assignment to a record's field outside its owner."""
    found = []
    for path in paths:
        for n, line in enumerate(path.read_text().splitlines(), start=1):
            code = line.split("!", 1)[0]
            found += [(path, n) for m in RECORD_ASSIGNMENT.finditer(code)
                      if path != RECORD_OWNER[m.group(1).lower()]]
    return found


def test_component_records_are_assigned_by_their_owners():
    """No flags as a protocol between files: the change-point and predictor
    records change only through their modules' procedures (src/ and the tests)."""
    paths = [*sources(), *sorted((ROOT / "test").glob("*.pf"))]
    assigned = [f"{path.relative_to(ROOT)}:{n}" for path, n in records_assigned_outside_their_owners(paths)]
    assert not assigned, "component records assigned outside their modules:\n" + "\n".join(assigned)


def test_record_check_sees_a_breach(tmp_path):
    """The check above is not vacuous: fields assigned elsewhere are caught;
    a comparison, a comment and the owners' own procedures are not."""
    other = tmp_path / "fem.f90"
    other.write_text("if (self%change%found == x) y = 1\n      self%change%found = .false.\n"
                     "fem%prediction%q(3) = 0 ! guard\n! fem%change%detect = .true.\n")
    assert records_assigned_outside_their_owners([other]) == [(other, 2), (other, 3)]
    assert records_assigned_outside_their_owners(list(RECORD_OWNER.values())) == []
