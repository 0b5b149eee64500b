"""Write the surrogate files of the old layout (1-D format 3, (z, r) format 1: induced
charges in C at the ball charge solved with, and that ball charge) that
tests/surrogate/test_surrogate_per_unit.py reads: the analytic plate model of
tests/plate_model.py (and its (z, r) variant, tests/zr_model.py), the small scene
``fx.scene_with()`` at -8 µC/m², and the same 1-D table at 0 µC/m².

Run it against a checkout of commit 5780630 (the last one writing that layout), e.g.

    git worktree add --detach /tmp/old 5780630
    PYTHONPATH=/tmp/old/src:tests .venv/bin/python tests/data/make_format3_surrogates.py tests/data
"""
from __future__ import annotations

import sys
from pathlib import Path

from tengfield import surrogate

import plate_model as fx
from zr_model import zr_model_solve


def main(out: str) -> None:
    out = Path(out)
    charged = fx.scene_with().with_values(device={"surface_charge_uC_per_m2": -8.0})
    uncharged = charged.with_values(device={"surface_charge_uC_per_m2": 0.0})
    surrogate.write_table(out / "surrogate_format3_plate.h5",
                          surrogate.precompute(charged, solve=fx.plate_model_solve))
    surrogate.write_table(out / "surrogate_format3_plate_uncharged.h5",
                          surrogate.precompute(uncharged, solve=fx.plate_model_solve))
    zr = surrogate.precompute_radial(charged, solve=zr_model_solve, solve_comm=object(),
                                     tolerance=1e-2, max_positions=17, max_offsets=9)
    surrogate.write_radial_table(out / "surrogate_zr_format1_plate.h5", zr)


if __name__ == "__main__":
    main(sys.argv[1])
