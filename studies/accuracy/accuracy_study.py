#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Accuracy against cost: FEKAP runs on decks with exact answers, sweeping one
setting at a time, recording the largest error against the exact answer and
the time the run took.

Studies (deck, what is swept, the exact answer):
  tolerance  Example 1 (four-bar), Newton tolerance 1e-4 ... 1e-14, with the
             paper's test and with the default test (whose length test,
             1e-12 x model size, stays on): closed-form B, C (and their rates)
  tolerance  Example 4 (Peaucellier), same sweep, default test: P.x = 2.7
  step       Example 1, dt = 0.1 ... 0.001, default settings
  predictor  Example 1 at dt = 0.025 and 0.1: previous, extrapolate, taylor
  penalty    slider-crank (x_B = cos th + sqrt(9 - sin^2 th)) and Example 5,
             the quick-return (P from the geometry of examples.md), with
             slideline penalty 1e0 ... 1e8 and 0 (automatic)
  elements   cantilever roll-up (decks/cantilever-rollup.deck), M = t 2 pi EI/L:
             the exact tip lies on the arc x = sin(phi)/kappa,
             y = (1 - cos(phi))/kappa with kappa = 2 pi t, phi = kappa L, L = 1;
             2 ... 128 elements
  dynamics   (a table of its own) the stiff pendulum (decks/dynamics/pendulum.deck):
             its first bottom pass against T/4 = 0.591960487 s and 4.429446918 m/s,
             generalized-alpha with rho_inf 0.5, 0.8, 1; the A02 chain, N = 2,
             over 4 s: the first crank's angle and rate against the exact
             motion (python/fekap/exact/a02.py, the energy integral's quadrature)
             before the first change point (t <= 0.7 s: the integrator's
             error, with its observed order) and over the 4 s (with the
             change points, where the elastic bars take a kick), generalized-alpha (GA) and energy-momentum (EM) with
             rho_inf 1, 0.9, 0.8, 0.5, dt 8e-3 ... 2.5e-4 (energy-momentum 1
             and 0.8 down to 6.25e-5), the observed order against the next
             larger dt; and the bars' stiffness swept from
             EA = 1e8 to 1e12 at dt 5e-4 and 2.5e-4 (the elastic model's share
             of the error: the plateau over the change points falls as the
             bars stiffen); Newton iterations and microseconds (analysis) per step

Errors are the largest distance between a tracked point and its exact position
over every written step (positions), and for Example 1 also the largest
velocity and acceleration errors relative to their largest magnitude. Time is
the listing's "time in analysis" (wall clock of the analysis, without output);
the child's CPU time (user + system, including starting the process and
reading the deck) is recorded beside it. Each point is run 5 times (--repeat):
mean analysis time, median CPU time.

