"""Sweep files (TOML) and command-line sweeps: which decks, which parameter values
and which fekap options, combined by ``grid`` (every combination) or ``zip``
(the i-th value of each), into a list of cases. Every problem of a sweep is
found before any case runs and named by file, line and key."""

from __future__ import annotations

import glob
import hashlib
import itertools
import json
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from . import deckinfo

#: Keys of a sweep file, by table ("" is the top level).
TOP_KEYS = {"decks", "combine", "output", "timeout", "retries", "measures", "parameters",
            "options", "reference", "plot", "max_cases"}
#: Most cases a sweep may have unless it says otherwise (max_cases, --max-cases): a grid of
#: 1000 x 1000 x 1000 values is refused before its cases are listed, not after eating memory.
MAX_CASES = 100_000
#: fekap options a case may set, and the kind of their values.
OPTIONS = {"method": str, "dt": float, "tol": float, "predictor": str, "compute": str}
OPTION_CHOICES = {"method": ("fem", "cartesian", "angles"),
                  "predictor": ("previous", "extrapolate", "taylor")}
PLOT_KEYS = {"point", "quantity", "parameter"}
REFERENCE_KEYS = {"parameters", "options"}


class SweepError(Exception):
    """A problem of a sweep, as 'file:line: key: message' lines."""


@dataclass
class Place:
    """Where a key of a sweep file is: its file and line (0: unknown)."""

    file: str
    line: int = 0

    def __str__(self) -> str:
        return f"{self.file}:{self.line}" if self.line else self.file


@dataclass
class Sweep:
    """A sweep before it is expanded into cases."""

    source: str
    decks: list[Path]
    combine: str = "grid"
    parameters: dict[str, list[float]] = field(default_factory=dict)
    options: dict[str, list] = field(default_factory=dict)
    output: Path | None = None
    timeout: float | None = None
    retries: int | None = None
    measures: list[str] = field(default_factory=list)
    reference: dict[str, dict] = field(default_factory=dict)
    plot: dict[str, str] = field(default_factory=dict)
    places: dict[str, Place] = field(default_factory=dict)
    max_cases: int = MAX_CASES


@dataclass(frozen=True)
class Case:
    """One run of fekap: a deck, parameter values and options, and its identity."""

    deck: Path
    parameters: tuple[tuple[str, float], ...]
    options: tuple[tuple[str, object], ...]
    key: str

    @property
    def name(self) -> str:
        """The case's directory name: deck stem and the short hash."""
        return f"{self.deck.stem}-{self.key}"

    def arguments(self) -> list[str]:
        """fekap's command-line arguments for this case, without -o."""
        args = []
        for name, value in self.options:
            args += [f"--{name}", format_value(value)]
        for name, value in self.parameters:
            args += ["--set", f"{name}={format_value(value)}"]
        return args + [str(self.deck)]

    def label(self) -> str:
        """Parameters and options as 'name=value ...'."""
        items = list(self.parameters) + list(self.options)
        return " ".join(f"{name}={format_value(value)}" for name, value in items) or "(deck as is)"


def format_value(value: object) -> str:
    """A value as fekap reads it: floats exactly (repr), others as text."""
    if isinstance(value, float):
        return repr(value)
    return str(value)


def case_key(deck_text: str, parameters, options, version: str) -> str:
    """Short hash of (deck text, parameters, options, FEKAP version)."""
    blob = json.dumps({"deck": deck_text, "parameters": [[n, format_value(v)] for n, v in parameters],
                       "options": [[n, format_value(v)] for n, v in options],
                       "version": version}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:12]


def key_places(text: str, file: str) -> dict[str, Place]:
    """Line of every key of a TOML text, as 'table.key' ('key' at the top level).

    A plain scan of the lines (tomllib gives no positions): table headers and
    'key =' at the start of a line, which covers the sweep files' form."""
    places: dict[str, Place] = {}
    table = ""
    header = re.compile(r"^\s*\[\s*([A-Za-z0-9_.\-\"' ]+?)\s*\]\s*(#.*)?$")
    assignment = re.compile(r"^\s*(\"[^\"]*\"|'[^']*'|[A-Za-z0-9_\-.]+)\s*=")
    for number, line in enumerate(text.splitlines(), start=1):
        match = header.match(line)
        if match:
            table = match.group(1).replace('"', "").replace("'", "").replace(" ", "")
            places.setdefault(table, Place(file, number))
            continue
        match = assignment.match(line)
        if match:
            key = match.group(1).strip("\"'")
            full = f"{table}.{key}" if table else key
            places.setdefault(full, Place(file, number))
    return places


