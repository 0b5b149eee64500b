"""Robustness of the field stage (issue 8): bad geometry/mesh values give one
FieldError line naming the key, Ctrl-C during a solve raises KeyboardInterrupt,
an uncharged ball gives no warnings and no NaN, colour-bar labels stay distinct."""
import math
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tengfield.errors import FieldError, SceneError
from tengfield.field import geometry_axisymmetric as geometry
from tengfield.field.plot import colour_bar_labels, colour_bar_scale
from tengfield.scene import default_scene


# -- colour bar (issue 8.18) ----------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(exponent=st.floats(-13.0, 5.0), mantissa=st.floats(1.0, 9.999))
def test_colour_bar_labels_are_distinct_at_any_scale(exponent, mantissa):
    limit = mantissa * 10.0 ** exponent
    for n in (5, 7):
        labels = colour_bar_labels(limit, n)
        assert len(set(labels)) == n, labels
        assert not any(label.startswith("-") and float(label) == 0.0 for label in labels), labels
        factor, unit, _ = colour_bar_scale(limit, n)
        assert 1.0 <= limit / factor < 1000.0 or unit in ("pV", "kV")


def test_colour_bar_of_small_potentials_uses_a_small_unit():
    assert colour_bar_scale(0.4)[1] == "mV"
    assert colour_bar_labels(0.4) == ["-400", "-200", "0", "200", "400"]
    assert colour_bar_scale(2e3)[1] == "kV"
    assert colour_bar_scale(0.0) == (1.0, "V", "%.0f")


# -- size budget and gmsh failures (issue 8.7) -------------------------------------------
def test_mesh_estimate_refuses_a_tiny_mesh_size_before_meshing(monkeypatch):
    # the scene refuses a mesh size far below the device's features, naming the key ...
    with pytest.raises(SceneError, match=r"mesh_size_mm = 0.001 is too fine"):
        default_scene().with_values(field={"mesh_size_mm": 0.001})
    # ... and the solver's own budget refuses any layout over MAX_DOFS_2D before gmsh
    # runs (what a library caller with an unchecked size would reach)
    scene = default_scene()
    lay = geometry.layout(scene, 1.5e-3, mesh_size=1e-6, grading_size=1e-6)
    assert geometry.estimated_dofs(lay, 2) > geometry.MAX_DOFS_2D
    with pytest.raises(FieldError) as err:
        geometry.check_mesh_budget(lay, 2, mesh_size_mm=0.001)
    message = str(err.value)
    assert "mesh_size_mm = 0.001" in message and "allowed" in message and "\n" not in message
    fine = geometry.layout(scene, 1.5e-3)
    geometry.check_mesh_budget(fine, 2)                      # the default passes


def test_mesh_estimate_is_close_to_the_real_mesh():
    """The estimate must be the right size (within 2x) to be a useful limit."""
    pytest.importorskip("dolfinx")
    from mpi4py import MPI

    from tengfield.field import solve_position
    scene = default_scene()
    res = solve_position(scene, 1.5e-3, comm=MPI.COMM_SELF, method="axisymmetric",
                         mesh_size_mm=1.0, estimate_error=False)
    lay = geometry.layout(scene.with_values(field={"mesh_size_mm": 1.0}), 1.5e-3)
    assert 0.5 < geometry.estimated_dofs(lay, 2) / res.dofs < 2.0


def test_gmsh_failure_is_one_line_naming_the_keys(monkeypatch):
    pytest.importorskip("gmsh")
    from mpi4py import MPI

    from tengfield.field import solve_position

    def broken(*args, **kwargs):
        raise Exception("OpenCASCADE: BRepAlgoAPI failed\nmore detail")
    monkeypatch.setattr(geometry, "build_model", broken)
    with pytest.raises(FieldError) as err:
        solve_position(default_scene(), 1.5e-3, comm=MPI.COMM_SELF, method="axisymmetric",
                       estimate_error=False)
    message = str(err.value)
    assert "\n" not in message
    for key in ("stroke_mm = 3", "ball_diameter_mm = 7", "mesh_size_mm = 0.5", "domain_radius_mm = 20",
                "BRepAlgoAPI"):
        assert key in message


# -- uncharged ball (issue 8.17) -----------------------------------------------------------
@pytest.mark.slow
def test_uncharged_ball_gives_no_warning_and_no_nan():
    pytest.importorskip("dolfinx")
    from mpi4py import MPI

    from tengfield.field import open_circuit
    from tengfield.field.io import summary_lines
    scene = default_scene().with_values(device={"surface_charge_uC_per_m2": 0.0})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            state = open_circuit(scene, 0.0, comm=MPI.COMM_SELF, method="axisymmetric",
                                 mesh_size_mm=1.0)   # contact rule + error estimate
    res = state.result
    assert res.ball_charge == 0.0 and np.all(res.induced_charge == 0.0)
    fractions = res.induced_fractions()
    assert np.all(np.isfinite(fractions)) and -1.0 < fractions.sum() < 0.0
    assert math.isfinite(res.relative_error_estimate)
    assert np.all(state.potentials == 0.0)
    text = "\n".join(summary_lines(res, "floating", state.potentials))
    assert "nan" not in text.lower()


# -- Ctrl-C (issue 8.16) -------------------------------------------------------------------
SCRIPT = """
import sys
from mpi4py import MPI
from tengfield.field import solve_position
from tengfield.scene import default_scene
print("ready", flush=True)
try:
    for _ in range(20):   # ~1 s each: the signal lands inside one and is handled soon after
        solve_position(default_scene(), 1.5e-3, comm=MPI.COMM_SELF, method="axisymmetric",
                       mesh_size_mm=0.5)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
"""


@pytest.mark.slow
def test_ctrl_c_during_a_field_solve_raises_keyboard_interrupt():
    pytest.importorskip("gmsh")
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(4.0)            # inside the solves (gmsh meshing is most of each)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, (proc.returncode, err[-2000:])
    assert "interrupted" in out


def test_gmsh_start_drops_only_the_mixed_mpi_false_alarm(monkeypatch, capfd):
    """Debian 13: the PETSc inside the gmsh wheel takes Open MPI 5's own symbols for
    MPICH's and prints a false alarm at every gmsh start. That line (written by C to
    file descriptor 2) is dropped; every other line gmsh writes there is kept, in order."""
    import os

    gmsh = pytest.importorskip("gmsh")
    from tengfield.field import _gmsh

    seen = []

    def start(argv, **kwargs):
        seen.append((argv, kwargs))
        os.write(2, b"Info    : a line gmsh writes\n")
        os.write(2, b"PETSc Error --- Application was linked against both OpenMPI and MPICH "
                    b"based MPI libraries and will not run correctly\n")
        os.write(2, b"Warning : another line\n")

    monkeypatch.setattr(gmsh, "initialize", start)
    _gmsh.initialize(("-nt", "1"), interruptible=False)
    assert seen == [(["-nt", "1"], {"interruptible": False})]
    assert capfd.readouterr().err == "Info    : a line gmsh writes\nWarning : another line\n"
    with pytest.raises(RuntimeError):                   # an error still restores stderr
        with _gmsh._without_line(b"x"):
            raise RuntimeError("gmsh failed")
    os.write(2, b"after\n")
    assert capfd.readouterr().err == "after\n"
