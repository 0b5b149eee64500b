"""The one lookup of every registry (``EXCITATIONS``, ``MODELS``, ``CIRCUITS``).

A registry is a plain dict from the scene file's name of a choice to its entry (as
SciPy's ``solve_ivp`` keeps ``METHODS``); the entry carries its capabilities, so
callers ask the entry (``EXCITATIONS[kind].periodic``) instead of comparing names.
:func:`lookup` turns an unknown name into the one-line :class:`SceneError`.
"""
from __future__ import annotations

from typing import Mapping, TypeVar

from .errors import SceneError

T = TypeVar("T")


def lookup(registry: Mapping[str, T], name: str, key: str) -> T:
    """``registry[name]``; an unknown ``name`` raises ``SceneError`` naming ``key``
    (e.g. ``"[excitation] kind"``), the value and the allowed names."""
    try:
        return registry[name]
    except (KeyError, TypeError):
        raise SceneError(f"{key} = {name!r}: allowed "
                         f"{', '.join(map(repr, registry))}") from None
