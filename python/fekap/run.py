"""The fekap executable and running it: finding the executable (one rule for the
scripts, the studies and the tests), running a deck, reading the listing's SUMMARY
and PLAN; and the studies' shared pieces (the Exudyn environment, rewriting generated
blocks of the docs between markers, the machine's description)."""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RELEASE_BIN = ROOT / "build" / "local" / "bin" / "fekap"
#: The comparison scripts' own environment with Exudyn (scripts/exudyn_*.py).
EXUDYN_VENV = ROOT / "build" / "venv-exudyn"
EXUDYN_PACKAGES = ("exudyn==1.13.6", "numpy==2.4.6")


def fekap_binary(explicit: str | None = None) -> str:
    """The fekap executable, one rule for the scripts, the studies and the tests: an explicit
    path (a --bin or --fekap option), else $FEKAP_BIN (scripts/test sets it to its checking
    build), else the release build of scripts/build (build/local/bin/fekap)."""
    for what, candidate in (("given", explicit), ("FEKAP_BIN", os.environ.get("FEKAP_BIN"))):
        if candidate:
            if not Path(candidate).is_file():
                raise SystemExit(f"no fekap executable at {candidate} ({what}): build it, or name another")
            return str(Path(candidate).resolve())
    if RELEASE_BIN.is_file():
        return str(RELEASE_BIN)
    raise SystemExit(f"no fekap executable at {RELEASE_BIN}: run scripts/build first (or set FEKAP_BIN)")


def run_fekap(*args: str, binary: str | None = None, cwd: Path = ROOT, timeout: float = 300,
              input: str | None = None) -> subprocess.CompletedProcess:
    """Run fekap with ``args`` (from the repository root unless ``cwd``), its output captured
    as text."""
    return subprocess.run([fekap_binary(binary), *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, input=input)


def in_exudyn_venv(script: str, argv: list[str]) -> None:
    """Return if Exudyn imports; else run `script` again in build/venv-exudyn,
    making it with EXUDYN_PACKAGES from PyPI on the first call (does not return)."""
    try:
        import exudyn  # noqa: F401
        return
    except ImportError:
        pass
    python = EXUDYN_VENV / "bin" / "python"
    if not python.is_file():
        import sys
        print(f"making {EXUDYN_VENV} with {', '.join(EXUDYN_PACKAGES)} from PyPI ...", file=sys.stderr)
        subprocess.run([sys.executable, "-m", "venv", str(EXUDYN_VENV)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", *EXUDYN_PACKAGES], check=True)
    # The scripts import this package: installed there too, in editable mode, as in build/venv.
    if subprocess.run([str(python), "-c", "import fekap"], capture_output=True).returncode != 0:
        subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", "-e", str(ROOT / "python")],
                       check=True)
    os.execv(str(python), [str(python), script, *argv])


def scratch_dir(prefix: str) -> Path:
    return Path(tempfile.mkdtemp(prefix=prefix))


def with_settings(deck_text: str, analysis: dict[str, str] | None = None,
                  output: dict[str, str] | None = None) -> str:
    """The deck with ANALysis / OUTPut settings added (a later value replaces an
    earlier one, so they are appended as extra blocks just before END)."""
    lines = deck_text.rstrip("\n").split("\n")
    end = max(i for i, line in enumerate(lines) if line.strip().upper() == "END")
    extra: list[str] = []
    if analysis:
        extra.append("ANALysis")
        extra += [f"  {key} {value}" for key, value in analysis.items()]
    if output:
        extra.append("OUTPut")
        extra += [f"  {key} {value}" for key, value in output.items()]
    return "\n".join(lines[:end] + extra + lines[end:]) + "\n"


def run_deck(binary: str, deck: Path, outdir: Path, *options: str,
             timeout: float = 3600, measure_memory: bool = False) -> dict:
    """Run fekap on a deck; return the exit code, the wall time, the peak RSS
    (kB, with /usr/bin/time when asked and available) and the listing's summary."""
    outdir.mkdir(parents=True, exist_ok=True)
    command = [binary, "-q", "-o", str(outdir), *options, str(deck)]
    timefile = outdir / "time.txt"
    if measure_memory and Path("/usr/bin/time").is_file():
        command = ["/usr/bin/time", "-f", "%e %M", "-o", str(timefile), *command]
    import time as _time
    start = _time.perf_counter()
    proc = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    wall = _time.perf_counter() - start
    result = {"rc": proc.returncode, "wall": wall, "stderr": proc.stderr, "outdir": outdir}
    if timefile.is_file():
        fields = timefile.read_text().split()
        if len(fields) >= 2:
            result["rss_kb"] = int(fields[-1])
    listing = outdir / (deck.stem + ".lis")
    if listing.is_file():
        result.update(read_listing(listing))
    return result


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?"


def read_listing(path: Path) -> dict:
    """The SUMMARY entries (label -> number) and the PLAN's half-bandwidth and
    equation count of a listing."""
    text = path.read_text()
    summary: dict[str, float] = {}
    if "SUMMARY" in text:
        for line in text.split("SUMMARY", 1)[1].splitlines():
            match = re.match(rf"^\s*(.+?)\s+({_NUMBER})\s*$", line)
            if match:
                summary[match.group(1).strip()] = float(match.group(2))
    plan: dict[str, int] = {}
    match = re.search(r"half-bandwidth\s+(\d+)", text)
    if match:
        plan["half_bandwidth"] = int(match.group(1))
    match = re.search(r"(\d+)\s+equations", text)
    if match:
        plan["equations"] = int(match.group(1))
    return {"summary": summary, "plan": plan}


def replace_block(path: Path, name: str, content: str) -> None:
    """Replace the text between <!-- NAME:begin --> and <!-- NAME:end --> in a
    doc (appending the block if the markers are missing)."""
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    block = f"{begin}\n{content.rstrip()}\n{end}"
    text = path.read_text() if path.is_file() else ""
    if begin in text and end in text:
        head, rest = text.split(begin, 1)
        tail = rest.split(end, 1)[1]
        text = head + block + tail
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    path.write_text(text)


def machine() -> dict[str, str]:
    """nproc, the CPU model and the gfortran version."""
    info = {"nproc": str(os.cpu_count())}
    try:
        info["nproc"] = subprocess.run(["nproc"], capture_output=True, text=True).stdout.strip()
    except OSError:
        pass
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    info["cpu"] = cpu
    try:
        info["gfortran"] = subprocess.run(["gfortran", "--version"], capture_output=True,
                                          text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        info["gfortran"] = "unknown"
    blas = "unknown"
    try:
        out = subprocess.run(["ldd", str(RELEASE_BIN)], capture_output=True, text=True).stdout
        blas = ", ".join(sorted({Path(line.split("=>")[1].split()[0]).name for line in out.splitlines()
                                 if "=>" in line and ("blas" in line or "lapack" in line)})) or blas
        resolved = [os.path.realpath(line.split("=>")[1].split()[0]) for line in out.splitlines()
                    if "=>" in line and "blas" in line]
        if resolved:
            blas += f" ({resolved[0]})"
    except (OSError, IndexError):
        pass
    info["blas"] = blas
    return info
