"""fekap-batch: parameter sweeps of FEKAP decks on Dask distributed (docs/batch.md)."""
