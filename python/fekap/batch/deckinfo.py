"""What the batch layer needs to know of a deck before running it: the names of
its parameters (the PARAmeters block), read with the deck reader's rules for
comments and cards (docs/deck-format.md). INCLude files are not followed."""

from __future__ import annotations

import re

CARDS = ("TITLE", "PARAMETERS", "SECTIONS", "NODES", "COORDINATES", "LINKS", "ELEMENTS", "WELDS",
         "SUPPORTS", "BOUNDARY", "DRIVES", "LOADS", "SLIDELINES", "ANALYSIS", "OUTPUT", "INCLUDE")


def card_of(field: str) -> str | None:
    """The card keyword a first field selects (FEAP-style 4-letter prefix), or None."""
    up = field.upper()
    if up == "END":
        return "END"
    if len(up) < 4 or not up.isalpha():
        return None
    return next((card for card in CARDS if card.startswith(up)), None)


def parameter_names(text: str) -> dict[str, str]:
    """The deck's parameter names, lower case -> as spelt, in deck order."""
    names: dict[str, str] = {}
    block = None
    for line in text.splitlines():
        if line.startswith("*"):
            continue
        code = line.split("!", 1)[0]
        fields = [f for f in re.split(r"[\s,]+", code.strip()) if f]
        if not fields:
            continue
        card = card_of(fields[0])
        if card is not None and (len(fields) == 1 or card in ("TITLE", "INCLUDE")):
            block = card
            continue
        if block == "PARAMETERS" and "=" in "".join(fields):
            name = "".join(fields).split("=", 1)[0]
            names.setdefault(name.lower(), name)
    return names
