"""The device as a source: the charge the ball carries over a run (issue #52: contact
electrification, ``charge``, ``contacts``, ``terminal``) and :class:`Source`, the device as
a two-terminal source along one run that every electrical consumer reads (issue #51,
``device``)."""
from __future__ import annotations

from .device import QUANTITIES, Source, terminal_quantities

__all__ = ["QUANTITIES", "Source", "terminal_quantities"]
