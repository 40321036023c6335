"""pytest fixtures of the app-level tests: the checking build of fekap, and
scratch directories under pytest's temporary area.

scripts/test sets FEKAP_BIN to the executable it built with run-time checks;
without it, fekap.run.fekap_binary() takes the release build of scripts/build."""

from __future__ import annotations

from pathlib import Path

import pytest

from apptest import fekap_binary


@pytest.fixture(scope="session")
def fekap() -> Path:
    """The fekap executable the tests run (must exist: a missing build is an error, not a skip)."""
    path = Path(fekap_binary())
    assert path.is_file(), f"no fekap executable at {path}: run scripts/test (or fpm build) first"
    return path


@pytest.fixture(scope="module", autouse=True)
def module_scratch(request, tmp_path_factory) -> Path | None:
    """A module with a module-level OUT (its runs' output directories) gets a
    fresh one for each pytest run; the tests of the module share it."""
    module = request.module
    if "OUT" not in getattr(module, "__annotations__", {}) and not hasattr(module, "OUT"):
        return None
    out = tmp_path_factory.mktemp(module.__name__.removeprefix("test_"))
    module.OUT = out
    return out
