"""The device as a source: the charge the ball carries over a run (issue #52: contact
electrification, ``charge``, ``contacts``, ``terminal``), the layer the terminal model
builds on (issue #51)."""
from __future__ import annotations


