"""Exact and independent solutions that the tests and the studies compare FEKAP with."""