Writes docs/performance/accuracy.png, docs/performance/accuracy.json and the
table between the accuracy markers of docs/performance.md.

  adaptive   (--adaptive, a plot of its own) fixed against adaptive steps
             (`time T0 T1 DT adaptive TOL`): the largest position error over
             the rows against the child's CPU time, on the pendulum
             (decks/dynamics/pendulum.deck with its link 1000 times stiffer,
             so that the rigid answer is exact to 1e-10 m; to 0.6 s against RK4
             of the rigid pendulum at 1e-5 s), the double pendulum (two 1 kg
             masses on stiff massless 1 m links from the horizontal, to 0.5 s,
             against RK4 of Lagrange's equations at 1e-5 s) and the flexible
             slider-crank (decks/dynamics/slider-crank.deck to 0.02 s, node M,
             against FEKAP's own run at dt 2.5e-6: no exact answer exists),
             generalized-alpha 0.8 with the consistent start; errors at the
             rows' common instants (multiples of the adaptive runs' DT).

Usage: studies/accuracy/accuracy_study.py [--short] [--dynamics] [--adaptive [--plot PNG]] [--bin FEKAP] [--repeat N]
  --short: a few points per study, prints the table, writes no docs.
  --dynamics: the dynamics table alone.
  --adaptive: the fixed-against-adaptive study alone; writes its plot to PNG
             (default docs/performance/accuracy-adaptive.png) and prints its table.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import resource
import shutil
import statistics
import sys
from pathlib import Path

import numpy as np

from fekap import dynamics as dc  # the benchmarks' answers from a run's CSV files
from fekap import read
from fekap import run as fb
from fekap.exact.fourbar import fourbar_exact  # hyper-dual closed form of Example 1
from fekap.exact.pendulums import double_pendulum_rate, double_pendulum_tip, rk4_states
from fekap.models import pendulums


def slider_exact(t: float) -> tuple[float, float]:
    th = 2 * math.pi * t
    return math.cos(th) + math.sqrt(9 - math.sin(th) ** 2), 0.0


def quick_return_exact(t: float) -> tuple[float, float]:
    """P of Example 5 from the geometry: crank pin C, lever direction O4->C,
    B at 150 sqrt(10) along it, P on y = 500 with |BP| = 50 sqrt(10) (left of B)."""
    phi = math.atan2(-1, 3) + 2 * math.pi * t
    cx, cy = 100 * math.cos(phi), 100 * math.sqrt(10) + 100 * math.sin(phi)
    r = math.hypot(cx, cy)
    bx, by = 150 * math.sqrt(10) * cx / r, 150 * math.sqrt(10) * cy / r
    return bx - math.sqrt(25000 - (500 - by) ** 2), 500.0


def rollup_exact(t: float) -> tuple[float, float]:
    kappa = 2 * math.pi * t
    if kappa == 0:
        return 1.0, 0.0
    return math.sin(kappa) / kappa, (1 - math.cos(kappa)) / kappa


def peaucellier_x(t: float) -> float:
    return 2.7


def set_penalty(text: str, value: str) -> str:
    """Add penalty=VALUE to every slideline line."""
    out, inside = [], False
    for line in text.split("\n"):
        word = line.split("!")[0].strip().split()
        if word and re.match(r"^[A-Za-z]{4,}$", word[0]) and len(word) == 1:
            inside = word[0].upper().startswith("SLID")
        elif inside and word and not line.lstrip().startswith(("*", "!")):
            code, _, comment = line.partition("!")
            line = code.rstrip() + f"  penalty={value}" + (f"  !{comment}" if comment else "")
        out.append(line)
    return "\n".join(out)


def set_elements(text: str, link: str, count: int) -> str:
    return re.sub(rf"^(\s*{link}\s+\S+\s+\S+\s+\S+)\s+\d+", rf"\g<1>  {count}", text, flags=re.M)


def run(binary: str, work: Path, deck: str, analysis: dict | None = None, text_edit=None,
        options: tuple = (), repeat: int = 1) -> dict:
    """Run a deck `repeat` times: the last run's result, with the mean analysis
    time (the listing prints it to 0.1 ms; the mean of repeats dithers that)
    and the median CPU time of the child."""
    text = (fb.ROOT / "decks" / deck).read_text()
    if text_edit:
        text = text_edit(text)
    text = fb.with_settings(text, analysis or {})
    path = work / f"{Path(deck).stem}-{len(list(work.iterdir()))}.deck"
    path.write_text(text)
    times, cpus = [], []
    for k in range(repeat):
        if k:
            shutil.rmtree(work / path.stem, ignore_errors=True)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        result = fb.run_deck(binary, path, work / path.stem, *options)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))
        times.append(result.get("summary", {}).get("time in analysis (s)", float("nan")))
    result["cpu"] = statistics.median(cpus)
    result["analysis"] = statistics.mean(times)
    return result


def position_error(outdir: Path, point: str, exact) -> float:
    rows = read.rows(outdir / "points.csv", True, point=point)
    return max(math.hypot(r["x"] - exact(r["t"])[0], r["y"] - exact(r["t"])[1]) for r in rows)


