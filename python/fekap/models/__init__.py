"""Deck writers of parametric models (run as ``scripts/python -m fekap.models.NAME``)."""
