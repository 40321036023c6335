"""The names of methods and predictors: one table (fekap_model's method_names
and predictor_names) read by the deck and the command line alike, each name
taken in full or shortened to 4 letters (FEAP's rule), in any case."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from apptest import ROOT, check, read_rows, run_fekap, run_suite  # noqa: E402

DECK = ROOT / "decks" / "fourbar.deck"
# (option, value as given, full name)
NAMES = [("--method", "cart", "cartesian"), ("--method", "ANGL", "angles"), ("--method", "fem", "fem"),
         ("--predictor", "extr", "extrapolate"), ("--predictor", "Prev", "previous"),
         ("--predictor", "tayl", "taylor")]
BAD = [("--method", "car"), ("--method", "cartesianx"), ("--predictor", "ex"), ("--predictor", "taylors")]


def run(outdir: Path, *args: str):
    return run_fekap("-q", "-o", str(outdir), *args, str(DECK))


def test_command_line_takes_abbreviations():
    """Each 4-letter abbreviation gives the very rows of the full name."""
    with tempfile.TemporaryDirectory() as work:
        for option, short, full in NAMES:
            a = run(Path(work) / f"{short}", option, short)
            b = run(Path(work) / f"{full}-full", option, full)
            check(a.returncode == 0, f"{option} {short}: exit {a.returncode}: {a.stderr}")
            check(b.returncode == 0, f"{option} {full}: exit {b.returncode}: {b.stderr}")
            check(read_rows(Path(work) / short / "points.csv") == read_rows(Path(work) / f"{full}-full" / "points.csv"),
                  f"{option} {short} and {option} {full} differ")


def test_command_line_refuses_other_names():
    """A prefix shorter than 4 letters, or a longer word, is refused with exit 2."""
    with tempfile.TemporaryDirectory() as work:
        for option, value in BAD:
            r = run(Path(work) / value, option, value)
            check(r.returncode == 2, f"{option} {value}: exit {r.returncode}, expected 2")
            check(f"{option} {value}: expected" in r.stderr, f"{option} {value}: message {r.stderr!r}")


def test_deck_takes_the_same_abbreviations():
    """The deck's ANALysis block takes the same names as the command line."""
    text = DECK.read_text()
    with tempfile.TemporaryDirectory() as work:
        for option, short, full in NAMES:
            key = option.lstrip("-")
            lines = [line for line in text.splitlines() if not line.strip().lower().startswith(key[:4])]
            at = next(i for i, line in enumerate(lines) if line.strip().upper().startswith("ANAL"))
            lines.insert(at + 1, f"  {key} {short}")
            deck = Path(work) / f"{key}-{short}.deck"
            deck.write_text("\n".join(lines) + "\n")
            a = run_fekap("-q", "-o", str(Path(work) / f"deck-{short}"), str(deck))
            b = run(Path(work) / f"cli-{full}", option, full)
            check(a.returncode == 0, f"deck with '{key} {short}': exit {a.returncode}: {a.stderr}")
            check(read_rows(Path(work) / f"deck-{short}" / "points.csv")
                  == read_rows(Path(work) / f"cli-{full}" / "points.csv"), f"deck '{key} {short}' and {option} {full} differ")


if __name__ == "__main__":
    sys.exit(run_suite("names", [test_command_line_takes_abbreviations, test_command_line_refuses_other_names,
                                 test_deck_takes_the_same_abbreviations]))