class Problems:
    """Collects the problems of a sweep; raises them all together."""

    def __init__(self, places: dict[str, Place], file: str, limit: int = MAX_CASES):
        self.places = places
        self.file = file
        self.items: list[str] = []
        #: Most values a list may have (the sweep's case limit): checked before it is made.
        self.limit = limit

    def add(self, key: str, message: str) -> None:
        place = self.places.get(key) or self.places.get(key.split(".")[0]) or Place(self.file)
        self.items.append(f"{place}: {key}: {message}")

    def check(self) -> None:
        if self.items:
            raise SweepError("\n".join(self.items))


def values_of(spec, key: str, problems: Problems, kind=float) -> list:
    """The values of a swept key: a scalar, a list, {linspace = [a, b, n]} or
    {range = [start, stop, step]} (stop included when a step lands on it)."""
    if isinstance(spec, dict):
        if set(spec) == {"linspace"}:
            args = spec["linspace"]
            if (not isinstance(args, list) or len(args) != 3 or not all(is_number(a) for a in args)
                    or not float(args[2]).is_integer()):
                problems.add(key, "linspace is [first, last, count] with a whole count")
                return []
            first, last, count = float(args[0]), float(args[1]), int(args[2])
            if count < 1:
                problems.add(key, f"empty range: linspace of {count} values")
                return []
            if count > problems.limit:
                problems.add(key, too_many(count, problems.limit, "values"))
                return []
            if count == 1:
                return [first]
            return [tidy(first + (last - first) * i / (count - 1)) for i in range(count)]
        if set(spec) == {"range"}:
            args = spec["range"]
            if not isinstance(args, list) or len(args) != 3 or not all(is_number(a) for a in args):
                problems.add(key, "range is [start, stop, step]")
                return []
            start, stop, step = (float(a) for a in args)
            if step == 0 or (stop - start) / step < 0:
                problems.add(key, f"empty range: from {start:g} to {stop:g} in steps of {step:g}")
                return []
            count = int(math.floor((stop - start) / step + 1e-9)) + 1
            if count > problems.limit:
                problems.add(key, too_many(count, problems.limit, "values"))
                return []
            return [tidy(start + i * step) for i in range(count)]
        problems.add(key, "expected a value, a list, {linspace = [first, last, count]} or "
                     "{range = [start, stop, step]}; got keys " + ", ".join(sorted(spec)))
        return []
    items = spec if isinstance(spec, list) else [spec]
    if not items:
        problems.add(key, "empty list: give at least one value")
        return []
    out = []
    for item in items:
        if kind is float:
            if not is_number(item):
                problems.add(key, f"expected a number, got {item!r}")
                return []
            out.append(float(item))
        elif not isinstance(item, (str, int, float)) or isinstance(item, bool):
            problems.add(key, f"expected a value, got {item!r}")
            return []
        else:
            out.append(item)
    return out


def too_many(count: int, limit: int, what: str) -> str:
    return (f"{count:,} {what}, more than the limit of {limit:,} cases (max_cases = N in the sweep "
            "file or --max-cases N raises it)")


def case_count(sweep: Sweep) -> int:
    """How many cases the sweep makes, counted without making them."""
    lengths = [len(v) for v in list(sweep.parameters.values()) + list(sweep.options.values())]
    if sweep.combine == "grid":
        rows = math.prod(lengths)
    else:
        rows = max(lengths, default=1)
    return rows * len(sweep.decks)


def check_count(sweep: Sweep) -> int:
    """The sweep's number of cases; a SweepError when it is over its limit."""
    count = case_count(sweep)
    if count > sweep.max_cases:
        where = sweep.places.get("max_cases") or Place(sweep.source)
        raise SweepError(f"{where}: the sweep has {too_many(count, sweep.max_cases, 'cases')}")
    return count


def tidy(value: float) -> float:
    """A computed grid value without its last-digit noise (1.7, not 1.7000000000000002)."""
    return float(f"{value:.12g}")