def fourbar_errors(outdir: Path) -> dict:
    """Largest position error of B and C, and velocity/acceleration errors
    relative to the largest exact magnitude."""
    errors = {"position": 0.0, "velocity": 0.0, "acceleration": 0.0}
    scales = {"velocity": 0.0, "acceleration": 0.0}
    for index, point in enumerate(("B", "C")):
        for r in read.rows(outdir / "points.csv", True, point=point):
            e = fourbar_exact(r["t"])[index]
            errors["position"] = max(errors["position"], math.hypot(r["x"] - e[0].f, r["y"] - e[1].f))
            for key, kx, ky, part in (("velocity", "vx", "vy", "d"), ("acceleration", "ax", "ay", "dd")):
                if r.get(kx) is None:
                    continue
                ex, ey = getattr(e[0], part), getattr(e[1], part)
                scales[key] = max(scales[key], math.hypot(ex, ey))
                errors[key] = max(errors[key], math.hypot(r[kx] - ex, r[ky] - ey))
    for key in scales:
        errors[key] = errors[key] / scales[key] if scales[key] else float("nan")
    return errors


def record(study: str, case: str, setting: str, result: dict, errors: dict) -> dict:
    s = result.get("summary", {})
    n = s.get("configurations solved", 0)
    return {"study": study, "case": case, "setting": setting, "rc": result["rc"],
            "analysis_ms": 1e3 * result["analysis"],
            "cpu_ms": 1e3 * result["cpu"], "configs": n,
            "iterations_per_step": s.get("Newton iterations", 0) / max(1, n - 1), **errors}


def studies(short: bool) -> list[tuple]:
    """(study, case, setting label, deck, analysis settings, deck edit, error kind)."""
    out = []
    tols = ["1e-4", "1e-8", "1e-12"] if short else ["1e-4", "1e-6", "1e-8", "1e-10", "1e-12", "1e-14"]
    for tol in tols:
        out.append(("tolerance", "Example 1, paper test", f"tol {tol}", "fourbar.deck",
                    {"tolerance": tol, "convergence": "paper", "predictor": "previous"}, None, "fourbar"))
        out.append(("tolerance", "Example 1, default test", f"tol {tol}", "fourbar.deck",
                    {"tolerance": tol}, None, "fourbar"))
        out.append(("tolerance", "Example 1, default test, length = tol", f"tol {tol}", "fourbar.deck",
                    {"tolerance": tol, "length": tol}, None, "fourbar"))
        if not short:
            out.append(("tolerance", "Example 4, default test", f"tol {tol}", "peaucellier.deck",
                        {"tolerance": tol}, None, "peaucellier"))
    for dt in (["0.1", "0.01"] if short else ["0.1", "0.05", "0.025", "0.01", "0.001"]):
        out.append(("step", "Example 1", f"dt {dt}", "fourbar.deck", {"time": f"0 1 {dt}"}, None, "fourbar"))
        if not short:
            out.append(("step", "Example 4", f"dt {dt}", "peaucellier.deck", {"time": f"0 1 {dt}"}, None,
                        "peaucellier"))
    for dt in (["0.025"] if short else ["0.025", "0.1"]):
        for predictor in ("previous", "extrapolate", "taylor"):
            out.append(("predictor", f"Example 1, dt {dt}", predictor, "fourbar.deck",
                        {"time": f"0 1 {dt}", "predictor": predictor}, None, "fourbar"))
    penalties = ["1e0", "1e4", "0"] if short else ["1e0", "1e1", "1e2", "1e3", "1e4", "1e6", "1e8", "0"]
    for penalty in penalties:
        label = "penalty auto" if penalty == "0" else f"penalty {penalty}"
        out.append(("penalty", "slider-crank", label, "slider-crank.deck", {},
                    (lambda text, p=penalty: set_penalty(text, p)), "slider"))
        if not short:
            out.append(("penalty", "Example 5 (quick-return)", label, "quick-return.deck", {},
                        (lambda text, p=penalty: set_penalty(text, p)), "quick-return"))
    for count in ([4, 16] if short else [2, 4, 8, 16, 32, 64, 128]):
        out.append(("elements", "cantilever roll-up", f"{count} elements", "cantilever-rollup.deck", {},
                    (lambda text, c=count: set_elements(text, "RT", c)), "rollup"))
    return out


