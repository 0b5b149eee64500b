"""A field solve and its field.png in one fresh Python process, the order a notebook
takes (``import tengfield``, solve, ``.write``) without importing pyvista first: on
Debian 12 VTK's text rendering aborted the process (SIGABRT in std::regex) when
dolfinx's libraries were loaded before VTK's; ``field/_dolfinx.py`` loads VTK's core
first."""
import subprocess
import sys

import pytest

SCRIPT = """
import sys
import tengfield as tf
from mpi4py import MPI
assert "pyvista" not in sys.modules and "dolfinx" not in sys.modules
scene = tf.parse_scene("[field]\\ndegree = 1\\nmesh_size_mm = 1.0\\n")
res = tf.solve_position(scene, 1.5e-3, comm=MPI.COMM_SELF, keep_solution=True)
res.write(sys.argv[1])
"""


@pytest.mark.slow
@pytest.mark.field
def test_a_solve_then_its_field_png_in_one_process(tmp_path, cli_env):
    out = tmp_path / "field-out"
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(out)], env=cli_env(),
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert {p.name for p in out.iterdir()} >= {"field.json", "field.png", "potential.xdmf"}
    assert (out / "field.png").stat().st_size > 10_000