def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def load_sweep(path: Path, max_cases: int | None = None) -> Sweep:
    """Read and check a sweep file (decks, values, keys); raise SweepError. ``max_cases``
    (the command line's) overrides the file's max_cases."""
    file = str(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise SweepError(f"{file}: cannot read the sweep file: {exc.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        match = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        where = f"{file}:{match.group(1)}:{match.group(2)}" if match else file
        raise SweepError(f"{where}: not valid TOML: {re.sub(r' [(]at line.*', '', str(exc))}") from None
    places = key_places(text, file)
    problems = Problems(places, file)
    for key in data:
        if key not in TOP_KEYS:
            problems.add(key, "unknown key (keys: " + ", ".join(sorted(TOP_KEYS)) + ")")
    sweep = Sweep(source=file, decks=[], places=places)
    if "max_cases" in data:
        value = data["max_cases"]
        if isinstance(value, int) and not isinstance(value, bool) and value >= 1:
            sweep.max_cases = value
        else:
            problems.add("max_cases", "expected a whole number >= 1")
    if max_cases is not None:
        sweep.max_cases = max_cases
    problems.limit = sweep.max_cases
    decks = data.get("decks")
    if decks is None:
        problems.add("decks", "missing: give decks = [\"DECK\" or \"GLOB\", ...]")
    else:
        patterns = decks if isinstance(decks, list) else [decks]
        if not patterns or not all(isinstance(p, str) for p in patterns):
            problems.add("decks", "expected a list of deck paths or globs")
        else:
            sweep.decks = expand_decks(patterns, path.parent, "decks", problems)
    combine = data.get("combine", "grid")
    if combine not in ("grid", "zip"):
        problems.add("combine", f"expected \"grid\" or \"zip\", got {combine!r}")
    sweep.combine = combine
    for name, spec in table(data, "parameters", problems).items():
        sweep.parameters[name] = values_of(spec, f"parameters.{name}", problems)
    for name, spec in table(data, "options", problems).items():
        sweep.options[name] = option_values(name, spec, f"options.{name}", problems)
    if "output" in data:
        if isinstance(data["output"], str) and data["output"]:
            sweep.output = Path(data["output"])
        else:
            problems.add("output", "expected a directory name")
    if "timeout" in data:
        if is_number(data["timeout"]) and data["timeout"] > 0:
            sweep.timeout = float(data["timeout"])
        else:
            problems.add("timeout", "expected a positive number of seconds")
    if "retries" in data:
        if isinstance(data["retries"], int) and not isinstance(data["retries"], bool) and data["retries"] >= 0:
            sweep.retries = data["retries"]
        else:
            problems.add("retries", "expected a whole number >= 0")
    if "measures" in data:
        measures = data["measures"]
        if isinstance(measures, list) and all(isinstance(m, str) for m in measures):
            sweep.measures = measures
        else:
            problems.add("measures", "expected a list of expressions such as \"max(points.C.y)\"")
    reference = table(data, "reference", problems)
    for key, value in reference.items():
        if key not in REFERENCE_KEYS:
            problems.add(f"reference.{key}", "unknown key (keys: parameters, options)")
        elif not isinstance(value, dict):
            problems.add(f"reference.{key}", "expected a table of values")
        else:
            kind = "parameters" if key == "parameters" else "options"
            checked = {}
            for name, item in value.items():
                where = f"reference.{key}.{name}"
                got = (values_of(item, where, problems) if kind == "parameters"
                       else option_values(name, item, where, problems))
                if len(got) > 1:
                    problems.add(where, "a reference takes one value")
                elif got:
                    checked[name] = got[0]
            sweep.reference[kind] = checked
    for key, value in table(data, "plot", problems).items():
        if key not in PLOT_KEYS:
            problems.add(f"plot.{key}", "unknown key (keys: " + ", ".join(sorted(PLOT_KEYS)) + ")")
        elif not isinstance(value, str):
            problems.add(f"plot.{key}", "expected a name")
        else:
            sweep.plot[key] = value
    problems.check()
    return sweep


def table(data: dict, key: str, problems: Problems) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        problems.add(key, "expected a table")
        return {}
    return value


def option_values(name: str, spec, key: str, problems: Problems) -> list:
    """Values of a fekap option, checked against what fekap accepts."""
    if name not in OPTIONS:
        problems.add(key, "unknown option (options: " + ", ".join(OPTIONS) + ")")
        return []
    kind = OPTIONS[name]
    values = values_of(spec, key, problems, kind=float if kind is float else str)
    for value in values:
        if kind is float and not value > 0:
            problems.add(key, f"expected a positive number, got {value!r}")
            return []
        if kind is str and not isinstance(value, str):
            problems.add(key, f"expected a name, got {value!r}")
            return []
        if name in OPTION_CHOICES and value not in OPTION_CHOICES[name]:
            problems.add(key, f"{value!r} is not one of " + ", ".join(OPTION_CHOICES[name]))
            return []
    return values


def expand_decks(patterns: list[str], base: Path, key: str, problems: Problems) -> list[Path]:
    """Deck paths and globs (relative to ``base``), each readable."""
    decks: list[Path] = []
    for pattern in patterns:
        full = pattern if Path(pattern).is_absolute() else str(base / pattern)
        if glob.has_magic(pattern):
            found = sorted(Path(p) for p in glob.glob(full))
            if not found:
                problems.add(key, f"no deck matches {pattern!r}")
            decks += found
        else:
            deck = Path(full)
            try:
                deck.read_text()
            except (OSError, UnicodeDecodeError) as exc:
                reason = exc.strerror if isinstance(exc, OSError) else "not a text file"
                problems.add(key, f"cannot read the deck {pattern!r} ({deck}): {reason}")
                continue
            decks.append(deck)
    return list(dict.fromkeys(decks))


def expand(sweep: Sweep, version: str) -> tuple[list[Case], dict[Case, Case]]:
    """The cases of a sweep, and the reference case of each (when a [reference]
    table is given). Checks that every parameter is one of each deck's."""
    problems = Problems(sweep.places, sweep.source)
    texts = {}
    for deck in sweep.decks:
        try:
            texts[deck] = deck.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            problems.add("decks", f"cannot read the deck {deck}: {exc}")
    problems.check()
    for deck, text in texts.items():
        known = deckinfo.parameter_names(text)
        wanted = list(sweep.parameters) + list(sweep.reference.get("parameters", {}))
        for name in wanted:
            if name.lower() not in known:
                key = f"parameters.{name}" if name in sweep.parameters else f"reference.parameters.{name}"
                have = ", ".join(known.values()) if known else "none: it has no PARAmeters block"
                problems.add(key, f"parameter {name!r} is not in the deck {deck} (its parameters: {have})")
    if sweep.combine == "zip":
        lengths = {k: len(v) for k, v in list(sweep.parameters.items()) + list(sweep.options.items())}
        longest = [k for k, n in lengths.items() if n > 1]
        if len({lengths[k] for k in longest}) > 1:
            for k in longest:
                section = "parameters" if k in sweep.parameters else "options"
                problems.add(f"{section}.{k}", "combine = \"zip\" needs lists of one length; "
                             "the lists have " + ", ".join(f"{n}: {lengths[n]}" for n in longest))
    problems.check()
    check_count(sweep)

    names = list(sweep.parameters) + list(sweep.options)
    lists = [sweep.parameters[n] for n in sweep.parameters] + [sweep.options[n] for n in sweep.options]
    if sweep.combine == "grid":
        rows = list(itertools.product(*lists))
    else:
        count = max((len(v) for v in lists), default=1)
        rows = [tuple(v[i] if len(v) > 1 else v[0] for v in lists) for i in range(count)]
    nparams = len(sweep.parameters)
    cases: list[Case] = []
    references: dict[Case, Case] = {}
    for deck in sweep.decks:
        for row in rows:
            parameters = tuple(zip(names[:nparams], row[:nparams]))
            options = tuple(zip(names[nparams:], row[nparams:]))
            case = make_case(deck, texts[deck], parameters, options, version)
            cases.append(case)
            if sweep.reference:
                ref_params = dict(parameters) | sweep.reference.get("parameters", {})
                ref_options = dict(options) | sweep.reference.get("options", {})
                references[case] = make_case(deck, texts[deck], tuple(ref_params.items()),
                                             tuple(ref_options.items()), version)
    return list(dict.fromkeys(cases)), references


def make_case(deck: Path, text: str, parameters, options, version: str) -> Case:
    parameters = tuple(parameters)
    options = tuple(options)
    return Case(deck=deck, parameters=parameters, options=options,
                key=case_key(text, parameters, options, version))
