"""Scene files: a TOML description of one BB-TENG and how it is driven.

Keys in the file carry their unit (``stroke_mm``, ``frequency_hz``); the
:class:`Scene` object holds SI values only (metres, seconds, coulombs...).
Every key is validated on load; a bad value raises :class:`SceneError`
naming the key, the value and the allowed range. The homes: ``schema`` (every
key, once), ``model`` (the dataclasses), ``parse`` (TOML text), ``recorded`` (the
CSV reader), ``limits`` (work, size and mesh limits), ``constants`` (G, EPS0).
"""
from ..errors import SceneError  # noqa: F401
from .constants import EPS0, G  # noqa: F401
from .model import (Array, Breakdown, Circuit, Contact, Device, Excitation, Field,  # noqa: F401
                    Initial, Instrument, Reference, Charge, Run, Scene, check_field)
from .parse import (as_scene, default_scene, default_text, load_scene,  # noqa: F401
                    parse_scene, with_settings)
