"""The plain summary dict every result offers as ``result.summary`` (a property).

A few results used to spell it ``result.summary()``; :class:`Summary` is a plain
``dict`` that still answers that call (with a :class:`DeprecationWarning`), so old
notebooks keep working while new code reads the property.
"""
from __future__ import annotations

import warnings


class Summary(dict):
    """A JSON-ready dict; calling it returns a copy and warns that the call is deprecated."""

    def __call__(self) -> dict:
        warnings.warn("result.summary() is deprecated: read the property result.summary",
                      DeprecationWarning, stacklevel=2)
        return dict(self)

