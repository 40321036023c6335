#!/usr/bin/env -S sh -c 'exec "$(dirname "$0")/python" "$0" "$@"'
"""Compare several FEKAP runs (or exact solutions) point by point:
scripts/compare.py RUN1 RUN2 [RUN...] [options] (--help for the options; the comparison is
fekap.compare, python/fekap/compare.py)."""

import sys

from fekap import compare
from fekap.read import run_main

if __name__ == "__main__":
    sys.exit(run_main(compare.PROG, compare.main))