def measure(binary: str, work: Path, item: tuple, repeat: int) -> dict:
    study, case, setting, deck, analysis, edit, kind = item
    result = run(binary, work, deck, analysis, edit, repeat=repeat)
    errors: dict = {"position": float("nan")}
    if result["rc"] == 0 or (result["outdir"] / "points.csv").is_file():
        try:
            if kind == "fourbar":
                errors = fourbar_errors(result["outdir"])
            elif kind == "peaucellier":
                errors = {"position": max(abs(r["x"] - 2.7) for r in read.rows(result["outdir"] / "points.csv", True, point="P"))}
            elif kind == "slider":
                errors = {"position": position_error(result["outdir"], "B", slider_exact)}
            elif kind == "quick-return":
                errors = {"position": position_error(result["outdir"], "P", quick_return_exact)}
            elif kind == "rollup":
                errors = {"position": position_error(result["outdir"], "T", rollup_exact)}
        except (KeyError, ValueError, IndexError):
            pass
    shutil.rmtree(result["outdir"], ignore_errors=True)
    return record(study, case, setting, result, errors)


def pendulum_errors(outdir: Path) -> dict:
    """Errors of the first bottom pass: time and speed (fekap.dynamics.bottom_pass)."""
    t, speed = dc.bottom_pass(outdir)
    return {"error": abs(t - dc.BOTTOM_TIME), "second": abs(speed - dc.BOTTOM_SPEED)}


def a02_errors(outdir: Path, n: int = 2) -> dict:
    """Largest errors of the first crank's angle (rad) and rate (rad/s)
    against the exact motion (fekap.dynamics.a02_errors): before the first
    change point (the integrator's error: error, second) and over the run
    (angle_all, rate_all: with the change points, where the elastic bars'
    stiff modes take a kick that the rigid answer has not)."""
    e = dc.a02_errors(outdir, n)
    return {"error": e["angle_before"], "second": e["rate_before"], "angle_all": e["angle"], "rate_all": e["rate"]}


#: Integrators of the dynamics table: (ANALysis integrator line, label).
INTEGRATORS = (("generalized-alpha 1", "GA 1"), ("generalized-alpha 0.9", "GA 0.9"),
               ("generalized-alpha 0.8", "GA 0.8"), ("generalized-alpha 0.5", "GA 0.5"),
               ("energy-momentum 1", "EM 1"), ("energy-momentum 0.9", "EM 0.9"),
               ("energy-momentum 0.8", "EM 0.8"), ("energy-momentum 0.5", "EM 0.5"))
A02_CASE = "A02 N = 2: crank angle (rad), rate (rad/s)"


def dynamics_studies(short: bool) -> list[tuple]:
    """(case, deck, dt, integrator, t_end, text_edit) of the dynamics table."""
    out = []
    for rho in ((0.8, 1.0) if short else (0.5, 0.8, 1.0)):
        for dt in ((4e-3, 1e-3) if short else (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)):
            out.append(("pendulum: bottom pass time (s), speed (m/s)", "dynamics/pendulum.deck", dt,
                        f"generalized-alpha {rho!r}", 0.62, None))
    integrators = (INTEGRATORS[0], INTEGRATORS[2], INTEGRATORS[4], INTEGRATORS[6]) if short else INTEGRATORS
    for line, _ in integrators:
        steps = (4e-3, 2e-3) if short else (8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)
        if not short and line in ("energy-momentum 1", "energy-momentum 0.8"):
            steps += (1.25e-4, 6.25e-5)  # does the plateau over 4 s fall with dt? (it does not)
        for dt in steps:
            out.append((A02_CASE, "dynamics/a02-n2.deck", dt, line, 4.0, None))
    # The elastic model's share: the bars' stiffness swept at a fixed small dt.
    for factor in ((1e-2, 1e2) if short else (1e-2, 1e-1, 1e0, 1e1, 1e2)):
        for line in ("energy-momentum 0.8", "generalized-alpha 0.8"):
            for dt in ((5e-4,) if short else (5e-4, 2.5e-4)):
                out.append((f"A02 N = 2, bars EA = {1e10 * factor:.0e} (EI = EA/100)", "dynamics/a02-n2.deck", dt, line,
                            4.0, lambda text, f=factor: stiffness(text, f)))
    return out


