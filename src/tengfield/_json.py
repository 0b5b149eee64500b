"""Plain-JSON conversion shared by every writer of ``*.json`` outputs."""
from __future__ import annotations

import math
from dataclasses import asdict, is_dataclass

import numpy as np


def jsonable(obj):
    """``obj`` as plain JSON types: dataclasses and objects become dicts (private
    attributes left out), arrays lists, NumPy scalars Python numbers, and NaN/inf
    ``None`` (strict JSON has no NaN)."""
    if is_dataclass(obj) and not isinstance(obj, type):
        return jsonable(asdict(obj))
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, (str, int, float, bool)) or obj is None:
        return obj
    if hasattr(obj, "__dict__"):
        return jsonable({k: v for k, v in vars(obj).items() if not k.startswith("_")})
    return str(obj)


def regime_dict(regime) -> dict | None:
    """A dynamics regime (:class:`tengfield.dynamics.Regime` or a dict) as a plain dict."""
    if regime is None:
        return None
    if hasattr(regime, "as_dict"):
        return regime.as_dict()
    return jsonable(regime)
