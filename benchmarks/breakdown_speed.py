"""Cost of the breakdown lines in a cold field stage (the default scene's surrogate).

    farm-bench -n 3 --timeout 900 --vs '.venv/bin/python benchmarks/breakdown_speed.py --no-lines' \\
        -- .venv/bin/python benchmarks/breakdown_speed.py

Each run computes the surrogate from scratch (no cache) in a fresh process, as the
field stage of a cold `tengfield run` does (dolfinx import included); with --no-lines
the solves skip the unit-charge back-substitution and the surface sampling. Prints the
precompute time and, with lines, sigma_max.
"""
from __future__ import annotations

import argparse
import time


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--no-lines", action="store_true")
    args = parser.parse_args()
    from tengfield import air_breakdown
    from tengfield.scene import default_scene
    from tengfield.surrogate import precompute

    scene = default_scene()
    start = time.perf_counter()
    table = precompute(scene, breakdown_lines=not args.no_lines)
    took = time.perf_counter() - start
    line = f"precompute {took:.2f} s, {table.count} positions"
    if not args.no_lines:
        start = time.perf_counter()
        res = air_breakdown.scene_breakdown(scene, table, air_breakdown.STATES)
        line += (f"; sigma_max {res.sigma_max * 1e6:.4g} uC/m^2 "
                 f"(evaluation {time.perf_counter() - start:.3f} s)")
    print(line)


if __name__ == "__main__":
    main()