def stiffness(text: str, factor: float) -> str:
    """The A02 bars `factor` times as stiff as the deck's (EA = kGA = 1e10, EI = 1e8)."""
    if "EA=1e10  kGA=1e10  EI=1e8" not in text:
        raise SystemExit("decks/dynamics/a02-n2.deck's section line changed; the stiffness study edits it")
    return text.replace("EA=1e10  kGA=1e10  EI=1e8",
                        f"EA={1e10 * factor:g}  kGA={1e10 * factor:g}  EI={1e8 * factor:g}")


def measure_dynamics(binary: str, work: Path, item: tuple, repeat: int) -> dict:
    case, deck, dt, integrator, t_end, edit = item
    result = run(binary, work, deck, {"time": f"0 {t_end!r} {dt!r}", "integrator": integrator},
                 text_edit=edit, repeat=repeat)
    errors = {"error": float("nan"), "second": float("nan"), "angle_all": float("nan"), "rate_all": float("nan")}
    if result["rc"] == 0:
        errors.update(pendulum_errors(result["outdir"]) if "pendulum" in deck else a02_errors(result["outdir"]))
    shutil.rmtree(result["outdir"], ignore_errors=True)
    s = result.get("summary", {})
    steps = max(1, s.get("configurations solved", 1) - 1)
    return {"case": case, "dt": dt, "integrator": integrator, "rc": result["rc"], **errors,
            "iterations_per_step": s.get("Newton iterations", 0) / steps,
            "us_per_step": 1e6 * result["analysis"] / steps}


def observed_orders(rows: list[dict]) -> None:
    """Each row's observed order of its error against the row before it (the
    same case and integrator, the previous dt): log(e_prev / e) / log(dt_prev / dt)."""
    for prev, row in zip(rows, rows[1:]):
        same = prev["case"] == row["case"] and prev["integrator"] == row["integrator"]
        for key in ("error", "second"):
            a, b = prev[key], row[key]
            ok = same and a > 0 and b > 0 and math.isfinite(a) and math.isfinite(b)
            row[f"order_{key}"] = math.log(a / b) / math.log(prev["dt"] / row["dt"]) if ok else float("nan")


