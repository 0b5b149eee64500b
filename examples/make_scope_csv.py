"""Write examples/scope.csv: the example "measured" trace of README's Quick start.

A `tengfield run` of the embedded default scene (7 mm PTFE ball, 20 Hz, 1.5 mm,
sigma = -8 uC/m^2), its steady half (t >= 0.5 s) sampled at 5 kHz as an instrument
would export it: time from the trigger, V_OC and Q_SC with Gaussian noise (1 % of each
peak-to-peak, seed 29). `tengfield fit my.toml --measured examples/scope.csv` calibrates
the default scene to it (sigma comes back near -8 uC/m^2).

    python examples/make_scope_csv.py        # rewrites examples/scope.csv
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

import tengfield as tf

HERE = Path(__file__).resolve().parent
START_S, RATE_HZ, NOISE, SEED = 0.5, 5000.0, 0.01, 29


def main() -> Path:
    r = tf.run(tf.default_scene())
    step = int(round(1.0 / (RATE_HZ * (r.t[1] - r.t[0]))))
    keep = np.flatnonzero(r.t >= START_S - 1e-12)[::step]
    t = r.t[keep] - r.t[keep[0]]
    rng = np.random.default_rng(SEED)
    columns = []
    for values in (r.V_oc[keep], r.Q_sc[keep]):
        columns.append(values + rng.normal(0.0, NOISE * np.ptp(values), values.size))
    path = HERE / "scope.csv"
    with open(path, "w") as f:
        f.write("# example trace for `tengfield fit --measured` (examples/make_scope_csv.py)\n"
                "# source: tengfield run of the default scene (7 mm PTFE ball, 20 Hz, 1.5 mm, "
                "sigma = -8 uC/m^2), t >= 0.5 s\n"
                f"# sample rate: {RATE_HZ:g} Hz; noise: Gaussian, {NOISE:.0%} of each "
                f"peak-to-peak (seed {SEED})\n"
                "# time from the first sample; V_oc_V open-circuit voltage [V], Q_sc_C "
                "short-circuit charge [C]\n"
                "time_s,V_oc_V,Q_sc_C\n")
        for row in zip(t, *columns):
            f.write(f"{row[0]:.6f},{row[1]:.6g},{row[2]:.6g}\n")
    return path


if __name__ == "__main__":
    print(f"wrote {main()}")
