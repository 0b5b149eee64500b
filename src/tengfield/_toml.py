"""TOML literals shared by every writer of ``*.toml`` outputs (fitted and recommended scenes)."""
from __future__ import annotations

import json


def toml_value(value) -> str:
    """A TOML literal for a bool, int, float (``inf``, ``-inf``, ``nan`` included), string
    or list of them; ``TypeError`` for anything else."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)                # always has ".", "e", "inf" or "nan": a TOML float
    if isinstance(value, str):
        return json.dumps(value)          # a TOML basic string is a JSON string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to TOML")