def dynamics_table(rows: list[dict]) -> str:
    observed_orders(rows)
    lines = ["| case | integrator (rho_inf) | dt | exit | error | order | second error | order "
             "| A02 over 4 s: angle, rate | Newton its/step | analysis (us/step) |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        whole = "-" if math.isnan(r["angle_all"]) else f"{fmt(r['angle_all'])}, {fmt(r['rate_all'])}"
        lines.append(f"| {r['case']} | {r['integrator']} | {r['dt']:g} | {r['rc']} | {fmt(r['error'])} | "
                     f"{order(r.get('order_error'))} | {fmt(r['second'])} | {order(r.get('order_second'))} | "
                     f"{whole} | {r['iterations_per_step']:.2f} | {r['us_per_step']:.1f} |")
    return "\n".join(lines)


def stiffness_summary(rows: list[dict]) -> str:
    """What the stiffness sweep says: per integrator and dt, the slope of
    log(error) against log(EA), fitted over the swept EA, for the angle error
    before the first change point and over the 4 s. A plateau made by the
    elastic bars falls as they stiffen (negative slope over 4 s); an error of
    the integrator on stiff bars grows with them."""
    groups: dict[tuple, list[tuple[float, dict]]] = {}
    for r in rows:
        match = re.search(r"bars EA = (\S+)", r["case"])
        if match and r["rc"] == 0:
            groups.setdefault((r["integrator"], r["dt"]), []).append((float(match.group(1)), r))
    lines = []
    for (integrator, dt), sel in groups.items():
        if len(sel) < 2:
            continue
        ea = np.log10([e for e, _ in sel])
        slopes = {key: np.polyfit(ea, np.log10([max(r[key], 1e-300) for _, r in sel]), 1)[0]
                  for key in ("error", "angle_all")}
        spread = ", ".join(f"{fmt(r['angle_all'])}" for _, r in sel)
        lines.append(f"- {integrator}, dt {dt:g}: over 4 s the angle error goes {spread} for EA = "
                     f"{', '.join(f'{e:.0e}' for e, _ in sel)}: slope {slopes['angle_all']:+.2f} per decade of EA "
                     f"({'falls as the bars stiffen: the elastic bars' if slopes['angle_all'] < -0.2 else 'does not fall'}); "
                     f"before the first change point slope {slopes['error']:+.2f}"
                     f"{' (grows with the stiffness: the integrator)' if slopes['error'] > 0.5 else ''}")
    return "\n".join(lines)


def order(value) -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return f"{value:.2f}"


def fmt(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return f"{value:.2e}"


def table(rows: list[dict]) -> str:
    lines = ["| study | case | setting | exit | max position error | velocity error (rel.) "
             "| acceleration error (rel.) | Newton its/step | analysis (ms) | CPU of the run (ms) |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        lines.append(f"| {r['study']} | {r['case']} | {r['setting']} | {r['rc']} | {fmt(r['position'])} | "
                     f"{fmt(r.get('velocity'))} | {fmt(r.get('acceleration'))} | "
                     f"{r['iterations_per_step']:.2f} | {r['analysis_ms']:.2f} | {r['cpu_ms']:.1f} |")
    return "\n".join(lines)


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 5))
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["study"], r["case"]), []).append(r)
    markers = "os^vD<>pPX*h"
    for k, ((study, case), sel) in enumerate(groups.items()):
        pts = [(max(r["analysis_ms"], 1e-2), max(r["position"], 1e-17)) for r in sel
               if r["rc"] == 0 and not math.isnan(r["position"])]
        if pts:
            ax.loglog(*zip(*pts), marker=markers[k % len(markers)], linestyle="-", label=f"{study}: {case}",
                      alpha=0.8)
    ax.set_xlabel("time in analysis (ms)")
    ax.set_ylabel("largest position error")
    ax.set_title("FEKAP: error against the exact answer vs cost")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


# --- fixed against adaptive steps (--adaptive) -------------------------------

G = 9.81

#: The double pendulum of point masses on stiff massless links (EA = 1e10),
#: released horizontal (fekap.models.pendulums).
DOUBLE_PENDULUM = pendulums.deck("double pendulum of point masses on stiff massless links", 1e10,
                                 pendulums.double_pendulum(), "  time 0 0.5 0.001\n",
                                 "  units length=m time=s\n  track C\n")


def pendulum_reference(t_end: float, h: float = 1e-5):
    """The rigid pendulum from the horizontal (angle th below it, th'' = g cos th): B at time t."""
    states = rk4_states(lambda y: np.array([y[1], G * math.cos(y[0])]), [0.0, 0.0], h, round(t_end / h))
    return lambda t: (math.cos(states[round(t / h), 0]), -math.sin(states[round(t / h), 0]))


def double_reference(t_end: float, h: float = 1e-5):
    """The double pendulum (angles from the downward vertical, both released at pi/2): C at time t."""
    states = rk4_states(double_pendulum_rate, [math.pi / 2, math.pi / 2, 0.0, 0.0], h, round(t_end / h))
    return lambda t: double_pendulum_tip(*states[round(t / h), :2])


def run_text(binary: str, work: Path, name: str, text: str, repeat: int) -> dict:
    """Run a deck text `repeat` times: the last run's result with the median child CPU time."""
    path = work / f"{name}-{len(list(work.iterdir()))}.deck"
    path.write_text(text)
    cpus = []
    for k in range(repeat):
        if k:
            shutil.rmtree(work / path.stem, ignore_errors=True)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        result = fb.run_deck(binary, path, work / path.stem)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))
    result["cpu"] = statistics.median(cpus)
    return result


