"""Write surrogate_before_issue9.json: the default scene's cold surrogate as computed
before the issue-9 speed work, with every position's own field error estimate.

Run it against a checkout of commit 9e36692 (the field stage issue #9 asked to
speed up), e.g.

    git worktree add --detach /tmp/old 9e36692
    PYTHONPATH=/tmp/old/src .venv/bin/python tests/data/make_surrogate_baseline.py OUT.json
"""
from __future__ import annotations

import json
import os
import sys
import tempfile

os.environ.setdefault("TENGFIELD_CACHE_DIR", tempfile.mkdtemp())

import numpy as np  # noqa: E402
import pyvista  # noqa: E402,F401 - before dolfinx

from tengfield import surrogate  # noqa: E402
from tengfield.scene import default_scene  # noqa: E402


def main(path: str) -> None:
    table = surrogate.precompute(default_scene(), field_error="every")
    data = {"about": "default scene, cold surrogate of tengfield 9e36692 (before the issue-9 "
                     "speed work), field_error='every': every position's own field error "
                     "estimate; made by tests/data/make_surrogate_baseline.py",
            "positions_m": table.positions.tolist(),
            "capacitance_F": np.asarray(table.capacitance).tolist(),
            "induced_charge_C": np.asarray(table.induced_charge).tolist(),
            "field_error": np.asarray(table.field_error).tolist(),
            "interpolation_error": float(table.interpolation_error)}
    with open(path, "w") as fh:
        json.dump(data, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1])
