"""The building blocks of the case file's sections (geometry.params): a field with an allowed
range, the error a bad value raises, and where a key sits in a case file (for messages)."""
from __future__ import annotations

import dataclasses
from dataclasses import field
from typing import Any

from geometry.artifacts import InputError


class CaseError(InputError):
    """A case file that cannot describe a buildable reducer; the message names key, value, range."""


def ranged(lo: float | None = None, hi: float | None = None, *, open_lo: bool = True,
           open_hi: bool = False, why: str = "", default: Any = dataclasses.MISSING) -> Any:
    """A field with an allowed range (open at lo by default: sizes must be positive); `why` is
    added to the message when a value falls outside."""
    md = {"lo": lo, "hi": hi, "open_lo": open_lo, "open_hi": open_hi, "why": why}
    if default is dataclasses.MISSING:
        return field(metadata=md)
    if isinstance(default, (list, tuple)):
        return field(default=tuple(default), metadata=md)
    return field(default=default, metadata=md)


def where(section: str, key: str, source: str) -> str:
    """'<file>: [section] key' for messages."""
    return f"{source + ': ' if source else ''}[{section}] {key}"
