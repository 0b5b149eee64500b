"""The device as a source: the charge the ball carries over a run (issue #52: contact
electrification, ``charge``, ``contacts``, ``terminal``), the layer the terminal model
builds on (issue #51)."""
from __future__ import annotations


def refuse_contact_charge(scene, what: str) -> None:
    """One line, before the work, where ``[charge] model = "contact"`` does not reach yet
    (``what``: the study, e.g. "tengfield sweep"): that study would run the ball at a
    constant charge without saying so."""
    if isinstance(scene, dict):          # the file-level sections of the Python API
        model = (scene.get("charge") or {}).get("model") if isinstance(scene.get("charge"), dict) else None
    else:
        model = getattr(getattr(scene, "charge", None), "model", None)
    if model == "contact":
        from ..errors import SceneError
        raise SceneError(f'[charge] model = "contact" is not supported by {what} yet (it '
                         'would hold the charge constant): `tengfield run` runs it; here '
                         'use [charge] model = "constant" or "breakdown" (docs/charge.md)')