def common_error(outdir: Path, point: str, exact, every: float) -> float:
    """The largest distance of `point` from exact(t) over the rows at multiples of `every`."""
    worst = 0.0
    for r in read.rows(outdir / "points.csv", True, point=point):
        k = round(r["t"] / every)
        if abs(r["t"] - k * every) <= 1e-9 * every:
            x, y = exact(k * every)
            worst = max(worst, math.hypot(r["x"] - x, r["y"] - y))
    return worst


def adaptive_cases(short: bool) -> list[dict]:
    """Each case: its deck text with the time line left to fill, the tracked
    point, the exact answer (a function of t), the rows' common spacing, the
    fixed steps and the adaptive tolerances."""
    pendulum = (fb.ROOT / "decks" / "dynamics" / "pendulum.deck").read_text().replace("E=2e11  G=8e10", "E=2e14  G=8e13")
    crank = (fb.ROOT / "decks" / "dynamics" / "slider-crank.deck").read_text()
    fixed_pendulum = [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4] if not short else [2e-3, 1e-3]
    cases = [
        dict(name="pendulum", text=pendulum, point="B", t_end=0.6, every=0.01, exact=pendulum_reference(0.6),
             fixed=fixed_pendulum, tols=[1e-6, 1e-7, 1e-8, 1e-9, 1e-10] if not short else [1e-7, 1e-9]),
        dict(name="double pendulum", text=DOUBLE_PENDULUM, point="C", t_end=0.5, every=0.01,
             exact=double_reference(0.5), fixed=fixed_pendulum,
             tols=[1e-6, 1e-7, 1e-8, 1e-9, 1e-10] if not short else [1e-7, 1e-9]),
        dict(name="flexible slider-crank", text=crank, point="M", t_end=0.02, every=1e-4, exact=None,
             fixed=[1e-4, 5e-5, 2.5e-5, 1.25e-5] if not short else [1e-4, 5e-5],
             tols=[1e-5, 1e-6, 1e-7, 1e-8] if not short else [1e-6]),
    ]
    return cases


def adaptive_study(binary: str, work: Path, short: bool, repeat: int) -> list[dict]:
    rows = []
    for case in adaptive_cases(short):
        def deck_text(time: str, text: str = case["text"]) -> str:
            return fb.with_settings(text, {"start": "consistent", "time": time})
        exact = case["exact"]
        if exact is None:
            # The flexible slider-crank: FEKAP's own run at a fine fixed step.
            ref_dt = 2.5e-6 if not short else 1.25e-5
            ref = run_text(binary, work, "reference", deck_text(f"0 {case['t_end']!r} {ref_dt!r}"), 1)
            reference = read.rows(ref["outdir"] / "points.csv", True, point=case["point"])
            table_ = {round(r["t"] / case["every"]): (r["x"], r["y"]) for r in reference
                      if abs(r["t"] / case["every"] - round(r["t"] / case["every"])) < 1e-6}
            exact = lambda t, table_=table_, every=case["every"]: table_[round(t / every)]  # noqa: E731
        settings = [("fixed", f"dt {dt:g}", f"0 {case['t_end']!r} {dt!r}") for dt in case["fixed"]]
        settings += [("adaptive", f"TOL {tol:g}", f"0 {case['t_end']!r} {case['every']!r} adaptive {tol!r}")
                     for tol in case["tols"]]
        for kind, setting, time in settings:
            result = run_text(binary, work, case["name"].replace(" ", "-"), deck_text(time), repeat)
            error = math.nan
            steps = None
            if result["rc"] == 0:
                error = common_error(result["outdir"], case["point"], exact, case["every"])
                steps = result.get("summary", {}).get("configurations solved")
            rows.append(dict(case=case["name"], kind=kind, setting=setting, rc=result["rc"], error=error,
                             cpu=result["cpu"], steps=steps))
            shutil.rmtree(result["outdir"], ignore_errors=True)
    return rows


