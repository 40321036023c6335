"""fekap-batch: parameter sweeps of FEKAP decks on Dask distributed (docs/batch.md)."""

import sys
from pathlib import Path

# compare.py and fekap_csv.py live next to this package, in scripts/.
_SCRIPTS = str(Path(__file__).resolve().parents[1])
if _SCRIPTS not in sys.path:
    sys.path.insert(0, _SCRIPTS)
