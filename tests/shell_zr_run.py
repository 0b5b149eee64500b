"""One ``tengfield run`` of the ball rolling and bouncing in the spherical shell with
``[contact] model = "3d"``: the run that builds the shell's (z, r) surrogate (issue #32).

Its (z, r) table is the most expensive thing the shell's tests solve (each point on the
wall's column is three 3D solves of the contact rule), so it is solved once per test
process (issue #41): ``tests/dynamics/motion3d/test_shell_cli.py`` checks the run (the
join of the 3D contact to the table) and ``tests/field/test_spherical_shell_3d.py`` reads
the same table from the run's cache and checks it against a held-out direct 3D solve.
The table is small (P1, 5 mm, one round of 5 heights x 3 offsets: 3 heights solved by the
mirror symmetry, the ends on the axis) instead of the default (P2, 1.5 mm, from 17 x 3 up
to 33 x 9: ~17 min on one core). (This 5-height grid hit a gmsh HXT meshing failure at
4 mm, in the coarse mesh of an error estimate; 4.5 and 5 mm mesh it.)
"""
from __future__ import annotations

import functools
from pathlib import Path
from unittest import mock

from shell_model import shell_device_toml

#: the shell under a 3-axis drive, its 3D contact on the spherical wall
SHELL_3D = shell_device_toml() + """\
[excitation]
frequency_hz = 20
amplitude_mm = 3
amplitude_x_mm = 1
phase_x_deg = 60

[contact]
model = "3d"

[run]
duration_s = 0.4
settle_periods = 2
sample_rate_hz = 5000
"""

#: the (z, r) table's [field] keys: radial_mesh_size_mm, radial_degree (and the axis's
#: 1-D surrogate coarse, P1 at 2 mm)
ZR_FIELD = {"mesh_size_mm": 2.0, "degree": 1, "radial_mesh_size_mm": 5.0, "radial_degree": 1}
#: the table's grid: one round from 3 x 2 to 5 x 3 (keywords of precompute_radial)
ZR_GRID = {"initial_positions": 3, "max_positions": 5, "max_offsets": 3}
#: the scene file of the run
SHELL_3D_ZR = SHELL_3D.replace("[run]", "[field]\n" + "".join(
    f"{key} = {value}\n" for key, value in ZR_FIELD.items()) + "\n[run]")

_DONE: dict[str, tuple[Path, Path, Path]] = {}


def shell_zr_run(tmp_path_factory) -> tuple[Path, Path, Path]:
    """``(scene file, output directory, cache directory)`` of ``tengfield run`` (in
    process, figures on) of :data:`SHELL_3D_ZR` with the grid :data:`ZR_GRID`; run on
    the first call, the same directories after. The run must succeed (exit code 0)."""
    if "run" not in _DONE:
        from tengfield import pipeline
        from tengfield.cli import main

        d = tmp_path_factory.mktemp("shell_zr_run")
        scene_file, out, cache = d / "shell3d.toml", d / "run", d / "cache"
        scene_file.write_text(SHELL_3D_ZR)
        small = functools.partial(pipeline.obtain_radial_table, **ZR_GRID)
        with mock.patch.object(pipeline, "obtain_radial_table", small):
            code = main(["run", str(scene_file), "-o", str(out), "--cache-dir", str(cache)])
        assert code == 0, f"tengfield run of the shell's (z, r) scene exited {code}"
        _DONE["run"] = (scene_file, out, cache)
    return _DONE["run"]
