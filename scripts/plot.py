#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/python" "$0" "$@"'
"""Plot the results of a FEKAP run: scripts/plot.py OUTDIR [options] (--help for the
options; the pictures are drawn by fekap.plot, python/fekap/plot.py)."""

import sys

from fekap import plot
from fekap.read import run_main

if __name__ == "__main__":
    sys.exit(run_main(plot.PROG, plot.main))
