"""Speed of an [array] run: 455 cells x 1000 excitation periods (issue #11 target: <= 30 s).

The honeycomb's cell count (455) with a phase, restitution and launch-speed
spread, 1000 periods at 33 Hz, per-cell bridges into one store
(``rectified-parallel``), sampled at 50 points per period. The field is the
analytic plate model of the tests (the surrogate is shared and cached, so a
real field only adds its one-off solve). Prints the wall time of the whole
``tengfield.run`` and of its two array stages (dynamics over processes;
the chunked electrical stage). Not a test: run it by hand.

    PYTHONPATH=src:tests python benchmarks/harvest_array_speed.py [--cells 455] [--periods 1000]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def main(argv=None) -> dict:
    import tengfield as tf
    import plate_model as fx

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cells", type=int, default=455)
    p.add_argument("--periods", type=int, default=1000)
    p.add_argument("--samples-per-period", type=int, default=50)
    p.add_argument("--connection", default="rectified-parallel")
    args = p.parse_args(argv)
    freq = 33.0
    scene = fx.scene_with(
        device={"stroke_mm": 3.0},
        excitation={"frequency_hz": freq, "amplitude_mm": 0.5},
        run={"duration_s": args.periods / freq, "settle_periods": 10,
             "sample_rate_hz": args.samples_per_period * freq},
        circuit={"kind": "rectifier", "storage_capacitance_uF": 10.0, "pmic": "uvlo"},
        array={"cells": args.cells, "connection": args.connection,
               "initial_phase_spread_deg": 90.0, "restitution_spread": 0.05,
               "initial_velocity_spread_m_per_s": 0.05, "seed": 1})
    with tempfile.TemporaryDirectory() as cache:
        # warm-up: numba caches and the surrogate (not timed)
        tf.run(scene.with_values(array={"cells": 8}, run={"duration_s": 20 / freq}),
               cache_dir=cache, solve=fx.plate_model_solve)
        start = time.perf_counter()
        result = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
        wall = time.perf_counter() - start
    arr = result.summary["array"]
    out = {"cells": args.cells, "periods": args.periods, "samples": len(result.t),
           "wall_time_s": wall, "dynamics_wall_time_s": arr["dynamics_wall_time_s"],
           "electrical_wall_time_s": arr["electrical_wall_time_s"],
           "array_over_N_cells": arr["array_over_N_cells"],
           "final_store_voltage_V": result.summary["rectifier"]["final_store_voltage_V"]}
    for k, v in out.items():
        print(f"{k:24s} {v:.4g}" if isinstance(v, float) else f"{k:24s} {v}")
    return out


if __name__ == "__main__":
    main()
