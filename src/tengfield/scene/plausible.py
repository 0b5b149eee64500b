"""A length typed in metres where a ``*_mm`` key asks for millimetres (issue #53).

``stroke_mm = 0.0015`` is a legal 1.5 µm stroke, and the run then gives rest and zeros
with no word. :func:`warn_metres_for_mm` is the one check for every ``*_mm`` key of the
schema: a non-zero value below the key's plausibility bound (:data:`PLAUSIBLE_MM`,
default :data:`PLAUSIBLE_MM_DEFAULT`) is named with its value and what it would be in
mm if it was meant in metres, all such keys of one scene in one warning line. It is a warning, not a refusal:
such a value may be meant.
"""
from __future__ import annotations

import warnings

#: the smallest length [mm] a ``*_mm`` key plausibly holds when it is not 0: a stroke,
#: gap, diameter, radius, thickness or band below 50 µm is no bouncing-ball device
PLAUSIBLE_MM_DEFAULT = 0.05
#: keys with their own bound [mm]: a table amplitude of a few µm drives a ball at a few
#: kHz; a mesh size is a fraction of the smallest feature; a contact's penetration limit
#: is µm by nature; the ball's start above the plate ([initial] gap_mm) and its offset
#: from the axis are positions, small by choice
PLAUSIBLE_MM = {"amplitude_mm": 0.005, "amplitude_x_mm": 0.005, "amplitude_y_mm": 0.005,
                "mesh_size_mm": 0.01, "radial_mesh_size_mm": 0.01,
                "penetration_max_mm": 1e-4, "gap_mm": 1e-4, "ball_offset_mm": 1e-3}


def _numbers(value) -> list[float]:
    """The numbers of a value as given (a number, or a list of them: harmonics)."""
    items = value if isinstance(value, (list, tuple)) else [value]
    return [float(v) for v in items
            if isinstance(v, (int, float)) and not isinstance(v, bool)]


def implausible_mm(section: str, key: str, value) -> str | None:
    """The warning for ``[section] key = value`` (file units), or None."""
    if not key.endswith("_mm"):
        return None
    bound = PLAUSIBLE_MM.get(key, PLAUSIBLE_MM_DEFAULT)
    small = [v for v in _numbers(value) if 0.0 < abs(v) < bound]
    if not small:
        return None
    v = small[0]
    return (f"[{section}] {key} = {v:g} mm is {v * 1e3:.3g} µm, below the {bound:g} mm "
            f"plausible for it: if it was meant in metres, it is {key} = {v * 1e3:g}")


def warn_metres_for_mm(data: dict, keys=None) -> None:
    """One warning per ``*_mm`` key of ``data`` (file-level sections of the schema)
    whose value is implausibly small for millimetres; ``keys``: only these
    ``(section, key)`` pairs (the ``--set`` ones), default every key of ``data``."""
    from .._mpi import launched_rank

    if launched_rank() != 0:        # under mpirun: one line, not one per rank
        return
    from .schema import SCHEMA

    texts = []
    for section, values in data.items():
        if section not in SCHEMA or not isinstance(values, dict):
            continue
        for key, value in values.items():
            if keys is not None and (section, key) not in keys:
                continue
            text = implausible_mm(section, key, value) if key in SCHEMA[section] else None
            if text is not None:
                texts.append(text)
    if texts:
        warnings.warn(_one_line(texts), UserWarning, stacklevel=3)


def _one_line(texts: list[str]) -> str:
    """One warning for several keys (a whole device typed in metres): the first in full,
    the others after it, ``;``-separated, so a refusal that follows stays readable."""
    if len(texts) == 1:
        return texts[0]
    return f"{len(texts)} lengths look like metres: " + "; ".join(texts)
