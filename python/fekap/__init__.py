"""FEKAP's Python package: everything the user commands of scripts/, the studies of
studies/ and the tests of test/app/ share.

- :mod:`fekap.read`: the output files of a run read whole (points, links, steps, nodes,
  reactions, energy, mesh, ...) into numpy arrays;
- :mod:`fekap.stream`: the same files read in blocks and reduced for plots of runs of any
  length, and mechanism.txt;
- :mod:`fekap.run`: the executable (one way to find it) and running a deck;
- :mod:`fekap.plot`: the pictures of scripts/plot.py;
- :mod:`fekap.batch`: parameter sweeps on Dask (scripts/fekap-batch);
- :mod:`fekap.exact`: exact and independent solutions (Example 1's four-bar, the A02
  N-four-bar, the spin-up beam);
- :mod:`fekap.models`: deck writers of parametric models (A02, spin-up beam, scissor lift);
- :mod:`fekap.dynamics`: the dynamics benchmarks' answers read from a run.
"""
