"""Speed of the 3D ball: 1 s of motion at 30 Hz / 3 mm on one core (target <= 2 s).

Cases: vertical drive on the axis (Hertz, paper materials), the same with a
1 mm lateral drive (wall contacts, friction, spin), and the power law
(k = 1e5 N/m). Each run is timed after a warm-up run (numba compilation is
cached on disk, so only the very first call in a fresh checkout compiles).

    .venv/bin/python benchmarks/motion3d_speed.py [--quick]
"""
from __future__ import annotations

import argparse
import time

from tengfield.dynamics.motion3d import simulate_3d
from tengfield.scene import default_scene

CASES = {
    "vertical 3 mm, Hertz": {},
    "vertical 3 mm + lateral 1 mm, Hertz": {"excitation": {"amplitude_x_mm": 1.0,
                                                          "phase_x_deg": 45.0}},
    "vertical 3 mm, power law k = 1e5 N/m": {"contact": {"law": "power"}},
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one repeat instead of three")
    args = ap.parse_args()
    base = default_scene().with_values(
        contact={"model": "3d"}, excitation={"frequency_hz": 30.0, "amplitude_mm": 3.0},
        run={"duration_s": 1.0, "settle_periods": 10})
    simulate_3d(base.with_values(run={"settle_periods": 1}), duration=0.05)  # warm-up (numba)
    repeats = 1 if args.quick else 3
    print(f"{'case':42s} {'wall s':>8s} {'steps':>8s} {'impacts':>8s} {'wall c.':>8s} "
          f"{'steps/contact':>14s}")
    for name, over in CASES.items():
        scene = base.with_values(**{k: {**v} for k, v in over.items()})
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            r = simulate_3d(scene)
            best = min(best, time.perf_counter() - t0)
        print(f"{name:42s} {best:8.3f} {r.n_events:8d} {len(r.impacts):8d} "
              f"{r.wall_contacts:8d} {r.steps_per_contact:8.1f} (min {r.min_steps_per_contact})")


if __name__ == "__main__":
    main()
