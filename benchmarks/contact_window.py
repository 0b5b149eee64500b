"""A ten-minute contact-charged run (issue #52): the charge over every impact, the
electrical stage over the steady window (`[charge] waveforms = "steady"`) or over the
whole run (`"start-up"`).

    .venv/bin/python benchmarks/contact_window.py --prepare     # the field, cached once
    farm-bench -n 3 --timeout 900 \\
        --vs '.venv/bin/python benchmarks/contact_window.py --waveforms start-up' \\
        -- .venv/bin/python benchmarks/contact_window.py --waveforms steady

Each run is a whole `tengfield run` process of the default scene with `[charge] model =
"contact"`, 600 s at 20 kHz (12 M samples), on a cached surrogate (`--prepare` makes it
in the benchmark's own cache folder). Prints the run's wall time and what it wrote.
Without arguments (`make bench`): the steady-window run, after preparing.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(tempfile.gettempdir()) / "tengfield-bench-contact-window"
SCENE = """\
[run]
duration_s = 600.0
sample_rate_hz = 20000.0
[charge]
model = "contact"
waveforms = "{waveforms}"
"""


def run(waveforms: str) -> float:
    HERE.mkdir(exist_ok=True)
    scene = HERE / f"{waveforms}.toml"
    scene.write_text(SCENE.format(waveforms=waveforms))
    out = HERE / f"out-{waveforms}"
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tengfield.cli", "run", str(scene), "-o", str(out),
                    "--cache-dir", str(HERE / "cache")], check=True,
                   stdout=subprocess.DEVNULL)
    took = time.perf_counter() - start
    sizes = ", ".join(f"{p.name} {p.stat().st_size / 1e6:.3g} MB"
                      for p in sorted(out.iterdir()) if p.suffix in (".csv", ".h5"))
    print(f"waveforms = {waveforms!r}: {took:.2f} s; {sizes}")
    return took


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--waveforms", choices=("steady", "start-up"))
    parser.add_argument("--prepare", action="store_true")
    args = parser.parse_args()
    if args.prepare or args.waveforms is None:
        run("steady")                 # the field solved into the cache
    if args.waveforms is not None:
        run(args.waveforms)
    elif not args.prepare:
        run("steady")


if __name__ == "__main__":
    main()