def adaptive_table(rows: list[dict]) -> str:
    lines = ["| case | steps | setting | accepted steps | largest position error | CPU (s) |",
             "|------|-------|---------|---------------:|-----------------------:|--------:|"]
    for r in rows:
        steps = "" if r["steps"] is None else f"{r['steps']:g}"
        lines.append(f"| {r['case']} | {r['kind']} | {r['setting']} | {steps} | {fmt(r['error'])} | {r['cpu']:.3f} |")
    return "\n".join(lines)


def adaptive_plot(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 4.5), squeeze=False)
    for ax, case in zip(axes[0], cases):
        for kind, marker in (("fixed", "o"), ("adaptive", "s")):
            pts = [(max(r["cpu"], 1e-3), r["error"]) for r in rows
                   if r["case"] == case and r["kind"] == kind and r["rc"] == 0 and r["error"] > 0]
            if pts:
                ax.loglog(*zip(*pts), marker=marker, label=f"{kind} steps")
        ax.set_title(case)
        ax.set_xlabel("CPU time of the run (s)")
        ax.set_ylabel("largest position error (m)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("FEKAP dynamics: error against CPU time, fixed and adaptive steps")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="FEKAP accuracy against cost")
    parser.add_argument("--short", action="store_true", help="a few points per study; no docs written")
    parser.add_argument("--bin", help="fekap executable")
    parser.add_argument("--repeat", type=int, help="runs per point (default 5, short 1)")
    parser.add_argument("--dynamics", action="store_true",
                        help="the dynamics table alone (written to docs/performance.md unless --short)")
    parser.add_argument("--adaptive", action="store_true",
                        help="the fixed-against-adaptive study alone (a plot and a table)")
    parser.add_argument("--plot", help="the adaptive study's PNG (default docs/performance/accuracy-adaptive.png)")
    args = parser.parse_args(argv)
    binary = fb.fekap_binary(args.bin)
    work = fb.scratch_dir("fekap-accuracy-")
    repeat = args.repeat or (1 if args.short else 5)
    if args.adaptive:
        adaptive = adaptive_study(binary, work, args.short, repeat)
        shutil.rmtree(work, ignore_errors=True)
        print(adaptive_table(adaptive))
        png = Path(args.plot) if args.plot else fb.ROOT / "docs" / "performance" / "accuracy-adaptive.png"
        adaptive_plot(adaptive, png)
        print(f"wrote {png}")
        return 0 if all(r["rc"] == 0 for r in adaptive) else 1
    rows = [] if args.dynamics else [measure(binary, work, item, repeat) for item in studies(args.short)]
    dynamics = [measure_dynamics(binary, work, item, repeat) for item in dynamics_studies(args.short)]
    shutil.rmtree(work, ignore_errors=True)
    text = table(rows)
    print(text)
    dynamics_text = dynamics_table(dynamics)
    summary = stiffness_summary(dynamics)
    if summary:
        dynamics_text += "\n\nThe bars' stiffness at a fixed dt (the plateau over the change points):\n\n" + summary
    print("\nDynamics: error against the exact answers by dt and integrator\n")
    print(dynamics_text)
    if args.dynamics and not args.short:
        fb.replace_block(fb.ROOT / "docs" / "performance.md", "accuracy-dynamics", dynamics_text)
        print("wrote docs/performance.md (dynamics table)")
    elif not args.short:
        fb.replace_block(fb.ROOT / "docs" / "performance.md", "accuracy", text)
        fb.replace_block(fb.ROOT / "docs" / "performance.md", "accuracy-dynamics", dynamics_text)
        plot(rows, fb.ROOT / "docs" / "performance" / "accuracy.png")
        (fb.ROOT / "docs" / "performance" / "accuracy.json").write_text(json.dumps(rows, indent=1) + "\n")
        print("wrote docs/performance.md (accuracy table), docs/performance/accuracy.png, accuracy.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
