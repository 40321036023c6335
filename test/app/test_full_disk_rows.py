#!/usr/bin/env python3
"""A full disk keeps a header and every completed row it can (issue #31,
item 7): on a disk too small for the run, every CSV file and the listing
keep their header and the whole rows that fitted, each file a prefix of the
same run's file on a roomy disk, cut at a line end; with VTK output the .pvd
lists exactly the .vtu files left.

The tests mount a small tmpfs of their own (test_robust.SmallFileSystem) and
are skipped, saying why, where that is not allowed.

Run alone:  scripts/test full_disk_rows
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree

import pytest

from apptest import ROOT
from test_robust import VTK_DECK_LINE, SmallFileSystem, deck_text, fekap, whole_rows, write_deck  # noqa: E402

FOURBAR = ROOT / "decks/fourbar.deck"
CSV_FILES = ("points.csv", "links.csv", "steps.csv", "nodes.csv")


@pytest.mark.parametrize("size", [64 * 1024, 96 * 1024])
def test_small_disk_keeps_headers_and_whole_rows(tmp_path, size):
    reference = tmp_path / "ref"
    done = fekap("-q", "-o", reference, "--dt", "1e-3", FOURBAR)
    assert done.returncode == 0, done.stderr
    fs = SmallFileSystem(size)
    try:
        out = fs.path / "run"
        done = fekap("-q", "-o", out, "--dt", "1e-3", FOURBAR)
        assert done.returncode == 4 and "No space left on device" in done.stderr, (done.returncode, done.stderr)
        kept_rows = 0
        for name in CSV_FILES:
            data = (out / name).read_bytes()
            full = (reference / name).read_bytes()
            header = full[:full.index(b"\n") + 1]
            assert data.startswith(header), f"{name} lost its header ({len(data)} bytes)"
            assert full.startswith(data), f"{name} is not a prefix of the run's file"
            whole_rows(out / name)
            kept_rows += data.count(b"\n") - 1
        # points.csv got the space first: whole rows of it, not 0 bytes.
        assert (out / "points.csv").read_bytes().count(b"\n") > 10
        assert kept_rows > 0
        listing = (out / "fourbar.lis").read_bytes()
        assert listing.startswith(b"FEKAP") or len(listing) > 100, listing[:100]
        assert listing.endswith(b"\n"), listing[-80:]
    finally:
        fs.close()


def test_small_disk_keeps_a_pvd_for_the_vtu_files_left(tmp_path):
    deck = write_deck(tmp_path / "fourbar.deck", deck_text(**{"OUTPut\n": "OUTPut\n" + VTK_DECK_LINE}))
    fs = SmallFileSystem(64 * 1024)
    try:
        out = fs.path / "run"
        done = fekap("-q", "-o", out, "--dt", "0.005", deck)
        assert done.returncode == 4 and "No space left on device" in done.stderr, (done.returncode, done.stderr)
        left = sorted(p.relative_to(out).as_posix() for p in (out / "vtk").glob("*.vtu"))
        assert left, "no .vtu file written"
        pvd = ElementTree.parse(out / "fourbar.pvd")
        listed = sorted(d.get("file") for d in pvd.iter("DataSet"))
        assert listed == left, (listed, left)
        for path in left:
            ElementTree.parse(out / path)
        assert not list(out.glob("*.fekap-tmp"))
    finally:
        fs.close()
