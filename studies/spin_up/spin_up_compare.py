#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/../../scripts/python" "$0" "$@"'
"""Compare FEKAP's spin-up beam (decks/dynamics/spin-up.deck) with the
independent linear rotating-beam model of python/fekap/exact/spin_up.py: the
transverse tip deflection in the hub's frame over 0-30 s, for 10, 20, 40 and
80 elements at dt 0.01, 0.005 and 0.0025 (the deck: 10 elements, dt 0.01).
A comparison script, not a test (test/app/test_dynamics.py checks the deck).

    studies/spin_up/spin_up_compare.py [--plot docs/dynamics/spin-up.png] [--beta B]

--beta B adds a run of the deck with stiffness-proportional Rayleigh damping
beta = B on the section (the published case has none; docs/dynamics.md shows
the objective damping's run with beta = 0.01).

Prints a Markdown table (peak deflection and its time, the value at t = 15 s,
the largest magnitude after t = 15 s, the largest difference from the model);
FEKAP is the release binary of scripts/build (build/local/bin/fekap).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import numpy as np

from fekap import dynamics as dc
from fekap import run as fb
from fekap.exact import spin_up as reference

ROOT = fb.ROOT
DECK = ROOT / "decks" / "dynamics" / "spin-up.deck"


def run(elements: int, dt: float, beta: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Times and transverse tip deflections in the hub's frame of one run."""
    text = DECK.read_text().replace("OT  O  T  beam  10", f"OT  O  T  beam  {elements}")
    if beta:
        text = text.replace("rhoI=6e-4", f"rhoI=6e-4  beta={beta:g}")
    work = fb.scratch_dir("fekap-spin-up-")
    deck = work / "spin-up.deck"
    deck.write_text(text)
    result = fb.run_deck(fb.fekap_binary(), deck, work / "out", "--set", f"dt={dt!r}")
    if result["rc"] != 0:
        sys.exit(f"fekap failed ({elements} elements, dt {dt}): {result['stderr']}")
    t, _, across = dc.spin_up_tip(work / "out")
    shutil.rmtree(work, ignore_errors=True)
    return t, across


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plot", type=Path, help="write the figure to this PNG")
    parser.add_argument("--beta", type=float, help="also a run with Rayleigh damping beta= on the section")
    args = parser.parse_args()
    model_t, model_v = reference.simulate(n_modes=6, dt=1e-3, t_end=30.0, law="table")
    model = dc.spin_up_features(model_t, model_v)
    exact = dc.spin_up_features(*reference.simulate(n_modes=6, dt=1e-3, t_end=30.0, law="exact"))
    print("| model | elements | dt (s) | peak | t of peak (s) | at t = 15 s | largest after 15 s | "
          "largest difference from the model (after 15 s) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, f in (("linear model, published law", exact), ("linear model, the deck's table", model)):
        print(f"| {name} | 6 modes | RK4 1e-3 | {f['peak']:.5f} | {f['t_peak']:.4f} | {f['at15']:.3e} | "
              f"{f['residual']:.3e} | |")
    series = {}
    for elements in (10, 20, 40, 80):
        for dt in (0.01, 0.005, 0.0025):
            t, v = run(elements, dt)
            series[elements, dt] = (t, v)
            f = dc.spin_up_features(t, v)
            diff = np.abs(v - np.interp(t, model_t, model_v))
            print(f"| FEKAP | {elements} | {dt:g} | {f['peak']:.5f} | {f['t_peak']:.4f} | {f['at15']:.3e} | "
                  f"{f['residual']:.3e} | {diff.max():.2e} ({diff[t >= 15].max():.2e}) |")
    if args.beta:
        damped_t, damped_v = run(10, 0.01, beta=args.beta)
        f = dc.spin_up_features(damped_t, damped_v)
        late = np.abs(damped_v[damped_t >= 25]).max()
        print(f"| FEKAP, beta = {args.beta:g} | 10 | 0.01 | {f['peak']:.5f} | {f['t_peak']:.4f} | {f['at15']:.3e} | "
              f"{f['residual']:.3e} (after 25 s: {late:.2e}) | |")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        style = ROOT / "scripts" / "fekap.mplstyle"
        if style.is_file():
            plt.style.use(str(style))
        fig, axes = plt.subplots(3, 1, figsize=(8, 9), constrained_layout=True)
        t10, v10 = series[10, 0.01]
        t80, v80 = series[80, 0.0025]
        axes[0].plot(model_t, model_v, "k-", lw=2.5, label="linear rotating-beam model (6 modes)")
        axes[0].plot(t10, v10, "C1--", label="FEKAP, the deck: 10 elements, dt 0.01")
        axes[0].set_ylabel("transverse tip deflection")
        axes[0].set_title("Spin-up beam: tip deflection in the hub's frame")
        axes[0].legend()
        after = model_t >= 14
        axes[1].plot(model_t[after], model_v[after], "k-", lw=2.5, label="model")
        for (t, v), label, style_ in (((t10, v10), "10 elements, dt 0.01", "C1--"),
                                      ((t80, v80), "80 elements, dt 0.0025", "C2:")):
            axes[1].plot(t[t >= 14], v[t >= 14], style_, label=f"FEKAP, {label}")
        axes[1].set_ylabel("after the spin-up")
        axes[1].legend(ncol=2, fontsize="small")
        for (t, v), label, style_ in (((t10, v10), "10 elements, dt 0.01", "C1-"),
                                      ((t80, v80), "80 elements, dt 0.0025", "C2-")):
            axes[2].plot(t, v - np.interp(t, model_t, model_v), style_, label=f"FEKAP {label}")
        axes[2].set_ylabel("FEKAP - model")
        axes[2].set_xlabel("t (s)")
        axes[2].legend()
        args.plot.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(args.plot, dpi=110)
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
